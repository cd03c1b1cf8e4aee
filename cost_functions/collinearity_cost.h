#pragma once
// Ceres cost functions for the collinearity model of core/collinearity.h. Every cost only maps
// pointers and calls the model; the analytic ones use the closed-form partials of the same model.
//
// Residuals are whitened: (observed - projected) / (pixel_size_um * sigma_px), so one unit is one
// standard deviation of the observation and a robust-loss scale of s pixels is s / sigma_px.
//
//  - PoseCost*:     resection. Parameter block: exterior orientation [X0, Y0, Z0, omega, phi, kappa]
//                   (m, rad, seed). The ground point, focal length and the distortion-free ideal
//                   image-plane observation (um) are data.
//  - Collinearity*: bundle adjustment and self-calibration. Parameter blocks: exterior orientation
//                   (6), ground point (3), the camera model's parameters (core/camera_models.h).
//                   The measurement, in the model's observation unit, is data. A kFrame camera with
//                   ApplyECC sees the point lowered by the earth-curvature drop
//                   (LowerByEarthCurvature, core/collinearity.h), in both derivative paths; a camera
//                   without it evaluates exactly the plain model (a separate cost type, no test).
// A point behind the camera makes every cost return false (never a silent zero).

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>

#include "core/camera_models.h"
#include "core/collinearity.h"
#include "cost_functions/camera_model_jacobians.h"
#include "core/types.h"

namespace photopose {

// The one switch for the derivative path, used by the library, the CLI and the comparison tool.
enum class JacobianType { kAnalytic, kAutodiff };

inline constexpr EnumNameEntry<JacobianType> kJacobianTypeNames[] = {
    {JacobianType::kAnalytic, "analytic"}, {JacobianType::kAutodiff, "autodiff"}};
constexpr EnumNameTable<JacobianType> EnumNames(JacobianType) {
  return EnumNameTable<JacobianType>(kJacobianTypeNames);
}

// ------------------------------------------------------------------ resection (pose only)

// The templated residual shared by both pose costs.
struct PoseCostFunctor {
  PoseCostFunctor(const Eigen::Vector2d& observed_um, const Eigen::Vector3d& point_in_ground,
                  double focal_um, double inverse_sigma_um)
      : observed_um(observed_um),
        point_in_ground(point_in_ground),
        focal_um(focal_um),
        inverse_sigma_um(inverse_sigma_um) {}

  template <typename T>
  bool operator()(const T* eo, T* residual) const {
    const T point[3] = {T(point_in_ground[0]), T(point_in_ground[1]), T(point_in_ground[2])};
    T xy[2];
    if (!ProjectToImagePlane(eo, point, T(focal_um), xy)) return false;
    residual[0] = (T(observed_um[0]) - xy[0]) * inverse_sigma_um;
    residual[1] = (T(observed_um[1]) - xy[1]) * inverse_sigma_um;
    return true;
  }

  Eigen::Vector2d observed_um;
  Eigen::Vector3d point_in_ground;
  double focal_um;
  double inverse_sigma_um;  // 1 / (pixel_size_um * sigma_px)
};

// The analytic pose residual of one observation through `projector`, the pose eo (6) made ready
// for projecting (SeedProjector(eo, data.focal_um), core/collinearity.h), and its Jacobian d_eo
// (2 x 6, row-major; may be null): PoseCostAnalytic::Evaluate, callable on the data itself by loops
// that keep the observations by value (the resection's refinement, without one heap CostFunction
// per mark) and make one projector for all marks of a pose. False when the point is on or behind
// the camera plane.
inline bool EvaluatePoseCostAnalytic(const PoseCostFunctor& data, const SeedProjector& projector,
                                     double* residuals, double* d_eo) {
  double xy[2];
  if (!projector.Project(data.point_in_ground.data(), xy, d_eo, nullptr, nullptr)) return false;
  residuals[0] = (data.observed_um[0] - xy[0]) * data.inverse_sigma_um;
  residuals[1] = (data.observed_um[1] - xy[1]) * data.inverse_sigma_um;
  if (d_eo != nullptr) {
    for (int k = 0; k < 2 * kExteriorOrientationSize; ++k) d_eo[k] *= -data.inverse_sigma_um;
  }
  return true;
}

// The same at the pose eo (6), its projector made for this observation alone.
inline bool EvaluatePoseCostAnalytic(const PoseCostFunctor& data, const double* eo,
                                     double* residuals, double* d_eo) {
  return EvaluatePoseCostAnalytic(data, SeedProjector(eo, data.focal_um), residuals, d_eo);
}

class PoseCostAnalytic final : public ceres::SizedCostFunction<kResidualSize, kExteriorOrientationSize> {
 public:
  explicit PoseCostAnalytic(const PoseCostFunctor& data) : data_(data) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    return EvaluatePoseCostAnalytic(data_, parameters[0], residuals,
                                    jacobians != nullptr ? jacobians[0] : nullptr);
  }

 private:
  PoseCostFunctor data_;
};

using PoseCostAutoDiff =
    ceres::AutoDiffCostFunction<PoseCostFunctor, kResidualSize, kExteriorOrientationSize>;

// Creates the pose cost with the requested derivative path (owned by the caller / the problem).
inline ceres::CostFunction* CreatePoseCost(JacobianType type, const PoseCostFunctor& data) {
  if (type == JacobianType::kAutodiff) return new PoseCostAutoDiff(new PoseCostFunctor(data));
  return new PoseCostAnalytic(data);
}

// ------------------------------------------------------------------ bundle (pose, point, camera)

// The templated residual of one measurement for bundle adjustment and self-calibration: the
// seed's collinearity ray (ProjectToNormalized) through a camera model (core/camera_models.h),
// whitened by the measurement's standard deviation in the model's observation unit.
struct CollinearityFunctor {
  CollinearityFunctor(CameraModelType model, const Eigen::Vector2d& observation,
                      const CameraModelData& data, double inverse_sigma,
                      double earth_radius_m = 0.0)
      : observation{observation.x(), observation.y()},
        inverse_sigma(inverse_sigma),
        earth_radius_m(earth_radius_m),
        data(data),
        model(model) {}

  template <typename T>
  bool operator()(const T* eo, const T* point, const T* camera, T* residual) const {
    T ab[2];
    if (earth_radius_m > 0.0) {
      T lowered[3];
      LowerByEarthCurvature(eo, point, earth_radius_m, lowered);
      if (!ProjectToNormalized(eo, lowered, ab)) return false;
    } else if (!ProjectToNormalized(eo, point, ab)) {
      return false;
    }
    CameraModelResidual(model, camera, ab, observation, data, residual);
    residual[0] *= inverse_sigma;
    residual[1] *= inverse_sigma;
    return true;
  }

  // The intersections build one per ray (the bundle's marks use CollinearityMarkFunctor): plain
  // doubles, no 16-byte-aligned Eigen member.
  double observation[2];  // film um (kFrame) or pixels (COLMAP models)
  double inverse_sigma;   // 1 / sigma of the measurement, in the observation unit
  double earth_radius_m;  // kFrame with ApplyECC: the earth-curvature radius (m); 0: none
  CameraModelData data;   // fixed data of the model (points into the camera it came from)
  CameraModelType model;
};
static_assert(sizeof(CollinearityFunctor) <= 72, "one per ray: keep it small");

// The analytic residual and Jacobians of one measurement: the closed-form collinearity partials
// (core/collinearity.h, c = 1) chained with the camera model's derivatives
// (cost_functions/camera_model_jacobians.h), whitened by inverse_sigma. d_eo (2 x 6), d_point
// (2 x 3) and d_camera (2 x kNumParams), row-major, each only when not null. False for a point
// behind the camera. kEarthCurvature: the point lowered by the earth-curvature drop of radius
// earth_radius_m (m; ProjectWithJacobiansEarthCurvature), else earth_radius_m is unused.
template <int kNumParams, bool kEarthCurvature = false>
bool EvaluateCollinearityAnalytic(CameraModelType model, const CameraModelData& data,
                                  const double* observation, double inverse_sigma,
                                  const double* eo, const double* point, const double* camera,
                                  double* residuals, double* d_eo, double* d_point,
                                  double* d_camera, double earth_radius_m = 0.0) {
  double ab[2];
  double ab_eo[2 * kExteriorOrientationSize], ab_point[2 * kPointSize];
  bool in_front;
  if constexpr (kEarthCurvature) {
    in_front = ProjectWithJacobiansEarthCurvature(eo, point, 1.0, earth_radius_m, ab,
                                                  d_eo ? ab_eo : nullptr,
                                                  d_point ? ab_point : nullptr, nullptr);
  } else {
    in_front = ProjectWithJacobians(eo, point, 1.0, ab, d_eo ? ab_eo : nullptr,
                                    d_point ? ab_point : nullptr, nullptr);
  }
  if (!in_front) return false;
  const double s = inverse_sigma;
  const bool derivatives = d_eo != nullptr || d_point != nullptr || d_camera != nullptr;
  double r_ab[4];
  if (!derivatives) {
    // The residual alone needs no derivatives.
    CameraModelResidual(model, camera, ab, observation, data, residuals);
  } else {
    EvaluateCameraModel<kNumParams>(model, camera, ab, observation, data, residuals, r_ab,
                                    d_camera);
  }
  residuals[0] *= s;
  residuals[1] *= s;
  if (d_eo != nullptr) {
    for (int k = 0; k < kExteriorOrientationSize; ++k) {
      const double x = ab_eo[k], y = ab_eo[kExteriorOrientationSize + k];
      d_eo[k] = s * (r_ab[0] * x + r_ab[1] * y);
      d_eo[kExteriorOrientationSize + k] = s * (r_ab[2] * x + r_ab[3] * y);
    }
  }
  if (d_point != nullptr) {
    for (int k = 0; k < kPointSize; ++k) {
      const double x = ab_point[k], y = ab_point[kPointSize + k];
      d_point[k] = s * (r_ab[0] * x + r_ab[1] * y);
      d_point[kPointSize + k] = s * (r_ab[2] * x + r_ab[3] * y);
    }
  }
  if (d_camera != nullptr)
    for (int k = 0; k < 2 * kNumParams; ++k) d_camera[k] *= s;
  return true;
}

// The analytic path of CollinearityFunctor.
template <int kNumParams>
class CollinearityCostAnalytic final
    : public ceres::SizedCostFunction<kResidualSize, kExteriorOrientationSize, kPointSize,
                                      kNumParams> {
 public:
  explicit CollinearityCostAnalytic(const CollinearityFunctor& data) : data_(data) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    double* d_eo = jacobians ? jacobians[0] : nullptr;
    double* d_point = jacobians ? jacobians[1] : nullptr;
    double* d_camera = jacobians ? jacobians[2] : nullptr;
    if (data_.earth_radius_m > 0.0) {
      return EvaluateCollinearityAnalytic<kNumParams, true>(
          data_.model, data_.data, data_.observation, data_.inverse_sigma, parameters[0],
          parameters[1], parameters[2], residuals, d_eo, d_point, d_camera, data_.earth_radius_m);
    }
    return EvaluateCollinearityAnalytic<kNumParams>(
        data_.model, data_.data, data_.observation, data_.inverse_sigma, parameters[0],
        parameters[1], parameters[2], residuals, d_eo, d_point, d_camera);
  }

 private:
  CollinearityFunctor data_;
};

// ------------------------------------------------------------------ bundle marks, compact

// What the marks of one camera share in a bundle adjustment: the model, its fixed data and, when
// the camera's parameters are held constant, those parameters (then not a parameter block of the
// marks' residuals: two parameter blocks per mark instead of three). Outlives the marks' costs.
struct CollinearityCamera {
  CameraModelType model = CameraModelType::kFrame;
  CameraModelData data;
  const double* constant_params = nullptr;  // null: the parameters are the third parameter block
  // kFrame with ApplyECC (BlockCamera::earth_curvature_radius_m): the radius of the earth-curvature
  // correction (m); its marks get the cost type with the correction. 0: none, the plain cost.
  double earth_radius_m = 0.0;
};

// The templated residual of one mark of a bundle adjustment: CollinearityFunctor's, with what the
// marks of a camera share held once (CollinearityCamera). The adjustment switches a rejected mark
// off by setting inverse_sigma to 0 in the cost it built (CreateCollinearityMarkCost hands out the
// functor inside), without building the problem again. 32 bytes: a 1000-image block holds 1.7
// million of them. The weight is held here, not in a table beside: Ceres evaluates the marks
// point by point, and a table in mark order cost a cache miss per evaluation (+30 % evaluation
// time on the 1000-image block).
struct CollinearityMarkFunctor {
  CollinearityMarkFunctor(const CollinearityCamera* camera, const Eigen::Vector2d& observation,
                          double inverse_sigma)
      : camera(camera), observation{observation.x(), observation.y()}, inverse_sigma(inverse_sigma) {}

  // Parameter blocks: exterior orientation, ground point (camera->constant_params set).
  template <typename T>
  bool operator()(const T* eo, const T* point, T* residual) const {
    const int n = CameraModelNumParams(camera->model);
    T params[kMaxCameraModelParams];
    for (int k = 0; k < n; ++k) params[k] = T(camera->constant_params[k]);
    return (*this)(eo, point, params, residual);
  }
  // Parameter blocks: exterior orientation, ground point, camera parameters.
  template <typename T>
  bool operator()(const T* eo, const T* point, const T* params, T* residual) const {
    T ab[2];
    if (!ProjectToNormalized(eo, point, ab)) return false;
    CameraModelResidual(camera->model, params, ab, observation, camera->data, residual);
    residual[0] *= inverse_sigma;
    residual[1] *= inverse_sigma;
    return true;
  }

  const CollinearityCamera* camera;
  double observation[2];       // film um (kFrame) or pixels (COLMAP models)
  double inverse_sigma;        // 1 / sigma of the mark in the observation unit; 0: switched off
};
static_assert(sizeof(CollinearityMarkFunctor) <= 32, "one per mark: keep it small");

// The autodiff functor of a mark whose camera applies the earth-curvature correction: the point
// lowered (LowerByEarthCurvature, radius camera->earth_radius_m), then CollinearityMarkFunctor. A
// type of its own so that the marks of other cameras carry no test.
struct EarthCurvatureMarkFunctor {
  explicit EarthCurvatureMarkFunctor(const CollinearityMarkFunctor& mark) : mark(mark) {}
  template <typename T>
  bool operator()(const T* eo, const T* point, T* residual) const {
    T lowered[3];
    LowerByEarthCurvature(eo, point, mark.camera->earth_radius_m, lowered);
    return mark(eo, lowered, residual);
  }
  template <typename T>
  bool operator()(const T* eo, const T* point, const T* params, T* residual) const {
    T lowered[3];
    LowerByEarthCurvature(eo, point, mark.camera->earth_radius_m, lowered);
    return mark(eo, lowered, params, residual);
  }
  CollinearityMarkFunctor mark;
};

// The analytic path of CollinearityMarkFunctor; kCameraBlock: the camera parameters are the third
// parameter block (self-calibration), else CollinearityCamera::constant_params; kEarthCurvature:
// with the earth-curvature correction of CollinearityCamera::earth_radius_m.
template <int kNumParams, bool kCameraBlock, bool kEarthCurvature = false>
class CollinearityMarkCostAnalytic final
    : public std::conditional_t<
          kCameraBlock,
          ceres::SizedCostFunction<kResidualSize, kExteriorOrientationSize, kPointSize, kNumParams>,
          ceres::SizedCostFunction<kResidualSize, kExteriorOrientationSize, kPointSize>> {
 public:
  explicit CollinearityMarkCostAnalytic(const CollinearityMarkFunctor& mark) : mark_(mark) {}
  CollinearityMarkFunctor* mutable_mark() { return &mark_; }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const CollinearityCamera& camera = *mark_.camera;
    const double* params = camera.constant_params;
    double* d_camera = nullptr;
    if constexpr (kCameraBlock) {
      params = parameters[2];
      d_camera = jacobians != nullptr ? jacobians[2] : nullptr;
    }
    return EvaluateCollinearityAnalytic<kNumParams, kEarthCurvature>(
        camera.model, camera.data, mark_.observation, mark_.inverse_sigma, parameters[0],
        parameters[1], params, residuals, jacobians != nullptr ? jacobians[0] : nullptr,
        jacobians != nullptr ? jacobians[1] : nullptr, d_camera,
        kEarthCurvature ? camera.earth_radius_m : 0.0);
  }

 private:
  CollinearityMarkFunctor mark_;
};

// Creates the collinearity cost of a measurement with the requested derivative path (owned by the
// caller or the problem). Parameter blocks: exterior orientation (6), ground point (3), camera
// parameters (CameraModelNumParams(data.model)).
ceres::CostFunction* CreateCollinearityCost(JacobianType type, const CollinearityFunctor& data);

// Creates the cost of one mark of a bundle adjustment (owned by the caller) with the requested
// derivative path. Parameter blocks: exterior orientation (6), ground point (3) and, when
// mark.camera->constant_params is null, the camera parameters (CameraModelNumParams). *inside, when
// not null, is the functor the cost evaluates (its inverse_sigma may be changed; it lives as long
// as the cost). A camera with earth_radius_m > 0 (kFrame only) gets the cost with the
// earth-curvature correction.
ceres::CostFunction* CreateCollinearityMarkCost(JacobianType type,
                                                const CollinearityMarkFunctor& mark,
                                                CollinearityMarkFunctor** inside = nullptr);

// ------------------------------------------------------------------ inline definitions

namespace internal {
template <int kNumParams>
ceres::CostFunction* MakeCollinearityCost(JacobianType type, const CollinearityFunctor& data) {
  if (type == JacobianType::kAutodiff) {
    return new ceres::AutoDiffCostFunction<CollinearityFunctor, kResidualSize,
                                           kExteriorOrientationSize, kPointSize, kNumParams>(
        new CollinearityFunctor(data));
  }
  return new CollinearityCostAnalytic<kNumParams>(data);
}

// Calls make(std::integral_constant<int, n>()) with n = CameraModelNumParams(model): the fixed
// parameter-block size of the cost templates.
template <typename Make>
ceres::CostFunction* WithNumCameraParams(CameraModelType model, Make&& make) {
  switch (CameraModelNumParams(model)) {
    case 3:
      return make(std::integral_constant<int, 3>());
    case 4:
      return make(std::integral_constant<int, 4>());
    case 5:
      return make(std::integral_constant<int, 5>());
    case 8:
      return make(std::integral_constant<int, 8>());
    case 12:
      return make(std::integral_constant<int, 12>());
    default:
      return make(std::integral_constant<int, kFrameNumParams>());
  }
}
}  // namespace internal

inline ceres::CostFunction* CreateCollinearityCost(JacobianType type,
                                                   const CollinearityFunctor& data) {
  return internal::WithNumCameraParams(data.model, [&](auto n) {
    return internal::MakeCollinearityCost<decltype(n)::value>(type, data);
  });
}

namespace internal {
// The functor a mark cost evaluates (its inverse_sigma switches the mark off).
inline CollinearityMarkFunctor* MarkOf(CollinearityMarkFunctor* functor) { return functor; }
inline CollinearityMarkFunctor* MarkOf(EarthCurvatureMarkFunctor* functor) { return &functor->mark; }

// The mark cost of one camera-parameter count, with (kEarthCurvature) or without the correction.
template <int kNumParams, bool kEarthCurvature>
ceres::CostFunction* MakeMarkCost(JacobianType type, const CollinearityMarkFunctor& mark,
                                  CollinearityMarkFunctor** inside) {
  using Functor =
      std::conditional_t<kEarthCurvature, EarthCurvatureMarkFunctor, CollinearityMarkFunctor>;
  const bool camera_block = mark.camera->constant_params == nullptr;
  if (type == JacobianType::kAutodiff) {
    // The cost owns the functor and evaluates that very object.
    Functor* functor = new Functor(mark);
    *inside = MarkOf(functor);
    if (camera_block) {
      return new ceres::AutoDiffCostFunction<Functor, kResidualSize, kExteriorOrientationSize,
                                             kPointSize, kNumParams>(functor);
    }
    return new ceres::AutoDiffCostFunction<Functor, kResidualSize, kExteriorOrientationSize,
                                           kPointSize>(functor);
  }
  if (camera_block) {
    auto* cost = new CollinearityMarkCostAnalytic<kNumParams, true, kEarthCurvature>(mark);
    *inside = cost->mutable_mark();
    return cost;
  }
  auto* cost = new CollinearityMarkCostAnalytic<kNumParams, false, kEarthCurvature>(mark);
  *inside = cost->mutable_mark();
  return cost;
}

// The earth-curvature costs exist for the frame model's parameter count alone (kFrame is the
// only model with a camera table, hence with ApplyECC).
template <int kNumParams>
ceres::CostFunction* MakeCollinearityMarkCost(JacobianType type,
                                              const CollinearityMarkFunctor& mark,
                                              CollinearityMarkFunctor** inside) {
  if constexpr (kNumParams == kFrameNumParams) {
    if (mark.camera->earth_radius_m > 0.0)
      return MakeMarkCost<kNumParams, true>(type, mark, inside);
  }
  return MakeMarkCost<kNumParams, false>(type, mark, inside);
}
}  // namespace internal

inline ceres::CostFunction* CreateCollinearityMarkCost(JacobianType type,
                                                       const CollinearityMarkFunctor& mark,
                                                       CollinearityMarkFunctor** inside) {
  CollinearityMarkFunctor* functor = nullptr;
  ceres::CostFunction* cost = internal::WithNumCameraParams(mark.camera->model, [&](auto n) {
    return internal::MakeCollinearityMarkCost<decltype(n)::value>(type, mark, &functor);
  });
  if (inside != nullptr) *inside = functor;
  return cost;
}

}  // namespace photopose
