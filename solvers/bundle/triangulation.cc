#include "solvers/bundle/triangulation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "core/rotation.h"
#include "cost_functions/collinearity_cost.h"

namespace photopose {
namespace {

// Gauss-Newton stops when the step is below this fraction of the distance to the nearest camera:
// 1e-9 of 100 m is 0.1 um.
constexpr double kRelativeStep = 1e-9;

// The rays' normal equations at `point`: N = sum J^T J, g = sum J^T r and the sum of squared
// whitened residuals, J the point's columns. False when a cost cannot be evaluated (the point is
// behind a camera).
bool LinearizeRays(const std::vector<RayObservation>& rays,
                   const std::vector<std::unique_ptr<ceres::CostFunction>>& costs,
                   const Eigen::Vector3d& point, Eigen::Matrix3d* N, Eigen::Vector3d* g,
                   double* sum) {
  N->setZero();
  g->setZero();
  *sum = 0.0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const double* parameters[] = {rays[i].eo.data(), point.data(), rays[i].camera->params.data()};
    double residual[2];
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J;
    double* jacobians[] = {nullptr, J.data(), nullptr};
    if (!costs[i]->Evaluate(parameters, residual, jacobians)) return false;
    const Eigen::Vector2d r(residual[0], residual[1]);
    *N += J.transpose() * J;
    *g += J.transpose() * r;
    *sum += r.squaredNorm();
  }
  return true;
}

// Step 1, linear: sum_i (I - d d^T) (X - C_i) = 0, refused when the rays meet at less than the
// options' angle (result->max_intersection_angle_rad: the largest angle between two rays).
Status IntersectLinearly(const TriangulationOptions& options,
                         const std::vector<RayObservation>& rays, Eigen::Vector3d* X,
                         TriangulationResult* result) {
  std::vector<Eigen::Vector3d> directions(rays.size()), centers(rays.size());
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < rays.size(); ++i) {
    const RayObservation& ray = rays[i];
    Eigen::Vector2d ab;
    const Status inverted = NormalizedFromObservation(ray.camera->model, ray.camera->params.data(),
                                                      ray.camera->data(), ray.observation, &ab);
    if (!inverted.ok()) return Status::Error("a ray cannot be formed: " + inverted.message());
    const Eigen::Matrix3d R =
        RotationFromAngles(RotationConvention::kSeed, ray.eo.angles_seed_rad());
    directions[i] = (R.transpose() * Eigen::Vector3d(ab.x(), ab.y(), -1.0)).normalized();
    centers[i] = ray.eo.center_in_ground();
    const Eigen::Matrix3d P =
        Eigen::Matrix3d::Identity() - directions[i] * directions[i].transpose();
    A += P;
    b += P * centers[i];
  }
  double max_angle = 0.0;
  for (size_t i = 0; i < rays.size(); ++i)
    for (size_t j = i + 1; j < rays.size(); ++j)
      max_angle =
          std::max(max_angle, std::acos(std::clamp(directions[i].dot(directions[j]), -1.0, 1.0)));
  result->max_intersection_angle_rad = max_angle;
  if (max_angle < options.min_intersection_angle_rad) {
    return Status::Error("the rays meet at " + std::to_string(max_angle * kDegreesPerRadian) +
                         " deg at most: the depth is not determined");
  }
  *X = A.ldlt().solve(b);
  if (!X->allFinite()) return Status::Error("the rays do not intersect");
  return Status::Ok();
}

}  // namespace

std::vector<RayObservation> PointRays(const Block& block, int point,
                                      const MarkSigmaDefaults& defaults,
                                      const std::vector<char>* skip) {
  std::vector<RayObservation> rays;
  if (point < 0 || point >= static_cast<int>(block.marks_of_point.size())) return rays;
  for (const int m : block.marks_of_point[point]) {
    if (skip != nullptr && (*skip)[m]) continue;
    const BlockMark& mark = block.marks[m];
    const BlockImage& image = block.images[mark.image];
    if (!image.eo) continue;
    RayObservation ray;
    ray.camera = &block.cameras[image.camera];
    ray.eo = *image.eo;
    ray.observation = mark.observation;
    ray.sigma = MarkSigma(mark, *ray.camera, defaults);
    rays.push_back(ray);
  }
  return rays;
}

ceres::CostFunction* CreateRayCost(const RayObservation& ray) {
  return CreateCollinearityCost(
      JacobianType::kAnalytic,
      CollinearityFunctor(ray.camera->model, ray.observation, ray.camera->data(), 1.0 / ray.sigma,
                          ray.camera->earth_curvature_radius_m()));
}

Status TriangulatePoint(const TriangulationOptions& options,
                        const std::vector<RayObservation>& rays, TriangulationResult* result) {
  *result = TriangulationResult();
  if (rays.size() < 2)
    return Status::Error("needs at least two rays, has " + std::to_string(rays.size()));

  // 1. Linear.
  Eigen::Vector3d X;
  PHOTOPOSE_RETURN_IF_ERROR(IntersectLinearly(options, rays, &X, result));

  // 2. Gauss-Newton on the whitened collinearity residuals.
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  costs.reserve(rays.size());
  double nearest = std::numeric_limits<double>::infinity();
  for (const RayObservation& ray : rays) {
    costs.emplace_back(CreateRayCost(ray));
    nearest = std::min(nearest, (X - ray.eo.center_in_ground()).norm());
  }
  Eigen::Matrix3d normal;
  double ssq = 0.0;
  Eigen::Vector3d gradient;
  bool converged = false;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    if (!LinearizeRays(rays, costs, X, &normal, &gradient, &ssq))
      return Status::Error("the point is behind a camera");
    const Eigen::Vector3d step = -normal.ldlt().solve(gradient);
    if (!step.allFinite()) return Status::Error("the intersection is singular");
    X += step;
    result->iterations = iteration + 1;
    if (step.norm() <= kRelativeStep * nearest) {
      converged = true;
      break;
    }
  }
  if (!converged) return Status::Error("the intersection did not converge");
  if (!LinearizeRays(rays, costs, X, &normal, &gradient, &ssq))
    return Status::Error("the point is behind a camera");
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0))
    return Status::Error("the intersection is singular");
  result->point_m = X;
  result->covariance = ldlt.solve(Eigen::Matrix3d::Identity());
  result->rms_whitened = std::sqrt(ssq / (2.0 * rays.size()));
  return Status::Ok();
}

}  // namespace photopose
