#include "solvers/bundle/check_points.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "core/statistics.h"
#include "cost_functions/collinearity_cost.h"
#include "solvers/bundle/internal/bundle_statistics.h"
#include "solvers/bundle/triangulation.h"

namespace photopose {
namespace internal {
namespace {

// Coordinates with a smaller redundancy number (unitless) are not tested: a blunder there does not
// show in the residuals (the bundle's diagnostics leave w undefined below the same 1e-6).
constexpr double kMinTestedRedundancy = 1e-6;

// Whether data snooping removed the coordinates (the prior) of control point p.
bool PriorRemoved(const BundleAdjustmentResult& result, int p) {
  for (const BundleSnoopingStep& step : result.snooping)
    if (step.group == kControlPoints && step.item == p) return true;
  return false;
}

// The whitened residuals of the rays at `point_m` (2 per ray: observed - computed over the ray's
// sigma, unitless) and their redundancy numbers r = 1 - diag(A (A^T A)^-1 A^T), A the whitened
// Jacobian by the point (the images and cameras held fixed, as in the intersection). False when a
// ray cannot be evaluated or A^T A is singular.
bool IntersectionResiduals(const std::vector<RayObservation>& rays, const Eigen::Vector3d& point_m,
                           Eigen::VectorXd* whitened, Eigen::VectorXd* redundancy) {
  const Eigen::Index rows = 2 * static_cast<Eigen::Index>(rays.size());
  Eigen::MatrixXd A(rows, 3);
  whitened->resize(rows);
  for (size_t i = 0; i < rays.size(); ++i) {
    const RayObservation& ray = rays[i];
    const std::unique_ptr<ceres::CostFunction> cost(CreateRayCost(ray));
    const double* parameters[] = {ray.eo.data(), point_m.data(), ray.camera->params.data()};
    double residual[2];
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J;
    double* jacobians[] = {nullptr, J.data(), nullptr};
    if (!cost->Evaluate(parameters, residual, jacobians)) return false;
    A.middleRows<2>(2 * i) = J;
    (*whitened)(2 * i) = residual[0];
    (*whitened)(2 * i + 1) = residual[1];
  }
  const Eigen::LDLT<Eigen::Matrix3d> normal(A.transpose() * A);
  if (normal.info() != Eigen::Success || !(normal.vectorD().minCoeff() > 0.0)) return false;
  const Eigen::MatrixXd NinvAt = normal.solve(A.transpose());
  *redundancy = Eigen::VectorXd::Ones(rows) - (A.cwiseProduct(NinvAt.transpose())).rowwise().sum();
  return true;
}

// The factor (unitless) by which the adjustment's variance components rescaled the control marks'
// sigmas (1 without them): the control-marks group's mean sigma in use (its stated accuracy in
// the statistics) over the mean of the same marks' sigmas by `defaults`. Check marks are measured
// as control marks are, so they are weighed and tested with the same yardstick; 1 when the group
// is missing, mixes pixel and film marks (its unit is "sigma") or the marks cannot be matched.
double ControlMarkScale(const Block& block, const std::vector<BlockCamera>& cameras,
                        const MarkSigmaDefaults& defaults, const BundleAdjustmentResult& result) {
  const BundleGroupStatistics* group = nullptr;
  for (const BundleGroupStatistics& g : result.groups)
    if (g.group == kControlMarks && g.count > 0) group = &g;
  if (group == nullptr || group->unit == "sigma" || result.mark_residuals.size() != block.marks.size())
    return 1.0;
  double sum = 0.0;
  int count = 0;
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    if (block.points[mark.point].role != PointRole::kControl ||
        !result.mark_residuals[m].allFinite())
      continue;
    sum += MarkSigma(mark, cameras[block.images[mark.image].camera], defaults) /
           mark.observation_units_per_unit;
    ++count;
  }
  const double scale = count == group->count && sum > 0.0 ? group->stated_accuracy.x() * count / sum : 1.0;
  return std::isfinite(scale) && scale > 0.0 ? scale : 1.0;
}

}  // namespace

// The check point's row of the table: its intersection against its surveyed coordinates, after
// the w-test of its marks (their sigmas `sigma_scale` times the rule's). While the largest
// |w| = |v| / (s sigma sqrt(r)) of a mark's coordinate (s = max(1, sqrt(variance_factor)), the
// rule of the block's observations) exceeds `critical`,
// that mark is rejected (appended to `rejected`) and the point intersected again from the rest.
// False (with the reason in table->message) when it cannot be intersected.
bool TabulateCheckPoint(const Block& block, int p, const std::vector<const Vector6d*>& eo,
                        const std::vector<BlockCamera>& cameras,
                        const MarkSigmaDefaults& defaults, double sigma_scale,
                        double variance_factor, double critical,
                        const CheckPointCovariance& covariance, BundlePointResult* table,
                        std::vector<BundleRejectedCheckMark>* rejected) {
  std::vector<RayObservation> rays;
  std::vector<int> marks;
  for (const int m : block.marks_of_point[p]) {
    const BlockMark& mark = block.marks[m];
    if (eo[mark.image] == nullptr) continue;
    RayObservation ray;
    ray.camera = &cameras[block.images[mark.image].camera];
    ray.eo.parameters = *eo[mark.image];
    ray.observation = mark.observation;
    ray.sigma = sigma_scale * MarkSigma(mark, *ray.camera, defaults);
    rays.push_back(ray);
    marks.push_back(m);
  }
  const double scale = std::max(1.0, std::sqrt(variance_factor));
  int num_rejected = 0;
  TriangulationResult intersection;
  while (true) {
    table->num_observations = static_cast<int>(rays.size());
    const Status status = TriangulatePoint(TriangulationOptions(), rays, &intersection);
    if (!status.ok()) {
      table->message = num_rejected == 0 ? "not intersected: " + status.message()
                                         : "not intersected after the w-test rejected " +
                                               std::to_string(num_rejected) + " of its marks: " +
                                               status.message();
      return false;
    }
    Eigen::VectorXd whitened, redundancy;
    if (!IntersectionResiduals(rays, intersection.point_m, &whitened, &redundancy)) break;
    int worst = -1;
    double worst_w = critical;
    for (Eigen::Index k = 0; k < whitened.size(); ++k) {
      if (!(redundancy(k) > kMinTestedRedundancy)) continue;
      const double w = std::abs(whitened(k)) / (scale * std::sqrt(redundancy(k)));
      if (w > worst_w) worst_w = w, worst = static_cast<int>(k / 2);
    }
    if (worst < 0) break;
    BundleRejectedCheckMark mark;
    mark.mark = marks[worst];
    mark.normalized = worst_w;
    // The ray's sigma is in the camera model's observation unit; the report's, the mark's own.
    mark.residual = whitened.segment<2>(2 * worst) * rays[worst].sigma /
                    block.marks[marks[worst]].observation_units_per_unit;
    rejected->push_back(mark);
    ++num_rejected;
    rays.erase(rays.begin() + worst);
    marks.erase(marks.begin() + worst);
  }
  table->error_m = intersection.point_m - *block.points[p].surveyed_m;
  table->covariance = covariance ? covariance(rays, marks, intersection) : intersection.covariance;
  table->covariance *= variance_factor;
  table->has_covariance = true;
  table->covariance_complete = static_cast<bool>(covariance);
  return true;
}

void TabulateControlAndCheckPoints(const Block& block, const std::vector<const Vector6d*>& eo,
                                   const std::vector<BlockCamera>& cameras,
                                   const BundleAccuracies& accuracies, double variance_factor,
                                   const CheckPointCovariance& covariance,
                                   BundleAdjustmentResult* result) {
  const MarkSigmaDefaults defaults = GroupMarkDefaults(accuracies, kControlMarks);
  // The w-test's critical value: the block's (its family-wise level over all its observations)
  // when its diagnostics set one, else the default level over the check marks' coordinates.
  double critical = result->critical_value;
  if (!(critical > 0.0)) {
    int num_check_coordinates = 0;
    for (size_t p = 0; p < block.points.size(); ++p)
      if (block.points[p].role == PointRole::kCheck)
        num_check_coordinates += 2 * static_cast<int>(block.marks_of_point[p].size());
    critical = NormalQuantile(1.0 - 0.5 * BundleStatisticsOptions().snooping_alpha /
                                        std::max(1, num_check_coordinates));
  }
  // The control marks' sigmas in use, variance components applied: the check marks' too.
  const double sigma_scale = ControlMarkScale(block, cameras, defaults, *result);
  result->rejected_check_marks.clear();
  Eigen::Vector3d control_ssq = Eigen::Vector3d::Zero(), check_ssq = Eigen::Vector3d::Zero();
  result->num_control_points = result->num_check_points = 0;
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    BundlePointResult& table = result->points[p];
    // A control point whose coordinates snooping removed keeps its error in the table but stays
    // out of the RMSE (it is reported as removed); so does one held fixed (its error is 0).
    if (point.role == PointRole::kControl && table.error_m && !IsHeldFixed(point) &&
        !PriorRemoved(*result, static_cast<int>(p))) {
      ++result->num_control_points;
      control_ssq += table.error_m->cwiseAbs2();
    }
    if (point.role != PointRole::kCheck) continue;
    if (!TabulateCheckPoint(block, static_cast<int>(p), eo, cameras, defaults, sigma_scale,
                            variance_factor, critical, covariance, &table,
                            &result->rejected_check_marks))
      continue;
    ++result->num_check_points;
    check_ssq += table.error_m->cwiseAbs2();
  }
  // Without a point there is no RMSE (NaN: null in the JSON report), not a zero error.
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  result->control_rmse_m = result->check_rmse_m = Eigen::Vector3d::Constant(kNaN);
  result->control_rmse_total_m = result->check_rmse_total_m = kNaN;
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

Eigen::Matrix3d SurveyedPointErrorCovariance(const BlockPoint& point,
                                             const Eigen::Matrix3d& estimate_covariance_m2,
                                             double default_marker_m) {
  const Eigen::Vector3d surveyed_sigma_m =
      point.accuracy_m.value_or(Eigen::Vector3d::Constant(default_marker_m));
  Eigen::Matrix3d covariance = estimate_covariance_m2;
  covariance.diagonal() += surveyed_sigma_m.cwiseAbs2();
  return covariance;
}

}  // namespace photopose
