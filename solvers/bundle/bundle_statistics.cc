// The statistics of a converged bundle adjustment round: residuals per group, covariances from
// the reduced normal matrix, redundancy numbers, normalized residuals and reliability (Baarda,
// Foerstner), self-calibration correlations, check points.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "core/rotation.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/check_points.h"
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

double NormalQuantile(double p) {
  // Phi(x) = erfc(-x / sqrt 2) / 2 is increasing; bisect on [-40, 40].
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

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

void ComputeBundleStatistics(const BundleAdjustmentOptions& options, const Block& block,
                             const BundlePlan& plan, const BundleState& state,
                             const BundleRound& round, BundleAdjustmentResult* result,
                             GroupVariance* variance) {
  BundleAdjustmentSummary& summary = result->summary;
  *variance = GroupVariance();
  const double sigma0 = summary.sigma0;
  const double variance_factor = std::isfinite(sigma0) ? sigma0 * sigma0 : 1.0;
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

  // Per group: count, per-axis sums of squared residuals and of stated sigmas (in the group's
  // unit), and the leverage (sum of hat-matrix diagonals) once known.
  struct Sums {
    int count = 0;
    Eigen::Vector3d ssq = Eigen::Vector3d::Zero();
    Eigen::Vector3d stated = Eigen::Vector3d::Zero();
    double leverage = 0.0;
    std::string unit;
  };
  Sums sums[kNumBundleGroups];
  sums[kTieMarks].unit = sums[kControlMarks].unit = "px";
  sums[kControlPoints].unit = sums[kCameraPositions].unit = "m";
  sums[kAttitudes].unit = "deg";

  // Residuals of every observation in its unit, from the round's whitened residuals.
  std::vector<double> image_ssq(block.images.size(), 0.0);
  bool film_marks = false;
  // The unit scale of one row: residual (unit) = whitened * scale.
  auto row_scale = [&](const ResidualInfo& info, int row) -> double {
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
  };
  for (const ResidualInfo& info : round.residuals) {
    double whitened[3] = {0.0, 0.0, 0.0};
    double cost;
    round.problem->EvaluateResidualBlock(info.id, false, &cost, whitened, nullptr);
    Sums& s = sums[info.group];
    variance->scalar_rows[info.group] += info.rows;
    for (int row = 0; row < info.rows; ++row)
      variance->whitened_ssq[info.group] += whitened[row] * whitened[row];
    if (info.group == kTieMarks || info.group == kControlMarks) {
      const BlockMark& mark = block.marks[info.item];
      const double scale = row_scale(info, 0);
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
      ++summary.num_marks;
      continue;
    }
    if (info.group != kControlPoints || info.first_axis == 0) ++s.count;
    for (int row = 0; row < info.rows; ++row) {
      const int axis = info.first_axis + row;
      const double scale = row_scale(info, row);
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

  // Covariances and redundancy numbers from the reduced normal matrix.
  ReducedNormals reduced;
  int e_size = 0;
  for (const int size : round.e_sizes) e_size += size;
  const bool asked = e_size <= options.max_covariance_parameters;
  if (asked) BuildReducedNormals(round, &reduced);
  const bool diagnostics = reduced.ok && options.observation_diagnostics;
  // The w-test's level: alpha for the whole block (Bonferroni: alpha / n per observation) unless
  // asked per observation; with tens of thousands of observations a per-observation 0.1 % would
  // reject dozens of good ones.
  int num_tested = 0;
  for (int g = 0; g < kNumBundleGroups; ++g) num_tested += variance->scalar_rows[g];
  const double alpha_each = options.snooping_family_wise
                                ? options.snooping_alpha / std::max(1, num_tested)
                                : options.snooping_alpha;
  result->alpha_per_observation = alpha_each;
  result->critical_value = NormalQuantile(1.0 - 0.5 * alpha_each);
  result->delta0 = result->critical_value + NormalQuantile(options.snooping_power);
  if (reduced.ok) {
    // Exterior orientations, in the ambient (Euler) parameters: P C P^T.
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
    // The camera-centre columns of the e space (tangent components 0..2 of each image block; the
    // relative gauge's scale image has one of them held), for the external reliability.
    struct CentreColumns {
      int offset;
      int count;
    };
    // C restricted to those rows (C is symmetric: its columns), so that the shifts cost half the
    // full products (measured: 58.6 s of statistics at 300 images before).
    std::vector<CentreColumns> centres;
    std::vector<int> centre_rows;
    for (size_t i = 0; i < block.images.size(); ++i) {
      const auto found = reduced.e_index.find(state.eo[i].data());
      if (found == reduced.e_index.end()) continue;
      const int count = static_cast<int>(i) == plan.relative_scale_image ? 2 : 3;
      centres.push_back({static_cast<int>(centre_rows.size()), count});
      for (int k = 0; k < count; ++k) centre_rows.push_back(reduced.e_offset[found->second] + k);
    }
    Eigen::MatrixXd C_centres;
    if (diagnostics) {
      C_centres.resize(static_cast<Eigen::Index>(centre_rows.size()), reduced.size);
      for (size_t r = 0; r < centre_rows.size(); ++r)
        C_centres.row(static_cast<Eigen::Index>(r)) = reduced.C.col(centre_rows[r]).transpose();
    }
    // The yardstick of the normalized residuals: the stated accuracies (sigma0 = 1), or the
    // a-posteriori sigma0 when the data say they were optimistic (Pope's tau-test then).
    const double s0 = std::isfinite(sigma0) ? std::max(1.0, sigma0) : 1.0;
    BlockRows rows;
    std::vector<Eigen::VectorXd> shifts;
    for (const ResidualInfo& info : round.residuals) {
      if (!diagnostics && info.group == kTieMarks) continue;  // its share is the remainder
      if (!EvaluateBlockRows(round, reduced, info, &rows)) continue;
      const Eigen::VectorXd h =
          Leverages(reduced, rows, &C_centres, diagnostics ? &shifts : nullptr);
      for (int row = 0; row < info.rows; ++row) sums[info.group].leverage += h[row];
      if (!diagnostics) continue;
      for (int row = 0; row < info.rows; ++row) {
        BundleObservationDiagnostics d;
        d.group = info.group;
        d.item = info.item;
        d.axis = info.first_axis + row;
        const double scale = row_scale(info, row);
        d.residual = rows.residuals[row] * scale;
        d.sigma = scale;
        d.redundancy = std::clamp(1.0 - h[row], 0.0, 1.0);
        if (d.redundancy > kZeroRedundancy) {
          d.normalized = rows.residuals[row] / (s0 * std::sqrt(d.redundancy));
          d.mdb = result->delta0 * scale / std::sqrt(d.redundancy);
          // The largest camera-centre shift from a whitened error mdb / sigma in this row.
          const double delta = result->delta0 / std::sqrt(d.redundancy);
          double largest = 0.0;
          for (const CentreColumns& centre : centres)
            largest = std::max(largest, shifts[row].segment(centre.offset, centre.count).norm());
          d.external_m = largest * delta;
          d.rejected = std::abs(d.normalized) > result->critical_value;
        } else {
          d.normalized = kNaN;
          d.mdb = kInfinity;
          d.external_m = kInfinity;
        }
        if (d.redundancy < options.uncontrolled_redundancy) ++result->num_uncontrolled;
        result->observations.push_back(d);
      }
    }
    if (!diagnostics) {
      // The tie marks' leverage is the rest: sum of all redundancy numbers = redundancy.
      double other_redundancy = 0.0;
      for (int g = kControlMarks; g < kNumBundleGroups; ++g)
        other_redundancy += variance->scalar_rows[g] - sums[g].leverage;
      sums[kTieMarks].leverage =
          variance->scalar_rows[kTieMarks] - (summary.redundancy - other_redundancy);
    }
    for (int g = 0; g < kNumBundleGroups; ++g)
      variance->redundancy[g] = variance->scalar_rows[g] - sums[g].leverage;
    // Self-calibration.
    for (size_t c = 0; c < block.cameras.size(); ++c) {
      if (plan.calibrated[c].empty()) continue;
      const auto found = reduced.e_index.find(state.cameras[c].data());
      if (found == reduced.e_index.end()) continue;
      const int offset = reduced.e_offset[found->second];
      const int n = static_cast<int>(plan.calibrated[c].size());
      BundleCalibrationResult calibration;
      calibration.camera = static_cast<int>(c);
      const std::vector<std::string> names = CameraModelParamNames(block.cameras[c].model);
      const Eigen::MatrixXd C = variance_factor * reduced.C.block(offset, offset, n, n);
      calibration.correlation.resize(n, n);
      for (int a = 0; a < n; ++a) {
        const int index = plan.calibrated[c][a];
        calibration.indices.push_back(index);
        calibration.names.push_back(names[index]);
        calibration.values.push_back(state.cameras[c][index]);
        calibration.sigmas.push_back(std::sqrt(std::max(C(a, a), 0.0)));
      }
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          calibration.correlation(a, b) = C(a, b) / (calibration.sigmas[a] * calibration.sigmas[b]);
          if (b > a && std::abs(calibration.correlation(a, b)) > options.high_correlation) {
            calibration.high_correlations.push_back(calibration.names[a] + "~" +
                                                    calibration.names[b] + ": " +
                                                    Format3(calibration.correlation(a, b)));
          }
        }
      }
      result->calibration.push_back(std::move(calibration));
    }
  } else {
    for (int g = 0; g < kNumBundleGroups; ++g) variance->redundancy[g] = kNaN;
    for (size_t c = 0; c < block.cameras.size(); ++c) {
      if (plan.calibrated[c].empty()) continue;
      BundleCalibrationResult calibration;
      calibration.camera = static_cast<int>(c);
      const std::vector<std::string> names = CameraModelParamNames(block.cameras[c].model);
      for (const int index : plan.calibrated[c]) {
        calibration.indices.push_back(index);
        calibration.names.push_back(names[index]);
        calibration.values.push_back(state.cameras[c][index]);
      }
      result->calibration.push_back(std::move(calibration));
    }
    summary.message = asked ? "the normal matrix is singular: no covariances"
                            : "covariances skipped (" + std::to_string(e_size) +
                                  " parameters after point elimination, more than " +
                                  std::to_string(options.max_covariance_parameters) + ")";
  }
  if (plan.use_lever) result->lever_arm_m = state.lever;

  for (int g = 0; g < kNumBundleGroups; ++g) {
    const Sums& s = sums[g];
    if (s.count == 0) continue;
    BundleGroupStatistics group;
    group.group = static_cast<BundleGroup>(g);
    group.count = s.count;
    group.unit = s.unit;
    group.num_axes = (g == kTieMarks || g == kControlMarks) ? 2 : 3;
    group.stated_accuracy = s.stated / s.count;
    group.rms = (s.ssq / s.count).cwiseSqrt();
    group.rms_total = std::sqrt(s.ssq.sum() / (s.count * group.num_axes));
    const int rows = variance->scalar_rows[g];
    group.ratio = std::sqrt(variance->whitened_ssq[g] / rows);
    group.redundancy_share = variance->redundancy[g] / rows;
    const bool prior = g == kControlPoints || g == kCameraPositions || g == kAttitudes;
    const bool share_known = std::isfinite(group.redundancy_share);
    if (prior && (group.ratio < options.overfit_ratio ||
                  (share_known && group.redundancy_share < options.overfit_redundancy_share))) {
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

  // Control and check points; check points are intersected from the adjusted images and cameras.
  Eigen::Vector3d control_ssq = Eigen::Vector3d::Zero(), check_ssq = Eigen::Vector3d::Zero();
  result->num_control_points = result->num_check_points = 0;
  std::vector<BlockCamera> adjusted_cameras = block.cameras;
  for (size_t c = 0; c < adjusted_cameras.size(); ++c) adjusted_cameras[c].params = state.cameras[c];
  const double marker_px = options.accuracies.marker_projection_px;
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    BundlePointResult& out = result->points[p];
    // A control point whose coordinates snooping removed keeps its error in the table but stays
    // out of the RMSE (it is reported as removed).
    bool prior_kept = true;
    for (const BundleSnoopingStep& step : result->snooping)
      if (step.group == kControlPoints && step.item == static_cast<int>(p)) prior_kept = false;
    if (point.role == PointRole::kControl && out.error_m && prior_kept) {
      ++result->num_control_points;
      control_ssq += out.error_m->cwiseAbs2();
    }
    if (point.role != PointRole::kCheck) continue;
    std::vector<RayObservation> rays;
    for (const int m : block.marks_of_point[p]) {
      const BlockMark& mark = block.marks[m];
      RayObservation ray;
      ray.camera = &adjusted_cameras[block.images[mark.image].camera];
      ray.eo.parameters = state.eo[mark.image];
      ray.observation = mark.observation;
      ray.sigma = MarkSigma(mark, marker_px,
                            DefaultFilmMarkSigmaUm(*ray.camera, marker_px,
                                          options.accuracies.marker_projection_film_um));
      rays.push_back(ray);
    }
    out.num_observations = static_cast<int>(rays.size());
    TriangulationResult triangulated;
    const Status status = TriangulatePoint(TriangulationOptions(), rays, &triangulated);
    if (!status.ok()) {
      out.message = "not intersected: " + status.message();
      continue;
    }
    out.error_m = triangulated.point_m - *point.surveyed_m;
    out.covariance = triangulated.covariance;
    if (reduced.ok) {
      // The images' and cameras' own uncertainty carried into the intersection. The point
      // minimises sum_j |r_j(X, e)|^2, so dX/de = -N^-1 B with N = sum_j J_X,j^T J_X,j and
      // B = sum_j J_X,j^T J_e,j (whitened, e in the tangent spaces of the reduced system), and
      // C_X = N^-1 + (N^-1 B) C (N^-1 B)^T.
      Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(3, reduced.size);
      for (size_t j = 0; j < rays.size(); ++j) {
        const int image = block.marks[block.marks_of_point[p][j]].image;
        const int camera = block.images[image].camera;
        const std::unique_ptr<ceres::CostFunction> cost(CreateCollinearityCost(
            JacobianType::kAnalytic, CollinearityFunctor(rays[j].camera->model, rays[j].observation,
                                                         rays[j].camera->data(), 1.0 / rays[j].sigma)));
        const int n = static_cast<int>(state.cameras[camera].size());
        Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J_eo;
        Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J_X;
        Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor> J_cam(2, n);
        const double* parameters[] = {state.eo[image].data(), triangulated.point_m.data(),
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
          const ceres::Manifold* manifold =
              round.problem->GetManifold(const_cast<double*>(block_ptr));
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
      out.covariance = N_inverse + A * reduced.C * A.transpose();
    }
    out.covariance *= variance_factor;
    out.has_covariance = true;
    ++result->num_check_points;
    check_ssq += out.error_m->cwiseAbs2();
  }
  result->control_rmse_m = result->check_rmse_m = Eigen::Vector3d::Zero();
  result->control_rmse_total_m = result->check_rmse_total_m = 0.0;
  if (result->num_control_points > 0) {
    result->control_rmse_m = (control_ssq / result->num_control_points).cwiseSqrt();
    result->control_rmse_total_m = std::sqrt(control_ssq.sum() / result->num_control_points);
  }
  if (result->num_check_points > 0) {
    result->check_rmse_m = (check_ssq / result->num_check_points).cwiseSqrt();
    result->check_rmse_total_m = std::sqrt(check_ssq.sum() / result->num_check_points);
  }
}

}  // namespace photopose::internal
