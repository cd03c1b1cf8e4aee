#pragma once
// Multi-ray intersection of one ground point from images of known exterior orientation and
// interior orientation (forward intersection): the starting point of tie points in a block, and
// the check points of a bundle adjustment.
//
// 1. Linear: the point nearest, in the least-squares sense, to every ray (X0_i + t d_i), d_i the
//    direction of the measurement's ray R_i^T (a_i, b_i, -1) from its camera model's inversion.
// 2. Gauss-Newton on the whitened collinearity residuals of the measurements (the same cost
//    functions as the bundle adjustment, the images and cameras held fixed, with each camera's
//    earth-curvature correction: CreateRayCost), until the step is below 1e-9 of the distance to
//    the nearest camera. The linear start ignores the correction (decimetres at most).
// 3. Covariance (J^T J)^-1 of the whitened residuals: the a-priori covariance of the point from
//    the measurement accuracies alone (images taken as error-free); multiply by sigma0^2 for the
//    a-posteriori one.
//
// Failures (fewer than two rays, rays nearly parallel, the point behind a camera, no convergence)
// return an error with the reason.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/mark_weight.h"
#include "core/status.h"
#include "core/types.h"

namespace ceres {
class CostFunction;
}

namespace photopose {

// One measurement of the point: its camera, its image's exterior orientation, the observation in
// the camera model's unit and its standard deviation in that unit.
struct RayObservation {
  const BlockCamera* camera = nullptr;
  ExteriorOrientation eo;
  Eigen::Vector2d observation = Eigen::Vector2d::Zero();
  double sigma = 1.0;
};

struct TriangulationOptions {
  // Smallest angle between two rays for a usable intersection (rad): below it the depth is not
  // determined. 2 degrees by default.
  double min_intersection_angle_rad = 0.0349;
  int max_iterations = 20;  // Gauss-Newton iterations (count)
};

struct TriangulationResult {
  Eigen::Vector3d point_m = Eigen::Vector3d::Zero();
  // A-priori covariance (m^2), from the measurement sigmas with the images fixed.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double max_intersection_angle_rad = 0.0;  // largest angle between two of the rays
  double rms_whitened = 0.0;                // RMS of the whitened residuals (unitless)
  int iterations = 0;
};

// The cost of one ray (analytic; parameter blocks: the eo, the point, the camera's parameters):
// the collinearity model of its camera, whitened by the ray's sigma, with the camera's
// earth-curvature correction (BlockCamera::earth_curvature_radius_m). The one model of every
// intersection: the tie points' start values, the check points and their covariances.
ceres::CostFunction* CreateRayCost(const RayObservation& ray);

Status TriangulatePoint(const TriangulationOptions& options,
                        const std::vector<RayObservation>& rays, TriangulationResult* result);

// The rays of every mark of block point `point` whose image has an eo, each with the sigma of
// core/mark_weight.h under `defaults`. Marks listed in `skip` (indices into Block::marks) are left
// out.
std::vector<RayObservation> PointRays(const Block& block, int point,
                                      const MarkSigmaDefaults& defaults,
                                      const std::vector<char>* skip = nullptr);

}  // namespace photopose
