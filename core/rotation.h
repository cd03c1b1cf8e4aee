#pragma once
// Rotation conventions. Internally photopose uses the seed's matrix (lecture notes, equation 1):
//
//   R_camera_from_ground = Rx(omega) * Ry(phi) * Rz(kappa)
//   Rx(a) = [1 0 0; 0 cos a -sin a; 0 sin a cos a], Ry(a) = [cos a 0 sin a; 0 1 0; -sin a 0 cos a],
//   Rz(a) = [cos a -sin a 0; sin a cos a 0; 0 0 1],
//
// which maps a ground vector (X - X0) to camera coordinates (u, v, w). Other conventions are converted
// to and from this matrix at the boundaries (tables, CLI). docs/conventions.md has a worked example
// of each. All angles are radians unless a name says otherwise.

#include <Eigen/Core>
#include <optional>
#include <string>

#include "core/enum_names.h"
#include "core/status.h"
#include "core/types.h"

namespace photopose {

enum class RotationConvention {
  // R_camera_from_ground = Rx(omega) Ry(phi) Rz(kappa): the seed lecture's equation 1, photopose's
  // internal convention. Named "rxryrz" at the boundaries ("seed" is accepted as an alias).
  kSeed,
  // Wolf & Dewitt / PATB omega-phi-kappa: M = M_kappa M_phi M_omega maps ground to image, with
  // M_omega = [1 0 0; 0 cos sin; 0 -sin cos] etc. For the same three numbers M is the transpose of
  // the seed's matrix.
  kOpk,
  // Y-primary phi-omega-kappa of Chinese textbooks: R_ground_from_camera = R_phi R_omega R_kappa
  // with a3 = -sin(phi) cos(omega), b3 = -sin(omega), c3 = cos(phi) cos(omega); the collinearity
  // uses its transpose.
  kPok,
};

// "rxryrz", "opk", "pok": the names every output prints; "seed" is accepted for "rxryrz"; case is
// ignored when parsing (core/enum_names.h).
inline constexpr EnumNameEntry<RotationConvention> kRotationConventionNames[] = {
    {RotationConvention::kSeed, "rxryrz"},
    {RotationConvention::kOpk, "opk"},
    {RotationConvention::kPok, "pok"},
    {RotationConvention::kSeed, "seed"}};
constexpr EnumNameTable<RotationConvention> EnumNames(RotationConvention) {
  return EnumNameTable<RotationConvention>(kRotationConventionNames, NameMatch::kIgnoreCase);
}

// Elementary rotations (active, right-handed), templated for Ceres Jets.
template <typename T>
Eigen::Matrix<T, 3, 3> RotationX(const T& a);
template <typename T>
Eigen::Matrix<T, 3, 3> RotationY(const T& a);
template <typename T>
Eigen::Matrix<T, 3, 3> RotationZ(const T& a);

// The seed's matrix, row-major into R[9], templated for Ceres Jets. R = Rx(omega) Ry(phi) Rz(kappa).
template <typename T>
void SeedRotationMatrix(const T omega, const T phi, const T kappa, T* R);
// The same from the sines and cosines of omega, phi, kappa (for callers that compute them once).
template <typename T>
void SeedRotationFromSinCos(const T& so, const T& co, const T& sp, const T& cp, const T& sk,
                            const T& ck, T* R);

// R_camera_from_ground for three angles (rad) in the named convention.
Eigen::Matrix3d RotationFromAngles(RotationConvention convention, const Eigen::Vector3d& angles_rad);

// Inverse of RotationFromAngles, returning (omega, phi, kappa). The angle of the middle rotation
// is returned in [-pi/2, pi/2] (phi for seed and opk, omega for the Y-primary pok), the others in
// (-pi, pi]. At the gimbal lock (middle rotation at +-90 deg) the primary angle is set to zero and
// kappa carries the combined rotation.
Eigen::Vector3d AnglesFromRotation(RotationConvention convention,
                                   const Eigen::Matrix3d& R_camera_from_ground);

// Platform attitude of the seed's section 1: roll about the forward axis, pitch about the lateral
// axis, yaw about the vertical axis, composed as equation 1: R_platform_from_ground =
// Rx(roll) Ry(pitch) Rz(yaw) (it is the seed's matrix with (omega, phi, kappa) = (roll, pitch, yaw)).
Eigen::Matrix3d RotationFromRollPitchYaw(double roll_rad, double pitch_rad, double yaw_rad);
Eigen::Vector3d RollPitchYawFromRotation(const Eigen::Matrix3d& R_platform_from_ground);

// The ArcGIS camera-table flags that change the meaning of the angles in a frames table.
struct AngleFlags {
  // AngleDirection: -1 (schema default, "clockwise"): the angles are used as the convention defines
  // them; +1 ("counterclockwise"): the three angles are of the opposite sense and are negated on
  // reading and writing.
  int angle_direction = -1;
};

// Applies AngleDirection to angles read from or written to a table (an involution).
Eigen::Vector3d ApplyAngleDirection(const AngleFlags& flags, const Eigen::Vector3d& angles_rad);

// ------------------------------------------------------------------ the one boundary conversion
// The frames tables (read and written), resect's and bundle's JSON reports and console lines and
// the comparison tool go through these two functions, so that all agree.
//
// ConventionAnglesFromSeed: photopose's internal angles (seed convention, rad) -> the three angles
// (rad) of `convention` with the camera's AngleDirection applied: the rotation matrix of the seed
// angles, decomposed in `convention`, negated for AngleDirection +1. SeedAnglesFromConvention is
// its inverse. Polarity does not enter: photopose applies it in the camera model as the mirror
// (x, y) -> (-x, -y) of the image plane (core/camera_models.h), so the rotation needs no share of it.
Eigen::Vector3d ConventionAnglesFromSeed(RotationConvention convention, const AngleFlags& flags,
                                         const Eigen::Vector3d& seed_angles_rad);
Eigen::Vector3d SeedAnglesFromConvention(RotationConvention convention, const AngleFlags& flags,
                                         const Eigen::Vector3d& convention_angles_rad);
// d(ConventionAnglesFromSeed) / d(seed angles) (3 x 3, unitless) by central differences (step
// 1e-6 rad, differences wrapped to (-pi, pi]): propagates covariances to the angles written.
Eigen::Matrix3d ConventionFromSeedJacobian(RotationConvention convention, const AngleFlags& flags,
                                           const Eigen::Vector3d& seed_angles_rad);

// ------------------------------------------------------------------ computer-vision poses
// COLMAP, OpenSfM and OpenCV give an image's pose as the world -> camera rigid transformation
// x_camera = R_cv_camera_from_world X + t, in a camera frame x right, y down, z forward (the
// optical axis). The seed's camera frame is (u, v, w) = (x, -y, -z), so R_camera_from_ground =
// diag(1, -1, -1) R_cv_camera_from_world and the centre X0 = -R_cv_camera_from_world^T t. Every
// reader and writer of such a format converts through these two functions (exactly; a round trip
// keeps R and the centre to 1e-12).
ExteriorOrientation EoFromComputerVisionPose(const Eigen::Matrix3d& R_cv_camera_from_world,
                                             const Eigen::Vector3d& t);
void ComputerVisionPoseFromEo(const ExteriorOrientation& eo,
                              Eigen::Matrix3d* R_cv_camera_from_world, Eigen::Vector3d* t);

// A rotation vector (angle-axis: the axis times the angle, rad; BAL, OpenSfM) and its matrix.
// RotationVectorFromRotation returns the angle in [0, pi].
Eigen::Matrix3d RotationFromRotationVector(const Eigen::Vector3d& rotation_vector_rad);
Eigen::Vector3d RotationVectorFromRotation(const Eigen::Matrix3d& R);

// Checks that a 3x3 matrix is a proper rotation (orthonormal to `tolerance`, determinant +1).
Status CheckRotationMatrix(const Eigen::Matrix3d& R, double tolerance = 1e-6);

// Wraps an angle to (-pi, pi].
double WrapAngle(double angle_rad);

// ------------------------------------------------------------------ template definitions

template <typename T>
Eigen::Matrix<T, 3, 3> RotationX(const T& a) {
  using std::cos;
  using std::sin;
  Eigen::Matrix<T, 3, 3> R;
  R << T(1), T(0), T(0), T(0), cos(a), -sin(a), T(0), sin(a), cos(a);
  return R;
}

template <typename T>
Eigen::Matrix<T, 3, 3> RotationY(const T& a) {
  using std::cos;
  using std::sin;
  Eigen::Matrix<T, 3, 3> R;
  R << cos(a), T(0), sin(a), T(0), T(1), T(0), -sin(a), T(0), cos(a);
  return R;
}

template <typename T>
Eigen::Matrix<T, 3, 3> RotationZ(const T& a) {
  using std::cos;
  using std::sin;
  Eigen::Matrix<T, 3, 3> R;
  R << cos(a), -sin(a), T(0), sin(a), cos(a), T(0), T(0), T(0), T(1);
  return R;
}

template <typename T>
void SeedRotationMatrix(const T omega, const T phi, const T kappa, T* R) {
  using std::cos;
  using std::sin;
  SeedRotationFromSinCos(sin(omega), cos(omega), sin(phi), cos(phi), sin(kappa), cos(kappa), R);
}

template <typename T>
void SeedRotationFromSinCos(const T& so, const T& co, const T& sp, const T& cp, const T& sk,
                            const T& ck, T* R) {
  // Rx(omega) * Ry(phi) * Rz(kappa), expanded.
  R[0] = cp * ck;
  R[1] = -cp * sk;
  R[2] = sp;
  R[3] = co * sk + so * sp * ck;
  R[4] = co * ck - so * sp * sk;
  R[5] = -so * cp;
  R[6] = so * sk - co * sp * ck;
  R[7] = so * ck + co * sp * sk;
  R[8] = co * cp;
}

}  // namespace photopose
