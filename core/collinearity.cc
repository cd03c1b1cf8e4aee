#include "core/collinearity.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace photopose {

namespace {

// The rotation part of a SeedProjector for one set of angles.
struct SeedTrig {
  double angles[3];
  double R[9];
  double sin_omega, cos_omega;
};

void ComputeSeedTrig(const double* angles, SeedTrig* trig) {
  // One sincos per angle (the trigonometry dominates the kernel), then the seed's matrix.
  double so, co, sp, cp, sk, ck;
  sincos(angles[0], &so, &co);
  sincos(angles[1], &sp, &cp);
  sincos(angles[2], &sk, &ck);
  SeedRotationFromSinCos(so, co, sp, cp, sk, ck, trig->R);
  std::copy(angles, angles + 3, trig->angles);
  trig->sin_omega = so;
  trig->cos_omega = co;
}

// The last pose's trigonometry of this thread (ProjectWithJacobians).
const SeedTrig& MemoisedSeedTrig(const double* angles) {
  thread_local SeedTrig memo = {{std::nan(""), 0.0, 0.0}, {}, 0.0, 0.0};
  if (!(angles[0] == memo.angles[0] && angles[1] == memo.angles[1] && angles[2] == memo.angles[2]))
    ComputeSeedTrig(angles, &memo);
  return memo;
}

}  // namespace

SeedProjector::SeedProjector(const double* eo, double focal) : focal_(focal) {
  std::copy(eo, eo + 3, center_);
  const SeedTrig& trig = MemoisedSeedTrig(eo + 3);
  std::copy(trig.R, trig.R + 9, R_);
  sin_omega_ = trig.sin_omega;
  cos_omega_ = trig.cos_omega;
}

bool SeedProjector::Project(const double* point, double* xy, double* d_eo, double* d_point,
                            double* d_focal) const {
  const double* R = R_;
  const double focal = focal_;
  const double d[3] = {point[0] - center_[0], point[1] - center_[1], point[2] - center_[2]};
  const double u = R[0] * d[0] + R[1] * d[1] + R[2] * d[2];
  const double v = R[3] * d[0] + R[4] * d[1] + R[5] * d[2];
  const double w = R[6] * d[0] + R[7] * d[1] + R[8] * d[2];
  if (!(w < 0.0)) return false;
  const double inv_w = 1.0 / w;
  const double x = -focal * u * inv_w;
  const double y = -focal * v * inv_w;
  xy[0] = x;
  xy[1] = y;
  if (d_focal != nullptr) {
    d_focal[0] = -u * inv_w;
    d_focal[1] = -v * inv_w;
  }
  if (d_eo == nullptr && d_point == nullptr) return true;

  // dx = (-c/w) du - (x/w) dw,  dy = (-c/w) dv - (y/w) dw.
  const double a = -focal * inv_w;
  const double bx = -x * inv_w;
  const double by = -y * inv_w;
  // Ground-point partials: d(u,v,w)/dX = R.
  double dp[6];
  for (int j = 0; j < 3; ++j) {
    dp[j] = a * R[j] + bx * R[6 + j];
    dp[3 + j] = a * R[3 + j] + by * R[6 + j];
  }
  if (d_point != nullptr) {
    for (int k = 0; k < 6; ++k) d_point[k] = dp[k];
  }
  if (d_eo != nullptr) {
    // Projection-centre partials are the negated point partials (equations 17-19, 23-25).
    for (int j = 0; j < 3; ++j) {
      d_eo[j] = -dp[j];
      d_eo[6 + j] = -dp[3 + j];
    }
    // Rotations: d(u,v,w) = axis x (u,v,w) with axis e_x (omega), Rx e_y = (0, cos w, sin w) (phi)
    // and R e_z = third column of R (kappa). In image coordinates this gives
    //   dx/domega = x y / c, dy/domega = c + y^2 / c                               (eqs 20, 26)
    //   dx/dphi = -c cos w - y sin w - x^2 cos w / c, dy/dphi = x sin w - x y cos w / c (eqs 21, 27)
    //   d/dkappa = d/dX0 (Y - Y0) - d/dY0 (X - X0)                                    (eqs 22, 28)
    const double so = sin_omega_, co = cos_omega_;
    const double inv_c = 1.0 / focal;
    d_eo[3] = x * y * inv_c;
    d_eo[9] = focal + y * y * inv_c;
    d_eo[4] = -focal * co - y * so - x * x * co * inv_c;
    d_eo[10] = x * so - x * y * co * inv_c;
    d_eo[5] = d_eo[0] * d[1] - d_eo[1] * d[0];
    d_eo[11] = d_eo[6] * d[1] - d_eo[7] * d[0];
  }
  return true;
}

bool ProjectWithJacobians(const double* eo, const double* point, double focal, double* xy,
                          double* d_eo, double* d_point, double* d_focal) {
  return SeedProjector(eo, focal).Project(point, xy, d_eo, d_point, d_focal);
}

bool ProjectWithJacobiansEarthCurvature(const double* eo, const double* point, double focal,
                                        double earth_radius_m, double* xy, double* d_eo,
                                        double* d_point, double* d_focal) {
  double lowered[3];
  LowerByEarthCurvature(eo, point, earth_radius_m, lowered);
  double point_partials[6];
  double* d_lowered = d_point != nullptr ? d_point : (d_eo != nullptr ? point_partials : nullptr);
  if (!ProjectWithJacobians(eo, lowered, focal, xy, d_eo, d_lowered, d_focal)) return false;
  if (d_lowered == nullptr) return true;
  // d(lowered Z)/dX = -g_X, d(lowered Z)/dY = -g_Y; the rotation partials need no change.
  const double g_x = (point[0] - eo[0]) / earth_radius_m;
  const double g_y = (point[1] - eo[1]) / earth_radius_m;
  for (int row = 0; row < 2; ++row) {
    double* p = d_lowered + 3 * row;
    const double by_z = p[2];
    p[0] -= by_z * g_x;
    p[1] -= by_z * g_y;
    if (d_eo != nullptr) {
      d_eo[6 * row + 0] = -p[0];
      d_eo[6 * row + 1] = -p[1];
    }
  }
  return true;
}

double EarthCurvatureDrop(const Eigen::Vector3d& center, const Eigen::Vector3d& point,
                          double earth_radius_m) {
  return EarthCurvatureDropOf(center.data(), point.data(), earth_radius_m);
}

namespace {

double CameraEarthCurvatureDrop(const FrameCamera& camera, const Eigen::Vector3d& center,
                                const Eigen::Vector3d& point) {
  return camera.apply_ecc ? EarthCurvatureDrop(center, point, camera.earth_radius_m) : 0.0;
}

}  // namespace

Status ProjectGroundPoint(const FrameCamera& camera, const ExteriorOrientation& eo,
                          const Eigen::Vector3d& point_in_ground, PixelOrigin origin,
                          Eigen::Vector2d* column_row) {
  Eigen::Vector3d p = point_in_ground;
  p.z() -= CameraEarthCurvatureDrop(camera, eo.center_in_ground(), point_in_ground);
  double xy[2];
  if (!ProjectToImagePlane(eo.data(), p.data(), camera.focal_length_um, xy))
    return Status::Error("point is behind the camera");
  return PixelFromImagePlane(camera, Eigen::Vector2d(xy[0], xy[1]), origin, column_row);
}

Status IntersectRayWithPlane(const FrameCamera& camera, const ExteriorOrientation& eo,
                             const Eigen::Vector2d& column_row, PixelOrigin origin, double height_m,
                             Eigen::Vector3d* point_in_ground) {
  Eigen::Vector2d xy;
  Status status = ImagePlaneFromPixel(camera, column_row, origin, &xy);
  if (!status.ok()) return status;
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
  // The ray in camera coordinates is (x, y, -c); in ground coordinates R^T (x, y, -c).
  const Eigen::Vector3d ray = R.transpose() * Eigen::Vector3d(xy.x(), xy.y(), -camera.focal_length_um);
  const Eigen::Vector3d center = eo.center_in_ground();
  if (!(std::abs(ray.z()) > 1e-12 * ray.norm()))
    return Status::Error("ray is parallel to the plane");
  double plane_z = height_m;
  Eigen::Vector3d p;
  for (int iteration = 0; iteration < 20; ++iteration) {
    const double t = (plane_z - center.z()) / ray.z();
    if (!(t > 0.0)) return Status::Error("plane is behind the camera along this ray");
    p = center + t * ray;
    // With ECC the curved surface at height h lies at h - D^2/(2R) in the tangent-plane frame.
    const double next_z = height_m - CameraEarthCurvatureDrop(camera, center, p);
    if (std::abs(next_z - plane_z) < 1e-9) break;
    plane_z = next_z;
  }
  p.z() = height_m;
  *point_in_ground = p;
  return Status::Ok();
}

Status IntersectRayWithAverageZ(const FrameCamera& camera, const ExteriorOrientation& eo,
                                const Eigen::Vector2d& column_row, PixelOrigin origin,
                                Eigen::Vector3d* point_in_ground) {
  return IntersectRayWithPlane(camera, eo, column_row, origin, camera.average_z_m.value_or(0.0),
                               point_in_ground);
}

}  // namespace photopose
