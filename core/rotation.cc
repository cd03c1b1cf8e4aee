#include "core/rotation.h"

#include "core/types.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

namespace photopose {
namespace {

// Angles of the seed's matrix R = Rx(omega) Ry(phi) Rz(kappa): R(0,2) = sin(phi),
// R(1,2) = -sin(omega) cos(phi), R(2,2) = cos(omega) cos(phi), R(0,1) = -cos(phi) sin(kappa),
// R(0,0) = cos(phi) cos(kappa).
Eigen::Vector3d SeedAnglesFromMatrix(const Eigen::Matrix3d& R) {
  const double s_phi = std::clamp(R(0, 2), -1.0, 1.0);
  const double phi = std::asin(s_phi);
  double omega, kappa;
  if (std::abs(s_phi) < 1.0 - 1e-12) {
    omega = std::atan2(-R(1, 2), R(2, 2));
    kappa = std::atan2(-R(0, 1), R(0, 0));
  } else {
    // Gimbal lock: only omega +- kappa is defined; put it all into kappa.
    omega = 0.0;
    kappa = std::atan2(R(1, 0), R(1, 1));
  }
  return Eigen::Vector3d(omega, phi, kappa);
}

}  // namespace

Eigen::Matrix3d RotationFromAngles(RotationConvention convention, const Eigen::Vector3d& angles) {
  const double omega = angles[0], phi = angles[1], kappa = angles[2];
  switch (convention) {
    case RotationConvention::kSeed: {
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R;
      SeedRotationMatrix(omega, phi, kappa, R.data());
      return R;
    }
    case RotationConvention::kOpk:
      // M = M_kappa M_phi M_omega with the passive elementary matrices M_a = R(-a).
      return RotationZ(-kappa) * RotationY(-phi) * RotationX(-omega);
    case RotationConvention::kPok:
      // R_ground_from_camera = R_phi R_omega R_kappa with R_phi = Ry(-phi) (a3 = -sin phi cos omega).
      return (RotationY(-phi) * RotationX(omega) * RotationZ(kappa)).transpose();
  }
  return Eigen::Matrix3d::Identity();
}

Eigen::Vector3d AnglesFromRotation(RotationConvention convention, const Eigen::Matrix3d& R) {
  switch (convention) {
    case RotationConvention::kSeed:
      return SeedAnglesFromMatrix(R);
    case RotationConvention::kOpk:
      // M(omega, phi, kappa) = seed(omega, phi, kappa)^T.
      return SeedAnglesFromMatrix(R.transpose());
    case RotationConvention::kPok: {
      const Eigen::Matrix3d G = R.transpose();  // R_ground_from_camera: [a1 a2 a3; b1 b2 b3; c1 c2 c3]
      const double s_omega = std::clamp(-G(1, 2), -1.0, 1.0);
      const double omega = std::asin(s_omega);
      double phi, kappa;
      if (std::abs(s_omega) < 1.0 - 1e-12) {
        phi = std::atan2(-G(0, 2), G(2, 2));
        kappa = std::atan2(G(1, 0), G(1, 1));
      } else {
        phi = 0.0;
        kappa = std::atan2(-G(0, 1), G(0, 0));
      }
      return Eigen::Vector3d(omega, phi, kappa);
    }
  }
  return Eigen::Vector3d::Zero();
}

Eigen::Matrix3d RotationFromRollPitchYaw(double roll, double pitch, double yaw) {
  return RotationFromAngles(RotationConvention::kSeed, Eigen::Vector3d(roll, pitch, yaw));
}

Eigen::Vector3d RollPitchYawFromRotation(const Eigen::Matrix3d& R_platform_from_ground) {
  return SeedAnglesFromMatrix(R_platform_from_ground);
}

Eigen::Vector3d ApplyAngleDirection(const AngleFlags& flags, const Eigen::Vector3d& angles) {
  return flags.angle_direction > 0 ? Eigen::Vector3d(-angles) : angles;
}

Eigen::Vector3d ConventionAnglesFromSeed(RotationConvention convention, const AngleFlags& flags,
                                         const Eigen::Vector3d& seed_angles_rad) {
  return ApplyAngleDirection(
      flags, AnglesFromRotation(convention,
                                RotationFromAngles(RotationConvention::kSeed, seed_angles_rad)));
}

Eigen::Vector3d SeedAnglesFromConvention(RotationConvention convention, const AngleFlags& flags,
                                         const Eigen::Vector3d& convention_angles_rad) {
  return AnglesFromRotation(
      RotationConvention::kSeed,
      RotationFromAngles(convention, ApplyAngleDirection(flags, convention_angles_rad)));
}

Eigen::Matrix3d ConventionFromSeedJacobian(RotationConvention convention, const AngleFlags& flags,
                                           const Eigen::Vector3d& seed_angles_rad) {
  // Truncation (~h^2) and rounding (~1e-16 / h) errors are both below 1e-10 at this step.
  constexpr double kStepRad = 1e-6;
  Eigen::Matrix3d J;
  for (int j = 0; j < 3; ++j) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    step[j] = kStepRad;
    const Eigen::Vector3d plus = ConventionAnglesFromSeed(convention, flags, seed_angles_rad + step);
    const Eigen::Vector3d minus = ConventionAnglesFromSeed(convention, flags, seed_angles_rad - step);
    for (int i = 0; i < 3; ++i) J(i, j) = WrapAngle(plus[i] - minus[i]) / (2.0 * kStepRad);
  }
  return J;
}

namespace {
// The computer-vision camera frame (x right, y down, z forward) -> the seed's (u, v, w) = (x, -y,
// -z).
const Eigen::Matrix3d& SeedFromComputerVisionCamera() {
  static const Eigen::Matrix3d kFlip = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  return kFlip;
}
}  // namespace

ExteriorOrientation EoFromComputerVisionPose(const Eigen::Matrix3d& R_cv_camera_from_world,
                                             const Eigen::Vector3d& t) {
  ExteriorOrientation eo;
  eo.set_center_in_ground(-R_cv_camera_from_world.transpose() * t);
  eo.set_angles_seed_rad(AnglesFromRotation(
      RotationConvention::kSeed, SeedFromComputerVisionCamera() * R_cv_camera_from_world));
  return eo;
}

void ComputerVisionPoseFromEo(const ExteriorOrientation& eo,
                              Eigen::Matrix3d* R_cv_camera_from_world, Eigen::Vector3d* t) {
  *R_cv_camera_from_world = SeedFromComputerVisionCamera() *
                            RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
  *t = -*R_cv_camera_from_world * eo.center_in_ground();
}

Eigen::Matrix3d RotationFromRotationVector(const Eigen::Vector3d& rotation_vector_rad) {
  const double angle = rotation_vector_rad.norm();
  if (!(angle > 0.0)) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, rotation_vector_rad / angle).toRotationMatrix();
}

Eigen::Vector3d RotationVectorFromRotation(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd angle_axis(R);
  return angle_axis.angle() * angle_axis.axis();
}

Status CheckRotationMatrix(const Eigen::Matrix3d& R, double tolerance) {
  if (!R.allFinite()) return Status::Error("rotation matrix has a non-finite element");
  const double orthogonality = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality > tolerance) {
    std::ostringstream os;
    os << "rotation matrix is not orthonormal (max |R R^T - I| = " << orthogonality << ")";
    return Status::Error(os.str());
  }
  if (R.determinant() < 0.0) return Status::Error("rotation matrix has determinant -1 (a reflection)");
  return Status::Ok();
}

double WrapAngle(double a) {
  // Already in (-pi, pi]: remainder would return it unchanged (it is exact, and at pi the quotient
  // 1/2 rounds to the even 0); the comparison pair costs far less than the call.
  if (a > -kPi && a <= kPi) return a;
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}

}  // namespace photopose
