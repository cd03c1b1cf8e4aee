// The pictures of `photopose bundle`'s HTML page (tools/report/bundle_plots.h): plan view,
// radial distortion, image residuals.
#include "tools/report/bundle_plots.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

#include "core/camera_models.h"
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

// The plan view's drawing frame: the data's bounding box (m) mapped onto the SVG, one scale for
// both axes, north up.
struct PlanFrame {
  Eigen::Vector2d lo, hi, span;
  double scale = 1.0;   // SVG units per metre
  double extent = 0.0;  // the larger side of the bounding box (m)
  double X(double x) const { return kPlanMargin + (x - lo.x()) * scale; }
  double Y(double y) const { return kPlanHeight - kPlanMargin - (y - lo.y()) * scale; }
};

PlanFrame PlanFrameOf(const std::vector<Eigen::Vector2d>& all) {
  PlanFrame frame;
  frame.lo = all.front();
  frame.hi = all.front();
  for (const auto& p : all) {
    frame.lo = frame.lo.cwiseMin(p);
    frame.hi = frame.hi.cwiseMax(p);
  }
  frame.span = (frame.hi - frame.lo).cwiseMax(1e-9);
  frame.scale = std::min((kPlanWidth - 2 * kPlanMargin) / frame.span.x(),
                         (kPlanHeight - 2 * kPlanMargin) / frame.span.y());
  frame.extent = std::max(frame.span.x(), frame.span.y());
  return frame;
}

// The plan view's exaggerations: the largest ellipse and vector drawn about 4 % of the extent.
struct PlanExaggerations {
  double ellipse = 1.0;  // of the cameras' 1-sigma ellipses
  double vector = 1.0;   // of the surveyed points' error vectors
};

PlanExaggerations PlanExaggerationsOf(const PlanData& data, double extent) {
  double largest_sigma = 0.0, largest_error = 0.0;
  for (const PlanData::Camera& camera : data.cameras)
    if (camera.covariance) largest_sigma = std::max(largest_sigma, std::sqrt(camera.covariance->trace()));
  for (const PlanData::Surveyed& point : data.surveyed)
    if (point.error) largest_error = std::max(largest_error, point.error->norm());
  PlanExaggerations factors;
  factors.ellipse = largest_sigma > 0.0 ? NiceAtMost(0.04 * extent / largest_sigma) : 1.0;
  factors.vector = largest_error > 0.0 ? NiceAtMost(0.04 * extent / largest_error) : 1.0;
  return factors;
}

// Tie points as grey dots.
std::string PlanTiesSvg(const PlanData& data, const PlanFrame& f) {
  std::ostringstream svg;
  svg << "<g fill=\"#999\">";
  for (const Eigen::Vector2d& tie : data.ties)
    svg << "<circle cx=\"" << F(f.X(tie.x()), "%.1f") << "\" cy=\"" << F(f.Y(tie.y()), "%.1f")
        << "\" r=\"0.8\"/>";
  svg << "</g>\n";
  return svg.str();
}

// Cameras as squares with their exaggerated 1-sigma ellipses.
std::string PlanCamerasSvg(const PlanData& data, const PlanFrame& f, double ellipse_factor) {
  std::ostringstream svg;
  for (const PlanData::Camera& camera : data.cameras) {
    const double cx = f.X(camera.xy.x()), cy = f.Y(camera.xy.y());
    if (camera.covariance) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(*camera.covariance);
      const Eigen::Vector2d axes =
          eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt() * ellipse_factor * f.scale;
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
  return svg.str();
}

// Control points (triangles) and check points (dots) with their exaggerated residual vectors.
std::string PlanSurveyedSvg(const PlanData& data, const PlanFrame& f, double vector_factor) {
  std::ostringstream svg;
  for (const PlanData::Surveyed& point : data.surveyed) {
    const double px = f.X(point.xy.x()), py = f.Y(point.xy.y());
    const bool control = point.control;
    const char* color = control ? "#D55E00" : "#009E73";
    if (point.error) {
      const Eigen::Vector2d& e = *point.error;
      svg << "<line x1=\"" << F(px, "%.1f") << "\" y1=\"" << F(py, "%.1f") << "\" x2=\""
          << F(px + e.x() * vector_factor * f.scale, "%.1f") << "\" y2=\""
          << F(py - e.y() * vector_factor * f.scale, "%.1f") << "\" stroke=\"" << color
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
  return svg.str();
}

// The scale bar (metres) and the legend with the exaggerations.
std::string PlanScaleAndLegendSvg(const PlanFrame& f, const PlanExaggerations& factors) {
  std::ostringstream svg;
  const double bar = NiceAtMost(0.25 * f.extent);
  const double bar_y = kPlanHeight - 14.0;
  svg << "<line x1=\"" << kPlanMargin << "\" y1=\"" << bar_y << "\" x2=\""
      << F(kPlanMargin + bar * f.scale, "%.1f") << "\" y2=\"" << bar_y
      << "\" stroke=\"#222\" stroke-width=\"2\"/><text x=\""
      << F(kPlanMargin + bar * f.scale + 6, "%.1f") << "\" y=\"" << bar_y + 4 << "\" class=\""
      << kAxisLabelClass << "\">" << FormatSignificant(bar, 3)
      << " m (plan: east right, north up)</text>\n";
  svg << "<text x=\"" << kPlanWidth - 10 << "\" y=\"16\" text-anchor=\"end\">"
      << "blue squares: cameras, ellipses 1-sigma x" << FormatSignificant(factors.ellipse, 3)
      << "; red triangles: control, green dots: check, vectors x"
      << FormatSignificant(factors.vector, 3) << "; grey: tie points</text>\n";
  return svg.str();
}

// The plan view: tie points, cameras with 1-sigma error ellipses, control and check points with
// their residual vectors, each exaggerated by a stated factor; the corner coordinates written.
std::string PlanView(const PlanData& data) {
  std::vector<Eigen::Vector2d> all = data.ties;
  for (const PlanData::Camera& camera : data.cameras) all.push_back(camera.xy);
  for (const PlanData::Surveyed& point : data.surveyed) all.push_back(point.xy);
  if (all.empty()) return "<p>Nothing to draw.</p>";
  const PlanFrame frame = PlanFrameOf(all);
  const PlanExaggerations factors = PlanExaggerationsOf(data, frame.extent);
  const std::string svg = SvgOpen(kPlanWidth, kPlanHeight, "plan view") + "\n" +
                          PlanTiesSvg(data, frame) + PlanCamerasSvg(data, frame, factors.ellipse) +
                          PlanSurveyedSvg(data, frame, factors.vector) +
                          PlanScaleAndLegendSvg(frame, factors) + "</svg>";
  std::string caption = data.caption.empty() ? std::string() : HtmlEscape(data.caption) + " ";
  caption += "Lower left " + F(frame.lo.x(), "%.2f") + ", " + F(frame.lo.y(), "%.2f") +
             "; upper right " + F(frame.hi.x(), "%.2f") + ", " + F(frame.hi.y(), "%.2f") + ".";
  return svg + "\n<p>" + caption + "</p>";
}

}  // namespace

std::string PlanViewHtml(const Block& block, const BundleAdjustmentResult& result,
                         const GeoreferenceResult* georeference) {
  return PlanView(georeference != nullptr ? GeoreferencedPlanData(block, result, *georeference)
                                          : PlanDataOf(block, result));
}

// Radial distortion of a camera along the image's x axis: the measurement of each ray against
// the same camera without its distortion (model unit), out to the image corner.
std::string DistortionPlot(const BlockCamera& camera) {
  const CameraModelData data = camera.data();
  std::vector<double> ideal_params = camera.params;
  const bool frame = camera.model == CameraModelType::kFrame;
  const size_t first_distortion = frame ? kFrameK0 : (ColmapModelHasTwoFocals(camera.model) ? 4 : 3);
  for (size_t k = first_distortion; k < ideal_params.size(); ++k) ideal_params[k] = 0.0;
  const double focal = CameraModelFocal(camera.model, camera.params.data());
  double half_diagonal = 0.0;  // model unit
  if (frame && camera.table.pixel_size_um > 0.0 && camera.table.n_columns > 0)
    half_diagonal = 0.5 * camera.table.pixel_size_um *
                    std::hypot(camera.table.n_columns, camera.table.n_rows);
  else if (!frame)
    half_diagonal = std::hypot(camera.params[ColmapModelHasTwoFocals(camera.model) ? 2 : 1],
                               camera.params[ColmapModelHasTwoFocals(camera.model) ? 3 : 2]);
  if (!(focal > 0.0) || !(half_diagonal > 0.0)) return "";
  LinePlot plot;
  plot.title = "radial distortion, camera " + camera.camera_id;
  plot.x_label = frame ? "radius from the principal point (mm)" : "radius (px)";
  plot.y_label = frame ? "distortion (" + Utf8UnitName("um") + ")" : "distortion (px)";
  PlotSeries series;
  series.label = "along x";
  constexpr int kSteps = 40;
  for (int k = 0; k <= kSteps; ++k) {
    const double radius = half_diagonal * k / kSteps;
    const Eigen::Vector2d ab(radius / focal, 0.0);
    Eigen::Vector2d with, without;
    if (!ObservationFromNormalized(camera.model, camera.params.data(), data, ab, &with).ok() ||
        !ObservationFromNormalized(camera.model, ideal_params.data(), data, ab, &without).ok())
      continue;
    series.x.push_back(frame ? radius / 1000.0 : radius);
    series.y.push_back((with - without).norm());
  }
  if (series.x.size() < 2) return "";
  plot.series.push_back(series);
  return RenderLinePlotSvg(plot);
}

// Mean mark residual vectors over the image format of a camera (8 x 6 cells of the marks'
// extent), exaggerated by a stated factor.
std::string ImageResidualPlot(const Block& block, const BundleAdjustmentResult& result, int cam,
                              const std::string& unit) {
  constexpr int kCols = 8, kRows = 6;
  constexpr double kWidth = 340.0, kHeight = 260.0;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  std::vector<int> marks;
  for (size_t m = 0; m < block.marks.size() && m < result.mark_residuals.size(); ++m) {
    if (block.images[block.marks[m].image].camera != cam || !result.mark_residuals[m].allFinite())
      continue;
    marks.push_back(static_cast<int>(m));
    lo = lo.cwiseMin(block.marks[m].observation);
    hi = hi.cwiseMax(block.marks[m].observation);
  }
  if (marks.size() < 10) return "";
  std::vector<Eigen::Vector2d> sum(kCols * kRows, Eigen::Vector2d::Zero());
  std::vector<int> count(kCols * kRows, 0);
  const Eigen::Vector2d span = (hi - lo).cwiseMax(1e-9);
  for (const int m : marks) {
    const Eigen::Vector2d f = (block.marks[m].observation - lo).cwiseQuotient(span);
    const int cx = std::clamp(static_cast<int>(f.x() * kCols), 0, kCols - 1);
    const int cy = std::clamp(static_cast<int>(f.y() * kRows), 0, kRows - 1);
    sum[cy * kCols + cx] += result.mark_residuals[m];
    ++count[cy * kCols + cx];
  }
  double largest = 0.0;
  for (int k = 0; k < kCols * kRows; ++k)
    if (count[k] > 0) largest = std::max(largest, (sum[k] / count[k]).norm());
  const PlotFrame frame = SmallPlotFrame(kWidth, kHeight);
  PlotAxis x_axis, y_axis;
  x_axis.lo = lo.x(), x_axis.hi = hi.x();
  y_axis.lo = lo.y(), y_axis.hi = hi.y();
  const bool frame_model = block.cameras[cam].model == CameraModelType::kFrame;
  const std::string title = "mean residuals, camera " + block.cameras[cam].camera_id;
  std::ostringstream svg;
  svg << SvgOpen(kWidth, kHeight, title)
      << SvgText(kWidth / 2, 20, title, "middle", " font-size=\"14\" font-weight=\"bold\"");
  const double cell = std::min(frame.width / kCols, frame.height / kRows);
  const double factor = largest > 0.0 ? NiceAtMost(0.45 * cell / largest) : 1.0;
  const std::string exaggeration = "; vectors x" + FormatSignificant(factor, 3);
  // Ticks along x; along y only for film (y up like the plot; pixel rows grow down).
  const std::string film = Utf8UnitName("um");
  svg << SvgAxes(frame, &x_axis, frame_model ? &y_axis : nullptr,
                 (frame_model ? "film x (" + film + ")" : "column (px)") + exaggeration,
                 frame_model ? "film y (" + film + ")" : "row (px)");
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c) {
      const int k = r * kCols + c;
      if (count[k] == 0) continue;
      const Eigen::Vector2d mean = sum[k] / count[k];
      const ValuesInOneUnit mean_text = FormatInOneUnit({mean.norm()}, unit);
      const double x = frame.left + (c + 0.5) * frame.width / kCols;
      // Film y grows up, pixel rows down: draw each as its image shows it.
      const double y = frame_model ? frame.top + frame.height - (r + 0.5) * frame.height / kRows
                                   : frame.top + (r + 0.5) * frame.height / kRows;
      const double dy = (frame_model ? -1.0 : 1.0) * mean.y() * factor;
      svg << "<line x1=\"" << ReportNumber(x, "%.1f") << "\" y1=\"" << ReportNumber(y, "%.1f")
          << "\" x2=\"" << ReportNumber(x + mean.x() * factor, "%.1f") << "\" y2=\""
          << ReportNumber(y + dy, "%.1f") << "\" stroke=\"" << PlotColor(1)
          << "\" stroke-width=\"2\"><title>" << count[k] << " marks, mean " << mean_text.texts[0]
          << " " << Utf8UnitName(mean_text.unit) << "</title></line>"
          << "<circle cx=\"" << ReportNumber(x, "%.1f") << "\" cy=\"" << ReportNumber(y, "%.1f")
          << "\" r=\"1.5\" fill=\"#555\"/>";
    }
  svg << "</svg>";
  return svg.str();
}

}  // namespace photopose::cli
