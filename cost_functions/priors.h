#pragma once
// Prior cost functions for the weighted bundle adjustment (the bundle-objective seed note):
// control-point residuals / marker accuracy, camera-position (GNSS) residuals / camera accuracy, and
// attitude residuals / attitude accuracy. Residuals are whitened: (estimate - measured) / sigma, per
// axis. All three are linear in their parameters; the Jacobians are the diagonal 1 / sigma.

#include <ceres/ceres.h>

#include <Eigen/Core>

#include "core/rotation.h"
#include "core/types.h"

namespace photopose {

// Ground (control) point prior. Parameter block: ground point (3). Sigmas in metres, one per axis.
class GroundPointPrior final : public ceres::SizedCostFunction<3, kPointSize> {
 public:
  GroundPointPrior(const Eigen::Vector3d& measured_m, const Eigen::Vector3d& sigma_m)
      : measured_m_(measured_m), inverse_sigma_(sigma_m.cwiseInverse()) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    for (int i = 0; i < 3; ++i) residuals[i] = (parameters[0][i] - measured_m_[i]) * inverse_sigma_[i];
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[0]);
      J = inverse_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::Vector3d measured_m_;
  Eigen::Vector3d inverse_sigma_;
};

// Camera-position (GNSS) prior on X0, Y0, Z0. Parameter block: exterior orientation (6).
class CameraPositionPrior final : public ceres::SizedCostFunction<3, kExteriorOrientationSize> {
 public:
  CameraPositionPrior(const Eigen::Vector3d& measured_m, const Eigen::Vector3d& sigma_m)
      : measured_m_(measured_m), inverse_sigma_(sigma_m.cwiseInverse()) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    for (int i = 0; i < 3; ++i) residuals[i] = (parameters[0][i] - measured_m_[i]) * inverse_sigma_[i];
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> J(jacobians[0]);
      J.setZero();
      J.leftCols<3>() = inverse_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::Vector3d measured_m_;
  Eigen::Vector3d inverse_sigma_;
};

// Attitude prior on the seed angles omega, phi, kappa (rad; differences wrapped to (-pi, pi]).
// Parameter block: exterior orientation (6).
class AttitudePrior final : public ceres::SizedCostFunction<3, kExteriorOrientationSize> {
 public:
  AttitudePrior(const Eigen::Vector3d& measured_rad, const Eigen::Vector3d& sigma_rad)
      : measured_rad_(measured_rad), inverse_sigma_(sigma_rad.cwiseInverse()) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    for (int i = 0; i < 3; ++i)
      residuals[i] = WrapAngle(parameters[0][3 + i] - measured_rad_[i]) * inverse_sigma_[i];
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> J(jacobians[0]);
      J.setZero();
      J.rightCols<3>() = inverse_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::Vector3d measured_rad_;
  Eigen::Vector3d inverse_sigma_;
};

}  // namespace photopose
