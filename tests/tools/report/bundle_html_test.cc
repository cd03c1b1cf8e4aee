// The HTML page of `photopose bundle` on a small simulated block, adjusted: the kit's page head,
// the verdicts first, the plan view, a labelled histogram per group, the point tables.
#include <gtest/gtest.h>

#include <string>

#include "core/simulation/synthetic_block.h"
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

TEST_F(BundleHtmlTest, PageHasTheKitHeadVerdictsPlotsAndTables) {
  const std::string html = BundleReportHtml(block_, result_, context_);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>\n<html lang=\"en\">", 0), 0u);
  EXPECT_NE(html.find("<title>photopose bundle</title>"), std::string::npos);
  EXPECT_NE(html.find("<h1>photopose bundle: 8 images, "), std::string::npos);
  EXPECT_NE(html.find("<style media=\"print\">"), std::string::npos);
  EXPECT_EQ(html.substr(html.size() - 8), "</html>\n");
  // Verdicts come before the plan view; the check points are measured.
  const size_t verdict = html.find("class=\"verdict");
  const size_t plan = html.find("<h2>Plan view</h2>");
  ASSERT_NE(verdict, std::string::npos);
  ASSERT_NE(plan, std::string::npos);
  EXPECT_LT(verdict, plan);
  EXPECT_NE(html.find("<b>Check points:</b> 2,"), std::string::npos);
  // Plan view plus one histogram per residual group, each with its axis titled.
  ASSERT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("<svg", html.find("<svg") + 1), std::string::npos);
  EXPECT_NE(html.find(">residual (px)</text>"), std::string::npos);
  EXPECT_NE(html.find(">count</text>"), std::string::npos);
  // Tables of the control and check points, by id; the command line escaped.
  EXPECT_NE(html.find("<h2>Control points</h2>"), std::string::npos);
  EXPECT_NE(html.find("<td>C001</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>K001</td>"), std::string::npos);
  EXPECT_NE(html.find("--frames=&lt;f&gt;.txt"), std::string::npos);
  for (const char* forbidden : {"<script", "src=", "href=", "@import", "url(", "nan", "inf<"})
    EXPECT_EQ(html.find(forbidden), std::string::npos) << forbidden;
}

TEST_F(BundleHtmlTest, AFailedAdjustmentSaysSoFirst) {
  result_.summary.termination = SolverTermination::kFailure;
  result_.summary.message = "the normal matrix is <singular>";
  const std::string html = BundleReportHtml(block_, result_, context_);
  const size_t failed = html.find("<b>Not adjusted:</b> the normal matrix is &lt;singular&gt;");
  ASSERT_NE(failed, std::string::npos);
  EXPECT_LT(failed, html.find("<h2>Plan view</h2>"));
}

}  // namespace
}  // namespace photopose::cli
