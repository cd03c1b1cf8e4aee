// The bundle adjustment (solvers/bundle/bundle_adjustment.h) with its composed options, config and
// result (statistics, check points, diagnostics), its progress as a Python callback; the block's
// initial values (solvers/bundle/block_initialization.h); control-point cross-validation.

#include <exception>

#include "common.h"
#include "solvers/bundle/block_initialization.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/taylor_bundle.h"

namespace photopose::python {
namespace {

py::dict ObservationColumns(const BundleAdjustmentResult& r) {
  const size_t n = r.observations.size();
  std::vector<int> group(n), item(n), axis(n);
  // The reported values are single precision in the result (BundleObservationDiagnostics): float32.
  std::vector<double> redundancy(n), normalized(n);
  std::vector<float> residual(n), sigma(n), mdb(n), external(n);
  py::array_t<bool> rejected(static_cast<py::ssize_t>(n));
  for (size_t i = 0; i < n; ++i) {
    const BundleObservationDiagnostics& o = r.observations[i];
    group[i] = static_cast<int>(o.group);
    item[i] = o.item;
    axis[i] = o.axis;
    residual[i] = o.residual;
    sigma[i] = o.sigma;
    redundancy[i] = o.redundancy;
    normalized[i] = o.normalized;
    mdb[i] = o.mdb;
    external[i] = o.external_m;
    rejected.mutable_data()[i] = o.rejected;
  }
  py::dict d;
  d["group"] = ToArray(group);
  d["item"] = ToArray(item);
  d["axis"] = ToArray(axis);
  d["residual"] = ToArray(residual);
  d["sigma"] = ToArray(sigma);
  d["redundancy"] = ToArray(redundancy);
  d["normalized"] = ToArray(normalized);
  d["mdb"] = ToArray(mdb);
  d["external_m"] = ToArray(external);
  d["rejected"] = rejected;
  return d;
}

std::string SummaryRepr(const BundleAdjustmentSummary& s) {
  return "BundleAdjustmentSummary(" + s.BriefReport() + ")";
}

// The options of bundle_adjust, one class per part, then the composed BundleAdjustmentOptions.
void BindBundleOptions(py::module_& m) {
  auto acc = BindStruct<BundleAccuracies>(m, "BundleAccuracies", R"doc(
The stated accuracies of the objective's groups (one sigma; Metashape's reference settings by
default). A per-row accuracy of the tables overrides its row's default.)doc");
  acc.def_readwrite("tie_px", &BundleAccuracies::tie_px, "px")
      .def_readwrite("marker_projection_px", &BundleAccuracies::marker_projection_px, "px")
      .def_readwrite("tie_film_um", &BundleAccuracies::tie_film_um, "um")
      .def_readwrite("marker_projection_film_um", &BundleAccuracies::marker_projection_film_um, "um")
      .def_readwrite("marker_m", &BundleAccuracies::marker_m, "m, per axis")
      .def_readwrite("camera_m", &BundleAccuracies::camera_m, "m, X, Y, Z")
      .def_readwrite("camera_positions_are_priors", &BundleAccuracies::camera_positions_are_priors)
      .def_readwrite("attitude_deg", &BundleAccuracies::attitude_deg, "deg per angle, or None");

  auto rob = BindStruct<BundleRobustnessOptions>(m, "BundleRobustnessOptions",
                                                 "Robust loss on tie marks, rejection rounds, data snooping.");
  rob.def_readwrite("tie_loss", &BundleRobustnessOptions::tie_loss, "'none', 'huber', 'cauchy', 'softl1'")
      .def_readwrite("tie_loss_scale_sigmas", &BundleRobustnessOptions::tie_loss_scale_sigmas, "sigmas")
      .def_readwrite("rejection_threshold", &BundleRobustnessOptions::rejection_threshold, "unitless")
      .def_readwrite("max_rejection_rounds", &BundleRobustnessOptions::max_rejection_rounds, "count")
      .def_readwrite("snoop", &BundleRobustnessOptions::snoop)
      .def_readwrite("max_snooping_removals", &BundleRobustnessOptions::max_snooping_removals, "count")
      .def_readwrite("snooping_batch", &BundleRobustnessOptions::snooping_batch,
                     "several removals per round where the round's statistics decide them");
  DefValidate(rob, "BundleRobustnessOptions");

  auto stats = BindStruct<BundleStatisticsOptions>(m, "BundleStatisticsOptions",
                                                   "Covariances, verdicts, diagnostics, variance components.");
  stats
      .def_readwrite("covariances", &BundleStatisticsOptions::covariances,
                     "'full' (selected inversion), 'dense' (the test oracle) or 'none'")
      .def_readwrite(
          "weak_sigma_inflation", &BundleStatisticsOptions::weak_sigma_inflation,
          "unitless: sigma inflation above which a parameter is listed as weakly determined")
      .def_readwrite("relative_covariance", &BundleStatisticsOptions::relative_covariance,
                     "a relative block's covariance datum: 'points', 'centres' or 'first_image'")
      .def_readwrite("overfit_ratio", &BundleStatisticsOptions::overfit_ratio)
      .def_readwrite("overfit_redundancy_share", &BundleStatisticsOptions::overfit_redundancy_share)
      .def_readwrite("checked_redundancy_share", &BundleStatisticsOptions::checked_redundancy_share,
                     "above it a prior group's small RMS is a loose accuracy, not over-fitting")
      .def_readwrite("high_correlation", &BundleStatisticsOptions::high_correlation)
      .def_readwrite("observation_diagnostics", &BundleStatisticsOptions::observation_diagnostics)
      .def_readwrite("snooping_alpha", &BundleStatisticsOptions::snooping_alpha)
      .def_readwrite("snooping_family_wise", &BundleStatisticsOptions::snooping_family_wise)
      .def_readwrite("snooping_power", &BundleStatisticsOptions::snooping_power)
      .def_readwrite("uncontrolled_redundancy", &BundleStatisticsOptions::uncontrolled_redundancy)
      .def_readwrite("estimate_accuracies", &BundleStatisticsOptions::estimate_accuracies)
      .def_readwrite("max_variance_iterations", &BundleStatisticsOptions::max_variance_iterations)
      .def_readwrite("variance_tolerance", &BundleStatisticsOptions::variance_tolerance)
      .def_readwrite("min_variance_redundancy", &BundleStatisticsOptions::min_variance_redundancy)
      .def_readwrite("cross_validation", &BundleStatisticsOptions::cross_validation,
                     "'update' (one linearised step per left-out point from the full adjustment) "
                     "or 'refit' (one adjustment per point)");
  DefValidate(stats, "BundleStatisticsOptions");

  auto solver = BindStruct<BundleSolverOptions>(m, "BundleSolverOptions", R"doc(
How the minimum is found. The progress hook is bundle_adjust's `progress` argument.)doc");
  solver.def_readwrite("jacobian", &BundleSolverOptions::jacobian, "'analytic' or 'autodiff'")
      .def_readwrite("max_iterations", &BundleSolverOptions::max_iterations, "per round")
      .def_readwrite("function_tolerance", &BundleSolverOptions::function_tolerance)
      .def_readwrite("parameter_tolerance", &BundleSolverOptions::parameter_tolerance)
      .def_readwrite("gradient_tolerance", &BundleSolverOptions::gradient_tolerance)
      .def_readwrite("linear_solver", &BundleSolverOptions::linear_solver)
      .def_readwrite("free_gauge_for_relative_blocks", &BundleSolverOptions::free_gauge_for_relative_blocks)
      .def_readwrite("num_threads", &BundleSolverOptions::num_threads, "0: all cores");
  DefValidate(solver, "BundleSolverOptions");

  auto options = BindStruct<BundleAdjustmentOptions>(m, "BundleAdjustmentOptions", R"doc(
The options of bundle_adjust, composed as in C++: accuracies, robustness, statistics, solver.)doc");
  options.def_readwrite("accuracies", &BundleAdjustmentOptions::accuracies)
      .def_readwrite("robustness", &BundleAdjustmentOptions::robustness)
      .def_readwrite("statistics", &BundleAdjustmentOptions::statistics)
      .def_readwrite("solver", &BundleAdjustmentOptions::solver);
  DefValidate(options, "BundleAdjustmentOptions");
}

// What the adjustment holds constant or estimates.
void BindBundleConfig(py::module_& m) {
  auto config = BindStruct<BundleAdjustmentConfig>(m, "BundleAdjustmentConfig", R"doc(
What the adjustment holds constant or estimates: per camera the parameter indices to calibrate,
constant images and points, the GNSS lever arm (camera frame u, v, w; m).)doc");
  config.def_readwrite("calibrated_params", &BundleAdjustmentConfig::calibrated_params)
      .def_readwrite("constant_images", &BundleAdjustmentConfig::constant_images)
      .def_readwrite("constant_points", &BundleAdjustmentConfig::constant_points)
      .def_readwrite("lever_arm_m", &BundleAdjustmentConfig::lever_arm_m)
      .def_readwrite("estimate_lever_arm", &BundleAdjustmentConfig::estimate_lever_arm);
  config.def_static("from_calibration_names", [](const PythonBlock& block, const std::vector<std::string>& names) {
    BundleAdjustmentConfig out;
    ThrowIfError(BundleAdjustmentConfig::FromCalibrationNames(block.block, names, &out));
    return out;
  }, py::arg("block"), py::arg("names"),
     "Self-calibration of every camera by name ('FocalLength', 'PrincipalX', 'K1', ...: "
     "`photopose bundle --calibrate`).");
}

// The progress hook's iteration and the summary of an adjustment.
void BindBundleProgressAndSummary(py::module_& m) {
  py::class_<BundleIterationInfo> info(m, "BundleIterationInfo", "One iteration, as progress reports it.");
  info.def_readonly("round", &BundleIterationInfo::round)
      .def_readonly("iteration", &BundleIterationInfo::iteration)
      .def_readonly("cost", &BundleIterationInfo::cost)
      .def_readonly("sigma0", &BundleIterationInfo::sigma0)
      .def_readonly("step_norm", &BundleIterationInfo::step_norm)
      .def_readonly("elapsed_seconds", &BundleIterationInfo::elapsed_seconds)
      .def_readonly("free_gauge", &BundleIterationInfo::free_gauge)
      .def_readonly("trust_region_radius", &BundleIterationInfo::trust_region_radius)
      .def_readonly("step_quality", &BundleIterationInfo::step_quality)
      .def_readonly("step_successful", &BundleIterationInfo::step_successful)
      .def_readonly("linear_solver_seconds", &BundleIterationInfo::linear_solver_seconds)
      .def_readonly("iteration_seconds", &BundleIterationInfo::iteration_seconds)
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });

  py::class_<BundleAdjustmentSummary> summary(m, "BundleAdjustmentSummary");
  summary.def_readonly("termination", &BundleAdjustmentSummary::termination,
                       "'converged', 'no_convergence', 'failure' or 'cancelled'")
      .def_readonly("message", &BundleAdjustmentSummary::message)
      .def_readonly("datum", &BundleAdjustmentSummary::datum, "'absolute' or 'relative'")
      .def_readonly("datum_description", &BundleAdjustmentSummary::datum_description)
      .def_readonly("rounds", &BundleAdjustmentSummary::rounds)
      .def_readonly("snooping_rounds", &BundleAdjustmentSummary::snooping_rounds, "count")
      .def_readonly("snooping_seconds", &BundleAdjustmentSummary::snooping_seconds, "s")
      .def_readonly("iterations", &BundleAdjustmentSummary::iterations)
      .def_readonly("initial_cost", &BundleAdjustmentSummary::initial_cost)
      .def_readonly("final_cost", &BundleAdjustmentSummary::final_cost)
      .def_readonly("sigma0", &BundleAdjustmentSummary::sigma0)
      .def_readonly("redundancy", &BundleAdjustmentSummary::redundancy)
      .def_readonly("num_images", &BundleAdjustmentSummary::num_images)
      .def_readonly("num_points", &BundleAdjustmentSummary::num_points)
      .def_readonly("num_marks", &BundleAdjustmentSummary::num_marks)
      .def_readonly("num_rejected_marks", &BundleAdjustmentSummary::num_rejected_marks)
      .def_readonly("tie_points_left_out", &BundleAdjustmentSummary::tie_points_left_out)
      .def_readonly("time_seconds", &BundleAdjustmentSummary::time_seconds)
      .def_readonly("statistics_seconds", &BundleAdjustmentSummary::statistics_seconds)
      .def_readonly("problem_build_seconds", &BundleAdjustmentSummary::problem_build_seconds)
      .def_readonly("solver_preprocessing_seconds", &BundleAdjustmentSummary::solver_preprocessing_seconds)
      .def_readonly("residual_evaluation_seconds", &BundleAdjustmentSummary::residual_evaluation_seconds)
      .def_readonly("jacobian_evaluation_seconds", &BundleAdjustmentSummary::jacobian_evaluation_seconds)
      .def_readonly("linear_solver_seconds", &BundleAdjustmentSummary::linear_solver_seconds)
      .def_readonly("schur_structure", &BundleAdjustmentSummary::schur_structure)
      .def_readonly("solver", &BundleAdjustmentSummary::solver,
                    "'ceres', 'taylor' or 'taylor_as_printed': which solver the times are of")
      .def_readonly("plan_seconds", &BundleAdjustmentSummary::plan_seconds, "s")
      .def_readonly("round_seconds", &BundleAdjustmentSummary::round_seconds, "s per round")
      .def_readonly("rejection_seconds", &BundleAdjustmentSummary::rejection_seconds, "s")
      .def_readonly("factorization_seconds", &BundleAdjustmentSummary::factorization_seconds, "s")
      .def_readonly("inversion_seconds", &BundleAdjustmentSummary::inversion_seconds, "s")
      .def_readonly("covariance_entries", &BundleAdjustmentSummary::covariance_entries, "count")
      .def_readonly("covariance_memory_bytes", &BundleAdjustmentSummary::covariance_memory_bytes,
                    "bytes")
      .def_readonly("covariance_datum", &BundleAdjustmentSummary::covariance_datum,
                    "what the covariances refer to, in words")
      .def("is_solution_usable", &BundleAdjustmentSummary::IsSolutionUsable)
      .def("brief_report", &BundleAdjustmentSummary::BriefReport)
      .def("__repr__", &SummaryRepr);
}

// The parts of a result: per image, per point, per group, calibration, rejections, snooping.
// The per-item parts of a BundleAdjustmentResult: images, points, groups, calibrations.
void BindBundleItemResults(py::module_& m) {
  py::class_<BundleImageResult>(m, "BundleImageResult")
      .def_readonly("adjusted", &BundleImageResult::adjusted)
      .def_readonly("message", &BundleImageResult::message)
      .def_property_readonly("covariance", [](const BundleImageResult& r) { return Matrix6d(r.covariance); },
                             "6 x 6 (m, rad; seed)")
      .def_readonly("has_covariance", &BundleImageResult::has_covariance)
      .def_readonly("num_marks", &BundleImageResult::num_marks)
      .def_readonly("rms_residual", &BundleImageResult::rms_residual)
      .def_readonly("unit", &BundleImageResult::unit,
                    "rms_residual's unit: 'px', 'um', or 'sigma' for an image with pixel and film marks")
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });

  py::class_<BundlePointResult>(m, "BundlePointResult")
      .def_readonly("num_observations", &BundlePointResult::num_observations)
      .def_property_readonly("covariance", [](const BundlePointResult& r) { return Eigen::Matrix3d(r.covariance); },
                             "3 x 3 (m^2)")
      .def_readonly("has_covariance", &BundlePointResult::has_covariance)
      .def_readonly("covariance_complete", &BundlePointResult::covariance_complete,
                    "False for a check point whose covariance is the intersection's alone (no "
                    "statistics: the images taken as error-free)")
      .def_readonly("error_m", &BundlePointResult::error_m, "adjusted or intersected - surveyed (m)")
      .def_readonly("message", &BundlePointResult::message)
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });

  py::class_<BundleGroupStatistics>(m, "BundleGroupStatistics", "One group of the objective.")
      .def_readonly("group", &BundleGroupStatistics::group)
      .def_readonly("count", &BundleGroupStatistics::count)
      .def_readonly("unit", &BundleGroupStatistics::unit)
      .def_readonly("stated_accuracy", &BundleGroupStatistics::stated_accuracy)
      .def_readonly("num_axes", &BundleGroupStatistics::num_axes)
      .def_readonly("rms", &BundleGroupStatistics::rms)
      .def_readonly("rms_total", &BundleGroupStatistics::rms_total)
      .def_readonly("ratio", &BundleGroupStatistics::ratio)
      .def_readonly("redundancy_share", &BundleGroupStatistics::redundancy_share)
      .def_readonly("overfit", &BundleGroupStatistics::overfit)
      .def_readonly("message", &BundleGroupStatistics::message)
      .def_readonly("num_fixed", &BundleGroupStatistics::num_fixed,
                    "items held fixed (control points stated error-free): not in count or verdict")
      .def_property_readonly("fixed", &BundleGroupStatistics::fixed,
                             "every item held fixed: no residuals, no verdict")
      .def_readonly("estimated_accuracy", &BundleGroupStatistics::estimated_accuracy)
      .def_readonly("estimated_accuracy_standard_error", &BundleGroupStatistics::estimated_accuracy_standard_error)
      .def_readonly("estimation_message", &BundleGroupStatistics::estimation_message)
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });

  py::class_<BundleCalibrationResult>(m, "BundleCalibrationResult")
      .def_readonly("camera", &BundleCalibrationResult::camera)
      .def_readonly("names", &BundleCalibrationResult::names)
      .def_readonly("indices", &BundleCalibrationResult::indices)
      .def_readonly("values", &BundleCalibrationResult::values)
      .def_readonly("sigmas", &BundleCalibrationResult::sigmas)
      .def_readonly("correlation", &BundleCalibrationResult::correlation)
      .def_readonly("high_correlations", &BundleCalibrationResult::high_correlations)
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
}

// What the rounds of a bundle took out or flagged: rejected marks, weak parameters, rejected
// check marks, data-snooping steps.
void BindBundleRejections(py::module_& m) {
  py::class_<BundleRejectedMark>(m, "BundleRejectedMark")
      .def_readonly("mark", &BundleRejectedMark::mark)
      .def_readonly("round", &BundleRejectedMark::round)
      .def_readonly("whitened_residual", &BundleRejectedMark::whitened_residual)
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });

  py::class_<BundleWeakParameter>(m, "BundleWeakParameter",
                                  "A parameter that trades off nearly exactly with others (weakly determined).")
      .def_readonly("parameter", &BundleWeakParameter::parameter, "in words, e.g. \"image 'IMG_3': omega\"")
      .def_readonly("sigma_inflation", &BundleWeakParameter::sigma_inflation,
                    "its sigma over what its own observations give it (unitless)")
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
  py::class_<BundleRejectedCheckMark>(m, "BundleRejectedCheckMark",
                                      "A check point's mark rejected by the w-test of its intersection.")
      .def_readonly("mark", &BundleRejectedCheckMark::mark, "index into the block's marks")
      .def_readonly("normalized", &BundleRejectedCheckMark::normalized, "the larger |w| of x and y")
      .def_property_readonly("residual", [](const BundleRejectedCheckMark& r) { return Eigen::Vector2d(r.residual); },
                             "observed - computed at the intersection that still held it, in the mark's own unit (px or um; "
                             "x right, y up)")
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });

  py::class_<BundleSnoopingStep>(m, "BundleSnoopingStep")
      .def_readonly("group", &BundleSnoopingStep::group)
      .def_readonly("item", &BundleSnoopingStep::item)
      .def_readonly("axis", &BundleSnoopingStep::axis)
      .def_readonly("normalized", &BundleSnoopingStep::normalized)
      .def_readonly("residual", &BundleSnoopingStep::residual)
      .def_readonly("round", &BundleSnoopingStep::round, "1-based")
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
}

// The result of bundle_adjust, with its per-observation diagnostics and arrays.
void BindBundleResult(py::module_& m) {
  py::class_<BundleAdjustmentResult> result(m, "BundleAdjustmentResult", R"doc(
The adjustment's result: summary (termination, sigma0, redundancy, timings), per image and per
point results, the groups' statistics and over-fitting verdicts, calibration, rejected marks,
check- and control-point RMSE, mark residuals, per-observation diagnostics. The block passed to
bundle_adjust holds the adjusted values.)doc");
  result.def_readonly("summary", &BundleAdjustmentResult::summary)
      .def_readonly("images", &BundleAdjustmentResult::images)
      .def_readonly("points", &BundleAdjustmentResult::points)
      .def_readonly("groups", &BundleAdjustmentResult::groups)
      .def_readonly("calibration", &BundleAdjustmentResult::calibration)
      .def_readonly("weakly_determined", &BundleAdjustmentResult::weakly_determined,
                    "weakly determined parameters of an absolute block, the worst first")
      .def_readonly("rejected_marks", &BundleAdjustmentResult::rejected_marks)
      .def_readonly("rejected_check_marks", &BundleAdjustmentResult::rejected_check_marks)
      .def_readonly("lever_arm_m", &BundleAdjustmentResult::lever_arm_m)
      .def_readonly("num_check_points", &BundleAdjustmentResult::num_check_points)
      .def_readonly("check_rmse_m", &BundleAdjustmentResult::check_rmse_m)
      .def_readonly("check_rmse_total_m", &BundleAdjustmentResult::check_rmse_total_m)
      .def_readonly("num_control_points", &BundleAdjustmentResult::num_control_points)
      .def_readonly("control_rmse_m", &BundleAdjustmentResult::control_rmse_m)
      .def_readonly("control_rmse_total_m", &BundleAdjustmentResult::control_rmse_total_m)
      .def_property_readonly("mark_residuals", [](const BundleAdjustmentResult& r) { return ToArray(r.mark_residuals); },
                             "M x 2 observed - computed (the mark's unit); NaN rows: not used.")
      .def_readonly("variance_iterations", &BundleAdjustmentResult::variance_iterations)
      .def_property_readonly("observations", &ObservationColumns, R"doc(
Per-observation diagnostics as columns (dict of equal-length arrays): group (0 tie marks, 1
control marks, 2 control points, 3 camera positions, 4 attitudes), item, axis, residual, sigma,
redundancy, normalized, mdb, external_m, rejected. Empty arrays when not computed.)doc")
      .def_readonly("critical_value", &BundleAdjustmentResult::critical_value)
      .def_readonly("alpha_per_observation", &BundleAdjustmentResult::alpha_per_observation)
      .def_readonly("delta0", &BundleAdjustmentResult::delta0)
      .def_readonly("num_uncontrolled", &BundleAdjustmentResult::num_uncontrolled)
      .def_readonly("snooping", &BundleAdjustmentResult::snooping)
      .def_property_readonly("image_adjusted", [](const BundleAdjustmentResult& r) {
        py::array_t<bool> out(static_cast<py::ssize_t>(r.images.size()));
        for (size_t i = 0; i < r.images.size(); ++i) out.mutable_data()[i] = r.images[i].adjusted;
        return out;
      })
      .def_property_readonly("image_covariances", [](const BundleAdjustmentResult& r) {
        return StackOrNaN(r.images.size(), 6, 6, [&](size_t i) -> std::optional<Matrix6d> {
          if (!r.images[i].has_covariance) return std::nullopt;
          return r.images[i].covariance;
        });
      }, "N x 6 x 6 (m, rad; seed); NaN without covariance.")
      .def_property_readonly("image_standard_deviations", [](const BundleAdjustmentResult& r) {
        return OptionalRowsArray(r.images.size(), 6, [&](size_t i) -> std::optional<Vector6d> {
          if (!r.images[i].has_covariance) return std::nullopt;
          return r.images[i].covariance.diagonal().cwiseSqrt();
        });
      }, "N x 6 (m, rad; seed); NaN without covariance.")
      .def_property_readonly("point_errors_m", [](const BundleAdjustmentResult& r) {
        return OptionalRowsArray(r.points.size(), 3, [&](size_t i) { return r.points[i].error_m; });
      }, "N x 3 adjusted (control) or intersected (check) - surveyed (m); NaN for tie points.")
      .def("full_report", [](const BundleAdjustmentResult& r, const PythonBlock& b) { return r.FullReport(b.block); },
           py::arg("block"), "The multi-line report: summary, groups and verdicts, images, points, calibration.")
      .def("__repr__", [](const BundleAdjustmentResult& r) {
        return "BundleAdjustmentResult(" + r.summary.BriefReport() + ")";
      });
}

// bundle_adjust: the adjustment in place, its progress as a Python callback.
void BindBundleAdjust(py::module_& m) {
  m.def("bundle_adjust",
        [](PythonBlock& block, std::optional<BundleAdjustmentOptions> options,
           std::optional<BundleAdjustmentConfig> config, const py::object& progress,
           PoseSolver solver) {
          BundleAdjustmentOptions o = options.value_or(BundleAdjustmentOptions());
          const BundleAdjustmentConfig c = config.value_or(BundleAdjustmentConfig());
          ProgressRelay relay(progress);
          o.solver.progress = relay.Function();
          BundleAdjustmentResult result;
          CallWithoutGil([&] { return BundleAdjustWithSolver(solver, o, c, &block.block, &result); },
                         &relay);
          return result;
        },
        py::arg("block"), py::arg("options") = py::none(), py::arg("config") = py::none(),
        py::kw_only(), py::arg("progress") = py::none(), py::arg("solver") = PoseSolver::kCeres,
        R"doc(
Adjusts the block in place: on success its images' orientations, points' positions and cameras'
parameters hold the adjusted values. Every image needs an orientation and every tie point a
position (initialize_block). solver: 'ceres' (BundleAdjust, the default), 'taylor' (the
hand-written Levenberg-Marquardt block solver on its reduced normal equations, the same objective,
rounds and statistics) or 'taylor_as_printed' (the lecture's partials as printed); the Taylor
solvers refuse what they cannot adjust (self-calibration, COLMAP camera models, an estimated lever
arm) with the reason. Raises photopose.Error for invalid options or a block the
adjustment cannot use; a failed or unconverged adjustment is result.summary.termination with the
block unchanged. progress(info: BundleIterationInfo) is called after every iteration (from the
adjusting thread, with the GIL); returning False stops the adjustment after that iteration
(result.summary.termination 'cancelled', the block unchanged; the Taylor solvers too); an
exception it raises stops it too and is raised when the call returns.)doc");
}

// Initial values of a block (solvers/bundle/block_initialization.h).
void BindBlockInitialization(py::module_& m) {
  auto init_options = BindStruct<BlockInitializationOptions>(m, "BlockInitializationOptions",
                                                             "Initial values of a block: resection and intersection.");
  init_options.def_readwrite("resection", &BlockInitializationOptions::resection)
      .def_readwrite("min_marks_for_resection", &BlockInitializationOptions::min_marks_for_resection)
      .def_readwrite("min_intersection_angle_rad", &BlockInitializationOptions::min_intersection_angle_rad, "rad")
      .def_readwrite("max_ray_misfit_rad", &BlockInitializationOptions::max_ray_misfit_rad, "rad")
      .def_readwrite("default_sigma_px", &BlockInitializationOptions::default_sigma_px, "px")
      .def_readwrite("default_sigma_um", &BlockInitializationOptions::default_sigma_um, "um")
      .def_readwrite("max_rounds", &BlockInitializationOptions::max_rounds);

  py::class_<BlockInitializationSummary>(m, "BlockInitializationSummary")
      .def_readonly("images_given", &BlockInitializationSummary::images_given)
      .def_readonly("images_resected", &BlockInitializationSummary::images_resected)
      .def_readonly("points_given", &BlockInitializationSummary::points_given)
      .def_readonly("points_triangulated", &BlockInitializationSummary::points_triangulated)
      .def_readonly("rounds", &BlockInitializationSummary::rounds)
      .def_readonly("not_oriented", &BlockInitializationSummary::not_oriented, "[(image, reason)]")
      .def_readonly("points_not_triangulated", &BlockInitializationSummary::points_not_triangulated)
      .def("brief_report", &BlockInitializationSummary::BriefReport)
      .def("__repr__", [](const BlockInitializationSummary& s) {
        return "BlockInitializationSummary(" + s.BriefReport() + ")";
      });

  m.def("initialize_block",
        [](PythonBlock& block, std::optional<BlockInitializationOptions> options) {
          const BlockInitializationOptions o = options.value_or(BlockInitializationOptions());
          BlockInitializationSummary summary;
          CallWithoutGil([&] { return InitializeBlock(o, &block.block, &summary); });
          return summary;
        },
        py::arg("block"), py::arg("options") = py::none(),
        "Fills in missing orientations (resection) and tie-point positions (intersection) in "
        "place (InitializeBlock); images it cannot orient are listed in the summary.");
}

// Leave-one-out cross-validation of the control points.
void BindCrossValidation(py::module_& m) {
  py::class_<BundleCrossValidationPoint>(m, "BundleCrossValidationPoint")
      .def_readonly("point", &BundleCrossValidationPoint::point)
      .def_readonly("ok", &BundleCrossValidationPoint::ok)
      .def_readonly("message", &BundleCrossValidationPoint::message)
      .def_readonly("error_m", &BundleCrossValidationPoint::error_m)
      .def_readonly("num_images", &BundleCrossValidationPoint::num_images)
      .def_readonly("normalized", &BundleCrossValidationPoint::normalized)
      .def_readonly("stands_out", &BundleCrossValidationPoint::stands_out)
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
  py::class_<BundleCrossValidationResult>(m, "BundleCrossValidationResult")
      .def_readonly("points", &BundleCrossValidationResult::points)
      .def_readonly("count", &BundleCrossValidationResult::count)
      .def_readonly("rmse_m", &BundleCrossValidationResult::rmse_m)
      .def_readonly("rmse_total_m", &BundleCrossValidationResult::rmse_total_m)
      .def_readonly("threshold", &BundleCrossValidationResult::threshold)
      .def_readonly("time_seconds", &BundleCrossValidationResult::time_seconds)
      .def_readonly("method", &BundleCrossValidationResult::method)
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
  m.def("cross_validate_control_points",
        [](const PythonBlock& adjusted, const BundleAdjustmentResult& full,
           std::optional<BundleAdjustmentOptions> options, std::optional<BundleAdjustmentConfig> config,
           int num_threads) {
          const BundleAdjustmentOptions o = options.value_or(BundleAdjustmentOptions());
          const BundleAdjustmentConfig c = config.value_or(BundleAdjustmentConfig());
          if (num_threads < 0) throw py::value_error("num_threads must be >= 0 (0: all cores)");
          BundleCrossValidationResult out;
          CallWithoutGil([&] {
            return CrossValidateControlPoints(o, c, adjusted.block, full, num_threads, &out);
          });
          return out;
        },
        py::arg("adjusted"), py::arg("full"), py::arg("options") = py::none(),
        py::arg("config") = py::none(), py::arg("num_threads") = 0,
        "Leave-one-out: each control point of the adjusted block in turn as a check point "
        "(CrossValidateControlPoints), with the options and config of the full adjustment.");
}

}  // namespace

// In this order: a function's signature names the classes bound before it.
void BindBundle(py::module_& m) {
  BindBundleOptions(m);
  BindBundleConfig(m);
  BindBundleProgressAndSummary(m);
  BindBundleItemResults(m);
  BindBundleRejections(m);
  BindBundleResult(m);
  BindBundleAdjust(m);
  BindBlockInitialization(m);
  BindCrossValidation(m);
}

}  // namespace photopose::python
