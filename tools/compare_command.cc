// photopose compare: the pose solvers side by side, on Monte-Carlo scenes or on a dataset.
//
// Every flag of this command is registered as compare_<name> so that it can never collide with a
// flag of another subcommand linked into the same executable (--cameras, --seed, --noise_px ... are
// taken); the user writes --<name>, and the parsing, the messages and --help use the user's names.
#include <gflags/gflags.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "core/rotation.h"
#include "core/synthetic_scene.h"
#include "core/tables.h"
#include "tools/cli_common.h"
#include "tools/commands.h"
#include "tools/comparison.h"
#include "tools/html_report.h"

// Both modes.
DEFINE_string(compare_solvers, "taylor_as_printed,taylor,ceres_analytic,ceres_autodiff",
              "Comma-separated solvers to compare: taylor_as_printed (the seed's Taylor "
              "linearisation with the partial derivatives as printed), taylor (corrected "
              "partials), ceres_analytic and ceres_autodiff (Ceres Levenberg-Marquardt with the "
              "closed-form or the automatic Jacobian), or all.");
DEFINE_string(
    compare_losses, "none,huber",
    "Comma-separated robust losses; every Ceres solver is run with each: none, huber, softl1, "
    "cauchy, arctan, tukey, or all. The Taylor solvers are always plain least squares.");
DEFINE_string(
    compare_ceres_minimizer, "tiny_solver",
    "How the Ceres solvers minimise each image: tiny_solver (ceres::TinySolver, the robust loss by "
    "iterative reweighting; the library default) or problem (ceres::Problem and ceres::Solve).");
DEFINE_double(compare_loss_scale, 2.0,
              "Scale of the robust losses in standard deviations of the marks: residuals beyond "
              "it are down-weighted.");
DEFINE_double(compare_confidence, 0.999,
              "Confidence of the outlier decisions of every solver, between 0 and 1: the "
              "consensus threshold (the square root of the chi-square(2) quantile, 3.72 standard "
              "deviations at 0.999) and the data-snooping test.");
DEFINE_int32(compare_max_iterations, 50, "Largest number of iterations of every solver.");
DEFINE_uint64(compare_seed, 1,
              "Monte-Carlo: trial t of every setting uses the scene seed seed + t (photopose "
              "simulate --seed makes the same scene). Dataset: the seed of the consensus "
              "sampling (images with few marks try every minimal sample and ignore it).");
DEFINE_int32(compare_threads, 1,
             "Threads: Monte-Carlo trials or dataset images run in parallel; 0 uses all cores. One "
             "thread gives the steadiest timings.");
DEFINE_string(compare_csv, "",
              "Write the results as CSV to this file: one row per setting and solver (Monte-Carlo) "
              "or per image and solver (dataset).");
DEFINE_string(compare_html, "",
              "Write a self-contained HTML report (tables and SVG plots, no script, no network) to "
              "this file.");
DEFINE_string(compare_markdown, "", "Write the tables as Markdown to this file.");
// Monte-Carlo mode.
DEFINE_string(
    compare_scenarios, "nadir,oblique",
    "Monte-Carlo: comma-separated scenarios of photopose simulate: nadir, oblique, uav_block.");
DEFINE_string(compare_noise_px, "0.5,0,1,2",
              "Monte-Carlo: comma-separated image noise levels, one sigma in pixels; the first is "
              "the baseline.");
DEFINE_string(compare_outlier_fractions, "0,0.1,0.2",
              "Monte-Carlo: comma-separated fractions of marks with gross errors of 20 to 200 "
              "pixels, each in [0, 1); the first is the baseline.");
DEFINE_string(compare_control_points, "20,6",
              "Monte-Carlo: comma-separated numbers of control points per image (at least 3); the "
              "first is the baseline.");
DEFINE_int32(
    compare_check_points, 5,
    "Monte-Carlo: check points per image (not used to solve; their residuals are reported).");
DEFINE_string(
    compare_initial_errors, "5:2,50:10,100:20",
    "Monte-Carlo: comma-separated errors of the approximate frames as POSITION_M:ANGLE_DEG, "
    "uniform in plus or minus that much per axis and per angle; the first is the baseline.");
DEFINE_int32(compare_trials, 50, "Monte-Carlo: trials per setting, each a new seeded scene.");
DEFINE_string(compare_sweep, "axes",
              "Monte-Carlo: axes (vary one list at a time, the others at their first value) or "
              "grid (every combination).");
DEFINE_string(
    compare_initial, "frames",
    "Monte-Carlo: initial values of every solver: frames (the scene's approximate frames, the "
    "initial-error sweep) or ransac (LO-RANSAC per image, the same for every solver).");
DEFINE_double(
    compare_success_sigmas, 10.0,
    "Monte-Carlo: a solve succeeds when its position error is at most this many design standard "
    "deviations (sqrt of the trace of the position block of (J^T P J)^-1 at the true pose).");
// Dataset mode.
DEFINE_string(
    compare_cameras, "",
    "Dataset: camera table (CSV, ArcGIS frame-camera schema). Giving it selects the dataset mode.");
DEFINE_string(
    compare_points, "",
    "Dataset: ground points (CSV: PointID, X, Y, Z in metres, optional Role control|check).");
DEFINE_string(compare_marks, "",
              "Dataset: image marks (CSV: Raster, PointID, Column and Row in pixels or FilmX and "
              "FilmY in micrometres, optional Accuracy in pixels).");
DEFINE_string(compare_gcp_list, "",
              "Dataset: OpenDroneMap gcp_list.txt instead of --points and --marks.");
DEFINE_string(compare_frames, "",
              "Dataset: optional frames table of approximate exterior orientations, the initial "
              "values of every solver (otherwise RANSAC, the same for every solver).");
DEFINE_string(compare_reference, "",
              "Dataset: optional frames table of a reference orientation; every solver's "
              "difference to it is reported.");
DEFINE_string(compare_rotation, "rxryrz",
              "Dataset: angle convention of the frames tables read and of the angles printed: "
              "rxryrz (alias seed), opk or pok; the camera's AngleDirection applies.");
DEFINE_double(compare_default_accuracy, 0.0,
              "Dataset: accuracy (one sigma) of marks without an Accuracy value, in the mark's "
              "own unit (pixels, or micrometres for film marks); 0 leaves it unstated and sigma0 "
              "comes from the data.");
DEFINE_bool(compare_pixel_center_origin, false,
            "Dataset: read Column/Row with (0,0) at the centre of the first pixel instead of the "
            "top-left corner.");

namespace photopose::cli {
namespace {

constexpr char kCommand[] = "compare";
constexpr char kPrefix[] = "compare_";

constexpr char kUsage[] =
    "photopose compare: the pose solvers side by side (Taylor as printed, Taylor corrected, Ceres\n"
    "analytic and autodiff, each Ceres solver with the requested robust losses).\n\n"
    "Monte-Carlo mode (no --cameras): synthetic scenes swept over noise, outliers, control points\n"
    "and initial error, every solver on the same data from the same initial values, against "
    "truth:\n"
    "  photopose compare [--scenarios=nadir,oblique,uav_block] [--noise_px=0.5,0,1] [--trials=N]\n"
    "      [--outlier_fractions=0,0.2] [--control_points=20,6] [--initial_errors=5:2,100:20]\n"
    "      [--solvers=...] [--losses=none,huber,cauchy] [--csv=F] [--html=F] [--markdown=F]\n"
    "Dataset mode: every solver on real tables, their differences and, optionally, a reference:\n"
    "  photopose compare --cameras=C.csv --points=P.csv --marks=M.csv [--frames=approx.csv]\n"
    "      [--reference=frames.csv] [--rotation=rxryrz|opk|pok] [--csv=F] [--html=F]\n"
    "  photopose compare --cameras=C.csv --gcp_list=gcp_list.txt ...\n\n"
    "Exit status: 0 the comparison ran (solver failures are results, shown in the tables), 2 bad\n"
    "input or usage. docs/comparison.md explains every column.\n";

// The user's flag names that belong to one mode only.
const char* const kMonteCarloFlags[] = {"scenarios",      "noise_px",     "outlier_fractions",
                                        "control_points", "check_points", "initial_errors",
                                        "trials",         "sweep",        "initial",
                                        "success_sigmas"};
const char* const kDatasetFlags[] = {"frames", "reference", "rotation", "default_accuracy",
                                     "pixel_center_origin"};

bool IsOurFlag(const std::string& name, gflags::CommandLineFlagInfo* info) {
  return gflags::GetCommandLineFlagInfo((kPrefix + name).c_str(), info) &&
         info->filename.find("compare_command") != std::string::npos;
}

bool WasGiven(const std::string& name) {
  gflags::CommandLineFlagInfo info;
  return IsOurFlag(name, &info) && !info.is_default;
}

void PrintCompareHelp() {
  std::cout << kUsage << "\n" << kConventionsHelp << "\nFlags:\n";
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  for (const auto& flag : flags) {
    if (flag.filename.find("compare_command") == std::string::npos) continue;
    if (flag.name.rfind(kPrefix, 0) != 0) continue;
    std::cout << "  --" << flag.name.substr(sizeof(kPrefix) - 1) << " (" << flag.type
              << ", default: \"" << flag.default_value << "\")\n      " << flag.description << "\n";
  }
  std::cout << "  --flagfile=F\n      Reads further flags, one per line, from the file F.\n";
}

bool IsHelp(const std::string& arg) {
  return arg == "--help" || arg == "-h" || arg == "--helpfull" || arg == "-help";
}

// Parses --name=value, --name value, --bool_flag, --nobool_flag and --flagfile=F (one flag per
// line,
// "--name value" allowed, '#' comments) into the compare_<name> flags, like ParseFlags does for the
// other subcommands but with the user's flag names in every message. Prints one line and returns
// false on an unknown flag, a bad value, a stray argument or an unreadable flag file.
bool ParseCompareFlags(const std::vector<std::string>& args, bool* help, int depth = 0) {
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (IsHelp(arg)) {
      *help = true;
      continue;
    }
    if (arg.size() < 2 || arg[0] != '-') {
      BadInput(kCommand, "unexpected argument '" + arg + "' (flags are --name=value)");
      return false;
    }
    const std::string body = arg.substr(arg.rfind("--", 0) == 0 ? 2 : 1);
    const size_t equals = body.find('=');
    std::string name = body.substr(0, equals);
    const bool has_value = equals != std::string::npos;
    std::string value = has_value ? body.substr(equals + 1) : "";
    if (name == "flagfile") {
      if (!has_value && i + 1 < args.size()) value = args[++i];
      std::ifstream file(value);
      if (value.empty() || !file || depth > 8) {
        BadInput(kCommand, "cannot read the flag file '" + value + "'");
        return false;
      }
      std::vector<std::string> lines;
      for (std::string line; std::getline(file, line);) {
        const size_t begin = line.find_first_not_of(" \t\r");
        if (begin == std::string::npos || line[begin] == '#') continue;
        line = line.substr(begin, line.find_last_not_of(" \t\r") - begin + 1);
        const size_t space = line.find_first_of(" \t");
        if (space != std::string::npos && line.find('=') > space) {
          // "--name value"
          lines.push_back(line.substr(0, space));
          lines.push_back(line.substr(line.find_first_not_of(" \t", space)));
        } else {
          lines.push_back(line);
        }
      }
      if (!ParseCompareFlags(lines, help, depth + 1)) return false;
      continue;
    }
    gflags::CommandLineFlagInfo info;
    if (!IsOurFlag(name, &info)) {
      if (name.rfind("no", 0) == 0 && !has_value && IsOurFlag(name.substr(2), &info) &&
          info.type == "bool") {
        name = name.substr(2);
        value = "false";
      } else {
        BadInput(kCommand, "unknown flag --" + name + " (see photopose compare --help)");
        return false;
      }
    } else if (!has_value) {
      if (info.type == "bool") {
        value = "true";
      } else if (i + 1 < args.size()) {
        value = args[++i];
      } else {
        BadInput(kCommand, "flag --" + name + " needs a value");
        return false;
      }
    }
    if (gflags::SetCommandLineOption((kPrefix + name).c_str(), value.c_str()).empty()) {
      BadInput(kCommand,
               "invalid value '" + value + "' for --" + name + " (" + info.type + " expected)");
      return false;
    }
  }
  return true;
}

bool ParseDoubles(const std::string& text, std::vector<double>* values) {
  values->clear();
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) {
    char* end = nullptr;
    const double value = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(value)) return false;
    values->push_back(value);
  }
  return !values->empty();
}

bool ParseInts(const std::string& text, std::vector<int>* values) {
  values->clear();
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) {
    char* end = nullptr;
    const long value = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || value < -1000000 || value > 1000000) return false;
    values->push_back(static_cast<int>(value));
  }
  return !values->empty();
}

std::string QuoteForShell(const std::string& arg) {
  if (arg.find_first_of(" \t'\"$\\;&|<>*?()") == std::string::npos) return arg;
  std::string quoted = "'";
  for (char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// A progress line on stderr for runs longer than a couple of seconds: the first after
// kFirstSeconds, then every kEverySeconds, and the last when the run is done (if any was printed).
// Thread-safe: the Monte-Carlo workers call it.
class ProgressLine {
 public:
  explicit ProgressLine(std::string items) : items_(std::move(items)) {}
  void operator()(size_t done, size_t total) {
    constexpr double kFirstSeconds = 2.0, kEverySeconds = 5.0;
    const std::lock_guard<std::mutex> lock(mutex_);
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const bool last = done == total;
    if (last ? !printed_ : elapsed < next_seconds_) return;
    next_seconds_ = std::max(elapsed, kFirstSeconds) + kEverySeconds;
    printed_ = true;
    char line[160];
    std::snprintf(line, sizeof(line), "photopose compare: %zu of %zu %s (%.0f%%), %.0f s", done,
                  total, items_.c_str(), 100.0 * done / std::max<size_t>(total, 1), elapsed);
    std::cerr << line;
    if (!last && done > 0)
      std::cerr << ", about " << static_cast<long>(elapsed * (total - done) / done + 0.5)
                << " s left";
    std::cerr << "\n";
  }

 private:
  std::string items_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  double next_seconds_ = 2.0;
  bool printed_ = false;
};

// The files the outputs go to, for the closing summary.
std::string WrittenFiles() {
  std::string files;
  for (const std::string& path : {FLAGS_compare_csv, FLAGS_compare_html, FLAGS_compare_markdown})
    if (!path.empty()) files += (files.empty() ? "" : ", ") + path;
  return files.empty() ? "no file written (see --csv, --html, --markdown)" : "wrote " + files;
}

Status WriteOutputs(const std::string& csv, const std::string& html,
                    const std::vector<TextTable>& tables, const std::vector<std::string>& notes) {
  if (!FLAGS_compare_csv.empty()) {
    const Status status = WriteFileAtomically(FLAGS_compare_csv, csv);
    if (!status.ok()) return status;
  }
  if (!FLAGS_compare_html.empty()) {
    const Status status = WriteFileAtomically(FLAGS_compare_html, html);
    if (!status.ok()) return status;
  }
  if (!FLAGS_compare_markdown.empty()) {
    std::string markdown;
    for (const TextTable& table : tables) markdown += RenderMarkdown(table) + "\n";
    for (const std::string& note : notes) markdown += "- " + note + "\n";
    const Status status = WriteFileAtomically(FLAGS_compare_markdown, markdown);
    if (!status.ok()) return status;
  }
  return Status::Ok();
}

int RunMonteCarloMode(const std::vector<SolverVariant>& solvers, const ResectionOptions& resection,
                      const std::string& command_line) {
  MonteCarloOptions options;
  options.solvers = solvers;
  options.resection = resection;
  options.scenarios.clear();
  std::stringstream names(FLAGS_compare_scenarios);
  for (std::string name; std::getline(names, name, ',');) {
    const auto scenario = ParseScenario(name);
    if (!scenario)
      return BadInput(kCommand,
                      "--scenarios: unknown scenario '" + name + "' (nadir, oblique or uav_block)");
    options.scenarios.push_back(*scenario);
  }
  if (options.scenarios.empty()) return BadInput(kCommand, "--scenarios is empty");
  if (!ParseDoubles(FLAGS_compare_noise_px, &options.noise_px))
    return BadInput(kCommand, "--noise_px must be comma-separated numbers, not '" +
                                  FLAGS_compare_noise_px + "'");
  if (!ParseDoubles(FLAGS_compare_outlier_fractions, &options.outlier_fractions))
    return BadInput(kCommand, "--outlier_fractions must be comma-separated numbers, not '" +
                                  FLAGS_compare_outlier_fractions + "'");
  if (!ParseInts(FLAGS_compare_control_points, &options.control_points))
    return BadInput(kCommand, "--control_points must be comma-separated integers, not '" +
                                  FLAGS_compare_control_points + "'");
  const Status initial = ParseInitialErrors(FLAGS_compare_initial_errors, &options.initial_errors);
  if (!initial.ok()) return BadInput(kCommand, "--initial_errors: " + initial.message());
  if (FLAGS_compare_sweep == "axes") {
    options.sweep = SweepType::kAxes;
  } else if (FLAGS_compare_sweep == "grid") {
    options.sweep = SweepType::kGrid;
  } else {
    return BadInput(kCommand, "--sweep must be axes or grid, not '" + FLAGS_compare_sweep + "'");
  }
  if (FLAGS_compare_initial == "frames") {
    options.initial = InitialValues::kApproximateFrames;
  } else if (FLAGS_compare_initial == "ransac") {
    options.initial = InitialValues::kRansac;
  } else {
    return BadInput(kCommand,
                    "--initial must be frames or ransac, not '" + FLAGS_compare_initial + "'");
  }
  options.check_points = FLAGS_compare_check_points;
  options.trials = FLAGS_compare_trials;
  options.seed = FLAGS_compare_seed;
  options.success_sigmas = FLAGS_compare_success_sigmas;
  options.num_threads = FLAGS_compare_threads;
  std::string why;
  if (!options.IsValid(&why)) return BadInput(kCommand, why);

  ProgressLine progress("trials");
  options.progress = [&progress](size_t done, size_t total) { progress(done, total); };
  MonteCarloResult result;
  const Status status = RunMonteCarlo(options, &result);
  if (!status.ok()) return BadInput(kCommand, status.message());
  const std::vector<TextTable> tables = MonteCarloTables(options, result);
  for (const TextTable& table : tables) std::cout << RenderText(table) << "\n";
  const std::vector<std::string> notes = MonteCarloNotes(options);
  for (const std::string& note : notes) std::cout << note << "\n";
  const Status written = WriteOutputs(MonteCarloCsv(result),
                                      MonteCarloHtml(options, result, command_line), tables, notes);
  if (!written.ok()) return BadInput(kCommand, written.message());
  std::cout << "compare: " << result.settings.size() << " settings x " << options.trials
            << " trials x " << result.solver_names.size() << " solvers in " << result.wall_seconds
            << " s; " << WrittenFiles() << "\n";
  return kExitSuccess;
}

int RunDatasetMode(const std::vector<SolverVariant>& solvers, const ResectionOptions& resection,
                   const std::string& command_line) {
  DatasetComparisonOptions options;
  options.solvers = solvers;
  options.reference_path = FLAGS_compare_reference;
  options.num_threads = FLAGS_compare_threads;
  ResectionJobOptions& job = options.job;
  job.files.cameras = FLAGS_compare_cameras;
  job.files.points = FLAGS_compare_points;
  job.files.marks = FLAGS_compare_marks;
  job.files.gcp_list = FLAGS_compare_gcp_list;
  job.files.frames = FLAGS_compare_frames;
  job.input.default_accuracy = FLAGS_compare_default_accuracy;
  job.files.pixel_origin =
      FLAGS_compare_pixel_center_origin ? PixelOrigin::kCenter : PixelOrigin::kCorner;
  job.resection = resection;
  if (FLAGS_compare_cameras.empty())
    return BadInput(kCommand, "--cameras is required in the dataset mode");
  if (FLAGS_compare_gcp_list.empty() &&
      (FLAGS_compare_points.empty() || FLAGS_compare_marks.empty()))
    return BadInput(kCommand,
                    "--points and --marks (or --gcp_list) are required in the dataset mode");
  if (!FLAGS_compare_gcp_list.empty() &&
      (!FLAGS_compare_points.empty() || !FLAGS_compare_marks.empty()))
    return BadInput(kCommand, "--gcp_list replaces --points and --marks; give one or the other");
  const auto rotation = ParseRotationConvention(FLAGS_compare_rotation);
  if (!rotation)
    return BadInput(kCommand, std::string("--rotation must be ") + RotationConventionChoices() +
                                  ", not '" + FLAGS_compare_rotation + "'");
  job.files.rotation = *rotation;
  if (!(FLAGS_compare_default_accuracy >= 0.0) || !std::isfinite(FLAGS_compare_default_accuracy))
    return BadInput(kCommand, "--default_accuracy must be positive (or 0 for none)");
  std::string why;
  if (!options.IsValid(&why)) return BadInput(kCommand, why);

  ProgressLine progress("solvers");
  options.progress = [&progress](size_t done, size_t total) { progress(done, total); };
  DatasetComparisonResult result;
  const Status status = RunDatasetComparison(options, &result);
  if (!status.ok()) return BadInput(kCommand, status.message());
  const std::vector<TextTable> tables = DatasetTables(result);
  for (const TextTable& table : tables) std::cout << RenderText(table) << "\n";
  const Status written =
      WriteOutputs(DatasetCsv(result), DatasetHtml(result, command_line), tables, {});
  if (!written.ok()) return BadInput(kCommand, written.message());
  const size_t images = result.summaries.empty() ? 0 : result.summaries.front().images;
  std::cout << "compare: " << images << " images x " << result.solver_names.size()
            << " solvers; " << WrittenFiles() << "\n";
  return kExitSuccess;
}

}  // namespace

int RunCompare(int argc, char** argv) {
  bool help = false;
  if (!ParseCompareFlags(std::vector<std::string>(argv, argv + argc), &help)) return kExitBadInput;
  if (help) {
    PrintCompareHelp();
    return kExitSuccess;
  }
  std::string command_line = "photopose compare";
  for (int i = 0; i < argc; ++i) command_line += " " + QuoteForShell(argv[i]);

  const bool dataset = !FLAGS_compare_cameras.empty() || !FLAGS_compare_points.empty() ||
                       !FLAGS_compare_marks.empty() || !FLAGS_compare_gcp_list.empty();
  const std::vector<std::string> other_mode_flags =
      dataset ? std::vector<std::string>(std::begin(kMonteCarloFlags), std::end(kMonteCarloFlags))
              : std::vector<std::string>(std::begin(kDatasetFlags), std::end(kDatasetFlags));
  for (const std::string& name : other_mode_flags) {
    if (WasGiven(name))
      return BadInput(kCommand, "--" + name + " applies to the " +
                                    (dataset ? "Monte-Carlo mode only (drop --cameras, --points, "
                                               "--marks, --gcp_list)"
                                             : "dataset mode only (give --cameras and the marks)"));
  }
  std::vector<SolverVariant> solvers;
  const Status parsed = ParseSolverVariants(FLAGS_compare_solvers, FLAGS_compare_losses, &solvers);
  if (!parsed.ok()) return BadInput(kCommand, "--solvers/--losses: " + parsed.message());
  ResectionOptions resection;
  const auto minimizer = ParseCeresMinimizer(FLAGS_compare_ceres_minimizer);
  if (!minimizer)
    return BadInput(kCommand, "--ceres_minimizer must be tiny_solver or problem, not '" +
                                  FLAGS_compare_ceres_minimizer + "'");
  resection.refinement.ceres.minimizer = *minimizer;
  resection.refinement.loss_scale = FLAGS_compare_loss_scale;
  resection.test.confidence = FLAGS_compare_confidence;
  resection.refinement.ceres.max_iterations = FLAGS_compare_max_iterations;
  resection.refinement.taylor.max_iterations = FLAGS_compare_max_iterations;
  resection.consensus.ransac.seed = FLAGS_compare_seed;
  if (FLAGS_compare_threads < 0) return BadInput(kCommand, "--threads must be >= 0");
  std::string why;
  if (!resection.IsValid(&why)) return BadInput(kCommand, why);
  for (const auto& [flag, path] :
       {std::pair<std::string, std::string>{"--csv", FLAGS_compare_csv},
        {"--html", FLAGS_compare_html},
        {"--markdown", FLAGS_compare_markdown}}) {
    const Status folder = CheckOutputFolder(flag, path);
    if (!folder.ok()) return BadInput(kCommand, folder.message());
  }
  return dataset ? RunDatasetMode(solvers, resection, command_line)
                 : RunMonteCarloMode(solvers, resection, command_line);
}

}  // namespace photopose::cli
