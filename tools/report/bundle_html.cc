// The HTML page of `photopose bundle` (tools/report/bundle_report.h): one self-contained file,
// inline CSS and SVG, no script; page head, tables, number formats, plots and SVG primitives from
// tools/report/html_kit.h, its pictures from tools/report/bundle_plots.h. Sections in the order a
// surveyor reads them: overview, verdicts, control and check points, cameras, calibration,
// residuals, rejected observations, diagnostics. One file past ~800 lines on purpose: one
// function per section, in the page's order, each a list of named steps (its tables, verdicts and
// plots) defined just above it, so that the page reads top to bottom here.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <map>
#include <sstream>

#include "core/camera_models.h"
#include "core/statistics.h"

#include "tools/report/bundle_plots.h"
#include "tools/report/bundle_report.h"
#include "tools/report/html_kit.h"

namespace photopose::cli {
namespace {

// ------------------------------------------------------------------ helpers

// The area (m^2) of the convex hull of plan points (Andrew's monotone chain).
double HullArea(std::vector<Eigen::Vector2d> points) {
  if (points.size() < 3) return 0.0;
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = points.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  double area = 0.0;
  for (size_t i = 0; i + 1 < k; ++i)
    area += hull[i].x() * hull[i + 1].y() - hull[i + 1].x() * hull[i].y();
  return 0.5 * std::abs(area);
}

std::string FormatArea(double area_m2) {
  if (area_m2 >= 1e5) return FormatSignificant(area_m2 / 1e6, 3) + " km\u00b2";
  return FormatSignificant(area_m2, 3) + " m\u00b2";
}

// Columns in units (core/units.h FormatColumnsInUnits) with their units as the page reads them
// (Utf8UnitName: um as µm).
ColumnsInUnits PageColumnsInUnits(const std::vector<std::vector<double>>& columns,
                                  const std::vector<std::string>& row_kinds) {
  ColumnsInUnits in_units = FormatColumnsInUnits(columns, row_kinds);
  in_units.unit = Utf8UnitName(in_units.unit);
  for (std::string& unit : in_units.units) unit = Utf8UnitName(unit);
  return in_units;
}

// A georeferenced block's errors (the output CRS's E, N, U) as the page prints them, in section
// 3's tables and in the check points' verdict of section 2 (the same cells): each stage's lengths
// in the one unit its largest error calls for, named above its columns.
struct GeoreferenceStageUnits {
  LengthUnit after_similarity = LengthUnit::kMetre;
  LengthUnit after_adjustment = LengthUnit::kMetre;
};

GeoreferenceStageUnits GeoreferenceStageUnitsOf(const GeoreferenceResult& g) {
  std::vector<double> similarity, adjustment;
  for (const GeoreferencePointError& e : g.point_errors) {
    if (e.after_similarity_m) similarity.push_back(e.after_similarity_m->norm());
    if (e.after_adjustment_m) adjustment.push_back(e.after_adjustment_m->norm());
  }
  return {LengthUnitFor(LargestMagnitude(similarity)), LengthUnitFor(LargestMagnitude(adjustment))};
}

// A role's RMSE at one stage in `unit` (without it): E, N, U, total; "n/a" without a point.
std::vector<std::string> RmseCells(const GeoreferenceRmse& rmse, LengthUnit unit) {
  std::vector<std::string> cells;
  for (int a = 0; a < 3; ++a)
    cells.push_back(rmse.count > 0 ? FormatLength(rmse.rmse_m[a], unit) : "n/a");
  cells.push_back(rmse.count > 0 ? FormatLength(rmse.total_m, unit) : "n/a");
  return cells;
}

// The output CRS of a georeferenced block by PROJ's name, else as given.
std::string OutCrsName(const GeoreferenceResult& g) {
  return g.out_crs_info.name.empty() ? g.out_crs : g.out_crs_info.name;
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d %H:%M UTC", &utc);
  return buffer;
}

// A group whose RMS / stated lies outside [1 / kWeightFactor, kWeightFactor] has a stated accuracy
// that the data contradict (unitless): said in the verdicts, with the estimate when there is one.
constexpr double kWeightFactor = 2.0;

// ------------------------------------------------------------------ 1. overview

// What the overview says of the block's shape: its points, ground, heights and overlap.
struct BlockShape {
  int num_tie = 0, num_control = 0, num_check = 0;
  std::vector<Eigen::Vector2d> ground_plan;  // every point with coordinates (m)
  std::vector<double> images_per_tie;        // sorted
  double mean_per_tie = 0.0;                 // NaN without tie points
  double height = 0.0;                       // mean flying height above the median ground point (m)
  double gsd_m = 0.0;                        // summed over num_gsd images (m per pixel)
  int num_gsd = 0;
};

// The points by role, the ground (every point with coordinates: adjusted, else surveyed) and
// how many images see each tie point.
void CountPoints(const Block& block, BlockShape* shape, std::vector<double>* ground_z) {
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.role == PointRole::kTie) ++shape->num_tie;
    if (point.role == PointRole::kControl) ++shape->num_control;
    if (point.role == PointRole::kCheck) ++shape->num_check;
    if (point.role == PointRole::kTie && point.position_m)
      shape->images_per_tie.push_back(static_cast<double>(block.marks_of_point[p].size()));
    const std::optional<Eigen::Vector3d>& xyz = point.position_m ? point.position_m : point.surveyed_m;
    if (xyz) {
      shape->ground_plan.push_back(xyz->head<2>());
      ground_z->push_back(xyz->z());
    }
  }
}

BlockShape BlockShapeOf(const Block& block) {
  BlockShape shape;
  std::vector<double> ground_z;
  CountPoints(block, &shape, &ground_z);
  double camera_z = 0.0;
  int num_oriented = 0;
  std::sort(ground_z.begin(), ground_z.end());
  const double median_ground_z = ground_z.empty() ? std::nan("") : ground_z[ground_z.size() / 2];
  for (const BlockImage& image : block.images) {
    if (!image.eo) continue;
    ++num_oriented;
    camera_z += image.eo->center_in_ground().z();
    // Ground sample distance: height above the median ground point times pixel over focal length.
    const BlockCamera& camera = block.cameras[image.camera];
    const double focal = CameraModelFocal(camera.model, camera.params.data());
    const double pixel = camera.model == CameraModelType::kFrame ? camera.table.pixel_size_um : 1.0;
    const double height = image.eo->center_in_ground().z() - median_ground_z;
    if (focal > 0.0 && pixel > 0.0 && std::isfinite(height)) {
      shape.gsd_m += std::abs(height) * pixel / focal;
      ++shape.num_gsd;
    }
  }
  shape.height = num_oriented > 0 ? camera_z / num_oriented - median_ground_z : std::nan("");
  std::sort(shape.images_per_tie.begin(), shape.images_per_tie.end());
  double mean_per_tie = 0.0;
  for (const double n : shape.images_per_tie) mean_per_tie += n;
  shape.mean_per_tie =
      shape.images_per_tie.empty() ? std::nan("") : mean_per_tie / shape.images_per_tie.size();
  return shape;
}

// The overview's facts about the run and the block.
std::vector<std::pair<std::string, std::string>> OverviewFacts(const Block& block,
                                                               const BundleAdjustmentResult& result,
                                                               const BlockShape& shape) {
  const BundleAdjustmentSummary& s = result.summary;
  return {
      {"Date", UtcNow()},
      {"Software", std::string("photopose ") + PHOTOPOSE_VERSION},
      {"Images adjusted", std::to_string(s.num_images) + " of " +
                              FormatCount(static_cast<long long>(block.images.size()), "image")},
      {"Cameras", FormatCount(static_cast<long long>(block.cameras.size()), "camera")},
      {"Points", FormatCount(shape.num_tie, "tie point") + ", " +
                     FormatCount(shape.num_control, "control point") + ", " +
                     FormatCount(shape.num_check, "check point")},
      {"Marks used", FormatCount(s.num_marks, "mark") + " (" +
                         FormatCount(static_cast<long long>(result.rejected_marks.size() +
                                                            result.rejected_check_marks.size()),
                                     "mark") +
                         " rejected, see Rejected observations)"},
      {"Mean flying height above the median ground point",
       std::isfinite(shape.height) ? FormatSignificant(shape.height, 4) + " m"
                                   : "n/a (no ground points)"},
      {"Ground sample distance (mean over images)",
       shape.num_gsd > 0 ? FormatLengthWithUnit(shape.gsd_m / shape.num_gsd) + " per pixel"
                         : "n/a (no pixel size or no ground points)"},
      {"Images per tie point (mean, median)",
       shape.images_per_tie.empty()
           ? "n/a (no tie points)"
           : FormatUnitless(shape.mean_per_tie, 1) + ", " +
                 FormatSignificant(shape.images_per_tie[shape.images_per_tie.size() / 2], 3)},
      {"Area covered by the ground points (convex hull)", FormatArea(HullArea(shape.ground_plan))},
      {"Datum", s.datum_description},
      {"Covariances (datum they refer to)",
       s.covariance_datum.empty() ? "n/a (not computed)" : s.covariance_datum},
      {"sigma0 (unitless, 1 when the stated accuracies hold)", FormatUnitless(s.sigma0, 3)},
      {"Redundancy", FormatCount(s.redundancy, "observation") + " more than unknowns"},
      {"Adjustment time", FormatSignificant(s.time_seconds, 3) + " s (" +
                              FormatCount(s.rounds, "round") + ", " +
                              FormatCount(s.iterations, "iteration") + ")"},
  };
}

// The unmatched names the overview lists before "...".
constexpr size_t kMaxUnmatchedNamesListed = 5;

// A georeferenced block's facts: the output CRS and the local frame the block was adjusted in,
// what matched the model's images by name, camera positions without height, inputs read and not
// used.
void GeoreferenceFacts(const GeoreferenceResult& g,
                       std::vector<std::pair<std::string, std::string>>* facts) {
  const CrsInfo& crs = g.out_crs_info;
  std::string out_crs = OutCrsName(g);
  if (!crs.name.empty() && !g.out_crs.empty() && g.out_crs != crs.name)
    out_crs += " (" + g.out_crs + ")";
  if (!g.out_crs_reason.empty()) out_crs += "; " + g.out_crs_reason;
  facts->push_back({"Output CRS (the points and frames files)", out_crs});
  const Eigen::Vector3d& origin = g.frame.origin_lon_lat_h();
  facts->push_back({"Adjusted in", "the local East-North-Up frame (m), origin " +
                                       ReportFixed(origin.x(), 6) + " E, " +
                                       ReportFixed(origin.y(), 6) + " N, ellipsoidal height " +
                                       FormatCoordinate(origin.z()) + " m (WGS 84)"});
  // Names that match no image are counted and listed here as in the JSON and on stderr (issue
  // 21: never dropped silently, also with --quiet).
  const auto names = [](const std::vector<std::string>& unmatched) {
    std::string listed;
    for (size_t k = 0; k < unmatched.size() && k < kMaxUnmatchedNamesListed; ++k)
      listed += (k ? ", " : "") + unmatched[k];
    if (unmatched.size() > kMaxUnmatchedNamesListed) listed += ", ...";
    return listed;
  };
  std::string matched = FormatCount(g.positions_matched, "camera position") + " matched";
  if (!g.positions_unmatched.empty())
    matched += ", " + std::to_string(g.positions_unmatched.size()) + " naming no image of the model (" +
               names(g.positions_unmatched) + ")";
  matched += "; " + FormatCount(g.control_marks_matched, "control mark") + " matched";
  if (!g.control_marks_unmatched.empty())
    matched += ", " + std::to_string(g.control_marks_unmatched.size()) + " on images the model does not have (" +
               names(g.control_marks_unmatched) + ")";
  facts->push_back({"Matched to the model's images by name", matched});
  if (g.positions_without_height > 0)
    facts->push_back(
        {"Camera positions without height",
         FormatCount(g.positions_without_height, "position") +
             ": horizontal only (not in the similarity; heights free in the adjustment)"});
  std::string not_used;
  for (const std::string& line : g.inputs_not_used)
    not_used += (not_used.empty() ? "" : "; ") + line;
  if (!not_used.empty()) facts->push_back({"Inputs read and not used", not_used});
}

std::string OverviewHtml(const Block& block, const BundleAdjustmentResult& result,
                         const BundleReportContext& context) {
  std::vector<std::pair<std::string, std::string>> facts =
      OverviewFacts(block, result, BlockShapeOf(block));
  if (context.georeference != nullptr) {
    GeoreferenceFacts(*context.georeference, &facts);
  } else if (const std::string srs = BundlePointsSrs(block, nullptr); !srs.empty()) {
    facts.push_back({"Coordinate reference system (as the tables name it)", srs});
  }
  std::ostringstream html;
  html << "<h2>1. Survey overview</h2>\n" << HtmlFactsTable("", facts);
  html << PlanViewHtml(block, result, context.georeference) << "\n";
  return html.str();
}

// ------------------------------------------------------------------ 2. verdicts

// Over-fitting of the priors: none, or the groups the solution follows rather than the images.
std::string OverfitVerdictHtml(const BundleAdjustmentResult& result,
                               const BundleReportContext& context) {
  std::vector<std::string> overfit, loose;
  for (const BundleGroupStatistics& g : result.groups) {
    if (g.overfit) overfit.push_back(g.message);
    else if (!g.message.empty()) loose.push_back(g.message);
  }
  const BundleStatisticsOptions& so = context.options.statistics;
  std::ostringstream html;
  const bool judged = std::all_of(result.groups.begin(), result.groups.end(), OverfitJudged);
  if (overfit.empty() && !judged) {
    html << "<div class=\"verdict note\"><b>Over-fitting not judged:</b> the redundancy shares "
            "that say whether the tie points check the priors need the statistics, which this "
            "run did not compute.</div>\n";
  } else if (overfit.empty()) {
    // True of every prior group: none follows its priors (share below the first limit), none
    // has an RMS well below its accuracy unless the block checks it (share above the second).
    html << "<div class=\"verdict good\"><b>No prior group is over-fitted:</b> each is checked "
            "by the tie points (redundancy share at least "
         << FormatUnitless(so.overfit_redundancy_share) << "), and each fits within its stated "
         << "accuracy (RMS / stated at least " << FormatUnitless(so.overfit_ratio) << ")"
         << (loose.empty() ? "" : " or, where it fits better, is checked by the block (share at "
                                  "least " + FormatUnitless(so.checked_redundancy_share) +
                                      "): its accuracy is loose, as noted below")
         << ".</div>\n";
    if (!loose.empty()) {
      html << "<div class=\"verdict note\"><b>Loose stated accuracies</b> (the data fit them "
              "better than stated; stated as measured they would weigh more):<ul>";
      for (const std::string& m : loose) html << "<li>" << HtmlEscape(m) << "</li>";
      html << "</ul></div>\n";
    }
  } else {
    html << "<div class=\"verdict bad\"><b>Over-fitted prior groups</b> (the solution follows "
            "them rather than the images, so their residuals say little about their accuracy):<ul>";
    for (const std::string& m : overfit) html << "<li>" << HtmlEscape(m) << "</li>";
    html << "</ul></div>\n";
  }
  return html.str();
}

// The groups held fixed, the groups that absorbed gross errors, control points removed on an
// assumed accuracy, the weakly determined parameters.
std::string FixedGrossWeakVerdictsHtml(const Block& block, const BundleAdjustmentResult& result,
                                       const BundleReportContext& context) {
  std::ostringstream html;
  for (const BundleGroupStatistics& g : result.groups) {
    if (g.num_fixed == 0) continue;
    html << "<div class=\"verdict note\"><b>Held fixed:</b> "
         << FormatCount(g.num_fixed, "control point")
         << " stated error-free (AccuracyX/Y/Z 0), not adjusted: no residuals and no verdict"
         << (g.fixed() ? "" : "; the verdict above covers the weighted ones only") << ".</div>\n";
  }
  for (const BundleGroupStatistics& g : result.groups) {
    const std::string gross = GrossErrorsAbsorbed(g, UnitText::kUtf8);
    if (!gross.empty())
      html << "<div class=\"verdict bad\"><b>Gross errors absorbed:</b> " << HtmlEscape(gross)
           << "</div>\n";
  }
  const std::string assumed =
      ControlRemovedOnAssumedAccuracy(block, result, context.options.accuracies.marker_m);
  if (!assumed.empty())
    html << "<div class=\"verdict bad\"><b>Control removed on an assumed accuracy:</b> "
         << HtmlEscape(assumed) << "</div>\n";
  const std::string weak = WeaklyDeterminedWarning(result);
  if (!weak.empty())
    html << "<div class=\"verdict bad\"><b>Weakly determined:</b> " << HtmlEscape(weak) << "</div>\n";
  return html.str();
}

// The groups whose RMS / stated lies outside [1 / kWeightFactor, kWeightFactor], with the
// estimate when there is one.
std::string StatedAccuraciesVerdictHtml(const BundleAdjustmentResult& result) {
  std::vector<std::string> weights;
  for (const BundleGroupStatistics& g : result.groups) {
    if (g.count == 0 || !(g.ratio > 0.0)) continue;
    if (g.ratio < 1.0 / kWeightFactor || g.ratio > kWeightFactor) {
      const BundleGroupFigures figures = FormatGroupFigures(g);
      const std::string unit = " " + Utf8UnitName(figures.unit);
      std::string line = std::string(EnumName(g.group)) + ": RMS / stated " +
                         FormatUnitless(g.ratio) + ", the stated " + figures.stated + unit +
                         " looks " + FormatUnitless(g.ratio < 1.0 ? 1.0 / g.ratio : g.ratio, 1) +
                         " times too " + (g.ratio < 1.0 ? "pessimistic" : "optimistic");
      if (std::isfinite(g.estimated_accuracy.x()))
        line += "; estimated from the data: " + figures.estimated + unit;
      weights.push_back(line + ".");
    }
  }
  if (weights.empty()) return "";
  std::ostringstream html;
  html << "<div class=\"verdict note\"><b>Stated accuracies the data contradict</b> (RMS / "
          "stated outside "
       << FormatUnitless(1.0 / kWeightFactor) << " to " << FormatUnitless(kWeightFactor)
       << "; set them to the estimate, e.g. with --estimate_accuracies):<ul>";
  for (const std::string& w : weights) html << "<li>" << HtmlEscape(w) << "</li>";
  html << "</ul></div>\n";
  return html.str();
}

// The check points' count and RMSE as the verdict says them: a georeferenced block's after the
// adjustment along the output CRS's E, N, U (the cells of section 3's table, RmseCells), else the
// local frame's X, Y, Z; no figure when no check point was intersected.
std::string CheckPointsRmseText(const BundleAdjustmentResult& result,
                                const GeoreferenceResult* georeference) {
  if (georeference != nullptr && georeference->evaluated) {
    const GeoreferenceRmse& rmse = georeference->check_after_adjustment;
    std::string text = FormatCount(rmse.count, "point") + " intersected";
    if (rmse.count == 0) return text;
    const LengthUnit unit = GeoreferenceStageUnitsOf(*georeference).after_adjustment;
    const std::vector<std::string> cells = RmseCells(rmse, unit);
    const std::string u = std::string(" ") + LengthUnitName(unit);
    return text + ", RMSE after the adjustment in " + OutCrsName(*georeference) + " (" +
           GeoreferenceErrorAxes(georeference->out_crs_info) + "): E " + cells[0] + u + ", N " +
           cells[1] + u + ", U " + cells[2] + u + ", total " + cells[3] + u;
  }
  std::string text = FormatCount(result.num_check_points, "point") + " intersected";
  if (result.num_check_points == 0) return text;
  const std::vector<std::string> rmse =
      FormatLengthsWithUnit({result.check_rmse_m.x(), result.check_rmse_m.y(),
                             result.check_rmse_m.z(), result.check_rmse_total_m});
  return text + ", RMSE X " + rmse[0] + ", Y " + rmse[1] + ", Z " + rmse[2] + ", total " + rmse[3];
}

// The check points: their RMSE, those beyond their covariance or not intersected; or none.
std::string CheckPointsVerdictHtml(const Block& block, const BundleAdjustmentResult& result,
                                   const BundleReportContext& context) {
  std::ostringstream html;
  if (result.num_check_points == 0 && result.rejected_check_marks.empty()) {
    html << "<div class=\"verdict note\"><b>No check points:</b> nothing independent measures the "
            "block's accuracy"
         << (context.cross_validation != nullptr ? " (see the leave-one-out table below)" : "")
         << ".</div>\n";
    return html.str();
  }
  const std::vector<std::string> out_of_tolerance =
      CheckPointsOutOfTolerance(block, result, context.options.accuracies.marker_m);
  std::vector<std::string> not_intersected;
  for (size_t p = 0; p < block.points.size() && p < result.points.size(); ++p)
    if (block.points[p].role == PointRole::kCheck && !result.points[p].error_m)
      not_intersected.push_back(block.points[p].id + " " + result.points[p].message);
  const bool bad = !out_of_tolerance.empty() || !not_intersected.empty();
  html << "<div class=\"verdict " << (bad ? "bad" : "good") << "\"><b>Check points:</b> "
       << HtmlEscape(CheckPointsRmseText(result, context.georeference)) << ".";
  if (!bad)
    html << " Every error is within what its covariance allows (chi-square(3) at "
         << FormatUnitless(100.0 * kCheckPointLevel, 1) << " %).";
  if (!result.rejected_check_marks.empty())
    html << " "
         << FormatCount(static_cast<long long>(result.rejected_check_marks.size()), "check mark")
         << " rejected by the w-test before intersecting (see Rejected observations).";
  if (bad) {
    html << "<ul>";
    for (const std::string& m : out_of_tolerance) html << "<li>" << HtmlEscape(m) << "</li>";
    for (const std::string& m : not_intersected) html << "<li>" << HtmlEscape(m) << "</li>";
    html << "</ul>";
  }
  html << "</div>\n";
  return html.str();
}

std::string VerdictsHtml(const Block& block, const BundleAdjustmentResult& result,
                         const BundleReportContext& context) {
  const BundleAdjustmentSummary& s = result.summary;
  std::ostringstream html;
  html << "<h2>2. Verdicts</h2>\n";
  if (!s.IsSolutionUsable()) {
    html << "<div class=\"verdict bad\"><b>Not adjusted:</b> " << HtmlEscape(s.message)
         << "</div>\n";
  }
  html << OverfitVerdictHtml(result, context) << FixedGrossWeakVerdictsHtml(block, result, context)
       << StatedAccuraciesVerdictHtml(result) << CheckPointsVerdictHtml(block, result, context);
  return html.str();
}

// ------------------------------------------------------------------ 3. control and check points

// RMSE per axis, horizontal and total over a set of errors (m).
std::vector<std::string> RmseRow(const std::string& name, const std::vector<Eigen::Vector3d>& e,
                                 LengthUnit unit) {
  Eigen::Vector3d ssq = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : e) ssq += v.cwiseAbs2();
  const double n = std::max<double>(1.0, e.size());
  std::vector<std::string> row = {name, std::to_string(e.size())};
  for (int a = 0; a < 3; ++a) row.push_back(FormatLength(std::sqrt(ssq[a] / n), unit));
  row.push_back(FormatLength(std::sqrt((ssq.x() + ssq.y()) / n), unit));
  row.push_back(FormatLength(std::sqrt(ssq.sum() / n), unit));
  if (e.empty()) row = {name, "0", "", "", "", "", ""};
  return row;
}

// A role's RMSE at one stage: count, then RmseCells.
void AppendRmseCells(const GeoreferenceRmse& rmse, LengthUnit unit, std::vector<std::string>* row) {
  row->push_back(std::to_string(rmse.count));
  for (const std::string& cell : RmseCells(rmse, unit)) row->push_back(cell);
}

// A georeferenced block's control and check errors in the output CRS (along its level axes at
// each point: E, N, U), after the similarity alone and after the adjustment side by side, so that
// a reader sees what the adjustment bought; the figures of the JSON's "georeference" section.
std::string GeoreferenceRmseHtml(const GeoreferenceResult& g, const GeoreferenceStageUnits& units) {
  std::vector<std::vector<std::string>> rows(2);
  rows[0] = {"control"};
  AppendRmseCells(g.control_after_similarity, units.after_similarity, &rows[0]);
  AppendRmseCells(g.control_after_adjustment, units.after_adjustment, &rows[0]);
  rows[1] = {"check"};
  AppendRmseCells(g.check_after_similarity, units.after_similarity, &rows[1]);
  AppendRmseCells(g.check_after_adjustment, units.after_adjustment, &rows[1]);
  const std::vector<HeaderGroup> groups = {
      {"", 1},
      {"after the similarity (" + std::string(LengthUnitName(units.after_similarity)) + ")", 5},
      {"after the adjustment (" + std::string(LengthUnitName(units.after_adjustment)) + ")", 5}};
  return HtmlTable(
      "Root mean square errors in " + OutCrsName(g) +
          ": after the similarity and after the adjustment",
      {"points", "count", "E", "N", "U", "total", "count", "E", "N", "U", "total"}, rows,
      {"E, N, U: " + GeoreferenceErrorAxes(g.out_crs_info) + " of " + OutCrsName(g) +
           " at each point; count: the points with an error at that stage",
       "after the similarity: the model's points moved by the similarity alone (fitted to the "
       "camera positions and control); after the adjustment: control points adjusted, check "
       "points intersected from the adjusted images. Control points take part in both, so their "
       "errors are small by construction; check points measure the block's accuracy"},
      groups);
}

// Each control and check point's errors at both stages: control points first, then check points.
std::string GeoreferencePointErrorsHtml(const Block& block, const GeoreferenceResult& g,
                                        const GeoreferenceStageUnits& units) {
  std::vector<std::vector<std::string>> rows;
  bool not_intersected = false;
  const auto cells = [&](const std::optional<Eigen::Vector3d>& e, LengthUnit unit,
                         std::vector<std::string>* row) {
    for (int a = 0; a < 3; ++a) row->push_back(e ? FormatLength((*e)[a], unit) : "n/a");
    not_intersected = not_intersected || !e;
  };
  for (const PointRole role : {PointRole::kControl, PointRole::kCheck}) {
    for (const GeoreferencePointError& e : g.point_errors) {
      const BlockPoint& point = block.points[e.point];
      if (point.role != role) continue;
      std::vector<std::string> row = {point.id, role == PointRole::kControl ? "control" : "check"};
      cells(e.after_similarity_m, units.after_similarity, &row);
      cells(e.after_adjustment_m, units.after_adjustment, &row);
      rows.push_back(row);
    }
  }
  std::vector<std::string> notes = {"error: estimate minus surveyed, along E, N, U as above"};
  if (not_intersected)
    notes.push_back(
        "n/a: no estimate at that stage (the point is not intersected: fewer than two of its "
        "rays, or rays that do not meet; see the tables below)");
  return HtmlTable(
      "Each point's error in " + OutCrsName(g) + ": after the similarity and after the adjustment",
      {"point", "role", "E", "N", "U", "E", "N", "U"}, rows, notes,
      {{"", 2},
       {"after the similarity (" + std::string(LengthUnitName(units.after_similarity)) + ")", 3},
       {"after the adjustment (" + std::string(LengthUnitName(units.after_adjustment)) + ")", 3}});
}

// default_marker_m: the surveyed accuracy of a control or check point that states none (m).
// `georeference` (may be null): a georeferenced block's errors in the output CRS, after the
// similarity and after the adjustment, in place of the RMSE table of the local frame.
std::string PointsHtml(const Block& block, const BundleAdjustmentResult& result,
                       double default_marker_m, const GeoreferenceResult* georeference) {
  std::vector<double> magnitudes;
  for (size_t p = 0; p < block.points.size() && p < result.points.size(); ++p) {
    const BundlePointResult& r = result.points[p];
    if (block.points[p].role == PointRole::kTie) continue;
    if (r.error_m) magnitudes.push_back(r.error_m->norm());
    if (r.has_covariance) magnitudes.push_back(std::sqrt(r.covariance.trace()));
    if (r.has_covariance && r.covariance_complete && block.points[p].role == PointRole::kCheck)
      magnitudes.push_back(CheckPointErrorSigma(block.points[p], r, default_marker_m));
  }
  const LengthUnit unit = LengthUnitFor(LargestMagnitude(magnitudes));
  const std::string u = LengthUnitName(unit);
  std::vector<Eigen::Vector3d> control_errors, check_errors;
  ScatterPlot vertical;
  vertical.title = "vertical errors";
  vertical.x_label = "point (row of the tables: control, then check)";
  vertical.y_label = "error Z (" + u + ")";
  auto point_rows = [&](PointRole role, std::vector<Eigen::Vector3d>* errors) {
    std::vector<std::vector<std::string>> out;
    for (size_t p = 0; p < block.points.size() && p < result.points.size(); ++p) {
      const BlockPoint& point = block.points[p];
      if (point.role != role) continue;
      const BundlePointResult& r = result.points[p];
      if (!r.error_m) {
        out.push_back({point.id, std::to_string(r.num_observations), "", "", "", "", "",
                       r.message.empty() ? "not in the adjustment" : r.message});
        continue;
      }
      if (IsHeldFixed(point)) {  // error and sigma 0 by construction: not plotted
        out.push_back({point.id, std::to_string(r.num_observations), "0", "0", "0", "0", "0",
                       "held fixed"});
        continue;
      }
      errors->push_back(*r.error_m);
      vertical.x.push_back(static_cast<double>(vertical.x.size() + 1));
      vertical.y.push_back(LengthIn(r.error_m->z(), unit));
      vertical.labels.push_back(point.id);
      // A check point: the sigma of its error and the test (the intersection's covariance plus
      // the surveyed coordinates'); a control point: its adjusted sigma, no test (its error is a
      // residual of the adjustment, not an independent miss).
      const bool check = role == PointRole::kCheck;
      const double sigma = check ? CheckPointErrorSigma(point, r, default_marker_m)
                                 : std::sqrt(r.covariance.trace());
      out.push_back(
          {point.id, std::to_string(r.num_observations), FormatLength(r.error_m->x(), unit),
           FormatLength(r.error_m->y(), unit), FormatLength(r.error_m->z(), unit),
           FormatLength(r.error_m->norm(), unit),
           r.has_covariance && std::isfinite(sigma) ? FormatLength(sigma, unit) : "n/a",
           !check ? "n/a"
           : r.has_covariance && r.covariance_complete
               ? FormatUnitless(CheckPointNormalizedError(point, r, default_marker_m), 1)
               : "n/a"});
    }
    return out;
  };
  const std::vector<std::string> header = {"point", "marks", "error X (" + u + ")",
                                           "error Y (" + u + ")", "error Z (" + u + ")",
                                           "|error| (" + u + ")", "sigma (" + u + ")",
                                           "e^T C^-1 e"};
  std::ostringstream html;
  html << "<h2>3. Control and check points</h2>\n";
  const auto control_rows = point_rows(PointRole::kControl, &control_errors);
  const auto check_rows = point_rows(PointRole::kCheck, &check_errors);
  const bool georeferenced = georeference != nullptr && georeference->evaluated;
  if (georeferenced) {
    const GeoreferenceStageUnits units = GeoreferenceStageUnitsOf(*georeference);
    html << GeoreferenceRmseHtml(*georeference, units)
         << GeoreferencePointErrorsHtml(block, *georeference, units);
  } else {
    html << HtmlTable("Root mean square errors",
                      {"points", "count", "X (" + u + ")", "Y (" + u + ")", "Z (" + u + ")",
                       "XY (" + u + ")", "total (" + u + ")"},
                      {RmseRow("control (adjusted - surveyed)", control_errors, unit),
                       RmseRow("check (intersected - surveyed)", check_errors, unit)},
                      {"control points take part in the adjustment, so their errors are small by "
                       "construction; check points do not, and measure the block's accuracy"});
  }
  // A georeferenced block's tables below are in the local frame it was adjusted in.
  const std::string local_frame =
      georeferenced ? "X, Y, Z: the local East-North-Up frame the block was adjusted in (the "
                      "tables above: " + OutCrsName(*georeference) + ")"
                    : "";
  std::vector<std::string> control_notes = {
      "sigma: of the adjusted point; e^T C^-1 e n/a: a control point's error is a residual of "
      "the adjustment, not an independent miss"};
  if (georeferenced) control_notes.insert(control_notes.begin(), local_frame);
  html << HtmlTable("Control points: adjusted minus surveyed", header, control_rows, control_notes);
  std::vector<std::string> check_notes = {
      "sigma: of the error, square root of the trace of C = the intersection's covariance "
      "(sigma0-scaled) plus the surveyed coordinates' (their stated accuracy, " +
          FormatLengthWithUnit(default_marker_m) + " where none is stated)",
      "e^T C^-1 e: the error against C, chi-square with 3 degrees of freedom when both are "
      "honest (above " +
          FormatUnitless(ChiSquaredQuantile(kCheckPointLevel, 3.0), 1) + " in 0.1 % of cases)"};
  if (georeferenced) check_notes.insert(check_notes.begin(), local_frame);
  html << HtmlTable("Check points: intersected from the adjusted images minus surveyed", header,
                    check_rows, check_notes);
  if (!vertical.x.empty()) html << "<div class=\"plots\">" << RenderScatterPlotSvg(vertical) << "</div>\n";
  return html.str();
}

// ------------------------------------------------------------------ 4. cameras

// The cameras table's length units (of the sigmas, and of the differences to the measured
// centres, which a position without height gives horizontally only) and its marks' RMS residual
// column in the images' unit (px, um, or sigma for an image mixing both): in the header when every
// image has the same, else in a unit column after it.
struct CamerasColumns {
  LengthUnit sigma_unit = LengthUnit::kMetre;
  LengthUnit error_unit = LengthUnit::kMetre;
  bool measured = false;  // some image has a measured centre: the comparison columns
  ColumnsInUnits rms;
  bool rms_unit_column = false;
};

CamerasColumns CamerasColumnsOf(const Block& block, const BundleAdjustmentResult& result) {
  std::vector<double> sigmas, errors;
  for (size_t i = 0; i < block.images.size() && i < result.images.size(); ++i) {
    const BundleImageResult& r = result.images[i];
    if (r.has_covariance)
      for (int a = 0; a < 3; ++a) sigmas.push_back(std::sqrt(r.covariance(a, a)));
    const BlockImage& image = block.images[i];
    if (image.eo && image.measured_center_m)
      errors.push_back((image.eo->center_in_ground() - *image.measured_center_m)
                           .head(image.center_height_measured ? 3 : 2)
                           .norm());
  }
  CamerasColumns columns;
  columns.sigma_unit = LengthUnitFor(LargestMagnitude(sigmas));
  columns.error_unit = LengthUnitFor(LargestMagnitude(errors));
  columns.measured = !errors.empty();
  std::vector<double> rms_residuals;
  std::vector<std::string> rms_kinds;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BundleImageResult* r = i < result.images.size() ? &result.images[i] : nullptr;
    const bool adjusted = block.images[i].eo && r != nullptr && r->adjusted;
    rms_residuals.push_back(adjusted ? r->rms_residual : std::nan(""));
    rms_kinds.push_back(adjusted ? r->unit : "");
  }
  // An image not adjusted (no unit, no value) takes the first adjusted image's kind: no part in
  // the choice.
  const auto first = std::find_if(rms_kinds.begin(), rms_kinds.end(),
                                  [](const std::string& k) { return !k.empty(); });
  const std::string first_kind = first == rms_kinds.end() ? "px" : *first;
  for (std::string& kind : rms_kinds)
    if (kind.empty()) kind = first_kind;
  columns.rms = PageColumnsInUnits({rms_residuals}, rms_kinds);
  columns.rms_unit_column = columns.rms.unit.empty() && !rms_kinds.empty();
  return columns;
}

// Grouped columns, each quantity's unit named once above its axes: the table fits a 1280 px
// screen and the A4 width. The comparison with the measured centres only when there are some.
void CamerasHeader(const CamerasColumns& c, std::vector<std::string>* header,
                   std::vector<HeaderGroup>* groups) {
  const std::string rms_header =
      c.rms_unit_column ? "RMS residual" : "RMS residual (" + c.rms.unit + ")";
  *header = {"image", "marks", rms_header, "X", "Y", "Z", "X", "Y", "Z", "omega", "phi", "kappa"};
  if (c.rms_unit_column) header->insert(header->begin() + 3, "unit");
  *groups = {{"", c.rms_unit_column ? 4 : 3},
             {"projection centre (m)", 3},
             {"sigma of the centre (" + std::string(LengthUnitName(c.sigma_unit)) + ")", 3},
             {"sigma of the angles (arcsec)", 3}};
  if (c.measured) {
    header->insert(header->end(), {"X", "Y", "Z"});
    groups->push_back(
        {"adjusted - measured (" + std::string(LengthUnitName(c.error_unit)) + ")", 3});
  }
}

// An adjusted image's row: marks, RMS residual, centre, its sigmas, the angles' sigmas and the
// difference to the measured centre.
std::vector<std::string> CameraRow(const BlockImage& image, const BundleImageResult& r, size_t i,
                                   const CamerasColumns& c) {
  const Eigen::Vector3d center = image.eo->center_in_ground();
  std::vector<std::string> row = {image.name, std::to_string(r.num_marks), c.rms.texts[0][i]};
  if (c.rms_unit_column) row.push_back(c.rms.units[i]);
  for (int a = 0; a < 3; ++a) row.push_back(FormatCoordinate(center[a]));
  for (int a = 0; a < 3; ++a)
    row.push_back(r.has_covariance ? FormatLength(std::sqrt(r.covariance(a, a)), c.sigma_unit)
                                   : "n/a");
  for (int a = 3; a < 6; ++a)
    row.push_back(r.has_covariance
                      ? FormatArcSeconds(std::sqrt(r.covariance(a, a)) * kDegreesPerRadian)
                      : "n/a");
  if (c.measured) {
    for (int a = 0; a < 3; ++a)
      row.push_back(image.measured_center_m && (a < 2 || image.center_height_measured)
                        ? FormatLength(center[a] - (*image.measured_center_m)[a], c.error_unit)
                        : "n/a");
  }
  return row;
}

std::string CamerasHtml(const Block& block, const BundleAdjustmentResult& result) {
  const CamerasColumns columns = CamerasColumnsOf(block, result);
  std::vector<std::string> header;
  std::vector<HeaderGroup> groups;
  CamerasHeader(columns, &header, &groups);
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> notes = {
      "sigmas: sigma0-scaled, from the posterior covariance; angles: the seed's omega, phi, kappa"};
  if (columns.measured) notes.push_back("measured: the frames table's projection centre (GNSS)");
  if (std::any_of(block.images.begin(), block.images.end(), [](const BlockImage& image) {
        return image.measured_center_m && !image.center_height_measured;
      }))
    notes.push_back("Z n/a: a camera position without height, compared horizontally only");
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    const BundleImageResult* r = i < result.images.size() ? &result.images[i] : nullptr;
    if (!image.eo || r == nullptr || !r->adjusted) {
      std::vector<std::string> row(header.size(), "");
      row[0] = image.name;
      row[1] = "not adjusted";
      rows.push_back(row);
      notes.push_back(image.name + " not adjusted" +
                      (r != nullptr && !r->message.empty() ? ": " + r->message : ""));
      continue;
    }
    rows.push_back(CameraRow(image, *r, i, columns));
  }
  std::ostringstream html;
  html << "<h2>4. Cameras</h2>\n"
       << HtmlTable("Adjusted projection centres and their precision", header, rows, notes,
                    groups);
  return html.str();
}

// ------------------------------------------------------------------ 5. calibration

std::string CalibrationHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::ostringstream html;
  html << "<h2>5. Camera calibration</h2>\n";
  if (result.calibration.empty()) {
    html << "<p>Not estimated: the cameras were held as given.</p>\n";
  }
  for (const BundleCalibrationResult& c : result.calibration) {
    const BlockCamera& camera = block.cameras[c.camera];
    std::vector<std::vector<std::string>> rows;
    for (size_t k = 0; k < c.names.size(); ++k) {
      const CoefficientTexts texts =
          FormatCoefficient(c.values[k], k < c.sigmas.size() ? c.sigmas[k] : std::nan(""));
      const std::string unit = Utf8UnitName(CameraParamUnit(camera.model, c.names[k]));
      rows.push_back({c.names[k], texts.value, texts.sigma,
                      texts.scale.empty() ? unit : texts.scale + " " + unit});
    }
    html << HtmlTable("Camera '" + camera.camera_id + "' (" + EnumName(camera.model) + ")",
                      {"parameter", "value", "sigma", "unit"}, rows, c.high_correlations);
    if (c.correlation.rows() == static_cast<Eigen::Index>(c.names.size()) && !c.names.empty()) {
      std::vector<std::string> header = {""};
      for (const std::string& n : c.names) header.push_back(n);
      std::vector<std::vector<std::string>> corr;
      for (size_t i = 0; i < c.names.size(); ++i) {
        std::vector<std::string> row = {c.names[i]};
        for (size_t j = 0; j < c.names.size(); ++j)
          row.push_back(j <= i ? FormatUnitless(c.correlation(i, j)) : "");
        corr.push_back(row);
      }
      html << HtmlTable("Correlations of the estimated parameters (unitless)", header, corr,
                        {"above 0.9 in magnitude: the data cannot tell the two apart"});
    }
  }
  std::string plots;
  for (const BlockCamera& camera : block.cameras) plots += DistortionPlot(camera);
  if (!plots.empty()) html << "<div class=\"plots\">" << plots << "</div>\n";
  return html.str();
}

// ------------------------------------------------------------------ 6. residuals

std::string ResidualsHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::map<std::string, std::string> units;
  for (const BundleGroupStatistics& g : result.groups) units[EnumName(g.group)] = g.unit;
  // Per group and axis: (group, axis) -> values.
  std::map<std::pair<std::string, std::string>, std::vector<double>> by_axis;
  if (!result.observations.empty()) {
    for (const BundleObservationDiagnostics& d : result.observations)
      by_axis[{EnumName(d.group), BundleAxisName(d.group, d.axis)}].push_back(d.residual);
  } else {
    for (size_t m = 0; m < block.marks.size() && m < result.mark_residuals.size(); ++m) {
      if (!result.mark_residuals[m].allFinite()) continue;
      const BundleGroup group =
          block.points[block.marks[m].point].role == PointRole::kControl ? kControlMarks : kTieMarks;
      by_axis[{EnumName(group), "x"}].push_back(result.mark_residuals[m].x());
      by_axis[{EnumName(group), "y"}].push_back(result.mark_residuals[m].y());
    }
  }
  // Each group's residuals in its fixed unit (core/units.h): marks in px or um, lengths in the
  // mm, cm or m of the group's largest, angles in arc seconds.
  std::map<std::string, std::vector<double>> by_group;
  for (const auto& [key, values] : by_axis)
    by_group[key.first].insert(by_group[key.first].end(), values.begin(), values.end());
  std::map<std::string, std::pair<std::string, double>> scale;  // group -> (unit, factor)
  for (const auto& [group, values] : by_group) {
    const std::string& kind = units[group];
    if (kind == "m") {
      const LengthUnit unit = LengthUnitFor(LargestMagnitude(values));
      scale[group] = {LengthUnitName(unit), LengthIn(1.0, unit)};
    } else if (kind == "deg") {
      scale[group] = {"arcsec", 3600.0};
    } else {
      scale[group] = {kind.empty() ? "unitless" : Utf8UnitName(kind), 1.0};
    }
  }
  std::ostringstream html;
  html << "<h2>6. Residuals</h2>\n";
  std::string current;
  for (const auto& [key, values] : by_axis) {
    const auto& [group, axis] = key;
    if (group != current) {
      if (!current.empty()) html << "</div>\n";
      html << "<h3>" << HtmlEscape(group) << "</h3>\n<div class=\"plots\">";
      current = group;
    }
    const auto& [unit, factor] = scale[group];
    HistogramPlot plot;
    plot.title = group + ", " + axis;
    plot.x_label = "residual " + axis + " (" + unit + ")";
    for (const double v : values) plot.values.push_back(factor * v);
    html << RenderHistogramSvg(plot);
  }
  if (!current.empty()) html << "</div>\n";
  std::string vectors;
  for (size_t c = 0; c < block.cameras.size(); ++c)
    vectors += ImageResidualPlot(block, result, static_cast<int>(c), units[EnumName(kTieMarks)]);
  if (!vectors.empty())
    html << "<h3>Over the image format</h3>\n<div class=\"plots\">" << vectors
         << "</div>\n<p>Mean residual of the marks in each of 8 x 6 cells of the measured extent; "
            "a pattern left there is distortion the camera model does not take up.</p>\n";
  return html.str();
}

// ------------------------------------------------------------------ 7. rejected

// Tie marks rejected after a round.
std::string RejectedTieMarksHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::vector<std::vector<std::string>> rows;
  for (const BundleRejectedMark& r : result.rejected_marks) {
    const BlockMark& mark = block.marks[r.mark];
    rows.push_back({block.points[mark.point].id, block.images[mark.image].name,
                    std::to_string(mark.line), std::to_string(r.round),
                    FormatUnitless(r.whitened_residual, 1)});
  }
  return HtmlTable("Tie marks rejected after a round (|v| / (sigma sigma0) above the threshold)",
                   {"point", "image", "marks file line", "round", "|v| / (sigma sigma0)"}, rows);
}

// Check marks rejected by the w-test of their point's intersection, residuals in the mark's unit
// (px or um): in the headers when every mark has the same.
std::string RejectedCheckMarksHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::vector<std::vector<double>> residuals(2);
  std::vector<std::string> kinds;
  for (const BundleRejectedCheckMark& r : result.rejected_check_marks) {
    residuals[0].push_back(r.residual.x());
    residuals[1].push_back(r.residual.y());
    kinds.push_back(EnumName(block.marks[r.mark].unit));
  }
  const ColumnsInUnits in_units = PageColumnsInUnits(residuals, kinds);
  const std::string u = in_units.unit.empty() ? "" : " (" + in_units.unit + ")";
  std::vector<std::vector<std::string>> rows;
  for (size_t k = 0; k < result.rejected_check_marks.size(); ++k) {
    const BundleRejectedCheckMark& r = result.rejected_check_marks[k];
    const BlockMark& mark = block.marks[r.mark];
    rows.push_back({block.points[mark.point].id, block.images[mark.image].name,
                    std::to_string(mark.line), FormatUnitless(r.normalized, 1),
                    in_units.texts[0][k], in_units.texts[1][k]});
    if (in_units.unit.empty()) rows.back().push_back(in_units.units[k]);
  }
  std::vector<std::string> header = {"point", "image",          "marks file line",
                                     "|w|",   "residual x" + u, "residual y" + u};
  if (in_units.unit.empty()) header.push_back("unit");
  return HtmlTable(
      "Check marks rejected by the w-test of their point's intersection (|w| above " +
          FormatUnitless(result.critical_value > 0.0 ? result.critical_value : std::nan(""), 2) +
          ")",
      header, rows,
      {"residuals: observed - computed in the mark's own unit, at the intersection that still "
       "held the mark"});
}

// The observations data snooping removed, in order. Residuals in their group's unit, one per kind
// (marks px or um, lengths mm, cm or m, attitudes arcsec): in the header when every step has the
// same, else in a unit column.
std::string SnoopingHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::map<BundleGroup, std::string> group_units;
  for (const BundleGroupStatistics& g : result.groups) group_units[g.group] = g.unit;
  std::vector<double> residuals;
  std::vector<std::string> kinds;
  for (const BundleSnoopingStep& step : result.snooping) {
    residuals.push_back(step.residual);
    const auto unit = group_units.find(step.group);
    kinds.push_back(unit != group_units.end() ? unit->second : "");
  }
  const ColumnsInUnits in_units = PageColumnsInUnits({residuals}, kinds);
  std::vector<std::vector<std::string>> rows;
  for (size_t k = 0; k < result.snooping.size(); ++k) {
    const BundleSnoopingStep& step = result.snooping[k];
    rows.push_back({std::to_string(k + 1), EnumName(step.group),
                    BundleItemName(block, step.group, step.item),
                    BundleAxisName(step.group, step.axis), FormatUnitless(step.normalized, 1),
                    in_units.texts[0][k]});
    if (in_units.unit.empty()) rows.back().push_back(in_units.units[k]);
  }
  std::vector<std::string> header = {
      "step", "group", "observation",
      "axis", "|w|",   in_units.unit.empty() ? "residual" : "residual (" + in_units.unit + ")"};
  if (in_units.unit.empty()) header.push_back("unit");
  return HtmlTable("Data snooping: observations removed, in order (|w| above " +
                       FormatUnitless(result.critical_value) + ")",
                   header, rows);
}

std::string RejectedHtml(const Block& block, const BundleAdjustmentResult& result) {
  std::ostringstream html;
  html << "<h2>7. Rejected observations</h2>\n";
  if (!result.rejected_marks.empty()) html << RejectedTieMarksHtml(block, result);
  if (!result.rejected_check_marks.empty()) html << RejectedCheckMarksHtml(block, result);
  if (!result.snooping.empty()) html << SnoopingHtml(block, result);
  const std::vector<std::string>& left_out = result.summary.tie_points_left_out;
  if (!left_out.empty()) {
    std::vector<std::vector<std::string>> rows;
    for (const std::string& id : left_out) rows.push_back({id});
    html << HtmlTable("Tie points left out (no initial coordinates: rays too close to parallel)",
                      {"point"}, rows);
  }
  if (result.rejected_marks.empty() && result.rejected_check_marks.empty() &&
      result.snooping.empty() && left_out.empty())
    html << "<p>None: every mark and prior was kept.</p>\n";
  return html.str();
}

// ------------------------------------------------------------------ 8. diagnostics

// One group's row of the diagnostics table (the unit column, when there is one, added by the
// caller): count, stated, RMS, estimated, RMS / stated, redundancy share, verdict; its figures
// as the console prints them (FormatGroupFigures).
std::vector<std::string> GroupRow(const BundleGroupStatistics& g,
                                  const BundleGroupFigures& figures) {
  if (g.fixed()) {
    return {EnumName(g.group),
            FormatCount(g.num_fixed, "held fixed", "held fixed"),
            "0 (error-free)",
            "n/a",
            "n/a",
            "n/a",
            "n/a",
            "fixed"};
  }
  std::string verdict = "fits";
  if (g.num_fixed > 0) verdict += ", " + std::to_string(g.num_fixed) + " more held fixed";
  if (g.overfit) {
    verdict = "OVER-FITTED";
  } else if (!OverfitJudged(g)) {
    verdict = "not judged";  // no statistics: no redundancy share (its message may say the RMS)
  } else if (IsPriorGroup(g.group) && !g.message.empty()) {
    verdict = "loose";  // checked by the block, RMS well below the stated accuracy
  } else if (g.ratio > kWeightFactor || g.ratio < 1.0 / kWeightFactor) {
    verdict = "weight off";
  }
  // A group stated differently per axis (GNSS 3/3/6 cm) shows X/Y/Z: its RMS / stated is the
  // whitened ratio over all three, which X alone would not explain.
  return {EnumName(g.group),
          std::to_string(g.count),
          figures.stated,
          figures.rms,
          std::isfinite(g.estimated_accuracy.x())
              ? figures.estimated
              : (g.estimation_message.empty() ? "not asked" : "not estimated"),
          FormatUnitless(g.ratio),
          std::isfinite(g.redundancy_share) ? FormatUnitless(g.redundancy_share) : "n/a",
          verdict};
}

// The groups of the objective against their stated accuracies. Each group's stated, RMS and
// estimated figures in the unit its own values call for (FormatGroupFigures: a control-point
// group in mm beside camera positions in m; marks in px or um; attitudes in arc seconds): named
// in the headers when every group has the same, else in a unit column; never in a cell.
std::string GroupsTableHtml(const BundleAdjustmentResult& result,
                            const BundleReportContext& context) {
  std::vector<BundleGroupFigures> figures;
  std::vector<std::string> units;
  for (const BundleGroupStatistics& g : result.groups) {
    figures.push_back(FormatGroupFigures(g));
    units.push_back(g.fixed() ? "" : Utf8UnitName(figures.back().unit));
  }
  // A fixed group shows no figure: it takes any unit.
  std::string common;
  bool unit_column = false;
  for (const std::string& unit : units) {
    if (unit.empty()) continue;
    if (common.empty())
      common = unit;
    else if (unit != common)
      unit_column = true;
  }
  const std::string u = unit_column || common.empty() ? "" : " (" + common + ")";
  std::vector<std::vector<std::string>> rows;
  for (size_t k = 0; k < result.groups.size(); ++k) {
    std::vector<std::string> row = GroupRow(result.groups[k], figures[k]);
    if (unit_column) row.insert(row.begin() + 2, units[k].empty() ? "n/a" : units[k]);
    rows.push_back(row);
  }
  std::vector<std::string> header = {"group",
                                     "count",
                                     "stated" + u,
                                     "RMS" + u,
                                     "estimated accuracy" + u,
                                     "RMS / stated",
                                     "redundancy share",
                                     "verdict"};
  // The notes of what the table shows: a verdict's or a notation's note only when a row uses it.
  const auto shown = [&rows](const std::string& verdict) {
    for (const std::vector<std::string>& row : rows)
      if (row.back() == verdict) return true;
    return false;
  };
  const BundleStatisticsOptions& so = context.options.statistics;
  std::vector<std::string> notes = {
      "redundancy share: the group's summed redundancy numbers over its observations, how much "
      "of it the rest of the block checks (0 to 1)",
      "over-fitted: a prior group whose redundancy share is below " +
          FormatUnitless(so.overfit_redundancy_share) + ", or whose RMS / stated is below " +
          FormatUnitless(so.overfit_ratio) + " with a share below " +
          FormatUnitless(so.checked_redundancy_share),
      "weight off: RMS / stated outside " + FormatUnitless(1.0 / kWeightFactor) + " to " +
          FormatUnitless(kWeightFactor)};
  if (std::any_of(result.groups.begin(), result.groups.end(), StatedPerAxis))
    notes.insert(notes.begin(), "stated: X/Y/Z where a group's axes differ (RMS / stated is the "
                                "whitened ratio over all of them)");
  if (shown("loose"))
    notes.push_back("loose: RMS / stated below " + FormatUnitless(so.overfit_ratio) +
                    " in a prior group the block checks (share at least " +
                    FormatUnitless(so.checked_redundancy_share) +
                    "): its stated accuracy is looser than the data");
  if (shown("not judged"))
    notes.push_back("not judged: no redundancy share (statistics turned off)");
  if (unit_column) {
    header.insert(header.begin() + 2, "unit");
    notes.insert(notes.begin(),
                 "unit: of the row's stated, RMS and estimated accuracy, chosen from the "
                 "row's own values (every one with two significant digits)");
  }
  return HtmlTable("Groups of the objective: residuals against the stated accuracies", header, rows,
                   notes);
}

// The uncontrolled observations, the test's figures and a histogram of the redundancy numbers
// per group.
std::string RedundancyHtml(const BundleAdjustmentResult& result,
                           const BundleReportContext& context) {
  std::map<std::string, std::vector<double>> redundancy;
  for (const BundleObservationDiagnostics& d : result.observations)
    redundancy[EnumName(d.group)].push_back(d.redundancy);
  std::ostringstream html;
  html << "<p>" << FormatCount(result.num_uncontrolled, "observation")
       << " with a redundancy number below "
       << FormatUnitless(context.options.statistics.uncontrolled_redundancy)
       << ": a blunder there cannot be seen. The w-test's critical value is "
       << FormatUnitless(result.critical_value)
       << "; smallest detectable errors use delta0 = " << FormatUnitless(result.delta0)
       << ".</p>\n<div class=\"plots\">";
  for (const auto& [group, values] : redundancy) {
    HistogramPlot plot;
    plot.title = "redundancy numbers, " + group;
    plot.x_label = "redundancy number r (unitless, 0 to 1)";
    plot.values = values;
    plot.lo = 0.0;
    plot.hi = 1.0;
    html << RenderHistogramSvg(plot);
  }
  html << "</div>\n";
  return html.str();
}

// Each control point left out in turn: its error as a check point.
std::string CrossValidationHtml(const Block& block, const BundleCrossValidationResult& cv) {
  std::vector<double> magnitudes;
  for (const BundleCrossValidationPoint& p : cv.points)
    if (p.ok) magnitudes.push_back(p.error_m.norm());
  const LengthUnit unit = LengthUnitFor(LargestMagnitude(magnitudes));
  const std::string u = LengthUnitName(unit);
  std::vector<std::vector<std::string>> cv_rows;
  for (const BundleCrossValidationPoint& p : cv.points) {
    cv_rows.push_back({block.points[p.point].id, p.ok ? FormatLength(p.error_m.x(), unit) : "",
                       p.ok ? FormatLength(p.error_m.y(), unit) : "",
                       p.ok ? FormatLength(p.error_m.z(), unit) : "",
                       p.ok ? FormatUnitless(p.normalized, 1) : "",
                       p.stands_out ? "STANDS OUT" : (p.ok ? "fits" : p.message)});
  }
  return HtmlTable(
      "Leave-one-out control points: each adjusted as a check point (" +
          std::string(cv.method == BundleCrossValidationMethod::kUpdate
                          ? "by a low-rank update of the full adjustment"
                          : "by one adjustment per point") +
          ", " + FormatSignificant(cv.time_seconds, 3) + " s); RMSE X " +
          FormatLength(cv.rmse_m.x(), unit) + ", Y " + FormatLength(cv.rmse_m.y(), unit) + ", Z " +
          FormatLength(cv.rmse_m.z(), unit) + " " + u,
      {"point", "error X (" + u + ")", "error Y (" + u + ")", "error Z (" + u + ")", "e^T C^-1 e",
       "verdict"},
      cv_rows, {"e^T C^-1 e: chi-square(3); stands out above " + FormatUnitless(cv.threshold, 1)});
}

// How the adjustment ran, and the command.
std::string RunHtml(const BundleAdjustmentSummary& s, const BundleReportContext& context) {
  std::ostringstream html;
  html << "<h3>Run</h3>\n<p>" << HtmlEscape(EnumName(s.termination)) << ": "
       << FormatCount(s.rounds, "round") << ", " << FormatCount(s.iterations, "iteration")
       << ", cost (half the sum of squared whitened residuals) "
       << FormatSignificant(s.initial_cost, 6) << " to " << FormatSignificant(s.final_cost, 6)
       << ", " << FormatSignificant(s.time_seconds, 3) << " s (statistics "
       << FormatSignificant(s.statistics_seconds, 3) << " s).</p>\n<p><code>"
       << HtmlEscape(context.command_line) << "</code></p>\n";
  return html.str();
}

std::string DiagnosticsHtml(const Block& block, const BundleAdjustmentResult& result,
                            const BundleReportContext& context) {
  std::ostringstream html;
  html << "<h2>8. Diagnostics</h2>\n" << GroupsTableHtml(result, context);
  if (!result.observations.empty()) html << RedundancyHtml(result, context);
  if (context.cross_validation != nullptr)
    html << CrossValidationHtml(block, *context.cross_validation);
  html << RunHtml(result.summary, context) << BundleGlossaryHtml();
  return html.str();
}

}  // namespace

std::string BundleGlossaryHtml() {
  static const std::vector<std::pair<std::string, std::string>> kTerms = {
      {"control point, check point",
       "Surveyed ground points. Control points take part in the adjustment with their stated "
       "accuracy; check points do not: they are intersected from the adjusted images afterwards, "
       "so their errors measure the block's accuracy."},
      {"sigma0", "The a-posteriori standard deviation of unit weight: the RMS of all residuals in "
                 "units of their stated accuracies (unitless); 1 when the stated accuracies hold."},
      {"RMS / stated", "A group's residual RMS over its stated accuracy: below 0.5 the accuracy "
                       "was stated too loose (or the group is over-fitted), above 2 too tight."},
      {"redundancy number r, redundancy share",
       "The part of an observation's error that shows in its own residual, 0 to 1: near 0 the rest "
       "of the block does not check it (a blunder there cannot be seen), near 1 it is fully "
       "checked. A group's redundancy share is its mean redundancy number."},
      {"over-fitted", "A prior group (control points, camera positions, attitudes) the solution "
                      "follows rather than the images: RMS / stated or redundancy share small."},
      {"w-test, |w|", "Baarda's test of one observation: its residual over the residual's standard "
                      "deviation. Above the critical value it is taken as a gross error."},
      {"data snooping", "The w-test applied one observation at a time: the worst above the "
                        "critical value is removed and the block adjusted again."},
      {"delta0, smallest detectable error",
       "The size, in standard deviations, of an error the w-test finds with the chosen power; an "
       "observation's smallest detectable error is delta0 sigma / sqrt(r)."},
      {"e^T C^-1 e", "An error against its covariance: chi-square with 3 degrees of freedom for a "
                     "point when both are honest, mean 3."},
      {"datum", "What fixes the block's position, orientation and scale: control points, camera "
                "positions, or a gauge held for a relative block."},
  };
  return "<h3>Terms</h3>\n" + HtmlGlossary(kTerms);
}

std::string BundleReportHtml(const Block& block, const BundleAdjustmentResult& result,
                             const BundleReportContext& context) {
  const BundleAdjustmentSummary& s = result.summary;
  std::ostringstream html;
  html << HtmlPageOpen("photopose bundle adjustment report", "Bundle adjustment report");
  html << "<p class=\"meta\">" << FormatCount(s.num_images, "image") << ", "
       << FormatCount(s.num_points, "point") << ", " << FormatCount(s.num_marks, "mark")
       << "; photopose " << PHOTOPOSE_VERSION << "</p>\n";
  html << OverviewHtml(block, result, context) << VerdictsHtml(block, result, context)
       << PointsHtml(block, result, context.options.accuracies.marker_m, context.georeference)
       << CamerasHtml(block, result)
       << CalibrationHtml(block, result) << ResidualsHtml(block, result)
       << RejectedHtml(block, result) << DiagnosticsHtml(block, result, context);
  html << HtmlPageClose();
  return html.str();
}

}  // namespace photopose::cli
