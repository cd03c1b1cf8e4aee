#pragma once
// A seeded synthetic scene generator shared by the tests, the benchmarks, `photopose simulate` and
// `photopose compare`: cameras, true and approximate exterior orientations, ground points with
// control/check roles, and pixel marks with Gaussian noise and gross outliers. The same options and
// seed always give the same scene.
// Not merged with synthetic_block.h: a scene is independent images for resection (points per
// footprint, outliers, no tie points) and its draws are pinned by examples/; a block is one survey.

#include <cstdint>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/io/block_tables.h"
#include "core/camera.h"
#include "core/enum_names.h"
#include "core/status.h"
#include "core/io/tables.h"

namespace photopose {

enum class Scenario {
  kNadir,     // one vertical aerial frame, 100.5 mm lens, 6 um pixels, 800 m above ground
  kOblique,   // one frame tilted 45 deg about the flight axis, same camera
  kUavBlock,  // 3 x 4 images of a UAV block at 100 m, 8.8 mm lens, 2.41 um pixels, radial distortion
};

inline constexpr EnumNameEntry<Scenario> kScenarioNames[] = {
    {Scenario::kNadir, "nadir"},
    {Scenario::kOblique, "oblique"},
    {Scenario::kUavBlock, "uav_block"}};
constexpr EnumNameTable<Scenario> EnumNames(Scenario) {
  return EnumNameTable<Scenario>(kScenarioNames);
}

struct SyntheticSceneOptions {
  Scenario scenario = Scenario::kNadir;
  uint64_t seed = 1;                     // random generator seed
  double noise_px = 0.5;                 // Gaussian image noise, one sigma (pixels)
  double outlier_fraction = 0.0;         // fraction of marks replaced by gross errors, [0, 1)
  double outlier_min_px = 20.0;          // gross errors are uniform in [min, max] pixels
  double outlier_max_px = 200.0;         //   in a random direction
  int num_control_points = 20;           // control points per image footprint (about)
  int num_check_points = 5;              // check points per image footprint (about)
  double terrain_relief_m = 30.0;        // ground heights uniform in +- relief / 2 (m)
  double initial_position_error_m = 5.0; // approximate frames: uniform error per axis, +- (m)
  double initial_angle_error_deg = 2.0;  // approximate frames: uniform error per angle, +- (deg)
  double mark_accuracy_px = 0.0;         // Accuracy column of the marks (0: noise_px, or 1 if zero)

  Status IsValid() const;
};

struct SyntheticScene {
  std::vector<FrameCamera> cameras;
  std::vector<FrameRecord> true_frames;
  std::vector<FrameRecord> approximate_frames;
  std::vector<GroundPoint> points;   // true positions; Role control/check
  std::vector<ImageMark> marks;      // Column/Row pixels (PixelOrigin::kCorner), noisy
  std::vector<bool> mark_is_outlier; // parallel to marks
};

Status MakeSyntheticScene(const SyntheticSceneOptions& options, SyntheticScene* scene);

// The scene as the tables of a block (core/block.h): its cameras, points, marks (corner pixel
// origin) and approximate frames, for AssembleBlock. Block mark m is scene mark m.
BlockTables SceneBlockTables(const SyntheticScene& scene);

}  // namespace photopose
