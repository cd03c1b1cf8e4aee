#include "tools/compare/block_comparison.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <mutex>
#include <sstream>

#include "core/parallel.h"
#include "core/simulation/synthetic_block.h"
#include "core/statistics.h"
#include "solvers/bundle/taylor_bundle.h"
#include "core/io/csv.h"

namespace photopose::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using Clock = std::chrono::steady_clock;


// What one solver gave on one block.
struct TrialOutcome {
  bool success = false;
  std::string failure;
  std::vector<Eigen::Vector3d> centres;  // per image (empty on failure)
  double camera_ssq = 0.0;               // sum over images of |centre - truth|^2
  int num_images = 0;
  double check_ssq = 0.0;
  int num_checks = 0;
  double nees_sum = 0.0;
  int nees_count = 0;
  int iterations = 0;
  double seconds = 0.0;
};

// One solver variant's adjustment of a block, as both comparisons run it.
struct VariantRun {
  bool usable = false;  // a solution to compare
  std::string failure;  // why not
  BundleAdjustmentResult result;
  double seconds = 0.0;  // wall time of the adjustment
};

// Adjusts `block` in place with `variant` on `num_threads` threads. Covariances yes (NEES);
// per-observation tests no: every solver rejects tie marks by their whitened residual beyond
// 4.5 max(1, sigma0) (the rounds both solvers share), the cheaper rule.
VariantRun RunVariant(const BlockSolverVariant& variant, int num_threads, Block* block) {
  BundleAdjustmentOptions options;
  options.solver.num_threads = num_threads;
  options.solver.jacobian = variant.jacobian;
  options.robustness.tie_loss = variant.loss;
  options.statistics.observation_diagnostics = false;
  VariantRun run;
  const Clock::time_point begin = Clock::now();
  const Status status =
      BundleAdjustWithSolver(variant.solver, options, BundleAdjustmentConfig(), block, &run.result);
  run.seconds = std::chrono::duration<double>(Clock::now() - begin).count();
  if (!status.ok()) {
    run.failure = status.message();
  } else if (!run.result.summary.IsSolutionUsable()) {
    run.failure = run.result.summary.message;
  } else {
    run.usable = true;
  }
  return run;
}

TrialOutcome SolveBlock(const BlockSolverVariant& variant, const Block& start,
                        const SyntheticBlockTruth& truth) {
  TrialOutcome out;
  Block block = start;
  const VariantRun run = RunVariant(variant, /*num_threads=*/1, &block);
  const BundleAdjustmentResult& result = run.result;
  out.seconds = run.seconds;
  out.iterations = result.summary.iterations;
  if (!run.usable) {
    out.failure = run.failure;
    return out;
  }
  out.success = true;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const Eigen::Vector3d centre = block.images[i].eo->center_in_ground();
    out.centres.push_back(centre);
    const Eigen::Vector3d error = centre - truth.eo[i].center_in_ground();
    out.camera_ssq += error.squaredNorm();
    ++out.num_images;
    if (i < result.images.size() && result.images[i].has_covariance) {
      const Eigen::Matrix3d C = result.images[i].covariance.topLeftCorner<3, 3>();
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(C);
      if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
        out.nees_sum += error.dot(ldlt.solve(error));
        ++out.nees_count;
      }
    }
  }
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role != PointRole::kCheck || p >= result.points.size()) continue;
    const BundlePointResult& r = result.points[p];
    if (!r.error_m || !point.surveyed_m) continue;
    // The intersected position (surveyed + error) against the true one.
    out.check_ssq += (*point.surveyed_m + *r.error_m - truth.points_m[p]).squaredNorm();
    ++out.num_checks;
  }
  return out;
}

}  // namespace

std::string BlockSolverVariant::Name() const {
  if (solver != PoseSolver::kCeres)
    return EnumName(solver) + (loss == LossType::kNone ? "" : "/" + std::string(EnumName(loss)));
  return std::string("ceres_") + EnumName(jacobian) + "/" + EnumName(loss);
}

Status ParseBlockSolverVariants(const std::string& solvers, const std::string& losses,
                                std::vector<BlockSolverVariant>* variants) {
  variants->clear();
  std::vector<LossType> loss_list;
  for (const std::string& name : SplitCommaList(losses)) {
    if (name.empty()) continue;
    std::vector<LossType> add(std::begin(kBundleTieLosses), std::end(kBundleTieLosses));
    if (name != "all") {
      add.resize(1);
      if (!ParseEnum(name, &add[0]) || !IsBundleTieLoss(add[0]))
        return Status::Error("--losses: '" + name +
                             "' is not a tie-mark loss of the block solvers (" +
                             EnumNameList(kBundleTieLosses) + ")");
    }
    for (const LossType loss : add)
      if (std::find(loss_list.begin(), loss_list.end(), loss) == loss_list.end())
        loss_list.push_back(loss);
  }
  if (loss_list.empty()) loss_list.push_back(LossType::kNone);
  for (const std::string& name : SplitCommaList(solvers)) {
    if (name.empty()) continue;
    const std::vector<std::string> names =
        name == "all"
            ? std::vector<std::string>{"taylor_as_printed", "taylor", "ceres_analytic",
                                       "ceres_autodiff"}
            : std::vector<std::string>{name};
    for (const std::string& n : names) {
      std::vector<BlockSolverVariant> add;
      BlockSolverVariant taylor;
      if ((n == "taylor" || n == "taylor_as_printed") && ParseEnum(n, &taylor.solver)) {
        for (const auto loss : loss_list) {
          taylor.loss = loss;
          add.push_back(taylor);
        }
      } else if (n == "ceres_analytic" || n == "ceres_autodiff") {
        for (const auto loss : loss_list) {
          BlockSolverVariant v;
          v.jacobian = n == "ceres_analytic" ? JacobianType::kAnalytic : JacobianType::kAutodiff;
          v.loss = loss;
          add.push_back(v);
        }
      } else {
        return Status::Error("--solvers: unknown solver '" + n +
                             "' (taylor_as_printed, taylor, ceres_analytic, ceres_autodiff, all)");
      }
      for (const BlockSolverVariant& v : add) {
        const bool seen = std::any_of(variants->begin(), variants->end(),
                                      [&](const BlockSolverVariant& w) { return w.Name() == v.Name(); });
        if (!seen) variants->push_back(v);
      }
    }
  }
  if (variants->empty()) return Status::Error("--solvers: no solver given");
  return Status::Ok();
}

bool BlockComparisonOptions::IsValid(std::string* why) const {
  if (solvers.empty()) return InvalidBecause(why, "no solver");
  if (noise_px.empty() || tie_blunders.empty() || tie_points.empty() || gnss_sigma_m.empty())
    return InvalidBecause(why, "every sweep axis needs at least one value");
  for (const double v : noise_px)
    if (!(v >= 0.0 && v <= 100.0)) return InvalidBecause(why, "noise must be in [0, 100] px");
  for (const int v : tie_blunders)
    if (v < 0 || v > 100000) return InvalidBecause(why, "tie blunders must be in [0, 100000]");
  for (const long long v : tie_points)
    if (v < 10 || v > 1000000) return InvalidBecause(why, "tie points must be in [10, 1000000]");
  for (const double v : gnss_sigma_m)
    if (!(v > 0.0 && v <= 100.0)) return InvalidBecause(why, "GNSS sigma must be in (0, 100] m");
  if (lines < 1 || lines > 100 || images_per_line < 2 || images_per_line > 100)
    return InvalidBecause(why, "a block has 1-100 lines of 2-100 images");
  if (trials < 1 || trials > 10000) return InvalidBecause(why, "trials must be in [1, 10000]");
  if (num_threads < 0 || num_threads > 1024)
    return InvalidBecause(why, "threads must be in [0, 1024]");
  return true;
}

std::string BlockSetting::Label() const {
  std::ostringstream os;
  os << "noise " << noise_px << " px, " << tie_blunders << " tie blunders, " << tie_points
     << " tie points, GNSS " << gnss_sigma_m << " m";
  return os.str();
}

namespace {

// The baseline (the first value of every axis), then each further value of one axis.
std::vector<BlockSetting> BlockSettings(const BlockComparisonOptions& options) {
  BlockSetting base;
  base.axis = "baseline";
  base.noise_px = options.noise_px[0];
  base.tie_blunders = options.tie_blunders[0];
  base.tie_points = options.tie_points[0];
  base.gnss_sigma_m = options.gnss_sigma_m[0];
  std::vector<BlockSetting> settings = {base};
  const auto sweep = [&](const char* axis, const auto& values, auto BlockSetting::*field) {
    for (size_t k = 1; k < values.size(); ++k) {
      BlockSetting s = base;
      s.axis = axis;
      s.*field = values[k];
      settings.push_back(s);
    }
  };
  sweep("noise_px", options.noise_px, &BlockSetting::noise_px);
  sweep("tie_blunders", options.tie_blunders, &BlockSetting::tie_blunders);
  sweep("tie_points", options.tie_points, &BlockSetting::tie_points);
  sweep("gnss_sigma_m", options.gnss_sigma_m, &BlockSetting::gnss_sigma_m);
  return settings;
}

// Simulates the block of one (setting, trial) and runs every solver on it.
Status RunTrial(const BlockComparisonOptions& options, const BlockSetting& setting, int trial,
                std::vector<TrialOutcome>* outcomes) {
  SyntheticBlockOptions o;
  o.seed = options.seed + static_cast<uint64_t>(trial);
  o.num_lines = options.lines;
  o.images_per_line = options.images_per_line;
  o.num_tie_points = setting.tie_points;
  o.mark_sigma_px = setting.noise_px;
  o.mark_accuracy_px = std::max(setting.noise_px, 0.05);  // stated = true (0 noise: 0.05)
  o.gnss_sigma_m =
      Eigen::Vector3d(setting.gnss_sigma_m, setting.gnss_sigma_m, 2.0 * setting.gnss_sigma_m);
  o.num_tie_blunders = setting.tie_blunders;
  o.control_sigma_m = 0.005;
  Block block;
  SyntheticBlockTruth truth;
  const Status made = MakeSyntheticBlock(o, &block, &truth);
  if (!made.ok()) {
    return Status::Error(setting.Label() + ", trial " + std::to_string(trial) + ": " +
                         made.message());
  }
  for (const BlockSolverVariant& variant : options.solvers)
    outcomes->push_back(SolveBlock(variant, block, truth));
  return Status::Ok();
}

// One solver's figures over the trials [first, first + count) of `outcomes` ([job][solver]);
// `reference` is the corrected Taylor solver's index (-1 without it), the baseline of position
// offsets.
BlockSolverStatistics BlockSolverStatisticsOf(
    const std::vector<std::vector<TrialOutcome>>& outcomes, size_t first, size_t count,
    size_t solver, int reference) {
  BlockSolverStatistics st;
  double camera_ssq = 0.0, check_ssq = 0.0, nees = 0.0, iterations = 0.0, seconds = 0.0;
  int cameras = 0, checks = 0;
  for (size_t trial = first; trial < first + count; ++trial) {
    const std::vector<TrialOutcome>& job = outcomes[trial];
    const TrialOutcome& o = job[solver];
    ++st.trials;
    iterations += o.iterations;
    seconds += o.seconds;
    if (!o.success) {
      if (st.failures.size() < 3) st.failures.push_back(o.failure);
      continue;
    }
    ++st.successes;
    camera_ssq += o.camera_ssq;
    cameras += o.num_images;
    check_ssq += o.check_ssq;
    checks += o.num_checks;
    nees += o.nees_sum;
    st.nees_count += o.nees_count;
    if (reference >= 0 && job[reference].success) {
      for (size_t i = 0; i < o.centres.size(); ++i) {
        st.max_position_offset_m = std::max(st.max_position_offset_m,
                                            (o.centres[i] - job[reference].centres[i]).norm());
      }
    }
  }
  st.camera_rmse_m = cameras > 0 ? std::sqrt(camera_ssq / (3.0 * cameras)) : kNaN;
  st.check_rmse_m = checks > 0 ? std::sqrt(check_ssq / (3.0 * checks)) : kNaN;
  st.mean_nees = st.nees_count > 0 ? nees / st.nees_count : kNaN;
  st.nees_interval_95 = NeesInterval{kNaN, kNaN};
  if (st.nees_count > 0) {
    const double dof = 3.0 * st.nees_count;
    st.nees_interval_95 = NeesInterval{ChiSquaredQuantile(0.025, dof) / st.nees_count,
                                       ChiSquaredQuantile(0.975, dof) / st.nees_count};
  }
  st.mean_iterations = iterations / st.trials;
  st.mean_seconds = seconds / st.trials;
  if (reference < 0) st.max_position_offset_m = kNaN;
  return st;
}

// The corrected Taylor solver among `solvers`, the baseline of the "x Taylor" time ratio (and of
// the simulated blocks' position offsets): the one without a loss when it runs without one, else
// its first loss; -1 when it is not compared. The one rule of both comparisons.
int TaylorBaseline(const std::vector<BlockSolverVariant>& solvers) {
  int taylor = -1;
  for (size_t s = 0; s < solvers.size(); ++s) {
    const BlockSolverVariant& v = solvers[s];
    if (v.solver != PoseSolver::kTaylor) continue;
    if (taylor < 0 || (v.loss == LossType::kNone && solvers[taylor].loss != LossType::kNone))
      taylor = static_cast<int>(s);
  }
  return taylor;
}

}  // namespace

Status RunBlockComparison(const BlockComparisonOptions& options, BlockComparisonResult* result) {
  *result = BlockComparisonResult();
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options));
  const Clock::time_point start = Clock::now();
  result->settings = BlockSettings(options);
  for (const BlockSolverVariant& v : options.solvers) result->solver_names.push_back(v.Name());
  const size_t num_settings = result->settings.size();
  const size_t num_solvers = options.solvers.size();
  const size_t trials = static_cast<size_t>(options.trials);
  const size_t jobs = num_settings * trials;
  result->images_per_block = options.lines * options.images_per_line;

  // [job][solver], job = setting * trials + trial.
  std::vector<std::vector<TrialOutcome>> outcomes(jobs);
  std::vector<Status> errors(jobs, Status::Ok());
  std::atomic<size_t> done{0};
  std::atomic<bool> cancelled{false};
  std::mutex progress_mutex;
  ParallelFor(jobs, options.num_threads, [&](size_t job) {
    if (cancelled.load()) return;
    errors[job] = RunTrial(options, result->settings[job / trials], static_cast<int>(job % trials),
                           &outcomes[job]);
    const size_t finished = ++done;
    if (options.progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      if (!options.progress(finished, jobs)) cancelled = true;
    }
  });
  if (cancelled) {
    return Status::Error("cancelled by the progress hook after " + std::to_string(done.load()) +
                         " of " + std::to_string(jobs) + " blocks");
  }
  for (const Status& error : errors) PHOTOPOSE_RETURN_IF_ERROR(error);

  const int taylor = TaylorBaseline(options.solvers);
  result->statistics.assign(num_settings, {});
  for (size_t setting = 0; setting < num_settings; ++setting) {
    std::vector<BlockSolverStatistics>& row = result->statistics[setting];
    for (size_t s = 0; s < num_solvers; ++s)
      row.push_back(BlockSolverStatisticsOf(outcomes, setting * trials, trials, s, taylor));
    for (BlockSolverStatistics& st : row)
      st.time_ratio_to_taylor = taylor >= 0 ? st.mean_seconds / row[taylor].mean_seconds : kNaN;
  }
  result->wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return Status::Ok();
}

Status RunBlockDatasetComparison(const BlockDatasetOptions& options, const Block& block,
                                 BlockDatasetResult* result) {
  *result = BlockDatasetResult();
  if (options.solvers.empty()) return Status::Error("no solver");
  result->num_images = static_cast<int>(block.images.size());
  result->num_points = static_cast<int>(block.points.size());
  result->num_marks = static_cast<int>(block.marks.size());
  std::vector<std::vector<Eigen::Vector3d>> centres(options.solvers.size());
  int reference = -1;
  const int taylor = TaylorBaseline(options.solvers);
  for (size_t s = 0; s < options.solvers.size(); ++s) {
    const BlockSolverVariant& variant = options.solvers[s];
    BlockDatasetSolverSummary summary;
    summary.name = variant.Name();
    Block copy = block;
    const VariantRun run = RunVariant(variant, options.num_threads, &copy);
    const BundleAdjustmentResult& adjusted = run.result;
    summary.seconds = run.seconds;
    summary.iterations = adjusted.summary.iterations;
    if (!run.usable) {
      summary.message = run.failure;
    } else {
      summary.success = true;
      summary.sigma0 = adjusted.summary.sigma0;
      summary.num_check_points = adjusted.num_check_points;
      summary.check_rmse_m = adjusted.num_check_points > 0 ? adjusted.check_rmse_total_m : kNaN;
      for (const BlockImage& image : copy.images) centres[s].push_back(image.eo->center_in_ground());
      if (reference < 0 && variant.solver == PoseSolver::kCeres) reference = static_cast<int>(s);
    }
    result->solvers.push_back(summary);
    if (options.progress && !options.progress(s + 1, options.solvers.size())) {
      return Status::Error("cancelled by the progress hook after " + std::to_string(s + 1) +
                           " of " + std::to_string(options.solvers.size()) + " solvers");
    }
  }
  if (reference < 0) {
    for (size_t s = 0; s < options.solvers.size() && reference < 0; ++s)
      if (result->solvers[s].success) reference = static_cast<int>(s);
  }
  result->reference = reference >= 0 ? result->solvers[reference].name : "";
  for (size_t s = 0; s < result->solvers.size(); ++s) {
    BlockDatasetSolverSummary& summary = result->solvers[s];
    summary.time_ratio_to_taylor = taylor >= 0 && result->solvers[taylor].success
                                       ? summary.seconds / result->solvers[taylor].seconds
                                       : kNaN;
    if (!summary.success || reference < 0) {
      summary.offset_rms_m = summary.offset_max_m = kNaN;
      continue;
    }
    double ssq = 0.0;
    for (size_t i = 0; i < centres[s].size(); ++i) {
      const double d = (centres[s][i] - centres[reference][i]).norm();
      ssq += d * d;
      summary.offset_max_m = std::max(summary.offset_max_m, d);
    }
    summary.offset_rms_m = centres[s].empty() ? kNaN : std::sqrt(ssq / (3.0 * centres[s].size()));
  }
  return Status::Ok();
}

}  // namespace photopose::cli
