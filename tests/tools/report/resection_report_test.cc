#include "tools/report/resection_report.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "core/block.h"
#include "core/io/tables.h"
#include "core/simulation/synthetic_scene.h"
#include "tests/support/temp_dir.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

struct Fixture {
  SyntheticScene scene;
  BlockTables tables;
  Block block;
};

TEST(ResectionReport, TheFramesTableHasTheSolvedImagesOnly) {
  // The nadir scene without noise (one image, 20 control and 5 check points) and a second marked
  // image: a copy of its marks under another name.
  SyntheticSceneOptions scene_options;
  scene_options.noise_px = 0.0;
  Fixture f;
  ASSERT_TRUE(MakeSyntheticScene(scene_options, &f.scene).ok());
  f.tables = SceneBlockTables(f.scene);
  for (size_t m = 0, n = f.tables.marks.size(); m < n; ++m) {
    ImageMark copy = f.tables.marks[m];
    copy.raster = "COPY";
    f.tables.marks.push_back(copy);
  }
  ASSERT_TRUE(AssembleBlock(f.tables, &f.block).ok());
  ResectionJob job;
  ASSERT_TRUE(PrepareResectionJob(f.block, ResectionInputOptions(), &job).ok());
  ASSERT_EQ(job.inputs.size(), 2u);
  std::vector<ResectionResult> results(2);
  results[0].success = true;
  results[0].eo = f.scene.true_frames[0].eo;
  results[0].inliers.assign(20, 1);
  results[0].num_inliers = 18;
  results[1].success = false;  // not solved: not written
  const testing::ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  ResectionJobOptions options;
  const std::string path = dir.Path("frames.csv");
  ASSERT_TRUE(WriteResectionFrames(path, options, job, results).ok());
  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(path, FramesTableOptions(), &frames).ok());
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].raster, job.inputs[0].raster);
  EXPECT_LT((frames[0].eo.parameters - results[0].eo.parameters).norm(), 1e-9);
  // The verdict, and the input frame's measured centre beside the adjusted one.
  ASSERT_GE(frames[0].extra_columns.size(), 6u);
  const std::vector<std::pair<std::string, std::string>> extra = {
      {"NumObservations", "20"}, {"NumInliers", "18"}, {"Reliability", "ok"}};
  const std::vector<std::pair<std::string, std::string>> first_three(
      frames[0].extra_columns.begin(), frames[0].extra_columns.begin() + 3);
  EXPECT_EQ(first_three, extra);
  const Eigen::Vector3d measured = *job.block.images[job.images[0]].measured_center_m;
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(frames[0].extra_columns[3 + k].first, std::string("Measured") + "XYZ"[k]);
    EXPECT_NEAR(std::stod(frames[0].extra_columns[3 + k].second), measured[k], 1e-4);
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
