#include "solvers/resection/data_snooping.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/resection/pose_refinement.h"
#include "tests/solvers/resection/scene_input.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// A clean synthetic image with n marks of 1 px noise (Accuracy 1 px), as the resection input, and
// the least-squares pose of all its marks.
struct Adjusted {
  ResectionInput input;
  std::vector<double> sigmas;  // image-plane units
  ExteriorOrientation eo;
};

Adjusted Adjust(int n, uint64_t seed, double noise_px = 1.0) {
  SyntheticSceneOptions options;
  options.seed = seed;
  options.noise_px = noise_px;
  options.num_control_points = n;
  options.num_check_points = 0;
  const testing::SceneInput s = testing::MakeSceneInput(options);
  Adjusted a{s.input, s.sigmas, s.truth};
  PoseRefinementSummary summary;
  EXPECT_TRUE(RefinePose(PoseRefinementOptions(), a.input.image_plane, a.input.points_in_ground,
                         a.sigmas, a.input.focal_length, s.all, &a.eo, &summary));
  return a;
}

// delta0 of the 2-D test at alpha = 0.001 and power 0.8, evaluated independently (the Poisson
// series of the non-central chi-square(2) in Python, and 200000 Monte Carlo draws at that lambda
// exceeding 13.8 with frequency 0.7995); the series converges to 1e-12, the bisection to 1e-9.
TEST(DataSnooping, DetectableBiasMatchesAnIndependentEvaluation) {
  constexpr double kIndependentDigits = 1e-6;
  EXPECT_NEAR(DetectableBiasSigmas(0.999, 0.8), 4.434228863, kIndependentDigits);
  // More power or more confidence needs a larger blunder.
  EXPECT_GT(DetectableBiasSigmas(0.999, 0.9), DetectableBiasSigmas(0.999, 0.8));
  EXPECT_GT(DetectableBiasSigmas(0.9999, 0.8), DetectableBiasSigmas(0.999, 0.8));
}

TEST(DataSnooping, CriticalValuesByHand) {
  // chi-square(2): P(X > x) = exp(-x / 2).
  EXPECT_NEAR(SnoopingCriticalValue(0.999), -2.0 * std::log(0.001), 1e-12);
  EXPECT_NEAR(MarkThresholdSigmas(0.999), 3.7169, 1e-4);
  // Tau (two dimensions): T / Omega ~ Beta(1, (r - 2) / 2), P(B > b) = (1 - b)^((r - 2) / 2).
  EXPECT_NEAR(TauCriticalValue(0.999, 10), 10.0 * (1.0 - std::pow(0.001, 0.25)), 1e-12);
  EXPECT_TRUE(std::isnan(TauCriticalValue(0.999, 2)));
  // Predicted residual: 2 F(2, r), P(F > f) = (1 + 2 f / r)^(-r / 2).
  EXPECT_NEAR(PredictedCriticalValue(0.999, 2), 2.0 * (1000.0 - 1.0), 1e-9);
  EXPECT_NEAR(PredictedCriticalValue(0.999, 1000000), SnoopingCriticalValue(0.999), 1e-3);
  EXPECT_NEAR(GlobalTestCriticalValue(0.999, 2), SnoopingCriticalValue(0.999), 1e-6);
  OutlierTestOptions options;
  EXPECT_TRUE(options.IsValid(nullptr));
  options.confidence = 1.0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_FALSE(why.empty());
}

TEST(DataSnooping, RedundancyNumbersSumToTheRedundancyAndTIsTheDropOfOmega) {
  // 0.01 px noise (Accuracy 0.01 px): the same whitened residuals as at 1 px, with the model's
  // curvature 100 times smaller, so the linear identities below hold to ~1e-5.
  const Adjusted a = Adjust(8, 5, 0.01);
  const std::vector<char> used(8, 1);
  PoseAdjustmentStatistics s;
  ASSERT_TRUE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                              a.sigmas, a.input.focal_length, a.eo, used, &s)
                  .ok());
  EXPECT_EQ(s.redundancy, 10);
  double sum = 0.0;
  for (const double r : s.redundancy_numbers) sum += r;
  EXPECT_NEAR(sum, 5.0, 1e-9);  // (2n - 6) / 2
  // T_i = Omega - Omega without mark i (exact for the linearised model).
  for (int i = 0; i < 8; ++i) {
    std::vector<int> others;
    for (int k = 0; k < 8; ++k)
      if (k != i) others.push_back(k);
    ExteriorOrientation eo = a.eo;
    PoseRefinementSummary summary;
    ASSERT_TRUE(RefinePose(PoseRefinementOptions(), a.input.image_plane, a.input.points_in_ground,
                           a.sigmas, a.input.focal_length, others, &eo, &summary));
    std::vector<char> without(8, 1);
    without[i] = 0;
    PoseAdjustmentStatistics t;
    ASSERT_TRUE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                                a.sigmas, a.input.focal_length, eo, without, &t)
                    .ok());
    EXPECT_NEAR(s.test_statistics[i], s.omega - t.omega, 1e-4 * s.omega) << i;
    // The left-out mark's predicted-residual statistic at that pose is the same number.
    EXPECT_NEAR(t.test_statistics[i], s.test_statistics[i], 1e-4 * s.omega) << i;
  }
}

// The distributions behind the tests, checked by simulation at alpha = 0.1 (2400 tests each, the
// binomial standard deviation of the rate is 0.006): with known sigma T_i ~ chi-square(2); with
// sigma0 estimated, T_i / s0^2 against the tau critical value; Omega against chi-square(r).
TEST(DataSnooping, FalseRejectionRatesAreAlpha) {
  constexpr double kConfidence = 0.9;
  constexpr int kImages = 400, kMarks = 6;
  int known = 0, estimated = 0, global = 0, tests = 0;
  for (int k = 0; k < kImages; ++k) {
    const Adjusted a = Adjust(kMarks, 1000 + k);
    PoseAdjustmentStatistics s;
    ASSERT_TRUE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                                a.sigmas, a.input.focal_length, a.eo,
                                                std::vector<char>(kMarks, 1), &s)
                    .ok());
    const double s0_squared = s.omega / s.redundancy;
    for (int i = 0; i < kMarks; ++i, ++tests) {
      known += s.test_statistics[i] > SnoopingCriticalValue(kConfidence);
      estimated += s.test_statistics[i] / s0_squared > TauCriticalValue(kConfidence, s.redundancy);
    }
    global += s.omega > GlobalTestCriticalValue(kConfidence, s.redundancy);
  }
  EXPECT_NEAR(static_cast<double>(known) / tests, 0.1, 0.025);
  EXPECT_NEAR(static_cast<double>(estimated) / tests, 0.1, 0.025);
  EXPECT_NEAR(static_cast<double>(global) / kImages, 0.1, 0.05);
}

// Field by field, bit for bit (the reuse of a statistics struct must leave nothing of the last).
void ExpectSameStatistics(const PoseAdjustmentStatistics& a, const PoseAdjustmentStatistics& b) {
  EXPECT_EQ(a.num_used, b.num_used);
  EXPECT_EQ(a.redundancy, b.redundancy);
  EXPECT_EQ(a.omega, b.omega);
  EXPECT_EQ(a.normal, b.normal);
  EXPECT_EQ(a.cofactor, b.cofactor);
  EXPECT_EQ(a.determined, b.determined);
  EXPECT_EQ(a.whitened_residuals, b.whitened_residuals);
  EXPECT_EQ(a.redundancy_numbers, b.redundancy_numbers);
  EXPECT_EQ(a.test_statistics, b.test_statistics);
  EXPECT_EQ(a.in_front, b.in_front);
  EXPECT_EQ(a.detectable_blunder_per_delta, b.detectable_blunder_per_delta);
  EXPECT_EQ(a.pose_shift_per_delta, b.pose_shift_per_delta);
}

// The resection's set tests ask for StatisticsScope::kTests into one reused struct: the tests must
// be those of the full statistics into a fresh one, the reliability left at zero, and a struct
// that held another image's larger set must come out as a fresh one.
TEST(DataSnooping, TheTestsAloneAndAReusedStructGiveTheFullStatisticsTests) {
  const Adjusted a = Adjust(8, 21);
  std::vector<char> used(8, 1);
  used[3] = 0;  // one mark left out: its predicted-residual statistic too
  PoseAdjustmentStatistics full;
  ASSERT_TRUE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                              a.sigmas, a.input.focal_length, a.eo, used, &full)
                  .ok());
  for (int i = 0; i < 8; ++i)
    if (used[i]) EXPECT_GT(full.detectable_blunder_per_delta[i], 1.0) << i;

  PoseAdjustmentStatistics reused;
  const Adjusted other = Adjust(12, 22);
  ASSERT_TRUE(ComputePoseAdjustmentStatistics(other.input.image_plane, other.input.points_in_ground,
                                              other.sigmas, other.input.focal_length, other.eo,
                                              std::vector<char>(12, 1), &reused)
                  .ok());
  ASSERT_TRUE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                              a.sigmas, a.input.focal_length, a.eo, used, &reused)
                  .ok());
  ExpectSameStatistics(reused, full);

  PoseAdjustmentStatistics tests_only = full;
  ASSERT_TRUE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                              a.sigmas, a.input.focal_length, a.eo, used,
                                              &tests_only, StatisticsScope::kTests)
                  .ok());
  PoseAdjustmentStatistics expected = full;
  expected.detectable_blunder_per_delta.assign(8, 0.0);
  expected.pose_shift_per_delta.assign(8, 0.0);
  ExpectSameStatistics(tests_only, expected);
}

TEST(DataSnooping, RefusesTooFewMarksAndMarksBehindTheCamera) {
  const Adjusted a = Adjust(5, 9);
  PoseAdjustmentStatistics s;
  std::vector<char> two = {1, 1, 0, 0, 0};
  EXPECT_FALSE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                               a.sigmas, a.input.focal_length, a.eo, two, &s)
                   .ok());
  ExteriorOrientation below = a.eo;
  below.parameters[2] = -2000.0;  // the camera under the ground, looking down: all behind
  EXPECT_FALSE(ComputePoseAdjustmentStatistics(a.input.image_plane, a.input.points_in_ground,
                                               a.sigmas, a.input.focal_length, below,
                                               std::vector<char>(5, 1), &s)
                   .ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
