#pragma once
// Basic types shared by every part of photopose.
//
// Frames: "ground" is the object-space frame of the control points (a projected or local Cartesian
// system, metres); "camera" is the seed's (u, v, w) frame: origin at the projection centre, u along
// film x, v along film y, w towards the viewer, so visible points have w < 0 and the image plane sits
// at w = -c (the seed's equations 4-5).

#include <Eigen/Core>
#include <array>
#include <cmath>

namespace photopose {

// Parameter block sizes, defined once for the model, the cost functions and the solvers.
constexpr int kExteriorOrientationSize = 6;  // X0, Y0, Z0 (m), omega, phi, kappa (rad, seed)
constexpr int kPointSize = 3;                // X, Y, Z (m)
constexpr int kResidualSize = 2;             // x, y

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;
constexpr double kArcSecondsPerRadian = 3600.0 * kDegreesPerRadian;

inline double DegreesToRadians(double degrees) { return degrees / kDegreesPerRadian; }
inline double RadiansToDegrees(double radians) { return radians * kDegreesPerRadian; }

// Exterior orientation in the seed convention: the projection centre in the ground frame and the
// angles (omega, phi, kappa) of R_camera_from_ground = Rx(omega) * Ry(phi) * Rz(kappa), so that
// (u, v, w) = R_camera_from_ground * (X - X0). Stored as one contiguous 6-vector, the Ceres block.
struct ExteriorOrientation {
  // X0, Y0, Z0 (m), omega, phi, kappa (rad).
  Eigen::Matrix<double, 6, 1> parameters = Eigen::Matrix<double, 6, 1>::Zero();

  Eigen::Vector3d center_in_ground() const { return parameters.head<3>(); }
  Eigen::Vector3d angles_seed_rad() const { return parameters.tail<3>(); }
  void set_center_in_ground(const Eigen::Vector3d& c) { parameters.head<3>() = c; }
  void set_angles_seed_rad(const Eigen::Vector3d& a) { parameters.tail<3>() = a; }
  double* data() { return parameters.data(); }
  const double* data() const { return parameters.data(); }
};

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

}  // namespace photopose
