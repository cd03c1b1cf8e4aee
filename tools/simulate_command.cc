// photopose simulate: a complete synthetic dataset with its truth kept apart.
#include <gflags/gflags.h>

#include <filesystem>
#include <iostream>

#include "core/synthetic_scene.h"
#include "core/tables.h"
#include "tools/cli_common.h"
#include "tools/commands.h"

DEFINE_string(scenario, "nadir", "Scene to simulate: nadir (one vertical aerial frame), oblique (one frame tilted 45 degrees) or uav_block (3 x 4 UAV images with lens distortion).");
DEFINE_uint64(sim_seed, 1, "Seed of the random generator; the same seed and flags give the same dataset. (--seed is accepted as an alias.)");
DEFINE_double(noise_px, 0.5, "Gaussian noise added to every mark, one sigma in pixels.");
DEFINE_double(outlier_fraction, 0.0, "Fraction of the marks replaced by gross errors of 20 to 200 pixels, from 0 up to (not including) 1.");
DEFINE_int32(control_points, 20, "Control points generated per image footprint.");
DEFINE_int32(check_points, 5, "Check points generated per image footprint (Role check: not used to resect, reported as check residuals).");
DEFINE_double(initial_position_error, 5.0, "Error of the approximate frames: uniform in plus or minus this many metres per axis.");
DEFINE_double(initial_angle_error, 2.0, "Error of the approximate frames: uniform in plus or minus this many degrees per angle.");
DEFINE_string(out_dir, "", "Folder to write the dataset into (created when missing): cameras.csv, points.csv, marks.csv, frames_approx.csv, and truth/frames.csv with truth/outliers.csv.");
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

}  // namespace

int RunSimulate(int argc, char** argv) {
  // --seed and --rotation are the names the other commands use; accept them here too.
  std::vector<std::string> renamed;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    for (const char* name : {"seed", "rotation"}) {
      const std::string flag = std::string("--") + name;
      if (arg == flag || arg.rfind(flag + "=", 0) == 0) arg = "--sim_" + arg.substr(2);
    }
    renamed.push_back(arg);
  }
  for (auto& arg : renamed) args.push_back(arg.data());
  bool help = false;
  if (!ParseFlags(static_cast<int>(args.size()), args.data(), "simulate", &help)) return kExitBadInput;
  if (help) {
    PrintHelp(kUsage, "simulate_command");
    return kExitSuccess;
  }
  const auto scenario = ParseScenario(FLAGS_scenario);
  if (!scenario) return BadInput("simulate", "--scenario must be nadir, oblique or uav_block, not '" + FLAGS_scenario + "'");
  const auto rotation = ParseRotationConvention(FLAGS_sim_rotation);
  if (!rotation)
    return BadInput("simulate", std::string("--rotation must be ") + RotationConventionChoices());
  if (FLAGS_out_dir.empty()) return BadInput("simulate", "--out_dir is required");

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

  const std::filesystem::path dir(FLAGS_out_dir);
  std::error_code error;
  std::filesystem::create_directories(dir / "truth", error);
  if (error) return BadInput("simulate", FLAGS_out_dir + ": cannot create: " + error.message());
  FramesTableOptions frames_options;
  frames_options.convention = *rotation;
  frames_options.cameras = &scene.cameras;
  std::string outliers = "Raster,PointID,Outlier\n";
  for (size_t i = 0; i < scene.marks.size(); ++i)
    outliers += scene.marks[i].raster + "," + scene.marks[i].point_id + "," +
                (scene.mark_is_outlier[i] ? "1" : "0") + "\n";
  for (const Status& s :
       {WriteCameraTable((dir / "cameras.csv").string(), scene.cameras),
        WriteGroundPoints((dir / "points.csv").string(), scene.points),
        WriteImageMarks((dir / "marks.csv").string(), scene.marks),
        WriteFramesTable((dir / "frames_approx.csv").string(), frames_options, scene.approximate_frames),
        WriteFramesTable((dir / "truth" / "frames.csv").string(), frames_options, scene.true_frames),
        WriteFileAtomically((dir / "truth" / "outliers.csv").string(), outliers)}) {
    if (!s.ok()) return BadInput("simulate", s.message());
  }
  std::cout << "simulate: " << ScenarioName(*scenario) << ", seed " << FLAGS_sim_seed << ": "
            << scene.true_frames.size() << " images, " << scene.points.size() << " points, "
            << scene.marks.size() << " marks written to " << FLAGS_out_dir << "\n";
  return kExitSuccess;
}

}  // namespace photopose::cli
