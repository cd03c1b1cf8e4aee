#include "tools/report/comparison_html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace photopose::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Line plot geometry (SVG user units).
constexpr double kWidth = 680.0;
constexpr double kHeight = 380.0;
constexpr double kLeft = 72.0;
constexpr double kRight = 200.0;  // room for the legend
constexpr double kTop = 34.0;
constexpr double kBottom = 52.0;

// Colour-blind-safe palette (Okabe-Ito, then darker variants), cycled.
const char* const kColors[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00",
                               "#56B4E9", "#000000", "#8C510A", "#762A83", "#1B7837"};
constexpr int kNumColors = sizeof(kColors) / sizeof(kColors[0]);

std::string Number(double value, const char* format = "%g") {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// A "nice" tick step (1, 2 or 5 times a power of ten) for about `count` intervals over `range`.
double NiceStep(double range, int count) {
  const double raw = range / count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double factor : {1.0, 2.0, 5.0, 10.0})
    if (factor * magnitude >= raw) return factor * magnitude;
  return 10.0 * magnitude;
}

std::string TickLabel(double value) {
  if (value == 0.0) return "0";
  const double magnitude = std::abs(value);
  if (magnitude < 1e-3 || magnitude >= 1e5) return Number(value, "%.0e");
  return Number(value, "%g");
}

struct Axis {
  double lo = 0.0, hi = 1.0;
  bool log = false;
  // Position of a value in [0, 1] along the axis.
  double Fraction(double value) const {
    if (log) {
      const double v = value > 0.0 ? std::log10(value) : lo;
      return (std::clamp(v, lo, hi) - lo) / (hi - lo);
    }
    return (value - lo) / (hi - lo);
  }
  std::vector<double> Ticks() const {
    std::vector<double> ticks;
    if (log) {
      const int step = std::max(1, static_cast<int>(std::ceil((hi - lo) / 8.0)));
      for (int e = static_cast<int>(lo); e <= static_cast<int>(hi); e += step) {
        ticks.push_back(std::pow(10.0, e));
        // Few decades: 2 and 5 times each power of ten as well.
        if (hi - lo <= 2.0 && e < static_cast<int>(hi))
          for (double f : {2.0, 5.0}) ticks.push_back(f * std::pow(10.0, e));
      }
      return ticks;
    }
    const double step = NiceStep(hi - lo, 5);
    for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
      ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
    return ticks;
  }
};

Axis LinearAxis(double lo, double hi, bool from_zero) {
  if (from_zero && lo >= 0.0) lo = 0.0;
  if (!(hi > lo)) {
    const double pad = lo == 0.0 ? 1.0 : 0.1 * std::abs(lo);
    lo -= pad;
    hi += pad;
    if (from_zero && lo < 0.0 && hi > 0.0) lo = 0.0;
  } else {
    const double step = NiceStep(hi - lo, 5);
    lo = std::floor(lo / step + 1e-9) * step;
    hi = std::ceil(hi / step - 1e-9) * step;
  }
  Axis axis;
  axis.lo = lo;
  axis.hi = hi;
  return axis;
}

std::string Text(double x, double y, const std::string& text, const char* anchor = "middle",
                 const std::string& extra = "") {
  std::ostringstream out;
  out << "<text x=\"" << Number(x, "%.1f") << "\" y=\"" << Number(y, "%.1f") << "\" text-anchor=\""
      << anchor << "\"" << extra << ">" << HtmlEscape(text) << "</text>";
  return out.str();
}

// An open <path> element drawing marker shape `index` (circle, square, triangle, diamond, cycled)
// of half-size r at (x, y); the caller closes it (so a <title> can go inside).
std::string Marker(size_t index, double x, double y, double r, const char* color) {
  std::ostringstream d;
  auto p = [](double v) { return Number(v, "%.1f"); };
  switch (index % 4) {
    case 0:  // circle, as two arcs
      d << "M" << p(x - r) << "," << p(y) << "a" << p(r) << "," << p(r) << " 0 1,0 " << p(2 * r)
        << ",0a" << p(r) << "," << p(r) << " 0 1,0 " << p(-2 * r) << ",0Z";
      break;
    case 1:  // square
      d << "M" << p(x - r) << "," << p(y - r) << "h" << p(2 * r) << "v" << p(2 * r) << "h"
        << p(-2 * r) << "Z";
      break;
    case 2:  // triangle
      d << "M" << p(x) << "," << p(y - 1.2 * r) << "L" << p(x + 1.1 * r) << "," << p(y + r) << "L"
        << p(x - 1.1 * r) << "," << p(y + r) << "Z";
      break;
    default:  // diamond
      d << "M" << p(x) << "," << p(y - 1.3 * r) << "L" << p(x + 1.3 * r) << "," << p(y) << "L"
        << p(x) << "," << p(y + 1.3 * r) << "L" << p(x - 1.3 * r) << "," << p(y) << "Z";
  }
  return "<path d=\"" + d.str() + "\" fill=\"" + color +
         "\" stroke=\"#ffffff\" stroke-width=\"0.5\">";
}

std::string SvgOpen(double width, double height, const std::string& title) {
  std::ostringstream out;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << width << " " << height
      << "\" width=\"" << width << "\" height=\"" << height << "\" role=\"img\" aria-label=\""
      << HtmlEscape(title) << "\" font-family=\"sans-serif\" font-size=\"12\">"
      << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>";
  return out.str();
}

// The x value of a setting along `axis` and the axis label.
std::string AxisLabel(const std::string& axis) {
  if (axis == "noise") return "image noise (px, one sigma)";
  if (axis == "outliers") return "outlier fraction (%)";
  if (axis == "control") return "control points per image";
  return "initial angle error (+- deg per angle)";
}

double PlotX(const SweepSetting& setting, const std::string& axis) {
  const double value = AxisValue(setting, axis);
  return axis == "outliers" ? 100.0 * value : value;
}

const char kStyle[] =
    "body{font-family:sans-serif;margin:2em auto;max-width:1400px;color:#222;padding:0 1em}"
    "h1{font-size:1.5em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}"
    "table{border-collapse:collapse;margin:1em 0;font-size:0.85em}"
    "caption{text-align:left;font-weight:bold;padding:0.3em 0}"
    "th,td{border:1px solid #ccc;padding:0.2em 0.5em;text-align:right;white-space:nowrap}"
    "th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}"
    "ul.notes{font-size:0.85em;color:#444}"
    ".plots{display:flex;flex-wrap:wrap;gap:1em}.plots svg{border:1px solid #ddd}"
    "code,pre{background:#f6f6f6;padding:0.1em 0.3em;white-space:pre-wrap}";

std::string PageOpen(const std::string& title) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
         HtmlEscape(title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n<h1>" +
         HtmlEscape(title) + "</h1>\n";
}

}  // namespace

std::string HtmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
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
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string RenderLinePlotSvg(const LinePlot& plot) {
  // Data ranges.
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  double y_lo = x_lo, y_hi = -x_lo, y_positive_lo = x_lo;
  for (const PlotSeries& s : plot.series) {
    for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      x_lo = std::min(x_lo, s.x[k]);
      x_hi = std::max(x_hi, s.x[k]);
      y_lo = std::min(y_lo, s.y[k]);
      y_hi = std::max(y_hi, s.y[k]);
      if (s.y[k] > 0.0) y_positive_lo = std::min(y_positive_lo, s.y[k]);
    }
  }
  if (std::isfinite(plot.reference_y)) {
    y_lo = std::min(y_lo, plot.reference_y);
    y_hi = std::max(y_hi, plot.reference_y);
    if (plot.reference_y > 0.0) y_positive_lo = std::min(y_positive_lo, plot.reference_y);
  }
  const bool empty = !std::isfinite(x_lo);
  if (empty) x_lo = 0.0, x_hi = 1.0, y_lo = 0.0, y_hi = 1.0, y_positive_lo = 1.0;
  Axis x_axis = LinearAxis(x_lo, x_hi, false);
  Axis y_axis;
  if (plot.log_y) {
    y_axis.log = true;
    if (!std::isfinite(y_positive_lo)) y_positive_lo = 1.0;
    y_axis.lo = std::floor(std::log10(y_positive_lo));
    y_axis.hi = std::ceil(std::log10(std::max(y_hi, y_positive_lo)));
    if (y_axis.hi <= y_axis.lo) y_axis.hi = y_axis.lo + 1.0;
  } else if (std::isfinite(plot.y_min) && std::isfinite(plot.y_max)) {
    y_axis.lo = plot.y_min;
    y_axis.hi = plot.y_max;
  } else {
    y_axis = LinearAxis(y_lo, y_hi, true);
  }
  const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  auto px = [&](double x) { return kLeft + x_axis.Fraction(x) * plot_w; };
  auto py = [&](double y) { return kTop + (1.0 - y_axis.Fraction(y)) * plot_h; };

  std::ostringstream svg;
  svg << SvgOpen(kWidth, kHeight, plot.title);
  svg << Text(kLeft + plot_w / 2, 20, plot.title, "middle",
              " font-size=\"14\" font-weight=\"bold\"");
  // Grid and ticks.
  for (double t : y_axis.Ticks()) {
    const double y = py(t);
    svg << "<line x1=\"" << kLeft << "\" x2=\"" << kLeft + plot_w << "\" y1=\"" << Number(y, "%.1f")
        << "\" y2=\"" << Number(y, "%.1f") << "\" stroke=\"#e5e5e5\"/>";
    svg << Text(kLeft - 6, y + 4, TickLabel(t), "end");
  }
  for (double t : x_axis.Ticks()) {
    const double x = px(t);
    svg << "<line x1=\"" << Number(x, "%.1f") << "\" x2=\"" << Number(x, "%.1f") << "\" y1=\""
        << kTop << "\" y2=\"" << kTop + plot_h << "\" stroke=\"#f0f0f0\"/>";
    svg << Text(x, kTop + plot_h + 16, TickLabel(t));
  }
  svg << "<rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\"" << plot_w << "\" height=\""
      << plot_h << "\" fill=\"none\" stroke=\"#888\"/>";
  svg << Text(kLeft + plot_w / 2, kHeight - 12, plot.x_label);
  svg << Text(16, kTop + plot_h / 2, plot.y_label, "middle",
              " transform=\"rotate(-90 16 " + Number(kTop + plot_h / 2, "%.1f") + ")\"");
  if (std::isfinite(plot.reference_y)) {
    const double y = py(plot.reference_y);
    svg << "<line x1=\"" << kLeft << "\" x2=\"" << kLeft + plot_w << "\" y1=\"" << Number(y, "%.1f")
        << "\" y2=\"" << Number(y, "%.1f") << "\" stroke=\"#555\" stroke-dasharray=\"6 4\"/>";
    svg << Text(kLeft + 4, y - 4, plot.reference_label, "start", " fill=\"#555\"");
  }
  if (empty) svg << Text(kLeft + plot_w / 2, kTop + plot_h / 2, "no data");
  // Series, then the legend.
  const size_t num_series = plot.series.size();
  for (size_t s = 0; s < num_series; ++s) {
    const PlotSeries& series = plot.series[s];
    const char* color = kColors[s % kNumColors];
    const char* dash = (s / kNumColors) % 2 == 1 ? " stroke-dasharray=\"4 3\"" : "";
    // Earlier series are drawn wider, so that series with equal values still show underneath.
    const double line_width =
        1.5 + 3.5 * static_cast<double>(num_series - 1 - s) / std::max<size_t>(1, num_series - 1);
    const std::string stroke_width = Number(line_width, "%.2f");
    std::string points;
    auto flush = [&]() {
      if (!points.empty())
        svg << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << stroke_width
            << "\"" << dash << " points=\"" << points << "\"/>";
      points.clear();
    };
    for (size_t k = 0; k < series.x.size() && k < series.y.size(); ++k) {
      if (!std::isfinite(series.x[k]) || !std::isfinite(series.y[k])) {
        flush();
        continue;
      }
      points += Number(px(series.x[k]), "%.1f") + "," + Number(py(series.y[k]), "%.1f") + " ";
    }
    flush();
    for (size_t k = 0; k < series.x.size() && k < series.y.size(); ++k) {
      if (!std::isfinite(series.x[k]) || !std::isfinite(series.y[k])) continue;
      svg << Marker(s, px(series.x[k]), py(series.y[k]), 1.0 + line_width, color) << "<title>"
          << HtmlEscape(series.label) << ": " << Number(series.x[k]) << ", "
          << Number(series.y[k], "%.4g") << "</title></path>";
    }
    const double ly = kTop + 8 + 18.0 * s;
    const double lx = kWidth - kRight + 14;
    svg << "<line x1=\"" << lx << "\" x2=\"" << lx + 22 << "\" y1=\"" << ly << "\" y2=\"" << ly
        << "\" stroke=\"" << color << "\" stroke-width=\"2\"" << dash << "/>";
    svg << Marker(s, lx + 11, ly, 3.5, color) << "</path>";
    svg << Text(lx + 28, ly + 4, series.label, "start");
  }
  svg << "</svg>";
  return svg.str();
}

std::string RenderBarPlotSvg(const BarPlot& plot) {
  constexpr double kBarHeight = 20.0, kGap = 6.0, kLabelWidth = 190.0, kValueRoom = 80.0;
  const double width = kWidth;
  const double height = kTop + plot.labels.size() * (kBarHeight + kGap) + kBottom;
  double max_value = 0.0;
  for (double v : plot.values)
    if (std::isfinite(v)) max_value = std::max(max_value, v);
  if (!(max_value > 0.0)) max_value = 1.0;
  Axis axis = LinearAxis(0.0, max_value, true);
  const double bar_w = width - kLabelWidth - kValueRoom - 20.0;
  const double plot_h = plot.labels.size() * (kBarHeight + kGap);
  std::ostringstream svg;
  svg << SvgOpen(width, height, plot.title);
  svg << Text(width / 2, 20, plot.title, "middle", " font-size=\"14\" font-weight=\"bold\"");
  for (double t : axis.Ticks()) {
    const double x = kLabelWidth + axis.Fraction(t) * bar_w;
    svg << "<line x1=\"" << Number(x, "%.1f") << "\" x2=\"" << Number(x, "%.1f") << "\" y1=\""
        << kTop << "\" y2=\"" << kTop + plot_h << "\" stroke=\"#e5e5e5\"/>";
    svg << Text(x, kTop + plot_h + 16, TickLabel(t));
  }
  for (size_t k = 0; k < plot.labels.size(); ++k) {
    const double y = kTop + k * (kBarHeight + kGap);
    svg << Text(kLabelWidth - 8, y + kBarHeight * 0.7, plot.labels[k], "end");
    const double v = k < plot.values.size() ? plot.values[k] : kNaN;
    if (!std::isfinite(v)) {
      svg << Text(kLabelWidth + 4, y + kBarHeight * 0.7, "n/a", "start", " fill=\"#888\"");
      continue;
    }
    const double w = std::max(0.5, axis.Fraction(v) * bar_w);
    svg << "<rect x=\"" << kLabelWidth << "\" y=\"" << Number(y, "%.1f") << "\" width=\""
        << Number(w, "%.1f") << "\" height=\"" << kBarHeight << "\" fill=\""
        << kColors[k % kNumColors] << "\"><title>" << HtmlEscape(plot.labels[k]) << ": "
        << Number(v, "%.4g") << "</title></rect>";
    svg << Text(kLabelWidth + w + 4, y + kBarHeight * 0.7, Number(v, "%.3g"), "start");
  }
  svg << Text(kLabelWidth + bar_w / 2, height - 12, plot.value_label);
  svg << "</svg>";
  return svg.str();
}

std::string RenderHtmlTable(const TextTable& table) {
  std::ostringstream html;
  html << "<table>\n";
  if (!table.title.empty()) html << "<caption>" << HtmlEscape(table.title) << "</caption>\n";
  html << "<tr>";
  for (const auto& h : table.header) html << "<th>" << HtmlEscape(h) << "</th>";
  html << "</tr>\n";
  for (const auto& row : table.rows) {
    html << "<tr>";
    for (const auto& cell : row) html << "<td>" << HtmlEscape(cell) << "</td>";
    html << "</tr>\n";
  }
  html << "</table>\n";
  if (!table.notes.empty()) {
    html << "<ul class=\"notes\">\n";
    for (const auto& note : table.notes) html << "<li>" << HtmlEscape(note) << "</li>\n";
    html << "</ul>\n";
  }
  return html.str();
}

std::string MonteCarloHtml(const MonteCarloOptions& options, const MonteCarloResult& result,
                           const std::string& command_line) {
  std::ostringstream html;
  html << PageOpen("photopose compare: Monte-Carlo comparison of the pose solvers");
  html << "<p>Command: <code>" << HtmlEscape(command_line) << "</code></p>\n";
  html << "<p>" << options.trials << " trials per setting, sweep " << EnumName(options.sweep)
       << ", initial values " << EnumName(options.initial) << ", wall time "
       << Number(result.wall_seconds, "%.1f") << " s. Solvers: ";
  for (size_t s = 0; s < result.solver_names.size(); ++s)
    html << (s ? ", " : "") << "<code>" << HtmlEscape(result.solver_names[s]) << "</code>";
  html << ".</p>\n<ul class=\"notes\">\n";
  for (const std::string& note : MonteCarloNotes(options))
    html << "<li>" << HtmlEscape(note) << "</li>\n";
  html << "</ul>\n";

  const std::vector<TextTable> tables = MonteCarloTables(options, result);
  for (Scenario scenario : options.scenarios) {
    html << "<h2>Scenario " << EnumName(scenario) << "</h2>\n<div class=\"plots\">\n";
    // Metric of a solver in a setting, for the plots.
    struct Metric {
      const char* name;
      const char* unit_label;
      bool log_y;
      bool rate;
      bool nees_reference;  // draw the dashed line at 6
      double (*get)(const SolverStatistics&);
    };
    const Metric position{
        "position RMSE", "position RMSE (m)", true, false, false, [](const SolverStatistics& s) {
          return s.position_rmse_m;
        }};
    const Metric success{"success rate", "success rate",
                         false,          true,
                         false,          [](const SolverStatistics& s) { return s.success_rate; }};
    const Metric nees{"mean NEES (sigma0 = 1)",
                      "mean NEES, a-priori covariance",
                      true,
                      false,
                      true,
                      [](const SolverStatistics& s) { return s.mean_nees_apriori; }};
    const Metric iterations{
        "mean iterations", "iterations", false, false, false, [](const SolverStatistics& s) {
          return s.mean_iterations;
        }};
    const std::vector<std::pair<std::string, std::vector<Metric>>> plots = {
        {"noise", {position, nees}},
        {"outliers", {position, success}},
        {"initial", {success, iterations}},
        {"control", {position, success}},
    };
    for (const auto& [axis, metrics] : plots) {
      const std::vector<size_t> along = SettingsAlongAxis(options, result, scenario, axis);
      if (along.empty()) continue;
      for (const Metric& metric : metrics) {
        LinePlot plot;
        plot.title = std::string(EnumName(scenario)) + ": " + metric.name + " vs " +
                     (axis == "initial" ? "initial error" : axis);
        plot.x_label = AxisLabel(axis);
        if (axis == "initial") {
          plot.x_label += "; position +-";
          for (size_t k = 0; k < along.size(); ++k)
            plot.x_label +=
                (k ? "/" : "") + Number(result.settings[along[k]].setting.initial_error.position_m);
          plot.x_label += " m";
        }
        plot.y_label = metric.unit_label;
        plot.log_y = metric.log_y;
        if (metric.rate) plot.y_min = 0.0, plot.y_max = 1.0;
        if (metric.nees_reference) {
          plot.reference_y = 6.0;
          plot.reference_label = "6 (honest)";
        }
        // Logarithmic only when the values span more than a factor of 30.
        double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
        for (size_t k : along)
          for (const SolverStatistics& s : result.settings[k].solvers) {
            const double v = metric.get(s);
            if (std::isfinite(v) && v > 0.0) lo = std::min(lo, v), hi = std::max(hi, v);
          }
        if (plot.log_y && std::isfinite(lo) && hi < 30.0 * lo && lo > 0.0 && !(hi < 1e-3))
          plot.log_y = false;
        for (size_t s = 0; s < result.solver_names.size(); ++s) {
          PlotSeries series;
          series.label = result.solver_names[s];
          for (size_t k : along) {
            series.x.push_back(PlotX(result.settings[k].setting, axis));
            series.y.push_back(metric.get(result.settings[k].solvers[s]));
          }
          plot.series.push_back(series);
        }
        html << RenderLinePlotSvg(plot) << "\n";
      }
    }
    // Time per solve at the scenario's baseline setting (the first of the scenario).
    for (const SettingResult& setting : result.settings) {
      if (setting.setting.scenario != scenario) continue;
      BarPlot bars;
      bars.title = std::string(EnumName(scenario)) + ": median time per solve (" +
                   setting.setting.axis + " setting)";
      bars.value_label = "microseconds per image (ResectImage wall time)";
      BarPlot refinement = bars;
      refinement.title = std::string(EnumName(scenario)) + ": median refinement time (" +
                         setting.setting.axis + " setting)";
      refinement.value_label = "microseconds per image (the solver's own iterations)";
      for (const SolverStatistics& s : setting.solvers) {
        bars.labels.push_back(s.solver);
        bars.values.push_back(s.median_seconds * 1e6);
        refinement.labels.push_back(s.solver);
        refinement.values.push_back(s.median_refinement_seconds * 1e6);
      }
      html << RenderBarPlotSvg(bars) << "\n" << RenderBarPlotSvg(refinement) << "\n";
      break;
    }
    html << "</div>\n";
    for (size_t k = 0; k < result.settings.size(); ++k)
      if (result.settings[k].setting.scenario == scenario) {
        html << RenderHtmlTable(tables[k]);
      }
  }
  html << "</body>\n</html>\n";
  return html.str();
}

std::string DatasetHtml(const DatasetComparisonResult& result, const std::string& command_line) {
  std::ostringstream html;
  html << PageOpen("photopose compare: the pose solvers on a dataset");
  html << "<p>Command: <code>" << HtmlEscape(command_line) << "</code></p>\n";
  const std::vector<TextTable> tables = DatasetTables(result);
  html << "<div class=\"plots\">\n";
  BarPlot time;
  time.title = "median time per image";
  time.value_label = "microseconds per image (ResectImage wall time)";
  BarPlot difference;
  difference.title = "RMS position difference to " + result.reference_solver;
  difference.value_label = "metres (n/a: the solver itself or none solved)";
  BarPlot reference = difference;
  reference.title = "RMS position difference to the reference frames";
  reference.value_label = "metres";
  for (const DatasetSolverSummary& s : result.summaries) {
    time.labels.push_back(s.solver);
    time.values.push_back(s.median_seconds * 1e6);
    difference.labels.push_back(s.solver);
    difference.values.push_back(s.compared > 0 ? s.difference_position_m : kNaN);
    reference.labels.push_back(s.solver);
    reference.values.push_back(s.referenced > 0 ? s.reference_position_m : kNaN);
  }
  html << RenderBarPlotSvg(time) << "\n" << RenderBarPlotSvg(difference) << "\n";
  if (result.has_reference) html << RenderBarPlotSvg(reference) << "\n";
  html << "</div>\n";
  for (const TextTable& table : tables) html << RenderHtmlTable(table);
  html << "</body>\n</html>\n";
  return html.str();
}

}  // namespace photopose::cli
