#include "solvers/resection/pose_refinement.h"

#include <gtest/gtest.h>

#include "tests/solvers/resection/scene_input.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using Problem = testing::SceneInput;

Problem MakeProblem(Scenario scenario, double noise_px, double outlier_fraction, uint64_t seed) {
  SyntheticSceneOptions options;
  options.scenario = scenario;
  options.seed = seed;
  options.noise_px = noise_px;
  options.outlier_fraction = outlier_fraction;
  options.num_check_points = 0;
  return testing::MakeSceneInput(options);
}

bool Refine(const PoseRefinementOptions& options, const Problem& p, ExteriorOrientation* eo,
            PoseRefinementSummary* summary) {
  return RefinePose(options, p.input.image_plane, p.input.points_in_ground, p.sigmas,
                    p.input.focal_length, p.all, eo, summary);
}

TEST(PoseRefinement, EverySolverReachesTheSameLeastSquaresPose) {
  const Problem p = MakeProblem(Scenario::kOblique, 1.0, 0.0, 3);
  std::vector<ExteriorOrientation> poses;
  for (PoseSolver solver : {PoseSolver::kCeres, PoseSolver::kTaylor}) {
    for (JacobianType jacobian : {JacobianType::kAnalytic, JacobianType::kAutodiff}) {
      for (CeresMinimizer minimizer : {CeresMinimizer::kTinySolver, CeresMinimizer::kProblem}) {
        PoseRefinementOptions options;
        options.solver = solver;
        options.jacobian = jacobian;
        options.ceres.minimizer = minimizer;
        ExteriorOrientation eo = *p.input.approximate;
        PoseRefinementSummary summary;
        ASSERT_TRUE(Refine(options, p, &eo, &summary)) << summary.message;
        EXPECT_TRUE(summary.converged());
        EXPECT_LT(summary.final_cost, summary.initial_cost);
        poses.push_back(eo);
      }
    }
  }
  // Each stops within 1e-6 of a standard deviation (~0.1 m, 1e-4 rad) of the minimum.
  for (const ExteriorOrientation& eo : poses) {
    EXPECT_LT((eo.parameters - poses[0].parameters).head<3>().norm(), 1e-5);
    EXPECT_LT((eo.parameters - poses[0].parameters).tail<3>().norm(), 1e-8);
  }
}

TEST(PoseRefinement, RobustLossBeatsPlainLeastSquaresWhenEveryMarkIsKept) {
  // 20% gross errors and every mark in the adjustment (no decisions here): least squares is
  // pulled off, the Cauchy loss is not.
  const Problem p = MakeProblem(Scenario::kNadir, 0.5, 0.2, 12);
  PoseRefinementOptions plain, robust;
  robust.loss = LossType::kCauchy;
  ExteriorOrientation a = *p.input.approximate, b = *p.input.approximate;
  PoseRefinementSummary summary;
  const bool plain_ok = Refine(plain, p, &a, &summary);
  ASSERT_TRUE(Refine(robust, p, &b, &summary)) << summary.message;
  const double error_robust = (b.center_in_ground() - p.truth.center_in_ground()).norm();
  EXPECT_LT(error_robust, 0.5);
  if (plain_ok) {
    const double error_plain = (a.center_in_ground() - p.truth.center_in_ground()).norm();
    EXPECT_GT(error_plain, 5.0 * error_robust);
  }
}

TEST(PoseRefinement, IterationLimitIsNoConvergenceAndLeavesThePose) {
  const Problem p = MakeProblem(Scenario::kOblique, 1.0, 0.0, 5);
  for (PoseSolver solver : {PoseSolver::kCeres, PoseSolver::kTaylor}) {
    PoseRefinementOptions options;
    options.solver = solver;
    options.ceres.max_iterations = 1;
    options.taylor.max_iterations = 1;
    ExteriorOrientation eo = *p.input.approximate;
    eo.parameters[2] += 150.0;
    const ExteriorOrientation start = eo;
    PoseRefinementSummary summary;
    EXPECT_FALSE(Refine(options, p, &eo, &summary));
    EXPECT_EQ(summary.termination, SolverTermination::kNoConvergence) << summary.message;
    EXPECT_FALSE(summary.message.empty());
    EXPECT_EQ(eo.parameters, start.parameters);
  }
}

TEST(PoseRefinement, OptionsAreChecked) {
  PoseRefinementOptions options;
  std::string why;
  EXPECT_TRUE(options.IsValid(&why));
  options.ceres.step_tolerance_sigmas = 0.0;
  EXPECT_FALSE(options.IsValid(&why));
  options = PoseRefinementOptions();
  options.loss_scale = -1.0;
  EXPECT_FALSE(options.IsValid(&why));
  options = PoseRefinementOptions();
  options.taylor.max_iterations = 0;
  EXPECT_FALSE(options.IsValid(&why));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
