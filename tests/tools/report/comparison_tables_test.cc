// The console tables of `photopose compare` (tools/report/comparison_tables.cc): at most
// kConsoleWidth characters wide, the naming column repeated in every block of columns, notes
// word-wrapped.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "tools/compare/comparison.h"
#include "tools/report/comparison_tables.h"

namespace photopose::cli {
namespace {

TEST(ComparisonTables, WideTablesWrapIntoBlocksWithinTheConsoleWidth) {
  TextTable table;
  table.title = "a table";
  table.header = {"solver"};
  for (int c = 0; c < 18; ++c) table.header.push_back("column_" + std::to_string(c));
  for (const char* solver : {"taylor", "ceres_autodiff/huber"}) {
    std::vector<std::string> row = {solver};
    for (int c = 0; c < 18; ++c) row.push_back(std::to_string(1000 + c));
    table.rows.push_back(row);
  }
  table.notes = {std::string(60, 'x') + " " + std::string(60, 'y') + " and more words"};
  const std::string text = RenderText(table);
  std::istringstream lines(text);
  std::string line;
  size_t widest = 0, solver_lines = 0, headers = 0;
  while (std::getline(lines, line)) {
    widest = std::max(widest, line.size());
    if (line.rfind("ceres_autodiff/huber", 0) == 0) ++solver_lines;
    if (line.rfind("solver", 0) == 0) ++headers;
  }
  EXPECT_LE(widest, kConsoleWidth) << text;
  EXPECT_GE(headers, 2u) << text;            // more than one block
  EXPECT_EQ(solver_lines, headers) << text;  // the solver named in each
  // Every column is somewhere, once.
  for (int c = 0; c < 18; ++c) {
    const std::string name = "column_" + std::to_string(c) + " ";
    EXPECT_NE(text.find("column_" + std::to_string(c)), std::string::npos) << c;
  }
  EXPECT_NE(text.find("\n    y"), std::string::npos) << text;  // the note's continuation line
}

TEST(ComparisonTables, NarrowTablesStayOneBlockAndNumbersPlain) {
  TextTable table;
  table.header = {"solver", "value"};
  table.rows = {{"taylor", "1"}};
  const std::string text = RenderText(table);
  EXPECT_EQ(text, "solver  value\n-------------\ntaylor      1\n");
  EXPECT_EQ(WrapText("one two three", "- ", "  ", 9), "- one two\n  three\n");
}

}  // namespace
}  // namespace photopose::cli
