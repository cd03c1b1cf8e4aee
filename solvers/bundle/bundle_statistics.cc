// The statistics of a converged bundle adjustment round: residuals per group, covariances from
// the reduced normal matrix, redundancy numbers, normalized residuals and reliability (Baarda,
// Foerstner), self-calibration correlations, check points. One file past ~800 lines on purpose:
// the steps in the order they are computed, each a named function, sharing one round's rows; the
// reduced normals they start from are in reduced_normals.cc, the selected inversion in
// selected_inversion.cc.
#include "solvers/bundle/internal/bundle_statistics.h"

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "core/parallel.h"
#include "core/rotation.h"
#include "core/statistics.h"
#include "core/units.h"
#include "cost_functions/exterior_orientation_manifold.h"
#include "solvers/bundle/internal/inner_constraints.h"
#include "solvers/bundle/triangulation.h"

namespace photopose::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

double SnoopingCriticalValue(const BundleStatisticsOptions& options, int num_tested,
                             double* alpha_each) {
  const double alpha = options.snooping_family_wise
                           ? options.snooping_alpha / std::max(1, num_tested)
                           : options.snooping_alpha;
  if (alpha_each != nullptr) *alpha_each = alpha;
  return NormalQuantile(1.0 - 0.5 * alpha);
}

// ------------------------------------------------------------------ the steps of the statistics
namespace {

// Per group: count, per-axis sums of squared residuals and of stated sigmas (in the group's
// unit), and the leverage (sum of hat-matrix diagonals) once known.
struct GroupSums {
  int count = 0;
  // Scalar rows per axis: a camera position without height has no Z row.
  Eigen::Vector3d rows = Eigen::Vector3d::Zero();
  Eigen::Vector3d ssq = Eigen::Vector3d::Zero();
  Eigen::Vector3d stated = Eigen::Vector3d::Zero();
  double leverage = 0.0;
  std::string unit;
};

// The unit scale of one row of a residual block: residual (unit of its group) = whitened * scale.
double RowScale(const Block& block, const BundlePlan& plan, const ResidualInfo& info, int row) {
  switch (info.group) {
    case kTieMarks:
    case kControlMarks:
      return plan.mark_sigma[info.item] / block.marks[info.item].observation_units_per_unit;
    case kControlPoints:
      return plan.point_sigma[info.item][info.first_axis + row];
    case kCameraPositions:
      return plan.image_prior_sigma[info.item][row];
    case kAttitudes:
      return plan.image_attitude_sigma[info.item][row] * kDegreesPerRadian;
    default:
      return 1.0;
  }
}

// Clears the result's per-item tables and counts the points of the round.
void ResetStatistics(const Block& block, const BundlePlan& plan, BundleAdjustmentResult* result,
                     GroupVariance* variance) {
  BundleAdjustmentSummary& summary = result->summary;
  *variance = GroupVariance();
  result->images.assign(block.images.size(), BundleImageResult());
  result->points.assign(block.points.size(), BundlePointResult());
  result->mark_residuals.assign(block.marks.size(), Eigen::Vector2d::Constant(kNaN));
  result->groups.clear();
  result->calibration.clear();
  result->weakly_determined.clear();
  result->observations.clear();
  result->num_uncontrolled = 0;
  summary.num_images = static_cast<int>(block.images.size());
  summary.num_points = 0;
  summary.num_marks = 0;
  for (size_t p = 0; p < block.points.size(); ++p) summary.num_points += plan.point_in_problem[p];
}

// Residuals of every observation in its unit, from the round's whitened residuals: per group
// (sums, variance), per mark, per image, and the control points' errors.
void TabulateResiduals(const Block& block, const BundlePlan& plan, const BundleState& state,
                       const BundleRound& round, GroupSums* sums, BundleAdjustmentResult* result,
                       GroupVariance* variance) {
  // A mark group's unit: its marks' own ("px" or "um") when they share one; a group that mixes
  // pixel and film marks has no one unit, and states its accuracy and RMS in each mark's own
  // sigma ("sigma": residual / sigma, the stated accuracy 1).
  // The same rule per image: an image with pixel and film marks has its RMS in sigmas.
  bool has_unit[kNumBundleGroups][2] = {};
  std::vector<std::array<bool, 2>> image_has_unit(block.images.size(), {false, false});
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!plan.mark_used[m]) continue;
    const bool film = block.marks[m].unit == MarkUnit::kFilm;
    has_unit[plan.mark_group[m]][film] = true;
    image_has_unit[block.marks[m].image][film] = true;
  }
  bool in_sigmas[kNumBundleGroups] = {};
  for (const int g : {kTieMarks, kControlMarks}) {
    in_sigmas[g] = has_unit[g][0] && has_unit[g][1];
    sums[g].unit = in_sigmas[g] ? "sigma" : EnumName(has_unit[g][1] ? MarkUnit::kFilm : MarkUnit::kPixel);
  }
  sums[kControlPoints].unit = sums[kCameraPositions].unit = "m";
  sums[kAttitudes].unit = "deg";
  std::vector<double> image_ssq(block.images.size(), 0.0);
  std::unique_ptr<ceres::CostFunction> made;
  std::vector<double*> parameters;
  for (const ResidualInfo& info : round.residuals) {
    double whitened[3] = {0.0, 0.0, 0.0};
    // Without loss function (Ceres' EvaluateResidualBlock with apply_loss_function false).
    const ceres::CostFunction* cost = ResidualBlockOf(round, info, &made, &parameters);
    if (!cost->Evaluate(parameters.data(), whitened, nullptr)) std::fill_n(whitened, 3, kNaN);
    GroupSums& s = sums[info.group];
    variance->scalar_rows[info.group] += info.rows;
    for (int row = 0; row < info.rows; ++row)
      variance->whitened_ssq[info.group] += whitened[row] * whitened[row];
    if (info.group == kTieMarks || info.group == kControlMarks) {
      const BlockMark& mark = block.marks[info.item];
      const double scale = RowScale(block, plan, info, 0);
      const Eigen::Vector2d residual(whitened[0] * scale, whitened[1] * scale);
      result->mark_residuals[info.item] = residual;
      ++s.count;
      const double unit = in_sigmas[info.group] ? 1.0 : scale;
      s.ssq.head<2>() += (Eigen::Vector2d(whitened[0], whitened[1]) * unit).cwiseAbs2();
      s.stated.head<2>() += Eigen::Vector2d::Constant(unit);
      s.rows.head<2>() += Eigen::Vector2d::Ones();
      BundleImageResult& image = result->images[mark.image];
      ++image.num_marks;
      const bool image_in_sigmas = image_has_unit[mark.image][0] && image_has_unit[mark.image][1];
      image_ssq[mark.image] += image_in_sigmas ? whitened[0] * whitened[0] + whitened[1] * whitened[1]
                                               : residual.squaredNorm();
      image.unit = image_in_sigmas ? "sigma" : EnumName(mark.unit);
      ++result->points[mark.point].num_observations;
      ++result->summary.num_marks;
      continue;
    }
    if (info.group != kControlPoints || info.first_axis == 0) ++s.count;
    for (int row = 0; row < info.rows; ++row) {
      const int axis = info.first_axis + row;
      const double scale = RowScale(block, plan, info, row);
      s.ssq[axis] += (whitened[row] * scale) * (whitened[row] * scale);
      s.stated[axis] += scale;
      s.rows[axis] += 1.0;
    }
  }
  for (size_t i = 0; i < block.images.size(); ++i) {
    BundleImageResult& image = result->images[i];
    image.adjusted = true;
    image.rms_residual = image.num_marks > 0 ? std::sqrt(image_ssq[i] / image.num_marks) : 0.0;
  }
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (plan.point_in_problem[p] && block.points[p].role == PointRole::kControl)
      result->points[p].error_m = state.points[p] - *block.points[p].surveyed_m;
  }
}

// The w-test's level: alpha for the whole block (Bonferroni: alpha / n per observation) unless
// asked per observation; with tens of thousands of observations a per-observation 0.1 % would
// reject dozens of good ones.
void SetTestLevel(const BundleAdjustmentOptions& options, const GroupVariance& variance,
                  BundleAdjustmentResult* result) {
  int num_tested = 0;
  for (int g = 0; g < kNumBundleGroups; ++g) num_tested += variance.scalar_rows[g];
  result->critical_value =
      SnoopingCriticalValue(options.statistics, num_tested, &result->alpha_per_observation);
  result->delta0 = result->critical_value + NormalQuantile(options.statistics.snooping_power);
}

// Exterior orientations, in the ambient (Euler) parameters (P C P^T), with `inner` a relative
// block's in its inner-constraint datum (the images the gauge holds too); and the points held
// fixed (the adjusted points' covariances are ObservationDiagnostics').
void OrientationAndFixedPointCovariances(const Block& block, const BundlePlan& plan,
                                         const BundleState& state, const BundleRound& round,
                                         const ReducedNormals& reduced,
                                         const InnerConstraintTransform* inner,
                                         double variance_factor, BundleAdjustmentResult* result) {
  const ExteriorOrientationManifold full_tangent;
  Eigen::MatrixXd C;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const double* eo = state.eo[i].data();
    const auto found = reduced.e_index.find(eo);
    const bool held = static_cast<int>(i) == plan.relative_fixed_image;
    if (found == reduced.e_index.end() && !(inner != nullptr && held)) continue;
    // The gauge's covariance in the full tangent space (zero where the gauge holds a component).
    Matrix6d gauge = Matrix6d::Zero();
    if (found != reduced.e_index.end()) {
      if (!reduced.C.Block(found->second, found->second, &C)) continue;  // diagonal: always known
      const int image = static_cast<int>(i);
      for (int r = 0; r < C.rows(); ++r)
        for (int c = 0; c < C.cols(); ++c)
          gauge(OrientationComponent(plan, image, r), OrientationComponent(plan, image, c)) = C(r, c);
    }
    if (inner != nullptr) gauge = inner->Image(static_cast<int>(i), gauge);
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> P;
    full_tangent.PlusJacobian(eo, P.data());
    result->images[i].covariance = variance_factor * P * gauge * P.transpose();
    result->images[i].has_covariance = true;
  }
  // A point held fixed (stated error-free, or a constant point of the config) has covariance 0;
  // the adjusted points' are ObservationDiagnostics', which makes each point's support once.
  std::vector<char> adjusted(block.points.size(), 0);
  for (const int p : round.point_of_block) adjusted[p] = 1;
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p] || adjusted[p]) continue;
    result->points[p].covariance.setZero();
    result->points[p].has_covariance = true;
    result->points[p].covariance_complete = true;
  }
}

// Per e block, the camera-centre components leading its tangent space (0..2; the relative
// gauge's scale image has one of them held), 0 for blocks that are not images: the rows of the
// external reliability.
std::vector<int> CentreComponents(const Block& block, const BundlePlan& plan,
                                  const BundleState& state, const ReducedNormals& reduced) {
  std::vector<int> centres(reduced.e_offset.size(), 0);
  for (size_t i = 0; i < block.images.size(); ++i) {
    const auto found = reduced.e_index.find(state.eo[i].data());
    if (found == reduced.e_index.end()) continue;
    centres[found->second] = static_cast<int>(i) == plan.relative_scale_image ? 2 : 3;
  }
  return centres;
}

// The diagnostics of one row: redundancy number, normalized residual (w-test against the
// critical value), smallest detectable error and its largest camera-centre shift (`shift`: per
// unit whitened error, from Leverages).
BundleObservationDiagnostics RowDiagnostics(const BundleAdjustmentResult& result,
                                            const ResidualInfo& info, int row, double whitened,
                                            double scale, double leverage, double s0,
                                            double shift) {
  BundleObservationDiagnostics d;
  d.group = static_cast<BundleGroup>(info.group);
  d.item = info.item;
  d.axis = static_cast<std::int8_t>(info.first_axis + row);
  d.residual = static_cast<float>(whitened * scale);
  d.sigma = static_cast<float>(scale);
  d.redundancy = std::clamp(1.0 - leverage, 0.0, 1.0);
  if (d.redundancy > kZeroRedundancy) {
    d.normalized = whitened / (s0 * std::sqrt(d.redundancy));
    d.mdb = static_cast<float>(result.delta0 * scale / std::sqrt(d.redundancy));
    // The largest camera-centre shift from a whitened error mdb / sigma in this row.
    d.external_m = static_cast<float>(shift * result.delta0 / std::sqrt(d.redundancy));
    d.rejected = std::abs(d.normalized) > result.critical_value;
  } else {
    d.normalized = kNaN;
    d.mdb = std::numeric_limits<float>::infinity();
    d.external_m = std::numeric_limits<float>::infinity();
  }
  return d;
}

// What the parallel pass keeps of a row until the rows are listed in the round's order, in the
// row's own entry: its leverage and whitened residual (double, unrounded) and its largest
// camera-centre shift per unit whitened error (rounded to float, as the external_m made of it).
void Stash(double leverage, double whitened, double shift, BundleObservationDiagnostics* d) {
  d->redundancy = leverage;
  d->normalized = whitened;
  d->external_m = static_cast<float>(shift);
}
double StashedLeverage(const BundleObservationDiagnostics& d) { return d.redundancy; }
double StashedWhitened(const BundleObservationDiagnostics& d) { return d.normalized; }
double StashedShift(const BundleObservationDiagnostics& d) { return d.external_m; }

// What ObservationDiagnostics' groups share: the round and its reduced normals, and the per-row
// arrays each group writes its own rows of.
struct DiagnosticsPass {
  const Block& block;
  const BundlePlan& plan;
  const BundleRound& round;
  const ReducedNormals& reduced;
  const InnerConstraintTransform* inner;
  double variance_factor;
  bool diagnostics;
  double s0;                 // the normalized residuals' yardstick
  std::vector<int> centres;  // CentreComponents
  // Per residual block of the round: its first wanted row (every row with the diagnostics, else
  // all but the tie marks'), one past the last at the end; whether it was evaluated.
  std::vector<int> first_row;  // int: at most round.num_observations, an int (4 bytes a block)
  std::vector<char> evaluated;
  std::vector<double> leverage;  // per wanted row, without the diagnostics
  // Per wanted row, with the diagnostics: its entry, holding until it is listed what the entry is
  // made of (Stash), so that no per-row array is held beside the entries.
  BundleObservationDiagnostics* observations = nullptr;
  BundleAdjustmentResult* result;

  void Group(size_t order);
  bool AnyRowWanted(int begin, int end) const;
  void DiagnoseRows(int begin, int end, const std::vector<BlockRows>& rows,
                    const SupportCovariance& support);
};

std::vector<int> FirstWantedRows(const BundleRound& round, bool diagnostics) {
  std::vector<int> first_row(round.residuals.size() + 1, 0);
  for (size_t r = 0; r < round.residuals.size(); ++r) {
    const ResidualInfo& info = round.residuals[r];
    const bool wanted = diagnostics || info.group != kTieMarks;
    first_row[r + 1] = first_row[r] + (wanted ? info.rows : 0);
  }
  return first_row;
}

// Group `order`: a point (in reduced.point_order: neighbours share images) with its covariance
// set, or after the points a residual block without a point (a prior); its rows evaluated and
// diagnosed through their support's covariance.
void DiagnosticsPass::Group(size_t order) {
  const int num_points = static_cast<int>(reduced.V_inverse.size());
  const int first_other = reduced.point_residual_start[num_points];
  const size_t g = static_cast<int>(order) < num_points ? reduced.point_order[order] : order;
  const int begin = static_cast<int>(g) < num_points
                        ? reduced.point_residual_start[g]
                        : first_other + static_cast<int>(g) - num_points;
  const int end =
      static_cast<int>(g) < num_points ? reduced.point_residual_start[g + 1] : begin + 1;
  const int point = static_cast<int>(g) < num_points ? static_cast<int>(g) : -1;
  const bool wanted = AnyRowWanted(begin, end);
  // A point's rows are evaluated in any case: its W (its covariance's) is made from them.
  if (point < 0 && !wanted) return;
  thread_local std::vector<BlockRows> rows;
  if (rows.size() < static_cast<size_t>(end - begin)) rows.resize(end - begin);
  bool all_evaluated = true;
  for (int k = begin; k < end; ++k) {
    const int r = reduced.residual_order[k];
    evaluated[r] = EvaluateBlockRows(round, reduced, round.residuals[r], &rows[k - begin]);
    all_evaluated = all_evaluated && evaluated[r];
  }
  SupportCovariance support;
  if (point >= 0) {
    // The point's covariance (V^-1 + V^-1 W^T C W V^-1, in the datum).
    thread_local Eigen::MatrixXd W;
    if (!all_evaluated) return;
    PointW(round, reduced, point, rows.data(), &W);
    if (!MakeSupportCovariance(reduced, point, &W, {}, &support)) return;
    Eigen::Matrix3d covariance = PointCovariance(reduced, support, point);
    if (inner != nullptr) covariance = inner->Point(point, covariance, W);
    BundlePointResult& point_result = result->points[round.point_of_block[point]];
    point_result.covariance = variance_factor * covariance;
    point_result.has_covariance = true;
    point_result.covariance_complete = true;
  }
  if (!wanted) return;
  // A prior's support is its own e blocks.
  if (point < 0 && (!evaluated[reduced.residual_order[begin]] ||
                    !MakeSupportCovariance(reduced, point, nullptr, rows[0].e_blocks, &support)))
    return;
  DiagnoseRows(begin, end, rows, support);
}

// A tie point's rows are wanted only with the diagnostics (the others are priors).
bool DiagnosticsPass::AnyRowWanted(int begin, int end) const {
  bool any = false;
  for (int k = begin; k < end && !any; ++k) {
    const int r = reduced.residual_order[k];
    any = first_row[r + 1] > first_row[r];
  }
  return any;
}

// The leverages of the group's wanted rows (rows[k - begin] those of its k-th residual block),
// and with the diagnostics their entries.
void DiagnosticsPass::DiagnoseRows(int begin, int end, const std::vector<BlockRows>& rows,
                                   const SupportCovariance& support) {
  Eigen::VectorXd largest;
  for (int k = begin; k < end; ++k) {
    const int r = reduced.residual_order[k];
    if (!evaluated[r] || first_row[r + 1] == first_row[r]) continue;
    const Eigen::VectorXd h =
        Leverages(reduced, support, rows[k - begin], diagnostics ? &centres : nullptr,
                  diagnostics ? &largest : nullptr);
    // Only the first info.rows rows are observations (a control point's Z prior block has a
    // zero row beside it).
    const ResidualInfo& info = round.residuals[r];
    for (int row = 0; row < info.rows; ++row) {
      const int at = first_row[r] + row;
      if (diagnostics)
        Stash(h[row], rows[k - begin].residuals[row], largest[row], &observations[at]);
      else
        leverage[at] = h[row];
    }
  }
}

// Leverages per group (variance->redundancy) and, with `diagnostics`, every observation's
// diagnostics. Without them the tie marks' share is the remainder (the sum of all redundancy
// numbers is the redundancy), which spares their rows.
//
// The rows are taken point by point (a point's rows share one SupportCovariance; the residuals
// grouped by point in `reduced`), the points in parallel, each evaluating its own rows
// (EvaluateBlockRows). The results land in per-row arrays, summed and listed afterwards in the
// round's order, so the figures do not depend on the threads.
void ObservationDiagnostics(const BundleAdjustmentOptions& options, const Block& block,
                            const BundlePlan& plan, const BundleState& state,
                            const BundleRound& round, const ReducedNormals& reduced,
                            const InnerConstraintTransform* inner, double variance_factor,
                            bool diagnostics, GroupSums* sums, BundleAdjustmentResult* result,
                            GroupVariance* variance) {
  // The yardstick of the normalized residuals: the stated accuracies (sigma0 = 1), or the
  // a-posteriori sigma0 when the data say they were optimistic (Pope's tau-test then).
  const double sigma0 = result->summary.sigma0;
  DiagnosticsPass pass{block,
                       plan,
                       round,
                       reduced,
                       inner,
                       variance_factor,
                       diagnostics,
                       std::isfinite(sigma0) ? std::max(1.0, sigma0) : 1.0,
                       CentreComponents(block, plan, state, reduced),
                       FirstWantedRows(round, diagnostics),
                       std::vector<char>(round.residuals.size(), 0),
                       {},
                       nullptr,
                       result};
  const size_t num_residuals = round.residuals.size();
  if (!diagnostics) pass.leverage.assign(pass.first_row.back(), kNaN);
  // With the diagnostics the rows of residual blocks that could not be evaluated are dropped
  // afterwards. (Per-row arrays of the leverage, the whitened residual and the centre shift held
  // 24 bytes more per row at the statistics' peak: 82 MB at 1000 images; the entries hold them.)
  const size_t first_observation = result->observations.size();
  if (diagnostics)
    result->observations.resize(first_observation + static_cast<size_t>(pass.first_row.back()));
  pass.observations = result->observations.data() + first_observation;
  // Groups: one per point, then one per residual block without a point.
  const int num_points = static_cast<int>(reduced.V_inverse.size());
  const int first_other = reduced.point_residual_start[num_points];
  const int num_groups = num_points + static_cast<int>(reduced.residual_order.size()) - first_other;
  ParallelForChunks(num_groups, options.solver.num_threads, 64,
                    [&](size_t order) { pass.Group(order); });
  // In the round's order: the group sums, and the rows listed (those evaluated, moved up over
  // the ones that were not).
  size_t listed = first_observation;
  for (size_t r = 0; r < num_residuals; ++r) {
    const ResidualInfo& info = round.residuals[r];
    if (pass.first_row[r + 1] == pass.first_row[r] || !pass.evaluated[r]) continue;
    for (int row = 0; row < info.rows; ++row) {
      const int at = pass.first_row[r] + row;
      if (!diagnostics) {
        sums[info.group].leverage += pass.leverage[at];
        continue;
      }
      // Read whole before it is written over: `listed` is at or before `at`.
      const BundleObservationDiagnostics stash = pass.observations[at];
      sums[info.group].leverage += StashedLeverage(stash);
      const BundleObservationDiagnostics d = RowDiagnostics(
          *result, info, row, StashedWhitened(stash), RowScale(block, plan, info, row),
          StashedLeverage(stash), pass.s0, StashedShift(stash));
      if (d.redundancy < options.statistics.uncontrolled_redundancy) ++result->num_uncontrolled;
      result->observations[listed++] = d;
    }
  }
  if (diagnostics) result->observations.resize(listed);
  if (!diagnostics) {
    double other_redundancy = 0.0;
    for (int g = kControlMarks; g < kNumBundleGroups; ++g)
      other_redundancy += variance->scalar_rows[g] - sums[g].leverage;
    sums[kTieMarks].leverage =
        variance->scalar_rows[kTieMarks] - (result->summary.redundancy - other_redundancy);
  }
  for (int g = 0; g < kNumBundleGroups; ++g)
    variance->redundancy[g] = variance->scalar_rows[g] - sums[g].leverage;
}

// An observation (a mark, a point's prior, ...) as one key: its group and item.
int64_t ObservationKey(int group, int item) {
  return static_cast<int64_t>(item) * kNumBundleGroups + group;
}

// The observations the w-test rejects, the largest |w| first (ties by key), at most
// kMaxSnoopingCandidates of them: (|w|, key). *num_flagged: all of them.
std::vector<std::pair<double, int64_t>> RankRejected(const BundleAdjustmentResult& result,
                                                     int* num_flagged) {
  std::unordered_map<int64_t, double> worst;  // per rejected observation, its largest |w|
  for (const BundleObservationDiagnostics& d : result.observations) {
    if (!d.rejected) continue;
    double& w = worst[ObservationKey(d.group, d.item)];
    w = std::max(w, std::abs(d.normalized));
  }
  std::vector<std::pair<double, int64_t>> ranked;
  ranked.reserve(worst.size());
  for (const auto& [observation, w] : worst) ranked.emplace_back(w, observation);
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  *num_flagged = static_cast<int>(ranked.size());
  if (ranked.size() > static_cast<size_t>(kMaxSnoopingCandidates))
    ranked.resize(kMaxSnoopingCandidates);
  return ranked;
}

// A candidate's row: its residual block's rows (an index into the evaluated ones) and the row.
struct CandidateRow {
  int block_rows;
  int row;
};

// The candidates' rows (residual blocks evaluated, in candidate order) with their diagnostics
// (out->observation, out->first_row). False when a residual block cannot be evaluated or a row
// has no diagnostics.
bool CandidateRows(const BundleRound& round, const ReducedNormals& reduced,
                   const std::unordered_map<int64_t, int>& candidate_of,
                   const std::vector<std::array<int, 3>>& diagnostics_of,
                   std::vector<BlockRows>* evaluated, std::vector<CandidateRow>* rows,
                   SnoopingCandidates* out) {
  const int num_candidates = static_cast<int>(diagnostics_of.size());
  std::vector<std::vector<int>> residuals_of(num_candidates);
  for (size_t r = 0; r < round.residuals.size(); ++r) {
    const ResidualInfo& info = round.residuals[r];
    const auto found = candidate_of.find(ObservationKey(info.group, info.item));
    if (found != candidate_of.end()) residuals_of[found->second].push_back(static_cast<int>(r));
  }
  out->first_row.push_back(0);
  for (int c = 0; c < num_candidates; ++c) {
    for (const int r : residuals_of[c]) {
      const ResidualInfo& info = round.residuals[r];
      evaluated->emplace_back();
      if (!EvaluateBlockRows(round, reduced, info, &evaluated->back())) return false;
      for (int row = 0; row < info.rows; ++row) {
        const int d = diagnostics_of[c][std::clamp(info.first_axis + row, 0, 2)];
        if (d < 0) return false;
        rows->push_back({static_cast<int>(evaluated->size()) - 1, row});
        out->observation.push_back(d);
      }
    }
    out->first_row.push_back(static_cast<int>(rows->size()));
  }
  return true;
}

// The rows' cofactors J_a Qxx J_b^T = g_a^T C g_b, plus the point's own q_a^T V^-1 q_b when a
// and b share it, with g_a = E_a - W V^-1 q_a in the e columns (q_a = J_p,a^T; W made again from
// the point's rows, PointW). False when a row cannot be evaluated or the solve with the factor
// fails.
bool CandidateCofactors(const BundleRound& round, const ReducedNormals& reduced,
                        const std::vector<BlockRows>& evaluated,
                        const std::vector<CandidateRow>& rows, Eigen::MatrixXd* H) {
  const int n = static_cast<int>(rows.size());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(reduced.size, n);
  std::vector<BlockRows> scratch;
  Eigen::MatrixXd W;
  for (int a = 0; a < n; ++a) {
    const BlockRows& br = evaluated[rows[a].block_rows];
    const int row = rows[a].row;
    for (size_t k = 0; k < br.e_columns.size(); ++k) G(br.e_columns[k], a) += br.J_e(row, k);
    if (br.point < 0) continue;
    const int p = br.point;
    if (!EvaluatePointW(round, reduced, p, &scratch, &W)) return false;
    const Eigen::VectorXd WVq = W * (reduced.V_inverse[p] * br.J_p.row(row).transpose());
    SubtractAtPointBlocks(reduced, p, WVq, G.col(a));
  }
  *H = Eigen::MatrixXd::Zero(n, n);
  if (reduced.size > 0 && n > 0) {
    const Eigen::MatrixXd CG = reduced.C.Solve(G);
    if (!CG.allFinite()) return false;
    H->noalias() = G.transpose() * CG;
  }
  for (int a = 0; a < n; ++a) {
    const BlockRows& ra = evaluated[rows[a].block_rows];
    if (ra.point < 0) continue;
    for (int b = 0; b < n; ++b) {
      const BlockRows& rb = evaluated[rows[b].block_rows];
      if (rb.point != ra.point) continue;
      (*H)(a, b) += (ra.J_p.row(rows[a].row) * reduced.V_inverse[ra.point] *
                     rb.J_p.row(rows[b].row).transpose())
                        .value();
    }
  }
  return true;
}

// Batch data snooping's candidates (internal/bundle_statistics.h, SnoopingCandidates): the
// observations the w-test rejects, the largest |w| first, and the cofactors of their rows. Left
// not computed (the rounds then snoop one at a time) when a row cannot be evaluated or the solve
// fails.
void FindSnoopingCandidates(const BundleRound& round, const ReducedNormals& reduced,
                            const GroupVariance& variance, const BundleAdjustmentResult& result,
                            SnoopingCandidates* out) {
  const auto start = std::chrono::steady_clock::now();
  *out = SnoopingCandidates();
  const std::vector<std::pair<double, int64_t>> ranked = RankRejected(result, &out->num_flagged);
  const int num_candidates = static_cast<int>(ranked.size());
  std::unordered_map<int64_t, int> candidate_of;
  for (int c = 0; c < num_candidates; ++c) candidate_of[ranked[c].second] = c;
  // Each candidate row's diagnostics (by axis), and the largest |w| outside the candidates.
  std::vector<std::array<int, 3>> diagnostics_of(num_candidates, {-1, -1, -1});
  for (size_t k = 0; k < result.observations.size(); ++k) {
    const BundleObservationDiagnostics& d = result.observations[k];
    const auto found = candidate_of.find(ObservationKey(d.group, d.item));
    if (found != candidate_of.end())
      diagnostics_of[found->second][std::clamp<int>(d.axis, 0, 2)] = static_cast<int>(k);
    else if (std::isfinite(d.normalized))
      out->outside = std::max(out->outside, std::abs(d.normalized));
  }
  std::vector<BlockRows> evaluated;
  std::vector<CandidateRow> rows;
  if (!CandidateRows(round, reduced, candidate_of, diagnostics_of, &evaluated, &rows, out)) return;
  const int n = static_cast<int>(rows.size());
  out->v.resize(n);
  for (int a = 0; a < n; ++a) out->v[a] = evaluated[rows[a].block_rows].residuals[rows[a].row];
  Eigen::MatrixXd H;
  if (!CandidateCofactors(round, reduced, evaluated, rows, &H)) return;
  out->Qvv = Eigen::MatrixXd::Identity(n, n) - 0.5 * (H + H.transpose());
  out->sigma0 = result.summary.sigma0;
  out->redundancy = result.summary.redundancy;
  for (int g = 0; g < kNumBundleGroups; ++g) out->num_tested += variance.scalar_rows[g];
  out->computed = true;
  out->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Self-calibration: the estimated parameters of each calibrated camera, with their sigmas and
// correlations when the reduced normal matrix is known (`reduced` not null).
void CalibrationResults(const BundleAdjustmentOptions& options, const Block& block,
                        const BundlePlan& plan, const BundleState& state,
                        const ReducedNormals* reduced, double variance_factor,
                        BundleAdjustmentResult* result) {
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    if (plan.calibrated[c].empty()) continue;
    int e_block = -1;
    if (reduced != nullptr) {
      const auto found = reduced->e_index.find(state.cameras[c].data());
      if (found == reduced->e_index.end()) continue;
      e_block = found->second;
    }
    const int n = static_cast<int>(plan.calibrated[c].size());
    BundleCalibrationResult calibration;
    calibration.camera = static_cast<int>(c);
    const std::vector<std::string> names = CameraModelParamNames(block.cameras[c].model);
    for (const int index : plan.calibrated[c]) {
      calibration.indices.push_back(index);
      calibration.names.push_back(names[index]);
      calibration.values.push_back(state.cameras[c][index]);
    }
    if (reduced != nullptr) {
      Eigen::MatrixXd C;
      if (!reduced->C.Block(e_block, e_block, &C)) C = Eigen::MatrixXd::Constant(n, n, kNaN);
      C = variance_factor * C.topLeftCorner(n, n);
      for (int a = 0; a < n; ++a) calibration.sigmas.push_back(std::sqrt(std::max(C(a, a), 0.0)));
      calibration.correlation.resize(n, n);
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          calibration.correlation(a, b) = C(a, b) / (calibration.sigmas[a] * calibration.sigmas[b]);
          if (b > a && std::abs(calibration.correlation(a, b)) > options.statistics.high_correlation) {
            calibration.high_correlations.push_back(calibration.names[a] + "~" +
                                                    calibration.names[b] + ": " +
                                                    FormatSignificant(calibration.correlation(a, b), 3));
          }
        }
      }
    }
    result->calibration.push_back(std::move(calibration));
  }
}

}  // namespace

std::string OverfitMessage(const BundleGroupStatistics& group, const char* accuracy) {
  std::ostringstream message;
  message << EnumName(group.group) << " over-fitted: residual RMS " << FormatSignificant(group.ratio, 3)
          << " of the " << accuracy << " accuracy";
  if (std::isfinite(group.redundancy_share))
    message << ", redundancy share " << FormatSignificant(group.redundancy_share, 3);
  message << ". The adjustment bends to these priors: too few or too weak tie points, or a "
             "stated accuracy that is too loose.";
  if (group.group == kControlPoints)
    message << " Control points taken as error-free are held fixed with AccuracyX/Y/Z 0.";
  return message.str();
}

std::string LooseAccuracyMessage(const BundleGroupStatistics& group, const char* accuracy) {
  std::ostringstream message;
  message << EnumName(group.group) << ": residual RMS " << FormatSignificant(group.ratio, 3)
          << " of the " << accuracy << " accuracy, redundancy share "
          << FormatSignificant(group.redundancy_share, 3)
          << ". The block checks these priors and they fit better than " << accuracy
          << ": the accuracy is loose, not over-fitted; stated as measured, they would weigh "
             "more.";
  return message.str();
}

std::string OverfitNotJudgedMessage(const BundleGroupStatistics& group, const char* accuracy) {
  std::ostringstream message;
  message << EnumName(group.group) << ": residual RMS " << FormatSignificant(group.ratio, 3)
          << " of the " << accuracy
          << " accuracy; without the redundancy share (statistics not computed) it cannot be told "
             "whether the adjustment bends to these priors (over-fitted) or their accuracy is loose: "
             "not judged.";
  return message.str();
}

namespace {

// Control points in the round held fixed (no parameter block adjusted: stated error-free or in the
// config's constant points).
int NumFixedControlPoints(const Block& block, const BundlePlan& plan, const BundleRound& round) {
  std::vector<char> adjusted(block.points.size(), 0);
  for (const int p : round.point_of_block) adjusted[p] = 1;
  int fixed = 0;
  for (size_t p = 0; p < block.points.size(); ++p)
    fixed += plan.point_in_problem[p] && !adjusted[p] && block.points[p].role == PointRole::kControl;
  return fixed;
}

// The report's groups: counts, stated accuracies, RMS, ratio, redundancy share, over-fit flags; a
// group held fixed (only control points can be) without residuals or verdict.
void GroupStatistics(const BundleAdjustmentOptions& options, const GroupSums* sums,
                     const GroupVariance& variance, int num_fixed_control_points,
                     BundleAdjustmentResult* result) {
  for (int g = 0; g < kNumBundleGroups; ++g) {
    const GroupSums& s = sums[g];
    const int num_fixed = g == kControlPoints ? num_fixed_control_points : 0;
    if (s.count == 0 && num_fixed == 0) continue;
    BundleGroupStatistics group;
    group.group = static_cast<BundleGroup>(g);
    group.count = s.count;
    group.num_fixed = num_fixed;
    group.unit = s.unit;
    group.num_axes = (g == kTieMarks || g == kControlMarks) ? 2 : 3;
    if (group.fixed()) {
      group.ratio = group.redundancy_share = kNaN;
      result->groups.push_back(group);
      continue;
    }
    // Per axis over the rows it has (an axis without rows: 0, as the marks' Z).
    const Eigen::Vector3d rows_per_axis = s.rows.cwiseMax(1.0);
    group.stated_accuracy = s.stated.cwiseQuotient(rows_per_axis);
    group.rms = s.ssq.cwiseQuotient(rows_per_axis).cwiseSqrt();
    group.rms_total = std::sqrt(s.ssq.sum() / s.rows.sum());
    const int rows = variance.scalar_rows[g];
    group.ratio = std::sqrt(variance.whitened_ssq[g] / rows);
    group.redundancy_share = variance.redundancy[g] / rows;
    const bool prior = IsPriorGroup(static_cast<BundleGroup>(g));
    const bool share_known = std::isfinite(group.redundancy_share);
    const BundleStatisticsOptions& so = options.statistics;
    const bool follows_priors = share_known && group.redundancy_share < so.overfit_redundancy_share;
    const bool below = group.ratio < so.overfit_ratio;
    const bool checked = share_known && group.redundancy_share >= so.checked_redundancy_share;
    if (prior && (follows_priors || (below && share_known && !checked))) {
      group.overfit = true;
      group.message = OverfitMessage(group, "stated");
    } else if (prior && below && checked) {
      group.message = LooseAccuracyMessage(group, "stated");
    } else if (prior && below) {
      group.message = OverfitNotJudgedMessage(group, "stated");
    }
    result->groups.push_back(group);
  }
}

// The covariance of a check point with the images' and cameras' own uncertainty carried in. The
// point minimises sum_j |r_j(X, e)|^2, so dX/de = -N^-1 B (CheckPointSensitivity) and
// C_X = N^-1 + (N^-1 B) C (N^-1 B)^T (unscaled).
Eigen::Matrix3d PropagatedCheckPointCovariance(const Block& block, const BundleState& state,
                                               const BundleRound& round,
                                               const ReducedNormals& reduced,
                                               const std::vector<RayObservation>& rays,
                                               const std::vector<int>& marks,
                                               const TriangulationResult& intersection) {
  Eigen::Matrix3d N_inverse;
  Eigen::MatrixXd A;
  CheckPointSensitivity(block, state, round, reduced, rays, marks, intersection, &N_inverse, &A);
  // Its images need not share a tie point (check marks are not in the adjustment): C A^T
  // through the factor, three solves.
  return N_inverse + A * reduced.C.Solve(A.transpose());
}

// The parameter of tangent component t of e block b, in words (UnknownName); empty when not known.
std::string ParameterName(const Block& block, const BundlePlan& plan, const BundleState& state,
                          const BundleRound& round, int b, int t) {
  if (b < 0 || t < 0) return "";
  const double* e = round.e_blocks[b];
  for (size_t i = 0; i < block.images.size(); ++i)
    if (state.eo[i].data() == e)
      return UnknownName(block, UnknownKind::kOrientation, static_cast<int>(i),
                         OrientationComponent(plan, static_cast<int>(i), t));
  for (size_t c = 0; c < block.cameras.size(); ++c)
    if (state.cameras[c].data() == e && t < static_cast<int>(plan.calibrated[c].size()))
      return UnknownName(block, UnknownKind::kCalibration, static_cast<int>(c),
                         plan.calibrated[c][t]);
  if (e == state.lever.data()) return UnknownName(block, UnknownKind::kLeverArm, 0, t);
  return "";
}

// What a singular normal matrix leaves undetermined, in words: the parameter of the column where
// the factorisation found the rank defect, or the point whose rays do not determine it.
std::string Undetermined(const Block& block, const BundlePlan& plan, const BundleState& state,
                         const BundleRound& round, const ReducedNormals& reduced) {
  constexpr const char* kNotDetermined = " is not determined by the observations";
  if (reduced.undetermined_point >= 0) {
    const int p = round.point_of_block[reduced.undetermined_point];
    return "point '" + block.points[p].id + "' is not determined by its rays";
  }
  const std::string name = ParameterName(block, plan, state, round, reduced.singular_block,
                                         reduced.singular_component);
  return (name.empty() ? "a combination of parameters" : name) + kNotDetermined;
}

// Parameters of an absolute block whose sigma the trade-off with others inflates beyond
// options.statistics.weak_sigma_inflation (the datum is physical there; a relative block's gauge
// inflates its parameters by construction), the worst first.
void WeaklyDeterminedParameters(const BundleAdjustmentOptions& options, const Block& block,
                                const BundlePlan& plan, const BundleState& state,
                                const BundleRound& round, const ReducedNormals& reduced,
                                BundleAdjustmentResult* result) {
  if (plan.datum != BundleDatum::kControl) return;
  const double limit = options.statistics.weak_sigma_inflation;
  for (int b = 0; b < reduced.C.num_blocks(); ++b) {
    const Eigen::VectorXd inflation = reduced.C.VarianceInflation(b).cwiseSqrt();
    for (int t = 0; t < inflation.size(); ++t) {
      if (!(inflation[t] > limit)) continue;
      BundleWeakParameter weak;
      weak.parameter = ParameterName(block, plan, state, round, b, t);
      if (weak.parameter.empty()) weak.parameter = "a parameter of the reduced camera system";
      weak.sigma_inflation = inflation[t];
      result->weakly_determined.push_back(weak);
    }
  }
  std::sort(result->weakly_determined.begin(), result->weakly_determined.end(),
            [](const BundleWeakParameter& a, const BundleWeakParameter& b) {
              return a.sigma_inflation > b.sigma_inflation;
            });
}

// Control and check points: the shared table (internal/bundle_statistics.h), check points
// intersected from the adjusted images and cameras.
void ControlAndCheckPoints(const BundleAdjustmentOptions& options, const Block& block,
                           const BundleState& state, const BundleRound& round,
                           const ReducedNormals& reduced, double variance_factor,
                           BundleAdjustmentResult* result) {
  std::vector<BlockCamera> adjusted_cameras = block.cameras;
  for (size_t c = 0; c < adjusted_cameras.size(); ++c) adjusted_cameras[c].params = state.cameras[c];
  std::vector<const Vector6d*> eo(block.images.size());
  for (size_t i = 0; i < block.images.size(); ++i) eo[i] = &state.eo[i];
  CheckPointCovariance covariance;
  if (reduced.ok) {
    covariance = [&](const std::vector<RayObservation>& rays, const std::vector<int>& marks,
                     const TriangulationResult& intersection) {
      return PropagatedCheckPointCovariance(block, state, round, reduced, rays, marks,
                                            intersection);
    };
  }
  TabulateControlAndCheckPoints(block, eo, adjusted_cameras, options.accuracies, variance_factor,
                                covariance, result);
}

}  // namespace

void CheckPointSensitivity(const Block& block, const BundleState& state, const BundleRound& round,
                           const ReducedNormals& reduced, const std::vector<RayObservation>& rays,
                           const std::vector<int>& marks, const TriangulationResult& intersection,
                           Eigen::Matrix3d* N_inverse, Eigen::MatrixXd* A) {
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(3, reduced.size);
  for (size_t j = 0; j < rays.size(); ++j) {
    const int image = block.marks[marks[j]].image;
    const int camera = block.images[image].camera;
    const std::unique_ptr<ceres::CostFunction> cost(CreateRayCost(rays[j]));
    const int n = static_cast<int>(rays[j].camera->params.size());
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J_eo;
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J_X;
    Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor> J_cam(2, n);
    const double* eo = rays[j].eo.parameters.data();
    const double* params = rays[j].camera->params.data();
    const double* parameters[] = {eo, intersection.point_m.data(), params};
    double residual[2];
    double* jacobians[] = {J_eo.data(), J_X.data(), J_cam.data()};
    if (!cost->Evaluate(parameters, residual, jacobians)) continue;
    N += J_X.transpose() * J_X;
    // The e block's columns of `key` (the state's parameter block), its manifold's Jacobian at
    // `at` (the ray's value of it).
    auto add = [&](const double* key, const double* at, const Eigen::MatrixXd& J_ambient) {
      const auto found = reduced.e_index.find(key);
      if (found == reduced.e_index.end()) return;
      const int offset = reduced.e_offset[found->second];
      const int tangent = round.e_sizes[found->second];
      const ceres::Manifold* manifold = round.e_manifolds[found->second];
      Eigen::MatrixXd P = Eigen::MatrixXd::Identity(J_ambient.cols(), tangent);
      if (manifold != nullptr) {
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Pr(J_ambient.cols(),
                                                                                  tangent);
        manifold->PlusJacobian(at, Pr.data());
        P = Pr;
      }
      B.block(0, offset, 3, tangent) += J_X.transpose() * (J_ambient * P);
    };
    add(state.eo[image].data(), eo, J_eo);
    add(state.cameras[camera].data(), params, J_cam);
  }
  *N_inverse = N.ldlt().solve(Eigen::Matrix3d::Identity());
  *A = *N_inverse * B;
}

Status ComputeBundleStatistics(const BundleAdjustmentOptions& options, const Block& block,
                               const BundlePlan& plan, const BundleState& state,
                               const BundleRound& round, BundleAdjustmentResult* result,
                               GroupVariance* variance) {
  BundleAdjustmentSummary& summary = result->summary;
  const double sigma0 = summary.sigma0;
  const double variance_factor = std::isfinite(sigma0) ? sigma0 * sigma0 : 1.0;
  ResetStatistics(block, plan, result, variance);
  GroupSums sums[kNumBundleGroups];
  TabulateResiduals(block, plan, state, round, sums, result, variance);

  // Covariances and redundancy numbers from the reduced normal matrix (without them, the
  // adjustment checks its last round with CheckBundleDeterminacy).
  ReducedNormals reduced;
  const BundleCovarianceMethod method = options.statistics.covariances;
  const bool asked = method != BundleCovarianceMethod::kNone;
  if (asked) {
    SelectedInversionOptions inversion;
    inversion.dense = method == BundleCovarianceMethod::kDenseInverse;
    BuildReducedNormals(round, inversion, options.solver.num_threads, &reduced);
  }
  const bool covariances = reduced.ok;
  summary.covariance_entries = covariances ? reduced.C.num_entries() : 0;
  summary.covariance_memory_bytes = covariances ? reduced.C.memory_bytes() : 0;
  summary.factorization_seconds = covariances ? reduced.C.factorization_seconds() : 0.0;
  summary.inversion_seconds = covariances ? reduced.C.inversion_seconds() : 0.0;
  SetTestLevel(options, *variance, result);
  if (covariances) {
    InnerConstraintTransform inner;
    bool use_inner =
        plan.datum == BundleDatum::kRelative &&
        options.statistics.relative_covariance != BundleRelativeCovariance::kFirstImage;
    if (plan.datum != BundleDatum::kRelative) {
      summary.covariance_datum = "the block's datum (absolute)";
    } else {
      summary.covariance_datum = "the adjustment's gauge (" + RelativeGaugeInWords(block, plan) + ")";
      if (use_inner) {
        const Status datum = inner.Compute(options.statistics.relative_covariance, block, plan,
                                           state, round, reduced, options.solver.num_threads);
        use_inner = datum.ok();
        summary.covariance_datum =
            use_inner ? inner.description() : summary.covariance_datum + ", because " + datum.message();
      }
    }
    OrientationAndFixedPointCovariances(block, plan, state, round, reduced,
                                        use_inner ? &inner : nullptr, variance_factor, result);
    ObservationDiagnostics(options, block, plan, state, round, reduced, use_inner ? &inner : nullptr,
                           variance_factor, options.statistics.observation_diagnostics, sums,
                           result, variance);
    CalibrationResults(options, block, plan, state, &reduced, variance_factor, result);
    WeaklyDeterminedParameters(options, block, plan, state, round, reduced, result);
    if (options.robustness.snoop && options.robustness.snooping_batch &&
        options.statistics.observation_diagnostics)
    {
      FindSnoopingCandidates(round, reduced, *variance, *result, &variance->snooping);
      summary.snooping_seconds += variance->snooping.seconds;
    }
  } else {
    for (int g = 0; g < kNumBundleGroups; ++g) variance->redundancy[g] = kNaN;
    CalibrationResults(options, block, plan, state, nullptr, variance_factor, result);
    summary.message = asked ? "no covariances: " + reduced.message
                            : "covariances not computed (statistics turned off)";
  }
  if (plan.use_lever) result->lever_arm_m = state.lever;
  GroupStatistics(options, sums, *variance, NumFixedControlPoints(block, plan, round), result);
  ControlAndCheckPoints(options, block, state, round, reduced, variance_factor, result);
  if (reduced.singular)
    return Status::Error("the normal matrix is singular: " +
                         Undetermined(block, plan, state, round, reduced));
  return Status::Ok();
}

Status CheckBundleDeterminacy(const Block& block, const BundlePlan& plan, const BundleState& state,
                              const BundleRound& round, int num_threads,
                              double* factorization_seconds) {
  ReducedNormals reduced;
  SelectedInversionOptions factor_only;
  factor_only.factor_only = true;
  BuildReducedNormals(round, factor_only, num_threads, &reduced);
  *factorization_seconds = reduced.C.factorization_seconds();
  if (reduced.singular)
    return Status::Error("the normal matrix is singular: " +
                         Undetermined(block, plan, state, round, reduced));
  return Status::Ok();
}

}  // namespace photopose::internal
