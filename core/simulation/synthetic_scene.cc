#include "core/io/block_tables.h"
#include "core/simulation/synthetic_scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/collinearity.h"

namespace photopose {
namespace {

FrameCamera AerialCamera() {
  // An UltraCamXp-like panchromatic frame (the seed's camera-table example: 100.5 mm, 6 um).
  FrameCamera camera;
  camera.object_id = 1;
  camera.camera_id = "UltraCamXp_Pan";
  camera.focal_length_um = 100500.0;
  camera.principal_x_um = -120.0;
  camera.principal_y_um = 0.0;
  camera.pixel_size_um = 6.0;
  camera.n_columns = 17310;
  camera.n_rows = 11310;
  camera.n_bands = 1;
  camera.average_z_m = 50.0;
  return camera;
}

FrameCamera UavCamera() {
  // A 1-inch 20 MP UAV camera: 8.8 mm lens, 2.41 um pixels, 5472 x 3648, barrel distortion.
  FrameCamera camera;
  camera.object_id = 1;
  camera.camera_id = "UAV_8.8mm";
  camera.focal_length_um = 8800.0;
  camera.principal_x_um = 12.0;
  camera.principal_y_um = -7.0;
  camera.pixel_size_um = 2.41;
  camera.n_columns = 5472;
  camera.n_rows = 3648;
  camera.n_bands = 3;
  camera.radial_k = {0.0, -1.2e-4, 2.0e-7, 0.0};
  camera.tangential_p = {3.0e-6, -2.0e-6};
  camera.average_z_m = 0.0;
  return camera;
}

std::string Name(const char* prefix, int index) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%s%04d", prefix, index);
  return buffer;
}

bool InsideImage(const FrameCamera& camera, const Eigen::Vector2d& column_row) {
  return column_row.x() >= 0.0 && column_row.y() >= 0.0 && column_row.x() <= camera.n_columns &&
         column_row.y() <= camera.n_rows;
}

}  // namespace

Status SyntheticSceneOptions::IsValid() const {
  if (!(noise_px >= 0.0) || !std::isfinite(noise_px)) return Status::Error("noise_px must be >= 0");
  if (!(outlier_fraction >= 0.0 && outlier_fraction < 1.0))
    return Status::Error("outlier_fraction must be in [0, 1)");
  if (!(outlier_min_px >= 0.0 && outlier_max_px >= outlier_min_px))
    return Status::Error("outlier range must satisfy 0 <= min <= max");
  if (num_control_points < 0 || num_check_points < 0)
    return Status::Error("point counts must be >= 0");
  // In 64 bits: two int counts can overflow an int sum. The scene holds every point and mark in
  // memory, so a million points per footprint is the most it generates.
  constexpr int64_t kMaxPointsPerImage = 1000000;
  const int64_t points_per_image = int64_t{num_control_points} + int64_t{num_check_points};
  if (points_per_image < 1) return Status::Error("the scene needs points");
  if (points_per_image > kMaxPointsPerImage)
    return Status::Error("control plus check points must be at most " +
                         std::to_string(kMaxPointsPerImage) + " per image");
  if (!(terrain_relief_m >= 0.0)) return Status::Error("terrain_relief_m must be >= 0");
  if (!(initial_position_error_m >= 0.0) || !(initial_angle_error_deg >= 0.0))
    return Status::Error("initial errors must be >= 0");
  if (!(mark_accuracy_px >= 0.0)) return Status::Error("mark_accuracy_px must be >= 0");
  return Status::Ok();
}

namespace {

// The scene's random draws. The components of a vector are drawn last to first, written out: the
// arguments of Eigen::Vector3d(Uniform(), Uniform(), Uniform()) are evaluated in an unspecified
// order (GCC: last first; Clang: first first), which gave the two compilers different scenes for
// one seed; last-to-first keeps the scenes GCC always made.
struct SceneDraws {
  explicit SceneDraws(uint64_t seed) : rng(seed) {}
  double Uniform(double lo, double hi) { return lo + (hi - lo) * unit(rng); }
  double Gaussian() { return gaussian(rng); }
  // (Uniform(lo[0], hi[0]), ...) drawn last to first.
  Eigen::Vector3d Uniform3(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    const double z = Uniform(lo.z(), hi.z());
    const double y = Uniform(lo.y(), hi.y());
    return Eigen::Vector3d(Uniform(lo.x(), hi.x()), y, z);
  }
  Eigen::Vector2d Uniform2(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
    const double y = Uniform(lo.y(), hi.y());
    return Eigen::Vector2d(Uniform(lo.x(), hi.x()), y);
  }
  Eigen::Vector2d Gaussian2() {
    const double y = Gaussian();
    return Eigen::Vector2d(Gaussian(), y);
  }

  std::mt19937_64 rng;
  std::uniform_real_distribution<double> unit{0.0, 1.0};
  std::normal_distribution<double> gaussian{0.0, 1.0};
};

// The scenario's camera (into scene->cameras) and true poses; *ground_z the terrain's mean height.
std::vector<ExteriorOrientation> TruePoses(const SyntheticSceneOptions& options, SceneDraws* draw,
                                           SyntheticScene* scene, double* ground_z) {
  std::vector<ExteriorOrientation> poses;
  if (options.scenario == Scenario::kUavBlock) {
    scene->cameras.push_back(UavCamera());
    *ground_z = 20.0;
    for (int strip = 0; strip < 3; ++strip) {
      for (int i = 0; i < 4; ++i) {
        const int along = strip % 2 == 0 ? i : 3 - i;  // serpentine flight
        ExteriorOrientation eo;
        eo.set_center_in_ground(
            Eigen::Vector3d(300000.0 + 45.0 * along, 4100000.0 + 40.0 * strip, *ground_z + 100.0) +
            draw->Uniform3(Eigen::Vector3d(-2, -2, -1.5), Eigen::Vector3d(2, 2, 1.5)));
        const Eigen::Vector3d jitter_deg =
            draw->Uniform3(Eigen::Vector3d(-3, -3, -5), Eigen::Vector3d(3, 3, 5));
        eo.set_angles_seed_rad(Eigen::Vector3d(
            DegreesToRadians(jitter_deg.x()), DegreesToRadians(jitter_deg.y()),
            DegreesToRadians((strip % 2 ? 180.0 : 0.0) + jitter_deg.z())));
        poses.push_back(eo);
      }
    }
    return poses;
  }
  // kNadir, kOblique: one aerial image.
  scene->cameras.push_back(AerialCamera());
  *ground_z = 50.0;
  ExteriorOrientation eo;
  const bool oblique = options.scenario == Scenario::kOblique;
  const Eigen::Vector2d xy =
      draw->Uniform2(Eigen::Vector2d(4000, 4000), Eigen::Vector2d(6000, 6000));
  eo.set_center_in_ground(Eigen::Vector3d(xy.x(), xy.y(), *ground_z + (oblique ? 600.0 : 800.0)));
  const double tilt = oblique ? DegreesToRadians(45.0) : 0.0;
  const Eigen::Vector3d jitter_deg =
      draw->Uniform3(Eigen::Vector3d(-2, -2, -180), Eigen::Vector3d(2, 2, 180));
  eo.set_angles_seed_rad(Eigen::Vector3d(tilt + DegreesToRadians(jitter_deg.x()),
                                         DegreesToRadians(jitter_deg.y()),
                                         DegreesToRadians(jitter_deg.z())));
  poses.push_back(eo);
  return poses;
}

// The true and the approximate frames (the truth moved by the asked initial errors).
void Frames(const SyntheticSceneOptions& options, const std::vector<ExteriorOrientation>& poses,
            SceneDraws* draw, SyntheticScene* scene) {
  const FrameCamera& camera = scene->cameras.front();
  for (size_t i = 0; i < poses.size(); ++i) {
    FrameRecord truth;
    truth.raster = Name("img_", static_cast<int>(i + 1));
    truth.camera_id = camera.camera_id;
    truth.eo = poses[i];
    FrameRecord approximate = truth;
    Eigen::Vector3d center = poses[i].center_in_ground();
    Eigen::Vector3d angles = poses[i].angles_seed_rad();
    for (int k = 0; k < 3; ++k) {
      center[k] += draw->Uniform(-1, 1) * options.initial_position_error_m;
      angles[k] += DegreesToRadians(draw->Uniform(-1, 1) * options.initial_angle_error_deg);
    }
    approximate.eo.set_center_in_ground(center);
    approximate.eo.set_angles_seed_rad(angles);
    scene->true_frames.push_back(truth);
    scene->approximate_frames.push_back(approximate);
  }
}

// Ground points: rays of random pixels of each image meet the terrain at a random height, so
// every point is seen by the image that made it (and by its neighbours where they overlap).
Status GroundPoints(const SyntheticSceneOptions& options,
                    const std::vector<ExteriorOrientation>& poses, double ground_z,
                    SceneDraws* draw, SyntheticScene* scene) {
  const FrameCamera& camera = scene->cameras.front();
  int point_index = 0;
  for (const ExteriorOrientation& eo : poses) {
    const int total = options.num_control_points + options.num_check_points;
    for (int k = 0; k < total; ++k) {
      const double margin = 0.03;
      const Eigen::Vector2d pixel =
          draw->Uniform2(Eigen::Vector2d::Constant(margin), Eigen::Vector2d::Constant(1 - margin))
              .cwiseProduct(Eigen::Vector2d(camera.n_columns, camera.n_rows));
      const double height = ground_z + draw->Uniform(-0.5, 0.5) * options.terrain_relief_m;
      GroundPoint point;
      const Status status = IntersectRayWithPlane(camera, eo, pixel, PixelOrigin::kCorner, height,
                                                  &point.position);
      if (!status.ok()) return Status::Error("synthetic scene: " + status.message());
      point.point_id = Name("P", ++point_index);
      point.role = k < options.num_control_points ? PointRole::kControl : PointRole::kCheck;
      scene->points.push_back(point);
    }
  }
  return Status::Ok();
}

// Marks: every point inside every image, with noise; then exactly round(fraction * marks) gross
// errors, on marks drawn without replacement.
void Marks(const SyntheticSceneOptions& options, const std::vector<ExteriorOrientation>& poses,
           SceneDraws* draw, SyntheticScene* scene) {
  const FrameCamera& camera = scene->cameras.front();
  const double accuracy_px = options.mark_accuracy_px > 0.0 ? options.mark_accuracy_px
                             : options.noise_px > 0.0        ? options.noise_px
                                                             : 1.0;
  for (size_t i = 0; i < poses.size(); ++i) {
    for (const GroundPoint& point : scene->points) {
      Eigen::Vector2d pixel;
      if (!ProjectGroundPoint(camera, poses[i], point.position, PixelOrigin::kCorner, &pixel).ok())
        continue;
      if (!InsideImage(camera, pixel)) continue;
      ImageMark mark;
      mark.raster = scene->true_frames[i].raster;
      mark.point_id = point.point_id;
      mark.camera_id = camera.camera_id;
      mark.accuracy_px = accuracy_px;
      mark.column_row = pixel + options.noise_px * draw->Gaussian2();
      scene->marks.push_back(mark);
      scene->mark_is_outlier.push_back(false);
    }
  }
  const size_t num_outliers =
      static_cast<size_t>(std::lround(options.outlier_fraction * scene->marks.size()));
  std::vector<size_t> order(scene->marks.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), draw->rng);
  for (size_t k = 0; k < num_outliers; ++k) {
    ImageMark& mark = scene->marks[order[k]];
    const double magnitude = draw->Uniform(options.outlier_min_px, options.outlier_max_px);
    const double direction = draw->Uniform(-kPi, kPi);
    *mark.column_row += magnitude * Eigen::Vector2d(std::cos(direction), std::sin(direction));
    scene->mark_is_outlier[order[k]] = true;
  }
}

}  // namespace

Status MakeSyntheticScene(const SyntheticSceneOptions& options, SyntheticScene* scene) {
  PHOTOPOSE_RETURN_IF_ERROR(options.IsValid());
  *scene = SyntheticScene();
  SceneDraws draw(options.seed);
  double ground_z = 0.0;
  const std::vector<ExteriorOrientation> poses = TruePoses(options, &draw, scene, &ground_z);
  Frames(options, poses, &draw, scene);
  PHOTOPOSE_RETURN_IF_ERROR(GroundPoints(options, poses, ground_z, &draw, scene));
  Marks(options, poses, &draw, scene);
  return Status::Ok();
}

BlockTables SceneBlockTables(const SyntheticScene& scene) {
  BlockTables tables;
  tables.cameras = scene.cameras;
  tables.points = scene.points;
  tables.marks = scene.marks;
  tables.frames = scene.approximate_frames;
  tables.cameras_file = tables.points_file = tables.marks_file = tables.frames_file =
      "synthetic scene";
  return tables;
}

}  // namespace photopose
