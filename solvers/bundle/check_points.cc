#include "solvers/bundle/check_points.h"

#include <cmath>
#include <vector>

#include "solvers/bundle/internal/bundle_statistics.h"
#include "solvers/bundle/triangulation.h"

namespace photopose {
namespace internal {
namespace {

// Whether data snooping removed the coordinates (the prior) of control point p.
bool PriorRemoved(const BundleAdjustmentResult& result, int p) {
  for (const BundleSnoopingStep& step : result.snooping)
    if (step.group == kControlPoints && step.item == p) return true;
  return false;
}

// The check point's row of the table: its intersection against its surveyed coordinates. False
// (with the reason in table->message) when it cannot be intersected.
bool TabulateCheckPoint(const Block& block, int p, const std::vector<const Vector6d*>& eo,
                        const std::vector<BlockCamera>& cameras,
                        const MarkSigmaDefaults& defaults, double variance_factor,
                        const CheckPointCovariance& covariance, BundlePointResult* table) {
  std::vector<RayObservation> rays;
  std::vector<int> marks;
  for (const int m : block.marks_of_point[p]) {
    const BlockMark& mark = block.marks[m];
    if (eo[mark.image] == nullptr) continue;
    RayObservation ray;
    ray.camera = &cameras[block.images[mark.image].camera];
    ray.eo.parameters = *eo[mark.image];
    ray.observation = mark.observation;
    ray.sigma = MarkSigma(mark, *ray.camera, defaults);
    rays.push_back(ray);
    marks.push_back(m);
  }
  table->num_observations = static_cast<int>(rays.size());
  TriangulationResult intersection;
  const Status status = TriangulatePoint(TriangulationOptions(), rays, &intersection);
  if (!status.ok()) {
    table->message = "not intersected: " + status.message();
    return false;
  }
  table->error_m = intersection.point_m - *block.points[p].surveyed_m;
  table->covariance = covariance ? covariance(rays, marks, intersection) : intersection.covariance;
  table->covariance *= variance_factor;
  table->has_covariance = true;
  return true;
}

}  // namespace

void TabulateControlAndCheckPoints(const Block& block, const std::vector<const Vector6d*>& eo,
                                   const std::vector<BlockCamera>& cameras,
                                   const BundleAccuracies& accuracies, double variance_factor,
                                   const CheckPointCovariance& covariance,
                                   BundleAdjustmentResult* result) {
  const MarkSigmaDefaults defaults = GroupMarkDefaults(accuracies, kControlMarks);
  Eigen::Vector3d control_ssq = Eigen::Vector3d::Zero(), check_ssq = Eigen::Vector3d::Zero();
  result->num_control_points = result->num_check_points = 0;
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    BundlePointResult& table = result->points[p];
    // A control point whose coordinates snooping removed keeps its error in the table but stays
    // out of the RMSE (it is reported as removed).
    if (point.role == PointRole::kControl && table.error_m &&
        !PriorRemoved(*result, static_cast<int>(p))) {
      ++result->num_control_points;
      control_ssq += table.error_m->cwiseAbs2();
    }
    if (point.role != PointRole::kCheck) continue;
    if (!TabulateCheckPoint(block, static_cast<int>(p), eo, cameras, defaults, variance_factor,
                            covariance, &table))
      continue;
    ++result->num_check_points;
    check_ssq += table.error_m->cwiseAbs2();
  }
  result->control_rmse_m = result->check_rmse_m = Eigen::Vector3d::Zero();
  result->control_rmse_total_m = result->check_rmse_total_m = 0.0;
  if (result->num_control_points > 0) {
    result->control_rmse_m = (control_ssq / result->num_control_points).cwiseSqrt();
    result->control_rmse_total_m = std::sqrt(control_ssq.sum() / result->num_control_points);
  }
  if (result->num_check_points > 0) {
    result->check_rmse_m = (check_ssq / result->num_check_points).cwiseSqrt();
    result->check_rmse_total_m = std::sqrt(check_ssq.sum() / result->num_check_points);
  }
}

}  // namespace internal

void TabulateControlAndCheckPoints(const Block& adjusted, const BundleAccuracies& accuracies,
                                   double variance_factor, BundleAdjustmentResult* result) {
  std::vector<const Vector6d*> eo(adjusted.images.size(), nullptr);
  for (size_t i = 0; i < adjusted.images.size(); ++i)
    if (adjusted.images[i].eo) eo[i] = &adjusted.images[i].eo->parameters;
  internal::TabulateControlAndCheckPoints(adjusted, eo, adjusted.cameras, accuracies,
                                          variance_factor, nullptr, result);
}

}  // namespace photopose
