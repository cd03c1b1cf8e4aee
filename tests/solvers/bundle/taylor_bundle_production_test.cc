// The Taylor bundle adjustment as a production path (issue 23): Levenberg-Marquardt against the
// lecture's Gauss-Newton from poor starts, the CHOLMOD supernodal factor against Eigen's LDL^T,
// one thread against two, and the final cost against Ceres on a mid-size block.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/taylor_bundle.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ tolerances
// The two factorisations of the same Jacobi-scaled reduced system (condition ~1e8 on these
// blocks) give corrections that differ by rounding, ~1e-16 x 1e8 relative per iteration; the
// converged solutions then differ far below the 1e-9 of the block size asked (measured: printed).
constexpr double kFactorisationAgreement = 1e-9;
// Taylor and Ceres minimise the same objective; each stops on its own tolerances (Taylor:
// corrections below 1 um and 1e-9 rad; Ceres: relative cost change 1e-10), so their final costs
// agree to about 1e-10 relative; issue 23 asks for 1e-6.
constexpr double kCostAgreement = 1e-6;

// The block of the solver benchmarks (SolverBenchmarkBlockOptions: frame images at 100 m, 20 m /
// 30 m spacing, 5 control and 2 check points, GNSS, 0.5 px marks, the generator's perturbed start).
struct TestBlock {
  Block block;
  SyntheticBlockTruth truth;
  double size_m = 0.0;
};

TestBlock MakeBlock(int lines, int images_per_line, int tie_points) {
  const SyntheticBlockOptions o = SolverBenchmarkBlockOptions(lines, images_per_line, tie_points);
  TestBlock out;
  const Status status = MakeSyntheticBlock(o, &out.block, &out.truth);
  EXPECT_TRUE(status.ok()) << status.message();
  out.size_m = std::hypot(std::hypot((lines - 1) * o.side_spacing_m,
                                     (images_per_line - 1) * o.forward_spacing_m),
                          o.flying_height_m);
  return out;
}

TaylorBundleOptions Options() {
  TaylorBundleOptions options;
  options.rejection_threshold = 0.0;
  options.statistics.covariances = BundleCovarianceMethod::kNone;
  return options;
}

// The largest difference of camera centres and points between two adjusted copies (m), and of
// the angles (rad).
void Differences(const Block& a, const Block& b, double* position_m, double* angle_rad) {
  *position_m = *angle_rad = 0.0;
  for (size_t i = 0; i < a.images.size(); ++i) {
    const Vector6d d = a.images[i].eo->parameters - b.images[i].eo->parameters;
    *position_m = std::max(*position_m, d.head<3>().cwiseAbs().maxCoeff());
    *angle_rad = std::max(*angle_rad, d.tail<3>().cwiseAbs().maxCoeff());
  }
  for (size_t p = 0; p < a.points.size(); ++p) {
    if (!a.points[p].position_m || !b.points[p].position_m) continue;
    *position_m = std::max(
        *position_m, (*a.points[p].position_m - *b.points[p].position_m).cwiseAbs().maxCoeff());
  }
}

// A poor start: every kappa turned by kappa_deg, every camera centre moved by up to shift_m
// (seeded), the tie points left where the generator put them.
void PoorStart(double kappa_deg, double shift_m, Block* block) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (BlockImage& image : block->images) {
    image.eo->parameters[0] += shift_m * uniform(rng);
    image.eo->parameters[1] += shift_m * uniform(rng);
    image.eo->parameters[5] += kappa_deg / 180.0 * M_PI;
  }
}

TEST(TaylorBundleDamping, LevenbergMarquardtConvergesWhereGaussNewtonDoesNot) {
  const TestBlock data = MakeBlock(3, 4, 144);
  // The minimum, from the generator's start.
  Block reference = data.block;
  TaylorBundleResult reference_result;
  ASSERT_TRUE(TaylorBundleAdjust(Options(), BundleAdjustmentConfig(), &reference,
                                 &reference_result)
                  .ok());
  ASSERT_TRUE(reference_result.summary.IsSolutionUsable())
      << reference_result.summary.BriefReport();

  // Starts from which Gauss-Newton fails (a point falls behind a camera, or it diverges) on
  // this block (measured: kappa 90 deg with centres 60 m off, 120 deg with 30 m, 143 deg with 60 m).
  struct Start {
    double kappa_deg, shift_m;
  };
  // Where undamped Gauss-Newton goes from such a start is chaotic (it converged from the 90 deg
  // start in CI's clang build): it must fail from most of them; LM must converge from every one.
  int gauss_newton_failures = 0;
  for (const Start start : {Start{90.0, 60.0}, Start{120.0, 30.0}, Start{143.0, 60.0}}) {
    SCOPED_TRACE("kappa " + std::to_string(start.kappa_deg) + " deg, centres " +
                 std::to_string(start.shift_m) + " m");
    Block poor = data.block;
    PoorStart(start.kappa_deg, start.shift_m, &poor);
    Block gauss_newton = poor;
    TaylorBundleOptions undamped = Options();
    undamped.damping = TaylorDamping::kNone;
    TaylorBundleResult gn_result;
    ASSERT_TRUE(
        TaylorBundleAdjust(undamped, BundleAdjustmentConfig(), &gauss_newton, &gn_result).ok());
    std::printf("  kappa %3.0f deg, centres %2.0f m: Gauss-Newton %s after %d; ", start.kappa_deg,
                start.shift_m, EnumName(gn_result.summary.termination_type),
                gn_result.summary.iterations);
    gauss_newton_failures += !gn_result.summary.IsSolutionUsable();

    Block levenberg = poor;
    TaylorBundleResult lm_result;
    ASSERT_TRUE(
        TaylorBundleAdjust(Options(), BundleAdjustmentConfig(), &levenberg, &lm_result).ok());
    ASSERT_TRUE(lm_result.summary.IsSolutionUsable()) << lm_result.summary.BriefReport();
    EXPECT_GT(lm_result.summary.refused_steps, 0);  // the damping did something
    double position_m = 0.0, angle_rad = 0.0;
    Differences(reference, levenberg, &position_m, &angle_rad);
    std::printf("LM converged in %d (%d refused), %.1e m, %.1e rad from the minimum\n",
                lm_result.summary.iterations, lm_result.summary.refused_steps, position_m,
                angle_rad);
    EXPECT_LT(position_m, 1e-6 * data.size_m);
    EXPECT_LT(angle_rad, 1e-6);
    EXPECT_NEAR(lm_result.summary.final_cost, reference_result.summary.final_cost,
                kCostAgreement * reference_result.summary.final_cost);
    // A step taken decreased the cost; a refused one left it unchanged.
    for (size_t k = 1; k < lm_result.history.size(); ++k)
      EXPECT_LE(lm_result.history[k].cost, lm_result.history[k - 1].cost * (1.0 + 1e-12));
  }
  EXPECT_GE(gauss_newton_failures, 2);
}

TEST(TaylorBundleDamping, SameMinimumWithAndWithoutDampingFromAGoodStart) {
  const TestBlock data = MakeBlock(3, 4, 144);
  Block damped = data.block, undamped = data.block;
  TaylorBundleOptions gn = Options();
  gn.damping = TaylorDamping::kNone;
  TaylorBundleResult lm_result, gn_result;
  ASSERT_TRUE(TaylorBundleAdjust(Options(), BundleAdjustmentConfig(), &damped, &lm_result).ok());
  ASSERT_TRUE(TaylorBundleAdjust(gn, BundleAdjustmentConfig(), &undamped, &gn_result).ok());
  ASSERT_TRUE(lm_result.summary.IsSolutionUsable()) << lm_result.summary.BriefReport();
  ASSERT_TRUE(gn_result.summary.IsSolutionUsable()) << gn_result.summary.BriefReport();
  double position_m = 0.0, angle_rad = 0.0;
  Differences(damped, undamped, &position_m, &angle_rad);
  EXPECT_LT(position_m, 1e-6 * data.size_m);
  EXPECT_LT(angle_rad, 1e-6);
}

TEST(TaylorBundleLinearSolver, CholmodSupernodalEqualsEigenLdlt) {
  for (const TaylorDamping damping : {TaylorDamping::kNone, TaylorDamping::kLevenbergMarquardt}) {
    SCOPED_TRACE(EnumName(damping));
    const TestBlock data = MakeBlock(5, 8, 900);
    Block cholmod = data.block, eigen = data.block;
    TaylorBundleOptions options = Options();
    options.damping = damping;
    options.statistics.covariances = BundleCovarianceMethod::kSelectedInversion;
    TaylorBundleResult cholmod_result, eigen_result;
    ASSERT_TRUE(
        TaylorBundleAdjust(options, BundleAdjustmentConfig(), &cholmod, &cholmod_result).ok());
    options.linear_solver = TaylorLinearSolver::kEigenLdlt;
    ASSERT_TRUE(TaylorBundleAdjust(options, BundleAdjustmentConfig(), &eigen, &eigen_result).ok());
    ASSERT_TRUE(cholmod_result.summary.IsSolutionUsable());
    ASSERT_TRUE(eigen_result.summary.IsSolutionUsable());
    double position_m = 0.0, angle_rad = 0.0;
    Differences(cholmod, eigen, &position_m, &angle_rad);
    std::printf("  %s: CHOLMOD against Eigen LDL^T: %.2e m (%.2e of the block), %.2e rad\n",
                EnumName(damping), position_m, position_m / data.size_m, angle_rad);
    EXPECT_LT(position_m, kFactorisationAgreement * data.size_m);
    EXPECT_LT(angle_rad, kFactorisationAgreement);
    EXPECT_EQ(cholmod_result.summary.iterations, eigen_result.summary.iterations);
    EXPECT_NEAR(cholmod_result.summary.final_cost, eigen_result.summary.final_cost,
                1e-12 * eigen_result.summary.final_cost);
    // The statistics follow the same solution.
    for (size_t i = 0; i < cholmod.images.size(); ++i) {
      const Matrix6d& a = cholmod_result.adjustment.images[i].covariance;
      const Matrix6d& b = eigen_result.adjustment.images[i].covariance;
      EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-6 * b.cwiseAbs().maxCoeff());
    }
  }
}

TEST(TaylorBundleThreads, OneAndTwoThreadsGiveIdenticalResults) {
  for (const TaylorDamping damping : {TaylorDamping::kNone, TaylorDamping::kLevenbergMarquardt}) {
    SCOPED_TRACE(EnumName(damping));
    const TestBlock data = MakeBlock(5, 8, 900);
    Block one = data.block, two = data.block;
    TaylorBundleOptions options = Options();
    options.damping = damping;
    options.statistics.covariances = BundleCovarianceMethod::kSelectedInversion;
    TaylorBundleResult one_result, two_result;
    options.num_threads = 1;
    ASSERT_TRUE(TaylorBundleAdjust(options, BundleAdjustmentConfig(), &one, &one_result).ok());
    options.num_threads = 2;
    ASSERT_TRUE(TaylorBundleAdjust(options, BundleAdjustmentConfig(), &two, &two_result).ok());
    ASSERT_TRUE(one_result.summary.IsSolutionUsable());
    EXPECT_EQ(two_result.summary.num_threads, 2);
    // Bit for bit: the sums run in the same order whatever the thread count.
    EXPECT_EQ(one_result.summary.final_cost, two_result.summary.final_cost);
    EXPECT_EQ(one_result.summary.iterations, two_result.summary.iterations);
    ASSERT_EQ(one_result.history.size(), two_result.history.size());
    for (size_t k = 0; k < one_result.history.size(); ++k)
      EXPECT_EQ(one_result.history[k].cost, two_result.history[k].cost);
    for (size_t i = 0; i < one.images.size(); ++i) {
      EXPECT_EQ(one.images[i].eo->parameters, two.images[i].eo->parameters) << i;
      EXPECT_EQ(one_result.adjustment.images[i].covariance,
                two_result.adjustment.images[i].covariance)
          << i;
    }
    for (size_t p = 0; p < one.points.size(); ++p)
      if (one.points[p].position_m) EXPECT_EQ(*one.points[p].position_m, *two.points[p].position_m);
  }
}

TEST(TaylorBundleVsCeres, SameFinalCostOnAMidSizeBlock) {
  // The 60-image block of the benchmarks: 6 lines x 10 images, 1600 tie points.
  const TestBlock data = MakeBlock(6, 10, 1600);
  BundleAdjustmentOptions ceres_options;
  ceres_options.solver.num_threads = 2;
  ceres_options.robustness.rejection_threshold = 0.0;
  ceres_options.statistics.covariances = BundleCovarianceMethod::kNone;
  Block ceres = data.block, taylor = data.block;
  BundleAdjustmentResult ceres_result, taylor_result;
  ASSERT_TRUE(BundleAdjust(ceres_options, BundleAdjustmentConfig(), &ceres, &ceres_result).ok());
  TaylorBundleResult taylor_full;
  ASSERT_TRUE(BundleAdjustWithSolver(PoseSolver::kTaylor, ceres_options, BundleAdjustmentConfig(),
                                     &taylor, &taylor_result, &taylor_full)
                  .ok());
  ASSERT_EQ(ceres_result.summary.termination, SolverTermination::kConverged);
  ASSERT_EQ(taylor_result.summary.termination, SolverTermination::kConverged)
      << taylor_full.summary.BriefReport();
  EXPECT_EQ(taylor_full.summary.damping, TaylorDamping::kLevenbergMarquardt);
  EXPECT_EQ(taylor_full.summary.num_threads, 2);
  const double relative = std::abs(taylor_result.summary.final_cost -
                                   ceres_result.summary.final_cost) /
                          ceres_result.summary.final_cost;
  std::printf("  60 images: final cost Taylor %.10g, Ceres %.10g (relative %.1e); iterations %d / %d\n",
              taylor_result.summary.final_cost, ceres_result.summary.final_cost, relative,
              taylor_result.summary.iterations, ceres_result.summary.iterations);
  EXPECT_LT(relative, kCostAgreement);
  double position_m = 0.0, angle_rad = 0.0;
  Differences(ceres, taylor, &position_m, &angle_rad);
  EXPECT_LT(position_m, 1e-6 * data.size_m);
  EXPECT_LT(angle_rad, 1e-6);
}

// Robust losses by iteratively reweighted least squares (taylor_bundle.h): on a block with tie
// blunders the Taylor path reaches Ceres' minimum of the same robust cost, for each tie loss
// BundleAdjust offers. The blunders make the loss matter: without it the minimum moves by
// centimetres (checked).
TEST(TaylorBundleRobust, EveryTieLossReachesCeresMinimum) {
  TestBlock data = MakeBlock(5, 8, 900);
  data.block.BuildIndex();
  int blunders = 0;
  for (size_t p = 0; p < data.block.points.size() && blunders < 12; ++p) {
    if (data.block.points[p].role != PointRole::kTie || data.block.marks_of_point[p].size() < 4)
      continue;
    BlockMark& mark = data.block.marks[data.block.marks_of_point[p][0]];
    mark.observation += Eigen::Vector2d(20.0, -15.0) * mark.observation_units_per_unit;
    ++blunders;
  }
  ASSERT_EQ(blunders, 12);
  BundleAdjustmentOptions ceres_options;
  ceres_options.solver.num_threads = 1;
  ceres_options.robustness.rejection_threshold = 0.0;
  ceres_options.statistics.covariances = BundleCovarianceMethod::kNone;
  Block plain = data.block;
  BundleAdjustmentResult plain_result;
  ASSERT_TRUE(BundleAdjust(ceres_options, BundleAdjustmentConfig(), &plain, &plain_result).ok());
  for (const LossType loss : kBundleTieLosses) {
    if (loss == LossType::kNone) continue;
    SCOPED_TRACE(EnumName(loss));
    ceres_options.robustness.tie_loss = loss;
    Block ceres = data.block, taylor = data.block;
    BundleAdjustmentResult ceres_result, taylor_result;
    ASSERT_TRUE(BundleAdjust(ceres_options, BundleAdjustmentConfig(), &ceres, &ceres_result).ok());
    TaylorBundleResult taylor_full;
    ASSERT_TRUE(BundleAdjustWithSolver(PoseSolver::kTaylor, ceres_options,
                                       BundleAdjustmentConfig(), &taylor, &taylor_result,
                                       &taylor_full)
                    .ok());
    ASSERT_TRUE(ceres_result.summary.IsSolutionUsable()) << ceres_result.summary.BriefReport();
    ASSERT_TRUE(taylor_result.summary.IsSolutionUsable()) << taylor_full.summary.BriefReport();
    const double relative = std::abs(taylor_result.summary.final_cost -
                                     ceres_result.summary.final_cost) /
                            ceres_result.summary.final_cost;
    double position_m = 0.0, angle_rad = 0.0, moved_m = 0.0, unused = 0.0;
    Differences(ceres, taylor, &position_m, &angle_rad);
    Differences(plain, taylor, &moved_m, &unused);
    std::printf("  %s: final cost Taylor %.10g, Ceres %.10g (relative %.1e); %.1e m apart, %.1e m "
                "from plain least squares; iterations %d / %d\n",
                EnumName(loss), taylor_result.summary.final_cost, ceres_result.summary.final_cost,
                relative, position_m, moved_m, taylor_result.summary.iterations,
                ceres_result.summary.iterations);
    EXPECT_LT(relative, kCostAgreement);
    EXPECT_LT(position_m, 1e-6 * data.size_m);
    EXPECT_LT(angle_rad, 1e-6);
    EXPECT_GT(moved_m, 1e-3);  // the loss changed the minimum
    EXPECT_NEAR(taylor_result.summary.sigma0, ceres_result.summary.sigma0,
                kCostAgreement * ceres_result.summary.sigma0);
  }
}

TEST(TaylorBundleDamping, OptionsAreChecked) {
  std::string why;
  TaylorBundleOptions options;
  EXPECT_TRUE(options.IsValid(&why)) << why;
  options.partials = TaylorPartials::kAsPrinted;  // LM with the printed partials: refused
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("gain ratio"), std::string::npos) << why;
  options.damping = DefaultTaylorDamping(TaylorPartials::kAsPrinted);
  EXPECT_TRUE(options.IsValid(&why)) << why;
  options = TaylorBundleOptions();
  options.initial_damping = 0.0;
  EXPECT_FALSE(options.IsValid(&why));
  options = TaylorBundleOptions();
  options.min_gain_ratio = 1.0;
  EXPECT_FALSE(options.IsValid(&why));
  options = TaylorBundleOptions();
  options.num_threads = -1;
  EXPECT_FALSE(options.IsValid(&why));
  // The spellings of --taylor_damping (docs/formats.md).
  EXPECT_EQ(EnumChoices<TaylorDamping>(),
            "none (alias gauss_newton) or levenberg_marquardt (alias lm)");
  EXPECT_EQ(EnumChoices<TaylorLinearSolver>(), "cholmod_supernodal or eigen_ldlt");
  TaylorDamping damping;
  EXPECT_TRUE(ParseEnum("levenberg_marquardt", &damping));
  EXPECT_EQ(damping, TaylorDamping::kLevenbergMarquardt);
  EXPECT_TRUE(ParseEnum("none", &damping));
  EXPECT_EQ(damping, TaylorDamping::kNone);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
