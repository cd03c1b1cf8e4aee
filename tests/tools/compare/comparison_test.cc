// Tests of the comparison engine (tools/compare/comparison.h) and its HTML report: the statistics helpers
// against published values, one Monte-Carlo trial recomputed by calling the solver directly, the
// covariance honesty of a correctly weighted solver, and what the comparison must show.
#include "core/io/block_tables.h"
#include "tools/compare/comparison.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>

#include "core/camera.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_scene.h"
#include "solvers/resection/resection.h"
#include "tests/tools/cli_test_util.h"
#include "tools/report/comparison_html.h"
#include "tools/report/comparison_tables.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

// Chi-square quantiles are tabulated to 4-5 significant digits.
constexpr double kTableTolerance = 2e-3;
// The engine and the direct call run the same deterministic code on the same data.
constexpr double kSameComputationTolerance = 1e-9;

const SolverStatistics& StatisticsOf(const SettingResult& setting, const std::string& solver) {
  for (const SolverStatistics& s : setting.solvers)
    if (s.solver == solver) return s;
  ADD_FAILURE() << "no solver " << solver;
  return setting.solvers.front();
}

std::vector<SolverVariant> Variants(const std::string& solvers, const std::string& losses) {
  std::vector<SolverVariant> variants;
  const Status status = ParseSolverVariants(solvers, losses, &variants);
  EXPECT_TRUE(status.ok()) << status.message();
  return variants;
}

TEST(ComparisonStatistics, MeanNeesIntervalNarrowsAroundSix) {
  const NeesInterval one = MeanNeesInterval(1, 0.95);
  EXPECT_NEAR(one.lower, 1.2373, kTableTolerance);
  EXPECT_NEAR(one.upper, 14.449, kTableTolerance);
  // For many samples the mean of chi-square(6) is about normal: 6 +- z sqrt(12 / N).
  const int n = 2000;
  const NeesInterval many = MeanNeesInterval(n, 0.99);
  const double half_width = 2.5758 * std::sqrt(12.0 / n);
  EXPECT_NEAR(many.lower, 6.0 - half_width, 0.01);
  EXPECT_NEAR(many.upper, 6.0 + half_width, 0.01);
  EXPECT_TRUE(many.Contains(6.0));
  EXPECT_FALSE(many.Contains(6.5));
}

TEST(ComparisonStatistics, RotationErrorIsTheAngleBetweenTheRotations) {
  // Kappa differs by 10 arc-seconds: the angle between the rotations is 10 arc-seconds.
  const Eigen::Vector3d a(0.1, -0.2, 0.3);
  const Eigen::Vector3d b = a + Eigen::Vector3d(0, 0, 10.0 / kArcSecondsPerRadian);
  EXPECT_NEAR(RotationErrorArcSeconds(a, b), 10.0, 1e-6);
  // Accurate far below acos' resolution: 1e-9 rad.
  const Eigen::Vector3d c = a + Eigen::Vector3d(1e-9, 0, 0);
  EXPECT_NEAR(RotationErrorArcSeconds(a, c), 1e-9 * kArcSecondsPerRadian,
              1e-12 * kArcSecondsPerRadian);
  EXPECT_NEAR(RotationErrorArcSeconds(a, a), 0.0, 1e-9);
}

TEST(ComparisonStatistics, NeesOfAHandComputedCase) {
  ExteriorOrientation truth, estimate;
  truth.parameters << 100, 200, 300, 0.1, 0.2, kPi - 0.001;
  estimate.parameters << 101, 198, 300, 0.1, 0.2, -kPi + 0.001;  // kappa error 0.002 after wrapping
  Matrix6d covariance = Matrix6d::Zero();
  covariance.diagonal() << 1.0, 4.0, 1.0, 1e-6, 1e-6, 1e-6;
  // (1/1)^2 + (2/2)^2 + 0 + 0 + 0 + (0.002/0.001)^2 = 6.
  EXPECT_NEAR(NormalizedEstimationErrorSquared(estimate, truth, covariance), 6.0, 1e-6);
  // The other seed-angle triple of the same rotation: no rotation error, phi's sign flipped.
  ExteriorOrientation same = truth;
  same.parameters.tail<3>() << truth.parameters[3] + kPi, kPi - truth.parameters[4] + 0.001,
      truth.parameters[5] - kPi;
  covariance(4, 5) = covariance(5, 4) = 0.5e-6;
  EXPECT_NEAR(RotationErrorArcSeconds(truth.angles_seed_rad(), same.angles_seed_rad()),
              0.001 * kArcSecondsPerRadian, 1e-6);
  // phi' = pi - phi carries the error -0.001 with variance 1e-6; its covariance with kappa flips.
  const double expected = 0.001 * 0.001 / 1e-6 * (1.0 / (1.0 - 0.25));
  EXPECT_NEAR(NormalizedEstimationErrorSquared(same, truth, covariance), expected, 1e-6);
  covariance(0, 0) = -1.0;
  EXPECT_TRUE(std::isnan(NormalizedEstimationErrorSquared(estimate, truth, covariance)));
}

TEST(ComparisonOptions, ParsesSolversLossesAndInitialErrors) {
  std::vector<SolverVariant> variants = Variants("all", "none,huber");
  std::vector<std::string> names;
  for (const auto& v : variants) names.push_back(v.Name());
  EXPECT_EQ(names, (std::vector<std::string>{"taylor_as_printed", "taylor", "ceres_analytic/none",
                                             "ceres_analytic/huber", "ceres_autodiff/none",
                                             "ceres_autodiff/huber"}));
  EXPECT_EQ(variants[3].ApplyTo(ResectionOptions()).refinement.loss, LossType::kHuber);
  // Taylor: plain least squares.
  EXPECT_EQ(variants[1].ApplyTo(ResectionOptions()).refinement.loss, LossType::kNone);
  EXPECT_EQ(Variants("taylor,taylor,ceres_analytic", "all").size(), 7u);     // duplicates dropped
  Status status = ParseSolverVariants("taylor,newton", "none", &variants);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("'newton'"), std::string::npos);
  EXPECT_FALSE(ParseSolverVariants("ceres_analytic", "l2", &variants).ok());

  std::vector<InitialError> errors;
  ASSERT_TRUE(ParseInitialErrors("5:2,100:20.5", &errors).ok());
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[1].position_m, 100.0);
  EXPECT_EQ(errors[1].angle_deg, 20.5);
  for (const char* bad : {"5", "a:2", "5:", "-1:2", "5:2:1", ""})
    EXPECT_FALSE(ParseInitialErrors(bad, &errors).ok()) << bad;
}

TEST(ComparisonSweep, AxesVaryOneListAtATimeAndGridCombinesAll) {
  MonteCarloOptions options;
  options.scenarios = {Scenario::kNadir, Scenario::kOblique};
  options.noise_px = {0.5, 0.0, 1.0};
  options.outlier_fractions = {0.0, 0.2};
  options.control_points = {20};
  options.initial_errors = {{5, 2}, {50, 10}};
  options.sweep = SweepType::kAxes;
  const std::vector<SweepSetting> axes = MakeSweepSettings(options);
  ASSERT_EQ(axes.size(), 2u * (1 + 2 + 1 + 0 + 1));
  EXPECT_EQ(axes[0].axis, "baseline");
  EXPECT_EQ(axes[1].axis, "noise");
  EXPECT_EQ(axes[1].noise_px, 0.0);
  EXPECT_EQ(axes[1].outlier_fraction, 0.0);  // the other axes at their baseline
  options.sweep = SweepType::kGrid;
  EXPECT_EQ(MakeSweepSettings(options).size(), 2u * 3 * 2 * 1 * 2);
}

// The engine's numbers for one trial equal those of a direct call of the solver on the same scene.
TEST(ComparisonMonteCarlo, OneTrialAgreesWithADirectCallOfTheSolver) {
  MonteCarloOptions options;
  options.scenarios = {Scenario::kOblique};
  options.noise_px = {0.7};
  options.outlier_fractions = {0.1};
  options.initial_errors = {{20.0, 5.0}};
  options.trials = 3;
  options.seed = 41;
  options.solvers = Variants("taylor_as_printed,taylor,ceres_analytic", "none,cauchy");
  options.keep_samples = true;
  MonteCarloResult result;
  const Status status = RunMonteCarlo(options, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(result.settings.size(), 1u);
  const SettingResult& setting = result.settings[0];
  ASSERT_EQ(setting.samples.size(), 3u * options.solvers.size());

  // Trial 2, built by hand: the scene of seed 41 + 2, its control marks, the approximate frame as
  // the start.
  const int trial = 2;
  SyntheticSceneOptions scene_options = SceneOptionsFor(options, setting.setting, trial);
  EXPECT_EQ(scene_options.seed, 43u);
  SyntheticScene scene;
  ASSERT_TRUE(MakeSyntheticScene(scene_options, &scene).ok());
  ASSERT_EQ(scene.true_frames.size(), 1u);
  // The library's one assembly: the scene's tables into a block, its image into an input.
  Block block;
  ASSERT_TRUE(AssembleBlock(SceneBlockTables(scene), &block).ok());
  ResectionInput input;
  ASSERT_TRUE(MakeResectionInput(block, 0, ResectionInputOptions(), &input, nullptr).ok());
  ASSERT_TRUE(input.approximate.has_value());  // the scene's approximate frame as the start
  const ExteriorOrientation& truth = scene.true_frames[0].eo;
  int compared = 0;
  for (size_t s = 0; s < options.solvers.size(); ++s) {
    const ResectionResult direct =
        ResectImage(options.solvers[s].ApplyTo(options.resection), input);
    for (const SolveOutcome& sample : setting.samples) {
      if (sample.trial != trial || sample.solver != static_cast<int>(s)) continue;
      ++compared;
      ASSERT_EQ(sample.solved, direct.success) << result.solver_names[s];
      EXPECT_EQ(sample.iterations, direct.summary.iterations) << result.solver_names[s];
      if (!direct.success) continue;
      const double position_error =
          (direct.eo.center_in_ground() - truth.center_in_ground()).norm();
      EXPECT_NEAR(sample.position_error_m, position_error, kSameComputationTolerance)
          << result.solver_names[s];
      const Eigen::Matrix3d R_true =
          RotationFromAngles(RotationConvention::kSeed, truth.angles_seed_rad());
      const Eigen::Matrix3d R_est =
          RotationFromAngles(RotationConvention::kSeed, direct.eo.angles_seed_rad());
      const double angle =
          Eigen::AngleAxisd(R_true.transpose() * R_est).angle() * kArcSecondsPerRadian;
      EXPECT_NEAR(sample.rotation_error_arcsec, angle, 1e-3) << result.solver_names[s];
      EXPECT_NEAR(sample.sigma0, direct.sigma0, kSameComputationTolerance);
    }
  }
  EXPECT_EQ(compared, static_cast<int>(options.solvers.size()));
  // And the statistics are those of the samples: RMS of the solved position errors.
  for (size_t s = 0; s < options.solvers.size(); ++s) {
    double sum = 0.0;
    int solved = 0;
    for (const SolveOutcome& sample : setting.samples)
      if (sample.solver == static_cast<int>(s) && sample.solved)
        sum += sample.position_error_m * sample.position_error_m, ++solved;
    const SolverStatistics& stats = setting.solvers[s];
    EXPECT_EQ(stats.solved, solved);
    if (solved > 0) EXPECT_NEAR(stats.position_rmse_m, std::sqrt(sum / solved), 1e-12);
  }
}

// A correctly weighted solver on Gaussian noise reports an honest covariance: the mean NEES of
// 200 nadir trials with 20 control points lies in its 99% interval.
TEST(ComparisonMonteCarlo, NeesOfCorrectlyWeightedSolversIsWithinItsInterval) {
  MonteCarloOptions options;
  options.scenarios = {Scenario::kNadir};
  options.noise_px = {0.5};
  options.control_points = {20};
  options.trials = 200;
  options.seed = 7;
  options.solvers = Variants("taylor,ceres_analytic", "none");
  MonteCarloResult result;
  ASSERT_TRUE(RunMonteCarlo(options, &result).ok());
  for (const SolverStatistics& s : result.settings[0].solvers) {
    ASSERT_EQ(s.nees_count, 200) << s.solver;
    EXPECT_TRUE(s.nees_interval_99.Contains(s.mean_nees_apriori))
        << s.solver << ": " << s.mean_nees_apriori << " not in [" << s.nees_interval_99.lower
        << ", " << s.nees_interval_99.upper << "]";
    // The marks state their accuracy: the solver's covariance is the a-priori one
    // (PoseCovarianceFactor), its NEES the a-priori NEES, expected 6 (not 6 r / (r - 2)).
    EXPECT_EQ(s.expected_nees, 6.0) << s.solver;
    EXPECT_EQ(s.mean_nees, s.mean_nees_apriori) << s.solver;
    EXPECT_TRUE(s.nees_interval_99.Contains(s.mean_nees)) << s.solver << ": " << s.mean_nees;
    EXPECT_EQ(s.success_rate, 1.0) << s.solver;
  }
}

// What the comparison exists to show, in small seeded runs.
TEST(ComparisonMonteCarlo, ShowsTheMisprintAndThatDataSnoopingHandlesGrossErrors) {
  MonteCarloOptions options;
  options.scenarios = {Scenario::kOblique};
  options.noise_px = {0.5, 0.0};
  options.outlier_fractions = {0.0, 0.2};
  options.trials = 30;
  options.solvers = Variants("taylor_as_printed,taylor,ceres_analytic", "none,cauchy");
  MonteCarloResult result;
  ASSERT_TRUE(RunMonteCarlo(options, &result).ok());
  ASSERT_EQ(result.settings.size(), 3u);  // baseline, noise 0, outliers 0.2
  const SettingResult& noisy = result.settings[0];
  const SettingResult& exact = result.settings[1];
  const SettingResult& outliers = result.settings[2];
  ASSERT_EQ(exact.setting.noise_px, 0.0);
  ASSERT_EQ(outliers.setting.outlier_fraction, 0.2);
  // Noise-free: the truth is a fixed point of both Taylor variants; the misprint costs iterations
  // (linear instead of quadratic convergence at omega = 45 deg).
  EXPECT_LT(StatisticsOf(exact, "taylor").position_rmse_m, 1e-9);
  EXPECT_LT(StatisticsOf(exact, "taylor_as_printed").position_rmse_m, 1e-6);
  EXPECT_GT(StatisticsOf(exact, "taylor_as_printed").mean_iterations,
            2.0 * StatisticsOf(exact, "taylor").mean_iterations);
  // Noisy: the corrected Taylor and Ceres find the same least-squares pose; the misprinted normal
  // equations stop elsewhere, farther from the truth on average.
  EXPECT_NEAR(StatisticsOf(noisy, "taylor").position_rmse_m,
              StatisticsOf(noisy, "ceres_analytic/none").position_rmse_m, 1e-6);
  EXPECT_GT(StatisticsOf(noisy, "taylor_as_printed").position_rmse_m,
            StatisticsOf(noisy, "taylor").position_rmse_m);
  // 20% gross errors from approximate values: data snooping rejects them one at a time, so plain
  // least squares over the accepted marks succeeds (it failed in most trials when it kept every
  // mark) and is at least as accurate as the Cauchy loss.
  for (const char* solver : {"taylor", "ceres_analytic/none", "ceres_analytic/cauchy"})
    EXPECT_GE(StatisticsOf(outliers, solver).success_rate, 0.95) << solver;
  EXPECT_LE(StatisticsOf(outliers, "ceres_analytic/none").position_rmse_m,
            StatisticsOf(outliers, "ceres_analytic/cauchy").position_rmse_m);
  EXPECT_LT(StatisticsOf(outliers, "ceres_analytic/none").position_rmse_m,
            1.5 * StatisticsOf(noisy, "taylor").position_rmse_m);
}

// Why samples were not solved is told with the particulars of the first failure of each kind,
// numbers included (no '#' placeholders).
TEST(ComparisonMonteCarlo, FailureReasonsKeepTheirNumbers) {
  MonteCarloOptions options;
  options.scenarios = {Scenario::kNadir};
  options.control_points = {4};
  options.outlier_fractions = {0.25};  // one gross error among four marks: never solved
  options.check_points = 0;
  options.initial = InitialValues::kRansac;
  options.trials = 5;
  options.solvers = Variants("ceres_analytic", "none");
  MonteCarloResult result;
  ASSERT_TRUE(RunMonteCarlo(options, &result).ok());
  const SolverStatistics& s = result.settings[0].solvers[0];
  EXPECT_EQ(s.solved, 0);
  ASSERT_FALSE(s.failure_reasons.empty());
  EXPECT_EQ(s.failure_reasons[0].second, 5);
  const std::string& reason = s.failure_reasons[0].first;
  EXPECT_NE(reason.find("no redundancy"), std::string::npos) << reason;
  EXPECT_NE(reason.find_first_of("0123456789"), std::string::npos) << reason;
  for (const TextTable& table : MonteCarloTables(options, result))
    for (const std::string& note : table.notes) EXPECT_EQ(note.find('#'), std::string::npos) << note;
}

// The progress hook sees every trial once, the last call with done == total.
TEST(ComparisonMonteCarlo, ReportsProgressPerTrial) {
  MonteCarloOptions options;
  options.trials = 7;
  options.num_threads = 2;
  options.solvers = Variants("taylor", "none");
  std::mutex mutex;
  std::vector<size_t> done;
  size_t total = 0;
  options.progress = [&](size_t d, size_t t) {
    const std::lock_guard<std::mutex> lock(mutex);
    done.push_back(d);
    total = t;
    return true;
  };
  MonteCarloResult result;
  ASSERT_TRUE(RunMonteCarlo(options, &result).ok());
  EXPECT_EQ(total, 7u);
  ASSERT_EQ(done.size(), 7u);
  EXPECT_EQ(*std::max_element(done.begin(), done.end()), 7u);
}

// A hook that returns false cancels the run: no trial starts after it (one thread: exactly the
// trials before), and the call fails saying so, with no result.
TEST(ComparisonMonteCarlo, AProgressHookReturningFalseCancelsTheRun) {
  MonteCarloOptions options;
  options.trials = 7;
  options.num_threads = 1;
  options.solvers = Variants("taylor", "none");
  int calls = 0;
  options.progress = [&](size_t, size_t) { return ++calls < 3; };
  MonteCarloResult result;
  const Status status = RunMonteCarlo(options, &result);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), "cancelled by the progress hook after 3 of 7 trials");
  EXPECT_EQ(calls, 3);
  EXPECT_TRUE(result.settings.empty());
}

TEST(ComparisonMonteCarlo, RejectsInvalidOptions) {
  MonteCarloOptions options;
  options.solvers = Variants("taylor", "none");
  MonteCarloResult result;
  options.trials = 0;
  EXPECT_FALSE(RunMonteCarlo(options, &result).ok());
  options.trials = 1;
  options.outlier_fractions = {1.0};
  EXPECT_FALSE(RunMonteCarlo(options, &result).ok());
  options.outlier_fractions = {0.0};
  options.control_points = {2};
  EXPECT_FALSE(RunMonteCarlo(options, &result).ok());
  options.control_points = {20};
  options.solvers.clear();
  EXPECT_FALSE(RunMonteCarlo(options, &result).ok());
}

// Dataset mode on the bundled example (simulated UAV block with 5% gross errors) against its truth.
TEST(ComparisonDataset, EverySolverOnTheExampleWithItsTruthAsReference) {
  DatasetComparisonOptions options;
  options.job.files.cameras = testing::SourcePath("examples/cameras.csv");
  options.job.files.points = testing::SourcePath("examples/points.csv");
  options.job.files.marks = testing::SourcePath("examples/marks.csv");
  options.reference_path = testing::SourcePath("examples/truth/frames.csv");
  options.solvers = Variants("taylor_as_printed,taylor,ceres_analytic", "none,huber");
  DatasetComparisonResult result;
  const Status status = RunDatasetComparison(options, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(result.summaries.size(), 4u);
  EXPECT_TRUE(result.has_reference);
  EXPECT_EQ(result.reference_solver, "taylor");
  const int images = result.summaries[0].images;
  EXPECT_EQ(images, 12);
  EXPECT_EQ(result.solves.size(), static_cast<size_t>(images) * 4);
  for (const DatasetSolverSummary& s : result.summaries) {
    EXPECT_EQ(s.solved, images) << s.solver;
    EXPECT_EQ(s.referenced, images) << s.solver;
    EXPECT_LT(s.reference_position_m, 0.05) << s.solver;  // 0.5 px noise at 100 m
    EXPECT_NEAR(s.rms_sigma0, 1.0, 0.35) << s.solver;     // marks carry Accuracy = noise
  }
  // From the same RANSAC start and inliers, the corrected Taylor and plain Ceres agree; the
  // printed partials stop elsewhere (near nadir, by well under a millimetre).
  for (size_t i = 0; i < result.solves.size(); i += 4) {
    const DatasetSolve& taylor = result.solves[i + 1];
    const DatasetSolve& ceres = result.solves[i + 2];
    ASSERT_EQ(taylor.raster, ceres.raster);
    EXPECT_FALSE(taylor.has_difference);
    ASSERT_TRUE(ceres.has_difference);
    EXPECT_LT(ceres.difference_position_m, 1e-5);
    EXPECT_LT((taylor.eo.center_in_ground() - ceres.eo.center_in_ground()).norm(), 1e-5);
    EXPECT_LT(result.solves[i].difference_position_m, 5e-3);
  }
  const std::vector<TextTable> tables = DatasetTables(result);
  ASSERT_EQ(tables.size(), 2u);
  EXPECT_EQ(tables[0].rows.size(), 4u);
  EXPECT_EQ(tables[1].rows.size(), result.solves.size());
  EXPECT_EQ(testing::CountLines(DatasetCsv(result)), 1 + static_cast<int>(result.solves.size()));
}

// A hook that returns false after the first solver cancels the dataset comparison.
TEST(ComparisonDataset, AProgressHookReturningFalseCancelsTheRun) {
  DatasetComparisonOptions options;
  options.job.files.cameras = testing::SourcePath("examples/cameras.csv");
  options.job.files.points = testing::SourcePath("examples/points.csv");
  options.job.files.marks = testing::SourcePath("examples/marks.csv");
  options.solvers = Variants("taylor,ceres_analytic", "none");
  std::vector<size_t> done;
  options.progress = [&](size_t d, size_t) {
    done.push_back(d);
    return false;
  };
  DatasetComparisonResult result;
  const Status status = RunDatasetComparison(options, &result);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), "cancelled by the progress hook after 1 of 2 solvers");
  EXPECT_EQ(done, std::vector<size_t>{1});
}

TEST(ComparisonDataset, UnreadableInputIsAnError) {
  DatasetComparisonOptions options;
  options.job.files.cameras = "/nonexistent/cameras.csv";
  options.job.files.points = testing::SourcePath("examples/points.csv");
  options.job.files.marks = testing::SourcePath("examples/marks.csv");
  options.solvers = Variants("taylor", "none");
  DatasetComparisonResult result;
  const Status status = RunDatasetComparison(options, &result);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("cameras.csv"), std::string::npos);
}

// ------------------------------------------------------------------ rendering

TEST(ComparisonRendering, TextTableColumnsAreAligned) {
  TextTable table;
  table.title = "t";
  table.header = {"solver", "a", "value"};
  table.rows = {{"taylor", "1", "2.5"}, {"ceres_analytic/none", "100", "-"}};
  const std::string text = RenderText(table);
  std::istringstream lines(text);
  std::string line;
  std::getline(lines, line);  // title
  std::vector<size_t> widths;
  while (std::getline(lines, line)) widths.push_back(line.size());
  ASSERT_EQ(widths.size(), 4u);  // header, rule, two rows
  for (size_t w : widths) EXPECT_EQ(w, widths[0]) << text;
  const std::string markdown = RenderMarkdown(table);
  EXPECT_NE(markdown.find("| solver | a | value |"), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("|---|---:|---:|"), std::string::npos) << markdown;
}

TEST(ComparisonRendering, SvgPlotsAndTheReportAreSelfContained) {
  LinePlot plot;
  plot.title = "error <vs> noise";
  plot.x_label = "noise (px)";
  plot.y_label = "RMSE (m)";
  plot.log_y = true;
  plot.series = {{"a", {0, 0.5, 1}, {1e-12, 0.1, 0.2}},
                 {"b", {0, 0.5, 1}, {0.0, std::nan(""), 0.3}}};
  const std::string svg = RenderLinePlotSvg(plot);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("error &lt;vs&gt; noise"), std::string::npos);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
  EXPECT_NE(svg.find("<polyline"), std::string::npos);
  EXPECT_EQ(HtmlEscape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");

  MonteCarloOptions options;
  options.scenarios = {Scenario::kNadir};
  options.noise_px = {0.5, 1.0};
  options.initial_errors = {{5, 2}, {50, 10}};
  options.trials = 3;
  options.solvers = Variants("taylor,ceres_analytic", "none");
  MonteCarloResult result;
  ASSERT_TRUE(RunMonteCarlo(options, &result).ok());
  const std::string html = MonteCarloHtml(options, result, "photopose compare --trials=3");
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_GE(html.find("</html>"), html.size() - 10);
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("success rate vs initial error"), std::string::npos);
  EXPECT_NE(html.find("position RMSE vs noise"), std::string::npos);
  EXPECT_NE(html.find("median time per solve"), std::string::npos);
  // Nothing to fetch: no script, no external resource.
  for (const char* forbidden : {"<script", "src=", "href=", "@import", "url("})
    EXPECT_EQ(html.find(forbidden), std::string::npos) << forbidden;
  EXPECT_EQ(testing::CountLines(MonteCarloCsv(result)), 1 + 3 * 2);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
