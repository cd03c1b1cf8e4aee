#include "solvers/georeference/synthetic_georeference.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/simulation/synthetic_block.h"
#include "tests/support/exact_block.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// The similarity and the dome are evaluated in doubles on the block's UTM-like coordinates (~4e6
// m), scaled by 0.05 and back: ~1e-16 relative gives ~1e-9 m (measured up to 1.5e-9); 1e-8 m is
// above that and far below any effect tested. PROJ's round trip (EPSG:4326 and UTM and back) is good to ~1e-8 m; 1e-6 m
// leaves room and is far below any measurement noise.
constexpr double kArithmeticTolerance = 1e-8;
constexpr double kProjRoundTripTolerance = 1e-6;

// A small block (2 x 4 images) with exact marks: the scene is built from its truth.
testing::ExactBlock MakeSmallBlock() {
  SyntheticBlockOptions o;
  o.seed = 11;
  o.num_lines = 2;
  o.images_per_line = 4;
  o.num_tie_points = 200;
  return testing::MakeExactBlock(o);
}

// A model point back in the local frame by the inverse of the options' similarity (the dome
// stays in it).
Eigen::Vector3d ModelToLocal(const SyntheticGeoreferenceOptions& o, const Eigen::Vector3d& model) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(o.model_rotation_z_rad, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(o.model_rotation_x_rad, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return R.transpose() * (model - o.model_shift) / o.model_scale;
}

TEST(SyntheticGeoreference, ModelIsTheTruthBentByTheDomeAndMovedByTheSimilarity) {
  const testing::ExactBlock b = MakeSmallBlock();
  SyntheticGeoreferenceOptions options;
  options.dome_m = 2.0;
  options.block_origin_m = b.block.images[0].measured_center_m->cwiseProduct(Eigen::Vector3d(1.0, 1.0, 0.0));
  SyntheticGeoreference scene;
  ASSERT_TRUE(MakeSyntheticGeoreference(b.block, b.truth, options, &scene).ok());
  // Images: all of them, their centres the truth moved (the dome lowers a camera less than the
  // farthest point, but it lowers it).
  ASSERT_EQ(scene.model.images.size(), b.block.images.size());
  ASSERT_EQ(scene.true_centres_local.size(), b.block.images.size());
  double largest_drop_m = 0.0;
  for (size_t i = 0; i < scene.model.images.size(); ++i) {
    const Eigen::Vector3d back = ModelToLocal(options, scene.model.images[i].eo->center_in_ground());
    EXPECT_NEAR((back - b.truth.eo[i].center_in_ground()).head<2>().norm(), 0.0, kArithmeticTolerance);
    EXPECT_EQ(scene.true_centres_local[i], b.truth.eo[i].center_in_ground() - options.block_origin_m);
    EXPECT_LE(back.z(), b.truth.eo[i].center_in_ground().z() + kArithmeticTolerance);
    EXPECT_FALSE(scene.model.images[i].measured_center_m.has_value());
  }
  // Tie points only, lowered by at most the dome and, at the edge, by nearly all of it.
  size_t ties = 0;
  for (const BlockPoint& point : b.block.points) ties += point.role == PointRole::kTie;
  ASSERT_EQ(scene.model.points.size(), ties);
  for (size_t p = 0; p < scene.model.points.size(); ++p) {
    EXPECT_EQ(scene.model.points[p].role, PointRole::kTie);
    const Eigen::Vector3d back = ModelToLocal(options, *scene.model.points[p].position_m);
    const Eigen::Vector3d truth_in_block = scene.true_points_local[p] + options.block_origin_m;
    EXPECT_NEAR((back - truth_in_block).head<2>().norm(), 0.0, kArithmeticTolerance);
    const double drop_m = truth_in_block.z() - back.z();
    EXPECT_LE(drop_m, options.dome_m + kArithmeticTolerance);
    EXPECT_GE(drop_m, -kArithmeticTolerance);
    largest_drop_m = std::max(largest_drop_m, drop_m);
  }
  EXPECT_GT(largest_drop_m, 0.5 * options.dome_m);

  // The measurements: the block's own, in their CRSs; back through PROJ they are the block's.
  ASSERT_EQ(scene.inputs.positions.size(), b.block.images.size());
  std::vector<Eigen::Vector3d> positions;
  for (const CameraPositionMeasurement& m : scene.inputs.positions) positions.push_back(m.position);
  EXPECT_NEAR(positions[0].x(), 11.2, 0.05);  // longitude first
  EXPECT_NEAR(positions[0].y(), 47.8, 0.05);
  ASSERT_TRUE(scene.truth_frame.ToLocal("EPSG:4326", &positions).ok());
  for (size_t i = 0; i < positions.size(); ++i)
    EXPECT_NEAR((positions[i] + options.block_origin_m - *b.block.images[i].measured_center_m).norm(), 0.0,
                kProjRoundTripTolerance);
  std::vector<Eigen::Vector3d> control;
  for (const GroundPoint& gp : scene.inputs.control_points) control.push_back(gp.position);
  ASSERT_FALSE(control.empty());
  EXPECT_NEAR(control[0].x(), 665000.0, 5000.0);  // UTM 32N at 11.2 E, 47.8 N: the block is at the origin
  EXPECT_NEAR(control[0].y(), 5296000.0, 5000.0);
  ASSERT_TRUE(scene.truth_frame.ToLocal("EPSG:32632", &control).ok());
  size_t k = 0;
  for (const BlockPoint& point : b.block.points) {
    if (point.role == PointRole::kTie) continue;
    EXPECT_EQ(scene.inputs.control_points[k].point_id, "GCP_" + point.id);
    EXPECT_EQ(scene.inputs.control_points[k].role, point.role);
    EXPECT_NEAR((control[k] + options.block_origin_m - *point.surveyed_m).norm(), 0.0, kProjRoundTripTolerance);
    ++k;
  }
  EXPECT_EQ(scene.model.marks.size() + scene.inputs.control_marks.size(), b.block.marks.size());
}

TEST(SyntheticGeoreference, BadOptionsAndAForeignTruthAreRefused) {
  const testing::ExactBlock b = MakeSmallBlock();
  SyntheticGeoreference scene;
  SyntheticGeoreferenceOptions options;
  options.model_scale = 0.0;
  EXPECT_EQ(MakeSyntheticGeoreference(b.block, b.truth, options, &scene).message(),
            "synthetic georeference: the model's scale must be a positive finite number");
  options = SyntheticGeoreferenceOptions();
  options.dome_m = std::nan("");
  EXPECT_EQ(MakeSyntheticGeoreference(b.block, b.truth, options, &scene).message(),
            "synthetic georeference: the dome must be a finite height in metres");
  SyntheticBlockTruth other = b.truth;
  other.points_m.pop_back();
  EXPECT_EQ(MakeSyntheticGeoreference(b.block, other, SyntheticGeoreferenceOptions(), &scene).message(),
            "synthetic georeference: the truth is not the block's (images or points differ in number)");
  options = SyntheticGeoreferenceOptions();
  options.control_crs = "EPSG:999999";
  EXPECT_FALSE(MakeSyntheticGeoreference(b.block, b.truth, options, &scene).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
