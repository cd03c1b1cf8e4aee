#include "solvers/resection/pose_refinement.h"

#include <gtest/gtest.h>

#include <thread>

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

// RefinePose keeps its problem, weights and TinySolver per thread. A thread that refined other
// images before (more marks, a robust loss, the autodiff path) must give the same pose, bit for
// bit, as a fresh thread.
TEST(PoseRefinement, AThreadThatRefinedOtherImagesGivesTheFreshThreadsPose) {
  const Problem small = MakeProblem(Scenario::kOblique, 1.0, 0.0, 31);
  SyntheticSceneOptions large_options;
  large_options.seed = 32;
  large_options.noise_px = 0.5;
  large_options.outlier_fraction = 0.2;
  large_options.num_control_points = 40;
  large_options.num_check_points = 0;
  const Problem large = testing::MakeSceneInput(large_options);
  ASSERT_LT(small.all.size(), large.all.size());
  std::vector<JacobianType> jacobians = {JacobianType::kAnalytic, JacobianType::kAutodiff};
  for (const JacobianType jacobian : jacobians) {
    PoseRefinementOptions options;
    options.jacobian = jacobian;
    const auto refine_small = [&](ExteriorOrientation* eo) {
      *eo = *small.input.approximate;
      PoseRefinementSummary summary;
      return Refine(options, small, eo, &summary);
    };
    ExteriorOrientation fresh;
    bool fresh_ok = false;
    std::thread([&] { fresh_ok = refine_small(&fresh); }).join();
    ASSERT_TRUE(fresh_ok);

    ExteriorOrientation reused;
    bool reused_ok = false;
    std::thread([&] {
      for (const LossType loss : {LossType::kCauchy, LossType::kNone}) {
        PoseRefinementOptions before;
        before.loss = loss;
        before.jacobian =
            jacobian == JacobianType::kAnalytic ? JacobianType::kAutodiff : JacobianType::kAnalytic;
        ExteriorOrientation eo = *large.input.approximate;
        PoseRefinementSummary summary;
        Refine(before, large, &eo, &summary);
      }
      reused_ok = refine_small(&reused);
    }).join();
    ASSERT_TRUE(reused_ok);
    EXPECT_EQ(reused.parameters, fresh.parameters) << EnumName(jacobian);
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
