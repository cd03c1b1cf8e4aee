#pragma once
// The one kit every HTML page of photopose is written with (`photopose compare`, `photopose
// bundle`, the block comparison): the page head (doctype, charset, title, the one stylesheet and a
// print stylesheet), HTML escaping, number formatting for pages, tables, and the SVG plots (axes
// with labelled ticks and axis titles, lines with markers, bars, histogram bars, legend). Pages are
// self-contained: inline CSS and SVG, no script, no external resource. Numbers on pages go
// through one formatter per quantity kind (fixed units: mm/cm for errors, um for film, px for
// marks, degrees and arc seconds for angles), never an exponent.
//
// Coordinates are SVG user units (1 unit = 1 CSS px at 100 %); y grows downwards.

#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/units.h"

namespace photopose::cli {

// ------------------------------------------------------------------ page

// "<!DOCTYPE html>" ... "<body>" and the page's <h1>: the one stylesheet (classes: .plots for a row
// of plots, ul.notes, .verdict with .good / .bad / .note, dl.glossary, p.meta for the line under
// the heading, table.facts for a key-value table whose values wrap) and its print variant (A4
// pages, 12 mm margins: 186 mm = 703 CSS px of content; plots and tables shrink to it, no plot or
// table row split across pages).
std::string HtmlPageOpen(const std::string& title, const std::string& heading);
// "</body></html>" and a final newline.
std::string HtmlPageClose();

// &, <, >, " and ' escaped.
std::string HtmlEscape(const std::string& text);

// Numbers on pages and in report tables: `value` printed with a printf `format` for one double;
// "n/a" when it is not finite. For SVG coordinates; page text uses core/units.h.
std::string ReportNumber(double value, const char* format = "%.3g");
// The numbers a surveyor reads (lengths, angles, marks in their fixed units): core/units.h.

// A header cell over `span` columns of a table's header row (e.g. "centre (m)" over X, Y, Z):
// the quantity and its unit once, short axis names under it.
struct HeaderGroup {
  std::string label;  // empty over columns that need no group
  int span = 1;       // columns (count)
};

// A <table> with a <caption> (the title, left out when empty) and the notes as a list under it;
// every cell escaped. With `groups` (their spans summing to the header's size) a row of grouped
// header cells above the header.
std::string HtmlTable(const std::string& title, const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows,
                      const std::vector<std::string>& notes = {},
                      const std::vector<HeaderGroup>& groups = {});

// A key-value table (<table class="facts">, columns "item" and "value"; the caption left out when
// `title` is empty), every cell escaped. Its values wrap, a long word (a path, a CRS definition)
// anywhere, so that the table keeps to the page's width on the screen and on A4.
std::string HtmlFactsTable(const std::string& title,
                           const std::vector<std::pair<std::string, std::string>>& facts);

// Rows of a table under a heading row that spans every column (e.g. one section per setting of a
// sweep under one header), and notes on that section as rows spanning every column after them.
struct TableSection {
  std::string heading;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> notes;
};
// One <table>: the caption (left out when empty), the header once, then each section; the notes
// as a list under it; every cell escaped.
std::string HtmlSectionedTable(const std::string& title, const std::vector<std::string>& header,
                               const std::vector<TableSection>& sections,
                               const std::vector<std::string>& notes = {});

// A glossary: <dl class="glossary"> with a <dt> term and <dd> meaning per pair, escaped.
std::string HtmlGlossary(const std::vector<std::pair<std::string, std::string>>& terms);

// ------------------------------------------------------------------ SVG primitives

// The colour of series / bar `index`: the colour-blind-safe Okabe-Ito palette, then darker
// variants, cycled.
const char* PlotColor(size_t index);
constexpr size_t kNumPlotColors = 10;

// "<svg ...>" of width x height with class "plot" (and `kind`, e.g. "histogram", when not empty),
// role="img", an aria-label (the title), sans-serif 12 and a white background; the caller closes it
// with "</svg>".
std::string SvgOpen(double width, double height, const std::string& title,
                    const std::string& kind = "");
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
  int steps = 5;  // about this many tick steps on a linear axis (count; fewer on a narrow panel)
  // Position of a value along the axis, 0 at lo and 1 at hi (log: values <= 0 at lo).
  double Fraction(double value) const;
  // Tick values: about `steps` "nice" steps (linear), or decades with 2 and 5 between few decades
  // (log).
  std::vector<double> Ticks() const;
};
// A linear axis over the data range [lo, hi] widened to whole tick steps (from 0 when
// `from_zero` and lo >= 0; a flat range is padded).
PlotAxis LinearPlotAxis(double lo, double hi, bool from_zero);
// A tick's label: FormatSignificant with 6 digits (never an exponent).
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
// The data rectangle of a small plot (histogram, scatter plot, small multiple) of width x height:
// room for the title above, tick labels and the axis titles left and below.
PlotFrame SmallPlotFrame(double width, double height);
// Grid lines and labelled ticks of both axes (tick labels of class "tick-x" and "tick-y"), the
// frame, the x-axis title under the ticks and the y-axis title turned along the left edge. A null
// axis draws neither its ticks nor its grid.
std::string SvgAxes(const PlotFrame& frame, const PlotAxis* x_axis, const PlotAxis* y_axis,
                    const std::string& x_title, const std::string& y_title);
// Plot convention (checked by the browser test, tests/tools/report/render_pages_test.py): every
// <svg> of a page carries class "plot" and at least one <text class="axis-label"> naming an axis
// with its unit (SvgAxes writes them; a plot without axes, like the plan view, writes its own).
constexpr char kAxisLabelClass[] = "axis-label";
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

// A histogram of values: 24 bins over [lo, hi] when both are finite (e.g. 0 and 1 for redundancy
// numbers), else symmetric about 0 over +- the larger magnitude of the 0.25 % and 99.75 %
// quantiles (a blunder does not squash the rest); values beyond go to the end bins. The y axis
// counts, with ticks; the <svg> has class "plot histogram"; without values its axes say "no data".
struct HistogramPlot {
  std::string title;           // the count of finite values is appended
  std::string x_label;         // with its unit
  std::vector<double> values;  // non-finite values are left out
  double lo = std::numeric_limits<double>::quiet_NaN();
  double hi = std::numeric_limits<double>::quiet_NaN();
};

// Points of a scatter plot (x, y) with a label each (its <title>), e.g. vertical errors by point.
struct ScatterPlot {
  std::string title;
  std::string x_label;  // with its unit
  std::string y_label;  // with its unit
  std::vector<double> x, y;
  std::vector<std::string> labels;
  bool zero_line = true;  // a dashed line at y = 0
};

// <svg> elements (no XML prolog): line plots 680 x 380, bar plots 680 wide, histograms 360 x 220.
std::string RenderLinePlotSvg(const LinePlot& plot);
std::string RenderBarPlotSvg(const BarPlot& plot);
// Small multiples of a line plot instead of overlapping lines: one <svg> 700 wide (the A4 content
// width) and 150 high holding a row of panels side by side, one per series with its label as the
// panel's title, on the same axes (y ticks labelled on the first panel, grid lines in all; the
// plot's title above, the axis titles once), the reference line in every panel and the other
// series drawn thin and grey behind the panel's own for comparison.
std::string RenderSmallMultiplesSvg(const LinePlot& plot);
std::string RenderHistogramSvg(const HistogramPlot& plot);
// 340 x 240: a small multiple (several side by side in a .plots row).
std::string RenderScatterPlotSvg(const ScatterPlot& plot);

}  // namespace photopose::cli
