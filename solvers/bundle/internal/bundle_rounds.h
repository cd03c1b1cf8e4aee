#pragma once
// The steps between the rounds of a bundle adjustment, the same for BundleAdjust and
// TaylorBundleAdjust: after a round's statistics (internal/bundle_statistics.h), blunders out (a
// rejection round, or data snooping one observation at a time) or, once none is left, each group's
// sigmas rescaled by its variance component; then the next round. Not part of the library's
// interface.

#include <Eigen/Core>
#include <string>
#include <vector>

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

// Batch data snooping (BundleRobustnessOptions::snooping_batch). One removal of one-at-a-time
// snooping, predicted from the round's statistics: observations A out is the same as one shift
// parameter per row of A, so (whitened, Q = Qvv of the candidates' rows, internal/
// bundle_statistics.h SnoopingCandidates) the residuals and cofactors of the other rows become
//   v|A = v - Q_.A Q_AA^-1 v_A,   Q|A = Q - Q_.A Q_AA^-1 Q_A.,
// the block's sum of squares drops by v_A^T Q_AA^-1 v_A and its redundancy by the rows of A, so
//   w_i|A = (v|A)_i / (s0|A sqrt((Q|A)_ii)),  s0|A = max(1, sqrt((s0^2 r - v_A^T Q_AA^-1 v_A) /
//   (r - |A|))),
// against k(alpha) of n - |A| tested rows: exact for the linearised block, which is what the next
// round's statistics see but for the nonlinearity. The candidates are taken in that order (the
// largest |w_i|A| of an observation's rows next) while that |w| exceeds k, beats the largest |w|
// of every row outside the candidates scaled by s0 / s0|A (they are assumed uncorrelated with A,
// which the correlation bound below makes true of the candidates themselves) and the next is
// correlated at most kMaxSnoopingCorrelation with each row taken; the first that fails ends the
// round's batch (the next round decides it, as one at a time would).
//
// The conditioned test of the rows of the candidates given `taken` (candidate indices): per row,
// its |w| (NaN when its redundancy number is zero) and its whitened residual; *s0 and *k the yardstick
// and the critical value without them.
struct ConditionedTest {
  Eigen::VectorXd normalized;  // per candidate row, w|A (unitless; NaN on a row of A)
  Eigen::VectorXd residual;    // per candidate row, v|A (whitened)
  double s0 = 1.0;             // max(1, sigma0|A) (unitless)
  double critical_value = 0.0;
};
ConditionedTest ConditionedSnoopingTest(const SnoopingCandidates& candidates,
                                        const std::vector<int>& taken,
                                        const BundleStatisticsOptions& options);
// Two rows more correlated than this (|rho| of their residuals, unitless) are not removed in one
// round: a blunder in one moves the other's residual by rho times its own, so the other's w is
// for the next round to judge. Two marks of one point with three rays correlate ~0.5; marks of
// different points in one image below 0.1 in the simulated blocks of the tests.
constexpr double kMaxSnoopingCorrelation = 0.3;
struct SnoopingChoice {
  int candidate = -1;      // index into the candidates
  int row = -1;            // its row with the largest |w|A| (index into the candidates' rows)
  double normalized = 0.0; // that |w|A| (unitless)
  double residual = 0.0;   // that row's v|A (whitened)
};
// The removals of one round in order, at most max_removals.
std::vector<SnoopingChoice> ChooseSnoopingBatch(const SnoopingCandidates& candidates,
                                                const BundleStatisticsOptions& options,
                                                int max_removals);

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
// A step's notice (snooping not done or stopped, accuracies not estimated, variance components not
// settled) added to a summary's message after what it says already (the statistics' reason when the
// covariances are missing, an earlier notice), once, so that no notice hides another.
void AddRoundNotice(const std::string& notice, std::string* message);
// After the last round, with estimate_accuracies: each group's estimated accuracy (the sigmas in
// use) and its standard error, the stated accuracy the user's, or why it was not estimated.
void ReportEstimatedAccuracies(const RoundChanges& changes);

}  // namespace photopose::internal
