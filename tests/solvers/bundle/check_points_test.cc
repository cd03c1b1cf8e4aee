#include "solvers/bundle/check_points.h"

#include <gtest/gtest.h>

#include <cmath>

#include "solvers/bundle/triangulation.h"
#include "tests/support/exact_block.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::ExactBlock;
using testing::MakeExactBlock;

// Noise-free marks, true orientations and an exact survey: a check point's intersection error is
// the Gauss-Newton stop and rounding only.
constexpr double kExactPointM = 1e-6;

std::vector<int> PointsOfRole(const Block& block, PointRole role) {
  std::vector<int> points;
  for (size_t p = 0; p < block.points.size(); ++p)
    if (block.points[p].role == role) points.push_back(static_cast<int>(p));
  return points;
}

TEST(CheckPoints, ExactBlockHasNoCheckErrorAndItsControlErrorsAsGiven) {
  SyntheticBlockOptions options;
  options.num_check_points = 2;
  const ExactBlock data = MakeExactBlock(options);
  const std::vector<int> checks = PointsOfRole(data.block, PointRole::kCheck);
  const std::vector<int> controls = PointsOfRole(data.block, PointRole::kControl);
  ASSERT_EQ(checks.size(), 2u);
  ASSERT_GE(controls.size(), 2u);
  BundleAdjustmentResult result;
  result.points.assign(data.block.points.size(), BundlePointResult());
  // Two control points with errors (3, 4, 0) mm and (0, 0, 5) mm: RMSE per axis
  // (sqrt(4.5), sqrt(8), sqrt(12.5)) mm, total 5 mm.
  result.points[controls[0]].error_m = Eigen::Vector3d(0.003, 0.004, 0.0);
  result.points[controls[1]].error_m = Eigen::Vector3d(0.0, 0.0, 0.005);
  constexpr double kVarianceFactor = 4.0;
  TabulateControlAndCheckPoints(data.block, BundleAccuracies(), kVarianceFactor, &result);
  EXPECT_EQ(result.num_control_points, 2);
  EXPECT_NEAR(result.control_rmse_total_m, 0.005, 1e-15);
  EXPECT_NEAR(result.control_rmse_m.x(), std::sqrt(4.5e-6), 1e-15);
  EXPECT_NEAR(result.control_rmse_m.z(), std::sqrt(12.5e-6), 1e-15);
  EXPECT_EQ(result.num_check_points, 2);
  EXPECT_LT(result.check_rmse_total_m, kExactPointM);
  for (const int p : checks) {
    const BundlePointResult& row = result.points[p];
    ASSERT_TRUE(row.error_m.has_value()) << row.message;
    EXPECT_EQ(row.num_observations, static_cast<int>(data.block.marks_of_point[p].size()));
    EXPECT_TRUE(row.has_covariance);
    // The intersection's a-priori covariance (marks with their stated 0.5 px) times the factor.
    MarkSigmaDefaults control;
    control.pixel_px = BundleAccuracies().marker_projection_px;
    control.film_um = BundleAccuracies().marker_projection_film_um;
    TriangulationResult intersection;
    ASSERT_TRUE(
        TriangulatePoint(TriangulationOptions(), PointRays(data.block, p, control), &intersection)
            .ok());
    EXPECT_TRUE(row.covariance.isApprox(kVarianceFactor * intersection.covariance, 1e-12));
  }
}

TEST(CheckPoints, MarksWithoutAccuracyTakeTheMarkerProjectionDefault) {
  ExactBlock data = MakeExactBlock();
  for (BlockMark& mark : data.block.marks) mark.accuracy.reset();
  const int p = PointsOfRole(data.block, PointRole::kCheck)[0];
  BundleAccuracies accuracies;
  accuracies.marker_projection_px = 2.0;  // 8 um on 4 um pixels: covariance (8 / 2)^2 the 2 um one
  BundleAdjustmentResult result;
  result.points.assign(data.block.points.size(), BundlePointResult());
  TabulateControlAndCheckPoints(data.block, accuracies, 1.0, &result);
  MarkSigmaDefaults two_um;
  two_um.pixel_px = 0.5;
  TriangulationResult reference;
  ASSERT_TRUE(
      TriangulatePoint(TriangulationOptions(), PointRays(data.block, p, two_um), &reference).ok());
  EXPECT_TRUE(result.points[p].covariance.isApprox(16.0 * reference.covariance, 1e-9));
}

TEST(CheckPoints, OneRayIsReportedNotCountedAndRemovedControlLeavesTheRmse) {
  ExactBlock data = MakeExactBlock();
  const int check = PointsOfRole(data.block, PointRole::kCheck)[0];
  const int control = PointsOfRole(data.block, PointRole::kControl)[0];
  // Every image but the first of the check point's marks loses its orientation.
  const std::vector<int> marks = data.block.marks_of_point[check];
  for (size_t k = 1; k < marks.size(); ++k)
    data.block.images[data.block.marks[marks[k]].image].eo.reset();
  BundleAdjustmentResult result;
  result.points.assign(data.block.points.size(), BundlePointResult());
  result.points[control].error_m = Eigen::Vector3d(1.0, 0.0, 0.0);
  result.snooping.push_back({kControlPoints, control, 0, 5.0, 1.0});
  TabulateControlAndCheckPoints(data.block, BundleAccuracies(), 1.0, &result);
  const BundlePointResult& row = result.points[check];
  EXPECT_FALSE(row.error_m.has_value());
  EXPECT_FALSE(row.has_covariance);
  EXPECT_EQ(row.num_observations, 1);
  EXPECT_NE(row.message.find("not intersected"), std::string::npos) << row.message;
  EXPECT_EQ(result.num_control_points, 0);  // its coordinates were removed by snooping
  EXPECT_TRUE(std::isnan(result.control_rmse_total_m)) << "no control point, no RMSE";
  EXPECT_TRUE(result.control_rmse_m.array().isNaN().all());
}

// A check mark 40 um (10 px) off: the w-test of the intersection rejects it (and only it), the point is
// intersected from the rest and its error is back to the exact one; the others stay untouched.
TEST(CheckPoints, ABlunderedCheckMarkIsRejectedByTheWTest) {
  ExactBlock data = MakeExactBlock();
  const int check = PointsOfRole(data.block, PointRole::kCheck)[0];
  const std::vector<int> marks = data.block.marks_of_point[check];
  ASSERT_GE(marks.size(), 4u);  // redundancy enough to tell which mark is wrong
  const int blunder = marks[1];
  data.block.marks[blunder].observation.x() += 40.0;
  BundleAdjustmentResult result;
  result.points.assign(data.block.points.size(), BundlePointResult());
  TabulateControlAndCheckPoints(data.block, BundleAccuracies(), 1.0, &result);
  ASSERT_EQ(result.rejected_check_marks.size(), 1u);
  EXPECT_EQ(result.rejected_check_marks[0].mark, blunder);
  EXPECT_GT(result.rejected_check_marks[0].normalized, 10.0);
  // Its residual is most of the blunder (the rest went into the intersection that still held it),
  // in the mark's own unit: 10 px, not the model's 40 um.
  const double px = std::abs(result.rejected_check_marks[0].residual.x());
  EXPECT_GT(px, 5.0);
  EXPECT_LT(px, 10.0 + 1e-9);
  const BundlePointResult& row = result.points[check];
  ASSERT_TRUE(row.error_m.has_value()) << row.message;
  EXPECT_EQ(row.num_observations, static_cast<int>(marks.size()) - 1);
  EXPECT_LT(row.error_m->norm(), kExactPointM);
  EXPECT_LT(result.check_rmse_total_m, kExactPointM);
}

// Two rays cannot tell which of them is wrong: the point is listed as not intersected, with the
// w-test as the reason, and stays out of the RMSE. The blunder has a part across the epipolar
// line (one along it only slides the intersection and cannot be seen with two rays).
TEST(CheckPoints, TwoDisagreeingRaysLeaveThePointUnintersectedWithTheReason) {
  ExactBlock data = MakeExactBlock();
  const int check = PointsOfRole(data.block, PointRole::kCheck)[0];
  const std::vector<int> marks = data.block.marks_of_point[check];
  ASSERT_GE(marks.size(), 3u);
  for (size_t k = 2; k < marks.size(); ++k)
    data.block.images[data.block.marks[marks[k]].image].eo.reset();
  data.block.marks[marks[0]].observation += Eigen::Vector2d(40.0, 40.0);
  BundleAdjustmentResult result;
  result.points.assign(data.block.points.size(), BundlePointResult());
  TabulateControlAndCheckPoints(data.block, BundleAccuracies(), 1.0, &result);
  const BundlePointResult& row = result.points[check];
  EXPECT_FALSE(row.error_m.has_value());
  EXPECT_EQ(result.rejected_check_marks.size(), 1u);
  EXPECT_NE(row.message.find("w-test rejected 1"), std::string::npos) << row.message;
}


// Variance component estimation found the control marks 30 times less accurate than stated (the
// README's example with --estimate_accuracies: 0.5 px stated, 15-19 px estimated). Check marks are
// measured as control marks are, so they are tested and weighed with the same yardstick: the
// 40 um mark rejected above at the stated 0.5 px is 1/3 of a sigma in use and stays, and the
// check point's covariance grows by 30^2. Before, check marks kept the stated sigma whatever the
// estimation found (78 of 163 check marks rejected on the example).
TEST(CheckPoints, CheckMarksTakeTheControlMarksSigmaTheVarianceComponentsSet) {
  ExactBlock data = MakeExactBlock();
  const int check = PointsOfRole(data.block, PointRole::kCheck)[0];
  const std::vector<int> marks = data.block.marks_of_point[check];
  ASSERT_GE(marks.size(), 4u);
  data.block.marks[marks[1]].observation.x() += 40.0;
  constexpr double kScale = 30.0;
  BundleAdjustmentResult result;
  result.points.assign(data.block.points.size(), BundlePointResult());
  result.mark_residuals.assign(data.block.marks.size(), Eigen::Vector2d::Constant(std::nan("")));
  BundleGroupStatistics control_marks;
  control_marks.group = kControlMarks;
  for (size_t m = 0; m < data.block.marks.size(); ++m) {
    const BlockMark& mark = data.block.marks[m];
    if (data.block.points[mark.point].role != PointRole::kControl) continue;
    ASSERT_TRUE(mark.accuracy.has_value());
    result.mark_residuals[m].setZero();  // in the adjustment
    control_marks.stated_accuracy += Eigen::Vector3d(*mark.accuracy, *mark.accuracy, 0.0);
    ++control_marks.count;
  }
  ASSERT_GT(control_marks.count, 0);
  control_marks.stated_accuracy *= kScale / control_marks.count;  // the mean sigma in use
  control_marks.unit = EnumName(data.block.marks[marks[0]].unit);
  result.groups.push_back(control_marks);
  TabulateControlAndCheckPoints(data.block, BundleAccuracies(), 1.0, &result);
  EXPECT_TRUE(result.rejected_check_marks.empty());
  const BundlePointResult& row = result.points[check];
  ASSERT_TRUE(row.has_covariance) << row.message;
  EXPECT_EQ(row.num_observations, static_cast<int>(marks.size()));

  // Without the estimation: the stated sigma, the mark rejected.
  BundleAdjustmentResult stated;
  stated.points.assign(data.block.points.size(), BundlePointResult());
  TabulateControlAndCheckPoints(data.block, BundleAccuracies(), 1.0, &stated);
  EXPECT_EQ(stated.rejected_check_marks.size(), 1u);
  // The covariance 30^2 times that of the stated sigmas on the same rays (the mark restored: the
  // intersections differ by the 40 um pull only, 1 %).
  data.block.marks[marks[1]].observation.x() -= 40.0;
  TabulateControlAndCheckPoints(data.block, BundleAccuracies(), 1.0, &stated);
  ASSERT_TRUE(stated.rejected_check_marks.empty());
  EXPECT_NEAR(row.covariance.trace() / stated.points[check].covariance.trace(), kScale * kScale,
              0.01 * kScale * kScale);
}

// The error of a surveyed point against an estimate that left it out carries both covariances:
// the estimate's and the surveyed coordinates' (stated, else the default marker accuracy; none
// when stated error-free).
TEST(CheckPoints, TheErrorCovarianceAddsTheSurveyedAccuracy) {
  Eigen::Matrix3d estimate;
  estimate << 4e-4, 1e-4, 0.0, 1e-4, 9e-4, 0.0, 0.0, 0.0, 1e-4;
  BlockPoint point;
  point.role = PointRole::kCheck;
  const Eigen::Matrix3d unstated = SurveyedPointErrorCovariance(point, estimate, 0.005);
  EXPECT_TRUE(unstated.isApprox(estimate + 2.5e-5 * Eigen::Matrix3d::Identity(), 1e-15))
      << unstated;
  point.accuracy_m = Eigen::Vector3d(0.01, 0.02, 0.03);
  const Eigen::Matrix3d stated = SurveyedPointErrorCovariance(point, estimate, 0.005);
  EXPECT_TRUE(stated.isApprox(estimate + Eigen::Vector3d(1e-4, 4e-4, 9e-4).asDiagonal().toDenseMatrix(),
                              1e-15))
      << stated;
  point.accuracy_m = Eigen::Vector3d::Zero();  // error-free: the estimate's alone
  EXPECT_EQ(SurveyedPointErrorCovariance(point, estimate, 0.005), estimate);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
