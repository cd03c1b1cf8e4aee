// The HTML page of `photopose bundle` on a small simulated block, adjusted: the kit's page head,
// the verdicts first, the plan view, a labelled histogram per group, the point tables.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "core/geodesy/crs.h"
#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/check_points.h"
#include "tests/support/bundle_groups.h"
#include "tests/support/page_tables.h"
#include "tools/report/bundle_report.h"
#include "tools/report/html_kit.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

using testing::TableWithCaption;

class BundleHtmlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SyntheticBlockOptions o;
    o.seed = 5;
    o.num_lines = 2;
    o.images_per_line = 4;
    o.num_tie_points = 150;
    o.num_control_points = 4;
    o.num_check_points = 2;
    o.control_sigma_m = 0.01;
    ASSERT_TRUE(MakeSyntheticBlock(o, &block_, nullptr).ok());
    context_.command_line = "photopose bundle --frames=<f>.txt";
    context_.options.solver.num_threads = 1;
    ASSERT_TRUE(BundleAdjust(context_.options, BundleAdjustmentConfig(), &block_, &result_).ok());
    ASSERT_TRUE(result_.summary.IsSolutionUsable()) << result_.summary.BriefReport();
  }
  Block block_;
  BundleAdjustmentResult result_;
  BundleReportContext context_;
};

TEST_F(BundleHtmlTest, SectionsComeInTheOrderASurveyorReadsThem) {
  const std::string html = BundleReportHtml(block_, result_, context_);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>\n<html lang=\"en\">", 0), 0u);
  EXPECT_NE(html.find("<title>photopose bundle adjustment report</title>"), std::string::npos);
  EXPECT_NE(html.find("<p class=\"meta\">8 images, "), std::string::npos);
  EXPECT_NE(html.find("<style media=\"print\">"), std::string::npos);
  EXPECT_EQ(html.substr(html.size() - 8), "</html>\n");
  size_t previous = 0;
  for (const char* heading :
       {"<h2>1. Survey overview</h2>", "<h2>2. Verdicts</h2>",
        "<h2>3. Control and check points</h2>", "<h2>4. Cameras</h2>",
        "<h2>5. Camera calibration</h2>", "<h2>6. Residuals</h2>",
        "<h2>7. Rejected observations</h2>", "<h2>8. Diagnostics</h2>"}) {
    const size_t at = html.find(heading);
    ASSERT_NE(at, std::string::npos) << heading;
    EXPECT_GT(at, previous) << heading;
    previous = at;
  }
  EXPECT_GT(html.find("<h3>Terms</h3>"), previous);  // the glossary closes the diagnostics
  // The overview: counts with their nouns, the flying height and GSD of the simulated block.
  EXPECT_NE(html.find("<td>8 of 8 images</td>"), std::string::npos);
  EXPECT_NE(html.find("Ground sample distance"), std::string::npos);
  EXPECT_NE(html.find("<b>Check points:</b> 2 points intersected"), std::string::npos);
  // Per-axis RMSE rows for control and check points, one length unit named in the header.
  EXPECT_NE(html.find("<td>control (adjusted - surveyed)</td><td>4</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>check (intersected - surveyed)</td><td>2</td>"), std::string::npos);
  EXPECT_NE(html.find("<th>XY (mm)</th>"), std::string::npos);
  // Histograms per axis (x and y apart) with counts on their y axis; redundancy over [0, 1].
  EXPECT_NE(html.find(">residual x (px)</text>"), std::string::npos);
  EXPECT_NE(html.find(">residual y (px)</text>"), std::string::npos);
  EXPECT_NE(html.find(">count</text>"), std::string::npos);
  EXPECT_NE(html.find(">redundancy number r (unitless, 0 to 1)</text>"), std::string::npos);
  // Every plot carries the kit's class and an axis label.
  size_t plots = 0, histograms = 0;
  for (size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) {
    ++plots;
    const size_t end = html.find("</svg>", at);
    const std::string svg = html.substr(at, end - at);
    EXPECT_NE(svg.find("class=\"plot"), std::string::npos);
    EXPECT_NE(svg.find("class=\"axis-label\""), std::string::npos) << svg.substr(0, 200);
    if (svg.find("class=\"plot histogram\"") == std::string::npos) continue;
    ++histograms;
    // A histogram: the count on y, a unit on x (lengths in mm, cm or m by the group's largest,
    // never raw metres for marks); redundancy numbers with every x tick in [0, 1].
    EXPECT_NE(svg.find(">count</text>"), std::string::npos) << svg.substr(0, 200);
    EXPECT_TRUE(std::regex_search(
        svg, std::regex("class=\"axis-label\">[^<]*\\((px|um|mm|cm|m|arcsec|unitless[^)]*)\\)<")))
        << svg.substr(0, 200);
    if (svg.find("aria-label=\"redundancy numbers") == std::string::npos) continue;
    const std::regex tick("class=\"tick-x\">([^<]*)<");
    int ticks = 0;
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), tick); it != std::sregex_iterator();
         ++it, ++ticks) {
      const double value = std::stod((*it)[1].str());
      EXPECT_GE(value, 0.0) << svg.substr(0, 200);
      EXPECT_LE(value, 1.0) << svg.substr(0, 200);
    }
    EXPECT_GE(ticks, 2) << svg.substr(0, 200);
  }
  EXPECT_GE(plots, 6u);
  EXPECT_GE(histograms, 3u);
  // Camera positions' residuals (a few cm of GNSS noise) in cm or mm, not in metres.
  EXPECT_EQ(html.find(">residual X (m)</text>"), std::string::npos);
  // The cameras' table: each quantity and its unit once over its axes (narrow enough for a 1280 px
  // screen, tests/tools/report/render_pages_test.py).
  EXPECT_NE(html.find("<th colspan=\"3\" class=\"group\">projection centre (m)</th>"),
            std::string::npos);
  EXPECT_NE(html.find("<th colspan=\"3\" class=\"group\">sigma of the angles (arcsec)</th>"),
            std::string::npos);
  EXPECT_NE(html.find("<th>omega</th><th>phi</th><th>kappa</th>"), std::string::npos);
  // The marks' RMS residual of every image in pixels: the unit in the header, not in the cells.
  EXPECT_NE(html.find("<th>RMS residual (px)</th>"), std::string::npos);
  EXPECT_EQ(html.find(" px</td>"), std::string::npos);
  // Tables of the control and check points, by id; the command line escaped; nothing failed.
  EXPECT_NE(html.find("<td>C001</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>K001</td>"), std::string::npos);
  EXPECT_NE(html.find("--frames=&lt;f&gt;.txt"), std::string::npos);
  EXPECT_NE(html.find("<p>None: every mark and prior was kept.</p>"), std::string::npos);
  for (const char* forbidden : {"<script", "src=", "href=", "@import", "url(", "nan", "inf<"})
    EXPECT_EQ(html.find(forbidden), std::string::npos) << forbidden;
  // No number in scientific notation in the page's text (tags and the stylesheet's colours
  // aside), no verdict cell left empty.
  const std::string text = std::regex_replace(
      std::regex_replace(html, std::regex("<style[^>]*>[^<]*</style>"), " "),
      std::regex("<[^>]*>"), " ");
  std::smatch exponent;
  EXPECT_FALSE(std::regex_search(text, exponent, std::regex("[0-9]e[+-]?[0-9]")))
      << exponent.str();
  EXPECT_EQ(html.find("<td></td></tr>"), std::string::npos);
}

// A check mark 10 px off is rejected by the w-test of its point's intersection: the page lists
// it under the rejected observations and says so in the check-point verdict.
TEST_F(BundleHtmlTest, ARejectedCheckMarkIsListedAndNamedInTheVerdict) {
  int check = -1;
  for (size_t p = 0; p < block_.points.size(); ++p)
    if (block_.points[p].role == PointRole::kCheck && block_.marks_of_point[p].size() >= 4)
      check = static_cast<int>(p);
  ASSERT_GE(check, 0);
  const int blunder = block_.marks_of_point[check][0];
  block_.marks[blunder].observation.x() += 10.0 * block_.marks[blunder].observation_units_per_unit;
  TabulateControlAndCheckPoints(block_, context_.options.accuracies, 1.0, &result_);
  ASSERT_EQ(result_.rejected_check_marks.size(), 1u);
  const std::string html = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(html.find("check mark rejected by the w-test"), std::string::npos);
  const size_t table = html.find("Check marks rejected by the w-test");
  ASSERT_NE(table, std::string::npos);
  EXPECT_GT(table, html.find("<h2>7. Rejected observations</h2>"));
  EXPECT_NE(html.find("<td>" + block_.points[check].id + "</td><td>" +
                          block_.images[block_.marks[blunder].image].name + "</td>",
                      table),
            std::string::npos);
  // Its residuals in the mark's unit, named in the header.
  EXPECT_NE(html.find("<th>residual x (px)</th><th>residual y (px)</th>", table),
            std::string::npos);
}

BundleGroupStatistics Group(BundleGroup group, const std::string& unit, double stated, double rms) {
  return testing::GroupOf(group, unit, stated, rms, 0.5);
}

// The diagnostics' group table: each group's figures in the unit its own values call for (control
// points in mm beside camera positions in cm, not "0.5 / 0.3 cm"), the unit in its own column when
// the rows differ, never in a cell.
TEST_F(BundleHtmlTest, TheGroupTableTakesOneUnitPerRow) {
  result_.groups = {Group(kTieMarks, "px", 0.5, 0.43), Group(kControlPoints, "m", 0.005, 0.003),
                    Group(kCameraPositions, "m", 0.5, 0.2), Group(kAttitudes, "deg", 0.01, 0.005)};
  result_.groups[2].estimated_accuracy = Eigen::Vector3d::Constant(0.21);
  const std::string table =
      TableWithCaption(BundleReportHtml(block_, result_, context_), "Groups of the objective");
  ASSERT_NE(table, "");
  EXPECT_NE(table.find("<th>group</th><th>count</th><th>unit</th><th>stated</th><th>RMS</th>"
                       "<th>estimated accuracy</th>"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("<td>tie_marks</td><td>12</td><td>px</td><td>0.50</td><td>0.43</td>"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("<td>control_points</td><td>12</td><td>mm</td><td>5.0</td><td>3.0</td>"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("<td>camera_positions</td><td>12</td><td>cm</td><td>50.0</td><td>20.0</td>"
                       "<td>21.0</td>"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("<td>attitudes</td><td>12</td><td>arcsec</td><td>36.0</td><td>18.0</td>"),
            std::string::npos)
      << table;
  // No cell holds a number with a unit after it.
  std::smatch with_unit;
  EXPECT_FALSE(
      std::regex_search(table, with_unit, std::regex("<td>[-0-9.]+ (mm|cm|m|px|um|arcsec)</td>")))
      << with_unit.str();
  // The row's figures are the console's (FormatGroupFigures): the same group, the same texts.
  const BundleGroupFigures figures = FormatGroupFigures(result_.groups[1]);
  EXPECT_NE(table.find("<td>" + figures.unit + "</td><td>" + figures.stated + "</td><td>" +
                       figures.rms + "</td>"),
            std::string::npos);
  // A film mark group's unit reads as µm on the page.
  result_.groups = {Group(kTieMarks, "um", 2.0, 1.7), Group(kControlPoints, "m", 0.005, 0.0005)};
  const std::string film =
      TableWithCaption(BundleReportHtml(block_, result_, context_), "Groups of the objective");
  EXPECT_NE(film.find("<td>tie_marks</td><td>12</td><td>\u00b5m</td><td>2.00</td><td>1.70</td>"),
            std::string::npos)
      << film;
  EXPECT_NE(film.find("<td>control_points</td><td>12</td><td>mm</td><td>5.00</td><td>0.50</td>"),
            std::string::npos)
      << film;

  // Groups of one kind: the unit in the headers, no unit column.
  result_.groups = {Group(kTieMarks, "px", 0.5, 0.43), Group(kControlMarks, "px", 0.5, 1.7)};
  const std::string marks =
      TableWithCaption(BundleReportHtml(block_, result_, context_), "Groups of the objective");
  EXPECT_NE(marks.find("<th>count</th><th>stated (px)</th><th>RMS (px)</th>"
                       "<th>estimated accuracy (px)</th>"),
            std::string::npos)
      << marks;
  EXPECT_NE(marks.find("<td>control_marks</td><td>12</td><td>0.50</td><td>1.70</td>"),
            std::string::npos)
      << marks;
  EXPECT_EQ(marks.find("<th>unit</th>"), std::string::npos) << marks;
}

// The groups table's verdict: a prior group the block checks whose RMS is well below its stated
// accuracy is "loose"; the same figures without statistics (no redundancy share, the library's
// message saying so) are "not judged", never "loose".
TEST_F(BundleHtmlTest, AGroupWithoutARedundancyShareIsNotJudgedNotLoose) {
  BundleGroupStatistics cameras = testing::GroupOf(kCameraPositions, "m", 10.0, 2.8, 0.9);
  cameras.message = "camera_positions: residual RMS 0.28 of the stated accuracy, loose";
  result_.groups = {Group(kTieMarks, "px", 0.5, 0.43), cameras};
  std::string table =
      TableWithCaption(BundleReportHtml(block_, result_, context_), "Groups of the objective");
  EXPECT_NE(table.find("<td>loose</td></tr>"), std::string::npos) << table;
  result_.groups[1].redundancy_share = std::nan("");
  result_.groups[1].message = "camera_positions: residual RMS 0.28 of the stated accuracy; not judged.";
  table = TableWithCaption(BundleReportHtml(block_, result_, context_), "Groups of the objective");
  EXPECT_NE(table.find("<td>not judged</td></tr>"), std::string::npos) << table;
  EXPECT_EQ(table.find("<td>loose</td>"), std::string::npos) << table;
}

// Columns whose rows are of different kinds take a unit column: an image measured on film among
// pixel images, data snooping that removed a mark and a control point's coordinate.
TEST_F(BundleHtmlTest, ColumnsMixingKindsTakeAUnitColumn) {
  result_.images[0].unit = "um";
  result_.images[0].rms_residual = 1.25;
  result_.snooping = {{kTieMarks, 0, 0, 9.5, 3.25}, {kControlPoints, 0, 2, 5.1, 0.0421}};
  const std::string html = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(html.find("<th>RMS residual</th><th>unit</th>"), std::string::npos);
  EXPECT_NE(
      html.find("<td>" + block_.images[0].name + "</td><td>" +
                std::to_string(result_.images[0].num_marks) + "</td><td>1.25</td><td>\u00b5m</td>"),
      std::string::npos);
  const std::string snooping = TableWithCaption(html, "Data snooping");
  EXPECT_NE(snooping.find("<th>|w|</th><th>residual</th><th>unit</th>"), std::string::npos)
      << snooping;
  EXPECT_NE(snooping.find("<td>9.5</td><td>3.25</td><td>px</td>"), std::string::npos) << snooping;
  EXPECT_NE(snooping.find("<td>5.1</td><td>42.1</td><td>mm</td>"), std::string::npos) << snooping;
}

// The overview names the CRS: a georeferenced block's output CRS (PROJ's name, as given, why) and
// the local frame it was adjusted in; a block of tables the CRS they name.
TEST_F(BundleHtmlTest, TheOverviewNamesTheCrs) {
  block_.crs = "EPSG:32632";
  std::string overview = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(overview.find("<td>Coordinate reference system (as the tables name it)</td>"
                          "<td>EPSG:32632</td>"),
            std::string::npos);
  block_.crs.clear();
  overview = BundleReportHtml(block_, result_, context_);
  EXPECT_EQ(overview.find("Coordinate reference system"), std::string::npos);

  GeoreferenceResult georeference;
  georeference.out_crs = "EPSG:4326";
  ASSERT_TRUE(ResolveCrs(georeference.out_crs, &georeference.out_crs_info).ok());
  georeference.out_crs_reason = "asked (--out_crs)";
  ASSERT_TRUE(
      LocalFrame::Create("EPSG:4979", Eigen::Vector3d(11.2, 47.8, 500.0), &georeference.frame)
          .ok());
  context_.georeference = &georeference;
  overview = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(overview.find("<td>Output CRS (the points and frames files)</td><td>" +
                          georeference.out_crs_info.name + " (EPSG:4326); asked (--out_crs)</td>"),
            std::string::npos);
  EXPECT_NE(overview.find("<td>Adjusted in</td><td>the local East-North-Up frame (m), origin "
                          "11.200000 E, 47.800000 N, ellipsoidal height 500.000 m (WGS 84)</td>"),
            std::string::npos);
  EXPECT_NE(overview.find("<td>Matched to the model&#39;s images by name</td><td>0 camera positions matched; "
                          "0 control marks matched</td>"),
            std::string::npos)
      << overview;
  // Names matching no image are counted and listed (the first five), never dropped silently.
  georeference.positions_matched = 40;
  georeference.positions_unmatched = {"a.jpg", "b.jpg", "c.jpg", "d.jpg", "e.jpg", "f.jpg"};
  georeference.control_marks_matched = 12;
  georeference.control_marks_unmatched = {"NOPE.JPG (line 126)"};
  overview = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(overview.find("<td>40 camera positions matched, 6 naming no image of the model (a.jpg, b.jpg, c.jpg, "
                          "d.jpg, e.jpg, ...); 12 control marks matched, 1 on images the model does not have "
                          "(NOPE.JPG (line 126))</td>"),
            std::string::npos)
      << overview;
  context_.georeference = nullptr;
}

// A georeferenced block: section 3 shows the control and check errors in the output CRS (E, N,
// U) after the similarity and after the adjustment side by side, each stage in the unit of its own
// errors (cm before, mm after here), RMSE per role and each point's errors, n/a where a stage has
// none; the RMSE table of the local frame gives way to it and the local tables say their frame.
// A georeferenced block's errors in EPSG:32632 as EvaluateGeoreference gives them: each control
// point (0.12, -0.05, 0.30) m after the similarity and (2, -1, 4) mm after the adjustment; each
// check point (0.20, 0.10, -0.45) m after the similarity, the first (8, -6, 12) mm after the
// adjustment, the second not intersected then. *check_ids: the check points' ids.
GeoreferenceResult GeoreferencedErrors(const Block& block, std::vector<std::string>* check_ids) {
  GeoreferenceResult g;
  g.out_crs = "EPSG:32632";
  EXPECT_TRUE(ResolveCrs(g.out_crs, &g.out_crs_info).ok());
  EXPECT_TRUE(
      LocalFrame::Create("EPSG:4979", Eigen::Vector3d(11.2, 47.8, 500.0), &g.frame).ok());
  for (size_t p = 0; p < block.points.size(); ++p) {
    const PointRole role = block.points[p].role;
    if (role == PointRole::kTie) continue;
    GeoreferencePointError e;
    e.point = static_cast<int>(p);
    if (role == PointRole::kControl) {
      e.after_similarity_m = Eigen::Vector3d(0.12, -0.05, 0.30);
      e.after_adjustment_m = Eigen::Vector3d(0.002, -0.001, 0.004);
    } else {
      e.after_similarity_m = Eigen::Vector3d(0.20, 0.10, -0.45);
      // The second check point is not intersected after the adjustment.
      if (check_ids->empty()) e.after_adjustment_m = Eigen::Vector3d(0.008, -0.006, 0.012);
      check_ids->push_back(block.points[p].id);
    }
    g.point_errors.push_back(e);
  }
  // The RMSEs of those errors (EvaluateGeoreference's), by hand: total sqrt(E^2 + N^2 + U^2).
  g.control_after_similarity = {4, Eigen::Vector3d(0.12, 0.05, 0.30), std::sqrt(0.1069)};
  g.control_after_adjustment = {4, Eigen::Vector3d(0.002, 0.001, 0.004), std::sqrt(21e-6)};
  g.check_after_similarity = {2, Eigen::Vector3d(0.20, 0.10, 0.45), std::sqrt(0.2525)};
  g.check_after_adjustment = {1, Eigen::Vector3d(0.008, 0.006, 0.012), std::sqrt(244e-6)};
  g.evaluated = true;
  return g;
}

TEST_F(BundleHtmlTest, AGeoreferencedBlockShowsItsErrorsAfterTheSimilarityAndTheAdjustment) {
  std::vector<std::string> check_ids;
  GeoreferenceResult g = GeoreferencedErrors(block_, &check_ids);
  ASSERT_EQ(check_ids.size(), 2u);
  context_.georeference = &g;
  const std::string html = BundleReportHtml(block_, result_, context_);
  context_.georeference = nullptr;
  const std::string rmse = TableWithCaption(html, "Root mean square errors in WGS 84 / UTM zone 32N");
  ASSERT_NE(rmse, "") << html;
  EXPECT_NE(rmse.find("<th colspan=\"5\" class=\"group\">after the similarity (cm)</th>"
                      "<th colspan=\"5\" class=\"group\">after the adjustment (mm)</th>"),
            std::string::npos)
      << rmse;
  EXPECT_NE(rmse.find("<td>control</td><td>4</td><td>12.0</td><td>5.0</td><td>30.0</td>"
                      "<td>32.7</td><td>4</td><td>2.0</td><td>1.0</td><td>4.0</td><td>4.6</td>"),
            std::string::npos)
      << rmse;
  EXPECT_NE(rmse.find("<td>check</td><td>2</td><td>20.0</td><td>10.0</td><td>45.0</td>"
                      "<td>50.2</td><td>1</td><td>8.0</td><td>6.0</td><td>12.0</td><td>15.6</td>"),
            std::string::npos)
      << rmse;
  // The notes under the table name the axes.
  const size_t rmse_at = html.find(rmse);
  EXPECT_LT(html.find("E, N, U: grid east, grid north, up of WGS 84 / UTM zone 32N", rmse_at),
            html.find("<table", rmse_at + 1));
  const std::string points = TableWithCaption(html, "Each point&#39;s error in WGS 84 / UTM zone 32N");
  ASSERT_NE(points, "") << html;
  EXPECT_NE(points.find("<td>" + check_ids[0] + "</td><td>check</td><td>20.0</td><td>10.0</td>"
                        "<td>-45.0</td><td>8.0</td><td>-6.0</td><td>12.0</td>"),
            std::string::npos)
      << points;
  EXPECT_NE(points.find("<td>" + check_ids[1] + "</td><td>check</td><td>20.0</td><td>10.0</td>"
                        "<td>-45.0</td><td>n/a</td><td>n/a</td><td>n/a</td>"),
            std::string::npos)
      << points;
  // Control points first, then check points, as the tables below.
  EXPECT_LT(points.find("<td>control</td>"), points.find("<td>check</td>"));
  // The local frame's RMSE table gives way; the local tables name their frame.
  EXPECT_EQ(html.find("<caption>Root mean square errors</caption>"), std::string::npos);
  const size_t check_at = html.find("<caption>Check points: intersected");
  ASSERT_NE(check_at, std::string::npos);
  EXPECT_LT(html.find("X, Y, Z: the local East-North-Up frame the block was adjusted in", check_at),
            html.find("</ul>", check_at));
  // Without a georeference the page keeps its one RMSE table.
  const std::string plain = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(plain.find("<caption>Root mean square errors</caption>"), std::string::npos);
  EXPECT_EQ(plain.find("after the similarity"), std::string::npos);
}

// The check points' verdict (section 2) of a georeferenced block gives section 3's figures: the
// RMSE after the adjustment along the output CRS's E, N, U, in the same unit and digits, not the
// local frame's X, Y, Z; without a check point intersected after the adjustment, no figure at all
// (n/a in section 3), never a 0.
TEST_F(BundleHtmlTest, TheCheckPointVerdictOfAGeoreferencedBlockGivesSection3sFigures) {
  ASSERT_GT(result_.num_check_points, 0);
  std::vector<std::string> check_ids;
  GeoreferenceResult g = GeoreferencedErrors(block_, &check_ids);
  context_.georeference = &g;
  const std::string html = BundleReportHtml(block_, result_, context_);
  const std::string rmse = TableWithCaption(html, "Root mean square errors in WGS 84 / UTM zone 32N");
  ASSERT_NE(rmse, "") << html;
  // Section 3's check row: count, E, N, U, total after the similarity, then after the adjustment.
  const std::vector<double> cells = testing::RowNumbers(rmse, "<td>check</td>");
  ASSERT_EQ(cells.size(), 10u) << rmse;
  std::smatch verdict;
  ASSERT_TRUE(std::regex_search(
      html, verdict,
      std::regex("<b>Check points:</b> ([0-9]+) points? intersected, RMSE after the adjustment in "
                 "WGS 84 / UTM zone 32N \\(grid east, grid north, up\\): E ([-0-9.]+) (mm|cm|m), N "
                 "([-0-9.]+) \\3, U ([-0-9.]+) \\3, total ([-0-9.]+) \\3\\.")))
      << html.substr(html.find("<h2>2. Verdicts</h2>"), 3000);
  EXPECT_EQ(std::stod(verdict[1]), cells[5]);
  EXPECT_EQ(verdict[3], "mm");  // the unit named over section 3's columns after the adjustment
  EXPECT_NE(rmse.find(">after the adjustment (mm)<"), std::string::npos) << rmse;
  EXPECT_EQ(std::stod(verdict[2]), cells[6]);
  EXPECT_EQ(std::stod(verdict[4]), cells[7]);
  EXPECT_EQ(std::stod(verdict[5]), cells[8]);
  EXPECT_EQ(std::stod(verdict[6]), cells[9]);
  EXPECT_EQ(html.find("RMSE X "), std::string::npos);  // not the local frame's figures
  // No check point intersected after the adjustment: the count alone, n/a in section 3.
  g.check_after_adjustment = GeoreferenceRmse{};
  for (GeoreferencePointError& e : g.point_errors)
    if (block_.points[e.point].role == PointRole::kCheck) e.after_adjustment_m.reset();
  const std::string none = BundleReportHtml(block_, result_, context_);
  context_.georeference = nullptr;
  EXPECT_NE(none.find("<b>Check points:</b> 0 points intersected."), std::string::npos)
      << none.substr(none.find("<h2>2. Verdicts</h2>"), 3000);
  EXPECT_NE(none.find("<td>check</td><td>2</td><td>20.0</td><td>10.0</td><td>45.0</td>"
                      "<td>50.2</td><td>0</td><td>n/a</td><td>n/a</td><td>n/a</td><td>n/a</td>"),
            std::string::npos);
}

// Film marks read as µm on the page, also in the sentences shared with the console (the gross
// errors a group's estimated accuracy absorbed): no "um" after a number or in parentheses.
TEST_F(BundleHtmlTest, FilmUnitsReadAsMicrometresOnThePage) {
  result_.groups = {Group(kTieMarks, "um", 2.0, 7.5)};
  result_.groups[0].estimated_accuracy = Eigen::Vector3d::Constant(8.0);  // 4 x the stated
  result_.images[0].unit = "um";
  const std::string html = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(html.find("<b>Gross errors absorbed:</b> tie_marks: the estimated accuracy 8.00 "
                      "\u00b5m is 4.0 times the stated 2.00 \u00b5m"),
            std::string::npos);
  std::smatch ascii;
  EXPECT_FALSE(std::regex_search(html, ascii, std::regex("[0-9] um\\b|\\(um\\)|>um<")))
      << ascii.str();
}

// The calibration table: each value at its sigma's precision, the film unit as µm.
TEST_F(BundleHtmlTest, CalibrationValuesKeepTheirSigmasPrecision) {
  BundleCalibrationResult calibration;
  calibration.camera = 0;
  calibration.names = {"FocalLength", "K1"};
  calibration.values = {24012.3456, -1.234567e-4};
  calibration.sigmas = {1.23, 2.5e-7};
  result_.calibration = {calibration};
  const std::string html = BundleReportHtml(block_, result_, context_);
  EXPECT_NE(html.find("<td>FocalLength</td><td>24012.3</td><td>1.2</td><td>\u00b5m</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<td>K1</td><td>-1.2346</td><td>0.0025</td><td>10^-4 mm^-2</td>"),
            std::string::npos);
}

TEST_F(BundleHtmlTest, AFailedAdjustmentSaysSoFirst) {
  result_.summary.termination = SolverTermination::kFailure;
  result_.summary.message = "the normal matrix is <singular>";
  const std::string html = BundleReportHtml(block_, result_, context_);
  const size_t failed = html.find("<b>Not adjusted:</b> the normal matrix is &lt;singular&gt;");
  ASSERT_NE(failed, std::string::npos);
  EXPECT_LT(failed, html.find("<h2>3. Control and check points</h2>"));
}


// Every term the report uses without explaining it in place is in its glossary, and the glossary
// is on the page.
// What the adjustment left out and what the data cannot carry, each in its place: a tie mark
// rejected after a round in section 7 with its file line, round and |v|; a group whose estimate
// is far above its statement and the parameters that trade off with others among the verdicts.
TEST_F(BundleHtmlTest, RejectedTieMarksAbsorbedGrossErrorsAndWeakParametersAreShown) {
  const int mark = 3;
  const BlockMark& m = block_.marks[mark];
  result_.rejected_marks = {BundleRejectedMark{mark, 2, 7.26}};
  result_.groups = {Group(kTieMarks, "px", 0.5, 2.0)};
  result_.groups[0].estimated_accuracy = Eigen::Vector3d::Constant(2.1);  // 4.2 x the stated
  result_.weakly_determined = {BundleWeakParameter{"image 'IMG_1': omega", 12.6}};
  result_.summary.tie_points_left_out = {"T_far"};
  const std::string html = BundleReportHtml(block_, result_, context_);
  const std::string rejected = TableWithCaption(html, "Tie marks rejected after a round");
  ASSERT_FALSE(rejected.empty());
  EXPECT_GT(html.find(rejected), html.find("<h2>7. Rejected observations</h2>"));
  EXPECT_NE(rejected.find("<td>" + block_.points[m.point].id + "</td><td>" +
                          block_.images[m.image].name + "</td><td>" + std::to_string(m.line) +
                          "</td><td>2</td><td>7.3</td>"),
            std::string::npos)
      << rejected;
  EXPECT_FALSE(TableWithCaption(html, "Tie points left out").empty());
  EXPECT_EQ(html.find("None: every mark and prior was kept."), std::string::npos);
  const size_t verdicts = html.find("<h2>2. Verdicts</h2>");
  const size_t gross = html.find("<b>Gross errors absorbed:</b> tie_marks: the estimated accuracy");
  const size_t weak = html.find("<b>Weakly determined:</b> 1 parameter trade off");
  EXPECT_GT(gross, verdicts);
  EXPECT_GT(weak, gross);
  EXPECT_LT(weak, html.find("<h2>3. Control and check points</h2>"));
  EXPECT_NE(html.find("image &#39;IMG_1&#39;: omega (sigma 13 times", weak), std::string::npos)
      << html.substr(weak, 300);
}

TEST(BundleHtml, TheGlossaryExplainsTheReportsTerms) {
  const std::string glossary = BundleGlossaryHtml();
  EXPECT_EQ(glossary.rfind("<h3>Terms</h3>\n<dl class=\"glossary\">", 0), 0u);
  for (const char* term : {"sigma0", "RMS / stated", "redundancy number", "redundancy share",
                           "over-fitted", "w-test", "data snooping", "delta0", "e^T C^-1 e",
                           "datum", "check point"})
    EXPECT_NE(glossary.find(HtmlEscape(term)), std::string::npos) << term;
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
