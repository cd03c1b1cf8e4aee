// Issue 21's scene: a synthetic block bent by a dome and moved into a model frame, its GNSS and
// control in their CRSs (solvers/georeference/synthetic_georeference.h).
#include "solvers/georeference/synthetic_georeference.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/rotation.h"

namespace photopose {

bool SyntheticGeoreferenceOptions::IsValid(std::string* why) const {
  if (!std::isfinite(dome_m)) {
    *why = "the dome must be a finite height in metres";
  } else if (!(std::isfinite(model_scale) && model_scale > 0.0)) {
    *why = "the model's scale must be a positive finite number";
  } else if (!origin_lon_lat_h.allFinite() || !block_origin_m.allFinite() || !model_shift.allFinite() || !std::isfinite(model_rotation_z_rad) ||
             !std::isfinite(model_rotation_x_rad)) {
    *why = "the origins, rotation and shift must be finite";
  } else if (positions_crs.empty() || control_crs.empty()) {
    *why = "the CRSs of the positions and of the control must be named";
  } else {
    return true;
  }
  return false;
}

Status MakeSyntheticGeoreference(const Block& block, const SyntheticBlockTruth& truth,
                                 const SyntheticGeoreferenceOptions& options,
                                 SyntheticGeoreference* out) {
  std::string why;
  if (!options.IsValid(&why)) return Status::Error("synthetic georeference: " + why);
  if (truth.eo.size() != block.images.size() || truth.points_m.size() != block.points.size() || block.images.empty())
    return Status::Error("synthetic georeference: the truth is not the block's (images or points differ in number)");
  SyntheticGeoreference scene;
  PHOTOPOSE_RETURN_IF_ERROR(LocalFrame::Create("EPSG:4979", options.origin_lon_lat_h, &scene.truth_frame));

  // The dome about the centre of the camera centres, then the similarity into the model frame.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const ExteriorOrientation& eo : truth.eo) centre += eo.center_in_ground();
  centre /= static_cast<double>(truth.eo.size());
  double r_max = 1.0;
  for (const Eigen::Vector3d& p : truth.points_m) r_max = std::max(r_max, (p - centre).head<2>().norm());
  const auto dome = [&](Eigen::Vector3d x) {
    x.z() -= options.dome_m * (x - centre).head<2>().squaredNorm() / (r_max * r_max);
    return x;
  };
  const Eigen::Matrix3d R_model_from_local =
      (Eigen::AngleAxisd(options.model_rotation_z_rad, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(options.model_rotation_x_rad, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const auto to_model = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(options.model_scale * (R_model_from_local * dome(x)) + options.model_shift);
  };

  // The model: the block's images and tie points; control / check points and their marks leave.
  Block& model = scene.model;
  GeoreferenceInputs& inputs = scene.inputs;
  model.cameras = block.cameras;
  model.images = block.images;
  std::vector<int> new_index(block.points.size(), -1);
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role == PointRole::kTie) {
      new_index[p] = static_cast<int>(model.points.size());
      BlockPoint tie = point;
      tie.position_m = to_model(truth.points_m[p]);
      model.points.push_back(tie);
      scene.true_points_local.push_back(truth.points_m[p] - options.block_origin_m);
    } else {
      if (!point.surveyed_m) return Status::Error("synthetic georeference: control point '" + point.id + "' has no survey");
      GroundPoint gp;
      gp.point_id = options.control_id_prefix + point.id;
      gp.position = *point.surveyed_m - options.block_origin_m;
      gp.accuracy_m = point.accuracy_m;
      gp.role = point.role;
      inputs.control_points.push_back(gp);
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
      im.point_id = options.control_id_prefix + block.points[mark.point].id;
      im.column_row = mark.measured;
      im.accuracy_px = mark.accuracy;
      inputs.control_marks.push_back(im);
    }
  }
  for (size_t i = 0; i < model.images.size(); ++i) {
    BlockImage& image = model.images[i];
    scene.true_centres_local.push_back(truth.eo[i].center_in_ground() - options.block_origin_m);
    if (image.measured_center_m) {
      CameraPositionMeasurement m;
      m.image = image.name;
      m.position = *image.measured_center_m - options.block_origin_m;
      m.accuracy_m = image.center_accuracy_m;
      inputs.positions.push_back(m);
    }
    image.measured_center_m.reset();
    image.center_accuracy_m.reset();
    const Eigen::Matrix3d R_camera_from_local =
        RotationFromAngles(RotationConvention::kSeed, truth.eo[i].angles_seed_rad());
    ExteriorOrientation eo;
    eo.set_center_in_ground(to_model(truth.eo[i].center_in_ground()));
    eo.set_angles_seed_rad(
        AnglesFromRotation(RotationConvention::kSeed, R_camera_from_local * R_model_from_local.transpose()));
    image.eo = eo;
  }
  model.BuildIndex();

  // The measurements into their CRSs.
  const auto into_crs = [&](const std::string& crs, auto* measurements, auto position_of) -> Status {
    std::vector<Eigen::Vector3d> positions;
    for (auto& m : *measurements) positions.push_back(*position_of(m));
    PHOTOPOSE_RETURN_IF_ERROR(scene.truth_frame.FromLocal(crs, &positions));
    for (size_t k = 0; k < positions.size(); ++k) *position_of((*measurements)[k]) = positions[k];
    return Status::Ok();
  };
  PHOTOPOSE_RETURN_IF_ERROR(into_crs(options.positions_crs, &inputs.positions,
                                     [](CameraPositionMeasurement& m) { return &m.position; }));
  PHOTOPOSE_RETURN_IF_ERROR(
      into_crs(options.control_crs, &inputs.control_points, [](GroundPoint& gp) { return &gp.position; }));
  inputs.positions_crs = options.positions_crs;
  inputs.positions_source = options.positions_source;
  inputs.control_crs = options.control_crs;
  inputs.control_source = options.control_source;
  *out = std::move(scene);
  return Status::Ok();
}

}  // namespace photopose
