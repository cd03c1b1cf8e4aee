// End-to-end tests of `photopose bundle` (with `photopose simulate --scenario=block`): the
// executable as a user runs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "core/block.h"
#include "core/io/colmap.h"
#include "core/io/tables.h"
#include "core/rotation.h"
#include "tests/support/singular_block.h"
#include "tests/tools/cli_test_util.h"

namespace photopose {
namespace {

using testing::CliRun;
using testing::ReadFile;
using testing::ReadFrames;
using testing::RunCli;
using testing::ScratchDir;
using testing::SharedDataPath;

// A small block: 3 lines of 6 images, tie blunders, written into dir/block.
std::string SimulateBlock(const std::string& dir, const std::string& extra = "") {
  const CliRun run = RunCli("simulate --scenario=block --lines=3 --images_per_line=6 --seed=7 "
                            "--tie_blunders=4 --colmap --out_dir=" + dir + "/block " + extra,
                            dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return dir + "/block";
}

std::string TableArgs(const std::string& block) {
  return "--cameras=" + block + "/cameras.csv --points=" + block + "/points.csv --marks=" + block +
         "/marks.csv --frames=" + block + "/frames.csv";
}

TEST(BundleCommand, SimulatedBlockAdjustsToItsTruthWithEveryBlunderFound) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const CliRun run = RunCli("bundle " + TableArgs(block) + " --out=" + dir + "/frames.csv" +
                                " --out_points=" + dir + "/points.csv --report=" + dir +
                                "/report.json --html=" + dir + "/report.html",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Progress on stderr, the closing summary with the files written on stdout.
  EXPECT_NE(run.err.find("iteration"), std::string::npos) << run.err;
  EXPECT_NE(run.out.find("wrote " + dir + "/frames.csv"), std::string::npos) << run.out;

  // Every adjusted position within 5 of its own standard deviations (+1 mm) of the truth.
  const auto solved = ReadFrames(dir + "/frames.csv");
  const auto truth = ReadFrames(block + "/truth/frames.csv");
  ASSERT_EQ(solved.size(), 18u);
  for (const auto& [raster, frame] : solved) {
    ASSERT_TRUE(frame.covariance.has_value()) << raster;
    const Eigen::Vector3d error =
        frame.eo.center_in_ground() - truth.at(raster).eo.center_in_ground();
    for (int k = 0; k < 3; ++k) {
      EXPECT_LT(std::abs(error[k]), 5.0 * std::sqrt((*frame.covariance)(k, k)) + 1e-3)
          << raster << " axis " << k;
    }
  }

  // The report: converged, the groups, and exactly the injected blunders rejected.
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  EXPECT_EQ(report["summary"]["termination"], "converged");
  std::set<std::string> groups;
  for (const auto& group : report["groups"]) groups.insert(group["name"].get<std::string>());
  for (const char* name : {"tie_marks", "control_marks", "control_points", "camera_positions"})
    EXPECT_EQ(groups.count(name), 1u) << name;
  std::set<std::pair<std::string, std::string>> rejected, injected;
  for (const auto& mark : report["rejected_marks"])
    rejected.insert({mark["raster"].get<std::string>(), mark["point_id"].get<std::string>()});
  const std::string blunders = ReadFile(block + "/truth/blunders.csv");
  size_t pos = blunders.find('\n') + 1;
  while (pos < blunders.size()) {
    const size_t end = blunders.find('\n', pos);
    const std::string line = blunders.substr(pos, end - pos);
    pos = end + 1;
    const size_t a = line.find(','), b = line.find(',', a + 1), c = line.find(',', b + 1);
    injected.insert({line.substr(a + 1, b - a - 1), line.substr(b + 1, c - b - 1)});
  }
  EXPECT_EQ(injected.size(), 4u);
  EXPECT_EQ(rejected, injected);
  // The HTML page and the points table were written too.
  EXPECT_NE(ReadFile(dir + "/report.html").find("<html"), std::string::npos);
  EXPECT_NE(ReadFile(dir + "/points.csv").find("PointID"), std::string::npos);
}

TEST(BundleCommand, TaylorAndCeresSolversReachTheSamePoses) {
  const std::string dir = ScratchDir();
  // Without blunders and without rejection: the two minimise the same objective.
  const std::string block = SimulateBlock(dir, "--tie_blunders=0");
  for (const char* solver : {"ceres", "taylor"}) {
    const CliRun run = RunCli("bundle " + TableArgs(block) + " --quiet --rejection_threshold=0 --solver=" + solver +
                                  " --out=" + dir + "/" + solver + ".csv",
                              dir);
    ASSERT_EQ(run.exit_code, 0) << solver << ": " << run.err;
  }
  const auto ceres = ReadFrames(dir + "/ceres.csv");
  const auto taylor = ReadFrames(dir + "/taylor.csv");
  const auto start = ReadFrames(block + "/frames.csv");
  // Every image of the block (3 lines x 6 images) in both, so that the loop below sees them all.
  ASSERT_EQ(ceres.size(), 18u);
  ASSERT_EQ(taylor.size(), 18u);
  ASSERT_EQ(start.size(), 18u);
  // The same minimum: 10 um (with Ceres' relative step tolerance at 1e-10 of the norm of all
  // parameters, UTM coordinates made it stop 0.05 mm short here).
  double largest_turn_rad = 0.0;
  for (const auto& [raster, frame] : ceres) {
    ASSERT_EQ(taylor.count(raster), 1u) << raster;
    EXPECT_LT((frame.eo.center_in_ground() - taylor.at(raster).eo.center_in_ground()).norm(), 1e-5)
        << raster;
    const Eigen::Vector3d turn = frame.eo.angles_seed_rad() - start.at(raster).eo.angles_seed_rad();
    for (int k = 0; k < 3; ++k)
      largest_turn_rad = std::max(largest_turn_rad, std::abs(WrapAngle(turn[k])));
  }
  // Two runs that wrote the start unchanged would agree too: the start angles of the block are
  // 1 degree (one sigma per angle) off the truth, so an adjustment turns some image of the 18 by
  // far more than 0.1 degree (the start positions are the GNSS ones, only centimetres off).
  EXPECT_GT(largest_turn_rad, DegreesToRadians(0.1));
}

// The marks of each image of a block by point id, to compare models across a run.
std::set<std::pair<std::string, std::string>> ImagePointPairs(const Block& block) {
  std::set<std::pair<std::string, std::string>> pairs;
  for (const BlockMark& mark : block.marks)
    pairs.insert({block.images[mark.image].name, block.points[mark.point].id});
  return pairs;
}

TEST(BundleCommand, ColmapModelInColmapModelOutWithoutTheRejectedMarks) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const CliRun run = RunCli("bundle --colmap_model=" + block + "/colmap --out_colmap=" + dir +
                                "/adjusted --report=" + dir + "/report.json --quiet",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Block in, out;
  ColmapModelExtras in_extras, out_extras;
  ASSERT_TRUE(ReadColmapModel(block + "/colmap", &in, &in_extras).ok());
  ASSERT_TRUE(ReadColmapModel(dir + "/adjusted", &out, &out_extras).ok());
  EXPECT_EQ(out.images.size(), in.images.size());
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  EXPECT_EQ(report["summary"]["termination"], "converged");
  EXPECT_EQ(report["summary"]["datum"], "relative");
  ASSERT_GE(report["rejected_marks"].size(), 4u);  // the 4 blunders at least
  // Every step's time: one entry per round, and the steps within the whole run's time.
  const nlohmann::json& time = report["summary"]["time_breakdown"];
  ASSERT_EQ(time["round_seconds"].size(), report["summary"]["rounds"].get<size_t>());
  double steps = time["plan_seconds"].get<double>() + time["rejection_seconds"].get<double>() +
                 time["statistics_seconds"].get<double>();
  for (const auto& round : time["round_seconds"]) steps += round.get<double>();
  EXPECT_GT(time["read_seconds"].get<double>(), 0.0);
  EXPECT_GT(time["rejection_seconds"].get<double>(), 0.0);
  EXPECT_LE(steps, report["summary"]["time_seconds"].get<double>());
  EXPECT_LE(time["setup_seconds"].get<double>(), report["summary"]["time_seconds"].get<double>());
  const auto in_pairs = ImagePointPairs(in), out_pairs = ImagePointPairs(out);
  for (const auto& rejected : report["rejected_marks"]) {
    const std::pair<std::string, std::string> pair{rejected["raster"], rejected["point_id"]};
    EXPECT_EQ(in_pairs.count(pair), 1u);
    EXPECT_EQ(out_pairs.count(pair), 0u) << pair.first << " " << pair.second;
  }
  // Every keypoint is still there, at its index: rejected marks became keypoints without a point.
  EXPECT_EQ(out_extras.num_keypoints, in_extras.num_keypoints);
  EXPECT_EQ(out.marks.size() + out_extras.unmatched.size(),
            in.marks.size() + in_extras.unmatched.size());
  EXPECT_LE(out.marks.size(), in.marks.size() - report["rejected_marks"].size());
  // What is left is consistent: no point with fewer than 2 marks, none far from its projection
  // (the blunders were tens of pixels off).
  for (size_t p = 0; p < out.points.size(); ++p) EXPECT_GE(out.marks_of_point[p].size(), 2u);
  std::vector<double> errors;
  MarkReprojectionErrors(out, &errors);
  EXPECT_LT(*std::max_element(errors.begin(), errors.end()), 5.0);
}

TEST(BundleCommand, BinaryColmapModelInBinaryOutUnlessAsked) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  Block model;
  ColmapModelExtras extras;
  ASSERT_TRUE(ReadColmapModel(block + "/colmap", &model, &extras).ok());
  ColmapWriteOptions binary;
  binary.format = ColmapFormat::kBinary;
  ASSERT_TRUE(WriteColmapModel(dir + "/bin", model, &extras, binary).ok());

  CliRun run = RunCli("bundle --colmap_model=" + dir + "/bin --out_colmap=" + dir +
                          "/out_bin --quiet",
                      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out_bin/points3D.bin"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/out_bin/points3D.txt"));
  Block from_binary;
  ASSERT_TRUE(ReadColmapModel(dir + "/out_bin", &from_binary).ok());

  run = RunCli("bundle --colmap_model=" + dir + "/bin --out_colmap=" + dir +
                   "/out_txt --out_colmap_format=text --quiet",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out_txt/points3D.txt"));
  Block from_text;
  ColmapFormat format = ColmapFormat::kBinary;
  ASSERT_TRUE(ReadColmapModel(dir + "/out_txt", &from_text, nullptr, &format).ok());
  EXPECT_EQ(format, ColmapFormat::kText);
  // The same adjustment either way (to the rounding of sums in another order by the threads of
  // the linear algebra: 1e-10 m here, at UTM coordinates of 5e5 m).
  ASSERT_EQ(from_text.images.size(), from_binary.images.size());
  for (size_t i = 0; i < from_text.images.size(); ++i) {
    EXPECT_LT((from_text.images[i].eo->parameters - from_binary.images[i].eo->parameters)
                  .cwiseAbs()
                  .maxCoeff(),
              1e-8);
  }

  // Text over a binary model: the binary files would be read instead, so it is refused.
  run = RunCli("bundle --colmap_model=" + dir + "/bin --out_colmap=" + dir +
                   "/out_bin --out_colmap_format=text --quiet",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--out_colmap=" + dir +
                         "/out_bin holds a binary COLMAP model (cameras.bin, images.bin, "
                         "points3D.bin), which COLMAP and photopose read instead of the text model "
                         "written here"),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out_bin/points3D.txt"));
  run = RunCli("bundle --colmap_model=" + dir + "/bin --out_colmap=" + dir +
                   "/out_x --out_colmap_format=ply --quiet",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--out_colmap_format"), std::string::npos) << run.err;
  run = RunCli("bundle --colmap_model=" + dir + "/nowhere --out_colmap=" + dir + "/out_y --quiet",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--colmap_model: " + dir + "/nowhere: is no folder"), std::string::npos)
      << run.err;
}

TEST(BundleCommand, CalibrateTakesColmapsParameterNames) {
  const std::string dir = ScratchDir();
  // colmap_ar7 is one SIMPLE_RADIAL camera: f, cx, cy, k.
  const CliRun run = RunCli("bundle --colmap_model=" + SharedDataPath("colmap_ar7") +
                                " --calibrate=f,K --report=" + dir + "/report.json --quiet",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  ASSERT_EQ(report["calibration"].size(), 1u);
  const nlohmann::json& parameters = report["calibration"][0]["parameters"];
  ASSERT_EQ(parameters.size(), 2u) << parameters.dump();
  EXPECT_EQ(parameters[0]["name"], "f");
  EXPECT_EQ(parameters[1]["name"], "k");
  const CliRun bad = RunCli("bundle --colmap_model=" + SharedDataPath("colmap_ar7") +
                                " --calibrate=k2 --report=" + dir + "/r2.json --quiet",
                            dir);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("the SIMPLE_RADIAL camera model has no parameter 'k2'"),
            std::string::npos)
      << bad.err;
}

TEST(BundleCommand, SelfCalibratedDistortionForAColmapOutputIsRefusedBeforeAnyWork) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const CliRun run = RunCli("bundle " + TableArgs(block) + " --calibrate=FocalLength,K1 --out=" +
                                dir + "/frames.csv --out_colmap=" + dir + "/colmap",
                            dir);
  EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
  EXPECT_NE(run.err.find("--out_colmap: camera '"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("': calibrating K1 would make it no COLMAP pinhole camera"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(run.err.find("iteration"), std::string::npos) << run.err;       // no adjustment
  EXPECT_EQ(run.err.find("initial values"), std::string::npos) << run.err;  // nor its start
  EXPECT_FALSE(std::filesystem::exists(dir + "/frames.csv"));
  // The focal length alone keeps it a pinhole: no refusal.
  const CliRun focal = RunCli("bundle " + TableArgs(block) + " --calibrate=FocalLength --out=" +
                                  dir + "/frames.csv --out_colmap=" + dir + "/colmap --quiet",
                              dir);
  EXPECT_EQ(focal.exit_code, 0) << focal.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/colmap/cameras.txt"));
}

TEST(BundleCommand, BalProblemIsAdjusted) {
  const std::string dir = ScratchDir();
  const CliRun run =
      RunCli("bundle --bal=" + SharedDataPath("bal_dubrovnik/dubrovnik-3-7-pre.txt") +
                 " --rejection_threshold=0 --report=" + dir + "/report.json --quiet",
             dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  EXPECT_EQ(report["summary"]["termination"], "converged");
  EXPECT_LT(report["summary"]["final_cost"].get<double>(),
            0.5 * report["summary"]["initial_cost"].get<double>());
}

TEST(BundleCommand, AnOutputThatIsAnInputIsRefusedBeforeAnyWork) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const std::string marks_before = ReadFile(block + "/marks.csv");
  const CliRun run = RunCli("bundle " + TableArgs(block) + " --out=" + block + "/marks.csv", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--out=" + block + "/marks.csv is the input --marks"), std::string::npos)
      << run.err;
  EXPECT_EQ(ReadFile(block + "/marks.csv"), marks_before);
}

TEST(BundleCommand, AnAdjustmentThatDidNotConvergeWritesOnlyItsReport) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const CliRun run = RunCli("bundle " + TableArgs(block) + " --max_iterations=1 --quiet --out=" +
                                dir + "/frames.csv --report=" + dir + "/report.json",
                            dir);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("not adjusted"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/frames.csv"));
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  EXPECT_NE(report["summary"]["termination"], "converged");
}

TEST(BundleCommand, ImagesWithoutInitialValuesAreResectedOrNamed) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  // Without the frames table every image is resected from the control points it sees, and the
  // images that see too few are oriented from the tie points intersected so far.
  const CliRun run = RunCli("bundle --cameras=" + block + "/cameras.csv --points=" + block +
                                "/points.csv --marks=" + block + "/marks.csv --out=" + dir +
                                "/frames.csv --report=" + dir + "/report.json",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("resected"), std::string::npos) << run.err;
  const auto solved = ReadFrames(dir + "/frames.csv");
  const auto truth = ReadFrames(block + "/truth/frames.csv");
  ASSERT_EQ(solved.size(), truth.size());
  for (const auto& [raster, frame] : solved) {
    EXPECT_LT((frame.eo.center_in_ground() - truth.at(raster).eo.center_in_ground()).norm(), 0.1)
        << raster;
  }
}

TEST(BundleCommand, ABlockWithNothingToOrientItFromIsRefusedWithTheReason) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  // No control points and no frames: no image can be oriented, nothing is written.
  const CliRun run = RunCli("bundle --cameras=" + block + "/cameras.csv --marks=" + block +
                                "/marks.csv --quiet --out=" + dir + "/frames.csv",
                            dir);
  EXPECT_EQ(run.exit_code, 1) << run.out << run.err;
  EXPECT_NE(run.err.find("not oriented"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/frames.csv"));
}

// Accuracies stated 10 times too optimistic: sigma0 near 10, no gross error to find. The search
// (snooping in every group) runs, sigma0 stays above 3: not adjusted, the group to blame named,
// only the report written; with --force every output, still exit 1.
TEST(BundleCommand, Sigma0FarAboveOneAfterTheSearchIsAFailureNamingTheGroup) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const std::string common = "bundle --colmap_model=" + block + "/colmap --tie_accuracy=0.05 --out=" + dir +
                             "/frames.csv --report=" + dir + "/report.json --quiet";
  const CliRun run = RunCli(common, dir);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("searching every group for gross errors"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("after the search for gross errors"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("groups to blame: tie_marks (RMS/stated "), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/frames.csv"));
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  EXPECT_EQ(report["summary"]["termination"], "failure");
  EXPECT_TRUE(report["options"]["snoop"].get<bool>());

  const CliRun forced = RunCli(common + " --force", dir);
  EXPECT_EQ(forced.exit_code, 1) << forced.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/frames.csv"));
  const nlohmann::json forced_report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  EXPECT_EQ(forced_report["summary"]["message"].get<std::string>().rfind("FAILED the sigma0 check", 0), 0u);
}

// An image whose marks all lie on one ground line (tests/support/singular_block.h), as a COLMAP
// model (start values without priors, COLMAP's gauge): Ceres converges, the normal matrix is
// singular. Not adjusted, exit 1, the one-line reason names the image and the parameter, only the
// report written; with every statistics option, and --force (which is for the sigma0 check)
// changes nothing.
TEST(BundleCommand, ASingularNormalMatrixIsAFailureNamingWhatIsNotDetermined) {
  const std::string dir = ScratchDir();
  const testing::SingularBlock data = testing::BlockWithAnImageOnALine();
  std::filesystem::create_directories(dir + "/model");
  ASSERT_TRUE(WriteColmapModel(dir + "/model", data.block).ok());
  const std::string image = data.block.images[data.image].name;
  const std::string common = "bundle --colmap_model=" + dir + "/model --quiet --out_colmap=" + dir +
                             "/out --report=" + dir + "/report.json";
  for (const std::string extra : {"", " --statistics=dense", " --statistics=none", " --force"}) {
    SCOPED_TRACE(extra);
    std::filesystem::remove(dir + "/report.json");
    const CliRun run = RunCli(common + extra, dir);
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_NE(run.err.find("photopose bundle: not adjusted: round 1: the normal matrix is "
                           "singular: image '" +
                           image + "': omega is not determined by the observations\n"),
              std::string::npos)
        << run.err;
    EXPECT_NE(run.out.find("bundle: not adjusted"), std::string::npos) << run.out;
    EXPECT_FALSE(std::filesystem::exists(dir + "/out/images.txt"));
    const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
    EXPECT_EQ(report["summary"]["termination"], "failure");
  }
}

}  // namespace
}  // namespace photopose
