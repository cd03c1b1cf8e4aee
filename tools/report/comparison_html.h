#pragma once
// The HTML report of `photopose compare`: one self-contained file (inline CSS and SVG, no script,
// no external resource) that opens in any browser without a server. Tables are those of
// tools/compare/comparison.h; the page head and the plots come from tools/report/html_kit.h.

#include <string>
#include <vector>

#include "tools/compare/block_comparison.h"
#include "tools/compare/comparison.h"
#include "tools/report/comparison_tables.h"
#include "tools/report/html_kit.h"

namespace photopose::cli {

// A TextTable as an HTML table (HtmlTable: its title as the caption, its notes under it); one of
// more than 10 value columns as blocks of columns one under the other, each repeating the naming
// columns (the title and notes once), so that it fits an A4 page.
std::string RenderHtmlTable(const TextTable& table);

// The glossary of the comparison pages: every solver name, loss suffix and column term
// (taylor_as_printed, NEES, t/ref, ...) in one sentence each, as a <dl class="glossary">.
std::string ComparisonGlossaryHtml();

// The solvers among `names` that tie for the best of `values` (smaller is better; non-finite ones
// never): within `relative` (unitless) of the smallest. Empty when none is finite.
std::vector<size_t> TiedBest(const std::vector<double>& values, double relative);

// The Monte-Carlo report: the verdict first (per scenario: the solvers that tie for the most
// accurate at the baseline, the fastest of them, whose covariance is honest, which stays robust at
// the most outliers), the glossary, then per scenario one row of small multiples per metric and
// sweep (a panel per solver side by side: error against noise, outliers and control points,
// success against outliers, initial error and control points, iterations against initial error,
// NEES against noise), the time per solve, and one table of every setting (a section each under
// one header). Compact for print: 7 A4 pages at the default scenarios (render_pages_test.py).
std::string MonteCarloHtml(const MonteCarloOptions& options, const MonteCarloResult& result,
                           const std::string& command_line);

// The dataset report: the verdict (solvers that solve every image, the ones that tie for the
// smallest residuals, the fastest of them), the glossary, the bar plots of time per solve and of
// the differences between the solvers (and to the reference when given), and the tables.
std::string DatasetHtml(const DatasetComparisonResult& result, const std::string& command_line);

// The block comparisons: the verdicts, the definitions and the tables.
std::string BlockComparisonHtml(const BlockComparisonOptions& options,
                                const BlockComparisonResult& result,
                                const std::string& command_line);

std::string BlockDatasetHtml(const BlockDatasetResult& result, const std::string& command_line);

}  // namespace photopose::cli
