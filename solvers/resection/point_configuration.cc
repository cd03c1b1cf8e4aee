#include "solvers/resection/point_configuration.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <string>

namespace photopose {

PointSpread ComputePointSpread(const std::vector<Eigen::Vector3d>& points) {
  PointSpread spread;
  if (points.empty()) return spread;
  for (const Eigen::Vector3d& p : points) {
    spread.finite = spread.finite && p.allFinite();
    spread.centroid += p;
  }
  spread.centroid /= static_cast<double>(points.size());
  if (!spread.finite) return spread;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d d = p - spread.centroid;
    scatter.noalias() += d * d.transpose();
  }
  scatter /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter, Eigen::EigenvaluesOnly);
  spread.extents_m = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt();  // ascending
  return spread;
}

Status CheckControlConfiguration(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) {
    return Status::Error("needs at least three control points, has " +
                         std::to_string(points.size()));
  }
  const PointSpread spread = ComputePointSpread(points);
  if (!spread.finite) return Status::Error("a control point has a non-finite coordinate");
  if (spread.collinear()) {
    return Status::Error(
        "all control points lie on one line (or coincide): the rotation about that line is "
        "undetermined");
  }
  return Status::Ok();
}

}  // namespace photopose
