// The statistics of a converged bundle adjustment round: residuals per group, covariances from
// the reduced normal matrix, redundancy numbers, normalized residuals and reliability (Baarda,
// Foerstner), self-calibration correlations, check points.
#include "solvers/bundle/internal/bundle_statistics.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "core/rotation.h"
#include "core/statistics.h"
#include "solvers/bundle/triangulation.h"

namespace photopose::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// A redundancy number below this is zero in all but rounding: the observation is not checked at
// all and its normalized residual is undefined.
constexpr double kZeroRedundancy = 1e-6;
// The smallest pivot of the Jacobi-scaled reduced normal matrix relative to its largest below
// which the matrix is treated as singular (a datum defect in all but name).
constexpr double kSingularPivot = 1e-12;

std::string Format3(double value) {
  std::ostringstream os;
  os.precision(3);
  os << value;
  return os.str();
}

// Sparse vector in e space.
struct SparseE {
  std::vector<int> index;
  std::vector<double> value;
  void Add(int i, double v) {
    for (size_t k = 0; k < index.size(); ++k) {
      if (index[k] == i) {
        value[k] += v;
        return;
      }
    }
    index.push_back(i);
    value.push_back(v);
  }
};

}  // namespace

bool EvaluateBlockRows(const BundleRound& round, const ReducedNormals& reduced,
                       const ResidualInfo& info, BlockRows* out) {
  ceres::Problem& problem = *round.problem;
  const int num_residuals = problem.GetCostFunctionForResidualBlock(info.id)->num_residuals();
  std::vector<double*> parameters;
  problem.GetParameterBlocksForResidualBlock(info.id, &parameters);
  std::vector<double*> jacobians(parameters.size(), nullptr);
  std::vector<std::vector<double>> storage(parameters.size());
  for (size_t k = 0; k < parameters.size(); ++k) {
    double* block = parameters[k];
    if (problem.IsParameterBlockConstant(block)) continue;
    const int tangent = problem.ParameterBlockTangentSize(block);
    storage[k].assign(static_cast<size_t>(num_residuals) * tangent, 0.0);
    jacobians[k] = storage[k].data();
  }
  double cost;
  out->residuals.assign(num_residuals, 0.0);
  if (!problem.EvaluateResidualBlock(info.id, false, &cost, out->residuals.data(),
                                     jacobians.data()))
    return false;
  out->rows = num_residuals;
  out->e_columns.clear();
  out->point = -1;
  out->J_p.resize(0, 3);
  std::vector<std::pair<int, int>> e_parts;  // (parameter k, tangent size)
  for (size_t k = 0; k < parameters.size(); ++k) {
    if (jacobians[k] == nullptr) continue;
    const int tangent = problem.ParameterBlockTangentSize(parameters[k]);
    const auto e = reduced.e_index.find(parameters[k]);
    if (e != reduced.e_index.end()) {
      for (int c = 0; c < tangent; ++c) out->e_columns.push_back(reduced.e_offset[e->second] + c);
      e_parts.push_back({static_cast<int>(k), tangent});
    } else {
      const auto p = reduced.point_index.find(parameters[k]);
      if (p == reduced.point_index.end()) continue;
      out->point = p->second;
      out->J_p = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
          jacobians[k], num_residuals, 3);
    }
  }
  out->J_e.resize(num_residuals, static_cast<int>(out->e_columns.size()));
  int column = 0;
  for (const auto& [k, tangent] : e_parts) {
    for (int r = 0; r < num_residuals; ++r)
      for (int c = 0; c < tangent; ++c) out->J_e(r, column + c) = jacobians[k][r * tangent + c];
    column += tangent;
  }
  return true;
}

void BuildReducedNormals(const BundleRound& round, ReducedNormals* reduced) {
  *reduced = ReducedNormals();
  int offset = 0;
  for (size_t b = 0; b < round.e_blocks.size(); ++b) {
    reduced->e_index[round.e_blocks[b]] = static_cast<int>(b);
    reduced->e_offset.push_back(offset);
    offset += round.e_sizes[b];
  }
  reduced->size = offset;
  for (size_t p = 0; p < round.point_blocks.size(); ++p)
    reduced->point_index[round.point_blocks[p]] = static_cast<int>(p);
  const size_t num_points = round.point_blocks.size();
  std::vector<Eigen::Matrix3d> V(num_points, Eigen::Matrix3d::Zero());
  std::vector<std::map<int, Eigen::RowVector3d>> W_rows(num_points);
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(offset, offset);
  BlockRows rows;
  for (const ResidualInfo& info : round.residuals) {
    if (!EvaluateBlockRows(round, *reduced, info, &rows)) return;
    const int ne = static_cast<int>(rows.e_columns.size());
    if (ne > 0) {
      const Eigen::MatrixXd JtJ = rows.J_e.transpose() * rows.J_e;
      for (int a = 0; a < ne; ++a)
        for (int b = 0; b < ne; ++b) S(rows.e_columns[a], rows.e_columns[b]) += JtJ(a, b);
    }
    if (rows.point >= 0) {
      V[rows.point] += rows.J_p.transpose() * rows.J_p;
      if (ne > 0) {
        const Eigen::MatrixXd JeJp = rows.J_e.transpose() * rows.J_p;
        for (int a = 0; a < ne; ++a) {
          auto [it, inserted] = W_rows[rows.point].emplace(rows.e_columns[a], JeJp.row(a));
          if (!inserted) it->second += JeJp.row(a);
        }
      }
    }
  }
  reduced->V_inverse.resize(num_points);
  reduced->W_columns.resize(num_points);
  reduced->W.resize(num_points);
  for (size_t p = 0; p < num_points; ++p) {
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(V[p]);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return;
    reduced->V_inverse[p] = ldlt.solve(Eigen::Matrix3d::Identity());
    const int k = static_cast<int>(W_rows[p].size());
    reduced->W_columns[p].reserve(k);
    reduced->W[p].resize(k, 3);
    int row = 0;
    for (const auto& [column, values] : W_rows[p]) {
      reduced->W_columns[p].push_back(column);
      reduced->W[p].row(row++) = values;
    }
    const Eigen::MatrixXd update =
        reduced->W[p] * reduced->V_inverse[p] * reduced->W[p].transpose();
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b)
        S(reduced->W_columns[p][a], reduced->W_columns[p][b]) -= update(a, b);
  }
  if (offset == 0) {
    reduced->ok = true;
    return;
  }
  // Jacobi scaling first: camera parameters in mixed units (um next to mm^-6) give diagonals
  // twenty orders of magnitude apart, which would hide a real rank defect or fake one.
  const Eigen::VectorXd d = S.diagonal();
  if (!(d.minCoeff() > 0.0)) return;
  const Eigen::VectorXd scale = d.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * S * scale.asDiagonal();
  S.resize(0, 0);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(scaled);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return;
  if (!(ldlt.vectorD().minCoeff() > kSingularPivot * ldlt.vectorD().maxCoeff())) return;
  reduced->C = scale.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(offset, offset)) *
               scale.asDiagonal();
  reduced->ok = reduced->C.allFinite();
}

Eigen::Matrix3d PointCovariance(const ReducedNormals& reduced, int p) {
  const std::vector<int>& cols = reduced.W_columns[p];
  const int k = static_cast<int>(cols.size());
  Eigen::MatrixXd C_sub(k, k);
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b) C_sub(a, b) = reduced.C(cols[a], cols[b]);
  const Eigen::Matrix3d& Vi = reduced.V_inverse[p];
  const Eigen::MatrixXd WV = reduced.W[p] * Vi;  // k x 3
  return Vi + WV.transpose() * C_sub * WV;
}

// With `shift`, also C_rows g_i per row: the shift of the parameters in the rows of C_rows (the
// camera-centre rows of C: the external reliability needs no others) per unit whitened error.
Eigen::VectorXd Leverages(const ReducedNormals& reduced, const BlockRows& rows,
                          const Eigen::MatrixXd* C_rows, std::vector<Eigen::VectorXd>* shift) {
  // h_i = g_i^T C g_i + J_p,i V^-1 J_p,i^T with g_i = J_e,i^T - W V^-1 J_p,i^T (e space): the
  // point's own part and its elimination folded into one sparse vector per row.
  Eigen::VectorXd h(rows.rows);
  if (shift != nullptr) shift->assign(rows.rows, Eigen::VectorXd());
  for (int r = 0; r < rows.rows; ++r) {
    SparseE g;
    for (size_t a = 0; a < rows.e_columns.size(); ++a) g.Add(rows.e_columns[a], rows.J_e(r, a));
    double point_part = 0.0;
    if (rows.point >= 0) {
      const Eigen::Vector3d Jp = rows.J_p.row(r).transpose();
      const Eigen::Vector3d VJ = reduced.V_inverse[rows.point] * Jp;
      point_part = Jp.dot(VJ);
      const Eigen::VectorXd WVJ = reduced.W[rows.point] * VJ;
      for (size_t a = 0; a < reduced.W_columns[rows.point].size(); ++a)
        g.Add(reduced.W_columns[rows.point][a], -WVJ[a]);
    }
    double quadratic = 0.0;
    for (size_t a = 0; a < g.index.size(); ++a) {
      for (size_t b = 0; b < g.index.size(); ++b)
        quadratic += g.value[a] * reduced.C(g.index[a], g.index[b]) * g.value[b];
    }
    h[r] = quadratic + point_part;
    if (shift != nullptr) {
      Eigen::VectorXd& s = (*shift)[r];
      s = Eigen::VectorXd::Zero(C_rows->rows());
      for (size_t b = 0; b < g.index.size(); ++b) s += C_rows->col(g.index[b]) * g.value[b];
    }
  }
  return h;
}

// ------------------------------------------------------------------ the steps of the statistics
namespace {

// Per group: count, per-axis sums of squared residuals and of stated sigmas (in the group's
// unit), and the leverage (sum of hat-matrix diagonals) once known.
struct GroupSums {
  int count = 0;
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
  sums[kTieMarks].unit = sums[kControlMarks].unit = "px";
  sums[kControlPoints].unit = sums[kCameraPositions].unit = "m";
  sums[kAttitudes].unit = "deg";
  std::vector<double> image_ssq(block.images.size(), 0.0);
  bool film_marks = false;
  for (const ResidualInfo& info : round.residuals) {
    double whitened[3] = {0.0, 0.0, 0.0};
    double cost;
    round.problem->EvaluateResidualBlock(info.id, false, &cost, whitened, nullptr);
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
      s.ssq.head<2>() += residual.cwiseAbs2();
      s.stated.head<2>() += Eigen::Vector2d::Constant(scale);
      film_marks |= mark.unit == MarkUnit::kFilm;
      BundleImageResult& image = result->images[mark.image];
      ++image.num_marks;
      image_ssq[mark.image] += residual.squaredNorm();
      image.unit = EnumName(mark.unit);
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
    }
  }
  if (film_marks) sums[kTieMarks].unit = sums[kControlMarks].unit = "px or um";
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
  const double alpha_each = options.statistics.snooping_family_wise
                                ? options.statistics.snooping_alpha / std::max(1, num_tested)
                                : options.statistics.snooping_alpha;
  result->alpha_per_observation = alpha_each;
  result->critical_value = NormalQuantile(1.0 - 0.5 * alpha_each);
  result->delta0 = result->critical_value + NormalQuantile(options.statistics.snooping_power);
}

// Exterior orientations, in the ambient (Euler) parameters (P C P^T), and control points.
void OrientationAndPointCovariances(const Block& block, const BundleState& state,
                                    const BundleRound& round, const ReducedNormals& reduced,
                                    double variance_factor, BundleAdjustmentResult* result) {
  for (size_t i = 0; i < block.images.size(); ++i) {
    const double* eo = state.eo[i].data();
    const auto found = reduced.e_index.find(eo);
    if (found == reduced.e_index.end()) continue;
    const int offset = reduced.e_offset[found->second];
    const int tangent = round.e_sizes[found->second];
    Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor> P(6, tangent);
    round.problem->GetManifold(const_cast<double*>(eo))->PlusJacobian(eo, P.data());
    const Eigen::MatrixXd C = reduced.C.block(offset, offset, tangent, tangent);
    result->images[i].covariance = variance_factor * P * C * P.transpose();
    result->images[i].has_covariance = true;
  }
  for (const auto& [block_ptr, index] : reduced.point_index) {
    const int p = round.point_of_block[index];
    if (block.points[p].role != PointRole::kControl) continue;
    result->points[p].covariance = variance_factor * PointCovariance(reduced, index);
    result->points[p].has_covariance = true;
  }
}

// The camera-centre columns of the e space (tangent components 0..2 of each image block; the
// relative gauge's scale image has one of them held), for the external reliability, with C
// restricted to those rows (C is symmetric: its columns), so that the shifts cost half the full
// products (measured: 58.6 s of statistics at 300 images before).
struct CentreColumns {
  struct Image {
    int offset;  // first row in `C_rows`
    int count;
  };
  std::vector<Image> images;
  Eigen::MatrixXd C_rows;
};

CentreColumns MakeCentreColumns(const Block& block, const BundlePlan& plan,
                                const BundleState& state, const ReducedNormals& reduced,
                                bool with_rows) {
  CentreColumns centres;
  std::vector<int> rows;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const auto found = reduced.e_index.find(state.eo[i].data());
    if (found == reduced.e_index.end()) continue;
    const int count = static_cast<int>(i) == plan.relative_scale_image ? 2 : 3;
    centres.images.push_back({static_cast<int>(rows.size()), count});
    for (int k = 0; k < count; ++k) rows.push_back(reduced.e_offset[found->second] + k);
  }
  if (with_rows) {
    centres.C_rows.resize(static_cast<Eigen::Index>(rows.size()), reduced.size);
    for (size_t r = 0; r < rows.size(); ++r)
      centres.C_rows.row(static_cast<Eigen::Index>(r)) = reduced.C.col(rows[r]).transpose();
  }
  return centres;
}

// The diagnostics of one row: redundancy number, normalized residual (w-test against the
// critical value), smallest detectable error and its largest camera-centre shift.
BundleObservationDiagnostics RowDiagnostics(const BundleAdjustmentResult& result,
                                            const ResidualInfo& info, int row, double whitened,
                                            double scale, double leverage, double s0,
                                            const CentreColumns& centres,
                                            const Eigen::VectorXd& shift) {
  BundleObservationDiagnostics d;
  d.group = static_cast<BundleGroup>(info.group);
  d.item = info.item;
  d.axis = info.first_axis + row;
  d.residual = whitened * scale;
  d.sigma = scale;
  d.redundancy = std::clamp(1.0 - leverage, 0.0, 1.0);
  if (d.redundancy > kZeroRedundancy) {
    d.normalized = whitened / (s0 * std::sqrt(d.redundancy));
    d.mdb = result.delta0 * scale / std::sqrt(d.redundancy);
    // The largest camera-centre shift from a whitened error mdb / sigma in this row.
    const double delta = result.delta0 / std::sqrt(d.redundancy);
    double largest = 0.0;
    for (const CentreColumns::Image& centre : centres.images)
      largest = std::max(largest, shift.segment(centre.offset, centre.count).norm());
    d.external_m = largest * delta;
    d.rejected = std::abs(d.normalized) > result.critical_value;
  } else {
    d.normalized = kNaN;
    d.mdb = kInfinity;
    d.external_m = kInfinity;
  }
  return d;
}

// Leverages per group (variance->redundancy) and, with `diagnostics`, every observation's
// diagnostics. Without them the tie marks' share is the remainder (the sum of all redundancy
// numbers is the redundancy), which spares their rows.
void ObservationDiagnostics(const BundleAdjustmentOptions& options, const Block& block,
                            const BundlePlan& plan, const BundleState& state,
                            const BundleRound& round, const ReducedNormals& reduced,
                            bool diagnostics, GroupSums* sums, BundleAdjustmentResult* result,
                            GroupVariance* variance) {
  const CentreColumns centres = MakeCentreColumns(block, plan, state, reduced, diagnostics);
  // The yardstick of the normalized residuals: the stated accuracies (sigma0 = 1), or the
  // a-posteriori sigma0 when the data say they were optimistic (Pope's tau-test then).
  const double sigma0 = result->summary.sigma0;
  const double s0 = std::isfinite(sigma0) ? std::max(1.0, sigma0) : 1.0;
  BlockRows rows;
  std::vector<Eigen::VectorXd> shifts;
  for (const ResidualInfo& info : round.residuals) {
    if (!diagnostics && info.group == kTieMarks) continue;  // its share is the remainder
    if (!EvaluateBlockRows(round, reduced, info, &rows)) continue;
    const Eigen::VectorXd h =
        Leverages(reduced, rows, &centres.C_rows, diagnostics ? &shifts : nullptr);
    for (int row = 0; row < info.rows; ++row) sums[info.group].leverage += h[row];
    if (!diagnostics) continue;
    for (int row = 0; row < info.rows; ++row) {
      const BundleObservationDiagnostics d =
          RowDiagnostics(*result, info, row, rows.residuals[row],
                         RowScale(block, plan, info, row), h[row], s0, centres, shifts[row]);
      if (d.redundancy < options.statistics.uncontrolled_redundancy) ++result->num_uncontrolled;
      result->observations.push_back(d);
    }
  }
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

// Self-calibration: the estimated parameters of each calibrated camera, with their sigmas and
// correlations when the reduced normal matrix is known (`reduced` not null).
void CalibrationResults(const BundleAdjustmentOptions& options, const Block& block,
                        const BundlePlan& plan, const BundleState& state,
                        const ReducedNormals* reduced, double variance_factor,
                        BundleAdjustmentResult* result) {
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    if (plan.calibrated[c].empty()) continue;
    int offset = -1;
    if (reduced != nullptr) {
      const auto found = reduced->e_index.find(state.cameras[c].data());
      if (found == reduced->e_index.end()) continue;
      offset = reduced->e_offset[found->second];
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
      const Eigen::MatrixXd C = variance_factor * reduced->C.block(offset, offset, n, n);
      for (int a = 0; a < n; ++a) calibration.sigmas.push_back(std::sqrt(std::max(C(a, a), 0.0)));
      calibration.correlation.resize(n, n);
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          calibration.correlation(a, b) = C(a, b) / (calibration.sigmas[a] * calibration.sigmas[b]);
          if (b > a && std::abs(calibration.correlation(a, b)) > options.statistics.high_correlation) {
            calibration.high_correlations.push_back(calibration.names[a] + "~" +
                                                    calibration.names[b] + ": " +
                                                    Format3(calibration.correlation(a, b)));
          }
        }
      }
    }
    result->calibration.push_back(std::move(calibration));
  }
}

// The report's groups: counts, stated accuracies, RMS, ratio, redundancy share, over-fit flags.
void GroupStatistics(const BundleAdjustmentOptions& options, const GroupSums* sums,
                     const GroupVariance& variance, BundleAdjustmentResult* result) {
  for (int g = 0; g < kNumBundleGroups; ++g) {
    const GroupSums& s = sums[g];
    if (s.count == 0) continue;
    BundleGroupStatistics group;
    group.group = static_cast<BundleGroup>(g);
    group.count = s.count;
    group.unit = s.unit;
    group.num_axes = (g == kTieMarks || g == kControlMarks) ? 2 : 3;
    group.stated_accuracy = s.stated / s.count;
    group.rms = (s.ssq / s.count).cwiseSqrt();
    group.rms_total = std::sqrt(s.ssq.sum() / (s.count * group.num_axes));
    const int rows = variance.scalar_rows[g];
    group.ratio = std::sqrt(variance.whitened_ssq[g] / rows);
    group.redundancy_share = variance.redundancy[g] / rows;
    const bool prior = g == kControlPoints || g == kCameraPositions || g == kAttitudes;
    const bool share_known = std::isfinite(group.redundancy_share);
    if (prior && (group.ratio < options.statistics.overfit_ratio ||
                  (share_known && group.redundancy_share < options.statistics.overfit_redundancy_share))) {
      group.overfit = true;
      std::ostringstream message;
      message << EnumName(group.group) << " over-fitted: residual RMS " << Format3(group.ratio)
              << " of the stated accuracy";
      if (share_known) message << ", redundancy share " << Format3(group.redundancy_share);
      message << ". The adjustment bends to these priors: too few or too weak tie points, or a "
                 "stated accuracy that is too loose.";
      group.message = message.str();
    }
    result->groups.push_back(group);
  }
}

// The covariance of a check point with the images' and cameras' own uncertainty carried in. The
// point minimises sum_j |r_j(X, e)|^2, so dX/de = -N^-1 B with N = sum_j J_X,j^T J_X,j and
// B = sum_j J_X,j^T J_e,j (whitened, e in the tangent spaces of the reduced system), and
// C_X = N^-1 + (N^-1 B) C (N^-1 B)^T (unscaled).
Eigen::Matrix3d PropagatedCheckPointCovariance(const Block& block, const BundleState& state,
                                               const BundleRound& round,
                                               const ReducedNormals& reduced,
                                               const std::vector<RayObservation>& rays,
                                               const std::vector<int>& marks,
                                               const TriangulationResult& intersection) {
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(3, reduced.size);
  for (size_t j = 0; j < rays.size(); ++j) {
    const int image = block.marks[marks[j]].image;
    const int camera = block.images[image].camera;
    const std::unique_ptr<ceres::CostFunction> cost(CreateCollinearityCost(
        JacobianType::kAnalytic, CollinearityFunctor(rays[j].camera->model, rays[j].observation,
                                                     rays[j].camera->data(), 1.0 / rays[j].sigma)));
    const int n = static_cast<int>(state.cameras[camera].size());
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J_eo;
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J_X;
    Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor> J_cam(2, n);
    const double* parameters[] = {state.eo[image].data(), intersection.point_m.data(),
                                  state.cameras[camera].data()};
    double residual[2];
    double* jacobians[] = {J_eo.data(), J_X.data(), J_cam.data()};
    if (!cost->Evaluate(parameters, residual, jacobians)) continue;
    N += J_X.transpose() * J_X;
    auto add = [&](const double* block_ptr, const Eigen::MatrixXd& J_ambient) {
      const auto found = reduced.e_index.find(block_ptr);
      if (found == reduced.e_index.end()) return;
      const int offset = reduced.e_offset[found->second];
      const int tangent = round.e_sizes[found->second];
      const ceres::Manifold* manifold = round.problem->GetManifold(const_cast<double*>(block_ptr));
      Eigen::MatrixXd P = Eigen::MatrixXd::Identity(J_ambient.cols(), tangent);
      if (manifold != nullptr) {
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Pr(
            J_ambient.cols(), tangent);
        manifold->PlusJacobian(block_ptr, Pr.data());
        P = Pr;
      }
      B.block(0, offset, 3, tangent) += J_X.transpose() * (J_ambient * P);
    };
    add(state.eo[image].data(), J_eo);
    add(state.cameras[camera].data(), J_cam);
  }
  const Eigen::Matrix3d N_inverse = N.ldlt().solve(Eigen::Matrix3d::Identity());
  const Eigen::MatrixXd A = N_inverse * B;
  return N_inverse + A * reduced.C * A.transpose();
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

void ComputeBundleStatistics(const BundleAdjustmentOptions& options, const Block& block,
                             const BundlePlan& plan, const BundleState& state,
                             const BundleRound& round, BundleAdjustmentResult* result,
                             GroupVariance* variance) {
  BundleAdjustmentSummary& summary = result->summary;
  const double sigma0 = summary.sigma0;
  const double variance_factor = std::isfinite(sigma0) ? sigma0 * sigma0 : 1.0;
  ResetStatistics(block, plan, result, variance);
  GroupSums sums[kNumBundleGroups];
  TabulateResiduals(block, plan, state, round, sums, result, variance);

  // Covariances and redundancy numbers from the reduced normal matrix.
  ReducedNormals reduced;
  int e_size = 0;
  for (const int size : round.e_sizes) e_size += size;
  const bool asked = e_size <= options.statistics.max_covariance_parameters;
  if (asked) BuildReducedNormals(round, &reduced);
  SetTestLevel(options, *variance, result);
  if (reduced.ok) {
    OrientationAndPointCovariances(block, state, round, reduced, variance_factor, result);
    ObservationDiagnostics(options, block, plan, state, round, reduced,
                           options.statistics.observation_diagnostics, sums, result, variance);
    CalibrationResults(options, block, plan, state, &reduced, variance_factor, result);
  } else {
    for (int g = 0; g < kNumBundleGroups; ++g) variance->redundancy[g] = kNaN;
    CalibrationResults(options, block, plan, state, nullptr, variance_factor, result);
    summary.message = asked ? "the normal matrix is singular: no covariances"
                            : "covariances skipped (" + std::to_string(e_size) +
                                  " parameters after point elimination, more than " +
                                  std::to_string(options.statistics.max_covariance_parameters) + ")";
  }
  if (plan.use_lever) result->lever_arm_m = state.lever;
  GroupStatistics(options, sums, *variance, result);
  ControlAndCheckPoints(options, block, state, round, reduced, variance_factor, result);
}

}  // namespace photopose::internal
