// The HTML calibration report (report.hpp): hand-written inline SVG, no scripts.
#include "accelcal/report.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "accelcal/calibration_file.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/engineering.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/gyro_model.hpp"
#include "accelcal/sensor_parameters.hpp"
#include "core/text_format.hpp"
#include "output/html_svg.hpp"

namespace accelcal {

namespace {

using namespace internal::html;  // NOLINT: the page's shared pieces
constexpr double kPi = 3.14159265358979323846;
// One position of the file, with what the plots need.
struct PositionView {
  Vec3 mean = Vec3::Zero(), direction = Vec3::UnitZ(), residual = Vec3::Zero();
  double after = 0;
  std::optional<double> held_out, before;
  std::optional<std::pair<double, double>> time;     // interval [t_begin, t_end] s
  std::optional<std::pair<double, double>> samples;  // interval [begin, end) indices
};

struct Document {
  const LoadedCalibration& cal;
  std::vector<PositionView> positions;
  std::string unit;  // specific-force unit
};

Document Read(const ReportInput& input) {
  Document d{input.calibration, {}, std::string(ToString(input.calibration.unit))};
  for (const FilePosition& p : d.cal.positions) {
    PositionView v;
    v.mean = p.mean;
    v.direction = p.direction.value_or(Vec3::UnitZ());
    v.residual = p.residual.value_or(Vec3::Zero());
    v.after = p.gravity_norm_error.value_or(0.0);
    v.held_out = p.crossval_error;
    if (d.cal.gravity_norm_rms_before) v.before = v.mean.norm() - d.cal.gravity;
    if (p.interval) {
      v.time = std::pair(p.interval->t_begin, p.interval->t_end);
      v.samples = std::pair(p.interval->begin, p.interval->end);
    }
    d.positions.push_back(v);
  }
  return d;
}

// The raw signal, at most ~1000 min/max pairs per axis, with the intervals shaded.
std::string SignalPlot(const Document& d, const ReportInput& input) {
  const RawLog& log = *input.log;
  const std::size_t n = log.samples.size();
  const bool timed = log.time_s.size() == n;
  const auto t_of = [&](std::size_t i) { return timed ? log.time_s[i] : static_cast<double>(i); };
  double lo = log.samples[0].minCoeff(), hi = log.samples[0].maxCoeff();
  for (const Vec3& s : log.samples)
    lo = std::min(lo, s.minCoeff()), hi = std::max(hi, s.maxCoeff());
  if (!Plottable(t_of(0), t_of(n - 1), lo, hi)) return NotPlotted("raw signal");
  const Frame2d f = Padded(t_of(0), t_of(n - 1), lo, hi);
  std::string body;
  const auto shade = [&](double a, double b, const char* cls, const std::string& tip) {
    body += "<rect class=\"" + std::string(cls) + "\" x=\"" + Px(f.X(a)) + "\" y=\"" + Px(f.top) +
            "\" width=\"" + Px(std::max(1.0, f.X(b) - f.X(a))) + "\" height=\"" + Px(f.height) +
            "\"><title>" + Escape(tip) + "</title></rect>\n";
  };
  for (std::size_t k = 0; k < d.positions.size(); ++k) {
    const PositionView& p = d.positions[k];
    std::optional<std::pair<double, double>> span = timed ? p.time : p.samples;
    if (!span) continue;
    shade(span->first, span->second, "interval", "position " + std::to_string(k + 1));
    body += "<text class=\"tick\" x=\"" + Px(f.X((span->first + span->second) / 2)) + "\" y=\"" +
            Px(f.top + 11) + "\" text-anchor=\"middle\">" + std::to_string(k + 1) + "</text>\n";
  }
  for (const RejectedInterval& r : input.rejected) {
    shade(timed ? r.t_begin_s : static_cast<double>(r.begin),
          timed ? r.t_end_s : static_cast<double>(r.end), "rejected", "not used: " + r.reason);
  }
  // Times are seconds from the first sample; a clock that does not start at 0 (an epoch time) is
  // stated once, here.
  const std::string time_label =
      log.time && log.time->origin_s != 0
          ? "time [s] from the first sample, at " + Format("%.15g", log.time->origin_s) + " s"
          : std::string("time [s]");
  body += Axes(f, timed ? time_label : "sample", "raw reading [" + d.cal.raw_unit + "]");
  const std::size_t buckets = std::min<std::size_t>(n, 1000);
  for (int a = 0; a < 3; ++a) {
    std::string points;
    for (std::size_t b = 0; b < buckets; ++b) {
      const std::size_t begin = b * n / buckets, end = std::max(begin + 1, (b + 1) * n / buckets);
      std::size_t i_min = begin, i_max = begin;
      for (std::size_t i = begin; i < end; ++i) {
        if (log.samples[i](a) < log.samples[i_min](a)) i_min = i;
        if (log.samples[i](a) > log.samples[i_max](a)) i_max = i;
      }
      for (const std::size_t i : {std::min(i_min, i_max), std::max(i_min, i_max)}) {
        points += Px(f.X(t_of(i))) + "," + Px(f.Y(log.samples[i](a))) + " ";
      }
    }
    body += "<polyline class=\"trace\" stroke=\"" + std::string(kAxisColor[a]) + "\" points=\"" +
            points + "\"/>\n";
  }
  body += Legend(f.left + 8, f.Bottom() + 50,
                 {{kAxisColor[0], "x"},
                  {kAxisColor[1], "y"},
                  {kAxisColor[2], "z"},
                  {"#cfd8e3", "static interval (used)"},
                  {"#f4c7c3", "still, not used"}});
  return Svg("raw-signal", 300, "raw signal with the static intervals", body);
}

// |f| − g per position: after calibration, held out, and before when the readings are forces.
std::string NormPlot(const Document& d) {
  const std::size_t m = d.positions.size();
  double lo = 0, hi = 0;
  for (const PositionView& p : d.positions) {
    for (const std::optional<double>& v : {std::optional<double>(p.after), p.held_out, p.before}) {
      if (v) lo = std::min(lo, *v), hi = std::max(hi, *v);
    }
  }
  if (!Plottable(0, static_cast<double>(m), lo, hi)) return NotPlotted("|f| - g per position");
  const Frame2d f = Padded(0.5, static_cast<double>(m) + 0.5, lo, hi);
  std::string body = Axes(f, "position", "|f| - g [" + d.unit + "]");
  body += "<line class=\"zero\" x1=\"" + Px(f.left) + "\" y1=\"" + Px(f.Y(0)) + "\" x2=\"" +
          Px(f.left + f.width) + "\" y2=\"" + Px(f.Y(0)) + "\"/>\n";
  for (std::size_t k = 0; k < m; ++k) {
    const PositionView& p = d.positions[k];
    const double x = f.X(static_cast<double>(k + 1));
    const std::string tip = "position " + std::to_string(k + 1);
    if (p.before) {
      body += "<rect class=\"before\" x=\"" + Px(x - 3) + "\" y=\"" + Px(f.Y(*p.before) - 3) +
              "\" width=\"6\" height=\"6\"><title>" + tip + " before: " + Short(*p.before) +
              "</title></rect>\n";
    }
    if (p.held_out) {
      body += "<circle class=\"held-out\" cx=\"" + Px(x) + "\" cy=\"" + Px(f.Y(*p.held_out)) +
              "\" r=\"4.5\"><title>" + tip + " held out: " + Short(*p.held_out) +
              "</title></circle>\n";
    }
    body += "<circle class=\"after\" cx=\"" + Px(x) + "\" cy=\"" + Px(f.Y(p.after)) +
            "\" r=\"3\"><title>" + tip + " after: " + Short(p.after) + "</title></circle>\n";
  }
  std::vector<std::pair<std::string, std::string>> legend = {{"#1f77b4", "after calibration"}};
  if (m > 0 && d.positions[0].held_out) legend.push_back({"#ff7f0e", "held out (fit without it)"});
  if (m > 0 && d.positions[0].before) legend.push_back({"#7f7f7f", "before (raw as force)"});
  body += Legend(f.left + 8, f.Bottom() + 50, legend);
  return Svg("norm-error", 300, "|f| - g per position", body);
}

// Lambert azimuthal equal-area projection of each hemisphere about its pole.
std::string SpherePlot(const Document& d) {
  std::string body;
  const double radius = 150, cy = 190;
  for (int h = 0; h < 2; ++h) {
    const double cx = 225 + 450 * h;
    const double sign = h == 0 ? 1.0 : -1.0;
    body += "<circle class=\"disc\" cx=\"" + Px(cx) + "\" cy=\"" + Px(cy) + "\" r=\"" + Px(radius) +
            "\"/>\n";
    for (const double polar_deg : {30.0, 60.0}) {  // circles of equal polar angle
      const double r = radius * std::sqrt(2.0) * std::sin(polar_deg * kPi / 360.0);
      body += "<circle class=\"grid\" cx=\"" + Px(cx) + "\" cy=\"" + Px(cy) + "\" r=\"" + Px(r) +
              "\" fill=\"none\"/>\n";
    }
    body += "<text class=\"label\" x=\"" + Px(cx) + "\" y=\"22\" text-anchor=\"middle\">" +
            std::string(h == 0 ? "upper hemisphere, z &gt; 0 (seen from +z)"
                               : "lower hemisphere, z &lt; 0 (seen from -z)") +
            "</text>\n";
    body +=
        "<text class=\"tick\" x=\"" + Px(cx + radius + 4) + "\" y=\"" + Px(cy + 4) + "\">+x</text>";
    body += "<text class=\"tick\" x=\"" + Px(cx - 6) + "\" y=\"" +
            Px(h == 0 ? cy - radius - 4 : cy + radius + 14) + "\">+y</text>\n";
    for (std::size_t k = 0; k < d.positions.size(); ++k) {
      const Vec3 c = d.positions[k].direction.normalized();
      if (!c.allFinite() || (h == 0) != (c(2) >= 0)) continue;
      // Projection about the pole sign·e_z: distance 2 sin(θ/2) = √(2(1 − sign z)); seen from
      // outside the sphere, so the lower disc mirrors y.
      const double s = std::sqrt(2.0 / (1.0 + sign * c(2)));
      const double px = cx + radius / std::sqrt(2.0) * s * c(0);
      const double py = cy - sign * radius / std::sqrt(2.0) * s * c(1);
      body += "<circle class=\"direction\" cx=\"" + Px(px) + "\" cy=\"" + Px(py) +
              "\" r=\"5\"><title>position " + std::to_string(k + 1) + ": (" + Short(c(0)) + ", " +
              Short(c(1)) + ", " + Short(c(2)) + ")</title></circle>\n";
    }
  }
  return Svg("sphere", 380, "measured gravity directions, body frame", body);
}

std::string ResidualPlot(const Document& d) {
  const std::size_t m = d.positions.size();
  double lo = 0, hi = 0;
  for (const PositionView& p : d.positions)
    lo = std::min(lo, p.residual.minCoeff()), hi = std::max(hi, p.residual.maxCoeff());
  if (!Plottable(0, static_cast<double>(m), lo, hi)) return NotPlotted("residuals per axis");
  const Frame2d f = Padded(0.5, static_cast<double>(m) + 0.5, lo, hi);
  std::string body = Axes(f, "position", "residual p - mu [" + d.cal.raw_unit + "]");
  body += "<line class=\"zero\" x1=\"" + Px(f.left) + "\" y1=\"" + Px(f.Y(0)) + "\" x2=\"" +
          Px(f.left + f.width) + "\" y2=\"" + Px(f.Y(0)) + "\"/>\n";
  const double dx = std::min(6.0, 0.25 * f.width / std::max<double>(1, static_cast<double>(m)));
  for (std::size_t k = 0; k < m; ++k) {
    for (int a = 0; a < 3; ++a) {
      const double x = f.X(static_cast<double>(k + 1)) + (a - 1) * dx;
      body += "<circle cx=\"" + Px(x) + "\" cy=\"" + Px(f.Y(d.positions[k].residual(a))) +
              "\" r=\"2.5\" fill=\"" + kAxisColor[a] + "\"><title>position " +
              std::to_string(k + 1) + " " + kAxisName[a] + ": " +
              Short(d.positions[k].residual(a)) + "</title></circle>\n";
    }
  }
  body += Legend(f.left + 8, f.Bottom() + 50,
                 {{kAxisColor[0], "x"}, {kAxisColor[1], "y"}, {kAxisColor[2], "z"}});
  return Svg("residuals", 300, "residuals per axis", body);
}

// Each position's residual against its time, per axis, with the fitted drift added back (what a
// constant bias leaves: the drift made visible), and with a drifting bias the fitted curve
// D φ(t) and its band ±1σ of b(t). An axis' points are the positions that see its bias, gravity
// within 60° of it (|c_i| > 0.5): a position sees a bias change only along gravity, so the
// others' residual on that axis is near zero whatever the drift. Empty when the positions have
// no times, or come from several files (each its own clock).
std::string DriftPlot(const Document& d) {
  const LoadedCalibration& cal = d.cal;
  std::vector<std::pair<double, Vec3>> points;
  std::vector<Vec3> directions;
  for (const FilePosition& p : cal.positions) {
    if (p.file.value_or(0) != cal.positions.front().file.value_or(0)) return "";  // two clocks
    directions.push_back(p.direction.value_or(Vec3::Ones()));
    const std::optional<double> t =
        p.time       ? p.time
        : p.interval ? std::optional<double>(0.5 * (p.interval->t_begin + p.interval->t_end))
                     : std::nullopt;
    if (!t || !p.residual) return "";
    points.push_back({*t, *p.residual + p.drift_offset.value_or(Vec3::Zero())});
  }
  if (points.size() < 2) return "";
  double t0 = points.front().first, t1 = t0, lo = 0, hi = 0;
  for (const auto& [t, v] : points) {
    t0 = std::min(t0, t), t1 = std::max(t1, t);
    lo = std::min(lo, v.minCoeff()), hi = std::max(hi, v.maxCoeff());
  }
  // The curve and its band at 200 times over the session.
  std::vector<double> times;
  std::vector<Vec3> curve, sigma;
  if (cal.drift) {
    int bias_slots[3] = {0, 0, 0};
    const auto& slots = ParameterSlots(cal.model, cal.frame);
    for (std::size_t s = 0; s < slots.size(); ++s) {
      if (slots[s].group == ParameterGroup::kBias) bias_slots[slots[s].row] = static_cast<int>(s);
    }
    for (int i = 0; i <= 200; ++i) {
      const double t = t0 + (t1 - t0) * i / 200.0;
      times.push_back(t);
      curve.push_back(cal.drift->Offset(t));
      const Vec3 s = cal.drift->BiasSigma(t, bias_slots);
      sigma.push_back(s.allFinite() ? s : Vec3::Zero());
      lo = std::min(lo, (curve.back() - sigma.back()).minCoeff());
      hi = std::max(hi, (curve.back() + sigma.back()).maxCoeff());
    }
  }
  if (!Plottable(t0, t1, lo, hi) || !(t1 > t0)) return NotPlotted("bias over the session");
  const Frame2d f = Padded(t0, t1, lo, hi);
  std::string body =
      Axes(f, "time [s]", (cal.drift ? "residual + drift [" : "residual [") + cal.raw_unit + "]");
  body += "<line class=\"zero\" x1=\"" + Px(f.left) + "\" y1=\"" + Px(f.Y(0)) + "\" x2=\"" +
          Px(f.left + f.width) + "\" y2=\"" + Px(f.Y(0)) + "\"/>\n";
  for (int a = 0; a < 3 && !times.empty(); ++a) {
    std::string band, line;
    for (std::size_t i = 0; i < times.size(); ++i) {
      band += Px(f.X(times[i])) + "," + Px(f.Y(curve[i](a) + sigma[i](a))) + " ";
      line += Px(f.X(times[i])) + "," + Px(f.Y(curve[i](a))) + " ";
    }
    for (std::size_t i = times.size(); i-- > 0;) {
      band += Px(f.X(times[i])) + "," + Px(f.Y(curve[i](a) - sigma[i](a))) + " ";
    }
    body += "<polygon points=\"" + band + "\" fill=\"" + kAxisColor[a] +
            "\" fill-opacity=\"0.15\" stroke=\"none\"/>\n";
    body += "<polyline class=\"trace\" stroke=\"" + std::string(kAxisColor[a]) + "\" points=\"" +
            line + "\"/>\n";
  }
  for (std::size_t k = 0; k < points.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      if (!(std::abs(directions[k](a)) > 0.5)) continue;
      body += "<circle cx=\"" + Px(f.X(points[k].first)) + "\" cy=\"" +
              Px(f.Y(points[k].second(a))) + "\" r=\"2.5\" fill=\"" + kAxisColor[a] +
              "\"><title>position " + std::to_string(k + 1) + " " + kAxisName[a] + " at " +
              Short(points[k].first) + " s: " + Short(points[k].second(a)) + "</title></circle>\n";
    }
  }
  body += Legend(f.left + 8, f.Bottom() + 50,
                 {{kAxisColor[0], "x"}, {kAxisColor[1], "y"}, {kAxisColor[2], "z"}});
  const std::string title =
      cal.drift ? "residuals with the fitted drift added back, and the drift D phi(t) +- 1 sigma "
                  "of the bias b(t) (" +
                      ToString(cal.drift->basis.model) + " bias)"
                : "residuals against time (a constant bias: a trend is a drift it leaves)";
  return Svg("drift", 300, title, body);
}

std::string Row(const std::string& quantity, double value, std::optional<double> sigma,
                const std::string& unit, const char* format = "%.6g") {
  return "<tr><td>" + Escape(quantity) + "</td><td class=\"num\">" + Format(format, value) +
         "</td><td class=\"num\">" + (sigma ? "&plusmn; " + Format("%.2g", *sigma) : "&ndash;") +
         "</td><td>" + Escape(unit) + "</td></tr>\n";
}

// ±1σ of the engineering quantities from the file's covariance; none without degrees of freedom.
std::optional<EngineeringStd> EngineeringSigmas(const Document& d) {
  if (d.cal.covariance.size() == 0) return std::nullopt;
  const LoadedCalibration& cal = d.cal;
  return EngineeringUncertainty(cal.params, cal.model, cal.frame, cal.gravity, cal.covariance);
}

std::string ParameterTable(const Document& d) {
  const LoadedCalibration& cal = d.cal;
  const std::optional<EngineeringStd> std_eng = EngineeringSigmas(d);
  const EngineeringParameters eng = ToEngineering(cal.params, cal.gravity);
  const Misalignment mis = MisalignmentOf(cal.params.K, cal.frame);
  const std::string scale_unit = cal.raw_unit + " per " + d.unit;
  std::string rows;
  for (int i = 0; i < 3; ++i) {
    rows += Row(std::string("scale factor ") + kAxisName[i], eng.scale_factor(i),
                std_eng ? std::optional(std_eng->scale_factor(i)) : std::nullopt, scale_unit);
  }
  for (Eigen::Index i = 0; i < mis.rad.size(); ++i) {
    rows +=
        Row("misalignment " + std::string(mis.names[static_cast<std::size_t>(i)]),
            mis.rad(i) * kArcsecPerRad,
            std_eng ? std::optional(std_eng->misalignment_rad(i) * kArcsecPerRad) : std::nullopt,
            "arcsec", "%.1f");
  }
  const double micro_g = 1e6 / cal.gravity;  // the calibration's g is 1 g
  for (int i = 0; i < 3; ++i) {
    rows +=
        Row(std::string("bias ") + kAxisName[i], eng.bias_force(i) * micro_g,
            std_eng ? std::optional(std_eng->bias_force(i) * micro_g) : std::nullopt, "µg", "%.1f");
  }
  if (cal.model == ModelKind::kQuadratic) {
    for (int i = 0; i < 3; ++i) {
      rows += Row(std::string("squared coefficient ") + kAxisName[i], eng.k2_g_per_g2(i),
                  std_eng ? std::optional(std_eng->k2_g_per_g2(i)) : std::nullopt, "g/g²", "%.3g");
    }
  }
  return "<table id=\"parameters\"><thead><tr><th>quantity</th><th>value</th><th>1σ</th>"
         "<th>unit</th></tr></thead><tbody>\n" +
         rows + "</tbody></table>\n" +
         (std_eng ? "" : "<p>No uncertainties: the fit had no degrees of freedom left.</p>\n");
}

// The gyroscope's section: its parameters ±1σ, each turn's direction error (fitted and held
// out), and each still position's mean rate beside the fitted bias and g-sensitivity.
std::string GyroSection(const Document& d) {
  const UnitGyroscope& g = *d.cal.gyroscope;
  const auto deg = [](double v) {
    return std::isfinite(v) ? Format("%.3g", v) + " deg" : std::string("n/a");
  };
  std::string html = "<section id=\"gyroscope\"><h2>Gyroscope</h2>\n<dl>\n";
  html += Item("model", std::string(ToString(g.model)) + ", w_raw = K w + b + G f" + ", " +
                            std::string(ToString(g.estimator)) + " fit");
  html += Item("rotations", std::to_string(g.rotations.size()) + " turns; direction error RMS " +
                                deg(g.rms_deg) + ", held out " + deg(g.heldout_rms_deg));
  std::string scales;
  for (int i = 0; i < 3; ++i) scales += (i ? ", " : "") + Format("%.8g", g.params.K.row(i).norm());
  html += Item("scale factors", scales + " " + g.raw_unit + " per rad/s (row norms of K)");
  if (g.thermal) {
    std::string text = Format("degree %d", g.thermal->bias.degree());
    if (g.thermal->bias.degree() > 0) {
      text += Format(", b(T) = b + sum_d b_d (T - T_ref)^d, the bias below at T_ref = %.6g degC; ",
                     g.thermal->bias.t_ref_c);
      for (int k = 1; k <= g.thermal->bias.degree(); ++k) {
        const Vec3& b = g.thermal->bias.coefficients[static_cast<std::size_t>(k - 1)];
        text += Format("%sb_%d = (%.4g, %.4g, %.4g) %s per K^%d", k > 1 ? "; " : "", k, b(0), b(1),
                       b(2), g.raw_unit.c_str(), k);
      }
    } else {
      text += " (the offsets constant over temperature)";
    }
    text += Format("; still positions from %.4g to %.4g degC", g.thermal->range_c.first,
                   g.thermal->range_c.second);
    html += Item("offsets over temperature", text);
  }
  html += "</dl>\n";
  // The parameters in their file order, ±1σ.
  const std::vector<SensorParameter> parameters = ListParameters(g.params, g.model);
  std::string rows;
  for (std::size_t p = 0; p < parameters.size(); ++p) {
    const auto i = static_cast<Eigen::Index>(p);
    const std::string unit = ParameterUnit(parameters[p].role, g.raw_unit, "rad/s", d.unit);
    const std::string name(parameters[p].name);
    if (g.covariance.rows() > i) {
      const double sigma = std::sqrt(std::max(0.0, g.covariance(i, i)));
      rows += Row(name, parameters[p].value, sigma, unit, "%.8g");
    } else {
      rows += Row(name, parameters[p].value, std::nullopt, unit, "%.8g");
    }
  }
  html +=
      "<table id=\"gyro-parameters\"><thead><tr><th>parameter</th><th>value</th><th>1σ</th>"
      "<th>unit</th></tr></thead><tbody>\n" +
      rows + "</tbody></table>\n";
  // Each turn's error: the angle between the direction it predicts and the fitted one.
  if (!g.rotations.empty()) {
    const std::size_t n = g.rotations.size();
    double lo = 0, hi = 0;
    for (const auto& r : g.rotations) {
      const double heldout = std::isfinite(r.heldout_deg) ? r.heldout_deg : 0.0;
      lo = std::min({lo, r.residual_deg, heldout});
      hi = std::max({hi, r.residual_deg, heldout});
    }
    if (!Plottable(0, static_cast<double>(n), lo, hi))
      return html + NotPlotted("turns") + "</section>\n";
    const Frame2d f = Padded(0.5, static_cast<double>(n) + 0.5, lo, hi);
    std::string body = Axes(f, "turn", "direction error [deg]");
    for (std::size_t k = 0; k < n; ++k) {
      const auto& r = g.rotations[k];
      const double x = f.X(static_cast<double>(k + 1));
      const std::string tip = Format("turn %zu (position %zu to %zu)", k + 1, r.from + 1, r.to + 1);
      if (std::isfinite(r.heldout_deg)) {
        body += "<circle class=\"held-out\" cx=\"" + Px(x) + "\" cy=\"" + Px(f.Y(r.heldout_deg)) +
                "\" r=\"4.5\"><title>" + tip + " held out: " + Short(r.heldout_deg) +
                " deg</title></circle>\n";
      }
      body += "<circle class=\"after\" cx=\"" + Px(x) + "\" cy=\"" + Px(f.Y(r.residual_deg)) +
              "\" r=\"3\"><title>" + tip + ": " + Short(r.residual_deg) +
              (std::isfinite(r.turned_deg) ? " deg, turned through " + Short(r.turned_deg)
                                           : std::string()) +
              " deg</title></circle>\n";
    }
    std::vector<std::pair<std::string, std::string>> legend = {{"#1f77b4", "fitted"}};
    if (std::isfinite(g.rotations[0].heldout_deg))
      legend.push_back({"#ff7f0e", "held out (fit without it)"});
    body += Legend(f.left + 8, f.Bottom() + 50, legend);
    html += Svg("gyro-rotations", 300, "direction error of each turn", body);
  }
  // Each still position's mean rate less the bias, beside G f of its fitted direction.
  bool directions = g.still_spans.size() == d.cal.positions.size() && !g.still_spans.empty();
  for (const FilePosition& p : d.cal.positions) directions = directions && p.direction.has_value();
  if (directions) {
    const std::size_t m = g.still_spans.size();
    std::vector<Vec3> measured, modelled;
    double lo = 0, hi = 0;
    // A position the gyro turned throughout (its still rate NaN) is not drawn.
    std::vector<bool> drawn(m, true);
    for (std::size_t k = 0; k < m; ++k) {
      measured.push_back(g.still_spans[k].mean_raw - g.params.bias);
      modelled.push_back(g.params.G * (d.cal.gravity * *d.cal.positions[k].direction));
      if (!g.still_spans[k].still && modelled.back().allFinite()) {
        drawn[k] = false;
        continue;
      }
      if (!measured.back().allFinite() || !modelled.back().allFinite()) {
        return html + NotPlotted("still rates") + "</section>\n";
      }
      lo = std::min({lo, measured.back().minCoeff(), modelled.back().minCoeff()});
      hi = std::max({hi, measured.back().maxCoeff(), modelled.back().maxCoeff()});
    }
    if (!Plottable(0, static_cast<double>(m), lo, hi)) {
      return html + NotPlotted("still rates") + "</section>\n";
    }
    const Frame2d f = Padded(0.5, static_cast<double>(m) + 0.5, lo, hi);
    std::string body = Axes(f, "position", "still rate - bias [" + g.raw_unit + "]");
    const double dx = std::min(6.0, 0.25 * f.width / static_cast<double>(m));
    for (std::size_t k = 0; k < m; ++k) {
      if (!drawn[k]) continue;
      for (int a = 0; a < 3; ++a) {
        const double x = f.X(static_cast<double>(k + 1)) + (a - 1) * dx;
        const std::string tip = "position " + std::to_string(k + 1) + " " + kAxisName[a];
        body += "<circle cx=\"" + Px(x) + "\" cy=\"" + Px(f.Y(modelled[k](a))) +
                "\" r=\"4.5\" fill=\"none\" stroke=\"" + kAxisColor[a] + "\"><title>" + tip +
                " G f: " + Short(modelled[k](a)) + "</title></circle>\n";
        body += "<circle cx=\"" + Px(x) + "\" cy=\"" + Px(f.Y(measured[k](a))) +
                "\" r=\"2.5\" fill=\"" + kAxisColor[a] + "\"><title>" + tip +
                " measured: " + Short(measured[k](a)) + "</title></circle>\n";
      }
    }
    body += Legend(f.left + 8, f.Bottom() + 50,
                   {{kAxisColor[0], "x"}, {kAxisColor[1], "y"}, {kAxisColor[2], "z"}});
    html +=
        "<p>Still rates less the fitted bias (dots) beside the fitted g-sensitivity G f "
        "(rings): what the model leaves is the difference.</p>\n" +
        Svg("gyro-stills", 300, "still-position rates against bias and g-sensitivity", body);
  }
  return html + "</section>\n";
}

// The calibration file's own diagnosis (diagnosis.hpp), and the still periods not used that the
// report's log shows, when the file does not list them already. Warnings and failures only; notes
// are listed apart.
std::vector<std::string> Warnings(const Document& d, const ReportInput& input, bool notes = false) {
  std::vector<std::string> w;
  if (!d.cal.diagnostics) {
    if (!notes) {
      w.push_back(
          "the calibration file carries no diagnosis (written by an earlier accelcal): "
          "calibrate again to have it checked");
    }
    return w;
  }
  bool has_periods = false;
  for (const Finding& f : *d.cal.diagnostics) {
    has_periods = has_periods || f.code == "rejected_period";
    if ((f.severity == Severity::kNote) != notes) continue;
    w.push_back((f.severity == Severity::kFailure ? "FAILED: " : "") + f.message);
  }
  if (!has_periods) {
    for (const Finding& f : RejectedPeriodFindings(input.rejected)) {
      if ((f.severity == Severity::kNote) == notes) w.push_back(f.message);
    }
  }
  return w;
}

std::string Render(const ReportInput& input) {
  const Document d = Read(input);
  const std::string source = d.cal.source.empty() ? input.calibration_name : d.cal.source;
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>accelcal report: " +
      Escape(source) + "</title>\n<style>\n" + kStyle +
      "</style>\n</head>\n<body>\n<h1>Accelerometer calibration: " + Escape(source) + "</h1>\n";
  const SolverRecord& solver = d.cal.solver;
  html += "<section id=\"summary\"><dl>\n";
  html += Item("model", std::string(ToString(d.cal.model)) + ", frame " +
                            std::string(ToString(d.cal.frame)));
  html += Item("method", (solver.method.empty() ? std::string("?") : solver.method) + " (" +
                             solver.estimator + "), " +
                             (solver.iterations ? std::to_string(*solver.iterations) : "?") +
                             " iterations, " + (solver.converged ? "converged" : "NOT converged"));
  html += Item("positions", std::to_string(d.positions.size()));
  if (const std::optional<ThermalTerms>& t = d.cal.thermal) {
    std::string text = "degrees " + t->params.degrees.ToString() +
                       Format(", the parameters below at T_ref = %.6g degC", t->params.t_ref_c);
    if (d.cal.thermal_range_c) {
      text += Format("; positions from %.4g to %.4g degC", d.cal.thermal_range_c->first,
                     d.cal.thermal_range_c->second);
    }
    html += Item("temperature", text + " (the coefficients: the file's thermal section)");
  }
  html += Item("gravity", Format("%.6g", d.cal.gravity) + " " + d.unit);
  const auto rms = [&](const std::optional<double>& value) -> std::string {
    return value ? Short(*value) + " " + d.unit : "n/a";
  };
  html += Item("RMS of |f| - g", "before " + rms(d.cal.gravity_norm_rms_before) + ", after " +
                                     rms(d.cal.gravity_norm_rms_after) + ", held out " +
                                     rms(d.cal.crossval_rms));
  html += "</dl></section>\n";
  const std::vector<std::string> warnings = Warnings(d, input);
  html += "<section id=\"warnings\"><h2>Warnings</h2>\n<p>Verdict: <b>" +
          Escape(d.cal.verdict.empty() ? std::string("not recorded") : d.cal.verdict) +
          "</b></p>\n";
  if (warnings.empty()) {
    html += "<p>None.</p>\n";
  } else {
    html += "<ul class=\"warn\">\n";
    for (const std::string& w : warnings) html += "<li>" + Escape(w) + "</li>\n";
    html += "</ul>\n";
  }
  const std::vector<std::string> notes = Warnings(d, input, true);
  if (!notes.empty()) {
    html += "<h3>Notes</h3>\n<ul class=\"note\">\n";
    for (const std::string& n : notes) html += "<li>" + Escape(n) + "</li>\n";
    html += "</ul>\n";
  }
  html += "</section>\n<section><h2>Parameters</h2>\n" + ParameterTable(d) + "</section>\n";
  html += "<section><h2>Raw signal and static intervals</h2>\n";
  if (input.log != nullptr && !input.log->samples.empty()) {
    html += SignalPlot(d, input);
  } else {
    html += "<p>No raw log was given (<code>accelcal report CAL.json LOG</code> shows it).</p>\n";
  }
  html += "</section>\n<section><h2>|f| - g per position</h2>\n" + NormPlot(d) + "</section>\n";
  html += "<section><h2>Coverage of the sphere</h2>\n" + SpherePlot(d) + "</section>\n";
  html += "<section><h2>Residuals per axis</h2>\n" + ResidualPlot(d) + "</section>\n";
  if (const std::string drift = DriftPlot(d); !drift.empty()) {
    html += "<section><h2>Bias over the session</h2>\n" + drift + "</section>\n";
  }
  if (d.cal.has_gyroscope()) html += GyroSection(d);
  html += "<footer><p>accelcal " + Escape(source) + "</p></footer>\n</body>\n</html>\n";
  return html;
}

}  // namespace

std::vector<std::string> ReportWarnings(const ReportInput& input) {
  return Warnings(Read(input), input);
}

std::string RenderReport(const ReportInput& input) { return Render(input); }

}  // namespace accelcal
