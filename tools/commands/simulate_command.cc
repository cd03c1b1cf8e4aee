// photopose simulate: a complete synthetic dataset with its truth kept apart.
#include <gflags/gflags.h>

#include <filesystem>
#include <iostream>
#include <optional>

#include "core/io/block_tables.h"
#include "core/io/colmap.h"
#include "core/io/csv.h"
#include "core/io/opensfm.h"
#include "core/io/output_files.h"
#include "core/simulation/synthetic_block.h"
#include "core/simulation/synthetic_scene.h"
#include "core/io/tables.h"
#include "solvers/georeference/synthetic_georeference.h"
#include "tools/commands/cli_common.h"
#include "tools/commands/commands.h"

DEFINE_string(scenario, "nadir", "Scene to simulate: nadir (one vertical aerial frame), oblique (one frame tilted 45 degrees), uav_block (3 x 4 UAV images with lens distortion, for resection) or block (an aerial block for bundle adjustment: flight lines, tie points, control and check points, GNSS positions; see the block flags).");
DEFINE_uint64(sim_seed, 1, "Seed of the random generator; the same seed and flags give the same dataset.");
DEFINE_double(noise_px, 0.5, "Gaussian noise added to every mark, one sigma in pixels.");
DEFINE_double(outlier_fraction, 0.0, "Fraction of the marks replaced by gross errors of 20 to 200 pixels, from 0 up to (not including) 1.");
DEFINE_int32(control_points, 20, "Control points generated per image footprint (nadir, oblique, uav_block); with --scenario=block the block's total (default there 8: corners, edge midpoints, centre, interior).");
DEFINE_int32(check_points, 5, "Check points generated per image footprint (Role check: not used to resect, reported as check residuals); with --scenario=block the block's total (default there 6).");
DEFINE_double(initial_position_error, 5.0, "Error of the approximate frames: uniform in plus or minus this many metres per axis (single-image scenarios); with --scenario=block a Gaussian sigma per axis (default there 2 m).");
DEFINE_double(initial_angle_error, 2.0, "Error of the approximate frames: uniform in plus or minus this many degrees per angle (single-image scenarios); with --scenario=block a Gaussian sigma per angle (default there 1 degree).");
DEFINE_string(out_dir, "", "Folder to write the dataset into (created when missing): cameras.csv, points.csv, marks.csv, frames_approx.csv, and truth/frames.csv with truth/outliers.csv (--scenario=block: frames.csv with the start and the GNSS positions, truth/frames.csv, truth/points.csv, truth/blunders.csv, colmap/ with --colmap, and with --georeferenced colmap/, colmap_bin/, opensfm/, geo.txt, gcp_list.txt, gcp_points.csv, gcp_marks.csv). The folder is replaced as a whole, all or nothing: other files in it are carried over, subfolders other than truth are refused.");
DEFINE_int32(lines, 4, "block: flight lines.");
DEFINE_int32(images_per_line, 10, "block: exposures per flight line.");
DEFINE_double(forward_overlap, 0.8, "block: forward overlap of neighbouring images along a line, from 0 up to (not including) 1.");
DEFINE_double(side_overlap, 0.6, "block: side overlap of neighbouring lines, from 0 up to (not including) 1.");
DEFINE_double(flying_height, 100.0, "block: flying height above the mean terrain, in metres (24 mm / 4 um / 6000 x 4000 camera).");
DEFINE_int64(tie_points, 0, "block: number of tie points; 0 draws them at 0.05 per square metre.");
DEFINE_bool(gnss, true, "block: the frames table carries measured camera positions (GNSS) with AccuracyX/Y/Z.");
DEFINE_double(gnss_sigma, 0.03, "block: Gaussian error of the measured camera positions, one sigma in metres horizontally (twice that vertically); also their stated accuracy.");
DEFINE_double(control_sigma, 0.005, "block: Gaussian error of the surveyed control and check point coordinates, one sigma per axis in metres; also their stated accuracy.");
DEFINE_int32(tie_blunders, 0, "block: tie marks moved by 20 pixels (listed in truth/blunders.csv).");
DEFINE_int32(control_blunders, 0, "block: control points whose surveyed position is 0.5 m off.");
DEFINE_int32(gnss_blunders, 0, "block: camera positions 5 m off (needs --gnss).");
DEFINE_bool(benchmark_block, false, "block: the scaling benchmark's block instead (25 lines x 40 images 13 m apart on lines 30 m apart, 120 000 tie points, about 1.7 million marks; docs/performance.md). --lines and --images_per_line resize it (120 tie points per image unless --tie_points is given); the other block flags are ignored.");
DEFINE_bool(colmap, false, "block: also write the block as a COLMAP text model (colmap/cameras.txt, images.txt, points3D.txt) at the perturbed start, tie points included.");
DEFINE_bool(georeferenced, false, "block: issue 21's scene, an SfM reconstruction to georeference: the block as a model in an arbitrary similarity frame (scale 0.05, rotated, shifted), bent by --dome, written as colmap/ (text), colmap_bin/ (binary) and opensfm/ (reconstruction.json, tracks.csv), without control; its GNSS centres in geo.txt (EPSG:4326: longitude, latitude, ellipsoidal height) and its control and check points in UTM zone 32N (EPSG:32632) as gcp_list.txt and as gcp_points.csv + gcp_marks.csv; the block's frame (truth/ and the block's tables) is the local East-North-Up frame at 11.2 E, 47.8 N, 500 m on the WGS84 ellipsoid, shifted horizontally by the mean of the true camera centres. Needs --gnss.");
DEFINE_double(dome, 1.0, "block: with --georeferenced, the height in metres the model loses at the block's edge (the point farthest from the centre; the model's heights lowered by dome * (r / r_max)^2 before the similarity), as a wrong radial distortion bends parallel nadir lines; 0: no bending.");
DEFINE_string(sim_rotation, "rxryrz", "Angle convention of the frames tables written: rxryrz (alias seed), opk or pok.");

namespace photopose::cli {
namespace {

constexpr char kUsage[] =
    "photopose simulate: write a synthetic dataset with its truth kept apart.\n\n"
    "Usage: photopose simulate --scenario=nadir|oblique|uav_block --seed=N --noise_px=S\n"
    "                          --outlier_fraction=F --out_dir=D\n"
    "   or: photopose simulate --scenario=block --lines=4 --images_per_line=10 [--tie_points=N]\n"
    "                          [--gnss_sigma=M] [--tie_blunders=N] [--colmap]\n"
    "                          [--georeferenced [--dome=M]] --out_dir=D\n\n"
    "Writes D/cameras.csv, D/points.csv, D/marks.csv, D/frames_approx.csv (approximate exterior\n"
    "orientations) and D/truth/frames.csv (true poses), D/truth/outliers.csv (which marks carry a\n"
    "gross error). Resect it with: photopose resect --cameras=D/cameras.csv --points=D/points.csv\n"
    "--marks=D/marks.csv --out=frames.csv\n\n"
    "The block scenario writes D/cameras.csv, D/points.csv (control and check points; tie points\n"
    "have marks and no row), D/marks.csv, D/frames.csv (measured camera positions with their\n"
    "accuracy, start angles), D/truth/frames.csv, D/truth/points.csv (every point's true position),\n"
    "D/truth/blunders.csv and, with --colmap, D/colmap/. Adjust it with: photopose bundle\n"
    "--cameras=D/cameras.csv --points=D/points.csv --marks=D/marks.csv --frames=D/frames.csv\n"
    "--out=frames.csv\n\n"
    "With --georeferenced, the SfM scene of issue 21 besides (colmap/, colmap_bin/, opensfm/, geo.txt,\n"
    "gcp_list.txt, gcp_points.csv, gcp_marks.csv). Georeference it with: photopose bundle\n"
    "--colmap_model=D/colmap --geo=D/geo.txt --gcp_list=D/gcp_list.txt --check_points=<the ids the\n"
    "closing line names> --out=frames.csv --out_points=points.csv\n";

const CommandFlags& SimulateFlags() {
  static const CommandFlags* const kFlags =
      new CommandFlags{"simulate",
                       "simulate_command",
                       "",
                       // --seed and --rotation are the names the other commands use.
                       {{"seed", "sim_seed"}, {"rotation", "sim_rotation"}},
                       {{"seed", 0.0, 18446744073709551615.0},
                        {"noise_px", 0.0, 1000.0, false, false, "px"},
                        {"outlier_fraction", 0.0, 1.0, false, true},
                        {"control_points", 0.0, 10000.0},
                        {"check_points", 0.0, 10000.0},
                        {"initial_position_error", 0.0, 1e6, false, false, "m"},
                        {"initial_angle_error", 0.0, 180.0, false, false, "degrees"},
                        {"lines", 1.0, 1000.0},
                        {"images_per_line", 1.0, 1000.0},
                        {"forward_overlap", 0.0, 1.0, false, true},
                        {"side_overlap", 0.0, 1.0, false, true},
                        {"flying_height", 0.0, 1e5, true, false, "m"},
                        {"tie_points", 0.0, 1e7},
                        {"gnss_sigma", 0.0, 1000.0, false, false, "m"},
                        {"control_sigma", 0.0, 1000.0, false, false, "m"},
                        {"tie_blunders", 0.0, 1e6},
                        {"control_blunders", 0.0, 1e4},
                        {"gnss_blunders", 0.0, 1e6},
                        {"dome", -1000.0, 1000.0, false, false, "m"}}};
  return *kFlags;
}

bool IsDefault(const char* gflag) {
  gflags::CommandLineFlagInfo info;
  return !gflags::GetCommandLineFlagInfo(gflag, &info) || info.is_default;
}

// --out_dir checked for the dataset's files: writable, and none of them a flag file of this run
// (photopose never writes over an input).
Status CheckDatasetFolder(const ParsedFlags& parsed, const std::vector<FolderFile>& files) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckOutputFolder("--out_dir", FLAGS_out_dir, files));
  for (const std::string& flag_file : parsed.flag_files) {
    for (const FolderFile& file : files) {
      std::error_code error;
      if (std::filesystem::equivalent(
              flag_file, std::filesystem::path(FLAGS_out_dir) / file.relative_path, error))
        return Status::Error("--out_dir=" + FLAGS_out_dir + " would overwrite the flag file " +
                             flag_file + " with " + file.relative_path +
                             "; photopose never writes over an input");
    }
  }
  return Status::Ok();
}

// The first flag set on the command line that only a block uses, or "": the one rule is the
// flag's help, which starts with "block:".
std::string BlockOnlyFlagSet() {
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  for (const gflags::CommandLineFlagInfo& flag : flags) {
    if (!flag.is_default && flag.filename.find("simulate_command") != std::string::npos &&
        flag.description.rfind("block:", 0) == 0)
      return flag.name;
  }
  return "";
}

// --scenario=block: a synthetic block (core/simulation/synthetic_block.h) as the project's tables, its truth
// and, with --colmap, a COLMAP model, written into --out_dir all or nothing.
// The block's options from the flags; false (and *why) for a flag the chosen block cannot use.
bool BlockOptionsFromFlags(SyntheticBlockOptions* options, std::string* why) {
  if (FLAGS_outlier_fraction != 0.0) {
    *why = "--outlier_fraction is for the single-image scenarios; a block takes --tie_blunders, "
           "--control_blunders and --gnss_blunders";
    return false;
  }
  if (FLAGS_benchmark_block) {
    // The benchmark's layout; --lines and --images_per_line resize it for the growth curve, with
    // the same tie-point density (120 per image) unless --tie_points says otherwise. Its
    // geometry and blunders are fixed: the flags that would change them are refused.
    for (const char* flag : {"forward_overlap", "side_overlap", "flying_height", "control_points",
                             "check_points", "tie_blunders", "control_blunders", "gnss_blunders"}) {
      if (!IsDefault(flag)) {
        *why = std::string("--") + flag + " does not apply to --benchmark_block (its layout is "
               "fixed; --lines, --images_per_line and --tie_points resize it)";
        return false;
      }
    }
    *options = BenchmarkBlockOptions();
    const int default_images = options->num_lines * options->images_per_line;
    if (!IsDefault("lines")) options->num_lines = FLAGS_lines;
    if (!IsDefault("images_per_line")) options->images_per_line = FLAGS_images_per_line;
    options->num_tie_points =
        !IsDefault("tie_points")
            ? FLAGS_tie_points
            : static_cast<int>(static_cast<long long>(options->num_tie_points) *
                               options->num_lines * options->images_per_line / default_images);
  } else {
    options->num_lines = FLAGS_lines;
    options->images_per_line = FLAGS_images_per_line;
    options->forward_overlap = FLAGS_forward_overlap;
    options->side_overlap = FLAGS_side_overlap;
    options->flying_height_m = FLAGS_flying_height;
    options->num_tie_points = FLAGS_tie_points;
    if (!IsDefault("control_points")) options->num_control_points = FLAGS_control_points;
    if (!IsDefault("check_points")) options->num_check_points = FLAGS_check_points;
    options->num_tie_blunders = FLAGS_tie_blunders;
    options->num_control_blunders = FLAGS_control_blunders;
    options->num_gnss_blunders = FLAGS_gnss_blunders;
  }
  options->seed = FLAGS_sim_seed;
  options->mark_sigma_px = FLAGS_noise_px;
  options->control_sigma_m = FLAGS_control_sigma;
  options->gnss = FLAGS_gnss;
  options->gnss_sigma_m =
      Eigen::Vector3d(FLAGS_gnss_sigma, FLAGS_gnss_sigma, 2.0 * FLAGS_gnss_sigma);
  if (!IsDefault("initial_position_error"))
    options->start_position_sigma_m = FLAGS_initial_position_error;
  if (!IsDefault("initial_angle_error")) options->start_angle_sigma_deg = FLAGS_initial_angle_error;
  if (options->num_gnss_blunders > 0 && !options->gnss) {
    *why = "--gnss_blunders needs --gnss";
    return false;
  }
  if (!IsDefault("dome") && !FLAGS_georeferenced) {
    *why = "--dome bends the model of --georeferenced; without it no model is bent";
    return false;
  }
  if (FLAGS_georeferenced && !options->gnss) {
    *why = "--georeferenced needs --gnss (geo.txt holds the measured camera centres)";
    return false;
  }
  const Status valid = options->IsValid();
  if (!valid.ok()) *why = valid.message();
  return valid.ok();
}

// The files of --out_dir (contents empty), checked writable and never over a flag file.
Status SimulatedBlockFiles(const ParsedFlags& parsed, std::vector<FolderFile>* files) {
  *files = {{"cameras.csv", ""},      {"points.csv", ""},       {"marks.csv", ""},
            {"frames.csv", ""},       {"truth/frames.csv", ""}, {"truth/points.csv", ""},
            {"truth/blunders.csv", ""}};
  if (FLAGS_colmap || FLAGS_georeferenced) {
    for (const char* name : {"colmap/cameras.txt", "colmap/images.txt", "colmap/points3D.txt"})
      files->push_back({name, ""});
  }
  if (FLAGS_georeferenced) {
    for (const char* name : {"colmap_bin/cameras.bin", "colmap_bin/images.bin", "colmap_bin/points3D.bin",
                             "opensfm/reconstruction.json", "opensfm/tracks.csv", "geo.txt", "gcp_list.txt",
                             "gcp_points.csv", "gcp_marks.csv"})
      files->push_back({name, ""});
  }
  return CheckDatasetFolder(parsed, *files);
}

// The block and its truth as the contents of *files (in SimulatedBlockFiles' order).
Status FormatSimulatedBlock(const Block& block, const SyntheticBlockTruth& truth,
                            const SyntheticBlockOptions& options, RotationConvention rotation,
                            std::vector<FolderFile>* files) {
  BlockTableWriteOptions table_options;
  table_options.rotation = rotation;
  table_options.write_tie_points = false;  // tie points: marks without a row, as in a survey
  BlockTableText tables;
  PHOTOPOSE_RETURN_IF_ERROR(FormatBlockTables(block, table_options, &tables));
  SyntheticTruthText truth_text;
  PHOTOPOSE_RETURN_IF_ERROR(
      FormatSyntheticBlockTruth(block, truth, options, rotation, &truth_text));
  std::vector<FolderFile>& f = *files;
  f[0].contents = std::move(tables.cameras);
  f[1].contents = std::move(tables.points);
  f[2].contents = std::move(tables.marks);
  f[3].contents = std::move(tables.frames);
  f[4].contents = std::move(truth_text.frames);
  f[5].contents = std::move(truth_text.points);
  f[6].contents = std::move(truth_text.blunders);
  if (FLAGS_colmap && !FLAGS_georeferenced) {
    ColmapModelFiles model;
    PHOTOPOSE_RETURN_IF_ERROR(FormatColmapModel(block, nullptr, ColmapWriteOptions(), &model));
    f[7].contents = std::move(model.cameras);
    f[8].contents = std::move(model.images);
    f[9].contents = std::move(model.points3D);
  }
  return Status::Ok();
}

// --georeferenced: the scene's model and measurements as the contents of files[7..] (in
// SimulatedBlockFiles' order); *check_points: the check point ids, comma-separated.
Status FormatGeoreferenceScene(const SyntheticGeoreference& scene, std::vector<FolderFile>* files,
                               std::string* check_points) {
  std::vector<FolderFile>& f = *files;
  const GeoreferenceInputs& inputs = scene.inputs;
  for (const ColmapFormat format : {ColmapFormat::kText, ColmapFormat::kBinary}) {
    ColmapWriteOptions options;
    options.format = format;
    ColmapModelFiles model;
    PHOTOPOSE_RETURN_IF_ERROR(FormatColmapModel(scene.model, nullptr, options, &model));
    const size_t first = format == ColmapFormat::kText ? 7 : 10;
    f[first].contents = std::move(model.cameras);
    f[first + 1].contents = std::move(model.images);
    f[first + 2].contents = std::move(model.points3D);
  }
  // OpenSfM holds cameras in pixels: the model as COLMAP holds it (its pinhole frame camera a
  // SIMPLE_PINHOLE or PINHOLE), as a user converts one.
  Block colmap_model;
  const ColmapModelFiles colmap_text{ColmapFormat::kText, f[7].contents, f[8].contents, f[9].contents};
  PHOTOPOSE_RETURN_IF_ERROR(ParseColmapModel(colmap_text, "colmap", &colmap_model));
  OpenSfmText opensfm;
  PHOTOPOSE_RETURN_IF_ERROR(FormatOpenSfmReconstruction(colmap_model, nullptr, &opensfm));
  f[13].contents = std::move(opensfm.reconstruction_json);
  f[14].contents = std::move(opensfm.tracks_csv);
  GeoTxt geo;
  geo.crs = inputs.positions_crs;
  for (const CameraPositionMeasurement& m : inputs.positions) {
    GeoTxtRecord record;
    record.image = m.image;
    record.position = m.position;
    if (m.accuracy_m) {
      record.horizontal_accuracy_m = m.accuracy_m->x();
      record.vertical_accuracy_m = m.accuracy_m->z();
    }
    geo.records.push_back(record);
  }
  PHOTOPOSE_RETURN_IF_ERROR(FormatGeoTxt(geo, f[15].relative_path, &f[15].contents));
  GcpList gcp;
  gcp.crs = inputs.control_crs;
  gcp.points = inputs.control_points;
  gcp.marks = inputs.control_marks;
  PHOTOPOSE_RETURN_IF_ERROR(FormatGcpList(gcp, f[16].relative_path, &f[16].contents));
  PHOTOPOSE_RETURN_IF_ERROR(FormatGroundPoints(inputs.control_points, f[17].relative_path, &f[17].contents));
  PHOTOPOSE_RETURN_IF_ERROR(FormatImageMarks(inputs.control_marks, f[18].relative_path, &f[18].contents));
  check_points->clear();
  for (const GroundPoint& point : inputs.control_points)
    if (point.role == PointRole::kCheck) *check_points += (check_points->empty() ? "" : ",") + point.point_id;
  return Status::Ok();
}

// The closing line's end: the folder and every file written into it ("wrote sim: cameras.csv,
// points.csv, ..., truth/frames.csv").
std::string FilesWritten(const std::vector<FolderFile>& files) {
  std::string names;
  for (const FolderFile& file : files)
    names += (names.empty() ? "" : ", ") + file.relative_path;
  return "wrote " + FLAGS_out_dir + ": " + names;
}

int RunSimulateBlock(const ParsedFlags& parsed, RotationConvention rotation) {
  SyntheticBlockOptions options;
  std::string why;
  if (!BlockOptionsFromFlags(&options, &why)) return BadInput("simulate", why);
  std::vector<FolderFile> files;
  Status status = SimulatedBlockFiles(parsed, &files);
  if (!status.ok()) return BadInput("simulate", status.message());
  Block block;
  SyntheticBlockTruth truth;
  status = MakeSyntheticBlock(options, &block, &truth);
  if (status.ok()) status = FormatSimulatedBlock(block, truth, options, rotation, &files);
  std::string georeferenced;  // the closing line's words on the scene
  if (status.ok() && FLAGS_georeferenced) {
    SyntheticGeoreferenceOptions scene_options;
    scene_options.dome_m = FLAGS_dome;
    // The ENU origin at the block's centre (the mean of the true camera centres, horizontally).
    for (const ExteriorOrientation& eo : truth.eo) scene_options.block_origin_m.head<2>() += eo.center_in_ground().head<2>();
    scene_options.block_origin_m /= static_cast<double>(truth.eo.size());
    scene_options.block_origin_m.z() = 0.0;
    SyntheticGeoreference scene;
    std::string check_points;
    status = MakeSyntheticGeoreference(block, truth, scene_options, &scene);
    if (status.ok()) status = FormatGeoreferenceScene(scene, &files, &check_points);
    georeferenced = "; georeferenced: model domed by " + FormatNumber(FLAGS_dome) + " m, GNSS in " +
                    scene.inputs.positions_crs + ", control in " + scene.inputs.control_crs + ", check points " +
                    (check_points.empty() ? "none" : check_points);
  }
  if (status.ok()) status = WriteFolderAtomically("--out_dir", FLAGS_out_dir, files);
  if (!status.ok()) return BadInput("simulate", status.message());
  int controls = 0, checks = 0, ties = 0;
  for (const BlockPoint& point : block.points) {
    controls += point.role == PointRole::kControl;
    checks += point.role == PointRole::kCheck;
    ties += point.role == PointRole::kTie;
  }
  const size_t blunders = truth.blunder_marks.size() + truth.blunder_control_points.size() +
                         truth.blunder_gnss_images.size();
  std::cout << "simulate: block, seed " << FLAGS_sim_seed << ": " << block.images.size()
            << " images, " << ties << " tie points, " << controls << " control and " << checks
            << " check points, " << block.marks.size() << " marks, " << blunders << " blunders"
            << georeferenced << "; " << FilesWritten(files) << "\n";
  return kExitSuccess;
}

}  // namespace

int RunSimulate(int argc, char** argv) {
  ParsedFlags parsed;
  if (const std::optional<int> done = StartCommand(argc, argv, kUsage, SimulateFlags(), &parsed)) return *done;
  RotationConvention rotation = RotationConvention::kSeed;
  if (!ParseEnum(FLAGS_sim_rotation, &rotation))
    return BadInput("simulate", EnumFlagError<RotationConvention>("--rotation", FLAGS_sim_rotation));
  if (FLAGS_out_dir.empty()) return BadInput("simulate", "--out_dir is required");
  if (FLAGS_scenario == "block") return RunSimulateBlock(parsed, rotation);
  Scenario scenario = Scenario::kNadir;
  if (!ParseEnum(FLAGS_scenario, &scenario)) {
    std::string choices;  // the single-image scenarios, then block
    for (const EnumNameEntry<Scenario>& entry : kScenarioNames) choices += std::string(entry.name) + ", ";
    choices.replace(choices.size() - 2, 2, " or block");
    return BadInput("simulate", "--scenario must be " + choices + ", not '" + FLAGS_scenario + "'");
  }
  const std::string block_flag = BlockOnlyFlagSet();
  if (!block_flag.empty()) {
    return BadInput("simulate",
                    "--" + block_flag + " is for --scenario=block, not " + FLAGS_scenario);
  }
  // The dataset's files, for the pre-flight check of the folder before any work.
  std::vector<FolderFile> files = {{"cameras.csv", ""},      {"points.csv", ""},
                                   {"marks.csv", ""},        {"frames_approx.csv", ""},
                                   {"truth/frames.csv", ""}, {"truth/outliers.csv", ""}};
  const Status folder = CheckDatasetFolder(parsed, files);
  if (!folder.ok()) return BadInput("simulate", folder.message());

  SyntheticSceneOptions options;
  options.scenario = scenario;
  options.seed = FLAGS_sim_seed;
  options.noise_px = FLAGS_noise_px;
  options.outlier_fraction = FLAGS_outlier_fraction;
  options.num_control_points = FLAGS_control_points;
  options.num_check_points = FLAGS_check_points;
  options.initial_position_error_m = FLAGS_initial_position_error;
  options.initial_angle_error_deg = FLAGS_initial_angle_error;
  SyntheticScene scene;
  Status status = MakeSyntheticScene(options, &scene);
  if (!status.ok()) return BadInput("simulate", status.message());

  FramesTableOptions frames_options;
  frames_options.convention = rotation;
  frames_options.cameras = &scene.cameras;
  std::string outliers = "Raster,PointID,Outlier\n";
  for (size_t i = 0; i < scene.marks.size(); ++i)
    outliers += scene.marks[i].raster + "," + scene.marks[i].point_id + "," +
                (scene.mark_is_outlier[i] ? "1" : "0") + "\n";
  // Every file is checked and formatted first; then the folder is written all or nothing.
  const auto path = [](const std::string& relative) { return FLAGS_out_dir + "/" + relative; };
  for (const Status& s : {FormatCameraTable(scene.cameras, path("cameras.csv"), &files[0].contents),
                          FormatGroundPoints(scene.points, path("points.csv"), &files[1].contents),
                          FormatImageMarks(scene.marks, path("marks.csv"), &files[2].contents),
                          FormatFramesTable(frames_options, scene.approximate_frames,
                                            path("frames_approx.csv"), &files[3].contents),
                          FormatFramesTable(frames_options, scene.true_frames,
                                            path("truth/frames.csv"), &files[4].contents)}) {
    if (!s.ok()) return BadInput("simulate", s.message());
  }
  files[5].contents = std::move(outliers);
  const Status written = WriteFolderAtomically("--out_dir", FLAGS_out_dir, files);
  if (!written.ok()) return BadInput("simulate", written.message());
  std::cout << "simulate: " << EnumName(scenario) << ", seed " << FLAGS_sim_seed << ": "
            << scene.true_frames.size() << " images, " << scene.points.size() << " points, "
            << scene.marks.size() << " marks; " << FilesWritten(files) << "\n";
  return kExitSuccess;
}

}  // namespace photopose::cli
