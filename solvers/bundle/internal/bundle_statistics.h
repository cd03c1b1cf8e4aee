#pragma once
// The statistics of a converged round of solvers/bundle/bundle_adjustment.h (residuals per group,
// covariances from the reduced normal matrix, redundancy numbers, reliability, self-calibration),
// and the control- and check-point table both solvers share. Not part of the library's interface.

#include <Eigen/Core>
#include <functional>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/reduced_normals.h"
#include "solvers/bundle/triangulation.h"

namespace photopose::internal {

// A redundancy number below this is zero in all but rounding: the observation is not checked at
// all and its normalized residual is undefined.
constexpr double kZeroRedundancy = 1e-6;

// The w-test's critical value k(alpha) with num_tested scalar observations in the block: alpha
// for the whole block (Bonferroni: alpha / n per observation, options.snooping_family_wise) or per
// observation; *alpha_each (may be null) receives the level per observation.
double SnoopingCriticalValue(const BundleStatisticsOptions& options, int num_tested,
                             double* alpha_each);

// Batch data snooping (BundleRobustnessOptions::snooping_batch, internal/bundle_rounds.h): the
// observations of a round whose w-test rejects them (every row of each), the largest |w| first, at
// most kMaxSnoopingCandidates of them, with the cofactor matrix of their whitened residuals
//   Qvv_ab = delta_ab - J_a Qxx J_b^T
// (Qll = I: whitened rows are independent). J_a Qxx J_b^T = g_a^T C g_b + [p_a = p_b] q_a^T V^-1 q_b
// with g_a = E_a - W V^-1 q_a (the row's e part with its point eliminated, q_a = J_p,a^T); the
// pairs of different images off S's pattern come from C G = S^-1 G, one solve through the factor
// for all rows (cost ~ rows x nnz(L)), never a dense inverse.
struct SnoopingCandidates {
  bool computed = false;
  // Per candidate: its rows are first_row[c] .. first_row[c + 1] - 1 (size candidates + 1).
  std::vector<int> first_row;
  // Per row: the index of its diagnostics in BundleAdjustmentResult::observations, its whitened
  // residual (unitless).
  std::vector<int> observation;
  Eigen::VectorXd v;
  Eigen::MatrixXd Qvv;  // rows x rows, unitless
  // The largest |w| of a row of no candidate (unitless; 0 when there is none): an observation
  // left out by the bound, or one the w-test accepts.
  double outside = 0.0;
  // The round's sigma0 (unitless), redundancy and tested rows (count): sigma0 and k(alpha) once
  // observations are out.
  double sigma0 = 0.0;
  int redundancy = 0;
  int num_tested = 0;
  int num_flagged = 0;  // observations the w-test rejects (count; candidates are the first ones)
  double seconds = 0.0;  // their computation (s)
};
// At most this many candidates per round: the solve costs ~3 rows each times nnz(L), the choice
// among them (internal/bundle_rounds.h) a dense factorisation of at most 3 x 64 rows per step.
constexpr int kMaxSnoopingCandidates = 64;

// Per group, what variance component estimation needs: the whitened sum of squares and the
// redundancy (sum of redundancy numbers; NaN when not computed); and what batch data snooping
// needs (`snooping`, computed with options.robustness.snoop and snooping_batch).
struct GroupVariance {
  double whitened_ssq[kNumBundleGroups] = {};
  double redundancy[kNumBundleGroups] = {};
  int scalar_rows[kNumBundleGroups] = {};
  SnoopingCandidates snooping;
};

// Everything the result reports about a converged round: residuals, groups, covariances,
// calibration, per-observation diagnostics (with the whitened normalized residual of each of the
// round's observations in `normalized`, aligned with `round.residuals` rows), check points.
// With covariances asked for, an error when the round's normal matrix is singular (a parameter
// the observations do not determine): the message names it ("the normal matrix is singular: image
// 'IMG_12': omega is not determined by the observations"), the result holds what needs no
// covariance. A singular normal matrix is a failed adjustment, never a success without
// covariances.
[[nodiscard]] Status ComputeBundleStatistics(const BundleAdjustmentOptions& options,
                                             const Block& block, const BundlePlan& plan,
                                             const BundleState& state, const BundleRound& round,
                                             BundleAdjustmentResult* result,
                                             GroupVariance* variance);

// The same check without covariances (BundleCovarianceMethod::kNone): the reduced normal matrix
// built and factorised once, not inverted; the error as above. Ceres' Levenberg-Marquardt steps
// solve damped systems, which are never singular, so a parameter no observation determines
// converges to wherever the damping left it: only an undamped factorisation shows it.
// *factorization_seconds: the factorisation's time (s).
[[nodiscard]] Status CheckBundleDeterminacy(const Block& block, const BundlePlan& plan,
                                            const BundleState& state, const BundleRound& round,
                                            int num_threads, double* factorization_seconds);

// The over-fitting verdict of a prior group in words: its residual RMS as group.ratio of the
// `accuracy` ("stated", or "estimated" once variance components replaced it) accuracy, its
// redundancy share, and what to do.
std::string OverfitMessage(const BundleGroupStatistics& group, const char* accuracy);
// The note of a prior group the block checks (redundancy share at least checked_redundancy_share)
// whose residual RMS is well below its `accuracy` accuracy: the accuracy is loose, the solution
// does not bend to it.
std::string LooseAccuracyMessage(const BundleGroupStatistics& group, const char* accuracy);
// The note of a prior group whose residual RMS is well below its `accuracy` accuracy when its
// redundancy share is unknown (statistics not computed): over-fitted and loose cannot be told
// apart, no verdict (overfit false).
std::string OverfitNotJudgedMessage(const BundleGroupStatistics& group, const char* accuracy);

// The images' and cameras' own uncertainty carried into the covariance of a check point: given
// its rays, the marks they come from (indices into Block::marks) and its intersection, the
// unscaled covariance (m^2) that replaces the intersection's a-priori one.
using CheckPointCovariance = std::function<Eigen::Matrix3d(
    const std::vector<RayObservation>& rays, const std::vector<int>& marks,
    const TriangulationResult& intersection)>;

// How a point intersected from `rays` (from the marks `marks`, indices into Block::marks) moves
// with the reduced system's parameters: N = sum_j J_X,j^T J_X,j over the rays (whitened) and
// A = N^-1 B, B = sum_j J_X,j^T J_e,j in the reduced system's columns (3 x reduced.size; the
// rays' images and cameras that are e blocks), the derivatives taken at the rays' own values. The
// point's covariance with the images' own uncertainty is N^-1 + A C A^T (unscaled; C the
// reduced system's inverse, or a left-out one).
void CheckPointSensitivity(const Block& block, const BundleState& state, const BundleRound& round,
                           const ReducedNormals& reduced, const std::vector<RayObservation>& rays,
                           const std::vector<int>& marks, const TriangulationResult& intersection,
                           Eigen::Matrix3d* N_inverse, Eigen::MatrixXd* A);

// One check point's row of the table (TabulateControlAndCheckPoints' rule, solvers/bundle/
// check_points.h): point p intersected from its marks whose image has an eo (eo[i] null: not
// oriented), their sigmas `sigma_scale` times core/mark_weight.h's under `defaults`, its marks
// tested by the w-test against `critical` and the worst rejected (appended to *rejected) until
// none is; error_m, covariance (variance_factor times `covariance`'s, or the intersection's
// a-priori one without it) and num_observations into *table. False, the reason in
// table->message, when it cannot be intersected.
bool TabulateCheckPoint(const Block& block, int p, const std::vector<const Vector6d*>& eo,
                        const std::vector<BlockCamera>& cameras, const MarkSigmaDefaults& defaults,
                        double sigma_scale, double variance_factor, double critical,
                        const CheckPointCovariance& covariance, BundlePointResult* table,
                        std::vector<BundleRejectedCheckMark>* rejected);

// The control- and check-point table of an adjusted block (the one rule of both solvers; see
// solvers/bundle/check_points.h). The adjusted values: eo[i] the seed exterior orientation of
// image i (null: not oriented, its marks are left out), cameras the adjusted cameras of the block.
// Check points are intersected from their marks (sigmas: the control marks' rule of
// core/mark_weight.h) with covariance = variance_factor times `covariance` of the intersection
// when given, else its a-priori covariance. Control points count with the error_m already set
// unless data snooping removed their coordinates (result->snooping). Sets the counts and RMSEs.
// result->points must have one entry per point of the block.
void TabulateControlAndCheckPoints(const Block& block, const std::vector<const Vector6d*>& eo,
                                   const std::vector<BlockCamera>& cameras,
                                   const BundleAccuracies& accuracies, double variance_factor,
                                   const CheckPointCovariance& covariance,
                                   BundleAdjustmentResult* result);

}  // namespace photopose::internal
