// photopose bundle: the weighted bundle adjustment of a block (solvers/bundle/bundle_adjustment.h).
// One file past ~800 lines on purpose: the command's steps in the order they run (flags, inputs,
// georeferencing, initial values, adjustment, checks, outputs, closing summary), each a named
// function over one BundleRun; the formats and reports it calls live in core/io and tools/report.
#include <gflags/gflags.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>

#include "core/io/bal.h"
#include "core/block.h"
#include "core/io/block_tables.h"
#include "core/io/colmap.h"
#include "core/io/opensfm.h"
#include "core/io/csv.h"
#include "core/io/exif_gps.h"
#include "core/io/output_files.h"
#include "core/io/tables.h"
#include "core/geodesy/crs.h"
#include "core/mark_weight.h"
#include "solvers/bundle/block_initialization.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/taylor_bundle.h"
#include "solvers/georeference/adjusted_colmap_model.h"
#include "solvers/georeference/georeference.h"
#include "tools/report/bundle_report.h"
#include "tools/report/html_kit.h"
#include "tools/commands/cli_common.h"
#include "tools/commands/commands.h"

DEFINE_string(bundle_cameras, "", "Camera table (CSV, ArcGIS frame-camera schema): the interior orientation of every CameraID.");
DEFINE_string(bundle_marks, "", "Image marks (CSV: Raster, PointID, Column and Row in pixels or FilmX and FilmY in micrometres, optional Accuracy in the mark's own unit and CameraID). A point with marks but no row in --points is a tie point.");
DEFINE_string(bundle_points, "", "Ground points (CSV: PointID, X, Y, Z in metres, optional AccuracyX/Y/Z in metres, all three 0 holding a control point fixed, and Role control|check|tie). Optional for a block held by camera positions.");
DEFINE_string(bundle_frames, "", "Frames table: PerspectiveX/Y/Z are the measured camera positions: priors with their per-row AccuracyX/Y/Z, else with --camera_accuracy (10 m by default, Metashape's: give a large value for positions that are initial values only) and Omega/Phi/Kappa initial values (priors with --attitude_accuracy or per-row AccuracyOmega/Phi/Kappa). Images without a row are oriented by resection.");
DEFINE_string(bundle_colmap_model, "", "A COLMAP model folder to adjust instead of the tables: binary (cameras.bin, images.bin, points3D.bin) when all three are there, else text (cameras.txt, images.txt, points3D.txt).");
DEFINE_string(bundle_bal, "", "A BAL problem file to adjust instead of the tables.");
DEFINE_string(bundle_opensfm, "", "An OpenSfM / OpenDroneMap reconstruction to adjust instead of the tables: reconstruction.json or the folder holding it (ODM: <project>/opensfm), tracks.csv beside it. Georeferenced like --colmap_model with --geo, --gcp_list, --frames, --points or --model_gps.");
DEFINE_bool(bundle_model_gps, false, "With --opensfm: the shots' GNSS positions the reconstruction holds (gps_position in its topocentric frame at reference_lla, accuracy gps_dop) are the camera positions to georeference with.");
DEFINE_string(bundle_geo, "", "With --colmap_model: camera positions as an OpenDroneMap geo.txt (first line the CRS; then image x y z [yaw pitch roll] [horizontal vertical accuracy]; x = easting or longitude). The model is georeferenced: aligned by a robust similarity, then adjusted with the positions as priors.");
DEFINE_string(bundle_images, "", "With --colmap_model or --opensfm: the folder of the images (names as the model gives them); their EXIF GPS tags (or DJI's XMP drone-dji tags) are the camera positions, DJI's RtkStdLon/RtkStdLat/RtkStdHgt their accuracies where present.");
DEFINE_string(bundle_exif_crs, "", "With --images: the CRS of the images' GPS positions. Default EPSG:4979 (WGS84, heights above the ellipsoid); EPSG:4326+5773 takes the heights as EGM96 (sea level, as the EXIF standard defines GPSAltitude). Which one a camera writes depends on its make and firmware.");
DEFINE_string(bundle_gcp_list, "", "With --colmap_model: ground control as an OpenDroneMap gcp_list.txt (first line the CRS; X Y Z px py image [name]); points named in --check_points are check points.");
DEFINE_string(bundle_crs, "", "With --colmap_model: the CRS of --points, and of the --frames rows without an SRS value (EPSG:<code>, a +proj string, WKT; X = easting or longitude first); a frames row whose SRS names another CRS is refused.");
DEFINE_string(bundle_out_crs, "", "CRS of the outputs of a georeferenced model (--out, --out_points); default: the control's CRS, else the positions' CRS when projected, else the WGS84 UTM zone of the block's centre.");
DEFINE_string(bundle_check_points, "", "Comma list of --gcp_list point names used as check points (held out of the adjustment, compared with it).");
DEFINE_string(bundle_out, "", "Output frames table (CSV) of the adjusted images with SigmaX..SigmaKappa, Sigma0, NumObservations and RmsResidual.");
DEFINE_string(bundle_out_points, "", "Output points table (CSV): PointID, X, Y, Z, SigmaX/Y/Z, Role, NumObservations, ErrorX/Y/Z.");
DEFINE_string(bundle_out_cameras, "", "Output camera table (CSV) with the calibrated interior orientation (frame cameras).");
DEFINE_string(bundle_out_colmap, "", "Output COLMAP model folder of the adjusted block; marks the adjustment rejected are written as keypoints without a 3D point.");
DEFINE_string(bundle_out_colmap_format, "", "Format of --out_colmap: text or binary. Empty: the format of --colmap_model when it is given, else text.");
DEFINE_string(bundle_report, "", "JSON report: summary, groups with their over-fitting verdict, control and check points, images, calibration, diagnostics, options (docs/formats.md).");
DEFINE_string(bundle_html, "", "Self-contained HTML page of the adjustment: verdicts, plan view, residual histograms, tables.");
DEFINE_string(bundle_rotation, "rxryrz", "Angle convention of the frames tables read and written: rxryrz (R = Rx(omega) Ry(phi) Rz(kappa) maps ground to camera; 'seed' is an alias), opk or pok (see docs/conventions.md).");
DEFINE_string(bundle_solver, "ceres", "Block solver: ceres (Levenberg-Marquardt on the cost functions), taylor (the seed's Taylor linearisation with hand-written normal equations; Levenberg-Marquardt unless --taylor_damping=none) or taylor_as_printed (with the partial derivatives as printed in the seed; Gauss-Newton).");
DEFINE_string(bundle_taylor_damping, "", "Damping of --solver=taylor: levenberg_marquardt (the default) or none (the lecture's plain Gauss-Newton, which diverges from poor starts). Empty: the solver's default.");
DEFINE_double(bundle_tie_accuracy, 1.0, "Accuracy (one sigma) of tie marks without an Accuracy value, in pixels.");
DEFINE_double(bundle_marker_projection_accuracy, 0.5, "Accuracy (one sigma) of control and check marks without an Accuracy value, in pixels.");
DEFINE_double(bundle_film_tie_accuracy, 5.0, "Accuracy of tie marks in film coordinates without an Accuracy value when the camera has no pixel size, in micrometres.");
DEFINE_double(bundle_film_marker_projection_accuracy, 2.5, "Accuracy of control marks in film coordinates without an Accuracy value when the camera has no pixel size, in micrometres.");
DEFINE_double(bundle_marker_accuracy, 0.005, "Accuracy (one sigma, per axis) of control point coordinates without AccuracyX/Y/Z, in metres.");
DEFINE_string(bundle_camera_accuracy, "", "Accuracy of the measured camera positions without per-row AccuracyX/Y/Z, in metres: one value or X,Y,Z. Empty: 10 m (Metashape's default) when --frames is given.");
DEFINE_double(bundle_attitude_accuracy, 0.0, "Accuracy of the measured attitudes without per-row accuracies, in degrees per angle; 0: no attitude prior.");
DEFINE_string(bundle_lever_arm, "", "GNSS antenna offset from the projection centre in the camera frame (x right, y up, z towards the viewer), in metres: X,Y,Z.");
DEFINE_bool(bundle_estimate_lever_arm, false, "Estimate the lever arm (starting from --lever_arm or zero).");
DEFINE_string(bundle_calibrate, "", "Self-calibration: a comma list of FocalLength, PrincipalX, PrincipalY, K0, K1, K2, K3, P1, P2, Affinity, Skew (for COLMAP models also COLMAP's own names of the model's parameters: f, fx, fy, cx, cy, k, k1, k2, p1, p2; f names fx and fy together); the rest held constant.");
DEFINE_string(bundle_loss, "none", "Robust loss on tie marks: none, huber, cauchy or softl1.");
DEFINE_double(bundle_loss_scale, 3.0, "Scale of the robust loss on tie marks, in standard deviations of each mark's own accuracy (its Accuracy, else --tie_accuracy or --film_tie_accuracy), as in resect.");
DEFINE_string(bundle_jacobian, "analytic", "Derivative path of the collinearity cost: analytic or autodiff.");
DEFINE_string(bundle_linear_solver, "sparse_schur", "Linear solver: sparse_schur (SuiteSparse), dense_schur, iterative_schur_jacobi or iterative_schur_cluster_jacobi.");
DEFINE_int32(bundle_max_iterations, 100, "Largest number of Levenberg-Marquardt iterations per adjustment round.");
DEFINE_double(bundle_rejection_threshold, 4.5, "Marks whose normalized residual exceeds this are rejected and the block adjusted again; 0 keeps every mark.");
DEFINE_int32(bundle_max_rejection_rounds, 3, "Largest number of rejection rounds.");
DEFINE_bool(bundle_estimate_accuracies, false, "Estimate every group's accuracy from the data (variance component estimation) and adjust with the estimates.");
DEFINE_bool(bundle_snoop, false, "Data snooping: remove the most significant rejected observation (marks, control points, camera positions), adjust again, repeat.");
DEFINE_bool(bundle_snooping_batch, true, "With --snoop: remove in one round every observation that one-at-a-time snooping would remove next as far as the round's statistics can tell (the largest w-test conditioned on those already taken, weakly correlated with them); false removes one per round, each after a fresh adjustment and statistics.");
DEFINE_double(bundle_alpha, 0.001, "Significance level of the w-test per observation (two-sided).");
DEFINE_bool(bundle_cross_validate, false, "Leave each control point out in turn and report its error as a check point.");
DEFINE_string(bundle_cross_validation_method, "update", "With --cross_validate: how the adjustment without each control point is found: update (one linearised step from the full adjustment by a low-rank update of its reduced normal matrix, one factorisation for all points; with either solver) or refit (one adjustment per point, Ceres', the update's oracle; not with --solver=taylor or taylor_as_printed).");
DEFINE_string(bundle_statistics, "full", "Posterior covariances, redundancy numbers, reliability and the verdicts that need them: full (at every block size, by selected inversion of the reduced camera system's sparse factor), none (group RMS and check points only), or dense (the dense inverse, for comparison; n^2 memory in the reduced parameters).");
DEFINE_string(bundle_relative_covariance, "points", "The datum of a relative block's orientation and point covariances (residuals, redundancy numbers and w-tests are the same in every datum): points (inner constraints on the adjusted points: the smallest trace of their covariance, every image with a covariance), centres (inner constraints on the camera centres), or first_image (the adjustment's own gauge: the first image's covariance zero). Blocks with control points or camera positions have their own datum; this flag is refused for them.");
DEFINE_string(bundle_relative_gauge, "free", "Relative blocks (no control points, no camera positions): free solves without a gauge and then moves the result into COLMAP's gauge (the first image as given, one coordinate of the second), the same minimum in far fewer iterations; fixed holds COLMAP's gauge from the start.");
DEFINE_int32(bundle_threads, 0, "Threads of the linear algebra and of the cross-validation; 0 uses all cores. With --solver=ceres and more than one thread Ceres sums in the order its threads finish: reruns agree to about 1e-13 m, not byte for byte; --threads=1 or --solver=taylor (bit-identical on any thread count) for byte-identical reruns.");
DEFINE_bool(bundle_quiet, false, "No progress lines on stderr.");
DEFINE_bool(bundle_force, false, "Write the outputs of an adjustment whose sigma0 stays above 3 after the search for gross errors (the run still exits 1 and the report says the check failed).");
DEFINE_bool(bundle_pixel_center_origin, false, "Read Column/Row with (0,0) at the centre of the first pixel instead of the top-left corner of the image.");
DEFINE_bool(bundle_pixel_rows_up, false, "With the tables: read Row counted up from the bottom edge of the image (Row 0 at the bottom) in the marks and the camera table's A0-B2, instead of down from the top edge; needs NRows in the camera table. --out_cameras writes A0-B2 back with rows counted up.");

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
    "                        [--snoop] [--cross_validate] [--cross_validation_method=update|refit]\n"
    "                        [--threads=N] [--quiet]\n"
    "   or: photopose bundle --colmap_model=DIR [--out_colmap=DIR] [--out_colmap_format=text|binary]\n"
    "                        [--calibrate=LIST] ...\n"
    "   or: photopose bundle --colmap_model=DIR | --opensfm=DIR [--geo=geo.txt | --frames=F.csv [--crs=EPSG:N]\n"
    "                        | --images=DIR [--exif_crs=EPSG:N] | --model_gps] [--gcp_list=gcp_list.txt [--check_points=A,B] | --points=P.csv\n"
    "                        --marks=M.csv --crs=EPSG:N] [--out_crs=EPSG:N] --out=F.csv ...   (georeferencing)\n"
    "   or: photopose bundle --bal=problem.txt ...\n\n"
    "Minimises reprojection errors^2 / tie accuracy^2 + control residuals^2 / marker accuracy^2 +\n"
    "camera position residuals^2 / camera accuracy^2 (Metashape's reference settings) and reports,\n"
    "per group, whether the block bends to its priors (over-fitting). Images without initial values\n"
    "are oriented by resection and the tie points triangulated first. Ctrl-C (SIGINT) or SIGTERM\n"
    "cancels the run after the current iteration: nothing is written, exit status 130 or 143\n"
    "(docs/cli.md). Exit status: 0 converged, 1 not converged or some image could not be oriented\n"
    "(each named), 2 bad input or usage.\n";

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
       {"loss_scale", 0.0, 1000.0, true, false, "standard deviations"},
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
  std::optional<TaylorDamping> taylor_damping;  // --taylor_damping; empty: the solver's default
  BundleReportContext context;
  std::vector<std::pair<std::string, std::string>> written;  // (label, path) of the outputs
  Block block;
  ColmapModelExtras colmap_extras;
  OpenSfmExtras opensfm_extras;  // of --opensfm
  // A model georeferenced with positions and/or control (--geo, --gcp_list, --frames, --points).
  bool georeference = false;
  // A relative adjustment of a model georeferenced before (its folder holds georeference.json):
  // --out_colmap carries that file over, the frame being kept (issue 21).
  bool carries_frame_json = false;
  GeoreferenceResult georeferenced;
  ColmapFormat colmap_in_format = ColmapFormat::kText;   // of --colmap_model
  ColmapFormat colmap_out_format = ColmapFormat::kText;  // of --out_colmap
  BundleAdjustmentResult result;
  BundleCrossValidationResult cross_validation;
  int exit_code = kExitSuccess;  // kExitSomeFailed once an image could not be oriented
};

// A step's "go on" (any other value is the exit status to return).
constexpr int kGoOn = -1;

// Which input, and the outputs that fit it.
int CheckInputChoice(const char* command, BundleRun* run) {
  // With a model (COLMAP, OpenSfM), --marks are the control points' marks (georeferencing).
  const bool model = !FLAGS_bundle_colmap_model.empty() || !FLAGS_bundle_opensfm.empty();
  const bool table_marks = !FLAGS_bundle_marks.empty() && !model;
  const int sources = (!FLAGS_bundle_colmap_model.empty()) + (!FLAGS_bundle_opensfm.empty()) +
                      (!FLAGS_bundle_bal.empty()) + (table_marks || !FLAGS_bundle_cameras.empty());
  if (sources != 1)
    return BadInput(command, "give the tables (--cameras and --marks), --colmap_model, --opensfm or --bal: one of them");
  run->tables = !model && FLAGS_bundle_bal.empty();
  if (FLAGS_bundle_model_gps && FLAGS_bundle_opensfm.empty())
    return BadInput(command, "--model_gps takes the GNSS positions an OpenSfM reconstruction holds: give --opensfm");
  if (FLAGS_bundle_model_gps + !FLAGS_bundle_geo.empty() + !FLAGS_bundle_frames.empty() + !FLAGS_bundle_images.empty() > 1)
    return BadInput(command, "give the camera positions once: --model_gps, --geo, --frames or --images");
  if (!FLAGS_bundle_images.empty() && !model)
    return BadInput(command, "--images reads the camera positions of --colmap_model or --opensfm from the images' GPS tags; with the tables give --frames");
  if (!FLAGS_bundle_exif_crs.empty() && FLAGS_bundle_images.empty())
    return BadInput(command, "--exif_crs is the CRS of the GPS tags of --images: give --images too");
  if (!FLAGS_bundle_bal.empty() && !FLAGS_bundle_marks.empty())
    return BadInput(command, "--marks: a BAL problem holds its own observations");
  if (run->tables && (FLAGS_bundle_cameras.empty() || FLAGS_bundle_marks.empty()))
    return BadInput(command, "--cameras and --marks are both required with the tables");
  if (FLAGS_bundle_out.empty() && FLAGS_bundle_out_colmap.empty() && FLAGS_bundle_report.empty())
    return BadInput(command, "nothing to write: give --out, --out_colmap or --report");
  if (FLAGS_bundle_pixel_rows_up && !run->tables)
    return BadInput(command, "--pixel_rows_up applies to the tables: --colmap_model, --opensfm and --bal define their own pixels");
  if (FLAGS_bundle_pixel_center_origin && !run->tables)
    return BadInput(command, "--pixel_center_origin applies to the tables: --colmap_model, --opensfm and --bal define their own pixels (and a model's control marks count from the top-left corner)");
  if (!FLAGS_bundle_out_cameras.empty() && !run->tables)
    return BadInput(command, "--out_cameras writes a camera table of frame cameras; with --colmap_model or --bal use --out_colmap");
  // A COLMAP model is georeferenced with positions and control; a BAL problem takes nothing else.
  const bool measurements = !FLAGS_bundle_geo.empty() || !FLAGS_bundle_gcp_list.empty() || !FLAGS_bundle_images.empty() ||
                            !FLAGS_bundle_points.empty() || !FLAGS_bundle_frames.empty() ||
                            FLAGS_bundle_model_gps;
  if (!FLAGS_bundle_bal.empty() && measurements)
    return BadInput(command, "--bal holds its own points and poses: --geo, --gcp_list, --points and --frames are read with the tables or --colmap_model");
  if (run->tables && (!FLAGS_bundle_geo.empty() || !FLAGS_bundle_gcp_list.empty()))
    return BadInput(command, "--geo and --gcp_list georeference a --colmap_model; with the tables give --frames and --points");
  if (run->tables && (!FLAGS_bundle_crs.empty() || !FLAGS_bundle_out_crs.empty()))
    return BadInput(command, "--crs and --out_crs georeference a --colmap_model; the tables are adjusted in their own ground frame");
  run->georeference = model && measurements;
  if (model) {
    if (!FLAGS_bundle_gcp_list.empty() && !FLAGS_bundle_points.empty())
      return BadInput(command, "give the control as --gcp_list or as --points with --marks, not both");
    if (!FLAGS_bundle_points.empty() && FLAGS_bundle_marks.empty())
      return BadInput(command, "--points with --colmap_model needs --marks (the control points' image marks)");
    if (!FLAGS_bundle_marks.empty() && FLAGS_bundle_points.empty())
      return BadInput(command, "--marks beside --colmap_model or --opensfm are the control points' image marks: give their --points (with --crs) too");
    // A frames table may name its CRS in its SRS column (PositionsFromFrames); a points table has none.
    if (!FLAGS_bundle_points.empty() && FLAGS_bundle_crs.empty())
      return BadInput(command, "--crs is needed: a points table has no SRS column, so --points carry no coordinate system (e.g. --crs=EPSG:32632)");
    if (!FLAGS_bundle_crs.empty() && FLAGS_bundle_points.empty() && FLAGS_bundle_frames.empty())
      return BadInput(command, "--crs names the CRS of --points and --frames, and neither is given (geo.txt and gcp_list.txt name their own)");
    if (!FLAGS_bundle_out_crs.empty() && !run->georeference)
      return BadInput(command, "--out_crs: nothing is georeferenced; give --geo, --gcp_list, --frames or --points with the model");
  }
  if (!FLAGS_bundle_check_points.empty() && FLAGS_bundle_gcp_list.empty())
    return BadInput(command, "--check_points names points of --gcp_list (a points table says Role=check itself)");
  if (!FLAGS_bundle_out_colmap_format.empty() && FLAGS_bundle_out_colmap.empty())
    return BadInput(command, "--out_colmap_format is the format of --out_colmap: give --out_colmap too");
  if (!FLAGS_bundle_bal.empty() && !FLAGS_bundle_out_colmap.empty())
    return BadInput(command, "--out_colmap: a BAL problem has no image size and counts pixels from the image centre, which a COLMAP model cannot hold; write --out, --out_points or --report");
  // A CRS given by a flag is resolved now, named by its flag (the CRSs files name are named with
  // their file and line by PrepareGeoreference).
  for (const auto& [flag, crs] : {std::pair<const char*, const std::string&>{"--crs", FLAGS_bundle_crs},
                                  {"--out_crs", FLAGS_bundle_out_crs}, {"--exif_crs", FLAGS_bundle_exif_crs}}) {
    CrsInfo info;
    if (const Status known = crs.empty() ? Status::Ok() : ResolveCrs(crs, &info); !known.ok())
      return BadInput(command, std::string(flag) + ": " + known.message());
  }
  run->context.input_kind = run->tables ? "tables" : !FLAGS_bundle_colmap_model.empty() ? "colmap" : !FLAGS_bundle_opensfm.empty() ? "opensfm" : "bal";
  if (!ParseEnum(FLAGS_bundle_rotation, &run->context.rotation))
    return BadInput(command, EnumFlagError<RotationConvention>("--rotation", FLAGS_bundle_rotation));
  return kGoOn;
}

// The longest progress line (characters): a terminal's width, no wrapping.
constexpr size_t kMaxProgressLine = 119;

// The progress line of every iteration, on stderr, at most kMaxProgressLine characters, the
// essentials first: "photopose bundle: round 1 iteration   1: cost 895984  sigma0 14.2136  step 254
// 0.0 s", then as far as they fit, from Ceres: "  solve 0.00 of 0.01 s" (the linear solve's and
// the iteration's seconds; tools/benchmarks/bundle_scaling.sh reads "iteration N:" and "solve A of
// B s"), "  REJECTED" for a step not taken, "  quality 1.00" (the step's), "  radius 30000" (the
// trust region's).
// Numbers through core/units.h: fixed notation, never an exponent.
// Returns false (the adjustment stops after this iteration) once SIGINT or SIGTERM asked the run
// to stop (CancelOnSignals).
bool PrintProgress(const BundleIterationInfo& info) {
  char iteration[16];
  std::snprintf(iteration, sizeof(iteration), "%3d", info.iteration);
  std::string line = "photopose bundle: round " + std::to_string(info.round) +
                     (info.free_gauge ? " (free gauge)" : "") + " iteration " + iteration +
                     ": cost " + FormatSignificant(info.cost, 6) + "  sigma0 " +
                     FormatUnitless(info.sigma0, 4) + "  step " +
                     FormatSignificant(info.step_norm, 3) + "  " +
                     FormatUnitless(info.elapsed_seconds, 1) + " s";
  if (std::isfinite(info.trust_region_radius)) {
    for (const std::string& more :
         {"  solve " + FormatUnitless(info.linear_solver_seconds, 2) + " of " +
              FormatUnitless(info.iteration_seconds, 2) + " s",
          std::string(info.step_successful ? "" : "  REJECTED"),
          "  quality " + FormatUnitless(info.step_quality, 2),
          "  radius " + FormatSignificant(info.trust_region_radius, 2)}) {
      if (line.size() + more.size() > kMaxProgressLine) break;
      line += more;
    }
  }
  std::cerr << line + "\n";
  return !CancelRequested();
}

// The hook of --quiet: no line, only the cancellation.
bool CancelWhenAsked(const BundleIterationInfo&) { return !CancelRequested(); }

// The accuracy flags -> options.accuracies, and the lever arm of the config.
int AccuraciesFromFlags(const char* command, BundleRun* run) {
  BundleAccuracies& acc = run->options.accuracies;
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
  return kGoOn;
}

// --solver and --taylor_damping -> the block solver, with the flags that only one solver uses
// refused for the other.
int BlockSolverFromFlags(const char* command, BundleRun* run) {
  if (!ParseEnum(FLAGS_bundle_solver, &run->solver))
    return BadInput(command, EnumFlagError<PoseSolver>("--solver", FLAGS_bundle_solver));
  // What only the Ceres solver uses is refused with the Taylor solvers, never silently ignored
  // (--max_iterations and --loss apply to both).
  if (run->solver != PoseSolver::kCeres) {
    for (const char* flag : {"jacobian", "linear_solver"}) {
      if (FlagGiven((std::string("bundle_") + flag).c_str()))
        return BadInput(command,
                        "--" + std::string(flag) +
                            " is for --solver=ceres; --solver=" + FLAGS_bundle_solver +
                            " builds and solves its own normal equations with the seed's partials");
    }
  }
  if (run->solver != PoseSolver::kCeres && FLAGS_bundle_cross_validate &&
      run->options.statistics.cross_validation == BundleCrossValidationMethod::kRefit)
    return BadInput(command, "--solver=" + FLAGS_bundle_solver +
                                 " does not refit (the left-out adjustments are Ceres'); use "
                                 "--cross_validation_method=update or --solver=ceres");
  if (!FLAGS_bundle_taylor_damping.empty()) {
    TaylorDamping damping;
    if (!ParseEnum(FLAGS_bundle_taylor_damping, &damping))
      return BadInput(
          command, EnumFlagError<TaylorDamping>("--taylor_damping", FLAGS_bundle_taylor_damping));
    if (run->solver == PoseSolver::kCeres)
      return BadInput(command,
                      "--taylor_damping is for --solver=taylor or taylor_as_printed; Ceres damps "
                      "by its own trust region");
    run->taylor_damping = damping;
  }
  const bool gauss_newton = run->solver == PoseSolver::kTaylorAsPrinted ||
                            (run->taylor_damping && *run->taylor_damping == TaylorDamping::kNone);
  if (gauss_newton && FLAGS_bundle_relative_gauge == "free" && FlagGiven("bundle_relative_gauge"))
    return BadInput(
        command,
        "--relative_gauge=free needs a damped solver (the free directions stay still only under "
        "Levenberg-Marquardt's damping); Gauss-Newton holds COLMAP's gauge from the start");
  return kGoOn;
}

// The flags -> the options (accuracies, robustness, statistics, solver), the lever arm of the
// config, the --calibrate names and the block solver.
int OptionsFromFlags(const char* command, BundleRun* run) {
  if (const int code = AccuraciesFromFlags(command, run); code != kGoOn) return code;
  BundleAdjustmentOptions& options = run->options;
  BundleSolverOptions& solver = options.solver;
  if (!ParseEnum(FLAGS_bundle_jacobian, &solver.jacobian))
    return BadInput(command, EnumFlagError<JacobianType>("--jacobian", FLAGS_bundle_jacobian));
  if (!ParseEnum(FLAGS_bundle_linear_solver, &solver.linear_solver))
    return BadInput(command, EnumFlagError<BundleLinearSolver>("--linear_solver", FLAGS_bundle_linear_solver));
  BundleRobustnessOptions& robustness = options.robustness;
  if (!ParseEnum(FLAGS_bundle_loss, &robustness.tie_loss) || !IsBundleTieLoss(robustness.tie_loss))
    return BadInput(command, "--loss must be " + EnumNameList(kBundleTieLosses) + ", not '" + FLAGS_bundle_loss + "'");
  robustness.tie_loss_scale_sigmas = FLAGS_bundle_loss_scale;
  solver.max_iterations = FLAGS_bundle_max_iterations;
  robustness.rejection_threshold = FLAGS_bundle_rejection_threshold;
  robustness.max_rejection_rounds = FLAGS_bundle_max_rejection_rounds;
  options.statistics.estimate_accuracies = FLAGS_bundle_estimate_accuracies;
  robustness.snoop = FLAGS_bundle_snoop;
  robustness.snooping_batch = FLAGS_bundle_snooping_batch;
  options.statistics.snooping_alpha = FLAGS_bundle_alpha;
  if (!ParseEnum(FLAGS_bundle_statistics, &options.statistics.covariances))
    return BadInput(command, EnumFlagError<BundleCovarianceMethod>("--statistics", FLAGS_bundle_statistics));
  if (!ParseEnum(FLAGS_bundle_cross_validation_method, &options.statistics.cross_validation))
    return BadInput(command, EnumFlagError<BundleCrossValidationMethod>(
                                 "--cross_validation_method", FLAGS_bundle_cross_validation_method));
  if (FlagGiven("bundle_cross_validation_method") && !FLAGS_bundle_cross_validate)
    return BadInput(command, "--cross_validation_method is for --cross_validate, which is not given");
  if (!ParseEnum(FLAGS_bundle_relative_covariance, &options.statistics.relative_covariance))
    return BadInput(command, EnumFlagError<BundleRelativeCovariance>("--relative_covariance",
                                                                     FLAGS_bundle_relative_covariance));
  solver.num_threads = FLAGS_bundle_threads;
  if (FLAGS_bundle_relative_gauge != "free" && FLAGS_bundle_relative_gauge != "fixed")
    return BadInput(command, "--relative_gauge must be free or fixed, not '" + FLAGS_bundle_relative_gauge + "'");
  solver.free_gauge_for_relative_blocks = FLAGS_bundle_relative_gauge == "free";
  solver.progress = FLAGS_bundle_quiet ? CancelWhenAsked : PrintProgress;
  // What needs the statistics is refused without them, never skipped in silence: the rule of
  // BundleAdjustmentOptions::IsValid and CrossValidateControlPoints, said in the flags' names.
  if (options.statistics.covariances == BundleCovarianceMethod::kNone) {
    const std::pair<bool, std::string> needs[] = {
        {FLAGS_bundle_snoop, "--snoop needs the statistics (the w-test divides each residual by its observation's redundancy number, from the covariances)"},
        {FLAGS_bundle_estimate_accuracies, "--estimate_accuracies needs the statistics (a group's variance factor divides by its redundancy, the sum of its redundancy numbers, from the covariances)"},
        {FLAGS_bundle_cross_validate, "--cross_validate needs the statistics (a left-out control point's normalized error takes the images' uncertainty from the covariances)"}};
    for (const auto& [asked, why] : needs)
      if (asked) return BadInput(command, why + "; --statistics=none computes none: give --statistics=full or leave the flag out");
  }
  if (const Status valid = Validate(options); !valid.ok()) return BadInput(command, valid.message());
  for (const std::string& name : SplitCommaList(FLAGS_bundle_calibrate))
    if (!name.empty()) run->calibrate.push_back(name);
  run->context.calibrate = run->calibrate;
  return BlockSolverFromFlags(command, run);
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
  // The reconstruction when named as a file (a folder holds no output anyway).
  std::error_code no_error;
  const std::string opensfm_file =
      std::filesystem::is_regular_file(FLAGS_bundle_opensfm, no_error) ? FLAGS_bundle_opensfm : std::string();
  for (const auto& [label, path] : {std::pair<const char*, const std::string&>{"--cameras", FLAGS_bundle_cameras},
                                    {"--marks", FLAGS_bundle_marks}, {"--points", FLAGS_bundle_points},
                                    {"--frames", FLAGS_bundle_frames}, {"--bal", FLAGS_bundle_bal},
                                    {"--geo", FLAGS_bundle_geo}, {"--gcp_list", FLAGS_bundle_gcp_list},
                                    {"--opensfm", opensfm_file}}) {
    const Status input = outputs->AddInput(label, path);
    if (!input.ok()) return BadInput(command, input.message());
    if (!path.empty()) run->context.inputs.push_back(path);
  }
  if (!FLAGS_bundle_colmap_model.empty()) {
    const Status detected = DetectColmapFormat(FLAGS_bundle_colmap_model, &run->colmap_in_format);
    if (!detected.ok()) return BadInput(command, "--colmap_model: " + detected.message());
    for (const char* name : ColmapFileNames(run->colmap_in_format)) {
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
    run->colmap_out_format = run->colmap_in_format;
    if (!FLAGS_bundle_out_colmap_format.empty() && !ParseEnum(FLAGS_bundle_out_colmap_format, &run->colmap_out_format))
      return BadInput(command, EnumFlagError<ColmapFormat>("--out_colmap_format", FLAGS_bundle_out_colmap_format));
    // A binary model left in the folder would be read (by COLMAP too) instead of the text written.
    ColmapFormat there = ColmapFormat::kText;
    if (run->colmap_out_format == ColmapFormat::kText && DetectColmapFormat(FLAGS_bundle_out_colmap, &there).ok() && there == ColmapFormat::kBinary)
      return BadInput(command, "--out_colmap=" + FLAGS_bundle_out_colmap + " holds a binary COLMAP model (cameras.bin, images.bin, points3D.bin), which COLMAP and photopose read instead of the text model written here: remove it, or give --out_colmap_format=binary");
    std::vector<std::string> names;
    for (const char* name : ColmapFileNames(run->colmap_out_format)) names.push_back(name);
    // A georeferenced model is written in the local frame, with that frame beside it; a relative
    // adjustment keeps the frame of a model georeferenced before, and its georeference.json.
    std::error_code error;
    run->carries_frame_json = !run->georeference && !FLAGS_bundle_colmap_model.empty() &&
                              std::filesystem::is_regular_file(FLAGS_bundle_colmap_model + "/" + kGeoreferenceJsonName, error);
    if (run->georeference || run->carries_frame_json) names.push_back(kGeoreferenceJsonName);
    for (const std::string& name : names) {
      const std::string path = FLAGS_bundle_out_colmap + "/" + name;
      const Status declared = outputs->AddOutput("--out_colmap", path);
      if (!declared.ok()) return BadInput(command, declared.message());
      run->written.push_back({"--out_colmap", path});
    }
  }
  return kGoOn;
}

// --model_gps: the shots' GNSS positions an OpenSfM reconstruction holds.
int PositionsFromModelGps(const char* command, const BundleRun& run, GeoreferenceInputs* inputs) {
  // The shots' GNSS, in the reconstruction's topocentric frame at reference_lla: to EPSG:4979.
  const OpenSfmExtras& extras = run.opensfm_extras;
  if (!extras.reference_lla)
    return BadInput(command, "--model_gps: " + FLAGS_bundle_opensfm + " has no reference_lla (nor a reference_lla.json beside it): its GNSS positions have no place on Earth");
  LocalFrame frame;
  const Status made = LocalFrame::Create("EPSG:4979", Eigen::Vector3d(extras.reference_lla->longitude_deg, extras.reference_lla->latitude_deg, extras.reference_lla->altitude_m), &frame);
  if (!made.ok()) return BadInput(command, "--model_gps: " + made.message());
  std::vector<Eigen::Vector3d> positions;
  std::vector<int> images;
  for (size_t i = 0; i < run.block.images.size() && i < extras.gps_position_m.size(); ++i) {
    if (!extras.gps_position_m[i]) continue;
    positions.push_back(*extras.gps_position_m[i]);
    images.push_back(static_cast<int>(i));
  }
  if (positions.empty()) return BadInput(command, "--model_gps: no shot of " + FLAGS_bundle_opensfm + " has a gps_position");
  const Status moved = frame.FromLocal("EPSG:4979", &positions);
  if (!moved.ok()) return BadInput(command, "--model_gps: " + moved.message());
  inputs->positions_crs = "EPSG:4979";
  inputs->positions_source = FLAGS_bundle_opensfm;
  for (size_t k = 0; k < positions.size(); ++k) {
    CameraPositionMeasurement m;
    m.image = run.block.images[images[k]].name;
    m.position = positions[k];
    const std::optional<double>& dop = run.opensfm_extras.gps_dop_m[images[k]];
    if (dop && *dop > 0.0) m.accuracy_m = Eigen::Vector3d::Constant(*dop);
    inputs->positions.push_back(m);
  }
  return kGoOn;
}

// --images: the camera positions from the images' GPS tags (DJI's RTK accuracies where present).
int PositionsFromImages(const char* command, const BundleRun& run, GeoreferenceInputs* inputs) {
  std::vector<std::string> names;
  for (const BlockImage& image : run.block.images) names.push_back(image.name);
  std::vector<std::optional<ExifGps>> gps;
  std::vector<std::string> missing;
  const Status read = ReadExifGpsOfImages(FLAGS_bundle_images, names, &gps, &missing);
  if (!read.ok()) return BadInput(command, "--images: " + read.message());
  if (missing.size() == names.size())
    return BadInput(command, "--images: no image in " + FLAGS_bundle_images + " has GPS tags (EXIF GPSLatitude/GPSLongitude or DJI XMP GpsLatitude/GpsLongitude)");
  SetPositionsFromGps(names, gps, FLAGS_bundle_exif_crs.empty() ? "EPSG:4979" : FLAGS_bundle_exif_crs,
                      FLAGS_bundle_images + " (GPS tags)", inputs);
  const long with_rtk = std::count_if(inputs->positions.begin(), inputs->positions.end(),
                                      [](const CameraPositionMeasurement& m) { return m.accuracy_m.has_value(); });
  if (!FLAGS_bundle_quiet) {
    std::cerr << "photopose bundle: --images: " << inputs->positions.size() << " camera positions from GPS tags ("
              << with_rtk << " with DJI RTK accuracies), heights as " << inputs->positions_crs << " defines them\n";
    if (!missing.empty()) {
      std::cerr << "photopose bundle: --images: " << missing.size() << (missing.size() == 1 ? " image" : " images")
                << " without GPS tags, adjusted without a position:";
      for (size_t k = 0; k < missing.size() && k < 5; ++k) std::cerr << " " << missing[k];
      std::cerr << (missing.size() > 5 ? " ...\n" : "\n");
    }
  }
  return kGoOn;
}

// --geo: the camera positions of an OpenDroneMap geo.txt.
int PositionsFromGeoTxt(const char* command, GeoreferenceInputs* inputs) {
  GeoTxt geo;
  const Status read = ReadGeoTxt(FLAGS_bundle_geo, &geo);
  if (!read.ok()) return BadInput(command, read.message());
  SetPositionsFromGeoTxt(geo, FLAGS_bundle_geo, inputs);
  return kGoOn;
}

// --frames: PerspectiveX/Y/Z of a frames table as the camera positions, in the CRS of its SRS
// column or --crs (one CRS: SetPositionsFromFrames); its Omega/Phi/Kappa are recorded as read and
// not used (GeoreferenceResult::inputs_not_used).
int PositionsFromFrames(const char* command, GeoreferenceInputs* inputs) {
  std::vector<FrameRecord> frames;
  FramesTableOptions frames_options;
  const Status read = ReadFramesTable(FLAGS_bundle_frames, frames_options, &frames);
  if (!read.ok()) return BadInput(command, read.message());
  const Status positions = SetPositionsFromFrames(frames, FLAGS_bundle_crs, "--crs", FLAGS_bundle_frames, inputs);
  if (!positions.ok()) return BadInput(command, "--frames " + positions.message());
  return kGoOn;
}

// --gcp_list (with --check_points), or --points with --marks (with --crs): the control.
int ControlFromFiles(const char* command, GeoreferenceInputs* inputs) {
  if (!FLAGS_bundle_gcp_list.empty()) {
    GcpList gcp;
    const Status read = ReadGcpList(FLAGS_bundle_gcp_list, &gcp);
    if (!read.ok()) return BadInput(command, read.message());
    std::vector<std::string> checks;
    for (const std::string& id : SplitCommaList(FLAGS_bundle_check_points))
      if (!id.empty()) checks.push_back(id);
    const Status control = SetControlFromGcpList(gcp, checks, FLAGS_bundle_gcp_list, inputs);
    if (!control.ok()) return BadInput(command, "--check_points: " + control.message());
  } else if (!FLAGS_bundle_points.empty()) {
    const Status points = ReadGroundPoints(FLAGS_bundle_points, &inputs->control_points);
    if (!points.ok()) return BadInput(command, points.message());
    const Status marks = ReadImageMarks(FLAGS_bundle_marks, &inputs->control_marks);
    if (!marks.ok()) return BadInput(command, marks.message());
    inputs->control_crs = FLAGS_bundle_crs;
    inputs->control_source = FLAGS_bundle_points;
  }
  return kGoOn;
}

// The camera positions and control of a georeferenced model, as files give them: the positions
// from one source (CheckInputChoice allows one), then the control.
int ReadGeoreferenceInputs(const char* command, const BundleRun& run, GeoreferenceInputs* inputs) {
  int code = kGoOn;
  if (FLAGS_bundle_model_gps) {
    code = PositionsFromModelGps(command, run, inputs);
  } else if (!FLAGS_bundle_images.empty()) {
    code = PositionsFromImages(command, run, inputs);
  } else if (!FLAGS_bundle_geo.empty()) {
    code = PositionsFromGeoTxt(command, inputs);
  } else if (!FLAGS_bundle_frames.empty()) {
    code = PositionsFromFrames(command, inputs);
  }
  if (code != kGoOn) return code;
  return ControlFromFiles(command, inputs);
}

// Moves the model into the local frame of its positions and control (PrepareGeoreference);
// printed by PrintGeoreference once the flags are checked against the block it gives.
int GeoreferenceModel(const char* command, BundleRun* run) {
  GeoreferenceInputs inputs;
  const int code = ReadGeoreferenceInputs(command, *run, &inputs);
  if (code != kGoOn) return code;
  GeoreferenceOptions options;
  options.out_crs = FLAGS_bundle_out_crs;
  options.default_camera_accuracy_m = run->options.accuracies.camera_m.mean();
  options.default_marker_accuracy_m = run->options.accuracies.marker_m;
  const Status prepared = PrepareGeoreference(options, inputs, &run->block, &run->georeferenced);
  if (!prepared.ok()) return BadInput(command, prepared.message());
  if (!inputs.positions.empty()) run->options.accuracies.camera_positions_are_priors = true;
  return kGoOn;
}

// The georeferencing's lines on stderr (unless --quiet): the output CRS, what matched, the
// similarity.
void PrintGeoreference(const GeoreferenceResult& g) {
  if (!FLAGS_bundle_quiet) {
    std::cerr << "photopose bundle: georeference: output CRS " << g.out_crs << " (" << g.out_crs_info.name
              << ", " << g.out_crs_reason << "); " << g.positions_matched << " camera positions matched";
    if (g.positions_without_height > 0)
      std::cerr << " (" << g.positions_without_height << " without height: horizontal only)";
    if (!g.positions_unmatched.empty()) std::cerr << ", " << g.positions_unmatched.size() << " name no image of the model (first: '" << g.positions_unmatched[0] << "')";
    std::cerr << "; " << g.control_marks_matched << " control marks";
    if (!g.control_marks_unmatched.empty()) std::cerr << ", " << g.control_marks_unmatched.size() << " on images the model does not have (first: " << g.control_marks_unmatched[0] << ")";
    std::cerr << "\nphotopose bundle: similarity: scale " << FormatSignificant(g.model_to_local.scale, 6) << ", " << g.similarity.num_inliers
              << " of " << g.similarity.residual_m.size() << " pairs inliers";
    if (g.control_after_similarity.count > 0) std::cerr << "; control RMSE after it " << FormatLengthWithUnit(g.control_after_similarity.total_m);
    if (g.check_after_similarity.count > 0) std::cerr << "; check RMSE after it " << FormatLengthWithUnit(g.check_after_similarity.total_m);
    std::cerr << "\n";
  }
}

// The accuracy and datum flags this block cannot use, refused when given (issue 21: a flag
// silently ignored is a defect): the one rule of what each needs, run once the block is read and,
// for a model, georeferenced (its camera positions and control are then in the block; nothing is
// printed before), before any adjustment. A given flag is one set on the command line or in a
// flag file (FlagGiven), even to its default.
int RefuseFlagsWithoutEffect(const char* command, const BundleRun& run) {
  const std::string models = "the marks of --colmap_model, --opensfm and --bal are pixels";
  // A block with control points or camera positions has them as its datum: the tables (a table
  // block without either is refused after the adjustment) and a georeferenced model.
  if (run.tables || run.georeference) {
    const char* const datum = "; this block's datum is its control points and camera positions";
    if (FlagGiven("bundle_relative_covariance"))
      return BadInput(command, std::string("--relative_covariance chooses the datum of a relative block's covariances (a model without positions or control, or --bal)") + datum);
    if (FlagGiven("bundle_relative_gauge"))
      return BadInput(command, std::string("--relative_gauge chooses how a relative block's gauge is held while it is solved (a model without positions or control, or --bal)") + datum);
  }
  // The defaults only some marks, points and images take: a mark's (core/mark_weight.h,
  // TakesPixelDefault, TakesFilmDefault; check marks take the control marks' defaults,
  // solvers/bundle/check_points.h), a control or check point's without AccuracyX/Y/Z (its prior
  // in MakeBundlePlan, the check points' and the cross-validation's SurveyedPointErrorCovariance,
  // the similarity of PrepareGeoreference), a measured position's and attitude's without their
  // own accuracies (PlanImagePriors, solvers/bundle/bundle_problem.cc; the similarity).
  const Block& block = run.block;
  bool tie_marks = false, control_marks = false, tie_pixel = false, control_pixel = false;
  bool film_tie = false, film_control = false, surveyed = false, surveyed_default = false;
  bool positions = false, position_default = false, attitude = false;
  const MarkSigmaDefaults defaults;
  for (const BlockMark& mark : block.marks) {
    const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
    const bool tie = block.points[mark.point].role == PointRole::kTie;
    (tie ? tie_marks : control_marks) = true;
    if (TakesPixelDefault(mark, camera, defaults)) (tie ? tie_pixel : control_pixel) = true;
    if (TakesFilmDefault(mark, camera, defaults)) (tie ? film_tie : film_control) = true;
  }
  for (const BlockPoint& point : block.points) {
    if (point.role == PointRole::kTie) continue;
    surveyed = true;
    surveyed_default = surveyed_default || !point.accuracy_m;
  }
  for (const BlockImage& image : block.images) {
    positions = positions || image.measured_center_m.has_value();
    position_default = position_default || (image.measured_center_m && !image.center_accuracy_m);
    attitude = attitude || (image.measured_angles_rad && !image.attitude_accuracy_rad);
  }
  if (FlagGiven("bundle_tie_accuracy") && !tie_pixel)
    return BadInput(command, std::string("--tie_accuracy is the accuracy of tie marks without an Accuracy (pixels, or film coordinates on a camera with a pixel size); no mark of this block is one") + (tie_marks ? " (every tie mark has its own Accuracy or takes --film_tie_accuracy)" : " (it has no tie marks)"));
  if (FlagGiven("bundle_marker_projection_accuracy") && !control_pixel)
    return BadInput(command, std::string("--marker_projection_accuracy is the accuracy of control and check marks without an Accuracy (pixels, or film coordinates on a camera with a pixel size); no mark of this block is one") + (control_marks ? " (every control and check mark has its own Accuracy or takes --film_marker_projection_accuracy)" : " (it has no control or check marks)"));
  if (FlagGiven("bundle_film_tie_accuracy") && !film_tie)
    return BadInput(command, "--film_tie_accuracy is the accuracy of tie marks in film coordinates (FilmX/FilmY) without an Accuracy, on a camera without a pixel size; no mark of this block is one" + (run.tables ? std::string() : " (" + models + ")"));
  if (FlagGiven("bundle_film_marker_projection_accuracy") && !film_control)
    return BadInput(command, "--film_marker_projection_accuracy is the accuracy of control and check marks in film coordinates (FilmX/FilmY) without an Accuracy, on a camera without a pixel size; no mark of this block is one" + (run.tables ? std::string() : " (" + models + ", and so are a model's control marks)"));
  if (FlagGiven("bundle_marker_accuracy") && !surveyed_default)
    return BadInput(command, std::string("--marker_accuracy is the accuracy of control and check point coordinates without AccuracyX/Y/Z; no point of this block is one") + (surveyed ? " (every control and check point has its own AccuracyX/Y/Z)" : run.tables ? " (no control or check point in --points)" : " (no control: --gcp_list, or --points with --crs, give it beside a model)"));
  if (FlagGiven("bundle_camera_accuracy") && !position_default)
    return BadInput(command, std::string("--camera_accuracy is the accuracy of measured camera positions without their own (AccuracyX/Y/Z, a geo.txt's or RTK accuracies); no image of this block has one") + (positions ? " (every camera position has its own accuracy)" : run.tables ? " (no --frames)" : " (no camera positions: --geo, --frames, --images or --model_gps give them beside a model)"));
  if (FlagGiven("bundle_attitude_accuracy") && !attitude)
    return BadInput(command, "--attitude_accuracy is the accuracy of measured attitudes without AccuracyOmega/Phi/Kappa (a frames table's Omega/Phi/Kappa with the tables); no image of this block has one" + (run.tables ? std::string(FLAGS_bundle_frames.empty() ? " (no --frames)" : " (every row of --frames has AccuracyOmega/Phi/Kappa)") : std::string(" (the attitudes of --colmap_model, --opensfm and --bal are unknowns of the adjustment, and those of --geo or --frames beside a model are read and not used)")));
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
    files.pixel_rows = FLAGS_bundle_pixel_rows_up ? PixelRows::kUp : PixelRows::kDown;
    run->context.pixel_rows = files.pixel_rows;
    const Status read = ReadBlock(files, &block);
    if (!read.ok()) return BadInput(command, read.message());
    // Measured centres are priors when an accuracy is known: per row, --camera_accuracy, or the
    // default when a frames table was given.
    run->options.accuracies.camera_positions_are_priors = !FLAGS_bundle_camera_accuracy.empty() || !FLAGS_bundle_frames.empty();
  } else if (!FLAGS_bundle_colmap_model.empty()) {
    const Status read = ReadColmapModel(FLAGS_bundle_colmap_model, &block, &run->colmap_extras, &run->colmap_in_format);
    if (!read.ok()) return BadInput(command, read.message());
  } else if (!FLAGS_bundle_opensfm.empty()) {
    OpenSfmExtras extras;
    const Status read = ReadOpenSfmReconstruction(FLAGS_bundle_opensfm, &block, &extras);
    if (!read.ok()) return BadInput(command, read.message());
    if (!FLAGS_bundle_quiet) {
      std::cerr << "photopose bundle: " << FLAGS_bundle_opensfm << ": " << block.images.size() << " shots, "
                << block.points.size() << " points, " << block.marks.size() << " marks";
      if (extras.further_reconstructions > 0)
        std::cerr << "; " << extras.further_reconstructions << " further reconstructions in the file not read (the first, OpenSfM's largest, is adjusted)";
      if (extras.tracks_of_other_images + extras.tracks_of_other_points > 0)
        std::cerr << "; tracks.csv entries left out: " << extras.tracks_of_other_images << " of images and "
                  << extras.tracks_of_other_points << " of points the reconstruction does not have";
      std::cerr << "\n";
    }
    run->opensfm_extras = std::move(extras);
  } else {
    const Status read = ReadBalProblem(FLAGS_bundle_bal, &block);
    if (!read.ok()) return BadInput(command, read.message());
  }
  if (run->georeference) {
    const int code = GeoreferenceModel(command, run);
    if (code != kGoOn) return code;
  }
  if (const int refused = RefuseFlagsWithoutEffect(command, *run); refused != kGoOn) return refused;
  if (run->georeference) PrintGeoreference(run->georeferenced);
  if (block.images.empty()) return BadInput(command, "the block has no image with marks");
  const Status calibration = BundleAdjustmentConfig::FromCalibrationNames(block, run->calibrate, &run->config);
  if (!calibration.ok()) return BadInput(command, "--calibrate: " + calibration.message());
  // Cameras a COLMAP model could not hold after the self-calibration: refused before any work.
  if (!FLAGS_bundle_out_colmap.empty()) {
    const Status writable = CheckColmapCamerasWritable(block, run->config.calibrated_params);
    if (!writable.ok()) return BadInput(command, "--out_colmap: " + writable.message());
  }
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
  // Two lines, each within kMaxProgressLine for counts up to six digits.
  if (!FLAGS_bundle_quiet) {
    std::cerr << "photopose bundle: initial values: " << initialization.ImagesReport() << "\n"
              << "photopose bundle: initial values: " << initialization.TiePointsReport() << "\n";
  }
  return kGoOn;
}

// sigma0 far above 1 is no small misstatement of accuracies but gross errors (issue 20): above
// this bound the block is searched for them in every group (data snooping: marks, control points,
// camera positions) and, when sigma0 stays above it, the adjustment fails naming the groups and
// the observations to blame (outputs only with --force).
constexpr double kSigma0Bound = 3.0;
constexpr int kSearchRemovals = 50;

// With --estimate_accuracies sigma0 ends near 1 whatever the data: a group estimated at more than
// kGrossErrorFactor times its stated accuracy is the same alarm (tools/report/bundle_report.h).
const BundleGroupStatistics* GroupAbsorbingGrossErrors(const BundleAdjustmentResult& result) {
  for (const BundleGroupStatistics& g : result.groups)
    if (AbsorbsGrossErrors(g)) return &g;
  return nullptr;
}

// An observation of the diagnostics in words: "mark of point 'P' in image 'I'", "control point
// 'C'", "camera_positions of image 'I'".
std::string ObservationName(const Block& block, const BundleObservationDiagnostics& d) {
  if (d.group == kTieMarks || d.group == kControlMarks) {
    const BlockMark& mark = block.marks[d.item];
    return "mark of point '" + block.points[mark.point].id + "' in image '" + block.images[mark.image].name + "'";
  }
  if (d.group == kControlPoints) return "control point '" + block.points[d.item].id + "'";
  return std::string(EnumName(d.group)) + " of image '" + block.images[d.item].name + "'";
}

// The same alarm from the w-test: an observation of what was surveyed (control marks, control
// points, camera positions, attitudes) beyond the block's critical value is a gross error the
// rejection rounds never remove (they take tie marks only). With many tie marks sigma0 stays near 1
// whatever such an error does: one control point 0.5 m off among five moved a simulated block by
// up to 0.5 m (30 of its 2 cm sigmas) at sigma0 1.19. The worst such observation, or nullptr
// (also without diagnostics: --statistics=none).
const BundleObservationDiagnostics* WorstSurveyedRejection(const BundleAdjustmentResult& result) {
  const BundleObservationDiagnostics* worst = nullptr;
  for (const BundleObservationDiagnostics& d : result.observations) {
    if (!d.rejected || d.group == kTieMarks) continue;
    if (worst == nullptr || std::abs(d.normalized) > std::abs(worst->normalized)) worst = &d;
  }
  return worst;
}

// The alarm in words, the one that says the most first: sigma0, an absorbed estimate, the w-test.
// Empty when none is raised.
std::string Sigma0Alarm(const Block& block, const BundleAdjustmentResult& result) {
  std::ostringstream alarm;
  const BundleGroupStatistics* absorbing = GroupAbsorbingGrossErrors(result);
  const BundleObservationDiagnostics* surveyed = WorstSurveyedRejection(result);
  if (result.summary.sigma0 > kSigma0Bound) {
    alarm << "sigma0 " << FormatUnitless(result.summary.sigma0, 2) << " is above "
          << FormatUnitless(kSigma0Bound, 0);
  } else if (absorbing != nullptr) {
    alarm << EnumName(absorbing->group) << " estimated at "
          << FormatUnitless(absorbing->estimated_accuracy.x() / absorbing->stated_accuracy.x(), 1)
          << " times the stated accuracy";
  } else if (surveyed != nullptr) {
    int flagged = 0;
    for (const BundleObservationDiagnostics& d : result.observations)
      flagged += d.rejected && d.group != kTieMarks;
    alarm << "sigma0 " << FormatUnitless(result.summary.sigma0, 2) << ", but the w-test flags "
          << flagged << (flagged == 1 ? " observation" : " observations")
          << " of what was surveyed (control marks, control points, camera positions, attitudes; "
             "worst: "
          << ObservationName(block, *surveyed) << ", |w| "
          << FormatUnitless(std::abs(surveyed->normalized), 1) << " > "
          << FormatUnitless(result.critical_value, 2) << ")";
  }
  return alarm.str();
}

// The search for gross errors: the adjustment again with data snooping in every group. Its result
// replaces the run's when usable; otherwise the reason it failed (the run's result is kept).
std::string SearchForGrossErrors(BundleRun* run) {
  std::cerr << "; searching every group for gross errors (data snooping, at most "
            << kSearchRemovals << " removals)\n";
  BundleAdjustmentOptions search = run->options;
  search.robustness.snoop = true;
  search.robustness.max_snooping_removals = kSearchRemovals;
  BundleAdjustmentResult searched;
  Block block = run->block;
  const Status again = BundleAdjustWithSolver(run->solver, search, run->config, &block, &searched,
                                              nullptr, run->taylor_damping);
  if (CancelRequested()) return "";  // the caller reports it
  if (again.ok() && searched.summary.IsSolutionUsable()) {
    run->block = std::move(block);
    run->result = std::move(searched);
    run->options = search;
    return "";
  }
  const std::string failure =
      again.ok() ? "its adjustment gave no usable solution (" + searched.summary.message + ")"
                 : again.message();
  std::cerr << "photopose bundle: the search for gross errors failed: " << failure
            << "; the adjustment without it is kept\n";
  return failure;
}

// Why the adjustment fails the check: the alarm that stands, the groups furthest beyond their
// stated accuracy and the three worst observations.
std::string Sigma0Failure(const BundleRun& run, const std::string& alarm,
                          const std::string& search_failure, bool searchable) {
  const BundleAdjustmentResult& result = run.result;
  std::ostringstream why;
  if (!search_failure.empty()) {
    why << alarm << " and the search for gross errors failed (" << search_failure
        << "): the stated accuracies do not describe these data, or gross errors are in them";
  } else if (searchable) {
    why << "sigma0 " << FormatUnitless(result.summary.sigma0, 2) << " stays above " << FormatUnitless(kSigma0Bound, 0)
        << " after the search for gross errors: the stated accuracies do not describe these data";
  } else {
    why << alarm
        << " and the block was not searched for gross errors (--statistics=none): the stated "
           "accuracies do not describe these data, or gross errors are in them";
  }
  std::vector<const BundleGroupStatistics*> groups;
  for (const BundleGroupStatistics& g : result.groups)
    if (g.count > 0 && g.ratio > kSigma0Bound) groups.push_back(&g);
  std::sort(groups.begin(), groups.end(),
            [](const auto* a, const auto* b) { return a->ratio > b->ratio; });
  for (size_t k = 0; k < groups.size(); ++k)
    why << (k == 0 ? "; groups to blame: " : ", ") << EnumName(groups[k]->group) << " (RMS/stated " << FormatUnitless(groups[k]->ratio, 2) << ")";
  std::vector<const BundleObservationDiagnostics*> worst;
  for (const BundleObservationDiagnostics& d : result.observations)
    if (std::isfinite(d.normalized)) worst.push_back(&d);
  std::sort(worst.begin(), worst.end(), [](const auto* a, const auto* b) { return std::abs(a->normalized) > std::abs(b->normalized); });
  for (size_t k = 0; k < worst.size() && k < 3; ++k) {
    const BundleObservationDiagnostics& d = *worst[k];
    why << (k == 0 ? "; worst: " : ", ") << ObservationName(run.block, d) << " |w| "
        << FormatUnitless(std::abs(d.normalized), 1);
  }
  why << (FLAGS_bundle_force ? " (outputs written because of --force)" : "; check them, state other accuracies, or give --force to write the outputs anyway");
  return why.str();
}

int CheckSigma0(const char* command, BundleRun* run) {
  if (!run->result.summary.IsSolutionUsable()) return kGoOn;
  const std::string alarm = Sigma0Alarm(run->block, run->result);
  if (alarm.empty()) return kGoOn;
  // Data snooping needs the statistics: with --statistics=none (only sigma0 can give the alarm
  // then) the block is not searched, and the failure below says so.
  const bool searchable = run->options.statistics.covariances != BundleCovarianceMethod::kNone;
  std::string search_failure;  // why the search's own adjustment gave no usable result
  if (!run->options.robustness.snoop) {
    std::cerr << "photopose bundle: " << alarm
              << ": the block disagrees with its stated accuracies by more than noise";
    if (!searchable)
      std::cerr << "; not searched for gross errors (data snooping needs the statistics, and "
                   "--statistics=none computes none)\n";
    else
      search_failure = SearchForGrossErrors(run);
    if (CancelRequested()) return kGoOn;  // the caller reports it
  }
  // A search that could not run leaves the alarm standing, whatever sigma0 is.
  BundleAdjustmentResult& result = run->result;
  if (!(result.summary.sigma0 > kSigma0Bound) && search_failure.empty()) return kGoOn;
  const std::string why = Sigma0Failure(*run, alarm, search_failure, searchable);
  std::cerr << "photopose bundle: " << why << "\n";
  run->exit_code = kExitSomeFailed;
  if (!FLAGS_bundle_force) {
    result.summary.termination = SolverTermination::kFailure;
    result.summary.message = why;
  } else {
    result.summary.message = "FAILED the sigma0 check, written because of --force: " + why;
  }
  return kGoOn;
}

// The adjustment, then the cross-validation when asked.
int AdjustBundleBlock(const char* command, BundleRun* run) {
  BundleAdjustmentResult& result = run->result;
  // A model the block cannot be written as is refused now, not after the adjustment.
  if (!FLAGS_bundle_out_colmap.empty()) {
    const Status writable = CheckAdjustedColmapModelWritable(
        run->block, run->georeference ? &run->georeferenced : nullptr,
        FLAGS_bundle_colmap_model.empty() ? nullptr : &run->colmap_extras);
    if (!writable.ok()) return BadInput(command, "--out_colmap: " + writable.message());
  }
  const Status adjusted = BundleAdjustWithSolver(run->solver, run->options, run->config, &run->block, &result, nullptr, run->taylor_damping);
  if (CancelRequested()) return ReportCancelled(command, "during the adjustment");
  if (!adjusted.ok()) return BadInput(command, adjusted.message());
  const int checked = CheckSigma0(command, run);
  if (checked != kGoOn) return checked;
  if (CancelRequested()) return ReportCancelled(command, "during the search for gross errors");
  if (run->tables && result.summary.datum == BundleDatum::kRelative) {
    return BadInput(command, "no datum: the block has no control points and no camera positions, so it has no ground coordinates to write; give --points with control points or --frames with camera positions");
  }
  if (run->georeference && result.summary.IsSolutionUsable()) {
    const Status evaluated = EvaluateGeoreference(run->block, result, &run->georeferenced);
    if (!evaluated.ok()) return BadInput(command, evaluated.message());
  }
  if (result.summary.IsSolutionUsable() && FLAGS_bundle_cross_validate) {
    const Status cv = CrossValidateControlPoints(run->options, run->config, run->block, result, FLAGS_bundle_threads, &run->cross_validation);
    if (CancelRequested()) return ReportCancelled(command, "during the cross-validation");
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
        std::vector<FrameRecord> frames = BundleFrames(block, result);
        if (run.georeference) PHOTOPOSE_RETURN_IF_ERROR(GeoreferencedFrames(run.georeferenced, &frames));
        return WriteFramesTable(path, frames_options, frames);
      });
    }
    if (status.ok() && !FLAGS_bundle_out_points.empty()) {
      std::string points;
      status = FormatBundlePoints(block, result, run.georeference ? &run.georeferenced : nullptr, &points);
      stage(FLAGS_bundle_out_points, points);
    }
    if (status.ok() && !FLAGS_bundle_out_cameras.empty()) {
      std::vector<FrameCamera> cameras;
      for (const BlockCamera& camera : block.cameras) {
        FrameCamera table = camera.table;
        if (status.ok()) status = SetFrameModelParams(camera.params.data(), &table);
        // A0-B2 back in the user's row convention (the block counts rows down).
        if (status.ok() && FLAGS_bundle_pixel_rows_up) status = AffineWithRowsFlipped(&table);
        cameras.push_back(table);
      }
      if (status.ok())
        status = final_outputs.StageWith(FLAGS_bundle_out_cameras,
                                   [&](const std::string& path) { return WriteCameraTable(path, cameras); });
    }
    if (status.ok() && !FLAGS_bundle_out_colmap.empty()) {
      // The library's one writer (solvers/georeference/adjusted_colmap_model.h): rejected marks
      // out of the tracks; a georeferenced model without its control, georeference.json beside it.
      // The model's files go to their temporaries in pieces as they are formatted (84 MB of text
      // at a thousand images never held whole).
      status = StageAdjustedColmapModel(
          FLAGS_bundle_out_colmap, block, result, run.georeference ? &run.georeferenced : nullptr,
          FLAGS_bundle_colmap_model.empty() ? nullptr : &run.colmap_extras, run.colmap_out_format,
          &final_outputs);
      if (!run.georeference && run.carries_frame_json) {
        // A relative adjustment keeps the model's frame (its gauge moves it by the noise, issue
        // 21): the georeference.json of a model georeferenced before goes with it, or the written
        // model would lose what ties its coordinates to the Earth.
        std::string text;
        if (status.ok()) status = ReadTextFile(FLAGS_bundle_colmap_model + "/" + kGeoreferenceJsonName, &text);
        stage(FLAGS_bundle_out_colmap + "/" + kGeoreferenceJsonName, text);
      }
    }
  }
  if (status.ok()) status = CommitUnlessCancelled(&final_outputs);
  return status;
}

// The closing line: images adjusted, sigma0, check RMSE, files written.
void PrintClosingSummary(const BundleRun& run, bool usable) {
  const BundleAdjustmentResult& result = run.result;
  std::cout << "bundle: " << (usable ? "adjusted " : "not adjusted: ")
            << FormatCount(result.summary.num_images, "image");
  if (std::isfinite(result.summary.sigma0))
    std::cout << ", sigma0 " << FormatUnitless(result.summary.sigma0, 3) << " (unitless)";
  if (result.num_check_points > 0)
    std::cout << ", check RMSE " << FormatLengthWithUnit(result.check_rmse_total_m);
  if (run.georeference && run.georeferenced.evaluated) {
    const GeoreferenceResult& g = run.georeferenced;
    std::cout << "; georeferenced in " << g.out_crs;
    // Each pair of figures in one unit (tools/report/html_kit.h).
    if (g.control_after_adjustment.count > 0) {
      const std::vector<std::string> rmse = FormatLengthsWithUnit({g.control_after_similarity.total_m, g.control_after_adjustment.total_m});
      std::cout << ": control RMSE " << rmse[0] << " after the similarity, " << rmse[1] << " after the adjustment";
    } else {
      std::cout << " by the camera positions alone (no control point)";
    }
    if (g.check_after_adjustment.count > 0) {
      const std::vector<std::string> rmse = FormatLengthsWithUnit({g.check_after_similarity.total_m, g.check_after_adjustment.total_m});
      std::cout << "; check RMSE " << rmse[0] << " -> " << rmse[1];
    }
  }
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

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int RunBundle(int argc, char** argv) {
  const char* const kCommand = "bundle";
  ParsedFlags parsed;
  if (const std::optional<int> done = StartCommand(argc, argv, kUsage, BundleFlags(), &parsed)) return *done;
  BundleRun run;
  run.context.command_line = "photopose bundle";
  for (int i = 0; i < argc; ++i) run.context.command_line += std::string(" ") + argv[i];

  CancelOnSignals();
  OutputFiles outputs;
  int code = CheckInputChoice(kCommand, &run);
  if (code == kGoOn) code = OptionsFromFlags(kCommand, &run);
  if (code == kGoOn) code = DeclareFiles(kCommand, parsed, &run, &outputs);
  const auto read_start = std::chrono::steady_clock::now();
  if (code == kGoOn) code = ReadBundleBlock(kCommand, &run);
  if (code == kGoOn && CancelRequested()) return ReportCancelled(kCommand, "while reading the block");
  if (code != kGoOn) return code;
  run.context.read_seconds = SecondsSince(read_start);
  {
    const ScopedSolving solving;
    const auto initialization_start = std::chrono::steady_clock::now();
    code = InitializeBundleBlock(kCommand, &run);
    run.context.initialization_seconds = SecondsSince(initialization_start);
    if (code == kGoOn && CancelRequested()) return ReportCancelled(kCommand, "while computing the initial values");
    if (code == kGoOn) code = AdjustBundleBlock(kCommand, &run);
    if (code != kGoOn) return code;
  }
  if (CancelRequested()) return ReportCancelled(kCommand, "after the adjustment");
  for (const auto& [label, path] : run.written) run.context.outputs.push_back(path);
  run.context.options = run.options;
  if (run.georeference) run.context.georeference = &run.georeferenced;
  run.context.config = run.config;

  const bool usable = run.result.summary.IsSolutionUsable();
  for (const std::string& line : BundleConsoleLines(run.block, run.result, run.context)) std::cout << line << "\n";
  if (!usable) {
    std::cerr << "photopose bundle: not adjusted: " << run.result.summary.message << "\n";
    run.exit_code = kExitSomeFailed;
  }
  outputs.Abort();
  const auto write_start = std::chrono::steady_clock::now();
  const Status written = WriteBundleOutputs(run, usable);
  if (CancelRequested() && !written.ok()) return ReportCancelled(kCommand, "before writing");
  if (!written.ok()) return BadInput(kCommand, written.message());
  const double write_seconds = SecondsSince(write_start);
  if (!FLAGS_bundle_quiet) std::fprintf(stderr, "photopose bundle: outputs written in %.3f s\n", write_seconds);
  if (run.georeference && !FLAGS_bundle_quiet) {
    std::fprintf(stderr,
                 "photopose bundle: georeference: %.3f s to prepare (CRSs, matching, similarity), "
                 "%.3f s to evaluate; outputs (in %s) written in %.3f s\n",
                 run.georeferenced.prepare_seconds, run.georeferenced.evaluate_seconds,
                 run.georeferenced.out_crs.c_str(), write_seconds);
  }
  PrintClosingSummary(run, usable);
  return run.exit_code;
}

}  // namespace photopose::cli
