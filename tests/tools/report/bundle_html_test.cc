// The HTML page of `photopose bundle` on a small simulated block, adjusted: the kit's page head,
// the verdicts first, the plan view, a labelled histogram per group, the point tables.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/check_points.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "tools/report/bundle_report.h"

namespace photopose::cli {
namespace {

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
  // The overview: counts with their nouns, the flying height and GSD of the simulated block.
  EXPECT_NE(html.find("<td>8 images of 8 images</td>"), std::string::npos);
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
  size_t plots = 0;
  for (size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) {
    ++plots;
    const size_t end = html.find("</svg>", at);
    const std::string svg = html.substr(at, end - at);
    EXPECT_NE(svg.find("class=\"plot\""), std::string::npos);
    EXPECT_NE(svg.find("class=\"axis-label\""), std::string::npos) << svg.substr(0, 200);
  }
  EXPECT_GE(plots, 6u);
  // The cameras' table: each quantity and its unit once over its axes (narrow enough for a 1280 px
  // screen, tests/tools/report/render_pages_test.py).
  EXPECT_NE(html.find("<th colspan=\"3\" class=\"group\">projection centre (m)</th>"),
            std::string::npos);
  EXPECT_NE(html.find("<th colspan=\"3\" class=\"group\">sigma of the angles (arcsec)</th>"),
            std::string::npos);
  EXPECT_NE(html.find("<th>omega</th><th>phi</th><th>kappa</th>"), std::string::npos);
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
}

TEST_F(BundleHtmlTest, AFailedAdjustmentSaysSoFirst) {
  result_.summary.termination = SolverTermination::kFailure;
  result_.summary.message = "the normal matrix is <singular>";
  const std::string html = BundleReportHtml(block_, result_, context_);
  const size_t failed = html.find("<b>Not adjusted:</b> the normal matrix is &lt;singular&gt;");
  ASSERT_NE(failed, std::string::npos);
  EXPECT_LT(failed, html.find("<h2>3. Control and check points</h2>"));
}

}  // namespace
}  // namespace photopose::cli
