// End-to-end tests of `photopose simulate`: the executable as a user runs it.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/io/colmap.h"
#include "core/io/opensfm.h"
#include "core/io/tables.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_scene.h"
#include "tests/tools/cli_test_util.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::CliRun;
using testing::CountLines;
using testing::ReadFile;
using testing::ReadFrames;
using testing::RunCli;
using testing::ScratchDir;

// Numbers are written as the shortest text that reads back exactly (core/io/csv.cc); angles go
// through degrees and back (~1e-15 rad). 1e-9 px / m / rad is far above both.
constexpr double kWrittenTolerance = 1e-9;

TEST(SimulateCommand, SameSeedSameDatasetAndTruthKeptApart) {
  const std::string dir = ScratchDir();
  ASSERT_EQ(RunCli("simulate --scenario=nadir --seed=5 --out_dir=" + dir + "/a", dir).exit_code, 0);
  ASSERT_EQ(RunCli("simulate --scenario=nadir --seed=5 --out_dir=" + dir + "/b", dir).exit_code, 0);
  ASSERT_EQ(RunCli("simulate --scenario=nadir --seed=6 --out_dir=" + dir + "/c", dir).exit_code, 0);
  EXPECT_EQ(ReadFile(dir + "/a/marks.csv"), ReadFile(dir + "/b/marks.csv"));
  EXPECT_NE(ReadFile(dir + "/a/marks.csv"), ReadFile(dir + "/c/marks.csv"));
  for (const char* file : {"cameras.csv", "points.csv", "marks.csv", "frames_approx.csv",
                           "truth/frames.csv", "truth/outliers.csv"})
    EXPECT_TRUE(std::filesystem::exists(dir + "/a/" + file)) << file;
  EXPECT_EQ(RunCli("simulate --scenario=mars --out_dir=" + dir, dir).exit_code, 2);
  EXPECT_EQ(RunCli("simulate --outlier_fraction=1.5 --out_dir=" + dir, dir).exit_code, 2);
}

TEST(SimulateCommand, WritesTheLibrarysSceneForTheSameFlags) {
  const std::string dir = ScratchDir();
  const CliRun run = RunCli(
      "simulate --scenario=oblique --seed=11 --noise_px=0.4 "
      "--outlier_fraction=0.2 --control_points=12 --check_points=3 --out_dir=" +
          dir + "/d",
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  SyntheticSceneOptions options;
  options.scenario = Scenario::kOblique;
  options.seed = 11;
  options.noise_px = 0.4;
  options.outlier_fraction = 0.2;
  options.num_control_points = 12;
  options.num_check_points = 3;
  SyntheticScene scene;
  ASSERT_TRUE(MakeSyntheticScene(options, &scene).ok());
  // One image sees its 12 + 3 points once each.
  ASSERT_EQ(scene.marks.size(), 15u);
  EXPECT_NE(run.out.find("1 images, 15 points, 15 marks"), std::string::npos) << run.out;
  // The closing line names every file written.
  EXPECT_NE(run.out.find("; wrote " + dir + "/d: cameras.csv, points.csv, marks.csv, "
                         "frames_approx.csv, truth/frames.csv, truth/outliers.csv\n"),
            std::string::npos)
      << run.out;

  std::vector<ImageMark> marks;
  ASSERT_TRUE(ReadImageMarks(dir + "/d/marks.csv", &marks).ok());
  ASSERT_EQ(marks.size(), scene.marks.size());
  for (size_t i = 0; i < marks.size(); ++i) {
    EXPECT_EQ(marks[i].raster, scene.marks[i].raster);
    EXPECT_EQ(marks[i].point_id, scene.marks[i].point_id);
    ASSERT_TRUE(marks[i].column_row.has_value());
    EXPECT_LT((*marks[i].column_row - *scene.marks[i].column_row).norm(), kWrittenTolerance) << i;
  }
  const auto truth = ReadFrames(dir + "/d/truth/frames.csv");
  const auto start = ReadFrames(dir + "/d/frames_approx.csv");
  const std::string& raster = scene.true_frames[0].raster;
  ASSERT_EQ(truth.size(), 1u);
  ASSERT_EQ(start.size(), 1u);
  ASSERT_EQ(truth.count(raster), 1u);
  ASSERT_EQ(start.count(raster), 1u);
  EXPECT_LT((truth.at(raster).eo.parameters - scene.true_frames[0].eo.parameters).norm(),
            kWrittenTolerance);
  EXPECT_LT((start.at(raster).eo.parameters - scene.approximate_frames[0].eo.parameters).norm(),
            kWrittenTolerance);
  // truth/outliers.csv: a header and one row per mark, Outlier as the scene drew it (20 % of 15
  // is 3).
  const std::string outliers = ReadFile(dir + "/d/truth/outliers.csv");
  ASSERT_EQ(CountLines(outliers), 16);
  int flagged = 0;
  for (size_t i = 0; i < scene.marks.size(); ++i) {
    const std::string row = scene.marks[i].raster + "," + scene.marks[i].point_id + "," +
                            (scene.mark_is_outlier[i] ? "1" : "0") + "\n";
    EXPECT_NE(outliers.find(row), std::string::npos) << row;
    flagged += scene.mark_is_outlier[i];
  }
  EXPECT_EQ(flagged, 3);
}

TEST(SimulateCommand, TheRotationFlagChangesTheWordsNotThePoses) {
  const std::string dir = ScratchDir();
  ASSERT_EQ(
      RunCli("simulate --scenario=oblique --seed=3 --out_dir=" + dir + "/seed", dir).exit_code, 0);
  ASSERT_EQ(
      RunCli("simulate --scenario=oblique --seed=3 --rotation=opk --out_dir=" + dir + "/opk", dir)
          .exit_code,
      0);
  // Written in two conventions, the angles differ; read each in its own, the pose is the same.
  EXPECT_NE(ReadFile(dir + "/seed/truth/frames.csv"), ReadFile(dir + "/opk/truth/frames.csv"));
  const auto seed = ReadFrames(dir + "/seed/truth/frames.csv");
  const auto opk = ReadFrames(dir + "/opk/truth/frames.csv", RotationConvention::kOpk);
  ASSERT_EQ(seed.size(), 1u);
  ASSERT_EQ(opk.size(), 1u);
  const Eigen::Vector3d seed_angles = seed.begin()->second.eo.angles_seed_rad();
  const Eigen::Vector3d opk_angles = opk.begin()->second.eo.angles_seed_rad();
  EXPECT_LT((RotationFromAngles(RotationConvention::kSeed, seed_angles) -
             RotationFromAngles(RotationConvention::kSeed, opk_angles))
                .cwiseAbs()
                .maxCoeff(),
            kWrittenTolerance);
  EXPECT_EQ(RunCli("simulate --rotation=xyz --out_dir=" + dir + "/x", dir).exit_code, 2);
}

TEST(SimulateCommand, BlockScenarioWritesTheBlockItsTruthAndColmap) {
  const std::string dir = ScratchDir();
  const CliRun run = RunCli(
      "simulate --scenario=block --lines=2 --images_per_line=3 --seed=4 "
      "--tie_blunders=2 --colmap --out_dir=" +
          dir + "/b",
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // 2 lines x 3 images; two tie blunders.
  EXPECT_NE(run.out.find("6 images"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find(" 2 blunders"), std::string::npos) << run.out;
  // The closing line names every file written.
  EXPECT_NE(run.out.find("; wrote " + dir + "/b: cameras.csv, points.csv, marks.csv, frames.csv, "
                         "truth/frames.csv, truth/points.csv, truth/blunders.csv, "
                         "colmap/cameras.txt, colmap/images.txt, colmap/points3D.txt\n"),
            std::string::npos)
      << run.out;
  EXPECT_EQ(ReadFrames(dir + "/b/truth/frames.csv").size(), 6u);
  // The measured positions (GNSS, on by default) with their accuracy, one row per image.
  const auto measured = ReadFrames(dir + "/b/frames.csv");
  ASSERT_EQ(measured.size(), 6u);
  for (const auto& [raster, frame] : measured)
    EXPECT_TRUE(frame.center_accuracy_m.has_value()) << raster;
  // truth/blunders.csv: a header and one row per blunder.
  EXPECT_EQ(CountLines(ReadFile(dir + "/b/truth/blunders.csv")), 3);
  for (const char* file : {"cameras.txt", "images.txt", "points3D.txt"})
    EXPECT_TRUE(std::filesystem::exists(dir + "/b/colmap/" + file)) << file;
}

// --georeferenced: every file of the scene, named in the closing line with the check points; the
// three models are one model, and the measurements are in the CRSs their files name.
TEST(SimulateCommand, GeoreferencedBlockWritesTheModelThreeWaysAndItsMeasurementsInTheirCrs) {
  const std::string dir = ScratchDir();
  const CliRun run = RunCli("simulate --scenario=block --lines=2 --images_per_line=3 --georeferenced --dome=1.5 --out_dir=" +
                                dir + "/b",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("; georeferenced: model domed by 1.5 m, GNSS in EPSG:4326, control in EPSG:32632, check points GCP_"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("colmap/cameras.txt, colmap/images.txt, colmap/points3D.txt, colmap_bin/cameras.bin, "
                         "colmap_bin/images.bin, colmap_bin/points3D.bin, opensfm/reconstruction.json, opensfm/tracks.csv, "
                         "geo.txt, gcp_list.txt, gcp_points.csv, gcp_marks.csv\n"),
            std::string::npos)
      << run.out;
  Block text, binary, opensfm;
  ASSERT_TRUE(ReadColmapModel(dir + "/b/colmap", &text).ok());
  ASSERT_TRUE(ReadColmapModel(dir + "/b/colmap_bin", &binary).ok());
  const Status read = ReadOpenSfmReconstruction(dir + "/b/opensfm/reconstruction.json", &opensfm);
  ASSERT_TRUE(read.ok()) << read.message();
  ASSERT_EQ(text.images.size(), 6u);
  ASSERT_EQ(binary.images.size(), 6u);
  ASSERT_EQ(opensfm.images.size(), 6u);
  ASSERT_EQ(binary.points.size(), text.points.size());
  ASSERT_EQ(opensfm.points.size(), text.points.size());
  std::map<std::string, Eigen::Vector3d> opensfm_centres;
  for (const BlockImage& image : opensfm.images) opensfm_centres[image.name] = image.eo->center_in_ground();
  for (size_t i = 0; i < text.images.size(); ++i) {
    EXPECT_EQ(binary.images[i].eo->center_in_ground(), text.images[i].eo->center_in_ground());
    ASSERT_EQ(opensfm_centres.count(text.images[i].name), 1u) << text.images[i].name;
    EXPECT_NEAR((opensfm_centres[text.images[i].name] - text.images[i].eo->center_in_ground()).norm(), 0.0,
                kWrittenTolerance);
  }
  // Not the block's frame: the model is scaled by 0.05 (the images are ~20 m apart in the block).
  const auto truth = ReadFrames(dir + "/b/truth/frames.csv");
  const double model_m = (text.images[0].eo->center_in_ground() - text.images[1].eo->center_in_ground()).norm();
  const double true_m = (truth.at(text.images[0].name).eo.center_in_ground() - truth.at(text.images[1].name).eo.center_in_ground()).norm();
  EXPECT_NEAR(model_m / true_m, 0.05, 0.002);
  GeoTxt geo;
  ASSERT_TRUE(ReadGeoTxt(dir + "/b/geo.txt", &geo).ok());
  EXPECT_EQ(geo.crs, "EPSG:4326");
  ASSERT_EQ(geo.records.size(), 6u);
  EXPECT_NEAR(geo.records[0].position.x(), 11.2, 0.01);  // longitude first
  EXPECT_NEAR(geo.records[0].position.y(), 47.8, 0.01);
  EXPECT_TRUE(geo.records[0].horizontal_accuracy_m.has_value());
  GcpList gcp;
  ASSERT_TRUE(ReadGcpList(dir + "/b/gcp_list.txt", &gcp).ok());
  EXPECT_EQ(gcp.crs, "EPSG:32632");
  std::vector<GroundPoint> points;
  ASSERT_TRUE(ReadGroundPoints(dir + "/b/gcp_points.csv", &points).ok());
  ASSERT_EQ(points.size(), gcp.points.size());
  std::vector<ImageMark> marks;
  ASSERT_TRUE(ReadImageMarks(dir + "/b/gcp_marks.csv", &marks).ok());
  EXPECT_EQ(marks.size(), gcp.marks.size());
  for (size_t k = 0; k < points.size(); ++k) {
    EXPECT_EQ(points[k].point_id, gcp.points[k].point_id);
    EXPECT_EQ(points[k].position, gcp.points[k].position);
    EXPECT_GT(points[k].position.x(), 600000.0);  // UTM 32N easting at 11.2 E
  }
}

TEST(SimulateCommand, BadUsageIsRefusedWithItsReason) {
  const std::string dir = ScratchDir();
  struct Refusal {
    std::string flags;
    std::string reason;
  };
  for (const Refusal& refusal : std::vector<Refusal>{
           {"--scenario=nadir", "--out_dir is required"},
           {"--scenario=mars --out_dir=" + dir + "/x", "--scenario must be"},
           {"--scenario=block --outlier_fraction=0.1 --out_dir=" + dir + "/x",
            "--outlier_fraction is for the single-image scenarios"},
           {"--scenario=block --gnss_blunders=1 --nognss --out_dir=" + dir + "/x",
            "--gnss_blunders needs --gnss"},
           {"--scenario=oblique --tie_points=50 --out_dir=" + dir + "/x",
            "--tie_points is for --scenario=block, not oblique"},
           {"--scenario=block --benchmark_block --forward_overlap=0.7 --out_dir=" + dir + "/x",
            "--forward_overlap does not apply to --benchmark_block"},
           {"--scenario=block --benchmark_block --tie_blunders=3 --out_dir=" + dir + "/x",
            "--tie_blunders does not apply to --benchmark_block"},
           {"--scenario=block --dome=2 --out_dir=" + dir + "/x",
            "--dome bends the model of --georeferenced; without it no model is bent"},
           {"--scenario=block --georeferenced --nognss --out_dir=" + dir + "/x",
            "--georeferenced needs --gnss (geo.txt holds the measured camera centres)"},
           {"--scenario=nadir --georeferenced --out_dir=" + dir + "/x",
            "--georeferenced is for --scenario=block, not nadir"},
       }) {
    const CliRun run = RunCli("simulate " + refusal.flags, dir);
    EXPECT_EQ(run.exit_code, 2) << refusal.flags;
    EXPECT_NE(run.err.find(refusal.reason), std::string::npos) << refusal.flags << ": " << run.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/x")) << refusal.flags;
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
