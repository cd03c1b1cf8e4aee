#pragma once
// The comparison results as text: the console and Markdown tables, the notes under them and the
// CSV files, of the Monte-Carlo and dataset comparisons (tools/compare/comparison.h) and of the
// block comparisons (tools/compare/block_comparison.h). The HTML pages: comparison_html.h.

#include <string>
#include <vector>

#include "tools/compare/block_comparison.h"
#include "tools/compare/comparison.h"

namespace photopose::cli {

// A table as text cells: rendered aligned for the terminal, as Markdown, or as HTML.
struct TextTable {
  std::string title;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> notes;  // lines printed under the table
};

// One sweep setting, for table titles and the comparison page: "oblique: noise 1 px, outliers
// 10%, 20 control points, initial error +-5 m +-2 deg (axis; 200 trials x 1 image)". The values
// through core/units.h: noise FormatSignificant in px, the outlier fraction in
// percent, the initial errors FormatScaledLength and FormatScaledAngle; never an exponent.
std::string SweepSettingTitle(const SweepSetting& setting, int trials, int images);

// One table per setting; its notes say why samples were not solved. The definitions of the columns
// are MonteCarloNotes. Every column of values is in the unit of its quantity (core/units.h
// FormatInOneUnit: lengths in the mm, cm or m of the column's largest, angle errors in arc seconds,
// marks in px), named in its header ("pos RMSE (cm)"); so are the other tables below.
std::vector<TextTable> MonteCarloTables(const MonteCarloOptions& options,
                                        const MonteCarloResult& result);
std::vector<TextTable> DatasetTables(const DatasetComparisonResult& result);

// The terminal's width the console tables keep to (characters).
constexpr size_t kConsoleWidth = 100;
// Right-aligned numeric columns, left-aligned first column (first two for per-image tables),
// title and notes; columns that do not fit in kConsoleWidth go to further blocks under the first,
// each repeating the naming columns; title and notes word-wrapped to kConsoleWidth.
std::string RenderText(const TextTable& table);
// `text` word-wrapped to `width` characters: the first line after `first_indent`, the others
// after `indent`; a final newline.
std::string WrapText(const std::string& text, const std::string& first_indent,
                     const std::string& indent, size_t width = kConsoleWidth);
std::string RenderMarkdown(const TextTable& table);

// One row per (scenario, setting, solver), full precision, units in the header names.
std::string MonteCarloCsv(const MonteCarloResult& result);
// One row per (image, solver).
std::string DatasetCsv(const DatasetComparisonResult& result);

// The definitions of the Monte-Carlo columns (success, RMSEs, times, NEES), one line each.
std::vector<std::string> MonteCarloNotes(const MonteCarloOptions& options);

// The block comparisons (--scenarios=block, and one given block).
std::vector<TextTable> BlockComparisonTables(const BlockComparisonOptions& options,
                                             const BlockComparisonResult& result);

std::string BlockComparisonCsv(const BlockComparisonResult& result);

TextTable BlockDatasetTable(const BlockDatasetResult& result);

std::string BlockDatasetCsv(const BlockDatasetResult& result);

}  // namespace photopose::cli
