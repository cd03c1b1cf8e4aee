#include "core/simulation/synthetic_block.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/collinearity.h"
#include "core/io/colmap.h"
#include "core/simulation/portable_random.h"
#include "core/io/csv.h"
#include "core/io/tables.h"
#include "core/rotation.h"
#include "tests/support/block_expect.h"
#include "tests/support/temp_dir.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::ScopedTempDir;

// Noise-free marks reproject to their point through the model to the accuracy of the model's
// inversions (core/camera_models.h: 1e-7 um on the film, 1e-12 normalised): far below 1e-6 px.
constexpr double kNoiseFreePx = 1e-6;
// A sample standard deviation of n Gaussian draws has a relative standard error of 1 / sqrt(2 n);
// five of those bound a correct generator with a failure chance of 1e-6.
double SigmaBand(size_t n) { return 5.0 / std::sqrt(2.0 * static_cast<double>(n)); }

// The residual (px) of a mark at the true orientation and point.
Eigen::Vector2d TrueResidualPx(const Block& block, const SyntheticBlockTruth& truth, int m) {
  const BlockMark& mark = block.marks[m];
  const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
  double ab[2], r[2];
  EXPECT_TRUE(ProjectToNormalized(truth.eo[mark.image].data(), truth.points_m[mark.point].data(), ab));
  CameraModelResidual(camera.model, camera.params.data(), ab, mark.observation.data(),
                      camera.data(), r);
  return Eigen::Vector2d(r[0], r[1]) / mark.observation_units_per_unit;
}

SyntheticBlockOptions SmallOptions() {
  SyntheticBlockOptions o;
  o.num_lines = 3;
  o.images_per_line = 6;
  o.num_tie_points = 400;
  return o;
}

TEST(SyntheticBlock, DefaultsMakeAValidBlock) {
  const SyntheticBlockOptions options;
  ASSERT_TRUE(options.IsValid().ok()) << options.IsValid().message();
  Block block;
  SyntheticBlockTruth truth;
  const Status status = MakeSyntheticBlock(options, &block, &truth);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(CheckBlock(block).ok()) << CheckBlock(block).message();
  EXPECT_EQ(block.images.size(), 40u);
  int control = 0, check = 0, tie = 0;
  for (const BlockPoint& p : block.points) {
    control += p.role == PointRole::kControl;
    check += p.role == PointRole::kCheck;
    tie += p.role == PointRole::kTie;
  }
  EXPECT_EQ(control, options.num_control_points);
  EXPECT_EQ(check, options.num_check_points);
  // Density mode: the points seen twice or more of 0.05 per m^2 of the covered rectangle.
  EXPECT_GT(tie, 0.5 * options.tie_point_density_per_m2 * truth.covered_area_m2);
  EXPECT_LE(tie, options.tie_point_density_per_m2 * truth.covered_area_m2 + 1);
  // 24 mm, 4 um, 6000 x 4000 px at 100 m: 100 m x 66.7 m footprint; 80% / 60% overlap.
  EXPECT_NEAR(truth.footprint_width_m, 100.0, 1e-9);
  EXPECT_NEAR(truth.footprint_height_m, 200.0 / 3.0, 1e-9);
  EXPECT_NEAR(truth.forward_spacing_m, 0.2 * 200.0 / 3.0, 1e-9);
  EXPECT_NEAR(truth.side_spacing_m, 40.0, 1e-9);
  for (const int n : {0, 1}) EXPECT_EQ(block.marks_of_image.size(), block.images.size()) << n;
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (block.points[p].role == PointRole::kTie)
      EXPECT_GE(block.marks_of_point[p].size(), static_cast<size_t>(options.min_tie_views));
  }
}

TEST(SyntheticBlock, NoiseFreeMarksReprojectExactly) {
  for (const CameraModelType model : {CameraModelType::kFrame, CameraModelType::kOpenCv}) {
    SyntheticBlockOptions o = SmallOptions();
    o.mark_sigma_px = 0.0;
    o.camera_model = model;
    if (model == CameraModelType::kFrame) {
      // A real lens: principal point off centre, radial and decentring distortion, affinity.
      o.camera_params = {24100.0, 15.0, -9.0, 0.0, -1.5e-4, 2e-7, 0.0, 3e-6, -2e-6, 2e-4, 0.0};
    } else {
      o.camera_params = {6020.0, 6010.0, 3010.0, 1995.0, -0.08, 0.02, 2e-4, -1e-4};
    }
    Block block;
    SyntheticBlockTruth truth;
    const Status status = MakeSyntheticBlock(o, &block, &truth);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_GT(block.marks.size(), 1000u);
    double worst = 0.0;
    for (size_t m = 0; m < block.marks.size(); ++m)
      worst = std::max(worst, TrueResidualPx(block, truth, static_cast<int>(m)).norm());
    EXPECT_LT(worst, kNoiseFreePx) << EnumName(model);
    // Every mark inside its image.
    for (const BlockMark& mark : block.marks) {
      ASSERT_GE(mark.measured.x(), 0.0);
      ASSERT_LE(mark.measured.x(), o.image_width_px);
      ASSERT_GE(mark.measured.y(), 0.0);
      ASSERT_LE(mark.measured.y(), o.image_height_px);
    }
  }
}

TEST(SyntheticBlock, NoiseHasTheStatedSigma) {
  SyntheticBlockOptions o = SmallOptions();
  o.mark_sigma_px = 0.7;
  o.gnss_sigma_m = {0.03, 0.03, 0.06};
  o.num_lines = 10;
  o.images_per_line = 30;
  o.num_tie_points = 1000;
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  double sum = 0.0;
  for (size_t m = 0; m < block.marks.size(); ++m)
    sum += TrueResidualPx(block, truth, static_cast<int>(m)).squaredNorm();
  const size_t n = 2 * block.marks.size();
  EXPECT_NEAR(std::sqrt(sum / n), o.mark_sigma_px, o.mark_sigma_px * SigmaBand(n));
  Eigen::Vector3d gnss_sum = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < block.images.size(); ++i) {
    const Eigen::Vector3d e = *block.images[i].measured_center_m - truth.eo[i].center_in_ground();
    gnss_sum += e.cwiseProduct(e);
    EXPECT_EQ(*block.images[i].center_accuracy_m, o.gnss_sigma_m);  // stated = sigma
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(std::sqrt(gnss_sum[k] / block.images.size()), o.gnss_sigma_m[k],
                o.gnss_sigma_m[k] * SigmaBand(block.images.size()));
  }
  EXPECT_EQ(*block.marks[0].accuracy, 0.7);
}

void ExpectSameBlock(const Block& a, const Block& b) {
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t i = 0; i < a.images.size(); ++i) {
    EXPECT_EQ(a.images[i].name, b.images[i].name);
    EXPECT_EQ(a.images[i].eo->parameters, b.images[i].eo->parameters);
    EXPECT_EQ(*a.images[i].measured_center_m, *b.images[i].measured_center_m);
  }
  EXPECT_TRUE(testing::SamePointsAndMarks(a, b));
}

TEST(SyntheticBlock, SameSeedSameBlockOtherSeedOtherBlock) {
  SyntheticBlockOptions o = SmallOptions();
  Block a, b, c;
  ASSERT_TRUE(MakeSyntheticBlock(o, &a, nullptr).ok());
  ASSERT_TRUE(MakeSyntheticBlock(o, &b, nullptr).ok());
  ExpectSameBlock(a, b);
  o.seed = 2;
  ASSERT_TRUE(MakeSyntheticBlock(o, &c, nullptr).ok());
  EXPECT_NE(a.images[0].eo->parameters, c.images[0].eo->parameters);
  EXPECT_NE(a.points.back().position_m, c.points.back().position_m);
}

TEST(SyntheticBlock, PortableDrawsArePinned) {
  // The first draws of the default block: they change only when the generator changes (which
  // then changes every synthetic result of the project) - never with the standard library.
  SyntheticBlockOptions o = SmallOptions();
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  PortableRandom random(1, 1);  // the pose stream of seed 1
  const double first_x_jitter = random.Uniform(-1.0, 1.0);
  EXPECT_EQ(truth.eo[0].center_in_ground().x(), o.origin_m.x() + first_x_jitter);
  PortableRandom mt(5489);  // std::mt19937_64's default seed: its 10000th output is fixed by the standard
  std::mt19937_64 reference;
  for (int k = 0; k < 9999; ++k) reference();
  EXPECT_EQ(reference(), 9981545732273789042ULL);
  // Uniform01 takes the top 53 bits.
  std::mt19937_64 engine(5489);
  EXPECT_EQ(mt.Uniform01(), static_cast<double>(engine() >> 11) * 0x1.0p-53);
}

TEST(SyntheticBlock, BlundersChangeOnlyWhatTheyName) {
  SyntheticBlockOptions o = SmallOptions();
  o.mark_sigma_px = 0.0;
  o.control_sigma_m = 0.0;
  o.gnss_sigma_m = {0.0, 0.0, 0.0};
  Block clean, dirty;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &clean, nullptr).ok());
  o.num_tie_blunders = 25;
  o.tie_blunder_px = 15.0;
  o.num_control_blunders = 2;
  o.control_blunder_m = 0.4;
  o.num_gnss_blunders = 3;
  o.gnss_blunder_m = 7.0;
  ASSERT_TRUE(MakeSyntheticBlock(o, &dirty, &truth).ok());
  ASSERT_EQ(truth.blunder_marks.size(), 25u);
  ASSERT_EQ(truth.blunder_control_points.size(), 2u);
  ASSERT_EQ(truth.blunder_gnss_images.size(), 3u);
  ASSERT_EQ(clean.marks.size(), dirty.marks.size());
  int blunders = 0;
  for (size_t m = 0; m < clean.marks.size(); ++m) {
    const double moved = (dirty.marks[m].measured - clean.marks[m].measured).norm();
    if (truth.mark_is_blunder[m]) {
      ++blunders;
      EXPECT_EQ(dirty.points[dirty.marks[m].point].role, PointRole::kTie);
      EXPECT_NEAR(moved, 15.0, 1e-9);
      EXPECT_GT(TrueResidualPx(dirty, truth, static_cast<int>(m)).norm(), 14.0);
    } else {
      EXPECT_EQ(moved, 0.0);
    }
  }
  EXPECT_EQ(blunders, 25);
  for (size_t p = 0; p < clean.points.size(); ++p) {
    if (clean.points[p].role == PointRole::kTie) continue;
    const bool blunder = std::count(truth.blunder_control_points.begin(),
                                    truth.blunder_control_points.end(), static_cast<int>(p)) > 0;
    const double off = (*dirty.points[p].surveyed_m - truth.points_m[p]).norm();
    EXPECT_NEAR(off, blunder ? 0.4 : 0.0, 1e-9) << dirty.points[p].id;
    if (blunder) EXPECT_EQ(dirty.points[p].role, PointRole::kControl);
  }
  for (size_t i = 0; i < clean.images.size(); ++i) {
    const bool blunder = std::count(truth.blunder_gnss_images.begin(),
                                    truth.blunder_gnss_images.end(), static_cast<int>(i)) > 0;
    const double off = (*dirty.images[i].measured_center_m - truth.eo[i].center_in_ground()).norm();
    EXPECT_NEAR(off, blunder ? 7.0 : 0.0, 1e-9);
  }
}

TEST(SyntheticBlock, ControlAtTheCornersCheckSpread) {
  SyntheticBlockOptions o = SmallOptions();
  o.num_control_points = 4;
  o.num_check_points = 9;
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  const double x1 = o.origin_m.x() + (o.num_lines - 1) * truth.side_spacing_m;
  const double y1 = o.origin_m.y() + (o.images_per_line - 1) * truth.forward_spacing_m;
  const std::vector<Eigen::Vector2d> corners = {
      {o.origin_m.x(), o.origin_m.y()}, {x1, o.origin_m.y()}, {x1, y1}, {o.origin_m.x(), y1}};
  for (int c = 0; c < 4; ++c) {
    EXPECT_EQ(block.points[c].role, PointRole::kControl);
    EXPECT_NEAR((truth.points_m[c].head<2>() - corners[c]).norm(), 0.0, 1e-9);
    EXPECT_GE(block.marks_of_point[c].size(), 2u);
  }
  // Nine check points, one per cell of a 3 x 3 grid over the centre rectangle.
  std::set<std::pair<int, int>> cells;
  for (int c = 4; c < 13; ++c) {
    EXPECT_EQ(block.points[c].role, PointRole::kCheck);
    const double u = (truth.points_m[c].x() - o.origin_m.x()) / (x1 - o.origin_m.x());
    const double v = (truth.points_m[c].y() - o.origin_m.y()) / (y1 - o.origin_m.y());
    cells.insert({static_cast<int>(u * 3), static_cast<int>(v * 3)});
  }
  EXPECT_EQ(cells.size(), 9u);
}

TEST(SyntheticBlock, PerturbedStartAndStatedAccuracies) {
  SyntheticBlockOptions o = SmallOptions();
  o.attitude = true;
  o.attitude_sigma_deg = 0.02;
  o.control_sigma_m = 0.01;
  o.control_accuracy_m = 0.02;
  o.tie_point_start = false;
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  for (size_t i = 0; i < block.images.size(); ++i) {
    EXPECT_NE(block.images[i].eo->parameters, truth.eo[i].parameters);
    EXPECT_LT((block.images[i].eo->center_in_ground() - truth.eo[i].center_in_ground()).norm(),
              6.0 * o.start_position_sigma_m);
    EXPECT_NEAR((*block.images[i].attitude_accuracy_rad)[0], DegreesToRadians(0.02), 1e-15);
  }
  for (const BlockPoint& p : block.points) {
    if (p.role == PointRole::kTie) {
      EXPECT_FALSE(p.position_m.has_value());
    } else {
      EXPECT_EQ(*p.position_m, *p.surveyed_m);
      EXPECT_EQ(*p.accuracy_m, Eigen::Vector3d::Constant(0.02));
    }
  }
}

TEST(SyntheticBlock, IssueTenGeometryGivesItsSizes) {
  // The benchmark block of issue 10 with 3 of its 25 lines of 40 images at 13 m / 30 m
  // spacing: across three lines a point sees at most 3 x (66.7 / 13 + 1) = 18 images.
  SyntheticBlockOptions o = BenchmarkBlockOptions();
  o.num_lines = 3;
  o.num_tie_points = 5000;
  o.num_control_points = 8;
  o.num_check_points = 6;
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  EXPECT_EQ(block.images.size(), 120u);
  EXPECT_EQ(block.points.size(), 5014u);
  const double marks_per_point = static_cast<double>(block.marks.size()) / block.points.size();
  EXPECT_GT(marks_per_point, 6.0);
  EXPECT_LT(marks_per_point, 3.0 * 6.2);
}

// ------------------------------------------------------------------ oblique blocks, layouts

// The angle (deg) between an image's optical axis and the vertical: the camera's -z axis in the
// ground is R_camera_from_ground^T (0, 0, -1).
double OffNadirDeg(const ExteriorOrientation& eo) {
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
  const Eigen::Vector3d axis = R.transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
  return std::acos(std::clamp(-axis.z(), -1.0, 1.0)) * kDegreesPerRadian;
}

// Whether point p projects inside image i's frame (the generator's own test of a view, done
// here for every image and point, without the flight grid's candidates).
bool InFrame(const Block& block, const SyntheticBlockTruth& truth, int i, int p) {
  const BlockCamera& camera = block.cameras[block.images[i].camera];
  double ab[2];
  Eigen::Vector2d film, pixel;
  if (!ProjectToNormalized(truth.eo[i].data(), truth.points_m[p].data(), ab)) return false;
  if (!ObservationFromNormalized(camera.model, camera.params.data(), camera.data(), {ab[0], ab[1]},
                                 &film)
           .ok() ||
      !PixelFromFilm(camera.table, film, PixelOrigin::kCorner, &pixel).ok())
    return false;
  return pixel.x() >= 0.0 && pixel.y() >= 0.0 && pixel.x() <= camera.table.n_columns &&
         pixel.y() <= camera.table.n_rows;
}

// Every view of every point was found: each point has a mark in exactly the images whose frame
// it projects into.
void ExpectEveryViewFound(const Block& block, const SyntheticBlockTruth& truth) {
  int missed = 0, extra = 0;
  for (size_t p = 0; p < block.points.size(); ++p) {
    std::set<int> marked;
    for (const int m : block.marks_of_point[p]) marked.insert(block.marks[m].image);
    for (size_t i = 0; i < block.images.size(); ++i) {
      const bool seen = InFrame(block, truth, static_cast<int>(i), static_cast<int>(p));
      missed += seen && !marked.count(static_cast<int>(i));
      extra += !seen && marked.count(static_cast<int>(i));
    }
  }
  EXPECT_EQ(missed, 0);
  EXPECT_EQ(extra, 0);
}

// A block looking obliquely: 35 and 55 deg in omega, with and without attitude jitter and
// serpentine lines.
TEST(SyntheticBlock, NominalTiltIsAppliedAndItsFootprintsCovered) {
  for (const double tilt_deg : {35.0, 55.0}) {
    for (const bool jitter : {false, true}) {
      SCOPED_TRACE(std::to_string(tilt_deg) + (jitter ? " deg, jittered" : " deg"));
      SyntheticBlockOptions o = SmallOptions();
      o.num_tie_points = 300;
      o.mark_sigma_px = 0.0;
      o.nominal_angles_deg = Eigen::Vector3d(tilt_deg, 0.0, 0.0);
      // At 55 deg the images see the ground 75 to 340 m ahead (lines flown north look south and
      // the others north): the centre rectangle's corners and the middle of the covered one are
      // seen by none, so the surveyed points go inside the footprints, in the two bands.
      o.survey_area = SyntheticBlockOptions::SurveyArea::kFootprints;
      o.control_layout = {{0.25, 0.25}, {0.75, 0.25}, {0.25, 0.75}, {0.75, 0.75}};
      o.check_layout = {{0.5, 0.2}, {0.5, 0.8}};
      if (!jitter) {
        o.attitude_jitter_deg = 0.0;
        o.position_jitter_m = 0.0;
      }
      Block block;
      SyntheticBlockTruth truth;
      const Status status = MakeSyntheticBlock(o, &block, &truth);
      ASSERT_TRUE(status.ok()) << status.message();
      // The optical axes make the stated angle with the vertical (kappa, 0 or 180 deg on lines
      // flown back, does not change it); the jitter of +- 2 deg per angle moves it by less than
      // 2 sqrt(2) deg.
      for (const ExteriorOrientation& eo : truth.eo)
        EXPECT_NEAR(OffNadirDeg(eo), tilt_deg, jitter ? 2.0 * std::sqrt(2.0) : 1e-9);
      // The tie points: all asked for, over the covered rectangle, each seen twice or more, and
      // every view of every point found by the flight grid's candidates.
      int ties = 0;
      for (size_t p = 0; p < block.points.size(); ++p) {
        if (block.points[p].role != PointRole::kTie) continue;
        ++ties;
        EXPECT_GE(block.marks_of_point[p].size(), 2u);
        const Eigen::Vector2d u =
            (truth.points_m[p].head<2>() - truth.covered_low_m).cwiseQuotient(truth.covered_size_m);
        EXPECT_TRUE(u.minCoeff() >= 0.0 && u.maxCoeff() <= 1.0) << block.points[p].id;
      }
      EXPECT_EQ(ties, o.num_tie_points);
      ExpectEveryViewFound(block, truth);
      if (jitter) continue;
      // Without jitter the covered rectangle is the union of the footprints at the mean terrain:
      // every corner ray meets that plane inside it, and the rectangle touches those points.
      const Eigen::Vector2d low = truth.covered_low_m, high = low + truth.covered_size_m;
      Eigen::Vector2d corner_low = Eigen::Vector2d::Constant(1e300), corner_high = -corner_low;
      for (const ExteriorOrientation& eo : truth.eo) {
        for (const Eigen::Vector2d pixel :
             {Eigen::Vector2d(0, 0), Eigen::Vector2d(o.image_width_px, 0),
              Eigen::Vector2d(0, o.image_height_px),
              Eigen::Vector2d(o.image_width_px, o.image_height_px)}) {
          Eigen::Vector3d ground;
          ASSERT_TRUE(IntersectRayWithPlane(block.cameras[0].table, eo, pixel, PixelOrigin::kCorner,
                                            o.ground_height_m, &ground)
                          .ok());
          corner_low = corner_low.cwiseMin(ground.head<2>());
          corner_high = corner_high.cwiseMax(ground.head<2>());
        }
      }
      EXPECT_LT((corner_low - low).cwiseAbs().maxCoeff(), 1e-6);
      EXPECT_LT((corner_high - high).cwiseAbs().maxCoeff(), 1e-6);
      // The tilt moves the footprints along the lines by about H tan(tilt) (serpentine: both ways).
      EXPECT_GT(truth.covered_size_m.y() - (o.images_per_line - 1) * truth.forward_spacing_m,
                2.0 * o.flying_height_m * std::tan(DegreesToRadians(tilt_deg)));
    }
  }
}

TEST(SyntheticBlock, ExtraAnglesTiltOnlyTheChosenImages) {
  SyntheticBlockOptions o = SmallOptions();
  o.attitude_jitter_deg = 0.0;
  o.mark_sigma_px = 0.0;
  Block level, block;
  SyntheticBlockTruth level_truth, truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &level, &level_truth).ok());
  const int chosen = o.images_per_line + 2;
  o.extra_angles_deg = {{chosen, Eigen::Vector3d(30.0, 0.0, 0.0)},
                        {chosen, Eigen::Vector3d(0.0, 10.0, 0.0)}};  // both are added
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  for (size_t i = 0; i < truth.eo.size(); ++i) {
    // Centres as they were (the tilt draws nothing); angles only of the chosen image.
    EXPECT_EQ(truth.eo[i].center_in_ground(), level_truth.eo[i].center_in_ground());
    if (static_cast<int>(i) != chosen) {
      EXPECT_EQ(truth.eo[i].parameters, level_truth.eo[i].parameters);
      EXPECT_NEAR(OffNadirDeg(truth.eo[i]), 0.0, 1e-6);
    }
  }
  EXPECT_NEAR(OffNadirDeg(truth.eo[chosen]),
              std::acos(std::cos(DegreesToRadians(30.0)) * std::cos(DegreesToRadians(10.0))) *
                  kDegreesPerRadian,
              1e-9);
  // Its footprint went 58 m away from its centre, beyond the neighbours' reach: its views are
  // found all the same.
  EXPECT_GT(block.marks_of_image[chosen].size(), 20u);
  ExpectEveryViewFound(block, truth);
}

TEST(SyntheticBlock, ExplicitLayoutsInTheCentreRectangleOrTheFootprints) {
  const std::vector<Eigen::Vector2d> control = {{0.2, 0.2}, {0.8, 0.2}, {0.2, 0.8}, {0.8, 0.8},
                                                {0.5, 0.5}};
  const std::vector<Eigen::Vector2d> check = {{0.35, 0.65}, {0.65, 0.35}};
  for (const bool oblique : {false, true}) {
    SCOPED_TRACE(oblique ? "oblique 35 deg, in the footprints" : "nadir, centre rectangle");
    SyntheticBlockOptions o = SmallOptions();
    o.control_layout = control;
    o.check_layout = check;
    o.num_control_blunders = 5;  // counted on the layout, not num_control_points
    if (oblique) {
      o.nominal_angles_deg = Eigen::Vector3d(35.0, 0.0, 0.0);
      o.survey_area = SyntheticBlockOptions::SurveyArea::kFootprints;
    }
    Block block;
    SyntheticBlockTruth truth;
    const Status status = MakeSyntheticBlock(o, &block, &truth);
    ASSERT_TRUE(status.ok()) << status.message();
    const Eigen::Vector2d low =
        oblique ? truth.covered_low_m : Eigen::Vector2d(o.origin_m.x(), o.origin_m.y());
    const Eigen::Vector2d size =
        oblique ? truth.covered_size_m
                : Eigen::Vector2d((o.num_lines - 1) * truth.side_spacing_m,
                                  (o.images_per_line - 1) * truth.forward_spacing_m);
    const size_t n = control.size() + check.size();
    ASSERT_GE(block.points.size(), n);
    for (size_t p = 0; p < n; ++p) {
      const bool is_control = p < control.size();
      const Eigen::Vector2d at = is_control ? control[p] : check[p - control.size()];
      EXPECT_EQ(block.points[p].role, is_control ? PointRole::kControl : PointRole::kCheck);
      const size_t number = is_control ? p + 1 : p + 1 - control.size();
      EXPECT_EQ(block.points[p].id, (is_control ? "C00" : "K00") + std::to_string(number));
      EXPECT_LT((truth.points_m[p].head<2>() - (low + at.cwiseProduct(size))).norm(), 1e-6);
      // Inside the footprints: seen by an image (the oblique ones see the ground 30 to 135 m from
      // their centres).
      EXPECT_GE(block.marks_of_point[p].size(), 1u) << block.points[p].id;
    }
    EXPECT_EQ(truth.blunder_control_points.size(), control.size());
  }
}

TEST(SyntheticBlock, LayoutOfTheDefaultPointsGivesTheDefaultBlock) {
  // The explicit layout of the default's first four control points draws nothing that the
  // default does not: the same block, bit for bit.
  SyntheticBlockOptions o = SmallOptions();
  o.num_control_points = 4;
  SyntheticBlockOptions explicit_layout = o;
  explicit_layout.num_control_points = 0;  // ignored once a layout is given
  explicit_layout.control_layout = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  Block a, b;
  ASSERT_TRUE(MakeSyntheticBlock(o, &a, nullptr).ok());
  ASSERT_TRUE(MakeSyntheticBlock(explicit_layout, &b, nullptr).ok());
  ExpectSameBlock(a, b);
}

struct InvalidCase {
  const char* name;
  void (*change)(SyntheticBlockOptions*);
  const char* message;
};

class SyntheticBlockInvalid : public ::testing::TestWithParam<InvalidCase> {};

TEST_P(SyntheticBlockInvalid, NamesTheField) {
  SyntheticBlockOptions o;
  GetParam().change(&o);
  const Status status = o.IsValid();
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find(GetParam().message), std::string::npos) << status.message();
  Block block;
  EXPECT_FALSE(MakeSyntheticBlock(o, &block, nullptr).ok());
}

INSTANTIATE_TEST_SUITE_P(
    Cases, SyntheticBlockInvalid,
    ::testing::Values(
        InvalidCase{"NoLines", [](SyntheticBlockOptions* o) { o->num_lines = 0; }, "num_lines"},
        InvalidCase{"HugeGrid",
                    [](SyntheticBlockOptions* o) {
                      o->num_lines = 2000000000;
                      o->images_per_line = 2000000000;
                    },
                    "num_lines x images_per_line"},
        InvalidCase{"Overlap", [](SyntheticBlockOptions* o) { o->forward_overlap = 1.0; },
                    "forward_overlap"},
        InvalidCase{"NaNHeight",
                    [](SyntheticBlockOptions* o) { o->flying_height_m = std::nan(""); },
                    "flying_height_m"},
        InvalidCase{"Relief", [](SyntheticBlockOptions* o) { o->terrain_relief_m = 150.0; },
                    "terrain_relief_m"},
        InvalidCase{"Params", [](SyntheticBlockOptions* o) { o->camera_params = {1.0, 2.0}; },
                    "camera_params"},
        InvalidCase{"TooManyPoints",
                    [](SyntheticBlockOptions* o) { o->tie_point_density_per_m2 = 1e9; },
                    "more than 32-bit indices hold"},
        InvalidCase{"TooManyMarks",
                    [](SyntheticBlockOptions* o) {
                      o->num_tie_points = 1500000000;
                    },
                    "more than 32-bit indices hold"},
        InvalidCase{"ControlBlunders",
                    [](SyntheticBlockOptions* o) { o->num_control_blunders = 9; },
                    "num_control_blunders"},
        InvalidCase{"GnssBlundersWithoutGnss",
                    [](SyntheticBlockOptions* o) {
                      o->gnss = false;
                      o->num_gnss_blunders = 1;
                    },
                    "needs gnss"},
        InvalidCase{"NegativeNoise", [](SyntheticBlockOptions* o) { o->mark_sigma_px = -1.0; },
                    "mark_sigma_px"},
        InvalidCase{"TiltToTheHorizon",
                    [](SyntheticBlockOptions* o) { o->nominal_angles_deg = {70.0, 0.0, 0.0}; },
                    "horizon"},
        InvalidCase{"ExtraAnglesOfNoImage",
                    [](SyntheticBlockOptions* o) {
                      o->extra_angles_deg = {{40, Eigen::Vector3d(10.0, 0.0, 0.0)}};
                    },
                    "extra_angles_deg"},
        InvalidCase{"LayoutOutside",
                    [](SyntheticBlockOptions* o) { o->check_layout = {{0.5, 1.5}}; },
                    "check_layout"},
        InvalidCase{"BlundersBeyondTheLayout",
                    [](SyntheticBlockOptions* o) {
                      o->control_layout = {{0.0, 0.0}, {1.0, 1.0}};
                      o->num_control_blunders = 3;
                    },
                    "num_control_blunders"}),
    [](const ::testing::TestParamInfo<InvalidCase>& info) { return std::string(info.param.name); });

TEST(SyntheticBlock, TooFewViewsForTheCountIsAClearError) {
  SyntheticBlockOptions o = SmallOptions();
  o.min_tie_views = 100;  // more images than the block has
  Block block;
  const Status status = MakeSyntheticBlock(o, &block, nullptr);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("only 0 of 400 tie points are seen by 100 images"),
            std::string::npos)
      << status.message();
}

TEST(SyntheticBlock, ColmapVariantWritesAsAColmapModel) {
  SyntheticBlockOptions o = SmallOptions();
  o.camera_model = CameraModelType::kSimpleRadial;
  o.camera_params = {6000.0, 3000.0, 2000.0, -0.05};
  Block block;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, nullptr).ok());
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  ASSERT_TRUE(WriteColmapModel(dir.path(), block).ok());
  Block again;
  const Status status = ReadColmapModel(dir.path(), &again);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(again.cameras[0].model, CameraModelType::kSimpleRadial);
  EXPECT_EQ(again.marks.size(), block.marks.size());
  EXPECT_EQ(again.images[5].name, block.images[5].name);
}

TEST(SyntheticBlock, WritesItsTruth) {
  SyntheticBlockOptions o = SmallOptions();
  o.num_tie_blunders = 2;
  o.num_control_blunders = 1;
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, &truth).ok());
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  SyntheticTruthFiles files{dir.Path("true_frames.csv"), dir.Path("true_points.csv"),
                            dir.Path("blunders.csv")};
  const Status status = WriteSyntheticBlockTruth(block, truth, o, files);
  ASSERT_TRUE(status.ok()) << status.message();
  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(files.frames, FramesTableOptions(), &frames).ok());
  ASSERT_EQ(frames.size(), block.images.size());
  EXPECT_LT((frames[3].eo.parameters - truth.eo[3].parameters).norm(), 1e-12 * 1e7);
  std::vector<GroundPoint> points;
  ASSERT_TRUE(ReadGroundPoints(files.points, &points).ok());
  ASSERT_EQ(points.size(), block.points.size());
  EXPECT_EQ(points.back().position, truth.points_m.back());
  EXPECT_EQ(points.back().role, PointRole::kTie);
  CsvTable blunders;
  ASSERT_TRUE(CsvTable::Read(files.blunders, CsvOptions(), &blunders).ok());
  EXPECT_EQ(blunders.rows().size(), 3u);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
