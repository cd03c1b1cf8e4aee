// Single-image resection (solvers/resection/resection.h): its composed options, its input from
// numpy arrays, its result with summary, covariance and per-mark statistics, one image or many.

#include "common.h"
#include "solvers/resection/resection.h"

namespace photopose::python {
namespace {

ResectionInput MakeInput(const py::object& image_plane, const py::object& points,
                         double focal_length, const py::object& sigma,
                         const py::object& units_per_unit, const py::object& units,
                         const py::object& point_ids, std::optional<ExteriorOrientation> approximate,
                         const std::string& raster, double earth_radius_m) {
  ResectionInput input;
  input.raster = raster;
  input.focal_length = focal_length;
  input.image_plane = Points2(image_plane, "image_plane");
  input.points_in_ground = Points3(points, "points_in_ground");
  const long n = static_cast<long>(input.image_plane.size());
  if (static_cast<long>(input.points_in_ground.size()) != n)
    throw py::value_error("image_plane has " + std::to_string(n) + " rows but points_in_ground " +
                          std::to_string(input.points_in_ground.size()));
  if (!sigma.is_none()) input.sigma = Vector(sigma, "sigma", n, true);
  if (!units_per_unit.is_none())
    input.observation_units_per_unit = Vector(units_per_unit, "observation_units_per_unit", n, true);
  if (!units.is_none()) {
    if (py::isinstance<py::str>(units)) {
      input.units.assign(n, units.cast<MarkUnit>());
    } else {
      for (const py::handle u : py::iter(units)) input.units.push_back(u.cast<MarkUnit>());
      if (static_cast<long>(input.units.size()) != n)
        throw py::value_error("units: expected " + std::to_string(n) + " names, got " +
                              std::to_string(input.units.size()));
    }
  }
  input.point_ids = Strings(point_ids, "point_ids");
  if (!input.point_ids.empty() && static_cast<long>(input.point_ids.size()) != n)
    throw py::value_error("point_ids: expected " + std::to_string(n) + " names, got " +
                          std::to_string(input.point_ids.size()));
  input.approximate = approximate;
  input.earth_radius_m = earth_radius_m;
  return input;
}

std::string ResultRepr(const ResectionResult& r) {
  std::string verdict = r.success ? (r.weak ? "weak" : "solved")
                        : r.cancelled        ? "cancelled"
                        : r.ambiguous        ? "ambiguous"
                        : r.accuracy_disagrees ? "accuracy_disagrees"
                                               : "not_solved";
  char text[512];
  const Eigen::Vector3d c = r.eo.center_in_ground();
  if (r.success) {
    std::snprintf(text, sizeof(text),
                  "ResectionResult(%s, center_in_ground=[%.4f, %.4f, %.4f], sigma0=%.4g, "
                  "inliers=%d/%zu, degrees_of_freedom=%d)",
                  verdict.c_str(), c.x(), c.y(), c.z(), r.sigma0, r.num_inliers,
                  r.mark_status.size(), r.degrees_of_freedom);
  } else {
    std::snprintf(text, sizeof(text), "ResectionResult(%s, message=%s)", verdict.c_str(),
                  std::string(py::repr(py::str(r.summary.message))).c_str());
  }
  return text;
}

// The consensus' options: RANSAC, the absolute-pose estimator, the tests' confidence.
void BindConsensusOptions(py::module_& m) {
  auto ransac = BindStruct<RansacOptions>(m, "RansacOptions",
                                          "The consensus' sampling (solvers/resection/ransac.h).");
  ransac.def_readwrite("max_trials", &RansacOptions::max_trials, "count, >= 1")
      .def_readwrite("min_trials", &RansacOptions::min_trials, "count")
      .def_readwrite("confidence", &RansacOptions::confidence, "(0, 1)")
      .def_readwrite("seed", &RansacOptions::seed)
      .def_readwrite("local_optimization", &RansacOptions::local_optimization)
      .def_readwrite("max_lo_iterations", &RansacOptions::max_lo_iterations, "count")
      .def_readwrite("max_exhaustive_samples", &RansacOptions::max_exhaustive_samples, "count")
      .def_readwrite("stop_enumeration_when_all_inliers",
                     &RansacOptions::stop_enumeration_when_all_inliers);
  DefValidate(ransac, "RansacOptions");

  auto consensus = BindStruct<AbsolutePoseRansacOptions>(
      m, "AbsolutePoseRansacOptions",
      "The consensus over P3P and DLT samples (solvers/resection/absolute_pose.h); the threshold "
      "and score are set per image by the resection from its tests.");
  consensus.def_readwrite("ransac", &AbsolutePoseRansacOptions::ransac)
      .def_readwrite("inlier_threshold", &AbsolutePoseRansacOptions::inlier_threshold)
      .def_readwrite("lo_gauss_newton_iterations",
                     &AbsolutePoseRansacOptions::lo_gauss_newton_iterations, "count, >= 1")
      .def_readwrite("final_gauss_newton_iterations",
                     &AbsolutePoseRansacOptions::final_gauss_newton_iterations, "count, >= 0");
  DefValidate(consensus, "AbsolutePoseRansacOptions");

  auto test = BindStruct<OutlierTestOptions>(m, "OutlierTestOptions",
                                             "The confidence of every test of the resection.");
  test.def_readwrite("confidence", &OutlierTestOptions::confidence, "1 - alpha, (0, 1)");
  DefValidate(test, "OutlierTestOptions");
}

// The refinement's options (Ceres, Taylor) and the composed ResectionOptions.
void BindRefinementOptions(py::module_& m) {
  auto ceres = BindStruct<CeresPoseOptions>(m, "CeresPoseOptions",
                                            "How Ceres minimises one image's problem.");
  ceres.def_readwrite("minimizer", &CeresPoseOptions::minimizer, "'tiny_solver' or 'problem'")
      .def_readwrite("max_iterations", &CeresPoseOptions::max_iterations, "count")
      .def_readwrite("max_reweighting_rounds", &CeresPoseOptions::max_reweighting_rounds, "count")
      .def_readwrite("step_tolerance_sigmas", &CeresPoseOptions::step_tolerance_sigmas,
                     "the pose's standard deviations")
      .def_readwrite("function_tolerance", &CeresPoseOptions::function_tolerance)
      .def_readwrite("parameter_tolerance", &CeresPoseOptions::parameter_tolerance);
  DefValidate(ceres, "CeresPoseOptions");

  auto taylor = BindStruct<TaylorResectionOptions>(
      m, "TaylorResectionOptions", "The seed's Taylor Gauss-Newton (solvers/resection/taylor_resection.h).");
  taylor.def_readwrite("partials", &TaylorResectionOptions::partials)
      .def_readwrite("max_iterations", &TaylorResectionOptions::max_iterations, "count")
      .def_readwrite("position_tolerance_m", &TaylorResectionOptions::position_tolerance_m, "m")
      .def_readwrite("angle_tolerance_rad", &TaylorResectionOptions::angle_tolerance_rad, "rad")
      .def_readwrite("collinearity_tolerance", &TaylorResectionOptions::collinearity_tolerance)
      .def_readwrite("min_reciprocal_condition", &TaylorResectionOptions::min_reciprocal_condition)
      .def_readwrite("divergence_distance_factor",
                     &TaylorResectionOptions::divergence_distance_factor);
  DefValidate(taylor, "TaylorResectionOptions");

  auto refinement = BindStruct<PoseRefinementOptions>(
      m, "PoseRefinementOptions",
      "The least-squares refinement: solver ('ceres', 'taylor', 'taylor_as_printed'), Jacobian "
      "('analytic', 'autodiff'), loss ('none', 'huber', ...) and its scale (sigmas).");
  refinement.def_readwrite("solver", &PoseRefinementOptions::solver)
      .def_readwrite("jacobian", &PoseRefinementOptions::jacobian)
      .def_readwrite("loss", &PoseRefinementOptions::loss)
      .def_readwrite("loss_scale", &PoseRefinementOptions::loss_scale, "sigmas of the marks")
      .def_readwrite("ceres", &PoseRefinementOptions::ceres)
      .def_readwrite("taylor", &PoseRefinementOptions::taylor);
  DefValidate(refinement, "PoseRefinementOptions");

  auto options = BindStruct<ResectionOptions>(m, "ResectionOptions", R"doc(
The robust resection's options, composed as in C++: consensus (RANSAC), test (confidence),
refinement (solver, Jacobian, loss), and the verdict's limits.)doc");
  options.def_readwrite("consensus", &ResectionOptions::consensus)
      .def_readwrite("test", &ResectionOptions::test)
      .def_readwrite("refinement", &ResectionOptions::refinement)
      .def_readwrite("allow_no_redundancy", &ResectionOptions::allow_no_redundancy)
      .def_readwrite("ambiguous_pose_sigmas", &ResectionOptions::ambiguous_pose_sigmas,
                     "the accepted pose's standard deviations")
      .def_readwrite("detection_power", &ResectionOptions::detection_power, "(0, 1)")
      .def_readwrite("weak_pose_shift_sigmas", &ResectionOptions::weak_pose_shift_sigmas,
                     "standard deviations of a pose parameter")
      .def_readwrite("refuse_weak", &ResectionOptions::refuse_weak)
      .def_readwrite("consensus_after_approximate", &ResectionOptions::consensus_after_approximate,
                     "try the consensus start when the approximate pose does not solve the image");
  DefValidate(options, "ResectionOptions");
}

// One image's control marks.
void BindResectionInput(py::module_& m) {
  py::class_<ResectionInput> input(m, "ResectionInput", R"doc(
One image's control marks: N x 2 ideal image-plane points (distortion removed, principal point at
the origin, x right, y up, in the unit of focal_length: um for film cameras, px for the COLMAP
models), their N x 3 ground points (m), per-mark sigma in the mark's own unit (0 or None: not
stated), observation_units_per_unit (image-plane units per mark unit, e.g. um per px) and units
('px' or 'um'), an optional approximate pose. Block.resection_input builds it from a block.)doc");
  input.def(py::init(&MakeInput), py::arg("image_plane"), py::arg("points_in_ground"),
            py::arg("focal_length"), py::kw_only(), py::arg("sigma") = py::none(),
            py::arg("observation_units_per_unit") = py::none(), py::arg("units") = py::none(),
            py::arg("point_ids") = py::none(), py::arg("approximate") = py::none(),
            py::arg("raster") = "", py::arg("earth_radius_m") = 0.0);
  input.def_readwrite("raster", &ResectionInput::raster)
      .def_readwrite("focal_length", &ResectionInput::focal_length)
      .def_property_readonly("image_plane", [](const ResectionInput& i) { return ToArray(i.image_plane); })
      .def_property_readonly("points_in_ground", [](const ResectionInput& i) { return ToArray(i.points_in_ground); })
      .def_property_readonly("sigma", [](const ResectionInput& i) { return ToArray(i.sigma); })
      .def_property_readonly("observation_units_per_unit",
                             [](const ResectionInput& i) { return ToArray(i.observation_units_per_unit); })
      .def_readonly("units", &ResectionInput::units)
      .def_readonly("point_ids", &ResectionInput::point_ids)
      .def_readwrite("approximate", &ResectionInput::approximate)
      .def_readwrite("earth_radius_m", &ResectionInput::earth_radius_m)
      .def("__len__", [](const ResectionInput& i) { return i.image_plane.size(); })
      .def("__repr__", [](const ResectionInput& i) {
        return "ResectionInput(raster='" + i.raster + "', marks=" + std::to_string(i.image_plane.size()) +
               ", focal_length=" + std::string(py::repr(py::float_(i.focal_length))) + ")";
      });
}

// The resection of one image: its summary and result.
void BindResectionResult(py::module_& m) {
  py::class_<ResectionSummary> summary(m, "ResectionSummary", "How the resection of one image went.");
  summary.def_readonly("termination", &ResectionSummary::termination,
                       "'converged', 'no_convergence', 'failure' or 'cancelled'")
      .def_readonly("message", &ResectionSummary::message, "why it failed, with its numbers")
      .def_readonly("used_approximate", &ResectionSummary::used_approximate)
      .def_readonly("consensus_after_approximate", &ResectionSummary::consensus_after_approximate,
                    "the approximate pose was tried first and abandoned for the consensus start")
      .def_readonly("approximate_message", &ResectionSummary::approximate_message,
                    "what the abandoned approximate start gave")
      .def_readonly("ransac_trials", &ResectionSummary::ransac_trials)
      .def_readonly("ransac_exhaustive", &ResectionSummary::ransac_exhaustive)
      .def_readonly("ransac_stopped_early", &ResectionSummary::ransac_stopped_early)
      .def_readonly("adjustments", &ResectionSummary::adjustments)
      .def_readonly("iterations", &ResectionSummary::iterations)
      .def_readonly("initial_cost", &ResectionSummary::initial_cost)
      .def_readonly("final_cost", &ResectionSummary::final_cost)
      .def_readonly("ransac_seconds", &ResectionSummary::ransac_seconds)
      .def_readonly("refinement_seconds", &ResectionSummary::refinement_seconds)
      .def_readonly("total_seconds", &ResectionSummary::total_seconds)
      .def("brief_report", &ResectionSummary::BriefReport)
      .def("is_solution_usable", &ResectionSummary::IsSolutionUsable)
      .def("__repr__", [](const ResectionSummary& s) { return "ResectionSummary(" + s.BriefReport() + ")"; });

  py::class_<ResectionResult> result(m, "ResectionResult", R"doc(
The resection of one image: success (never a pose on failure: summary.message says why), the pose
(seed angles), its 6 x 6 covariance (m, rad: a-priori with stated accuracies, sigma0^2 times it
without; covariance_factor says which) and standard deviations, sigma0, and per mark (input
order) residuals (N x 2, the mark's unit, image-plane axes), normalized residuals, redundancy
numbers, minimal detectable blunders, pose shifts (sigmas) and status.)doc");
  result.def_readonly("success", &ResectionResult::success)
      .def_readonly("eo", &ResectionResult::eo)
      .def_readonly("has_covariance", &ResectionResult::has_covariance)
      .def_property_readonly("covariance", [](const ResectionResult& r) { return Matrix6d(r.covariance); },
                             "6 x 6 (m^2, rad^2; X0, Y0, Z0, seed omega, phi, kappa)")
      .def_property_readonly("standard_deviations",
                             [](const ResectionResult& r) { return Vector6d(r.standard_deviations); },
                             "6 (m, rad)")
      .def_readonly("covariance_factor", &ResectionResult::covariance_factor,
                    "the covariance over N^-1: 1 with stated accuracies, sigma0^2 without")
      .def_readonly("sigma_upper_factor", &ResectionResult::sigma_upper_factor,
                    "how many times the true sigmas may exceed the reported ones at 95 % (1 with "
                    "stated accuracies)")
      .def_readonly("accuracy_stated", &ResectionResult::accuracy_stated)
      .def_readonly("sigma0", &ResectionResult::sigma0)
      .def_readonly("degrees_of_freedom", &ResectionResult::degrees_of_freedom)
      .def_readonly("num_inliers", &ResectionResult::num_inliers)
      .def_property_readonly("residuals", [](const ResectionResult& r) { return ToArray(r.residuals); })
      .def_property_readonly("normalized_residuals",
                             [](const ResectionResult& r) { return ToArray(r.normalized_residuals); })
      .def_property_readonly("redundancy_numbers",
                             [](const ResectionResult& r) { return ToArray(r.redundancy_numbers); })
      .def_property_readonly("minimal_detectable_blunders",
                             [](const ResectionResult& r) { return ToArray(r.minimal_detectable_blunders); })
      .def_property_readonly("pose_shifts_sigmas",
                             [](const ResectionResult& r) { return ToArray(r.pose_shifts_sigmas); })
      .def_readonly("mark_status", &ResectionResult::mark_status,
                    "per mark: 'accepted', 'outlier' or 'rejected'")
      .def_property_readonly("inliers", [](const ResectionResult& r) { return ToBoolArray(r.inliers); })
      .def_readonly("critical_normalized_residual", &ResectionResult::critical_normalized_residual)
      .def_readonly("max_pose_shift_sigmas", &ResectionResult::max_pose_shift_sigmas)
      .def_readonly("weakest_mark", &ResectionResult::weakest_mark)
      .def_readonly("weak", &ResectionResult::weak)
      .def_readonly("accuracy_disagrees", &ResectionResult::accuracy_disagrees)
      .def_readonly("ambiguous", &ResectionResult::ambiguous)
      .def_readonly("competing_eo", &ResectionResult::competing_eo)
      .def_property_readonly("competing_inliers",
                             [](const ResectionResult& r) { return ToBoolArray(r.competing_inliers); })
      .def_readonly("warnings", &ResectionResult::warnings)
      .def_readonly("cancelled", &ResectionResult::cancelled,
                    "not resected: the batch was cancelled before this image started")
      .def_readonly("summary", &ResectionResult::summary)
      .def("__repr__", &ResultRepr);
}

// resect and resect_images.
void BindResectionCalls(py::module_& m) {
  m.def(
      "resect",
      [](const ResectionInput& input, std::optional<ResectionOptions> options) {
        const ResectionOptions o = options.value_or(ResectionOptions());
        CheckOptions(o, "invalid options");
        py::gil_scoped_release release;
        return ResectImage(o, input);
      },
      py::arg("input"), py::arg("options") = py::none(),
      "Resects one image (ResectImage). A failure is success = False with summary.message; "
      "invalid options raise photopose.Error.");
  py::class_<ResectionProgress>(m, "ResectionProgress",
                                "resect_images' progress, given to its callback as the batch goes.")
      .def_readonly("images_done", &ResectionProgress::images_done, "count, increasing to images_total")
      .def_readonly("images_total", &ResectionProgress::images_total, "count")
      .def_readonly("elapsed_seconds", &ResectionProgress::elapsed_seconds, "s since the call started")
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
  m.def(
      "resect_images",
      [](const std::vector<ResectionInput>& inputs, std::optional<ResectionOptions> options,
         int num_threads, const py::object& progress) {
        ResectionBatchOptions batch;
        batch.num_threads = num_threads;
        ProgressRelay relay(progress, "a ResectionProgress");
        batch.progress = relay.Function<ResectionProgress>();
        std::vector<ResectionResult> results;
        CallWithoutGil(
            [&] {
              return ResectImages(options.value_or(ResectionOptions()), inputs, batch, &results);
            },
            &relay);
        return results;
      },
      py::arg("inputs"), py::arg("options") = py::none(), py::arg("num_threads") = 0,
      py::kw_only(), py::arg("progress") = py::none(), R"doc(
Resects many images in parallel (ResectImages; 0 threads: all cores), results in input order;
image i gets its own reproducible RANSAC seed. progress(info: ResectionProgress) is called as images
finish (when 1 % of the batch has finished or 0.1 s has passed since its last call, and once with
images_done == images_total; from a resecting thread, with the GIL taken for the call alone) with
images_done, images_total and elapsed_seconds; the results are the same, bit for bit, with and
without it. A callback that returns False cancels the batch: the images not yet started are
results with cancelled True (no pose). An exception it raises cancels the batch and is raised when
the call returns.)doc");
}

}  // namespace

// In this order: a function's signature names the classes bound before it.
void BindResection(py::module_& m) {
  BindConsensusOptions(m);
  BindRefinementOptions(m);
  BindResectionInput(m);
  BindResectionResult(m);
  BindResectionCalls(m);
}

}  // namespace photopose::python
