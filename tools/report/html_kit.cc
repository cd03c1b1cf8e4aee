#include "tools/report/html_kit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace photopose::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Line plot geometry (SVG user units).
constexpr double kLineWidth = 680.0;
constexpr double kLineHeight = 380.0;
constexpr double kLineLeft = 72.0;
constexpr double kLineRight = 200.0;  // room for the legend
constexpr double kLineTop = 34.0;
constexpr double kLineBottom = 52.0;

const char* const kColors[kNumPlotColors] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00",
                                             "#56B4E9", "#000000", "#8C510A", "#762A83", "#1B7837"};

// The one stylesheet, then what changes on paper: full width, plots one under the other, no
// plot or table row split across pages.
const char kStyle[] =
    "body{font-family:sans-serif;margin:2em auto;max-width:1400px;color:#222;padding:0 1em}"
    "p.meta{color:#555;margin-top:-0.5em}"
    "dl.glossary{font-size:0.85em}dl.glossary dt{font-weight:bold;margin-top:0.4em}"
    "dl.glossary dd{margin-left:1.5em}"
    "h1{font-size:1.5em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}"
    "table{border-collapse:collapse;margin:1em 0;font-size:0.85em}"
    "caption{text-align:left;font-weight:bold;padding:0.3em 0}"
    "th,td{border:1px solid #ccc;padding:0.2em 0.5em;text-align:right;white-space:nowrap}"
    "th{white-space:normal}"
    "th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}"
    "th.group{text-align:center}th.blank{background:none;border:none}"
    "tr.section th{text-align:left;background:#e3ebf5;white-space:normal}"
    "tr.note td{text-align:left;white-space:normal;color:#444}"
    "table.facts td+td{white-space:normal;overflow-wrap:anywhere}"
    "ul.notes{font-size:0.85em;color:#444}"
    ".plots{display:flex;flex-wrap:wrap;gap:1em}svg{background:#fff;border:1px solid #ddd}"
    ".verdict{padding:0.75em 1em;border-radius:6px;margin:0.5em 0}"
    ".bad{background:#fde2e1;border:1px solid #d55e00}"
    ".good{background:#e3f4ea;border:1px solid #009e73}"
    ".note{background:#eef3fa;border:1px solid #0072b2}"
    "code,pre{background:#f6f6f6;padding:0.1em 0.3em;white-space:pre-wrap}";
const char kPrintStyle[] =
    "@page{size:A4;margin:12mm}"
    "body{margin:0;max-width:none;padding:0;font-size:9pt}"
    "svg{max-width:100%;height:auto;box-sizing:border-box}.plots{gap:0.5em}"
    "table{font-size:7pt;max-width:100%}th,td{white-space:normal;padding:0.1em 0.2em}th{overflow-wrap:anywhere}"
    "code,pre{word-break:break-all}"
    "dl.glossary{columns:2;column-gap:1.5em;margin:0}dl.glossary dt{break-after:avoid}"
    "svg,tr,.verdict,dl.glossary dd{break-inside:avoid}h2,h3{break-after:avoid}";

std::string Coordinate(double value) { return ReportNumber(value, "%.1f"); }

// A plotted value as text (a bar's label, a marker's tooltip): three significant digits, "< 0.01"
// below 0.01 in magnitude (a value that would read 0.000003 says nothing a reader can use; the
// tables and CSV carry it).
std::string PlotValueText(double value) {
  if (value != 0.0 && std::abs(value) < 0.01) return value > 0.0 ? "< 0.01" : "> -0.01";
  return FormatSignificant(value, 3);
}

// A line from (x1, y1) to (x2, y2) with more attributes.
std::string SvgLine(double x1, double y1, double x2, double y2, const std::string& attributes) {
  return "<line x1=\"" + Coordinate(x1) + "\" x2=\"" + Coordinate(x2) + "\" y1=\"" +
         Coordinate(y1) + "\" y2=\"" + Coordinate(y2) + "\" " + attributes + "/>";
}

// The line plot's axes from its data (and reference line).
void LinePlotAxes(const LinePlot& plot, PlotAxis* x_axis, PlotAxis* y_axis, bool* empty) {
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  double y_lo = x_lo, y_hi = -x_lo, y_positive_lo = x_lo;
  auto add_y = [&](double y) {
    y_lo = std::min(y_lo, y);
    y_hi = std::max(y_hi, y);
    if (y > 0.0) y_positive_lo = std::min(y_positive_lo, y);
  };
  for (const PlotSeries& s : plot.series) {
    for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      x_lo = std::min(x_lo, s.x[k]);
      x_hi = std::max(x_hi, s.x[k]);
      add_y(s.y[k]);
    }
  }
  if (std::isfinite(plot.reference_y)) add_y(plot.reference_y);
  *empty = !std::isfinite(x_lo);
  if (*empty) x_lo = 0.0, x_hi = 1.0, y_lo = 0.0, y_hi = 1.0, y_positive_lo = 1.0;
  *x_axis = LinearPlotAxis(x_lo, x_hi, false);
  if (plot.log_y) {
    *y_axis = PlotAxis();
    y_axis->log = true;
    if (!std::isfinite(y_positive_lo)) y_positive_lo = 1.0;
    y_axis->lo = std::floor(std::log10(y_positive_lo));
    y_axis->hi = std::ceil(std::log10(std::max(y_hi, y_positive_lo)));
    if (y_axis->hi <= y_axis->lo) y_axis->hi = y_axis->lo + 1.0;
  } else if (std::isfinite(plot.y_min) && std::isfinite(plot.y_max)) {
    y_axis->lo = plot.y_min;
    y_axis->hi = plot.y_max;
  } else {
    *y_axis = LinearPlotAxis(y_lo, y_hi, true);
  }
}

// The polylines of a series (broken at non-finite values) in one colour and width.
std::string SeriesPolylines(const PlotSeries& series, const PlotFrame& frame,
                            const PlotAxis& x_axis, const PlotAxis& y_axis, const char* color,
                            double line_width, const char* dash) {
  std::ostringstream svg;
  std::string points;
  auto flush = [&]() {
    if (!points.empty())
      svg << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\""
          << ReportNumber(line_width, "%.2f") << "\"" << dash << " points=\"" << points << "\"/>";
    points.clear();
  };
  const size_t n = std::min(series.x.size(), series.y.size());
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(series.x[k]) || !std::isfinite(series.y[k])) {
      flush();
      continue;
    }
    points += Coordinate(frame.X(x_axis, series.x[k])) + "," +
              Coordinate(frame.Y(y_axis, series.y[k])) + " ";
  }
  flush();
  return svg.str();
}

// The markers of series `s`, each with its values as a tooltip.
std::string SeriesMarkers(const PlotSeries& series, size_t s, const PlotFrame& frame,
                          const PlotAxis& x_axis, const PlotAxis& y_axis, double r) {
  std::ostringstream svg;
  const size_t n = std::min(series.x.size(), series.y.size());
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(series.x[k]) || !std::isfinite(series.y[k])) continue;
    svg << SvgMarker(s, frame.X(x_axis, series.x[k]), frame.Y(y_axis, series.y[k]), r,
                     PlotColor(s))
        << "<title>" << HtmlEscape(series.label) << ": " << HtmlEscape(PlotValueText(series.x[k]))
        << ", " << HtmlEscape(PlotValueText(series.y[k])) << "</title></path>";
  }
  return svg.str();
}

// Series `s` of a line plot: its polylines (broken at non-finite values) and markers.
std::string LineSeriesSvg(const LinePlot& plot, size_t s, const PlotFrame& frame,
                          const PlotAxis& x_axis, const PlotAxis& y_axis) {
  const size_t num_series = plot.series.size();
  const char* dash = (s / kNumPlotColors) % 2 == 1 ? " stroke-dasharray=\"4 3\"" : "";
  // Earlier series are drawn wider, so that series with equal values still show underneath.
  const double line_width =
      1.5 + 3.5 * static_cast<double>(num_series - 1 - s) / std::max<size_t>(1, num_series - 1);
  return SeriesPolylines(plot.series[s], frame, x_axis, y_axis, PlotColor(s), line_width, dash) +
         SeriesMarkers(plot.series[s], s, frame, x_axis, y_axis, 1.0 + line_width);
}

// The dashed reference line of a plot, with its label.
std::string ReferenceLine(const LinePlot& plot, const PlotFrame& frame, const PlotAxis& y_axis) {
  if (!std::isfinite(plot.reference_y)) return "";
  const double y = frame.Y(y_axis, plot.reference_y);
  return SvgLine(frame.left, y, frame.left + frame.width, y,
                 "stroke=\"#555\" stroke-dasharray=\"6 4\"") +
         SvgText(frame.left + 4, y - 4, plot.reference_label, "start", " fill=\"#555\"");
}

std::string PlotTitle(double x, const std::string& title) {
  return SvgText(x, 20, title, "middle", " font-size=\"14\" font-weight=\"bold\"");
}

}  // namespace

std::string HtmlPageOpen(const std::string& title, const std::string& heading) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
         HtmlEscape(title) + "</title>\n<style>" + kStyle + "</style>\n<style media=\"print\">" +
         kPrintStyle + "</style>\n</head>\n<body>\n<h1>" + HtmlEscape(heading) + "</h1>\n";
}

std::string HtmlPageClose() { return "</body>\n</html>\n"; }

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

std::string ReportNumber(double value, const char* format) {
  if (!std::isfinite(value)) return "n/a";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

namespace {

// A table's opening, caption and a row of <th> cells; the rows of <td> cells; the notes as a
// list under a table.
std::string TableHead(const std::string& title, const std::vector<std::string>& header,
                      const std::string& table_class = "") {
  std::string html = table_class.empty() ? "<table>\n" : "<table class=\"" + table_class + "\">\n";
  if (!title.empty()) html += "<caption>" + HtmlEscape(title) + "</caption>\n";
  html += "<tr>";
  for (const auto& h : header) html += "<th>" + HtmlEscape(h) + "</th>";
  return html + "</tr>\n";
}

std::string TableRows(const std::vector<std::vector<std::string>>& rows) {
  std::string html;
  for (const auto& row : rows) {
    html += "<tr>";
    for (const auto& cell : row) html += "<td>" + HtmlEscape(cell) + "</td>";
    html += "</tr>\n";
  }
  return html;
}

std::string NotesList(const std::vector<std::string>& notes) {
  if (notes.empty()) return "";
  std::string html = "<ul class=\"notes\">\n";
  for (const auto& note : notes) html += "<li>" + HtmlEscape(note) + "</li>\n";
  return html + "</ul>\n";
}

}  // namespace

std::string HtmlTable(const std::string& title, const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows,
                      const std::vector<std::string>& notes,
                      const std::vector<HeaderGroup>& groups) {
  std::string head = TableHead(title, header);
  size_t grouped = 0;
  for (const HeaderGroup& g : groups) grouped += std::max(0, g.span);
  if (!groups.empty() && grouped == header.size()) {
    std::string row = "<tr>";
    for (const HeaderGroup& g : groups) {
      if (g.span <= 0) continue;
      row += "<th" + (g.span > 1 ? " colspan=\"" + std::to_string(g.span) + "\"" : std::string()) +
             (g.label.empty() ? " class=\"blank\"" : " class=\"group\"") + ">" +
             HtmlEscape(g.label) + "</th>";
    }
    // Above the header row, after the caption.
    head.insert(head.rfind("<tr>"), row + "</tr>\n");
  }
  return head + TableRows(rows) + "</table>\n" + NotesList(notes);
}

std::string HtmlFactsTable(const std::string& title,
                           const std::vector<std::pair<std::string, std::string>>& facts) {
  std::vector<std::vector<std::string>> rows;
  for (const auto& [item, value] : facts) rows.push_back({item, value});
  return TableHead(title, {"item", "value"}, "facts") + TableRows(rows) + "</table>\n";
}

std::string HtmlSectionedTable(const std::string& title, const std::vector<std::string>& header,
                               const std::vector<TableSection>& sections,
                               const std::vector<std::string>& notes) {
  const std::string columns = std::to_string(std::max<size_t>(1, header.size()));
  std::string html = TableHead(title, header);
  for (const TableSection& section : sections) {
    html += "<tr class=\"section\"><th colspan=\"" + columns + "\">" +
            HtmlEscape(section.heading) + "</th></tr>\n" + TableRows(section.rows);
    for (const auto& note : section.notes)
      html += "<tr class=\"note\"><td colspan=\"" + columns + "\">" + HtmlEscape(note) +
              "</td></tr>\n";
  }
  return html + "</table>\n" + NotesList(notes);
}

std::string HtmlGlossary(const std::vector<std::pair<std::string, std::string>>& terms) {
  std::string html = "<dl class=\"glossary\">\n";
  for (const auto& [term, meaning] : terms)
    html += "<dt>" + HtmlEscape(term) + "</dt><dd>" + HtmlEscape(meaning) + "</dd>\n";
  return html + "</dl>\n";
}

const char* PlotColor(size_t index) { return kColors[index % kNumPlotColors]; }

std::string SvgOpen(double width, double height, const std::string& title,
                    const std::string& kind) {
  std::ostringstream out;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << width << " " << height
      << "\" width=\"" << width << "\" height=\"" << height << "\" class=\"plot"
      << (kind.empty() ? "" : " " + kind) << "\" role=\"img\" aria-label=\""
      << HtmlEscape(title) << "\" font-family=\"sans-serif\" font-size=\"12\">"
      << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>";
  return out.str();
}

std::string SvgText(double x, double y, const std::string& text, const char* anchor,
                    const std::string& extra) {
  return "<text x=\"" + Coordinate(x) + "\" y=\"" + Coordinate(y) + "\" text-anchor=\"" + anchor +
         "\"" + extra + ">" + HtmlEscape(text) + "</text>";
}

std::string SvgMarker(size_t index, double x, double y, double r, const char* color) {
  std::ostringstream d;
  auto p = [](double v) { return Coordinate(v); };
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

double NiceStep(double range, int count) {
  const double raw = range / count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double factor : {1.0, 2.0, 5.0, 10.0})
    if (factor * magnitude >= raw) return factor * magnitude;
  return 10.0 * magnitude;
}

double NiceAtMost(double value) {
  if (!(value > 0.0)) return 1.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(value)));
  for (const double f : {5.0, 2.0, 1.0})
    if (f * magnitude <= value) return f * magnitude;
  return magnitude;
}

double PlotAxis::Fraction(double value) const {
  if (log) {
    const double v = value > 0.0 ? std::log10(value) : lo;
    return (std::clamp(v, lo, hi) - lo) / (hi - lo);
  }
  return (value - lo) / (hi - lo);
}

std::vector<double> PlotAxis::Ticks() const {
  std::vector<double> ticks;
  if (log) {
    // At most about steps + 3 decades labelled (8 at the default 5).
    const int step = std::max(1, static_cast<int>(std::ceil((hi - lo) / (std::max(1, steps) + 3.0))));
    for (int e = static_cast<int>(lo); e <= static_cast<int>(hi); e += step) {
      ticks.push_back(std::pow(10.0, e));
      // Few decades: 2 and 5 times each power of ten as well.
      if (hi - lo <= 2.0 && e < static_cast<int>(hi))
        for (double f : {2.0, 5.0}) ticks.push_back(f * std::pow(10.0, e));
    }
    return ticks;
  }
  const double step = NiceStep(hi - lo, std::max(1, steps));
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return ticks;
}

PlotAxis LinearPlotAxis(double lo, double hi, bool from_zero) {
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
  PlotAxis axis;
  axis.lo = lo;
  axis.hi = hi;
  return axis;
}

std::string TickLabel(double value) {
  if (value == 0.0) return "0";
  return FormatSignificant(value, 6);
}

PlotFrame SmallPlotFrame(double width, double height) {
  PlotFrame frame;
  frame.left = 58.0;
  frame.top = 30.0;
  frame.width = width - frame.left - 14.0;
  frame.height = height - frame.top - 52.0;
  frame.svg_height = height;
  return frame;
}

std::string SvgAxes(const PlotFrame& frame, const PlotAxis* x_axis, const PlotAxis* y_axis,
                    const std::string& x_title, const std::string& y_title) {
  const double right = frame.left + frame.width, bottom = frame.top + frame.height;
  std::ostringstream svg;
  if (y_axis != nullptr) {
    for (double t : y_axis->Ticks()) {
      const double y = frame.Y(*y_axis, t);
      svg << SvgLine(frame.left, y, right, y, "stroke=\"#e5e5e5\"");
      svg << SvgText(frame.left - 6, y + 4, TickLabel(t), "end", " class=\"tick-y\"");
    }
  }
  if (x_axis != nullptr) {
    for (double t : x_axis->Ticks()) {
      const double x = frame.X(*x_axis, t);
      svg << SvgLine(x, frame.top, x, bottom, "stroke=\"#f0f0f0\"");
      svg << SvgText(x, bottom + 16, TickLabel(t), "middle", " class=\"tick-x\"");
    }
  }
  svg << "<rect x=\"" << frame.left << "\" y=\"" << frame.top << "\" width=\"" << frame.width
      << "\" height=\"" << frame.height << "\" fill=\"none\" stroke=\"#888\"/>";
  if (!x_title.empty())
    svg << SvgText(frame.left + frame.width / 2, frame.svg_height - 12, x_title, "middle",
                   std::string(" class=\"") + kAxisLabelClass + "\"");
  if (!y_title.empty()) {
    const std::string middle = Coordinate(frame.top + frame.height / 2);
    svg << SvgText(16, frame.top + frame.height / 2, y_title, "middle",
                   std::string(" class=\"") + kAxisLabelClass + "\" transform=\"rotate(-90 16 " +
                       middle + ")\"");
  }
  return svg.str();
}

std::string SvgLegendEntry(size_t index, double x, double top, const std::string& label,
                           const char* dash) {
  const double y = top + 18.0 * index;
  const char* color = PlotColor(index);
  return SvgLine(x, y, x + 22, y,
                 std::string("stroke=\"") + color + "\" stroke-width=\"2\"" + dash) +
         SvgMarker(index, x + 11, y, 3.5, color) + "</path>" +
         SvgText(x + 28, y + 4, label, "start");
}

std::string RenderLinePlotSvg(const LinePlot& plot) {
  PlotAxis x_axis, y_axis;
  bool empty = false;
  LinePlotAxes(plot, &x_axis, &y_axis, &empty);
  PlotFrame frame;
  frame.left = kLineLeft;
  frame.top = kLineTop;
  frame.width = kLineWidth - kLineLeft - kLineRight;
  frame.height = kLineHeight - kLineTop - kLineBottom;
  frame.svg_height = kLineHeight;

  std::ostringstream svg;
  svg << SvgOpen(kLineWidth, kLineHeight, plot.title);
  svg << PlotTitle(frame.left + frame.width / 2, plot.title);
  svg << SvgAxes(frame, &x_axis, &y_axis, plot.x_label, plot.y_label);
  svg << ReferenceLine(plot, frame, y_axis);
  if (empty) svg << SvgText(frame.left + frame.width / 2, frame.top + frame.height / 2, "no data");
  // Series, then the legend.
  for (size_t s = 0; s < plot.series.size(); ++s) {
    svg << LineSeriesSvg(plot, s, frame, x_axis, y_axis);
    const char* dash = (s / kNumPlotColors) % 2 == 1 ? " stroke-dasharray=\"4 3\"" : "";
    svg << SvgLegendEntry(s, kLineWidth - kLineRight + 14, kLineTop + 8, plot.series[s].label,
                          dash);
  }
  svg << "</svg>";
  return svg.str();
}

std::string RenderSmallMultiplesSvg(const LinePlot& plot) {
  // A row of panels across the A4 content width: room for the y tick labels and the y title on
  // the left, the plot's title and the panels' titles above, x ticks and the x title below.
  constexpr double kWidth = 700.0, kHeight = 150.0, kLeft = 62.0, kRight = 6.0, kGap = 18.0;
  constexpr double kTop = 36.0, kBottom = 34.0;
  PlotAxis x_axis, y_axis;
  bool empty = false;
  LinePlotAxes(plot, &x_axis, &y_axis, &empty);
  x_axis.steps = 3;
  y_axis.steps = 3;
  const size_t n = std::max<size_t>(1, plot.series.size());
  const double panel = (kWidth - kLeft - kRight - kGap * (n - 1)) / n;
  std::ostringstream svg;
  svg << SvgOpen(kWidth, kHeight, plot.title)
      << SvgText(kLeft, 14, plot.title, "start", " font-size=\"13\" font-weight=\"bold\"");
  for (size_t s = 0; s < n; ++s) {
    PlotFrame frame;
    frame.left = kLeft + s * (panel + kGap);
    frame.top = kTop;
    frame.width = panel;
    frame.height = kHeight - kTop - kBottom;
    frame.svg_height = kHeight;
    svg << "<g font-size=\"10\">";
    if (s < plot.series.size()) {
      // A title wider than its panel (bold 10 px: about 6.2 px per character in any sans font)
      // is fitted to the panel plus 5 px each side, less than the gap and the right margin, so
      // that neighbouring titles never meet and the last never leaves the page.
      const std::string& title = plot.series[s].label;
      const double room = panel + 10.0;
      std::string fit;
      if (6.2 * static_cast<double>(title.size()) > 0.85 * room)
        fit = " textLength=\"" + Coordinate(room) + "\" lengthAdjust=\"spacingAndGlyphs\"";
      svg << SvgText(frame.left + panel / 2, kTop - 6, title, "middle",
                     " font-weight=\"bold\"" + fit);
    }
    // Tick labels of y on the first panel only; its grid lines in every one.
    svg << SvgAxes(frame, &x_axis, s == 0 ? &y_axis : nullptr, "", "");
    if (s > 0)
      for (const double t : y_axis.Ticks()) {
        const double y = frame.Y(y_axis, t);
        svg << SvgLine(frame.left, y, frame.left + panel, y, "stroke=\"#e5e5e5\"");
      }
    svg << ReferenceLine(plot, frame, y_axis) << "</g>";
    if (empty) svg << SvgText(frame.left + panel / 2, frame.top + frame.height / 2, "no data");
    if (s >= plot.series.size()) continue;
    for (size_t other = 0; other < plot.series.size(); ++other)
      if (other != s)
        svg << SeriesPolylines(plot.series[other], frame, x_axis, y_axis, "#cccccc", 1.0, "");
    svg << SeriesPolylines(plot.series[s], frame, x_axis, y_axis, PlotColor(s), 2.0, "")
        << SeriesMarkers(plot.series[s], s, frame, x_axis, y_axis, 2.5);
  }
  // The axis titles once: x under the panels, y along the left edge.
  const std::string label = std::string(" class=\"") + kAxisLabelClass + "\"";
  svg << SvgText(kLeft + (kWidth - kLeft - kRight) / 2, kHeight - 6, plot.x_label, "middle", label);
  const double middle = kTop + (kHeight - kTop - kBottom) / 2;
  svg << SvgText(12, middle, plot.y_label, "middle",
                 label + " font-size=\"11\" transform=\"rotate(-90 12 " + Coordinate(middle) + ")\"");
  svg << "</svg>";
  return svg.str();
}

std::string RenderBarPlotSvg(const BarPlot& plot) {
  constexpr double kBarHeight = 20.0, kGap = 6.0, kLabelWidth = 190.0, kValueRoom = 80.0;
  const double width = kLineWidth;
  const double plot_h = plot.labels.size() * (kBarHeight + kGap);
  const double height = kLineTop + plot_h + kLineBottom;
  double max_value = 0.0;
  for (double v : plot.values)
    if (std::isfinite(v)) max_value = std::max(max_value, v);
  if (!(max_value > 0.0)) max_value = 1.0;
  const PlotAxis axis = LinearPlotAxis(0.0, max_value, true);
  PlotFrame frame;
  frame.left = kLabelWidth;
  frame.top = kLineTop;
  frame.width = width - kLabelWidth - kValueRoom - 20.0;
  frame.height = plot_h;
  frame.svg_height = height;
  std::ostringstream svg;
  svg << SvgOpen(width, height, plot.title) << PlotTitle(width / 2, plot.title);
  svg << SvgAxes(frame, &axis, nullptr, plot.value_label, "");
  for (size_t k = 0; k < plot.labels.size(); ++k) {
    const double y = kLineTop + k * (kBarHeight + kGap);
    const double text_y = y + kBarHeight * 0.7;
    svg << SvgText(kLabelWidth - 8, text_y, plot.labels[k], "end");
    const double v = k < plot.values.size() ? plot.values[k] : kNaN;
    if (!std::isfinite(v)) {
      svg << SvgText(kLabelWidth + 4, text_y, "n/a", "start", " fill=\"#888\"");
      continue;
    }
    const double w = std::max(0.5, axis.Fraction(v) * frame.width);
    svg << "<rect x=\"" << kLabelWidth << "\" y=\"" << Coordinate(y) << "\" width=\""
        << Coordinate(w) << "\" height=\"" << kBarHeight << "\" fill=\"" << PlotColor(k)
        << "\"><title>" << HtmlEscape(plot.labels[k]) << ": " << HtmlEscape(PlotValueText(v))
        << "</title></rect>";
    svg << SvgText(kLabelWidth + w + 4, text_y, PlotValueText(v), "start");
  }
  svg << "</svg>";
  return svg.str();
}

std::string RenderHistogramSvg(const HistogramPlot& plot) {
  constexpr double kWidth = 360.0, kHeight = 220.0;
  constexpr int kBins = 24;
  std::vector<double> finite;
  for (const double v : plot.values)
    if (std::isfinite(v)) finite.push_back(v);
  const std::string title = plot.title + " (" + std::to_string(finite.size()) + ")";
  std::ostringstream svg;
  svg << SvgOpen(kWidth, kHeight, title, "histogram") << PlotTitle(kWidth / 2, title);
  const PlotFrame frame = SmallPlotFrame(kWidth, kHeight);
  if (finite.empty()) {
    PlotAxis x_axis = LinearPlotAxis(std::isfinite(plot.lo) ? plot.lo : -1.0,
                                     std::isfinite(plot.hi) ? plot.hi : 1.0, false);
    const PlotAxis y_axis = LinearPlotAxis(0.0, 1.0, true);
    return svg.str() + SvgAxes(frame, &x_axis, &y_axis, plot.x_label, "count") +
           SvgText(frame.left + frame.width / 2, frame.top + frame.height / 2, "no data") +
           "</svg>";
  }
  std::vector<double> sorted = finite;
  std::sort(sorted.begin(), sorted.end());
  double range_lo = plot.lo, range_hi = plot.hi;
  if (!(std::isfinite(range_lo) && std::isfinite(range_hi) && range_hi > range_lo)) {
    const double low = sorted[static_cast<size_t>(0.0025 * (sorted.size() - 1))];
    const double high = sorted[static_cast<size_t>(0.9975 * (sorted.size() - 1))];
    const double half = std::max({std::abs(low), std::abs(high), 1e-12});
    range_lo = -half;
    range_hi = half;
  }
  std::vector<int> counts(kBins, 0);
  for (const double v : finite) {
    const int bin = static_cast<int>(std::floor((v - range_lo) / (range_hi - range_lo) * kBins));
    ++counts[std::clamp(bin, 0, kBins - 1)];
  }
  const int top = *std::max_element(counts.begin(), counts.end());
  PlotAxis x_axis;
  x_axis.lo = range_lo;
  x_axis.hi = range_hi;
  const PlotAxis y_axis = LinearPlotAxis(0.0, top, true);
  svg << SvgAxes(frame, &x_axis, &y_axis, plot.x_label, "count");
  const double bar_width = frame.width / kBins;
  for (int b = 0; b < kBins; ++b) {
    const double y = frame.Y(y_axis, counts[b]);
    svg << "<rect x=\"" << Coordinate(frame.left + b * bar_width) << "\" y=\"" << Coordinate(y)
        << "\" width=\"" << Coordinate(bar_width - 1) << "\" height=\""
        << Coordinate(frame.top + frame.height - y) << "\" fill=\"" << PlotColor(0) << "\"/>";
  }
  svg << "</svg>";
  return svg.str();
}

std::string RenderScatterPlotSvg(const ScatterPlot& plot) {
  constexpr double kWidth = 340.0, kHeight = 240.0;
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
  const size_t n = std::min(plot.x.size(), plot.y.size());
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(plot.x[k]) || !std::isfinite(plot.y[k])) continue;
    x_lo = std::min(x_lo, plot.x[k]), x_hi = std::max(x_hi, plot.x[k]);
    y_lo = std::min(y_lo, plot.y[k]), y_hi = std::max(y_hi, plot.y[k]);
  }
  const bool empty = !std::isfinite(x_lo);
  if (empty) x_lo = y_lo = 0.0, x_hi = y_hi = 1.0;
  if (plot.zero_line) y_lo = std::min(y_lo, 0.0), y_hi = std::max(y_hi, 0.0);
  // Symmetric about 0 when the zero line is drawn: over and under read alike.
  if (plot.zero_line) y_hi = std::max(std::abs(y_lo), std::abs(y_hi)), y_lo = -y_hi;
  const PlotAxis x_axis = LinearPlotAxis(x_lo, x_hi, false);
  const PlotAxis y_axis = LinearPlotAxis(y_lo, y_hi, false);
  const PlotFrame frame = SmallPlotFrame(kWidth, kHeight);
  std::ostringstream svg;
  svg << SvgOpen(kWidth, kHeight, plot.title) << PlotTitle(kWidth / 2, plot.title);
  svg << SvgAxes(frame, &x_axis, &y_axis, plot.x_label, plot.y_label);
  if (plot.zero_line) {
    const double y = frame.Y(y_axis, 0.0);
    svg << SvgLine(frame.left, y, frame.left + frame.width, y,
                   "stroke=\"#555\" stroke-dasharray=\"6 4\"");
  }
  if (empty) svg << SvgText(frame.left + frame.width / 2, frame.top + frame.height / 2, "no data");
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(plot.x[k]) || !std::isfinite(plot.y[k])) continue;
    svg << SvgMarker(0, frame.X(x_axis, plot.x[k]), frame.Y(y_axis, plot.y[k]), 3.5, PlotColor(0))
        << "<title>" << HtmlEscape(k < plot.labels.size() ? plot.labels[k] : std::string()) << ": "
        << HtmlEscape(PlotValueText(plot.y[k])) << "</title></path>";
  }
  svg << "</svg>";
  return svg.str();
}

}  // namespace photopose::cli
