// The HTML noise report (noise_report.hpp).
#include "accelcal/noise_report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "output/html_svg.hpp"

namespace accelcal {

namespace {

using namespace internal::html;  // NOLINT: the page's shared pieces

constexpr double kHeight = 300;  // of a plot's frame

// One sensor's log-log plot: per axis the band between the deviation's confidence limits, the
// estimates, and the fitted model as a line through its value at each averaging time.
std::string AllanPlot(const NoiseReportSensor& s, std::size_t index) {
  const NoiseAnalysis& n = *s.analysis;
  double tx0 = std::numeric_limits<double>::infinity(), tx1 = -tx0, ty0 = tx0, ty1 = -tx0;
  for (const AxisNoise& axis : n.axes) {
    for (std::size_t i = 0; i < axis.points.size(); ++i) {
      const double tau = axis.points[i].tau_s;
      const AllanInterval& band = axis.fit.intervals[i];
      if (!(tau > 0) || !(band.low > 0) || !(band.high > 0)) continue;
      tx0 = std::min(tx0, std::log10(tau));
      tx1 = std::max(tx1, std::log10(tau));
      ty0 = std::min(ty0, std::log10(band.low));
      ty1 = std::max(ty1, std::log10(band.high));
    }
  }
  const std::string title = s.name + ": Allan deviation";
  if (!(tx1 >= tx0) || !(ty1 >= ty0) || !Plottable(tx0, tx1, ty0, ty1)) {
    return "<p>" + Escape(title) + ": no averaging time to plot.</p>\n";
  }
  Frame2d f = Padded(tx0, tx1, ty0, ty1);
  f.height = kHeight;
  std::string body = LogAxes(f, "averaging time tau [s]", "sigma(tau) [" + s.sample_unit + "]");
  for (int a = 0; a < 3; ++a) {
    const AxisNoise& axis = n.axes[std::size_t(a)];
    const std::string color = kAxisColor[a];
    std::string upper, lower, dots;
    for (std::size_t i = 0; i < axis.points.size(); ++i) {
      const double tau = axis.points[i].tau_s;
      const AllanInterval& band = axis.fit.intervals[i];
      if (!(tau > 0) || !(band.low > 0) || !(band.high > 0) || !(axis.points[i].avar > 0)) {
        continue;
      }
      const double x = f.X(std::log10(tau));
      upper += Px(x) + "," + Px(f.Y(std::log10(band.high))) + " ";
      lower = Px(x) + "," + Px(f.Y(std::log10(band.low))) + " " + lower;
      dots += "<circle cx=\"" + Px(x) + "\" cy=\"" +
              Px(f.Y(std::log10(std::sqrt(axis.points[i].avar)))) + "\" r=\"2.5\" fill=\"" + color +
              "\"/>";
    }
    body += "<polygon class=\"band\" fill=\"" + color + "\" points=\"" + upper + lower + "\"/>\n";
    // The fit as it was made: its model at each averaging time (a term the fit put below 0
    // included, as the fit has it; the table shows such a term clamped at 0).
    std::string line;
    for (std::size_t i = 0; i < axis.points.size() && i < axis.fit.model_avar.size(); ++i) {
      const double tau = axis.points[i].tau_s, avar = axis.fit.model_avar[i];
      if (!(tau > 0) || !(avar > 0)) continue;
      const double ly = std::clamp(0.5 * std::log10(avar), f.y0, f.y1);
      line += Px(f.X(std::log10(tau))) + "," + Px(f.Y(ly)) + " ";
    }
    body += "<polyline class=\"model\" stroke=\"" + color + "\" points=\"" + line + "\"/>\n" +
            dots + "\n";
  }
  body += Legend(f.left + 10, f.top + 16,
                 {{kAxisColor[0], "x"}, {kAxisColor[1], "y"}, {kAxisColor[2], "z"}});
  return Svg("allan-" + std::to_string(index), f.Bottom() + 44, title, body);
}

std::string TermCell(const NoiseTermEstimate& e, double factor) {
  if (!e.fitted) return "-";
  if (!e.resolved) return e.high > 0 ? "&lt; " + Format("%.3g", e.high * factor) : "below 0";
  return Format("%.4g &plusmn; %.2g", e.value * factor, e.sigma * factor);
}

std::string TermTable(const NoiseReportSensor& s) {
  // White noise first: the figure a data sheet and an estimator ask for (as the text output).
  const int order[kNoiseTerms] = {1, 2, 3, 0, 4};
  std::string t = "<table><tr><th>axis</th>";
  for (const int term : order) {
    t += "<th>" + Escape(std::string(ToString(NoiseTerm(term)))) + " [" +
         Escape(s.term_unit[std::size_t(term)]) + "]</th>";
  }
  t += "</tr>\n";
  for (int a = 0; a < 3; ++a) {
    t += std::string("<tr><td>") + kAxisName[a] + "</td>";
    for (const int term : order) {
      t += "<td class=\"num\">" +
           TermCell(s.analysis->axes[std::size_t(a)].fit.terms[std::size_t(term)],
                    s.term_factor[std::size_t(term)]) +
           "</td>";
    }
    t += "</tr>\n";
  }
  t += "</table>\n";
  std::string notes;
  for (int a = 0; a < 3; ++a) {
    for (const std::string& note : s.notes[std::size_t(a)]) {
      notes += std::string("<li>") + kAxisName[a] + ": " + Escape(note) + "</li>\n";
    }
  }
  if (!notes.empty()) t += "<ul class=\"note\">\n" + notes + "</ul>\n";
  return t;
}

}  // namespace

std::string RenderNoiseReport(const NoiseReportInput& input) {
  for (const NoiseReportSensor& s : input.sensors) {
    if (s.analysis == nullptr) throw std::invalid_argument("RenderNoiseReport: no analysis");
  }
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>accelcal noise: " +
      Escape(input.title) + "</title>\n<style>\n" + kStyle +
      ".band{fill-opacity:0.18;stroke:none}.model{fill:none;stroke-width:1.5}\n"
      "</style>\n</head>\n<body>\n<h1>Noise: " +
      Escape(input.title) + "</h1>\n";
  html += "<section id=\"summary\"><dl>\n";
  html += Item("verdict", input.verdict);
  html += Item("time", input.time_note);
  for (const NoiseReportSensor& s : input.sensors) {
    const NoiseAnalysis& n = *s.analysis;
    html += Item(s.name,
                 Format("%s: %zu samples at %.6g Hz (%.1f s), in %s", s.source.c_str(), n.samples,
                        1 / n.sample_period_s, static_cast<double>(n.samples) * n.sample_period_s,
                        s.sample_unit.c_str()));
  }
  html += Item("model",
               "sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2 "
               "(IEEE Std 952 Annex C), fitted to the overlapping Allan variance; bands: 95 % "
               "confidence of each estimate (equivalent degrees of freedom); lines: the fit; "
               "terms +- 1 sigma, \"< x\": not resolved, 95 % upper bound");
  html += "</dl></section>\n";
  for (std::size_t i = 0; i < input.sensors.size(); ++i) {
    const NoiseReportSensor& s = input.sensors[i];
    html += "<section><h2>" + Escape(s.name) + "</h2>\n" + AllanPlot(s, i) + TermTable(s) +
            "</section>\n";
  }
  html += "<footer><p>accelcal noise " + Escape(input.title) + "</p></footer>\n</body>\n</html>\n";
  return html;
}

}  // namespace accelcal
