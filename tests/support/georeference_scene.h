#pragma once
// A reconstruction as an SfM pipeline hands it over, for the georeferencing tests: a synthetic
// block (SIMPLE_RADIAL camera) whose truth lives in a local East-North-Up frame at a place on
// Earth; the model is that truth bent by a dome (heights lowered by dome_m * (r / r_max)^2 from
// the centre, as a wrong radial distortion bends parallel nadir lines) and then moved into an
// arbitrary similarity frame (scale 0.05, rotated, shifted). The measurements: GNSS centres with
// their noise in EPSG:4326 (longitude, latitude, ellipsoidal height) and control / check points
// in UTM zone 32N with their marks, as geo.txt / gcp_list.txt would carry them.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "core/block.h"
#include "core/geodesy/crs.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_block.h"
#include "solvers/georeference/georeference.h"

namespace photopose::testing {

struct GeoreferenceScene {
  Block model;                                 // tie points only, in the model frame
  GeoreferenceInputs inputs;                   // positions (EPSG:4326), control (EPSG:32632)
  std::vector<Eigen::Vector3d> true_points_local;  // per model point
  std::vector<Eigen::Vector3d> true_centres_local; // per image
  LocalFrame truth_frame;                      // where the truth is
};

inline GeoreferenceScene MakeGeoreferenceScene(double dome_m = 0.8, int lines = 3,
                                               int images_per_line = 8) {
  SyntheticBlockOptions o;
  o.seed = 3;
  o.num_lines = lines;
  o.images_per_line = images_per_line;
  o.origin_m = Eigen::Vector2d(-150.0, -80.0);
  o.ground_height_m = 0.0;
  o.camera_model = CameraModelType::kSimpleRadial;
  o.image_width_px = 3000;
  o.image_height_px = 2000;
  o.pixel_size_um = 4.0;
  o.focal_length_mm = 12.0;
  o.num_tie_points = 1500;
  o.num_control_points = 5;
  o.num_check_points = 4;
  o.mark_sigma_px = 0.3;
  o.mark_accuracy_px = 0.3;
  o.control_sigma_m = 0.005;
  o.control_accuracy_m = 0.005;
  o.gnss_sigma_m = Eigen::Vector3d(0.03, 0.03, 0.05);
  o.gnss_accuracy_m = Eigen::Vector3d(0.03, 0.03, 0.05);
  o.start_position_sigma_m = 0.0;
  o.start_angle_sigma_deg = 0.0;
  o.start_point_sigma_m = 0.0;
  GeoreferenceScene scene;
  Block block;
  SyntheticBlockTruth truth;
  const Status made = MakeSyntheticBlock(o, &block, &truth);
  EXPECT_TRUE(made.ok()) << made.message();
  // The truth frame: ENU at 11.2 E, 47.8 N, 500 m (UTM zone 32N).
  const Status frame = LocalFrame::Create("EPSG:4979", Eigen::Vector3d(11.2, 47.8, 500.0), &scene.truth_frame);
  EXPECT_TRUE(frame.ok()) << frame.message();

  // Dome about the block centre, then an arbitrary similarity.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const ExteriorOrientation& eo : truth.eo) centre += eo.center_in_ground();
  centre /= static_cast<double>(truth.eo.size());
  double r_max = 1.0;
  for (const Eigen::Vector3d& p : truth.points_m) r_max = std::max(r_max, (p - centre).head<2>().norm());
  const auto dome = [&](Eigen::Vector3d x) {
    x.z() -= dome_m * (x - centre).head<2>().squaredNorm() / (r_max * r_max);
    return x;
  };
  const Eigen::Matrix3d R_model_from_local =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const double scale = 0.05;
  const Eigen::Vector3d shift(3.0, -2.0, 7.0);
  const auto to_model = [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(scale * (R_model_from_local * dome(x)) + shift); };

  // The model: the block's images and tie points; control / check points and their marks leave.
  Block& model = scene.model;
  model.cameras = block.cameras;
  model.images = block.images;
  std::vector<int> new_index(block.points.size(), -1);
  std::vector<Eigen::Vector3d> control_local;
  std::vector<std::string> control_crs_points;
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role == PointRole::kTie) {
      new_index[p] = static_cast<int>(model.points.size());
      BlockPoint tie = point;
      tie.position_m = to_model(truth.points_m[p]);
      model.points.push_back(tie);
      scene.true_points_local.push_back(truth.points_m[p]);
    } else {
      GroundPoint gp;
      gp.point_id = "GCP_" + point.id;
      gp.position = *point.surveyed_m;
      gp.accuracy_m = point.accuracy_m;
      gp.role = point.role;
      scene.inputs.control_points.push_back(gp);
    }
  }
  for (const BlockMark& mark : block.marks) {
    if (new_index[mark.point] >= 0) {
      BlockMark m = mark;
      m.point = new_index[mark.point];
      model.marks.push_back(m);
    } else {
      ImageMark im;
      im.raster = block.images[mark.image].name;
      im.point_id = "GCP_" + block.points[mark.point].id;
      im.column_row = mark.measured;
      im.accuracy_px = mark.accuracy;
      scene.inputs.control_marks.push_back(im);
    }
  }
  for (size_t i = 0; i < model.images.size(); ++i) {
    BlockImage& image = model.images[i];
    scene.true_centres_local.push_back(truth.eo[i].center_in_ground());
    CameraPositionMeasurement m;
    m.image = image.name;
    m.position = *image.measured_center_m;
    m.accuracy_m = image.center_accuracy_m;
    scene.inputs.positions.push_back(m);
    image.measured_center_m.reset();
    image.center_accuracy_m.reset();
    const Eigen::Matrix3d R_camera_from_local = RotationFromAngles(RotationConvention::kSeed, truth.eo[i].angles_seed_rad());
    ExteriorOrientation eo;
    eo.set_center_in_ground(to_model(truth.eo[i].center_in_ground()));
    eo.set_angles_seed_rad(AnglesFromRotation(RotationConvention::kSeed, R_camera_from_local * R_model_from_local.transpose()));
    image.eo = eo;
  }
  model.BuildIndex();

  // Measurements into their CRSs.
  std::vector<Eigen::Vector3d> positions;
  for (const CameraPositionMeasurement& m : scene.inputs.positions) positions.push_back(m.position);
  EXPECT_TRUE(scene.truth_frame.FromLocal("EPSG:4326", &positions).ok());
  for (size_t k = 0; k < positions.size(); ++k) scene.inputs.positions[k].position = positions[k];
  scene.inputs.positions_crs = "EPSG:4326";
  scene.inputs.positions_source = "geo.txt";
  std::vector<Eigen::Vector3d> control;
  for (const GroundPoint& gp : scene.inputs.control_points) control.push_back(gp.position);
  EXPECT_TRUE(scene.truth_frame.FromLocal("EPSG:32632", &control).ok());
  for (size_t k = 0; k < control.size(); ++k) scene.inputs.control_points[k].position = control[k];
  scene.inputs.control_crs = "EPSG:32632";
  scene.inputs.control_source = "gcp_list.txt";
  return scene;
}

}  // namespace photopose::testing
