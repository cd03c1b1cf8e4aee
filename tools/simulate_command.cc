// photopose simulate: a complete synthetic dataset with its truth kept apart.
#include <gflags/gflags.h>

#include <filesystem>
#include <iostream>

#include "core/output_files.h"
#include "core/synthetic_scene.h"
#include "core/tables.h"
#include "tools/cli_common.h"
#include "tools/commands.h"

DEFINE_string(scenario, "nadir", "Scene to simulate: nadir (one vertical aerial frame), oblique (one frame tilted 45 degrees) or uav_block (3 x 4 UAV images with lens distortion).");
DEFINE_uint64(sim_seed, 1, "Seed of the random generator; the same seed and flags give the same dataset.");
DEFINE_double(noise_px, 0.5, "Gaussian noise added to every mark, one sigma in pixels.");
DEFINE_double(outlier_fraction, 0.0, "Fraction of the marks replaced by gross errors of 20 to 200 pixels, from 0 up to (not including) 1.");
DEFINE_int32(control_points, 20, "Control points generated per image footprint.");
DEFINE_int32(check_points, 5, "Check points generated per image footprint (Role check: not used to resect, reported as check residuals).");
DEFINE_double(initial_position_error, 5.0, "Error of the approximate frames: uniform in plus or minus this many metres per axis.");
DEFINE_double(initial_angle_error, 2.0, "Error of the approximate frames: uniform in plus or minus this many degrees per angle.");
DEFINE_string(out_dir, "", "Folder to write the dataset into (created when missing): cameras.csv, points.csv, marks.csv, frames_approx.csv, and truth/frames.csv with truth/outliers.csv. The folder is replaced as a whole, all or nothing: other files in it are carried over, subfolders other than truth are refused.");
DEFINE_string(sim_rotation, "rxryrz", "Angle convention of the frames tables written: rxryrz (alias seed), opk or pok.");

namespace photopose::cli {
namespace {

constexpr char kUsage[] =
    "photopose simulate: write a synthetic dataset with its truth kept apart.\n\n"
    "Usage: photopose simulate --scenario=nadir|oblique|uav_block --seed=N --noise_px=S\n"
    "                          --outlier_fraction=F --out_dir=D\n\n"
    "Writes D/cameras.csv, D/points.csv, D/marks.csv, D/frames_approx.csv (approximate exterior\n"
    "orientations) and D/truth/frames.csv (true poses), D/truth/outliers.csv (which marks carry a\n"
    "gross error). Resect it with: photopose resect --cameras=D/cameras.csv --points=D/points.csv\n"
    "--marks=D/marks.csv --out=frames.csv\n";

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
                        {"initial_angle_error", 0.0, 180.0, false, false, "degrees"}}};
  return *kFlags;
}

}  // namespace

int RunSimulate(int argc, char** argv) {
  ParsedFlags parsed;
  if (!ParseFlags(argc, argv, SimulateFlags(), &parsed)) return kExitBadInput;
  if (parsed.help) {
    PrintHelp(kUsage, SimulateFlags());
    return kExitSuccess;
  }
  const auto scenario = ParseScenario(FLAGS_scenario);
  if (!scenario)
    return BadInput("simulate",
                    "--scenario must be nadir, oblique or uav_block, not '" + FLAGS_scenario + "'");
  const auto rotation = ParseRotationConvention(FLAGS_sim_rotation);
  if (!rotation)
    return BadInput("simulate", std::string("--rotation must be ") + RotationConventionChoices());
  if (FLAGS_out_dir.empty()) return BadInput("simulate", "--out_dir is required");
  // The dataset's files, for the pre-flight check of the folder before any work.
  std::vector<FolderFile> files = {{"cameras.csv", ""},      {"points.csv", ""},
                                   {"marks.csv", ""},        {"frames_approx.csv", ""},
                                   {"truth/frames.csv", ""}, {"truth/outliers.csv", ""}};
  const Status folder = CheckOutputFolder("--out_dir", FLAGS_out_dir, files);
  if (!folder.ok()) return BadInput("simulate", folder.message());
  // A flag file that is one of the dataset's files would be overwritten by it.
  for (const std::string& flag_file : parsed.flag_files) {
    for (const FolderFile& file : files) {
      std::error_code error;
      if (std::filesystem::equivalent(
              flag_file, std::filesystem::path(FLAGS_out_dir) / file.relative_path, error))
        return BadInput("simulate", "--out_dir=" + FLAGS_out_dir +
                                        " would overwrite the flag file " + flag_file + " with " +
                                        file.relative_path +
                                        "; photopose never writes over an input");
    }
  }

  SyntheticSceneOptions options;
  options.scenario = *scenario;
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
  frames_options.convention = *rotation;
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
  std::cout << "simulate: " << ScenarioName(*scenario) << ", seed " << FLAGS_sim_seed << ": "
            << scene.true_frames.size() << " images, " << scene.points.size() << " points, "
            << scene.marks.size() << " marks written to " << FLAGS_out_dir << "\n";
  return kExitSuccess;
}

}  // namespace photopose::cli
