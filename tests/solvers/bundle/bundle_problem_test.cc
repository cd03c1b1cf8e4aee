// The plan of a bundle adjustment (solvers/bundle/internal/bundle_problem.h, MakeBundlePlan and
// RecheckBundlePlan): which marks enter with which sigma, the priors of each group, the points
// held fixed, and the datum a block is refused or accepted with, on small synthetic blocks.
#include "solvers/bundle/internal/bundle_problem.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <string>

#include "core/simulation/synthetic_block.h"
#include "core/types.h"
#include "solvers/bundle/bundle_adjustment.h"

namespace photopose::internal {
namespace PHOTOPOSE_UNITY_ID {

// Sigmas are products of two stated numbers: equal to rounding.
constexpr double kSigmaTolerance = 1e-12;

// Two lines of four images, 60 tie points, five control and two check points, measured centres
// with stated accuracies; marks without a stated accuracy (their group's default weighs them).
SyntheticBlockOptions SmallBlock() {
  SyntheticBlockOptions o;
  o.seed = 7;
  o.num_lines = 2;
  o.images_per_line = 4;
  o.num_tie_points = 60;
  o.num_control_points = 5;
  o.num_check_points = 2;
  o.control_sigma_m = 0.01;
  o.mark_sigma_px = 0.0;
  o.gnss = true;
  return o;
}

Block MakeBlock(const SyntheticBlockOptions& options) {
  Block block;
  SyntheticBlockTruth truth;
  const Status made = MakeSyntheticBlock(options, &block, &truth);
  EXPECT_TRUE(made.ok()) << made.message();
  return block;
}

Status Plan(const BundleAccuracies& accuracies, const BundleAdjustmentConfig& config,
            const Block& block, BundlePlan* plan, bool refuse_weak_datum = true) {
  BundlePlanOptions options;
  options.accuracies = accuracies;
  options.refuse_weak_datum = refuse_weak_datum;
  return MakeBundlePlan(options, config, block, plan);
}

int PointOfRole(const Block& block, PointRole role, int nth = 0) {
  for (size_t p = 0; p < block.points.size(); ++p)
    if (block.points[p].role == role && nth-- == 0) return static_cast<int>(p);
  ADD_FAILURE() << "no such point";
  return -1;
}

// Without control points, camera positions or attitudes: only the block's own points.
Block BlockWithoutControl() {
  SyntheticBlockOptions o = SmallBlock();
  o.num_control_points = 0;
  o.num_check_points = 0;
  o.gnss = false;
  return MakeBlock(o);
}

TEST(BundlePlan, MarksTakeTheirGroupsSigmaAndCheckMarksStayOut) {
  Block block = MakeBlock(SmallBlock());
  // One mark with its own accuracy: it wins over the group's default.
  const int stated = block.marks_of_point[PointOfRole(block, PointRole::kTie)][0];
  block.marks[stated].accuracy = 0.7;
  BundleAccuracies accuracies;
  accuracies.tie_px = 1.5;
  accuracies.marker_projection_px = 0.25;
  BundlePlan plan;
  ASSERT_TRUE(Plan(accuracies, BundleAdjustmentConfig(), block, &plan).ok());
  int tie = 0, control = 0;
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    const PointRole role = block.points[mark.point].role;
    SCOPED_TRACE("mark " + std::to_string(m));
    ASSERT_EQ(mark.unit, MarkUnit::kPixel);
    if (role == PointRole::kCheck) {
      EXPECT_FALSE(plan.mark_used[m]);
      continue;
    }
    if (!plan.mark_used[m]) continue;  // a tie point seen once
    const bool is_control = role == PointRole::kControl;
    EXPECT_EQ(plan.mark_group[m], is_control ? kControlMarks : kTieMarks);
    const double px = static_cast<int>(m) == stated ? 0.7
                      : is_control                  ? accuracies.marker_projection_px
                                                    : accuracies.tie_px;
    EXPECT_NEAR(plan.mark_sigma[m], px * mark.observation_units_per_unit, kSigmaTolerance);
    ++(is_control ? control : tie);
  }
  EXPECT_GT(tie, 100);
  EXPECT_GT(control, 5);
  for (size_t p = 0; p < block.points.size(); ++p)
    if (block.points[p].role == PointRole::kCheck) EXPECT_FALSE(plan.point_in_problem[p]);
}

TEST(BundlePlan, ControlPointsGetPriorsWithTheirOwnOrTheDefaultAccuracy) {
  Block block = MakeBlock(SmallBlock());
  const int own = PointOfRole(block, PointRole::kControl, 0);
  const int by_default = PointOfRole(block, PointRole::kControl, 1);
  block.points[own].accuracy_m = Eigen::Vector3d(0.02, 0.03, 0.05);
  block.points[by_default].accuracy_m.reset();
  BundleAccuracies accuracies;
  accuracies.marker_m = 0.004;
  BundlePlan plan;
  ASSERT_TRUE(Plan(accuracies, BundleAdjustmentConfig(), block, &plan).ok());
  EXPECT_TRUE(plan.point_in_problem[own]);
  EXPECT_TRUE(plan.point_prior[own]);
  EXPECT_EQ(plan.point_sigma[own], Eigen::Vector3d(0.02, 0.03, 0.05));
  EXPECT_TRUE(plan.point_prior[by_default]);
  EXPECT_EQ(plan.point_sigma[by_default], Eigen::Vector3d::Constant(0.004));
  const int tie = PointOfRole(block, PointRole::kTie);
  EXPECT_FALSE(plan.point_prior[tie]);
}

TEST(BundlePlan, CameraPositionAndAttitudePriorsPerImage) {
  SyntheticBlockOptions o = SmallBlock();
  o.attitude = true;
  Block block = MakeBlock(o);
  // Image 0: its own accuracy; image 1: none stated (the default); image 2: no height; image 3
  // held constant (no prior of any kind); image 4: no measured centre.
  block.images[0].center_accuracy_m = Eigen::Vector3d(0.03, 0.04, 0.08);
  block.images[0].attitude_accuracy_rad = Eigen::Vector3d(1e-4, 2e-4, 3e-4);
  block.images[1].center_accuracy_m.reset();
  block.images[1].attitude_accuracy_rad.reset();
  block.images[2].center_height_measured = false;
  block.images[4].measured_center_m.reset();
  BundleAdjustmentConfig config;
  config.constant_images.insert(3);
  BundleAccuracies accuracies;
  accuracies.camera_m = Eigen::Vector3d(1.0, 2.0, 3.0);
  accuracies.attitude_deg = 0.5;
  BundlePlan plan;
  ASSERT_TRUE(Plan(accuracies, config, block, &plan).ok());

  EXPECT_TRUE(plan.image_prior[0]);
  EXPECT_EQ(plan.image_prior_sigma[0], Eigen::Vector3d(0.03, 0.04, 0.08));
  EXPECT_EQ(ImagePriorRows(plan, 0), 3);
  EXPECT_TRUE(plan.image_attitude[0]);
  EXPECT_EQ(plan.image_attitude_sigma[0], Eigen::Vector3d(1e-4, 2e-4, 3e-4));

  EXPECT_TRUE(plan.image_prior[1]);
  EXPECT_EQ(plan.image_prior_sigma[1], Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_TRUE(plan.image_attitude[1]);
  EXPECT_EQ(plan.image_attitude_sigma[1], Eigen::Vector3d::Constant(DegreesToRadians(0.5)));

  // A position without height: X and Y only, its Z without weight.
  EXPECT_TRUE(plan.image_prior[2]);
  EXPECT_FALSE(plan.image_prior_height[2]);
  EXPECT_EQ(ImagePriorRows(plan, 2), 2);
  EXPECT_TRUE(std::isinf(plan.image_prior_sigma[2].z()));

  EXPECT_FALSE(plan.image_prior[3]);
  EXPECT_FALSE(plan.image_attitude[3]);
  EXPECT_EQ(ImagePriorRows(plan, 3), 0);
  EXPECT_FALSE(plan.image_prior[4]);

  // Positions without a stated accuracy are no priors when the default says so; attitudes without
  // one, when no default accuracy is given.
  accuracies.camera_positions_are_priors = false;
  accuracies.attitude_deg.reset();
  ASSERT_TRUE(Plan(accuracies, config, block, &plan).ok());
  EXPECT_TRUE(plan.image_prior[0]);
  EXPECT_FALSE(plan.image_prior[1]);
  EXPECT_TRUE(plan.image_attitude[0]);
  EXPECT_FALSE(plan.image_attitude[1]);
}

TEST(BundlePlan, PointsHeldFixedHaveNoPriorAndAreNamedInTheDatum) {
  Block block = MakeBlock(SmallBlock());
  const int held = PointOfRole(block, PointRole::kControl, 0);
  const int stated_error_free = PointOfRole(block, PointRole::kControl, 1);
  block.points[stated_error_free].accuracy_m = Eigen::Vector3d::Zero();
  const BundleAdjustmentConfig config = [&] {
    BundleAdjustmentConfig c;
    c.constant_points.insert(held);
    return WithFixedControlPoints(c, block);
  }();
  EXPECT_EQ(config.constant_points.count(stated_error_free), 1u);
  BundlePlan plan;
  ASSERT_TRUE(Plan(BundleAccuracies(), config, block, &plan).ok());
  for (const int p : {held, stated_error_free}) {
    EXPECT_TRUE(plan.point_in_problem[p]) << p;
    EXPECT_FALSE(plan.point_prior[p]) << p;
  }
  EXPECT_TRUE(plan.point_prior[PointOfRole(block, PointRole::kControl, 2)]);
  EXPECT_EQ(plan.datum, BundleDatum::kControl);
  EXPECT_EQ(plan.datum_description,
            "absolute: 2 points held fixed, 3 control points, 8 camera positions (the rest "
            "weighted as stated)");
}

TEST(BundlePlan, ABlockWithoutControlTakesTheRelativeGauge) {
  const Block block = BlockWithoutControl();
  BundlePlan plan;
  ASSERT_TRUE(Plan(BundleAccuracies(), BundleAdjustmentConfig(), block, &plan).ok());
  EXPECT_EQ(plan.datum, BundleDatum::kRelative);
  EXPECT_EQ(plan.relative_fixed_image, 0);
  EXPECT_EQ(plan.relative_scale_image, 1);
  EXPECT_EQ(plan.datum_description.rfind("relative: no control points and no camera positions; "
                                         "image '",
                                         0),
            0u)
      << plan.datum_description;
}

TEST(BundlePlan, AWeakDatumIsRefusedWithItsReason) {
  SyntheticBlockOptions o = SmallBlock();
  o.gnss = false;
  o.num_check_points = 0;
  o.num_control_points = 2;
  Block two = MakeBlock(o);
  BundlePlan plan;
  EXPECT_EQ(Plan(BundleAccuracies(), BundleAdjustmentConfig(), two, &plan).message(),
            "no datum: the 2 control points, 0 camera positions fix only 6 of the 7 similarity "
            "parameters of the block (fewer than three positions cannot fix the rotation); add "
            "control points off that line or camera positions");

  // Three control points on one line: the rotation about it is free.
  o.num_control_points = 3;
  Block line = MakeBlock(o);
  const Eigen::Vector3d start = *line.points[PointOfRole(line, PointRole::kControl, 0)].surveyed_m;
  for (int k = 1; k < 3; ++k) {
    *line.points[PointOfRole(line, PointRole::kControl, k)].surveyed_m =
        start + k * Eigen::Vector3d(40.0, 10.0, 1.0);
  }
  EXPECT_EQ(Plan(BundleAccuracies(), BundleAdjustmentConfig(), line, &plan).message(),
            "no datum: the 3 control points, 0 camera positions fix only 6 of the 7 similarity "
            "parameters of the block (the positions lie on one line (the rotation about it is "
            "free)); add control points off that line or camera positions");

  // The Taylor adjustment takes such a datum and shows its defect in the round.
  ASSERT_TRUE(Plan(BundleAccuracies(), BundleAdjustmentConfig(), line, &plan,
                   /*refuse_weak_datum=*/false)
                  .ok());
  EXPECT_EQ(plan.datum_description,
            "absolute: 3 control points, 0 camera positions weighted as stated (a datum defect "
            "shows as a singular reduced normal matrix)");
}

TEST(BundlePlan, CameraPositionsWithoutHeightLeaveTheVerticalFree) {
  SyntheticBlockOptions o = SmallBlock();
  o.num_control_points = 0;
  o.num_check_points = 0;
  Block block = MakeBlock(o);
  for (BlockImage& image : block.images) image.center_height_measured = false;
  BundlePlan plan;
  const std::string message =
      Plan(BundleAccuracies(), BundleAdjustmentConfig(), block, &plan).message();
  EXPECT_EQ(message.rfind("no datum: the 0 control points, 8 camera positions (8 without height) "
                          "fix only ",
                          0),
            0u)
      << message;
  EXPECT_NE(message.find("(no position has a height: the vertical is free); add control points or "
                         "camera positions with a height"),
            std::string::npos)
      << message;
  // Heights at the four corner images fix it.
  for (const int i : {0, 3, 4, 7}) block.images[i].center_height_measured = true;
  ASSERT_TRUE(Plan(BundleAccuracies(), BundleAdjustmentConfig(), block, &plan).ok());
  EXPECT_EQ(plan.datum_description,
            "absolute: 0 control points, 8 camera positions (4 without height) weighted as stated");
}

TEST(BundlePlan, ARecheckRefusesABlockThatLostItsDatum) {
  SyntheticBlockOptions o = SmallBlock();
  o.gnss = false;
  o.num_check_points = 0;
  o.num_control_points = 4;
  const Block block = MakeBlock(o);
  const BundleAdjustmentConfig config;
  BundlePlan plan;
  ASSERT_TRUE(Plan(BundleAccuracies(), config, block, &plan).ok());
  BundlePlan unchanged = plan;
  ASSERT_TRUE(RecheckBundlePlan(config, block, &unchanged).ok());
  EXPECT_EQ(unchanged.datum_description, plan.datum_description);
  // Every mark of two control points rejected: the two left cannot fix the rotation.
  for (int k = 0; k < 2; ++k)
    for (const int m : block.marks_of_point[PointOfRole(block, PointRole::kControl, k)])
      plan.mark_used[m] = 0;
  const std::string message = RecheckBundlePlan(config, block, &plan).message();
  EXPECT_EQ(message.rfind("no datum: the 2 control points, 0 camera positions fix only 6 ", 0), 0u)
      << message;
  EXPECT_FALSE(plan.point_in_problem[PointOfRole(block, PointRole::kControl, 0)]);
  // Every control mark rejected: nothing absolute is left, and the block would fall back to a
  // relative gauge it was not planned with.
  ASSERT_TRUE(Plan(BundleAccuracies(), config, block, &plan).ok());
  for (size_t m = 0; m < block.marks.size(); ++m)
    if (block.points[block.marks[m].point].role == PointRole::kControl) plan.mark_used[m] = 0;
  EXPECT_EQ(RecheckBundlePlan(config, block, &plan).message(), "the block lost its datum");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::internal
