// The console tables of `photopose compare` (tools/report/comparison_tables.cc): at most
// kConsoleWidth characters wide, the naming column repeated in every block of columns, notes
// word-wrapped; the sweep settings' titles in fixed notation with units.
#include "tools/report/comparison_tables.h"

#include <gtest/gtest.h>

#include <regex>
#include <sstream>
#include <string>

#include "tools/compare/comparison.h"

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

SweepSetting Setting(double noise_px, double outlier_fraction, int control_points,
                     double position_m, double angle_deg, const std::string& axis) {
  SweepSetting setting;
  setting.scenario = Scenario::kNadir;
  setting.noise_px = noise_px;
  setting.outlier_fraction = outlier_fraction;
  setting.control_points = control_points;
  setting.initial_error.position_m = position_m;
  setting.initial_error.angle_deg = angle_deg;
  setting.axis = axis;
  return setting;
}

// A sweep setting's title: fixed notation with units, never printf's %g exponents ("noise 1e-05
// px", "+-0.0001 m +-1e-05 deg").
TEST(ComparisonTables, SweepSettingTitlesPrintFixedValuesWithUnits) {
  EXPECT_EQ(SweepSettingTitle(Setting(0.5, 0.1, 20, 5.0, 2.0, "baseline"), 200, 1),
            "nadir: noise 0.5 px, outliers 10%, 20 control points, initial error +-5 m +-2 deg "
            "(baseline; 200 trials x 1 image)");
  const std::string tiny =
      SweepSettingTitle(Setting(1e-5, 0.000001, 1, 0.0001, 1e-5, "noise"), 1, 6);
  EXPECT_EQ(tiny,
            "nadir: noise 0.00001 px, outliers 0.0001%, 1 control point, initial error +-0.1 mm "
            "+-0.036 arcsec (noise; 1 trial x 6 images)");
  const std::string large =
      SweepSettingTitle(Setting(12345.678, 0.000001, 1, 0.0123456, 0.5, "noise"), 10, 2);
  EXPECT_EQ(large,
            "nadir: noise 12346 px, outliers 0.0001%, 1 control point, initial error +-12.35 mm "
            "+-0.5 deg (noise; 10 trials x 2 images)");
  for (const std::string& title : {tiny, large})
    EXPECT_FALSE(std::regex_search(title, std::regex("[0-9.][eE][+-]?[0-9]"))) << title;
}

}  // namespace
}  // namespace photopose::cli
