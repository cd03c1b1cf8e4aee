#pragma once
// A reconstruction as an SfM pipeline hands it over, for tests, benchmarks and `photopose simulate
// --scenario=block --georeferenced` (issue 21's scene): a synthetic block (core/simulation/
// synthetic_block.h) whose truth is taken as a local East-North-Up frame at a place on Earth; the
// model is that truth bent by a dome (heights lowered by dome_m * (r / r_max)^2, r the horizontal
// distance from the centre of the camera centres, as a wrong radial distortion bends parallel
// nadir lines) and then moved into an arbitrary similarity frame. The measurements are the
// block's own: its measured camera centres (GNSS, with their noise) in positions_crs and its
// control / check points (with their noise) and their marks in control_crs, as a geo.txt and a
// gcp_list.txt carry them (GeoreferenceInputs, solvers/georeference/georeference.h).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/geodesy/crs.h"
#include "core/simulation/synthetic_block.h"
#include "core/status.h"
#include "solvers/georeference/georeference.h"

namespace photopose {

struct SyntheticGeoreferenceOptions {
  // Height (m) the model loses at the block's edge (the point farthest from the centre): the
  // dome. 0: no bending.
  double dome_m = 0.8;
  // Where the truth's ENU frame lies: longitude, latitude (degrees), ellipsoidal height (m) of its
  // origin on WGS84 (EPSG:4979). The default, 11.2 E 47.8 N, lies in UTM zone 32N.
  Eigen::Vector3d origin_lon_lat_h{11.2, 47.8, 500.0};
  // The point of the block's frame at that origin (m): the truth in the ENU frame is the block's
  // truth minus it. A simulated block lies at UTM-like coordinates (SyntheticBlockOptions::
  // origin_m); without this shift it would be thousands of kilometres from the origin.
  Eigen::Vector3d block_origin_m = Eigen::Vector3d::Zero();
  // The similarity from the (bent) truth to the model frame: model = scale * R * local + shift,
  // R = Rz(model_rotation_z_rad) * Rx(model_rotation_x_rad). scale in model units per metre.
  double model_scale = 0.05;
  double model_rotation_z_rad = 0.7;
  double model_rotation_x_rad = -0.3;
  Eigen::Vector3d model_shift{3.0, -2.0, 7.0};  // model units
  // The CRSs the measurements are written in (any PROJ knows; GIS axis order).
  std::string positions_crs = "EPSG:4326";   // the GNSS centres (geo.txt: lon, lat, h)
  std::string control_crs = "EPSG:32632";    // the control and check points (gcp_list.txt)
  // The names of their sources, for messages and reports.
  std::string positions_source = "geo.txt";
  std::string control_source = "gcp_list.txt";
  // Prefix of the control / check point ids (the model's tie points keep the block's ids, so the
  // two must differ).
  std::string control_id_prefix = "GCP_";

  // False with *why for a dome or scale that is not finite, a scale <= 0, an empty CRS.
  bool IsValid(std::string* why) const;
};

struct SyntheticGeoreference {
  // The block's images (their true orientations moved into the model frame, no measured centre)
  // and tie points (true positions, bent and moved) with their marks; no control, no check point.
  Block model;
  // The block's measured centres (images with one) in positions_crs, its control and check
  // points (surveyed, with their noise) in control_crs with their marks.
  GeoreferenceInputs inputs;
  // The truth in truth_frame (the block's truth minus options.block_origin_m), m.
  std::vector<Eigen::Vector3d> true_points_local;   // per model point
  std::vector<Eigen::Vector3d> true_centres_local;  // per model image
  LocalFrame truth_frame;                           // where the truth is
};

// The scene of `block` and its `truth` (MakeSyntheticBlock's). Errors: options not valid, a CRS
// PROJ does not know, a block whose points or images do not match its truth.
Status MakeSyntheticGeoreference(const Block& block, const SyntheticBlockTruth& truth,
                                 const SyntheticGeoreferenceOptions& options,
                                 SyntheticGeoreference* scene);

}  // namespace photopose
