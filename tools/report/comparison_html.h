#pragma once
// The HTML report of `photopose compare`: one self-contained file (inline CSS and SVG, no script,
// no external resource) that opens in any browser without a server. Tables are those of
// tools/compare/comparison.h; the page head and the plots come from tools/report/html_kit.h.

#include <string>

#include "tools/compare/comparison.h"
#include "tools/report/html_kit.h"

namespace photopose::cli {

// A TextTable as an HTML table (HtmlTable: its title as the caption, its notes under it).
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
