#pragma once
// A reconstruction as an SfM pipeline hands it over, for the georeferencing tests: the library's
// synthetic scene (solvers/georeference/synthetic_georeference.h, which `photopose simulate
// --georeferenced` writes too) of a small SIMPLE_RADIAL block: its truth in a local East-North-Up
// frame at 11.2 E 47.8 N, the model bent by a dome and moved into an arbitrary similarity frame
// (scale 0.05, rotated, shifted), GNSS centres with their noise in EPSG:4326 (longitude, latitude,
// ellipsoidal height) and control / check points in UTM zone 32N with their marks, as geo.txt /
// gcp_list.txt would carry them.
#include <gtest/gtest.h>

#include "core/simulation/synthetic_block.h"
#include "solvers/georeference/synthetic_georeference.h"

namespace photopose::testing {

using GeoreferenceScene = SyntheticGeoreference;

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
  Block block;
  SyntheticBlockTruth truth;
  const Status made = MakeSyntheticBlock(o, &block, &truth);
  EXPECT_TRUE(made.ok()) << made.message();
  SyntheticGeoreferenceOptions options;
  options.dome_m = dome_m;
  GeoreferenceScene scene;
  const Status georeferenced = MakeSyntheticGeoreference(block, truth, options, &scene);
  EXPECT_TRUE(georeferenced.ok()) << georeferenced.message();
  return scene;
}

}  // namespace photopose::testing
