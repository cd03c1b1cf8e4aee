#pragma once
// The HTML report of `photopose compare`: one self-contained file (inline CSS and SVG, no script,
// no external resource) that opens in any browser without a server. Tables are those of
// tools/compare/comparison.h; the plots are drawn here as SVG.

#include <limits>
#include <string>
#include <vector>

#include "tools/compare/comparison.h"

namespace photopose::cli {

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

// An <svg> element (no XML prolog), 680 x 380 user units for line plots.
std::string RenderLinePlotSvg(const LinePlot& plot);
std::string RenderBarPlotSvg(const BarPlot& plot);

// &, <, >, " and ' escaped.
std::string HtmlEscape(const std::string& text);
// A <table> with a <caption> (the title) and the notes as a list under it.
std::string RenderHtmlTable(const TextTable& table);

// The Monte-Carlo report: the command line, the definitions, and per scenario the plots (error
// against noise and outlier fraction, success against initial error and control points, NEES
// against noise, time per solve) and the tables of every setting.
std::string MonteCarloHtml(const MonteCarloOptions& options, const MonteCarloResult& result,
                           const std::string& command_line);

// The dataset report: the tables and bar plots of time per solve and of the differences between
// the solvers (and to the reference when given).
std::string DatasetHtml(const DatasetComparisonResult& result, const std::string& command_line);

}  // namespace photopose::cli
