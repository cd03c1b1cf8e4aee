#pragma once
// The minimal absolute-pose problem: three bearings and their three ground points.
//
// Method: Lambda Twist (M. Persson and K. Nordberg, "Lambda Twist: An Accurate Fast Robust
// Perspective Three Point (P3P) Solver", ECCV 2018). The depths lambda_i of the three points along
// their bearings y_i satisfy the three distance constraints
//
//   lambda_i^2 + lambda_j^2 - 2 (y_i . y_j) lambda_i lambda_j = |x_i - x_j|^2,
//
// two homogeneous quadrics in lambda are formed from them, a degenerate member of their pencil is
// found from one root of a cubic, it factors into two planes through the origin, and each plane
// meets a quadric in at most two rays. The depths are polished by Newton's method on the three
// constraints, and the pose follows from the two congruent triangles.
//
// Frames: the bearings are in the camera frame (u, v, w) of core/types.h; the camera-frame point is
// R_camera_from_ground * (X - center_in_ground) = lambda * bearing with lambda > 0. For an ideal
// image-plane point (x, y) (um) and principal distance c (um) the bearing is normalize(x, y, -c).

#include <Eigen/Core>
#include <array>
#include <vector>

namespace photopose {

// One exterior orientation as a rotation matrix and a projection centre:
// (u, v, w) = R_camera_from_ground * (X - center_in_ground).
struct PoseCandidate {
  Eigen::Matrix3d R_camera_from_ground = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center_in_ground = Eigen::Vector3d::Zero();  // metres, ground frame
};

// bearings: directions (camera frame) from the projection centre to the three points; they are
// normalised here, so any positive multiple is accepted. points_in_ground: the three points (m).
// Appends every real solution with all three points in front along their bearings (at most 4) to
// *solutions and returns how many were appended. Returns 0, without touching *solutions, for a
// degenerate input: collinear or coincident points, zero or non-finite bearings.
int SolveP3P(const std::array<Eigen::Vector3d, 3>& bearings,
             const std::array<Eigen::Vector3d, 3>& points_in_ground,
             std::vector<PoseCandidate>* solutions);

// SolveP3P's normalisation of one bearing: *unit = bearing / |bearing|; false for a zero or
// non-finite bearing.
bool UnitBearing(const Eigen::Vector3d& bearing, Eigen::Vector3d* unit);
// SolveP3P for bearings already normalised by UnitBearing (the same solutions, bit for bit): a
// caller that draws many triples from the same bearings normalises each once.
int SolveP3PUnitBearings(const std::array<Eigen::Vector3d, 3>& unit_bearings,
                         const std::array<Eigen::Vector3d, 3>& points_in_ground,
                         std::vector<PoseCandidate>* solutions);

}  // namespace photopose
