// Tests of solvers/bundle/cross_validation.cc: the leave-one-out cross-validation of the control
// points by the low-rank update (kUpdate) against its oracle, one adjustment per point (kRefit).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/taylor_bundle.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// The update is one Gauss-Newton step from the full solution; the refit iterates to the minimum
// without the point. What one step leaves is second order: about |step|^2 over the flying height
// (100 m here), so the agreement, relative to the error, is of the order of the step over the
// flying height. Measured on the blocks below (the worst point of each; errors / normalized
// errors): GNSS with a 0.3 m control blunder 9e-5 / 1.8e-4, self-calibration 3.6e-5 / 4.8e-5, the
// Taylor solver's solution 9e-5 / 1.8e-4; control only with the blunder, whose left-out steps
// reach 25 cm, 1.6e-3 / 2.7e-3; estimated accuracies, where the step also carries the full
// solution back from the estimated to the stated weights, 7.5e-4 / 6.9e-4. Each scenario's bound
// is about ten times its measurement (refit's own convergence, 1e-10 of the cost, is below 1e-6
// of these errors). A step missing a term misses by far more (measured by breaking the update):
// without the point's gradient share r, errors off by 30-53 % in every scenario; without the
// block's gradient g, the estimated-accuracies errors off by 90 %.
// Errors this small (m) are compared absolutely: their relative difference is rounding.
constexpr double kErrorFloorM = 1e-6;
struct Scenario {
  std::string name;
  double error_agreement = 1e-3;       // |e_update - e_refit| / |e_refit|
  double normalized_agreement = 2e-3;  // |n_update - n_refit| / n_refit
  bool gnss = true;
  int num_control_points = 8;
  int num_control_blunders = 0;
  bool self_calibration = false;
  bool estimate_accuracies = false;
  PoseSolver solver = PoseSolver::kCeres;
};

struct Adjusted {
  Block block;
  BundleAdjustmentConfig config;
  BundleAdjustmentOptions options;
  BundleAdjustmentResult full;
};

// A 4 x 5 block of noise-level data (marks 0.5 px, control 5 mm, GNSS 2/2/4 cm), adjusted.
void Adjust(const Scenario& s, Adjusted* a) {
  SyntheticBlockOptions o;
  o.seed = 41;
  o.num_lines = 4;
  o.images_per_line = 5;
  o.tie_point_density_per_m2 = 0.02;
  o.gnss = s.gnss;
  o.num_control_points = s.num_control_points;
  o.num_check_points = 2;
  o.control_sigma_m = 0.005;
  o.mark_sigma_px = 0.5;
  o.num_control_blunders = s.num_control_blunders;
  o.control_blunder_m = 0.3;
  SyntheticBlockTruth truth;
  const Status made = MakeSyntheticBlock(o, &a->block, &truth);
  ASSERT_TRUE(made.ok()) << made.message();
  a->block.BuildIndex();
  if (s.self_calibration) {
    a->block.cameras[0].params[kFrameFocal] *= 1.001;
    ASSERT_TRUE(
        BundleAdjustmentConfig::FromCalibrationNames(a->block, {"FocalLength", "K1"}, &a->config)
            .ok());
  }
  a->options.solver.num_threads = 1;
  if (s.estimate_accuracies) {
    // Tie marks stated at twice their noise: the estimated accuracies move the minimum away from
    // that of the stated weights, which the cross-validation keeps.
    a->options.accuracies.tie_px = 1.0;
    for (BlockMark& mark : a->block.marks) mark.accuracy.reset();
    a->options.statistics.estimate_accuracies = true;
  }
  const Status adjusted =
      BundleAdjustWithSolver(s.solver, a->options, a->config, &a->block, &a->full);
  ASSERT_TRUE(adjusted.ok()) << adjusted.message();
  ASSERT_TRUE(a->full.summary.IsSolutionUsable()) << a->full.summary.BriefReport();
}

BundleCrossValidationResult CrossValidate(const Adjusted& a, BundleCrossValidationMethod method) {
  BundleAdjustmentOptions options = a.options;
  options.statistics.cross_validation = method;
  BundleCrossValidationResult cv;
  const Status status = CrossValidateControlPoints(options, a.config, a.block, a.full, 2, &cv);
  EXPECT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(cv.method, method);
  return cv;
}

// The point with the largest normalized error (-1 without any).
int Largest(const BundleCrossValidationResult& cv) {
  int largest = -1;
  double normalized = -1.0;
  for (const BundleCrossValidationPoint& p : cv.points)
    if (p.ok && p.normalized > normalized) normalized = p.normalized, largest = p.point;
  return largest;
}

class UpdateAgreesWithRefit : public ::testing::TestWithParam<Scenario> {};

TEST_P(UpdateAgreesWithRefit, ErrorsNormalizedErrorsAndVerdicts) {
  const Scenario& s = GetParam();
  Adjusted a;
  ASSERT_NO_FATAL_FAILURE(Adjust(s, &a));
  const BundleCrossValidationResult refit = CrossValidate(a, BundleCrossValidationMethod::kRefit);
  const BundleCrossValidationResult update = CrossValidate(a, BundleCrossValidationMethod::kUpdate);
  ASSERT_EQ(update.points.size(), refit.points.size());
  ASSERT_EQ(update.count, refit.count);
  ASSERT_GT(update.count, 0);
  double worst_error = 0.0, worst_normalized = 0.0;
  for (size_t k = 0; k < refit.points.size(); ++k) {
    const BundleCrossValidationPoint& r = refit.points[k];
    const BundleCrossValidationPoint& u = update.points[k];
    SCOPED_TRACE(a.block.points[r.point].id);
    ASSERT_EQ(u.point, r.point);
    ASSERT_TRUE(r.ok) << r.message;
    ASSERT_TRUE(u.ok) << u.message;
    EXPECT_EQ(u.num_images, r.num_images);
    const double error = (u.error_m - r.error_m).norm() / std::max(r.error_m.norm(), kErrorFloorM);
    const double normalized = std::abs(u.normalized - r.normalized) / r.normalized;
    worst_error = std::max(worst_error, error);
    worst_normalized = std::max(worst_normalized, normalized);
    EXPECT_LT(error, s.error_agreement)
        << "update " << u.error_m.transpose() << ", refit " << r.error_m.transpose();
    EXPECT_LT(normalized, s.normalized_agreement) << u.normalized << " vs " << r.normalized;
    EXPECT_EQ(u.stands_out, r.stands_out);
  }
  EXPECT_EQ(Largest(update), Largest(refit));
  EXPECT_LT((update.rmse_m - refit.rmse_m).norm(), s.error_agreement * refit.rmse_m.norm());
  std::printf(
      "[ measured ] %s: errors agree to %.2g, normalized errors to %.2g; update %.3g s, "
      "refit %.3g s\n",
      s.name.c_str(), worst_error, worst_normalized, update.time_seconds, refit.time_seconds);
  if (s.num_control_blunders > 0) {
    // The wrong point stands out in both.
    bool stands_out = false;
    for (const BundleCrossValidationPoint& u : update.points) stands_out |= u.stands_out;
    EXPECT_TRUE(stands_out);
  }
}

INSTANTIATE_TEST_SUITE_P(
    CrossValidation, UpdateAgreesWithRefit,
    ::testing::Values(Scenario{"gnss_and_control", 1e-3, 2e-3, true, 8, 1},
                      Scenario{"control_only", 1e-2, 2e-2, false, 8, 1},
                      Scenario{"self_calibration", 5e-4, 5e-4, true, 8, 0, true},
                      Scenario{"estimated_accuracies", 5e-3, 5e-3, true, 8, 0, false, true},
                      Scenario{"taylor_solver", 1e-3, 2e-3, true, 8, 1, false, false,
                               PoseSolver::kTaylor}),
    [](const ::testing::TestParamInfo<Scenario>& info) { return info.param.name; });

// Three control points and no camera positions: without any one of them the other two leave the
// rotation about their line free. Neither method cross-validates a point, and both say why in
// the same words (the plan's).
TEST(CrossValidation, RemovalWithoutDatumIsReportedByBoth) {
  Scenario s;
  s.gnss = false;
  s.num_control_points = 3;
  Adjusted a;
  ASSERT_NO_FATAL_FAILURE(Adjust(s, &a));
  const BundleCrossValidationResult refit = CrossValidate(a, BundleCrossValidationMethod::kRefit);
  const BundleCrossValidationResult update = CrossValidate(a, BundleCrossValidationMethod::kUpdate);
  ASSERT_EQ(update.points.size(), 3u);
  ASSERT_EQ(refit.points.size(), 3u);
  EXPECT_EQ(update.count, 0);
  EXPECT_EQ(refit.count, 0);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_FALSE(update.points[k].ok);
    EXPECT_FALSE(refit.points[k].ok);
    EXPECT_EQ(update.points[k].message.rfind("no datum", 0), 0u) << update.points[k].message;
    EXPECT_EQ(update.points[k].message, refit.points[k].message);
  }
  EXPECT_TRUE(std::isnan(update.rmse_total_m) || update.count == 0);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
