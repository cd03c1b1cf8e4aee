// The bundle adjustment's plan and its Ceres problem (internal/bundle_problem.h): what is unknown
// and what fixes the datum (the plan: datum checks, calibration, marks, points, priors,
// connectivity), then the problem built once per adjustment from that plan and updated per round,
// the relative gauge, and Ceres' solver options. One file past ~800 lines on purpose: the plan's
// checks and the problem's blocks are the two halves of one decision (what is a parameter, what
// is held), and both solvers take them from here.
#include "solvers/bundle/internal/bundle_problem.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

#include "core/parallel.h"
#include "core/rotation.h"
#include "cost_functions/exterior_orientation_manifold.h"
#include "cost_functions/losses.h"
#include "cost_functions/priors.h"

namespace photopose::internal {

Eigen::Matrix<double, 3, 7> SimilarityRows(const Eigen::Vector3d& p,
                                           const Eigen::Vector3d& centroid, double extent) {
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
  return J;
}

int OrientationComponent(const BundlePlan& plan, int image, int column) {
  const int held = image == plan.relative_scale_image ? plan.relative_scale_axis : 6;
  return column >= held ? column + 1 : column;
}

std::string UnknownName(const Block& block, UnknownKind kind, int index, int component) {
  switch (kind) {
    case UnknownKind::kOrientation: {
      static const char* const kNames[] = {"X", "Y", "Z", "omega", "phi", "kappa"};
      return "image '" + block.images[index].name + "': " + kNames[std::clamp(component, 0, 5)];
    }
    case UnknownKind::kCalibration:
      return "camera '" + block.cameras[index].camera_id + "': the self-calibrated " +
             CameraModelParamNames(block.cameras[index].model)[component];
    case UnknownKind::kLeverArm: {
      static const char* const kAxes[] = {"x", "y", "z"};
      return std::string("the lever arm's ") + kAxes[std::clamp(component, 0, 2)] +
             " (camera frame)";
    }
  }
  return "";
}

// A robust round that reached its iteration limit has stalled, not failed: on a tie point whose
// marks disagree with no majority (one of two marks gross, two of three), the misfit can sit in
// either mark, and with both residuals outside the loss's quadratic zone the robust cost is almost
// linear along the point's move. Reweighting (Ceres models a concave loss by it alone, with no
// second-order correction for rho'' < 0; the Taylor solver is iteratively reweighted least
// squares) gives a curvature the linear cost does not have, so every step goes a fraction of the
// way: the cost falls by the same amount each iteration (step quality 2: the model predicts half
// the actual decrease) for hundreds or thousands of iterations (measured in docs/performance.md,
// "Robust tie loss"). The data cannot say which mark is wrong; least squares splits the misfit
// between them, where the rejection's w-tests see it. A round that failed otherwise (a singular
// system, no decrease) stays a failure.
bool TieLossStalled(SolverTermination termination, LossType tie_loss) {
  return termination == SolverTermination::kNoConvergence && tie_loss != LossType::kNone;
}

std::string TieLossStalledMessage(int round, LossType tie_loss, int stalled_iterations) {
  return "round " + std::to_string(round) + ": the " + std::string(EnumName(tie_loss)) +
         " tie loss stalled (no convergence in " + std::to_string(stalled_iterations) +
         " iterations: tie marks outside its quadratic zone on points whose marks disagree); "
         "adjusted by least squares from there, blunders left to the rejection";
}

std::string RelativeGaugeInWords(const Block& block, const BundlePlan& plan) {
  const char* axes = "XYZ";
  return "image '" + block.images[plan.relative_fixed_image].name + "' held fixed and the " +
         std::string(1, axes[plan.relative_scale_axis]) + " coordinate of image '" +
         block.images[plan.relative_scale_image].name + "' fixes the scale";
}

namespace {

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

// A position that holds the datum: its coordinates, and whether it fixes the height (a camera
// position without height fixes X and Y only).
struct DatumPosition {
  Eigen::Vector3d position_m;
  bool fixes_height = true;
};

// Rows of the datum Jacobian of one fixed position (internal/bundle_problem.h), gathered; the Z row
// is zero for a position that does not fix the height.
void AddDatumRows(const DatumPosition& p, const Eigen::Vector3d& centroid, double extent,
                  std::vector<Eigen::Matrix<double, 3, 7>>* rows) {
  rows->push_back(SimilarityRows(p.position_m, centroid, extent));
  if (!p.fixes_height) rows->back().row(2).setZero();
}

// COLMAP's gauge for a relative block (no control points, camera positions or attitudes): the
// first image fixed; of the second, the centre coordinate farthest from the first image's fixes
// the scale.
Status PlanRelativeGauge(const Block& block, BundlePlan* plan) {
  plan->datum = BundleDatum::kRelative;
  if (block.images.size() < 2) return Status::Error("a relative block needs two images");
  plan->relative_fixed_image = 0;
  plan->relative_scale_image = 1;
  const Eigen::Vector3d baseline =
      block.images[1].eo->center_in_ground() - block.images[0].eo->center_in_ground();
  baseline.cwiseAbs().maxCoeff(&plan->relative_scale_axis);
  if (!(baseline.norm() > 0.0))
    return Status::Error("a relative block needs its first two images at different positions");
  plan->datum_description = "relative: no control points and no camera positions; " +
                            RelativeGaugeInWords(block, *plan) +
                            " (COLMAP's convention); coordinates are in the frame of the input";
  return Status::Ok();
}

// The singular values of the scaled datum Jacobian of the fixed positions and, when
// fixed_rotation, an attitude: how well they fix the seven similarity parameters.
Eigen::VectorXd DatumSingularValues(const std::vector<DatumPosition>& fixed_positions,
                                    bool fixed_rotation) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : fixed_positions) centroid += p.position_m;
  if (!fixed_positions.empty()) centroid /= static_cast<double>(fixed_positions.size());
  double extent = 0.0;
  for (const auto& p : fixed_positions) extent += (p.position_m - centroid).squaredNorm();
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
  return Eigen::JacobiSVD<Eigen::MatrixXd>(D).singularValues();
}

// The datum: what fixes the seven similarity parameters of the block (control points, camera
// positions, attitudes, held images and points), or COLMAP's gauge for a relative block. A weak
// datum is refused with the reason when plan->refuse_weak_datum, else left to the round.
Status CheckDatum(const BundleAdjustmentConfig& config, const Block& block, BundlePlan* plan) {
  std::vector<DatumPosition> fixed_positions;
  int num_control = 0, num_held = 0, num_cameras = 0, num_horizontal = 0, num_attitudes = 0;
  bool fixed_rotation = false;
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan->point_in_problem[p]) continue;
    if (plan->point_prior[p] || config.constant_points.count(static_cast<int>(p))) {
      fixed_positions.push_back({block.points[p].role == PointRole::kTie
                                     ? *block.points[p].position_m
                                     : *block.points[p].surveyed_m});
      ++(plan->point_prior[p] ? num_control : num_held);
    }
  }
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (plan->image_prior[i] || config.constant_images.count(static_cast<int>(i))) {
      const bool horizontal = plan->image_prior[i] && !plan->image_prior_height[i];
      fixed_positions.push_back({plan->image_prior[i] ? *block.images[i].measured_center_m
                                                      : block.images[i].eo->center_in_ground(),
                                 !horizontal});
      ++num_cameras;
      num_horizontal += horizontal;
    }
    if (plan->image_attitude[i] || config.constant_images.count(static_cast<int>(i))) {
      fixed_rotation = true;
      ++num_attitudes;
    }
  }
  if (fixed_positions.empty() && !fixed_rotation) return PlanRelativeGauge(block, plan);
  std::ostringstream what;
  if (num_held > 0) what << num_held << " point" << (num_held == 1 ? "" : "s") << " held fixed, ";
  what << num_control << " control point" << (num_control == 1 ? "" : "s") << ", " << num_cameras
       << " camera position" << (num_cameras == 1 ? "" : "s");
  if (num_horizontal > 0) what << " (" << num_horizontal << " without height)";
  if (num_attitudes > 0)
    what << ", " << num_attitudes << " attitude" << (num_attitudes == 1 ? "" : "s");
  const std::string weighted =
      num_held > 0 ? " (the rest weighted as stated)" : " weighted as stated";
  plan->datum = BundleDatum::kControl;
  if (!plan->refuse_weak_datum) {
    plan->datum_description = "absolute: " + what.str() + weighted +
                              " (a datum defect shows as a singular reduced normal matrix)";
    return Status::Ok();
  }
  const Eigen::VectorXd s = DatumSingularValues(fixed_positions, fixed_rotation);
  if (s.size() < 7 || !(s[6] > kDatumConditioning * s[0])) {
    int rank = 0;
    for (int k = 0; k < s.size(); ++k) rank += s[k] > kDatumConditioning * s[0];
    std::string why, remedy = "add control points off that line or camera positions";
    const bool any_height = std::any_of(fixed_positions.begin(), fixed_positions.end(),
                                        [](const DatumPosition& p) { return p.fixes_height; });
    if (num_horizontal > 0 && !any_height) {
      why = "no position has a height: the vertical is free";
      remedy = "add control points or camera positions with a height";
    } else if (fixed_positions.size() <= 2 && !fixed_rotation) {
      why = "fewer than three positions cannot fix the rotation";
    } else {
      why = "the positions lie on one line (the rotation about it is free)";
    }
    return Status::Error("no datum: the " + what.str() + " fix only " + std::to_string(rank) +
                         " of the 7 similarity parameters of the block (" + why + "); " + remedy);
  }
  plan->datum_description = "absolute: " + what.str() + weighted;
  return Status::Ok();
}

}  // namespace

namespace {

// Which parameters of each camera are estimated (self-calibration), from the config.
Status PlanCalibration(const BundleAdjustmentConfig& config, const Block& block, BundlePlan* plan) {
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
        return Status::Error("camera '" + block.cameras[c].camera_id + "': parameter index " +
                             std::to_string(index) + " out of range");
    plan->calibrated[c] = indices;
  }
  return Status::Ok();
}

// Marks in the adjustment: of control and tie points (check points stay out), each with its
// group's sigma (core/mark_weight.h). Every image needs an initial orientation.
Status PlanMarks(const BundleAccuracies& accuracies, const Block& block, BundlePlan* plan) {
  std::vector<std::string> missing_eo;
  for (size_t i = 0; i < block.images.size(); ++i)
    if (!block.images[i].eo) missing_eo.push_back(block.images[i].name);
  if (!missing_eo.empty()) {
    return Status::Error("images without initial exterior orientation: " + Names(missing_eo) +
                         " (give a frames table or let the initialisation orient them)");
  }
  const MarkSigmaDefaults tie = GroupMarkDefaults(accuracies, kTieMarks);
  const MarkSigmaDefaults control = GroupMarkDefaults(accuracies, kControlMarks);
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    const PointRole role = block.points[mark.point].role;
    if (role == PointRole::kCheck) continue;
    const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
    const bool is_control = role == PointRole::kControl;
    plan->mark_sigma[m] = MarkSigma(mark, camera, is_control ? control : tie);
    plan->mark_group[m] = is_control ? kControlMarks : kTieMarks;
    plan->mark_used[m] = 1;
  }
  return Status::Ok();
}

// Points in the adjustment: tie points need a start and two rays (a tie point with one ray adds
// nothing); control points seen at least once, with their prior unless held constant.
void PlanPoints(const BundleAdjustmentConfig& config, const Block& block, BundlePlan* plan) {
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
    if (point.role == PointRole::kTie && !point.position_m) {
      // Not intersected by the initialisation (rays too close to parallel, or marks that do not
      // meet): left out like a one-ray point, and listed in the summary.
      for (const int m : block.marks_of_point[p]) plan->mark_used[m] = 0;
      plan->tie_points_left_out.push_back(static_cast<int>(p));
      continue;
    }
    plan->point_in_problem[p] = 1;
    if (point.role == PointRole::kControl && !config.constant_points.count(static_cast<int>(p)))
      plan->point_prior[p] = 1;
    if (point.role == PointRole::kControl && point.accuracy_m)
      plan->point_sigma[p] = *point.accuracy_m;
  }
}

Status CheckMarksPerImage(const Block& block, const BundlePlan& plan) {
  for (size_t i = 0; i < block.images.size(); ++i) {
    int count = 0;
    for (const int m : block.marks_of_image[i]) count += plan.mark_used[m];
    if (count < kMinMarksPerImage) {
      return Status::Error("image '" + block.images[i].name + "' has " + std::to_string(count) +
                           " usable marks; an image needs at least " +
                           std::to_string(kMinMarksPerImage) +
                           " (marks of control points and of tie points seen in two images)");
    }
  }
  return Status::Ok();
}

// Camera-position and attitude priors of the images that are adjusted.
// A position without height constrains X and Y: its Z sigma is +infinity (no weight), its rows two.
Status PlanImagePriors(const BundlePlanOptions& options, const BundleAdjustmentConfig& config,
                       const Block& block, BundlePlan* plan) {
  const BundleAccuracies& acc = options.accuracies;
  plan->image_prior.assign(block.images.size(), 0);
  plan->image_prior_sigma.assign(block.images.size(), acc.camera_m);
  plan->image_prior_height.assign(block.images.size(), 1);
  plan->image_attitude.assign(block.images.size(), 0);
  plan->image_attitude_sigma.assign(block.images.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    if (config.constant_images.count(static_cast<int>(i))) continue;
    if (image.measured_center_m && (image.center_accuracy_m || acc.camera_positions_are_priors)) {
      plan->image_prior[i] = 1;
      if (image.center_accuracy_m) plan->image_prior_sigma[i] = *image.center_accuracy_m;
      if (!image.center_height_measured) {
        plan->image_prior_height[i] = 0;
        plan->image_prior_sigma[i].z() = std::numeric_limits<double>::infinity();
      }
    }
    if (image.measured_angles_rad && (image.attitude_accuracy_rad || acc.attitude_deg)) {
      plan->image_attitude[i] = 1;
      plan->image_attitude_sigma[i] =
          image.attitude_accuracy_rad
              ? *image.attitude_accuracy_rad
              : Eigen::Vector3d::Constant(DegreesToRadians(*acc.attitude_deg));
    }
  }
  return Status::Ok();
}

// Connectivity: images joined by the points they share; an error names the parts.
Status CheckConnected(const Block& block, const BundlePlan& plan) {
  std::vector<int> parent(block.images.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p]) continue;
    int first = -1;
    for (const int m : block.marks_of_point[p]) {
      if (!plan.mark_used[m]) continue;
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
  if (components.size() <= 1) return Status::Ok();
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

}  // namespace

MarkSigmaDefaults GroupMarkDefaults(const BundleAccuracies& accuracies, BundleGroup group) {
  MarkSigmaDefaults defaults;
  const bool control = group == kControlMarks;
  defaults.pixel_px = control ? accuracies.marker_projection_px : accuracies.tie_px;
  defaults.film_um = control ? accuracies.marker_projection_film_um : accuracies.tie_film_um;
  defaults.film_from_pixel_size = true;
  return defaults;
}

BundlePlanOptions PlanOptionsOf(const BundleAdjustmentOptions& options,
                                const BundleAdjustmentConfig& config) {
  BundlePlanOptions plan_options;
  plan_options.accuracies = options.accuracies;
  plan_options.use_lever = config.lever_arm_m.has_value() || config.estimate_lever_arm;
  plan_options.refuse_weak_datum = true;
  return plan_options;
}

Status MakeBundlePlan(const BundlePlanOptions& options, const BundleAdjustmentConfig& config,
                      const Block& block, BundlePlan* plan) {
  const BundleAccuracies& acc = options.accuracies;
  *plan = BundlePlan();
  const size_t num_marks = block.marks.size();
  plan->mark_used.assign(num_marks, 0);
  plan->mark_sigma.assign(num_marks, 1.0);
  plan->mark_group.assign(num_marks, kTieMarks);
  plan->point_in_problem.assign(block.points.size(), 0);
  plan->point_prior.assign(block.points.size(), 0);
  plan->point_sigma.assign(block.points.size(), Eigen::Vector3d::Constant(acc.marker_m));
  plan->refuse_weak_datum = options.refuse_weak_datum;
  plan->use_lever = options.use_lever;
  PHOTOPOSE_RETURN_IF_ERROR(PlanCalibration(config, block, plan));
  PHOTOPOSE_RETURN_IF_ERROR(PlanMarks(acc, block, plan));
  PlanPoints(config, block, plan);
  PHOTOPOSE_RETURN_IF_ERROR(CheckMarksPerImage(block, *plan));
  PHOTOPOSE_RETURN_IF_ERROR(PlanImagePriors(options, config, block, plan));
  PHOTOPOSE_RETURN_IF_ERROR(CheckConnected(block, *plan));
  return CheckDatum(config, block, plan);
}

Status RecheckBundlePlan(const BundleAdjustmentConfig& config, const Block& block,
                         BundlePlan* plan) {
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan->point_in_problem[p]) continue;
    int rays = 0;
    for (const int m : block.marks_of_point[p]) rays += plan->mark_used[m];
    const bool tie_like =
        !plan->point_prior[p] && !config.constant_points.count(static_cast<int>(p));
    if (rays == 0 || (tie_like && rays < 2)) {
      for (const int m : block.marks_of_point[p]) plan->mark_used[m] = 0;
      plan->point_in_problem[p] = 0;
      plan->point_prior[p] = 0;
    }
  }
  for (size_t i = 0; i < block.images.size(); ++i) {
    int count = 0;
    for (const int m : block.marks_of_image[i]) count += plan->mark_used[m];
    if (count < kMinMarksPerImage) {
      return Status::Error("image '" + block.images[i].name + "' keeps " + std::to_string(count) +
                           " marks: too few to orient it");
    }
  }
  const BundleDatum datum = plan->datum;
  PHOTOPOSE_RETURN_IF_ERROR(CheckDatum(config, block, plan));
  if (plan->datum != datum) return Status::Error("the block lost its datum");
  return Status::Ok();
}

namespace {

// An e block of the round: its tangent size, ambient size and manifold (null: none).
void AddEBlock(double* values, int tangent, int ambient, const ceres::Manifold* manifold,
               BundleRound* round) {
  round->e_blocks.push_back(values);
  round->e_sizes.push_back(tangent);
  round->e_ambient_sizes.push_back(ambient);
  round->e_manifolds.push_back(manifold);
}

// Exterior orientations with their manifold (one shared; the relative gauge's second image gets
// one with a fixed coordinate).
void AddOrientationBlocks(const BundleAdjustmentConfig& config, const Block& block,
                          const BundlePlan& plan, BundleState* state, BundleRound* round) {
  ceres::Problem* problem = round->problem.get();  // null: a round of rows alone
  round->manifolds.emplace_back(new ExteriorOrientationManifold());
  ceres::Manifold* eo_manifold = round->manifolds.back().get();
  for (size_t i = 0; i < block.images.size(); ++i) {
    double* eo = state->eo[i].data();
    if (problem != nullptr) problem->AddParameterBlock(eo, kExteriorOrientationSize);
    const bool constant = config.constant_images.count(static_cast<int>(i)) ||
                          static_cast<int>(i) == plan.relative_fixed_image;
    if (constant) {
      if (problem != nullptr) problem->SetParameterBlockConstant(eo);
      continue;
    }
    ceres::Manifold* manifold = eo_manifold;
    int tangent = kExteriorOrientationSize;
    if (static_cast<int>(i) == plan.relative_scale_image) {
      std::array<bool, 6> fixed{};
      fixed[plan.relative_scale_axis] = true;
      round->manifolds.emplace_back(new ExteriorOrientationManifold(fixed));
      manifold = round->manifolds.back().get();
      tangent = 5;
    }
    if (problem != nullptr) problem->SetManifold(eo, manifold);
    AddEBlock(eo, tangent, kExteriorOrientationSize, manifold, round);
  }
}

// Camera parameters: constant except the calibrated ones; the lever arm when used.
void AddCameraBlocks(const BundleAdjustmentConfig& config, const Block& block,
                     const BundlePlan& plan, BundleState* state, BundleRound* round) {
  ceres::Problem* problem = round->problem.get();  // null: a round of rows alone
  round->cameras.assign(block.cameras.size(), CollinearityCamera());
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    double* params = state->cameras[c].data();
    const int n = static_cast<int>(state->cameras[c].size());
    const std::vector<int>& free = plan.calibrated[c];
    round->cameras[c].model = block.cameras[c].model;
    round->cameras[c].data = block.cameras[c].data();
    round->cameras[c].earth_radius_m = block.cameras[c].earth_curvature_radius_m();
    if (free.empty()) {
      // Held constant: data of its marks' costs, not a parameter block.
      round->cameras[c].constant_params = params;
      continue;
    }
    if (problem != nullptr) problem->AddParameterBlock(params, n);
    ceres::Manifold* manifold = nullptr;
    if (static_cast<int>(free.size()) < n) {
      std::vector<int> constant;
      for (int k = 0; k < n; ++k)
        if (!std::binary_search(free.begin(), free.end(), k)) constant.push_back(k);
      round->manifolds.emplace_back(new ceres::SubsetManifold(n, constant));
      manifold = round->manifolds.back().get();
      if (problem != nullptr) problem->SetManifold(params, manifold);
    }
    AddEBlock(params, static_cast<int>(free.size()), n, manifold, round);
  }
  double* lever = state->lever.data();
  if (plan.use_lever) {
    if (problem != nullptr) problem->AddParameterBlock(lever, 3);
    if (config.estimate_lever_arm)
      AddEBlock(lever, 3, 3, nullptr, round);
    else if (problem != nullptr)
      problem->SetParameterBlockConstant(lever);
  }
}

void AddPointBlocks(const BundleAdjustmentConfig& config, const Block& block,
                    const BundlePlan& plan, BundleState* state, BundleRound* round) {
  ceres::Problem* problem = round->problem.get();  // null: a round of rows alone
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p]) continue;
    double* point = state->points[p].data();
    if (problem != nullptr) problem->AddParameterBlock(point, kPointSize);
    if (config.constant_points.count(static_cast<int>(p))) {
      if (problem != nullptr) problem->SetParameterBlockConstant(point);
      continue;
    }
    round->point_blocks.push_back(point);
    round->point_of_block.push_back(static_cast<int>(p));
  }
}

// What residual block `info` is made of: its parameter blocks (in its cost's order) and, when
// `cost` is not null, its cost (new; *inside: a mark's functor in it, may be null). The one rule of
// both kinds of round: a problem's residual blocks are built by it, a round of rows alone makes
// them by it when asked (ResidualBlockOf).
void NewResidualBlock(JacobianType jacobian, const Block& block, const BundlePlan& plan,
                      BundleState* state, const BundleRound& round, const ResidualInfo& info,
                      std::vector<double*>* parameters, ceres::CostFunction** cost,
                      CollinearityMarkFunctor** inside) {
  parameters->clear();
  switch (info.group) {
    case kTieMarks:
    case kControlMarks: {
      const BlockMark& mark = block.marks[info.item];
      const int camera_index = block.images[mark.image].camera;
      const CollinearityCamera& camera = round.cameras[camera_index];
      parameters->push_back(state->eo[mark.image].data());
      parameters->push_back(state->points[mark.point].data());
      if (camera.constant_params == nullptr)
        parameters->push_back(state->cameras[camera_index].data());
      if (cost != nullptr) {
        *cost = CreateCollinearityMarkCost(
            jacobian,
            CollinearityMarkFunctor(&camera, mark.observation, 1.0 / plan.mark_sigma[info.item]),
            inside);
      }
      return;
    }
    case kControlPoints: {
      // Two rows at a time: XY (first axis 0), then Z (first axis 2).
      const int p = info.item;
      parameters->push_back(state->points[p].data());
      if (cost == nullptr) return;
      const Eigen::Vector3d& surveyed = *block.points[p].surveyed_m;
      *cost = info.first_axis == 0 ? new GroundPointPriorRows(surveyed, plan.point_sigma[p], 0, 1)
                                   : new GroundPointPriorRows(surveyed, plan.point_sigma[p], 2, -1);
      return;
    }
    case kCameraPositions: {
      const int i = info.item;
      parameters->push_back(state->eo[i].data());
      if (plan.use_lever) parameters->push_back(state->lever.data());
      if (cost == nullptr) return;
      const Eigen::Vector3d& measured = *block.images[i].measured_center_m;
      *cost = plan.use_lever
                  ? CameraPositionLeverArmPrior::Create(measured, plan.image_prior_sigma[i])
                  : new CameraPositionPrior(measured, plan.image_prior_sigma[i]);
      return;
    }
    case kAttitudes: {
      const int i = info.item;
      parameters->push_back(state->eo[i].data());
      if (cost == nullptr) return;
      *cost = new AttitudePrior(*block.images[i].measured_angles_rad, plan.image_attitude_sigma[i]);
      return;
    }
    default:
      LOG(FATAL) << "no residual block of group " << static_cast<int>(info.group);
  }
}

// Residual block `info` into the round: built into its problem (the cost kept by the round, the
// loss `loss`), or listed alone in a round of rows alone.
void AddResidual(const BundleAdjustmentOptions& options, const Block& block, const BundlePlan& plan,
                 BundleState* state, ResidualInfo info, const ceres::LossFunction* loss,
                 BundleRound* round) {
  if (round->problem != nullptr) {
    thread_local std::vector<double*> parameters;
    ceres::CostFunction* cost = nullptr;
    CollinearityMarkFunctor** inside = info.group == kTieMarks || info.group == kControlMarks
                                           ? &round->mark_functor[info.item]
                                           : nullptr;
    NewResidualBlock(options.solver.jacobian, block, plan, state, *round, info, &parameters, &cost,
                     inside);
    round->costs.emplace_back(cost);
    info.id =
        round->problem->AddResidualBlock(cost, const_cast<ceres::LossFunction*>(loss),
                                         parameters.data(), static_cast<int>(parameters.size()));
  }
  round->residuals.push_back(info);
}

// The collinearity residual of every mark in use, weighted by its sigma; the tie loss on tie
// marks.
void AddMarkResiduals(const BundleAdjustmentOptions& options, const Block& block,
                      const BundlePlan& plan, BundleState* state, BundleRound* round) {
  const size_t num_used = std::count(plan.mark_used.begin(), plan.mark_used.end(), 1);
  round->residuals.reserve(num_used + 2 * block.points.size() + 2 * block.images.size());
  if (round->problem != nullptr) {
    round->costs.reserve(num_used + 2 * block.points.size() + 2 * block.images.size());
    round->mark_functor.assign(block.marks.size(), nullptr);
  }
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!plan.mark_used[m]) continue;
    const ceres::LossFunction* loss =
        plan.mark_group[m] == kTieMarks ? round->tie_loss.get() : nullptr;
    AddResidual(options, block, plan, state,
                MakeResidualInfo(plan.mark_group[m], static_cast<int>(m), 2, 0), loss, round);
  }
}

// Control-point priors (two rows at a time: XY, then Z), camera positions and attitudes.
void AddPriorResiduals(const BundleAdjustmentOptions& options, const Block& block,
                       const BundlePlan& plan, BundleState* state, BundleRound* round) {
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p] || !plan.point_prior[p]) continue;
    AddResidual(options, block, plan, state,
                MakeResidualInfo(kControlPoints, static_cast<int>(p), 2, 0), nullptr, round);
    AddResidual(options, block, plan, state,
                MakeResidualInfo(kControlPoints, static_cast<int>(p), 1, 2), nullptr, round);
  }
  for (size_t i = 0; i < block.images.size(); ++i) {
    // Without height the Z row has a zero weight (its sigma is infinite) and is not counted.
    if (plan.image_prior[i]) {
      AddResidual(
          options, block, plan, state,
          MakeResidualInfo(kCameraPositions, static_cast<int>(i), ImagePriorRows(plan, i), 0),
          nullptr, round);
    }
    if (plan.image_attitude[i]) {
      AddResidual(options, block, plan, state,
                  MakeResidualInfo(kAttitudes, static_cast<int>(i), 3, 0), nullptr, round);
    }
  }
}

// The round's blocks, residuals and counts, into its problem when it has one.
void FillBundleRound(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                     const Block& block, const BundlePlan& plan, BundleState* state,
                     BundleRound* round) {
  round->block = &block;
  round->plan = &plan;
  round->state = state;
  round->jacobian = options.solver.jacobian;
  round->tie_loss.reset(
      MakeLoss(options.robustness.tie_loss, options.robustness.tie_loss_scale_sigmas));
  AddOrientationBlocks(config, block, plan, state, round);
  AddCameraBlocks(config, block, plan, state, round);
  AddPointBlocks(config, block, plan, state, round);
  AddMarkResiduals(options, block, plan, state, round);
  AddPriorResiduals(options, block, plan, state, round);
  round->num_free_parameters = 3 * static_cast<int>(round->point_blocks.size());
  for (const int size : round->e_sizes) round->num_free_parameters += size;
  round->num_observations = 0;
  for (const ResidualInfo& info : round->residuals) round->num_observations += info.rows;
}

}  // namespace

ResidualInfo MakeResidualInfo(BundleGroup group, int item, int rows, int first_axis) {
  ResidualInfo info;
  info.item = item;
  info.group = group;
  info.rows = static_cast<std::int8_t>(rows);
  info.first_axis = static_cast<std::int8_t>(first_axis);
  return info;
}

BundleState StartState(const BundleAdjustmentConfig& config, const Block& block) {
  BundleState state;
  for (const BlockImage& image : block.images) state.eo.push_back(image.eo->parameters);
  for (const BlockPoint& point : block.points) {
    state.points.push_back(point.position_m   ? *point.position_m
                           : point.surveyed_m ? *point.surveyed_m
                                              : Eigen::Vector3d::Zero());
  }
  for (const BlockCamera& camera : block.cameras) state.cameras.push_back(camera.params);
  if (config.lever_arm_m) state.lever = *config.lever_arm_m;
  return state;
}

void BuildBundleRound(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                      const Block& block, const BundlePlan& plan, BundleState* state,
                      BundleRound* round) {
  round->problem.reset();
  *round = BundleRound();
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = false;
  round->problem = std::make_unique<ceres::Problem>(problem_options);
  FillBundleRound(options, config, block, plan, state, round);
}

void BuildBundleRoundRows(const BundleAdjustmentOptions& options,
                          const BundleAdjustmentConfig& config, const Block& block,
                          const BundlePlan& plan, BundleState* state, BundleRound* round) {
  round->problem.reset();
  *round = BundleRound();
  FillBundleRound(options, config, block, plan, state, round);
}

const ceres::CostFunction* ResidualBlockOf(const BundleRound& round, const ResidualInfo& info,
                                           std::unique_ptr<ceres::CostFunction>* made,
                                           std::vector<double*>* parameters) {
  if (round.problem != nullptr) {
    round.problem->GetParameterBlocksForResidualBlock(info.id, parameters);
    return round.problem->GetCostFunctionForResidualBlock(info.id);
  }
  ceres::CostFunction* cost = nullptr;
  NewResidualBlock(round.jacobian, *round.block, *round.plan, round.state, round, info, parameters,
                   &cost, nullptr);
  made->reset(cost);
  return cost;
}

void ResidualParameters(const BundleRound& round, const ResidualInfo& info,
                        std::vector<double*>* parameters) {
  if (round.problem != nullptr) {
    round.problem->GetParameterBlocksForResidualBlock(info.id, parameters);
    return;
  }
  NewResidualBlock(round.jacobian, *round.block, *round.plan, round.state, round, info, parameters,
                   nullptr, nullptr);
}

bool UpdateBundleRound(const BundlePlan& plan, BundleRound* round) {
  // Only marks and the tie points they leave behind: a prior removed or a weight changed needs
  // the problem built again; a round of rows alone is built again in any case (it is cheap).
  if (round->problem == nullptr) return false;
  for (const ResidualInfo& info : round->residuals) {
    switch (info.group) {
      case kTieMarks:
      case kControlMarks:
        if (plan.mark_used[info.item] &&
            round->mark_functor[info.item]->inverse_sigma != 1.0 / plan.mark_sigma[info.item])
          return false;
        break;
      case kControlPoints:
        if (!plan.point_prior[info.item]) return false;
        break;
      case kCameraPositions:
        if (!plan.image_prior[info.item]) return false;
        break;
      case kAttitudes:
        if (!plan.image_attitude[info.item]) return false;
        break;
      default:
        return false;
    }
  }
  const auto switched_off = [&](const ResidualInfo& info) {
    if (info.group != kTieMarks && info.group != kControlMarks) return false;
    if (plan.mark_used[info.item]) return false;
    round->mark_functor[info.item]->inverse_sigma = 0.0;
    return true;
  };
  round->residuals.erase(
      std::remove_if(round->residuals.begin(), round->residuals.end(), switched_off),
      round->residuals.end());
  size_t kept = 0;
  for (size_t k = 0; k < round->point_blocks.size(); ++k) {
    const int p = round->point_of_block[k];
    if (!plan.point_in_problem[p]) {
      round->problem->SetParameterBlockConstant(round->point_blocks[k]);
      continue;
    }
    round->point_blocks[kept] = round->point_blocks[k];
    round->point_of_block[kept] = p;
    ++kept;
  }
  round->point_blocks.resize(kept);
  round->point_of_block.resize(kept);
  round->num_free_parameters = 3 * static_cast<int>(round->point_blocks.size());
  for (const int size : round->e_sizes) round->num_free_parameters += size;
  round->num_observations = 0;
  for (const ResidualInfo& info : round->residuals) round->num_observations += info.rows;
  return true;
}

bool MoveToRelativeGauge(const BundlePlan& plan, const Vector6d& fixed_eo, double fixed_coordinate,
                         std::vector<Vector6d>* eo_seed, std::vector<Eigen::Vector3d>* points) {
  const int first = plan.relative_fixed_image;
  const int second = plan.relative_scale_image;
  const int axis = plan.relative_scale_axis;
  const Eigen::Vector3d c0 = (*eo_seed)[first].head<3>();
  const Eigen::Matrix3d R0 =
      RotationFromAngles(RotationConvention::kSeed, (*eo_seed)[first].tail<3>());
  const Eigen::Matrix3d R0_fixed =
      RotationFromAngles(RotationConvention::kSeed, fixed_eo.tail<3>());
  const Eigen::Vector3d c0_fixed = fixed_eo.head<3>();
  // R_camera_from_ground' = R R_s^T, so R_s = R0_fixed^T R0 returns the first image's attitude.
  const Eigen::Matrix3d R_s = R0_fixed.transpose() * R0;
  const double along = (R_s * ((*eo_seed)[second].head<3>() - c0))[axis];
  const double scale = (fixed_coordinate - c0_fixed[axis]) / along;
  if (!std::isfinite(scale) || !(scale > 0.0)) return false;
  const auto move = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return c0_fixed + scale * (R_s * (x - c0));
  };
  for (Vector6d& eo : *eo_seed) {
    const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.tail<3>());
    Eigen::Vector3d angles = AnglesFromRotation(RotationConvention::kSeed, R * R_s.transpose());
    // Keep every angle within pi of its previous value (no 2 pi jumps in the output).
    for (int k = 0; k < 3; ++k)
      angles[k] += 2.0 * M_PI * std::round((eo[3 + k] - angles[k]) / (2.0 * M_PI));
    eo.head<3>() = move(eo.head<3>());
    eo.tail<3>() = angles;
  }
  for (size_t p = 0; p < points->size(); ++p)
    if (plan.point_in_problem[p]) (*points)[p] = move((*points)[p]);
  // Exactly the fixed values (no rounding left in the held parameters).
  (*eo_seed)[first] = fixed_eo;
  (*eo_seed)[second][axis] = fixed_coordinate;
  return true;
}

void ApplyRelativeGauge(const BundlePlan& plan, BundleState* state, BundleRound* round) {
  ceres::Problem& problem = *round->problem;
  double* fixed = state->eo[plan.relative_fixed_image].data();
  double* scale = state->eo[plan.relative_scale_image].data();
  problem.SetParameterBlockConstant(fixed);
  std::array<bool, 6> axis{};
  axis[plan.relative_scale_axis] = true;
  round->manifolds.emplace_back(new ExteriorOrientationManifold(axis));
  problem.SetManifold(scale, round->manifolds.back().get());
  for (size_t k = 0; k < round->e_blocks.size(); ++k) {
    if (round->e_blocks[k] != scale) continue;
    round->e_sizes[k] = 5;
    round->e_manifolds[k] = round->manifolds.back().get();
  }
  for (size_t k = 0; k < round->e_blocks.size(); ++k) {
    if (round->e_blocks[k] != fixed) continue;
    round->e_blocks.erase(round->e_blocks.begin() + k);
    round->e_sizes.erase(round->e_sizes.begin() + k);
    round->e_ambient_sizes.erase(round->e_ambient_sizes.begin() + k);
    round->e_manifolds.erase(round->e_manifolds.begin() + k);
    break;
  }
  round->num_free_parameters = 3 * static_cast<int>(round->point_blocks.size());
  for (const int size : round->e_sizes) round->num_free_parameters += size;
}

ceres::Solver::Options CeresSolverOptions(const BundleAdjustmentOptions& options,
                                          const BundleRound& round) {
  ceres::Solver::Options solver;
  solver.max_num_iterations = options.solver.max_iterations;
  solver.function_tolerance = options.solver.function_tolerance;
  solver.parameter_tolerance = options.solver.parameter_tolerance;
  solver.gradient_tolerance = options.solver.gradient_tolerance;
  solver.num_threads = ResolveThreadCount(options.solver.num_threads);
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  switch (options.solver.linear_solver) {
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

}  // namespace photopose::internal
