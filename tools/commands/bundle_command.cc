// photopose bundle: the weighted bundle adjustment of a block (solvers/bundle/bundle_adjustment.h).
#include <gflags/gflags.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "core/io/bal.h"
#include "core/block.h"
#include "core/io/block_tables.h"
#include "core/io/colmap.h"
#include "core/io/csv.h"
#include "core/io/output_files.h"
#include "core/io/tables.h"
#include "solvers/bundle/block_initialization.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/taylor_bundle.h"
#include "tools/report/bundle_report.h"
#include "tools/commands/cli_common.h"
#include "tools/commands/commands.h"

DEFINE_string(bundle_cameras, "", "Camera table (CSV, ArcGIS frame-camera schema): the interior orientation of every CameraID.");
DEFINE_string(bundle_marks, "", "Image marks (CSV: Raster, PointID, Column and Row in pixels or FilmX and FilmY in micrometres, optional Accuracy in the mark's own unit and CameraID). A point with marks but no row in --points is a tie point.");
DEFINE_string(bundle_points, "", "Ground points (CSV: PointID, X, Y, Z in metres, optional AccuracyX/Y/Z in metres and Role control|check|tie). Optional for a block held by camera positions.");
DEFINE_string(bundle_frames, "", "Frames table: PerspectiveX/Y/Z are the measured camera positions (priors with --camera_accuracy or per-row AccuracyX/Y/Z, otherwise initial values only) and Omega/Phi/Kappa initial values (priors with --attitude_accuracy or per-row AccuracyOmega/Phi/Kappa). Images without a row are oriented by resection.");
DEFINE_string(bundle_colmap_model, "", "A COLMAP text model folder (cameras.txt, images.txt, points3D.txt) to adjust instead of the tables.");
DEFINE_string(bundle_bal, "", "A BAL problem file to adjust instead of the tables.");
DEFINE_string(bundle_out, "", "Output frames table (CSV) of the adjusted images with SigmaX..SigmaKappa, Sigma0, NumObservations and RmsResidual.");
DEFINE_string(bundle_out_points, "", "Output points table (CSV): PointID, X, Y, Z, SigmaX/Y/Z, Role, NumObservations, ErrorX/Y/Z.");
DEFINE_string(bundle_out_cameras, "", "Output camera table (CSV) with the calibrated interior orientation (frame cameras).");
DEFINE_string(bundle_out_colmap, "", "Output COLMAP text model folder of the adjusted block.");
DEFINE_string(bundle_report, "", "JSON report: summary, groups with their over-fitting verdict, control and check points, images, calibration, diagnostics, options (docs/formats.md).");
DEFINE_string(bundle_html, "", "Self-contained HTML page of the adjustment: verdicts, plan view, residual histograms, tables.");
DEFINE_string(bundle_rotation, "rxryrz", "Angle convention of the frames tables read and written: rxryrz (R = Rx(omega) Ry(phi) Rz(kappa) maps ground to camera; 'seed' is an alias), opk or pok (see docs/conventions.md).");
DEFINE_string(bundle_solver, "ceres", "Block solver: ceres (Levenberg-Marquardt on the cost functions), taylor (the seed's Taylor linearisation, hand-written Gauss-Newton) or taylor_as_printed (with the partial derivatives as printed in the seed).");
DEFINE_double(bundle_tie_accuracy, 1.0, "Accuracy (one sigma) of tie marks without an Accuracy value, in pixels.");
DEFINE_double(bundle_marker_projection_accuracy, 0.5, "Accuracy (one sigma) of control and check marks without an Accuracy value, in pixels.");
DEFINE_double(bundle_film_tie_accuracy, 5.0, "Accuracy of tie marks in film coordinates without an Accuracy value when the camera has no pixel size, in micrometres.");
DEFINE_double(bundle_film_marker_projection_accuracy, 2.5, "Accuracy of control marks in film coordinates without an Accuracy value when the camera has no pixel size, in micrometres.");
DEFINE_double(bundle_marker_accuracy, 0.005, "Accuracy (one sigma, per axis) of control point coordinates without AccuracyX/Y/Z, in metres.");
DEFINE_string(bundle_camera_accuracy, "", "Accuracy of the measured camera positions without per-row AccuracyX/Y/Z, in metres: one value or X,Y,Z. Empty: 10 m (Metashape's default) when --frames is given.");
DEFINE_double(bundle_attitude_accuracy, 0.0, "Accuracy of the measured attitudes without per-row accuracies, in degrees per angle; 0: no attitude prior.");
DEFINE_string(bundle_lever_arm, "", "GNSS antenna offset from the projection centre in the camera frame (x right, y up, z towards the viewer), in metres: X,Y,Z.");
DEFINE_bool(bundle_estimate_lever_arm, false, "Estimate the lever arm (starting from --lever_arm or zero).");
DEFINE_string(bundle_calibrate, "", "Self-calibration: a comma list of FocalLength, PrincipalX, PrincipalY, K0, K1, K2, K3, P1, P2, Affinity, Skew (for COLMAP models: f, cx, cy, k1, k2, p1, p2); the rest held constant.");
DEFINE_string(bundle_loss, "none", "Robust loss on tie marks: none, huber, cauchy or softl1.");
DEFINE_double(bundle_loss_scale, 3.0, "Scale of the robust loss on tie marks, in pixels.");
DEFINE_string(bundle_jacobian, "analytic", "Derivative path of the collinearity cost: analytic or autodiff.");
DEFINE_string(bundle_linear_solver, "sparse_schur", "Linear solver: sparse_schur (SuiteSparse), dense_schur, iterative_schur_jacobi or iterative_schur_cluster_jacobi.");
DEFINE_int32(bundle_max_iterations, 100, "Largest number of Levenberg-Marquardt iterations per adjustment round.");
DEFINE_double(bundle_rejection_threshold, 4.5, "Marks whose normalized residual exceeds this are rejected and the block adjusted again; 0 keeps every mark.");
DEFINE_int32(bundle_max_rejection_rounds, 3, "Largest number of rejection rounds.");
DEFINE_bool(bundle_estimate_accuracies, false, "Estimate every group's accuracy from the data (variance component estimation) and adjust with the estimates.");
DEFINE_bool(bundle_snoop, false, "Data snooping: remove the most significant rejected observation (marks, control points, camera positions), adjust again, repeat.");
DEFINE_double(bundle_alpha, 0.001, "Significance level of the w-test per observation (two-sided).");
DEFINE_bool(bundle_cross_validate, false, "Leave each control point out in turn and report its error as a check point.");
DEFINE_string(bundle_statistics, "full", "Posterior covariances, redundancy numbers, reliability and the verdicts that need them: full (at every block size, by selected inversion of the reduced camera system's sparse factor), none (group RMS and check points only), or dense (the dense inverse, for comparison; n^2 memory in the reduced parameters).");
DEFINE_string(bundle_relative_gauge, "free", "Relative blocks (no control points, no camera positions): free solves without a gauge and then moves the result into COLMAP's gauge (the first image as given, one coordinate of the second), the same minimum in far fewer iterations; fixed holds COLMAP's gauge from the start.");
DEFINE_int32(bundle_threads, 0, "Threads of the linear algebra and of the cross-validation; 0 uses all cores.");
DEFINE_bool(bundle_quiet, false, "No progress lines on stderr.");
DEFINE_bool(bundle_pixel_center_origin, false, "Read Column/Row with (0,0) at the centre of the first pixel instead of the top-left corner of the image.");

namespace photopose::cli {
namespace {

constexpr char kUsage[] =
    "photopose bundle: the weighted bundle adjustment of a block of images.\n\n"
    "Usage: photopose bundle --cameras=C.csv --marks=M.csv [--points=P.csv] [--frames=F.csv]\n"
    "                        --out=frames.csv [--out_points=P.csv] [--out_cameras=C.csv]\n"
    "                        [--report=report.json] [--html=report.html] [--rotation=rxryrz|opk|pok]\n"
    "                        [--tie_accuracy=PX] [--marker_accuracy=M] [--marker_projection_accuracy=PX]\n"
    "                        [--camera_accuracy=M or X,Y,Z] [--attitude_accuracy=DEG]\n"
    "                        [--lever_arm=X,Y,Z] [--calibrate=LIST] [--estimate_accuracies]\n"
    "                        [--snoop] [--cross_validate] [--threads=N] [--quiet]\n"
    "   or: photopose bundle --colmap_model=DIR [--out_colmap=DIR] [--calibrate=LIST] ...\n"
    "   or: photopose bundle --bal=problem.txt ...\n\n"
    "Minimises reprojection errors^2 / tie accuracy^2 + control residuals^2 / marker accuracy^2 +\n"
    "camera position residuals^2 / camera accuracy^2 (Metashape's reference settings) and reports,\n"
    "per group, whether the block bends to its priors (over-fitting). Images without initial values\n"
    "are oriented by resection and the tie points triangulated first. Exit status: 0 converged,\n"
    "1 not converged or some image could not be oriented (each named), 2 bad input or usage.\n";

const CommandFlags& BundleFlags() {
  static const CommandFlags* const kFlags = new CommandFlags{
      "bundle",
      "bundle_command",
      "bundle_",
      {},
      {{"tie_accuracy", 0.0, 1000.0, true, false, "px"},
       {"marker_projection_accuracy", 0.0, 1000.0, true, false, "px"},
       {"film_tie_accuracy", 0.0, 1e5, true, false, "um"},
       {"film_marker_projection_accuracy", 0.0, 1e5, true, false, "um"},
       {"marker_accuracy", 0.0, 1e6, true, false, "m"},
       {"attitude_accuracy", 0.0, 180.0, false, false, "degrees"},
       {"loss_scale", 0.0, 1000.0, true, false, "px"},
       {"max_iterations", 1.0, 100000.0},
       {"rejection_threshold", 0.0, 1000.0},
       {"max_rejection_rounds", 0.0, 100.0},
       {"alpha", 0.0, 0.5, true, true},
       {"threads", 0.0, 1024.0}}};
  return *kFlags;
}

// "a" or "a,b,c" -> three finite numbers.
bool ParseTriple(const std::string& text, bool allow_one, Eigen::Vector3d* value) {
  std::vector<double> numbers;
  for (const std::string& item : SplitCommaList(text)) {
    double number;
    std::string why;
    if (!ParseFiniteNumber(item, &number, &why)) return false;
    numbers.push_back(number);
  }
  if (numbers.size() == 3) {
    *value = Eigen::Vector3d(numbers[0], numbers[1], numbers[2]);
    return true;
  }
  if (allow_one && numbers.size() == 1) {
    *value = Eigen::Vector3d::Constant(numbers[0]);
    return true;
  }
  return false;
}

// What RunBundle's steps hand on to each other.
struct BundleRun {
  bool tables = false;  // the input is the tables (not --colmap_model or --bal)
  BundleAdjustmentOptions options;
  // The lever arm from the flags; the calibrated parameters once the block is read.
  BundleAdjustmentConfig config;
  std::vector<std::string> calibrate;  // --calibrate names
  PoseSolver solver = PoseSolver::kCeres;
  BundleReportContext context;
  std::vector<std::pair<std::string, std::string>> written;  // (label, path) of the outputs
  Block block;
  ColmapModelExtras colmap_extras;
  BundleAdjustmentResult result;
  BundleCrossValidationResult cross_validation;
  int exit_code = kExitSuccess;  // kExitSomeFailed once an image could not be oriented
};

// A step's "go on" (any other value is the exit status to return).
constexpr int kGoOn = -1;

// Which input, and the outputs that fit it.
int CheckInputChoice(const char* command, BundleRun* run) {
  const int sources = (!FLAGS_bundle_colmap_model.empty()) + (!FLAGS_bundle_bal.empty()) +
                      (!FLAGS_bundle_marks.empty() || !FLAGS_bundle_cameras.empty());
  if (sources != 1)
    return BadInput(command, "give the tables (--cameras and --marks), --colmap_model or --bal: one of them");
  run->tables = FLAGS_bundle_colmap_model.empty() && FLAGS_bundle_bal.empty();
  if (run->tables && (FLAGS_bundle_cameras.empty() || FLAGS_bundle_marks.empty()))
    return BadInput(command, "--cameras and --marks are both required with the tables");
  if (FLAGS_bundle_out.empty() && FLAGS_bundle_out_colmap.empty() && FLAGS_bundle_report.empty())
    return BadInput(command, "nothing to write: give --out, --out_colmap or --report");
  if (!FLAGS_bundle_out_cameras.empty() && !run->tables)
    return BadInput(command, "--out_cameras writes a camera table of frame cameras; with --colmap_model or --bal use --out_colmap");
  // The tables' other inputs: a COLMAP model or a BAL problem holds its own points and poses.
  if (!run->tables) {
    const std::string source = !FLAGS_bundle_colmap_model.empty() ? "--colmap_model" : "--bal";
    for (const auto& [flag, path] : {std::pair<const char*, const std::string&>{"--points", FLAGS_bundle_points},
                                     {"--frames", FLAGS_bundle_frames}}) {
      if (!path.empty())
        return BadInput(command, std::string(flag) + " is read with the tables (--cameras and --marks) only; " + source + " holds its own points and poses: leave " + flag + " out");
    }
  }
  if (!FLAGS_bundle_bal.empty() && !FLAGS_bundle_out_colmap.empty())
    return BadInput(command, "--out_colmap: a BAL problem has no image size and counts pixels from the image centre, which a COLMAP model cannot hold; write --out, --out_points or --report");
  run->context.input_kind = run->tables ? "tables" : !FLAGS_bundle_colmap_model.empty() ? "colmap" : "bal";
  if (!ParseEnum(FLAGS_bundle_rotation, &run->context.rotation))
    return BadInput(command, EnumFlagError<RotationConvention>("--rotation", FLAGS_bundle_rotation));
  return kGoOn;
}

// The progress line of every iteration, on stderr.
void PrintProgress(const BundleIterationInfo& info) {
  std::string lm;
  if (std::isfinite(info.trust_region_radius)) {
    char buffer[128];
    std::snprintf(buffer, sizeof(buffer), "  %s quality %.2f radius %.2g  solve %.2f of %.2f s",
                  info.step_successful ? "taken" : "REJECTED", info.step_quality,
                  info.trust_region_radius, info.linear_solver_seconds,
                  info.iteration_seconds);
    lm = buffer;
  }
  std::fprintf(stderr,
               "photopose bundle: round %d%s iteration %3d: cost %.6g  sigma0 %.4f  step %.3g%s  "
               "%.1f s\n",
               info.round, info.free_gauge ? " (free gauge)" : "", info.iteration, info.cost,
               info.sigma0, info.step_norm, lm.c_str(),
               info.elapsed_seconds);
}

// The flags -> the options (accuracies, robustness, statistics, solver), the lever arm of the
// config, the --calibrate names and the block solver.
int OptionsFromFlags(const char* command, BundleRun* run) {
  BundleAdjustmentOptions& options = run->options;
  BundleAccuracies& acc = options.accuracies;
  acc.tie_px = FLAGS_bundle_tie_accuracy;
  acc.marker_projection_px = FLAGS_bundle_marker_projection_accuracy;
  acc.tie_film_um = FLAGS_bundle_film_tie_accuracy;
  acc.marker_projection_film_um = FLAGS_bundle_film_marker_projection_accuracy;
  acc.marker_m = FLAGS_bundle_marker_accuracy;
  if (!FLAGS_bundle_camera_accuracy.empty()) {
    if (!ParseTriple(FLAGS_bundle_camera_accuracy, true, &acc.camera_m) || !(acc.camera_m.minCoeff() > 0.0))
      return BadInput(command, "--camera_accuracy must be one positive number or three (X,Y,Z) in metres, not '" + FLAGS_bundle_camera_accuracy + "'");
  }
  if (FLAGS_bundle_attitude_accuracy > 0.0) acc.attitude_deg = FLAGS_bundle_attitude_accuracy;
  if (!FLAGS_bundle_lever_arm.empty()) {
    Eigen::Vector3d lever;
    if (!ParseTriple(FLAGS_bundle_lever_arm, false, &lever) || lever.cwiseAbs().maxCoeff() > 100.0)
      return BadInput(command, "--lever_arm must be three numbers X,Y,Z in metres (at most 100 m each), not '" + FLAGS_bundle_lever_arm + "'");
    run->config.lever_arm_m = lever;
  }
  run->config.estimate_lever_arm = FLAGS_bundle_estimate_lever_arm;
  BundleSolverOptions& solver = options.solver;
  if (!ParseEnum(FLAGS_bundle_jacobian, &solver.jacobian))
    return BadInput(command, EnumFlagError<JacobianType>("--jacobian", FLAGS_bundle_jacobian));
  if (!ParseEnum(FLAGS_bundle_linear_solver, &solver.linear_solver))
    return BadInput(command, EnumFlagError<BundleLinearSolver>("--linear_solver", FLAGS_bundle_linear_solver));
  BundleRobustnessOptions& robustness = options.robustness;
  if (!ParseEnum(FLAGS_bundle_loss, &robustness.tie_loss) || !IsBundleTieLoss(robustness.tie_loss))
    return BadInput(command, "--loss must be " + EnumNameList(kBundleTieLosses) + ", not '" + FLAGS_bundle_loss + "'");
  robustness.tie_loss_scale_sigmas = FLAGS_bundle_loss_scale / FLAGS_bundle_tie_accuracy;
  solver.max_iterations = FLAGS_bundle_max_iterations;
  robustness.rejection_threshold = FLAGS_bundle_rejection_threshold;
  robustness.max_rejection_rounds = FLAGS_bundle_max_rejection_rounds;
  options.statistics.estimate_accuracies = FLAGS_bundle_estimate_accuracies;
  robustness.snoop = FLAGS_bundle_snoop;
  options.statistics.snooping_alpha = FLAGS_bundle_alpha;
  if (!ParseEnum(FLAGS_bundle_statistics, &options.statistics.covariances))
    return BadInput(command, EnumFlagError<BundleCovarianceMethod>("--statistics", FLAGS_bundle_statistics));
  solver.num_threads = FLAGS_bundle_threads;
  if (FLAGS_bundle_relative_gauge != "free" && FLAGS_bundle_relative_gauge != "fixed")
    return BadInput(command, "--relative_gauge must be free or fixed, not '" + FLAGS_bundle_relative_gauge + "'");
  solver.free_gauge_for_relative_blocks = FLAGS_bundle_relative_gauge == "free";
  if (!FLAGS_bundle_quiet) solver.progress = PrintProgress;
  std::string why;
  if (!options.IsValid(&why)) return BadInput(command, why);
  for (const std::string& name : SplitCommaList(FLAGS_bundle_calibrate))
    if (!name.empty()) run->calibrate.push_back(name);
  run->context.calibrate = run->calibrate;
  if (!ParseEnum(FLAGS_bundle_solver, &run->solver))
    return BadInput(command, EnumFlagError<PoseSolver>("--solver", FLAGS_bundle_solver));
  if (run->solver != PoseSolver::kCeres && (robustness.snoop || options.statistics.estimate_accuracies || FLAGS_bundle_cross_validate))
    return BadInput(command, "--solver=" + FLAGS_bundle_solver + " adjusts without snooping, accuracy estimation or cross-validation; use --solver=ceres for those");
  return kGoOn;
}

// Outputs: checked before any work (never an input, never each other), written all or nothing.
int DeclareFiles(const char* command, const ParsedFlags& parsed, BundleRun* run,
                 OutputFiles* outputs) {
  if (!FLAGS_bundle_out_colmap.empty()) {
    // The model's folder is created when missing (an empty folder is all a failed run leaves).
    std::error_code error;
    std::filesystem::create_directories(FLAGS_bundle_out_colmap, error);
    if (error)
      return BadInput(command, "--out_colmap=" + FLAGS_bundle_out_colmap + ": cannot create the folder: " + error.message());
  }
  for (const auto& [label, path] : {std::pair<const char*, const std::string&>{"--cameras", FLAGS_bundle_cameras},
                                    {"--marks", FLAGS_bundle_marks}, {"--points", FLAGS_bundle_points},
                                    {"--frames", FLAGS_bundle_frames}, {"--bal", FLAGS_bundle_bal}}) {
    const Status input = outputs->AddInput(label, path);
    if (!input.ok()) return BadInput(command, input.message());
    if (!path.empty()) run->context.inputs.push_back(path);
  }
  if (!FLAGS_bundle_colmap_model.empty()) {
    for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
      const std::string path = FLAGS_bundle_colmap_model + "/" + name;
      const Status input = outputs->AddInput("--colmap_model", path);
      if (!input.ok()) return BadInput(command, input.message());
      run->context.inputs.push_back(path);
    }
  }
  for (const std::string& flag_file : parsed.flag_files) {
    const Status input = outputs->AddInput("--flagfile", flag_file);
    if (!input.ok()) return BadInput(command, input.message());
  }
  for (const auto& [label, path] : {std::pair<const char*, const std::string&>{"--out", FLAGS_bundle_out},
                                    {"--out_points", FLAGS_bundle_out_points},
                                    {"--out_cameras", FLAGS_bundle_out_cameras},
                                    {"--report", FLAGS_bundle_report}, {"--html", FLAGS_bundle_html}}) {
    if (path.empty()) continue;
    const Status declared = outputs->AddOutput(label, path);
    if (!declared.ok()) return BadInput(command, declared.message());
    run->written.push_back({label, path});
  }
  if (!FLAGS_bundle_out_colmap.empty()) {
    for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
      const std::string path = FLAGS_bundle_out_colmap + "/" + name;
      const Status declared = outputs->AddOutput("--out_colmap", path);
      if (!declared.ok()) return BadInput(command, declared.message());
      run->written.push_back({"--out_colmap", path});
    }
  }
  return kGoOn;
}

// Reads the block (tables, COLMAP model or BAL problem) and the calibrated parameters.
int ReadBundleBlock(const char* command, BundleRun* run) {
  Block& block = run->block;
  if (run->tables) {
    BlockFiles files;
    files.cameras = FLAGS_bundle_cameras;
    files.marks = FLAGS_bundle_marks;
    files.points = FLAGS_bundle_points;
    files.frames = FLAGS_bundle_frames;
    files.rotation = run->context.rotation;
    files.pixel_origin = FLAGS_bundle_pixel_center_origin ? PixelOrigin::kCenter : PixelOrigin::kCorner;
    const Status read = ReadBlock(files, &block);
    if (!read.ok()) return BadInput(command, read.message());
    // Measured centres are priors when an accuracy is known: per row, --camera_accuracy, or the
    // default when a frames table was given.
    run->options.accuracies.camera_positions_are_priors = !FLAGS_bundle_camera_accuracy.empty() || !FLAGS_bundle_frames.empty();
  } else if (!FLAGS_bundle_colmap_model.empty()) {
    const Status read = ReadColmapModel(FLAGS_bundle_colmap_model, &block, &run->colmap_extras);
    if (!read.ok()) return BadInput(command, read.message());
  } else {
    const Status read = ReadBalProblem(FLAGS_bundle_bal, &block);
    if (!read.ok()) return BadInput(command, read.message());
  }
  if (block.images.empty()) return BadInput(command, "the block has no image with marks");
  const Status calibration = BundleAdjustmentConfig::FromCalibrationNames(block, run->calibrate, &run->config);
  if (!calibration.ok()) return BadInput(command, "--calibrate: " + calibration.message());
  return kGoOn;
}

// Initial values where they are missing; images that cannot be oriented leave the block.
int InitializeBundleBlock(const char* command, BundleRun* run) {
  Block& block = run->block;
  BlockInitializationSummary initialization;
  const Status initialized = InitializeBlock(BlockInitializationOptions(), &block, &initialization);
  if (!initialized.ok()) return BadInput(command, initialized.message());
  run->context.num_images_initialized = initialization.images_resected;
  for (const auto& [image, reason] : initialization.not_oriented) {
    std::cerr << "photopose bundle: " << block.images[image].name << ": not oriented: " << reason << "\n";
    run->exit_code = kExitSomeFailed;
  }
  if (!initialization.not_oriented.empty()) {
    std::cerr << "photopose bundle: " << initialization.not_oriented.size()
              << " images could not be oriented; the adjustment goes on without them\n";
    RemoveImages(initialization.not_oriented, &block);
    if (block.images.empty()) {
      std::cerr << "photopose bundle: no image could be oriented: give control points (--points) "
                   "or initial values (--frames); nothing written\n";
      return kExitSomeFailed;
    }
  }
  if (!FLAGS_bundle_quiet) std::cerr << "photopose bundle: initial values: " << initialization.BriefReport() << "\n";
  return kGoOn;
}

// The adjustment, then the cross-validation when asked.
int AdjustBundleBlock(const char* command, BundleRun* run) {
  BundleAdjustmentResult& result = run->result;
  // A model the block cannot be written as is refused now, not after the adjustment.
  if (!FLAGS_bundle_out_colmap.empty()) {
    const Status writable = CheckColmapModelWritable(
        run->block, FLAGS_bundle_colmap_model.empty() ? nullptr : &run->colmap_extras);
    if (!writable.ok()) return BadInput(command, "--out_colmap: " + writable.message());
  }
  const Status adjusted = BundleAdjustWithSolver(run->solver, run->options, run->config, &run->block, &result);
  if (!adjusted.ok()) return BadInput(command, adjusted.message());
  if (run->tables && result.summary.datum == BundleDatum::kRelative) {
    return BadInput(command, "no datum: the block has no control points and no camera positions, so it has no ground coordinates to write; give --points with control points or --frames with camera positions");
  }
  if (result.summary.IsSolutionUsable() && FLAGS_bundle_cross_validate) {
    const Status cv = CrossValidateControlPoints(run->options, run->config, run->block, result, FLAGS_bundle_threads, &run->cross_validation);
    if (!cv.ok()) return BadInput(command, cv.message());
    run->context.cross_validation = &run->cross_validation;
  }
  return kGoOn;
}

// Outputs: the report and the page always (they say why when it failed); tables and models only
// for an adjustment that converged. The ones written are declared again in the transaction that
// writes them (the pre-flight one is dropped unstaged: nothing of it is written).
Status WriteBundleOutputs(const BundleRun& run, bool usable) {
  const Block& block = run.block;
  const BundleAdjustmentResult& result = run.result;
  OutputFiles final_outputs;
  Status status = Status::Ok();
  for (const auto& [label, path] : run.written) {
    if (!usable && label != "--report" && label != "--html") continue;
    if (status.ok()) status = final_outputs.AddOutput(label, path);
  }
  if (!status.ok()) return status;
  auto stage = [&](const std::string& path, const std::string& text) {
    if (status.ok() && !path.empty()) status = final_outputs.Stage(path, text);
  };
  stage(FLAGS_bundle_report, BundleReportJson(block, result, run.context).dump(2) + "\n");
  stage(FLAGS_bundle_html, BundleReportHtml(block, result, run.context));
  if (usable) {
    if (status.ok() && !FLAGS_bundle_out.empty()) {
      status = final_outputs.StageWith(FLAGS_bundle_out, [&](const std::string& path) {
        FramesTableOptions frames_options;
        frames_options.convention = run.context.rotation;
        std::vector<FrameCamera> cameras;
        for (const BlockCamera& camera : block.cameras) cameras.push_back(camera.table);
        frames_options.cameras = &cameras;
        return WriteFramesTable(path, frames_options, BundleFrames(block, result));
      });
    }
    stage(FLAGS_bundle_out_points, BundlePointsCsv(block, result));
    if (status.ok() && !FLAGS_bundle_out_cameras.empty()) {
      std::vector<FrameCamera> cameras;
      for (const BlockCamera& camera : block.cameras) {
        FrameCamera table = camera.table;
        if (status.ok()) status = SetFrameModelParams(camera.params.data(), &table);
        cameras.push_back(table);
      }
      if (status.ok())
        status = final_outputs.StageWith(FLAGS_bundle_out_cameras,
                                   [&](const std::string& path) { return WriteCameraTable(path, cameras); });
    }
    if (status.ok() && !FLAGS_bundle_out_colmap.empty()) {
      ColmapModelText model;
      status = FormatColmapModel(block, FLAGS_bundle_colmap_model.empty() ? nullptr : &run.colmap_extras, &model);
      stage(FLAGS_bundle_out_colmap + "/cameras.txt", model.cameras);
      stage(FLAGS_bundle_out_colmap + "/images.txt", model.images);
      stage(FLAGS_bundle_out_colmap + "/points3D.txt", model.points3D);
    }
  }
  if (status.ok()) status = final_outputs.Commit();
  return status;
}

// The closing line: images adjusted, sigma0, check RMSE, files written.
void PrintClosingSummary(const BundleRun& run, bool usable) {
  const BundleAdjustmentResult& result = run.result;
  std::cout << "bundle: " << (usable ? "adjusted " : "not adjusted: ") << result.summary.num_images
            << " images";
  if (std::isfinite(result.summary.sigma0)) std::cout << ", sigma0 " << result.summary.sigma0;
  if (result.num_check_points > 0) std::cout << ", check RMSE " << result.check_rmse_total_m << " m";
  std::cout << "; wrote";
  bool any = false;
  for (const auto& [label, path] : run.written) {
    if (!usable && label != "--report" && label != "--html") continue;
    std::cout << (any ? ", " : " ") << path;
    any = true;
  }
  if (!any) std::cout << " nothing";
  std::cout << "\n";
}

}  // namespace

int RunBundle(int argc, char** argv) {
  const char* const kCommand = "bundle";
  ParsedFlags parsed;
  if (!ParseFlags(argc, argv, BundleFlags(), &parsed)) return kExitBadInput;
  if (parsed.help) {
    PrintHelp(kUsage, BundleFlags());
    return kExitSuccess;
  }
  BundleRun run;
  run.context.command_line = "photopose bundle";
  for (int i = 0; i < argc; ++i) run.context.command_line += std::string(" ") + argv[i];

  OutputFiles outputs;
  int code = CheckInputChoice(kCommand, &run);
  if (code == kGoOn) code = OptionsFromFlags(kCommand, &run);
  if (code == kGoOn) code = DeclareFiles(kCommand, parsed, &run, &outputs);
  if (code == kGoOn) code = ReadBundleBlock(kCommand, &run);
  if (code != kGoOn) return code;
  {
    const ScopedSolving solving;
    code = InitializeBundleBlock(kCommand, &run);
    if (code == kGoOn) code = AdjustBundleBlock(kCommand, &run);
    if (code != kGoOn) return code;
  }
  for (const auto& [label, path] : run.written) run.context.outputs.push_back(path);
  run.context.options = run.options;
  run.context.config = run.config;

  const bool usable = run.result.summary.IsSolutionUsable();
  for (const std::string& line : BundleConsoleLines(run.block, run.result, run.context)) std::cout << line << "\n";
  if (!usable) {
    std::cerr << "photopose bundle: not adjusted: " << run.result.summary.message << "\n";
    run.exit_code = kExitSomeFailed;
  }
  outputs.Abort();
  const Status written = WriteBundleOutputs(run, usable);
  if (!written.ok()) return BadInput(kCommand, written.message());
  PrintClosingSummary(run, usable);
  return run.exit_code;
}

}  // namespace photopose::cli
