#include "solvers/bundle/check_points.h"

#include <cmath>
#include <vector>

#include "solvers/bundle/triangulation.h"

namespace photopose {

double DefaultFilmMarkSigmaUm(const BlockCamera& camera, double sigma_px, double sigma_film_um) {
  if (camera.model == CameraModelType::kFrame && camera.table.pixel_size_um > 0.0)
    return sigma_px * camera.table.pixel_size_um;
  return sigma_film_um;
}

void TabulateControlAndCheckPoints(const Block& adjusted, const BundleAccuracies& accuracies,
                                   double variance_factor, BundleAdjustmentResult* result) {
  const double sigma_px = accuracies.marker_projection_px;
  Eigen::Vector3d control_ssq = Eigen::Vector3d::Zero(), check_ssq = Eigen::Vector3d::Zero();
  result->num_control_points = result->num_check_points = 0;
  for (size_t p = 0; p < adjusted.points.size(); ++p) {
    const BlockPoint& point = adjusted.points[p];
    BundlePointResult& table = result->points[p];
    if (point.role == PointRole::kControl && table.error_m) {
      ++result->num_control_points;
      control_ssq += table.error_m->cwiseAbs2();
    }
    if (point.role != PointRole::kCheck) continue;
    std::vector<RayObservation> rays;
    for (const int m : adjusted.marks_of_point[p]) {
      const BlockMark& mark = adjusted.marks[m];
      const BlockImage& image = adjusted.images[mark.image];
      if (!image.eo) continue;
      RayObservation ray;
      ray.camera = &adjusted.cameras[image.camera];
      ray.eo = *image.eo;
      ray.observation = mark.observation;
      ray.sigma = MarkSigma(
          mark, sigma_px,
          DefaultFilmMarkSigmaUm(*ray.camera, sigma_px, accuracies.marker_projection_film_um));
      rays.push_back(ray);
    }
    table.num_observations = static_cast<int>(rays.size());
    TriangulationResult intersection;
    const Status status = TriangulatePoint(TriangulationOptions(), rays, &intersection);
    if (!status.ok()) {
      table.message = "not intersected: " + status.message();
      continue;
    }
    table.error_m = intersection.point_m - *point.surveyed_m;
    table.covariance = variance_factor * intersection.covariance;
    table.has_covariance = true;
    ++result->num_check_points;
    check_ssq += table.error_m->cwiseAbs2();
  }
  if (result->num_control_points > 0) {
    result->control_rmse_m = (control_ssq / result->num_control_points).cwiseSqrt();
    result->control_rmse_total_m = std::sqrt(control_ssq.sum() / result->num_control_points);
  }
  if (result->num_check_points > 0) {
    result->check_rmse_m = (check_ssq / result->num_check_points).cwiseSqrt();
    result->check_rmse_total_m = std::sqrt(check_ssq.sum() / result->num_check_points);
  }
}

}  // namespace photopose
