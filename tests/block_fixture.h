#pragma once
// A seeded synthetic photogrammetric block built in memory for the block-solver tests and the
// benchmark: strips of frame images over flat terrain with relief, tie points on a jittered grid
// over the union of the footprints, control and check points, GNSS centres, noisy pixel marks, and
// perturbed approximate values. An interim fixture until core/simulation/synthetic_block.h (the shared block
// generator being written) lands; the same options and seed always give the same block.

#include <Eigen/Core>
#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/collinearity.h"
#include "core/rotation.h"

namespace photopose::testing {

struct FixtureBlockOptions {
  int strips = 3;            // flight lines (along Y)
  int images_per_strip = 4;  // images per line (along X)
  double forward_m = 20.0;   // base between images of a line (m)
  double side_m = 30.0;      // distance between lines (m)
  double height_m = 100.0;   // flying height above Z = 0 (m)
  // Camera: a frame camera, 24 mm lens, 6000 x 4000 pixels of 4 um, a little radial distortion.
  double focal_um = 24000.0;
  double pixel_um = 4.0;
  int columns = 6000, rows = 4000;
  double k1 = -2e-5;  // mm^-2
  // Attitude: every image at base_angles_deg (seed omega, phi, kappa) plus a uniform jitter of
  // +- attitude_jitter_deg per angle; `tilted` adds extra angles (deg) to chosen images.
  Eigen::Vector3d base_angles_deg = Eigen::Vector3d::Zero();
  double attitude_jitter_deg = 2.0;
  std::vector<std::pair<int, Eigen::Vector3d>> tilted;
  int tie_grid = 12;       // tie points per side of the grid over the footprints
  double relief_m = 10.0;  // tie-point heights uniform in +- relief / 2 (m)
  // Control and check points at these fractions of the camera-centre rectangle (0..1 in X and Y),
  // or of the union of the footprints (surveyed_in_footprints: for oblique blocks, whose images
  // look away from their centres), heights uniform in +- 1 m.
  std::vector<Eigen::Vector2d> control_at = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  std::vector<Eigen::Vector2d> check_at = {{0.5, 0.5}, {0.25, 0.75}};
  bool surveyed_in_footprints = false;
  double noise_px = 0.5;          // image noise, one sigma (px)
  double mark_accuracy_px = 0.5;  // the marks' stated accuracy (px)
  bool gnss = true;
  double gnss_noise_m = 0.03;           // GNSS error, one sigma (m)
  double gnss_accuracy_m = 0.03;        // its stated accuracy (m)
  double control_noise_m = 0.005;       // survey error of control and check points, one sigma (m)
  double control_accuracy_m = 0.005;    // its stated accuracy (m)
  double start_position_error_m = 2.0;  // approximate values: uniform +- per axis (m)
  double start_angle_error_deg = 1.0;   // uniform +- per angle (deg)
  double start_point_error_m = 1.0;     // tie points: uniform +- per axis (m)
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();  // added to every ground coordinate
  unsigned seed = 1;
};

struct FixtureBlock {
  Block block;
  std::vector<ExteriorOrientation> true_eo;  // per image
  std::vector<Eigen::Vector3d> true_points;  // per point
  double size_m = 0.0;  // diagonal of the camera-centre rectangle plus the flying height (m)
};

inline FixtureBlock MakeFixtureBlock(const FixtureBlockOptions& o) {
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  auto gauss3 = [&] { return Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)); };
  auto uniform3 = [&] { return Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)); };
  FixtureBlock out;
  Block& block = out.block;

  BlockCamera camera;
  camera.camera_id = camera.table.camera_id = "fixture";
  camera.table.focal_length_um = o.focal_um;
  camera.table.pixel_size_um = o.pixel_um;
  camera.table.n_columns = o.columns;
  camera.table.n_rows = o.rows;
  camera.table.radial_k = {0.0, o.k1, 0.0, 0.0};
  const auto params = FrameModelParams(camera.table);
  camera.params.assign(params.begin(), params.end());
  block.cameras.push_back(camera);
  const BlockCamera& cam = block.cameras[0];

  // Images, and the union of their footprints on Z = 0.
  Eigen::Vector2d low = Eigen::Vector2d::Constant(1e300), high = -low;
  for (int s = 0; s < o.strips; ++s) {
    for (int k = 0; k < o.images_per_strip; ++k) {
      const int index = static_cast<int>(block.images.size());
      Eigen::Vector3d angles_deg = o.base_angles_deg + o.attitude_jitter_deg * uniform3();
      for (const auto& [image, extra] : o.tilted)
        if (image == index) angles_deg += extra;
      ExteriorOrientation eo;
      eo.set_center_in_ground(Eigen::Vector3d(k * o.forward_m, s * o.side_m, o.height_m) +
                              o.offset_m);
      eo.set_angles_seed_rad(angles_deg / kDegreesPerRadian);
      out.true_eo.push_back(eo);
      for (const Eigen::Vector2d corner :
           {Eigen::Vector2d(0, 0), Eigen::Vector2d(o.columns, 0), Eigen::Vector2d(0, o.rows),
            Eigen::Vector2d(o.columns, o.rows)}) {
        Eigen::Vector3d ground;
        if (!IntersectRayWithPlane(cam.table, eo, corner, PixelOrigin::kCorner, o.offset_m.z(),
                                   &ground)
                 .ok())
          continue;
        low = low.cwiseMin(ground.head<2>());
        high = high.cwiseMax(ground.head<2>());
      }
      BlockImage image;
      image.name = "img_" + std::to_string(s) + "_" + std::to_string(k);
      image.camera = 0;
      ExteriorOrientation start = eo;
      start.parameters.head<3>() += o.start_position_error_m * uniform3();
      start.parameters.tail<3>() += o.start_angle_error_deg / kDegreesPerRadian * uniform3();
      image.eo = start;
      if (o.gnss) {
        image.measured_center_m = eo.center_in_ground() + o.gnss_noise_m * gauss3();
        image.center_accuracy_m = Eigen::Vector3d::Constant(o.gnss_accuracy_m);
      }
      block.images.push_back(image);
    }
  }
  const Eigen::Vector2d centres_low = o.offset_m.head<2>();
  const Eigen::Vector2d centres_span((o.images_per_strip - 1) * o.forward_m,
                                     (o.strips - 1) * o.side_m);
  out.size_m = std::hypot(centres_span.norm(), o.height_m);

  auto add_point = [&](const Eigen::Vector3d& X, PointRole role, const std::string& id) {
    BlockPoint point;
    point.id = id;
    point.role = role;
    if (role == PointRole::kTie) {
      point.position_m = X + o.start_point_error_m * uniform3();
    } else {
      point.surveyed_m = X + o.control_noise_m * gauss3();
      point.accuracy_m = Eigen::Vector3d::Constant(o.control_accuracy_m);
    }
    block.points.push_back(point);
    out.true_points.push_back(X);
  };
  for (int i = 0; i < o.tie_grid; ++i) {
    for (int j = 0; j < o.tie_grid; ++j) {
      const Eigen::Vector2d t((i + 0.5 + 0.3 * uniform(rng)) / o.tie_grid,
                              (j + 0.5 + 0.3 * uniform(rng)) / o.tie_grid);
      const Eigen::Vector2d xy = low + t.cwiseProduct(high - low);
      add_point({xy.x(), xy.y(), o.offset_m.z() + 0.5 * o.relief_m * uniform(rng)}, PointRole::kTie,
                "T" + std::to_string(i) + "_" + std::to_string(j));
    }
  }
  const Eigen::Vector2d surveyed_low = o.surveyed_in_footprints ? low : centres_low;
  const Eigen::Vector2d surveyed_span =
      o.surveyed_in_footprints ? Eigen::Vector2d(high - low) : centres_span;
  auto add_surveyed = [&](const std::vector<Eigen::Vector2d>& at, PointRole role,
                          const char* prefix) {
    for (size_t k = 0; k < at.size(); ++k) {
      const Eigen::Vector2d xy = surveyed_low + at[k].cwiseProduct(surveyed_span);
      add_point({xy.x(), xy.y(), o.offset_m.z() + uniform(rng)}, role, prefix + std::to_string(k));
    }
  };
  add_surveyed(o.control_at, PointRole::kControl, "C");
  add_surveyed(o.check_at, PointRole::kCheck, "K");

  // Marks: every point inside an image's frame, with Gaussian pixel noise.
  for (size_t i = 0; i < block.images.size(); ++i) {
    for (size_t p = 0; p < block.points.size(); ++p) {
      double ab[2];
      Eigen::Vector2d film, pixel;
      if (!ProjectToNormalized(out.true_eo[i].data(), out.true_points[p].data(), ab) ||
          !ObservationFromNormalized(cam.model, cam.params.data(), cam.data(), {ab[0], ab[1]},
                                     &film)
               .ok() ||
          !PixelFromFilm(cam.table, film, PixelOrigin::kCorner, &pixel).ok() || pixel.x() < 0 ||
          pixel.y() < 0 || pixel.x() > o.columns || pixel.y() > o.rows)
        continue;
      BlockMark mark;
      mark.image = static_cast<int>(i);
      mark.point = static_cast<int>(p);
      mark.unit = MarkUnit::kPixel;
      mark.measured = pixel + o.noise_px * Eigen::Vector2d(gauss(rng), gauss(rng));
      mark.accuracy = o.mark_accuracy_px;
      if (!FilmFromPixel(cam.table, mark.measured, PixelOrigin::kCorner, &mark.observation).ok())
        continue;
      mark.observation_units_per_unit = o.pixel_um;
      block.marks.push_back(mark);
    }
  }
  block.BuildIndex();
  return out;
}

// The block of `o` without mark noise or survey error, its true orientations in place of the
// approximate ones: what an adjustment returns on perfect data.
inline FixtureBlock MakeExactFixtureBlock(FixtureBlockOptions o = FixtureBlockOptions()) {
  o.noise_px = 0.0;
  o.control_noise_m = 0.0;
  FixtureBlock data = MakeFixtureBlock(o);
  for (size_t i = 0; i < data.block.images.size(); ++i) data.block.images[i].eo = data.true_eo[i];
  return data;
}

}  // namespace photopose::testing
