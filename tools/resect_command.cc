// photopose resect: space resection of every image that has marks.
#include <gflags/gflags.h>

#include <cstdio>
#include <iostream>

#include "core/camera.h"
#include "core/output_files.h"
#include "core/rotation.h"
#include "solvers/resection.h"
#include "tools/cli_common.h"
#include "tools/commands.h"
#include "tools/resection_job.h"

DEFINE_string(cameras, "", "Camera table (CSV, ArcGIS frame-camera schema): the interior orientation of every CameraID.");
DEFINE_string(points, "", "Ground points (CSV: PointID, X, Y, Z in metres, optional AccuracyX/Y/Z and Role control|check).");
DEFINE_string(marks, "", "Image marks (CSV: Raster, PointID, Column and Row in pixels or FilmX and FilmY in micrometres, optional Accuracy in pixels and CameraID).");
DEFINE_string(gcp_list, "", "OpenDroneMap gcp_list.txt to use instead of --points and --marks (first line a CRS, then 'X Y Z px py image [name]').");
DEFINE_string(frames, "", "Optional frames table with approximate exterior orientations; when an image has one, it replaces the automatic initial values (RANSAC).");
DEFINE_string(out, "", "Output frames table (CSV) with the solved exterior orientations, their standard deviations, Sigma0, NumObservations and NumInliers.");
DEFINE_string(report, "", "Optional JSON report: the options used and, per image, the pose, covariance, residual and inlier flag of every mark, RANSAC trials, iterations, termination and time.");
DEFINE_string(rotation, "seed", "Angle convention of the frames tables read and written: seed, opk or pok (see docs/conventions.md).");
DEFINE_string(solver, "ceres", "Pose solver: ceres (Levenberg-Marquardt with a robust loss), taylor (the seed's Taylor linearisation with corrected partials) or taylor_as_printed (with the partials as printed in the seed).");
DEFINE_string(jacobian, "analytic", "Derivative path of the Ceres cost: analytic (closed-form partials) or autodiff (Ceres Jets).");
DEFINE_string(loss, "huber", "Robust loss of the Ceres solver: none, huber, softl1, cauchy, arctan or tukey.");
DEFINE_string(ceres_minimizer, "tiny_solver", "How Ceres minimises each image: tiny_solver (ceres::TinySolver with iteratively reweighted robust loss, fast for one image) or problem (ceres::Problem and ceres::Solve).");
DEFINE_double(loss_scale, 2.0, "Scale of the robust loss in pixels: residuals beyond it are down-weighted.");
DEFINE_double(ransac_threshold, 6.0, "Inlier threshold in pixels for RANSAC and for the final inlier flags.");
DEFINE_double(default_accuracy, 1.0, "Accuracy in pixels (one sigma) of marks that have no Accuracy column value.");
DEFINE_uint64(seed, 0, "Seed of the random generator of RANSAC; the same seed gives the same result.");
DEFINE_int32(threads, 0, "Number of images resected in parallel; 0 uses all cores.");
DEFINE_bool(pixel_center_origin, false, "Read Column/Row with (0,0) at the centre of the first pixel instead of the top-left corner of the image.");

namespace photopose::cli {
namespace {

constexpr char kUsage[] =
    "photopose resect: space resection of every image that has marks.\n\n"
    "Usage: photopose resect --cameras=C.csv --points=P.csv --marks=M.csv --out=frames.csv\n"
    "                        [--frames=approx.csv] [--report=report.json] [--rotation=seed|opk|pok]\n"
    "                        [--solver=ceres|taylor|taylor_as_printed] [--jacobian=analytic|autodiff]\n"
    "                        [--loss=huber ...] [--loss_scale=px] [--ransac_threshold=px] [--threads=N]\n"
    "   or: photopose resect --cameras=C.csv --gcp_list=gcp_list.txt --out=frames.csv ...\n\n"
    "Without --frames the initial values come from LO-RANSAC over P3P and the DLT; then Ceres (or the\n"
    "Taylor linearisation) refines every pose. Exit status: 0 every image resected, 1 some image\n"
    "could not be (each says why), 2 bad input or usage.\n";

// Every numeric flag's range (docs/formats.md, "Limits and refusals").
const CommandFlags& ResectFlags() {
  static const CommandFlags* const kFlags =
      new CommandFlags{"resect",
                       "resect_command",
                       "",
                       {},
                       {{"loss_scale", 0.0, 1000.0, true, false, "px"},
                        {"ransac_threshold", 0.0, 1000.0, true, false, "px"},
                        {"default_accuracy", 0.0, 1000.0, true, false, "px"},
                        {"seed", 0.0, 18446744073709551615.0},
                        {"threads", 0.0, 1024.0}}};
  return *kFlags;
}

}  // namespace

int RunResect(int argc, char** argv) {
  ParsedFlags parsed;
  if (!ParseFlags(argc, argv, ResectFlags(), &parsed)) return kExitBadInput;
  if (parsed.help) {
    PrintHelp(kUsage, ResectFlags());
    return kExitSuccess;
  }
  ResectionJobOptions job;
  job.cameras_path = FLAGS_cameras;
  job.points_path = FLAGS_points;
  job.marks_path = FLAGS_marks;
  job.gcp_list_path = FLAGS_gcp_list;
  job.frames_path = FLAGS_frames;
  job.default_accuracy_px = FLAGS_default_accuracy;
  job.pixel_origin = FLAGS_pixel_center_origin ? PixelOrigin::kCenter : PixelOrigin::kCorner;
  if (FLAGS_cameras.empty()) return BadInput("resect", "--cameras is required");
  if (FLAGS_gcp_list.empty() && (FLAGS_points.empty() || FLAGS_marks.empty()))
    return BadInput("resect", "--points and --marks (or --gcp_list) are required");
  if (!FLAGS_gcp_list.empty() && (!FLAGS_points.empty() || !FLAGS_marks.empty()))
    return BadInput("resect", "--gcp_list replaces --points and --marks; give one or the other");
  if (FLAGS_out.empty()) return BadInput("resect", "--out is required");
  const auto rotation = ParseRotationConvention(FLAGS_rotation);
  if (!rotation) return BadInput("resect", "--rotation must be seed, opk or pok, not '" + FLAGS_rotation + "'");
  job.rotation = *rotation;
  const auto solver = ParsePoseSolver(FLAGS_solver);
  if (!solver) return BadInput("resect", "--solver must be ceres, taylor or taylor_as_printed, not '" + FLAGS_solver + "'");
  const auto jacobian = ParseJacobianType(FLAGS_jacobian);
  if (!jacobian) return BadInput("resect", "--jacobian must be analytic or autodiff, not '" + FLAGS_jacobian + "'");
  const auto loss = ParseLossType(FLAGS_loss);
  if (!loss) return BadInput("resect", "--loss must be none, huber, softl1, cauchy, arctan or tukey, not '" + FLAGS_loss + "'");
  const auto minimizer = ParseCeresMinimizer(FLAGS_ceres_minimizer);
  if (!minimizer) return BadInput("resect", "--ceres_minimizer must be tiny_solver or problem, not '" + FLAGS_ceres_minimizer + "'");
  if (!(FLAGS_default_accuracy > 0.0)) return BadInput("resect", "--default_accuracy must be positive");
  if (FLAGS_threads < 0) return BadInput("resect", "--threads must be >= 0");

  ResectionOptions& options = job.resection;
  options.solver = *solver;
  options.jacobian = *jacobian;
  options.loss = *loss;
  options.minimizer = *minimizer;
  options.loss_scale_px = FLAGS_loss_scale;
  options.ransac_threshold_px = FLAGS_ransac_threshold;
  options.ransac.seed = FLAGS_seed;
  std::string why;
  if (!options.IsValid(&why)) return BadInput("resect", why);

  // Outputs: checked before any work (never an input, never each other), written all or nothing.
  OutputFiles outputs;
  for (const auto& [label, path] :
       {std::pair<const char*, const std::string&>{"--cameras", FLAGS_cameras},
        {"--points", FLAGS_points},
        {"--marks", FLAGS_marks},
        {"--gcp_list", FLAGS_gcp_list},
        {"--frames", FLAGS_frames}}) {
    const Status input = outputs.AddInput(label, path);
    if (!input.ok()) return BadInput("resect", input.message());
  }
  for (const std::string& flag_file : parsed.flag_files) outputs.AddInput("--flagfile", flag_file);
  for (const auto& [label, path] : {std::pair<const char*, const std::string&>{"--out", FLAGS_out},
                                    {"--report", FLAGS_report}}) {
    if (path.empty()) continue;
    const Status declared = outputs.AddOutput(label, path);
    if (!declared.ok()) return BadInput("resect", declared.message());
  }

  // Read and check every input before any output is written.
  ResectionJob prepared;
  const Status read = PrepareResectionJob(job, &prepared);
  if (!read.ok()) return BadInput("resect", read.message());
  if (prepared.inputs.empty()) return BadInput("resect", "no image has marks of control points");

  std::vector<ResectionResult> results;
  {
    const ScopedSolving solving;
    results = ResectImages(options, prepared.inputs, FLAGS_threads);
  }

  int failures = 0;
  for (size_t i = 0; i < results.size(); ++i) {
    const ResectionResult& r = results[i];
    const std::string& raster = prepared.inputs[i].raster;
    if (!r.success) {
      ++failures;
      std::cerr << "photopose resect: " << raster << ": not resected: " << r.summary.message << "\n";
      continue;
    }
    const Eigen::Vector3d angles = AnglesFromRotation(
        job.rotation, RotationFromAngles(RotationConvention::kSeed, r.eo.angles_seed_rad()));
    std::printf("%s: X=%.4f Y=%.4f Z=%.4f m  %s omega=%.6f phi=%.6f kappa=%.6f deg  sigma0=%.3f  "
                "inliers=%d/%zu  %s\n",
                raster.c_str(), r.eo.parameters[0], r.eo.parameters[1], r.eo.parameters[2],
                RotationConventionName(job.rotation), RadiansToDegrees(angles[0]),
                RadiansToDegrees(angles[1]), RadiansToDegrees(angles[2]), r.sigma0, r.num_inliers,
                r.inliers.size(), r.summary.used_approximate ? "(from --frames)" : "(RANSAC)");
  }

  Status written = outputs.StageWith(FLAGS_out, [&](const std::string& path) {
    return WriteResectionFrames(path, job, prepared, results);
  });
  if (written.ok() && !FLAGS_report.empty()) {
    written = outputs.StageWith(FLAGS_report, [&](const std::string& path) {
      return WriteResectionReport(path, job, prepared, results);
    });
  }
  if (written.ok()) written = outputs.Commit();
  if (!written.ok()) return BadInput("resect", written.message());
  return failures == 0 ? kExitSuccess : kExitSomeFailed;
}

}  // namespace photopose::cli
