// The bundle's outputs other than its page (tools/report/bundle_report.h): the JSON report, the
// frames and points tables, the warnings the page shares, the console lines. One file past ~800
// lines on purpose: the report and the console say the same things (groups, check points, removed
// observations, cross-validation) through the same file-local names and numbers, one function
// per section.
#include "tools/report/bundle_report.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "core/io/csv.h"
#include "core/statistics.h"
#include "core/units.h"
#include "solvers/bundle/check_points.h"
#include "tools/report/comparison_html.h"

namespace photopose::cli {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A JSON number, or null when not finite.
json Number(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }
// A single-precision value (the observation diagnostics' reported ones) by its shortest decimal
// (0.1f as 0.1, not as the double 0.10000000149011612 it converts to).
json Number(float value) {
  if (!std::isfinite(value)) return json(nullptr);
  char text[32];
  const std::to_chars_result end = std::to_chars(text, text + sizeof(text), value);
  return json(std::strtod(std::string(text, end.ptr).c_str(), nullptr));
}

json Vector3(const Eigen::Vector3d& v) { return json::array({Number(v.x()), Number(v.y()), Number(v.z())}); }
json Vector3Single(const Eigen::Vector3f& v) {
  return json::array({Number(v.x()), Number(v.y()), Number(v.z())});
}

const char* RoleName(PointRole role) {
  switch (role) {
    case PointRole::kControl:
      return "control";
    case PointRole::kCheck:
      return "check";
    case PointRole::kTie:
      return "tie";
  }
  return "tie";
}

// The angles of an image in the report's convention, the camera's AngleDirection applied (deg),
// and their standard deviations propagated from the seed covariance (deg).
void ReportedAngles(const BlockCamera& camera, const ExteriorOrientation& eo,
                    const Matrix6d* covariance, RotationConvention convention,
                    Eigen::Vector3d* angles_deg, Eigen::Vector3d* sigmas_deg) {
  AngleFlags flags;
  flags.angle_direction = camera.table.angle_direction;
  const Eigen::Vector3d seed = eo.angles_seed_rad();
  *angles_deg = ConventionAnglesFromSeed(convention, flags, seed) * kDegreesPerRadian;
  sigmas_deg->setConstant(kNaN);
  if (covariance == nullptr) return;
  const Eigen::Matrix3d J = ConventionFromSeedJacobian(convention, flags, seed);
  const Eigen::Matrix3d C = J * covariance->bottomRightCorner<3, 3>() * J.transpose();
  *sigmas_deg = C.diagonal().cwiseMax(0.0).cwiseSqrt() * kDegreesPerRadian;
}

std::string PointName(const Block& block, int p) { return block.points[p].id; }

}  // namespace

// The item a diagnostic refers to, in words.
std::string BundleItemName(const Block& block, BundleGroup group, int item) {
  if (group == kTieMarks || group == kControlMarks) {
    const BlockMark& mark = block.marks[item];
    return "mark of '" + block.points[mark.point].id + "' in '" + block.images[mark.image].name + "'";
  }
  if (group == kControlPoints) return "control point '" + block.points[item].id + "'";
  if (group == kCameraPositions) return "camera position of '" + block.images[item].name + "'";
  if (group == kAttitudes) return "attitude of '" + block.images[item].name + "'";
  return EnumName(group) + std::string(" #") + std::to_string(item);
}

const char* BundleAxisName(BundleGroup group, int axis) {
  static const char* const kMark[] = {"x", "y"};
  static const char* const kXyz[] = {"X", "Y", "Z"};
  static const char* const kAngles[] = {"omega", "phi", "kappa"};
  if (group == kTieMarks || group == kControlMarks) return kMark[std::clamp(axis, 0, 1)];
  if (group == kAttitudes) return kAngles[std::clamp(axis, 0, 2)];
  return kXyz[std::clamp(axis, 0, 2)];
}

namespace {

// A role's RMSE at one stage; without a point (count 0) the figures are null, never a zero.
json RmseJson(const GeoreferenceRmse& rmse) {
  const bool figures = rmse.count > 0;
  return {{"count", rmse.count},
          {"rmse_m", figures ? Vector3(rmse.rmse_m) : json(nullptr)},
          {"rmse_total_m", figures ? Number(rmse.total_m) : json(nullptr)}};
}

// The "georeference" section: CRSs, the local frame, matching, the similarity and the control /
// check errors after it and after the adjustment (m, along the output CRS's level axes).
json GeoreferenceJson(const Block& block, const GeoreferenceResult& g) {
  json similarity = {{"scale", g.model_to_local.scale},
                     {"rotation_local_from_model", json::array()},
                     {"translation_m", {g.model_to_local.translation.x(), g.model_to_local.translation.y(), g.model_to_local.translation.z()}},
                     {"num_pairs", g.similarity.residual_m.size()},
                     {"num_inliers", g.similarity.num_inliers},
                     {"pairs", json::array()}};
  for (int r = 0; r < 3; ++r)
    similarity["rotation_local_from_model"].push_back({g.model_to_local.R_target_from_source(r, 0), g.model_to_local.R_target_from_source(r, 1), g.model_to_local.R_target_from_source(r, 2)});
  for (size_t k = 0; k < g.similarity.residual_m.size() && k < g.similarity_labels.size(); ++k)
    similarity["pairs"].push_back({{"pair", g.similarity_labels[k]}, {"residual_m", g.similarity.residual_m[k]}, {"inlier", g.similarity.inlier[k] != 0}});
  json points = json::array();
  for (const GeoreferencePointError& e : g.point_errors) {
    auto vec = [](const std::optional<Eigen::Vector3d>& v) { return v ? json({v->x(), v->y(), v->z()}) : json(nullptr); };
    points.push_back({{"id", block.points[e.point].id},
                      {"role", RoleName(block.points[e.point].role)},
                      {"error_after_similarity_m", vec(e.after_similarity_m)},
                      {"error_after_adjustment_m", vec(e.after_adjustment_m)}});
  }
  return {{"out_crs", g.out_crs},
          {"out_crs_name", g.out_crs_info.name},
          {"out_crs_reason", g.out_crs_reason},
          {"error_axes", GeoreferenceErrorAxes(g.out_crs_info) + " (m)"},
          {"local_frame", {{"definition", g.frame.definition()},
                           {"origin_lon_lat_h", {g.frame.origin_lon_lat_h().x(), g.frame.origin_lon_lat_h().y(), g.frame.origin_lon_lat_h().z()}},
                           {"note", "the other sections of this report (images, points, groups) are in this local East-North-Up frame (m)"}}},
          {"heights", g.heights_notes},
          {"inputs_not_used", g.inputs_not_used},
          {"positions_matched", g.positions_matched},
          {"positions_without_height", g.positions_without_height},
          {"positions_unmatched", g.positions_unmatched},
          {"images_without_position", g.images_without_position},
          {"control_marks_matched", g.control_marks_matched},
          {"control_marks_unmatched", g.control_marks_unmatched},
          {"control_points_without_marks", g.control_points_without_marks},
          {"similarity", similarity},
          {"control_after_similarity", RmseJson(g.control_after_similarity)},
          {"check_after_similarity", RmseJson(g.check_after_similarity)},
          {"control_after_adjustment", g.evaluated ? RmseJson(g.control_after_adjustment) : json(nullptr)},
          {"check_after_adjustment", g.evaluated ? RmseJson(g.check_after_adjustment) : json(nullptr)},
          {"points", points},
          {"time_seconds", {{"prepare", g.prepare_seconds}, {"evaluate", g.evaluate_seconds}}}};
}

// "summary": termination, costs, counts, the datum and the time breakdown.
void SummaryJson(const Block& block, const BundleAdjustmentResult& result,
                 const BundleReportContext& context, json* report) {
  const BundleAdjustmentSummary& s = result.summary;
  const BundleAdjustmentOptions& o = context.options;
  (*report)["summary"] = {{"termination", EnumName(s.termination)},
                          {"message", s.message},
                          {"sigma0", Number(s.sigma0)},
                          {"redundancy", s.redundancy},
                          {"rounds", s.rounds},
                          {"iterations", s.iterations},
                          {"initial_cost", Number(s.initial_cost)},
                          {"final_cost", Number(s.final_cost)},
                          {"time_seconds", s.time_seconds},
                          {"statistics_seconds", s.statistics_seconds},
                          {"snooping_rounds", s.snooping_rounds},
                          {"snooping_seconds", s.snooping_seconds},
                          {"statistics",
                           {{"covariances", EnumName(o.statistics.covariances)},
                            {"factorization_seconds", s.factorization_seconds},
                            {"inversion_seconds", s.inversion_seconds},
                            {"inverse_entries", s.covariance_entries},
                            {"memory_bytes", s.covariance_memory_bytes}}},
                          {"time_breakdown",
                           {{"read_seconds", context.read_seconds},
                            {"initialization_seconds", context.initialization_seconds},
                            {"plan_seconds", s.plan_seconds},
                            {"setup_seconds", s.plan_seconds + s.problem_build_seconds +
                                                  s.solver_preprocessing_seconds},
                            {"round_seconds", s.round_seconds},
                            {"rejection_seconds", s.rejection_seconds},
                            {"statistics_seconds", s.statistics_seconds},
                            {"problem_build_seconds", s.problem_build_seconds},
                            {"solver_preprocessing_seconds", s.solver_preprocessing_seconds},
                            {"residual_evaluation_seconds", s.residual_evaluation_seconds},
                            {"jacobian_evaluation_seconds", s.jacobian_evaluation_seconds},
                            {"linear_solver_seconds", s.linear_solver_seconds},
                            {"schur_structure", s.schur_structure},
                            {"solver", EnumName(s.solver)}}},
                          {"num_images", s.num_images},
                          {"num_points", s.num_points},
                          {"num_marks", s.num_marks},
                          {"num_rejected_marks", s.num_rejected_marks},
                          {"tie_points_left_out", s.tie_points_left_out},
                          {"num_images_initialized", context.num_images_initialized},
                          {"datum", EnumName(s.datum)},
                          {"datum_description", s.datum_description},
                          {"covariance_datum", s.covariance_datum}};
}

// "groups": each group of the objective against its stated accuracy.
void GroupsJson(const Block& block, const BundleAdjustmentResult& result,
                const BundleReportContext& context, json* report) {
  const BundleAdjustmentOptions& o = context.options;
  json groups = json::array();
  for (const BundleGroupStatistics& g : result.groups) {
    json group = {{"name", EnumName(g.group)},
                  {"count", g.count},
                  {"unit", g.unit},
                  {"stated_accuracy",
                   g.num_axes == 2 ? Number(g.stated_accuracy.x()) : Vector3(g.stated_accuracy)},
                  {"rms", g.num_axes == 2 ? json::array({Number(g.rms.x()), Number(g.rms.y())})
                                          : Vector3(g.rms)},
                  {"rms_total", Number(g.rms_total)},
                  {"ratio", Number(g.ratio)},
                  {"redundancy_share", Number(g.redundancy_share)},
                  {"overfit", OverfitJudged(g) ? json(g.overfit) : json(nullptr)},
                  {"fixed", g.fixed()},
                  {"num_fixed", g.num_fixed},
                  {"message", g.message}};
    if (o.statistics.estimate_accuracies) {
      group["estimated_accuracy"] =
          g.num_axes == 2 ? Number(g.estimated_accuracy.x()) : Vector3(g.estimated_accuracy);
      group["estimated_accuracy_relative_standard_error"] =
          Number(g.estimated_accuracy_standard_error);
      group["estimation_message"] = g.estimation_message;
    }
    groups.push_back(group);
  }
  (*report)["groups"] = groups;
}

// "control_points", "check_points" and their RMSE per axis.
void SurveyedPointsJson(const Block& block, const BundleAdjustmentResult& result,
                        const BundleReportContext& context, json* report) {
  json control = json::array(), check = json::array();
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role == PointRole::kTie) continue;
    // An adjustment that failed early has no per-point results: the point is listed without them.
    const BundlePointResult& r = p < result.points.size() ? result.points[p] : BundlePointResult();
    json row = {{"point_id", point.id},
                {"num_images", r.num_observations},
                {"surveyed", point.surveyed_m ? Vector3(*point.surveyed_m) : json(nullptr)},
                {"error_m", r.error_m ? Vector3(*r.error_m) : json(nullptr)},
                {"sigma_m",
                 r.has_covariance ? Vector3(r.covariance.diagonal().cwiseSqrt()) : json(nullptr)},
                {"fixed", IsHeldFixed(point)},
                {"message", r.message}};
    if (point.role == PointRole::kCheck) {
      // The console's and the page's test: the error against the intersection's covariance plus
      // the surveyed coordinates'.
      const double marker_m = context.options.accuracies.marker_m;
      const bool tested = r.error_m && r.has_covariance && r.covariance_complete;
      row["error_sigma_m"] =
          tested ? Vector3(SurveyedPointErrorCovariance(point, r.covariance, marker_m)
                               .diagonal()
                               .cwiseSqrt())
                 : json(nullptr);
      row["normalized_error"] = Number(CheckPointNormalizedError(point, r, marker_m));
      // False without statistics: sigma_m is then the intersection's alone (the images taken as
      // error-free), and the error is not tested (error_sigma_m, normalized_error null).
      row["covariance_complete"] = r.has_covariance && r.covariance_complete;
    }
    (point.role == PointRole::kControl ? control : check).push_back(row);
  }
  (*report)["control_points"] = control;
  (*report)["check_points"] = check;
  (*report)["control_rmse_m"] = {{"x", Number(result.control_rmse_m.x())},
                                 {"y", Number(result.control_rmse_m.y())},
                                 {"z", Number(result.control_rmse_m.z())},
                                 {"total", Number(result.control_rmse_total_m)},
                                 {"count", result.num_control_points}};
  (*report)["check_rmse_m"] = {{"x", Number(result.check_rmse_m.x())},
                               {"y", Number(result.check_rmse_m.y())},
                               {"z", Number(result.check_rmse_m.z())},
                               {"total", Number(result.check_rmse_total_m)},
                               {"count", result.num_check_points}};
}

// "images": each image's pose, its precision and its marks' RMS.
void ImagesJson(const Block& block, const BundleAdjustmentResult& result,
                const BundleReportContext& context, json* report) {
  json images = json::array();
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    const BundleImageResult& r = i < result.images.size() ? result.images[i] : BundleImageResult();
    json row = {{"raster", image.name},
                {"camera_id", block.cameras[image.camera].camera_id},
                {"adjusted", r.adjusted},
                {"message", r.message},
                {"num_marks", r.num_marks},
                {"rms_residual", Number(r.rms_residual)},
                {"unit", r.unit}};
    if (image.eo) {
      Eigen::Vector3d angles, sigmas;
      ReportedAngles(block.cameras[image.camera], *image.eo,
                     r.has_covariance ? &r.covariance : nullptr, context.rotation, &angles,
                     &sigmas);
      row["pose"] = {{"X", image.eo->parameters[0]},
                     {"Y", image.eo->parameters[1]},
                     {"Z", image.eo->parameters[2]},
                     {"omega_deg", angles[0]},
                     {"phi_deg", angles[1]},
                     {"kappa_deg", angles[2]},
                     {"convention", EnumName(context.rotation)}};
      if (r.has_covariance) {
        row["sigma"] = {{"X", std::sqrt(r.covariance(0, 0))}, {"Y", std::sqrt(r.covariance(1, 1))},
                        {"Z", std::sqrt(r.covariance(2, 2))}, {"omega_deg", Number(sigmas[0])},
                        {"phi_deg", Number(sigmas[1])},       {"kappa_deg", Number(sigmas[2])}};
      }
    }
    images.push_back(row);
  }
  (*report)["images"] = images;
}

// "calibration", "weakly_determined", "lever_arm_m".
void CalibrationJson(const Block& block, const BundleAdjustmentResult& result,
                     const BundleReportContext& context, json* report) {
  json calibration = json::array();
  for (const BundleCalibrationResult& c : result.calibration) {
    json correlation = json::array();
    for (int a = 0; a < c.correlation.rows(); ++a) {
      json row = json::array();
      for (int b = 0; b < c.correlation.cols(); ++b) row.push_back(Number(c.correlation(a, b)));
      correlation.push_back(row);
    }
    json values = json::array();
    for (size_t k = 0; k < c.names.size(); ++k) {
      values.push_back({{"name", c.names[k]},
                        {"value", c.values[k]},
                        {"sigma", k < c.sigmas.size() ? Number(c.sigmas[k]) : json(nullptr)}});
    }
    calibration.push_back({{"camera_id", block.cameras[c.camera].camera_id},
                           {"model", EnumName(block.cameras[c.camera].model)},
                           {"parameters", values},
                           {"correlation", correlation},
                           {"high_correlations", c.high_correlations}});
  }
  (*report)["calibration"] = calibration;
  json weak = json::array();
  for (const BundleWeakParameter& w : result.weakly_determined)
    weak.push_back({{"parameter", w.parameter}, {"sigma_inflation", Number(w.sigma_inflation)}});
  (*report)["weakly_determined"] = weak;
  if (result.lever_arm_m) (*report)["lever_arm_m"] = Vector3(*result.lever_arm_m);
}

// "rejected_marks" and "rejected_check_marks".
void RejectedJson(const Block& block, const BundleAdjustmentResult& result,
                  const BundleReportContext& context, json* report) {
  json rejected = json::array();
  for (const BundleRejectedMark& r : result.rejected_marks) {
    const BlockMark& mark = block.marks[r.mark];
    rejected.push_back({{"raster", block.images[mark.image].name},
                        {"point_id", block.points[mark.point].id},
                        {"round", r.round},
                        {"normalized_residual", Number(r.whitened_residual)}});
  }
  (*report)["rejected_marks"] = rejected;
  json unresolved = json::array();
  for (const BundleUnresolvedPoint& u : result.unresolved_points) {
    const BlockMark& worst = block.marks[u.worst_mark];
    const BlockMark& runner_up = block.marks[u.runner_up_mark];
    unresolved.push_back({{"point_id", block.points[u.point].id},
                          {"round", u.round},
                          {"worst_raster", block.images[worst.image].name},
                          {"worst_drop", Number(u.worst_drop)},
                          {"runner_up_raster", block.images[runner_up.image].name},
                          {"runner_up_drop", Number(u.runner_up_drop)}});
  }
  (*report)["unresolved_points"] = unresolved;
  json rejected_check = json::array();
  for (const BundleRejectedCheckMark& r : result.rejected_check_marks) {
    const BlockMark& mark = block.marks[r.mark];
    rejected_check.push_back({{"raster", block.images[mark.image].name},
                              {"point_id", block.points[mark.point].id},
                              {"normalized_residual", Number(r.normalized)},
                              {"residual", {Number(r.residual.x()), Number(r.residual.y())}}});
  }
  (*report)["rejected_check_marks"] = rejected_check;
}

// "diagnostics" (observation_diagnostics): the rejected, the uncontrolled and the reliability
// per image and control point.
void DiagnosticsJson(const Block& block, const BundleAdjustmentResult& result,
                     const BundleReportContext& context, json* report) {
  const BundleAdjustmentOptions& o = context.options;
  if (!result.observations.empty()) {
    json flagged = json::array(), uncontrolled = json::array();
    std::vector<float> image_mdb(block.images.size(), 0.0f);
    std::vector<float> image_external(block.images.size(), 0.0f);
    std::vector<Eigen::Vector3f> control_mdb(block.points.size(),
                                             Eigen::Vector3f::Constant(std::nanf("")));
    for (const BundleObservationDiagnostics& d : result.observations) {
      const bool is_uncontrolled = d.redundancy < o.statistics.uncontrolled_redundancy;
      // A row only for the few listed (millions of observations at a thousand images).
      if (d.rejected || is_uncontrolled) {
        const json row = {{"group", EnumName(d.group)},
                          {"item", BundleItemName(block, d.group, d.item)},
                          {"axis", BundleAxisName(d.group, d.axis)},
                          {"residual", Number(d.residual)},
                          {"sigma", Number(d.sigma)},
                          {"redundancy", Number(d.redundancy)},
                          {"normalized_residual", Number(d.normalized)},
                          {"mdb", Number(d.mdb)},
                          {"external_m", Number(d.external_m)}};
        if (d.rejected) flagged.push_back(row);
        if (is_uncontrolled) uncontrolled.push_back(row);
      }
      if (d.group == kControlPoints) control_mdb[d.item][d.axis] = d.mdb;
      if (d.group == kTieMarks || d.group == kControlMarks) {
        const int image = block.marks[d.item].image;
        image_mdb[image] = std::max(image_mdb[image], d.mdb);
        image_external[image] = std::max(image_external[image], d.external_m);
      }
    }
    json per_image = json::array();
    for (size_t i = 0; i < block.images.size(); ++i) {
      per_image.push_back({{"raster", block.images[i].name},
                           {"largest_mdb", Number(image_mdb[i])},
                           {"largest_external_m", Number(image_external[i])}});
    }
    json per_control = json::array();
    for (size_t p = 0; p < block.points.size(); ++p) {
      if (block.points[p].role != PointRole::kControl) continue;
      per_control.push_back(
          {{"point_id", block.points[p].id}, {"mdb_m", Vector3Single(control_mdb[p])}});
    }
    (*report)["diagnostics"] = {{"critical_value", result.critical_value},
                                {"delta0", result.delta0},
                                {"alpha", o.statistics.snooping_alpha},
                                {"alpha_per_observation", result.alpha_per_observation},
                                {"family_wise", o.statistics.snooping_family_wise},
                                {"power", o.statistics.snooping_power},
                                {"num_observations", result.observations.size()},
                                {"num_uncontrolled", result.num_uncontrolled},
                                {"rejected", flagged},
                                {"uncontrolled", uncontrolled},
                                {"images", per_image},
                                {"control_points", per_control}};
  }
}

// "snooping": the data-snooping removals, round by round.
void SnoopingJson(const Block& block, const BundleAdjustmentResult& result,
                  const BundleReportContext& context, json* report) {
  const BundleAdjustmentOptions& o = context.options;
  if (!result.snooping.empty() || o.robustness.snoop) {
    json steps = json::array();
    for (const BundleSnoopingStep& step : result.snooping) {
      steps.push_back({{"group", EnumName(step.group)},
                       {"item", BundleItemName(block, step.group, step.item)},
                       {"axis", BundleAxisName(step.group, step.axis)},
                       {"normalized_residual", step.normalized},
                       {"residual", step.residual},
                       {"round", step.round}});
      // A control point tested against --marker_accuracy, not its own (the console warns).
      if (step.group == kControlPoints && step.item >= 0 &&
          step.item < static_cast<int>(block.points.size()))
        steps.back()["accuracy_stated"] = block.points[step.item].accuracy_m.has_value();
    }
    (*report)["snooping"] = steps;
  }
}

// "cross_validation": each control point left out in turn, when run.
void CrossValidationJson(const Block& block, const BundleAdjustmentResult& result,
                         const BundleReportContext& context, json* report) {
  if (context.cross_validation != nullptr) {
    const BundleCrossValidationResult& cv = *context.cross_validation;
    json points = json::array();
    for (const BundleCrossValidationPoint& p : cv.points) {
      points.push_back({{"point_id", PointName(block, p.point)},
                        {"ok", p.ok},
                        {"message", p.message},
                        {"error_m", p.ok ? Vector3(p.error_m) : json(nullptr)},
                        {"num_images", p.num_images},
                        {"normalized", Number(p.normalized)},
                        {"stands_out", p.stands_out}});
    }
    (*report)["cross_validation"] = {{"method", EnumName(cv.method)},
                                     {"points", points},
                                     {"count", cv.count},
                                     {"rmse_m",
                                      {{"x", Number(cv.rmse_m.x())},
                                       {"y", Number(cv.rmse_m.y())},
                                       {"z", Number(cv.rmse_m.z())},
                                       {"total", Number(cv.rmse_total_m)}}},
                                     {"threshold", cv.threshold},
                                     {"time_seconds", cv.time_seconds}};
  }
}

// "options", "inputs", "outputs", "command_line" and "georeference": how the run was asked for.
void OptionsJson(const Block& block, const BundleAdjustmentResult& result,
                 const BundleReportContext& context, json* report) {
  const BundleAdjustmentOptions& o = context.options;
  const BundleAccuracies& a = o.accuracies;
  (*report)["options"] = {
      {"input", context.input_kind},
      {"pixel_origin", EnumName(block.pixel_origin)},
      {"pixel_rows", EnumName(context.pixel_rows)},
      {"rotation", EnumName(context.rotation)},
      {"jacobian", EnumName(o.solver.jacobian)},
      {"linear_solver", EnumName(o.solver.linear_solver)},
      {"tie_accuracy_px", a.tie_px},
      {"marker_projection_accuracy_px", a.marker_projection_px},
      {"tie_accuracy_film_um", a.tie_film_um},
      {"marker_projection_accuracy_film_um", a.marker_projection_film_um},
      {"marker_accuracy_m", a.marker_m},
      {"camera_accuracy_m", Vector3(a.camera_m)},
      {"camera_positions_are_priors", a.camera_positions_are_priors},
      {"attitude_accuracy_deg", a.attitude_deg ? json(*a.attitude_deg) : json(nullptr)},
      {"lever_arm_m",
       context.config.lever_arm_m ? Vector3(*context.config.lever_arm_m) : json(nullptr)},
      {"estimate_lever_arm", context.config.estimate_lever_arm},
      {"calibrate", context.calibrate},
      {"rejection_threshold", o.robustness.rejection_threshold},
      {"estimate_accuracies", o.statistics.estimate_accuracies},
      {"snoop", o.robustness.snoop},
      {"snooping_alpha", o.statistics.snooping_alpha},
      {"max_iterations", o.solver.max_iterations},
      {"num_threads", o.solver.num_threads}};
  (*report)["inputs"] = context.inputs;
  (*report)["outputs"] = context.outputs;
  (*report)["command_line"] = context.command_line;
  if (context.georeference != nullptr)
    (*report)["georeference"] = GeoreferenceJson(block, *context.georeference);
}

}  // namespace

json BundleReportJson(const Block& block, const BundleAdjustmentResult& result,
                      const BundleReportContext& context) {
  json report;
  SummaryJson(block, result, context, &report);
  GroupsJson(block, result, context, &report);
  SurveyedPointsJson(block, result, context, &report);
  ImagesJson(block, result, context, &report);
  CalibrationJson(block, result, context, &report);
  RejectedJson(block, result, context, &report);
  DiagnosticsJson(block, result, context, &report);
  SnoopingJson(block, result, context, &report);
  CrossValidationJson(block, result, context, &report);
  OptionsJson(block, result, context, &report);
  return report;
}

Status FormatBundlePoints(const Block& block, const BundleAdjustmentResult& result,
                          const GeoreferenceResult* georeference, std::string* csv) {
  // Rows: every point with an estimate or a survey; estimate, survey and level axes per row.
  std::vector<int> rows;
  std::vector<Eigen::Vector3d> estimate, surveyed;  // block frame; NaN where there is none
  const Eigen::Vector3d none = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<char> unresolved(block.points.size(), 0);
  for (const BundleUnresolvedPoint& u : result.unresolved_points) unresolved[u.point] = 1;
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (unresolved[p]) continue;  // not adjusted: no estimate to write (the report lists it)
    const BundlePointResult* r = p < result.points.size() ? &result.points[p] : nullptr;
    std::optional<Eigen::Vector3d> value = point.position_m;
    if (point.role == PointRole::kCheck)
      value = (r != nullptr && r->error_m && point.surveyed_m) ? std::optional<Eigen::Vector3d>(*point.surveyed_m + *r->error_m) : std::nullopt;
    if (!value && !point.surveyed_m) continue;  // a tie point that was not adjusted
    rows.push_back(static_cast<int>(p));
    estimate.push_back(value ? *value : none);
    surveyed.push_back(point.surveyed_m ? *point.surveyed_m : none);
  }
  std::vector<Eigen::Matrix3d> R_level(rows.size(), Eigen::Matrix3d::Identity());
  std::vector<Eigen::Vector3d> estimate_out = estimate, surveyed_out = surveyed;
  if (georeference != nullptr) {
    // PROJ needs finite points: transform the present ones.
    auto transform = [&](std::vector<Eigen::Vector3d>* points) -> Status {
      std::vector<Eigen::Vector3d> present;
      for (const Eigen::Vector3d& x : *points) if (x.allFinite()) present.push_back(x);
      PHOTOPOSE_RETURN_IF_ERROR(ToOutputCrs(*georeference, &present));
      size_t k = 0;
      for (Eigen::Vector3d& x : *points) if (x.allFinite()) x = present[k++];
      return Status::Ok();
    };
    std::vector<Eigen::Vector3d> where(rows.size());
    for (size_t k = 0; k < rows.size(); ++k) where[k] = surveyed[k].allFinite() ? surveyed[k] : estimate[k];
    PHOTOPOSE_RETURN_IF_ERROR(LevelAxes(*georeference, where, &R_level));
    PHOTOPOSE_RETURN_IF_ERROR(transform(&estimate_out));
    PHOTOPOSE_RETURN_IF_ERROR(transform(&surveyed_out));
  }
  const std::string srs = BundlePointsSrs(block, georeference);
  std::string text = CsvLine({"PointID", "X", "Y", "Z", "SigmaX", "SigmaY", "SigmaZ", "Role",
                              "NumObservations", "SurveyedX", "SurveyedY", "SurveyedZ", "ErrorX",
                              "ErrorY", "ErrorZ", "SRS"});
  auto triple = [](const Eigen::Vector3d& x, std::vector<std::string>* fields) {
    for (int k = 0; k < 3; ++k) fields->push_back(std::isfinite(x[k]) ? FormatNumber(x[k]) : std::string());
  };
  for (size_t k = 0; k < rows.size(); ++k) {
    const BlockPoint& point = block.points[rows[k]];
    const BundlePointResult* r = rows[k] < static_cast<int>(result.points.size()) ? &result.points[rows[k]] : nullptr;
    std::vector<std::string> fields = {point.id};
    triple(estimate_out[k], &fields);
    if (r != nullptr && r->has_covariance) {
      const Eigen::Matrix3d covariance = R_level[k] * r->covariance * R_level[k].transpose();
      triple(covariance.diagonal().cwiseMax(0.0).cwiseSqrt(), &fields);
    } else {
      triple(none, &fields);
    }
    fields.push_back(RoleName(point.role));
    fields.push_back(std::to_string(r != nullptr ? r->num_observations : 0));
    triple(surveyed_out[k], &fields);
    triple(r != nullptr && r->error_m && point.role != PointRole::kTie ? Eigen::Vector3d(R_level[k] * *r->error_m) : none, &fields);
    fields.push_back(srs);
    text += CsvLine(fields);
  }
  *csv = std::move(text);
  return Status::Ok();
}

std::string BundlePointsSrs(const Block& block, const GeoreferenceResult* georeference) {
  if (georeference != nullptr) return georeference->out_crs_info.definition;
  if (!block.crs.empty()) return block.crs;
  std::string named;
  for (const BlockCamera& camera : block.cameras) {
    if (camera.table.srs.empty()) continue;
    if (!named.empty() && named != camera.table.srs) return "";
    named = camera.table.srs;
  }
  return named;
}

std::vector<FrameRecord> BundleFrames(const Block& block, const BundleAdjustmentResult& result) {
  std::vector<FrameRecord> frames;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    if (!image.eo || i >= result.images.size() || !result.images[i].adjusted) continue;
    const BundleImageResult& r = result.images[i];
    FrameRecord frame;
    frame.raster = image.name;
    frame.camera_id = block.cameras[image.camera].camera_id;
    frame.srs = block.cameras[image.camera].table.srs.empty() ? block.crs
                                                              : block.cameras[image.camera].table.srs;
    frame.eo = *image.eo;
    if (r.has_covariance) frame.covariance = r.covariance;
    if (std::isfinite(result.summary.sigma0)) frame.sigma0 = result.summary.sigma0;
    frame.extra_columns = {{"NumObservations", std::to_string(r.num_marks)},
                           {"RmsResidual", FormatNumber(r.rms_residual)}};
    frames.push_back(std::move(frame));
  }
  return frames;
}

bool AbsorbsGrossErrors(const BundleGroupStatistics& group) {
  const double stated = group.stated_accuracy.x(), estimated = group.estimated_accuracy.x();
  return stated > 0.0 && estimated > kGrossErrorFactor * stated;
}

std::string GrossErrorsAbsorbed(const BundleGroupStatistics& group, UnitText unit_text) {
  if (!AbsorbsGrossErrors(group)) return "";
  const double stated = group.stated_accuracy.x(), estimated = group.estimated_accuracy.x();
  const BundleGroupFigures figures = FormatGroupFigures(group);
  const std::string unit = UnitNameFor(figures.unit, unit_text);
  std::string text = std::string(EnumName(group.group)) + ": the estimated accuracy " +
                     figures.estimated + " " + unit + " is " +
                     FormatUnitless(estimated / stated, 1) + " times the stated " +
                     figures.stated_x + " " + unit +
                     ": gross errors are far likelier than a misstated accuracy, and the "
                     "estimation absorbed them into every observation of the group (sigma0 "
                     "ends near 1 and does not show them)";
  if (group.group == kControlMarks)
    text += "; check marks are tested with this accuracy too";
  return text + ". Check the group's observations with the largest |w|, or state its accuracy.";
}

bool OverfitJudged(const BundleGroupStatistics& g) {
  // Without a redundancy share the library makes no verdict (BundleGroupStatistics::overfit).
  return !(IsPriorGroup(g.group) && g.count > 0 && !std::isfinite(g.redundancy_share));
}

double CheckPointNormalizedError(const BlockPoint& point, const BundlePointResult& r,
                                 double default_marker_m) {
  if (!r.error_m || !r.has_covariance || !r.covariance_complete) return std::nan("");
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(
      SurveyedPointErrorCovariance(point, r.covariance, default_marker_m));
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return std::nan("");
  return r.error_m->dot(ldlt.solve(*r.error_m));
}

double CheckPointErrorSigma(const BlockPoint& point, const BundlePointResult& r,
                            double default_marker_m) {
  if (!r.has_covariance || !r.covariance_complete) return std::nan("");
  return std::sqrt(SurveyedPointErrorCovariance(point, r.covariance, default_marker_m).trace());
}

std::vector<std::string> CheckPointsOutOfTolerance(const Block& block,
                                                   const BundleAdjustmentResult& result,
                                                   double default_marker_m) {
  const double level = ChiSquaredQuantile(kCheckPointLevel, 3.0);
  std::vector<std::string> out;
  for (size_t p = 0; p < block.points.size() && p < result.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role != PointRole::kCheck) continue;
    const BundlePointResult& r = result.points[p];
    const double normalized = CheckPointNormalizedError(point, r, default_marker_m);
    if (!(normalized > level)) continue;
    const std::vector<std::string> miss = FormatLengthsWithUnit(
        {r.error_m->norm(), CheckPointErrorSigma(point, r, default_marker_m)});
    out.push_back(block.points[p].id + " misses by " + miss[0] + " where its sigma is " + miss[1] +
                  " (e^T C^-1 e = " + FormatUnitless(normalized, 1) + " > " +
                  FormatUnitless(level, 1) + "): check its surveyed coordinates and its marks");
  }
  return out;
}

std::string ControlRemovedOnAssumedAccuracy(const Block& block,
                                            const BundleAdjustmentResult& result,
                                            double default_marker_m) {
  std::vector<int> removed;
  for (const BundleSnoopingStep& step : result.snooping)
    if (step.group == kControlPoints && step.item >= 0 &&
        step.item < static_cast<int>(block.points.size()) &&
        !block.points[step.item].accuracy_m &&
        std::find(removed.begin(), removed.end(), step.item) == removed.end())
      removed.push_back(step.item);
  if (removed.empty()) return "";
  int unstated = 0;
  for (const BlockPoint& point : block.points)
    if (point.role == PointRole::kControl && !point.accuracy_m) ++unstated;
  std::string ids;
  for (size_t k = 0; k < removed.size() && k < 5; ++k)
    ids += (k == 0 ? "'" : ", '") + block.points[removed[k]].id + "'";
  if (removed.size() > 5) ids += ", ...";
  return "data snooping removed " + std::to_string(removed.size()) + " of " +
         std::to_string(unstated) + " control points whose accuracy the points table does not " +
         "state (" + ids + "): they were tested against --marker_accuracy, " +
         FormatLengthWithUnit(default_marker_m) + ". If they were surveyed less accurately, " +
         "they are not blunders: state AccuracyX/Y/Z or --marker_accuracy and adjust again.";
}

std::string WeaklyDeterminedWarning(const BundleAdjustmentResult& result) {
  const std::vector<BundleWeakParameter>& weak = result.weakly_determined;
  if (weak.empty()) return "";
  std::string text = FormatCount(static_cast<long long>(weak.size()), "parameter") +
                     " trade off nearly exactly with others: ";
  for (size_t k = 0; k < weak.size() && k < 5; ++k)
    text += (k == 0 ? "" : ", ") + weak[k].parameter + " (sigma " +
            FormatSignificant(weak[k].sigma_inflation, 2) + " times what its own observations give)";
  if (weak.size() > 5) text += ", ...";
  return text + ". The normal matrix is regular, but these values rest on noise and their sigmas "
                "say so: add observations that separate them (control points, oblique images, "
                "marks spread over the image) or hold them fixed.";
}

namespace {

// The console's first line: how the adjustment ended, its size, costs, sigma0 and time.
std::string ConsoleSummaryLine(const BundleAdjustmentSummary& s) {
  std::ostringstream line;
  line << "bundle: " << EnumName(s.termination) << ": " << FormatCount(s.num_images, "image")
       << ", " << FormatCount(s.num_points, "point") << ", " << FormatCount(s.num_marks, "mark")
       << ", " << FormatCount(s.rounds, "round") << ", " << FormatCount(s.iterations, "iteration")
       << ", cost " << FormatSignificant(s.initial_cost, 6) << " -> "
       << FormatSignificant(s.final_cost, 6) << ", sigma0 " << FormatUnitless(s.sigma0, 3)
       << " (unitless; redundancy " << s.redundancy << ")";
  if (s.num_rejected_marks > 0)
    line << ", " << FormatCount(s.num_rejected_marks, "mark") << " rejected";
  if (!s.tie_points_left_out.empty())
    line << ", " << FormatCount(static_cast<long long>(s.tie_points_left_out.size()), "tie point")
         << " without initial coordinates left out";
  line << ", " << FormatSignificant(s.time_seconds, 3) << " s";
  if (!s.message.empty()) line << ": " << s.message;
  return line.str();
}

// Where the time went: the Ceres solve's parts, or the hand-written solver's rounds.
std::string ConsoleTimeLine(const BundleAdjustmentSummary& s) {
  auto seconds = [](double value) { return FormatSignificant(value, 3) + " s"; };
  std::ostringstream time;
  if (s.solver != PoseSolver::kCeres) {
    // The hand-written normal equations: no Ceres solve and no Ceres problem, only the round's
    // rows for the statistics (internal::BuildBundleRoundRows).
    double rounds = 0.0;
    for (const double r : s.round_seconds) rounds += r;
    time << "time: rounds " << seconds(rounds) << " (" << EnumName(s.solver)
         << ": hand-written normal equations), rows for the statistics "
         << seconds(s.problem_build_seconds) << ", statistics " << seconds(s.statistics_seconds);
  } else {
    time << "time: problem " << seconds(s.problem_build_seconds) << ", Ceres preprocessing "
         << seconds(s.solver_preprocessing_seconds) << ", residuals "
         << seconds(s.residual_evaluation_seconds) << ", Jacobians "
         << seconds(s.jacobian_evaluation_seconds) << ", linear solves "
         << seconds(s.linear_solver_seconds) << ", statistics " << seconds(s.statistics_seconds)
         << "; Schur structure " << (s.schur_structure.empty() ? "n/a" : s.schur_structure);
  }
  return time.str();
}

// What the georeferencing did not use, or used horizontally only.
void ConsoleGeoreferenceLines(const GeoreferenceResult& g, std::vector<std::string>* lines) {
  if (g.positions_without_height > 0)
    lines->push_back("georeference: " + FormatCount(g.positions_without_height, "camera position") +
                     " without height: horizontal only (not in the similarity; in the adjustment "
                     "their heights are free)");
  for (const std::string& line : g.inputs_not_used)
    lines->push_back("georeference: not used: " + line);
}

// One line per group of the objective (count, stated, RMS, RMS/stated), then its over-fitting.
void ConsoleGroupLines(const BundleAdjustmentResult& result, std::vector<std::string>* lines) {
  for (const BundleGroupStatistics& g : result.groups) {
    std::ostringstream line;
    if (g.fixed()) {
      line << EnumName(g.group) << ": " << g.num_fixed
           << " held fixed (stated error-free): no residuals, no verdict";
      lines->push_back(line.str());
      continue;
    }
    // The group's figures as the page's groups table shows them (one unit for the line).
    const BundleGroupFigures figures = FormatGroupFigures(g);
    const std::string unit = " " + figures.unit;
    line << EnumName(g.group) << ": " << g.count << ", stated "
         << (StatedPerAxis(g) ? "X/Y/Z " : "") << figures.stated << unit << ", RMS " << figures.rms
         << unit << ", RMS/stated " << FormatUnitless(g.ratio) << ", redundancy share "
         << FormatUnitless(g.redundancy_share) << (g.overfit ? "  OVERFIT" : "")
         << (OverfitJudged(g) ? "" : " (over-fitting not judged: no statistics)");
    if (g.num_fixed > 0) line << "; " << g.num_fixed << " more held fixed";
    lines->push_back(line.str());
  }
  for (const BundleGroupStatistics& g : result.groups)
    if (g.overfit) lines->push_back("warning: " + g.message);
    else if (!g.message.empty()) lines->push_back("note: " + g.message);
}

// The tie points that could not be intersected, the first five by name.
std::string TiePointsLeftOutWarning(const std::vector<std::string>& left_out) {
  std::string names;
  for (size_t k = 0; k < left_out.size() && k < 5; ++k) names += (k ? ", " : "") + left_out[k];
  if (left_out.size() > 5) names += ", ...";
  return "warning: " + std::to_string(left_out.size()) +
         " tie points seen in two or more images could not be intersected (rays too "
         "close to parallel, or marks that do not meet) and were left out: " +
         names + " (report: summary.tie_points_left_out)";
}

// Advice from the estimated accuracies (the flag's value in the flag's own unit), and the groups
// whose estimate says they absorbed gross errors.
void ConsoleAccuracyLines(const BundleAdjustmentResult& result, std::vector<std::string>* lines) {
  static const std::pair<BundleGroup, const char*> kFlags[] = {
      {kTieMarks, "--tie_accuracy"},
      {kControlMarks, "--marker_projection_accuracy"},
      {kControlPoints, "--marker_accuracy"},
      {kCameraPositions, "--camera_accuracy"},
      {kAttitudes, "--attitude_accuracy"}};
  for (const BundleGroupStatistics& g : result.groups) {
    if (!std::isfinite(g.estimated_accuracy.x())) {
      if (!g.estimation_message.empty())
        lines->push_back(EnumName(g.group) + std::string(" accuracy ") + g.estimation_message);
      continue;
    }
    for (const auto& [group, flag] : kFlags) {
      if (g.group != group) continue;
      std::ostringstream line;
      const BundleGroupFigures figures = FormatGroupFigures(g);
      line << EnumName(g.group) << ": " << figures.stated_x << " " << figures.unit << " stated, "
           << figures.estimated << " " << figures.unit << " estimated (+-"
           << FormatUnitless(100.0 * g.estimated_accuracy_standard_error, 0) << " %): set " << flag
           << "=" << FormatSignificant(g.estimated_accuracy.x(), 2);
      lines->push_back(line.str());
    }
    const std::string gross = GrossErrorsAbsorbed(g, UnitText::kAscii);
    if (!gross.empty()) lines->push_back("warning: " + gross);
  }
}

// The control and check points' RMSE, and the check points beyond their covariance
// (`default_marker_m`: the surveyed accuracy of a point that states none).
void ConsolePointLines(const Block& block, const BundleAdjustmentResult& result,
                       double default_marker_m, std::vector<std::string>* lines) {
  if (result.num_control_points > 0)
    lines->push_back("control points: " + std::to_string(result.num_control_points) + ", RMSE " +
                     FormatLengthWithUnit(result.control_rmse_total_m));
  if (result.num_check_points > 0) {
    const LengthUnit unit = LengthUnitFor(result.check_rmse_m.maxCoeff());
    lines->push_back("check points: " + std::to_string(result.num_check_points) + ", RMSE X " +
                     FormatLength(result.check_rmse_m.x(), unit) + " Y " +
                     FormatLength(result.check_rmse_m.y(), unit) + " Z " +
                     FormatLength(result.check_rmse_m.z(), unit) + " total " +
                     FormatLength(result.check_rmse_total_m, unit) + " " + LengthUnitName(unit));
    for (const std::string& miss :
         CheckPointsOutOfTolerance(block, result, default_marker_m))
      lines->push_back("warning: check point " + miss);
  }
}

// What the adjustment left out: rejected marks and check marks, snooped observations.
void ConsoleRemovedLines(const Block& block, const BundleAdjustmentResult& result,
                         double default_marker_m, std::vector<std::string>* lines) {
  if (!result.rejected_marks.empty())
    lines->push_back(std::to_string(result.rejected_marks.size()) +
                     " marks rejected as blunders (listed in the report)");
  for (const BundleUnresolvedPoint& u : result.unresolved_points)
    lines->push_back("warning: tie point '" + PointName(block, u.point) +
                     "' unresolved: its marks disagree, but leaving out its mark on image '" +
                     block.images[block.marks[u.worst_mark].image].name + "' or on image '" +
                     block.images[block.marks[u.runner_up_mark].image].name +
                     "' explains it nearly as well; left out with all its marks, not adjusted");
  for (const BundleRejectedCheckMark& r : result.rejected_check_marks) {
    const BlockMark& mark = block.marks[r.mark];
    lines->push_back("check mark of '" + PointName(block, mark.point) + "' on image '" +
                     block.images[mark.image].name + "' rejected by the w-test (|w| = " +
                     FormatUnitless(r.normalized, 1) + "): check its measurement");
  }
  for (const BundleSnoopingStep& step : result.snooping)
    lines->push_back("snooping removed the " + BundleItemName(block, step.group, step.item) + " (" +
                     BundleAxisName(step.group, step.axis) +
                     ", |w| = " + FormatUnitless(step.normalized, 1) + ")");
  const std::string assumed = ControlRemovedOnAssumedAccuracy(block, result, default_marker_m);
  if (!assumed.empty()) lines->push_back("warning: " + assumed);
}

// The leave-one-out RMSE of the control points and those that stand out.
void ConsoleCrossValidationLines(const Block& block, const BundleCrossValidationResult& cv,
                                 std::vector<std::string>* lines) {
  const LengthUnit unit = LengthUnitFor(cv.rmse_m.maxCoeff());
  lines->push_back("leave-one-out control points (" + std::string(EnumName(cv.method)) + ", " +
                   FormatSignificant(cv.time_seconds, 3) + " s): " + std::to_string(cv.count) +
                   ", RMSE X " + FormatLength(cv.rmse_m.x(), unit) + " Y " +
                   FormatLength(cv.rmse_m.y(), unit) + " Z " + FormatLength(cv.rmse_m.z(), unit) +
                   " " + LengthUnitName(unit));
  for (const BundleCrossValidationPoint& p : cv.points) {
    if (p.stands_out)
      lines->push_back(
          "control point '" + PointName(block, p.point) + "' stands out: left out, it misses by " +
          FormatLengthWithUnit(p.error_m.norm()) + " (normalized " + FormatUnitless(p.normalized) +
          " > " + FormatUnitless(cv.threshold) + "): check its coordinates and marks");
    else if (!p.ok)
      lines->push_back("control point '" + PointName(block, p.point) +
                       "' not cross-validated: " + p.message);
  }
}

}  // namespace

std::vector<std::string> BundleConsoleLines(const Block& block,
                                            const BundleAdjustmentResult& result,
                                            const BundleReportContext& context) {
  // Every number through the report kit's formatters (tools/report/html_kit.h): fixed units,
  // never an exponent.
  std::vector<std::string> lines;
  const BundleAdjustmentSummary& s = result.summary;
  lines.push_back(ConsoleSummaryLine(s));
  lines.push_back(ConsoleTimeLine(s));
  lines.push_back("datum: " + s.datum_description);
  if (context.georeference != nullptr) ConsoleGeoreferenceLines(*context.georeference, &lines);
  if (!s.covariance_datum.empty()) lines.push_back("covariances in " + s.covariance_datum);
  ConsoleGroupLines(result, &lines);
  if (!s.tie_points_left_out.empty())
    lines.push_back(TiePointsLeftOutWarning(s.tie_points_left_out));
  ConsoleAccuracyLines(result, &lines);
  ConsolePointLines(block, result, context.options.accuracies.marker_m, &lines);
  ConsoleRemovedLines(block, result, context.options.accuracies.marker_m, &lines);
  const std::string weak = WeaklyDeterminedWarning(result);
  if (!weak.empty()) lines.push_back("warning: weakly determined: " + weak);
  if (result.num_uncontrolled > 0)
    lines.push_back(std::to_string(result.num_uncontrolled) +
                    " observations are uncontrolled (redundancy number below " +
                    FormatUnitless(context.options.statistics.uncontrolled_redundancy) +
                    "): a blunder there cannot be seen; add images or points around them");
  if (context.cross_validation != nullptr)
    ConsoleCrossValidationLines(block, *context.cross_validation, &lines);
  return lines;
}

}  // namespace photopose::cli
