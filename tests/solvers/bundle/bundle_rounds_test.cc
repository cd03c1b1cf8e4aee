// The steps between the rounds (solvers/bundle/internal/bundle_rounds.h), here batch data
// snooping: the conditioned w-test against a brute-force dense computation, the choice on a
// hand-made set of candidates, and whole adjustments against one-at-a-time snooping.
#include "solvers/bundle/internal/bundle_rounds.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/bundle_statistics.h"
#include "solvers/bundle/taylor_bundle.h"

namespace photopose::internal {
namespace PHOTOPOSE_UNITY_ID {

// The cofactors of the candidates (selected inversion plus solves through the factor) against the
// dense projector I - J (J^T J)^-1 J^T: rounding only (measured 1.4e-13).
constexpr double kCofactor = 1e-9;
// The conditioned w against the dense projection of the block without A, relative: the formula
// takes the residuals to be orthogonal to J, true only to the solver's last step (measured 1.5e-8
// with the round converged to a relative step of 4e-17; 5.8e-7 at the default tolerances).
constexpr double kConditioned = 1e-7;
// The final adjustments of batch and one-at-a-time snooping: the same observations out, each
// converged to Ceres' function tolerance (1e-10) from a different start.
constexpr double kSameCost = 1e-9;

// ------------------------------------------------------------------ ChooseSnoopingBatch by hand

// Three one-row candidates, whitened residuals v, unit redundancy numbers but for the
// correlations given; sigma0 1 and a per-observation alpha, so k is fixed.
SnoopingCandidates HandMade(const Eigen::Vector3d& v, double rho01, double rho02) {
  SnoopingCandidates c;
  c.computed = true;
  c.first_row = {0, 1, 2, 3};
  c.observation = {0, 1, 2};
  c.v = v;
  c.Qvv = Eigen::Matrix3d::Identity();
  c.Qvv(0, 1) = c.Qvv(1, 0) = rho01;
  c.Qvv(0, 2) = c.Qvv(2, 0) = rho02;
  c.sigma0 = 1.0;
  c.redundancy = 1000;
  c.num_tested = 1000;
  return c;
}

BundleStatisticsOptions PerObservation() {
  BundleStatisticsOptions options;
  options.snooping_family_wise = false;  // k = 3.29 whatever is removed
  return options;
}

TEST(ChooseSnoopingBatch, UncorrelatedBlundersGoTogetherLargestFirst) {
  const SnoopingCandidates c = HandMade({8.0, -12.0, 5.0}, 0.0, 0.0);
  const std::vector<SnoopingChoice> choices = ChooseSnoopingBatch(c, PerObservation(), 10);
  ASSERT_EQ(choices.size(), 3u);
  EXPECT_EQ(choices[0].candidate, 1);
  EXPECT_EQ(choices[1].candidate, 0);
  EXPECT_EQ(choices[2].candidate, 2);
  // Uncorrelated: each w unchanged by the others (sigma0 1, s0 stays 1).
  EXPECT_NEAR(choices[0].normalized, 12.0, 1e-12);
  EXPECT_NEAR(choices[1].normalized, 8.0, 1e-12);
  EXPECT_NEAR(choices[2].residual, 5.0, 1e-12);
  // At most max_removals.
  EXPECT_EQ(ChooseSnoopingBatch(c, PerObservation(), 2).size(), 2u);
}

TEST(ChooseSnoopingBatch, ConditionedWBelowTheCriticalValueStays) {
  // Candidate 2 only echoes candidate 0 (rho 0.25, under the correlation bound): given 0 out,
  // v_2|0 = 1 - 0.25 * 8 = -1, Q_22|0 = 1 - 0.0625: |w| = 1.03 < k.
  const SnoopingCandidates c = HandMade({8.0, 0.0, 1.0}, 0.0, 0.25);
  const ConditionedTest test = ConditionedSnoopingTest(c, {0}, PerObservation());
  EXPECT_NEAR(test.residual[2], -1.0, 1e-12);
  EXPECT_NEAR(test.normalized[2], 1.0 / std::sqrt(1.0 - 0.0625), 1e-12);
  EXPECT_TRUE(std::isnan(test.normalized[0]));
  const std::vector<SnoopingChoice> choices = ChooseSnoopingBatch(c, PerObservation(), 10);
  ASSERT_EQ(choices.size(), 1u);
  EXPECT_EQ(choices[0].candidate, 0);
}

TEST(ChooseSnoopingBatch, CorrelatedCandidateWaitsForTheNextRound) {
  // w_1|0 = (-12 - 0.5 * 20) / sqrt(0.75) = -25.4: still a blunder given candidate 0, but rho 0.5
  // > kMaxSnoopingCorrelation, so the next round judges it.
  const SnoopingCandidates c = HandMade({20.0, -12.0, 6.0}, 0.5, 0.0);
  const std::vector<SnoopingChoice> choices = ChooseSnoopingBatch(c, PerObservation(), 10);
  ASSERT_EQ(choices.size(), 1u);
  EXPECT_EQ(choices[0].candidate, 0);
}

TEST(ChooseSnoopingBatch, AnObservationOutsideTheCandidatesComesFirst) {
  SnoopingCandidates c = HandMade({20.0, 5.0, 4.0}, 0.0, 0.0);
  c.outside = 4.5;  // a row left out by the bound, with |w| above candidates 1 and 2
  const std::vector<SnoopingChoice> choices = ChooseSnoopingBatch(c, PerObservation(), 10);
  ASSERT_EQ(choices.size(), 2u);
  EXPECT_EQ(choices[1].candidate, 1);
}

TEST(ChooseSnoopingBatch, SigmaZeroAndKFollowTheRemovals) {
  // sigma0 2 over redundancy 10: ssq 40. Candidate 0 (v = 6) out: ssq 4 over 9, s0|0 = 1 (max).
  SnoopingCandidates c = HandMade({6.0, 3.0, 0.0}, 0.0, 0.0);
  c.sigma0 = 2.0;
  c.redundancy = 10;
  c.num_tested = 10;
  BundleStatisticsOptions options;  // family-wise: k of alpha / (n - |A|)
  const ConditionedTest before = ConditionedSnoopingTest(c, {}, options);
  EXPECT_DOUBLE_EQ(before.s0, 2.0);
  EXPECT_NEAR(before.normalized[0], 3.0, 1e-12);
  const ConditionedTest after = ConditionedSnoopingTest(c, {0}, options);
  EXPECT_DOUBLE_EQ(after.s0, 1.0);
  EXPECT_NEAR(after.normalized[1], 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(after.critical_value, SnoopingCriticalValue(options, 9, nullptr));
  EXPECT_LT(after.critical_value, before.critical_value);
}

// ------------------------------------------------------------------ against a dense computation

// A small block with blunders of every kind the statistics test, adjusted once (no snooping, no
// rejection), then one round of statistics with the batch candidates.
struct OneRound {
  Block block;
  BundleAdjustmentOptions options;
  BundlePlan plan;
  BundleState state;
  BundleRound round;
  BundleAdjustmentResult result;
  GroupVariance variance;
};

SyntheticBlockOptions SmallBlockOptions() {
  SyntheticBlockOptions o;
  o.seed = 5;
  o.num_lines = 2;
  o.images_per_line = 4;
  o.num_tie_points = 60;
  o.num_control_points = 5;
  o.num_check_points = 0;
  o.control_sigma_m = 0.01;
  o.mark_sigma_px = 0.5;
  o.num_tie_blunders = 6;
  o.tie_blunder_px = 8.0;
  o.num_control_blunders = 1;
  o.control_blunder_m = 0.3;
  o.num_gnss_blunders = 1;
  o.gnss_blunder_m = 0.5;
  return o;
}

void RunOneRound(const Block& block, BundleCovarianceMethod method, OneRound* out) {
  out->block = block;
  out->options.statistics.covariances = method;
  out->options.robustness.max_rejection_rounds = 0;
  out->options.solver.num_threads = 1;
  BundleAdjustmentResult first;
  ASSERT_TRUE(BundleAdjust(out->options, BundleAdjustmentConfig(), &out->block, &first).ok());
  ASSERT_TRUE(first.summary.IsSolutionUsable()) << first.summary.BriefReport();
  const BundleAdjustmentConfig config;
  ASSERT_TRUE(MakeBundlePlan(PlanOptionsOf(out->options, config), config, out->block, &out->plan).ok());
  out->state = StartState(config, out->block);
  BuildBundleRound(out->options, config, out->block, out->plan, &out->state, &out->round);
  // Converged to the last digit, so that the residuals are orthogonal to J to rounding (the
  // conditioned test assumes the minimum; the dense oracle projects).
  BundleAdjustmentOptions tight = out->options;
  tight.solver.function_tolerance = 1e-16;
  tight.solver.gradient_tolerance = 1e-16;
  ceres::Solver::Summary summary;
  ceres::Solve(CeresSolverOptions(tight, out->round), out->round.problem.get(), &summary);
  ASSERT_EQ(summary.termination_type, ceres::CONVERGENCE);
  out->result.summary.redundancy = out->round.redundancy();
  out->result.summary.sigma0 = std::sqrt(2.0 * summary.final_cost / out->round.redundancy());
  out->options.robustness.snoop = true;
  ASSERT_TRUE(ComputeBundleStatistics(out->options, out->block, out->plan, out->state, out->round,
                                      &out->result, &out->variance)
                  .ok());
}

// The whitened Jacobian (tangent spaces; e blocks, then points) and residuals of the round, dense,
// and per residual block its first row.
void DenseJacobian(const BundleRound& round, Eigen::MatrixXd* J, Eigen::VectorXd* v,
                   std::vector<int>* first_row) {
  ceres::Problem::EvaluateOptions evaluate;
  first_row->assign(1, 0);
  for (const ResidualInfo& info : round.residuals) {
    evaluate.residual_blocks.push_back(info.id);
    first_row->push_back(first_row->back() +
                         round.problem->GetCostFunctionForResidualBlock(info.id)->num_residuals());
  }
  evaluate.parameter_blocks = round.e_blocks;
  evaluate.parameter_blocks.insert(evaluate.parameter_blocks.end(), round.point_blocks.begin(),
                                   round.point_blocks.end());
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  ASSERT_TRUE(round.problem->Evaluate(evaluate, nullptr, &residuals, nullptr, &crs));
  J->setZero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) (*J)(r, crs.cols[k]) = crs.values[k];
  *v = Eigen::Map<const Eigen::VectorXd>(residuals.data(), residuals.size());
}

// The row of the dense Jacobian of the candidates' row `row`.
int DenseRow(const OneRound& a, const std::vector<int>& first_row, int row) {
  const BundleObservationDiagnostics& d =
      a.result.observations[a.variance.snooping.observation[row]];
  for (size_t r = 0; r < a.round.residuals.size(); ++r) {
    const ResidualInfo& info = a.round.residuals[r];
    if (info.group == d.group && info.item == d.item && d.axis >= info.first_axis &&
        d.axis < info.first_axis + info.rows)
      return first_row[r] + d.axis - info.first_axis;
  }
  return -1;
}

// The dense cofactor matrix of the residuals of J's rows `keep`: I - J_k (J_k^T J_k)^-1 J_k^T.
Eigen::MatrixXd DenseCofactors(const Eigen::MatrixXd& J, const std::vector<int>& keep) {
  Eigen::MatrixXd J_k(keep.size(), J.cols());
  for (size_t i = 0; i < keep.size(); ++i) J_k.row(i) = J.row(keep[i]);
  const Eigen::MatrixXd N = J_k.transpose() * J_k;
  return Eigen::MatrixXd::Identity(keep.size(), keep.size()) -
         J_k * N.ldlt().solve(J_k.transpose());
}

void ExpectConditionedTestIsTheDenseOne(BundleCovarianceMethod method) {
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(SmallBlockOptions(), &block, &truth).ok());
  OneRound a;
  RunOneRound(block, method, &a);
  const SnoopingCandidates& c = a.variance.snooping;
  ASSERT_TRUE(c.computed);
  const int num_candidates = static_cast<int>(c.first_row.size()) - 1;
  // Blunders flagged: tie marks, the control point, the camera position (more rows than
  // candidates: priors have 3).
  ASSERT_GE(num_candidates, 4) << c.num_flagged;
  ASSERT_GT(c.v.size(), num_candidates);
  Eigen::MatrixXd J;
  Eigen::VectorXd v;
  std::vector<int> first_row;
  DenseJacobian(a.round, &J, &v, &first_row);
  const int n = static_cast<int>(c.v.size());
  std::vector<int> dense_row(n);
  for (int row = 0; row < n; ++row) {
    dense_row[row] = DenseRow(a, first_row, row);
    ASSERT_GE(dense_row[row], 0);
    EXPECT_NEAR(c.v[row], v[dense_row[row]], 1e-12);
  }
  // Unconditioned: Qvv among the candidates' rows; its diagonal the redundancy numbers.
  std::vector<int> all(J.rows());
  for (int r = 0; r < J.rows(); ++r) all[r] = r;
  const Eigen::MatrixXd Q = DenseCofactors(J, all);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) EXPECT_NEAR(c.Qvv(i, j), Q(dense_row[i], dense_row[j]), kCofactor);
    EXPECT_NEAR(c.Qvv(i, i), a.result.observations[c.observation[i]].redundancy, kCofactor);
  }
  // Conditioned on the first two and on the first three candidates (A): the block without A's
  // rows, its residuals v|A = Q|A v (v is orthogonal to J at the solution), sigma0 from their sum
  // of squares over the redundancy less A's rows.
  for (int taken_count : {2, 3}) {
    std::vector<int> taken;
    for (int k = 0; k < taken_count; ++k) taken.push_back(k);
    std::set<int> removed;
    int removed_rows = 0;
    for (const int k : taken) {
      for (int row = c.first_row[k]; row < c.first_row[k + 1]; ++row) ++removed_rows;
      const BundleObservationDiagnostics& d = a.result.observations[c.observation[c.first_row[k]]];
      for (size_t r = 0; r < a.round.residuals.size(); ++r)
        if (a.round.residuals[r].group == d.group && a.round.residuals[r].item == d.item)
          for (int row = first_row[r]; row < first_row[r + 1]; ++row) removed.insert(row);
    }
    std::vector<int> keep;
    std::vector<int> place(J.rows(), -1);
    for (int r = 0; r < J.rows(); ++r) {
      if (removed.count(r)) continue;
      place[r] = static_cast<int>(keep.size());
      keep.push_back(r);
    }
    const Eigen::MatrixXd Q_A = DenseCofactors(J, keep);
    Eigen::VectorXd v_keep(keep.size());
    for (size_t i = 0; i < keep.size(); ++i) v_keep[i] = v[keep[i]];
    const Eigen::VectorXd v_A = Q_A * v_keep;
    const double sigma0 =
        std::sqrt(v_A.squaredNorm() / (a.result.summary.redundancy - removed_rows));
    const double s0 = std::max(1.0, sigma0);
    const ConditionedTest test = ConditionedSnoopingTest(c, taken, a.options.statistics);
    EXPECT_NEAR(test.s0, s0, kConditioned * s0);
    int compared = 0;
    for (int row = c.first_row[taken_count]; row < n; ++row) {
      const int at = place[dense_row[row]];
      ASSERT_GE(at, 0);
      const double r = Q_A(at, at);
      if (r <= kZeroRedundancy) continue;
      const double w = std::abs(v_A[at]) / (s0 * std::sqrt(r));
      EXPECT_NEAR(test.normalized[row], w, kConditioned * std::max(1.0, w)) << "row " << row;
      EXPECT_NEAR(std::abs(test.residual[row]), std::abs(v_A[at]), kConditioned * std::max(1.0, w));
      ++compared;
    }
    EXPECT_GE(compared, num_candidates - taken_count);
  }
}

TEST(BatchSnooping, ConditionedTestEqualsTheDenseComputation) {
  ExpectConditionedTestIsTheDenseOne(BundleCovarianceMethod::kSelectedInversion);
}

TEST(BatchSnooping, ConditionedTestEqualsTheDenseComputationWithTheDenseInverse) {
  ExpectConditionedTestIsTheDenseOne(BundleCovarianceMethod::kDenseInverse);
}

// ------------------------------------------------------------------ whole adjustments

struct SnoopingRuns {
  Block block;
  SyntheticBlockTruth truth;
  BundleAdjustmentResult batch, one;
};

using Removal = std::pair<int, int>;  // group, item
std::set<Removal> Removals(const BundleAdjustmentResult& result) {
  std::set<Removal> out;
  for (const BundleSnoopingStep& step : result.snooping) out.insert({step.group, step.item});
  return out;
}

// runs->block adjusted with snooping, batch and one at a time.
void AdjustBoth(SnoopingRuns* runs) {
  BundleAdjustmentOptions options;
  options.robustness.snoop = true;
  options.solver.num_threads = 1;
  for (const bool batch : {true, false}) {
    options.robustness.snooping_batch = batch;
    Block block = runs->block;
    BundleAdjustmentResult& result = batch ? runs->batch : runs->one;
    ASSERT_TRUE(BundleAdjust(options, BundleAdjustmentConfig(), &block, &result).ok());
    ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  }
}

void RunBoth(const SyntheticBlockOptions& block_options, SnoopingRuns* runs) {
  ASSERT_TRUE(MakeSyntheticBlock(block_options, &runs->block, &runs->truth).ok());
  AdjustBoth(runs);
}

SyntheticBlockOptions ScatteredBlunders(int tie, int control, int gnss) {
  SyntheticBlockOptions o;
  o.seed = 21;
  o.num_lines = 4;
  o.images_per_line = 8;
  o.tie_point_density_per_m2 = 0.03;
  o.num_control_points = 8;
  o.num_check_points = 2;
  o.control_sigma_m = 0.01;
  o.mark_sigma_px = 0.5;
  o.num_tie_blunders = tie;
  o.tie_blunder_px = 10.0;
  o.num_control_blunders = control;
  o.control_blunder_m = 0.3;
  o.num_gnss_blunders = gnss;
  o.gnss_blunder_m = 0.5;
  return o;
}

void ExpectSameAsOneAtATime(const SnoopingRuns& runs, int max_batch_rounds) {
  const std::set<Removal> batch = Removals(runs.batch), one = Removals(runs.one);
  EXPECT_EQ(batch, one);
  EXPECT_EQ(runs.batch.snooping.size(), batch.size());  // nothing removed twice
  EXPECT_NEAR(runs.batch.summary.final_cost, runs.one.summary.final_cost,
              kSameCost * runs.one.summary.final_cost);
  EXPECT_EQ(runs.batch.summary.redundancy, runs.one.summary.redundancy);
  // One at a time: one round per removal and the one that finds none.
  EXPECT_EQ(runs.one.summary.snooping_rounds, static_cast<int>(one.size()) + 1);
  EXPECT_LE(runs.batch.summary.snooping_rounds, max_batch_rounds);
  std::cout << "removals " << one.size() << ", statistics computations: one at a time "
            << runs.one.summary.snooping_rounds << ", batch " << runs.batch.summary.snooping_rounds
            << "; time " << runs.one.summary.time_seconds << " s against "
            << runs.batch.summary.time_seconds << " s\n";
  // The injected blunders are among the removals: the priors', and the marks' but for a few a
  // point with two rays hides (10 px along the base shifts the point, no residual).
  int found = 0;
  for (const int m : runs.truth.blunder_marks) found += batch.count({kTieMarks, m});
  EXPECT_GE(found, 0.9 * runs.truth.blunder_marks.size());
  for (const int p : runs.truth.blunder_control_points)
    EXPECT_TRUE(batch.count({kControlPoints, p})) << p;
  for (const int i : runs.truth.blunder_gnss_images)
    EXPECT_TRUE(batch.count({kCameraPositions, i})) << i;
  // The rounds of the steps: from 1, non-decreasing.
  int round = 1;
  for (const BundleSnoopingStep& step : runs.batch.snooping) {
    EXPECT_GE(step.round, round);
    round = step.round;
  }
}

// Scattered blunders: tie marks, control points, camera positions, and the statistics
// computations batch snooping may take at most.
struct Scattered {
  int tie, control, gnss, max_batch_rounds;
};
class BatchSnoopingScattered : public ::testing::TestWithParam<Scattered> {};

TEST_P(BatchSnoopingScattered, RemovesWhatOneAtATimeRemovesInFewerRounds) {
  const Scattered& p = GetParam();
  SnoopingRuns runs;
  RunBoth(ScatteredBlunders(p.tie, p.control, p.gnss), &runs);
  ASSERT_EQ(runs.truth.blunder_marks.size(), static_cast<size_t>(p.tie));
  ExpectSameAsOneAtATime(runs, p.max_batch_rounds);
}

// 1 blunder: nothing to save (2 rounds either way); 5 and 30 of three kinds.
INSTANTIATE_TEST_SUITE_P(OneFiveThirty, BatchSnoopingScattered,
                         ::testing::Values(Scattered{1, 0, 0, 2}, Scattered{3, 1, 1, 3},
                                           Scattered{28, 1, 1, 5}));

TEST(BatchSnooping, CorrelatedBlundersOfOnePointWaitForTheNextRound) {
  // Two blunders on the marks of one tie point seen three times: their residuals correlate
  // beyond kMaxSnoopingCorrelation (each pulls the point towards the other's ray), so one round
  // removes at most one of them; the removals are one at a time's all the same.
  SnoopingRuns runs;
  ASSERT_TRUE(MakeSyntheticBlock(ScatteredBlunders(0, 0, 0), &runs.block, &runs.truth).ok());
  Block& block = runs.block;
  std::vector<std::vector<int>> marks_of(block.points.size());
  for (size_t m = 0; m < block.marks.size(); ++m) marks_of[block.marks[m].point].push_back(m);
  int point = -1;
  for (size_t p = 0; p < block.points.size() && point < 0; ++p)
    if (block.points[p].role == PointRole::kTie && marks_of[p].size() == 3) point = p;
  ASSERT_GE(point, 0);
  const int first = marks_of[point][0], second = marks_of[point][1];
  // 10 and 12 px across the flight lines (y: the axis two rays still check once one is gone;
  // px -> the observation unit).
  block.marks[first].observation.y() += 10.0 * block.marks[first].observation_units_per_unit;
  block.marks[second].observation.y() += 12.0 * block.marks[second].observation_units_per_unit;
  // The first round's cofactors: both candidates, correlated beyond the bound.
  OneRound a;
  RunOneRound(block, BundleCovarianceMethod::kSelectedInversion, &a);
  const SnoopingCandidates& c = a.variance.snooping;
  std::vector<int> rows_of_first, rows_of_second;
  for (size_t row = 0; row < c.observation.size(); ++row) {
    const BundleObservationDiagnostics& d = a.result.observations[c.observation[row]];
    if (d.group != kTieMarks) continue;
    if (d.item == first) rows_of_first.push_back(row);
    if (d.item == second) rows_of_second.push_back(row);
  }
  ASSERT_EQ(rows_of_first.size(), 2u);
  ASSERT_EQ(rows_of_second.size(), 2u);
  double correlation = 0.0;
  for (const int i : rows_of_first)
    for (const int j : rows_of_second)
      correlation = std::max(correlation,
                             std::abs(c.Qvv(i, j)) / std::sqrt(c.Qvv(i, i) * c.Qvv(j, j)));
  EXPECT_GT(correlation, kMaxSnoopingCorrelation);
  AdjustBoth(&runs);
  const BundleAdjustmentResult& batch = runs.batch;
  EXPECT_EQ(Removals(batch), Removals(runs.one));
  std::vector<int> rounds;
  for (const BundleSnoopingStep& step : batch.snooping)
    if (step.group == kTieMarks && (step.item == first || step.item == second))
      rounds.push_back(step.round);
  // Both found, never in one round.
  ASSERT_EQ(rounds.size(), 2u) << batch.FullReport(block);
  EXPECT_NE(rounds[0], rounds[1]);
}

TEST(BatchSnooping, StopsWhereTheBlockCouldNotLoseTheNextAsOneAtATime) {
  // Four control points, no camera positions, two of the control points wrong: the block holds
  // without one of them, not without both; both snooping modes remove one and stop, saying why.
  SyntheticBlockOptions o = ScatteredBlunders(0, 2, 0);
  o.gnss = false;
  o.num_control_points = 4;
  SnoopingRuns runs;
  RunBoth(o, &runs);
  ASSERT_EQ(runs.truth.blunder_control_points.size(), 2u);
  EXPECT_EQ(Removals(runs.batch), Removals(runs.one));
  EXPECT_NEAR(runs.batch.summary.final_cost, runs.one.summary.final_cost,
              kSameCost * runs.one.summary.final_cost);
  for (const BundleAdjustmentResult* result : {&runs.batch, &runs.one}) {
    ASSERT_EQ(result->snooping.size(), 1u);
    EXPECT_EQ(result->snooping[0].group, kControlPoints);
    EXPECT_NE(result->summary.message.find("data snooping stopped: removing control_points"),
              std::string::npos)
        << result->summary.message;
  }
}

// ------------------------------------------------------------------ the steps' notices

// The round a step sees when its statistics have no covariances: one tie-mark group of 10 rows,
// redundancy NaN, the statistics' own message in the summary.
struct RoundWithoutCovariances {
  explicit RoundWithoutCovariances(BundleCovarianceMethod method, const std::string& said) {
    options.statistics.covariances = method;
    options.robustness.snoop = true;
    options.statistics.estimate_accuracies = true;
    result.groups.resize(1);
    result.groups[0].group = kTieMarks;
    result.groups[0].count = 10;
    result.summary.message = said;
    variance.scalar_rows[kTieMarks] = 10;
    variance.whitened_ssq[kTieMarks] = 10.0;
    for (double& r : variance.redundancy) r = std::nan("");
  }
  BundleAdjustmentOptions options;
  BundleAdjustmentConfig config;
  Block block;  // read only when an observation is removed: none is here
  BundlePlan plan;
  BundleAdjustmentResult result;
  GroupVariance variance;
};

// Issue 22: without covariances snooping and the variance components cannot run; each says so
// after the statistics' own reason, neither hides the other (the accuracies' notice overwrote
// snooping's), and a group's estimation message gives the true reason (it said "the rest of the
// block checks it too little (redundancy n/a < 5)").
TEST(RoundNotices, WithoutCovariancesEveryStepSaysWhyAndNoneHidesAnother) {
  const struct {
    BundleCovarianceMethod method;
    std::string said;    // the statistics' message (internal/bundle_statistics.h)
    std::string reason;  // why the covariances are missing, as the notices give it
  } cases[] = {
      {BundleCovarianceMethod::kNone, "covariances not computed (statistics turned off)",
       "the statistics are turned off (covariances none)"},
      {BundleCovarianceMethod::kSelectedInversion,
       "no covariances: a point is not determined by its rays", "they were not computed"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.said);
    RoundWithoutCovariances a(c.method, c.said);
    RoundChanges changes(a.options, a.config, a.block, &a.plan, &a.result, &a.variance);
    EXPECT_EQ(ChangeAfterRound(&changes, 1), RoundChange::kNone);
    EXPECT_EQ(a.result.summary.message,
              c.said + "; data snooping not done: its w-test needs the covariances; " + c.reason +
                  "; accuracies not estimated: a group's redundancy needs the covariances; " +
                  c.reason);
    // A notice said once, however often its step runs.
    ChangeAfterRound(&changes, 2);
    EXPECT_EQ(a.result.summary.message.find("data snooping not done"),
              a.result.summary.message.rfind("data snooping not done"));
    ReportEstimatedAccuracies(changes);
    EXPECT_EQ(a.result.groups[0].estimation_message,
              "not estimated: its redundancy needs the covariances; " + c.reason);
  }
  // With covariances, a group the block checks too little says so with its redundancy.
  RoundWithoutCovariances a(BundleCovarianceMethod::kSelectedInversion, "");
  a.options.robustness.snoop = false;
  a.variance.redundancy[kTieMarks] = 3.0;
  RoundChanges changes(a.options, a.config, a.block, &a.plan, &a.result, &a.variance);
  EXPECT_EQ(ChangeAfterRound(&changes, 1), RoundChange::kNone);
  EXPECT_EQ(a.result.summary.message, "");
  ReportEstimatedAccuracies(changes);
  EXPECT_EQ(a.result.groups[0].estimation_message.rfind(
                "not estimated: the rest of the block checks it too little (redundancy 3", 0),
            0u)
      << a.result.groups[0].estimation_message;
}

// ------------------------------------------------------------------ rejection rounds

// A tie point seen by exactly three images with a 20-50 px blunder on one mark, in four
// directions, on each of its marks, with both solvers and the default rejection (threshold 4.5,
// three rounds): the blundered mark is removed and the point's good marks kept, or the point is
// unresolved (left out with all its marks) when removing another mark explains it as well —
// never adjusted with its blunder or without a good mark. Before (the worst |w| removed, one per
// point and round) the blunder on a three-ray point along the flight line, where the x rows of
// the three marks correlate near 1, dragged the point so that a good mark had the largest |w|:
// measured 4 of these 24 cases wrong with Ceres and 4 with Taylor (a good mark removed, the
// blunder kept). Now 16 removed right and 8 points unresolved with either solver.
TEST(RejectionRounds, AThreeRayPointsBlunderIsRemovedOrThePointIsUnresolved) {
  Block clean;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(ScatteredBlunders(0, 0, 0), &clean, &truth).ok());
  std::vector<int> three_ray;  // tie points with exactly three marks
  for (size_t p = 0; p < clean.points.size() && three_ray.size() < 2; ++p)
    if (clean.points[p].role == PointRole::kTie && clean.marks_of_point[p].size() == 3)
      three_ray.push_back(static_cast<int>(p));
  ASSERT_EQ(three_ray.size(), 2u);
  for (const PoseSolver solver : {PoseSolver::kCeres, PoseSolver::kTaylor}) {
    int resolved = 0, unresolved = 0, wrong = 0, cases = 0;
    for (const int point : three_ray) {
      for (int which = 0; which < 3; ++which) {
        for (const double angle_deg : {0.0, 45.0, 90.0, 135.0}) {
          ++cases;
          const double size_px = 20.0 + 10.0 * ((which + cases) % 4);  // 20-50 px
          Block block = clean;
          const int blunder = clean.marks_of_point[point][which];
          BlockMark& mark = block.marks[blunder];
          const double a = angle_deg * M_PI / 180.0;
          mark.observation +=
              size_px * mark.observation_units_per_unit * Eigen::Vector2d(std::cos(a), std::sin(a));
          BundleAdjustmentOptions options;
          options.solver.num_threads = 1;
          BundleAdjustmentResult result;
          ASSERT_TRUE(
              BundleAdjustWithSolver(solver, options, BundleAdjustmentConfig(), &block, &result).ok());
          ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
          const std::vector<char> removed = result.RemovedMarks(block.marks.size());
          const bool left_unresolved =
              std::any_of(result.unresolved_points.begin(), result.unresolved_points.end(),
                          [point](const BundleUnresolvedPoint& u) { return u.point == point; });
          int good_removed = 0;
          for (const int m : clean.marks_of_point[point]) good_removed += m != blunder && removed[m];
          if (left_unresolved) {
            ++unresolved;
            for (const int m : clean.marks_of_point[point]) EXPECT_TRUE(removed[m]);
          } else if (removed[blunder] && good_removed == 0) {
            ++resolved;
          } else {
            ++wrong;
            ADD_FAILURE() << EnumName(solver) << ": point " << clean.points[point].id << ", mark "
                          << which << ", " << size_px << " px at " << angle_deg
                          << " deg: blunder removed " << int(removed[blunder]) << ", good marks removed "
                          << good_removed;
          }
        }
      }
    }
    std::printf("%s: %d three-ray blunders: %d removed, %d points unresolved, %d wrong\n",
                EnumName(solver), cases, resolved, unresolved, wrong);
    EXPECT_EQ(wrong, 0);
    // Across the flight line the block tells the marks apart: not everything is unresolved.
    EXPECT_GT(resolved, cases / 4);
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::internal
