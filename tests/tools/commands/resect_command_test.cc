// End-to-end tests of `photopose resect` (datasets made with `photopose simulate`): the executable
// as a user runs it.
#include <gtest/gtest.h>

#include <array>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <regex>
#include <tuple>
#include <nlohmann/json.hpp>

#include "core/io/csv.h"
#include "core/rotation.h"
#include "core/io/tables.h"
#include "tests/tools/cli_test_util.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::CliRun;
using testing::CountLines;
using testing::ReadFile;
using testing::ReadFrames;
using testing::RunCli;
using testing::ScratchDir;
using testing::SharedDataPath;
using testing::SourcePath;
using testing::WriteFile;

std::string ExampleArgs() {
  return "--cameras=" + SourcePath("examples/cameras.csv") + " --points=" +
         SourcePath("examples/points.csv") + " --marks=" + SourcePath("examples/marks.csv");
}

TEST(ResectCommand, ResectsTheBundledExampleToItsTruth) {
  const std::string dir = ScratchDir();
  const CliRun run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/frames.csv --report=" +
                                dir + "/report.json",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto solved = ReadFrames(dir + "/frames.csv");
  const auto truth = ReadFrames(SourcePath("examples/truth/frames.csv"));
  ASSERT_EQ(solved.size(), truth.size());
  for (const auto& [raster, frame] : solved) {
    // 0.5 px noise at 100 m gives poses within about a centimetre and 0.005 deg of the truth;
    // 5 cm and 0.02 deg leave room for the geometry of the edge images.
    const Vector6d error = frame.eo.parameters - truth.at(raster).eo.parameters;
    for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(error[k]), 0.05) << raster;
    for (int k = 3; k < 6; ++k) EXPECT_LT(std::abs(error[k]), DegreesToRadians(0.02)) << raster;
  }
  // One line per image on stdout, and the report has every mark's residual and flag.
  EXPECT_EQ(CountLines(run.out), static_cast<int>(truth.size()));
  const auto report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  ASSERT_EQ(report["images"].size(), truth.size());
  EXPECT_EQ(report["options"]["solver"], "ceres");
  for (const auto& image : report["images"]) {
    EXPECT_TRUE(image["success"].get<bool>());
    EXPECT_GT(image["marks"].size(), 10u);
    EXPECT_NEAR(image["sigma0"].get<double>(), 1.0, 0.35);  // marks carry Accuracy = noise
  }
}

TEST(ResectCommand, PixelCentreOriginGivesTheSameSolutionAndCheckResiduals) {
  const std::string dir = ScratchDir();
  // The example's marks re-expressed with (0,0) at the centre of the first pixel.
  std::vector<ImageMark> marks;
  ASSERT_TRUE(ReadImageMarks(SourcePath("examples/marks.csv"), &marks).ok());
  for (auto& mark : marks) *mark.column_row -= Eigen::Vector2d(0.5, 0.5);
  ASSERT_TRUE(WriteImageMarks(dir + "/marks.csv", marks).ok());
  const std::string common = "resect --cameras=" + SourcePath("examples/cameras.csv") + " --points=" +
                             SourcePath("examples/points.csv");
  ASSERT_EQ(RunCli(common + " --marks=" + SourcePath("examples/marks.csv") + " --out=" + dir +
                       "/a.csv --report=" + dir + "/a.json",
                   dir).exit_code, 0);
  ASSERT_EQ(RunCli(common + " --marks=" + dir + "/marks.csv --pixel_center_origin --out=" + dir +
                       "/b.csv --report=" + dir + "/b.json",
                   dir).exit_code, 0);
  const auto a = nlohmann::json::parse(ReadFile(dir + "/a.json"))["images"];
  const auto b = nlohmann::json::parse(ReadFile(dir + "/b.json"))["images"];
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a[i]["pose"]["X"].get<double>(), b[i]["pose"]["X"].get<double>(), 1e-6);
    // Every check point with its own residual, the same in both.
    ASSERT_GT(a[i]["check_points"].size(), 0u);
    ASSERT_EQ(a[i]["check_points"].size(), b[i]["check_points"].size());
    for (size_t k = 0; k < a[i]["check_points"].size(); ++k) {
      const auto& ca = a[i]["check_points"][k];
      EXPECT_EQ(ca["point_id"], b[i]["check_points"][k]["point_id"]);
      EXPECT_EQ(ca["unit"], "px");
      EXPECT_NEAR(ca["residual"].get<double>(), b[i]["check_points"][k]["residual"].get<double>(),
                  1e-6);
    }
  }
}

// The example's marks with rows counted up from the bottom edge (Row' = NRows - Row, NRows 3648):
// with --pixel_rows_up the same poses as the original; without it, other poses or none.
TEST(ResectCommand, RowsCountedUpGiveTheSamePosesWithPixelRowsUp) {
  const std::string dir = ScratchDir();
  const std::string down_marks = testing::WriteExampleMarksWithRowsUp(dir);
  const std::string common = "resect --cameras=" + SourcePath("examples/cameras.csv") +
                             " --points=" + SourcePath("examples/points.csv");
  CliRun run = RunCli(common + " --marks=" + down_marks + " --out=" + dir +
                          "/down.csv --report=" + dir + "/down.json",
                      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = RunCli(common + " --marks=" + dir + "/marks_up.csv --pixel_rows_up --out=" + dir +
                   "/up.csv --report=" + dir + "/up.json",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto down = nlohmann::json::parse(ReadFile(dir + "/down.json"));
  const auto up = nlohmann::json::parse(ReadFile(dir + "/up.json"));
  EXPECT_EQ(up["options"]["pixel_rows"], "up");
  EXPECT_EQ(down["options"]["pixel_rows"], "down");
  ASSERT_EQ(down["images"].size(), up["images"].size());
  for (size_t i = 0; i < up["images"].size(); ++i) {
    const auto& a = down["images"][i]["pose"];
    const auto& b = up["images"][i]["pose"];
    for (const char* key : {"X", "Y", "Z", "omega_deg", "phi_deg", "kappa_deg"})
      EXPECT_NEAR(a[key].get<double>(), b[key].get<double>(), 1e-9) << key;
    // Residuals are on the image plane (x right, y up) either way.
    EXPECT_NEAR(down["images"][i]["marks"][0]["residual_y"].get<double>(),
                up["images"][i]["marks"][0]["residual_y"].get<double>(), 1e-9);
  }
  // Read as rows counted down, the turned marks give other poses (or none).
  run = RunCli(common + " --marks=" + dir + "/marks_up.csv --out=" + dir + "/wrong.csv --report=" +
                   dir + "/wrong.json",
               dir);
  // Some images unsolved, or none (and then nothing is written).
  if (std::filesystem::exists(dir + "/wrong.json")) {
    const auto wrong = nlohmann::json::parse(ReadFile(dir + "/wrong.json"));
    int same = 0;
    for (size_t i = 0; i < wrong["images"].size(); ++i) {
      if (!wrong["images"][i]["success"].get<bool>()) continue;
      same += std::abs(wrong["images"][i]["pose"]["X"].get<double>() -
                       down["images"][i]["pose"]["X"].get<double>()) < 1.0;
    }
    EXPECT_EQ(same, 0);
  }
  // A gcp_list counts rows down (OpenDroneMap's definition): refused with the flag.
  run = RunCli("resect --cameras=" + SourcePath("examples/cameras.csv") + " --gcp_list=" + dir +
                   "/gcp_list.txt --pixel_rows_up --out=" + dir + "/x.csv",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--pixel_rows_up: a gcp_list.txt counts pixel rows down"),
            std::string::npos)
      << run.err;
}

TEST(ResectCommand, OutlierFlagsMatchTheSimulatedTruth) {
  const std::string dir = ScratchDir();
  const CliRun run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/frames.csv --report=" +
                                dir + "/report.json",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // truth/outliers.csv: Raster,PointID,Outlier.
  std::map<std::pair<std::string, std::string>, bool> outlier;
  std::istringstream truth(ReadFile(SourcePath("examples/truth/outliers.csv")));
  std::string line;
  std::getline(truth, line);
  while (std::getline(truth, line)) {
    const size_t a = line.find(','), b = line.rfind(',');
    outlier[{line.substr(0, a), line.substr(a + 1, b - a - 1)}] = line.substr(b + 1) == "1";
  }
  const auto report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  int agree = 0, total = 0, missed_outliers = 0;
  for (const auto& image : report["images"]) {
    for (const auto& mark : image["marks"]) {
      const bool is_outlier = outlier.at({image["raster"], mark["point_id"]});
      const bool flagged = !mark["inlier"].get<bool>();
      agree += is_outlier == flagged;
      missed_outliers += is_outlier && !flagged;
      ++total;
    }
  }
  EXPECT_EQ(missed_outliers, 0);
  // A good mark lies beyond the 99.9 % threshold (3.72 sigma) once in a thousand.
  EXPECT_GE(agree, total - 3);
}

// A --frames start with omega 90 degrees off: control points behind the camera there; the
// consensus start solves the image, and the console and the report say so.
TEST(ResectCommand, AFarFramesStartFallsBackToTheConsensusAndSaysSo) {
  const std::string dir = ScratchDir();
  const CliRun simulated =
      RunCli("simulate --scenario=oblique --seed=3 --noise_px=0.3 --out_dir=" + dir, dir);
  ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(dir + "/frames_approx.csv", FramesTableOptions(), &frames).ok());
  ASSERT_EQ(frames.size(), 1u);
  frames[0].eo.parameters[3] += M_PI / 2;  // omega 90 degrees off
  ASSERT_TRUE(WriteFramesTable(dir + "/far.csv", FramesTableOptions(), frames).ok());
  const CliRun run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir +
                                "/points.csv --marks=" + dir + "/marks.csv --frames=" + dir +
                                "/far.csv --out=" + dir + "/out.csv --report=" + dir +
                                "/report.json",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(consensus, --frames start abandoned)"), std::string::npos) << run.out;
  EXPECT_NE(run.err.find(": warning: approximate pose abandoned: from it the image was not solved ("),
            std::string::npos)
      << run.err;
  const auto report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  ASSERT_EQ(report["images"].size(), 1u);
  const auto& image = report["images"][0];
  EXPECT_EQ(image["initial_values"], "consensus_after_frames");
  EXPECT_FALSE(image["frames_start_abandoned"].get<std::string>().empty());
  const auto truth = ReadFrames(dir + "/truth/frames.csv");
  const auto solved = ReadFrames(dir + "/out.csv");
  ASSERT_EQ(solved.size(), 1u);
  const Vector6d error =
      solved.begin()->second.eo.parameters - truth.at(solved.begin()->first).eo.parameters;
  EXPECT_LT(error.head<3>().norm(), 0.5);
}

// SIGINT or SIGTERM while the images are resected (after the progress line): the batch stops,
// nothing is written (the old output stays, no report, no temporary), exit 128 + the signal.
// The bundled example's twelve images repeated under other names make a batch of several seconds
// on one thread.
TEST(ResectCommand, ASignalCancelsTheRunAndNothingIsWritten) {
  constexpr int kCopies = 400;  // 4800 images of ~70 marks
  std::vector<ImageMark> example;
  ASSERT_TRUE(ReadImageMarks(SourcePath("examples/marks.csv"), &example).ok());
  for (const auto& [signal_number, exit_code, name] :
       {std::tuple<int, int, const char*>{SIGINT, 130, "SIGINT"}, {SIGTERM, 143, "SIGTERM"}}) {
    SCOPED_TRACE(name);
    const std::string dir = ScratchDir() + "/" + name;
    std::filesystem::create_directories(dir);
    std::vector<ImageMark> marks;
    marks.reserve(example.size() * kCopies);
    for (int copy = 0; copy < kCopies; ++copy) {
      for (ImageMark mark : example) {
        mark.raster += "_" + std::to_string(copy);
        marks.push_back(std::move(mark));
      }
    }
    ASSERT_TRUE(WriteImageMarks(dir + "/marks.csv", marks).ok());
    const std::string out = dir + "/frames.csv";
    WriteFile(out, "old output\n");
    const CliRun run = testing::RunCliAndSignal(
        {"resect", "--cameras=" + SourcePath("examples/cameras.csv"),
         "--points=" + SourcePath("examples/points.csv"), "--marks=" + dir + "/marks.csv",
         "--out=" + out, "--report=" + dir + "/report.json", "--threads=1"},
        dir, " images (", signal_number);
    EXPECT_EQ(run.exit_code, exit_code) << run.err;
    const std::regex cancelled(std::string("photopose resect: cancelled by ") + name +
                               " while resecting; nothing written\n$");
    EXPECT_TRUE(std::regex_search(run.err, cancelled)) << run.err.substr(run.err.size() > 2000 ? run.err.size() - 2000 : 0);
    EXPECT_EQ(ReadFile(out), "old output\n");
    EXPECT_FALSE(std::filesystem::exists(dir + "/report.json"));
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      EXPECT_NE(entry.path().filename().string().front(), '.') << "left behind: " << entry.path();
    EXPECT_EQ(run.out.find("wrote"), std::string::npos);
  }
}

TEST(ResectCommand, EverySolverAndJacobianAgreesFromApproximateFrames) {
  const std::string dir = ScratchDir();
  std::map<std::string, std::map<std::string, FrameRecord>> results;
  for (const std::string variant : {"--solver=ceres --jacobian=analytic --loss=none",
                                    "--solver=ceres --jacobian=autodiff --loss=none",
                                    "--solver=taylor", "--solver=taylor_as_printed"}) {
    // Without gross errors in the data: plain least squares everywhere.
    const CliRun run = RunCli("simulate --scenario=oblique --seed=3 --noise_px=0.3 --out_dir=" + dir, dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const CliRun resect = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir +
                                     "/points.csv --marks=" + dir + "/marks.csv --frames=" + dir +
                                     "/frames_approx.csv --out=" + dir + "/out.csv " + variant,
                                 dir);
    ASSERT_EQ(resect.exit_code, 0) << variant << ": " << resect.err;
    EXPECT_NE(resect.out.find("(from --frames)"), std::string::npos);
    results[variant] = ReadFrames(dir + "/out.csv");
  }
  // The oblique scenario is one image; every variant wrote it.
  constexpr char kReferenceVariant[] = "--solver=ceres --jacobian=analytic --loss=none";
  ASSERT_EQ(results.size(), 4u);
  for (const auto& [variant, frames] : results) ASSERT_EQ(frames.size(), 1u) << variant;
  const FrameRecord& solved = results.at(kReferenceVariant).begin()->second;
  const Vector6d& reference = solved.eo.parameters;
  // The reference itself is a solution, not the approximate frame handed in: near the truth
  // (0.3 px noise on one oblique image: centimetres), far from the start (up to 5 m and 2 degrees
  // off per axis: the simulate defaults).
  const auto truth = ReadFrames(dir + "/truth/frames.csv");
  const auto start = ReadFrames(dir + "/frames_approx.csv");
  ASSERT_EQ(truth.count(solved.raster), 1u);
  ASSERT_EQ(start.count(solved.raster), 1u);
  const Vector6d error = reference - truth.at(solved.raster).eo.parameters;
  EXPECT_LT(error.head<3>().norm(), 0.5);
  EXPECT_LT(error.tail<3>().norm(), DegreesToRadians(0.1));
  EXPECT_GT((reference - start.at(solved.raster).eo.parameters).head<3>().norm(),
            10.0 * error.head<3>().norm());
  for (const auto& [variant, frames] : results) {
    if (variant == kReferenceVariant) continue;
    const Vector6d difference = frames.begin()->second.eo.parameters - reference;
    if (variant == "--solver=taylor_as_printed") {
      // The printed eq. 21 biases the solution on noisy data; it must still converge nearby.
      EXPECT_LT(difference.head<3>().norm(), 5.0) << variant;
    } else {
      EXPECT_LT(difference.head<3>().norm(), 1e-6) << variant;
      EXPECT_LT(difference.tail<3>().norm(), 1e-9) << variant;
    }
  }
}

TEST(ResectCommand, DroneSprMatchesTheReferenceFromPixelsWithoutApproximateValues) {
  const std::string dir = ScratchDir();
  // The camera of ../shared/data/drone_spr/README.txt: 7952 x 5304 px, 4.4 um, c = 32.784 mm,
  // xp = -0.094217 mm, yp = -0.033517 mm, no distortion; picks are Column/Row from the top-left.
  WriteFile(dir + "/cameras.csv",
            "CameraID,FocalLength,PrincipalX,PrincipalY,PixelSize,NColumns,NRows\n"
            "DSC,32784,-94.217,-33.517,4.4,7952,5304\n");
  std::istringstream gcps(ReadFile(SharedDataPath("drone_spr/spr_gcp_inputs.csv")));
  std::string line, points = "PointID,X,Y,Z\n", marks = "Raster,PointID,Column,Row\n";
  std::getline(gcps, line);
  while (std::getline(gcps, line)) {
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) f.push_back(cell);
    ASSERT_EQ(f.size(), 7u);
    points += f[0] + "," + f[1] + "," + f[2] + "," + f[3] + "\n";
    marks += f[4] + "," + f[0] + "," + f[5] + "," + f[6] + "\n";
  }
  WriteFile(dir + "/points.csv", points);
  WriteFile(dir + "/marks.csv", marks);
  // No Accuracy: the default 1 px. The nine good picks of the eleven fit to 3.7 px only, so at
  // 1 px no set of them fits one pose alone (two six-mark sets fit poses 1.1 m apart): the image is
  // ambiguous, exit 1, the message names the flag to state another accuracy, and nothing is
  // written (an older frames table stays as it was).
  WriteFile(dir + "/frames.csv", "older\n");
  CliRun run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir +
                          "/points.csv --marks=" + dir + "/marks.csv --out=" + dir +
                          "/frames.csv --report=" + dir + "/report.json --rotation=opk",
                      dir);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("DSC00371: not resected: ambiguous: two poses fit"), std::string::npos)
      << run.err;
  EXPECT_NE(run.err.find("--default_accuracy"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("no image was resected"), std::string::npos) << run.err;
  EXPECT_EQ(ReadFile(dir + "/frames.csv"), "older\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/report.json"));
  // Stated at 4 px, the accuracy of the picks: two of the eleven are blunders, S01 (60 px) and
  // S07 (180 px from the pose of the others); the other nine fit to 3.7 px (sigma0 0.93 of 4 px).
  run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir + "/points.csv --marks=" +
                   dir + "/marks.csv --out=" + dir + "/frames.csv --report=" + dir +
                   "/report.json --rotation=opk --default_accuracy=4",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  const auto& image = report["images"][0];
  EXPECT_EQ(image["accuracy"], "stated");
  EXPECT_EQ(image["sigma0_unit"], "");
  EXPECT_NEAR(image["sigma0"].get<double>(), 3.73 / 4.0, 0.02);
  for (const auto& mark : image["marks"]) {
    const bool blunder = mark["point_id"] == "S01" || mark["point_id"] == "S07";
    EXPECT_EQ(mark["status"], blunder ? "outlier" : "accepted") << mark["point_id"];
    // Every accepted mark has its minimal detectable blunder (px) and pose shift in the report.
    if (!blunder) EXPECT_GT(mark["mdb"].get<double>(), 4.0) << mark["point_id"];
    if (!blunder) EXPECT_GT(mark["pose_shift_sigmas"].get<double>(), 0.0) << mark["point_id"];
  }
  // The pose is the least squares of the nine: the same as resecting them alone.
  std::string nine = "Raster,PointID,Column,Row\n";
  std::istringstream all_marks(marks);
  std::getline(all_marks, line);
  while (std::getline(all_marks, line))
    if (line.find(",S01,") == std::string::npos && line.find(",S07,") == std::string::npos)
      nine += line + "\n";
  WriteFile(dir + "/nine.csv", nine);
  run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir + "/points.csv --marks=" +
                   dir + "/nine.csv --out=" + dir + "/nine_frames.csv --rotation=opk "
                   "--default_accuracy=4",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const ExteriorOrientation eo = ReadFrames(dir + "/frames.csv", RotationConvention::kOpk).at("DSC00371").eo;
  const ExteriorOrientation nine_eo =
      ReadFrames(dir + "/nine_frames.csv", RotationConvention::kOpk).at("DSC00371").eo;
  EXPECT_LT((eo.parameters - nine_eo.parameters).head<3>().norm(), 1e-6);
  // Stating an accuracy loose enough to keep every pick (100 px) reproduces the repository's own
  // least squares of all eleven (final_eop.csv, opk), its sigma0 of ~32 px now 0.324 of 100 px.
  run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir + "/points.csv --marks=" +
                   dir + "/marks.csv --out=" + dir + "/all.csv --rotation=opk --default_accuracy=100",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto frames = ReadFrames(dir + "/all.csv", RotationConvention::kOpk);
  ASSERT_EQ(frames.count("DSC00371"), 1u);
  const ExteriorOrientation& reference = frames.at("DSC00371").eo;
  const Eigen::Vector3d opk = AnglesFromRotation(
      RotationConvention::kOpk, RotationFromAngles(RotationConvention::kSeed, reference.angles_seed_rad()));
  EXPECT_NEAR(reference.parameters[0], 318034.9733757887, 0.01);
  EXPECT_NEAR(reference.parameters[1], 4159882.531985079, 0.01);
  EXPECT_NEAR(reference.parameters[2], 198.38109474065996, 0.01);
  EXPECT_NEAR(RadiansToDegrees(opk[0]), 2.130102727226471, 1e-5);
  EXPECT_NEAR(RadiansToDegrees(opk[1]), -2.2006723326227857, 1e-5);
  EXPECT_NEAR(RadiansToDegrees(opk[2]), 14.234848004461039, 1e-5);
  EXPECT_NEAR(frames.at("DSC00371").sigma0.value(), 0.324, 0.005);
}

TEST(ResectCommand, OpenDroneMapGcpListResectsEveryImageWithThreePoints) {
  const std::string dir = ScratchDir();
  // The camera of ../shared/data/odm_br/README: 4000 x 3000 px, 4.5 mm, f ~ 2904 px.
  WriteFile(dir + "/cameras.csv",
            "CameraID,FocalLength,PixelSize,NColumns,NRows\nSX260HS,4500,1.5495867768595042,4000,3000\n");
  const CliRun run = RunCli("resect --cameras=" + dir + "/cameras.csv --gcp_list=" +
                                SharedDataPath("odm_br/odm_gcp_br_gcp_list_floatxy_raw.txt") +
                                " --out=" + dir + "/frames.csv --report=" + dir +
                                "/report.json --default_accuracy=2",
                            dir);
  // Stated at 2 px (the float picks scatter by 1-2 px; at the default 1 px four images do not fit).
  // IMG_5349 and IMG_5354 carry two targets each: they cannot be resected, and say so.
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("IMG_5349.JPG: not resected: needs at least three control points"),
            std::string::npos);
  EXPECT_NE(run.err.find("IMG_5354.JPG"), std::string::npos);
  // The closing summary names what was done and written.
  EXPECT_NE(run.err.find("8 of 10 images resected, not resected: IMG_5349.JPG, IMG_5354.JPG; "
                         "wrote " + dir + "/frames.csv, " + dir + "/report.json"),
            std::string::npos)
      << run.err;
  const auto frames = ReadFrames(dir + "/frames.csv");
  EXPECT_EQ(frames.size(), 8u);
  for (const auto& [raster, frame] : frames) {
    // 75 m above the targets (~890 m ellipsoidal), near nadir.
    EXPECT_NEAR(frame.eo.parameters[2] - 890.0, 73.0, 5.0) << raster;
    // Against the stated 2 px: the global test passed.
    EXPECT_LT(frame.sigma0.value(), 2.0) << raster;
    // The coordinate system of the gcp_list reaches the frames table.
    EXPECT_EQ(frame.srs, "+proj=utm +zone=22 +south +datum=WGS84 +units=m +no_defs") << raster;
  }
}

// The integer list: images with three targets are not solved (the 40-60 m wrong poses of before
// had no redundancy); IMG_5356 keeps all four targets; the output is the same for every seed.
TEST(ResectCommand, OpenDroneMapIntegerListIsTheSameForEverySeed) {
  const std::string dir = ScratchDir();
  WriteFile(dir + "/cameras.csv",
            "CameraID,FocalLength,PixelSize,NColumns,NRows\nSX260HS,4500,1.5495867768595042,4000,3000\n");
  std::string first_out, first_frames;
  for (int seed = 0; seed < 5; ++seed) {
    const CliRun run = RunCli("resect --cameras=" + dir + "/cameras.csv --gcp_list=" +
                                  SharedDataPath("odm_br/gcp_list.txt") + " --out=" + dir +
                                  "/frames.csv --seed=" + std::to_string(seed * 7777),
                              dir);
    EXPECT_EQ(run.exit_code, 1);
    for (const char* raster : {"IMG_5350.JPG", "IMG_5358.JPG"})
      EXPECT_NE(run.err.find(std::string(raster) + ": not resected: no redundancy"),
                std::string::npos)
          << run.err;
    EXPECT_NE(run.out.find("IMG_5356.JPG:"), std::string::npos);
    EXPECT_NE(run.out.find("inliers=4/4"), std::string::npos) << run.out;
    if (seed == 0) {
      first_out = run.out;
      first_frames = ReadFile(dir + "/frames.csv");
    }
    EXPECT_EQ(run.out, first_out);
    EXPECT_EQ(ReadFile(dir + "/frames.csv"), first_frames);
  }
}

// Wolf & Dewitt in film coordinates with the schema-minimal camera table and default flags: the
// published answer, all four points kept, PixelSize irrelevant, a warning that four marks without
// an accuracy cannot be tested, sigma0 in micrometres.
TEST(ResectCommand, TextbookFilmCoordinatesWithTheMinimalCameraTable) {
  const std::string dir = ScratchDir();
  WriteFile(dir + "/cameras.csv", "ObjectID,CameraID,FocalLength,PixelSize\n1,RC,152916,1\n");
  WriteFile(dir + "/points.csv",
            "PointID,X,Y,Z\nA,1268.102,1455.027,22.606\nB,732.181,545.344,22.299\n"
            "C,1454.553,731.666,22.649\nD,545.245,1268.232,22.336\n");
  WriteFile(dir + "/marks.csv",
            "Raster,PointID,FilmX,FilmY\nphoto,A,86421,-83977\nphoto,B,-100916,92582\n"
            "photo,C,-98322,-89161\nphoto,D,78812,98123\n");
  const CliRun run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir +
                                "/points.csv --marks=" + dir + "/marks.csv --out=" + dir +
                                "/frames.csv --rotation=opk",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("photo: X=1027.8571 Y=1044.1138 Z=648.1974 m  opk omega=-0.41088"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("phi=1.21014"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("kappa=102.80032"), std::string::npos) << run.out;
  // 3.328 um of the default film accuracy of 5 um; four marks leave the pose weak.
  EXPECT_NE(run.out.find("sigma0=0.666 "), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("inliers=4/4"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("WEAK"), std::string::npos) << run.out;
  EXPECT_NE(run.err.find("photo: warning: weak: an undetectable blunder"), std::string::npos)
      << run.err;
}

// ------------------------------------------------------------------ outputs agree

// The console line, the JSON report and the frames table show the same angles for every
// convention, AngleDirection and Polarity: one conversion serves them all.
TEST(ResectCommand, ConsoleReportAndTableShowTheSameAnglesForEveryConventionAndFlag) {
  const std::string dir = ScratchDir();
  std::vector<FrameCamera> cameras;
  ASSERT_TRUE(ReadCameraTable(SourcePath("examples/cameras.csv"), &cameras).ok());
  for (const char* rotation : {"rxryrz", "opk", "pok", "seed"}) {
    for (int angle_direction : {-1, 1}) {
      for (int polarity : {-1, 1}) {
        // The example's camera table with the flags set.
        for (FrameCamera& camera : cameras) {
          camera.angle_direction = angle_direction;
          camera.polarity = polarity;
        }
        ASSERT_TRUE(WriteCameraTable(dir + "/cameras.csv", cameras).ok());
        std::string row;
        const std::string label = std::string(rotation) + " AngleDirection " +
                                  std::to_string(angle_direction) + " Polarity " +
                                  std::to_string(polarity);
        const CliRun run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" +
                                      SourcePath("examples/points.csv") + " --marks=" +
                                      SourcePath("examples/marks.csv") + " --out=" + dir +
                                      "/frames.csv --report=" + dir + "/report.json --rotation=" +
                                      rotation,
                                  dir);
        ASSERT_EQ(run.exit_code, 0) << label << run.err;
        const auto report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
        // The table as written: the raw numbers of its angle columns.
        std::map<std::string, std::array<double, 3>> table_angles;
        std::istringstream csv(ReadFile(dir + "/frames.csv"));
        std::getline(csv, row);
        while (std::getline(csv, row)) {
          std::vector<std::string> f;
          std::stringstream fields(row);
          for (std::string cell; std::getline(fields, cell, ',');) f.push_back(cell);
          table_angles[f[0]] = {std::stod(f[5]), std::stod(f[6]), std::stod(f[7])};
        }
        std::istringstream console(run.out);
        int images = 0;
        for (std::string line; std::getline(console, line); ++images) {
          const std::string raster = line.substr(0, line.find(':'));
          double omega = 0, phi = 0, kappa = 0;
          const size_t at = line.find("omega=");
          ASSERT_NE(at, std::string::npos) << line;
          ASSERT_EQ(std::sscanf(line.c_str() + at, "omega=%lf phi=%lf kappa=%lf", &omega, &phi, &kappa), 3);
          EXPECT_NE(line.find(std::string(" ") + EnumName(*ParseEnum<RotationConvention>(rotation)) + " omega="),
                    std::string::npos) << line;
          const auto& json_pose = [&]() -> const nlohmann::json& {
            for (const auto& image : report["images"])
              if (image["raster"] == raster) return image["pose"];
            return report["images"][0]["pose"];
          }();
          const std::array<double, 3> console_angles = {omega, phi, kappa};
          const std::array<double, 3> json_angles = {json_pose["omega_deg"].get<double>(),
                                                     json_pose["phi_deg"].get<double>(),
                                                     json_pose["kappa_deg"].get<double>()};
          for (int k = 0; k < 3; ++k) {
            // The console prints six decimals.
            EXPECT_NEAR(console_angles[k], json_angles[k], 6e-7) << label << " " << raster;
            EXPECT_NEAR(table_angles.at(raster)[k], json_angles[k], 1e-9) << label << " " << raster;
          }
          EXPECT_EQ(json_pose["angle_direction"].get<int>(), angle_direction);
        }
        EXPECT_EQ(images, 12) << label;
      }
    }
  }
}

// ------------------------------------------------------------------ what the user sees

TEST(ResectCommand, VersionMissingOutputFolderAndTiePoints) {
  const std::string dir = ScratchDir();
  CliRun run = RunCli("--version", dir);
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.out.rfind("photopose ", 0), 0u) << run.out;
  run = RunCli("resect --version", dir);
  EXPECT_EQ(run.exit_code, 0);
  // An output in a folder that does not exist is refused before any work.
  run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/missing/frames.csv", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(run.err, "photopose resect: --out=" + dir + "/missing/frames.csv: the folder '" + dir +
                         "/missing' does not exist\n");
  EXPECT_EQ(run.out, "");
  run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/f.csv --report=" + dir +
                   "/nope/r.json",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir + "/f.csv"));
  // Marks of points without a row are tie points: left out of resection and counted.
  std::string marks = ReadFile(SourcePath("examples/marks.csv"));
  marks += "img_0001,T1,100.5,200.25,,,1,UAV_8.8mm\nimg_0002,T1,150.5,220.25,,,1,UAV_8.8mm\n";
  WriteFile(dir + "/marks.csv", marks);
  run = RunCli("resect --cameras=" + SourcePath("examples/cameras.csv") + " --points=" +
                   SourcePath("examples/points.csv") + " --marks=" + dir + "/marks.csv --out=" +
                   dir + "/f.csv",
               dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("12 of 12 images resected; 2 marks of tie points left out; wrote " + dir +
                         "/f.csv"),
            std::string::npos)
      << run.err;
}

// A Wild RC-30 style scanned photograph: marks in scan pixels, the pixel-to-film affine of the
// scan fitted to its measured fiducials (docs/formats.md's example); a misnumbered fiducial is
// refused with its line.
TEST(ResectCommand, ScannedFilmWithMeasuredFiducials) {
  const std::string dir = ScratchDir();
  WriteFile(dir + "/cameras.csv",
            "ObjectID,CameraID,FocalLength,PixelSize,FilmFiducials\n"
            "1,RC30,152916,1,\"-106000 -106000;106000 -106000;106000 106000;-106000 106000;"
            "0 -110000;110000 0;0 110000;-110000 0\"\n");
  WriteFile(dir + "/points.csv",
            "PointID,X,Y,Z\nA,1268.102,1455.027,22.606\nB,732.181,545.344,22.299\n"
            "C,1454.553,731.666,22.649\nD,545.245,1268.232,22.336\n");
  // The scan: 20 um pixels, the film centre at (5750.3, 5749.6), rows down, turned by 0.2 deg.
  const double angle = 0.2 * 3.14159265358979 / 180.0;
  const auto pixel = [&](double x, double y) {
    return Eigen::Vector2d(5750.3 + (std::cos(angle) * x - std::sin(angle) * y) / 20.0,
                           5749.6 - (std::sin(angle) * x + std::cos(angle) * y) / 20.0);
  };
  const double fiducials[8][2] = {{-106000, -106000}, {106000, -106000}, {106000, 106000},
                                  {-106000, 106000},  {0, -110000},      {110000, 0},
                                  {0, 110000},        {-110000, 0}};
  std::string table = "Raster,FiducialID,Column,Row\n";
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector2d p = pixel(fiducials[k][0], fiducials[k][1]);
    table += "scan_017.tif," + std::to_string(k + 1) + "," + FormatNumber(p.x()) + "," +
             FormatNumber(p.y()) + "\n";
  }
  WriteFile(dir + "/fiducials.csv", table);
  std::string marks = "Raster,PointID,Column,Row,Accuracy\n";
  const double film[4][2] = {{86421, -83977}, {-100916, 92582}, {-98322, -89161}, {78812, 98123}};
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d p = pixel(film[k][0], film[k][1]);
    marks += std::string("scan_017.tif,") + "ABCD"[k] + "," + FormatNumber(p.x()) + "," +
             FormatNumber(p.y()) + ",0.25\n";
  }
  WriteFile(dir + "/marks.csv", marks);
  const std::string common = "resect --cameras=" + dir + "/cameras.csv --points=" + dir +
                             "/points.csv --marks=" + dir + "/marks.csv --out=" + dir +
                             "/frames.csv --rotation=opk --report=" + dir + "/report.json";
  CliRun run = RunCli(common + " --fiducials=" + dir + "/fiducials.csv", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // The textbook pose: the scan reproduces the film coordinates exactly.
  EXPECT_NE(run.out.find("X=1027.8571 Y=1044.1138 Z=648.1974"), std::string::npos) << run.out;
  const auto report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  const auto& fit = report["images"][0]["fiducials"];
  EXPECT_EQ(fit["count"], 8);
  EXPECT_LT(fit["max_um"].get<double>(), 0.01);
  EXPECT_EQ(fit["residuals"].size(), 8u);
  // Residuals in pixels of the marks (0.25 px each stated): sigma0 is unitless.
  EXPECT_EQ(report["images"][0]["marks"][0]["unit"], "px");
  // Without the fiducials the camera has no way from pixels to film: refused at the first mark.
  run = RunCli(common, dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("marks.csv:2: Column: camera 'RC30' has no NRows and NColumns"),
            std::string::npos)
      << run.err;
  // Fiducials 1 and 2 misnumbered (each measured where the other is): 212 mm off, refused at a line.
  std::string swapped = "Raster,FiducialID,Column,Row\n";
  for (int k = 0; k < 8; ++k) {
    const int source = k == 0 ? 1 : k == 1 ? 0 : k;
    const Eigen::Vector2d p = pixel(fiducials[source][0], fiducials[source][1]);
    swapped += "scan_017.tif," + std::to_string(k + 1) + "," + FormatNumber(p.x()) + "," +
               FormatNumber(p.y()) + "\n";
  }
  WriteFile(dir + "/fiducials.csv", swapped);
  run = RunCli(common + " --fiducials=" + dir + "/fiducials.csv", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("fiducials.csv:"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("misnumbered or mismeasured fiducial"), std::string::npos) << run.err;
}

// The same scan measured by software that counts rows up from the bottom edge of the 11500-row
// scan: with --pixel_rows_up the textbook pose again, and the report's fitted A0-B2 in the rows
// the user counts (the rows-down fit with A0 + A2 NRows, -A2, B0 + B2 NRows, -B2).
TEST(ResectCommand, ScannedFilmWithRowsCountedUp) {
  const std::string dir = ScratchDir();
  WriteFile(dir + "/cameras.csv",
            "ObjectID,CameraID,FocalLength,PixelSize,NRows,NColumns,FilmFiducials\n"
            "1,RC30,152916,1,11500,11500,\"-106000 -106000;106000 -106000;106000 106000;"
            "-106000 106000\"\n");
  WriteFile(dir + "/points.csv",
            "PointID,X,Y,Z\nA,1268.102,1455.027,22.606\nB,732.181,545.344,22.299\n"
            "C,1454.553,731.666,22.649\nD,545.245,1268.232,22.336\n");
  const double angle = 0.2 * 3.14159265358979 / 180.0;
  // Rows counted down (as ScannedFilmWithMeasuredFiducials) and up.
  const auto pixel = [&](double x, double y, bool up) {
    const double row = 5749.6 - (std::sin(angle) * x + std::cos(angle) * y) / 20.0;
    return Eigen::Vector2d(5750.3 + (std::cos(angle) * x - std::sin(angle) * y) / 20.0,
                           up ? 11500.0 - row : row);
  };
  const double fiducials[4][2] = {{-106000, -106000}, {106000, -106000}, {106000, 106000},
                                  {-106000, 106000}};
  const double film[4][2] = {{86421, -83977}, {-100916, 92582}, {-98322, -89161}, {78812, 98123}};
  for (const bool up : {false, true}) {
    std::string table = "Raster,FiducialID,Column,Row\n";
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d p = pixel(fiducials[k][0], fiducials[k][1], up);
      table += "scan_017.tif," + std::to_string(k + 1) + "," + FormatNumber(p.x()) + "," +
               FormatNumber(p.y()) + "\n";
    }
    WriteFile(dir + (up ? "/fiducials_up.csv" : "/fiducials.csv"), table);
    std::string marks = "Raster,PointID,Column,Row,Accuracy\n";
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d p = pixel(film[k][0], film[k][1], up);
      marks += std::string("scan_017.tif,") + "ABCD"[k] + "," + FormatNumber(p.x()) + "," +
               FormatNumber(p.y()) + ",0.25\n";
    }
    WriteFile(dir + (up ? "/marks_up.csv" : "/marks.csv"), marks);
  }
  const std::string common = "resect --cameras=" + dir + "/cameras.csv --points=" + dir +
                             "/points.csv --rotation=opk";
  CliRun run = RunCli(common + " --marks=" + dir + "/marks.csv --fiducials=" + dir +
                          "/fiducials.csv --out=" + dir + "/down.csv --report=" + dir +
                          "/down.json",
                      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("X=1027.8571 Y=1044.1138 Z=648.1974"), std::string::npos) << run.out;
  run = RunCli(common + " --marks=" + dir + "/marks_up.csv --fiducials=" + dir +
                   "/fiducials_up.csv --pixel_rows_up --out=" + dir + "/up.csv --report=" + dir +
                   "/up.json",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("X=1027.8571 Y=1044.1138 Z=648.1974"), std::string::npos) << run.out;
  const auto down = nlohmann::json::parse(ReadFile(dir + "/down.json"))["images"][0]["fiducials"];
  const auto up = nlohmann::json::parse(ReadFile(dir + "/up.json"))["images"][0]["fiducials"];
  EXPECT_EQ(down["affine_pixel_rows"], "down");
  EXPECT_EQ(up["affine_pixel_rows"], "up");
  const std::vector<double> a = down["affine"].get<std::vector<double>>();
  const std::vector<double> b = up["affine"].get<std::vector<double>>();
  ASSERT_EQ(a.size(), 6u);
  ASSERT_EQ(b.size(), 6u);
  // The fit's coefficients agree to the rounding of the written pixels (1e-10 px x 20 um).
  const std::vector<double> expected = {a[0] + a[2] * 11500, a[1], -a[2],
                                        a[3] + a[5] * 11500, a[4], -a[5]};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(b[k], expected[k], 1e-6) << k;
}

// ------------------------------------------------------------------ bad input

struct BadInputCase {
  const char* name;
  const char* file;      // which input is replaced
  const char* contents;  // its contents
  int expected_exit;
  const char* expected_message;  // a part of the one-line error
};

// Names the case in test listings instead of a byte dump.
void PrintTo(const BadInputCase& c, std::ostream* os) { *os << c.name; }

class ResectBadInput : public ::testing::TestWithParam<BadInputCase> {};

TEST_P(ResectBadInput, FailsWithOneLineAndLeavesNoOutput) {
  const BadInputCase& c = GetParam();
  const std::string dir = ScratchDir();
  WriteFile(dir + "/cameras.csv",
            "CameraID,FocalLength,PixelSize,NColumns,NRows\ncam,35000,4.4,6000,4000\n");
  WriteFile(dir + "/points.csv",
            "PointID,X,Y,Z\nA,100,100,0\nB,300,120,5\nC,180,300,2\nD,260,260,8\nE,120,240,1\n");
  // Marks of an exact nadir view from (200, 200, 500): x = -c u / w.
  WriteFile(dir + "/marks.csv",
            "Raster,PointID,Column,Row\nimg,A,1409.1,3590.9\nimg,B,4607.0,3285.6\nimg,C,2680.5,402.7\n"
            "img,D,3970.1,1029.9\nimg,E,1724.7,1362.4\n");
  WriteFile(dir + "/frames.csv",
            "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa\nimg,cam,200,200,500,0,0,0\n");
  if (std::string(c.file) != "none") WriteFile(dir + "/" + c.file, c.contents);
  // An existing output must survive a failed run untouched.
  WriteFile(dir + "/out.csv", "previous contents\n");
  const std::string frames_flag = std::string(c.name).find("behind") != std::string::npos ||
                                          std::string(c.file) == "frames.csv"
                                      ? " --frames=" + dir + "/frames.csv"
                                      : "";
  const CliRun run = RunCli("resect --cameras=" + dir + "/cameras.csv --points=" + dir +
                                "/points.csv --marks=" + dir + "/marks.csv --out=" + dir +
                                "/out.csv" + frames_flag,
                            dir);
  EXPECT_EQ(run.exit_code, c.expected_exit) << run.err;
  EXPECT_NE(run.err.find(c.expected_message), std::string::npos) << run.err;
  // One line; a run that did its work (exit 1) adds the closing summary.
  EXPECT_EQ(CountLines(run.err), c.expected_exit == 2 ? 1 : 2) << run.err;
  if (c.expected_exit == 2) EXPECT_EQ(ReadFile(dir + "/out.csv"), "previous contents\n");
  // No temporary file is left beside the output.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) files += entry.is_regular_file();
  EXPECT_EQ(files, 7) << "a temporary file was left behind";
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ResectBadInput,
    ::testing::Values(
        BadInputCase{"missing_column", "points.csv", "PointID,X,Y\nA,1,2\n", 2, "points.csv:1: Z"},
        BadInputCase{"non_numeric", "points.csv", "PointID,X,Y,Z\nA,100,abc,0\n", 2, "points.csv:2: Y"},
        BadInputCase{"nan", "points.csv", "PointID,X,Y,Z\nA,100,100,nan\n", 2, "points.csv:2: Z"},
        BadInputCase{"inf", "marks.csv", "Raster,PointID,Column,Row\nimg,A,inf,1\n", 2, "marks.csv:2: Column"},
        BadInputCase{"duplicate_point", "points.csv", "PointID,X,Y,Z\nA,1,2,3\nA,1,2,3\n", 2, "points.csv:3"},
        // A point without a row is a tie point: left out of resection, counted in the summary.
        BadInputCase{"unknown_point", "marks.csv", "Raster,PointID,Column,Row\nimg,Z9,1,1\n", 1,
                     "needs at least three control points, has 0"},
        BadInputCase{"unknown_camera", "marks.csv", "Raster,PointID,Column,Row,CameraID\nimg,A,1,1,nocam\n", 2,
                     "marks.csv:2: CameraID"},
        BadInputCase{"bad_camera", "cameras.csv", "CameraID,FocalLength,PixelSize\ncam,-5,4.4\n", 2, "cameras.csv"},
        BadInputCase{"bad_frames_angle", "frames.csv",
                     "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa\nimg,cam,200,200,500,x,0,0\n",
                     2, "frames.csv:2: Omega"},
        BadInputCase{"two_points", "marks.csv", "Raster,PointID,Column,Row\nimg,A,1409.1,3590.9\nimg,B,4607.0,3285.6\n",
                     1, "needs at least three control points"},
        BadInputCase{"collinear", "points.csv",
                     "PointID,X,Y,Z\nA,100,100,0\nB,200,200,0\nC,300,300,0\nD,400,400,0\nE,150,150,0\n", 1,
                     "all control points lie on one line"}),
    // (A --frames start below the ground, the control points behind the camera there, is no longer
    // bad input: the consensus start solves the image, AFarFramesStartFallsBackToTheConsensus...)
    [](const ::testing::TestParamInfo<BadInputCase>& info) { return std::string(info.param.name); });

TEST(ResectCommand, MissingFileAndUsageErrors) {
  const std::string dir = ScratchDir();
  CliRun run = RunCli("resect " + ExampleArgs() + " --cameras=" + dir + "/nope.csv --out=" + dir + "/o.csv", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("nope.csv"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir + "/o.csv"));
  run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/o.csv --no_such_flag=1", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("unknown flag --no_such_flag"), std::string::npos);
  // A flag of another subcommand is unknown here too.
  run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/o.csv --noise_px=7", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("unknown flag --noise_px"), std::string::npos);
  run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/o.csv --loss=L2", dir);
  EXPECT_EQ(run.exit_code, 2);
  run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/o.csv --threads=abc", dir);
  EXPECT_EQ(run.exit_code, 2);
  run = RunCli("resect " + ExampleArgs(), dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--out is required"), std::string::npos);
  run = RunCli("resect --help", dir);
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_NE(run.out.find("top-left corner"), std::string::npos);
  EXPECT_NE(run.out.find("--confidence"), std::string::npos);
  EXPECT_NE(run.out.find("rxryrz"), std::string::npos);
  run = RunCli("frobnicate", dir);
  EXPECT_EQ(run.exit_code, 2);
}

// The Taylor solvers are the seed's least squares: a Ceres-only flag given with them is refused
// before any work, naming it (it was ignored: --solver=taylor --loss=cauchy ran least squares).
TEST(ResectCommand, CeresOnlyFlagsAreRefusedWithTheTaylorSolvers) {
  const std::string dir = ScratchDir();
  for (const std::string solver : {"taylor", "taylor_as_printed"}) {
    for (const std::string flag : {"--loss=cauchy", "--loss_scale=3", "--jacobian=autodiff",
                                   "--ceres_minimizer=problem"}) {
      const CliRun run = RunCli("resect " + ExampleArgs() + " --out=" + dir + "/o.csv --solver=" +
                                    solver + " " + flag,
                                dir);
      EXPECT_EQ(run.exit_code, 2) << solver << " " << flag << ": " << run.err;
      const std::string name = flag.substr(0, flag.find('='));
      EXPECT_NE(run.err.find(name + " is for --solver=ceres"), std::string::npos) << run.err;
      EXPECT_FALSE(std::filesystem::exists(dir + "/o.csv"));
    }
  }
  // With Ceres they are taken.
  const CliRun ceres = RunCli("resect " + ExampleArgs() + " --out=" + dir +
                                  "/o.csv --solver=ceres --loss=cauchy --jacobian=autodiff",
                              dir);
  EXPECT_NE(ceres.exit_code, 2) << ceres.err;
}

TEST(ResectCommand, AcceptsAFlagfile) {
  const std::string dir = ScratchDir();
  WriteFile(dir + "/flags", "--cameras=" + SourcePath("examples/cameras.csv") + "\n--points=" +
                                SourcePath("examples/points.csv") + "\n--marks=" +
                                SourcePath("examples/marks.csv") + "\n--out=" + dir + "/o.csv\n");
  const CliRun run = RunCli("resect --flagfile=" + dir + "/flags", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/o.csv"));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
