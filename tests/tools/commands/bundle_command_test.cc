// End-to-end tests of `photopose bundle` (with `photopose simulate --scenario=block`): the
// executable as a user runs it.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

#include "core/block.h"
#include "core/io/block_tables.h"
#include "core/io/colmap.h"
#include "core/io/tables.h"
#include "core/simulation/synthetic_block.h"
#include "core/rotation.h"
#include "tests/support/singular_block.h"
#include "tests/tools/cli_test_util.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::CliRun;
using testing::ReadFile;
using testing::ReadFrames;
using testing::RunCli;
using testing::ScratchDir;
using testing::SharedDataPath;
using testing::SourcePath;
using testing::SplitCsvText;

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

// Copies the CSV table `from` to `to` without the columns named.
void CopyWithoutColumns(const std::string& from, const std::string& to,
                        const std::set<std::string>& names) {
  const std::vector<std::vector<std::string>> rows = SplitCsvText(ReadFile(from));
  ASSERT_FALSE(rows.empty()) << from;
  std::string text;
  for (const std::vector<std::string>& row : rows) {
    if (row.size() != rows[0].size()) continue;  // the empty last line
    bool first = true;
    for (size_t k = 0; k < row.size(); ++k) {
      if (names.count(rows[0][k])) continue;
      text += (first ? "" : ",") + row[k];
      first = false;
    }
    text += "\n";
  }
  testing::WriteFile(to, text);
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

// Ctrl-C (SIGINT) or SIGTERM in the middle of an adjustment (issue 24): the run stops at the next
// iteration, writes nothing (the old --out untouched, no --report created, no temporary left) and
// says so in one line, exit status 128 + the signal. The signal is sent once a progress line shows
// the adjustment under way; a block of 120 images on one thread leaves it many iterations and its
// statistics to go. Ceres' hook with SIGINT, the Taylor solver's with SIGTERM.
TEST(BundleCommand, ASignalCancelsTheRunAndNothingIsWritten) {
  for (const auto& [signal_number, exit_code, name, solver] :
       {std::tuple<int, int, const char*, const char*>{SIGINT, 130, "SIGINT", "ceres"},
        {SIGTERM, 143, "SIGTERM", "taylor"}}) {
    SCOPED_TRACE(name);
    const std::string dir = ScratchDir() + "/" + solver;
    std::filesystem::create_directories(dir);
    const CliRun simulated =
        RunCli("simulate --scenario=block --lines=6 --images_per_line=20 --tie_points=6000 "
               "--seed=3 --tie_blunders=6 --out_dir=" + dir + "/block",
               dir);
    ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
    const std::string block = dir + "/block";
    const std::string out = dir + "/frames.csv";
    testing::WriteFile(out, "old output\n");
    const CliRun run = testing::RunCliAndSignal(
        {"bundle", "--cameras=" + block + "/cameras.csv", "--points=" + block + "/points.csv",
         "--marks=" + block + "/marks.csv", "--frames=" + block + "/frames.csv", "--out=" + out,
         "--report=" + dir + "/report.json", "--threads=1", std::string("--solver=") + solver},
        dir, " iteration ", signal_number);
    EXPECT_EQ(run.exit_code, exit_code) << run.err;
    const std::regex cancelled(std::string("photopose bundle: cancelled by ") + name +
                               " [a-z ]+; nothing written\n$");
    EXPECT_TRUE(std::regex_search(run.err, cancelled)) << run.err;
    EXPECT_EQ(ReadFile(out), "old output\n");
    EXPECT_FALSE(std::filesystem::exists(dir + "/report.json"));
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      EXPECT_NE(entry.path().filename().string().front(), '.') << "left behind: " << entry.path();
    // Nothing of the results on stdout either: no closing summary.
    EXPECT_EQ(run.out.find("wrote"), std::string::npos) << run.out;
  }
}

// The camera table's ApplyECC is honoured: the wide block of EarthCurvatureBlockOptions (800 m,
// 10 mm lens) whose marks were generated with the earth-curvature drop, written twice with ApplyECC true and false
// and otherwise the same tables. The frames and points written differ; with the correction the
// centres are at the truth within centimetres, without it farther off; --solver=taylor gives the
// same corrected centres.
// Issue 25: no scientific notation a surveyor has to read, on the console either. The progress
// lines (Ceres' trust-region radius starts at 10000, which %g printed as 1e+04) and the summary.
TEST(BundleCommand, ProgressAndSummaryLinesPrintNoExponent) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const CliRun run = RunCli("bundle " + TableArgs(block) + " --out=" + dir + "/frames.csv", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::regex exponent("[0-9]e[+-]?[0-9]");
  int progress = 0;
  for (const std::string& text : {run.err, run.out}) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      // The paths are the test's, not the command's figures.
      for (size_t at; (at = line.find(dir)) != std::string::npos;) line.replace(at, dir.size(), "DIR");
      EXPECT_FALSE(std::regex_search(line, exponent)) << line;
    }
  }
  // Each progress line under 120 characters, the essentials first (round, iteration, cost,
  // sigma0, step, elapsed), then Ceres' solve time that tools/benchmarks/bundle_scaling.sh reads.
  const std::regex essentials(
      "photopose bundle: round [0-9]+ iteration +[0-9]+: cost [0-9.]+  sigma0 [0-9.]+  step "
      "[0-9.]+  [0-9.]+ s  solve [0-9.]+ of [0-9.]+ s.*");
  std::istringstream lines(run.err);
  for (std::string line; std::getline(lines, line);) {
    if (line.find(" iteration ") == std::string::npos) continue;
    ++progress;
    EXPECT_LT(line.size(), 120u) << line;
    EXPECT_TRUE(std::regex_match(line, essentials)) << line;
  }
  EXPECT_GE(progress, 2) << run.err;
  EXPECT_NE(run.err.find("photopose bundle: round 1 iteration   0: cost "), std::string::npos)
      << run.err;
  // Every other line on stderr under 120 characters too (those that name the test's files aside):
  // the initial values in two lines, images and tie points.
  std::istringstream all(run.err);
  for (std::string line; std::getline(all, line);)
    if (line.find(dir) == std::string::npos) EXPECT_LT(line.size(), 120u) << line;
  EXPECT_TRUE(std::regex_search(
      run.err, std::regex("(^|\n)photopose bundle: initial values: 18 images with initial values, 0 "
                           "resected, 0 not oriented; [0-9]+ rounds?\n")))
      << run.err;
  EXPECT_TRUE(std::regex_search(
      run.err, std::regex("\nphotopose bundle: initial values: [0-9]+ tie points with "
                           "coordinates, [0-9]+ intersected, [0-9]+ not\n")))
      << run.err;
}

TEST(BundleCommand, TheCameraTablesApplyEccIsHonoured) {
  const std::string dir = ScratchDir();
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(EarthCurvatureBlockOptions(), &block, &truth).ok());
  std::map<std::string, double> center_rms_m;
  for (const bool apply_ecc : {true, false}) {
    const std::string name = apply_ecc ? "ecc" : "plain";
    block.cameras[0].table.apply_ecc = apply_ecc;
    const std::string in = dir + "/" + name;
    std::filesystem::create_directories(in);
    ASSERT_TRUE(WriteBlockTables(block, {in + "/cameras.csv", in + "/points.csv", in + "/marks.csv",
                                         in + "/frames.csv"})
                    .ok());
    const CliRun run = RunCli("bundle " + TableArgs(in) + " --quiet --out=" + dir + "/" + name +
                                  "_frames.csv --out_points=" + dir + "/" + name + "_points.csv",
                              dir);
    ASSERT_EQ(run.exit_code, 0) << name << ": " << run.err;
    const auto frames = ReadFrames(dir + "/" + name + "_frames.csv");
    ASSERT_EQ(frames.size(), block.images.size());
    double ssq = 0.0;
    for (size_t i = 0; i < block.images.size(); ++i) {
      ssq += (frames.at(block.images[i].name).eo.center_in_ground() -
              truth.eo[i].center_in_ground())
                 .squaredNorm();
    }
    center_rms_m[name] = std::sqrt(ssq / block.images.size());
    if (apply_ecc) {
      // The Taylor solver models the correction too: the same centres to a tenth of a millimetre.
      const CliRun taylor = RunCli("bundle " + TableArgs(in) + " --quiet --solver=taylor --out=" +
                                       dir + "/taylor_frames.csv",
                                   dir);
      ASSERT_EQ(taylor.exit_code, 0) << taylor.err;
      const auto taylor_frames = ReadFrames(dir + "/taylor_frames.csv");
      for (size_t i = 0; i < block.images.size(); ++i) {
        const std::string& image = block.images[i].name;
        EXPECT_LT((taylor_frames.at(image).eo.center_in_ground() -
                   frames.at(image).eo.center_in_ground())
                      .norm(),
                  1e-4)
            << image;
      }
    }
  }
  std::printf("  centres off the truth (RMS): with ApplyECC %.4f m, without %.4f m\n",
              center_rms_m["ecc"], center_rms_m["plain"]);
  EXPECT_NE(ReadFile(dir + "/ecc_frames.csv"), ReadFile(dir + "/plain_frames.csv"));
  EXPECT_NE(ReadFile(dir + "/ecc_points.csv"), ReadFile(dir + "/plain_points.csv"));
  EXPECT_LT(center_rms_m["ecc"], 0.05);
  EXPECT_GT(center_rms_m["plain"], 1.5 * center_rms_m["ecc"]);
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

// --solver=taylor snoops and estimates accuracies by BundleAdjust's rounds and statistics
// (issue 23): its report removes the same observations and gives the same verdicts as Ceres'.
// Cross-validation (Ceres' left-out adjustments) is refused in one line.
TEST(BundleCommand, TaylorSolverSnoopsAndEstimatesAsCeres) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  std::map<std::string, nlohmann::json> reports;
  for (const char* solver : {"ceres", "taylor"}) {
    const std::string report = dir + "/" + solver + ".json";
    const CliRun run = RunCli("bundle " + TableArgs(block) +
                                  " --quiet --snoop --estimate_accuracies --solver=" + solver +
                                  " --report=" + report,
                              dir);
    ASSERT_EQ(run.exit_code, 0) << solver << ": " << run.err;
    reports[solver] = nlohmann::json::parse(ReadFile(report));
  }
  const nlohmann::json& ceres = reports["ceres"];
  const nlohmann::json& taylor = reports["taylor"];
  ASSERT_TRUE(taylor.contains("snooping"));
  ASSERT_EQ(taylor["snooping"].size(), ceres["snooping"].size());
  EXPECT_GE(ceres["snooping"].size(), 4u);  // the four tie blunders
  for (size_t k = 0; k < ceres["snooping"].size(); ++k) {
    EXPECT_EQ(taylor["snooping"][k]["item"], ceres["snooping"][k]["item"]) << k;
    EXPECT_EQ(taylor["snooping"][k]["axis"], ceres["snooping"][k]["axis"]) << k;
  }
  ASSERT_EQ(taylor["groups"].size(), ceres["groups"].size());
  for (size_t g = 0; g < ceres["groups"].size(); ++g) {
    EXPECT_EQ(taylor["groups"][g]["name"], ceres["groups"][g]["name"]);
    EXPECT_EQ(taylor["groups"][g]["overfit"], ceres["groups"][g]["overfit"]);
  }
  EXPECT_NEAR(taylor["summary"]["sigma0"].get<double>(), ceres["summary"]["sigma0"].get<double>(),
              1e-6 * ceres["summary"]["sigma0"].get<double>());
  // --snooping_batch=false reaches the Taylor path too: one removal per round, the same removals.
  const std::string single_report = dir + "/taylor_single.json";
  const CliRun single = RunCli("bundle " + TableArgs(block) +
                                   " --quiet --snoop --snooping_batch=false --estimate_accuracies "
                                   "--solver=taylor --report=" + single_report,
                               dir);
  ASSERT_EQ(single.exit_code, 0) << single.err;
  const nlohmann::json one_at_a_time = nlohmann::json::parse(ReadFile(single_report));
  ASSERT_EQ(one_at_a_time["snooping"].size(), taylor["snooping"].size());
  EXPECT_GT(one_at_a_time["summary"]["snooping_rounds"].get<int>(),
            taylor["summary"]["snooping_rounds"].get<int>());

  // The cross-validation by the update serves the Taylor path (the shared statistics' code); the
  // refit's adjustments are Ceres' and are refused there, as is the method without
  // --cross_validate.
  const std::string cv_report = dir + "/cv.json";
  const CliRun cross_validated =
      RunCli("bundle " + TableArgs(block) +
                 " --quiet --solver=taylor --cross_validate --report=" + cv_report,
             dir);
  ASSERT_EQ(cross_validated.exit_code, 0) << cross_validated.err;
  const nlohmann::json cv = nlohmann::json::parse(ReadFile(cv_report))["cross_validation"];
  EXPECT_EQ(cv["method"], "update");
  EXPECT_GT(cv["count"].get<int>(), 0);
  EXPECT_GE(cv["time_seconds"].get<double>(), 0.0);
  const CliRun refused = RunCli(
      "bundle " + TableArgs(block) + " --quiet --solver=taylor " +
          "--cross_validate --cross_validation_method=refit --report=" + dir + "/cv_refit.json",
      dir);
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("--solver=taylor does not refit"), std::string::npos) << refused.err;
  const CliRun without =
      RunCli("bundle " + TableArgs(block) +
                 " --quiet --cross_validation_method=refit --report=" + dir + "/cv_without.json",
             dir);
  EXPECT_EQ(without.exit_code, 2);
  EXPECT_NE(without.err.find("--cross_validation_method is for --cross_validate"),
            std::string::npos)
      << without.err;
}

// --snooping_batch (on by default) removes the blunders in fewer rounds; =false one per round; the
// same observations either way.
TEST(BundleCommand, SnoopingBatchRemovesWhatOneAtATimeRemovesInFewerRounds) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  std::map<std::string, nlohmann::json> reports;
  for (const char* batch : {"true", "false"}) {
    const std::string report = dir + "/batch_" + batch + ".json";
    const CliRun run = RunCli("bundle " + TableArgs(block) + " --quiet --snoop --snooping_batch=" +
                                  batch + " --out=" + dir + "/frames_" + batch +
                                  ".csv --report=" + report,
                              dir);
    ASSERT_EQ(run.exit_code, 0) << batch << ": " << run.err;
    reports[batch] = nlohmann::json::parse(ReadFile(report));
  }
  std::map<std::string, std::set<std::string>> removed;
  for (auto& [batch, report] : reports)
    for (const nlohmann::json& step : report["snooping"])
      removed[batch].insert(step["group"].get<std::string>() + " " + step["item"].get<std::string>());
  EXPECT_GE(removed["false"].size(), 4u);  // the four tie blunders
  EXPECT_EQ(removed["true"], removed["false"]);
  // One at a time: a round per removal and the last; in a batch, the four in one.
  EXPECT_EQ(reports["false"]["summary"]["rounds"].get<int>(),
            static_cast<int>(removed["false"].size()) + 1);
  EXPECT_LT(reports["true"]["summary"]["rounds"].get<int>(),
            reports["false"]["summary"]["rounds"].get<int>());
  // The report says which round's statistics found each removal, and how many rounds snooped.
  std::set<int> batch_rounds, single_rounds;
  for (const nlohmann::json& step : reports["true"]["snooping"]) batch_rounds.insert(step["round"].get<int>());
  for (const nlohmann::json& step : reports["false"]["snooping"]) single_rounds.insert(step["round"].get<int>());
  EXPECT_EQ(single_rounds.size(), removed["false"].size());
  EXPECT_LT(batch_rounds.size(), single_rounds.size());
  EXPECT_LT(reports["true"]["summary"]["snooping_rounds"].get<int>(),
            reports["false"]["summary"]["snooping_rounds"].get<int>());
  EXPECT_GE(reports["true"]["summary"]["snooping_seconds"].get<double>(), 0.0);
}

// --solver=taylor adjusts a COLMAP model (relative, pixels) to the Ceres minimum, freeing the gauge
// first as Ceres does; Gauss-Newton cannot free it, so an explicit --relative_gauge=free is refused.
TEST(BundleCommand, TaylorSolverAdjustsAColmapModelAsCeres) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  std::map<std::string, nlohmann::json> reports;
  for (const char* solver : {"ceres", "taylor"}) {
    const std::string report = dir + "/colmap_" + solver + ".json";
    const CliRun run = RunCli("bundle --colmap_model=" + block + "/colmap --quiet --solver=" +
                                  solver + " --report=" + report,
                              dir);
    ASSERT_EQ(run.exit_code, 0) << solver << ": " << run.err;
    reports[solver] = nlohmann::json::parse(ReadFile(report));
  }
  const nlohmann::json& ceres = reports["ceres"]["summary"];
  const nlohmann::json& taylor = reports["taylor"]["summary"];
  EXPECT_EQ(taylor["redundancy"], ceres["redundancy"]);
  EXPECT_NEAR(taylor["final_cost"].get<double>(), ceres["final_cost"].get<double>(),
              1e-6 * ceres["final_cost"].get<double>());
  const CliRun refused =
      RunCli("bundle --colmap_model=" + block + "/colmap --quiet --solver=taylor " +
                 "--taylor_damping=none --relative_gauge=free --report=" + dir + "/gn.json",
             dir);
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("--relative_gauge=free needs a damped solver"), std::string::npos)
      << refused.err;
}

// --solver=taylor self-calibrates and estimates the lever arm (issue 23 item 3) to the Ceres
// adjustment's minimum: the same cost, calibration with the same sigmas, the same lever arm.
TEST(BundleCommand, TaylorSolverSelfCalibratesAsCeres) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir, "--tie_blunders=0");
  std::map<std::string, nlohmann::json> reports;
  for (const char* solver : {"ceres", "taylor"}) {
    const std::string report = dir + "/calibrated_" + solver + ".json";
    const CliRun run = RunCli("bundle " + TableArgs(block) +
                                  " --quiet --rejection_threshold=0 --calibrate=FocalLength,K1 "
                                  "--lever_arm=0,0,0 --estimate_lever_arm --solver=" +
                                  solver + " --report=" + report,
                              dir);
    ASSERT_EQ(run.exit_code, 0) << solver << ": " << run.err;
    reports[solver] = nlohmann::json::parse(ReadFile(report));
  }
  const nlohmann::json& ceres = reports["ceres"];
  const nlohmann::json& taylor = reports["taylor"];
  EXPECT_EQ(taylor["summary"]["redundancy"], ceres["summary"]["redundancy"]);
  // The cost to 1e-9 (measured 7.5e-13).
  EXPECT_NEAR(taylor["summary"]["final_cost"].get<double>(),
              ceres["summary"]["final_cost"].get<double>(),
              1e-9 * ceres["summary"]["final_cost"].get<double>());
  ASSERT_EQ(ceres["calibration"].size(), 1u);
  ASSERT_EQ(taylor["calibration"].size(), 1u);
  const nlohmann::json& cp = ceres["calibration"][0]["parameters"];
  const nlohmann::json& tp = taylor["calibration"][0]["parameters"];
  ASSERT_EQ(cp.size(), 2u);
  ASSERT_EQ(tp.size(), 2u);
  for (size_t k = 0; k < cp.size(); ++k) {
    EXPECT_EQ(tp[k]["name"], cp[k]["name"]);
    const double value = cp[k]["value"].get<double>(), sigma = cp[k]["sigma"].get<double>();
    // Ceres stops (relative cost change 1e-10) with the calibration a little off the minimum:
    // measured 3e-6 of max(|value|, sigma) (K1), the Taylor cost 7.5e-13 lower.
    EXPECT_NEAR(tp[k]["value"].get<double>(), value, 3e-5 * std::max(std::abs(value), sigma))
        << cp[k]["name"];
    EXPECT_NEAR(tp[k]["sigma"].get<double>(), sigma, 1e-6 * sigma) << cp[k]["name"];
  }
  ASSERT_TRUE(ceres.contains("lever_arm_m"));
  ASSERT_TRUE(taylor.contains("lever_arm_m"));
  for (int axis = 0; axis < 3; ++axis)
    EXPECT_NEAR(taylor["lever_arm_m"][axis].get<double>(), ceres["lever_arm_m"][axis].get<double>(),
                1e-4)  // m; measured 8.4e-6 (z), where Ceres stops
        << axis;
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
  EXPECT_NE(report["summary"]["covariance_datum"].get<std::string>().find(
                "inner constraints on the"),
            std::string::npos);
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

// With --estimate_accuracies sigma0 ends near 1 whatever the data, so the search for gross errors
// cannot wait for sigma0 > 3: a group estimated at more than 3 times its stated accuracy starts it
// (the bundled example: 12 control-mark blunders of 20-200 px would make the control marks 37 times
// their 0.5 px and move the check points by a metre).
TEST(BundleCommand, EstimatedAccuraciesThatAbsorbGrossErrorsStartTheSearch) {
  const std::string dir = ScratchDir();
  const CliRun run = RunCli("bundle --cameras=" + SourcePath("examples/cameras.csv") + " --points=" +
                                SourcePath("examples/points.csv") + " --marks=" +
                                SourcePath("examples/marks.csv") + " --frames=" +
                                SourcePath("examples/frames_approx.csv") +
                                " --estimate_accuracies --out=" + dir + "/f.csv --report=" + dir +
                                "/r.json",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("control_marks estimated at"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("searching every group for gross errors"), std::string::npos) << run.err;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/r.json"));
  const nlohmann::json& rmse = report["check_rmse_m"];
  EXPECT_GT(rmse["count"].get<int>(), 25);
  for (const char* axis : {"x", "y", "z"}) EXPECT_LT(rmse[axis].get<double>(), 0.05) << axis;  // 1 m before
  for (const auto& group : report["groups"]) {
    if (group["name"] != "control_marks") continue;
    EXPECT_LT(group["estimated_accuracy"].get<double>(), 1.0);  // px; 18.6 before
  }
}

// A relative block's covariance datum: the inner constraints on the points by default, the
// adjustment's gauge (its first image without a covariance) on request; refused where the block has
// its own datum, and a name it does not know is refused with the choices.
TEST(BundleCommand, RelativeCovarianceDatumIsChosenAndReported) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const std::string common = "bundle --colmap_model=" + block + "/colmap --quiet --report=" + dir;
  CliRun run = RunCli(common + "/gauge.json --relative_covariance=first_image", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = RunCli(common + "/points.json", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json gauge = nlohmann::json::parse(ReadFile(dir + "/gauge.json"));
  const nlohmann::json points = nlohmann::json::parse(ReadFile(dir + "/points.json"));
  EXPECT_NE(gauge["summary"]["covariance_datum"].get<std::string>().find("the adjustment's gauge"),
            std::string::npos);
  EXPECT_NE(points["summary"]["covariance_datum"].get<std::string>().find("adjusted points"),
            std::string::npos);
  // The residuals do not depend on the datum (the same adjustment; threads sum in any order).
  EXPECT_NEAR(gauge["summary"]["sigma0"].get<double>(), points["summary"]["sigma0"].get<double>(),
              1e-12);
  EXPECT_EQ(gauge["rejected_marks"].size(), points["rejected_marks"].size());

  run = RunCli(common + "/x.json --pixel_center_origin", dir);  // a model's pixels are its own
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--pixel_center_origin applies to the tables"), std::string::npos) << run.err;
  run = RunCli(common + "/x.json --relative_covariance=centers", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--relative_covariance"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("centres"), std::string::npos) << run.err;
  run = RunCli("bundle " + TableArgs(block) + " --out=" + dir +
                   "/f.csv --quiet --relative_covariance=points",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("this block's datum is its control points and camera positions"),
            std::string::npos)
      << run.err;
}

// Issue 21: an accuracy or datum flag the block cannot use is refused when given (exit 2, one
// line, before the adjustment: no iteration line, nothing written); where it acts it is taken.
TEST(BundleCommand, AccuracyAndDatumFlagsTheBlockCannotUseAreRefused) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const std::string out = " --out=" + dir + "/f.csv --report=" + dir + "/r.json";
  const std::string tables = "bundle " + TableArgs(block) + out;
  const std::string no_frames = "bundle --cameras=" + block + "/cameras.csv --points=" + block +
                                "/points.csv --marks=" + block + "/marks.csv" + out;
  const std::string model = "bundle --colmap_model=" + block + "/colmap" + out;
  const std::string absolute = "; this block's datum is its control points and camera positions";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {tables + " --relative_gauge=fixed",
       "photopose bundle: --relative_gauge chooses how a relative block's gauge is held while it "
       "is solved (a model without positions or control, or --bal)" + absolute},
      // Given at its default value it is still given: refused all the same.
      {tables + " --relative_gauge=free", "--relative_gauge chooses"},
      {tables + " --film_tie_accuracy=3",
       "photopose bundle: --film_tie_accuracy is the accuracy of tie marks in film coordinates "
       "(FilmX/FilmY) without an Accuracy, on a camera without a pixel size; no mark of this block "
       "is one"},
      {tables + " --film_marker_projection_accuracy=2",
       "photopose bundle: --film_marker_projection_accuracy is the accuracy of control and check "
       "marks in film coordinates (FilmX/FilmY) without an Accuracy, on a camera without a pixel "
       "size; no mark of this block is one"},
      {no_frames + " --attitude_accuracy=1",
       "photopose bundle: --attitude_accuracy is the accuracy of measured attitudes without "
       "AccuracyOmega/Phi/Kappa (a frames table's Omega/Phi/Kappa with the tables); no image of "
       "this block has one (no --frames)"},
      {model + " --attitude_accuracy=1", "(the attitudes of --colmap_model, --opensfm and --bal are unknowns"},
      {model + " --film_tie_accuracy=3", "no mark of this block is one (the marks of --colmap_model, --opensfm and --bal are pixels)"},
      // The simulated tables state every mark's, point's and position's accuracy: no default is
      // taken (issue 21 audit: these four were accepted and ignored).
      {tables + " --tie_accuracy=2",
       "photopose bundle: --tie_accuracy is the accuracy of tie marks without an Accuracy (pixels, "
       "or film coordinates on a camera with a pixel size); no mark of this block is one (every "
       "tie mark has its own Accuracy or takes --film_tie_accuracy)"},
      {tables + " --marker_projection_accuracy=1",
       "photopose bundle: --marker_projection_accuracy is the accuracy of control and check marks "
       "without an Accuracy (pixels, or film coordinates on a camera with a pixel size); no mark of "
       "this block is one (every control and check mark has its own Accuracy or takes "
       "--film_marker_projection_accuracy)"},
      {tables + " --marker_accuracy=0.01",
       "photopose bundle: --marker_accuracy is the accuracy of control and check point coordinates "
       "without AccuracyX/Y/Z; no point of this block is one (every control and check point has "
       "its own AccuracyX/Y/Z)"},
      {tables + " --camera_accuracy=0.1",
       "photopose bundle: --camera_accuracy is the accuracy of measured camera positions without "
       "their own (AccuracyX/Y/Z, a geo.txt's or RTK accuracies); no image of this block has one "
       "(every camera position has its own accuracy)"},
      {no_frames + " --camera_accuracy=0.1", "no image of this block has one (no --frames)"},
      {model + " --marker_accuracy=0.01",
       "no point of this block is one (no control: --gcp_list, or --points with --crs, give it "
       "beside a model)"},
      {model + " --marker_projection_accuracy=1", "no mark of this block is one (it has no control or check marks)"},
      {model + " --camera_accuracy=1",
       "no image of this block has one (no camera positions: --geo, --frames, --images or "
       "--model_gps give them beside a model)"},
  };
  for (const auto& [arguments, message] : cases) {
    const CliRun run = RunCli(arguments, dir);
    EXPECT_EQ(run.exit_code, 2) << arguments << "\n" << run.err;
    EXPECT_NE(run.err.find(message), std::string::npos) << arguments << "\n" << run.err;
    EXPECT_EQ(run.err.find("iteration"), std::string::npos) << arguments << "\n" << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << arguments << "\n" << run.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/f.csv")) << arguments;
    EXPECT_FALSE(std::filesystem::exists(dir + "/r.json")) << arguments;
  }
  // Where they act they are taken: the frames' Omega/Phi/Kappa become attitude priors, and a
  // relative model holds COLMAP's gauge from the start.
  CliRun run = RunCli(tables + " --quiet --attitude_accuracy=30", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/r.json"));
  int attitudes = 0;
  for (const nlohmann::json& group : report.at("groups"))
    if (group.at("name") == "attitudes") attitudes = group.at("count").get<int>();
  EXPECT_GT(attitudes, 0) << report.at("groups");
  run = RunCli(model + " --quiet --relative_gauge=fixed", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  // Tables without their Accuracy columns take the four defaults, and each flag changes its
  // group's stated accuracy by its ratio to the default (1 px, 0.5 px, 5 mm, 10 m).
  const std::string plain = dir + "/plain";
  std::filesystem::create_directories(plain);
  CopyWithoutColumns(block + "/marks.csv", plain + "/marks.csv", {"Accuracy"});
  CopyWithoutColumns(block + "/points.csv", plain + "/points.csv", {"AccuracyX", "AccuracyY", "AccuracyZ"});
  CopyWithoutColumns(block + "/frames.csv", plain + "/frames.csv", {"AccuracyX", "AccuracyY", "AccuracyZ"});
  const std::string plain_tables = "bundle --cameras=" + block + "/cameras.csv --points=" + plain +
                                   "/points.csv --marks=" + plain + "/marks.csv --frames=" + plain +
                                   "/frames.csv" + out + " --quiet";
  std::map<std::string, double> stated[2];
  for (const int flagged : {0, 1}) {
    run = RunCli(plain_tables + (flagged ? " --tie_accuracy=0.7 --marker_projection_accuracy=0.6 "
                                           "--marker_accuracy=0.02 --camera_accuracy=0.3"
                                         : ""),
                 dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    stated[flagged] = testing::StatedAccuracies(dir + "/r.json");
  }
  const std::map<std::string, double> ratio = {{"tie_marks", 0.7}, {"control_marks", 1.2},
                                               {"control_points", 4.0}, {"camera_positions", 0.03}};
  for (const auto& [group, expected] : ratio) {
    ASSERT_GT(stated[0][group], 0.0) << group;
    EXPECT_NEAR(stated[1][group] / stated[0][group], expected, 1e-9) << group;
  }
}

// Issue 22: data snooping, variance components and the cross-validation need the statistics;
// with --statistics=none each is refused before any work (it was ignored: --snoop kept 20
// blunders in), with either solver.
TEST(BundleCommand, StatisticsNoneRefusesWhatNeedsThem) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const std::string common = "bundle " + TableArgs(block) + " --out=" + dir + "/f.csv --report=" +
                             dir + "/r.json --statistics=none";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {" --snoop", "photopose bundle: --snoop needs the statistics (the w-test divides each residual by its observation's redundancy number, from the covariances); --statistics=none computes none: give --statistics=full or leave the flag out\n"},
      {" --estimate_accuracies", "photopose bundle: --estimate_accuracies needs the statistics (a group's variance factor divides by its redundancy, the sum of its redundancy numbers, from the covariances); --statistics=none computes none: give --statistics=full or leave the flag out\n"},
      {" --snoop --estimate_accuracies", "photopose bundle: --snoop needs the statistics"},
      {" --cross_validate", "photopose bundle: --cross_validate needs the statistics (a left-out control point's normalized error takes the images' uncertainty from the covariances); --statistics=none computes none"},
  };
  for (const std::string solver : {"", " --solver=taylor"}) {
    for (const auto& [flags, message] : cases) {
      const CliRun run = RunCli(common + solver + flags, dir);
      EXPECT_EQ(run.exit_code, 2) << solver << flags << "\n" << run.err;
      EXPECT_EQ(run.err.rfind(message, 0), 0u) << solver << flags << "\n" << run.err;
      EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
      EXPECT_FALSE(std::filesystem::exists(dir + "/r.json")) << solver << flags;
    }
  }
  // Turned off explicitly, each is no request: the run goes on.
  const CliRun run = RunCli(common + " --snoop=false --estimate_accuracies=false --quiet", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
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

// The bundled example with its marks' rows counted up (Row' = NRows - Row): --pixel_rows_up gives
// the frames of the original; the flag is refused where the block's own reader defines its pixels.
TEST(BundleCommand, RowsCountedUpGiveTheSameFramesWithPixelRowsUp) {
  const std::string dir = ScratchDir();
  const std::string down_marks = testing::WriteExampleMarksWithRowsUp(dir);
  // One thread: the frames are compared to 1e-9 m, and Ceres' sums over two threads differ from
  // run to run by up to 1e-6 m here (the same input gives different frames).
  const std::string common = "bundle --cameras=" + SourcePath("examples/cameras.csv") +
                             " --points=" + SourcePath("examples/points.csv") +
                             " --quiet --threads=1";
  CliRun run = RunCli(common + " --marks=" + down_marks + " --out=" + dir + "/down.csv", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = RunCli(common + " --marks=" + dir + "/marks_up.csv --pixel_rows_up --out=" + dir +
                   "/up.csv --report=" + dir + "/up.json",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // The report says how the rows were read.
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/up.json"));
  EXPECT_EQ(report["options"]["pixel_rows"], "up");
  EXPECT_EQ(report["options"]["pixel_origin"], "corner");
  const auto down = ReadFrames(dir + "/down.csv");
  const auto up = ReadFrames(dir + "/up.csv");
  ASSERT_EQ(down.size(), up.size());
  for (const auto& [raster, frame] : down) {
    ASSERT_EQ(up.count(raster), 1u) << raster;
    for (int k = 0; k < 6; ++k)
      EXPECT_NEAR(frame.eo.parameters[k], up.at(raster).eo.parameters[k], 1e-9) << raster << k;
  }
  // Without the flag the turned marks are another block: other frames, or no adjustment.
  run = RunCli(common + " --marks=" + dir + "/marks_up.csv --out=" + dir + "/wrong.csv", dir);
  if (run.exit_code == 0) {
    const auto wrong = ReadFrames(dir + "/wrong.csv");
    double largest = 0.0;
    for (const auto& [raster, frame] : wrong)
      if (down.count(raster))
        largest = std::max(largest, (frame.eo.center_in_ground() -
                                     down.at(raster).eo.center_in_ground()).norm());
    EXPECT_GT(largest, 1.0);
  }
  // The example's camera with its PixelSize (2.41 um, 5472 x 3648, film y up) as A0-B2 on rows
  // counted up: x = 2.41 (Column - 2736), y = 2.41 (Row' - 1824). --out_cameras writes them back as
  // read, and the frames are those of the PixelSize camera.
  std::vector<FrameCamera> cameras;
  ASSERT_TRUE(ReadCameraTable(SourcePath("examples/cameras.csv"), &cameras).ok());
  cameras[0].has_affine = true;
  cameras[0].affine_a = {-2736 * 2.41, 2.41, 0.0};
  cameras[0].affine_b = {-1824 * 2.41, 0.0, 2.41};
  ASSERT_TRUE(WriteCameraTable(dir + "/cameras_up.csv", cameras).ok());
  run = RunCli("bundle --cameras=" + dir + "/cameras_up.csv --points=" +
                   SourcePath("examples/points.csv") + " --quiet --threads=1 --marks=" + dir +
                   "/marks_up.csv --pixel_rows_up --out=" + dir + "/affine.csv --out_cameras=" +
                   dir + "/cameras_out.csv",
               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::vector<FrameCamera> written;
  ASSERT_TRUE(ReadCameraTable(dir + "/cameras_out.csv", &written).ok());
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(written[0].affine_a[k], cameras[0].affine_a[k], 1e-9) << k;
    EXPECT_NEAR(written[0].affine_b[k], cameras[0].affine_b[k], 1e-9) << k;
  }
  // The same pixel -> film map by another path of arithmetic: the same frames to 1e-5 m / rad.
  // Each run stops once its corrections fall below 0.001 mm (the bundle's position tolerance), so
  // two paths that differ only by rounding end up to a few of those apart (1.6e-6 m measured).
  for (const auto& [raster, frame] : ReadFrames(dir + "/affine.csv"))
    for (int k = 0; k < 6; ++k)
      EXPECT_NEAR(frame.eo.parameters[k], down.at(raster).eo.parameters[k], 1e-5) << raster << k;
  run = RunCli("bundle --bal=" + SharedDataPath("bal_dubrovnik/dubrovnik-3-7-pre.txt") +
                   " --pixel_rows_up --report=" + dir + "/r.json",
               dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--pixel_rows_up applies to the tables: --colmap_model, --opensfm and "
                         "--bal define their own pixels"),
            std::string::npos)
      << run.err;
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
// The same block with --statistics=none: sigma0 gives the alarm, but data snooping needs the
// statistics, so the block is not searched and the failure says so (it claimed "after the search
// for gross errors" of a search that could test nothing).
TEST(BundleCommand, Sigma0FarAboveOneWithoutStatisticsSaysTheBlockWasNotSearched) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  const CliRun run = RunCli("bundle --colmap_model=" + block + "/colmap --tie_accuracy=0.05 --out=" +
                                dir + "/frames.csv --report=" + dir + "/report.json --quiet "
                                "--statistics=none",
                            dir);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("the block disagrees with its stated accuracies by more than noise; not "
                         "searched for gross errors (data snooping needs the statistics, and "
                         "--statistics=none computes none)\n"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(run.err.find("searching every group"), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("after the search"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("and the block was not searched for gross errors (--statistics=none)"),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/frames.csv"));
}

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

// One control point 50 m off: sigma0 far above 3, the search for gross errors (data snooping in
// every group) finds it with either solver, and the block is then adjusted.
TEST(BundleCommand, AControlPoint50MetresOffIsFoundByTheSearchWithEitherSolver) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateBlock(dir);
  std::vector<std::string> lines;
  std::istringstream points(ReadFile(block + "/points.csv"));
  std::string moved;
  for (std::string line; std::getline(points, line);) {
    if (moved.empty() && line.find(",control") != std::string::npos) {
      moved = line.substr(0, line.find(','));
      const size_t x = line.find(',') + 1;
      const size_t end = line.find(',', x);
      line = line.substr(0, x) + std::to_string(std::stod(line.substr(x, end - x)) + 50.0) +
             line.substr(end);
    }
    lines.push_back(line);
  }
  ASSERT_FALSE(moved.empty());
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  testing::WriteFile(block + "/points.csv", text);
  for (const char* solver : {"ceres", "taylor"}) {
    const CliRun run = RunCli("bundle " + TableArgs(block) + " --solver=" + solver +
                                  " --quiet --out=" + dir + "/frames.csv --report=" + dir +
                                  "/report.json",
                              dir);
    EXPECT_EQ(run.exit_code, 0) << solver << ": " << run.err;
    EXPECT_NE(run.err.find("searching every group for gross errors"), std::string::npos)
        << solver << ": " << run.err;
    const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
    EXPECT_EQ(report["summary"]["termination"], "converged") << solver;
    EXPECT_LT(report["summary"]["sigma0"].get<double>(), 3.0) << solver;
    bool removed = false;
    for (const nlohmann::json& step : report["snooping"]) {
      removed = removed || (step["group"] == "control_points" &&
                            step["item"].get<std::string>().find(moved) != std::string::npos);
    }
    EXPECT_TRUE(removed) << solver << ": " << report["snooping"].dump();
  }
}

// A block of two lines (`flags` give the rest), written into dir/block; its path.
std::string SimulateTwoLineBlock(const std::string& dir, const std::string& flags) {
  const CliRun run =
      RunCli("simulate --scenario=block --lines=2 " + flags + " --out_dir=" + dir + "/block", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return dir + "/block";
}

std::string CsvText(const std::vector<std::vector<std::string>>& rows) {
  std::string text;
  for (const auto& row : rows) {
    for (size_t k = 0; k < row.size(); ++k) text += (k ? "," : "") + row[k];
    text += "\n";
  }
  return text;
}

// A surveyed observation the w-test rejects starts the search for gross errors even when the many
// tie marks keep sigma0 near 1 (issue 20): one control point 0.5 m off among five, and one control
// mark 30 px off, on a block without camera positions (sigma0 1.17-1.19; without the search both
// were "adjusted", exit 0, every image 0.1-0.5 m off at 2 cm sigmas). With either solver the
// search removes exactly the blunder and every centre is then within 5 sigma of the truth.
TEST(BundleCommand, ASurveyedObservationTheWTestRejectsStartsTheSearch) {
  const std::string dir = ScratchDir();
  const std::string flags = "--scenario=block --lines=3 --images_per_line=6 --control_points=5 "
                            "--check_points=3 --gnss=false --sim_seed=1";
  for (const std::string blunder : {"control_point", "control_mark"}) {
    const std::string block = dir + "/" + blunder;
    const CliRun simulated = RunCli(
        "simulate " + flags + (blunder == "control_point" ? " --control_blunders=1" : "") +
            " --out_dir=" + block, dir);
    ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
    std::string blundered = "C001";  // truth/blunders.csv names the moved control point
    if (blunder == "control_point") {
      ASSERT_NE(ReadFile(block + "/truth/blunders.csv").find("control_point,,C001,"), std::string::npos);
    } else {
      // The first mark of C002 moved 30 px along the row.
      auto marks = SplitCsvText(ReadFile(block + "/marks.csv"));
      ASSERT_EQ(marks[0][2], "Column");
      size_t moved = 0;
      for (size_t r = 1; r < marks.size() && moved == 0; ++r) {
        if (marks[r].size() > 2 && marks[r][1] == "C002") {
          marks[r][2] = std::to_string(std::stod(marks[r][2]) + 30.0);
          moved = r;
        }
      }
      ASSERT_GT(moved, 0u);
      blundered = "mark of 'C002' in '" + marks[moved][0] + "'";
      testing::WriteFile(block + "/marks.csv", CsvText(marks));
    }
    for (const char* solver : {"ceres", "taylor"}) {
      const CliRun run = RunCli("bundle " + TableArgs(block) + " --solver=" + solver +
                                    " --quiet --out=" + dir + "/frames.csv --report=" + dir +
                                    "/report.json",
                                dir);
      ASSERT_EQ(run.exit_code, 0) << blunder << ", " << solver << ": " << run.err;
      EXPECT_NE(run.err.find("but the w-test flags"), std::string::npos) << run.err;
      EXPECT_NE(run.err.find("searching every group for gross errors"), std::string::npos) << run.err;
      const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
      ASSERT_EQ(report["snooping"].size(), 1u) << blunder << ", " << solver << ": " << report["snooping"].dump();
      EXPECT_NE(report["snooping"][0]["item"].get<std::string>().find(blundered), std::string::npos)
          << report["snooping"].dump();
      const auto solved = ReadFrames(dir + "/frames.csv");
      const auto truth = ReadFrames(block + "/truth/frames.csv");
      ASSERT_EQ(solved.size(), 18u);
      for (const auto& [raster, frame] : solved) {
        ASSERT_TRUE(frame.covariance.has_value()) << raster;
        const Eigen::Vector3d error = frame.eo.center_in_ground() - truth.at(raster).eo.center_in_ground();
        for (int k = 0; k < 3; ++k)
          EXPECT_LT(std::abs(error[k]), 5.0 * std::sqrt((*frame.covariance)(k, k)) + 0.001)
              << blunder << ", " << solver << ", " << raster << " axis " << k;
      }
    }
  }
}

// A flag the chosen solver cannot use is refused, not ignored: --jacobian and --linear_solver are
// Ceres'; --max_iterations bounds the Taylor solver's rounds too (it was ignored: the Taylor path
// kept its own 50).
TEST(BundleCommand, EverySolverFlagIsHonouredOrRefused) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateTwoLineBlock(dir, "--images_per_line=5 --gnss=true");
  const std::string common = "bundle " + TableArgs(block) + " --quiet --out=" + dir +
                             "/frames.csv --report=" + dir + "/report.json";
  for (const std::string flag : {"--jacobian=autodiff", "--linear_solver=dense_schur"}) {
    const CliRun run = RunCli(common + " --solver=taylor " + flag, dir);
    EXPECT_EQ(run.exit_code, 2) << flag << ": " << run.err;
    EXPECT_NE(run.err.find(flag.substr(0, flag.find('=')) + " is for --solver=ceres"),
              std::string::npos) << run.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/frames.csv"));
  }
  for (const char* solver : {"ceres", "taylor"}) {
    const CliRun one = RunCli(common + " --solver=" + solver + " --max_iterations=1", dir);
    EXPECT_EQ(one.exit_code, 1) << solver << ": " << one.err;
    const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
    EXPECT_EQ(report["summary"]["termination"], "no_convergence") << solver;
    EXPECT_LE(report["summary"]["iterations"].get<int>(), report["summary"]["rounds"].get<int>()) << solver;
  }
}

// Control points with AccuracyX/Y/Z 0 are held fixed: the block (no camera positions) adjusts on
// them alone, they come out on their survey with sigmas 0, every tie point has its sigmas, and the
// group is reported "fixed" without a verdict; a row mixing 0 and non-zero is refused on one line
// naming file, line and field; resect takes the same table.
TEST(BundleCommand, ControlPointsWithAccuracyZeroAreHeldFixed) {
  const std::string dir = ScratchDir();
  const std::string block =
      SimulateTwoLineBlock(dir, "--images_per_line=5 --seed=3 --gnss=false --control_sigma=0");
  auto points = SplitCsvText(ReadFile(block + "/points.csv"));
  ASSERT_EQ(points[0][4], "AccuracyX");
  ASSERT_EQ(points[0][7], "Role");
  std::map<std::string, std::vector<std::string>> surveyed;
  for (size_t r = 1; r < points.size(); ++r) {
    if (points[r].size() < 8 || points[r][7] != "control") continue;
    points[r][4] = points[r][5] = points[r][6] = "0";
    surveyed[points[r][0]] = points[r];
  }
  ASSERT_GE(surveyed.size(), 4u);
  testing::WriteFile(dir + "/points0.csv", CsvText(points));
  const std::string inputs = "--cameras=" + block + "/cameras.csv --points=" + dir +
                             "/points0.csv --marks=" + block + "/marks.csv";
  const CliRun run = RunCli("bundle " + inputs + " --out=" + dir + "/frames.csv --out_points=" +
                                dir + "/adjusted.csv --report=" + dir + "/report.json --html=" +
                                dir + "/report.html --quiet",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("control_points: " + std::to_string(surveyed.size()) +
                         " held fixed (stated error-free): no residuals, no verdict"),
            std::string::npos)
      << run.out;
  EXPECT_EQ(run.out.find("control_points over-fitted"), std::string::npos) << run.out;

  const auto adjusted = SplitCsvText(ReadFile(dir + "/adjusted.csv"));
  ASSERT_EQ(CsvText({adjusted[0]}),
            "PointID,X,Y,Z,SigmaX,SigmaY,SigmaZ,Role,NumObservations,SurveyedX,SurveyedY,SurveyedZ,"
            "ErrorX,ErrorY,ErrorZ,SRS\n");
  int fixed = 0, tie = 0;
  for (size_t r = 1; r < adjusted.size(); ++r) {
    const auto& row = adjusted[r];
    if (row.size() < 8) continue;
    if (row[7] == "control") {
      ++fixed;
      const auto& in = surveyed.at(row[0]);
      for (int k = 1; k <= 3; ++k) EXPECT_EQ(std::stod(row[k]), std::stod(in[k])) << row[0];
      for (int k = 4; k <= 6; ++k) EXPECT_EQ(row[k], "0") << row[0];
    } else if (row[7] == "tie") {
      ++tie;
      for (int k = 4; k <= 6; ++k) {
        ASSERT_FALSE(row[k].empty()) << row[0];
        EXPECT_GT(std::stod(row[k]), 0.0) << row[0];
      }
    }
  }
  EXPECT_EQ(fixed, static_cast<int>(surveyed.size()));
  EXPECT_GT(tie, 100);

  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  bool found = false;
  for (const auto& group : report["groups"]) {
    if (group["name"] != "control_points") continue;
    found = true;
    EXPECT_TRUE(group["fixed"].get<bool>());
    EXPECT_EQ(group["num_fixed"].get<int>(), static_cast<int>(surveyed.size()));
    EXPECT_EQ(group["count"].get<int>(), 0);
    EXPECT_FALSE(group["overfit"].get<bool>());
  }
  EXPECT_TRUE(found);
  ASSERT_EQ(report["control_points"].size(), surveyed.size());
  for (const auto& point : report["control_points"]) {
    EXPECT_TRUE(point["fixed"].get<bool>()) << point;
    EXPECT_EQ(point["sigma_m"], nlohmann::json::parse("[0.0, 0.0, 0.0]")) << point;
  }
  EXPECT_EQ(report["control_rmse_m"]["count"].get<int>(), 0);
  const std::string html = ReadFile(dir + "/report.html");
  EXPECT_NE(html.find("<b>Held fixed:</b> " + std::to_string(surveyed.size()) + " control points"),
            std::string::npos);
  EXPECT_NE(html.find("<td>held fixed</td>"), std::string::npos);

  // resect takes the same points: control is fixed in a resection anyway.
  const CliRun resected = RunCli("resect " + inputs + " --out=" + dir + "/resected.csv", dir);
  EXPECT_EQ(resected.exit_code, 0) << resected.err;

  // 0 beside a non-zero accuracy: one line naming the file, line and field; nothing written.
  auto mixed = points;
  size_t row = 1;
  while (mixed[row][7] != "control") ++row;
  mixed[row][5] = "0.01";
  testing::WriteFile(dir + "/mixed.csv", CsvText(mixed));
  const CliRun refused = RunCli("bundle --cameras=" + block + "/cameras.csv --points=" + dir +
                                    "/mixed.csv --marks=" + block + "/marks.csv --out=" + dir +
                                    "/refused.csv --quiet",
                                dir);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_EQ(refused.err, "photopose bundle: " + dir + "/mixed.csv:" + std::to_string(row + 1) +
                             ": AccuracyY: 0.01 beside AccuracyX 0: AccuracyX, AccuracyY, "
                             "AccuracyZ are all positive, or all 0 (the point held fixed)\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/refused.csv"));
}

// Film marks (FilmX/FilmY) of a camera without PixelSize: adjusted (their defaults are in um),
// and the groups print um, not "px or um".
TEST(BundleCommand, FilmMarksOfACameraWithoutPixelSizeAreAdjustedInMicrometres) {
  const std::string dir = ScratchDir();
  const std::string block = SimulateTwoLineBlock(dir, "--images_per_line=4 --seed=5");
  // The simulated camera: 6000 x 4000 pixels of 4 um, principal point at the centre, film y up.
  auto cameras = SplitCsvText(ReadFile(block + "/cameras.csv"));
  ASSERT_EQ(cameras[0][5], "PixelSize");
  ASSERT_EQ(cameras[1][5], "4");
  ASSERT_EQ(cameras[1][6] + "x" + cameras[1][7], "4000x6000");
  cameras[1][5] = "";
  testing::WriteFile(dir + "/cameras.csv", CsvText(cameras));
  auto marks = SplitCsvText(ReadFile(block + "/marks.csv"));
  ASSERT_EQ(CsvText({marks[0]}), "Raster,PointID,Column,Row,FilmX,FilmY,Accuracy,CameraID\n");
  for (size_t r = 1; r < marks.size(); ++r) {
    if (marks[r].size() < 8) continue;
    marks[r][4] = std::to_string((std::stod(marks[r][2]) - 3000.0) * 4.0);
    marks[r][5] = std::to_string(-(std::stod(marks[r][3]) - 2000.0) * 4.0);
    marks[r][2] = marks[r][3] = marks[r][6] = "";  // no Accuracy: the film defaults
  }
  testing::WriteFile(dir + "/marks.csv", CsvText(marks));
  const CliRun run = RunCli("bundle --cameras=" + dir + "/cameras.csv --points=" + block +
                                "/points.csv --marks=" + dir + "/marks.csv --frames=" + block +
                                "/frames.csv --out=" + dir + "/frames.csv --quiet",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("tie_marks: "), std::string::npos) << run.out;
  EXPECT_NE(run.out.find(", stated 5.00 um, RMS "), std::string::npos) << run.out;  // --film_tie_accuracy
  EXPECT_NE(run.out.find(", stated 2.50 um, RMS "), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("px"), std::string::npos) << run.out;
  // Film marks without an Accuracy on a camera without a pixel size: the film flags are taken.
  const CliRun stated = RunCli("bundle --cameras=" + dir + "/cameras.csv --points=" + block +
                                   "/points.csv --marks=" + dir + "/marks.csv --frames=" + block +
                                   "/frames.csv --out=" + dir + "/frames.csv --quiet "
                                   "--film_tie_accuracy=4 --film_marker_projection_accuracy=2",
                               dir);
  ASSERT_EQ(stated.exit_code, 0) << stated.err;
  EXPECT_NE(stated.out.find(", stated 4.00 um, RMS "), std::string::npos) << stated.out;
  EXPECT_NE(stated.out.find(", stated 2.00 um, RMS "), std::string::npos) << stated.out;
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

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
