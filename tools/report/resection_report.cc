#include "tools/report/resection_report.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/io/output_files.h"
#include "core/io/tables.h"
#include "core/pixel_rows.h"

namespace photopose::cli {

Status WriteResectionFrames(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results) {
  std::vector<FrameRecord> frames;
  std::vector<FrameCamera> cameras;
  for (const BlockCamera& camera : job.block.cameras) cameras.push_back(camera.table);
  for (size_t i = 0; i < results.size(); ++i) {
    const ResectionResult& r = results[i];
    if (!r.success) continue;
    const BlockCamera& camera = job.camera(i);
    FrameRecord frame;
    frame.raster = job.inputs[i].raster;
    frame.camera_id = camera.camera_id;
    // The camera's SRS, else the ground system the marks came with (a gcp_list's first line).
    frame.srs = camera.table.srs.empty() ? job.block.crs : camera.table.srs;
    frame.eo = r.eo;
    if (r.has_covariance) {
      frame.covariance = r.covariance;
      frame.sigma0 = r.sigma0;
    }
    frame.extra_columns = {{"NumObservations", std::to_string(r.inliers.size())},
                           {"NumInliers", std::to_string(r.num_inliers)},
                           {"Reliability", r.weak ? "weak" : "ok"}};
    // The input frame's measured centre and its accuracy, kept apart from the adjusted
    // PerspectiveX/Y/Z: AccuracyX/Y/Z are the accuracies of MeasuredX/Y/Z.
    const BlockImage& block_image = job.block.images[job.images[i]];
    if (block_image.measured_center_m) {
      const Eigen::Vector3d& m = *block_image.measured_center_m;
      char text[64];
      for (int k = 0; k < 3; ++k) {
        std::snprintf(text, sizeof(text), "%.4f", m[k]);
        frame.extra_columns.push_back({std::string("Measured") + "XYZ"[k], text});
      }
      frame.center_accuracy_m = block_image.center_accuracy_m;
    }
    frames.push_back(std::move(frame));
  }
  FramesTableOptions frames_options;
  frames_options.convention = options.files.rotation;
  frames_options.cameras = &cameras;
  return WriteFramesTable(path, frames_options, frames);
}

namespace {

using nlohmann::json;

json FiniteOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// The options the run was made with.
json OptionsJson(const ResectionJobOptions& options) {
  const ResectionOptions& o = options.resection;
  return {
      {"solver", EnumName(o.refinement.solver)},
      {"jacobian", EnumName(o.refinement.jacobian)},
      {"loss", EnumName(o.refinement.loss)},
      {"loss_scale_sigmas", o.refinement.loss_scale},
      {"ceres_minimizer", EnumName(o.refinement.ceres.minimizer)},
      {"confidence", o.test.confidence},
      {"consensus_threshold_sigmas", MarkThresholdSigmas(o.test.confidence)},
      {"ransac_seed", o.consensus.ransac.seed},
      {"max_exhaustive_samples", o.consensus.ransac.max_exhaustive_samples},
      {"allow_no_redundancy", o.allow_no_redundancy},
      {"rotation", EnumName(options.files.rotation)},
      {"default_accuracy",
       options.input.default_accuracy > 0.0 ? json(options.input.default_accuracy) : json(nullptr)},
      {"default_film_accuracy_um", options.input.default_film_accuracy_um},
      {"strict", o.refuse_weak},
      {"consensus_after_frames", o.consensus_after_approximate},
      {"weak_pose_shift_sigmas", o.weak_pose_shift_sigmas},
      {"ambiguous_pose_sigmas", o.ambiguous_pose_sigmas},
      {"detection_power", o.detection_power},
      {"pixel_origin", EnumName(options.files.pixel_origin)},
      {"pixel_rows", EnumName(options.files.pixel_rows)}};
}

// What every image has, solved or not: its solve's summary and verdict.
json ImageSummaryJson(const ResectionJob& job, size_t i, const ResectionResult& r) {
  const ResectionSummary& s = r.summary;
  return {{"raster", job.inputs[i].raster},
          {"camera_id", job.camera(i).camera_id},
          {"success", r.success},
          {"message", s.message},
          {"termination", EnumName(s.termination)},
          {"initial_values", s.used_approximate                ? "frames"
                             : s.consensus_after_approximate ? "consensus_after_frames"
                                                             : "consensus"},
          {"consensus",
           {{"trials", s.ransac_trials},
            {"exhaustive", s.ransac_exhaustive},
            {"stopped_early", s.ransac_stopped_early}}},
          {"adjustments", s.adjustments},
          {"iterations", s.iterations},
          {"initial_cost", s.initial_cost},
          {"final_cost", s.final_cost},
          {"time_seconds", s.total_seconds},
          {"accuracy", r.accuracy_stated ? "stated" : "estimated"},
          {"verdict", ResectionVerdictName(r)},
          {"sigma0", r.sigma0},
          {"degrees_of_freedom", r.degrees_of_freedom},
          {"warnings", r.warnings}};
}

// One of two poses an ambiguous image fits equally well, with the points it takes as inliers.
json AmbiguousPoseJson(const ResectionJob& job, size_t i, RotationConvention rotation,
                       const ExteriorOrientation& eo, const std::vector<char>& inliers) {
  json ids = json::array();
  for (size_t k = 0; k < inliers.size(); ++k)
    if (inliers[k]) ids.push_back(job.inputs[i].point_ids[k]);
  const Eigen::Vector3d angles = OutputAnglesDeg(job, i, rotation, eo);
  return json{{"X", eo.parameters[0]},  {"Y", eo.parameters[1]}, {"Z", eo.parameters[2]},
              {"omega_deg", angles[0]}, {"phi_deg", angles[1]},  {"kappa_deg", angles[2]},
              {"point_ids", ids}};
}

// A scanned image's fiducial fit: residuals and the fitted A0-B2 in the user's row convention,
// as the camera table would take them.
Status FiducialsJson(const ResectionJobOptions& options, const ResectionJob& job, size_t i,
                     const FiducialFit& fit, json* out) {
  json residuals = json::array();
  for (const FiducialResidual& f : fit.residuals)
    residuals.push_back({{"fiducial_id", f.fiducial_id},
                         {"line", f.line},
                         {"residual_x_um", f.residual_um.x()},
                         {"residual_y_um", f.residual_um.y()}});
  FrameCamera affine = WithFiducialAffine(job.camera(i).table, fit);
  if (options.files.pixel_rows == PixelRows::kUp)
    PHOTOPOSE_RETURN_IF_ERROR(AffineWithRowsFlipped(&affine));
  *out = {{"count", fit.residuals.size()},
          {"rms_um", fit.rms_um},
          {"max_um", fit.max_um},
          {"redundancy", fit.redundancy},
          {"affine",
           {affine.affine_a[0], affine.affine_a[1], affine.affine_a[2], affine.affine_b[0],
            affine.affine_b[1], affine.affine_b[2]}},
          {"affine_pixel_rows", EnumName(options.files.pixel_rows)},
          {"residuals", residuals}};
  return Status::Ok();
}

// A solved image's pose in the output convention, its covariance and standard deviations.
void PoseJson(const ResectionJob& job, size_t i, RotationConvention rotation,
              const ResectionResult& r, json* image) {
  const Eigen::Vector3d angles = OutputAnglesDeg(job, i, rotation, r.eo);
  (*image)["pose"] = {{"X", r.eo.parameters[0]},
                      {"Y", r.eo.parameters[1]},
                      {"Z", r.eo.parameters[2]},
                      {"omega_deg", angles[0]},
                      {"phi_deg", angles[1]},
                      {"kappa_deg", angles[2]},
                      {"convention", EnumName(rotation)},
                      {"angle_direction", job.camera(i).table.angle_direction}};
  (*image)["seed_angles_rad"] = {r.eo.parameters[3], r.eo.parameters[4], r.eo.parameters[5]};
  const std::optional<Eigen::Vector3d> angle_sigmas = OutputAngleSigmasDeg(job, i, rotation, r);
  if (!r.has_covariance) {
    (*image)["covariance_seed"] = nullptr;
    (*image)["standard_deviations"] = nullptr;
    return;
  }
  json covariance = json::array();
  for (int row = 0; row < 6; ++row)
    for (int col = 0; col < 6; ++col) covariance.push_back(r.covariance(row, col));
  (*image)["covariance_seed"] = covariance;  // row-major, X0 Y0 Z0 (m) omega phi kappa (rad)
  (*image)["covariance_factor"] = r.covariance_factor;
  (*image)["standard_deviations"] = {
      {"X", r.standard_deviations[0]}, {"Y", r.standard_deviations[1]},
      {"Z", r.standard_deviations[2]}, {"omega_deg", (*angle_sigmas)[0]},
      {"phi_deg", (*angle_sigmas)[1]}, {"kappa_deg", (*angle_sigmas)[2]}};
}

// A solved image's marks: residuals, status and reliability.
json MarksJson(const ResectionJob& job, size_t i, const ResectionResult& r) {
  const Block& block = job.block;
  json marks = json::array();
  for (size_t k = 0; k < job.input_marks[i].size(); ++k) {
    const BlockMark& mark = block.marks[job.input_marks[i][k]];
    marks.push_back({{"point_id", block.points[mark.point].id},
                     {"line", mark.line},
                     {"status", EnumName(r.mark_status[k])},
                     {"inlier", static_cast<bool>(r.inliers[k])},
                     {"residual_x", r.residuals[k].x()},
                     {"residual_y", r.residuals[k].y()},
                     {"unit", EnumName(mark.unit)},
                     {"normalized_residual", FiniteOrNull(r.normalized_residuals[k])},
                     {"redundancy", r.redundancy_numbers[k]},
                     {"mdb", FiniteOrNull(r.minimal_detectable_blunders[k])},
                     {"pose_shift_sigmas", FiniteOrNull(r.pose_shifts_sigmas[k])}});
  }
  return marks;
}

// A solved image's check marks, projected through its pose.
json CheckPointsJson(const ResectionJob& job, size_t i, const ResectionResult& r) {
  const Block& block = job.block;
  json checks = json::array();
  for (const CheckResidual& c : CheckResiduals(job, i, r.eo)) {
    const BlockMark& mark = block.marks[c.mark];
    checks.push_back({{"point_id", block.points[mark.point].id},
                      {"line", mark.line},
                      {"residual_x", c.residual.x()},
                      {"residual_y", c.residual.y()},
                      {"residual", c.residual.norm()},
                      {"unit", EnumName(mark.unit)}});
  }
  return checks;
}

// What a solved image adds: its pose and sigmas, reliability, marks and check points.
void SolvedImageJson(const ResectionJob& job, size_t i, RotationConvention rotation,
                     const ResectionResult& r, json* image) {
  PoseJson(job, i, rotation, r, image);
  (*image)["sigma0_unit"] = Sigma0Unit(job, i, r);
  (*image)["num_inliers"] = r.num_inliers;
  (*image)["weak"] = r.weak;
  (*image)["max_pose_shift_sigmas"] = FiniteOrNull(r.max_pose_shift_sigmas);
  (*image)["critical_normalized_residual"] = FiniteOrNull(r.critical_normalized_residual);
  (*image)["marks"] = MarksJson(job, i, r);
  (*image)["check_points"] = CheckPointsJson(job, i, r);
}

// One image's entry of the report.
Status ImageJson(const ResectionJobOptions& options, const ResectionJob& job, size_t i,
                 const ResectionResult& r, json* image) {
  const RotationConvention rotation = options.files.rotation;
  *image = ImageSummaryJson(job, i, r);
  if (r.summary.consensus_after_approximate)
    (*image)["frames_start_abandoned"] = r.summary.approximate_message;
  if (r.ambiguous) {
    (*image)["ambiguous_poses"] = {
        AmbiguousPoseJson(job, i, rotation, r.eo, r.inliers),
        AmbiguousPoseJson(job, i, rotation, r.competing_eo, r.competing_inliers)};
  }
  const BlockImage& block_image = job.block.images[job.images[i]];
  if (block_image.fiducial_fit) {
    json fiducials;
    PHOTOPOSE_RETURN_IF_ERROR(
        FiducialsJson(options, job, i, *block_image.fiducial_fit, &fiducials));
    (*image)["fiducials"] = fiducials;
  }
  if (r.success) SolvedImageJson(job, i, rotation, r, image);
  return Status::Ok();
}

}  // namespace

Status WriteResectionReport(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results,
                            const std::vector<std::string>& written) {
  json report;
  report["options"] = OptionsJson(options);
  json images = json::array();
  int solved = 0;
  for (size_t i = 0; i < results.size(); ++i) {
    json image;
    PHOTOPOSE_RETURN_IF_ERROR(ImageJson(options, job, i, results[i], &image));
    if (results[i].success) ++solved;
    images.push_back(image);
  }
  report["images"] = images;
  report["summary"] = {{"images", results.size()},
                       {"solved", solved},
                       {"not_solved", static_cast<int>(results.size()) - solved},
                       {"tie_marks_left_out", job.num_tie_marks},
                       {"files_written", written}};
  return WriteFileAtomically(path, report.dump(2) + "\n");
}

}  // namespace photopose::cli
