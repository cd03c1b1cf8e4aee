// The Taylor bundle adjustment (taylor_bundle.h): options, the plan (internal::MakeBundlePlan plus
// its own ideal film points), the Gauss-Newton rounds, rejection and the results. The normal
// equations (layout, linearisation, elimination, factorisation, covariances) are the other stage,
// in taylor_bundle_normals.cc. One file past ~800 lines on purpose: the rounds, the
// Levenberg-Marquardt step control, the free gauge and the results share one context (Context),
// and each step is a named function; the normal equations are the other stage.
#include "solvers/bundle/taylor_bundle.h"

#include <glog/logging.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>

#include "core/camera_models.h"
#include "core/io/csv.h"
#include "core/parallel.h"
#include "core/rotation.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/bundle_rounds.h"
#include "solvers/bundle/internal/bundle_statistics.h"
#include "solvers/bundle/internal/selected_inversion.h"
#include "solvers/bundle/internal/taylor_normals.h"
#include "solvers/resection/taylor_resection.h"

namespace photopose {
namespace {

using Clock = std::chrono::steady_clock;
using internal::taylor::BuildLayout;
using internal::taylor::DenseRows;
using internal::taylor::EvaluateCost;
using internal::taylor::Factorize;
using internal::taylor::Frame;
using internal::taylor::IsFixed;
using internal::taylor::Layout;
using internal::taylor::Linearize;
using internal::taylor::MakeFrame;
using internal::taylor::MakePlan;
using internal::taylor::Normal;
using internal::taylor::Plan;
using internal::taylor::PointPartialsFromCentrePartials;
using internal::taylor::PredictedDecrease;
using internal::taylor::Reduce;
using internal::taylor::Reduction;
using internal::taylor::SolveCorrections;
using internal::taylor::State;
using internal::taylor::WriteScaled;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// Multiple of epsilon times the block's size below which a position correction is rounding noise.
constexpr double kPositionResolutionFactor = 256.0;
// A relative change of the cost (a sum of up to millions of rounded squares) below which its
// change says nothing about a step: Ceres' default function tolerance (unitless).
constexpr double kCostResolution = 1e-10;
// The factor by which the Taylor round's undamped pivot ratio must clear the statistics' bound
// (internal::SelectedInversionOptions::min_pivot_ratio) to stand for their determinacy check: the
// two factorise the same reduced system in two parameterisations of the rotations (Euler angles
// here, Ceres' manifold there), whose pivot ratios differ by far less than this.
constexpr double kDeterminedMargin = 1e3;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

Status CheckSupported(const BundleAdjustmentConfig& config, const Block& block) {
  for (const int i : config.constant_images)
    if (i < 0 || i >= static_cast<int>(block.images.size()))
      return Status::Error("the config holds a non-existent image constant");
  for (const int p : config.constant_points)
    if (p < 0 || p >= static_cast<int>(block.points.size()))
      return Status::Error("the config holds a non-existent point constant");
  return Status::Ok();
}

}  // namespace

// ------------------------------------------------------------------ set-up shared by both entries
// (declared in internal/taylor_normals.h for its tests)

namespace internal::taylor {

// The plan: BundleAdjust's (a weak datum is not refused: it shows as a singular reduced normal
// matrix in the round), then the unknowns held (config, relative gauge) and each mark's ideal
// image-plane point: the frame model's correction of the measured film point, constant with a
// fixed interior orientation (the marks of a forward model or a self-calibrated camera enter as
// observed, through the model per mark: MarkEquation in taylor_bundle_normals.cc).
Status MakePlan(const TaylorBundleOptions& options, const BundleAdjustmentConfig& config,
                const Block& block, Plan* plan) {
  internal::BundlePlanOptions plan_options;
  plan_options.accuracies = options.accuracies;
  plan_options.use_lever = config.lever_arm_m.has_value() || config.estimate_lever_arm;
  plan_options.refuse_weak_datum = false;
  PHOTOPOSE_RETURN_IF_ERROR(internal::MakeBundlePlan(plan_options, config, block, plan));
  plan->estimate_lever = config.estimate_lever_arm;
  plan->image_constant.assign(block.images.size(), 0);
  plan->point_constant.assign(block.points.size(), 0);
  plan->image_fixed.assign(block.images.size(), std::array<bool, 6>{});
  for (const int i : config.constant_images) plan->image_constant[i] = 1;
  for (const int p : config.constant_points) plan->point_constant[p] = 1;
  if (plan->datum == BundleDatum::kRelative) {
    plan->image_constant[plan->relative_fixed_image] = 1;
    plan->image_fixed[plan->relative_scale_image][plan->relative_scale_axis] = true;
  }
  plan->tie_loss.reset(MakeLoss(options.tie_loss, options.tie_loss_scale_sigmas));
  FillIdealPoints(block, plan);
  return Status::Ok();
}

void FillIdealPoints(const Block& block, Plan* plan) {
  plan->ideal_um.assign(block.marks.size(), Eigen::Vector2d::Zero());
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!plan->mark_used[m]) continue;
    const BlockMark& mark = block.marks[m];
    const int c = block.images[mark.image].camera;
    const BlockCamera& camera = block.cameras[c];
    if (camera.model != CameraModelType::kFrame || !plan->calibrated[c].empty()) continue;
    FrameCorrectFilmPoint(camera.params.data(), mark.observation.data(), camera.data(),
                          plan->ideal_um[m].data());
  }
}

Frame MakeFrame(const BundleAdjustmentConfig& config, const Block& block, const Plan& plan,
                State* state) {
  Frame frame;
  state->eo.clear();
  state->points.assign(block.points.size(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> positions;
  for (const BlockImage& image : block.images) {
    state->eo.push_back(image.eo->parameters);
    positions.push_back(image.eo->center_in_ground());
  }
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    state->points[p] = point.position_m   ? *point.position_m
                       : point.surveyed_m ? *point.surveyed_m
                                          : Eigen::Vector3d::Zero();
    if (plan.point_in_problem[p]) positions.push_back(state->points[p]);
  }
  for (const Eigen::Vector3d& x : positions) frame.centroid += x;
  frame.centroid /= static_cast<double>(positions.size());
  double ssq = 0.0;
  for (const Eigen::Vector3d& x : positions) ssq += (x - frame.centroid).squaredNorm();
  frame.extent_m = std::sqrt(ssq / positions.size());
  if (!(frame.extent_m > 0.0)) frame.extent_m = 1.0;
  for (Vector6d& eo : state->eo) eo.head<3>() -= frame.centroid;
  for (Eigen::Vector3d& x : state->points) x -= frame.centroid;
  frame.surveyed.assign(block.points.size(), Eigen::Vector3d::Zero());
  for (size_t p = 0; p < block.points.size(); ++p)
    if (block.points[p].surveyed_m)
      frame.surveyed[p] = *block.points[p].surveyed_m - frame.centroid;
  frame.measured.assign(block.images.size(), Eigen::Vector3d::Zero());
  frame.focal_um.assign(block.images.size(), 0.0);
  frame.model_camera.assign(block.images.size(), nullptr);
  frame.camera_index.assign(block.images.size(), 0);
  frame.earth_radius_m.assign(block.images.size(), 0.0);
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (block.images[i].measured_center_m)
      frame.measured[i] = *block.images[i].measured_center_m - frame.centroid;
    const int c = block.images[i].camera;
    const BlockCamera& camera = block.cameras[c];
    const bool per_mark = camera.model != CameraModelType::kFrame || !plan.calibrated[c].empty();
    frame.focal_um[i] = per_mark ? 1.0 : camera.params[kFrameFocal];
    if (per_mark) frame.model_camera[i] = &camera;
    frame.camera_index[i] = c;
    frame.earth_radius_m[i] = camera.earth_curvature_radius_m();
  }
  frame.use_lever = plan.use_lever;
  state->cameras.clear();
  for (const BlockCamera& camera : block.cameras) state->cameras.push_back(camera.params);
  state->lever = config.lever_arm_m.value_or(Eigen::Vector3d::Zero());
  return frame;
}

}  // namespace internal::taylor

namespace {

Status Prepare(const TaylorBundleOptions& options, const BundleAdjustmentConfig& config,
               const Block& block, Plan* plan) {
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options, "invalid options: "));
  // The lever arm moved from the options to the config; its message stays the one it had.
  if (config.lever_arm_m && !config.lever_arm_m->allFinite())
    return Status::Error("invalid options: the lever arm must be finite");
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(block));
  PHOTOPOSE_RETURN_IF_ERROR(CheckSupported(config, block));
  for (const BlockCamera& camera : block.cameras)
    if (!(CameraModelFocal(camera.model, camera.params.data()) > 0.0))
      return Status::Error("camera " + QuotedForMessage(camera.camera_id) +
                           " has no positive focal length");
  return MakePlan(options, config, block, plan);
}

std::string MarkName(const Block& block, int m) {
  const BlockMark& mark = block.marks[m];
  return "point " + QuotedForMessage(block.points[mark.point].id) + " in image " +
         QuotedForMessage(block.images[mark.image].name);
}

std::string Format(const char* format, double a, double b = 0.0) {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), format, a, b);
  return buffer;
}

// The threads worth starting: every ParallelFor starts its threads anew (tens of microseconds),
// which a small block's whole iteration does not repay; at least kMarksPerThread marks per
// thread (the 12-image block of the benchmarks, 705 marks, runs on one).
constexpr int kMarksPerThread = 1000;
int ThreadsForMarks(int num_threads, const Plan& plan) {
  const long long marks = std::count(plan.mark_used.begin(), plan.mark_used.end(), 1);
  return static_cast<int>(std::max<long long>(
      1, std::min<long long>(ResolveThreadCount(num_threads), marks / kMarksPerThread)));
}

// What one round needs besides its own structures.
struct Context {
  const TaylorBundleOptions& options;
  const Block& block;
  const Plan& plan;
  const Frame& frame;
  Clock::time_point start;
  int num_threads;  // resolved (>= 1)
};

std::string PointName(const Block& block, int p) {
  return "point " + QuotedForMessage(block.points[p].id);
}

std::string BehindMessage(const Block& block, const Normal& normal, const std::string& when) {
  std::ostringstream os;
  os << MarkName(block, normal.behind_mark) << ": the point is not in front of the camera " << when
     << " (w = " << normal.behind_w << " m)";
  return os.str();
}

// A global column in words (internal::UnknownName): a camera's self-calibrated parameter or a
// component of the lever arm.
std::string GlobalName(const Block& block, const Layout& layout, int j) {
  const int c = layout.global_camera[j];
  return c < 0 ? internal::UnknownName(block, internal::UnknownKind::kLeverArm, 0,
                                       layout.global_param[j])
               : internal::UnknownName(block, internal::UnknownKind::kCalibration, c,
                                       layout.global_param[j]);
}

// One Gauss-Newton correction from the linearisation `normal`: the points eliminated, the
// reduced system scaled, factorised and solved. False, with the reason, when it is singular.
bool SolveStep(const Context& ctx, const std::string& at, const Normal& normal, Layout* layout,
               Reduction* reduction, Eigen::VectorXd* d_e, std::vector<Eigen::Vector3d>* d_p,
               std::string* message) {
  const int singular_point = Reduce(normal, *layout, reduction);
  if (singular_point >= 0) {
    *message = PointName(ctx.block, singular_point) +
               " is not determined by its rays (its 3 x 3 normal block is singular)" + at;
    return false;
  }
  const int weightless = WriteScaled(ctx.plan, layout, reduction);
  const int cameras_size = 6 * static_cast<int>(layout->free_images.size());
  if (weightless >= cameras_size) {
    *message = GlobalName(ctx.block, *layout, weightless - cameras_size) +
               " has no weight (no observation depends on it)" + at;
    return false;
  }
  if (weightless >= 0) {
    *message = internal::UnknownName(ctx.block, internal::UnknownKind::kOrientation,
                                     layout->free_images[weightless / 6], weightless % 6) +
               " has no weight (no observation depends on it)" + at;
    return false;
  }
  if (!Factorize(ctx.options.min_pivot_ratio, *layout, reduction)) {
    if (!reduction->failure.empty()) {
      *message = "the reduced normal matrix could not be factorised" + at + ": " +
                 reduction->failure;
      return false;
    }
    reduction->singular = true;
    *message =
        Format("the reduced normal matrix is singular (pivot ratio %.3g)", reduction->pivot_ratio) +
        at +
        ": a datum defect (too few control points and camera positions, or all on one "
        "line) or an image its marks do not determine";
    return false;
  }
  SolveCorrections(ctx.plan, *layout, normal, *reduction, d_e, d_p);
  return true;
}

// The largest position and angle components of a correction and its squared norm. The lever
// arm's components count as positions (m); a calibration parameter's as the angle of view its
// correction moves the camera's marks by, RMS (Normal::global_angle_per_unit): its tolerance is
// the image shift of the angle tolerance.
void MeasureCorrections(const Layout& layout, const Normal& normal, const Eigen::VectorXd& d_e,
                        const std::vector<Eigen::Vector3d>& d_p, double* max_position,
                        double* max_angle, double* step_squared) {
  *max_position = *max_angle = 0.0;
  *step_squared = d_e.squaredNorm();
  for (size_t b = 0; b < layout.free_images.size(); ++b) {
    const Vector6d delta = d_e.segment<6>(6 * b);
    *max_position = std::max(*max_position, delta.head<3>().cwiseAbs().maxCoeff());
    *max_angle = std::max(*max_angle, delta.tail<3>().cwiseAbs().maxCoeff());
  }
  const int cameras_size = 6 * static_cast<int>(layout.free_images.size());
  for (int j = 0; j < layout.num_global; ++j) {
    const double delta = std::abs(d_e[cameras_size + j]);
    if (layout.global_camera[j] < 0) {
      *max_position = std::max(*max_position, delta);
    } else {
      *max_angle = std::max(*max_angle, delta * normal.global_angle_per_unit[j]);
    }
  }
  for (const Eigen::Vector3d& delta : d_p) {
    *max_position = std::max(*max_position, delta.cwiseAbs().maxCoeff());
    *step_squared += delta.squaredNorm();
  }
}

// Eqs. 9-14: unknown = approximation - correction.
void ApplyCorrections(const Layout& layout, const Eigen::VectorXd& d_e,
                      const std::vector<Eigen::Vector3d>& d_p, State* state) {
  for (size_t b = 0; b < layout.free_images.size(); ++b)
    state->eo[layout.free_images[b]] -= d_e.segment<6>(6 * b);
  for (size_t q = 0; q < layout.free_points.size(); ++q)
    state->points[layout.free_points[q]] -= d_p[q];
  const int cameras_size = 6 * static_cast<int>(layout.free_images.size());
  for (int j = 0; j < layout.num_global; ++j) {
    const int c = layout.global_camera[j];
    double& value =
        c < 0 ? state->lever[layout.global_param[j]] : state->cameras[c][layout.global_param[j]];
    value -= d_e[cameras_size + j];
  }
}

// True, with the message, when an image or point moved farther than divergence_m from the
// block's centroid.
bool Diverged(const Context& ctx, const Layout& layout, const State& state, double divergence_m,
              const std::string& at, std::string* message) {
  for (const int i : layout.free_images) {
    const double distance = state.eo[i].head<3>().norm();
    if (!(distance <= divergence_m)) {
      *message = "diverged" + at + ": image " + QuotedForMessage(ctx.block.images[i].name) +
                 Format(" moved %.0f m from the block's centroid", distance);
      return true;
    }
  }
  for (const int p : layout.free_points) {
    const double distance = state.points[p].norm();
    if (!(distance <= divergence_m)) {
      *message = "diverged" + at + ": " + PointName(ctx.block, p) +
                 Format(" moved %.0f m from the block's centroid", distance);
      return true;
    }
  }
  return false;
}

// Levenberg-Marquardt's decision on a step solved with damping step_lambda from the
// linearisation at cost `cost` (1/2 F^T P F): the trial state's cost, the gain ratio, and the
// next *lambda (and Nielsen's nu). True when the step is taken (*state replaced by the trial).
bool DecideStep(const Context& ctx, const Layout& layout, const Normal& normal, double cost,
                double step_lambda, const Eigen::VectorXd& d_e,
                const std::vector<Eigen::Vector3d>& d_p, State* state, double* lambda, double* nu,
                double* gain_ratio) {
  State trial = *state;
  ApplyCorrections(layout, d_e, d_p, &trial);
  const double predicted = PredictedDecrease(layout, normal, step_lambda, d_e, d_p);
  double trial_ssr = 0.0;
  int behind_mark = -1;
  const bool valid = EvaluateCost(ctx.options.partials, ctx.block, ctx.plan, layout, ctx.frame,
                                  trial, ctx.num_threads, &trial_ssr, &behind_mark);
  *gain_ratio = valid && predicted > 0.0 ? (cost - 0.5 * trial_ssr) / predicted
                                         : -std::numeric_limits<double>::infinity();
  // Near the minimum the decrease is below what the sum of the cost resolves and the gain ratio
  // is rounding noise: the step is taken, as Gauss-Newton would (the linearisation is exact
  // there).
  const bool unresolved = valid && predicted >= 0.0 && predicted <= kCostResolution * cost &&
                          0.5 * trial_ssr <= cost * (1.0 + kCostResolution);
  if (*gain_ratio > ctx.options.min_gain_ratio || unresolved) {
    *state = std::move(trial);
    // Nielsen's update needs a meaningful gain ratio; an unresolved one (rounding noise, possibly
    // far below zero) leaves lambda as it was.
    if (*gain_ratio > ctx.options.min_gain_ratio) {
      const double t = 2.0 * *gain_ratio - 1.0;
      *lambda *= std::max(1.0 / 3.0, 1.0 - t * t * t);
    }
    *nu = 2.0;
    return true;
  }
  *lambda *= *nu;
  *nu *= 2.0;
  return false;
}

// A round's limits on the corrections: the position tolerance (at least what the coordinates'
// doubles resolve, m) and the angle tolerance (rad), and the distance (m) beyond which a
// Gauss-Newton step has diverged.
struct RoundTolerances {
  double position_m = 0.0;
  double angle_rad = 0.0;
  double divergence_m = 0.0;
  bool Below(double position, double angle) const {
    return position <= position_m && angle <= angle_rad;
  }
};

RoundTolerances TolerancesOfRound(const Context& ctx, const Layout& layout, const State& state) {
  const TaylorBundleOptions& options = ctx.options;
  double max_norm = 0.0;
  for (const int i : layout.free_images)
    max_norm = std::max(max_norm, state.eo[i].head<3>().norm());
  for (const int p : layout.free_points) max_norm = std::max(max_norm, state.points[p].norm());
  RoundTolerances tolerances;
  tolerances.position_m =
      std::max(options.position_tolerance_m,
               kPositionResolutionFactor * kEpsilon * (ctx.frame.extent_m + max_norm));
  tolerances.angle_rad = options.angle_tolerance_rad;
  tolerances.divergence_m =
      options.divergence_distance_factor * std::max(ctx.frame.extent_m, max_norm);
  return tolerances;
}

// Solves the step with the record's damping and measures it: the record's largest corrections,
// the summary's count and last corrections, *step_squared. False on failure (*message).
bool SolveAndMeasureStep(const Context& ctx, const std::string& at, const Normal& normal,
                         Layout* layout, Reduction* reduction, Eigen::VectorXd* d_e,
                         std::vector<Eigen::Vector3d>* d_p, TaylorBundleIteration* record,
                         double* step_squared, TaylorBundleSummary* summary, std::string* message) {
  reduction->damping = record->damping;
  if (!SolveStep(ctx, at, normal, layout, reduction, d_e, d_p, message)) return false;
  double max_position = 0.0, max_angle = 0.0;
  MeasureCorrections(*layout, normal, *d_e, *d_p, &max_position, &max_angle, step_squared);
  summary->iterations += 1;
  summary->last_position_correction_m = record->max_position_correction_m = max_position;
  summary->last_angle_correction_rad = record->max_angle_correction_rad = max_angle;
  if (std::isfinite(*step_squared)) return true;
  *message = "the correction is not finite" + at;
  return false;
}

// After a damped step that met the tolerances: a damped step can be small because lambda is
// large, so the undamped step at the current linearisation decides, and checks the datum (a
// singular S fails as in Gauss-Newton). False on failure (*message); else *converged, and when
// converged the undamped step's largest corrections in *position (m) and *angle (rad).
bool UndampedStepConverges(const Context& ctx, const std::string& at, const Normal& normal,
                           const RoundTolerances& tolerances, Layout* layout, Reduction* reduction,
                           Eigen::VectorXd* d_e, std::vector<Eigen::Vector3d>* d_p, bool* converged,
                           double* position, double* angle, std::string* message) {
  reduction->damping = 0.0;
  if (!SolveStep(ctx, at, normal, layout, reduction, d_e, d_p, message)) return false;
  double gn_position = 0.0, gn_angle = 0.0, gn_squared = 0.0;
  MeasureCorrections(*layout, normal, *d_e, *d_p, &gn_position, &gn_angle, &gn_squared);
  *converged = tolerances.Below(gn_position, gn_angle);
  if (*converged) {
    *position = gn_position;
    *angle = gn_angle;
  }
  return true;
}

// Takes the step (d_e, d_p) solved at the linearisation of cost `record->cost`: Gauss-Newton
// applies it (false when it diverged: *message); Levenberg-Marquardt takes or refuses it by its
// gain ratio (DecideStep: record->taken, record->gain_ratio; the next *lambda and *nu).
bool TakeStep(const Context& ctx, const Layout& layout, const Normal& normal,
              const RoundTolerances& tolerances, const std::string& at, const Eigen::VectorXd& d_e,
              const std::vector<Eigen::Vector3d>& d_p, State* state, double* lambda, double* nu,
              TaylorBundleIteration* record, TaylorBundleSummary* summary, std::string* message) {
  if (ctx.options.damping == TaylorDamping::kLevenbergMarquardt) {
    record->taken = DecideStep(ctx, layout, normal, record->cost, record->damping, d_e, d_p, state,
                               lambda, nu, &record->gain_ratio);
    if (!record->taken) summary->refused_steps += 1;
    return true;
  }
  ApplyCorrections(layout, d_e, d_p, state);
  return !Diverged(ctx, layout, *state, tolerances.divergence_m, at, message);
}

// Why the linearisation after a taken step failed.
std::string RelinearizationFailure(const Block& block, const Normal& normal, int iteration) {
  return normal.behind_mark >= 0
             ? BehindMessage(block, normal,
                             "after iteration " + std::to_string(iteration) + " (diverged)")
             : "the residuals are not finite after iteration " + std::to_string(iteration);
}

// The progress hook after an iteration; false when it cancels the adjustment.
bool ProgressContinues(const Context& ctx, int round, int iteration, bool free_gauge,
                       int redundancy, const Normal& normal, double step_squared,
                       const TaylorBundleSummary& summary) {
  if (!ctx.options.progress) return true;
  BundleIterationInfo info;
  info.round = round;
  info.iteration = iteration;
  info.cost = summary.final_cost;
  info.sigma0 = redundancy > 0 ? std::sqrt(normal.weighted_ssr / redundancy) : kNaN;
  info.step_norm = std::sqrt(step_squared);
  info.elapsed_seconds = SecondsSince(ctx.start);
  info.free_gauge = free_gauge;
  return ctx.options.progress(info);
}

// The tolerances, in fixed notation (the corrections themselves are below them and would print
// as zeros): 0.001 mm and 0.0002 arc seconds by default.
std::string ConvergedMessage(const RoundTolerances& tolerances) {
  return Format("corrections below the tolerances (%.4f mm, %.4f arc seconds)",
                1e3 * tolerances.position_m, kArcSecondsPerRadian * tolerances.angle_rad);
}

std::string NoConvergenceMessage(const TaylorBundleOptions& options, int round,
                                 const TaylorBundleSummary& summary) {
  std::ostringstream os;
  os << "no convergence in " << options.max_iterations << " iterations of round " << round
     << " (last correction " << summary.last_position_correction_m << " m, "
     << summary.last_angle_correction_rad << " rad)";
  return os.str();
}

// One round from *state: Gauss-Newton (eqs. 9-16) or Levenberg-Marquardt on the same normal
// equations (options.damping). On kConvergence *state is the solution and *normal its
// linearisation; otherwise *message says why it stopped. free_gauge (a relative block's first
// solve, with the plan's gauge released and Levenberg-Marquardt): every step damped, lambda at
// least options.free_gauge_min_damping, converged when a damped step is below the tolerances (no
// undamped step: the reduced system is singular by the 7 free directions).
SolverTermination RunRound(const Context& ctx, int round, bool free_gauge, Layout* layout,
                           State* state, Normal* normal, Reduction* reduction,
                           TaylorBundleResult* result, std::string* message) {
  const TaylorBundleOptions& options = ctx.options;
  TaylorBundleSummary& summary = result->summary;
  const int redundancy = layout->num_observations - layout->num_unknowns;
  const RoundTolerances tolerances = TolerancesOfRound(ctx, *layout, *state);
  const auto linearize = [&]() {
    return Linearize(options.partials, ctx.block, ctx.plan, *layout, ctx.frame, *state,
                     ctx.num_threads, normal, nullptr);
  };
  if (!linearize()) {
    *message =
        normal->behind_mark >= 0
            ? BehindMessage(ctx.block, *normal, "at the start of round " + std::to_string(round))
            : "the residuals at the start are not finite";
    return SolverTermination::kFailure;
  }
  if (round == 1 && summary.iterations == 0) summary.initial_cost = 0.5 * normal->weighted_ssr;
  summary.final_cost = 0.5 * normal->weighted_ssr;

  const bool damped = options.damping == TaylorDamping::kLevenbergMarquardt;
  double lambda = damped ? options.initial_damping : 0.0;
  double nu = 2.0;
  Eigen::VectorXd d_e;
  std::vector<Eigen::Vector3d> d_p;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    const Clock::time_point iteration_start = Clock::now();
    const double cost = 0.5 * normal->weighted_ssr;
    const std::string at = " at iteration " + std::to_string(iteration);
    // The first step of a round is undamped: the datum check Gauss-Newton makes (a singular S
    // fails the round), and a full step when the start is good. Without a gauge every step is
    // damped.
    if (free_gauge) lambda = std::max(lambda, options.free_gauge_min_damping);
    const double step_lambda = damped && (iteration > 1 || free_gauge) ? lambda : 0.0;
    TaylorBundleIteration record{round, iteration, cost, 0.0, 0.0, 0.0, step_lambda, 1.0, true};
    double step_squared = 0.0;
    if (!SolveAndMeasureStep(ctx, at, *normal, layout, reduction, &d_e, &d_p, &record,
                             &step_squared, &summary, message))
      return SolverTermination::kFailure;
    bool converged =
        tolerances.Below(record.max_position_correction_m, record.max_angle_correction_rad);
    if (!TakeStep(ctx, *layout, *normal, tolerances, at, d_e, d_p, state, &lambda, &nu, &record,
                  &summary, message))
      return SolverTermination::kFailure;
    if (record.taken && !linearize()) {
      *message = RelinearizationFailure(ctx.block, *normal, iteration);
      return SolverTermination::kFailure;
    }
    if (damped && converged && step_lambda > 0.0 && !free_gauge) {
      if (!UndampedStepConverges(ctx, at, *normal, tolerances, layout, reduction, &d_e, &d_p,
                                 &converged, &summary.last_position_correction_m,
                                 &summary.last_angle_correction_rad, message))
        return SolverTermination::kFailure;
      if (!converged) {
        lambda = std::min(lambda, options.initial_damping);
        nu = 2.0;
      }
    } else if (damped && !converged && !(lambda <= options.max_damping)) {
      *message = Format("no decrease of the cost with damping %.3g", lambda) + at;
      return SolverTermination::kFailure;
    }
    summary.final_cost = 0.5 * normal->weighted_ssr;
    record.seconds = SecondsSince(iteration_start);
    summary.iteration_seconds += record.seconds;
    result->history.push_back(record);
    if (!ProgressContinues(ctx, round, iteration, free_gauge, redundancy, *normal, step_squared,
                           summary)) {
      *message = "cancelled by the progress hook after iteration " + std::to_string(iteration);
      return SolverTermination::kCancelled;
    }
    if (converged) {
      *message = ConvergedMessage(tolerances);
      return SolverTermination::kConverged;
    }
  }
  *message = NoConvergenceMessage(options, round, summary);
  return SolverTermination::kNoConvergence;
}

// The round's counts in the summary.
void SummarizeRound(const Block& block, const Plan& plan, const Layout& layout, int round,
                    TaylorBundleSummary* summary) {
  summary->rounds = round;
  summary->redundancy = layout.num_observations - layout.num_unknowns;
  summary->num_images = static_cast<int>(block.images.size());
  summary->num_marks = static_cast<int>(layout.marks.size());
  summary->num_points =
      static_cast<int>(std::count(plan.point_in_problem.begin(), plan.point_in_problem.end(), 1));
  summary->num_camera_unknowns =
      layout.num_unknowns - 3 * static_cast<int>(layout.free_points.size());
  summary->reduced_nonzeros = static_cast<int>(layout.S.nonZeros());
}

// BundleAdjust's options for the steps between rounds and the statistics of a Taylor solution:
// the same accuracies, rejection, snooping, statistics options and threads, its analytic Jacobian
// and no loss (the Taylor objective).
// A relative block's first solve without a gauge (options.free_gauge_for_relative_blocks), as
// BundleAdjust does: the plan's held first image and scale coordinate released, every step damped
// (RunRound's free_gauge), then the block moved by the similarity into COLMAP's gauge
// (internal::MoveToRelativeGauge), where the round goes on from the moved state. When the free
// solve fails or no similarity reaches the gauge, *state is left at the start and the round
// solves in the gauge from there. The free solve's structures are freed before the round builds
// its own. Returns the free solve's iterations; *ended is how the free solve ended, and *message
// says why when the progress hook cancelled it.
int SolveInFreeGaugeFirst(const Context& ctx, Plan* plan, State* state,
                          TaylorBundleResult* result, SolverTermination* ended,
                          std::string* message) {
  const int first = plan->relative_fixed_image;
  const int second = plan->relative_scale_image;
  const int axis = plan->relative_scale_axis;
  const State start = *state;
  const Vector6d fixed_eo = state->eo[first];
  const double fixed_coordinate = state->eo[second][axis];
  const char held_first = plan->image_constant[first];
  const bool held_axis = plan->image_fixed[second][axis];
  plan->image_constant[first] = 0;
  plan->image_fixed[second][axis] = false;
  const int iterations_before = result->summary.iterations;
  SolverTermination type = SolverTermination::kFailure;
  {
    Layout layout;
    BuildLayout(ctx.block, *plan, &layout);
    Normal normal;
    Reduction reduction;
    reduction.solver = ctx.options.linear_solver;
    reduction.num_threads = ctx.num_threads;
    type = RunRound(ctx, 1, /*free_gauge=*/true, &layout, state, &normal, &reduction, result,
                    message);
  }
  *ended = type;
  plan->image_constant[first] = held_first;
  plan->image_fixed[second][axis] = held_axis;
  if (type != SolverTermination::kConverged ||
      !internal::MoveToRelativeGauge(*plan, fixed_eo, fixed_coordinate, &state->eo, &state->points))
    *state = start;
  return result->summary.iterations - iterations_before;
}

BundleAdjustmentOptions AdjustmentOptionsOf(const TaylorBundleOptions& options) {
  BundleAdjustmentOptions out;
  out.accuracies = options.accuracies;
  out.robustness.rejection_threshold = options.rejection_threshold;
  out.robustness.max_rejection_rounds = options.max_rejection_rounds;
  out.robustness.snoop = options.snoop;
  out.robustness.snooping_batch = options.snooping_batch;
  out.robustness.tie_loss = options.tie_loss;
  out.robustness.tie_loss_scale_sigmas = options.tie_loss_scale_sigmas;
  out.robustness.max_snooping_removals = options.max_snooping_removals;
  out.statistics = options.statistics;
  out.solver.num_threads = options.num_threads;
  out.solver.free_gauge_for_relative_blocks = options.free_gauge_for_relative_blocks;
  return out;
}

// The statistics of each round's solution, by BundleAdjust's code
// (internal::ComputeBundleStatistics) so that both solvers report one set of figures. That code
// evaluates each observation's whitened rows by the cost functions of BundleAdjust's problem, made
// when asked from the round's rows alone (internal::BuildBundleRoundRows, per round: its cost is
// statistics_setup_seconds): no Ceres problem, which this solver never solves, and no cost object
// held per mark. A second implementation of every row in Ceres' tangent spaces behind an
// interface would be a second derivative path to keep in agreement with the first.
struct Statistics {
  Statistics(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
             const Block& block, const Plan& plan)
      : options(options),
        config(config),
        block(block),
        plan(plan),
        ground(internal::StartState(config, block)) {}
  const BundleAdjustmentOptions& options;
  const BundleAdjustmentConfig& config;
  const Block& block;
  const Plan& plan;
  internal::BundleState ground;  // the solution in the ground frame; the round points into it
  internal::BundleRound round;   // rows alone

  // The solution in the ground frame, in place: the round holds pointers to these values.
  void SetGround(const State& state, const Frame& frame) {
    for (size_t i = 0; i < block.images.size(); ++i) {
      ground.eo[i] = state.eo[i];
      ground.eo[i].head<3>() += frame.centroid;
    }
    for (size_t p = 0; p < block.points.size(); ++p)
      if (plan.point_in_problem[p]) ground.points[p] = state.points[p] + frame.centroid;
    // In place: the round's camera blocks point into these vectors.
    for (size_t c = 0; c < block.cameras.size(); ++c)
      std::copy(state.cameras[c].begin(), state.cameras[c].end(), ground.cameras[c].begin());
    ground.lever = state.lever;
  }

  // An error when the normal matrix at the solution is singular (naming what is undetermined):
  // the adjustment then fails, as BundleAdjust's does.
  Status Compute(const State& state, const Frame& frame, TaylorBundleSummary* summary,
                 BundleAdjustmentResult* out, internal::GroupVariance* variance) {
    Clock::time_point start = Clock::now();
    SetGround(state, frame);
    internal::BuildBundleRoundRows(options, config, block, plan, &ground, &round);
    summary->statistics_setup_seconds += SecondsSince(start);
    start = Clock::now();
    out->summary.sigma0 = summary->sigma0;
    out->summary.redundancy = summary->redundancy;
    out->summary.message.clear();
    const Status determined =
        internal::ComputeBundleStatistics(options, block, plan, ground, round, out, variance);
    if (!out->summary.message.empty()) summary->message += "; " + out->summary.message;
    summary->statistics_seconds += SecondsSince(start);
    return determined;
  }

  // What a singular reduced normal matrix at `state` leaves undetermined, named as BundleAdjust
  // names it (internal::CheckBundleDeterminacy on the round of that state); Ok when that check
  // finds S regular after all.
  Status NameUndetermined(const State& state, const Frame& frame) {
    SetGround(state, frame);
    internal::BuildBundleRoundRows(options, config, block, plan, &ground, &round);
    double factorization_seconds = 0.0;
    return internal::CheckBundleDeterminacy(block, plan, ground, round, options.solver.num_threads,
                                            &factorization_seconds);
  }

  // Without covariances the last round's normal matrix is factorised once all the same
  // (internal::CheckBundleDeterminacy), as BundleAdjust does.
  Status CheckDeterminacy(TaylorBundleSummary* summary) {
    const Clock::time_point start = Clock::now();
    double factorization_seconds = 0.0;
    const Status determined =
        internal::CheckBundleDeterminacy(block, plan, ground, round, options.solver.num_threads,
                                         &factorization_seconds);
    summary->statistics_seconds += SecondsSince(start);
    return determined;
  }
};

// The adjusted values, back in the ground frame, written into the block.
void WriteBack(const Plan& plan, const State& state, const Frame& frame, Block* block) {
  for (size_t i = 0; i < block->images.size(); ++i) {
    // An image held constant keeps its input values exactly (the centred frame would round them).
    if (plan.image_constant[i] && block->images[i].eo) continue;
    ExteriorOrientation eo;
    eo.parameters = state.eo[i];
    eo.parameters.head<3>() += frame.centroid;
    for (int k = 3; k < 6; ++k) eo.parameters[k] = WrapAngle(eo.parameters[k]);
    block->images[i].eo = eo;
  }
  for (size_t p = 0; p < block->points.size(); ++p)
    if (plan.point_in_problem[p]) block->points[p].position_m = state.points[p] + frame.centroid;
  for (size_t c = 0; c < block->cameras.size(); ++c)
    if (!plan.calibrated[c].empty()) block->cameras[c].params = state.cameras[c];
}

// BundleAdjust's summary, from the Taylor one (the single source of these numbers).
void FillBundleSummary(const TaylorBundleSummary& taylor, BundleAdjustmentSummary* out) {
  out->termination = taylor.termination_type;
  out->message = taylor.message;
  out->datum = taylor.datum;
  out->datum_description = taylor.datum_description;
  out->tie_points_left_out = taylor.tie_points_left_out;
  out->rounds = taylor.rounds;
  out->iterations = taylor.iterations;
  out->initial_cost = taylor.initial_cost;
  out->final_cost = taylor.final_cost;
  out->sigma0 = taylor.sigma0;
  out->redundancy = taylor.redundancy;
  out->num_images = taylor.num_images;
  out->num_points = taylor.num_points;
  out->num_marks = taylor.num_marks;
  out->num_rejected_marks = taylor.num_rejected_marks;
  out->time_seconds = taylor.time_seconds;
  out->problem_build_seconds = taylor.statistics_setup_seconds;
  out->statistics_seconds = taylor.statistics_seconds;
  out->round_seconds = taylor.round_seconds;
  out->solver = taylor.partials == TaylorPartials::kAsPrinted ? PoseSolver::kTaylorAsPrinted
                                                              : PoseSolver::kTaylor;
}

}  // namespace

bool TaylorBundleOptions::IsValid(std::string* why) const {
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (partials != TaylorPartials::kCorrected && partials != TaylorPartials::kAsPrinted)
    return InvalidBecause(why, "partials is not a TaylorPartials value");
  // The accuracies, the loss, the rejection and snooping limits, the threads, the statistics and
  // what needs them (snooping, variance components) are checked by the rule BundleAdjust applies
  // to the options the rounds run with.
  if (const Status valid = Validate(AdjustmentOptionsOf(*this)); !valid.ok())
    return InvalidBecause(why, valid.message());
  if (max_iterations < 1) return InvalidBecause(why, "max_iterations must be at least 1");
  if (damping != TaylorDamping::kNone && damping != TaylorDamping::kLevenbergMarquardt)
    return InvalidBecause(why, "damping is not a TaylorDamping value");
  if (linear_solver != TaylorLinearSolver::kCholmodSupernodal &&
      linear_solver != TaylorLinearSolver::kEigenLdlt)
    return InvalidBecause(why, "linear_solver is not a TaylorLinearSolver value");
  if (!positive(initial_damping))
    return InvalidBecause(why, "initial_damping must be positive and finite");
  if (!(min_gain_ratio >= 0.0 && min_gain_ratio < 1.0))
    return InvalidBecause(why, "min_gain_ratio must be in [0, 1)");
  if (!(max_damping > initial_damping) || !std::isfinite(max_damping))
    return InvalidBecause(why, "max_damping must be finite and greater than initial_damping");
  if (partials == TaylorPartials::kAsPrinted && damping != TaylorDamping::kNone)
    return InvalidBecause(
        why,
        "the as-printed partials are not the derivative of the objective, so Levenberg-Marquardt's "
        "gain ratio means nothing with them: use damping none (the lecture's Gauss-Newton)");
  if (!positive(position_tolerance_m))
    return InvalidBecause(why, "position_tolerance_m must be positive and finite");
  if (!positive(angle_tolerance_rad))
    return InvalidBecause(why, "angle_tolerance_rad must be positive and finite");
  if (!(divergence_distance_factor > 1.0) || !std::isfinite(divergence_distance_factor))
    return InvalidBecause(why, "divergence_distance_factor must be finite and greater than 1");
  if (!(min_pivot_ratio >= 0.0 && min_pivot_ratio < 1.0))
    return InvalidBecause(why, "min_pivot_ratio must be in [0, 1)");
  return true;
}

Status TaylorBundleOptionsFromBundleOptions(const BundleAdjustmentOptions& ceres,
                                            TaylorPartials partials, TaylorBundleOptions* options) {
  *options = TaylorBundleOptions();
  options->partials = partials;
  options->damping = DefaultTaylorDamping(partials);
  options->accuracies = ceres.accuracies;
  options->rejection_threshold = ceres.robustness.rejection_threshold;
  options->max_rejection_rounds = ceres.robustness.max_rejection_rounds;
  options->snoop = ceres.robustness.snoop;
  options->snooping_batch = ceres.robustness.snooping_batch;
  options->tie_loss = ceres.robustness.tie_loss;
  options->tie_loss_scale_sigmas = ceres.robustness.tie_loss_scale_sigmas;
  options->max_snooping_removals = ceres.robustness.max_snooping_removals;
  options->statistics = ceres.statistics;
  options->num_threads = ceres.solver.num_threads;
  options->max_iterations = ceres.solver.max_iterations;
  options->free_gauge_for_relative_blocks = ceres.solver.free_gauge_for_relative_blocks;
  options->progress = ceres.solver.progress;
  return Status::Ok();
}

std::string TaylorBundleSummary::BriefReport() const {
  std::ostringstream os;
  os << "Taylor bundle adjustment (" << EnumName(partials) << " partials, " << EnumName(damping)
     << ", " << EnumName(linear_solver) << ", " << num_threads
     << (num_threads == 1 ? " thread), " : " threads), ") << EnumName(termination_type) << ": "
     << num_images << " images, " << num_points << " points, " << num_marks << " marks, " << rounds
     << " round" << (rounds == 1 ? "" : "s") << ", " << iterations << " iterations";
  if (free_gauge_iterations > 0) os << " (" << free_gauge_iterations << " without a gauge)";
  os << ", cost " << initial_cost << " -> " << final_cost << ", sigma0 " << sigma0
     << " (redundancy " << redundancy << ")";
  if (num_rejected_marks > 0) os << ", " << num_rejected_marks << " marks rejected";
  os << ", " << time_seconds << " s";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

bool TaylorBundleSummary::IsSolutionUsable() const {
  return termination_type == SolverTermination::kConverged;
}

bool TaylorMarkPartials(TaylorPartials partials, const ExteriorOrientation& eo,
                        const Eigen::Vector3d& point_in_ground, double focal_um,
                        const Eigen::Vector2d& observed_um, Eigen::Matrix<double, 2, 6>* d_eo,
                        Eigen::Matrix<double, 2, 3>* d_point, Eigen::Vector2d* f_um) {
  const TaylorPoseLinearization pose(partials, eo.data(), focal_um);
  double row_u[6], row_v[6], fu, fv, w;
  if (!pose.Linearize(point_in_ground.data(), observed_um.data(), row_u, row_v, &fu, &fv, &w))
    return false;
  if (d_eo != nullptr) {
    for (int c = 0; c < 6; ++c) {
      (*d_eo)(0, c) = row_u[c];
      (*d_eo)(1, c) = row_v[c];
    }
  }
  if (d_point != nullptr) PointPartialsFromCentrePartials(row_u, row_v, d_point);
  if (f_um != nullptr) *f_um = Eigen::Vector2d(fu, fv);
  return true;
}

Eigen::Vector3d TaylorAntennaPosition(const ExteriorOrientation& eo, const Eigen::Vector3d& lever_m,
                                      Eigen::Matrix3d* d_angles) {
  const double omega = eo.parameters[3];
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
  const Eigen::Vector3d offset = R.transpose() * lever_m;  // R^T l, ground frame
  if (d_angles != nullptr) {
    // d(R^T l) = (dR)^T l: dR = [a]x R gives -R^T (a x l); dR = R [e3]x gives -e3 x (R^T l).
    const Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
    const Eigen::Vector3d a(0.0, std::cos(omega), std::sin(omega));  // Rx(omega) e2
    d_angles->col(0) = -R.transpose() * e1.cross(lever_m);
    d_angles->col(1) = -R.transpose() * a.cross(lever_m);
    d_angles->col(2) = -Eigen::Vector3d::UnitZ().cross(offset);
  }
  return eo.center_in_ground() + offset;
}

namespace {

// LinearizeTaylorBundle's columns: the free images' six, the global columns, the free points'
// three, in this order.
DenseRows DenseColumns(const Block& block, const Layout& layout) {
  DenseRows dense;
  dense.image_columns.assign(block.images.size(), -1);
  dense.point_columns.assign(block.points.size(), -1);
  for (const int i : layout.free_images) {
    dense.image_columns[i] = dense.num_columns;
    dense.num_columns += 6;
  }
  dense.global_column = dense.num_columns;
  dense.num_columns += layout.num_global;
  for (const int p : layout.free_points) {
    dense.point_columns[p] = dense.num_columns;
    dense.num_columns += 3;
  }
  return dense;
}

// The whitened observation equations into the system: its columns, J (the fixed components'
// columns zero) and the residuals.
void CopyObservationEquations(const Block& block, const Plan& plan, const Layout& layout,
                              const DenseRows& dense, TaylorBundleLinearSystem* system) {
  system->image_columns = dense.image_columns;
  system->point_columns = dense.point_columns;
  system->camera_columns.assign(block.cameras.size(), -1);
  for (size_t c = 0; c < block.cameras.size(); ++c)
    if (layout.camera_global[c] >= 0)
      system->camera_columns[c] = dense.global_column + layout.camera_global[c];
  if (layout.lever_global >= 0) system->lever_column = dense.global_column + layout.lever_global;
  system->jacobian.resize(static_cast<int>(dense.rows.size()), dense.num_columns);
  system->residual.resize(static_cast<int>(dense.rows.size()));
  for (size_t row = 0; row < dense.rows.size(); ++row) {
    system->jacobian.row(row) = dense.rows[row].transpose();
    system->residual[row] = dense.residuals[row];
  }
  for (size_t b = 0; b < layout.free_images.size(); ++b)
    for (int c = 0; c < 6; ++c)
      if (IsFixed(plan, layout, static_cast<int>(b), c))
        system->jacobian.col(dense.image_columns[layout.free_images[b]] + c).setZero();
}

// The reduced camera system as a dense matrix and right-hand side, a fixed component's row and
// column those of the identity.
void CopyReducedSystem(const Plan& plan, const Layout& layout, const Reduction& reduction,
                       TaylorBundleLinearSystem* system) {
  const int cameras_size = 6 * static_cast<int>(layout.free_images.size());
  const int n = cameras_size + layout.num_global;
  system->reduced_matrix = Eigen::MatrixXd::Zero(n, n);
  for (size_t k = 0; k < layout.pairs.size(); ++k) {
    const auto [b1, b2] = layout.pairs[k];
    system->reduced_matrix.block<6, 6>(6 * b1, 6 * b2) = reduction.blocks[k];
    system->reduced_matrix.block<6, 6>(6 * b2, 6 * b1) = reduction.blocks[k].transpose();
  }
  system->reduced_matrix.topRightCorner(cameras_size, layout.num_global) = reduction.border;
  system->reduced_matrix.bottomLeftCorner(layout.num_global, cameras_size) =
      reduction.border.transpose();
  system->reduced_matrix.bottomRightCorner(layout.num_global, layout.num_global) =
      reduction.corner;
  system->reduced_rhs = reduction.r;
  for (size_t b = 0; b < layout.free_images.size(); ++b) {
    for (int c = 0; c < 6; ++c) {
      if (!IsFixed(plan, layout, static_cast<int>(b), c)) continue;
      const int column = 6 * static_cast<int>(b) + c;
      system->reduced_matrix.row(column).setZero();
      system->reduced_matrix.col(column).setZero();
      system->reduced_matrix(column, column) = 1.0;
      system->reduced_rhs[column] = 0.0;
    }
  }
}

// The step in the system's columns.
void CopyCorrection(const Layout& layout, const DenseRows& dense, const Eigen::VectorXd& d_e,
                    const std::vector<Eigen::Vector3d>& d_p, TaylorBundleLinearSystem* system) {
  system->correction.resize(dense.num_columns);
  for (size_t b = 0; b < layout.free_images.size(); ++b)
    system->correction.segment<6>(dense.image_columns[layout.free_images[b]]) =
        d_e.segment<6>(6 * b);
  system->correction.segment(dense.global_column, layout.num_global) = d_e.tail(layout.num_global);
  for (size_t q = 0; q < layout.free_points.size(); ++q)
    system->correction.segment<3>(dense.point_columns[layout.free_points[q]]) = d_p[q];
}

// The end of a Taylor adjustment: its termination, message and time in both summaries. A block
// left at its input values keeps no statistics (an earlier round's would not describe it).
Status FinishAdjustment(SolverTermination type, const std::string& message, Clock::time_point start,
                        TaylorBundleResult* result) {
  TaylorBundleSummary& summary = result->summary;
  BundleAdjustmentResult& out = result->adjustment;
  if (type != SolverTermination::kConverged) {
    out.images.clear();
    out.points.clear();
    out.groups.clear();
    out.observations.clear();
    out.mark_residuals.clear();
  }
  summary.termination_type = type;
  summary.message = message;
  summary.time_seconds = SecondsSince(start);
  FillBundleSummary(summary, &out.summary);
  return Status::Ok();
}

// A block or options refused before any round: the status returned, its message in the summaries.
Status RefuseAdjustment(const Status& status, Clock::time_point start, TaylorBundleResult* result) {
  result->summary.message = status.message();
  result->summary.time_seconds = SecondsSince(start);
  FillBundleSummary(result->summary, &result->adjustment.summary);
  return status;
}

// The summary's words on the adjustment before its first round: the datum, the tie points left
// out, the solver's settings.
void DescribeAdjustment(const Context& context, TaylorBundleSummary* summary) {
  summary->datum = context.plan.datum;
  summary->datum_description = context.plan.datum_description;
  for (const int p : context.plan.tie_points_left_out)
    summary->tie_points_left_out.push_back(context.block.points[p].id);
  summary->message.clear();
  summary->damping = context.options.damping;
  summary->linear_solver = context.options.linear_solver;
  summary->num_threads = context.num_threads;
}

// What a round of TaylorBundleAdjust carries from one round to the next.
struct Rounds {
  Plan* plan;
  State* state;
  BundleAdjustmentOptions* adjustment_options;  // the statistics' and rounds' options
  Statistics* statistics;
  std::string stalled;  // the message of a robust round that stalled (internal::TieLossStalled)
  Layout layout;
  Normal normal;
  std::unique_ptr<Reduction> reduction;
};

// The round's structures, freed before the statistics, whose own peak comes after them: the
// layout (its S by a swap: Eigen's SparseMatrix assigned an empty one keeps its buffer, 16 MB at
// a thousand images), the normal equations, the reduction, and the marks' ideal points (27 MB;
// the statistics evaluate the marks by their cost functions; the next round makes them again).
void FreeRoundStructures(Rounds* rounds) {
  internal::taylor::SparseMatrix no_S;
  rounds->layout.S.swap(no_S);
  rounds->layout = Layout();
  rounds->normal = Normal();
  rounds->reduction.reset();
  std::vector<Eigen::Vector2d>().swap(rounds->plan->ideal_um);
}

// One round's adjustment (a relative block's first in a free gauge first, when asked), its time
// in the summary. kConverged, or how the adjustment ends with *message its words ("round N: ...",
// what is undetermined named as BundleAdjust names it).
SolverTermination AdjustRound(const Context& context, int round, Rounds* rounds,
                              TaylorBundleResult* result, std::string* message) {
  const TaylorBundleOptions& options = context.options;
  TaylorBundleSummary& summary = result->summary;
  const Clock::time_point round_start = Clock::now();
  SolverTermination free_ended = SolverTermination::kConverged;
  std::string free_message;
  // Released for the statistics (FreeRoundStructures); made again for the marks now used.
  if (rounds->plan->ideal_um.empty()) FillIdealPoints(context.block, rounds->plan);
  if (round == 1 && rounds->plan->datum == BundleDatum::kRelative &&
      options.free_gauge_for_relative_blocks &&
      options.damping == TaylorDamping::kLevenbergMarquardt)
    summary.free_gauge_iterations = SolveInFreeGaugeFirst(context, rounds->plan, rounds->state,
                                                          result, &free_ended, &free_message);
  BuildLayout(context.block, *rounds->plan, &rounds->layout);
  SummarizeRound(context.block, *rounds->plan, rounds->layout, round, &summary);
  if (free_ended == SolverTermination::kCancelled) {
    summary.round_seconds.push_back(SecondsSince(round_start));
    *message = "round 1: " + free_message + " (free gauge)";
    return free_ended;
  }
  rounds->reduction = std::make_unique<Reduction>();
  rounds->reduction->solver = options.linear_solver;
  rounds->reduction->num_threads = context.num_threads;
  SolverTermination type =
      RunRound(context, round, /*free_gauge=*/false, &rounds->layout, rounds->state,
               &rounds->normal, rounds->reduction.get(), result, message);
  if (internal::TieLossStalled(type, rounds->plan->tie_loss ? options.tie_loss : LossType::kNone)) {
    // Stalled: on from here as least squares, this round and the rest, statistics included.
    rounds->plan->tie_loss.reset();
    rounds->adjustment_options->robustness.tie_loss = LossType::kNone;
    rounds->stalled =
        internal::TieLossStalledMessage(round, options.tie_loss, options.max_iterations);
    type = RunRound(context, round, /*free_gauge=*/false, &rounds->layout, rounds->state,
                    &rounds->normal, rounds->reduction.get(), result, message);
  }
  summary.round_seconds.push_back(SecondsSince(round_start));
  if (type == SolverTermination::kConverged) return type;
  if (rounds->reduction->singular) {
    const Status named = rounds->statistics->NameUndetermined(*rounds->state, context.frame);
    if (!named.ok()) *message = named.message() + " (" + *message + ")";
  }
  *message = "round " + std::to_string(round) + ": " + *message;
  return type;
}

// Without covariances the determinacy is checked by the statistics' own rule
// (CheckBundleDeterminacy: the reduced system of the Ceres problem factorised once more, 11 s of
// a 1000-image block). The last round's undamped factorisation has already shown S regular; when
// its pivot ratio clears the statistics' bound by kDeterminedMargin the check is skipped,
// otherwise that rule decides and names what is undetermined.
Status CheckDeterminacyWithoutCovariances(const BundleAdjustmentOptions& adjustment_options,
                                          Statistics* statistics, TaylorBundleSummary* summary) {
  const double statistics_bound = internal::SelectedInversionOptions().min_pivot_ratio;
  if (adjustment_options.statistics.covariances != BundleCovarianceMethod::kNone ||
      summary->pivot_ratio >= kDeterminedMargin * statistics_bound)
    return Status::Ok();
  return statistics->CheckDeterminacy(summary);
}

}  // namespace

Status LinearizeTaylorBundle(const TaylorBundleOptions& options,
                             const BundleAdjustmentConfig& config, const Block& input,
                             TaylorBundleLinearSystem* system) {
  CHECK(system != nullptr);
  *system = TaylorBundleLinearSystem();
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(input));
  Block block = input;
  block.BuildIndex();
  Plan plan;
  PHOTOPOSE_RETURN_IF_ERROR(Prepare(options, config, block, &plan));
  State state;
  const Frame frame = MakeFrame(config, block, plan, &state);
  Layout layout;
  BuildLayout(block, plan, &layout);
  DenseRows dense = DenseColumns(block, layout);
  Normal normal;
  const int num_threads = ResolveThreadCount(options.num_threads);
  if (!Linearize(options.partials, block, plan, layout, frame, state, num_threads, &normal,
                 &dense)) {
    return Status::Error(normal.behind_mark >= 0 ? BehindMessage(block, normal, "")
                                                 : "the residuals are not finite");
  }
  CopyObservationEquations(block, plan, layout, dense, system);
  Reduction reduction;
  reduction.solver = options.linear_solver;
  reduction.num_threads = num_threads;
  const int singular_point = Reduce(normal, layout, &reduction);
  if (singular_point >= 0)
    return Status::Error(PointName(block, singular_point) + " is not determined by its rays");
  if (WriteScaled(plan, &layout, &reduction) >= 0)
    return Status::Error("an exterior-orientation parameter has no weight");
  CopyReducedSystem(plan, layout, reduction, system);
  if (!Factorize(options.min_pivot_ratio, layout, &reduction)) {
    if (!reduction.failure.empty())
      return Status::Error("the reduced normal matrix could not be factorised: " +
                           reduction.failure);
    return Status::Error(
        Format("the reduced normal matrix is singular (pivot ratio %.3g)", reduction.pivot_ratio));
  }
  Eigen::VectorXd d_e;
  std::vector<Eigen::Vector3d> d_p;
  SolveCorrections(plan, layout, normal, reduction, &d_e, &d_p);
  CopyCorrection(layout, dense, d_e, d_p, system);
  return Status::Ok();
}

Status TaylorBundleAdjust(const TaylorBundleOptions& options,
                          const BundleAdjustmentConfig& stated_config, Block* block,
                          TaylorBundleResult* result) {
  CHECK(block != nullptr);
  CHECK(result != nullptr);
  const BundleAdjustmentConfig config = WithFixedControlPoints(stated_config, *block);
  const Clock::time_point start = Clock::now();
  *result = TaylorBundleResult();
  TaylorBundleSummary& summary = result->summary;
  summary.partials = options.partials;
  summary.sigma0 = kNaN;
  const Status checked = CheckBlock(*block);
  if (!checked.ok()) return RefuseAdjustment(checked, start, result);
  block->BuildIndex();
  Plan plan;
  const Status prepared = Prepare(options, config, *block, &plan);
  if (!prepared.ok()) return RefuseAdjustment(prepared, start, result);
  State state;
  const Frame frame = MakeFrame(config, *block, plan, &state);
  const Context context{options, *block, plan,
                        frame,   start,  ThreadsForMarks(options.num_threads, plan)};
  DescribeAdjustment(context, &summary);
  BundleAdjustmentResult& out = result->adjustment;

  // Rounds: adjust; then, as BundleAdjust (internal/bundle_rounds.h), the statistics of the
  // solution, blunders out (rejection rounds or data snooping) or the groups rescaled (variance
  // components), and adjust again, until neither changes.
  BundleAdjustmentOptions adjustment_options = AdjustmentOptionsOf(options);
  internal::GroupVariance variance;
  internal::RoundChanges changes(adjustment_options, config, *block, &plan, &out, &variance);
  Statistics statistics(adjustment_options, config, *block, plan);
  Rounds rounds{&plan, &state, &adjustment_options, &statistics, {}, {}, {}, {}};
  // The steps' notices (snooping not done or stopped, accuracies not estimated, variance
  // components not settled) are the adjustment's, not a round's: kept past the next round, whose
  // statistics start the message again.
  std::string notices;
  for (int round = 1;; ++round) {
    std::string message;
    const SolverTermination type = AdjustRound(context, round, &rounds, result, &message);
    if (type != SolverTermination::kConverged) {
      summary.sigma0 = kNaN;
      return FinishAdjustment(type, message, start, result);
    }
    summary.message = rounds.stalled.empty() ? message : rounds.stalled;
    summary.pivot_ratio =
        rounds.reduction->pivot_ratio;  // undamped: RunRound converges on no other
    summary.sigma0 =
        summary.redundancy > 0 ? std::sqrt(rounds.normal.weighted_ssr / summary.redundancy) : kNaN;
    FreeRoundStructures(&rounds);
    const Status determined = statistics.Compute(state, frame, &summary, &out, &variance);
    if (!determined.ok()) {
      summary.sigma0 = kNaN;
      return FinishAdjustment(SolverTermination::kFailure,
                              "round " + std::to_string(round) + ": " + determined.message(), start,
                              result);
    }
    const size_t said = out.summary.message.size();  // the round's statistics' own words
    const internal::RoundChange change = internal::ChangeAfterRound(&changes, round);
    if (change == internal::RoundChange::kFailed)
      return FinishAdjustment(SolverTermination::kFailure, out.summary.message, start, result);
    if (out.summary.message.size() > said)
      internal::AddRoundNotice(out.summary.message.substr(said == 0 ? 0 : said + 2), &notices);
    if (change == internal::RoundChange::kNone) break;
  }
  const Status determined =
      CheckDeterminacyWithoutCovariances(adjustment_options, &statistics, &summary);
  if (!determined.ok()) {
    summary.sigma0 = kNaN;
    return FinishAdjustment(SolverTermination::kFailure,
                            "round " + std::to_string(summary.rounds) + ": " + determined.message(),
                            start, result);
  }
  summary.num_rejected_marks = static_cast<int>(out.rejected_marks.size());
  if (!notices.empty()) internal::AddRoundNotice(notices, &summary.message);
  if (adjustment_options.statistics.estimate_accuracies)
    internal::ReportEstimatedAccuracies(changes);
  WriteBack(plan, state, frame, block);
  return FinishAdjustment(SolverTermination::kConverged, summary.message, start, result);
}

Status BundleAdjustWithSolver(PoseSolver solver, const BundleAdjustmentOptions& options,
                              const BundleAdjustmentConfig& config, Block* block,
                              BundleAdjustmentResult* result, TaylorBundleResult* taylor_result,
                              std::optional<TaylorDamping> damping) {
  CHECK(result != nullptr);
  if (solver == PoseSolver::kCeres) return BundleAdjust(options, config, block, result);
  TaylorBundleOptions taylor_options;
  const TaylorPartials partials = solver == PoseSolver::kTaylorAsPrinted
                                      ? TaylorPartials::kAsPrinted
                                      : TaylorPartials::kCorrected;
  PHOTOPOSE_RETURN_IF_ERROR(
      TaylorBundleOptionsFromBundleOptions(options, partials, &taylor_options));
  if (damping) taylor_options.damping = *damping;
  TaylorBundleResult local;
  TaylorBundleResult& taylor = taylor_result != nullptr ? *taylor_result : local;
  const Status status = TaylorBundleAdjust(taylor_options, config, block, &taylor);
  // Moved when the caller keeps no Taylor result: a copy would hold the per-observation
  // diagnostics twice (3.4 million of 64 bytes at 1000 images).
  if (taylor_result != nullptr) {
    *result = taylor.adjustment;
  } else {
    *result = std::move(taylor.adjustment);
  }
  return status;
}

}  // namespace photopose
