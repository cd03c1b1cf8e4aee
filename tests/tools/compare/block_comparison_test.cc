#include "tools/compare/block_comparison.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/simulation/synthetic_block.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

TEST(BlockComparison, ParsesSolversAndLossesAndNamesWhatItRefuses) {
  std::vector<BlockSolverVariant> variants;
  ASSERT_TRUE(ParseBlockSolverVariants("taylor, ceres_analytic", "none,huber", &variants).ok());
  std::vector<std::string> names;
  for (const BlockSolverVariant& v : variants) names.push_back(v.Name());
  EXPECT_EQ(names, (std::vector<std::string>{"taylor", "taylor/huber", "ceres_analytic/none",
                                             "ceres_analytic/huber"}));
  const Status loss = ParseBlockSolverVariants("ceres_analytic", "tukey_typo", &variants);
  ASSERT_FALSE(loss.ok());
  EXPECT_NE(loss.message().find("'tukey_typo'"), std::string::npos) << loss.message();
  EXPECT_FALSE(ParseBlockSolverVariants("levmar", "none", &variants).ok());
  // The Taylor solvers run with every loss too (iteratively reweighted least squares).
  ASSERT_TRUE(ParseBlockSolverVariants("taylor,taylor_as_printed", "none,cauchy", &variants).ok());
  names.clear();
  for (const BlockSolverVariant& v : variants) names.push_back(v.Name());
  EXPECT_EQ(names, (std::vector<std::string>{"taylor", "taylor/cauchy", "taylor_as_printed",
                                             "taylor_as_printed/cauchy"}));
}

TEST(BlockComparison, TheTaylorSolverWithALossReachesCeresMinimumWithThatLoss) {
  BlockComparisonOptions options;
  ASSERT_TRUE(ParseBlockSolverVariants("taylor,ceres_analytic", "huber", &options.solvers).ok());
  options.tie_blunders = {6};
  options.tie_points = {400};
  options.lines = 3;
  options.images_per_line = 6;
  options.trials = 2;
  BlockComparisonResult result;
  ASSERT_TRUE(RunBlockComparison(options, &result).ok());
  EXPECT_EQ(result.solver_names, (std::vector<std::string>{"taylor/huber", "ceres_analytic/huber"}));
  const std::vector<BlockSolverStatistics>& row = result.statistics[0];
  EXPECT_EQ(row[0].successes, 2) << (row[0].failures.empty() ? "" : row[0].failures[0]);
  EXPECT_EQ(row[1].successes, 2) << (row[1].failures.empty() ? "" : row[1].failures[0]);
  // Its own reference: the offsets are Ceres' from taylor/huber, the same minimum.
  EXPECT_DOUBLE_EQ(row[0].time_ratio_to_taylor, 1.0);
  EXPECT_LT(row[1].max_position_offset_m, 1e-3);
}

TEST(BlockComparison, OneSettingPerAxisValueAndFiguresPerSolver) {
  BlockComparisonOptions options;
  ASSERT_TRUE(ParseBlockSolverVariants("taylor,ceres_analytic", "none", &options.solvers).ok());
  options.noise_px = {0.5, 1.0};
  options.tie_blunders = {0};
  options.tie_points = {120, 200};
  options.gnss_sigma_m = {0.03};
  options.lines = 2;
  options.images_per_line = 4;
  options.trials = 2;
  int progress_calls = 0;
  options.progress = [&](size_t done, size_t total) {
    ++progress_calls;
    EXPECT_LE(done, total);
    return true;
  };
  BlockComparisonResult result;
  const Status status = RunBlockComparison(options, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  // The baseline, then one setting per further value of an axis, the others at the baseline.
  ASSERT_EQ(result.settings.size(), 3u);
  EXPECT_EQ(result.settings[0].axis, "baseline");
  EXPECT_EQ(result.settings[1].axis, "noise_px");
  EXPECT_EQ(result.settings[1].noise_px, 1.0);
  EXPECT_EQ(result.settings[1].tie_points, 120);
  EXPECT_EQ(result.settings[2].axis, "tie_points");
  EXPECT_EQ(result.settings[2].tie_points, 200);
  EXPECT_EQ(result.settings[2].noise_px, 0.5);
  EXPECT_EQ(progress_calls, 6);  // 3 settings x 2 trials
  EXPECT_EQ(result.images_per_block, 8);
  ASSERT_EQ(result.statistics.size(), 3u);
  for (const std::vector<BlockSolverStatistics>& row : result.statistics) {
    ASSERT_EQ(row.size(), 2u);
    for (const BlockSolverStatistics& st : row) {
      EXPECT_EQ(st.trials, 2);
      EXPECT_EQ(st.successes, 2) << (st.failures.empty() ? "" : st.failures[0]);
      // Simulated with 0.5-1 px noise and 3 cm GNSS: centres within decimetres of the truth.
      EXPECT_GT(st.camera_rmse_m, 0.0);
      EXPECT_LT(st.camera_rmse_m, 0.2);
      EXPECT_GT(st.mean_iterations, 0.0);
    }
    // Taylor is the reference of times and offsets: its own ratio is 1 and its offset 0; the
    // Ceres solver reaches the same minimum (offsets of micrometres, not decimetres).
    EXPECT_DOUBLE_EQ(row[0].time_ratio_to_taylor, 1.0);
    EXPECT_EQ(row[0].max_position_offset_m, 0.0);
    EXPECT_TRUE(std::isfinite(row[1].time_ratio_to_taylor));
    EXPECT_LT(row[1].max_position_offset_m, 1e-3);
  }
  // More noise: larger errors on the same blocks (the seeds are the baseline's).
  EXPECT_GT(result.statistics[1][1].camera_rmse_m, result.statistics[0][1].camera_rmse_m);
}

TEST(BlockComparison, WithoutTaylorThereIsNoReference) {
  BlockComparisonOptions options;
  ASSERT_TRUE(ParseBlockSolverVariants("ceres_analytic", "none", &options.solvers).ok());
  options.tie_points = {120};
  options.lines = 2;
  options.images_per_line = 4;
  options.trials = 1;
  BlockComparisonResult result;
  ASSERT_TRUE(RunBlockComparison(options, &result).ok());
  ASSERT_EQ(result.statistics.size(), 1u);
  EXPECT_TRUE(std::isnan(result.statistics[0][0].time_ratio_to_taylor));
  EXPECT_TRUE(std::isnan(result.statistics[0][0].max_position_offset_m));
}

// A dataset block compared with and without a loss: "x Taylor" is against the Taylor solver
// without a loss (taylor), whatever follows it in the list (taylor/huber once was the baseline,
// and taylor showed 0.86 against itself); so taylor's own ratio is exactly 1.
// The dataset of the tests below: 2 lines of 4 images, 120 tie points.
Block DatasetBlock() {
  SyntheticBlockOptions o;
  o.seed = 5;
  o.num_lines = 2;
  o.images_per_line = 4;
  o.num_tie_points = 120;
  Block block;
  SyntheticBlockTruth truth;
  EXPECT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  return block;
}

TEST(BlockComparison, OnADatasetTheTaylorRowsOwnRatioIsOne) {
  const Block block = DatasetBlock();
  BlockDatasetOptions options;
  ASSERT_TRUE(
      ParseBlockSolverVariants("taylor,ceres_analytic", "none,huber", &options.solvers).ok());
  BlockDatasetResult result;
  ASSERT_TRUE(RunBlockDatasetComparison(options, block, &result).ok());
  ASSERT_EQ(result.solvers.size(), 4u);
  ASSERT_EQ(result.solvers[0].name, "taylor");
  ASSERT_EQ(result.solvers[1].name, "taylor/huber");
  ASSERT_TRUE(result.solvers[0].success) << result.solvers[0].message;
  EXPECT_EQ(result.solvers[0].time_ratio_to_taylor, 1.0);
  for (const BlockDatasetSolverSummary& s : result.solvers)
    EXPECT_EQ(s.time_ratio_to_taylor, s.seconds / result.solvers[0].seconds) << s.name;
}

// A hook that returns false cancels the run: no block (sweep) or solver (dataset) starts after
// it, and the call fails saying so.
TEST(BlockComparison, AProgressHookReturningFalseCancelsTheRun) {
  BlockComparisonOptions sweep;
  ASSERT_TRUE(ParseBlockSolverVariants("taylor", "none", &sweep.solvers).ok());
  sweep.noise_px = {0.5, 1.0};
  sweep.tie_points = {120};
  sweep.lines = 2;
  sweep.images_per_line = 4;
  sweep.trials = 2;
  sweep.num_threads = 1;
  int calls = 0;
  sweep.progress = [&](size_t, size_t) { return ++calls < 1; };
  BlockComparisonResult sweep_result;
  const Status swept = RunBlockComparison(sweep, &sweep_result);
  ASSERT_FALSE(swept.ok());
  EXPECT_EQ(swept.message(), "cancelled by the progress hook after 1 of 4 blocks");
  EXPECT_EQ(calls, 1);

  const Block block = DatasetBlock();
  BlockDatasetOptions dataset;
  ASSERT_TRUE(ParseBlockSolverVariants("taylor,ceres_analytic", "none", &dataset.solvers).ok());
  std::vector<size_t> done;
  dataset.progress = [&](size_t d, size_t total) {
    done.push_back(d);
    EXPECT_EQ(total, 2u);
    return false;
  };
  BlockDatasetResult dataset_result;
  const Status compared = RunBlockDatasetComparison(dataset, block, &dataset_result);
  ASSERT_FALSE(compared.ok());
  EXPECT_EQ(compared.message(), "cancelled by the progress hook after 1 of 2 solvers");
  EXPECT_EQ(done, std::vector<size_t>{1});
}

TEST(BlockComparison, RefusesInvalidOptionsWithTheReason) {
  BlockComparisonOptions options;
  BlockComparisonResult result;
  Status status = RunBlockComparison(options, &result);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), "no solver");
  ASSERT_TRUE(ParseBlockSolverVariants("taylor", "none", &options.solvers).ok());
  options.tie_points = {5};
  status = RunBlockComparison(options, &result);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), "tie points must be in [10, 1000000]");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
