#include "solvers/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>
#include <thread>

#include "core/collinearity.h"
#include "core/rotation.h"
#include "cost_functions/exterior_orientation_manifold.h"
#include "cost_functions/priors.h"
#include "solvers/triangulation.h"

namespace photopose {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// An image needs at least this many marks for its six unknowns.
constexpr int kMinMarksPerImage = 3;
// The seven datum parameters are fixed when the smallest singular value of the (scaled) datum
// Jacobian is above this fraction of the largest: below it one similarity motion is all but free
// (control points 1 mm off a line 1 km long, say), and the adjustment would rest on noise.
constexpr double kDatumConditioning = 1e-3;

enum Group : int {
  kTieMarks = 0,
  kControlMarks,
  kControlPoints,
  kCameraPositions,
  kAttitudes,
  kNumGroups
};
const char* const kGroupNames[kNumGroups] = {"tie_marks", "control_marks", "control_points",
                                             "camera_positions", "attitudes"};

// One residual block of the problem: which group, which item (mark, point or image) and how many
// of its rows are observations (the zero row of a control point's Z prior is not).
struct ResidualInfo {
  Group group;
  int item;
  int rows;
  int first_axis;  // the axis of the block's first row (priors: 0 for X/omega, 2 for Z)
  ceres::ResidualBlockId id;
  std::vector<double*> parameters;
};

// The values being adjusted, copied from the block so that a failure leaves it untouched.
struct State {
  std::vector<Vector6d> eo;
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<double>> cameras;
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();
};

// Everything decided before the first round.
struct Plan {
  std::vector<char> mark_used;        // per mark: in the adjustment
  std::vector<double> mark_sigma;     // per mark: sigma in the observation unit
  std::vector<Group> mark_group;      // per mark: tie or control
  std::vector<char> point_in_problem; // per point
  std::vector<char> image_prior;      // per image: camera-position prior active
  std::vector<Eigen::Vector3d> image_prior_sigma;
  std::vector<char> image_attitude;   // per image: attitude prior active
  std::vector<Eigen::Vector3d> image_attitude_sigma;
  std::vector<Eigen::Vector3d> point_sigma;  // per control point (m)
  std::vector<std::vector<int>> calibrated;  // per camera, from the config
  BundleDatum datum = BundleDatum::kControl;
  std::string datum_description;
  int relative_fixed_image = -1;      // kRelative: the image held fixed
  int relative_scale_image = -1;      // and the image whose one coordinate fixes the scale
  int relative_scale_axis = -1;
  bool use_lever = false;
};

// Union-find over images.
int Root(std::vector<int>* parent, int i) {
  while ((*parent)[i] != i) {
    (*parent)[i] = (*parent)[(*parent)[i]];
    i = (*parent)[i];
  }
  return i;
}

std::string Names(const std::vector<std::string>& names, size_t max_listed = 5) {
  std::string text;
  for (size_t i = 0; i < names.size() && i < max_listed; ++i)
    text += (i ? ", " : "") + std::string("'") + names[i] + "'";
  if (names.size() > max_listed) text += ", ... (" + std::to_string(names.size()) + " in all)";
  return text;
}

// The default sigma of a film mark of this camera: the pixel default through the pixel size when
// the camera has one, the film default otherwise (um).
double FilmDefaultUm(const BlockCamera& camera, double default_px, double default_film_um) {
  if (camera.model == CameraModelType::kFrame && camera.table.pixel_size_um > 0.0)
    return default_px * camera.table.pixel_size_um;
  return default_film_um;
}

// Rows of the datum Jacobian of one fixed position p: d p / d(t, rotation, scale) = [I, -[p-c]x,
// (p-c)], columns scaled so that the three kinds are comparable (extent = RMS spread).
void AddDatumRows(const Eigen::Vector3d& p, const Eigen::Vector3d& centroid, double extent,
                  std::vector<Eigen::Matrix<double, 3, 7>>* rows) {
  const Eigen::Vector3d d = (p - centroid) / extent;
  Eigen::Matrix<double, 3, 7> J = Eigen::Matrix<double, 3, 7>::Zero();
  J.leftCols<3>().setIdentity();
  J(0, 4) = d.z();
  J(0, 5) = -d.y();
  J(1, 3) = -d.z();
  J(1, 5) = d.x();
  J(2, 3) = d.y();
  J(2, 4) = -d.x();
  J.col(6) = d;
  rows->push_back(J);
}

Status MakePlan(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                const Block& block, Plan* plan) {
  const BundleAccuracies& acc = options.accuracies;
  const size_t num_marks = block.marks.size();
  plan->mark_used.assign(num_marks, 0);
  plan->mark_sigma.assign(num_marks, 1.0);
  plan->mark_group.assign(num_marks, kTieMarks);
  plan->point_in_problem.assign(block.points.size(), 0);
  plan->point_sigma.assign(block.points.size(), Eigen::Vector3d::Constant(acc.marker_m));

  // Calibration config.
  plan->calibrated.assign(block.cameras.size(), {});
  if (config.calibrated_params.size() > block.cameras.size())
    return Status::Error("the calibration config names more cameras than the block has");
  for (size_t c = 0; c < config.calibrated_params.size(); ++c) {
    const int n = CameraModelNumParams(block.cameras[c].model);
    std::vector<int> indices = config.calibrated_params[c];
    std::sort(indices.begin(), indices.end());
    indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
    for (const int index : indices)
      if (index < 0 || index >= n)
        return Status::Error("camera '" + block.cameras[c].camera_id +
                             "': parameter index " + std::to_string(index) + " out of range");
    plan->calibrated[c] = indices;
  }

  // Marks in the adjustment: of control and tie points, of images with an orientation.
  std::vector<std::string> missing_eo, missing_position;
  for (size_t i = 0; i < block.images.size(); ++i)
    if (!block.images[i].eo) missing_eo.push_back(block.images[i].name);
  if (!missing_eo.empty()) {
    return Status::Error("images without initial exterior orientation: " + Names(missing_eo) +
                         " (give a frames table or let the initialisation orient them)");
  }
  for (size_t m = 0; m < num_marks; ++m) {
    const BlockMark& mark = block.marks[m];
    const BlockPoint& point = block.points[mark.point];
    if (point.role == PointRole::kCheck) continue;
    const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
    const bool control = point.role == PointRole::kControl;
    const double px = control ? acc.marker_projection_px : acc.tie_px;
    const double film = FilmDefaultUm(camera, px,
                                      control ? acc.marker_projection_film_um : acc.tie_film_um);
    plan->mark_sigma[m] = MarkSigma(mark, px, film);
    plan->mark_group[m] = control ? kControlMarks : kTieMarks;
    plan->mark_used[m] = 1;
  }
  // Tie points need a start and two rays; a tie point with one ray adds nothing.
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role == PointRole::kCheck) continue;
    int rays = 0;
    for (const int m : block.marks_of_point[p]) rays += plan->mark_used[m];
    if (point.role == PointRole::kTie && rays < 2) {
      for (const int m : block.marks_of_point[p]) plan->mark_used[m] = 0;
      continue;
    }
    if (rays == 0) continue;
    if (point.role == PointRole::kTie && !point.position_m) missing_position.push_back(point.id);
    plan->point_in_problem[p] = 1;
    if (point.role == PointRole::kControl && point.accuracy_m) plan->point_sigma[p] = *point.accuracy_m;
  }
  if (!missing_position.empty()) {
    return Status::Error("tie points without initial coordinates: " + Names(missing_position) +
                         " (let the initialisation triangulate them)");
  }
  for (size_t i = 0; i < block.images.size(); ++i) {
    int count = 0;
    for (const int m : block.marks_of_image[i]) count += plan->mark_used[m];
    if (count < kMinMarksPerImage) {
      return Status::Error("image '" + block.images[i].name + "' has " + std::to_string(count) +
                           " usable marks; an image needs at least " +
                           std::to_string(kMinMarksPerImage) +
                           " (marks of control points and of tie points seen in two images)");
    }
  }

  // Priors of the images.
  plan->image_prior.assign(block.images.size(), 0);
  plan->image_prior_sigma.assign(block.images.size(), acc.camera_m);
  plan->image_attitude.assign(block.images.size(), 0);
  plan->image_attitude_sigma.assign(block.images.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    if (config.constant_images.count(static_cast<int>(i))) continue;
    if (image.measured_center_m && (image.center_accuracy_m || acc.camera_positions_are_priors)) {
      plan->image_prior[i] = 1;
      if (image.center_accuracy_m) plan->image_prior_sigma[i] = *image.center_accuracy_m;
    }
    if (image.measured_angles_rad && (image.attitude_accuracy_rad || acc.attitude_deg)) {
      plan->image_attitude[i] = 1;
      plan->image_attitude_sigma[i] =
          image.attitude_accuracy_rad
              ? *image.attitude_accuracy_rad
              : Eigen::Vector3d::Constant(DegreesToRadians(*acc.attitude_deg));
    }
  }
  plan->use_lever = options.lever_arm_m.has_value() || options.estimate_lever_arm;

  // Connectivity: images joined by the points they share.
  std::vector<int> parent(block.images.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan->point_in_problem[p]) continue;
    int first = -1;
    for (const int m : block.marks_of_point[p]) {
      if (!plan->mark_used[m]) continue;
      const int image = block.marks[m].image;
      if (first < 0) {
        first = image;
      } else {
        parent[Root(&parent, image)] = Root(&parent, first);
      }
    }
  }
  std::map<int, std::vector<std::string>> components;
  for (size_t i = 0; i < block.images.size(); ++i)
    components[Root(&parent, static_cast<int>(i))].push_back(block.images[i].name);
  if (components.size() > 1) {
    std::string parts;
    int k = 0;
    for (const auto& [root, names] : components) {
      if (k++ == 3) {
        parts += "; ...";
        break;
      }
      parts += (k > 1 ? "; " : "") + std::to_string(names.size()) + " image" +
               (names.size() == 1 ? "" : "s") + " (" + Names(names, 3) + ")";
    }
    return Status::Error("the block falls apart into " + std::to_string(components.size()) +
                         " parts that share no point: " + parts);
  }

  // Datum: what fixes the seven similarity parameters of the block.
  std::vector<Eigen::Vector3d> fixed_positions;
  int num_control = 0, num_cameras = 0, num_attitudes = 0;
  bool fixed_rotation = false;
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan->point_in_problem[p]) continue;
    if (block.points[p].role == PointRole::kControl || config.constant_points.count(static_cast<int>(p))) {
      fixed_positions.push_back(block.points[p].role == PointRole::kTie
                                    ? *block.points[p].position_m
                                    : *block.points[p].surveyed_m);
      ++num_control;
    }
  }
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (plan->image_prior[i] || config.constant_images.count(static_cast<int>(i))) {
      fixed_positions.push_back(plan->image_prior[i] ? *block.images[i].measured_center_m
                                                     : block.images[i].eo->center_in_ground());
      ++num_cameras;
    }
    if (plan->image_attitude[i] || config.constant_images.count(static_cast<int>(i))) {
      fixed_rotation = true;
      ++num_attitudes;
    }
  }
  if (fixed_positions.empty() && !fixed_rotation) {
    // A relative block: COLMAP's gauge. The first image fixed; of the second, the centre
    // coordinate farthest from the first image's fixes the scale.
    plan->datum = BundleDatum::kRelative;
    if (block.images.size() < 2) return Status::Error("a relative block needs two images");
    plan->relative_fixed_image = 0;
    plan->relative_scale_image = 1;
    const Eigen::Vector3d baseline =
        block.images[1].eo->center_in_ground() - block.images[0].eo->center_in_ground();
    baseline.cwiseAbs().maxCoeff(&plan->relative_scale_axis);
    if (!(baseline.norm() > 0.0))
      return Status::Error("a relative block needs its first two images at different positions");
    const char* axes = "XYZ";
    plan->datum_description =
        "relative: no control points and no camera positions; image '" + block.images[0].name +
        "' held fixed and the " + std::string(1, axes[plan->relative_scale_axis]) +
        " coordinate of image '" + block.images[1].name +
        "' fixes the scale (COLMAP's convention); coordinates are in the frame of the input";
    return Status::Ok();
  }
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : fixed_positions) centroid += p;
  if (!fixed_positions.empty()) centroid /= static_cast<double>(fixed_positions.size());
  double extent = 0.0;
  for (const auto& p : fixed_positions) extent += (p - centroid).squaredNorm();
  extent = fixed_positions.empty() ? 1.0 : std::sqrt(extent / fixed_positions.size());
  if (!(extent > 0.0)) extent = 1.0;
  std::vector<Eigen::Matrix<double, 3, 7>> rows;
  for (const auto& p : fixed_positions) AddDatumRows(p, centroid, extent, &rows);
  if (fixed_rotation) {
    Eigen::Matrix<double, 3, 7> J = Eigen::Matrix<double, 3, 7>::Zero();
    J.block<3, 3>(0, 3).setIdentity();
    rows.push_back(J);
  }
  Eigen::MatrixXd D(3 * rows.size(), 7);
  for (size_t k = 0; k < rows.size(); ++k) D.block<3, 7>(3 * k, 0) = rows[k];
  const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(D).singularValues();
  std::ostringstream what;
  what << num_control << " control point" << (num_control == 1 ? "" : "s") << ", " << num_cameras
       << " camera position" << (num_cameras == 1 ? "" : "s");
  if (num_attitudes > 0) what << ", " << num_attitudes << " attitude" << (num_attitudes == 1 ? "" : "s");
  if (s.size() < 7 || !(s[6] > kDatumConditioning * s[0])) {
    int rank = 0;
    for (int k = 0; k < s.size(); ++k) rank += s[k] > kDatumConditioning * s[0];
    std::string why;
    if (fixed_positions.size() <= 2 && !fixed_rotation) {
      why = "fewer than three positions cannot fix the rotation";
    } else {
      why = "the positions lie on one line (the rotation about it is free)";
    }
    return Status::Error("no datum: the " + what.str() + " fix only " + std::to_string(rank) +
                         " of the 7 similarity parameters of the block (" + why +
                         "); add control points off that line or camera positions");
  }
  plan->datum = BundleDatum::kControl;
  plan->datum_description = "absolute: " + what.str() + " weighted as stated";
  return Status::Ok();
}

ceres::LossFunction* MakeTieLoss(const BundleAdjustmentOptions& options) {
  const double s = options.tie_loss_scale_sigmas;
  switch (options.tie_loss) {
    case BundleAdjustmentOptions::TieLoss::kNone:
      return nullptr;
    case BundleAdjustmentOptions::TieLoss::kHuber:
      return new ceres::HuberLoss(s);
    case BundleAdjustmentOptions::TieLoss::kCauchy:
      return new ceres::CauchyLoss(s);
    case BundleAdjustmentOptions::TieLoss::kSoftL1:
      return new ceres::SoftLOneLoss(s);
  }
  return nullptr;
}

// One adjustment round's problem and what it needs to stay alive.
struct RoundProblem {
  std::unique_ptr<ceres::Problem> problem;
  std::vector<std::unique_ptr<ceres::Manifold>> manifolds;
  std::unique_ptr<ceres::LossFunction> tie_loss;
  std::vector<ResidualInfo> residuals;
  // Tangent sizes and the order of the variable parameter blocks for the statistics: cameras'
  // exterior orientations, camera parameters, lever arm ("e" blocks), then points.
  std::vector<double*> e_blocks;
  std::vector<int> e_sizes;
  std::vector<double*> point_blocks;
  std::vector<int> point_of_block;  // point index of each point block
  int num_free_parameters = 0;
  int num_observations = 0;
};

void BuildRound(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                const Block& block, const Plan& plan, State* state, RoundProblem* round) {
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = false;
  round->problem = std::make_unique<ceres::Problem>(problem_options);
  ceres::Problem& problem = *round->problem;
  round->tie_loss.reset(MakeTieLoss(options));

  // Exterior orientations with their manifold (one shared; the relative gauge's second image
  // gets one with a fixed coordinate).
  round->manifolds.emplace_back(new ExteriorOrientationManifold());
  ceres::Manifold* eo_manifold = round->manifolds.back().get();
  for (size_t i = 0; i < block.images.size(); ++i) {
    double* eo = state->eo[i].data();
    problem.AddParameterBlock(eo, kExteriorOrientationSize);
    const bool constant = config.constant_images.count(static_cast<int>(i)) ||
                          static_cast<int>(i) == plan.relative_fixed_image;
    if (constant) {
      problem.SetParameterBlockConstant(eo);
      continue;
    }
    if (static_cast<int>(i) == plan.relative_scale_image) {
      std::array<bool, 6> fixed{};
      fixed[plan.relative_scale_axis] = true;
      round->manifolds.emplace_back(new ExteriorOrientationManifold(fixed));
      problem.SetManifold(eo, round->manifolds.back().get());
      round->e_sizes.push_back(5);
    } else {
      problem.SetManifold(eo, eo_manifold);
      round->e_sizes.push_back(6);
    }
    round->e_blocks.push_back(eo);
  }
  // Camera parameters: constant except the calibrated ones.
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    double* params = state->cameras[c].data();
    const int n = static_cast<int>(state->cameras[c].size());
    problem.AddParameterBlock(params, n);
    const std::vector<int>& free = plan.calibrated[c];
    if (free.empty()) {
      problem.SetParameterBlockConstant(params);
      continue;
    }
    if (static_cast<int>(free.size()) < n) {
      std::vector<int> constant;
      for (int k = 0; k < n; ++k)
        if (!std::binary_search(free.begin(), free.end(), k)) constant.push_back(k);
      round->manifolds.emplace_back(new ceres::SubsetManifold(n, constant));
      problem.SetManifold(params, round->manifolds.back().get());
    }
    round->e_blocks.push_back(params);
    round->e_sizes.push_back(static_cast<int>(free.size()));
  }
  double* lever = state->lever.data();
  if (plan.use_lever) {
    problem.AddParameterBlock(lever, 3);
    if (options.estimate_lever_arm) {
      round->e_blocks.push_back(lever);
      round->e_sizes.push_back(3);
    } else {
      problem.SetParameterBlockConstant(lever);
    }
  }

  // Points.
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p]) continue;
    double* point = state->points[p].data();
    problem.AddParameterBlock(point, kPointSize);
    if (config.constant_points.count(static_cast<int>(p))) {
      problem.SetParameterBlockConstant(point);
      continue;
    }
    round->point_blocks.push_back(point);
    round->point_of_block.push_back(static_cast<int>(p));
  }

  // Marks.
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!plan.mark_used[m]) continue;
    const BlockMark& mark = block.marks[m];
    const int camera_index = block.images[mark.image].camera;
    const BlockCamera& camera = block.cameras[camera_index];
    ceres::CostFunction* cost = CreateCollinearityCost(
        options.jacobian, CollinearityFunctor(camera.model, mark.observation, camera.data(),
                                              1.0 / plan.mark_sigma[m]));
    std::vector<double*> parameters = {state->eo[mark.image].data(),
                                       state->points[mark.point].data(),
                                       state->cameras[camera_index].data()};
    ceres::LossFunction* loss = plan.mark_group[m] == kTieMarks ? round->tie_loss.get() : nullptr;
    const ceres::ResidualBlockId id = problem.AddResidualBlock(cost, loss, parameters);
    round->residuals.push_back({plan.mark_group[m], static_cast<int>(m), 2, 0, id, parameters});
  }
  // Control point priors, two rows at a time.
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p] || block.points[p].role != PointRole::kControl) continue;
    if (config.constant_points.count(static_cast<int>(p))) continue;
    double* point = state->points[p].data();
    const Eigen::Vector3d& surveyed = *block.points[p].surveyed_m;
    const ceres::ResidualBlockId xy = problem.AddResidualBlock(
        new GroundPointPriorRows(surveyed, plan.point_sigma[p], 0, 1), nullptr, point);
    round->residuals.push_back({kControlPoints, static_cast<int>(p), 2, 0, xy, {point}});
    const ceres::ResidualBlockId z = problem.AddResidualBlock(
        new GroundPointPriorRows(surveyed, plan.point_sigma[p], 2, -1), nullptr, point);
    round->residuals.push_back({kControlPoints, static_cast<int>(p), 1, 2, z, {point}});
  }
  // Camera positions and attitudes.
  for (size_t i = 0; i < block.images.size(); ++i) {
    double* eo = state->eo[i].data();
    if (plan.image_prior[i]) {
      const Eigen::Vector3d& measured = *block.images[i].measured_center_m;
      ceres::ResidualBlockId id;
      std::vector<double*> parameters = {eo};
      if (plan.use_lever) {
        parameters.push_back(lever);
        id = problem.AddResidualBlock(
            CameraPositionLeverArmPrior::Create(measured, plan.image_prior_sigma[i]), nullptr,
            parameters);
      } else {
        id = problem.AddResidualBlock(new CameraPositionPrior(measured, plan.image_prior_sigma[i]),
                                      nullptr, parameters);
      }
      round->residuals.push_back({kCameraPositions, static_cast<int>(i), 3, 0, id, parameters});
    }
    if (plan.image_attitude[i]) {
      const ceres::ResidualBlockId id = problem.AddResidualBlock(
          new AttitudePrior(*block.images[i].measured_angles_rad, plan.image_attitude_sigma[i]),
          nullptr, eo);
      round->residuals.push_back({kAttitudes, static_cast<int>(i), 3, 0, id, {eo}});
    }
  }

  round->num_free_parameters = 3 * static_cast<int>(round->point_blocks.size());
  for (const int size : round->e_sizes) round->num_free_parameters += size;
  round->num_observations = 0;
  for (const ResidualInfo& info : round->residuals) round->num_observations += info.rows;
}

class ProgressCallback final : public ceres::IterationCallback {
 public:
  ProgressCallback(const BundleAdjustmentOptions& options, int round, int redundancy,
                   Clock::time_point start)
      : options_(options), round_(round), redundancy_(redundancy), start_(start) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    BundleIterationInfo info;
    info.round = round_;
    info.iteration = summary.iteration;
    info.cost = summary.cost;
    info.sigma0 = redundancy_ > 0 ? std::sqrt(2.0 * summary.cost / redundancy_) : kNaN;
    info.step_norm = summary.step_norm;
    info.elapsed_seconds = SecondsSince(start_);
    options_.progress(info);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const BundleAdjustmentOptions& options_;
  int round_;
  int redundancy_;
  Clock::time_point start_;
};

ceres::Solver::Options SolverOptions(const BundleAdjustmentOptions& options,
                                     const RoundProblem& round) {
  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.num_threads = options.num_threads > 0
                           ? options.num_threads
                           : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  switch (options.linear_solver) {
    case BundleLinearSolver::kSparseSchur:
      solver.linear_solver_type = ceres::SPARSE_SCHUR;
      solver.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
      break;
    case BundleLinearSolver::kDenseSchur:
      solver.linear_solver_type = ceres::DENSE_SCHUR;
      break;
    case BundleLinearSolver::kIterativeSchurJacobi:
      solver.linear_solver_type = ceres::ITERATIVE_SCHUR;
      solver.preconditioner_type = ceres::SCHUR_JACOBI;
      break;
    case BundleLinearSolver::kIterativeSchurClusterJacobi:
      solver.linear_solver_type = ceres::ITERATIVE_SCHUR;
      solver.preconditioner_type = ceres::CLUSTER_JACOBI;
      solver.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
      break;
  }
  // Points first: they are eliminated (Schur complement); everything else forms the reduced
  // camera system.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (double* point : round.point_blocks) ordering->AddElementToGroup(point, 0);
  for (double* e : round.e_blocks) ordering->AddElementToGroup(e, 1);
  if (!round.point_blocks.empty() && !round.e_blocks.empty())
    solver.linear_solver_ordering = ordering;
  return solver;
}

// Whitened residual of every used mark (observed - computed over sigma), at the state.
void MarkResiduals(const Block& block, const Plan& plan, const RoundProblem& round,
                   std::vector<Eigen::Vector2d>* whitened) {
  whitened->assign(block.marks.size(), Eigen::Vector2d::Constant(kNaN));
  for (const ResidualInfo& info : round.residuals) {
    if (info.group != kTieMarks && info.group != kControlMarks) continue;
    double residual[2];
    double cost;
    if (!round.problem->EvaluateResidualBlock(info.id, false, &cost, residual, nullptr)) continue;
    (*whitened)[info.item] = Eigen::Vector2d(residual[0], residual[1]);
  }
  (void)plan;
}

// The dense reduced normal matrix S (e blocks, points eliminated) of the whitened problem, and
// what the statistics need of the point blocks.
struct Reduced {
  int size = 0;                     // number of e columns
  std::vector<int> e_offset;        // per e block
  std::map<const double*, int> e_index;
  std::map<const double*, int> point_index;  // point block -> index into point data
  Eigen::MatrixXd S;
  std::vector<Eigen::Matrix3d> V_inverse;  // per point block
  // W_p: per point block, the e columns it touches and the (e x 3) block.
  std::vector<std::vector<int>> W_columns;
  std::vector<Eigen::MatrixXd> W;
  Eigen::MatrixXd C;  // S^-1, unscaled
  bool ok = false;
};

// The Jacobian rows of one residual block in the tangent spaces: columns of e blocks (global e
// column indices) and of its point block (3 columns), if any.
struct BlockRows {
  int rows = 0;
  std::vector<int> e_columns;
  Eigen::MatrixXd J_e;               // rows x e_columns
  Eigen::Matrix<double, Eigen::Dynamic, 3> J_p;  // rows x 3, empty without a variable point
  int point = -1;                    // index into Reduced point data, or -1
};

bool EvaluateBlockRows(const RoundProblem& round, const Reduced& reduced, const ResidualInfo& info,
                       BlockRows* out) {
  ceres::Problem& problem = *round.problem;
  const int num_residuals = problem.GetCostFunctionForResidualBlock(info.id)->num_residuals();
  std::vector<double*> jacobians(info.parameters.size(), nullptr);
  std::vector<std::vector<double>> storage(info.parameters.size());
  for (size_t k = 0; k < info.parameters.size(); ++k) {
    double* block = info.parameters[k];
    if (problem.IsParameterBlockConstant(block)) continue;
    const int tangent = problem.ParameterBlockTangentSize(block);
    storage[k].assign(static_cast<size_t>(num_residuals) * tangent, 0.0);
    jacobians[k] = storage[k].data();
  }
  double cost;
  std::vector<double> residual(num_residuals);
  if (!problem.EvaluateResidualBlock(info.id, false, &cost, residual.data(), jacobians.data()))
    return false;
  out->rows = num_residuals;
  out->e_columns.clear();
  out->point = -1;
  std::vector<std::pair<int, int>> e_parts;  // (k, tangent)
  for (size_t k = 0; k < info.parameters.size(); ++k) {
    if (jacobians[k] == nullptr) continue;
    const int tangent = problem.ParameterBlockTangentSize(info.parameters[k]);
    const auto e = reduced.e_index.find(info.parameters[k]);
    if (e != reduced.e_index.end()) {
      for (int c = 0; c < tangent; ++c) out->e_columns.push_back(reduced.e_offset[e->second] + c);
      e_parts.push_back({static_cast<int>(k), tangent});
    } else {
      const auto p = reduced.point_index.find(info.parameters[k]);
      if (p == reduced.point_index.end()) continue;
      out->point = p->second;
      out->J_p = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
          jacobians[k], num_residuals, 3);
    }
  }
  out->J_e.resize(num_residuals, static_cast<int>(out->e_columns.size()));
  int column = 0;
  for (const auto& [k, tangent] : e_parts) {
    for (int r = 0; r < num_residuals; ++r)
      for (int c = 0; c < tangent; ++c) out->J_e(r, column + c) = jacobians[k][r * tangent + c];
    column += tangent;
  }
  return true;
}

void BuildReduced(const RoundProblem& round, Reduced* reduced) {
  reduced->e_offset.clear();
  int offset = 0;
  for (size_t b = 0; b < round.e_blocks.size(); ++b) {
    reduced->e_index[round.e_blocks[b]] = static_cast<int>(b);
    reduced->e_offset.push_back(offset);
    offset += round.e_sizes[b];
  }
  reduced->size = offset;
  for (size_t p = 0; p < round.point_blocks.size(); ++p)
    reduced->point_index[round.point_blocks[p]] = static_cast<int>(p);
  const size_t num_points = round.point_blocks.size();
  std::vector<Eigen::Matrix3d> V(num_points, Eigen::Matrix3d::Zero());
  std::vector<std::map<int, Eigen::RowVector3d>> W_rows(num_points);
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(offset, offset);
  BlockRows rows;
  for (const ResidualInfo& info : round.residuals) {
    if (!EvaluateBlockRows(round, *reduced, info, &rows)) continue;
    const int ne = static_cast<int>(rows.e_columns.size());
    if (ne > 0) {
      const Eigen::MatrixXd JtJ = rows.J_e.transpose() * rows.J_e;
      for (int a = 0; a < ne; ++a)
        for (int b = 0; b < ne; ++b) U(rows.e_columns[a], rows.e_columns[b]) += JtJ(a, b);
    }
    if (rows.point >= 0) {
      V[rows.point] += rows.J_p.transpose() * rows.J_p;
      if (ne > 0) {
        const Eigen::MatrixXd JeJp = rows.J_e.transpose() * rows.J_p;
        for (int a = 0; a < ne; ++a) {
          auto [it, inserted] = W_rows[rows.point].emplace(rows.e_columns[a], JeJp.row(a));
          if (!inserted) it->second += JeJp.row(a);
        }
      }
    }
  }
  reduced->V_inverse.resize(num_points);
  reduced->W_columns.resize(num_points);
  reduced->W.resize(num_points);
  for (size_t p = 0; p < num_points; ++p) {
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(V[p]);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return;
    reduced->V_inverse[p] = ldlt.solve(Eigen::Matrix3d::Identity());
    const int k = static_cast<int>(W_rows[p].size());
    reduced->W_columns[p].reserve(k);
    reduced->W[p].resize(k, 3);
    int row = 0;
    for (const auto& [column, values] : W_rows[p]) {
      reduced->W_columns[p].push_back(column);
      reduced->W[p].row(row++) = values;
    }
    const Eigen::MatrixXd update = reduced->W[p] * reduced->V_inverse[p] * reduced->W[p].transpose();
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b)
        U(reduced->W_columns[p][a], reduced->W_columns[p][b]) -= update(a, b);
  }
  reduced->S = std::move(U);
  if (offset == 0) {
    reduced->ok = true;
    return;
  }
  // Jacobi scaling first: camera parameters in mixed units (um next to mm^-6) give diagonals
  // twenty orders of magnitude apart, which would hide a real rank defect or fake one.
  const Eigen::VectorXd d = reduced->S.diagonal();
  if (!(d.minCoeff() > 0.0)) return;
  const Eigen::VectorXd scale = d.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * reduced->S * scale.asDiagonal();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(scaled);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return;
  // A positive pivot far below the largest is a datum defect in all but name.
  if (!(ldlt.vectorD().minCoeff() > 1e-12 * ldlt.vectorD().maxCoeff())) return;
  reduced->C = scale.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(offset, offset)) *
               scale.asDiagonal();
  reduced->ok = reduced->C.allFinite();
}

// Unscaled covariance of point block p: V^-1 + V^-1 W^T C W V^-1.
Eigen::Matrix3d PointCovariance(const Reduced& reduced, int p) {
  const std::vector<int>& cols = reduced.W_columns[p];
  const int k = static_cast<int>(cols.size());
  Eigen::MatrixXd C_sub(k, k);
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b) C_sub(a, b) = reduced.C(cols[a], cols[b]);
  const Eigen::Matrix3d& Vi = reduced.V_inverse[p];
  const Eigen::MatrixXd WV = reduced.W[p] * Vi;  // k x 3
  return Vi + WV.transpose() * C_sub * WV;
}

// Sum over the block's observation rows of the leverage h = J C J^T (unscaled C over every
// variable the rows touch).
double Leverage(const Reduced& reduced, const BlockRows& rows, int observation_rows) {
  const int ne = static_cast<int>(rows.e_columns.size());
  Eigen::MatrixXd C_ee(ne, ne);
  for (int a = 0; a < ne; ++a)
    for (int b = 0; b < ne; ++b) C_ee(a, b) = reduced.C(rows.e_columns[a], rows.e_columns[b]);
  double sum = 0.0;
  if (rows.point < 0) {
    const Eigen::MatrixXd H = rows.J_e * C_ee * rows.J_e.transpose();
    for (int r = 0; r < observation_rows; ++r) sum += H(r, r);
    return sum;
  }
  const int p = rows.point;
  const Eigen::Matrix3d C_pp = PointCovariance(reduced, p);
  // C_ep (for the row's e columns) = -C(e, W cols) W V^-1.
  const std::vector<int>& cols = reduced.W_columns[p];
  Eigen::MatrixXd C_ew(ne, cols.size());
  for (int a = 0; a < ne; ++a)
    for (size_t b = 0; b < cols.size(); ++b) C_ew(a, b) = reduced.C(rows.e_columns[a], cols[b]);
  const Eigen::MatrixXd C_ep = -C_ew * reduced.W[p] * reduced.V_inverse[p];  // ne x 3
  Eigen::MatrixXd H = rows.J_p * C_pp * rows.J_p.transpose();
  if (ne > 0) {
    const Eigen::MatrixXd cross = rows.J_e * C_ep * rows.J_p.transpose();
    H += rows.J_e * C_ee * rows.J_e.transpose() + cross + cross.transpose();
  }
  for (int r = 0; r < observation_rows; ++r) sum += H(r, r);
  return sum;
}

std::string FormatNumber3(double value) {
  std::ostringstream os;
  os.precision(3);
  os << value;
  return os.str();
}

}  // namespace

std::optional<BundleLinearSolver> ParseBundleLinearSolver(const std::string& name) {
  if (name == "sparse_schur") return BundleLinearSolver::kSparseSchur;
  if (name == "dense_schur") return BundleLinearSolver::kDenseSchur;
  if (name == "iterative_schur" || name == "iterative_schur_jacobi")
    return BundleLinearSolver::kIterativeSchurJacobi;
  if (name == "iterative_schur_cluster_jacobi")
    return BundleLinearSolver::kIterativeSchurClusterJacobi;
  return std::nullopt;
}

const char* BundleLinearSolverName(BundleLinearSolver solver) {
  switch (solver) {
    case BundleLinearSolver::kSparseSchur:
      return "sparse_schur";
    case BundleLinearSolver::kDenseSchur:
      return "dense_schur";
    case BundleLinearSolver::kIterativeSchurJacobi:
      return "iterative_schur_jacobi";
    case BundleLinearSolver::kIterativeSchurClusterJacobi:
      return "iterative_schur_cluster_jacobi";
  }
  return "?";
}

const char* BundleTerminationName(BundleTermination termination) {
  switch (termination) {
    case BundleTermination::kConverged:
      return "converged";
    case BundleTermination::kNoConvergence:
      return "no_convergence";
    case BundleTermination::kFailure:
      return "failure";
  }
  return "?";
}

bool BundleAdjustmentOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& text) {
    if (why != nullptr) *why = text;
    return false;
  };
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  const BundleAccuracies& a = accuracies;
  if (!positive(a.tie_px) || !positive(a.marker_projection_px) || !positive(a.tie_film_um) ||
      !positive(a.marker_projection_film_um) || !positive(a.marker_m) ||
      !positive(a.camera_m.minCoeff()) || !a.camera_m.allFinite())
    return fail("every accuracy must be positive and finite");
  if (a.attitude_deg && !positive(*a.attitude_deg)) return fail("the attitude accuracy must be positive");
  if (!positive(tie_loss_scale_sigmas)) return fail("the tie loss scale must be positive");
  if (!(rejection_threshold >= 0.0) || !std::isfinite(rejection_threshold))
    return fail("the rejection threshold must be >= 0 (0: no rejection)");
  if (max_rejection_rounds < 0) return fail("max_rejection_rounds must be >= 0");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!positive(function_tolerance) || !positive(parameter_tolerance) ||
      !(gradient_tolerance >= 0.0))
    return fail("tolerances must be positive");
  if (num_threads < 0) return fail("num_threads must be >= 0");
  if (lever_arm_m && !lever_arm_m->allFinite()) return fail("the lever arm must be finite");
  if (max_covariance_parameters < 0) return fail("max_covariance_parameters must be >= 0");
  if (!(overfit_ratio > 0.0 && overfit_ratio < 1.0)) return fail("overfit_ratio must be in (0, 1)");
  if (!(high_correlation > 0.0 && high_correlation < 1.0))
    return fail("high_correlation must be in (0, 1)");
  return true;
}

Status BundleAdjustmentConfig::FromCalibrationNames(const Block& block,
                                                    const std::vector<std::string>& names,
                                                    BundleAdjustmentConfig* config) {
  config->calibrated_params.assign(block.cameras.size(), {});
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    for (const std::string& name : names) {
      std::vector<int> indices;
      const Status status = CalibrationParamIndices(block.cameras[c].model, name, &indices);
      if (!status.ok())
        return Status::Error("camera '" + block.cameras[c].camera_id + "': " + status.message());
      config->calibrated_params[c].insert(config->calibrated_params[c].end(), indices.begin(),
                                          indices.end());
    }
  }
  return Status::Ok();
}

std::string BundleAdjustmentSummary::BriefReport() const {
  std::ostringstream os;
  os << BundleTerminationName(termination) << ": " << num_images << " images, " << num_points
     << " points, " << num_marks << " marks, " << rounds << " round" << (rounds == 1 ? "" : "s")
     << ", " << iterations << " iterations, cost " << initial_cost << " -> " << final_cost
     << ", sigma0 " << sigma0 << " (redundancy " << redundancy << ")";
  if (num_rejected_marks > 0) os << ", " << num_rejected_marks << " marks rejected";
  os << ", " << time_seconds << " s";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

std::string BundleAdjustmentResult::FullReport(const Block& block) const {
  std::ostringstream os;
  os << "Bundle adjustment: " << summary.BriefReport() << "\n";
  os << "Datum: " << summary.datum_description << "\n";
  os << "Groups (count, stated, RMS, RMS/stated, redundancy share):\n";
  for (const BundleGroupStatistics& g : groups) {
    os << "  " << g.name << ": " << g.count << ", " << FormatNumber3(g.stated_accuracy.x()) << " "
       << g.unit << ", " << FormatNumber3(g.rms_total) << " " << g.unit << ", "
       << FormatNumber3(g.ratio) << ", " << FormatNumber3(g.redundancy_share)
       << (g.overfit ? "  OVERFIT" : "") << "\n";
    if (!g.message.empty()) os << "    " << g.message << "\n";
  }
  if (num_control_points > 0)
    os << "Control points: " << num_control_points << ", RMSE " << control_rmse_total_m << " m\n";
  if (num_check_points > 0)
    os << "Check points: " << num_check_points << ", RMSE " << check_rmse_total_m << " m\n";
  for (const BundleCalibrationResult& c : calibration) {
    os << "Camera '" << block.cameras[c.camera].camera_id << "':\n";
    for (size_t k = 0; k < c.names.size(); ++k) {
      os << "  " << c.names[k] << " = " << c.values[k];
      if (k < c.sigmas.size()) os << " +- " << c.sigmas[k];
      os << "\n";
    }
    for (const std::string& h : c.high_correlations) os << "  high correlation " << h << "\n";
  }
  return os.str();
}

Status BundleAdjust(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                    Block* block, BundleAdjustmentResult* result) {
  const Clock::time_point start = Clock::now();
  *result = BundleAdjustmentResult();
  BundleAdjustmentSummary& summary = result->summary;
  std::string why;
  if (!options.IsValid(&why)) return Status::Error("invalid options: " + why);
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(*block));
  block->BuildIndex();
  for (const int i : config.constant_images)
    if (i < 0 || i >= static_cast<int>(block->images.size()))
      return Status::Error("the config holds a non-existent image constant");
  for (const int p : config.constant_points)
    if (p < 0 || p >= static_cast<int>(block->points.size()))
      return Status::Error("the config holds a non-existent point constant");

  Plan plan;
  PHOTOPOSE_RETURN_IF_ERROR(MakePlan(options, config, *block, &plan));
  summary.datum = plan.datum;
  summary.datum_description = plan.datum_description;

  State state;
  for (const BlockImage& image : block->images) state.eo.push_back(image.eo->parameters);
  for (const BlockPoint& point : block->points) {
    state.points.push_back(point.position_m ? *point.position_m
                           : point.surveyed_m ? *point.surveyed_m
                                              : Eigen::Vector3d::Zero());
  }
  for (const BlockCamera& camera : block->cameras) state.cameras.push_back(camera.params);
  if (options.lever_arm_m) state.lever = *options.lever_arm_m;

  // Rounds: adjust, reject the marks beyond the threshold, adjust again.
  RoundProblem round;
  std::vector<Eigen::Vector2d> whitened;
  const int max_rounds = options.rejection_threshold > 0.0 ? options.max_rejection_rounds + 1 : 1;
  bool converged = false;
  for (int r = 1; r <= max_rounds; ++r) {
    BuildRound(options, config, *block, plan, &state, &round);
    const int redundancy = round.num_observations - round.num_free_parameters;
    ceres::Solver::Options solver_options = SolverOptions(options, round);
    std::unique_ptr<ProgressCallback> callback;
    if (options.progress) {
      callback = std::make_unique<ProgressCallback>(options, r, redundancy, start);
      solver_options.callbacks.push_back(callback.get());
      solver_options.update_state_every_iteration = false;
    }
    ceres::Solver::Summary ceres_summary;
    ceres::Solve(solver_options, round.problem.get(), &ceres_summary);
    summary.rounds = r;
    summary.iterations += static_cast<int>(ceres_summary.iterations.size()) - 1;
    if (r == 1) summary.initial_cost = ceres_summary.initial_cost;
    summary.final_cost = ceres_summary.final_cost;
    summary.redundancy = redundancy;
    if (ceres_summary.termination_type != ceres::CONVERGENCE) {
      summary.termination = ceres_summary.termination_type == ceres::NO_CONVERGENCE
                                ? BundleTermination::kNoConvergence
                                : BundleTermination::kFailure;
      summary.message = "round " + std::to_string(r) + ": " + ceres_summary.message;
      summary.time_seconds = SecondsSince(start);
      return Status::Ok();
    }
    converged = true;
    summary.sigma0 = redundancy > 0 ? std::sqrt(2.0 * ceres_summary.final_cost / redundancy) : kNaN;
    MarkResiduals(*block, plan, round, &whitened);
    if (r == max_rounds) break;
    // Reject the marks beyond the threshold (in units of sigma0, never below the stated sigma).
    const double limit = options.rejection_threshold * std::max(1.0, summary.sigma0);
    int rejected = 0;
    for (size_t m = 0; m < block->marks.size(); ++m) {
      if (!plan.mark_used[m] || !(whitened[m].norm() > limit)) continue;
      plan.mark_used[m] = 0;
      result->rejected_marks.push_back({static_cast<int>(m), r, whitened[m].norm() / summary.sigma0});
      ++rejected;
    }
    if (rejected == 0) break;
    // Tie points left with one ray leave; every image must keep three marks.
    for (size_t p = 0; p < block->points.size(); ++p) {
      if (!plan.point_in_problem[p] || block->points[p].role != PointRole::kTie) continue;
      int rays = 0;
      for (const int m : block->marks_of_point[p]) rays += plan.mark_used[m];
      if (rays < 2) {
        for (const int m : block->marks_of_point[p]) plan.mark_used[m] = 0;
        plan.point_in_problem[p] = 0;
      }
    }
    for (size_t i = 0; i < block->images.size(); ++i) {
      int count = 0;
      for (const int m : block->marks_of_image[i]) count += plan.mark_used[m];
      if (count < kMinMarksPerImage) {
        summary.termination = BundleTermination::kFailure;
        summary.message = "after rejecting " + std::to_string(result->rejected_marks.size()) +
                          " marks as blunders, image '" + block->images[i].name + "' keeps " +
                          std::to_string(count) + " marks: too few to orient it";
        summary.time_seconds = SecondsSince(start);
        return Status::Ok();
      }
    }
  }
  if (!converged) return Status::Ok();
  summary.termination = BundleTermination::kConverged;
  summary.num_rejected_marks = static_cast<int>(result->rejected_marks.size());

  // ------------------------------------------------------------ statistics
  const Clock::time_point statistics_start = Clock::now();
  const double sigma0 = summary.sigma0;
  const double variance_factor = std::isfinite(sigma0) ? sigma0 * sigma0 : 1.0;
  result->images.assign(block->images.size(), BundleImageResult());
  result->points.assign(block->points.size(), BundlePointResult());
  result->mark_residuals.assign(block->marks.size(), Eigen::Vector2d::Constant(kNaN));
  summary.num_images = static_cast<int>(block->images.size());
  for (size_t p = 0; p < block->points.size(); ++p) summary.num_points += plan.point_in_problem[p];

  // Group sums: per axis sum of squared residuals (unit), whitened sum, count, stated sum.
  struct Sums {
    int count = 0;
    Eigen::Vector3d ssq = Eigen::Vector3d::Zero();
    Eigen::Vector3d stated = Eigen::Vector3d::Zero();
    double whitened_ssq = 0.0;
    int scalar_rows = 0;
    double leverage = 0.0;
    bool leverage_known = true;
    std::string unit;
  };
  Sums sums[kNumGroups];
  sums[kTieMarks].unit = sums[kControlMarks].unit = "px";
  sums[kControlPoints].unit = sums[kCameraPositions].unit = "m";
  sums[kAttitudes].unit = "deg";
  std::vector<double> image_ssq(block->images.size(), 0.0);
  bool any_film = false;
  for (size_t m = 0; m < block->marks.size(); ++m) {
    if (!plan.mark_used[m]) continue;
    const BlockMark& mark = block->marks[m];
    ++summary.num_marks;
    // Observed - computed in the mark's own unit.
    const Eigen::Vector2d residual = whitened[m] * plan.mark_sigma[m] / mark.observation_units_per_unit;
    result->mark_residuals[m] = residual;
    const double stated = plan.mark_sigma[m] / mark.observation_units_per_unit;
    Sums& s = sums[plan.mark_group[m]];
    ++s.count;
    s.ssq.head<2>() += residual.cwiseAbs2();
    s.stated.head<2>() += Eigen::Vector2d::Constant(stated);
    s.whitened_ssq += whitened[m].squaredNorm();
    s.scalar_rows += 2;
    if (mark.unit == MarkUnit::kFilm) any_film = true;
    BundleImageResult& image = result->images[mark.image];
    ++image.num_marks;
    image_ssq[mark.image] += residual.squaredNorm();
    image.unit = mark.unit == MarkUnit::kFilm ? "um" : "px";
    ++result->points[mark.point].num_observations;
  }
  if (any_film) sums[kTieMarks].unit = sums[kControlMarks].unit = "px or um";
  for (size_t i = 0; i < block->images.size(); ++i) {
    BundleImageResult& image = result->images[i];
    image.adjusted = true;
    image.rms_residual = image.num_marks > 0 ? std::sqrt(image_ssq[i] / image.num_marks) : 0.0;
  }
  for (size_t p = 0; p < block->points.size(); ++p) {
    if (!plan.point_in_problem[p] || block->points[p].role != PointRole::kControl) continue;
    const Eigen::Vector3d e = state.points[p] - *block->points[p].surveyed_m;
    Sums& s = sums[kControlPoints];
    ++s.count;
    s.ssq += e.cwiseAbs2();
    s.stated += plan.point_sigma[p];
    s.whitened_ssq += e.cwiseQuotient(plan.point_sigma[p]).squaredNorm();
    s.scalar_rows += 3;
    result->points[p].error_m = e;
  }
  for (size_t i = 0; i < block->images.size(); ++i) {
    if (plan.image_prior[i]) {
      Eigen::Vector3d antenna = state.eo[i].head<3>();
      if (plan.use_lever) {
        const Eigen::Matrix3d R =
            RotationFromAngles(RotationConvention::kSeed, state.eo[i].tail<3>());
        antenna += R.transpose() * state.lever;
      }
      const Eigen::Vector3d e = antenna - *block->images[i].measured_center_m;
      Sums& s = sums[kCameraPositions];
      ++s.count;
      s.ssq += e.cwiseAbs2();
      s.stated += plan.image_prior_sigma[i];
      s.whitened_ssq += e.cwiseQuotient(plan.image_prior_sigma[i]).squaredNorm();
      s.scalar_rows += 3;
    }
    if (plan.image_attitude[i]) {
      Eigen::Vector3d e;
      for (int k = 0; k < 3; ++k)
        e[k] = WrapAngle(state.eo[i][3 + k] - (*block->images[i].measured_angles_rad)[k]);
      Sums& s = sums[kAttitudes];
      ++s.count;
      s.ssq += (e * kDegreesPerRadian).cwiseAbs2();
      s.stated += plan.image_attitude_sigma[i] * kDegreesPerRadian;
      s.whitened_ssq += e.cwiseQuotient(plan.image_attitude_sigma[i]).squaredNorm();
      s.scalar_rows += 3;
    }
  }

  // Covariances and redundancy numbers from the reduced normal matrix.
  Reduced reduced;
  int e_size = 0;
  for (const int size : round.e_sizes) e_size += size;
  const bool covariance = e_size <= options.max_covariance_parameters;
  if (covariance) BuildReduced(round, &reduced);
  if (reduced.ok) {
    // Exterior orientations, in the ambient (Euler) parameters: P C P^T.
    for (size_t i = 0; i < block->images.size(); ++i) {
      const double* eo = state.eo[i].data();
      const auto found = reduced.e_index.find(eo);
      if (found == reduced.e_index.end()) continue;
      const int offset = reduced.e_offset[found->second];
      const int tangent = round.e_sizes[found->second];
      Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor> P(6, tangent);
      round.problem->GetManifold(const_cast<double*>(eo))->PlusJacobian(eo, P.data());
      const Eigen::MatrixXd C = reduced.C.block(offset, offset, tangent, tangent);
      result->images[i].covariance = variance_factor * P * C * P.transpose();
      result->images[i].has_covariance = true;
    }
    // Control points.
    for (const auto& [block_ptr, index] : reduced.point_index) {
      const int p = round.point_of_block[index];
      if (block->points[p].role != PointRole::kControl) continue;
      result->points[p].covariance = variance_factor * PointCovariance(reduced, index);
      result->points[p].has_covariance = true;
    }
    // Redundancy numbers of every group but the tie marks (whose share is the remainder).
    BlockRows rows;
    for (const ResidualInfo& info : round.residuals) {
      if (info.group == kTieMarks) continue;
      if (!EvaluateBlockRows(round, reduced, info, &rows)) continue;
      sums[info.group].leverage += Leverage(reduced, rows, info.rows);
    }
    double other_redundancy = 0.0;
    for (int g = kControlMarks; g < kNumGroups; ++g)
      other_redundancy += sums[g].scalar_rows - sums[g].leverage;
    sums[kTieMarks].leverage =
        sums[kTieMarks].scalar_rows - (summary.redundancy - other_redundancy);
    // Self-calibration.
    for (size_t c = 0; c < block->cameras.size(); ++c) {
      if (plan.calibrated[c].empty()) continue;
      const auto found = reduced.e_index.find(state.cameras[c].data());
      if (found == reduced.e_index.end()) continue;
      const int offset = reduced.e_offset[found->second];
      const int n = static_cast<int>(plan.calibrated[c].size());
      BundleCalibrationResult calibration;
      calibration.camera = static_cast<int>(c);
      const std::vector<std::string> names = CameraModelParamNames(block->cameras[c].model);
      const Eigen::MatrixXd C = variance_factor * reduced.C.block(offset, offset, n, n);
      calibration.correlation.resize(n, n);
      for (int a = 0; a < n; ++a) {
        const int index = plan.calibrated[c][a];
        calibration.indices.push_back(index);
        calibration.names.push_back(names[index]);
        calibration.values.push_back(state.cameras[c][index]);
        calibration.sigmas.push_back(std::sqrt(std::max(C(a, a), 0.0)));
      }
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          calibration.correlation(a, b) =
              C(a, b) / (calibration.sigmas[a] * calibration.sigmas[b]);
          if (b > a && std::abs(calibration.correlation(a, b)) > options.high_correlation) {
            calibration.high_correlations.push_back(calibration.names[a] + "~" +
                                                    calibration.names[b] + ": " +
                                                    FormatNumber3(calibration.correlation(a, b)));
          }
        }
      }
      result->calibration.push_back(std::move(calibration));
    }
    if (plan.use_lever) result->lever_arm_m = state.lever;
  } else {
    for (int g = 0; g < kNumGroups; ++g) sums[g].leverage_known = false;
    for (size_t c = 0; c < block->cameras.size(); ++c) {
      if (plan.calibrated[c].empty()) continue;
      BundleCalibrationResult calibration;
      calibration.camera = static_cast<int>(c);
      const std::vector<std::string> names = CameraModelParamNames(block->cameras[c].model);
      for (const int index : plan.calibrated[c]) {
        calibration.indices.push_back(index);
        calibration.names.push_back(names[index]);
        calibration.values.push_back(state.cameras[c][index]);
      }
      result->calibration.push_back(std::move(calibration));
    }
    if (plan.use_lever) result->lever_arm_m = state.lever;
    summary.message = covariance ? "the normal matrix is singular: no covariances"
                                 : "covariances skipped (more than " +
                                       std::to_string(options.max_covariance_parameters) +
                                       " parameters after point elimination)";
  }

  for (int g = 0; g < kNumGroups; ++g) {
    const Sums& s = sums[g];
    if (s.count == 0) continue;
    BundleGroupStatistics group;
    group.name = kGroupNames[g];
    group.count = s.count;
    group.unit = s.unit;
    group.num_axes = (g == kTieMarks || g == kControlMarks) ? 2 : 3;
    group.stated_accuracy = s.stated / s.count;
    group.rms = (s.ssq / s.count).cwiseSqrt();
    group.rms_total = std::sqrt(s.ssq.sum() / (s.count * group.num_axes));
    group.ratio = std::sqrt(s.whitened_ssq / s.scalar_rows);
    group.redundancy_share =
        s.leverage_known ? (s.scalar_rows - s.leverage) / s.scalar_rows : kNaN;
    const bool prior = g == kControlPoints || g == kCameraPositions || g == kAttitudes;
    if (prior && (group.ratio < options.overfit_ratio ||
                  (s.leverage_known && group.redundancy_share < options.overfit_ratio))) {
      group.overfit = true;
      std::ostringstream message;
      message << group.name << " over-fitted: residual RMS " << FormatNumber3(group.ratio)
              << " of the stated accuracy";
      if (s.leverage_known)
        message << ", redundancy share " << FormatNumber3(group.redundancy_share);
      message << ". The adjustment bends to these priors: too few or too weak tie points, or a "
                 "stated accuracy that is too loose.";
      group.message = message.str();
    }
    result->groups.push_back(group);
  }

  // Control and check points; check points are intersected from the adjusted images and cameras.
  Eigen::Vector3d control_ssq = Eigen::Vector3d::Zero(), check_ssq = Eigen::Vector3d::Zero();
  std::vector<BlockCamera> adjusted_cameras = block->cameras;
  for (size_t c = 0; c < adjusted_cameras.size(); ++c) adjusted_cameras[c].params = state.cameras[c];
  const double marker_px = options.accuracies.marker_projection_px;
  for (size_t p = 0; p < block->points.size(); ++p) {
    const BlockPoint& point = block->points[p];
    BundlePointResult& out = result->points[p];
    if (point.role == PointRole::kControl && out.error_m) {
      ++result->num_control_points;
      control_ssq += out.error_m->cwiseAbs2();
    }
    if (point.role != PointRole::kCheck) continue;
    std::vector<RayObservation> rays;
    for (const int m : block->marks_of_point[p]) {
      const BlockMark& mark = block->marks[m];
      RayObservation ray;
      ray.camera = &adjusted_cameras[block->images[mark.image].camera];
      ray.eo.parameters = state.eo[mark.image];
      ray.observation = mark.observation;
      ray.sigma = MarkSigma(mark, marker_px,
                            FilmDefaultUm(*ray.camera, marker_px,
                                          options.accuracies.marker_projection_film_um));
      rays.push_back(ray);
    }
    out.num_observations = static_cast<int>(rays.size());
    TriangulationResult triangulated;
    const Status status = TriangulatePoint(TriangulationOptions(), rays, &triangulated);
    if (!status.ok()) {
      out.message = "not intersected: " + status.message();
      continue;
    }
    out.error_m = triangulated.point_m - *point.surveyed_m;
    out.covariance = variance_factor * triangulated.covariance;
    out.has_covariance = true;
    ++result->num_check_points;
    check_ssq += out.error_m->cwiseAbs2();
  }
  if (result->num_control_points > 0) {
    result->control_rmse_m = (control_ssq / result->num_control_points).cwiseSqrt();
    result->control_rmse_total_m = std::sqrt(control_ssq.sum() / result->num_control_points);
  }
  if (result->num_check_points > 0) {
    result->check_rmse_m = (check_ssq / result->num_check_points).cwiseSqrt();
    result->check_rmse_total_m = std::sqrt(check_ssq.sum() / result->num_check_points);
  }
  summary.statistics_seconds = SecondsSince(statistics_start);

  // Write back.
  for (size_t i = 0; i < block->images.size(); ++i) {
    ExteriorOrientation eo;
    eo.parameters = state.eo[i];
    block->images[i].eo = eo;
  }
  for (size_t p = 0; p < block->points.size(); ++p)
    if (plan.point_in_problem[p]) block->points[p].position_m = state.points[p];
  for (size_t c = 0; c < block->cameras.size(); ++c) block->cameras[c].params = state.cameras[c];
  summary.time_seconds = SecondsSince(start);
  return Status::Ok();
}

}  // namespace photopose
