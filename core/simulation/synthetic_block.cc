// The one synthetic block generator (synthetic_block.h) of the tests, the benchmarks and
// `photopose simulate`. One file past ~800 lines on purpose: its options' checks, the flight,
// terrain and point layout, then the steps of MakeSyntheticBlock in order (each on its own random
// stream), and the truth as text; splitting it would scatter one seed's draws over several files.
#include "core/simulation/synthetic_block.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/camera.h"
#include "core/collinearity.h"
#include "core/simulation/portable_random.h"
#include "core/rotation.h"
#include "core/io/tables.h"
#include "core/io/csv.h"

namespace photopose {
namespace {

// Random streams, one per kind of draw (see the header).
enum Stream : uint64_t {
  kStreamPoses = 1,
  kStreamTerrain,
  kStreamTiePoints,
  kStreamControl,
  kStreamMarkNoise,
  kStreamGnss,
  kStreamAttitude,
  kStreamBlunders,
  kStreamStart,
};

constexpr long long kMaxIndex = std::numeric_limits<int>::max();
// Images in a block: beyond this the grid is a typing error rather than a survey.
constexpr long long kMaxImages = 10000000;
// Wavelengths of the terrain's hills (m) and the direction of the third one.
constexpr double kHillWavelength1M = 420.0;
constexpr double kHillWavelength2M = 310.0;
constexpr double kHillWavelength3M = 650.0;
// Tie points by count: give up after this many candidates per point asked (the geometry then
// cannot hold them, e.g. min_tie_views larger than the overlap gives).
constexpr long long kTieAttemptsPerPoint = 50;

bool NonNegative(double value) { return std::isfinite(value) && value >= 0.0; }
bool Positive(double value) { return std::isfinite(value) && value > 0.0; }

Status Invalid(const std::string& why) { return Status::Error("synthetic block: " + why); }

// Focal length in pixels of the options' camera.
double FocalPx(const SyntheticBlockOptions& o) {
  if (!o.camera_params.empty()) {
    if (o.camera_model == CameraModelType::kFrame) return o.camera_params[0] / o.pixel_size_um;
    return CameraModelFocal(o.camera_model, o.camera_params.data());
  }
  return o.focal_length_mm * 1000.0 / o.pixel_size_um;
}

// A rectangle on the ground relative to an image's nominal centre (m): X in [x0, x1], Y in
// [y0, y1].
struct GroundBox {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0;
  double y0 = x0, y1 = -x0;
  void Include(double x, double y) {
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  void Include(const GroundBox& b) {
    Include(b.x0, b.y0);
    Include(b.x1, b.y1);
  }
  void Widen(double m) {
    x0 -= m;
    x1 += m;
    y0 -= m;
    y1 += m;
  }
};

struct Geometry {
  double footprint_width_m, footprint_height_m;  // of a nadir image at the mean terrain
  double forward_m, side_m;
  GroundBox footprint;  // the nominal footprint at the mean terrain (over the lines' headings)
  GroundBox reach;      // where a ground point an image sees can lie (jitter, tilt, relief)
  bool rays_reach_ground = true;  // false: a tilted corner ray is too close to the horizon
};

// A corner ray must descend at least this much per unit of length (about 84 deg from the
// vertical): flatter ones reach the ground too far away for a block.
constexpr double kMinCornerRayDescent = 0.1;
// Widening of a tilted image's reach, relative to its size: the corner rays are taken through a
// centred pinhole; principal-point offsets and distortion move them by less than this.
constexpr double kTiltedReachSlack = 0.05;

bool Tilted(const SyntheticBlockOptions& o) { return !o.nominal_angles_deg.isZero(); }

// The box of the four corner rays of an image with seed angles `angles_rad`, its centre `depth_m`
// above a plane; false when a ray is too flat (kMinCornerRayDescent).
bool CornerRaysBox(const SyntheticBlockOptions& o, double f_px, const Eigen::Vector3d& angles_rad,
                   double depth_m, GroundBox* box) {
  // Ray of image point (x, y) in the camera frame: (x, y, -c) (core/collinearity.h), to ground
  // by R_camera_from_ground^T.
  const Eigen::Matrix3d R_ground_from_camera =
      RotationFromAngles(RotationConvention::kSeed, angles_rad).transpose();
  for (const double sx : {-0.5, 0.5}) {
    for (const double sy : {-0.5, 0.5}) {
      const Eigen::Vector3d ray =
          R_ground_from_camera *
          Eigen::Vector3d(sx * o.image_width_px, sy * o.image_height_px, -f_px);
      if (!(-ray.z() >= kMinCornerRayDescent * ray.norm())) return false;
      const double t = depth_m / -ray.z();
      box->Include(t * ray.x(), t * ray.y());
    }
  }
  return true;
}

// The footprint and reach of tilted images: corner rays at the nominal angles of each heading
// flown (kappa 0, and 180 on lines flown back), and for the reach at the nominal +- the jitter
// per angle, from the highest and the lowest camera above the terrain.
void TiltedFootprint(const SyntheticBlockOptions& o, Geometry* g) {
  const double f_px = FocalPx(o);
  const Eigen::Vector3d nominal_rad = o.nominal_angles_deg / kDegreesPerRadian;
  const double jitter_rad = DegreesToRadians(o.attitude_jitter_deg);
  const double vertical_slack_m = 0.5 * o.terrain_relief_m + o.position_jitter_m;
  std::vector<double> headings = {0.0};
  if (o.serpentine && o.num_lines > 1) headings.push_back(kPi);
  for (const double heading : headings) {
    const Eigen::Vector3d base = nominal_rad + Eigen::Vector3d(0.0, 0.0, heading);
    g->rays_reach_ground &= CornerRaysBox(o, f_px, base, o.flying_height_m, &g->footprint);
    for (int combo = 0; combo < 27; ++combo) {
      const Eigen::Vector3d step((combo % 3) - 1, (combo / 3 % 3) - 1, (combo / 9) - 1);
      for (const double depth :
           {o.flying_height_m - vertical_slack_m, o.flying_height_m + vertical_slack_m}) {
        g->rays_reach_ground &= CornerRaysBox(o, f_px, base + jitter_rad * step, depth, &g->reach);
      }
    }
  }
  if (!g->rays_reach_ground) return;
  g->reach.Widen(o.position_jitter_m + 1.0 +
                 kTiltedReachSlack *
                     std::max(g->reach.x1 - g->reach.x0, g->reach.y1 - g->reach.y0));
}

Geometry FlightGeometry(const SyntheticBlockOptions& o) {
  Geometry g;
  const double f_px = FocalPx(o);
  g.footprint_width_m = o.image_width_px / f_px * o.flying_height_m;
  g.footprint_height_m = o.image_height_px / f_px * o.flying_height_m;
  g.forward_m = o.forward_spacing_m > 0.0 ? o.forward_spacing_m
                                          : (1.0 - o.forward_overlap) * g.footprint_height_m;
  g.side_m = o.side_spacing_m > 0.0 ? o.side_spacing_m : (1.0 - o.side_overlap) * g.footprint_width_m;
  if (Tilted(o)) {
    TiltedFootprint(o, &g);
    return g;
  }
  // Nadir: the footprint centred on the image; jitter, tilt and relief can move it by the margin.
  g.footprint.Include(-0.5 * g.footprint_width_m, -0.5 * g.footprint_height_m);
  g.footprint.Include(0.5 * g.footprint_width_m, 0.5 * g.footprint_height_m);
  const double margin =
      o.position_jitter_m +
      o.flying_height_m * std::tan(DegreesToRadians(o.attitude_jitter_deg)) * 1.5 +
      o.terrain_relief_m + 1.0;
  g.reach = g.footprint;
  g.reach.Widen(margin);
  return g;
}

// The control points asked: the explicit layout's, else num_control_points.
int NumControlPoints(const SyntheticBlockOptions& o) {
  return o.control_layout.empty() ? o.num_control_points
                                  : static_cast<int>(o.control_layout.size());
}
int NumCheckPoints(const SyntheticBlockOptions& o) {
  return o.check_layout.empty() ? o.num_check_points : static_cast<int>(o.check_layout.size());
}

BlockCamera MakeCamera(const SyntheticBlockOptions& o) {
  BlockCamera camera;
  camera.camera_id = "SyntheticCamera";
  camera.model = o.camera_model;
  FrameCamera& table = camera.table;
  table.camera_id = camera.camera_id;
  table.n_columns = o.image_width_px;
  table.n_rows = o.image_height_px;
  table.n_bands = 3;
  if (o.camera_model == CameraModelType::kFrame) {
    table.object_id = 1;
    table.pixel_size_um = o.pixel_size_um;
    table.focal_length_um = o.focal_length_mm * 1000.0;
    table.average_z_m = o.ground_height_m;
    table.apply_ecc = o.earth_curvature;
    if (o.camera_params.empty()) {
      const auto params = FrameModelParams(table);
      camera.params.assign(params.begin(), params.end());
    } else {
      // The table shows c, the principal point and the distortion; affinity and skew stay in the
      // parameters (SetFrameModelParams folds them into A0-B2 when the table is written).
      camera.params = o.camera_params;
      const std::vector<double>& p = camera.params;
      table.focal_length_um = p[kFrameFocal];
      table.principal_x_um = p[kFramePrincipalX];
      table.principal_y_um = p[kFramePrincipalY];
      table.radial_k = {p[kFrameK0], p[kFrameK1], p[kFrameK2], p[kFrameK3]};
      table.tangential_p = {p[kFrameP1], p[kFrameP2]};
    }
    return camera;
  }
  if (!o.camera_params.empty()) {
    camera.params = o.camera_params;
    return camera;
  }
  const double f = FocalPx(o);
  const double cx = 0.5 * o.image_width_px, cy = 0.5 * o.image_height_px;
  switch (o.camera_model) {
    case CameraModelType::kSimplePinhole:
      camera.params = {f, cx, cy};
      break;
    case CameraModelType::kPinhole:
      camera.params = {f, f, cx, cy};
      break;
    case CameraModelType::kSimpleRadial:
      camera.params = {f, cx, cy, 0.0};
      break;
    case CameraModelType::kRadial:
      camera.params = {f, cx, cy, 0.0, 0.0};
      break;
    default:  // fx, fy, cx, cy and no distortion
      camera.params.assign(CameraModelNumParams(o.camera_model), 0.0);
      camera.params[0] = camera.params[1] = f;
      camera.params[2] = cx;
      camera.params[3] = cy;
      break;
  }
  return camera;
}

// The smooth terrain of the options.
class Terrain {
 public:
  Terrain(const SyntheticBlockOptions& o) : o_(o) {
    PortableRandom random(o.seed, kStreamTerrain);
    for (double& phase : phase_) phase = random.Uniform(0.0, 2.0 * kPi);
  }
  double Height(double x, double y) const {
    const double u = x - o_.origin_m.x(), v = y - o_.origin_m.y();
    const double h = 0.5 * (std::sin(2.0 * kPi * u / kHillWavelength1M + phase_[0]) *
                                std::sin(2.0 * kPi * v / kHillWavelength2M + phase_[1]) +
                            std::sin(2.0 * kPi * (0.6 * u + 0.8 * v) / kHillWavelength3M + phase_[2]));
    return o_.ground_height_m + 0.5 * o_.terrain_relief_m * h;
  }

 private:
  const SyntheticBlockOptions& o_;
  double phase_[3];
};

// The flight: nominal centres on the grid, images in flight order.
class Flight {
 public:
  Flight(const SyntheticBlockOptions& o, const Geometry& g) : o_(o), g_(g) {}
  int lines() const { return o_.num_lines; }
  int per_line() const { return o_.images_per_line; }
  // Image index of grid position (line, k), k counted northwards.
  int Image(int line, int k) const {
    const bool back = o_.serpentine && line % 2 == 1;
    return line * o_.images_per_line + (back ? o_.images_per_line - 1 - k : k);
  }
  double LineX(int line) const { return o_.origin_m.x() + line * g_.side_m; }
  double ExposureY(int k) const { return o_.origin_m.y() + k * g_.forward_m; }
  bool FlownBack(int line) const { return o_.serpentine && line % 2 == 1; }
  // Grid position of image `index`.
  void GridPosition(int index, int* line, int* k) const {
    *line = index / o_.images_per_line;
    const int j = index % o_.images_per_line;
    *k = FlownBack(*line) ? o_.images_per_line - 1 - j : j;
  }
  // Grid ranges of the images that may see ground point (x, y) (the point within the reach of
  // their nominal centre); empty ranges when none.
  void Candidates(double x, double y, int* line0, int* line1, int* k0, int* k1) const {
    const GroundBox& r = g_.reach;
    *line0 = std::max(0, static_cast<int>(std::ceil((x - r.x1 - o_.origin_m.x()) / g_.side_m)));
    *line1 = std::min(o_.num_lines - 1,
                      static_cast<int>(std::floor((x - r.x0 - o_.origin_m.x()) / g_.side_m)));
    *k0 = std::max(0, static_cast<int>(std::ceil((y - r.y1 - o_.origin_m.y()) / g_.forward_m)));
    *k1 = std::min(o_.images_per_line - 1,
                   static_cast<int>(std::floor((y - r.y0 - o_.origin_m.y()) / g_.forward_m)));
  }

 private:
  const SyntheticBlockOptions& o_;
  const Geometry& g_;
};

// Projects through the true orientation and the camera: the pixel (Column, Row; corner origin).
class Projector {
 public:
  Projector(const BlockCamera& camera) : camera_(camera), data_(camera.data()) {}
  bool Pixel(const ExteriorOrientation& eo, const Eigen::Vector3d& point,
             Eigen::Vector2d* pixel) const {
    double ab[2];
    double lowered[3] = {point.x(), point.y(), point.z()};
    if (camera_.earth_curvature_radius_m() > 0.0)
      LowerByEarthCurvature(eo.data(), point.data(), camera_.earth_curvature_radius_m(), lowered);
    if (!ProjectToNormalized(eo.data(), lowered, ab)) return false;
    Eigen::Vector2d observation;
    if (!ObservationFromNormalized(camera_.model, camera_.params.data(), data_, {ab[0], ab[1]},
                                   &observation)
             .ok())
      return false;
    if (camera_.model == CameraModelType::kFrame) {
      if (!PixelFromFilm(camera_.table, observation, PixelOrigin::kCorner, pixel).ok()) return false;
    } else {
      *pixel = observation;
    }
    return pixel->x() >= 0.0 && pixel->y() >= 0.0 && pixel->x() <= camera_.table.n_columns &&
           pixel->y() <= camera_.table.n_rows;
  }
  // The observation (model unit) of a pixel.
  Status Observation(const Eigen::Vector2d& pixel, Eigen::Vector2d* observation) const {
    if (camera_.model != CameraModelType::kFrame) {
      *observation = pixel;
      return Status::Ok();
    }
    return FilmFromPixel(camera_.table, pixel, PixelOrigin::kCorner, observation);
  }

 private:
  const BlockCamera& camera_;
  CameraModelData data_;
};

// A true observation found while placing the points.
struct View {
  int image;
  int point;
  Eigen::Vector2d pixel;
};

// `prefix` and `number` with leading zeros to `digits` digits.
std::string Numbered(std::string prefix, long long number, int digits) {
  const std::string text = std::to_string(number);
  if (static_cast<int>(text.size()) < digits) prefix.append(digits - text.size(), '0');
  return prefix + text;
}

int Digits(long long n) {
  int digits = 1;
  while (n >= 10) {
    n /= 10;
    ++digits;
  }
  return digits;
}

Eigen::Vector3d RandomDirection(PortableRandom* random) {
  const double z = random->Uniform(-1.0, 1.0);
  const double angle = random->Uniform(0.0, 2.0 * kPi);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(angle), r * std::sin(angle), z};
}

// `count` distinct values of `pool`, chosen uniformly (partial Fisher-Yates on a copy).
std::vector<int> Choose(std::vector<int> pool, int count, PortableRandom* random) {
  for (int k = 0; k < count; ++k) {
    const size_t j = k + static_cast<size_t>(random->Below(pool.size() - k));
    std::swap(pool[k], pool[j]);
  }
  pool.resize(count);
  std::sort(pool.begin(), pool.end());
  return pool;
}

// Control-point layout in the unit square: corners, edge midpoints, centre, inner quarter
// points, edge quarter points; more are drawn uniformly.
const std::vector<Eigen::Vector2d>& ControlLayout() {
  static const auto* const kLayout = new std::vector<Eigen::Vector2d>{
      {0, 0},       {1, 0},       {1, 1},     {0, 1},        {0.5, 0},   {1, 0.5},   {0.5, 1},
      {0, 0.5},     {0.5, 0.5},   {0.25, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.25, 0.75},
      {0.25, 0},    {0.75, 0},    {1, 0.25},  {1, 0.75},     {0.75, 1},  {0.25, 1},  {0, 0.75},
      {0, 0.25}};
  return *kLayout;
}

// The stated accuracy: the one given, else the sigma, else unset.
std::optional<double> Stated(double accuracy, double sigma) {
  if (accuracy > 0.0) return accuracy;
  if (sigma > 0.0) return sigma;
  return std::nullopt;
}

// ---- the steps of MakeSyntheticBlock, in order; each draws from its own random stream.

// The true poses on the grid, images in flight order, and their names.
void PlaceImages(const SyntheticBlockOptions& o, const Flight& flight, Block* block,
                 SyntheticBlockTruth* t) {
  const int num_images = o.num_lines * o.images_per_line;
  block->images.resize(num_images);
  t->eo.resize(num_images);
  PortableRandom random(o.seed, kStreamPoses);
  const int line_digits = std::max(2, Digits(o.num_lines));
  const int image_digits = std::max(3, Digits(o.images_per_line));
  const double jitter_rad = DegreesToRadians(o.attitude_jitter_deg);
  for (int line = 0; line < o.num_lines; ++line) {
    for (int j = 0; j < o.images_per_line; ++j) {
      const int k = flight.FlownBack(line) ? o.images_per_line - 1 - j : j;
      const int index = flight.Image(line, k);
      ExteriorOrientation eo;
      const double J = o.position_jitter_m;
      eo.set_center_in_ground({flight.LineX(line) + random.Uniform(-J, J),
                               flight.ExposureY(k) + random.Uniform(-J, J),
                               o.ground_height_m + o.flying_height_m + random.Uniform(-J, J)});
      eo.set_angles_seed_rad({random.Uniform(-jitter_rad, jitter_rad),
                              random.Uniform(-jitter_rad, jitter_rad),
                              WrapAngle((flight.FlownBack(line) ? kPi : 0.0) +
                                        random.Uniform(-jitter_rad, jitter_rad))});
      // Tilts draw nothing: the poses' stream is the same with or without them.
      Eigen::Vector3d tilt_deg = o.nominal_angles_deg;
      for (const auto& [image, extra_deg] : o.extra_angles_deg)
        if (image == index) tilt_deg += extra_deg;
      if (!tilt_deg.isZero()) {
        Eigen::Vector3d angles = eo.angles_seed_rad() + tilt_deg / kDegreesPerRadian;
        angles.z() = WrapAngle(angles.z());
        eo.set_angles_seed_rad(angles);
      }
      t->eo[index] = eo;
      BlockImage& image = block->images[index];
      image.name = Numbered("L", line + 1, line_digits) + Numbered("_", j + 1, image_digits);
      image.camera = 0;
    }
  }
}

// The true views of ground points: the candidate images of the flight grid whose frame a point
// projects into, then the images with extra angles outside those candidates.
class ViewFinder {
 public:
  ViewFinder(const SyntheticBlockOptions& o, const Flight& flight, const Projector& projector,
             const std::vector<ExteriorOrientation>& eo)
      : flight_(flight), projector_(projector), eo_(eo) {
    for (const auto& extra : o.extra_angles_deg) extra_images_.push_back(extra.first);
    std::sort(extra_images_.begin(), extra_images_.end());
    extra_images_.erase(std::unique(extra_images_.begin(), extra_images_.end()),
                        extra_images_.end());
  }
  // Finds the views of ground point X (index point_index); returns their number.
  int Look(const Eigen::Vector3d& X, int point_index) {
    views_.clear();
    int l0, l1, k0, k1;
    flight_.Candidates(X.x(), X.y(), &l0, &l1, &k0, &k1);
    for (int line = l0; line <= l1; ++line) {
      for (int k = k0; k <= k1; ++k) TryImage(flight_.Image(line, k), X, point_index);
    }
    for (const int image : extra_images_) {
      int line, k;
      flight_.GridPosition(image, &line, &k);
      if (line < l0 || line > l1 || k < k0 || k > k1) TryImage(image, X, point_index);
    }
    return static_cast<int>(views_.size());
  }
  // The views the last Look found.
  const std::vector<View>& views() const { return views_; }

 private:
  void TryImage(int image, const Eigen::Vector3d& X, int point_index) {
    Eigen::Vector2d pixel;
    if (projector_.Pixel(eo_[image], X, &pixel)) views_.push_back({image, point_index, pixel});
  }

  const Flight& flight_;
  const Projector& projector_;
  const std::vector<ExteriorOrientation>& eo_;
  std::vector<int> extra_images_;  // sorted, distinct
  std::vector<View> views_;
};

// A rectangle on the ground (m): low corner and size.
struct SurveyRectangle {
  double x0, y0, span_x, span_y;
};

// The rectangle the nominal footprints cover at the mean terrain: where tie points are drawn.
SurveyRectangle CoveredArea(const SyntheticBlockOptions& o, const Geometry& g) {
  return {o.origin_m.x() + g.footprint.x0, o.origin_m.y() + g.footprint.y0,
          (o.num_lines - 1) * g.side_m + (g.footprint.x1 - g.footprint.x0),
          (o.images_per_line - 1) * g.forward_m + (g.footprint.y1 - g.footprint.y0)};
}

// The rectangle control and check points are placed on (SyntheticBlockOptions::survey_area).
SurveyRectangle SurveyedArea(const SyntheticBlockOptions& o, const Geometry& g) {
  if (o.survey_area == SyntheticBlockOptions::SurveyArea::kFootprints) return CoveredArea(o, g);
  SurveyRectangle r{o.origin_m.x(), o.origin_m.y(), (o.num_lines - 1) * g.side_m,
                    (o.images_per_line - 1) * g.forward_m};
  if (r.span_x <= 0.0) {
    r.span_x = 0.5 * g.footprint_width_m;
    r.x0 -= 0.25 * g.footprint_width_m;
  }
  if (r.span_y <= 0.0) {
    r.span_y = 0.5 * g.footprint_height_m;
    r.y0 -= 0.25 * g.footprint_height_m;
  }
  return r;
}

// Control points at the explicit layout, else at ControlLayout() (then uniform); check points at
// theirs, else one per cell of a grid as square as the rectangle allows (cells chosen at random
// when there are more cells than points, inset by 5% of a cell); every one must be seen by an
// image.
Status PlaceSurveyedPoints(const SyntheticBlockOptions& o, const Geometry& g,
                           const Terrain& terrain, ViewFinder* finder, Block* block,
                           SyntheticBlockTruth* t, std::vector<View>* views) {
  const SurveyRectangle r = SurveyedArea(o, g);
  PortableRandom random(o.seed, kStreamControl);
  auto add = [&](const std::string& id, PointRole role, double u, double v) {
    const double x = r.x0 + u * r.span_x, y = r.y0 + v * r.span_y;
    BlockPoint point;
    point.id = id;
    point.role = role;
    block->points.push_back(point);
    t->points_m.emplace_back(x, y, terrain.Height(x, y));
  };
  const int num_control = NumControlPoints(o);
  const int control_digits = std::max(3, Digits(num_control));
  for (int c = 0; c < num_control; ++c) {
    const Eigen::Vector2d unit = !o.control_layout.empty() ? o.control_layout[c]
                                 : c < static_cast<int>(ControlLayout().size())
                                     ? ControlLayout()[c]
                                     : random.Uniform01x2();
    add(Numbered("C", c + 1, control_digits), PointRole::kControl, unit.x(), unit.y());
  }
  const int n = o.num_check_points;
  if (!o.check_layout.empty()) {
    const int check_digits = std::max(3, Digits(NumCheckPoints(o)));
    for (int c = 0; c < NumCheckPoints(o); ++c) {
      add(Numbered("K", c + 1, check_digits), PointRole::kCheck, o.check_layout[c].x(),
          o.check_layout[c].y());
    }
  } else if (n > 0) {
    const int gx = std::max(1, static_cast<int>(std::round(std::sqrt(n * r.span_x / r.span_y))));
    const int gy = (n + gx - 1) / gx;
    std::vector<int> cells(static_cast<size_t>(gx) * gy);
    std::iota(cells.begin(), cells.end(), 0);
    cells = Choose(cells, n, &random);
    const int check_digits = std::max(3, Digits(n));
    for (int c = 0; c < n; ++c) {
      const double u = ((cells[c] % gx) + random.Uniform(0.05, 0.95)) / gx;
      const double v = ((cells[c] / gx) + random.Uniform(0.05, 0.95)) / gy;
      add(Numbered("K", c + 1, check_digits), PointRole::kCheck, u, v);
    }
  }
  for (size_t p = 0; p < block->points.size(); ++p) {
    if (finder->Look(t->points_m[p], static_cast<int>(p)) == 0) {
      return Status::Error("synthetic block: " + block->points[p].id +
                           " is seen by no image (check the flight geometry)");
    }
    views->insert(views->end(), finder->views().begin(), finder->views().end());
  }
  return Status::Ok();
}

// Tie points uniform over the covered rectangle, kept when seen in min_tie_views images: exactly
// num_tie_points of them, or as many as the density's candidates give.
Status PlaceTiePoints(const SyntheticBlockOptions& o, const Geometry& g, const Terrain& terrain,
                      ViewFinder* finder, Block* block, SyntheticBlockTruth* t,
                      std::vector<View>* views) {
  const SurveyRectangle covered = CoveredArea(o, g);
  const double left = covered.x0, bottom = covered.y0;
  const double width = covered.span_x, height = covered.span_y;
  t->covered_low_m = {left, bottom};
  t->covered_size_m = {width, height};
  t->covered_area_m2 = width * height;
  const bool by_count = o.num_tie_points > 0;
  const long long candidates = by_count
                                   ? o.num_tie_points * kTieAttemptsPerPoint
                                   : std::llround(o.tie_point_density_per_m2 * t->covered_area_m2);
  const long long wanted = by_count ? o.num_tie_points : candidates;
  const int tie_digits = std::max(6, Digits(wanted));
  PortableRandom random(o.seed, kStreamTiePoints);
  long long placed = 0;
  for (long long attempt = 0; attempt < candidates && (!by_count || placed < wanted); ++attempt) {
    const double x = left + random.Uniform01() * width;
    const double y = bottom + random.Uniform01() * height;
    const Eigen::Vector3d X(x, y, terrain.Height(x, y));
    const int index = static_cast<int>(block->points.size());
    if (finder->Look(X, index) < o.min_tie_views) continue;
    BlockPoint point;
    point.id = Numbered("T", ++placed, tie_digits);
    point.role = PointRole::kTie;
    block->points.push_back(std::move(point));
    t->points_m.push_back(X);
    views->insert(views->end(), finder->views().begin(), finder->views().end());
    if (views->size() > static_cast<size_t>(kMaxIndex))
      return Status::Error("synthetic block: more marks than 32-bit indices hold");
  }
  if (by_count && placed < wanted) {
    return Status::Error("synthetic block: only " + std::to_string(placed) + " of " +
                         std::to_string(wanted) + " tie points are seen by " +
                         std::to_string(o.min_tie_views) +
                         " images or more (lower min_tie_views or raise the overlap)");
  }
  return Status::Ok();
}

// The marks, image by image (a counting sort of the views), with Gaussian noise.
Status MakeMarks(const SyntheticBlockOptions& o, const std::vector<View>& views,
                 const Projector& projector, Block* block) {
  const int num_images = static_cast<int>(block->images.size());
  std::vector<size_t> offset(num_images + 1, 0);
  for (const View& v : views) ++offset[v.image + 1];
  for (int i = 0; i < num_images; ++i) offset[i + 1] += offset[i];
  std::vector<int> order(views.size());
  std::vector<size_t> next(offset.begin(), offset.end() - 1);
  for (size_t v = 0; v < views.size(); ++v) order[next[views[v].image]++] = static_cast<int>(v);
  PortableRandom random(o.seed, kStreamMarkNoise);
  const std::optional<double> accuracy = Stated(o.mark_accuracy_px, o.mark_sigma_px);
  const BlockCamera& camera = block->cameras.front();
  const double units_per_px =
      camera.model == CameraModelType::kFrame ? camera.table.MeanPixelSizeUm() : 1.0;
  block->marks.resize(views.size());
  for (size_t m = 0; m < order.size(); ++m) {
    const View& v = views[order[m]];
    BlockMark& mark = block->marks[m];
    mark.image = v.image;
    mark.point = v.point;
    mark.unit = MarkUnit::kPixel;
    mark.measured =
        v.pixel + o.mark_sigma_px * random.Gaussian2();
    mark.accuracy = accuracy;
    mark.observation_units_per_unit = units_per_px;
    PHOTOPOSE_RETURN_IF_ERROR(projector.Observation(mark.measured, &mark.observation));
  }
  return Status::Ok();
}

// Surveyed coordinates of control and check points, then the GNSS centres (one stream).
void MeasureSurveyedAndGnss(const SyntheticBlockOptions& o, const SyntheticBlockTruth& t,
                            Block* block) {
  PortableRandom random(o.seed, kStreamGnss);
  const std::optional<double> accuracy = Stated(o.control_accuracy_m, o.control_sigma_m);
  for (size_t p = 0; p < block->points.size(); ++p) {
    BlockPoint& point = block->points[p];
    if (point.role == PointRole::kTie) continue;
    point.surveyed_m = t.points_m[p] + o.control_sigma_m * random.Gaussian3();
    if (accuracy) point.accuracy_m = Eigen::Vector3d::Constant(*accuracy);
  }
  if (!o.gnss) return;
  Eigen::Vector3d stated;
  bool stated_all = true;
  for (int k = 0; k < 3; ++k) {
    const std::optional<double> a = Stated(o.gnss_accuracy_m[k], o.gnss_sigma_m[k]);
    stated_all = stated_all && a.has_value();
    stated[k] = a.value_or(0.0);
  }
  for (size_t i = 0; i < block->images.size(); ++i) {
    Eigen::Vector3d noise;
    for (int k = 0; k < 3; ++k) noise[k] = o.gnss_sigma_m[k] * random.Gaussian();
    block->images[i].measured_center_m = t.eo[i].center_in_ground() + noise;
    if (stated_all) block->images[i].center_accuracy_m = stated;
  }
}

// Measured attitudes, when asked.
void MeasureAttitude(const SyntheticBlockOptions& o, const SyntheticBlockTruth& t, Block* block) {
  if (!o.attitude) return;
  PortableRandom random(o.seed, kStreamAttitude);
  const double sigma = DegreesToRadians(o.attitude_sigma_deg);
  const std::optional<double> accuracy = Stated(o.attitude_accuracy_deg, o.attitude_sigma_deg);
  for (size_t i = 0; i < block->images.size(); ++i) {
    Eigen::Vector3d angles = t.eo[i].angles_seed_rad();
    for (int k = 0; k < 3; ++k) angles[k] += sigma * random.Gaussian();
    block->images[i].measured_angles_rad = angles;
    if (accuracy)
      block->images[i].attitude_accuracy_rad =
          Eigen::Vector3d::Constant(DegreesToRadians(*accuracy));
  }
}

// Blunders of tie marks, control points and GNSS centres; the truth records which.
Status AddBlunders(const SyntheticBlockOptions& o, const Projector& projector, Block* block,
                   SyntheticBlockTruth* t) {
  PortableRandom random(o.seed, kStreamBlunders);
  if (o.num_tie_blunders > 0) {
    std::vector<int> tie_marks;
    for (size_t m = 0; m < block->marks.size(); ++m)
      if (block->points[block->marks[m].point].role == PointRole::kTie)
        tie_marks.push_back(static_cast<int>(m));
    if (static_cast<size_t>(o.num_tie_blunders) > tie_marks.size()) {
      return Status::Error("synthetic block: " + std::to_string(o.num_tie_blunders) +
                           " tie-mark blunders asked, the block has " +
                           std::to_string(tie_marks.size()) + " tie marks");
    }
    t->blunder_marks = Choose(std::move(tie_marks), o.num_tie_blunders, &random);
    for (const int m : t->blunder_marks) {
      BlockMark& mark = block->marks[m];
      const double angle = random.Uniform(0.0, 2.0 * kPi);
      mark.measured += o.tie_blunder_px * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      PHOTOPOSE_RETURN_IF_ERROR(projector.Observation(mark.measured, &mark.observation));
      t->mark_is_blunder[m] = 1;
    }
  }
  if (o.num_control_blunders > 0) {
    std::vector<int> control(NumControlPoints(o));
    std::iota(control.begin(), control.end(), 0);  // control points come first
    t->blunder_control_points = Choose(std::move(control), o.num_control_blunders, &random);
    for (const int p : t->blunder_control_points)
      *block->points[p].surveyed_m += o.control_blunder_m * RandomDirection(&random);
  }
  if (o.num_gnss_blunders > 0) {
    std::vector<int> images(block->images.size());
    std::iota(images.begin(), images.end(), 0);
    t->blunder_gnss_images = Choose(std::move(images), o.num_gnss_blunders, &random);
    for (const int i : t->blunder_gnss_images)
      *block->images[i].measured_center_m += o.gnss_blunder_m * RandomDirection(&random);
  }
  return Status::Ok();
}

// The perturbed start: orientations and tie points from the truth plus Gaussian errors, control
// and check points at their surveyed positions.
void PerturbStart(const SyntheticBlockOptions& o, const SyntheticBlockTruth& t, Block* block) {
  PortableRandom random(o.seed, kStreamStart);
  const double angle_sigma = DegreesToRadians(o.start_angle_sigma_deg);
  for (size_t i = 0; i < block->images.size(); ++i) {
    ExteriorOrientation eo = t.eo[i];
    for (int k = 0; k < 3; ++k) {
      eo.parameters[k] += o.start_position_sigma_m * random.Gaussian();
      eo.parameters[3 + k] += angle_sigma * random.Gaussian();
    }
    block->images[i].eo = eo;
  }
  for (size_t p = 0; p < block->points.size(); ++p) {
    BlockPoint& point = block->points[p];
    if (point.role != PointRole::kTie) {
      point.position_m = point.surveyed_m;
    } else if (o.tie_point_start) {
      point.position_m = t.points_m[p] + o.start_point_sigma_m * random.Gaussian3();
    }
  }
}

}  // namespace

SyntheticBlockOptions BenchmarkBlockOptions() {
  SyntheticBlockOptions options;
  options.num_lines = 25;
  options.images_per_line = 40;
  options.forward_spacing_m = 13.0;
  options.side_spacing_m = 30.0;
  options.num_tie_points = 120000;
  options.num_control_points = 12;
  options.num_check_points = 10;
  return options;
}

SyntheticBlockOptions SolverBenchmarkBlockOptions(int lines, int images_per_line, int tie_points) {
  SyntheticBlockOptions o;
  o.seed = 2026;
  o.num_lines = lines;
  o.images_per_line = images_per_line;
  o.num_tie_points = tie_points;
  o.forward_spacing_m = 20.0;
  o.side_spacing_m = 30.0;
  o.control_layout = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}};
  o.num_check_points = 2;
  o.control_sigma_m = 0.005;
  o.mark_sigma_px = 0.5;
  o.gnss_sigma_m = Eigen::Vector3d::Constant(0.03);
  return o;
}

SyntheticBlockOptions EarthCurvatureBlockOptions() {
  SyntheticBlockOptions o;
  o.seed = 2026;
  o.num_lines = 3;
  o.images_per_line = 5;
  o.forward_spacing_m = 400.0;
  o.side_spacing_m = 800.0;
  o.flying_height_m = 800.0;
  o.focal_length_mm = 10.0;
  o.terrain_relief_m = 30.0;
  o.num_tie_points = 600;
  o.mark_sigma_px = 0.1;
  o.control_sigma_m = 0.01;
  o.gnss_sigma_m = Eigen::Vector3d(0.03, 0.03, 0.05);
  o.earth_curvature = true;
  return o;
}

namespace {

// The flight and the camera.
Status CheckFlightAndCamera(const SyntheticBlockOptions& o) {
  if (o.num_lines < 1) return Invalid("num_lines must be >= 1");
  if (o.images_per_line < 1) return Invalid("images_per_line must be >= 1");
  const long long num_images = static_cast<long long>(o.num_lines) * o.images_per_line;
  if (num_images > kMaxImages)
    return Invalid("num_lines x images_per_line must be <= " + std::to_string(kMaxImages));
  if (!NonNegative(o.forward_spacing_m) || !NonNegative(o.side_spacing_m))
    return Invalid("the spacings must be finite and >= 0 (m)");
  if (o.forward_spacing_m == 0.0 && !(o.forward_overlap >= 0.0 && o.forward_overlap < 1.0))
    return Invalid("forward_overlap must be in [0, 1)");
  if (o.side_spacing_m == 0.0 && !(o.side_overlap >= 0.0 && o.side_overlap < 1.0))
    return Invalid("side_overlap must be in [0, 1)");
  if (!Positive(o.flying_height_m)) return Invalid("flying_height_m must be > 0");
  if (!o.origin_m.allFinite()) return Invalid("origin_m must be finite");
  if (!NonNegative(o.position_jitter_m)) return Invalid("position_jitter_m must be >= 0");
  if (!(NonNegative(o.attitude_jitter_deg) && o.attitude_jitter_deg < 30.0))
    return Invalid("attitude_jitter_deg must be in [0, 30)");
  if (!o.nominal_angles_deg.allFinite()) return Invalid("nominal_angles_deg must be finite");
  for (const auto& [image, extra_deg] : o.extra_angles_deg) {
    if (image < 0 || image >= num_images || !extra_deg.allFinite())
      return Invalid("extra_angles_deg: image indices in [0, number of images), finite angles");
  }
  if (!std::isfinite(o.ground_height_m)) return Invalid("ground_height_m must be finite");
  if (!(NonNegative(o.terrain_relief_m) &&
        0.5 * o.terrain_relief_m + o.position_jitter_m < 0.5 * o.flying_height_m))
    return Invalid("terrain_relief_m must be >= 0 and keep the terrain well below the cameras");
  if (!Positive(o.focal_length_mm)) return Invalid("focal_length_mm must be > 0");
  if (!Positive(o.pixel_size_um)) return Invalid("pixel_size_um must be > 0");
  if (o.image_width_px < 1 || o.image_height_px < 1) return Invalid("the image size must be >= 1 px");
  if (!o.camera_params.empty()) {
    if (static_cast<int>(o.camera_params.size()) != CameraModelNumParams(o.camera_model)) {
      return Invalid("camera_params must have the " +
                     std::to_string(CameraModelNumParams(o.camera_model)) + " parameters of " +
                     EnumName(o.camera_model));
    }
    for (const double p : o.camera_params)
      if (!std::isfinite(p)) return Invalid("camera_params must be finite");
    if (!(o.camera_params[0] > 0.0) ||
        !(CameraModelFocal(o.camera_model, o.camera_params.data()) > 0.0))
      return Invalid("the focal length in camera_params must be > 0");
  }
  return Status::Ok();
}

// Points, errors and blunders.
Status CheckPointsAndErrors(const SyntheticBlockOptions& o) {
  const long long num_images = static_cast<long long>(o.num_lines) * o.images_per_line;
  if (o.num_tie_points < 0 || o.num_tie_points > kMaxIndex)
    return Invalid("num_tie_points must be in [0, " + std::to_string(kMaxIndex) + "]");
  if (!NonNegative(o.tie_point_density_per_m2))
    return Invalid("tie_point_density_per_m2 must be >= 0");
  if (o.min_tie_views < 1) return Invalid("min_tie_views must be >= 1");
  if (o.num_control_points < 0 || o.num_check_points < 0)
    return Invalid("the control and check point counts must be >= 0");
  for (const auto* layout : {&o.control_layout, &o.check_layout}) {
    for (const Eigen::Vector2d& at : *layout) {
      if (!(at.minCoeff() >= 0.0 && at.maxCoeff() <= 1.0))
        return Invalid("control_layout and check_layout fractions must be in [0, 1]");
    }
  }
  if (!NonNegative(o.control_sigma_m) || !NonNegative(o.control_accuracy_m))
    return Invalid("control_sigma_m and control_accuracy_m must be >= 0");
  if (!NonNegative(o.mark_sigma_px) || !NonNegative(o.mark_accuracy_px))
    return Invalid("mark_sigma_px and mark_accuracy_px must be >= 0");
  if (o.earth_curvature && o.camera_model != CameraModelType::kFrame)
    return Invalid("earth_curvature needs the frame camera (its table's ApplyECC)");
  for (int k = 0; k < 3; ++k) {
    if (!NonNegative(o.gnss_sigma_m[k]) || !NonNegative(o.gnss_accuracy_m[k]))
      return Invalid("gnss_sigma_m and gnss_accuracy_m must be >= 0");
  }
  if (!NonNegative(o.attitude_sigma_deg) || !NonNegative(o.attitude_accuracy_deg))
    return Invalid("attitude_sigma_deg and attitude_accuracy_deg must be >= 0");
  if (o.num_tie_blunders < 0 || !NonNegative(o.tie_blunder_px))
    return Invalid("num_tie_blunders and tie_blunder_px must be >= 0");
  if (o.num_control_blunders < 0 || o.num_control_blunders > NumControlPoints(o) ||
      !NonNegative(o.control_blunder_m))
    return Invalid("num_control_blunders must be in [0, num_control_points], control_blunder_m >= 0");
  if (o.num_gnss_blunders < 0 || o.num_gnss_blunders > num_images || !NonNegative(o.gnss_blunder_m))
    return Invalid("num_gnss_blunders must be in [0, number of images], gnss_blunder_m >= 0");
  if (o.num_gnss_blunders > 0 && !o.gnss) return Invalid("num_gnss_blunders needs gnss");
  if (!NonNegative(o.start_position_sigma_m) || !NonNegative(o.start_angle_sigma_deg) ||
      !NonNegative(o.start_point_sigma_m))
    return Invalid("the start errors must be >= 0");

  return Status::Ok();
}

// Sizes, in floating point (no overflow): points and marks must fit 32-bit indices.
Status CheckSizes(const SyntheticBlockOptions& o, const Geometry& g) {
  const SurveyRectangle covered = CoveredArea(o, g);
  const double candidates = o.num_tie_points > 0
                                ? static_cast<double>(o.num_tie_points)
                                : o.tie_point_density_per_m2 * covered.span_x * covered.span_y;
  const double points = candidates + static_cast<double>(NumControlPoints(o)) +
                        static_cast<double>(NumCheckPoints(o));
  const double views = std::min(static_cast<double>(o.num_lines),
                                (g.footprint.x1 - g.footprint.x0) / g.side_m + 1.0) *
                       std::min(static_cast<double>(o.images_per_line),
                                (g.footprint.y1 - g.footprint.y0) / g.forward_m + 1.0);
  if (!(points <= static_cast<double>(kMaxIndex)) ||
      !(points * views <= static_cast<double>(kMaxIndex))) {
    return Invalid("the block would have about " + std::to_string(points) + " points and " +
                   std::to_string(points * views) + " marks, more than 32-bit indices hold");
  }
  return Status::Ok();
}

}  // namespace

Status SyntheticBlockOptions::IsValid() const {
  PHOTOPOSE_RETURN_IF_ERROR(CheckFlightAndCamera(*this));
  const Geometry g = FlightGeometry(*this);
  if (!Positive(g.forward_m) || !Positive(g.side_m))
    return Invalid("the spacings derived from the overlaps must be > 0");
  if (!g.rays_reach_ground) {
    return Invalid(
        "nominal_angles_deg (with the attitude jitter) tilts an image corner's ray to within 6 deg "
        "of the horizon");
  }
  PHOTOPOSE_RETURN_IF_ERROR(CheckPointsAndErrors(*this));
  return CheckSizes(*this, g);
}

Status MakeSyntheticBlock(const SyntheticBlockOptions& o, Block* block,
                          SyntheticBlockTruth* truth) {
  PHOTOPOSE_RETURN_IF_ERROR(o.IsValid());
  Block result;
  SyntheticBlockTruth t;
  const Geometry g = FlightGeometry(o);
  t.forward_spacing_m = g.forward_m;
  t.side_spacing_m = g.side_m;
  t.footprint_width_m = g.footprint_width_m;
  t.footprint_height_m = g.footprint_height_m;
  const Flight flight(o, g);
  const Terrain terrain(o);
  result.cameras.push_back(MakeCamera(o));
  const Projector projector(result.cameras.front());

  PlaceImages(o, flight, &result, &t);
  ViewFinder finder(o, flight, projector, t.eo);
  std::vector<View> views;
  PHOTOPOSE_RETURN_IF_ERROR(PlaceSurveyedPoints(o, g, terrain, &finder, &result, &t, &views));
  PHOTOPOSE_RETURN_IF_ERROR(PlaceTiePoints(o, g, terrain, &finder, &result, &t, &views));
  PHOTOPOSE_RETURN_IF_ERROR(MakeMarks(o, views, projector, &result));
  std::vector<View>().swap(views);
  t.mark_is_blunder.assign(result.marks.size(), 0);
  MeasureSurveyedAndGnss(o, t, &result);
  MeasureAttitude(o, t, &result);
  PHOTOPOSE_RETURN_IF_ERROR(AddBlunders(o, projector, &result, &t));
  PerturbStart(o, t, &result);

  result.pixel_origin = PixelOrigin::kCorner;
  result.marks_source = "synthetic block";
  result.BuildIndex();
  *block = std::move(result);
  if (truth != nullptr) *truth = std::move(t);
  return Status::Ok();
}

Status FormatSyntheticBlockTruth(const Block& block, const SyntheticBlockTruth& truth,
                                 const SyntheticBlockOptions& options, RotationConvention rotation,
                                 SyntheticTruthText* text) {
  if (truth.eo.size() != block.images.size() || truth.points_m.size() != block.points.size() ||
      truth.mark_is_blunder.size() != block.marks.size())
    return Status::Error("the synthetic truth does not belong to this block");
  std::vector<FrameRecord> frames;
  std::vector<FrameCamera> cameras;
  for (const BlockCamera& camera : block.cameras) cameras.push_back(camera.table);
  for (size_t i = 0; i < block.images.size(); ++i) {
    FrameRecord row;
    row.raster = block.images[i].name;
    row.camera_id = block.cameras[block.images[i].camera].camera_id;
    row.eo = truth.eo[i];
    frames.push_back(std::move(row));
  }
  std::vector<GroundPoint> points;
  for (size_t p = 0; p < block.points.size(); ++p) {
    GroundPoint row;
    row.point_id = block.points[p].id;
    row.role = block.points[p].role;
    row.position = truth.points_m[p];
    points.push_back(std::move(row));
  }
  text->blunders = CsvLine({"Kind", "Raster", "PointID", "Magnitude", "Unit"});
  for (const int m : truth.blunder_marks) {
    const BlockMark& mark = block.marks[m];
    text->blunders += CsvLine({"mark", block.images[mark.image].name, block.points[mark.point].id,
                               FormatNumber(options.tie_blunder_px), "px"});
  }
  for (const int p : truth.blunder_control_points) {
    text->blunders += CsvLine(
        {"control_point", "", block.points[p].id, FormatNumber(options.control_blunder_m), "m"});
  }
  for (const int i : truth.blunder_gnss_images) {
    text->blunders += CsvLine(
        {"camera_position", block.images[i].name, "", FormatNumber(options.gnss_blunder_m), "m"});
  }
  FramesTableOptions frames_options;
  frames_options.convention = rotation;
  frames_options.cameras = &cameras;
  PHOTOPOSE_RETURN_IF_ERROR(FormatFramesTable(frames_options, frames, "truth frames", &text->frames));
  return FormatGroundPoints(points, "truth points", &text->points);
}

Status WriteSyntheticBlockTruth(const Block& block, const SyntheticBlockTruth& truth,
                                const SyntheticBlockOptions& options,
                                const SyntheticTruthFiles& files) {
  SyntheticTruthText text;
  PHOTOPOSE_RETURN_IF_ERROR(
      FormatSyntheticBlockTruth(block, truth, options, RotationConvention::kSeed, &text));
  if (!files.frames.empty()) PHOTOPOSE_RETURN_IF_ERROR(WriteFileAtomically(files.frames, text.frames));
  if (!files.points.empty()) PHOTOPOSE_RETURN_IF_ERROR(WriteFileAtomically(files.points, text.points));
  if (!files.blunders.empty())
    PHOTOPOSE_RETURN_IF_ERROR(WriteFileAtomically(files.blunders, text.blunders));
  return Status::Ok();
}

}  // namespace photopose
