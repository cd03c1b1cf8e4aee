// photopose compare: the pose solvers side by side, on Monte-Carlo scenes or on a dataset.
//
// Every flag of this command is registered as compare_<name> so that it can never collide with a
// flag of another subcommand linked into the same executable (--cameras, --seed, --noise_px ... are
// taken); the user writes --<name>, and the parsing, the messages and --help use the user's names.
#include <gflags/gflags.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/io/block_tables.h"
#include "core/io/colmap.h"
#include "core/io/csv.h"
#include "core/io/output_files.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_scene.h"
#include "core/io/tables.h"
#include "solvers/bundle/block_initialization.h"
#include "tools/compare/block_comparison.h"
#include "tools/commands/cli_common.h"
#include "tools/commands/commands.h"
#include "tools/compare/comparison.h"
#include "tools/report/comparison_html.h"
#include "tools/report/comparison_tables.h"
#include "tools/report/html_kit.h"

// Both modes.
DEFINE_string(compare_solvers, "taylor_as_printed,taylor,ceres_analytic,ceres_autodiff",
              "Comma-separated solvers to compare: taylor_as_printed (the seed's Taylor "
              "linearisation with the partial derivatives as printed), taylor (corrected "
              "partials), ceres_analytic and ceres_autodiff (Ceres Levenberg-Marquardt with the "
              "closed-form or the automatic Jacobian), or all.");
DEFINE_string(
    compare_losses, "none,huber",
    "Comma-separated robust losses; every Ceres solver is run with each: none, huber, softl1, "
    "cauchy, arctan, tukey, or all. The single-image Taylor solvers are always plain least "
    "squares; with --scenarios=block (or a dataset block) every solver, Taylor included, runs "
    "with each tie-mark loss (none, huber, cauchy, softl1).");
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
              "the baseline. Each in [0, 1000] px, at most 100 items.");
DEFINE_string(compare_outlier_fractions, "0,0.1,0.2",
              "Monte-Carlo: comma-separated fractions of marks with gross errors of 20 to 200 "
              "pixels, each in [0, 1); the first is the baseline. At most 100 items.");
DEFINE_string(compare_control_points, "20,6",
              "Monte-Carlo: comma-separated numbers of control points per image; the first is the "
              "baseline. Each in [3, 10000], at most 100 items.");
DEFINE_int32(
    compare_check_points, 5,
    "Monte-Carlo: check points per image (not used to solve; their residuals are reported).");
DEFINE_string(
    compare_initial_errors, "5:2,50:10,100:20",
    "Monte-Carlo: comma-separated errors of the approximate frames as POSITION_M:ANGLE_DEG, "
    "uniform in plus or minus that much per axis and per angle; the first is the baseline. "
    "Positions in [0, 1000000] m, angles in [0, 180] degrees, at most 100 items.");
DEFINE_int32(compare_trials, 50, "Monte-Carlo: trials per setting, each a new seeded scene (5 blocks by default with --scenarios=block).");
DEFINE_string(compare_tie_blunders, "0,10",
              "Monte-Carlo, --scenarios=block: comma-separated numbers of tie marks moved by 20 "
              "pixels; the first is the baseline.");
DEFINE_string(compare_tie_points, "600,100",
              "Monte-Carlo, --scenarios=block: comma-separated numbers of tie points per block; the "
              "first is the baseline.");
DEFINE_string(compare_gnss_sigma, "0.03,0.3",
              "Monte-Carlo, --scenarios=block: comma-separated GNSS noise levels, one sigma in "
              "metres horizontally (twice that vertically), also the stated accuracy; the first is "
              "the baseline.");
DEFINE_string(compare_colmap_model, "",
              "Dataset, --scenarios=block: a COLMAP model folder (binary or text) to compare the block solvers "
              "on (or give the tables: --cameras, --marks, --points, --frames).");
DEFINE_int32(compare_block_lines, 3, "Monte-Carlo, --scenarios=block: flight lines per block.");
DEFINE_int32(compare_block_images, 8,
             "Monte-Carlo, --scenarios=block: images per flight line.");
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
DEFINE_double(compare_default_accuracy, 1.0,
              "Dataset: accuracy (one sigma) of pixel marks without an Accuracy value, in pixels "
              "(as photopose resect: the global test holds every image to it).");
DEFINE_double(compare_default_film_accuracy, 5.0,
              "Dataset: accuracy (one sigma) of film marks without an Accuracy value, in "
              "micrometres (as photopose resect).");
DEFINE_bool(compare_pixel_center_origin, false,
            "Dataset: read Column/Row with (0,0) at the centre of the first pixel instead of the "
            "top-left corner.");
DEFINE_bool(compare_pixel_rows_up, false,
            "Dataset (tables): read Row counted up from the bottom edge of the image (Row 0 at the "
            "bottom) in the marks and the camera table's A0-B2, instead of down from the top edge; "
            "needs NRows in the camera table.");

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
    "  photopose compare --scenarios=block [--noise_px=0.5,1] [--tie_blunders=0,10]\n"
    "      [--tie_points=600,100] [--gnss_sigma=0.03,0.3] [--block_lines=3] [--block_images=8]\n"
    "      [--losses=none,huber]   (the block solvers: Taylor as printed, Taylor, Ceres)\n"
    "  photopose compare --scenarios=block --colmap_model=DIR   (or --cameras --marks --points\n"
    "      --frames): the block solvers on one given block, offsets from the Ceres solution\n"
    "      [--outlier_fractions=0,0.2] [--control_points=20,6] [--initial_errors=5:2,100:20]\n"
    "      [--solvers=...] [--losses=none,huber,cauchy] [--csv=F] [--html=F] [--markdown=F]\n"
    "Dataset mode: every solver on real tables, their differences and, optionally, a reference:\n"
    "  photopose compare --cameras=C.csv --points=P.csv --marks=M.csv [--frames=approx.csv]\n"
    "      [--reference=frames.csv] [--rotation=rxryrz|opk|pok] [--csv=F] [--html=F]\n"
    "  photopose compare --cameras=C.csv --gcp_list=gcp_list.txt ...\n\n"
    "Exit status: 0 the comparison ran (solver failures are results, shown in the tables), 2 bad\n"
    "input or usage; Ctrl-C (SIGINT) or SIGTERM cancels the run: nothing is written, 130 or 143\n"
    "(docs/cli.md). docs/comparison.md explains every column.\n";

// The user's flag names that belong to one mode only.
const char* const kMonteCarloFlags[] = {"scenarios",      "noise_px",     "outlier_fractions",
                                        "control_points", "check_points", "initial_errors",
                                        "trials",         "sweep",        "initial",
                                        "success_sigmas", "tie_blunders", "tie_points",
                                        "gnss_sigma",     "block_lines",  "block_images"};
const char* const kDatasetFlags[] = {"frames", "reference", "rotation", "default_accuracy",
                                     "default_film_accuracy",
                                     "pixel_center_origin", "pixel_rows_up"};

// Every numeric flag's range; the comma-separated lists are checked item by item against the
// ranges of their items (kListItemRanges).
const CommandFlags& CompareFlags() {
  static const CommandFlags* const kFlags =
      new CommandFlags{kCommand,
                       "compare_command",
                       kPrefix,
                       {},
                       {{"loss_scale", 0.0, 1000.0, true, false, "standard deviations"},
                        {"confidence", 0.5, 1.0, false, true},
                        {"max_iterations", 1.0, 10000.0},
                        {"seed", 0.0, 18446744073709551615.0},
                        {"threads", 0.0, 1024.0},
                        {"check_points", 0.0, 10000.0},
                        {"trials", 1.0, 100000.0},
                        {"success_sigmas", 0.0, 1e6, true, false},
                        {"block_lines", 1.0, 100.0},
                        {"block_images", 2.0, 100.0},
                        {"default_accuracy", 0.0, 1e6, true, false, "px"},
                        {"default_film_accuracy", 0.0, 1e6, true, false, "um"}}};
  return *kFlags;
}

// Ranges of the items of the list flags (Monte-Carlo mode).
const FlagRange kNoiseItem{"noise_px", 0.0, 1000.0, false, false, "px"};
const FlagRange kOutlierItem{"outlier_fractions", 0.0, 1.0, false, true};
const FlagRange kControlItem{"control_points", 3.0, 10000.0};
const FlagRange kPositionErrorItem{"initial_errors", 0.0, 1e6, false, false, "m (position)"};
const FlagRange kAngleErrorItem{"initial_errors", 0.0, 180.0, false, false, "degrees (angle)"};
const FlagRange kTieBlunderItem{"tie_blunders", 0.0, 100000.0};
const FlagRange kTiePointItem{"tie_points", 10.0, 1000000.0};
const FlagRange kGnssItem{"gnss_sigma", 0.0, 100.0, true, false, "m"};
// Items of one list flag, at most.
constexpr size_t kMaxListItems = 100;
// Solves of one Monte-Carlo run, at most (settings x trials x solver variants): about an hour.
constexpr int64_t kMaxSolves = 10000000;

bool WasGiven(const std::string& name) {
  gflags::CommandLineFlagInfo info;
  return gflags::GetCommandLineFlagInfo((kPrefix + name).c_str(), &info) && !info.is_default;
}

// A comma-separated list of numbers, each within `range` (and whole when `whole`); false with a
// one-line reason naming the flag and the item.
bool ParseList(const std::string& text, const FlagRange& range, bool whole,
               std::vector<double>* values, std::string* why) {
  values->clear();
  for (const std::string& item : SplitCommaList(text)) {
    double value = 0.0;
    std::string reason;
    if (!ParseFiniteNumber(item, &value, &reason) || (whole && value != std::floor(value))) {
      *why = "--" + range.name + ": '" + item + "' is not a" + (whole ? " whole" : "") +
             " number (comma-separated " + (whole ? "whole " : "") + "numbers expected)";
      return false;
    }
    if (!range.Contains(value)) {
      *why = range.Refusal(item);
      return false;
    }
    values->push_back(value);
  }
  if (values->empty()) {
    *why = "--" + range.name + " is empty";
    return false;
  }
  if (values->size() > kMaxListItems) {
    *why = "--" + range.name + " has " + std::to_string(values->size()) + " items; at most " +
           std::to_string(kMaxListItems);
    return false;
  }
  return true;
}

// a * b, saturated at INT64_MAX (both non-negative).
int64_t SaturatedProduct(int64_t a, int64_t b) {
  int64_t product = 0;
  return __builtin_mul_overflow(a, b, &product) ? INT64_MAX : product;
}

// The number of sweep settings MakeSweepSettings would make, computed without making them.
int64_t CountSweepSettings(const MonteCarloOptions& options) {
  const int64_t lists[4] = {static_cast<int64_t>(options.noise_px.size()),
                            static_cast<int64_t>(options.outlier_fractions.size()),
                            static_cast<int64_t>(options.control_points.size()),
                            static_cast<int64_t>(options.initial_errors.size())};
  int64_t per_scenario = 1;  // grid: every combination; axes: the baseline ...
  for (const int64_t n : lists) {
    per_scenario = options.sweep == SweepType::kGrid ? SaturatedProduct(per_scenario, n)
                                                     : per_scenario + (n - 1);  // ... + the others
  }
  return SaturatedProduct(static_cast<int64_t>(options.scenarios.size()), per_scenario);
}

std::string QuoteForShell(const std::string& arg) {
  if (arg.find_first_of(" \t'\"$\\;&|<>*?()") == std::string::npos) return arg;
  std::string quoted = "'";
  for (char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// The files the outputs go to, for the closing summary.
std::string WrittenFiles() {
  std::string files;
  for (const std::string& path : {FLAGS_compare_csv, FLAGS_compare_html, FLAGS_compare_markdown})
    if (!path.empty()) files += (files.empty() ? "" : ", ") + path;
  return files.empty() ? "no file written (see --csv, --html, --markdown)" : "wrote " + files;
}

// The outputs of the run (--csv, --html, --markdown), declared before any work, with its inputs:
// the mode's files and every --flagfile read.
Status DeclareOutputs(std::vector<std::pair<std::string, std::string>> inputs,
                      const ParsedFlags& parsed, OutputFiles* outputs) {
  for (const std::string& flag_file : parsed.flag_files)
    inputs.emplace_back("--flagfile", flag_file);
  for (const auto& [label, path] : inputs)
    PHOTOPOSE_RETURN_IF_ERROR(outputs->AddInput(label, path));
  for (const auto& [label, path] : {std::pair<std::string, std::string>{"--csv", FLAGS_compare_csv},
                                    {"--html", FLAGS_compare_html},
                                    {"--markdown", FLAGS_compare_markdown}}) {
    if (!path.empty()) PHOTOPOSE_RETURN_IF_ERROR(outputs->AddOutput(label, path));
  }
  return Status::Ok();
}

// Writes every requested output, all or nothing.
Status WriteOutputs(const std::string& csv, const std::string& html,
                    const std::vector<TextTable>& tables, const std::vector<std::string>& notes,
                    OutputFiles* outputs) {
  std::string markdown;
  for (const TextTable& table : tables) markdown += RenderMarkdown(table) + "\n";
  for (const std::string& note : notes) markdown += "- " + note + "\n";
  for (const auto& [path, contents] :
       {std::pair<const std::string&, const std::string&>{FLAGS_compare_csv, csv},
        {FLAGS_compare_html, html},
        {FLAGS_compare_markdown, markdown}}) {
    if (!path.empty()) PHOTOPOSE_RETURN_IF_ERROR(outputs->Stage(path, contents));
  }
  return CommitUnlessCancelled(outputs);
}

// Runs one comparison engine (RunMonteCarlo, RunDatasetComparison, RunBlockComparison) as the
// solving phase of the run, with a progress line on stderr counting `items`; SIGINT or SIGTERM
// stops it at the hook's next call (the caller reports it: FailedOrCancelled).
template <typename Options, typename Result>
Status RunWithProgress(const char* items, Status (*run)(const Options&, Result*), Options* options,
                       Result* result) {
  ProgressLine progress("compare", items);
  options->progress = [&progress](size_t done, size_t total) {
    progress(done, total);
    return !CancelRequested();
  };
  Status status;
  {
    const ScopedSolving solving;
    status = run(*options, result);
  }
  options->progress = nullptr;  // `progress` ends here
  return status;
}

// The end of a run whose step failed or was cancelled by a signal: the one line and exit status
// of either.
int FailedOrCancelled(const Status& status, const std::string& when) {
  if (CancelRequested()) return ReportCancelled(kCommand, when);
  return BadInput(kCommand, status.message());
}

// Prints the tables (and the notes under them) on stdout, then writes every requested output.
Status PrintAndWrite(const std::vector<TextTable>& tables, const std::vector<std::string>& notes,
                     const std::string& csv, const std::string& html, OutputFiles* outputs) {
  for (const TextTable& table : tables) std::cout << RenderText(table) << "\n";
  for (const std::string& note : notes) std::cout << WrapText(note, "", "  ");
  return WriteOutputs(csv, html, tables, notes, outputs);
}

// The closing line of a sweep: "compare: 4 settings x 5 blocks x 3 solvers in 1.2 s; wrote F".
void PrintSweepSummary(long long settings, long long trials, const std::string& trial_word,
                       long long solvers, double wall_seconds) {
  std::cout << WrapText("compare: " + FormatCount(settings, "setting") + " x " +
                            FormatCount(trials, trial_word) + " x " +
                            FormatCount(solvers, "solver") + " in " +
                            FormatSignificant(wall_seconds, 3) + " s; " + WrittenFiles(),
                        "", "  ");
}

// The tables named by the dataset flags (--cameras, --points, --marks, --frames, --rotation,
// --pixel_center_origin, --pixel_rows_up); false with the refusal of --rotation.
bool TablesFromFlags(BlockFiles* files, std::string* why) {
  files->cameras = FLAGS_compare_cameras;
  files->points = FLAGS_compare_points;
  files->marks = FLAGS_compare_marks;
  files->frames = FLAGS_compare_frames;
  files->pixel_origin =
      FLAGS_compare_pixel_center_origin ? PixelOrigin::kCenter : PixelOrigin::kCorner;
  files->pixel_rows = FLAGS_compare_pixel_rows_up ? PixelRows::kUp : PixelRows::kDown;
  if (ParseEnum(FLAGS_compare_rotation, &files->rotation)) return true;
  *why = EnumFlagError<RotationConvention>("--rotation", FLAGS_compare_rotation);
  return false;
}

int RunMonteCarloMode(const std::vector<SolverVariant>& solvers, const ResectionOptions& resection,
                      const std::string& command_line, const ParsedFlags& parsed) {
  MonteCarloOptions options;
  options.solvers = solvers;
  options.resection = resection;
  options.scenarios.clear();
  for (const std::string& name : SplitCommaList(FLAGS_compare_scenarios)) {
    Scenario scenario;
    if (name == "block")
      return BadInput(kCommand, "--scenarios: 'block' compares the block solvers and runs alone (--scenarios=block); the single-image scenarios (" +
                                    EnumChoices<Scenario>() + ") go in another run");
    if (!ParseEnum(name, &scenario))
      return BadInput(kCommand, "--scenarios: unknown scenario '" + name + "' (" +
                                    EnumChoices<Scenario>() + ")");
    options.scenarios.push_back(scenario);
  }
  if (options.scenarios.empty()) return BadInput(kCommand, "--scenarios is empty");
  if (options.scenarios.size() > kMaxListItems)
    return BadInput(kCommand,
                    "--scenarios has more than " + std::to_string(kMaxListItems) + " items");
  std::string why;
  std::vector<double> control_points;
  if (!ParseList(FLAGS_compare_noise_px, kNoiseItem, false, &options.noise_px, &why) ||
      !ParseList(FLAGS_compare_outlier_fractions, kOutlierItem, false, &options.outlier_fractions,
                 &why) ||
      !ParseList(FLAGS_compare_control_points, kControlItem, true, &control_points, &why))
    return BadInput(kCommand, why);
  options.control_points.assign(control_points.begin(), control_points.end());
  const Status initial = ParseInitialErrors(FLAGS_compare_initial_errors, &options.initial_errors);
  if (!initial.ok()) return BadInput(kCommand, "--initial_errors: " + initial.message());
  if (options.initial_errors.size() > kMaxListItems)
    return BadInput(kCommand,
                    "--initial_errors has more than " + std::to_string(kMaxListItems) + " items");
  for (const InitialError& error : options.initial_errors) {
    if (!kPositionErrorItem.Contains(error.position_m))
      return BadInput(kCommand, kPositionErrorItem.Refusal(FormatNumber(error.position_m)));
    if (!kAngleErrorItem.Contains(error.angle_deg))
      return BadInput(kCommand, kAngleErrorItem.Refusal(FormatNumber(error.angle_deg)));
  }
  if (!ParseEnum(FLAGS_compare_sweep, &options.sweep))
    return BadInput(kCommand, EnumFlagError<SweepType>("--sweep", FLAGS_compare_sweep));
  if (!ParseEnum(FLAGS_compare_initial, &options.initial))
    return BadInput(kCommand, EnumFlagError<InitialValues>("--initial", FLAGS_compare_initial));
  options.check_points = FLAGS_compare_check_points;
  options.trials = FLAGS_compare_trials;
  options.seed = FLAGS_compare_seed;
  options.success_sigmas = FLAGS_compare_success_sigmas;
  options.num_threads = FLAGS_compare_threads;
  if (const Status valid = Validate(options); !valid.ok()) return BadInput(kCommand, valid.message());
  // Sizes in 64 bits: a grid of long lists times many trials must be refused, not allocated.
  const int64_t settings = CountSweepSettings(options);
  const int64_t solves = SaturatedProduct(SaturatedProduct(settings, options.trials),
                                          static_cast<int64_t>(solvers.size()));
  if (solves > kMaxSolves) {
    return BadInput(
        kCommand,
        "the sweep asks for " +
            (solves == INT64_MAX ? std::string("more than 9e18") : std::to_string(solves)) +
            " solves (" + std::to_string(settings) + " settings x " +
            std::to_string(options.trials) + " trials x " + std::to_string(solvers.size()) +
            " solvers); at most " + std::to_string(kMaxSolves) + " per run");
  }
  OutputFiles outputs;
  const Status declared = DeclareOutputs({}, parsed, &outputs);
  if (!declared.ok()) return BadInput(kCommand, declared.message());

  MonteCarloResult result;
  const Status status = RunWithProgress("trials", &RunMonteCarlo, &options, &result);
  if (!status.ok() || CancelRequested()) return FailedOrCancelled(status, "while comparing");
  const Status written =
      PrintAndWrite(MonteCarloTables(options, result), MonteCarloNotes(options),
                    MonteCarloCsv(result), MonteCarloHtml(options, result, command_line), &outputs);
  if (!written.ok()) return FailedOrCancelled(written, "before writing");
  PrintSweepSummary(static_cast<long long>(result.settings.size()), options.trials, "trial",
                    static_cast<long long>(result.solver_names.size()), result.wall_seconds);
  return kExitSuccess;
}

int RunDatasetMode(const std::vector<SolverVariant>& solvers, const ResectionOptions& resection,
                   const std::string& command_line, const ParsedFlags& parsed) {
  DatasetComparisonOptions options;
  options.solvers = solvers;
  options.reference_path = FLAGS_compare_reference;
  options.num_threads = FLAGS_compare_threads;
  ResectionJobOptions& job = options.job;
  job.input.default_accuracy = FLAGS_compare_default_accuracy;
  job.input.default_film_accuracy_um = FLAGS_compare_default_film_accuracy;
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
  std::string why;
  if (!TablesFromFlags(&job.files, &why)) return BadInput(kCommand, why);
  job.files.gcp_list = FLAGS_compare_gcp_list;
  if (!(FLAGS_compare_default_accuracy > 0.0) || !std::isfinite(FLAGS_compare_default_accuracy))
    return BadInput(kCommand, "--default_accuracy must be a positive number of pixels");
  if (!(FLAGS_compare_default_film_accuracy > 0.0) ||
      !std::isfinite(FLAGS_compare_default_film_accuracy))
    return BadInput(kCommand, "--default_film_accuracy must be a positive number of micrometres");
  if (const Status valid = Validate(options); !valid.ok()) return BadInput(kCommand, valid.message());
  OutputFiles outputs;
  const Status declared =
      DeclareOutputs({{"--cameras", job.files.cameras},
                      {"--points", job.files.points},
                      {"--marks", job.files.marks},
                      {"--gcp_list", job.files.gcp_list},
                      {"--frames", job.files.frames},
                      {"--fiducials", job.files.fiducials},
                      {"--reference", options.reference_path}},
                     parsed, &outputs);
  if (!declared.ok()) return BadInput(kCommand, declared.message());

  DatasetComparisonResult result;
  const Status status = RunWithProgress("solvers", &RunDatasetComparison, &options, &result);
  if (!status.ok() || CancelRequested()) return FailedOrCancelled(status, "while comparing");
  const Status written = PrintAndWrite(DatasetTables(result), {}, DatasetCsv(result),
                                       DatasetHtml(result, command_line), &outputs);
  if (!written.ok()) return FailedOrCancelled(written, "before writing");
  const size_t images = result.summaries.empty() ? 0 : result.summaries.front().images;
  std::cout << WrapText("compare: " + FormatCount(images, "image") + " x " +
                            FormatCount(result.solver_names.size(), "solver") + "; " +
                            WrittenFiles(),
                        "", "  ");
  return kExitSuccess;
}


// --scenarios=block: the block solvers on simulated blocks (tools/compare/block_comparison.h).
int RunBlockMode(const std::string& command_line, const ParsedFlags& parsed) {
  BlockComparisonOptions options;
  const Status variants =
      ParseBlockSolverVariants(FLAGS_compare_solvers, FLAGS_compare_losses, &options.solvers);
  if (!variants.ok()) return BadInput(kCommand, variants.message());
  for (const char* name : {"outlier_fractions", "control_points", "check_points", "initial_errors",
                           "initial", "success_sigmas", "sweep"}) {
    if (WasGiven(name))
      return BadInput(kCommand, std::string("--") + name +
                                    " applies to the single-image scenarios; blocks sweep "
                                    "--noise_px, --tie_blunders, --tie_points, --gnss_sigma");
  }
  std::vector<double> values;
  std::string why;
  if (!ParseList(FLAGS_compare_noise_px, kNoiseItem, false, &options.noise_px, &why))
    return BadInput(kCommand, why);
  if (!ParseList(FLAGS_compare_tie_blunders, kTieBlunderItem, true, &values, &why))
    return BadInput(kCommand, why);
  options.tie_blunders.assign(values.begin(), values.end());
  if (!ParseList(FLAGS_compare_tie_points, kTiePointItem, true, &values, &why))
    return BadInput(kCommand, why);
  options.tie_points.assign(values.begin(), values.end());
  if (!ParseList(FLAGS_compare_gnss_sigma, kGnssItem, false, &options.gnss_sigma_m, &why))
    return BadInput(kCommand, why);
  options.lines = FLAGS_compare_block_lines;
  options.images_per_line = FLAGS_compare_block_images;
  options.trials = WasGiven("trials") ? FLAGS_compare_trials : 5;
  options.seed = FLAGS_compare_seed;
  options.num_threads = FLAGS_compare_threads;
  if (const Status valid = Validate(options); !valid.ok()) return BadInput(kCommand, valid.message());
  const int64_t settings = static_cast<int64_t>(options.noise_px.size() + options.tie_blunders.size() +
                                                options.tie_points.size() +
                                                options.gnss_sigma_m.size()) - 3;
  const int64_t solves = SaturatedProduct(SaturatedProduct(settings, options.trials),
                                          static_cast<int64_t>(options.solvers.size()));
  if (solves > kMaxSolves / 1000) {
    return BadInput(kCommand, "the block sweep asks for " + std::to_string(solves) +
                                  " block adjustments; at most " +
                                  std::to_string(kMaxSolves / 1000) + " per run");
  }
  OutputFiles outputs;
  const Status declared = DeclareOutputs({}, parsed, &outputs);
  if (!declared.ok()) return BadInput(kCommand, declared.message());

  BlockComparisonResult result;
  const Status status = RunWithProgress("blocks", &RunBlockComparison, &options, &result);
  if (!status.ok() || CancelRequested()) return FailedOrCancelled(status, "while comparing");
  const Status written = PrintAndWrite(BlockComparisonTables(options, result), {},
                                       BlockComparisonCsv(result),
                                       BlockComparisonHtml(options, result, command_line), &outputs);
  if (!written.ok()) return FailedOrCancelled(written, "before writing");
  PrintSweepSummary(static_cast<long long>(result.settings.size()), options.trials, "block",
                    static_cast<long long>(result.solver_names.size()), result.wall_seconds);
  return kExitSuccess;
}
// --scenarios=block with a dataset: the block solvers on one given block.
int RunBlockDatasetMode(const std::string& command_line, const ParsedFlags& parsed) {
  BlockDatasetOptions options;
  const Status variants =
      ParseBlockSolverVariants(FLAGS_compare_solvers, FLAGS_compare_losses, &options.solvers);
  if (!variants.ok()) return BadInput(kCommand, variants.message());
  options.num_threads = FLAGS_compare_threads;
  const bool colmap = !FLAGS_compare_colmap_model.empty();
  if (colmap && !(FLAGS_compare_cameras.empty() && FLAGS_compare_marks.empty()))
    return BadInput(kCommand, "give --colmap_model or the tables (--cameras, --marks), not both");
  if (colmap && FLAGS_compare_pixel_rows_up)
    return BadInput(kCommand, "--pixel_rows_up applies to the tables: a COLMAP model defines its own pixels");
  if (!colmap && (FLAGS_compare_cameras.empty() || FLAGS_compare_marks.empty()))
    return BadInput(kCommand, "a block needs --cameras and --marks (or --colmap_model)");
  BlockFiles files;
  std::string why;
  if (!TablesFromFlags(&files, &why)) return BadInput(kCommand, why);
  OutputFiles outputs;
  std::vector<std::pair<std::string, std::string>> inputs = {{"--cameras", files.cameras},
                                                             {"--points", files.points},
                                                             {"--marks", files.marks},
                                                             {"--frames", files.frames}};
  if (colmap) {
    for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"})
      inputs.emplace_back("--colmap_model", FLAGS_compare_colmap_model + "/" + name);
  }
  const Status declared = DeclareOutputs(std::move(inputs), parsed, &outputs);
  if (!declared.ok()) return BadInput(kCommand, declared.message());

  Block block;
  const Status read =
      colmap ? ReadColmapModel(FLAGS_compare_colmap_model, &block) : ReadBlock(files, &block);
  if (!read.ok()) return BadInput(kCommand, read.message());
  BlockDatasetResult result;
  {
    const ScopedSolving solving;
    BlockInitializationSummary initialization;
    const Status initialized =
        InitializeBlock(BlockInitializationOptions(), &block, &initialization);
    if (!initialized.ok()) return BadInput(kCommand, initialized.message());
    if (!initialization.not_oriented.empty()) {
      for (const auto& [image, reason] : initialization.not_oriented)
        std::cerr << "photopose compare: " << block.images[image].name
                  << ": not oriented: " << reason << "\n";
      std::cerr << "photopose compare: " << FormatCount(initialization.not_oriented.size(), "image")
                << " could not be oriented; nothing compared, nothing written\n";
      return kExitSomeFailed;
    }
    if (CancelRequested()) return ReportCancelled(kCommand, "while computing the initial values");
    ProgressLine progress(kCommand, "solvers");
    options.progress = [&progress](size_t done, size_t total) {
      progress(done, total);
      return !CancelRequested();
    };
    const Status status = RunBlockDatasetComparison(options, block, &result);
    options.progress = nullptr;  // `progress` ends here
    if (!status.ok() || CancelRequested()) return FailedOrCancelled(status, "while comparing");
  }
  const Status written = PrintAndWrite({BlockDatasetTable(result)}, {}, BlockDatasetCsv(result),
                                       BlockDatasetHtml(result, command_line), &outputs);
  if (!written.ok()) return FailedOrCancelled(written, "before writing");
  std::cout << "compare: a block of " << result.num_images << " images x "
            << result.solvers.size() << " solvers; " << WrittenFiles() << "\n";
  return kExitSuccess;
}

}  // namespace

int RunCompare(int argc, char** argv) {
  ParsedFlags parsed;
  if (const std::optional<int> done = StartCommand(argc, argv, kUsage, CompareFlags(), &parsed)) return *done;
  std::string command_line = "photopose compare";
  for (int i = 0; i < argc; ++i) command_line += " " + QuoteForShell(argv[i]);
  CancelOnSignals();

  const bool dataset = !FLAGS_compare_cameras.empty() || !FLAGS_compare_points.empty() ||
                       !FLAGS_compare_marks.empty() || !FLAGS_compare_gcp_list.empty();
  if (FLAGS_compare_scenarios == "block" && (dataset || !FLAGS_compare_colmap_model.empty()))
    return RunBlockDatasetMode(command_line, parsed);
  if (!FLAGS_compare_colmap_model.empty())
    return BadInput(kCommand, "--colmap_model is a block: give --scenarios=block with it");
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
  if (!dataset && FLAGS_compare_scenarios == "block") return RunBlockMode(command_line, parsed);
  if (!dataset) {
    for (const char* name : {"tie_blunders", "tie_points", "gnss_sigma", "block_lines", "block_images"})
      if (WasGiven(name))
        return BadInput(kCommand, std::string("--") + name + " applies to --scenarios=block only");
  }
  std::vector<SolverVariant> solvers;
  const Status variants =
      ParseSolverVariants(FLAGS_compare_solvers, FLAGS_compare_losses, &solvers);
  if (!variants.ok()) return BadInput(kCommand, "--solvers/--losses: " + variants.message());
  ResectionOptions resection;
  if (!ParseEnum(FLAGS_compare_ceres_minimizer, &resection.refinement.ceres.minimizer))
    return BadInput(kCommand, EnumFlagError<CeresMinimizer>("--ceres_minimizer",
                                                            FLAGS_compare_ceres_minimizer));
  resection.refinement.loss_scale = FLAGS_compare_loss_scale;
  resection.test.confidence = FLAGS_compare_confidence;
  resection.refinement.ceres.max_iterations = FLAGS_compare_max_iterations;
  resection.refinement.taylor.max_iterations = FLAGS_compare_max_iterations;
  resection.consensus.ransac.seed = FLAGS_compare_seed;
  if (FLAGS_compare_threads < 0) return BadInput(kCommand, "--threads must be >= 0");
  if (const Status valid = Validate(resection); !valid.ok()) return BadInput(kCommand, valid.message());
  return dataset ? RunDatasetMode(solvers, resection, command_line, parsed)
                 : RunMonteCarloMode(solvers, resection, command_line, parsed);
}

}  // namespace photopose::cli
