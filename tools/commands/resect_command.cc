// photopose resect: space resection of every image that has marks.
#include <gflags/gflags.h>

#include <cstdio>
#include <iostream>
#include <optional>

#include "core/io/block_tables.h"
#include "core/camera.h"
#include "core/io/output_files.h"
#include "core/rotation.h"
#include "solvers/resection/resection.h"
#include "tools/commands/cli_common.h"
#include "tools/commands/commands.h"
#include "tools/jobs/resection_job.h"
#include "tools/report/resection_report.h"

DEFINE_string(cameras, "", "Camera table (CSV, ArcGIS frame-camera schema): the interior orientation of every CameraID.");
DEFINE_string(points, "", "Ground points (CSV: PointID, X, Y, Z in metres, optional AccuracyX/Y/Z (0 allowed: control points are fixed in a resection anyway) and Role control|check|tie); a point that has marks but no row is a tie point and is left out.");
DEFINE_string(marks, "", "Image marks (CSV: Raster, PointID, Column and Row in pixels or FilmX and FilmY in micrometres, optional Accuracy in the mark's own unit and CameraID).");
DEFINE_string(gcp_list, "", "OpenDroneMap gcp_list.txt to use instead of --points and --marks (first line a CRS, then 'X Y Z px py image [name]'); its CRS goes to the SRS column of the output.");
DEFINE_string(frames, "", "Optional frames table with approximate exterior orientations; when an image has one, it replaces the automatic initial values (the consensus of minimal samples).");
DEFINE_string(fiducials, "", "Optional measured fiducials of scanned film (CSV: Raster, FiducialID, Column, Row in pixels): each image's pixel-to-film affine is fitted to the camera table's FilmFiducials.");
DEFINE_double(max_fiducial_residual, 30.0, "Largest accepted residual of a measured fiducial after the affine fit, in micrometres; a larger one is refused as a misnumbered or mismeasured fiducial.");
DEFINE_string(out, "", "Output frames table (CSV) with the solved exterior orientations, their standard deviations, Sigma0, NumObservations and NumInliers.");
DEFINE_string(report, "", "Optional JSON report: the options used and, per image, the pose, covariance, the residual, normalized residual, redundancy number and status of every mark, the residual of every check point, warnings, termination and time.");
DEFINE_string(rotation, "rxryrz", "Angle convention of the frames tables read and written and of every angle printed: rxryrz (R = Rx(omega) Ry(phi) Rz(kappa) maps ground to camera; 'seed' is an alias), opk or pok (see docs/conventions.md).");
DEFINE_string(solver, "ceres", "Pose solver: ceres (Levenberg-Marquardt), taylor (the seed's Taylor linearisation with corrected partials) or taylor_as_printed (with the partials as printed in the seed).");
DEFINE_string(jacobian, "analytic", "Derivative path of the Ceres cost: analytic (closed-form partials) or autodiff (Ceres Jets).");
DEFINE_string(loss, "none", "Loss of the Ceres solver: none (least squares over the accepted marks, the default), huber, softl1, cauchy, arctan or tukey.");
DEFINE_string(ceres_minimizer, "tiny_solver", "How Ceres minimises each image: tiny_solver (ceres::TinySolver with an iteratively reweighted loss, fast for one image) or problem (ceres::Problem and ceres::Solve).");
DEFINE_double(loss_scale, 2.0, "Scale of the robust loss in standard deviations of the marks: residuals beyond it are down-weighted.");
DEFINE_double(confidence, 0.999, "Confidence of the outlier decisions, between 0 and 1: the consensus threshold is the square root of the chi-square(2) quantile at it (3.72 standard deviations at 0.999), and data snooping rejects a mark whose test statistic exceeds the quantile.");
DEFINE_double(default_accuracy, 1.0, "Accuracy (one sigma) of pixel marks (Column/Row) without an Accuracy value, in pixels; every test (global test, data snooping, consensus threshold) and the loss scale use it.");
DEFINE_double(default_film_accuracy, 5.0, "Accuracy (one sigma) of film marks (FilmX/FilmY) without an Accuracy value, in micrometres.");
DEFINE_bool(strict, false, "Refuse weak poses (an undetectable blunder of the minimal detectable size could move them by more than 3 of their standard deviations) instead of reporting them flagged weak.");
DEFINE_bool(allow_no_redundancy, false, "Also report poses whose accepted marks leave no redundancy (three points), without standard deviations and with a warning; otherwise such an image is not solved.");
DEFINE_uint64(seed, 0, "Seed of the random sampling of the consensus when an image has too many marks to try every minimal sample; the same seed gives the same result.");
DEFINE_int32(threads, 0, "Number of images resected in parallel; 0 uses all cores.");
DEFINE_bool(pixel_center_origin, false, "Read Column/Row with (0,0) at the centre of the first pixel instead of the top-left corner of the image.");
DEFINE_bool(pixel_rows_up, false, "Read Row counted up from the bottom edge of the image (Row 0 at the bottom) in the marks, the measured fiducials and the camera table's A0-B2, instead of down from the top edge; needs NRows in the camera table. Not with --gcp_list (OpenDroneMap counts rows down).");

namespace photopose::cli {
namespace {

constexpr char kUsage[] =
    "photopose resect: space resection of every image that has marks.\n\n"
    "Usage: photopose resect --cameras=C.csv --points=P.csv --marks=M.csv --out=frames.csv\n"
    "                        [--frames=approx.csv] [--report=report.json] [--rotation=rxryrz|opk|pok]\n"
    "                        [--fiducials=F.csv] [--default_accuracy=1] [--default_film_accuracy=5]\n"
    "                        [--strict] [--confidence=0.999]\n"
    "                        [--allow_no_redundancy] [--solver=ceres|taylor|taylor_as_printed]\n"
    "                        [--jacobian=analytic|autodiff] [--loss=none ...] [--threads=N]\n"
    "   or: photopose resect --cameras=C.csv --gcp_list=gcp_list.txt --out=frames.csv ...\n\n"
    "Without --frames the initial values come from a consensus of minimal samples (every sample\n"
    "when there are few, LO-RANSAC over P3P and the DLT otherwise); least squares then refines\n"
    "every pose over the marks that fit, and data snooping rejects blunders one at a time. Marks\n"
    "without an Accuracy take --default_accuracy (1 px) or --default_film_accuracy (5 um); an\n"
    "image whose marks fail the global test at that accuracy, or that two poses fit, is not\n"
    "solved; a pose an undetectable blunder could move by more than 3 sigma is flagged weak\n"
    "(refused with --strict). A pose that no redundant mark checks is not reported. Nothing is\n"
    "written when no image is resected. A run longer than 2 s prints a progress line on stderr\n"
    "every 5 s. Ctrl-C (SIGINT) or SIGTERM cancels the run: nothing is written, exit status 130 or\n"
    "143 (docs/cli.md). Exit status: 0 every image resected, 1 some image could not be (each says\n"
    "why), 2 bad input or usage.\n";

// Every numeric flag's range (docs/formats.md, "Limits and refusals").
const CommandFlags& ResectFlags() {
  static const CommandFlags* const kFlags =
      new CommandFlags{"resect",
                       "resect_command",
                       "",
                       {},
                       {{"loss_scale", 0.0, 1000.0, true, false, "standard deviations"},
                        {"confidence", 0.5, 1.0, false, true},
                        {"default_accuracy", 0.0, 1e6, true, false, "px"},
                        {"default_film_accuracy", 0.0, 1e6, true, false, "um"},
                        {"max_fiducial_residual", 0.0, 1e6, true, false, "um"},
                        {"seed", 0.0, 18446744073709551615.0},
                        {"threads", 0.0, 1024.0}}};
  return *kFlags;
}

// "A, B and C" of at most five names, then "and N more".
std::string NameList(const std::vector<std::string>& names) {
  std::string text;
  const size_t shown = std::min<size_t>(names.size(), 5);
  for (size_t k = 0; k < shown; ++k) text += (k == 0 ? "" : ", ") + names[k];
  if (names.size() > shown) text += " and " + std::to_string(names.size() - shown) + " more";
  return text;
}

// The job (tables, input and resection options) from the flags; false (and *why) for a missing or
// invalid one.
bool JobFromFlags(ResectionJobOptions* job, std::string* why) {
  BlockFiles& files = job->files;
  files.cameras = FLAGS_cameras;
  files.points = FLAGS_points;
  files.marks = FLAGS_marks;
  files.gcp_list = FLAGS_gcp_list;
  files.frames = FLAGS_frames;
  files.fiducials = FLAGS_fiducials;
  files.max_fiducial_residual_um = FLAGS_max_fiducial_residual;
  files.pixel_origin = FLAGS_pixel_center_origin ? PixelOrigin::kCenter : PixelOrigin::kCorner;
  files.pixel_rows = FLAGS_pixel_rows_up ? PixelRows::kUp : PixelRows::kDown;
  job->input.default_accuracy = FLAGS_default_accuracy;
  job->input.default_film_accuracy_um = FLAGS_default_film_accuracy;
  if (FLAGS_cameras.empty()) return InvalidBecause(why, "--cameras is required");
  if (FLAGS_gcp_list.empty() && (FLAGS_points.empty() || FLAGS_marks.empty()))
    return InvalidBecause(why, "--points and --marks (or --gcp_list) are required");
  if (!FLAGS_gcp_list.empty() && (!FLAGS_points.empty() || !FLAGS_marks.empty()))
    return InvalidBecause(why, "--gcp_list replaces --points and --marks; give one or the other");
  if (!FLAGS_gcp_list.empty() && FLAGS_pixel_rows_up)
    return InvalidBecause(why,
                          "--pixel_rows_up: a gcp_list.txt counts pixel rows down from the "
                          "top-left corner (OpenDroneMap's definition); it applies to --marks");
  if (FLAGS_out.empty()) return InvalidBecause(why, "--out is required");
  if (!ParseEnum(FLAGS_rotation, &files.rotation))
    return InvalidBecause(why, EnumFlagError<RotationConvention>("--rotation", FLAGS_rotation));
  ResectionOptions& options = job->resection;
  PoseRefinementOptions& refinement = options.refinement;
  if (!ParseEnum(FLAGS_solver, &refinement.solver))
    return InvalidBecause(why, EnumFlagError<PoseSolver>("--solver", FLAGS_solver));
  if (!ParseEnum(FLAGS_jacobian, &refinement.jacobian))
    return InvalidBecause(why, EnumFlagError<JacobianType>("--jacobian", FLAGS_jacobian));
  if (!ParseEnum(FLAGS_loss, &refinement.loss))
    return InvalidBecause(why, EnumFlagError<LossType>("--loss", FLAGS_loss));
  if (!ParseEnum(FLAGS_ceres_minimizer, &refinement.ceres.minimizer))
    return InvalidBecause(
        why, EnumFlagError<CeresMinimizer>("--ceres_minimizer", FLAGS_ceres_minimizer));
  if (!(FLAGS_default_accuracy > 0.0) || !std::isfinite(FLAGS_default_accuracy))
    return InvalidBecause(why, "--default_accuracy must be a positive number of pixels");
  if (!(FLAGS_default_film_accuracy > 0.0) || !std::isfinite(FLAGS_default_film_accuracy))
    return InvalidBecause(why, "--default_film_accuracy must be a positive number of micrometres");
  if (!(FLAGS_max_fiducial_residual > 0.0) || !std::isfinite(FLAGS_max_fiducial_residual))
    return InvalidBecause(why, "--max_fiducial_residual must be a positive number of micrometres");
  if (FLAGS_threads < 0) return InvalidBecause(why, "--threads must be >= 0");
  // What only the Ceres solver uses is refused with the Taylor solvers, never silently ignored.
  if (refinement.solver != PoseSolver::kCeres) {
    for (const char* flag : {"loss", "loss_scale", "jacobian", "ceres_minimizer"}) {
      if (FlagGiven(flag))
        return InvalidBecause(why, "--" + std::string(flag) +
                                       " is for --solver=ceres; --solver=" + FLAGS_solver +
                                       " is the seed's least squares with its own partials");
    }
  }
  refinement.loss_scale = FLAGS_loss_scale;
  options.test.confidence = FLAGS_confidence;
  options.consensus.ransac.seed = FLAGS_seed;
  options.allow_no_redundancy = FLAGS_allow_no_redundancy;
  options.refuse_weak = FLAGS_strict;
  return options.IsValid(why);
}

// Inputs and outputs declared before any work: an output is never an input nor another output.
Status DeclareFiles(const ParsedFlags& parsed, OutputFiles* outputs) {
  for (const auto& [label, path] :
       {std::pair<const char*, const std::string&>{"--cameras", FLAGS_cameras},
        {"--points", FLAGS_points},
        {"--marks", FLAGS_marks},
        {"--gcp_list", FLAGS_gcp_list},
        {"--frames", FLAGS_frames},
        {"--fiducials", FLAGS_fiducials}}) {
    PHOTOPOSE_RETURN_IF_ERROR(outputs->AddInput(label, path));
  }
  for (const std::string& flag_file : parsed.flag_files)
    PHOTOPOSE_RETURN_IF_ERROR(outputs->AddInput("--flagfile", flag_file));
  for (const auto& [label, path] : {std::pair<const char*, const std::string&>{"--out", FLAGS_out},
                                    {"--report", FLAGS_report}}) {
    if (!path.empty()) PHOTOPOSE_RETURN_IF_ERROR(outputs->AddOutput(label, path));
  }
  return Status::Ok();
}

// One line per image: the pose on stdout, or why it was not resected (and its warnings) on
// stderr. Returns the images not resected.
std::vector<std::string> PrintResults(const ResectionJob& prepared, RotationConvention rotation,
                                      const std::vector<ResectionResult>& results) {
  std::vector<std::string> failed;
  for (size_t i = 0; i < results.size(); ++i) {
    const ResectionResult& r = results[i];
    const std::string& raster = prepared.inputs[i].raster;
    if (!r.success) {
      failed.push_back(raster);
      std::cerr << "photopose resect: " << raster << ": not resected: " << r.summary.message;
      if (r.accuracy_disagrees || r.ambiguous)
        std::cerr << "; state the marks' accuracy in their Accuracy column, or with "
                     "--default_accuracy (px) / --default_film_accuracy (um)";
      std::cerr << "\n";
      continue;
    }
    for (const std::string& warning : r.warnings)
      std::cerr << "photopose resect: " << raster << ": warning: " << warning << "\n";
    const Eigen::Vector3d angles = OutputAnglesDeg(prepared, i, rotation, r.eo);
    const std::string unit = Sigma0Unit(prepared, i, r);
    std::printf("%s: X=%.4f Y=%.4f Z=%.4f m  %s omega=%.6f phi=%.6f kappa=%.6f deg  ",
                raster.c_str(), r.eo.parameters[0], r.eo.parameters[1], r.eo.parameters[2],
                EnumName(rotation), angles[0], angles[1], angles[2]);
    if (r.degrees_of_freedom > 0) {
      std::printf("sigma0=%.3f%s%s  ", r.sigma0, unit.empty() ? "" : " ", unit.c_str());
    } else {
      std::printf("sigma0=none (no redundancy)  ");
    }
    std::printf("inliers=%d/%zu  %s%s\n", r.num_inliers, r.inliers.size(),
                r.summary.used_approximate              ? "(from --frames)"
                : r.summary.consensus_after_approximate ? "(consensus, --frames start abandoned)"
                                                        : "(consensus)",
                r.weak ? "  WEAK" : "");
  }
  return failed;
}

}  // namespace

int RunResect(int argc, char** argv) {
  ParsedFlags parsed;
  if (const std::optional<int> done = StartCommand(argc, argv, kUsage, ResectFlags(), &parsed)) return *done;
  CancelOnSignals();
  ResectionJobOptions job;
  std::string why;
  if (!JobFromFlags(&job, &why)) return BadInput("resect", why);
  OutputFiles outputs;
  const Status declared = DeclareFiles(parsed, &outputs);
  if (!declared.ok()) return BadInput("resect", declared.message());

  // Read and check every input before any output is written.
  ResectionJob prepared;
  const Status read = PrepareResectionJob(job, &prepared);
  if (!read.ok()) return BadInput("resect", read.message());
  if (prepared.inputs.empty()) return BadInput("resect", "no image has marks");
  if (CancelRequested()) return ReportCancelled("resect", "while reading the inputs");
  // A progress line on stderr when the batch runs longer than a couple of seconds.
  ProgressLine progress_line("resect", "images");
  ResectionBatchOptions batch;
  batch.num_threads = FLAGS_threads;
  // SIGINT / SIGTERM stop the batch at the hook's next call: no image is started after it.
  batch.progress = [&progress_line](const ResectionProgress& progress) {
    progress_line(progress.images_done, progress.images_total);
    return !CancelRequested();
  };
  std::vector<ResectionResult> results;
  {
    const ScopedSolving solving;
    const Status resected = ResectImages(job.resection, prepared.inputs, batch, &results);
    if (CancelRequested()) return ReportCancelled("resect", "while resecting");
    if (!resected.ok()) return BadInput("resect", resected.message());
  }
  const std::vector<std::string> failed = PrintResults(prepared, job.files.rotation, results);
  // Nothing solved: nothing written (an older output stays), exit 1 with the reason.
  if (failed.size() == results.size()) {
    std::cerr << "photopose resect: no image was resected (" << NameList(failed)
              << "); nothing written\n";
    return kExitSomeFailed;
  }

  std::vector<std::string> written = {FLAGS_out};
  if (!FLAGS_report.empty()) written.push_back(FLAGS_report);
  Status status = outputs.StageWith(FLAGS_out, [&](const std::string& path) {
    return WriteResectionFrames(path, job, prepared, results);
  });
  if (status.ok() && !FLAGS_report.empty()) {
    status = outputs.StageWith(FLAGS_report, [&](const std::string& path) {
      return WriteResectionReport(path, job, prepared, results, written);
    });
  }
  if (status.ok()) status = CommitUnlessCancelled(&outputs);
  if (CancelRequested() && !status.ok()) return ReportCancelled("resect", "before writing");
  if (!status.ok()) return BadInput("resect", status.message());
  std::string summary = "photopose resect: " + std::to_string(results.size() - failed.size()) +
                        " of " + std::to_string(results.size()) + " images resected";
  if (!failed.empty()) summary += ", not resected: " + NameList(failed);
  if (prepared.num_tie_marks > 0)
    summary += "; " + std::to_string(prepared.num_tie_marks) + " marks of tie points left out";
  std::string files_written;
  for (const std::string& path : written) files_written += (files_written.empty() ? "" : ", ") + path;
  std::cerr << summary << "; wrote " << files_written << "\n";
  return failed.empty() ? kExitSuccess : kExitSomeFailed;
}

}  // namespace photopose::cli
