// The console lines of `photopose bundle` (tools/report/bundle_report.cc): every number in fixed
// units through the report kit, never in scientific notation; the warning when variance
// components absorbed gross errors.
#include "tools/report/bundle_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "tests/support/bundle_groups.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

// A digit or point followed by an exponent: "6.97e-05", "1e+04", "5.7E7".
const std::regex kScientific("[0-9.][eE][+-]?[0-9]");

// Redundancy share 0.00007: %g would print it with an exponent.
BundleGroupStatistics Group(BundleGroup group, const std::string& unit, double stated, double rms) {
  return testing::GroupOf(group, unit, stated, rms, 0.00007);
}

// A result whose figures all take an exponent under printf's %g: tiny lengths and times, a large
// cost.
BundleAdjustmentResult TinyAndLargeFigures() {
  BundleAdjustmentResult result;
  BundleAdjustmentSummary& s = result.summary;
  s.termination = SolverTermination::kConverged;
  s.num_images = 1;
  s.num_points = 143;
  s.num_marks = 656;
  s.rounds = 1;
  s.iterations = 4;
  s.initial_cost = 5.71083e+07;
  s.final_cost = 2.5e-05;
  s.sigma0 = 0.0000123;
  s.redundancy = 1276;
  s.time_seconds = 0.0000456;
  s.problem_build_seconds = 0.000061;
  s.statistics_seconds = 1.5e-05;
  s.datum_description = "absolute";
  result.groups.push_back(Group(kControlMarks, "px", 0.5, 0.0000446));
  result.groups.push_back(Group(kControlPoints, "m", 0.005, 6.97e-05));
  result.groups.push_back(Group(kAttitudes, "deg", 0.01, 0.0000214));
  result.groups.back().estimated_accuracy = Eigen::Vector3d::Constant(0.0000214);
  result.groups.back().estimated_accuracy_standard_error = 0.12;
  result.num_control_points = 143;
  result.control_rmse_total_m = 6.97e-05;
  result.num_check_points = 31;
  result.check_rmse_m = Eigen::Vector3d(6.97e-05, 0.0000088, 0.0000225);
  result.check_rmse_total_m = 0.0000734;
  return result;
}

TEST(BundleReport, ConsoleLinesNeverPrintAnExponent) {
  const std::vector<std::string> lines =
      BundleConsoleLines(Block(), TinyAndLargeFigures(), BundleReportContext());
  ASSERT_GE(lines.size(), 8u);
  for (const std::string& line : lines)
    EXPECT_FALSE(std::regex_search(line, kScientific)) << line;
  // Fixed units: lengths in mm (one unit for a row of axes), sigma0 unitless, seconds.
  const auto has = [&](const std::string& text) {
    for (const std::string& line : lines)
      if (line.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("check points: 31, RMSE X 0.1 Y 0.0 Z 0.0 total 0.1 mm"));
  EXPECT_TRUE(has("control points: 143, RMSE 0.1 mm"));
  // The group's own figures: two significant digits for the smallest (0.070 mm, not 0.1 mm).
  EXPECT_TRUE(has("control_points: 12, stated 5.000 mm, RMS 0.070 mm"));
  EXPECT_TRUE(has("cost 57108300 -> 0.000025, sigma0 0.000 (unitless; redundancy 1276)"));
  EXPECT_TRUE(has("1 image, 143 points"));
  EXPECT_TRUE(has("attitudes: 36.000 arcsec stated, 0.077 arcsec estimated (+-12 %)"));
  EXPECT_TRUE(has("time: problem 0.000061 s"));
}

// One unit per line: a group's stated accuracy, RMS and estimate are printed in the unit the
// largest of them calls for, not each in its own (no "stated 10.000 m, RMS 278.7 cm"), with the
// decimals that give the smallest two significant digits; each group in its own unit.
TEST(BundleReport, AGroupLinePrintsItsLengthsInOneUnit) {
  BundleAdjustmentResult result;
  result.summary.datum_description = "absolute";
  result.groups.push_back(Group(kCameraPositions, "m", 10.0, 2.787));
  result.groups.back().estimated_accuracy = Eigen::Vector3d::Constant(3.1);
  result.groups.back().estimated_accuracy_standard_error = 0.2;
  result.groups.push_back(Group(kControlPoints, "m", 0.005, 0.25));
  const std::vector<std::string> lines = BundleConsoleLines(Block(), result, BundleReportContext());
  const auto has = [&](const std::string& text) {
    for (const std::string& line : lines)
      if (line.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("camera_positions: 12, stated 10.0 m, RMS 2.8 m, RMS/stated 0.28"));
  EXPECT_TRUE(
      has("camera_positions: 10.0 m stated, 3.1 m estimated (+-20 %): set "
          "--camera_accuracy=3.1"));
  EXPECT_TRUE(has("control_points: 12, stated 0.50 cm, RMS 25.00 cm, RMS/stated 50.00"));
  // The gross-error warning's two accuracies too.
  BundleGroupStatistics points = Group(kControlPoints, "m", 0.005, 0.25);
  points.estimated_accuracy = Eigen::Vector3d::Constant(0.26);
  EXPECT_NE(GrossErrorsAbsorbed(points, UnitText::kAscii).find("the estimated accuracy 26.00 cm is 52.0 times the "
                                             "stated 0.50 cm"),
            std::string::npos)
      << GrossErrorsAbsorbed(points, UnitText::kAscii);
}

// GNSS stated at 3/3/6 cm: the line shows X/Y/Z, so that RMS/stated (whitened over the three
// axes) can be read against them; equal axes keep one figure.
TEST(BundleReport, AGroupStatedPerAxisShowsEachAxis) {
  BundleAdjustmentResult result;
  result.summary.datum_description = "absolute";
  result.groups.push_back(Group(kCameraPositions, "m", 0.03, 0.0413));
  result.groups.back().num_axes = 3;
  result.groups.back().stated_accuracy = Eigen::Vector3d(0.03, 0.03, 0.06);
  result.groups.back().ratio = 0.97;
  result.groups.push_back(Group(kControlPoints, "m", 0.005, 0.004));
  result.groups.back().num_axes = 3;
  const std::vector<std::string> lines = BundleConsoleLines(Block(), result, BundleReportContext());
  const auto has = [&](const std::string& text) {
    for (const std::string& line : lines)
      if (line.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("camera_positions: 12, stated X/Y/Z 30.0/30.0/60.0 mm, RMS 41.3 mm, "
                  "RMS/stated 0.97"));
  EXPECT_TRUE(has("control_points: 12, stated 5.0 mm, RMS 4.0 mm,"));
}

// A control point without a stated accuracy that data snooping removed was judged against the
// default --marker_accuracy: the console says so, naming it; one with its own accuracy is a
// blunder by its own standard and is not in the warning.
TEST(BundleReport, ControlRemovedOnAnAssumedAccuracyIsSaid) {
  Block block;
  for (const char* id : {"C1", "C2", "C3", "T1"}) {
    BlockPoint point;
    point.id = id;
    point.role = id[0] == 'C' ? PointRole::kControl : PointRole::kTie;
    block.points.push_back(point);
  }
  block.points[2].accuracy_m = Eigen::Vector3d::Constant(0.02);  // C3 states its own
  BundleAdjustmentResult result;
  result.points.resize(4);
  EXPECT_EQ(ControlRemovedOnAssumedAccuracy(block, result, 0.005), "");
  BundleSnoopingStep c1x, c1z, c3;
  c1x.group = c1z.group = c3.group = kControlPoints;
  c1x.item = c1z.item = 0;
  c1z.axis = 2;
  c3.item = 2;
  result.snooping = {c3};
  EXPECT_EQ(ControlRemovedOnAssumedAccuracy(block, result, 0.005), "") << "C3 states its own";
  result.snooping = {c1x, c3, c1z};
  const std::string expected =
      "data snooping removed 1 of 2 control points whose accuracy the points table does not state "
      "('C1'): they were tested against --marker_accuracy, 5.0 mm. If they were surveyed less "
      "accurately, they are not blunders: state AccuracyX/Y/Z or --marker_accuracy and adjust "
      "again.";
  EXPECT_EQ(ControlRemovedOnAssumedAccuracy(block, result, 0.005), expected);
  BundleReportContext context;
  context.options.accuracies.marker_m = 0.005;
  const std::vector<std::string> lines = BundleConsoleLines(block, result, context);
  EXPECT_NE(std::find(lines.begin(), lines.end(), "warning: " + expected), lines.end());
}

// A check point whose error its covariance cannot explain (e^T C^-1 e above the chi-square(3)
// 99.9 % quantile, 16.27) is named on the console as on the page; one within it is not. C is the
// intersection's covariance plus the surveyed coordinates': a point surveyed to 3 cm that misses
// by 6 cm is within it, though the intersection alone (1 cm) would call it out.
TEST(BundleReport, ACheckPointBeyondItsCovarianceIsNamedOnTheConsole) {
  Block block;
  for (const char* id : {"C1", "K1", "K2", "K3", "K4"}) {
    BlockPoint point;
    point.id = id;
    point.role = id[0] == 'C' ? PointRole::kControl : PointRole::kCheck;
    block.points.push_back(point);
  }
  block.points[3].accuracy_m = Eigen::Vector3d::Constant(0.03);  // K3: surveyed to 3 cm
  block.points[4].accuracy_m = Eigen::Vector3d::Zero();          // K4: stated error-free
  BundleAdjustmentResult result;
  result.points.resize(5);
  for (BundlePointResult& r : result.points) {
    r.has_covariance = true;
    r.covariance_complete = true;
    r.covariance = Eigen::Matrix3d::Identity() * 1e-4;  // 1 cm per axis
  }
  result.points[0].error_m = Eigen::Vector3d(0.10, 0.0, 0.0);   // control: not tested here
  result.points[1].error_m = Eigen::Vector3d(0.05, 0.0, 0.0);   // 0.05^2 / (1e-4 + 0.005^2) = 20
  result.points[2].error_m = Eigen::Vector3d(0.02, 0.02, 0.0);  // 6.4 < 16.27
  result.points[3].error_m = Eigen::Vector3d(0.06, 0.0, 0.0);   // 0.06^2 / (1e-4 + 9e-4) = 3.6
  result.points[4].error_m = Eigen::Vector3d(0.05, 0.0, 0.0);   // 0.05^2 / 1e-4 = 25
  result.num_check_points = 4;
  const double marker_m = 0.005;  // the default marker accuracy of a point that states none
  EXPECT_NEAR(CheckPointNormalizedError(block.points[1], result.points[1], marker_m), 20.0, 1e-9);
  EXPECT_NEAR(CheckPointNormalizedError(block.points[3], result.points[3], marker_m), 3.6, 1e-9);
  EXPECT_NEAR(CheckPointNormalizedError(block.points[4], result.points[4], marker_m), 25.0, 1e-9);
  const std::vector<std::string> misses = CheckPointsOutOfTolerance(block, result, marker_m);
  ASSERT_EQ(misses.size(), 2u);
  EXPECT_EQ(misses[0],
            "K1 misses by 50.0 mm where its sigma is 19.4 mm (e^T C^-1 e = 20.0 > 16.3): check its "
            "surveyed coordinates and its marks");
  EXPECT_EQ(misses[1],
            "K4 misses by 50.0 mm where its sigma is 17.3 mm (e^T C^-1 e = 25.0 > 16.3): check its "
            "surveyed coordinates and its marks");
  // The console takes the run's default marker accuracy from its options.
  BundleReportContext context;
  context.options.accuracies.marker_m = marker_m;
  size_t warnings = 0;
  for (const std::string& line : BundleConsoleLines(block, result, context))
    if (line.rfind("warning: check point ", 0) == 0) {
      EXPECT_EQ(line, "warning: check point " + misses[warnings]);
      ++warnings;
    }
  EXPECT_EQ(warnings, 2u);
  // A larger default accuracy explains K1 (0.05^2 / (1e-4 + 0.02^2) = 5), not K4 (stated 0).
  EXPECT_EQ(CheckPointsOutOfTolerance(block, result, 0.02).size(), 1u);
  // The intersection's covariance alone (no statistics: the images taken as error-free) is too
  // small to test against: no verdict, null in the JSON, flagged there as incomplete.
  result.points[1].covariance_complete = false;
  EXPECT_TRUE(std::isnan(CheckPointNormalizedError(block.points[1], result.points[1], marker_m)));
  EXPECT_TRUE(std::isnan(CheckPointErrorSigma(block.points[1], result.points[1], marker_m)));
  ASSERT_EQ(CheckPointsOutOfTolerance(block, result, marker_m).size(), 1u);
  const nlohmann::json json = BundleReportJson(block, result, context);
  ASSERT_EQ(json["check_points"].size(), 4u);
  EXPECT_EQ(json["check_points"][0]["covariance_complete"], false);
  EXPECT_TRUE(json["check_points"][0]["normalized_error"].is_null());
  EXPECT_TRUE(json["check_points"][0]["error_sigma_m"].is_null());
  EXPECT_EQ(json["check_points"][1]["covariance_complete"], true);
  result.points[1].has_covariance = false;  // no covariance: nothing to test against
  result.points[4].has_covariance = false;
  EXPECT_TRUE(CheckPointsOutOfTolerance(block, result, marker_m).empty());
}

// The README's example with --estimate_accuracies: the control marks' gross errors (5 % of the
// marks, 20-200 px) stay in and the estimation makes 0.5 px into 18.6 px. The report says so in
// words; an estimate within the factor says nothing.
TEST(BundleReport, AnEstimateFarAboveTheStatedAccuracyIsCalledGrossErrors) {
  BundleGroupStatistics marks = Group(kControlMarks, "px", 0.5, 17.8);
  marks.estimated_accuracy = Eigen::Vector3d::Constant(18.6);
  const std::string text = GrossErrorsAbsorbed(marks, UnitText::kAscii);
  EXPECT_NE(text.find("control_marks: the estimated accuracy 18.60 px is 37.2 times the stated "
                      "0.50 px: gross errors"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("check marks are tested with this accuracy"), std::string::npos);
  EXPECT_NE(text.find("largest |w|"), std::string::npos);  // what to check after the search
  BundleAdjustmentResult result = TinyAndLargeFigures();
  result.groups.push_back(marks);
  bool warned = false;
  for (const std::string& line : BundleConsoleLines(Block(), result, BundleReportContext()))
    warned = warned || line == "warning: " + text;
  EXPECT_TRUE(warned);

  // Film marks: the console's line names um, a page's µm.
  BundleGroupStatistics film = Group(kTieMarks, "um", 2.0, 7.5);
  film.estimated_accuracy = Eigen::Vector3d::Constant(8.0);
  EXPECT_NE(GrossErrorsAbsorbed(film, UnitText::kAscii)
                .find("the estimated accuracy 8.00 um is 4.0 times the stated 2.00 um:"),
            std::string::npos)
      << GrossErrorsAbsorbed(film, UnitText::kAscii);
  EXPECT_NE(GrossErrorsAbsorbed(film, UnitText::kUtf8)
                .find("the estimated accuracy 8.00 \u00b5m is 4.0 times the stated 2.00 \u00b5m:"),
            std::string::npos)
      << GrossErrorsAbsorbed(film, UnitText::kUtf8);

  marks.estimated_accuracy = Eigen::Vector3d::Constant(1.4);  // 2.8 times: a misstated accuracy
  EXPECT_EQ(GrossErrorsAbsorbed(marks, UnitText::kAscii), "");
  marks.estimated_accuracy = Eigen::Vector3d::Constant(std::nan(""));  // not estimated
  EXPECT_EQ(GrossErrorsAbsorbed(marks, UnitText::kAscii), "");
}

// A group's figures on the console are the library's (FormatGroupFigures, tested in
// tests/solvers/bundle/bundle_adjustment_test.cc): the control points' RMS of 0.5 mm beside camera
// positions stated at 10 m, each in its own unit.
TEST(BundleReport, AGroupLineShowsTheLibrarysFigures) {
  BundleGroupStatistics points = Group(kControlPoints, "m", 0.005, 0.0005);
  BundleAdjustmentResult result;
  result.groups = {Group(kCameraPositions, "m", 10.0, 12.0), points};
  const std::vector<std::string> lines = BundleConsoleLines(Block(), result, BundleReportContext());
  for (const BundleGroupStatistics& g : result.groups) {
    const BundleGroupFigures figures = FormatGroupFigures(g);
    const std::string start = std::string(EnumName(g.group)) + ": 12, stated " + figures.stated +
                              " " + figures.unit + ", RMS " + figures.rms + " " + figures.unit +
                              ",";
    EXPECT_NE(std::find_if(lines.begin(), lines.end(),
                           [&](const std::string& line) { return line.rfind(start, 0) == 0; }),
              lines.end())
        << start;
  }
  EXPECT_NE(std::find_if(lines.begin(), lines.end(),
                         [](const std::string& line) {
                           return line.rfind("control_points: 12, stated 5.00 mm, RMS 0.50 mm,",
                                             0) == 0;
                         }),
            lines.end());
}

// Without statistics (--statistics=none) no prior group has a redundancy share and no over-fitting
// verdict was made: the JSON's `overfit` is null there, not false; a mark group and a judged prior
// group keep their boolean.
TEST(BundleReport, OverfitIsNullWhenNotJudged) {
  BundleAdjustmentResult result;
  result.groups = {Group(kTieMarks, "px", 0.5, 0.4), Group(kControlPoints, "m", 0.005, 0.004),
                   Group(kCameraPositions, "m", 0.05, 0.04)};
  result.groups[0].redundancy_share = std::nan("");
  result.groups[1].redundancy_share = std::nan("");
  result.groups[2].redundancy_share = 0.6;
  EXPECT_TRUE(OverfitJudged(result.groups[0]));
  EXPECT_FALSE(OverfitJudged(result.groups[1]));
  EXPECT_TRUE(OverfitJudged(result.groups[2]));
  const nlohmann::json report = BundleReportJson(Block(), result, BundleReportContext());
  ASSERT_EQ(report["groups"].size(), 3u);
  EXPECT_EQ(report["groups"][0]["overfit"], false);
  EXPECT_TRUE(report["groups"][1]["overfit"].is_null());
  EXPECT_EQ(report["groups"][2]["overfit"], false);
  // The console says so too.
  bool said = false;
  for (const std::string& line : BundleConsoleLines(Block(), result, BundleReportContext()))
    said = said || (line.rfind("control_points:", 0) == 0 &&
                    line.find("over-fitting not judged") != std::string::npos);
  EXPECT_TRUE(said);
  // An RMS far below the stated accuracy (0.28 of a 10 m statement) without a share is no verdict
  // either (the library flags nothing then: over-fitting and a loose accuracy look the same).
  result.groups[2].redundancy_share = std::nan("");
  result.groups[2].ratio = 0.28;
  EXPECT_FALSE(OverfitJudged(result.groups[2]));
  EXPECT_TRUE(BundleReportJson(Block(), result, BundleReportContext())["groups"][2]["overfit"].is_null());
  // A fixed group (every point held fixed) is never over-fitted: judged.
  BundleGroupStatistics fixed = Group(kControlPoints, "m", 0.0, 0.0);
  fixed.count = 0;
  fixed.num_fixed = 4;
  fixed.redundancy_share = std::nan("");
  EXPECT_TRUE(OverfitJudged(fixed));
}

// A block without check points (or control points) has no RMSE: null in the JSON, not a zero
// error; with points, the figures.
TEST(BundleReport, RmseIsNullWithoutAPoint) {
  BundleAdjustmentResult result;
  const nlohmann::json none = BundleReportJson(Block(), result, BundleReportContext());
  for (const char* key : {"check_rmse_m", "control_rmse_m"})
    for (const char* axis : {"x", "y", "z", "total"}) EXPECT_TRUE(none[key][axis].is_null()) << key << " " << axis;
  result.num_check_points = 3;
  result.check_rmse_m = Eigen::Vector3d(0.01, 0.02, 0.03);
  result.check_rmse_total_m = 0.0216;
  const nlohmann::json some = BundleReportJson(Block(), result, BundleReportContext());
  EXPECT_DOUBLE_EQ(some["check_rmse_m"]["y"].get<double>(), 0.02);
  EXPECT_DOUBLE_EQ(some["check_rmse_m"]["total"].get<double>(), 0.0216);
  EXPECT_TRUE(some["control_rmse_m"]["total"].is_null());
}

// The diagnostics' single-precision values (BundleObservationDiagnostics) print as their shortest
// decimal, 0.1 and not the double 0.10000000149011612 that 0.1f converts to; the double ones in
// full.
TEST(BundleReport, SinglePrecisionDiagnosticsPrintTheirShortestDecimal) {
  Block block;
  block.cameras.resize(1);
  block.cameras[0].camera_id = "c1";
  block.images.resize(1);
  block.images[0].name = "IMG_1";
  block.images[0].camera = 0;
  block.points.resize(1);
  block.points[0].id = "T1";
  block.marks.resize(1);
  block.marks[0].image = 0;
  block.marks[0].point = 0;
  BundleAdjustmentResult result;
  result.images.resize(1);
  result.points.resize(1);
  result.mark_residuals.assign(1, Eigen::Vector2d(0.05, 0.1));
  BundleObservationDiagnostics d;
  d.group = kTieMarks;
  d.item = 0;
  d.axis = 1;
  d.residual = 0.1f;
  d.sigma = 0.3f;
  d.mdb = 1.1f;
  d.external_m = 0.07f;
  d.redundancy = 0.1;
  d.normalized = 1.0 / 3.0;
  d.rejected = true;
  result.observations.push_back(d);
  const nlohmann::json report = BundleReportJson(block, result, BundleReportContext());
  const nlohmann::json& row = report["diagnostics"]["rejected"].at(0);
  EXPECT_EQ(row["axis"], "y");
  EXPECT_EQ(row["residual"].dump(), "0.1");
  EXPECT_EQ(row["sigma"].dump(), "0.3");
  EXPECT_EQ(row["mdb"].dump(), "1.1");
  EXPECT_EQ(row["external_m"].dump(), "0.07");
  EXPECT_EQ(row["normalized_residual"].get<double>(), 1.0 / 3.0);
  EXPECT_EQ(report["diagnostics"]["images"].at(0)["largest_mdb"].dump(), "1.1");
  EXPECT_EQ(report["diagnostics"]["images"].at(0)["largest_external_m"].dump(), "0.07");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
