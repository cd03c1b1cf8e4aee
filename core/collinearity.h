#pragma once
// The collinearity model: the seed's equations 4-5, the single source of truth for every solver.
//
//   (u, v, w) = R_camera_from_ground * (X - X0),   R = Rx(omega) Ry(phi) Rz(kappa)
//   x = -c u / w,   y = -c v / w                    (image plane, same unit as c: micrometres)
//
// A point is visible when w < 0 (in front of the negative plane at w = -c). The templated functions
// serve Ceres autodiff; ProjectWithJacobians is the double-only twin with closed-form partials used by
// the analytic cost functions and the Taylor Gauss-Newton solver.

#include <Eigen/Core>
#include <cmath>

#include "core/camera.h"
#include "core/rotation.h"
#include "core/status.h"
#include "core/types.h"

namespace photopose {

// (u, v, w) = R_camera_from_ground (X - X0): a ground point in the seed's camera frame.
// eo = [X0, Y0, Z0, omega, phi, kappa] (m, rad), point = [X, Y, Z] (m).
template <typename T>
void CameraFromGround(const T* eo, const T* point, T* uvw) {
  T R[9];
  SeedRotationMatrix(eo[3], eo[4], eo[5], R);
  const T dx = point[0] - eo[0];
  const T dy = point[1] - eo[1];
  const T dz = point[2] - eo[2];
  uvw[0] = R[0] * dx + R[1] * dy + R[2] * dz;
  uvw[1] = R[3] * dx + R[4] * dy + R[5] * dz;
  uvw[2] = R[6] * dx + R[7] * dy + R[8] * dz;
}

// Seed equations 4-5. eo = [X0, Y0, Z0, omega, phi, kappa] (m, rad), point = [X, Y, Z] (m),
// focal = c (um). Writes xy (um). Returns false when the point is not in front of the camera.
template <typename T>
bool ProjectToImagePlane(const T* eo, const T* point, const T& focal, T* xy) {
  T uvw[3];
  CameraFromGround(eo, point, uvw);
  if (!(uvw[2] < T(0))) return false;
  xy[0] = -focal * uvw[0] / uvw[2];
  xy[1] = -focal * uvw[1] / uvw[2];
  return true;
}

// The same at c = 1: the normalised image coordinates (a, b) = (-u / w, -v / w) that the camera
// models of core/camera_models.h take. Returns false when the point is not in front (w >= 0).
template <typename T>
bool ProjectToNormalized(const T* eo, const T* point, T* ab) {
  T uvw[3];
  CameraFromGround(eo, point, uvw);
  if (!(uvw[2] < T(0))) return false;
  ab[0] = -uvw[0] / uvw[2];
  ab[1] = -uvw[1] / uvw[2];
  return true;
}

// The earth-curvature correction (ApplyECC of the camera table): the ground surface lies
// D^2 / (2 R) below the tangent plane of the ground frame at horizontal distance D from the
// projection centre, so a camera at eo sees the point at
//   lowered = (X, Y, Z - ((X - X0)^2 + (Y - Y0)^2) / (2 R)),   R = earth_radius_m (m, > 0).
// It depends on the point and on the projection centre; the rotation does not enter. Templated for
// the autodiff costs; EarthCurvatureDrop and ProjectWithJacobiansEarthCurvature use the same rule.
template <typename T>
T EarthCurvatureDropOf(const T* center, const T* point, double earth_radius_m) {
  const T dx = point[0] - center[0];
  const T dy = point[1] - center[1];
  return (dx * dx + dy * dy) / (2.0 * earth_radius_m);
}
template <typename T>
void LowerByEarthCurvature(const T* eo, const T* point, double earth_radius_m, T* lowered) {
  lowered[0] = point[0];
  lowered[1] = point[1];
  lowered[2] = point[2] - EarthCurvatureDropOf(eo, point, earth_radius_m);
}

// The double-only projection of one pose: R and the trigonometry computed once, then any number of
// points projected with closed-form partial derivatives (the corrected equations 17-28 of the seed,
// see docs/taylor_derivatives.md).
class SeedProjector {
 public:
  // eo = [X0, Y0, Z0, omega, phi, kappa] (m, rad), focal = c (um).
  SeedProjector(const double* eo, double focal);

  // Writes xy (um). Each Jacobian pointer may be null; all are row-major: d_eo 2x6 (um per m, um per
  // rad), d_point 2x3 (um per m), d_focal 2x1 (unitless). False when the point is not in front.
  bool Project(const double* point, double* xy, double* d_eo, double* d_point, double* d_focal) const;

 private:
  double center_[3];
  double focal_;
  double R_[9];
  double sin_omega_, cos_omega_;
};

// One point through a SeedProjector. The trigonometry of the last pose seen by the calling thread is
// memoised: a cost function evaluated for every observation of an image at the same pose (as Ceres
// does) computes it once. Results are bit-identical with or without the memo.
bool ProjectWithJacobians(const double* eo, const double* point, double focal, double* xy,
                          double* d_eo, double* d_point, double* d_focal);

// ProjectWithJacobians of the point as the camera sees it with the earth-curvature correction
// (LowerByEarthCurvature, earth_radius_m > 0), the partials chained through the drop: with
// g = d(drop)/d(X, Y) = ((X - X0) / R, (Y - Y0) / R) and P_Z the projection's partial by the
// lowered Z,  d/dX = P_X - P_Z g_X,  d/dY = P_Y - P_Z g_Y,  d/dZ = P_Z, and the centre's partials
// stay the point's negated (d/dX0 = -d/dX, ...; the drop depends on X - X0, Y - Y0 only); the
// rotation partials are those of the lowered point. Same layout and contract as
// ProjectWithJacobians.
bool ProjectWithJacobiansEarthCurvature(const double* eo, const double* point, double focal,
                                        double earth_radius_m, double* xy, double* d_eo,
                                        double* d_point, double* d_focal);

// The earth-curvature drop D^2 / (2 R) (m) of a ground point at horizontal distance D from the
// projection centre (ApplyECC of the camera table): the ground surface lies that much below the
// tangent plane of the ground frame (EarthCurvatureDropOf).
double EarthCurvatureDrop(const Eigen::Vector3d& center_in_ground,
                          const Eigen::Vector3d& point_in_ground, double earth_radius_m);

// Ground point -> pixel through the whole camera: collinearity, Polarity, distortion, film, pixel.
// With camera.apply_ecc the earth-curvature drop D^2 / (2 R) is subtracted from Z (D: horizontal
// distance from the projection centre).
Status ProjectGroundPoint(const FrameCamera& camera, const ExteriorOrientation& eo,
                          const Eigen::Vector3d& point_in_ground, PixelOrigin origin,
                          Eigen::Vector2d* column_row);

// Pixel -> ground: the ray of an image point intersected with the horizontal plane Z = height (m),
// with the earth-curvature correction when camera.apply_ecc (iterated). Fails when the ray does not
// meet the plane in front of the camera.
Status IntersectRayWithPlane(const FrameCamera& camera, const ExteriorOrientation& eo,
                             const Eigen::Vector2d& column_row, PixelOrigin origin, double height_m,
                             Eigen::Vector3d* point_in_ground);

// Same, at the camera's AverageZ (0 when the table leaves it unset).
Status IntersectRayWithAverageZ(const FrameCamera& camera, const ExteriorOrientation& eo,
                                const Eigen::Vector2d& column_row, PixelOrigin origin,
                                Eigen::Vector3d* point_in_ground);

}  // namespace photopose
