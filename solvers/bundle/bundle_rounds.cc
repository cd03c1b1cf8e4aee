// The steps between the rounds of a bundle adjustment (internal/bundle_rounds.h): rejection
// rounds, data snooping, variance components.
#include "solvers/bundle/internal/bundle_rounds.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/units.h"

namespace photopose::internal {
namespace {

// Why a step that needs the covariances (snooping's w-test, a group's redundancy) could not take
// them: the statistics turned off, or their computation failed (the statistics' own message, "no
// covariances: ...", says why).
std::string CovariancesMissing(const BundleAdjustmentOptions& options) {
  return options.statistics.covariances == BundleCovarianceMethod::kNone
             ? "the statistics are turned off (covariances none)"
             : "they were not computed";
}

// Removes one observation found by data snooping: a mark, or the whole prior of a control point,
// camera position or attitude.
void RemoveObservation(const BundleObservationDiagnostics& d, BundlePlan* plan) {
  switch (d.group) {
    case kTieMarks:
    case kControlMarks:
      plan->mark_used[d.item] = 0;
      break;
    case kControlPoints:
      plan->point_prior[d.item] = 0;
      break;
    case kCameraPositions:
      plan->image_prior[d.item] = 0;
      break;
    case kAttitudes:
      plan->image_attitude[d.item] = 0;
      break;
    default:
      break;
  }
}

// Scales every sigma of group g by `factor`.
void ScaleGroup(int g, double factor, BundlePlan* plan) {
  switch (g) {
    case kTieMarks:
    case kControlMarks:
      for (size_t m = 0; m < plan->mark_sigma.size(); ++m)
        if (plan->mark_group[m] == g) plan->mark_sigma[m] *= factor;
      break;
    case kControlPoints:
      for (auto& sigma : plan->point_sigma) sigma *= factor;
      break;
    case kCameraPositions:
      for (auto& sigma : plan->image_prior_sigma) sigma *= factor;
      break;
    case kAttitudes:
      for (auto& sigma : plan->image_attitude_sigma) sigma *= factor;
      break;
    default:
      break;
  }
}

// Data snooping: removes the observation with the largest rejected |w|, if the block still holds
// without it. Returns whether one was removed.
bool SnoopOne(RoundChanges* a, int r) {
  BundleAdjustmentResult* result = a->result;
  if (result->observations.empty() && !result->groups.empty())
    AddRoundNotice("data snooping not done: its w-test needs the covariances; " +
                       CovariancesMissing(a->options),
                   &result->summary.message);
  const BundleObservationDiagnostics* worst = nullptr;
  for (const BundleObservationDiagnostics& d : result->observations) {
    if (!d.rejected) continue;
    if (worst == nullptr || std::abs(d.normalized) > std::abs(worst->normalized)) worst = &d;
  }
  if (worst == nullptr ||
      static_cast<int>(result->snooping.size()) >= a->options.robustness.max_snooping_removals)
    return false;
  BundlePlan trial = *a->plan;
  RemoveObservation(*worst, &trial);
  const Status still = RecheckBundlePlan(a->config, a->block, &trial);
  if (!still.ok()) {
    AddRoundNotice("data snooping stopped: removing " + std::string(EnumName(worst->group)) +
                       " #" + std::to_string(worst->item) + " would leave " + still.message(),
                   &result->summary.message);
    return false;
  }
  result->snooping.push_back(
      {worst->group, worst->item, worst->axis, std::abs(worst->normalized), worst->residual, r});
  *a->plan = std::move(trial);
  return true;
}

// Batch data snooping: the removals ChooseSnoopingBatch predicts from this round's statistics,
// each checked to leave a block that holds. Returns whether any was removed; false with the
// candidates not computed (the caller then snoops one at a time).
bool SnoopBatch(RoundChanges* a, int r, bool* computed) {
  BundleAdjustmentResult* result = a->result;
  const SnoopingCandidates& candidates = a->variance->snooping;
  *computed = candidates.computed;
  if (!candidates.computed) return false;
  const int left = a->options.robustness.max_snooping_removals -
                   static_cast<int>(result->snooping.size());
  const std::vector<SnoopingChoice> choices =
      ChooseSnoopingBatch(candidates, a->options.statistics, left);
  const auto record = [&](const SnoopingChoice& choice) {
    const BundleObservationDiagnostics& d =
        result->observations[candidates.observation[choice.row]];
    result->snooping.push_back(
        {d.group, d.item, d.axis, choice.normalized, choice.residual * d.sigma, r});
  };
  // All at once when the block holds without them (one copy and check of the plan, not one per
  // removal), else one by one up to the first it cannot lose.
  BundlePlan trial = *a->plan;
  for (const SnoopingChoice& choice : choices)
    RemoveObservation(result->observations[candidates.observation[choice.row]], &trial);
  if (!choices.empty() && RecheckBundlePlan(a->config, a->block, &trial).ok()) {
    for (const SnoopingChoice& choice : choices) record(choice);
    *a->plan = std::move(trial);
    return true;
  }
  trial = *a->plan;
  int removed = 0;
  for (const SnoopingChoice& choice : choices) {
    const BundleObservationDiagnostics& d =
        result->observations[candidates.observation[choice.row]];
    BundlePlan next = trial;
    RemoveObservation(d, &next);
    const Status still = RecheckBundlePlan(a->config, a->block, &next);
    if (!still.ok()) {
      // The first of the round ends snooping as one at a time would; a later one waits.
      if (removed == 0)
        AddRoundNotice("data snooping stopped: removing " + std::string(EnumName(d.group)) + " #" +
                           std::to_string(d.item) + " would leave " + still.message(),
                       &result->summary.message);
      break;
    }
    record(choice);
    trial = std::move(next);
    ++removed;
  }
  if (removed == 0) return false;
  *a->plan = std::move(trial);
  return true;
}

// The rejection score of every tie mark: its normalized residual when known, else its whitened
// residual, with the limit it is held against. Control and check marks score 0: they are a
// surveyor's own measurements and are tested and reported (diagnostics), removed only by data
// snooping (--snoop), never by the automatic rejection.
std::vector<double> RejectionScores(const RoundChanges& a, double* limit) {
  const Block& block = a.block;
  std::vector<double> score(block.marks.size(), 0.0);
  *limit = a.options.robustness.rejection_threshold;
  if (!a.result->observations.empty()) {
    for (const BundleObservationDiagnostics& d : a.result->observations) {
      const int g = d.group;
      if (g != kTieMarks) continue;
      if (std::isfinite(d.normalized)) score[d.item] = std::max(score[d.item], std::abs(d.normalized));
    }
    return score;
  }
  *limit *= std::max(1.0, a.result->summary.sigma0);
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!a.plan->mark_used[m] || !a.result->mark_residuals[m].allFinite()) continue;
    if (block.points[block.marks[m].point].role != PointRole::kTie) continue;
    score[m] = a.result->mark_residuals[m].norm() * block.marks[m].observation_units_per_unit /
               a.plan->mark_sigma[m];
  }
  return score;
}

// Per tie mark with diagnostics, the drop of the block's sum of squares its removal gives, about
// w_x^2 + w_y^2 (its rows' normalized residuals; the x-y correlation within a mark left out);
// NaN where a row has no w (redundancy number ~0) or without diagnostics.
std::vector<double> RemovalDrops(const RoundChanges& a) {
  std::vector<double> drop(a.block.marks.size(), std::numeric_limits<double>::quiet_NaN());
  for (const BundleObservationDiagnostics& d : a.result->observations) {
    if (d.group != kTieMarks) continue;
    double& t = drop[d.item];
    t = (d.axis == 0 ? 0.0 : t) + d.normalized * d.normalized;
  }
  return drop;
}

// A rejection round: marks beyond the threshold (normalized residuals when known, whitened
// residuals in units of max(1, sigma0) otherwise), one per point and round, its worst: a blunder
// in one mark of a track pulls the point and raises its other marks' residuals too, and those
// recover once it is gone.
// The worst is removed only when the block can tell it from the point's other marks. Removing
// mark k drops the sum of squares by T_k (RemovalDrops), so the likelihood ratio of "the blunder
// is in k" against "in j" is exp((T_k - T_j) / 2); k goes when T_k - T_j exceeds -2 ln(alpha)
// (statistics.snooping_alpha: 13.8 at 0.001) for every other mark j of the point in use. Where it
// does not, removing another mark would explain the point as well: three rays whose residuals
// are one pattern (cameras on one line: the x rows correlate near 1), or two rays. The point is
// then unresolved: all its marks leave the adjustment (rejected_marks) and it is listed
// (unresolved_points), neither adjusted with its blunder nor without a good mark. Without
// diagnostics (statistics none) the worst is removed as before. kFailed when the block no longer
// holds (the summary says why).
enum class Rejection { kNone, kRemoved, kFailed };

Rejection RejectMarks(RoundChanges* a, int r) {
  const Block& block = a->block;
  double limit = 0.0;
  const std::vector<double> score = RejectionScores(*a, &limit);
  const std::vector<double> drop = RemovalDrops(*a);
  const double separable = -2.0 * std::log(a->options.statistics.snooping_alpha);
  BundlePlan trial = *a->plan;
  std::vector<BundleRejectedMark> rejected;
  std::vector<BundleUnresolvedPoint> unresolved;
  std::vector<int> worst_of_point(block.points.size(), -1);
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!trial.mark_used[m] || !(score[m] > limit)) continue;
    int& worst = worst_of_point[block.marks[m].point];
    if (worst < 0 || score[m] > score[worst]) worst = static_cast<int>(m);
  }
  for (size_t p = 0; p < block.points.size(); ++p) {
    const int worst = worst_of_point[p];
    if (worst < 0) continue;
    // The point's other mark in use that removing would explain it best.
    int runner_up = -1;
    if (std::isfinite(drop[worst])) {
      for (const int m : block.marks_of_point[p]) {
        if (m == worst || !trial.mark_used[m]) continue;
        const double t = std::isfinite(drop[m]) ? drop[m] : drop[worst];  // untestable: no better
        if (runner_up < 0 || t > (std::isfinite(drop[runner_up]) ? drop[runner_up] : drop[worst]))
          runner_up = m;
      }
    }
    const double runner_up_drop =
        runner_up < 0 ? 0.0 : (std::isfinite(drop[runner_up]) ? drop[runner_up] : drop[worst]);
    if (runner_up < 0 || drop[worst] - runner_up_drop > separable) {
      trial.mark_used[worst] = 0;
      rejected.push_back({worst, r, score[worst]});
      continue;
    }
    unresolved.push_back({static_cast<int>(p), r, worst, runner_up, drop[worst], runner_up_drop});
    for (const int m : block.marks_of_point[p]) {
      if (!trial.mark_used[m]) continue;
      trial.mark_used[m] = 0;
      rejected.push_back({m, r, score[m]});
    }
  }
  ++a->rejections_done;
  if (rejected.empty()) return Rejection::kNone;
  const Status still = RecheckBundlePlan(a->config, block, &trial);
  if (!still.ok()) {
    BundleAdjustmentSummary& summary = a->result->summary;
    summary.termination = SolverTermination::kFailure;
    summary.message = "after rejecting " + std::to_string(rejected.size()) +
                      " marks as blunders, " + still.message();
    return Rejection::kFailed;
  }
  a->result->rejected_marks.insert(a->result->rejected_marks.end(), rejected.begin(),
                                   rejected.end());
  a->result->unresolved_points.insert(a->result->unresolved_points.end(), unresolved.begin(),
                                      unresolved.end());
  *a->plan = std::move(trial);
  return Rejection::kRemoved;
}

// Variance components: each estimable group's factor; true (adjust again) when one is not 1
// within the tolerance, after rescaling the groups; false when they settled (the reported
// adjustment is then the one whose weights produced them) or cannot go on.
bool RescaleGroups(RoundChanges* a) {
  const BundleAdjustmentOptions& options = a->options;
  const GroupVariance& variance = *a->variance;
  BundleAdjustmentResult* result = a->result;
  if (!std::isfinite(variance.redundancy[0]) && variance.scalar_rows[0] > 0) {
    AddRoundNotice("accuracies not estimated: a group's redundancy needs the covariances; " +
                       CovariancesMissing(options),
                   &result->summary.message);
    return false;
  }
  double factors[kNumBundleGroups];
  bool changed = false;
  for (int g = 0; g < kNumBundleGroups; ++g) {
    a->group_estimable[g] = variance.scalar_rows[g] > 0 &&
                            variance.redundancy[g] >= options.statistics.min_variance_redundancy;
    factors[g] = a->group_estimable[g] ? variance.whitened_ssq[g] / variance.redundancy[g] : 1.0;
    if (std::abs(factors[g] - 1.0) > options.statistics.variance_tolerance) changed = true;
  }
  ++result->variance_iterations;
  if (!changed) return false;
  if (result->variance_iterations >= options.statistics.max_variance_iterations) {
    const int n = result->variance_iterations;
    AddRoundNotice("variance components did not settle in " + std::to_string(n) +
                       (n == 1 ? " iteration" : " iterations"),
                   &result->summary.message);
    return false;
  }
  for (int g = 0; g < kNumBundleGroups; ++g) {
    if (!a->group_estimable[g]) continue;
    a->group_scale[g] *= std::sqrt(factors[g]);
    ScaleGroup(g, std::sqrt(factors[g]), a->plan);
  }
  return true;
}

}  // namespace

void AddRoundNotice(const std::string& notice, std::string* message) {
  if (message->find(notice) != std::string::npos) return;
  *message += (message->empty() ? "" : "; ") + notice;
}

ConditionedTest ConditionedSnoopingTest(const SnoopingCandidates& candidates,
                                        const std::vector<int>& taken,
                                        const BundleStatisticsOptions& options) {
  const Eigen::MatrixXd& Q = candidates.Qvv;
  const int n = static_cast<int>(candidates.v.size());
  std::vector<int> A;  // rows taken
  std::vector<char> in_A(n, 0);
  for (const int c : taken)
    for (int row = candidates.first_row[c]; row < candidates.first_row[c + 1]; ++row) {
      A.push_back(row);
      in_A[row] = 1;
    }
  const int m = static_cast<int>(A.size());
  ConditionedTest test;
  test.residual = candidates.v;
  Eigen::VectorXd q = Q.diagonal();
  double drop = 0.0;  // v_A^T Q_AA^-1 v_A
  if (m > 0) {
    Eigen::MatrixXd Q_AA(m, m), Q_nA(n, m);
    Eigen::VectorXd v_A(m);
    for (int i = 0; i < m; ++i) {
      v_A[i] = candidates.v[A[i]];
      Q_nA.col(i) = Q.col(A[i]);
      for (int j = 0; j < m; ++j) Q_AA(i, j) = Q(A[i], A[j]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(Q_AA);
    const Eigen::VectorXd u = ldlt.solve(v_A);
    const Eigen::MatrixXd K = ldlt.solve(Q_nA.transpose());  // Q_AA^-1 Q_A.
    drop = v_A.dot(u);
    test.residual -= Q_nA * u;
    q -= (Q_nA.cwiseProduct(K.transpose())).rowwise().sum();
  }
  const int redundancy = candidates.redundancy - m;
  const double ssq = candidates.sigma0 * candidates.sigma0 * candidates.redundancy - drop;
  const double sigma0 = redundancy > 0 ? std::sqrt(std::max(ssq, 0.0) / redundancy) : 0.0;
  test.s0 = std::isfinite(sigma0) ? std::max(1.0, sigma0) : 1.0;
  test.critical_value = SnoopingCriticalValue(options, candidates.num_tested - m, nullptr);
  test.normalized.resize(n);
  for (int row = 0; row < n; ++row) {
    test.normalized[row] = !in_A[row] && q[row] > kZeroRedundancy
                               ? std::abs(test.residual[row]) / (test.s0 * std::sqrt(q[row]))
                               : std::numeric_limits<double>::quiet_NaN();
  }
  return test;
}

std::vector<SnoopingChoice> ChooseSnoopingBatch(const SnoopingCandidates& candidates,
                                                const BundleStatisticsOptions& options,
                                                int max_removals) {
  std::vector<SnoopingChoice> choices;
  std::vector<int> taken;
  const int num_candidates = static_cast<int>(candidates.first_row.size()) - 1;
  const Eigen::MatrixXd& Q = candidates.Qvv;
  const double s0 = std::isfinite(candidates.sigma0) ? std::max(1.0, candidates.sigma0) : 1.0;
  std::vector<char> is_taken(std::max(num_candidates, 0), 0);
  while (static_cast<int>(choices.size()) < max_removals) {
    const ConditionedTest test = ConditionedSnoopingTest(candidates, taken, options);
    SnoopingChoice best;
    for (int c = 0; c < num_candidates; ++c) {
      if (is_taken[c]) continue;
      for (int row = candidates.first_row[c]; row < candidates.first_row[c + 1]; ++row) {
        const double w = test.normalized[row];
        if (std::isfinite(w) && w > best.normalized) best = {c, row, w, test.residual[row]};
      }
    }
    if (best.candidate < 0 || !(best.normalized > test.critical_value)) break;
    if (!taken.empty()) {
      // An observation outside the candidates would come first.
      if (!(best.normalized > candidates.outside * s0 / test.s0)) break;
      // Rows with a zero redundancy number (untested, residual 0) have no correlation to speak of.
      double correlation = 0.0;
      for (int row = candidates.first_row[best.candidate];
           row < candidates.first_row[best.candidate + 1]; ++row) {
        if (!(Q(row, row) > kZeroRedundancy)) continue;
        for (const int c : taken)
          for (int other = candidates.first_row[c]; other < candidates.first_row[c + 1]; ++other)
            if (Q(other, other) > kZeroRedundancy)
              correlation = std::max(correlation, std::abs(Q(row, other)) /
                                                      std::sqrt(Q(row, row) * Q(other, other)));
      }
      if (!(correlation <= kMaxSnoopingCorrelation)) break;
    }
    choices.push_back(best);
    taken.push_back(best.candidate);
    is_taken[best.candidate] = 1;
  }
  return choices;
}

// The sigmas in use are the estimates; the report's stated accuracy stays what the user stated.
void ReportEstimatedAccuracies(const RoundChanges& a) {
  for (BundleGroupStatistics& group : a.result->groups) {
    if (group.fixed()) continue;  // no observations to estimate from
    const int g = group.group;
    const double r = a.variance->redundancy[g];
    if (a.group_estimable[g]) {
      // The verdict's ratio is against the accuracy in use, the estimate (before the rescale).
      if (group.overfit) group.message = OverfitMessage(group, "estimated");
      else if (!group.message.empty()) group.message = LooseAccuracyMessage(group, "estimated");
      group.estimated_accuracy = group.stated_accuracy;
      group.estimated_accuracy_standard_error = 1.0 / std::sqrt(2.0 * r);
      group.stated_accuracy /= a.group_scale[g];
      group.ratio *= a.group_scale[g];
    } else if (!std::isfinite(r)) {
      group.estimation_message =
          "not estimated: its redundancy needs the covariances; " + CovariancesMissing(a.options);
    } else {
      std::ostringstream message;
      message << "not estimated: the rest of the block checks it too little (redundancy "
              << FormatSignificant(r, 3) << " < " << FormatSignificant(a.options.statistics.min_variance_redundancy, 3)
              << ")";
      group.estimation_message = message.str();
    }
  }
}

RoundChanges::RoundChanges(const BundleAdjustmentOptions& options,
                           const BundleAdjustmentConfig& config, const Block& block,
                           BundlePlan* plan, BundleAdjustmentResult* result,
                           const GroupVariance* variance)
    : options(options), config(config), block(block), plan(plan), result(result),
      variance(variance) {
  const BundleRobustnessOptions& robustness = options.robustness;
  rejection_rounds = robustness.snoop || robustness.rejection_threshold <= 0.0
                         ? 0
                         : robustness.max_rejection_rounds;
  max_rounds = 1 + rejection_rounds + (robustness.snoop ? robustness.max_snooping_removals : 0) +
               (options.statistics.estimate_accuracies
                    ? options.statistics.max_variance_iterations
                    : 0);
}

RoundChange ChangeAfterRound(RoundChanges* a, int r) {
  if (r >= a->max_rounds) return RoundChange::kNone;
  // 1. Blunders.
  if (a->options.robustness.snoop) {
    ++a->result->summary.snooping_rounds;
    bool batch_computed = false;
    if (a->options.robustness.snooping_batch && SnoopBatch(a, r, &batch_computed))
      return RoundChange::kMarksRemoved;
    if (!batch_computed && SnoopOne(a, r)) return RoundChange::kMarksRemoved;
  } else if (a->rejections_done < a->rejection_rounds) {
    const auto start = std::chrono::steady_clock::now();
    const Rejection rejection = RejectMarks(a, r);
    a->result->summary.rejection_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (rejection == Rejection::kFailed) return RoundChange::kFailed;
    if (rejection == Rejection::kRemoved) return RoundChange::kMarksRemoved;
  }
  // 2. Variance components.
  if (a->options.statistics.estimate_accuracies && RescaleGroups(a))
    return RoundChange::kWeightsChanged;
  return RoundChange::kNone;
}

}  // namespace photopose::internal
