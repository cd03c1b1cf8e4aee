#pragma once
// The steps between the rounds of a bundle adjustment, the same for BundleAdjust and
// TaylorBundleAdjust: after a round's statistics (internal/bundle_statistics.h), blunders out (a
// rejection round, or data snooping one observation at a time) or, once none is left, each group's
// sigmas rescaled by its variance component; then the next round. Not part of the library's
// interface.

#include "core/block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/bundle_statistics.h"

namespace photopose::internal {

// What the steps read and change across an adjustment's rounds. `plan` is changed in place (a
// Taylor plan, derived from BundlePlan, keeps its own fields); `result` receives the rejected marks,
// the snooping steps and the variance iterations, and the reason when a step ends the rounds.
struct RoundChanges {
  RoundChanges(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
               const Block& block, BundlePlan* plan, BundleAdjustmentResult* result,
               const GroupVariance* variance);
  const BundleAdjustmentOptions& options;
  const BundleAdjustmentConfig& config;
  const Block& block;
  BundlePlan* plan;
  BundleAdjustmentResult* result;
  const GroupVariance* variance;  // of the last round's statistics
  int rejection_rounds = 0;       // at most (count; 0 when snooping or not rejecting)
  int max_rounds = 1;             // adjustments at most (count)
  // Variance component estimation rescales each group's sigmas by group_scale (unitless).
  double group_scale[kNumBundleGroups] = {1.0, 1.0, 1.0, 1.0, 1.0};
  bool group_estimable[kNumBundleGroups] = {};
  int rejections_done = 0;
};

enum class RoundChange {
  kNone,            // the rounds are over
  kMarksRemoved,    // a blunder step: marks (or, snooping, a prior) out of the plan
  kWeightsChanged,  // the groups rescaled
  kFailed,          // the block no longer holds without the blunders (result->summary says why)
};
// After the statistics of round r (1-based): the next step, in BundleAdjust's order (snooping or a
// rejection round while they find blunders, then variance components). The time spent choosing
// rejected marks is added to result->summary.rejection_seconds. kFailed sets the summary's
// termination and message.
RoundChange ChangeAfterRound(RoundChanges* changes, int r);
// After the last round, with estimate_accuracies: each group's estimated accuracy (the sigmas in
// use) and its standard error, the stated accuracy the user's, or why it was not estimated.
void ReportEstimatedAccuracies(const RoundChanges& changes);

}  // namespace photopose::internal
