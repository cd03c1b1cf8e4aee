#include "solvers/georeference/georeference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "tests/support/georeference_scene.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::GeoreferenceScene;
using testing::MakeGeoreferenceScene;

// The RMS distance (m) of the block's camera centres from the truth, through EPSG:4979.
double CentreRms(const GeoreferenceScene& scene, const Block& block, const GeoreferenceResult& result) {
  std::vector<Eigen::Vector3d> centres;
  for (const BlockImage& image : block.images) centres.push_back(image.eo->center_in_ground());
  EXPECT_TRUE(result.frame.FromLocal("EPSG:4979", &centres).ok());
  EXPECT_TRUE(scene.truth_frame.ToLocal("EPSG:4979", &centres).ok());
  double sum = 0.0;
  for (size_t i = 0; i < centres.size(); ++i) sum += (centres[i] - scene.true_centres_local[i]).squaredNorm();
  return std::sqrt(sum / centres.size());
}

// GeoreferenceBlock of the scene's model with the default options, into *block: success when it
// ran and the adjustment converged.
::testing::AssertionResult GeoreferenceTheScene(const GeoreferenceScene& scene, Block* block,
                                                GeoreferenceResult* result,
                                                BundleAdjustmentResult* adjustment) {
  *block = scene.model;
  BundleAdjustmentOptions options;
  options.solver.progress = nullptr;
  const Status status = GeoreferenceBlock(GeoreferenceOptions(), scene.inputs, options,
                                          BundleAdjustmentConfig(), block, result, adjustment);
  if (!status.ok()) return ::testing::AssertionFailure() << status.message();
  if (!adjustment->summary.IsSolutionUsable())
    return ::testing::AssertionFailure() << adjustment->summary.message;
  return ::testing::AssertionSuccess();
}

TEST(Georeference, DomedModelWithGnssAndControlReachesTheNoiseAfterTheAdjustment) {
  GeoreferenceScene scene = MakeGeoreferenceScene(2.0);
  Block block;
  GeoreferenceResult result;
  BundleAdjustmentResult adjustment;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &block, &result, &adjustment));
  EXPECT_EQ(result.out_crs, "EPSG:32632");  // the control's
  EXPECT_EQ(result.positions_matched, 24);
  EXPECT_TRUE(result.positions_unmatched.empty());
  EXPECT_NEAR(result.model_to_local.scale, 20.0, 0.2);
  ASSERT_EQ(result.check_after_similarity.count, 4);
  ASSERT_EQ(result.check_after_adjustment.count, 4);
  // The dome (2 m at the edge) survives the similarity; the adjustment removes it down to the noise
  // (0.3 px marks at a 1.3 cm ground pixel, 3-5 cm GNSS, 5 mm control).
  EXPECT_GT(result.check_after_similarity.total_m, 0.1);
  EXPECT_LT(result.check_after_adjustment.total_m, 0.03);
  EXPECT_LT(result.check_after_adjustment.rmse_m.z(), 0.03);
  EXPECT_LT(CentreRms(scene, block, result), 0.03);
}

// Control points stated error-free (accuracy 0) align the model like weighted ones and are then
// held fixed by the adjustment: they end on their survey, the block at the noise.
TEST(Georeference, ControlPointsWithAccuracyZeroAlignTheModelAndAreHeldFixed) {
  GeoreferenceScene scene = MakeGeoreferenceScene(2.0);
  int fixed = 0;
  for (GroundPoint& point : scene.inputs.control_points) {
    if (point.role != PointRole::kControl) continue;
    point.accuracy_m = Eigen::Vector3d::Zero();
    ++fixed;
  }
  ASSERT_GT(fixed, 2);
  Block block;
  GeoreferenceResult result;
  BundleAdjustmentResult adjustment;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &block, &result, &adjustment));
  int held = 0;
  for (const BlockPoint& point : block.points) {
    if (!IsHeldFixed(point)) continue;
    ++held;
    EXPECT_EQ(*point.position_m, *point.surveyed_m) << point.id;
  }
  EXPECT_EQ(held, fixed);
  EXPECT_LT(result.check_after_adjustment.total_m, 0.03);
  EXPECT_LT(CentreRms(scene, block, result), 0.03);
}

TEST(Georeference, FramesComeOutInTheOutputCrsWithAttitudesToItsGrid) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  Block block = scene.model;
  GeoreferenceResult result;
  GeoreferenceOptions options;
  options.out_crs = "EPSG:32632";
  ASSERT_TRUE(PrepareGeoreference(options, scene.inputs, &block, &result).ok());
  std::vector<FrameRecord> frames(1);
  frames[0].eo = *block.images[0].eo;
  ASSERT_TRUE(GeoreferencedFrames(result, &frames).ok());
  EXPECT_EQ(frames[0].srs, "EPSG:32632");
  // The centre: the truth in UTM within the GNSS noise.
  std::vector<Eigen::Vector3d> truth = {scene.true_centres_local[0]};
  ASSERT_TRUE(scene.truth_frame.FromLocal("EPSG:32632", &truth).ok());
  EXPECT_LT((frames[0].eo.center_in_ground() - truth[0]).norm(), 0.15);
  // The optical axis of a near-nadir image stays near-nadir in the grid's level frame.
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, frames[0].eo.angles_seed_rad());
  EXPECT_GT(std::abs(R(2, 2)), 0.99);
}

TEST(Georeference, NamesMatchingNoImageAreCountedNotDropped) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  CameraPositionMeasurement stray = scene.inputs.positions[0];
  stray.image = "not_in_model.jpg";
  scene.inputs.positions.push_back(stray);
  ImageMark ghost = scene.inputs.control_marks[0];
  ghost.raster = "ghost.jpg";
  scene.inputs.control_marks.push_back(ghost);
  // Folders in the model's names do not stop a match on the file name.
  scene.inputs.positions[1].image = "flight/" + scene.inputs.positions[1].image;
  Block block = scene.model;
  GeoreferenceResult result;
  ASSERT_TRUE(PrepareGeoreference(GeoreferenceOptions(), scene.inputs, &block, &result).ok());
  EXPECT_EQ(result.positions_matched, 24);
  ASSERT_EQ(result.positions_unmatched.size(), 1u);
  EXPECT_EQ(result.positions_unmatched[0], "not_in_model.jpg");
  ASSERT_EQ(result.control_marks_unmatched.size(), 1u);
  EXPECT_EQ(result.control_marks_unmatched[0].rfind("ghost.jpg", 0), 0u);
}

TEST(Georeference, BadCrsCollidingIdsAndALineOfPositionsAreRefusedLeavingTheBlock) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  const Block before = scene.model;
  GeoreferenceResult result;
  {
    GeoreferenceInputs inputs = scene.inputs;
    inputs.control_crs = "EPSG:999999";
    Block block = before;
    const Status status = PrepareGeoreference(GeoreferenceOptions(), inputs, &block, &result);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("EPSG:999999"), std::string::npos) << status.message();
    EXPECT_EQ(block.points.size(), before.points.size());
  }
  {
    GeoreferenceInputs inputs = scene.inputs;
    inputs.control_points[0].point_id = before.points[0].id;
    Block block = before;
    const Status status = PrepareGeoreference(GeoreferenceOptions(), inputs, &block, &result);
    EXPECT_NE(status.message().find("the model has a point of that id"), std::string::npos) << status.message();
  }
  {
    // One flight line, no control: the roll about the line is not determined.
    GeoreferenceInputs inputs = scene.inputs;
    inputs.control_points.clear();
    inputs.control_marks.clear();
    inputs.positions.resize(8);
    const Eigen::Vector3d first = inputs.positions[0].position, last = inputs.positions[7].position;
    for (int k = 0; k < 8; ++k) inputs.positions[k].position = first + (last - first) * (k / 7.0);
    Block block = before;
    const Status status = PrepareGeoreference(GeoreferenceOptions(), inputs, &block, &result);
    EXPECT_NE(status.message().find("lie on a line"), std::string::npos) << "[" << status.message() << "]";
  }
}

// geo.txt yaw/pitch/roll are read, counted and reported as not used; ODM's "0 0 0" (not
// available) is not an attitude.
TEST(Georeference, GeoTxtAttitudesAreReportedAsReadAndNotUsed) {
  GeoTxt geo;
  ASSERT_TRUE(ParseGeoTxt("EPSG:4326\n"
                          "a.jpg 11.1 47.1 500 12.5 -3.0 0.5\n"
                          "b.jpg 11.2 47.1 500 0 0 0\n"
                          "c.jpg 11.3 47.1 500\n"
                          "d.jpg 11.4 47.1 500 90 0 0 0.05 0.1\n",
                          "geo.txt", &geo)
                  .ok());
  GeoreferenceInputs inputs;
  SetPositionsFromGeoTxt(geo, "geo.txt", &inputs);
  EXPECT_EQ(inputs.positions.size(), 4u);
  EXPECT_EQ(inputs.attitudes_not_used, 2);

  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  Block block = scene.model;
  GeoreferenceResult result;
  ASSERT_TRUE(PrepareGeoreference(GeoreferenceOptions(), scene.inputs, &block, &result).ok());
  EXPECT_TRUE(result.inputs_not_used.empty());
  scene.inputs.attitudes_not_used = 2;
  scene.inputs.attitude_names = inputs.attitude_names;
  scene.inputs.attitudes_not_used_reason = inputs.attitudes_not_used_reason;
  block = scene.model;
  ASSERT_TRUE(PrepareGeoreference(GeoreferenceOptions(), scene.inputs, &block, &result).ok());
  ASSERT_EQ(result.inputs_not_used.size(), 1u);
  EXPECT_EQ(result.inputs_not_used[0], scene.inputs.positions_source +
                                           ": 2 attitudes (yaw pitch roll) read and not used (" +
                                           GeoTxtAttitudesNotUsedReason() + ")");
}

// A frames table's Omega/Phi/Kappa are read and not used beside a model: every row counted, the
// line worded as the geo.txt one (AttitudesNotUsedLine) with the frames table's reason.
TEST(Georeference, FramesTableAttitudesAreReportedAsReadAndNotUsed) {
  std::vector<FrameRecord> frames(3);
  for (size_t k = 0; k < frames.size(); ++k) {
    frames[k].raster = "img" + std::to_string(k) + ".jpg";
    frames[k].eo.set_center_in_ground(Eigen::Vector3d(500000.0 + 10.0 * k, 5300000.0, 600.0));
    frames[k].line = static_cast<int>(k) + 2;
  }
  frames[1].center_accuracy_m = Eigen::Vector3d(0.02, 0.02, 0.04);
  GeoreferenceInputs inputs;
  ASSERT_TRUE(SetPositionsFromFrames(frames, "EPSG:32632", "--crs", "frames.csv", &inputs).ok());
  ASSERT_EQ(inputs.positions.size(), 3u);
  EXPECT_EQ(inputs.positions_crs, "EPSG:32632");
  EXPECT_EQ(inputs.positions[1].position, Eigen::Vector3d(500010.0, 5300000.0, 600.0));
  EXPECT_EQ(inputs.positions[1].accuracy_m, frames[1].center_accuracy_m);
  EXPECT_EQ(inputs.positions[2].line, 4);
  EXPECT_EQ(inputs.attitudes_not_used, 3);
  EXPECT_EQ(AttitudesNotUsedLine(inputs),
            "frames.csv: 3 attitudes (Omega Phi Kappa) read and not used (" + FramesAttitudesNotUsedReason() + ")");
  // Positions of another source leave nothing of the frames table's count behind.
  SetPositionsFromGps({}, {}, "EPSG:4979", "GPS tags", &inputs);
  EXPECT_EQ(AttitudesNotUsedLine(inputs), "");
}

// Three frames rows at lines 2-4 with the given SRS values.
std::vector<FrameRecord> FramesWithSrs(const std::vector<std::string>& srs) {
  std::vector<FrameRecord> frames(srs.size());
  for (size_t k = 0; k < frames.size(); ++k) {
    frames[k].raster = "img" + std::to_string(k) + ".jpg";
    frames[k].eo.set_center_in_ground(Eigen::Vector3d(500000.0 + 10.0 * k, 5300000.0, 600.0));
    frames[k].srs = srs[k];
    frames[k].line = static_cast<int>(k) + 2;
  }
  return frames;
}

// The CRS of a frames table's positions: its rows' SRS, else the given CRS; one CRS for all rows,
// compared by what the texts name (SameCrs), every refusal naming the file, the line and SRS.
TEST(Georeference, FramesTablePositionsAreInTheirSrsOrTheGivenCrsAndInOneCrs) {
  const auto crs_of = [](const std::vector<std::string>& srs, const std::string& given) {
    GeoreferenceInputs inputs;
    const Status set = SetPositionsFromFrames(FramesWithSrs(srs), given, "--crs", "F.csv", &inputs);
    return set.ok() ? "ok " + inputs.positions_crs : set.message();
  };
  // The table's own SRS, without --crs; with an --crs that names the same CRS, however spelled.
  EXPECT_EQ(crs_of({"EPSG:32632", "EPSG:32632", "EPSG:32632"}, ""), "ok EPSG:32632");
  EXPECT_EQ(crs_of({"EPSG:32632", "WGS84 UTM 32N", "EPSG:32632"}, ""), "ok EPSG:32632");
  EXPECT_EQ(crs_of({"EPSG:32632", "EPSG:32632", "EPSG:32632"}, "WGS84 UTM 32N"), "ok WGS84 UTM 32N");
  // --crs for the rows without SRS: all of them, or some beside rows naming the same CRS.
  EXPECT_EQ(crs_of({"", "", ""}, "EPSG:32632"), "ok EPSG:32632");
  EXPECT_EQ(crs_of({"", "EPSG:32632", ""}, "EPSG:32632"), "ok EPSG:32632");
  // Refused: --crs naming another CRS than a row; two rows in two CRSs; a row without SRS beside
  // rows with one and no --crs; an SRS PROJ does not know; nothing naming the CRS.
  EXPECT_EQ(crs_of({"EPSG:32632", "EPSG:32632", "EPSG:32632"}, "EPSG:32633"),
            "F.csv:2: SRS: 'EPSG:32632' is another CRS than --crs=EPSG:32633: the positions of a frames table are "
            "in one CRS");
  EXPECT_EQ(crs_of({"", "", "EPSG:32632"}, "EPSG:32633"),
            "F.csv:4: SRS: 'EPSG:32632' is another CRS than --crs=EPSG:32633: the positions of a frames table are "
            "in one CRS");
  EXPECT_EQ(crs_of({"EPSG:32632", "EPSG:32632", "EPSG:32633"}, ""),
            "F.csv:4: SRS: 'EPSG:32633' is another CRS than line 2's 'EPSG:32632': the positions of a frames "
            "table are in one CRS");
  EXPECT_EQ(crs_of({"", "EPSG:32632", ""}, ""),
            "F.csv:2: SRS: empty, and line 3's 'EPSG:32632' names one: give every row's SRS, or --crs for the "
            "rows without one");
  EXPECT_EQ(crs_of({"EPSG:32632", "EPSG:999999", "EPSG:32632"}, "").rfind("F.csv:3: SRS: CRS 'EPSG:999999' is not known to PROJ (proj.db)", 0), 0u);
  EXPECT_EQ(crs_of({"EPSG:999999", "EPSG:32632", "EPSG:32632"}, "").rfind("F.csv:2: SRS: CRS 'EPSG:999999' is not known to PROJ (proj.db)", 0), 0u);
  EXPECT_EQ(crs_of({"", "", ""}, ""),
            "F.csv: no SRS column value and no --crs: the coordinate system of the positions is unknown");
  // A refusal leaves the inputs as they were.
  GeoreferenceInputs inputs;
  inputs.positions_crs = "EPSG:4979";
  EXPECT_FALSE(SetPositionsFromFrames(FramesWithSrs({"EPSG:32632", "EPSG:32633"}), "", "--crs", "F.csv", &inputs).ok());
  EXPECT_EQ(inputs.positions_crs, "EPSG:4979");
  EXPECT_TRUE(inputs.positions.empty());
}

// ------------------------------------------------------------------ positions without height

// The scene's positions, every `stride`-th one from `first` without height (z NaN, as a geo.txt
// line "image x y" gives it); returns how many.
int DropHeights(GeoreferenceInputs* inputs, int first, int stride) {
  int dropped = 0;
  for (size_t k = first; k < inputs->positions.size(); k += stride) {
    inputs->positions[k].has_height = false;
    inputs->positions[k].position.z() = std::numeric_limits<double>::quiet_NaN();
    ++dropped;
  }
  return dropped;
}

// Half the images without a height, with control: the model is aligned on the others and the
// control, the adjustment holds those images horizontally only, and every height comes out right
// (the vertical datum from the control and the other images). Their rows are two, not three: the
// redundancy is smaller by one per such image than with every height.
TEST(Georeference, PositionsWithoutHeightConstrainTheHorizontalAndTheHeightsComeOutRight) {
  GeoreferenceScene scene = MakeGeoreferenceScene(2.0);
  Block full_block;
  GeoreferenceResult full_result;
  BundleAdjustmentResult full_adjustment;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &full_block, &full_result, &full_adjustment));

  const int dropped = DropHeights(&scene.inputs, 0, 2);
  ASSERT_EQ(dropped, 12);
  Block block;
  GeoreferenceResult result;
  BundleAdjustmentResult adjustment;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &block, &result, &adjustment));
  EXPECT_EQ(result.positions_matched, 24);
  EXPECT_EQ(result.positions_without_height, 12);
  // Only the 12 positions with a height (and the control) are pairs of the similarity.
  int position_pairs = 0;
  for (const std::string& label : result.similarity_labels) position_pairs += label.rfind("position ", 0) == 0;
  EXPECT_EQ(position_pairs, 12);
  EXPECT_EQ(full_adjustment.summary.redundancy - adjustment.summary.redundancy, 12);
  // The data agree with their stated accuracies, as with every height.
  EXPECT_NEAR(adjustment.summary.sigma0, 1.0, 0.15);
  EXPECT_NEAR(adjustment.summary.sigma0, full_adjustment.summary.sigma0, 0.05);
  for (size_t i = 0; i < block.images.size(); ++i)
    EXPECT_EQ(block.images[i].center_height_measured, i % 2 != 0) << block.images[i].name;
  EXPECT_NE(adjustment.summary.datum_description.find("(12 without height)"), std::string::npos)
      << adjustment.summary.datum_description;
  EXPECT_TRUE(std::any_of(result.heights_notes.begin(), result.heights_notes.end(), [](const std::string& note) {
    return note.find(": 12 without height: only their horizontal position is used") != std::string::npos;
  }));

  // Heights of every image within the noise (GNSS 5 cm vertical, marks 0.3 px at 1.3 cm).
  std::vector<Eigen::Vector3d> centres;
  for (const BlockImage& image : block.images) centres.push_back(image.eo->center_in_ground());
  ASSERT_TRUE(result.frame.FromLocal("EPSG:4979", &centres).ok());
  ASSERT_TRUE(scene.truth_frame.ToLocal("EPSG:4979", &centres).ok());
  double worst_height_m = 0.0;
  for (size_t i = 0; i < centres.size(); i += 2)
    worst_height_m = std::max(worst_height_m, std::abs(centres[i].z() - scene.true_centres_local[i].z()));
  EXPECT_LT(worst_height_m, 0.05);
  EXPECT_LT(CentreRms(scene, block, result), 0.03);
  EXPECT_LT(result.check_after_adjustment.rmse_m.z(), 0.03);
  EXPECT_LT(result.check_after_adjustment.total_m, 0.03);
}

// The z of a position without height is never read: any value there gives the same measured
// centres, to the last bit, as NaN, and the same adjustment (to 1e-9: Ceres' threads sum in any
// order).
TEST(Georeference, TheZOfAPositionWithoutHeightIsNeverRead) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.5);
  DropHeights(&scene.inputs, 1, 3);
  Block a, b;
  GeoreferenceResult result_a, result_b;
  BundleAdjustmentResult adjustment_a, adjustment_b;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &a, &result_a, &adjustment_a));
  for (CameraPositionMeasurement& m : scene.inputs.positions)
    if (!m.has_height) m.position.z() = 1234.5;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &b, &result_b, &adjustment_b));
  for (size_t i = 0; i < a.images.size(); ++i) {
    EXPECT_LT((a.images[i].eo->parameters - b.images[i].eo->parameters).cwiseAbs().maxCoeff(), 1e-9)
        << a.images[i].name;
    EXPECT_EQ(*a.images[i].measured_center_m, *b.images[i].measured_center_m) << a.images[i].name;
  }
}

// Without control, the heights of the images that have one carry the vertical datum: all images
// come out right.
TEST(Georeference, WithoutControlTheOtherImagesHeightsCarryTheVertical) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  scene.inputs.control_points.clear();
  scene.inputs.control_marks.clear();
  DropHeights(&scene.inputs, 0, 3);
  Block block;
  GeoreferenceResult result;
  BundleAdjustmentResult adjustment;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &block, &result, &adjustment));
  EXPECT_EQ(result.positions_without_height, 8);
  EXPECT_LT(CentreRms(scene, block, result), 0.05);
}

// Camera positions alone: no control or check point has an error at either stage, so there is no
// RMSE (NaN: the JSON's null, Python's None, n/a on the page and the console), never a 0 that
// reads as no error.
TEST(Georeference, WithoutControlOrCheckPointsThereIsNoRmse) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  scene.inputs.control_points.clear();
  scene.inputs.control_marks.clear();
  Block block;
  GeoreferenceResult result;
  BundleAdjustmentResult adjustment;
  ASSERT_TRUE(GeoreferenceTheScene(scene, &block, &result, &adjustment));
  ASSERT_TRUE(result.evaluated);
  for (const GeoreferenceRmse* rmse : {&result.control_after_similarity, &result.check_after_similarity,
                                       &result.control_after_adjustment, &result.check_after_adjustment}) {
    EXPECT_EQ(rmse->count, 0);
    EXPECT_TRUE(std::isnan(rmse->total_m)) << rmse->total_m;
    EXPECT_TRUE(rmse->rmse_m.array().isNaN().all()) << rmse->rmse_m.transpose();
  }
}

// No height anywhere (and no control): refused before any work, saying why; too few positions
// with a height for the similarity: refused, counting those without.
TEST(Georeference, PositionsWithoutAnyHeightAreRefusedWithTheReason) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  scene.inputs.control_points.clear();
  scene.inputs.control_marks.clear();
  const Block before = scene.model;
  {
    GeoreferenceInputs none = scene.inputs;
    DropHeights(&none, 0, 1);
    Block block = before;
    GeoreferenceResult result;
    const Status status = PrepareGeoreference(GeoreferenceOptions(), none, &block, &result);
    EXPECT_EQ(status.message(), "geo.txt: none of its 24 camera positions has a height and there is no control "
                                "point: nothing ties the model's heights to the ground (give z, or control points)");
    EXPECT_EQ(block.images[0].eo->parameters, before.images[0].eo->parameters);
  }
  {
    GeoreferenceInputs two = scene.inputs;
    DropHeights(&two, 2, 1);  // images 0 and 1 keep their heights
    Block block = before;
    GeoreferenceResult result;
    const Status status = PrepareGeoreference(GeoreferenceOptions(), two, &block, &result);
    EXPECT_NE(status.message().find("(2 pairs of camera positions and control points intersected in the model; "
                                    "22 camera positions without height take no part in it): similarity: 2 pairs; "
                                    "at least 3 are needed"),
              std::string::npos)
        << status.message();
  }
}

// The local East-North-Up frame holds the earth's curvature in its coordinates: a camera with
// ApplyECC would have it counted twice, so the block is refused as it is, naming the camera.
TEST(Georeference, EarthCurvatureCorrectionIsRefusedInTheLocalFrame) {
  GeoreferenceScene scene = MakeGeoreferenceScene(0.0);
  Block block = scene.model;
  block.cameras[0].model = CameraModelType::kFrame;
  block.cameras[0].table.apply_ecc = true;
  ASSERT_GT(block.cameras[0].earth_curvature_radius_m(), 0.0);
  const Block before = block;
  GeoreferenceResult result;
  const Status status = PrepareGeoreference(GeoreferenceOptions(), scene.inputs, &block, &result);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind("camera '" + block.cameras[0].camera_id + "': ApplyECC: ", 0), 0u) << status.message();
  EXPECT_EQ(status.message().find('\n'), std::string::npos);
  EXPECT_EQ(block.images[0].eo->parameters, before.images[0].eo->parameters);
  EXPECT_EQ(block.points.size(), before.points.size());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
