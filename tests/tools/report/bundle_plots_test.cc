// The pictures of the bundle page (tools/report/bundle_plots.h) on a small simulated block,
// adjusted: one symbol per camera, control and check point in the plan view, an ellipse per camera
// with a covariance; the distortion curve of a camera with and without distortion; the residual
// vectors of an image, which account for every adjusted mark of its camera.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "tools/report/bundle_plots.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class BundlePlotsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SyntheticBlockOptions o;
    o.seed = 9;
    o.num_lines = 2;
    o.images_per_line = 3;
    o.num_tie_points = 120;
    o.num_control_points = 4;
    o.num_check_points = 3;
    o.control_sigma_m = 0.01;
    ASSERT_TRUE(MakeSyntheticBlock(o, &block_, nullptr).ok());
    BundleAdjustmentOptions options;
    options.solver.num_threads = 1;
    ASSERT_TRUE(BundleAdjust(options, BundleAdjustmentConfig(), &block_, &result_).ok());
    ASSERT_TRUE(result_.summary.IsSolutionUsable()) << result_.summary.BriefReport();
  }
  Block block_;
  BundleAdjustmentResult result_;
};

TEST_F(BundlePlotsTest, PlanViewDrawsEveryCameraAndSurveyedPoint) {
  const std::string svg = PlanViewHtml(block_, result_, nullptr);
  size_t with_covariance = 0;
  for (const BundleImageResult& image : result_.images) with_covariance += image.has_covariance;
  ASSERT_GT(with_covariance, 0u);
  EXPECT_EQ(Count(svg, "<ellipse "), with_covariance);
  EXPECT_EQ(Count(svg, "fill=\"#0072B2\"><title>"), block_.images.size());
  for (const BlockImage& image : block_.images)
    EXPECT_NE(svg.find("<title>" + image.name + "</title>"), std::string::npos) << image.name;
  size_t control = 0, check = 0;
  for (const BlockPoint& point : block_.points) {
    control += point.role == PointRole::kControl;
    check += point.role == PointRole::kCheck;
  }
  EXPECT_EQ(Count(svg, "l4.5,8h-9z\" fill=\"#D55E00\""), control);
  EXPECT_EQ(Count(svg, "r=\"4\" fill=\"#009E73\""), check);
  // The scale bar names its unit, the caption the drawn extent.
  EXPECT_NE(svg.find(" m (plan: east right, north up)</text>"), std::string::npos);
  EXPECT_NE(svg.find("<p>Lower left "), std::string::npos);
}

TEST_F(BundlePlotsTest, PlanViewOfAnEmptyBlockSaysSo) {
  EXPECT_EQ(PlanViewHtml(Block(), BundleAdjustmentResult(), nullptr), "<p>Nothing to draw.</p>");
}

TEST(BundleDistortionPlot, DrawsTheCurveOfACameraWithAFocalLength) {
  BlockCamera camera;
  camera.camera_id = "c1";
  camera.model = CameraModelType::kSimpleRadial;
  camera.params = {1000.0, 500.0, 400.0, 0.05};  // f, cx, cy (px), k (unitless)
  const std::string svg = DistortionPlot(camera);
  ASSERT_FALSE(svg.empty());
  EXPECT_NE(svg.find("radial distortion, camera c1"), std::string::npos);
  EXPECT_NE(svg.find(">radius (px)</text>"), std::string::npos);
  EXPECT_NE(svg.find(">distortion (px)</text>"), std::string::npos);
  // At the corner (640 px from the principal point) k r^3 / f^2 = 13.1 px: the axis reaches it.
  std::smatch last;
  const std::regex tick(R"(>([0-9.]+)</text>)");
  double largest = 0.0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), tick); it != std::sregex_iterator();
       ++it)
    largest = std::max(largest, std::stod((*it)[1]));
  EXPECT_GE(largest, 13.0);

  camera.params[0] = 0.0;  // no focal length: nothing to draw
  EXPECT_TRUE(DistortionPlot(camera).empty());
}

TEST_F(BundlePlotsTest, ImageResidualVectorsAccountForEveryMarkOfTheCamera) {
  ASSERT_EQ(result_.mark_residuals.size(), block_.marks.size());
  const std::string svg = ImageResidualPlot(block_, result_, 0, "um");
  ASSERT_FALSE(svg.empty());
  const std::regex cell(R"(<title>([0-9]+) marks, mean )");
  size_t marks = 0, cells = 0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), cell); it != std::sregex_iterator();
       ++it, ++cells)
    marks += std::stoul((*it)[1]);
  EXPECT_GT(cells, 1u);
  EXPECT_LE(cells, 48u);  // 8 x 6 cells at most
  size_t expected = 0;
  for (size_t m = 0; m < block_.marks.size(); ++m)
    expected += block_.images[block_.marks[m].image].camera == 0 &&
                result_.mark_residuals[m].allFinite();
  ASSERT_GT(expected, 10u);
  EXPECT_EQ(marks, expected);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
