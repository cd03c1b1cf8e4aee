#include "tools/jobs/resection_job.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/block.h"
#include "core/io/tables.h"
#include "core/simulation/synthetic_scene.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

// Noise-free marks reproject to ~1e-9 px (the projection in double precision); a shift of 2 px
// must show as 2 px.
constexpr double kExactResidualPx = 1e-6;

struct Fixture {
  SyntheticScene scene;
  BlockTables tables;
  Block block;
};

// The nadir scene without noise (one image, 20 control and 5 check points), plus one mark of a
// tie point (no row in the points) in that image and a frames row of a second image without
// marks.
Fixture MakeFixture() {
  Fixture f;
  SyntheticSceneOptions options;
  options.noise_px = 0.0;
  EXPECT_TRUE(MakeSyntheticScene(options, &f.scene).ok());
  f.tables = SceneBlockTables(f.scene);
  ImageMark tie = f.tables.marks.front();
  tie.point_id = "TIE1";
  f.tables.marks.push_back(tie);
  FrameRecord empty = f.tables.frames.front();
  empty.raster = "NO_MARKS";
  f.tables.frames.push_back(empty);
  const Status assembled = AssembleBlock(f.tables, &f.block);
  EXPECT_TRUE(assembled.ok()) << assembled.message();
  return f;
}

TEST(ResectionJob, OneInputPerImageWithMarksControlMarksOnly) {
  Fixture f = MakeFixture();
  ASSERT_EQ(f.block.images.size(), 2u);  // the marked image first, then the frames-only one
  ResectionJob job;
  ASSERT_TRUE(PrepareResectionJob(f.block, ResectionInputOptions(), &job).ok());
  ASSERT_EQ(job.inputs.size(), 1u);
  ASSERT_EQ(job.images, std::vector<int>{0});
  EXPECT_EQ(job.inputs[0].raster, f.scene.true_frames[0].raster);
  // 20 control marks go into the resection; the 5 check marks are kept apart; the tie mark is
  // counted and left out.
  ASSERT_EQ(job.input_marks.size(), 1u);
  ASSERT_EQ(job.input_marks[0].size(), 20u);
  for (const int m : job.input_marks[0])
    EXPECT_EQ(job.block.points[job.block.marks[m].point].role, PointRole::kControl) << m;
  ASSERT_EQ(job.check_marks.size(), 1u);
  ASSERT_EQ(job.check_marks[0].size(), 5u);
  for (const int m : job.check_marks[0])
    EXPECT_EQ(job.block.points[job.block.marks[m].point].role, PointRole::kCheck) << m;
  EXPECT_EQ(job.num_tie_marks, 1);
}

TEST(ResectionJob, CheckResidualsAreZeroAtTheTruthAndShowAShiftedMark) {
  Fixture f = MakeFixture();
  // Move the first check mark 2 px to the right (Column + 2).
  int shifted = -1;
  for (size_t m = 0; m < f.tables.marks.size(); ++m) {
    for (const GroundPoint& p : f.scene.points) {
      if (p.point_id == f.tables.marks[m].point_id && p.role == PointRole::kCheck && shifted < 0) {
        shifted = static_cast<int>(m);
        f.tables.marks[m].column_row->x() += 2.0;
      }
    }
  }
  ASSERT_GE(shifted, 0);
  ASSERT_TRUE(AssembleBlock(f.tables, &f.block).ok());
  ResectionJob job;
  ASSERT_TRUE(PrepareResectionJob(f.block, ResectionInputOptions(), &job).ok());
  ASSERT_EQ(job.check_marks.size(), 1u);
  const std::vector<CheckResidual> residuals = CheckResiduals(job, 0, f.scene.true_frames[0].eo);
  ASSERT_EQ(residuals.size(), 5u);
  for (const CheckResidual& r : residuals) {
    // Block mark m is table mark m (SceneBlockTables; the tie mark was appended).
    EXPECT_NEAR(r.residual.norm(), r.mark == shifted ? 2.0 : 0.0, kExactResidualPx) << r.mark;
  }
}

TEST(ResectionJob, OutputAnglesFollowTheConventionAndTheAngleDirection) {
  Fixture f = MakeFixture();
  ResectionJob job;
  ASSERT_TRUE(PrepareResectionJob(f.block, ResectionInputOptions(), &job).ok());
  ExteriorOrientation eo;
  eo.parameters << 1.0, 2.0, 3.0, 0.1, -0.2, 0.3;
  // Seed convention, AngleDirection -1 (the default): the seed angles in degrees.
  const Eigen::Vector3d seed = OutputAnglesDeg(job, 0, RotationConvention::kSeed, eo);
  EXPECT_LT((seed - Eigen::Vector3d(0.1, -0.2, 0.3) * 180.0 / kPi).norm(), 1e-12);
  // AngleDirection +1 negates them.
  job.block.cameras[job.block.images[0].camera].table.angle_direction = 1;
  const Eigen::Vector3d negated = OutputAnglesDeg(job, 0, RotationConvention::kSeed, eo);
  EXPECT_LT((negated + seed).norm(), 1e-12);
}

TEST(ResectionJob, AngleSigmasAndSigma0Unit) {
  Fixture f = MakeFixture();
  ResectionJob job;
  ASSERT_TRUE(PrepareResectionJob(f.block, ResectionInputOptions(), &job).ok());
  ResectionResult result;
  result.eo.parameters << 0.0, 0.0, 100.0, 0.05, 0.02, 0.4;
  EXPECT_FALSE(OutputAngleSigmasDeg(job, 0, RotationConvention::kSeed, result).has_value());
  // Seed angles written in the seed convention: the Jacobian is the identity, so the sigmas are
  // the square roots of the diagonal: (1, 2, 3) mrad = (0.0573, 0.1146, 0.1719) deg.
  result.has_covariance = true;
  result.covariance.bottomRightCorner<3, 3>() = Eigen::Vector3d(1e-6, 4e-6, 9e-6).asDiagonal();
  const auto sigmas = OutputAngleSigmasDeg(job, 0, RotationConvention::kSeed, result);
  ASSERT_TRUE(sigmas.has_value());
  EXPECT_LT((*sigmas - Eigen::Vector3d(1e-3, 2e-3, 3e-3) * 180.0 / kPi).norm(), 1e-9);
  // sigma0 is unitless when the accuracy was stated, else in the marks' unit (pixels here).
  result.accuracy_stated = true;
  EXPECT_EQ(Sigma0Unit(job, 0, result), "");
  result.accuracy_stated = false;
  EXPECT_EQ(Sigma0Unit(job, 0, result), "px");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
