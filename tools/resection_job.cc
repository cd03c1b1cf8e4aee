#include "tools/resection_job.h"

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>

#include "core/collinearity.h"

namespace photopose::cli {
namespace {

std::string Where(const std::string& file, int line, const std::string& column) {
  return file + ":" + std::to_string(line) + ": " + column + ": ";
}

}  // namespace

Status PrepareResectionJob(const ResectionJobOptions& options, ResectionJob* job) {
  *job = ResectionJob();
  job->pixel_origin = options.pixel_origin;
  Status status = ReadCameraTable(options.cameras_path, &job->cameras);
  if (!status.ok()) return status;
  if (job->cameras.empty()) return Status::Error(options.cameras_path + ": the camera table has no rows");
  for (const FrameCamera& camera : job->cameras) {
    status = camera.IsValid();
    if (!status.ok()) return Status::Error(options.cameras_path + ": camera '" + camera.camera_id + "': " + status.message());
  }
  if (!options.gcp_list_path.empty()) {
    GcpList gcp;
    status = ReadGcpList(options.gcp_list_path, &gcp);
    if (!status.ok()) return status;
    job->points = std::move(gcp.points);
    job->marks = std::move(gcp.marks);
    job->marks_label = options.gcp_list_path;
  } else {
    status = ReadGroundPoints(options.points_path, &job->points);
    if (!status.ok()) return status;
    status = ReadImageMarks(options.marks_path, &job->marks);
    if (!status.ok()) return status;
    job->marks_label = options.marks_path;
    status = CheckMarks(options.marks_path, job->marks, job->points);
    if (!status.ok()) return status;
  }
  if (!options.frames_path.empty()) {
    FramesTableOptions frames_options;
    frames_options.convention = options.rotation;
    frames_options.cameras = &job->cameras;
    status = ReadFramesTable(options.frames_path, frames_options, &job->approximate_frames);
    if (!status.ok()) return status;
  }

  std::map<std::string, const FrameCamera*> camera_by_id;
  for (const FrameCamera& camera : job->cameras) camera_by_id[camera.camera_id] = &camera;
  std::map<std::string, const GroundPoint*> point_by_id;
  for (const GroundPoint& point : job->points) point_by_id[point.point_id] = &point;
  std::map<std::string, const FrameRecord*> frame_by_raster;
  for (const FrameRecord& frame : job->approximate_frames) frame_by_raster[frame.raster] = &frame;

  std::map<std::string, size_t> input_by_raster;
  for (size_t m = 0; m < job->marks.size(); ++m) {
    const ImageMark& mark = job->marks[m];
    const auto point = point_by_id.find(mark.point_id);
    if (point == point_by_id.end())
      return Status::Error(Where(job->marks_label, mark.line, "PointID") + "unknown point '" + mark.point_id + "'");
    auto [it, inserted] = input_by_raster.emplace(mark.raster, job->inputs.size());
    if (inserted) {
      // The camera of this image: the mark's CameraID, the approximate frame's, or the only one.
      const FrameCamera* camera = nullptr;
      const auto frame = frame_by_raster.find(mark.raster);
      std::string camera_id = mark.camera_id;
      if (camera_id.empty() && frame != frame_by_raster.end()) camera_id = frame->second->camera_id;
      if (!camera_id.empty()) {
        const auto found = camera_by_id.find(camera_id);
        if (found == camera_by_id.end())
          return Status::Error(Where(job->marks_label, mark.line, "CameraID") + "unknown camera '" + camera_id + "'");
        camera = found->second;
      } else if (job->cameras.size() == 1) {
        camera = &job->cameras.front();
      } else {
        return Status::Error(Where(job->marks_label, mark.line, "CameraID") + "image '" + mark.raster +
                             "' names no camera and the camera table has several");
      }
      ResectionInput input;
      input.raster = mark.raster;
      input.focal_length_um = camera->focal_length_um;
      input.pixel_size_um = camera->MeanPixelSizeUm();
      if (frame != frame_by_raster.end()) input.approximate = frame->second->eo;
      job->inputs.push_back(std::move(input));
      job->input_cameras.push_back(camera);
      job->input_marks.emplace_back();
      job->input_check_marks.emplace_back();
    }
    const size_t index = it->second;
    if (!mark.camera_id.empty() && mark.camera_id != job->input_cameras[index]->camera_id)
      return Status::Error(Where(job->marks_label, mark.line, "CameraID") + "image '" + mark.raster +
                           "' has marks of two cameras");
    status = CheckMarkInsideImage(job->marks_label, mark, *job->input_cameras[index],
                                  options.pixel_origin);
    if (!status.ok()) return status;
    if (point->second->role == PointRole::kCheck) {
      job->input_check_marks[index].push_back({m, point->second->position});
      continue;
    }
    if (point->second->role == PointRole::kTie) continue;  // unknown coordinates: not for resection
    const FrameCamera& camera = *job->input_cameras[index];
    Eigen::Vector2d image_plane;
    if (mark.column_row.has_value()) {
      status = ImagePlaneFromPixel(camera, *mark.column_row, options.pixel_origin, &image_plane);
      if (!status.ok()) return Status::Error(Where(job->marks_label, mark.line, "Column") + status.message());
    } else {
      image_plane = ImagePlaneFromFilm(camera, *mark.film_um);
    }
    ResectionInput& input = job->inputs[index];
    input.image_plane_um.push_back(image_plane);
    input.points_in_ground.push_back(point->second->position);
    input.sigma_px.push_back(mark.accuracy_px.value_or(options.default_accuracy_px));
    input.point_ids.push_back(mark.point_id);
    job->input_marks[index].push_back(m);
  }
  return Status::Ok();
}

std::vector<Eigen::Vector2d> CheckPointResidualsPx(const ResectionJob& job, size_t index,
                                                   const ExteriorOrientation& eo) {
  std::vector<Eigen::Vector2d> residuals;
  const FrameCamera& camera = *job.input_cameras[index];
  for (const ResectionJob::CheckMark& check : job.input_check_marks[index]) {
    const ImageMark& mark = job.marks[check.mark];
    Eigen::Vector2d observed;
    if (mark.column_row.has_value()) {
      observed = *mark.column_row;
    } else if (!PixelFromFilm(camera, *mark.film_um, job.pixel_origin, &observed).ok()) {
      continue;
    }
    Eigen::Vector2d projected;
    if (!ProjectGroundPoint(camera, eo, check.point_in_ground, job.pixel_origin, &projected).ok())
      continue;
    residuals.push_back(observed - projected);
  }
  return residuals;
}

Status WriteResectionFrames(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results) {
  std::vector<FrameRecord> frames;
  for (size_t i = 0; i < results.size(); ++i) {
    const ResectionResult& r = results[i];
    if (!r.success) continue;
    FrameRecord frame;
    frame.raster = job.inputs[i].raster;
    frame.camera_id = job.input_cameras[i]->camera_id;
    frame.srs = job.input_cameras[i]->srs;
    frame.eo = r.eo;
    frame.covariance = r.covariance;
    frame.sigma0 = r.sigma0;
    frame.extra_columns = {{"NumObservations", std::to_string(r.inliers.size())},
                           {"NumInliers", std::to_string(r.num_inliers)}};
    frames.push_back(std::move(frame));
  }
  FramesTableOptions frames_options;
  frames_options.convention = options.rotation;
  frames_options.cameras = &job.cameras;
  return WriteFramesTable(path, frames_options, frames);
}

Status WriteResectionReport(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results) {
  using nlohmann::json;
  const ResectionOptions& o = options.resection;
  json report;
  report["options"] = {{"solver", PoseSolverName(o.solver)},
                       {"jacobian", JacobianTypeName(o.jacobian)},
                       {"loss", LossTypeName(o.loss)},
                       {"ceres_minimizer", CeresMinimizerName(o.minimizer)},
                       {"loss_scale_px", o.loss_scale_px},
                       {"ransac_threshold_px", o.ransac_threshold_px},
                       {"ransac_seed", o.ransac.seed},
                       {"rotation", RotationConventionName(options.rotation)},
                       {"default_accuracy_px", options.default_accuracy_px},
                       {"pixel_origin", options.pixel_origin == PixelOrigin::kCorner ? "corner" : "center"}};
  json images = json::array();
  for (size_t i = 0; i < results.size(); ++i) {
    const ResectionResult& r = results[i];
    const ResectionSummary& s = r.summary;
    json image = {{"raster", job.inputs[i].raster},
                  {"camera_id", job.input_cameras[i]->camera_id},
                  {"success", r.success},
                  {"message", s.message},
                  {"termination", s.IsSolutionUsable() ? "converged" : "failure"},
                  {"initial_values", s.used_approximate ? "frames" : "ransac"},
                  {"ransac_trials", s.ransac_trials},
                  {"iterations", s.iterations},
                  {"initial_cost", s.initial_cost},
                  {"final_cost", s.final_cost},
                  {"time_seconds", s.total_seconds}};
    if (r.success) {
      const Eigen::Vector3d angles = AnglesFromRotation(
          options.rotation, RotationFromAngles(RotationConvention::kSeed, r.eo.angles_seed_rad()));
      image["pose"] = {{"X", r.eo.parameters[0]},
                       {"Y", r.eo.parameters[1]},
                       {"Z", r.eo.parameters[2]},
                       {"omega_deg", RadiansToDegrees(angles[0])},
                       {"phi_deg", RadiansToDegrees(angles[1])},
                       {"kappa_deg", RadiansToDegrees(angles[2])},
                       {"convention", RotationConventionName(options.rotation)}};
      image["seed_angles_rad"] = {r.eo.parameters[3], r.eo.parameters[4], r.eo.parameters[5]};
      json covariance = json::array();
      for (int row = 0; row < 6; ++row)
        for (int col = 0; col < 6; ++col) covariance.push_back(r.covariance(row, col));
      image["covariance_seed"] = covariance;  // row-major, X0 Y0 Z0 (m) omega phi kappa (rad, seed)
      image["sigma0"] = r.sigma0;
      image["degrees_of_freedom"] = r.degrees_of_freedom;
      image["num_inliers"] = r.num_inliers;
      json marks = json::array();
      for (size_t k = 0; k < job.input_marks[i].size(); ++k) {
        const ImageMark& mark = job.marks[job.input_marks[i][k]];
        marks.push_back({{"point_id", mark.point_id},
                         {"residual_x_px", r.residuals_px[k].x()},
                         {"residual_y_px", r.residuals_px[k].y()},
                         {"inlier", static_cast<bool>(r.inliers[k])}});
      }
      image["marks"] = marks;
      const std::vector<Eigen::Vector2d> check = CheckPointResidualsPx(job, i, r.eo);
      double ssq = 0.0;
      for (const auto& c : check) ssq += c.squaredNorm();
      image["check_points"] = {{"count", check.size()},
                               {"rmse_px", check.empty() ? 0.0 : std::sqrt(ssq / check.size())}};
    }
    images.push_back(image);
  }
  report["images"] = images;
  return WriteFileAtomically(path, report.dump(2) + "\n");
}

}  // namespace photopose::cli
