// The HTML page of `photopose bundle` (tools/report/bundle_report.h): one self-contained file,
// inline CSS and SVG, no script; page head, tables, histograms and SVG primitives from
// tools/report/html_kit.h.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

#include "tools/report/bundle_report.h"
#include "tools/report/html_kit.h"

namespace photopose::cli {
namespace {

// Plan view (SVG user units).
constexpr double kPlanWidth = 760.0;
constexpr double kPlanHeight = 560.0;
constexpr double kPlanMargin = 40.0;
// Tie points drawn at most (evenly subsampled beyond).
constexpr size_t kMaxTieDots = 4000;

// Numbers on the page: three significant digits unless a format is given; "n/a" when not finite.
std::string F(double value, const char* format = "%.3g") { return ReportNumber(value, format); }

// What the plan view draws, in one horizontal frame (m): the block's ground frame, or the grid of
// a projected output CRS for a georeferenced model.
struct PlanData {
  struct Camera {
    std::string name;
    Eigen::Vector2d xy = Eigen::Vector2d::Zero();
    std::optional<Eigen::Matrix2d> covariance;  // m^2
  };
  struct Surveyed {
    std::string id;
    bool control = true;
    Eigen::Vector2d xy = Eigen::Vector2d::Zero();
    std::optional<Eigen::Vector2d> error;  // m
  };
  std::vector<Camera> cameras;
  std::vector<Eigen::Vector2d> ties;  // at most kMaxTieDots of them
  std::vector<Surveyed> surveyed;
  std::string caption;  // the frame, when it is not the block's own
};

PlanData PlanDataOf(const Block& block, const BundleAdjustmentResult& result) {
  PlanData data;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    if (!image.eo) continue;
    PlanData::Camera camera{image.name, image.eo->center_in_ground().head<2>(), std::nullopt};
    if (i < result.images.size() && result.images[i].has_covariance)
      camera.covariance = result.images[i].covariance.topLeftCorner<2, 2>();
    data.cameras.push_back(camera);
  }
  std::vector<const BlockPoint*> ties;
  for (const BlockPoint& point : block.points)
    if (point.role == PointRole::kTie && point.position_m) ties.push_back(&point);
  const size_t step = std::max<size_t>(1, ties.size() / kMaxTieDots);
  for (size_t k = 0; k < ties.size(); k += step) data.ties.push_back(ties[k]->position_m->head<2>());
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role == PointRole::kTie || !point.surveyed_m) continue;
    PlanData::Surveyed s{point.id, point.role == PointRole::kControl, point.surveyed_m->head<2>(), std::nullopt};
    if (p < result.points.size() && result.points[p].error_m) s.error = result.points[p].error_m->head<2>();
    data.surveyed.push_back(s);
  }
  return data;
}

// The plan data of a georeferenced model in the grid of its projected output CRS: coordinates
// through PROJ, ellipses and vectors turned to the grid's level axes. Left in the local frame (and
// said so) for a geographic output CRS, whose degrees are no plan.
PlanData GeoreferencedPlanData(const Block& block, const BundleAdjustmentResult& result,
                               const GeoreferenceResult& g) {
  PlanData data = PlanDataOf(block, result);
  if (!g.out_crs_info.projected) {
    data.caption = "Local East-North-Up frame of the adjustment (m), origin " +
                   F(g.frame.origin_lon_lat_h().x(), "%.6f") + " E, " + F(g.frame.origin_lon_lat_h().y(), "%.6f") +
                   " N; the output CRS " + g.out_crs + " is geographic.";
    return data;
  }
  std::vector<Eigen::Vector3d> local;
  for (size_t i = 0; i < block.images.size(); ++i)
    if (block.images[i].eo) local.push_back(block.images[i].eo->center_in_ground());
  const size_t num_cameras = local.size();
  std::vector<const BlockPoint*> surveyed;
  for (const BlockPoint& point : block.points)
    if (point.role != PointRole::kTie && point.surveyed_m) {
      local.push_back(*point.surveyed_m);
      surveyed.push_back(&point);
    }
  std::vector<const BlockPoint*> ties;
  for (const BlockPoint& point : block.points)
    if (point.role == PointRole::kTie && point.position_m) ties.push_back(&point);
  const size_t step = std::max<size_t>(1, ties.size() / kMaxTieDots);
  for (size_t k = 0; k < ties.size(); k += step) local.push_back(*ties[k]->position_m);
  std::vector<Eigen::Vector3d> grid = local;
  std::vector<Eigen::Matrix3d> R;
  if (!ToOutputCrs(g, &grid).ok() || !LevelAxes(g, std::vector<Eigen::Vector3d>(local.begin(), local.begin() + num_cameras + surveyed.size()), &R).ok()) {
    data.caption = "Local East-North-Up frame of the adjustment (m): PROJ could not map it into " + g.out_crs + ".";
    return data;
  }
  for (size_t k = 0; k < num_cameras; ++k) {
    data.cameras[k].xy = grid[k].head<2>();
    if (data.cameras[k].covariance) {
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      C.topLeftCorner<2, 2>() = *data.cameras[k].covariance;
      data.cameras[k].covariance = (R[k] * C * R[k].transpose()).topLeftCorner<2, 2>();
    }
  }
  for (size_t k = 0; k < surveyed.size(); ++k) {
    data.surveyed[k].xy = grid[num_cameras + k].head<2>();
    if (data.surveyed[k].error) {
      const Eigen::Vector3d e(data.surveyed[k].error->x(), data.surveyed[k].error->y(), 0.0);
      data.surveyed[k].error = (R[num_cameras + k] * e).head<2>();
    }
  }
  for (size_t k = 0; k < data.ties.size(); ++k) data.ties[k] = grid[num_cameras + surveyed.size() + k].head<2>();
  data.caption = "Grid of " + g.out_crs_info.name + " (" + g.out_crs + "): easting and northing (m).";
  return data;
}

// The plan view: tie points, cameras with 1-sigma error ellipses, control and check points with
// their residual vectors, each exaggerated by a stated factor; the corner coordinates written.
std::string PlanView(const PlanData& data) {
  std::vector<Eigen::Vector2d> all = data.ties;
  for (const PlanData::Camera& camera : data.cameras) all.push_back(camera.xy);
  for (const PlanData::Surveyed& point : data.surveyed) all.push_back(point.xy);
  if (all.empty()) return "<p>Nothing to draw.</p>";
  Eigen::Vector2d lo = all.front(), hi = all.front();
  for (const auto& p : all) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Eigen::Vector2d span = (hi - lo).cwiseMax(1e-9);
  const double scale = std::min((kPlanWidth - 2 * kPlanMargin) / span.x(),
                                (kPlanHeight - 2 * kPlanMargin) / span.y());
  auto X = [&](double x) { return kPlanMargin + (x - lo.x()) * scale; };
  auto Y = [&](double y) { return kPlanHeight - kPlanMargin - (y - lo.y()) * scale; };
  const double extent = std::max(span.x(), span.y());

  // Exaggerations: the largest ellipse and vector drawn about 4 % of the extent.
  double largest_sigma = 0.0, largest_error = 0.0;
  for (const PlanData::Camera& camera : data.cameras)
    if (camera.covariance) largest_sigma = std::max(largest_sigma, std::sqrt(camera.covariance->trace()));
  for (const PlanData::Surveyed& point : data.surveyed)
    if (point.error) largest_error = std::max(largest_error, point.error->norm());
  const double ellipse_factor = largest_sigma > 0.0 ? NiceAtMost(0.04 * extent / largest_sigma) : 1.0;
  const double vector_factor = largest_error > 0.0 ? NiceAtMost(0.04 * extent / largest_error) : 1.0;

  std::ostringstream svg;
  svg << SvgOpen(kPlanWidth, kPlanHeight, "plan view") << "\n";
  // Tie points.
  svg << "<g fill=\"#999\">";
  for (const Eigen::Vector2d& tie : data.ties)
    svg << "<circle cx=\"" << F(X(tie.x()), "%.1f") << "\" cy=\"" << F(Y(tie.y()), "%.1f") << "\" r=\"0.8\"/>";
  svg << "</g>\n";
  // Cameras and their ellipses.
  for (const PlanData::Camera& camera : data.cameras) {
    const double cx = X(camera.xy.x()), cy = Y(camera.xy.y());
    if (camera.covariance) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(*camera.covariance);
      const Eigen::Vector2d axes = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt() * ellipse_factor * scale;
      const Eigen::Vector2d major = eigen.eigenvectors().col(1);
      const double angle = -std::atan2(major.y(), major.x()) * 180.0 / kPi;
      svg << "<ellipse cx=\"" << F(cx, "%.1f") << "\" cy=\"" << F(cy, "%.1f") << "\" rx=\""
          << F(std::max(axes[1], 0.5), "%.2f") << "\" ry=\"" << F(std::max(axes[0], 0.5), "%.2f")
          << "\" transform=\"rotate(" << F(angle, "%.1f") << " " << F(cx, "%.1f") << " "
          << F(cy, "%.1f") << ")\" fill=\"none\" stroke=\"#0072B2\" stroke-width=\"1\"/>";
    }
    svg << "<rect x=\"" << F(cx - 2.5, "%.1f") << "\" y=\"" << F(cy - 2.5, "%.1f")
        << "\" width=\"5\" height=\"5\" fill=\"#0072B2\"><title>" << HtmlEscape(camera.name)
        << "</title></rect>\n";
  }
  // Control and check points with their residual vectors.
  for (const PlanData::Surveyed& point : data.surveyed) {
    const double px = X(point.xy.x()), py = Y(point.xy.y());
    const bool control = point.control;
    const char* color = control ? "#D55E00" : "#009E73";
    if (point.error) {
      const Eigen::Vector2d& e = *point.error;
      svg << "<line x1=\"" << F(px, "%.1f") << "\" y1=\"" << F(py, "%.1f") << "\" x2=\""
          << F(px + e.x() * vector_factor * scale, "%.1f") << "\" y2=\""
          << F(py - e.y() * vector_factor * scale, "%.1f") << "\" stroke=\"" << color
          << "\" stroke-width=\"2\"/>";
    }
    if (control) {
      svg << "<path d=\"M" << F(px, "%.1f") << "," << F(py - 5, "%.1f") << "l4.5,8h-9z\" fill=\""
          << color << "\">";
    } else {
      svg << "<circle cx=\"" << F(px, "%.1f") << "\" cy=\"" << F(py, "%.1f") << "\" r=\"4\" fill=\""
          << color << "\">";
    }
    svg << "<title>" << HtmlEscape(point.id) << "</title>" << (control ? "</path>" : "</circle>")
        << "\n";
  }
  // Scale bar and legend.
  const double bar = NiceAtMost(0.25 * extent);
  const double bar_y = kPlanHeight - 14.0;
  svg << "<line x1=\"" << kPlanMargin << "\" y1=\"" << bar_y << "\" x2=\""
      << F(kPlanMargin + bar * scale, "%.1f") << "\" y2=\"" << bar_y
      << "\" stroke=\"#222\" stroke-width=\"2\"/><text x=\"" << F(kPlanMargin + bar * scale + 6, "%.1f")
      << "\" y=\"" << bar_y + 4 << "\">" << F(bar, "%g") << " m</text>\n";
  svg << "<text x=\"" << kPlanWidth - 10 << "\" y=\"16\" text-anchor=\"end\">"
      << "blue squares: cameras, ellipses 1-sigma x" << F(ellipse_factor, "%g")
      << "; red triangles: control, green dots: check, vectors x" << F(vector_factor, "%g")
      << "; grey: tie points</text>\n";
  svg << "</svg>";
  std::string caption = data.caption.empty() ? std::string() : HtmlEscape(data.caption) + " ";
  caption += "Lower left " + F(lo.x(), "%.2f") + ", " + F(lo.y(), "%.2f") + "; upper right " +
             F(hi.x(), "%.2f") + ", " + F(hi.y(), "%.2f") + ".";
  return svg.str() + "\n<p>" + caption + "</p>";
}

// A histogram of a group's values, the axis titled with the quantity and unit.
std::string Histogram(const std::string& title, const std::string& x_label,
                      const std::vector<double>& values) {
  HistogramPlot plot;
  plot.title = title;
  plot.x_label = x_label;
  plot.values = values;
  return RenderHistogramSvg(plot);
}

// The verdicts, first on the page: not adjusted, over-fitted groups, the check points.
std::string VerdictsHtml(const BundleAdjustmentResult& result, const BundleReportContext& context) {
  const BundleAdjustmentSummary& s = result.summary;
  std::ostringstream html;
  std::vector<std::string> overfit;
  for (const BundleGroupStatistics& g : result.groups)
    if (g.overfit) overfit.push_back(g.message);
  if (!s.IsSolutionUsable()) {
    html << "<div class=\"verdict bad\"><b>Not adjusted:</b> " << HtmlEscape(s.message) << "</div>\n";
  }
  if (overfit.empty()) {
    html << "<div class=\"verdict good\"><b>No prior group is over-fitted:</b> each is checked "
            "by the tie points and fits within its stated accuracy.</div>\n";
  } else {
    html << "<div class=\"verdict bad\"><b>Over-fitted:</b><ul>";
    for (const std::string& m : overfit) html << "<li>" << HtmlEscape(m) << "</li>";
    html << "</ul></div>\n";
  }
  if (result.num_check_points > 0) {
    html << "<div class=\"verdict note\"><b>Check points:</b> " << result.num_check_points
         << ", RMSE X " << F(result.check_rmse_m.x()) << " m, Y " << F(result.check_rmse_m.y())
         << " m, Z " << F(result.check_rmse_m.z()) << " m, total " << F(result.check_rmse_total_m)
         << " m</div>\n";
  } else {
    html << "<div class=\"verdict note\"><b>No check points:</b> nothing independent measures the "
            "block's accuracy"
         << (context.cross_validation != nullptr ? " (see the leave-one-out table below)" : "")
         << ".</div>\n";
  }
  return html.str();
}

// The groups of the objective against their stated accuracies, and their residuals' histograms.
std::string GroupsHtml(const Block& block, const BundleAdjustmentResult& result,
                       const BundleReportContext& context) {
  std::ostringstream html;
  std::vector<std::vector<std::string>> rows;
  for (const BundleGroupStatistics& g : result.groups) {
    rows.push_back({EnumName(g.group), std::to_string(g.count), F(g.stated_accuracy.x()) + " " + g.unit,
                    F(g.rms_total) + " " + g.unit, F(g.ratio), F(g.redundancy_share),
                    std::isfinite(g.estimated_accuracy.x())
                        ? F(g.estimated_accuracy.x()) + " " + g.unit
                        : (g.estimation_message.empty() ? "" : "not estimated"),
                    g.overfit ? "OVERFIT" : ""});
  }
  html << "<h2>Groups of the objective</h2>\n"
       << HtmlTable(
              "Residuals against the stated accuracies",
              {"group", "count", "stated", "RMS", "RMS / stated", "redundancy share",
               "estimated accuracy", "verdict"},
              rows,
              {"redundancy share: the group's summed redundancy numbers over its observations, "
               "how much of it the rest of the block checks",
               "over-fitted: a prior group whose RMS / stated is below " +
                   F(context.options.statistics.overfit_ratio) + " or whose redundancy share is below " +
                   F(context.options.statistics.overfit_redundancy_share)});

  // Histograms.
  std::map<std::string, std::vector<double>> by_group;
  std::map<std::string, std::string> units;
  if (!result.observations.empty()) {
    for (const BundleObservationDiagnostics& d : result.observations) by_group[EnumName(d.group)].push_back(d.residual);
  } else {
    for (size_t m = 0; m < block.marks.size() && m < result.mark_residuals.size(); ++m) {
      if (!result.mark_residuals[m].allFinite()) continue;
      const std::string group = EnumName(
          block.points[block.marks[m].point].role == PointRole::kControl ? kControlMarks : kTieMarks);
      by_group[group].push_back(result.mark_residuals[m].x());
      by_group[group].push_back(result.mark_residuals[m].y());
    }
  }
  for (const BundleGroupStatistics& g : result.groups) units[EnumName(g.group)] = g.unit;
  html << "<h2>Residuals</h2>\n";
  for (const auto& [group, values] : by_group)
    html << Histogram(group, "residual (" + units[group] + ")", values) << "\n";

  return html.str();
}

// The control and check points: adjusted (or intersected) minus surveyed.
std::string PointsHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::ostringstream html;
  auto point_rows = [&](PointRole role) {
    std::vector<std::vector<std::string>> out;
    for (size_t p = 0; p < block.points.size(); ++p) {
      const BlockPoint& point = block.points[p];
      if (point.role != role || p >= result.points.size()) continue;
      const BundlePointResult& r = result.points[p];
      if (r.error_m) {
        out.push_back({point.id, std::to_string(r.num_observations), F(r.error_m->x()),
                       F(r.error_m->y()), F(r.error_m->z()), F(r.error_m->norm()),
                       r.has_covariance ? F(std::sqrt(r.covariance.trace())) : ""});
      } else {
        out.push_back({point.id, std::to_string(r.num_observations), "", "", "", "",
                       r.message.empty() ? "not in the adjustment" : r.message});
      }
    }
    return out;
  };
  const std::vector<std::string> point_header = {"point", "images", "error X (m)", "error Y (m)",
                                                 "error Z (m)", "|error| (m)", "sigma (m)"};
  html << "<h2>Control points</h2>\n"
       << HtmlTable("Adjusted minus surveyed; RMSE " + F(result.control_rmse_total_m) + " m",
                    point_header, point_rows(PointRole::kControl))
       << "<h2>Check points</h2>\n"
       << HtmlTable("Intersected from the adjusted images minus surveyed; RMSE " +
                        F(result.check_rmse_total_m) + " m",
                    point_header, point_rows(PointRole::kCheck));

  return html.str();
}

// Self-calibration and data snooping, when there were any.
std::string CalibrationAndSnoopingHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::ostringstream html;
  if (!result.calibration.empty()) {
    html << "<h2>Self-calibration</h2>\n";
    for (const BundleCalibrationResult& c : result.calibration) {
      std::vector<std::vector<std::string>> calibration_rows;
      for (size_t k = 0; k < c.names.size(); ++k)
        calibration_rows.push_back(
            {c.names[k], F(c.values[k], "%.8g"), k < c.sigmas.size() ? F(c.sigmas[k]) : ""});
      html << HtmlTable("Camera '" + block.cameras[c.camera].camera_id + "' (" +
                            EnumName(block.cameras[c.camera].model) + ")",
                        {"parameter", "value", "sigma"}, calibration_rows, c.high_correlations);
    }
  }
  if (!result.snooping.empty()) {
    std::vector<std::vector<std::string>> snooping_rows;
    for (size_t k = 0; k < result.snooping.size(); ++k) {
      const BundleSnoopingStep& step = result.snooping[k];
      snooping_rows.push_back({std::to_string(k + 1), EnumName(step.group), std::to_string(step.item),
                               F(step.normalized), F(step.residual)});
    }
    html << "<h2>Data snooping</h2>\n"
         << HtmlTable("Observations removed, in order (|w| > " + F(result.critical_value) + ")",
                      {"step", "group", "item", "|w|", "residual"}, snooping_rows);
  }
  return html.str();
}

// Reliability (redundancy numbers) and the leave-one-out control points, when computed.
std::string ReliabilityHtml(const Block& block, const BundleAdjustmentResult& result,
                            const BundleReportContext& context) {
  std::ostringstream html;
  if (!result.observations.empty()) {
    // Redundancy numbers per group as a distribution.
    std::map<std::string, std::vector<double>> redundancy;
    for (const BundleObservationDiagnostics& d : result.observations)
      redundancy[EnumName(d.group)].push_back(d.redundancy);
    html << "<h2>Reliability</h2>\n<p>" << result.num_uncontrolled
         << " observations have a redundancy number below "
         << F(context.options.statistics.uncontrolled_redundancy)
         << ": a blunder there cannot be seen. Smallest detectable errors use delta0 = "
         << F(result.delta0) << ".</p>\n";
    for (const auto& [group, values] : redundancy)
      html << Histogram("redundancy numbers, " + group, "redundancy number", values) << "\n";
  }
  if (context.cross_validation != nullptr) {
    const BundleCrossValidationResult& cv = *context.cross_validation;
    std::vector<std::vector<std::string>> cv_rows;
    for (const BundleCrossValidationPoint& p : cv.points) {
      cv_rows.push_back({block.points[p.point].id, p.ok ? F(p.error_m.x()) : "",
                         p.ok ? F(p.error_m.y()) : "", p.ok ? F(p.error_m.z()) : "",
                         p.ok ? F(p.normalized) : "", p.stands_out ? "STANDS OUT" : p.message});
    }
    html << "<h2>Leave-one-out control points</h2>\n"
         << HtmlTable(
                "Each control point adjusted as a check point; RMSE X " + F(cv.rmse_m.x()) +
                    ", Y " + F(cv.rmse_m.y()) + ", Z " + F(cv.rmse_m.z()) + " m",
                {"point", "error X (m)", "error Y (m)", "error Z (m)", "normalized", "verdict"},
                cv_rows,
                {"normalized: e^T C^-1 e, chi-square(3); stands out above " + F(cv.threshold)});
  }
  return html.str();
}

}  // namespace

std::string BundleReportHtml(const Block& block, const BundleAdjustmentResult& result,
                             const BundleReportContext& context) {
  const BundleAdjustmentSummary& s = result.summary;
  std::ostringstream html;
  html << HtmlPageOpen("photopose bundle", "photopose bundle: " + std::to_string(s.num_images) +
                                               " images, " + std::to_string(s.num_points) +
                                               " points, " + std::to_string(s.num_marks) +
                                               " marks");
  html << VerdictsHtml(result, context);
  html << "<p>" << HtmlEscape(s.BriefReport()) << "<br>Datum: " << HtmlEscape(s.datum_description)
       << "</p>\n";
  const PlanData plan = context.georeference != nullptr
                             ? GeoreferencedPlanData(block, result, *context.georeference)
                             : PlanDataOf(block, result);
  html << "<h2>Plan view</h2>\n" << PlanView(plan) << "\n";
  html << GroupsHtml(block, result, context) << PointsHtml(block, result)
       << CalibrationAndSnoopingHtml(block, result) << ReliabilityHtml(block, result, context);
  html << "<h2>Run</h2>\n<p><code>" << HtmlEscape(context.command_line) << "</code></p>\n";
  html << HtmlPageClose();
  return html.str();
}

}  // namespace photopose::cli
