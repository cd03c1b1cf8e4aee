#pragma once
// A seeded synthetic photogrammetric BLOCK for bundle adjustment: an aerial survey flown in
// parallel lines over smooth terrain, with tie points, control and check points, GNSS camera
// positions, optional attitude measurements, noisy marks, optional blunders and a perturbed start.
// The truth (true orientations and points, which data are blunders) is kept apart from the block.
// Shared by the tests, the benchmarks and `photopose simulate --scenario=block`; written out as
// the project's tables (core/io/block_tables.h) or as a COLMAP model (core/io/colmap.h).
//
// Geometry: flight lines run along +Y (north), side by side along +X (east), `origin_m` being the
// first image centre; lines are flown alternately north and south (kappa 0 and 180 deg) unless
// `serpentine` is false. The image width lies across the lines and the height along them: a
// nadir image with seed angles (0, 0, 0) has film x east and film y north. Ground footprint of an
// image: width_px / f_px x height_px / f_px times the flying height. Oblique blocks
// (nominal_angles_deg): the footprints move and widen, and the tie-point rectangle and the search
// for views follow them; images tilted on their own (extra_angles_deg) are searched apart. These
// options draw no random numbers: left at their defaults they change nothing, bit for bit.
//
// Reproducible: the same options and seed give the same block, bit for bit, with any standard
// library (core/simulation/portable_random.h); each kind of draw has its own random stream, so that e.g.
// adding blunders leaves the tie points and the noise of the other marks as they were.
//
// Scale: issue 10's block (25 lines x 40 images, 24 mm / 4 um / 6000 x 4000 at 100 m, 13 m
// forward and 30 m side spacing, 120 000 tie points, about 1.8 million marks) is generated in a
// few seconds in a few hundred MB (docs/performance.md).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/block.h"
#include "core/camera_models.h"
#include "core/rotation.h"
#include "core/status.h"

namespace photopose {

struct SyntheticBlockOptions {
  uint64_t seed = 1;  // random generator seed

  // ---- flight
  int num_lines = 4;                // flight lines (rows of the grid), >= 1
  int images_per_line = 10;         // exposures per line (columns of the grid), >= 1
  double forward_spacing_m = 0.0;   // exposure spacing along a line (m); 0: from forward_overlap
  double side_spacing_m = 0.0;      // spacing of the lines (m); 0: from side_overlap
  double forward_overlap = 0.8;     // share of the footprint height two neighbours along a line
                                    // have in common, [0, 1) (used when forward_spacing_m is 0)
  double side_overlap = 0.6;        // the same across the lines (used when side_spacing_m is 0)
  double flying_height_m = 100.0;   // height of the projection centres above ground_height_m (m)
  Eigen::Vector2d origin_m{500000.0, 4100000.0};  // X, Y of the first image centre (m, e.g. UTM)
  bool serpentine = true;           // alternate lines flown back (kappa 180 deg)
  double position_jitter_m = 1.0;   // true centres: nominal + uniform in +- this, per axis (m)
  double attitude_jitter_deg = 2.0; // true omega, phi, kappa: nominal + uniform in +- this (deg)
  // Oblique blocks: added to every image's seed angles omega, phi, kappa (deg), a camera tilted in
  // the aircraft (so on lines flown back it looks the other way). The optical axis then makes
  // acos(cos omega cos phi) with the vertical; the corner rays must stay below the horizon.
  Eigen::Vector3d nominal_angles_deg{0.0, 0.0, 0.0};
  // Extra seed angles (deg) for chosen images (index in the block, i.e. in flight order), on top
  // of the nominal ones and the jitter: e.g. one oblique image in a nadir block. Every image with
  // extra angles is looked at for every point, wherever its footprint went.
  std::vector<std::pair<int, Eigen::Vector3d>> extra_angles_deg;

  // ---- terrain: Z = ground_height_m + relief / 2 * h(X, Y), h smooth with |h| <= 1 (hills a
  // few hundred metres across, phases from the seed)
  double ground_height_m = 50.0;    // mean terrain height (m)
  double terrain_relief_m = 10.0;   // peak-to-peak height range (m), >= 0

  // ---- camera: core/camera_models.h's kFrame (marks in pixels, PixelSize, FCS 1, Polarity -1)
  // or a COLMAP model (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV,
  // OPENCV_FISHEYE; marks in pixels)
  CameraModelType camera_model = CameraModelType::kFrame;
  double focal_length_mm = 24.0;    // lens focal length (mm)
  double pixel_size_um = 4.0;       // pixel pitch (um)
  int image_width_px = 6000;        // NColumns
  int image_height_px = 4000;       // NRows
  // The model's parameters in the order and units of core/camera_models.h, replacing the values
  // derived from the four fields above (principal point at the image centre, no distortion).
  // Empty: derived. Must have CameraModelNumParams(camera_model) values.
  std::vector<double> camera_params;
  // kFrame only: the camera table says ApplyECC (EarthRadius 6378137 m) and every mark is
  // generated with the earth-curvature drop (core/collinearity.h, LowerByEarthCurvature).
  bool earth_curvature = false;

  // ---- ground points
  long long num_tie_points = 0;     // exactly this many tie points when > 0, else by density:
  double tie_point_density_per_m2 = 0.05;  // candidates per m^2 of the covered rectangle
  int min_tie_views = 2;            // a tie point is kept only when seen in this many images
  int num_control_points = 8;       // corners first, then edge midpoints, centre, interior
  int num_check_points = 6;         // spread over the block (one per cell of a grid)
  // Explicit layouts: control / check points at these fractions (0..1 in X and Y) of the survey
  // area, in this order, in place of num_control_points / num_check_points and their default
  // layouts (when not empty).
  std::vector<Eigen::Vector2d> control_layout;
  std::vector<Eigen::Vector2d> check_layout;
  // The rectangle control and check points are laid out on: the image centres' (on one line or
  // one exposure per line: the middle half of the footprint across it), or the union of the
  // nominal footprints at the mean terrain (the tie-point area), for oblique blocks whose images
  // look away from their centres.
  enum class SurveyArea { kImageCentres, kFootprints };
  SurveyArea survey_area = SurveyArea::kImageCentres;
  double control_sigma_m = 0.0;     // Gaussian error of surveyed control/check coordinates (m)
  double control_accuracy_m = 0.0;  // stated AccuracyX/Y/Z of control/check points (m); 0: the
                                    // sigma, left unset when that is 0 too (adjustment default)

  // ---- marks
  double mark_sigma_px = 0.3;       // Gaussian noise per image axis of every mark (px)
  double mark_accuracy_px = 0.0;    // stated Accuracy (px); 0: mark_sigma_px, unset when 0 too

  // ---- camera positions (GNSS) and attitudes
  bool gnss = true;                 // measured centres (BlockImage::measured_center_m)
  Eigen::Vector3d gnss_sigma_m{0.02, 0.02, 0.04};     // Gaussian error per axis (m)
  Eigen::Vector3d gnss_accuracy_m{0.0, 0.0, 0.0};     // stated per axis (m); 0: the sigma (unset
                                                      // when that is 0 too)
  bool attitude = false;            // measured angles (BlockImage::measured_angles_rad)
  double attitude_sigma_deg = 0.01;     // Gaussian error per angle (deg)
  double attitude_accuracy_deg = 0.0;   // stated (deg); 0: the sigma (unset when 0 too)

  // ---- blunders (the truth says which)
  int num_tie_blunders = 0;         // tie marks moved by exactly tie_blunder_px, random direction
  double tie_blunder_px = 20.0;
  int num_control_blunders = 0;     // control points whose surveyed position is off by
  double control_blunder_m = 0.5;   //   exactly this distance (m), random 3D direction
  int num_gnss_blunders = 0;        // images whose measured centre is off by exactly this (m),
  double gnss_blunder_m = 5.0;      //   random 3D direction (needs gnss)

  // ---- perturbed start (BlockImage::eo, BlockPoint::position_m)
  double start_position_sigma_m = 2.0;  // start centres: truth + Gaussian, per axis (m)
  double start_angle_sigma_deg = 1.0;   // start angles: truth + Gaussian, per angle (deg)
  double start_point_sigma_m = 0.5;     // start tie points: truth + Gaussian, per axis (m)
  bool tie_point_start = true;          // false: tie points without a position (to triangulate)

  // Every field in range and finite, the sizes within 32-bit indices (computed in 64 bits).
  Status IsValid() const;
};

// Issue 10's benchmark block: 25 lines x 40 images of the default camera (24 mm / 4 um /
// 6000 x 4000) at 100 m, 13 m forward and 30 m side spacing (80% / 70% overlap), 120 000 tie
// points, 12 control and 10 check points: about 1.7 million marks (docs/performance.md).
SyntheticBlockOptions BenchmarkBlockOptions();

// The block of the solver benchmarks (tools/benchmarks/bundle_benchmark.cc, docs/performance.md)
// and of the tests that compare solvers on it: `lines` x `images_per_line` images of the default
// camera at 100 m, 20 m forward and 30 m side spacing, `tie_points` tie points, five control points
// (the corners and the centre of the camera-centre rectangle, 5 mm) and two check points, 0.5 px
// marks, 3 cm GNSS, the generator's perturbed start; seed 2026.
SyntheticBlockOptions SolverBenchmarkBlockOptions(int lines, int images_per_line, int tie_points);

// The block of the earth-curvature tests (ApplyECC, docs/conventions.md): 3 lines of 5 images of
// a 10 mm / 4 um / 6000 x 4000 frame camera at 800 m (0.32 m ground pixel, 1.9 x 1.3 km
// footprint), 400 m apart along the lines and 800 m across, 600 tie points, 30 m of relief, 0.1 px
// marks, 1 cm control, GNSS 3/3/5 cm; earth_curvature on, so that the marks carry the drop: 0.10 m
// at an image corner (D = 1.15 km), about half a pixel in the image. Seed 2026.
SyntheticBlockOptions EarthCurvatureBlockOptions();

// The truth of a synthetic block, parallel to the block's vectors.
struct SyntheticBlockTruth {
  std::vector<ExteriorOrientation> eo;       // per image: the true orientation
  std::vector<Eigen::Vector3d> points_m;     // per point: the true position (m)
  std::vector<unsigned char> mark_is_blunder;  // per mark: 1 for a tie-mark blunder
  std::vector<int> blunder_marks;            // indices of those marks
  std::vector<int> blunder_control_points;   // points whose surveyed position is a blunder
  std::vector<int> blunder_gnss_images;      // images whose measured centre is a blunder
  // Derived geometry, for reports.
  double forward_spacing_m = 0.0;            // as used
  double side_spacing_m = 0.0;
  double footprint_width_m = 0.0;            // across the lines, at the mean terrain (nadir)
  double footprint_height_m = 0.0;           // along the lines (nadir)
  // The rectangle the nominal footprints cover at the mean terrain (nominal angles, no jitter;
  // the tie points are drawn in it): X, Y of its low corner and its size (m).
  Eigen::Vector2d covered_low_m{0.0, 0.0};
  Eigen::Vector2d covered_size_m{0.0, 0.0};
  double covered_area_m2 = 0.0;              // its area
};

// Where WriteSyntheticBlockTruth writes the truth; an empty path leaves that file out.
struct SyntheticTruthFiles {
  std::string frames;    // frames table of the true orientations (seed convention, degrees)
  std::string points;    // ground points at their true positions, every role
  std::string blunders;  // CSV Kind,Raster,PointID,Magnitude,Unit: one row per blunder (kind
                         // mark: px; control_point: m; camera_position: m)
};

// Builds the block (index built) and its truth. Fails on invalid options, or when the geometry
// cannot give what was asked (e.g. fewer tie points seen in min_tie_views images than asked).
Status MakeSyntheticBlock(const SyntheticBlockOptions& options, Block* block,
                          SyntheticBlockTruth* truth);

// The truth files' contents (frames table in `rotation`, degrees), formatted in memory for callers
// that write them with other files as one transaction.
struct SyntheticTruthText {
  std::string frames;
  std::string points;
  std::string blunders;
};
Status FormatSyntheticBlockTruth(const Block& block, const SyntheticBlockTruth& truth,
                                 const SyntheticBlockOptions& options, RotationConvention rotation,
                                 SyntheticTruthText* text);

// Writes the truth of a block made by MakeSyntheticBlock (with the options it was made with, for
// the blunder magnitudes), apart from the block's own tables.
Status WriteSyntheticBlockTruth(const Block& block, const SyntheticBlockTruth& truth,
                                const SyntheticBlockOptions& options,
                                const SyntheticTruthFiles& files);

}  // namespace photopose
