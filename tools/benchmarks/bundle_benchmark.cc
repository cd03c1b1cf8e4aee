// Block benchmarks (docs/performance.md, "Bundle adjustment: Taylor against Ceres"): the seed's
// Taylor Gauss-Newton with its hand-assembled reduced normal equations (solvers/bundle/taylor_bundle.h)
// against the Ceres adjustment (solvers/bundle/bundle_adjustment.h, SPARSE_SCHUR, analytic and autodiff
// Jacobians), on the same simulated blocks from the same approximate values, in one run. Reported
// per solve: the whole call and, as counters, the Gauss-Newton / Levenberg-Marquardt iterations,
// the time per iteration and the camera-centre error against the truth, so that speed is never
// bought with quality unseen. Statistics (covariances) are off for both: the solve is timed.
//
// Time per iteration is taken the same way for both solvers, from their progress callbacks: the
// elapsed time from the first report to the last over the iterations between them (Ceres reports
// iteration 0 after its first evaluation; the Taylor solver reports after each correction, so its
// first interval starts at its second report and the average is over the remaining ones).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/taylor_bundle.h"
#include "core/simulation/synthetic_block.h"

namespace photopose {
namespace {

// Block sizes: lines x images per line, tie points.
struct BlockSize {
  int lines, images_per_line, tie_points;
};
const BlockSize kBlockSizes[] = {{3, 4, 144}, {6, 10, 1600}, {10, 15, 4900}};

// A simulated block and its truth.
struct BenchData {
  Block block;
  SyntheticBlockTruth truth;
};

// The generator's nadir block (core/simulation/synthetic_block.h: 24 mm / 4 um / 6000 x 4000 at
// 100 m over 10 m of relief, lines flown alternately, 1 m / 2 deg jitter, its perturbed start) at
// 20 m forward and 30 m side spacing; five control points (the corners and the centre of the
// camera-centre rectangle, 5 mm) and two check points; 0.5 px marks, 3 cm GNSS.
const BenchData& BenchBlock(int size_index) {
  static std::map<int, BenchData> cache;
  auto found = cache.find(size_index);
  if (found != cache.end()) return found->second;
  const SyntheticBlockOptions o = SolverBenchmarkBlockOptions(
      kBlockSizes[size_index].lines, kBlockSizes[size_index].images_per_line,
      kBlockSizes[size_index].tie_points);
  BenchData data;
  const Status status = MakeSyntheticBlock(o, &data.block, &data.truth);
  if (!status.ok()) {
    std::fprintf(stderr, "bundle benchmark: %s\n", status.message().c_str());
    std::abort();
  }
  return cache.emplace(size_index, std::move(data)).first->second;
}

// Per-iteration timing from a progress callback's elapsed times.
struct IterationClock {
  std::vector<double> elapsed;
  void Reset() { elapsed.clear(); }
  void Add(const BundleIterationInfo& info) { elapsed.push_back(info.elapsed_seconds); }
  // Mean seconds per iteration between the first and the last report.
  double PerIteration() const {
    return elapsed.size() < 2 ? NAN : (elapsed.back() - elapsed.front()) / (elapsed.size() - 1);
  }
};

double CentreRmseMm(const BenchData& data, const Block& adjusted) {
  double ssq = 0.0;
  for (size_t i = 0; i < adjusted.images.size(); ++i)
    ssq += (adjusted.images[i].eo->center_in_ground() - data.truth.eo[i].center_in_ground())
               .squaredNorm();
  return 1e3 * std::sqrt(ssq / adjusted.images.size());
}

// Times `adjust(block, progress) -> (iterations, converged)` on fresh copies of the block; the
// copy is outside the timing.
template <typename Adjust>
void TimeAdjustment(benchmark::State& state, const BenchData& data, Adjust adjust) {
  IterationClock clock;
  const std::function<bool(const BundleIterationInfo&)> progress =
      [&clock](const BundleIterationInfo& info) {
        clock.Add(info);
        return true;
      };
  Block block;
  double per_iteration_sum = 0.0;
  int solves = 0;
  std::pair<int, bool> outcome{0, false};
  for (auto _ : state) {
    state.PauseTiming();
    block = data.block;
    clock.Reset();
    state.ResumeTiming();
    outcome = adjust(&block, progress);
    per_iteration_sum += clock.PerIteration();
    ++solves;
  }
  state.counters["images"] = static_cast<double>(data.block.images.size());
  state.counters["marks"] = static_cast<double>(data.block.marks.size());
  state.counters["iterations"] = outcome.first;
  state.counters["ms_per_iteration"] = 1e3 * per_iteration_sum / solves;
  state.counters["centre_rmse_mm"] = CentreRmseMm(data, block);
  state.counters["converged"] = outcome.second ? 1.0 : 0.0;
}

// The Taylor solver's production settings (Levenberg-Marquardt, CHOLMOD supernodal) on one and
// two threads, the lecture's undamped Gauss-Newton with Eigen's LDL^T (its first implementation),
// and the printed partials.
void BM_BundleTaylor(benchmark::State& state, TaylorPartials partials, TaylorDamping damping,
                     TaylorLinearSolver linear_solver, int threads) {
  const BenchData& data = BenchBlock(static_cast<int>(state.range(0)));
  TaylorBundleOptions options;
  options.partials = partials;
  options.damping = damping;
  options.linear_solver = linear_solver;
  options.num_threads = threads;
  options.rejection_threshold = 0.0;
  options.statistics.covariances = BundleCovarianceMethod::kNone;
  if (partials == TaylorPartials::kAsPrinted) options.max_iterations = 200;
  TaylorBundleResult result;
  TimeAdjustment(state, data, [&](Block* block, const auto& progress) {
    options.progress = progress;
    const Status adjusted = TaylorBundleAdjust(options, BundleAdjustmentConfig(), block, &result);
    return std::make_pair(result.summary.iterations,
                          adjusted.ok() && result.summary.IsSolutionUsable());
  });
}
BENCHMARK_CAPTURE(BM_BundleTaylor, corrected, TaylorPartials::kCorrected,
                  TaylorDamping::kLevenbergMarquardt, TaylorLinearSolver::kCholmodSupernodal, 1)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BundleTaylor, corrected_two_threads, TaylorPartials::kCorrected,
                  TaylorDamping::kLevenbergMarquardt, TaylorLinearSolver::kCholmodSupernodal, 2)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BundleTaylor, gauss_newton_eigen_ldlt, TaylorPartials::kCorrected,
                  TaylorDamping::kNone, TaylorLinearSolver::kEigenLdlt, 1)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BundleTaylor, as_printed, TaylorPartials::kAsPrinted, TaylorDamping::kNone,
                  TaylorLinearSolver::kCholmodSupernodal, 1)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);

void BM_BundleCeres(benchmark::State& state, JacobianType jacobian, int threads) {
  const BenchData& data = BenchBlock(static_cast<int>(state.range(0)));
  BundleAdjustmentOptions options;
  options.solver.jacobian = jacobian;
  options.solver.num_threads = threads;
  options.robustness.rejection_threshold = 0.0;
  options.statistics.covariances = BundleCovarianceMethod::kNone;
  BundleAdjustmentResult result;
  TimeAdjustment(state, data, [&](Block* block, const auto& progress) {
    options.solver.progress = progress;
    const Status adjusted = BundleAdjust(options, BundleAdjustmentConfig(), block, &result);
    return std::make_pair(result.summary.iterations,
                          adjusted.ok() && result.summary.IsSolutionUsable());
  });
}
BENCHMARK_CAPTURE(BM_BundleCeres, analytic, JacobianType::kAnalytic, 1)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BundleCeres, autodiff, JacobianType::kAutodiff, 1)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BundleCeres, analytic_all_threads, JacobianType::kAnalytic, 0)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace photopose
