#pragma once
// `photopose compare --scenarios=block`: the block solvers side by side on simulated blocks with
// known truth (core/simulation/synthetic_block.h) — the hand-written Taylor bundle adjustment (corrected and
// as printed, solvers/bundle/taylor_bundle.h) against the Ceres one (analytic and autodiff, each with the
// tie-mark losses asked for, solvers/bundle/bundle_adjustment.h), every solver on the same block from
// the same start, swept over mark noise, tie blunders, tie-point count and GNSS accuracy.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/status.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/resection/pose_refinement.h"
#include "tools/compare/comparison.h"

namespace photopose::cli {

// One block solver configuration.
struct BlockSolverVariant {
  PoseSolver solver = PoseSolver::kCeres;
  JacobianType jacobian = JacobianType::kAnalytic;                    // Ceres only
  LossType loss = LossType::kNone;  // one of kBundleTieLosses
  // "taylor_as_printed", "taylor", "taylor/huber", "ceres_analytic/none", "ceres_autodiff/huber", ...
  std::string Name() const;
};

// Comma-separated solvers (taylor_as_printed, taylor, ceres_analytic, ceres_autodiff; "all") and
// tie-mark losses (none, huber, cauchy, softl1; "all"): every solver runs with each loss ("taylor",
// "taylor/huber", "ceres_analytic/none", ...).
Status ParseBlockSolverVariants(const std::string& solvers, const std::string& losses,
                                std::vector<BlockSolverVariant>* variants);

struct BlockComparisonOptions {
  std::vector<BlockSolverVariant> solvers;
  // Sweep axes; the first value of each is the baseline, and each further value is a setting
  // with the other axes at their baseline.
  std::vector<double> noise_px = {0.5};       // mark noise, one sigma (px)
  std::vector<int> tie_blunders = {0};        // tie marks moved by 20 px (count)
  std::vector<long long> tie_points = {600};  // tie points of the block (count)
  std::vector<double> gnss_sigma_m = {0.03};  // GNSS noise, one sigma horizontally (m; 2x up)
  int lines = 3;                              // flight lines of every block
  int images_per_line = 8;                    // images per line
  int trials = 5;                             // blocks per setting
  uint64_t seed = 1;                          // of the first block; trial t uses seed + t
  int num_threads = 1;                        // blocks solved in parallel
  // Progress: (done, total) blocks; may be empty. Returning false cancels the run: no block
  // starts after it, and RunBlockComparison returns an error that says so (no result).
  std::function<bool(size_t, size_t)> progress;

  bool IsValid(std::string* why) const;
};

// One setting of the sweep.
struct BlockSetting {
  std::string axis;  // "baseline", "noise_px", "tie_blunders", "tie_points", "gnss_sigma_m"
  double noise_px = 0.5;
  int tie_blunders = 0;
  long long tie_points = 600;
  double gnss_sigma_m = 0.03;
  std::string Label() const;
};

// Per setting and solver, over the trials.
struct BlockSolverStatistics {
  int trials = 0;
  int successes = 0;                   // converged (usable) adjustments
  double camera_rmse_m = 0.0;          // RMS over images and trials of |centre - truth| per axis
  double check_rmse_m = 0.0;           // RMS of the check points' errors against their truth
  double mean_nees = 0.0;              // of the camera positions (3 dof): 3 when honest
  int nees_count = 0;                  // images with a covariance
  NeesInterval nees_interval_95;       // of that mean
  double mean_iterations = 0.0;
  double mean_seconds = 0.0;           // per adjustment
  double time_ratio_to_taylor = 0.0;   // mean_seconds / the corrected Taylor's (NaN without it)
  double max_position_offset_m = 0.0;  // largest |centre - corrected Taylor's centre| (m)
  std::vector<std::string> failures;   // the first few reasons
};

struct BlockComparisonResult {
  std::vector<BlockSetting> settings;
  std::vector<std::string> solver_names;
  // [setting][solver]
  std::vector<std::vector<BlockSolverStatistics>> statistics;
  int images_per_block = 0;
  double wall_seconds = 0.0;
};

Status RunBlockComparison(const BlockComparisonOptions& options, BlockComparisonResult* result);


// ------------------------------------------------------------------ dataset mode

// The block solvers on one given block (tables or a COLMAP model), without truth: each solver's
// camera centres against the first Ceres solver's (the reference), check points against their
// surveyed coordinates.
struct BlockDatasetOptions {
  std::vector<BlockSolverVariant> solvers;
  int num_threads = 1;  // of each adjustment
  // Called after each solver with (solvers done, solvers in all); may be empty. Returning false
  // cancels the run: no solver starts after it, and RunBlockDatasetComparison returns an error
  // that says so (no result).
  std::function<bool(size_t, size_t)> progress;
};

struct BlockDatasetSolverSummary {
  std::string name;
  bool success = false;
  std::string message;                 // why not, when not
  double offset_rms_m = 0.0;           // RMS over images and axes of centre - reference centre
  double offset_max_m = 0.0;           // largest |centre - reference centre|
  double check_rmse_m = 0.0;           // total, against the surveyed coordinates (NaN: none)
  int num_check_points = 0;
  double sigma0 = 0.0;
  int iterations = 0;
  double seconds = 0.0;
  double time_ratio_to_taylor = 0.0;   // NaN without the corrected Taylor solver
};

struct BlockDatasetResult {
  int num_images = 0, num_points = 0, num_marks = 0;
  std::string reference;  // name of the reference solver
  std::vector<BlockDatasetSolverSummary> solvers;
};

// `block` must have initial values (solvers/bundle/block_initialization.h).
Status RunBlockDatasetComparison(const BlockDatasetOptions& options, const Block& block,
                                 BlockDatasetResult* result);

}  // namespace photopose::cli
