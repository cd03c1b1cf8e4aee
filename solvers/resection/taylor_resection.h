#pragma once
// Space resection by the seed's Taylor-series Gauss-Newton (lecture notes "カメラの幾何学2",
// equations 7-28): the exterior orientation of one frame from control points with known ground
// coordinates and their ideal image-plane coordinates.
//
//   Fu = -c (a11 dX + a12 dY + a13 dZ) / (a31 dX + a32 dY + a33 dZ) - u_observed     (eq. 7)
//   Fv = -c (a21 dX + a22 dY + a23 dZ) / (a31 dX + a32 dY + a33 dZ) - v_observed     (eq. 8)
//
// with a_ij the seed's matrix R_camera_from_ground = Rx(omega) Ry(phi) Rz(kappa) (eq. 3) and
// (dX, dY, dZ) = point_in_ground - center_in_ground. The unknowns are the parameters of
// ExteriorOrientation: X0, Y0, Z0 (m), omega, phi, kappa (rad).
//
// Sign convention of equations 9-16: an unknown is its approximation minus a correction,
// x0 = x00 - dx0 (eqs. 9-14), so the linearisation reads F ~ F(approx) - (dF/dp) d (eqs. 15-16).
// Asking F = 0 in the least-squares sense gives the normal equations
//
//   (A^T P A) d = A^T P F(approx),   A = dF/dp (eqs. 17-28),   p_new = p_approx - d.
//
// This is plain Gauss-Newton (the usual step is -d). The iteration stops when every correction is
// below its tolerance. Only Eigen is used; no Ceres. It deliberately evaluates Fu, Fv and the
// partials from the seed's printed formulas rather than through core/collinearity.h: it is the
// hand-written baseline the Ceres solvers are compared with, and its tests check it against
// ProjectWithJacobians and central differences.
//
// Equation 21 as printed is wrong: its middle term reads -u sin(omega) but the derivative has
// -v sin(omega) (u, v the computed image coordinates). TaylorPartials selects the corrected set or
// the printed one; docs/taylor_derivatives.md has the derivation and the measured consequences.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/enum_names.h"
#include "core/status.h"
#include "core/termination.h"
#include "core/types.h"

namespace photopose {

// Which set of partial derivatives (seed eqs. 17-28) builds the Gauss-Newton matrix A.
enum class TaylorPartials {
  // Eqs. 17-28 with eq. 21 corrected to
  //   dFu/dphi = -(u^2 / c) cos(omega) - v sin(omega) - c cos(omega).
  // Equals ProjectWithJacobians' d_eo. The default.
  kCorrected,
  // Eqs. 17-28 exactly as printed, eq. 21 = -(u^2 / c) cos(omega) - u sin(omega) - c cos(omega),
  // off by (v - u) sin(omega). Kept so that the comparison tool can show what the misprint does:
  // linear instead of quadratic convergence, a solution that is not the least-squares one on noisy
  // data, and for some strongly tilted poses no convergence or a spurious fixed point.
  kAsPrinted,
};

// "corrected" / "as_printed" (parsed also from "as-printed" and "printed"; case is ignored).
inline constexpr EnumNameEntry<TaylorPartials> kTaylorPartialsNames[] = {
    {TaylorPartials::kCorrected, "corrected"},
    {TaylorPartials::kAsPrinted, "as_printed"},
    {TaylorPartials::kAsPrinted, "as-printed"},
    {TaylorPartials::kAsPrinted, "printed"}};
constexpr EnumNameTable<TaylorPartials> EnumNames(TaylorPartials) {
  return EnumNameTable<TaylorPartials>(kTaylorPartialsNames, NameMatch::kIgnoreCase);
}

struct TaylorResectionOptions {
  // Partial derivatives used in the normal equations.
  TaylorPartials partials = TaylorPartials::kCorrected;
  // Maximum number of Gauss-Newton corrections (count).
  int max_iterations = 50;
  // Convergence: the iteration stops after a correction whose three position components are all at
  // most position_tolerance_m (m, absolute) and whose three angle components are all at most
  // angle_tolerance_rad (rad). The position test is never made tighter than the floating-point
  // resolution of the problem, 256 * epsilon * (extent of the points around their centroid plus the
  // camera's distance from it), so large map coordinates cannot make convergence unreachable (the
  // solver works in coordinates relative to the centroid of the points). With the corrected
  // partials Gauss-Newton converges quadratically on small-residual problems, so the final error is
  // far below these tolerances.
  double position_tolerance_m = 1e-9;
  double angle_tolerance_rad = 1e-12;
  // The control points are rejected as collinear when the second singular value of the centred
  // point matrix is at most this fraction of the first (unitless). Three or more points on one line
  // leave the rotation about that line undetermined.
  double collinearity_tolerance = 1e-6;
  // The normal matrix A^T P A is rejected when the reciprocal condition number (LDLT estimate) of
  // its Jacobi-scaled form D^-1/2 N D^-1/2 is below this (unitless).
  double min_reciprocal_condition = 1e-13;
  // The iteration is declared divergent when the camera moves farther than this factor times the
  // larger of the extent of the points and the initial camera distance from their centroid
  // (unitless).
  double divergence_distance_factor = 1e3;

  // True when every field is in range; otherwise false with the reason in *why (may be null).
  bool IsValid(std::string* why) const;
};

struct TaylorResectionSummary {
  SolverTermination termination_type = SolverTermination::kFailure;
  // Why the solver stopped (one line).
  std::string message;
  TaylorPartials partials = TaylorPartials::kCorrected;
  int num_points = 0;
  // Gauss-Newton corrections applied (count).
  int iterations = 0;
  // Cost = 1/2 v^T P v, v the image residuals (um), P = diag(1 / sigma^2). In um^2 when the sigmas
  // are left empty (all 1 um), otherwise unitless. At the initial and at the final orientation.
  double initial_cost = 0.0;
  double final_cost = 0.0;
  // Largest component of the last correction: position (m) and angle (rad).
  double last_position_correction_m = 0.0;
  double last_angle_correction_rad = 0.0;
  // 2 n - 6.
  int degrees_of_freedom = 0;
  // A-posteriori standard deviation of unit weight sqrt(v^T P v / (2 n - 6)): in um with unit
  // weights (empty sigmas), unitless (1 when the sigmas are right) with sigmas. NaN when the
  // redundancy is zero (three points): then nothing can be estimated and the covariance is the
  // a-priori one, (A^T P A)^-1.
  double sigma0 = 0.0;
  // Wall time of the whole call (s).
  double time_seconds = 0.0;

  // One line: termination, iterations, costs, sigma0, time.
  std::string BriefReport() const;
  // True only for kConverged.
  bool IsSolutionUsable() const;
};

struct TaylorResectionResult {
  // The estimate; all NaN unless the solver converged. Angles wrapped to (-pi, pi].
  ExteriorOrientation eo;
  // f (A^T P A)^-1, order X0, Y0, Z0 (m), omega, phi, kappa (rad), with A from the last
  // linearisation (within the tolerances of the estimate) and the selected partials (so the
  // as-printed variant reports its own, wrong, covariance). f by PoseCovarianceFactor
  // (data_snooping.h), as every resection: 1 with sigmas given (the a-priori covariance; the
  // caller tests sigma0 against them), sigma0^2 (um^2) with unit weights (empty sigmas), 1 with
  // zero redundancy. All NaN unless the solver converged.
  Matrix6d covariance = Matrix6d::Zero();
  // Observed minus computed image-plane coordinates at the estimate (um), one per point, i.e.
  // -(Fu, Fv). Empty unless the solver converged.
  std::vector<Eigen::Vector2d> residuals_um;
  TaylorResectionSummary summary;
};

// The seed's Gauss-Newton space resection.
//   image_plane_um:   ideal image-plane observations (um, relative to the principal point,
//                     distortion removed, negative-plane sign as in core/collinearity.h).
//   points_in_ground: the control points (m), same order.
//   sigmas_um:        one standard deviation per point for both coordinates (um), or empty (all 1).
//   focal_um:         c (um).
//   initial:          approximate values x00, y00, z00, omega0, phi0, kappa0.
// Returns Ok with the estimate, or an error with the reason (then result->summary says why and
// result holds no pose): invalid input or options, fewer than three points, collinear points, a
// point behind the camera at the start or during the iteration, a singular or ill-conditioned
// normal matrix, NaN, divergence, or no convergence within max_iterations (summary kNoConvergence).
Status TaylorResection(const TaylorResectionOptions& options,
                       const std::vector<Eigen::Vector2d>& image_plane_um,
                       const std::vector<Eigen::Vector3d>& points_in_ground,
                       const std::vector<double>& sigmas_um, double focal_um,
                       const ExteriorOrientation& initial, TaylorResectionResult* result);

// The seed's functions Fu, Fv (eqs. 7-8) of one observation at eo (um): the computed image-plane
// coordinates minus the observed ones. Returns false when the point is not in front of the camera
// (w >= 0); then nothing is written.
bool TaylorFunctions(const ExteriorOrientation& eo, const Eigen::Vector3d& point_in_ground,
                     double focal_um, const Eigen::Vector2d& observed_um, double* fu_um,
                     double* fv_um);

// The linearisation of one observation (eqs. 7-8 and 17-28) at eo: row_u[k] = dFu/dp_k and
// row_v[k] = dFv/dp_k for p = (X0, Y0, Z0, omega, phi, kappa) (um per m, um per rad), evaluated
// with the computed image coordinates in place of the seed's u, v, as printed or corrected. fu_um,
// fv_um (may be null) receive Fu, Fv. Returns false when w >= 0; then nothing is written.
bool TaylorPartialsForPoint(TaylorPartials partials, const ExteriorOrientation& eo,
                            const Eigen::Vector3d& point_in_ground, double focal_um,
                            const Eigen::Vector2d& observed_um, double row_u[6], double row_v[6],
                            double* fu_um, double* fv_um);

// The seed's functions and partials (eqs. 7-8 and 17-28) of any number of points seen from one
// pose, with R and sin/cos(omega) computed once: the linearisation that TaylorPartialsForPoint
// gives point by point, for the block solver (solvers/bundle/taylor_bundle.h), which linearises every mark
// of an image at the same pose.
class TaylorPoseLinearization {
 public:
  // eo = [X0, Y0, Z0, omega, phi, kappa] (m, rad, seed), focal_um = c (um). earth_radius_m > 0:
  // the camera table's earth-curvature correction (ApplyECC): every point is seen lowered by
  // ((X - X0)^2 + (Y - Y0)^2) / (2 R) (core/collinearity.h, LowerByEarthCurvature), and the
  // partials by the centre are chained through the drop, dF/dX0 -= dF/dZ0 (X - X0) / R and
  // dF/dY0 -= dF/dZ0 (Y - Y0) / R (the point's partials stay the centre's negated).
  TaylorPoseLinearization(TaylorPartials partials, const double* eo, double focal_um,
                          double earth_radius_m = 0.0);

  // For the point (m, the frame of eo's centre) observed at observed_um (um): Fu, Fv (um) and the
  // rows dFu/dp, dFv/dp, p = (X0, Y0, Z0, omega, phi, kappa), exactly as TaylorPartialsForPoint.
  // w_m receives w (m). Returns false when w >= 0 (or NaN); then only w_m is written.
  bool Linearize(const double* point, const double* observed_um, double row_u[6], double row_v[6],
                 double* fu_um, double* fv_um, double* w_m) const;
  // Fu, Fv and w alone, the same values Linearize gives (a cost evaluation without partials).
  bool Residual(const double* point, const double* observed_um, double* fu_um, double* fv_um,
                double* w_m) const;

 private:
  // The point relative to the centre, lowered by the earth-curvature drop when asked.
  void Difference(const double* point, double d[3]) const;

  double center_[3];
  double R_[9];
  double sin_omega_, cos_omega_;
  double focal_um_;
  double earth_radius_m_;
  bool as_printed_;
};

// Approximate values for a near-vertical frame: a 2-D similarity between the image coordinates and
// the ground X, Y gives the scale c / H and kappa; the centre is the ground point imaged at the
// principal point, at H above the mean height of the points; omega = phi = 0. Needs two or more
// distinct points. Only a starting point for TaylorResection, not an estimate.
Status ApproximateVerticalOrientation(const std::vector<Eigen::Vector2d>& image_plane_um,
                                      const std::vector<Eigen::Vector3d>& points_in_ground,
                                      double focal_um, ExteriorOrientation* eo);

}  // namespace photopose
