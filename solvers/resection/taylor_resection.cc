#include "solvers/resection/taylor_resection.h"

#include "solvers/resection/data_snooping.h"
#include "solvers/resection/point_configuration.h"

#include <glog/logging.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <utility>

#include "core/collinearity.h"
#include "core/rotation.h"
#include "core/units.h"

namespace photopose {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// Multiple of epsilon times the problem's size below which a position correction is rounding noise.
constexpr double kPositionResolutionFactor = 256.0;

#if defined(__GNUC__) || defined(__clang__)
#define PHOTOPOSE_TAYLOR_INLINE inline __attribute__((always_inline))
#else
#define PHOTOPOSE_TAYLOR_INLINE inline
#endif

// What does not change during one pose's iteration: the rotation and sin/cos of omega.
struct PoseTrig {
  double R[9];  // a11 .. a33, row-major (seed eq. 3)
  double sin_omega;
  double cos_omega;
};

// sin and cos of the three angles once per iteration, and the seed's matrix from them (the same
// expansion as SeedRotationMatrix; tests compare the projection with ProjectToImagePlane).
inline void ComputeTrig(const double* eo, PoseTrig* trig) {
  const double so = std::sin(eo[3]), co = std::cos(eo[3]);
  const double sp = std::sin(eo[4]), cp = std::cos(eo[4]);
  const double sk = std::sin(eo[5]), ck = std::cos(eo[5]);
  SeedRotationFromSinCos(so, co, sp, cp, sk, ck, trig->R);
  trig->sin_omega = so;
  trig->cos_omega = co;
}

// Eqs. 7-8 and 17-28 for one point. d = point - centre (m), (obs_x, obs_y) the observation (um).
// Writes Fu, Fv and, when rows are wanted, the partials. Returns false and w when w >= 0 or NaN.
template <bool kWantRows>
PHOTOPOSE_TAYLOR_INLINE bool Linearize(const PoseTrig& t, double c, double inv_c, bool as_printed,
                                       const double* d, double obs_x, double obs_y, double* row_u,
                                       double* row_v, double* fu, double* fv, double* w_out) {
  const double* a = t.R;
  const double U = a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
  const double V = a[3] * d[0] + a[4] * d[1] + a[5] * d[2];
  const double W = a[6] * d[0] + a[7] * d[1] + a[8] * d[2];
  *w_out = W;
  if (!(W < 0.0)) return false;
  const double inv_w = 1.0 / W;
  // The computed image coordinates, the seed's u, v in eqs. 17-28 (eqs. 4-5).
  const double x = -c * U * inv_w;
  const double y = -c * V * inv_w;
  *fu = x - obs_x;
  *fv = y - obs_y;
  if (!kWantRows) return true;
  const double so = t.sin_omega, co = t.cos_omega;
  // Eqs. 17-19 and 23-25: (c a1j + u a3j) / W and (c a2j + v a3j) / W.
  row_u[0] = (c * a[0] + x * a[6]) * inv_w;
  row_u[1] = (c * a[1] + x * a[7]) * inv_w;
  row_u[2] = (c * a[2] + x * a[8]) * inv_w;
  row_v[0] = (c * a[3] + y * a[6]) * inv_w;
  row_v[1] = (c * a[4] + y * a[7]) * inv_w;
  row_v[2] = (c * a[5] + y * a[8]) * inv_w;
  // Eqs. 20 and 26.
  const double xy_over_c = x * y * inv_c;
  row_u[3] = xy_over_c;
  row_v[3] = c + y * y * inv_c;
  // Eq. 21: the printed middle term uses u (x); the derivative has v (y).
  const double middle = as_printed ? x : y;
  row_u[4] = -x * x * inv_c * co - middle * so - c * co;
  // Eq. 27.
  row_v[4] = x * so - xy_over_c * co;
  // Eqs. 22 and 28.
  row_u[5] = row_u[0] * d[1] - row_u[1] * d[0];
  row_v[5] = row_v[0] * d[1] - row_v[1] * d[0];
  return true;
}

// The data of one resection, with the points relative to their centroid so that the corrections
// are not limited by the resolution of large map coordinates.
struct Problem {
  std::vector<Eigen::Vector3d> centred_points;   // m
  const std::vector<Eigen::Vector2d>* observed;  // um
  std::vector<double> weights;                   // 1 / sigma^2 (um^-2); empty: all 1
  double focal = 0.0;                            // um
  bool as_printed = false;
};

struct Evaluation {
  Matrix6d normal;            // A^T P A, upper triangle until Symmetrize
  Vector6d rhs;               // A^T P F
  double weighted_ssr = 0.0;  // F^T P F
  int behind_index = -1;      // first point with w >= 0 (or NaN), -1 if none
  double behind_w = 0.0;
};

// One pass over the points at eo (centred): the normal equations and F^T P F. False when a point
// is not in front of the camera. Templated on the variant so that the inner loop has no branch.
template <bool kAsPrinted>
bool EvaluateImpl(const Problem& problem, const Vector6d& eo, Evaluation* e) {
  PoseTrig trig;
  ComputeTrig(eo.data(), &trig);
  const double c = problem.focal;
  const double inv_c = 1.0 / c;
  double N[6][6] = {};
  double g[6] = {};
  double ssr = 0.0;
  const int n = static_cast<int>(problem.centred_points.size());
  const bool weighted = !problem.weights.empty();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& point = problem.centred_points[i];
    const double d[3] = {point[0] - eo[0], point[1] - eo[1], point[2] - eo[2]};
    const Eigen::Vector2d& obs = (*problem.observed)[i];
    double ru[6], rv[6], fu, fv, w;
    if (!Linearize<true>(trig, c, inv_c, kAsPrinted, d, obs[0], obs[1], ru, rv, &fu, &fv, &w)) {
      e->behind_index = i;
      e->behind_w = w;
      return false;
    }
    const double p = weighted ? problem.weights[i] : 1.0;
    double pru[6], prv[6];
    for (int k = 0; k < 6; ++k) {
      pru[k] = p * ru[k];
      prv[k] = p * rv[k];
    }
    for (int r = 0; r < 6; ++r) {
      for (int s = r; s < 6; ++s) N[r][s] += pru[r] * ru[s] + prv[r] * rv[s];
      g[r] += pru[r] * fu + prv[r] * fv;
    }
    ssr += p * (fu * fu + fv * fv);
  }
  for (int r = 0; r < 6; ++r) {
    for (int s = r; s < 6; ++s) {
      e->normal(r, s) = N[r][s];
      e->normal(s, r) = N[r][s];
    }
    e->rhs[r] = g[r];
  }
  e->weighted_ssr = ssr;
  e->behind_index = -1;
  return true;
}

bool Evaluate(const Problem& problem, const Vector6d& eo, Evaluation* e) {
  return problem.as_printed ? EvaluateImpl<true>(problem, eo, e)
                            : EvaluateImpl<false>(problem, eo, e);
}

// The residual pass at the final estimate: v = observed - computed (um) and v^T P v. False when a
// point is not in front of the camera.
bool EvaluateResiduals(const Problem& problem, const Vector6d& eo,
                       std::vector<Eigen::Vector2d>* residuals, Evaluation* e) {
  PoseTrig trig;
  ComputeTrig(eo.data(), &trig);
  const double c = problem.focal;
  const int n = static_cast<int>(problem.centred_points.size());
  residuals->resize(n);
  double ssr = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& point = problem.centred_points[i];
    const double d[3] = {point[0] - eo[0], point[1] - eo[1], point[2] - eo[2]};
    const Eigen::Vector2d& obs = (*problem.observed)[i];
    double fu = 0.0, fv = 0.0, w = 0.0;
    if (!Linearize<false>(trig, c, 1.0 / c, false, d, obs[0], obs[1], nullptr, nullptr, &fu, &fv,
                          &w)) {
      e->behind_index = i;
      e->behind_w = w;
      return false;
    }
    (*residuals)[i] = Eigen::Vector2d(-fu, -fv);
    ssr += (problem.weights.empty() ? 1.0 : problem.weights[i]) * (fu * fu + fv * fv);
  }
  e->weighted_ssr = ssr;
  return true;
}

// LDL^T factorisation of a symmetric positive-definite 6x6 matrix (no pivoting is needed for SPD):
// A = L D L^T with unit lower-triangular L. False when a pivot is not positive.
struct Ldlt6 {
  double L[6][6];
  double D[6];

  bool Factor(const Matrix6d& A) {
    for (int j = 0; j < 6; ++j) {
      double dj = A(j, j);
      for (int k = 0; k < j; ++k) dj -= L[j][k] * L[j][k] * D[k];
      if (!(dj > 0.0)) return false;
      D[j] = dj;
      L[j][j] = 1.0;
      for (int i = j + 1; i < 6; ++i) {
        double lij = A(i, j);
        for (int k = 0; k < j; ++k) lij -= L[i][k] * L[j][k] * D[k];
        L[i][j] = lij / dj;
      }
    }
    return true;
  }

  Vector6d Solve(const Vector6d& b) const {
    Vector6d x = b;
    for (int i = 0; i < 6; ++i) {
      for (int k = 0; k < i; ++k) x[i] -= L[i][k] * x[k];
    }
    for (int i = 0; i < 6; ++i) x[i] /= D[i];
    for (int i = 5; i >= 0; --i) {
      for (int k = i + 1; k < 6; ++k) x[i] -= L[k][i] * x[k];
    }
    return x;
  }
};

// Solves N d = g through the LDL^T of the Jacobi-scaled matrix S N S, S = diag(N)^-1/2 (N mixes m
// and rad, so its raw condition number says little). The reciprocal 1-norm condition number of
// S N S is computed exactly from its inverse (six solves, cheap at 6x6). Optionally returns N^-1.
// False, with rcond, when N is singular or ill-conditioned.
bool SolveNormalEquations(const Matrix6d& N, const Vector6d& g, double min_rcond, Vector6d* delta,
                          Matrix6d* inverse, double* rcond) {
  *rcond = 0.0;
  Vector6d scale;
  for (int k = 0; k < 6; ++k) {
    if (!(N(k, k) > 0.0) || !std::isfinite(N(k, k))) return false;
    scale[k] = 1.0 / std::sqrt(N(k, k));
  }
  const Matrix6d scaled = scale.asDiagonal() * N * scale.asDiagonal();
  Ldlt6 ldlt;
  if (!ldlt.Factor(scaled)) return false;
  Matrix6d scaled_inverse;
  for (int k = 0; k < 6; ++k) scaled_inverse.col(k) = ldlt.Solve(Vector6d::Unit(k));
  const double norm = scaled.cwiseAbs().colwise().sum().maxCoeff();
  const double inverse_norm = scaled_inverse.cwiseAbs().colwise().sum().maxCoeff();
  *rcond = 1.0 / (norm * inverse_norm);
  if (!(*rcond >= min_rcond)) return false;
  if (delta != nullptr) *delta = scale.asDiagonal() * ldlt.Solve(scale.asDiagonal() * g);
  if (inverse != nullptr) *inverse = scale.asDiagonal() * scaled_inverse * scale.asDiagonal();
  return true;
}

std::string FormatPoint(int index) {
  std::ostringstream os;
  os << "point " << index;
  return os.str();
}

// "point i <what> (w = W m)": the first point of an evaluation that is not in front of the camera.
std::string NotInFront(const Evaluation& evaluation, const std::string& what) {
  std::ostringstream os;
  os << FormatPoint(evaluation.behind_index) << " " << what << " (w = " << evaluation.behind_w << " m)";
  return os.str();
}

double ElapsedSeconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Whether the data can be resected: matching lengths, at least three points, a positive focal
// length, finite values and positive sigmas. False with the reason in *why.
bool InputsAreUsable(const std::vector<Eigen::Vector2d>& image_plane_um,
                     const std::vector<Eigen::Vector3d>& points_in_ground,
                     const std::vector<double>& sigmas_um, double focal_um,
                     const ExteriorOrientation& initial, std::string* why) {
  const int n = static_cast<int>(points_in_ground.size());
  if (image_plane_um.size() != points_in_ground.size()) {
    return InvalidBecause(why, "image_plane_um and points_in_ground differ in length");
  }
  if (!sigmas_um.empty() && sigmas_um.size() != points_in_ground.size()) {
    return InvalidBecause(why, "sigmas_um must be empty or have one entry per point");
  }
  if (n < 3) {
    return InvalidBecause(
        why, "at least 3 points are needed for 6 unknowns (got " + std::to_string(n) + ")");
  }
  if (!(focal_um > 0.0) || !std::isfinite(focal_um)) {
    return InvalidBecause(why, "focal_um must be positive and finite");
  }
  if (!initial.parameters.allFinite())
    return InvalidBecause(why, "initial orientation is not finite");
  for (int i = 0; i < n; ++i) {
    if (!image_plane_um[i].allFinite())
      return InvalidBecause(why, "image coordinates of " + FormatPoint(i) + " are not finite");
    if (!points_in_ground[i].allFinite())
      return InvalidBecause(why, "ground coordinates of " + FormatPoint(i) + " are not finite");
    if (!sigmas_um.empty() && !(sigmas_um[i] > 0.0 && std::isfinite(sigmas_um[i]))) {
      return InvalidBecause(why, "sigma of " + FormatPoint(i) + " must be positive and finite");
    }
  }
  return true;
}

// The problem with its points relative to their centroid (*centroid, m) and their RMS distance
// from it (*extent_m). False when the points are collinear (or coincide): the rotation about their
// line is then undetermined (solvers/resection/point_configuration.h).
bool MakeProblem(const TaylorResectionOptions& options, const std::vector<Eigen::Vector2d>& image_plane_um,
                 const std::vector<Eigen::Vector3d>& points_in_ground, const std::vector<double>& sigmas_um,
                 double focal_um, Problem* problem, Eigen::Vector3d* centroid, double* extent_m) {
  const int n = static_cast<int>(points_in_ground.size());
  *centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points_in_ground) *centroid += p;
  *centroid /= n;
  problem->centred_points.resize(n);
  for (int i = 0; i < n; ++i) problem->centred_points[i] = points_in_ground[i] - *centroid;
  const PointSpread spread = ComputePointSpread(points_in_ground);
  if (spread.collinear(options.collinearity_tolerance)) return false;
  *extent_m = spread.extents_m.norm();
  problem->observed = &image_plane_um;
  problem->focal = focal_um;
  problem->as_printed = options.partials == TaylorPartials::kAsPrinted;
  if (!sigmas_um.empty()) {
    problem->weights.resize(n);
    for (int i = 0; i < n; ++i) problem->weights[i] = 1.0 / (sigmas_um[i] * sigmas_um[i]);
  }
  return true;
}

// Gauss-Newton (eqs. 9-16) from *eo (centred) until the corrections fall below the tolerances.
// Each pass: solve the normal equations built at the current approximation, apply the correction
// (eqs. 9-14), and linearise again only if the correction was not yet negligible. After the last,
// negligible, correction only the residuals are recomputed; *inverse, for the covariance, is the
// normal matrix of the previous approximation, which differs from the final one by a correction
// below the tolerances (a relative change ~1e-12 of A^T P A). Returns kConverged, or kFailure /
// kNoConvergence with the reason in *message; fills the summary's costs, iterations and last
// corrections.
SolverTermination IterateGaussNewton(const TaylorResectionOptions& options, const Problem& problem,
                                     double extent_m, Vector6d* eo, Matrix6d* inverse,
                                     TaylorResectionSummary* summary, std::string* message) {
  const double initial_distance_m = eo->head<3>().norm();
  const double divergence_distance_m =
      options.divergence_distance_factor * std::max(extent_m, initial_distance_m);
  auto fail = [message](const std::string& why) {
    *message = why;
    return SolverTermination::kFailure;
  };
  Evaluation evaluation;
  if (!Evaluate(problem, *eo, &evaluation))
    return fail(NotInFront(evaluation, "is not in front of the camera at the initial orientation"));
  if (!std::isfinite(evaluation.weighted_ssr)) return fail("initial residuals are not finite");
  summary->initial_cost = 0.5 * evaluation.weighted_ssr;
  summary->final_cost = summary->initial_cost;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    Vector6d delta;
    double rcond;
    if (!SolveNormalEquations(evaluation.normal, evaluation.rhs, options.min_reciprocal_condition,
                              &delta, inverse, &rcond)) {
      std::ostringstream os;
      os << "normal matrix is singular or ill-conditioned at iteration " << iteration
         << " (reciprocal condition " << rcond << "): the geometry does not determine the pose";
      return fail(os.str());
    }
    if (!delta.allFinite()) {
      return fail("correction is not finite at iteration " + std::to_string(iteration));
    }
    // Eqs. 9-14: unknown = approximation - correction.
    *eo -= delta;
    summary->iterations = iteration;
    summary->last_position_correction_m = delta.head<3>().cwiseAbs().maxCoeff();
    summary->last_angle_correction_rad = delta.tail<3>().cwiseAbs().maxCoeff();
    const double distance_m = eo->head<3>().norm();
    if (!(distance_m <= divergence_distance_m)) {
      std::ostringstream os;
      os << "diverged at iteration " << iteration << ": the camera moved " << distance_m
         << " m from the centroid of the points";
      return fail(os.str());
    }
    const double position_tolerance_m =
        std::max(options.position_tolerance_m,
                 kPositionResolutionFactor * kEpsilon * (extent_m + distance_m));
    if (summary->last_position_correction_m <= position_tolerance_m &&
        summary->last_angle_correction_rad <= options.angle_tolerance_rad) {
      return SolverTermination::kConverged;
    }
    if (!Evaluate(problem, *eo, &evaluation)) {
      return fail(NotInFront(evaluation, "went behind the camera at iteration " + std::to_string(iteration)) +
                  ": diverged");
    }
    if (!std::isfinite(evaluation.weighted_ssr) || !evaluation.normal.allFinite()) {
      return fail("residuals are not finite at iteration " + std::to_string(iteration));
    }
    summary->final_cost = 0.5 * evaluation.weighted_ssr;
  }
  std::ostringstream os;
  os << "no convergence in " << options.max_iterations << " iterations (last correction "
     << FormatSignificant(summary->last_position_correction_m, 3) << " m, "
     << FormatSignificant(summary->last_angle_correction_rad, 3) << " rad)";
  *message = os.str();
  return SolverTermination::kNoConvergence;
}

}  // namespace

bool TaylorResectionOptions::IsValid(std::string* why) const {
  if (partials != TaylorPartials::kCorrected && partials != TaylorPartials::kAsPrinted) {
    return InvalidBecause(why, "partials is not a TaylorPartials value");
  }
  if (max_iterations < 1) return InvalidBecause(why, "max_iterations must be at least 1");
  if (!(position_tolerance_m > 0.0) || !std::isfinite(position_tolerance_m)) {
    return InvalidBecause(why, "position_tolerance_m must be positive and finite");
  }
  if (!(angle_tolerance_rad > 0.0) || !std::isfinite(angle_tolerance_rad)) {
    return InvalidBecause(why, "angle_tolerance_rad must be positive and finite");
  }
  if (!(collinearity_tolerance >= 0.0 && collinearity_tolerance < 1.0)) {
    return InvalidBecause(why, "collinearity_tolerance must be in [0, 1)");
  }
  if (!(min_reciprocal_condition >= 0.0 && min_reciprocal_condition < 1.0)) {
    return InvalidBecause(why, "min_reciprocal_condition must be in [0, 1)");
  }
  if (!(divergence_distance_factor > 1.0) || !std::isfinite(divergence_distance_factor)) {
    return InvalidBecause(why, "divergence_distance_factor must be finite and greater than 1");
  }
  return true;
}

std::string TaylorResectionSummary::BriefReport() const {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer),
                "Taylor resection (%s partials), %s: %d points, %d iterations, cost %.6e -> %.6e, "
                "sigma0 %.6g, dof %d, time %.1f us. ",
                EnumName(partials), EnumName(termination_type),
                num_points, iterations, initial_cost, final_cost, sigma0, degrees_of_freedom,
                time_seconds * 1e6);
  return buffer + message;
}

bool TaylorResectionSummary::IsSolutionUsable() const {
  return termination_type == SolverTermination::kConverged;
}

bool TaylorFunctions(const ExteriorOrientation& eo, const Eigen::Vector3d& point_in_ground,
                     double focal_um, const Eigen::Vector2d& observed_um, double* fu_um,
                     double* fv_um) {
  PoseTrig trig;
  ComputeTrig(eo.data(), &trig);
  const Eigen::Vector3d d = point_in_ground - eo.center_in_ground();
  double fu, fv, w;
  if (!Linearize<false>(trig, focal_um, 1.0 / focal_um, false, d.data(), observed_um[0],
                        observed_um[1], nullptr, nullptr, &fu, &fv, &w)) {
    return false;
  }
  *fu_um = fu;
  *fv_um = fv;
  return true;
}

bool TaylorPartialsForPoint(TaylorPartials partials, const ExteriorOrientation& eo,
                            const Eigen::Vector3d& point_in_ground, double focal_um,
                            const Eigen::Vector2d& observed_um, double row_u[6], double row_v[6],
                            double* fu_um, double* fv_um) {
  PoseTrig trig;
  ComputeTrig(eo.data(), &trig);
  const Eigen::Vector3d d = point_in_ground - eo.center_in_ground();
  double ru[6], rv[6], fu, fv, w;
  if (!Linearize<true>(trig, focal_um, 1.0 / focal_um, partials == TaylorPartials::kAsPrinted,
                       d.data(), observed_um[0], observed_um[1], ru, rv, &fu, &fv, &w)) {
    return false;
  }
  std::copy(ru, ru + 6, row_u);
  std::copy(rv, rv + 6, row_v);
  if (fu_um != nullptr) *fu_um = fu;
  if (fv_um != nullptr) *fv_um = fv;
  return true;
}

TaylorPoseLinearization::TaylorPoseLinearization(TaylorPartials partials, const double* eo,
                                                 double focal_um, double earth_radius_m)
    : focal_um_(focal_um),
      earth_radius_m_(earth_radius_m),
      as_printed_(partials == TaylorPartials::kAsPrinted) {
  PoseTrig trig;
  ComputeTrig(eo, &trig);
  std::copy(eo, eo + 3, center_);
  std::copy(trig.R, trig.R + 9, R_);
  sin_omega_ = trig.sin_omega;
  cos_omega_ = trig.cos_omega;
}

void TaylorPoseLinearization::Difference(const double* point, double d[3]) const {
  d[0] = point[0] - center_[0];
  d[1] = point[1] - center_[1];
  d[2] = point[2] - center_[2];
  if (earth_radius_m_ > 0.0) d[2] -= EarthCurvatureDropOf(center_, point, earth_radius_m_);
}

bool TaylorPoseLinearization::Linearize(const double* point, const double* observed_um,
                                        double row_u[6], double row_v[6], double* fu_um,
                                        double* fv_um, double* w_m) const {
  PoseTrig trig;
  std::copy(R_, R_ + 9, trig.R);
  trig.sin_omega = sin_omega_;
  trig.cos_omega = cos_omega_;
  double d[3];
  Difference(point, d);
  if (!photopose::Linearize<true>(trig, focal_um_, 1.0 / focal_um_, as_printed_, d,
                                  observed_um[0], observed_um[1], row_u, row_v, fu_um, fv_um,
                                  w_m))
    return false;
  if (earth_radius_m_ > 0.0) {
    // The drop depends on X - X0, Y - Y0: the centre's partials chained through it.
    const double gx = d[0] / earth_radius_m_, gy = d[1] / earth_radius_m_;
    for (double* row : {row_u, row_v}) {
      row[0] -= row[2] * gx;
      row[1] -= row[2] * gy;
    }
  }
  return true;
}

bool TaylorPoseLinearization::Residual(const double* point, const double* observed_um,
                                       double* fu_um, double* fv_um, double* w_m) const {
  PoseTrig trig;
  std::copy(R_, R_ + 9, trig.R);
  trig.sin_omega = sin_omega_;
  trig.cos_omega = cos_omega_;
  double d[3];
  Difference(point, d);
  return photopose::Linearize<false>(trig, focal_um_, 1.0 / focal_um_, as_printed_, d,
                                     observed_um[0], observed_um[1], nullptr, nullptr, fu_um,
                                     fv_um, w_m);
}

Status TaylorResection(const TaylorResectionOptions& options,
                       const std::vector<Eigen::Vector2d>& image_plane_um,
                       const std::vector<Eigen::Vector3d>& points_in_ground,
                       const std::vector<double>& sigmas_um, double focal_um,
                       const ExteriorOrientation& initial, TaylorResectionResult* result) {
  CHECK(result != nullptr);
  const auto start = std::chrono::steady_clock::now();
  TaylorResectionSummary& summary = result->summary;
  summary = TaylorResectionSummary();
  summary.partials = options.partials;
  summary.sigma0 = kNaN;
  result->eo.parameters.setConstant(kNaN);
  result->covariance.setConstant(kNaN);
  result->residuals_um.clear();

  auto finish = [&](SolverTermination type, const std::string& message) {
    summary.termination_type = type;
    summary.message = message;
    summary.time_seconds = ElapsedSeconds(start);
    return type == SolverTermination::kConverged ? Status::Ok() : Status::Error(message);
  };
  auto fail = [&](const std::string& message) {
    return finish(SolverTermination::kFailure, message);
  };

  if (const Status valid = Validate(options, "invalid options: "); !valid.ok())
    return fail(valid.message());
  const int n = static_cast<int>(points_in_ground.size());
  summary.num_points = n;
  summary.degrees_of_freedom = 2 * n - 6;
  if (std::string why; !InputsAreUsable(image_plane_um, points_in_ground, sigmas_um, focal_um, initial, &why))
    return fail(why);
  Problem problem;
  Eigen::Vector3d centroid;
  double extent_m = 0.0;
  if (!MakeProblem(options, image_plane_um, points_in_ground, sigmas_um, focal_um, &problem, &centroid,
                   &extent_m)) {
    return fail(
        "the control points are collinear (or coincide): the rotation about their line is "
        "undetermined");
  }
  Vector6d eo = initial.parameters;
  eo.head<3>() -= centroid;
  Matrix6d inverse;
  std::string message;
  const SolverTermination iterated =
      IterateGaussNewton(options, problem, extent_m, &eo, &inverse, &summary, &message);
  if (iterated != SolverTermination::kConverged) return finish(iterated, message);

  // Residuals and precision at the converged orientation.
  std::vector<Eigen::Vector2d> residuals;
  Evaluation evaluation;
  if (!EvaluateResiduals(problem, eo, &residuals, &evaluation))
    return fail(NotInFront(evaluation, "is behind the camera at the converged orientation"));
  if (!std::isfinite(evaluation.weighted_ssr)) return fail("final residuals are not finite");
  summary.final_cost = 0.5 * evaluation.weighted_ssr;
  if (summary.degrees_of_freedom > 0)
    summary.sigma0 = std::sqrt(evaluation.weighted_ssr / summary.degrees_of_freedom);
  // The one rule of a resection's covariance: a-priori with stated sigmas, sigma0^2 without.
  result->covariance = PoseCovarianceFactor(/*accuracy_stated=*/!sigmas_um.empty(),
                                            evaluation.weighted_ssr, summary.degrees_of_freedom) *
                       inverse;
  result->residuals_um = std::move(residuals);
  eo.head<3>() += centroid;
  for (int k = 3; k < 6; ++k) eo[k] = WrapAngle(eo[k]);
  result->eo.parameters = eo;
  char converged[128];
  std::snprintf(converged, sizeof(converged), "corrections below tolerance (%.3g m, %.3g rad)",
                summary.last_position_correction_m, summary.last_angle_correction_rad);
  return finish(SolverTermination::kConverged, converged);
}

Status ApproximateVerticalOrientation(const std::vector<Eigen::Vector2d>& image_plane_um,
                                      const std::vector<Eigen::Vector3d>& points_in_ground,
                                      double focal_um, ExteriorOrientation* eo) {
  const int n = static_cast<int>(points_in_ground.size());
  if (image_plane_um.size() != points_in_ground.size()) {
    return Status::Error("image_plane_um and points_in_ground differ in length");
  }
  if (n < 2) return Status::Error("at least 2 points are needed for a vertical approximation");
  if (!(focal_um > 0.0) || !std::isfinite(focal_um)) {
    return Status::Error("focal_um must be positive and finite");
  }
  // A near-vertical frame with omega = phi = 0 images the ground as x + i y = lambda (g - g0) with
  // g = X + i Y, lambda = (c / H) exp(i kappa) (R = Rz(kappa), w = Z - Z0 = -H): fit lambda and g0.
  Eigen::Vector2d image_mean = Eigen::Vector2d::Zero();
  Eigen::Vector3d ground_mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    if (!image_plane_um[i].allFinite() || !points_in_ground[i].allFinite()) {
      return Status::Error("non-finite coordinates of " + FormatPoint(i));
    }
    image_mean += image_plane_um[i];
    ground_mean += points_in_ground[i];
  }
  image_mean /= n;
  ground_mean /= n;
  // lambda = sum (z_i - mean) conj(g_i - mean) / sum |g_i - mean|^2.
  CHECK(eo != nullptr);
  double re = 0.0, im = 0.0, norm2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = image_plane_um[i][0] - image_mean[0];
    const double y = image_plane_um[i][1] - image_mean[1];
    const double gx = points_in_ground[i][0] - ground_mean[0];
    const double gy = points_in_ground[i][1] - ground_mean[1];
    re += x * gx + y * gy;
    im += y * gx - x * gy;
    norm2 += gx * gx + gy * gy;
  }
  if (!(norm2 > 0.0)) return Status::Error("the points coincide in plan");
  re /= norm2;
  im /= norm2;
  const double scale = std::hypot(re, im);  // c / H, um per m
  if (!(scale > 0.0)) return Status::Error("the image coordinates coincide");
  const double height_m = focal_um / scale;
  // g0 = mean_g - mean_z / lambda.
  const double inv_re = re / (scale * scale), inv_im = -im / (scale * scale);  // 1 / lambda
  const double cx = ground_mean[0] - (image_mean[0] * inv_re - image_mean[1] * inv_im);
  const double cy = ground_mean[1] - (image_mean[0] * inv_im + image_mean[1] * inv_re);
  eo->parameters << cx, cy, ground_mean[2] + height_m, 0.0, 0.0, std::atan2(im, re);
  return Status::Ok();
}

}  // namespace photopose
