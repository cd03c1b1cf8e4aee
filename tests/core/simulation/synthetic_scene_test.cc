#include "core/simulation/synthetic_scene.h"

#include <gtest/gtest.h>

#include <limits>
#include <map>

#include "core/collinearity.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

SyntheticScene Make(const SyntheticSceneOptions& options) {
  SyntheticScene scene;
  const Status status = MakeSyntheticScene(options, &scene);
  EXPECT_TRUE(status.ok()) << status.message();
  return scene;
}

TEST(SyntheticScene, SameSeedSameSceneOtherSeedOtherScene) {
  SyntheticSceneOptions options;
  options.scenario = Scenario::kUavBlock;
  options.outlier_fraction = 0.1;
  const SyntheticScene a = Make(options), b = Make(options);
  ASSERT_EQ(a.marks.size(), b.marks.size());
  for (size_t i = 0; i < a.marks.size(); ++i) EXPECT_EQ(*a.marks[i].column_row, *b.marks[i].column_row);
  EXPECT_EQ(a.mark_is_outlier, b.mark_is_outlier);
  options.seed = 2;
  const SyntheticScene c = Make(options);
  EXPECT_NE(a.true_frames[0].eo.parameters, c.true_frames[0].eo.parameters);
}

TEST(SyntheticScene, NoiseFreeMarksAreExactProjectionsInsideTheImage) {
  for (Scenario scenario : {Scenario::kNadir, Scenario::kOblique, Scenario::kUavBlock}) {
    SyntheticSceneOptions options;
    options.scenario = scenario;
    options.noise_px = 0.0;
    const SyntheticScene scene = Make(options);
    const FrameCamera& camera = scene.cameras.front();
    std::map<std::string, Eigen::Vector3d> points;
    for (const auto& p : scene.points) points[p.point_id] = p.position;
    std::map<std::string, ExteriorOrientation> poses;
    for (const auto& f : scene.true_frames) poses[f.raster] = f.eo;
    // Marks to check, in every image: one image sees each of its 20 control and 5 check points
    // (the defaults) once; the UAV block's 12 images see their own footprint's points at least.
    if (scenario == Scenario::kUavBlock) {
      ASSERT_EQ(scene.true_frames.size(), 12u);
    } else {
      ASSERT_EQ(scene.true_frames.size(), 1u);
      ASSERT_EQ(scene.marks.size(), 25u) << EnumName(scenario);
    }
    std::map<std::string, int> marks_per_image;
    for (const ImageMark& mark : scene.marks) {
      ASSERT_TRUE(mark.column_row.has_value());
      ++marks_per_image[mark.raster];
      Eigen::Vector2d projected;
      ASSERT_TRUE(ProjectGroundPoint(camera, poses.at(mark.raster), points.at(mark.point_id),
                                     PixelOrigin::kCorner, &projected).ok());
      EXPECT_LE((projected - *mark.column_row).norm(), 1e-9) << EnumName(scenario);
      // Inside the image: column in [0, n_columns], row in [0, n_rows] (pixel corners).
      EXPECT_GE(mark.column_row->x(), 0.0);
      EXPECT_LE(mark.column_row->x(), camera.n_columns);
      EXPECT_GE(mark.column_row->y(), 0.0);
      EXPECT_LE(mark.column_row->y(), camera.n_rows);
    }
    EXPECT_EQ(marks_per_image.size(), scene.true_frames.size()) << EnumName(scenario);
    for (const auto& [raster, count] : marks_per_image) EXPECT_GE(count, 6) << raster;
  }
}

TEST(SyntheticScene, CountsRolesOutliersAndInitialErrorsAsAsked) {
  SyntheticSceneOptions options;
  options.num_control_points = 30;
  options.num_check_points = 7;
  options.outlier_fraction = 0.25;
  options.initial_position_error_m = 3.0;
  options.initial_angle_error_deg = 1.5;
  const SyntheticScene scene = Make(options);
  int control = 0, check = 0;
  for (const auto& p : scene.points) (p.role == PointRole::kControl ? control : check)++;
  EXPECT_EQ(control, 30);  // one image: every generated point is seen by it
  EXPECT_EQ(check, 7);
  int outliers = 0;
  for (bool o : scene.mark_is_outlier) outliers += o;
  EXPECT_EQ(outliers, static_cast<int>(std::lround(0.25 * scene.marks.size())));
  const Vector6d error = scene.approximate_frames[0].eo.parameters - scene.true_frames[0].eo.parameters;
  EXPECT_LE(error.head<3>().cwiseAbs().maxCoeff(), 3.0);
  EXPECT_LE(error.tail<3>().cwiseAbs().maxCoeff(), DegreesToRadians(1.5));
  EXPECT_GT(error.head<3>().norm(), 0.0);
}

TEST(SyntheticScene, ScenariosHaveTheirGeometry) {
  SyntheticSceneOptions options;
  options.scenario = Scenario::kOblique;
  const SyntheticScene oblique = Make(options);
  EXPECT_NEAR(RadiansToDegrees(oblique.true_frames[0].eo.parameters[3]), 45.0, 2.0);
  options.scenario = Scenario::kUavBlock;
  const SyntheticScene block = Make(options);
  EXPECT_EQ(block.true_frames.size(), 12u);
  EXPECT_NE(block.cameras[0].radial_k[1], 0.0);  // the UAV camera carries lens distortion
  // Neighbouring images overlap: some points are marked in more than one image.
  std::map<std::string, int> images_per_point;
  for (const auto& m : block.marks) images_per_point[m.point_id]++;
  int shared = 0;
  for (const auto& [id, count] : images_per_point) shared += count > 1;
  EXPECT_GT(shared, 50);
}

TEST(SyntheticScene, RejectsInvalidOptions) {
  SyntheticSceneOptions options;
  SyntheticScene scene;
  options.outlier_fraction = 1.0;
  EXPECT_FALSE(MakeSyntheticScene(options, &scene).ok());
  options = SyntheticSceneOptions();
  options.noise_px = -1.0;
  EXPECT_FALSE(MakeSyntheticScene(options, &scene).ok());
  options = SyntheticSceneOptions();
  options.num_control_points = options.num_check_points = 0;
  EXPECT_FALSE(MakeSyntheticScene(options, &scene).ok());
  EXPECT_EQ(ParseEnum<Scenario>("uav_block"), Scenario::kUavBlock);
  EXPECT_FALSE(ParseEnum<Scenario>("satellite").has_value());
}

TEST(SyntheticScene, HugePointCountsAreRefusedWithoutOverflow) {
  // INT_MAX + INT_MAX overflowed an int sum (undefined behaviour; the UBSan build checks it).
  SyntheticSceneOptions options;
  options.num_control_points = std::numeric_limits<int>::max();
  options.num_check_points = std::numeric_limits<int>::max();
  EXPECT_EQ(options.IsValid().message(), "control plus check points must be at most 1000000 per image");
  options.num_check_points = 0;
  EXPECT_FALSE(options.IsValid().ok());
  options.num_control_points = 1000000;
  EXPECT_TRUE(options.IsValid().ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
