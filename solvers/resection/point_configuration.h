#pragma once
// The one check of a ground-point configuration for resection: is the point cloud spread out enough
// in two (collinearity) or three (coplanarity) directions for the pose to be determined? Resection,
// LO-RANSAC, the DLT and the Taylor solver all use it.
//
// The spread is measured by the RMS extents of the centred points along their principal axes: the
// square roots of the eigenvalues of the scatter matrix sum (X - mean)(X - mean)^T / n, i.e. the
// singular values of the centred n x 3 point matrix over sqrt(n). Points whose second extent is at
// most `ratio` times the first lie on one line: every pose rotated about that line fits them
// equally well.

#include <Eigen/Core>
#include <vector>

#include "core/status.h"

namespace photopose {

// Relative extent below which the cloud counts as flat in a direction (unitless): well above the
// rounding of the eigenvalues (~1e-8 of the largest extent after the square root), well below any
// real survey (1 mm across 1 km is 1e-6).
constexpr double kDegenerateExtentRatio = 1e-6;

struct PointSpread {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d extents_m = Eigen::Vector3d::Zero();  // RMS extents, ascending (m)
  bool finite = true;                                   // every coordinate finite

  // The second extent is at most `ratio` times the first (all points on one line, or coincident).
  bool collinear(double ratio = kDegenerateExtentRatio) const {
    return !(extents_m[1] > ratio * extents_m[2]);
  }
  // The smallest extent is at most `ratio` times the first (all points in one plane).
  bool coplanar(double ratio = kDegenerateExtentRatio) const {
    return !(extents_m[0] > ratio * extents_m[2]);
  }
};

// Centroid and principal RMS extents (iterative symmetric eigensolver: the closed form loses the
// small eigenvalue's digits). Empty input gives zeros.
PointSpread ComputePointSpread(const std::vector<Eigen::Vector3d>& points);

// Resection's requirement: at least three points, finite coordinates, not all on one line. The
// error says which: "needs at least three control points, has 2", "a control point has a non-finite
// coordinate", "all control points lie on one line (or coincide): the rotation about that line is
// undetermined".
Status CheckControlConfiguration(const std::vector<Eigen::Vector3d>& points_in_ground);

}  // namespace photopose
