#pragma once
// The one kit every HTML page of photopose is written with (`photopose compare`, `photopose
// bundle`, the block comparison): the page head (doctype, charset, title, the one stylesheet and a
// print stylesheet), HTML escaping, number formatting for pages, tables, and the SVG plots (axes
// with labelled ticks and axis titles, lines with markers, bars, histogram bars, legend). Pages are
// self-contained: inline CSS and SVG, no script, no external resource.
//
// Coordinates are SVG user units (1 unit = 1 CSS px at 100 %); y grows downwards.

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace photopose::cli {

// ------------------------------------------------------------------ page

// "<!DOCTYPE html>" ... "<body>" and the page's <h1>: the one stylesheet (classes: .plots for a row
// of plots, ul.notes, .verdict with .good / .bad / .note) and its print variant.
std::string HtmlPageOpen(const std::string& title, const std::string& heading);
// "</body></html>" and a final newline.
std::string HtmlPageClose();

// &, <, >, " and ' escaped.
std::string HtmlEscape(const std::string& text);

// Numbers on pages and in report tables: `value` printed with a printf `format` for one double;
// "n/a" when it is not finite.
std::string ReportNumber(double value, const char* format = "%.3g");
// `value` with `digits` decimals; "n/a" when it is not finite.
std::string ReportFixed(double value, int digits);

// A <table> with a <caption> (the title, left out when empty) and the notes as a list under it;
// every cell escaped.
std::string HtmlTable(const std::string& title, const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows,
                      const std::vector<std::string>& notes = {});

// ------------------------------------------------------------------ SVG primitives

// The colour of series / bar `index`: the colour-blind-safe Okabe-Ito palette, then darker
// variants, cycled.
const char* PlotColor(size_t index);
constexpr size_t kNumPlotColors = 10;

// "<svg ...>" of width x height with role="img", an aria-label (the title), sans-serif 12 and a
// white background; the caller closes it with "</svg>".
std::string SvgOpen(double width, double height, const std::string& title);
// A <text> at (x, y), escaped; `anchor` is start / middle / end; `extra` more attributes (with a
// leading space).
std::string SvgText(double x, double y, const std::string& text, const char* anchor = "middle",
                    const std::string& extra = "");
// An open <path> drawing marker shape `index` (circle, square, triangle, diamond, cycled) of
// half-size r at (x, y); the caller closes it with "</path>" (so a <title> can go inside).
std::string SvgMarker(size_t index, double x, double y, double r, const char* color);

// 1, 2 or 5 times a power of ten: the smallest at least range / count (a tick step), or the
// largest at most `value` (NiceAtMost: a scale bar, an exaggeration factor; 1 when value <= 0).
double NiceStep(double range, int count);
double NiceAtMost(double value);

// One plot axis: linear over [lo, hi] or logarithmic over the decades [lo, hi] (log10 values).
struct PlotAxis {
  double lo = 0.0, hi = 1.0;
  bool log = false;
  // Position of a value along the axis, 0 at lo and 1 at hi (log: values <= 0 at lo).
  double Fraction(double value) const;
  // Tick values: about 5 "nice" steps (linear), or decades with 2 and 5 between few decades (log).
  std::vector<double> Ticks() const;
};
// A linear axis over the data range [lo, hi] widened to whole tick steps (from 0 when
// `from_zero` and lo >= 0; a flat range is padded).
PlotAxis LinearPlotAxis(double lo, double hi, bool from_zero);
// A tick's label: %g, or %.0e for very small and very large magnitudes.
std::string TickLabel(double value);

// The rectangle the data are drawn in, inside an SVG of `svg_height`.
struct PlotFrame {
  double left = 0.0, top = 0.0, width = 0.0, height = 0.0;
  double svg_height = 0.0;
  double X(const PlotAxis& axis, double value) const { return left + axis.Fraction(value) * width; }
  double Y(const PlotAxis& axis, double value) const {
    return top + (1.0 - axis.Fraction(value)) * height;
  }
};
// Grid lines and labelled ticks of both axes, the frame, the x-axis title under the ticks and the
// y-axis title turned along the left edge. A null axis draws neither its ticks nor its grid.
std::string SvgAxes(const PlotFrame& frame, const PlotAxis* x_axis, const PlotAxis* y_axis,
                    const std::string& x_title, const std::string& y_title);
// Legend entry `index` (its colour, line and marker) at row `index` from (x, top).
std::string SvgLegendEntry(size_t index, double x, double top, const std::string& label,
                           const char* dash = "");

// ------------------------------------------------------------------ plots

// One polyline of a line plot. Points with a non-finite y are left out (the line breaks there).
struct PlotSeries {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;
};

struct LinePlot {
  std::string title;
  std::string x_label;  // with its unit
  std::string y_label;  // with its unit
  // Logarithmic y axis (decades); values <= 0 are drawn on the bottom of the axis.
  bool log_y = false;
  // Fixed y range when both are finite (linear axis only), e.g. 0 and 1 for rates.
  double y_min = std::numeric_limits<double>::quiet_NaN();
  double y_max = std::numeric_limits<double>::quiet_NaN();
  // Optional horizontal reference line (e.g. the expected NEES), drawn dashed, with its label.
  double reference_y = std::numeric_limits<double>::quiet_NaN();
  std::string reference_label;
  std::vector<PlotSeries> series;
};

// Horizontal bars, one per label.
struct BarPlot {
  std::string title;
  std::string value_label;  // with its unit
  std::vector<std::string> labels;
  std::vector<double> values;  // non-finite values are drawn as "n/a"
};

// A histogram of values, symmetric about 0: 24 bins over +- the larger magnitude of the 0.25 % and
// 99.75 % quantiles (a blunder does not squash the rest; values beyond go to the end bins).
struct HistogramPlot {
  std::string title;           // the count of finite values is appended
  std::string x_label;         // with its unit
  std::vector<double> values;  // non-finite values are left out
};

// <svg> elements (no XML prolog): line plots 680 x 380, bar plots 680 wide, histograms 360 x 220.
std::string RenderLinePlotSvg(const LinePlot& plot);
std::string RenderBarPlotSvg(const BarPlot& plot);
std::string RenderHistogramSvg(const HistogramPlot& plot);

}  // namespace photopose::cli
