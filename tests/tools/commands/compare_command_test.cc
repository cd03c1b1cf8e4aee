// End-to-end tests of `photopose compare`: the executable as a user runs it.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include "tests/tools/cli_test_util.h"
#include "tools/compare/comparison.h"
#include "tools/report/comparison_tables.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::CliRun;
using testing::CountLines;
using testing::ReadFile;
using testing::RunCli;
using testing::ScratchDir;
using testing::SourcePath;
using testing::SplitCsvText;
using testing::WriteFile;

// The CSV carries ten significant digits.
constexpr double kCsvRelativeTolerance = 1e-8;

size_t Column(const std::vector<std::string>& header, const std::string& name) {
  for (size_t c = 0; c < header.size(); ++c)
    if (header[c] == name) return c;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// Lines of the terminal output that start with the solver's name.
int RowsStartingWith(const std::string& out, const std::string& name) {
  int rows = 0;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) rows += line.rfind(name + " ", 0) == 0;
  return rows;
}

// The longest line of the output that does not name a file under `dir` (a path is not wrapped).
size_t LongestLine(const std::string& out, const std::string& dir) {
  size_t longest = 0;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);)
    if (line.find(dir) == std::string::npos) longest = std::max(longest, line.size());
  return longest;
}

constexpr char kSmallSweep[] =
    "compare --scenarios=nadir --trials=6 --seed=5 --noise_px=0.5 --outlier_fractions=0,0.2 "
    "--control_points=20 --initial_errors=5:2 --losses=none,cauchy";

// Ctrl-C (SIGINT) during a Monte-Carlo sweep: no trial starts after the next progress call, no
// table is printed, no --csv written, exit status 130. The signal follows the first progress line
// (after 2 s), of a sweep far longer than that.
TEST(CompareCommand, SigintCancelsTheSweepAndNothingIsWritten) {
  const std::string dir = ScratchDir();
  const CliRun run = testing::RunCliAndSignal(
      {"compare", "--scenarios=nadir", "--trials=100000", "--threads=1", "--solvers=taylor",
       "--losses=none", "--csv=" + dir + "/c.csv"},
      dir, " trials (", SIGINT);
  EXPECT_EQ(run.exit_code, 130) << run.err;
  EXPECT_NE(run.err.find("photopose compare: cancelled by SIGINT while comparing; nothing "
                         "written\n"),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/c.csv"));
  EXPECT_EQ(run.out, "");
}

TEST(CompareCommand, MonteCarloRunsWritesEveryOutputAndAgreesWithTheEngine) {
  const std::string dir = ScratchDir();
  const CliRun run = RunCli(std::string(kSmallSweep) + " --csv=" + dir + "/c.csv --html=" + dir +
                                "/r.html --markdown=" + dir + "/t.md",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Nothing on stderr but the progress lines a slow run (a sanitizer build) shows after 2 s.
  std::istringstream err_lines(run.err);
  for (std::string line; std::getline(err_lines, line);)
    EXPECT_NE(line.find(" trials ("), std::string::npos) << line;
  // Two settings, each with a row per solver in each block of columns (one header per block),
  // every line within the console width.
  const std::vector<std::string> solvers = {"taylor_as_printed",   "taylor",
                                            "ceres_analytic/none", "ceres_analytic/cauchy",
                                            "ceres_autodiff/none", "ceres_autodiff/cauchy"};
  const int headers = RowsStartingWith(run.out, "solver");
  EXPECT_GE(headers, 2);
  EXPECT_EQ(headers % 2, 0);
  for (const std::string& solver : solvers)
    EXPECT_EQ(RowsStartingWith(run.out, solver), headers) << solver;
  EXPECT_LE(LongestLine(run.out, dir), cli::kConsoleWidth) << run.out;
  const std::string html = ReadFile(dir + "/r.html");
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_NE(ReadFile(dir + "/t.md").find("| taylor |"), std::string::npos);

  // The CSV equals a direct run of the engine with the same options.
  const auto csv = SplitCsvText(ReadFile(dir + "/c.csv"));
  ASSERT_EQ(csv.size(), 1u + 2 * solvers.size());
  cli::MonteCarloOptions options;
  options.scenarios = {Scenario::kNadir};
  options.trials = 6;
  options.seed = 5;
  options.noise_px = {0.5};
  options.outlier_fractions = {0.0, 0.2};
  options.control_points = {20};
  options.initial_errors = {{5.0, 2.0}};
  ASSERT_TRUE(cli::ParseSolverVariants("all", "none,cauchy", &options.solvers).ok());
  cli::MonteCarloResult result;
  ASSERT_TRUE(cli::RunMonteCarlo(options, &result).ok());
  const auto& header = csv[0];
  const size_t solver_column = Column(header, "solver");
  const size_t fraction_column = Column(header, "outlier_fraction");
  int checked = 0;
  for (size_t row = 1; row < csv.size(); ++row) {
    const size_t setting = std::stod(csv[row][fraction_column]) > 0.0 ? 1 : 0;
    for (const cli::SolverStatistics& s : result.settings[setting].solvers) {
      if (s.solver != csv[row][solver_column]) continue;
      ++checked;
      EXPECT_EQ(std::stoi(csv[row][Column(header, "solved")]), s.solved);
      EXPECT_EQ(std::stoi(csv[row][Column(header, "successes")]), s.successes);
      const std::string rmse = csv[row][Column(header, "position_rmse_m")];
      if (s.solved == 0) {
        EXPECT_EQ(rmse, "");
      } else {
        EXPECT_NEAR(std::stod(rmse), s.position_rmse_m, kCsvRelativeTolerance * s.position_rmse_m);
      }
    }
  }
  EXPECT_EQ(checked, static_cast<int>(2 * solvers.size()));
}

TEST(CompareCommand, DatasetModeComparesEverySolverToTheReference) {
  const std::string dir = ScratchDir();
  const CliRun run =
      RunCli("compare --cameras=" + SourcePath("examples/cameras.csv") +
                 " --points=" + SourcePath("examples/points.csv") +
                 " --marks=" + SourcePath("examples/marks.csv") +
                 " --reference=" + SourcePath("examples/truth/frames.csv") +
                 " --solvers=taylor_as_printed,taylor,ceres_analytic --losses=huber --csv=" + dir +
                 "/d.csv --html=" + dir + "/d.html",
             dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // The summary table: a row per solver in each of its blocks of columns.
  for (const char* solver : {"taylor_as_printed", "taylor", "ceres_analytic/huber"})
    EXPECT_EQ(RowsStartingWith(run.out, solver), RowsStartingWith(run.out, "solver")) << solver;
  EXPECT_LE(LongestLine(run.out, dir), cli::kConsoleWidth) << run.out;
  const auto csv = SplitCsvText(ReadFile(dir + "/d.csv"));
  ASSERT_EQ(csv.size(), 1u + 12 * 3);
  const size_t success = Column(csv[0], "Success");
  const size_t reference = Column(csv[0], "RefPositionM");
  for (size_t row = 1; row < csv.size(); ++row) {
    EXPECT_EQ(csv[row][success], "1");
    EXPECT_LT(std::stod(csv[row][reference]), 0.05);
  }
  const std::string html = ReadFile(dir + "/d.html");
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
}

TEST(CompareCommand, HelpAndFlagfile) {
  const std::string dir = ScratchDir();
  CliRun run = RunCli("compare --help", dir);
  EXPECT_EQ(run.exit_code, 0);
  for (const char* flag : {"--losses", "--solvers", "--noise_px", "--initial_errors", "--reference",
                           "--html", "--csv"})
    EXPECT_NE(run.out.find(std::string("  ") + flag + " ("), std::string::npos) << flag;
  EXPECT_EQ(run.out.find("compare_"), std::string::npos);  // internal flag names stay hidden
  WriteFile(dir + "/flags", "# a small sweep\n--scenarios=nadir\n--trials 2\n--solvers=taylor\n");
  run = RunCli("compare --flagfile=" + dir + "/flags --noise_px=1", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("noise 1 px"), std::string::npos);
  // Axes sweep with the default lists: baseline, 2 outlier fractions, 1 control count, 2 initial
  // errors (the noise list has one value): 6 tables, each with the same blocks of columns.
  const int headers = RowsStartingWith(run.out, "solver");
  EXPECT_GE(headers, 6);
  EXPECT_EQ(headers % 6, 0);
  EXPECT_EQ(RowsStartingWith(run.out, "taylor"), headers);
}

struct UsageCase {
  const char* name;
  const char* arguments;
  const char* expected_message;
};

void PrintTo(const UsageCase& c, std::ostream* os) { *os << c.name; }

class CompareBadUsage : public ::testing::TestWithParam<UsageCase> {};

TEST_P(CompareBadUsage, ExitsWithTwoAndOneLine) {
  const UsageCase& c = GetParam();
  const std::string dir = ScratchDir();
  std::string arguments = c.arguments;
  const std::string examples = SourcePath("examples");
  for (size_t at; (at = arguments.find("EX")) != std::string::npos;)
    arguments.replace(at, 2, examples);
  const CliRun run = RunCli("compare " + arguments, dir);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_EQ(run.err.rfind("photopose compare: ", 0), 0u) << run.err;
  EXPECT_NE(run.err.find(c.expected_message), std::string::npos) << run.err;
  EXPECT_EQ(run.out, "");
}

INSTANTIATE_TEST_SUITE_P(
    CompareCommandUsage, CompareBadUsage,
    ::testing::Values(
        UsageCase{"unknown_flag", "--bogus=1", "unknown flag --bogus"},
        UsageCase{"another_commands_flag", "--out=x.csv", "unknown flag --out"},
        UsageCase{"unknown_solver", "--solvers=taylor,newton", "'newton'"},
        UsageCase{"unknown_loss", "--losses=l2", "'l2'"},
        UsageCase{"bad_noise", "--noise_px=0.5,abc", "--noise_px"},
        UsageCase{"bad_initial_error", "--initial_errors=5", "--initial_errors"},
        UsageCase{"bad_fraction", "--outlier_fractions=1.5", "--outlier_fractions=1.5 is outside [0, 1)"},
        UsageCase{"too_few_points", "--control_points=2", "--control_points=2 is outside [3, 10000]"},
        UsageCase{"unknown_scenario", "--scenarios=moon", "'moon'"},
        UsageCase{"bad_sweep", "--sweep=zigzag", "--sweep"},
        UsageCase{"bad_initial", "--initial=guess", "--initial"},
        UsageCase{"bad_number", "--threads=many", "invalid value 'many' for --threads"},
        UsageCase{"missing_value", "--trials", "--trials needs a value"},
        UsageCase{"stray_argument", "nadir", "unexpected argument 'nadir'"},
        UsageCase{"dataset_flag_without_cameras", "--reference=EX/truth/frames.csv",
                  "dataset mode only"},
        UsageCase{"monte_carlo_flag_with_cameras",
                  "--cameras=EX/cameras.csv --points=EX/points.csv --marks=EX/marks.csv --trials=2",
                  "--trials applies to the Monte-Carlo mode only"},
        UsageCase{"missing_output_folder", "--csv=/nonexistent/folder/c.csv",
                  "--csv=/nonexistent/folder/c.csv: the folder '/nonexistent/folder' does not exist"},
        UsageCase{"rows_up_without_tables", "--pixel_rows_up", "dataset mode only"},
        UsageCase{"rows_up_with_a_colmap_model",
                  "--scenarios=block --colmap_model=EX --pixel_rows_up",
                  "--pixel_rows_up applies to the tables: a COLMAP model defines its own pixels"},
        UsageCase{"sweep_flag_in_dataset_mode",
                  "--cameras=EX/cameras.csv --points=EX/points.csv --sweep=axes",
                  "--sweep applies"}),
    [](const ::testing::TestParamInfo<UsageCase>& info) { return std::string(info.param.name); });

TEST(CompareCommand, DatasetInputErrorsExitWithTwo) {
  const std::string dir = ScratchDir();
  const std::string examples = SourcePath("examples");
  CliRun run = RunCli(
      "compare --cameras=" + examples + "/cameras.csv --points=" + examples + "/points.csv", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--points and --marks"), std::string::npos) << run.err;
  run = RunCli("compare --cameras=" + dir + "/none.csv --points=" + examples +
                   "/points.csv --marks=" + examples + "/marks.csv --csv=" + dir + "/o.csv",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("none.csv"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/o.csv"));
  run = RunCli("compare --cameras=" + examples + "/cameras.csv --points=" + examples +
                   "/points.csv --marks=" + examples + "/marks.csv --rotation=xyz",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--rotation"), std::string::npos) << run.err;
}

TEST(CompareCommand, BlockModeComparesTheBlockSolversOnTheSameBlocks) {
  const std::string dir = testing::ScratchDir();
  const testing::CliRun run = testing::RunCli(
      "compare --scenarios=block --trials=2 --noise_px=0.5 --tie_blunders=0,5 --tie_points=300 "
      "--gnss_sigma=0.03 --losses=none --csv=" + dir + "/blocks.csv --html=" + dir + "/blocks.html",
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string csv = testing::ReadFile(dir + "/blocks.csv");
  // Two settings (baseline, 5 tie blunders) x four solvers, after the header.
  std::vector<std::map<std::string, std::string>> rows;
  std::vector<std::string> header;
  std::stringstream lines(csv);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    if (header.empty()) {
      header = cells;
      continue;
    }
    std::map<std::string, std::string> row;
    for (size_t k = 0; k < cells.size() && k < header.size(); ++k) row[header[k]] = cells[k];
    rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 8u) << csv;
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("Successes"), "2") << row.at("Solver");
    const double offset = std::stod(row.at("MaxOffsetFromTaylorM"));
    // Ceres, analytic or autodiff, reaches the corrected Taylor's minimum; the printed eq. 21
    // lands elsewhere.
    if (row.at("Solver").rfind("ceres", 0) == 0) EXPECT_LT(offset, 1e-5) << row.at("Solver");
    if (row.at("Solver") == "taylor_as_printed") EXPECT_GT(offset, 1e-5);
    EXPECT_LT(std::stod(row.at("CameraRmseM")), 0.05) << row.at("Solver");
  }
  EXPECT_NE(testing::ReadFile(dir + "/blocks.html").find("<h2>Verdict</h2>"), std::string::npos);
  // Flags of the other scenarios are refused with blocks, and block flags without them.
  EXPECT_EQ(testing::RunCli("compare --scenarios=block --outlier_fractions=0.1", dir).exit_code, 2);
  EXPECT_EQ(testing::RunCli("compare --scenarios=nadir --tie_points=100", dir).exit_code, 2);
}

TEST(CompareCommand, BlockDatasetModeComparesTheSolversOnOneBlock) {
  const std::string dir = testing::ScratchDir();
  testing::CliRun run = testing::RunCli(
      "simulate --scenario=block --lines=3 --images_per_line=6 --seed=4 --colmap --out_dir=" + dir +
          "/block",
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string b = dir + "/block";
  run = testing::RunCli("compare --scenarios=block --losses=none --cameras=" + b +
                            "/cameras.csv --points=" + b + "/points.csv --marks=" + b +
                            "/marks.csv --frames=" + b + "/frames.csv --csv=" + dir + "/one.csv",
                        dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string csv = testing::ReadFile(dir + "/one.csv");
  std::stringstream lines(csv);
  std::string line;
  std::getline(lines, line);  // header
  int rows = 0;
  while (std::getline(lines, line)) {
    ++rows;
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    ASSERT_GE(cells.size(), 3u);
    EXPECT_EQ(cells[1], "1") << line;  // converged
    // Offsets from the Ceres solution: Taylor and the other Ceres path at the same minimum, the
    // printed eq. 21 off it.
    if (cells[0] == "taylor_as_printed") {
      EXPECT_GT(std::stod(cells[3]), 1e-5) << line;
    } else {
      EXPECT_LT(std::stod(cells[3]), 1e-5) << line;
    }
  }
  EXPECT_EQ(rows, 4);
  // The same on the COLMAP model of the block (a relative block: offsets in its own frame).
  run = testing::RunCli("compare --scenarios=block --losses=none --solvers=taylor,ceres_analytic "
                        "--colmap_model=" + b + "/colmap",
                        dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("ceres_analytic/none"), std::string::npos) << run.out;
  // Without control points and frames no image can be oriented: each named, then one closing line
  // saying nothing was written.
  run = testing::RunCli("compare --scenarios=block --losses=none --cameras=" + b +
                            "/cameras.csv --marks=" + b + "/marks.csv --csv=" + dir + "/none.csv",
                        dir);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find(": not oriented: "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("photopose compare: 18 images could not be oriented; nothing compared, "
                         "nothing written\n"),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/none.csv"));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
