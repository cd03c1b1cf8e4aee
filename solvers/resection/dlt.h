#pragma once
// Linear pose from six or more non-coplanar points with known interior orientation: the direct
// linear transformation (Abdel-Aziz and Karara 1971) on calibrated bearings, with Hartley's
// normalisation (R. Hartley, "In defense of the eight-point algorithm", PAMI 1997; Hartley and
// Zisserman, Multiple View Geometry, 2nd ed., algorithm 7.1).
//
// The 3x4 matrix P ~ [R | t] with bearing_i ~ P (X_i, 1) is the null vector of the stacked
// constraints e_k^T P (X_i, 1) = 0, e_1 and e_2 spanning the plane orthogonal to bearing_i (the
// calibrated form of the cross-product constraint). Its left 3x3 block, scaled and signed so the
// points lie in front, is projected onto SO(3) with an SVD; the translation is then re-solved
// linearly for that rotation. The result is an initial value, not a least-squares estimate.
//
// Frames as p3p.h: bearings in the camera frame (normalize(x, y, -c) for an image-plane point),
// points in the ground frame (m).

#include <Eigen/Core>
#include <vector>

#include "core/status.h"
#include "solvers/resection/p3p.h"

namespace photopose {

// Minimum number of correspondences of SolveDlt (11 unknowns of P up to scale, two rows each).
constexpr int kDltMinimumPoints = 6;

// bearings[i] (any positive multiple of the direction) looks at points_in_ground[i]. Writes *pose
// on success. Errors: fewer than kDltMinimumPoints, unequal sizes, non-finite or zero input,
// collinear or coplanar ground points (their thinnest RMS extent below 1e-6 of the widest), a
// linear system without a one-dimensional null space, a reflection, or most points behind the
// camera.
Status SolveDlt(const std::vector<Eigen::Vector3d>& bearings,
                const std::vector<Eigen::Vector3d>& points_in_ground, PoseCandidate* pose);

}  // namespace photopose
