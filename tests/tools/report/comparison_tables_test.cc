// The console tables of `photopose compare` (tools/report/comparison_tables.cc): columns in the
// units of their quantity, named in the header, never 0.000003 or an exponent; at most
// kConsoleWidth characters wide, the naming column repeated in every block of columns, notes
// word-wrapped; the sweep settings' titles in fixed notation with units.
#include "tools/report/comparison_tables.h"

#include <gtest/gtest.h>

#include <limits>
#include <regex>
#include <sstream>
#include <string>

#include "tools/compare/block_comparison.h"
#include "tools/compare/comparison.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

double kNaN() { return std::numeric_limits<double>::quiet_NaN(); }

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


// What a reader cannot use in a console table: an exponent, or a value below its unit's decimals
// (0.000003: a length or an angle printed in raw metres or degrees).
void ExpectReadable(const std::string& text) {
  EXPECT_FALSE(std::regex_search(text, std::regex("[0-9.][eE][+-]?[0-9]"))) << text;
  EXPECT_FALSE(std::regex_search(text, std::regex("(^|[^0-9.])-?0\\.0000[0-9]"))) << text;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) EXPECT_LE(line.size(), kConsoleWidth) << line;
}

// The column named `name` with its unit, e.g. "pos RMSE (cm)": its index in the header.
size_t ColumnOf(const TextTable& table, const std::string& header) {
  for (size_t c = 0; c < table.header.size(); ++c)
    if (table.header[c] == header) return c;
  ADD_FAILURE() << "no column " << header;
  return 0;
}

// Monte-Carlo columns in the units: each length column in the mm, cm or m of its largest
// value, angle errors in arc seconds, marks in pixels, the unit in the header and never in a cell.
TEST(ComparisonTables, MonteCarloColumnsTakeTheUnitOfTheirQuantity) {
  MonteCarloOptions options;
  options.trials = 10;
  MonteCarloResult result;
  result.solver_names = {"taylor", "ceres_analytic/none"};
  SettingResult setting;
  setting.setting = Setting(0.5, 0.0, 20, 5.0, 2.0, "baseline");
  setting.images_per_trial = 1;
  for (int s = 0; s < 2; ++s) {
    SolverStatistics st;
    st.solver = result.solver_names[s];
    st.samples = st.solved = st.successes = 10;
    st.success_rate = 1.0;
    st.position_rmse_m = s == 0 ? 0.166 : 0.165;             // cm
    st.rotation_rmse_arcsec = 40.7;                           // arcsec
    st.difference_position_rmse_m = s == 0 ? kNaN() : 3e-9;   // rounding: mm, "0.0"
    st.difference_rotation_rmse_arcsec = s == 0 ? kNaN() : 3e-6;
    st.check_rmse_px = 0.8934;
    st.reprojection_rmse_px = 0.000003;
    st.mean_iterations = 5.1;
    st.median_seconds = 13.2e-6;
    st.median_refinement_seconds = 11.8e-6;
    st.mean_nees = st.mean_nees_apriori = 6.92;
    st.expected_nees = 6.38;
    st.nees_count = 10;
    st.nees_interval_99 = {3.55, 9.2};
    setting.solvers.push_back(st);
  }
  result.settings = {setting};
  const std::vector<TextTable> tables = MonteCarloTables(options, result);
  ASSERT_EQ(tables.size(), 1u);
  const TextTable& table = tables[0];
  const size_t pos = ColumnOf(table, "pos RMSE (cm)");
  EXPECT_EQ(table.rows[0][pos], "16.6");
  EXPECT_EQ(table.rows[0][ColumnOf(table, "rot RMSE (arcsec)")], "40.7");
  const size_t d_ref = ColumnOf(table, "d_ref pos (mm)");
  EXPECT_EQ(table.rows[0][d_ref], "-");  // the reference itself
  EXPECT_EQ(table.rows[1][d_ref], "0.0");
  EXPECT_EQ(table.rows[1][ColumnOf(table, "d_ref rot (arcsec)")], "0.0");
  EXPECT_EQ(table.rows[0][ColumnOf(table, "check RMSE (px)")], "0.89");
  EXPECT_EQ(table.rows[0][ColumnOf(table, "reproj RMSE (px)")], "0.00");
  EXPECT_EQ(table.rows[0][ColumnOf(table, "99% int")], "[3.55, 9.20]");
  ExpectReadable(RenderText(table));
  // A diverged solver moves the whole column to metres, not one row.
  result.settings[0].solvers[1].position_rmse_m = 25.0;
  const TextTable diverged = MonteCarloTables(options, result)[0];
  EXPECT_EQ(diverged.rows[0][ColumnOf(diverged, "pos RMSE (m)")], "0.166");
  EXPECT_EQ(diverged.rows[1][ColumnOf(diverged, "pos RMSE (m)")], "25.000");
}

TEST(ComparisonTables, BlockAndDatasetColumnsTakeTheUnitOfTheirQuantity) {
  BlockComparisonOptions options;
  BlockComparisonResult result;
  result.settings = {BlockSetting{}};
  result.settings[0].axis = "baseline";
  result.solver_names = {"taylor", "ceres_analytic/none"};
  result.images_per_block = 24;
  result.statistics.resize(1);
  for (int s = 0; s < 2; ++s) {
    BlockSolverStatistics st;
    st.trials = st.successes = 2;
    st.camera_rmse_m = 0.01104;
    st.check_rmse_m = 0.00694;
    st.mean_nees = 3.38;
    st.nees_count = 48;
    st.nees_interval_95 = {2.35, 3.73};
    st.mean_seconds = 0.0305;
    st.time_ratio_to_taylor = s == 0 ? 1.0 : 1.07;
    st.max_position_offset_m = s == 0 ? 0.0 : 2.4e-7;
    result.statistics[0].push_back(st);
  }
  const std::vector<TextTable> tables = BlockComparisonTables(options, result);
  ASSERT_EQ(tables.size(), 1u);
  EXPECT_EQ(tables[0].rows[0][ColumnOf(tables[0], "camera RMSE (mm)")], "11.0");
  EXPECT_EQ(tables[0].rows[1][ColumnOf(tables[0], "max offset from Taylor (mm)")], "0.0");
  ExpectReadable(RenderText(tables[0]));

  DatasetComparisonResult dataset;
  dataset.solver_names = {"taylor", "ceres_analytic/none"};
  dataset.reference_solver = "taylor";
  dataset.has_reference = true;
  for (int s = 0; s < 2; ++s) {
    DatasetSolverSummary summary;
    summary.solver = dataset.solver_names[s];
    summary.images = summary.solved = 12;
    summary.rms_sigma0 = 1.008;
    summary.rms_px = 0.689;
    summary.median_seconds = 2.8e-3;
    summary.compared = s;
    summary.difference_position_m = 1.84e-9;
    summary.difference_rotation_arcsec = 3.34e-6;
    summary.referenced = 12;
    summary.reference_position_m = 0.0138;
    summary.reference_rotation_arcsec = 24.2;
    dataset.summaries.push_back(summary);
  }
  const TextTable summary = DatasetTables(dataset)[0];
  EXPECT_EQ(summary.rows[1][ColumnOf(summary, "d_ref pos (mm)")], "0.0");
  EXPECT_EQ(summary.rows[0][ColumnOf(summary, "d_frames pos (mm)")], "13.8");
  EXPECT_EQ(summary.rows[0][ColumnOf(summary, "d_frames rot (arcsec)")], "24.2");
  EXPECT_EQ(summary.rows[0][ColumnOf(summary, "sigma0")], "1.008");
  ExpectReadable(RenderText(summary));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
