#include "solvers/georeference/adjusted_colmap_model.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/io/csv.h"
#include "tests/support/georeference_scene.h"
#include "tests/support/temp_dir.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::GeoreferenceScene;
using testing::MakeGeoreferenceScene;

// Coordinates written as text and read back: COLMAP's text keeps 17 significant digits, so a
// coordinate of a few hundred metres comes back to well below a micrometre.
constexpr double kTextRoundTripM = 1e-9;

// The scene's model as a reader gives it (block and extras), georeferenced and adjusted.
struct Adjusted {
  Block block;
  ColmapModelExtras extras;
  GeoreferenceResult georeference;
  BundleAdjustmentResult adjustment;
  size_t model_points = 0, model_marks = 0;  // as read
};

::testing::AssertionResult ReadAndGeoreference(const GeoreferenceScene& scene, Adjusted* out) {
  ColmapModelFiles files;
  Status status = FormatColmapModel(scene.model, nullptr, ColmapWriteOptions(), &files);
  if (status.ok()) status = ParseColmapModel(files, "model", &out->block, &out->extras);
  if (!status.ok()) return ::testing::AssertionFailure() << status.message();
  out->model_points = out->block.points.size();
  out->model_marks = out->block.marks.size();
  BundleAdjustmentOptions options;
  options.solver.progress = nullptr;
  status = GeoreferenceBlock(GeoreferenceOptions(), scene.inputs, options, BundleAdjustmentConfig(), &out->block,
                             &out->georeference, &out->adjustment);
  if (!status.ok()) return ::testing::AssertionFailure() << status.message();
  if (!out->adjustment.summary.IsSolutionUsable())
    return ::testing::AssertionFailure() << out->adjustment.summary.message;
  return ::testing::AssertionSuccess();
}

TEST(AdjustedColmapModel, GeoreferencedModelIsWrittenWithoutItsControlWithItsFrameBeside) {
  const GeoreferenceScene scene = MakeGeoreferenceScene();
  Adjusted a;
  ASSERT_TRUE(ReadAndGeoreference(scene, &a));
  // The control joined the block after the model's own points and marks.
  EXPECT_EQ(a.georeference.model_points, a.model_points);
  EXPECT_EQ(a.georeference.model_marks, a.model_marks);
  ASSERT_EQ(a.block.points.size(), a.model_points + scene.inputs.control_points.size());
  ASSERT_GT(a.block.marks.size(), a.model_marks);
  // The extras read describe the model alone: the whole block does not fit them.
  ColmapModelFiles whole;
  EXPECT_FALSE(FormatColmapModel(a.block, &a.extras, ColmapWriteOptions(), &whole).ok());

  // A model mark whose point keeps at least two others, and a control mark, left out.
  int model_mark = -1;
  for (size_t m = 0; m < a.model_marks && model_mark < 0; ++m)
    if (a.block.marks_of_point[a.block.marks[m].point].size() >= 3) model_mark = static_cast<int>(m);
  ASSERT_GE(model_mark, 0);
  a.adjustment.rejected_marks.clear();
  a.adjustment.snooping.clear();
  a.adjustment.rejected_marks.push_back({model_mark, 1, 9.0});
  a.adjustment.rejected_marks.push_back({static_cast<int>(a.model_marks), 1, 9.0});

  AdjustedColmapModelFiles files;
  const Status formatted =
      FormatAdjustedColmapModel(a.block, a.adjustment, &a.georeference, &a.extras, ColmapFormat::kText, &files);
  ASSERT_TRUE(formatted.ok()) << formatted.message();
  Block written;
  const Status parsed = ParseColmapModel(files.model, "out", &written);
  ASSERT_TRUE(parsed.ok()) << parsed.message();
  ASSERT_EQ(written.points.size(), a.model_points);
  EXPECT_EQ(written.marks.size(), a.model_marks - 1);  // the rejected model mark out of its track
  for (size_t p = 0; p < written.points.size(); ++p) {
    EXPECT_EQ(written.points[p].id, a.block.points[p].id);
    EXPECT_TRUE(written.points[p].position_m->isApprox(*a.block.points[p].position_m, kTextRoundTripM)) << p;
  }
  // The frame beside it: the PROJ pipeline of the local frame and the output CRS.
  EXPECT_NE(files.georeference_json.find(a.georeference.frame.definition()), std::string::npos);
  EXPECT_NE(files.georeference_json.find("\"out_crs\": \"" + a.georeference.out_crs + "\""), std::string::npos)
      << files.georeference_json;

  // Written into a new folder: the three files and georeference.json, as formatted.
  testing::ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string folder = dir.path() + "/adjusted";
  const Status wrote =
      WriteAdjustedColmapModel(folder, a.block, a.adjustment, &a.georeference, &a.extras, ColmapFormat::kBinary);
  ASSERT_TRUE(wrote.ok()) << wrote.message();
  std::string json;
  ASSERT_TRUE(ReadTextFile(folder + "/" + kGeoreferenceJsonName, &json).ok());
  EXPECT_EQ(json, files.georeference_json);
  Block read;
  ColmapFormat format = ColmapFormat::kText;
  ASSERT_TRUE(ReadColmapModel(folder, &read, nullptr, &format).ok());
  EXPECT_EQ(format, ColmapFormat::kBinary);
  EXPECT_EQ(read.points.size(), a.model_points);
  EXPECT_EQ(read.marks.size(), a.model_marks - 1);
}

TEST(AdjustedColmapModel, BlockWithoutGeoreferenceIsWrittenWholeWithoutFrameFile) {
  const GeoreferenceScene scene = MakeGeoreferenceScene();
  BundleAdjustmentResult adjustment;
  adjustment.rejected_marks.push_back({0, 1, 9.0});
  AdjustedColmapModelFiles files;
  ASSERT_TRUE(FormatAdjustedColmapModel(scene.model, adjustment, nullptr, nullptr, ColmapFormat::kText, &files).ok());
  EXPECT_TRUE(files.georeference_json.empty());
  Block written;
  ASSERT_TRUE(ParseColmapModel(files.model, "out", &written).ok());
  EXPECT_EQ(written.points.size(), scene.model.points.size());
  EXPECT_LT(written.marks.size(), scene.model.marks.size());
  testing::ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  ASSERT_TRUE(WriteAdjustedColmapModel(dir.path(), scene.model, adjustment, nullptr, nullptr).ok());
  EXPECT_FALSE(std::filesystem::exists(dir.path() + "/" + kGeoreferenceJsonName));
}

TEST(AdjustedColmapModel, GeoreferenceOfAnotherBlockIsRefused) {
  const GeoreferenceScene scene = MakeGeoreferenceScene();
  GeoreferenceResult other;
  other.model_points = scene.model.points.size() + 1;
  Block model;
  const Status refused = ModelPartOfBlock(scene.model, &other, &model);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("does not belong to this block"), std::string::npos) << refused.message();
  AdjustedColmapModelFiles files;
  EXPECT_FALSE(FormatAdjustedColmapModel(scene.model, BundleAdjustmentResult(), &other, nullptr,
                                         ColmapFormat::kText, &files)
                   .ok());
  EXPECT_FALSE(CheckAdjustedColmapModelWritable(scene.model, &other, nullptr).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
