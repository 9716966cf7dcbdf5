#pragma once
// The HTML pages' shared pieces (report.hpp's calibration report, noise_report.hpp's noise
// report): escaping, numbers in the "C" locale, plot frames with linear or decade axes, the SVG
// element, legends and the style sheet. Hand-written inline SVG, no scripts.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/text_format.hpp"

namespace accelcal::internal::html {

inline constexpr const char* kAxisColor[3] = {"#d62728", "#2ca02c", "#1f77b4"};
inline constexpr const char* kAxisName[3] = {"x", "y", "z"};

using internal::Format;  // printf in the "C" locale: 0.5, never 0,5
inline std::string Px(double v) { return Format("%.1f", v); }
inline std::string Short(double v) { return Format("%.4g", v); }

inline std::string Escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// About `target` round tick values covering [lo, hi].
inline std::vector<double> NiceTicks(double lo, double hi, int target = 5) {
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw) break;
  }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

// A plot frame mapping data coordinates into a rectangle of the SVG.
struct Frame2d {
  double x0, x1, y0, y1;
  double left = 70, top = 14, width = 800, height = 220;
  double X(double x) const { return left + (x - x0) / (x1 - x0) * width; }
  double Y(double y) const { return top + height - (y - y0) / (y1 - y0) * height; }
  double Bottom() const { return top + height; }
};

// One entry of a summary's definition list.
inline std::string Item(const std::string& key, const std::string& value) {
  return "<dt>" + Escape(key) + "</dt><dd>" + Escape(value) + "</dd>\n";
}

// A plot's ranges must be finite: a file's value near the largest double (1e308) reads, but its
// span overflows and every coordinate would be NaN.
inline bool Plottable(double x0, double x1, double y0, double y1) {
  return std::isfinite(x1 - x0) && std::isfinite(y1 - y0) && std::isfinite(2 * (y1 - y0));
}

inline std::string NotPlotted(const std::string& title) {
  return "<p>" + Escape(title) +
         ": not plotted, its values span more than a plot can (a value near 1e308 in the "
         "file?).</p>\n";
}

inline Frame2d Padded(double x0, double x1, double y0, double y1) {
  if (!(x1 > x0)) x0 -= 0.5, x1 += 0.5;
  if (!(y1 > y0)) {
    const double pad = std::max(std::abs(y0) * 0.1, 1e-12);
    y0 -= pad, y1 += pad;
  }
  const double pad = 0.05 * (y1 - y0);
  return Frame2d{x0, x1, y0 - pad, y1 + pad};
}

// A frame's rectangle, its grid lines and tick labels at `x_ticks`, `y_ticks` (in its
// coordinates, labelled by `label`) and its two axis labels.
template <typename Label>
std::string FrameAxes(const Frame2d& f, const std::vector<double>& x_ticks,
                      const std::vector<double>& y_ticks, const Label& label,
                      const std::string& x_label, const std::string& y_label) {
  std::string s = "<rect class=\"frame\" x=\"" + Px(f.left) + "\" y=\"" + Px(f.top) +
                  "\" width=\"" + Px(f.width) + "\" height=\"" + Px(f.height) + "\"/>\n";
  for (const double t : x_ticks) {
    s += "<line class=\"grid\" x1=\"" + Px(f.X(t)) + "\" y1=\"" + Px(f.top) + "\" x2=\"" +
         Px(f.X(t)) + "\" y2=\"" + Px(f.Bottom()) + "\"/><text class=\"tick\" x=\"" + Px(f.X(t)) +
         "\" y=\"" + Px(f.Bottom() + 14) + "\" text-anchor=\"middle\">" + label(t) + "</text>\n";
  }
  for (const double t : y_ticks) {
    s += "<line class=\"grid\" x1=\"" + Px(f.left) + "\" y1=\"" + Px(f.Y(t)) + "\" x2=\"" +
         Px(f.left + f.width) + "\" y2=\"" + Px(f.Y(t)) + "\"/><text class=\"tick\" x=\"" +
         Px(f.left - 6) + "\" y=\"" + Px(f.Y(t) + 4) + "\" text-anchor=\"end\">" + label(t) +
         "</text>\n";
  }
  s += "<text class=\"label\" x=\"" + Px(f.left + f.width / 2) + "\" y=\"" + Px(f.Bottom() + 32) +
       "\" text-anchor=\"middle\">" + Escape(x_label) + "</text>\n";
  s += "<text class=\"label\" transform=\"translate(14 " + Px(f.top + f.height / 2) +
       ") rotate(-90)\" text-anchor=\"middle\">" + Escape(y_label) + "</text>\n";
  return s;
}

inline std::string Axes(const Frame2d& f, const std::string& x_label, const std::string& y_label) {
  return FrameAxes(f, NiceTicks(f.x0, f.x1, 8), NiceTicks(f.y0, f.y1, 5), Short, x_label, y_label);
}

inline std::string Svg(const std::string& id, double height, const std::string& title,
                       const std::string& body) {
  return "<svg id=\"" + id + "\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 900 " +
         Px(height) + "\" role=\"img\"><title>" + Escape(title) + "</title>\n" + body + "</svg>\n";
}

inline std::string Legend(double x, double y,
                          const std::vector<std::pair<std::string, std::string>>& items) {
  std::string s;
  for (const auto& [color, label] : items) {
    s += "<circle cx=\"" + Px(x) + "\" cy=\"" + Px(y - 4) + "\" r=\"4\" fill=\"" + color +
         "\"/><text class=\"tick\" x=\"" + Px(x + 8) + "\" y=\"" + Px(y) + "\">" + Escape(label) +
         "</text>";
    x += 24 + 7.0 * static_cast<double>(label.size());
  }
  return s + "\n";
}

inline const char* const kStyle =
    R"(body{font:14px/1.45 system-ui,sans-serif;max-width:940px;margin:24px auto;color:#222}
h1{font-size:22px}h2{font-size:17px;margin-top:28px}svg{width:100%;height:auto;display:block}
.frame{fill:none;stroke:#888}.grid{stroke:#e3e3e3}.tick{font-size:11px;fill:#444}.label{font-size:12px;fill:#222}
.zero{stroke:#555;stroke-dasharray:4 3}.trace{fill:none;stroke-width:1}.interval{fill:#cfd8e3}.rejected{fill:#f4c7c3}
.after{fill:#1f77b4}.held-out{fill:none;stroke:#ff7f0e;stroke-width:1.5}.before{fill:#7f7f7f}
.disc{fill:#f7f7f7;stroke:#888}.direction{fill:#1f77b4;stroke:#fff}
table{border-collapse:collapse}td,th{padding:3px 10px;border-bottom:1px solid #ddd;text-align:left}
td.num{text-align:right;font-variant-numeric:tabular-nums}.warn li{color:#a33}dl{display:grid;grid-template-columns:max-content auto;gap:2px 16px}dd{margin:0}
)";

// Decade ticks of a log10 axis: the whole powers of ten within [lo, hi] (log10 values), labelled
// "1e-3" style; when the span holds fewer than two, the ends.
inline std::vector<double> DecadeTicks(double lo, double hi) {
  std::vector<double> ticks;
  for (double t = std::ceil(lo); t <= hi + 1e-9; t += 1) ticks.push_back(t);
  if (ticks.size() < 2) ticks = {lo, hi};
  return ticks;
}

// Axes of a frame whose coordinates are log10 of the data on both axes.
inline std::string LogAxes(const Frame2d& f, const std::string& x_label,
                           const std::string& y_label) {
  const auto label = [](double t) { return Format("%.3g", std::pow(10.0, t)); };
  return FrameAxes(f, DecadeTicks(f.x0, f.x1), DecadeTicks(f.y0, f.y1), label, x_label, y_label);
}

}  // namespace accelcal::internal::html
