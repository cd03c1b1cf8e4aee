#pragma once
// From tables to resection inputs and back: used by `photopose resect` and `photopose compare`.

#include <string>
#include <vector>

#include "core/camera.h"
#include "core/rotation.h"
#include "core/status.h"
#include "core/tables.h"
#include "solvers/resection.h"

namespace photopose::cli {

struct ResectionJobOptions {
  std::string cameras_path;    // camera table (required)
  std::string points_path;     // ground points (or gcp_list_path)
  std::string marks_path;      // image marks (or gcp_list_path)
  std::string gcp_list_path;   // OpenDroneMap gcp_list.txt
  std::string frames_path;     // optional approximate frames
  RotationConvention rotation = RotationConvention::kSeed;  // of the frames tables
  double default_accuracy_px = 1.0;  // marks without Accuracy (pixels, one sigma)
  PixelOrigin pixel_origin = PixelOrigin::kCorner;
  ResectionOptions resection;
};

// Everything read, and the per-image inputs in order of first appearance in the marks.
struct ResectionJob {
  std::vector<FrameCamera> cameras;
  std::vector<GroundPoint> points;
  std::vector<ImageMark> marks;
  std::vector<FrameRecord> approximate_frames;
  std::vector<ResectionInput> inputs;
  std::vector<const FrameCamera*> input_cameras;          // camera of each input
  std::vector<std::vector<size_t>> input_marks;           // control marks of each input (into marks)
  // A check-point mark (index into marks) with its ground point.
  struct CheckMark {
    size_t mark;
    Eigen::Vector3d point_in_ground;
  };
  std::vector<std::vector<CheckMark>> input_check_marks;  // check-point marks of each input
  PixelOrigin pixel_origin = PixelOrigin::kCorner;        // of the marks' Column/Row
  std::string marks_label;                                 // file named in messages
};

Status PrepareResectionJob(const ResectionJobOptions& options, ResectionJob* job);

// Check-point residuals (pixels) of one solved image: observed minus projected check marks.
std::vector<Eigen::Vector2d> CheckPointResidualsPx(const ResectionJob& job, size_t input_index,
                                                   const ExteriorOrientation& eo);

Status WriteResectionFrames(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results);
Status WriteResectionReport(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results);

}  // namespace photopose::cli
