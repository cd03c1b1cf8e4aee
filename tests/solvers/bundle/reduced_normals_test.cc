// The reduced normal matrix of solvers/bundle/reduced_normals.cc: its rows against Ceres' own
// evaluation of the same residual blocks (tangent-space Jacobians through the manifolds), and the
// reduction the same, bit for bit, on one thread and on several.
#include "solvers/bundle/internal/reduced_normals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/internal/bundle_problem.h"

namespace photopose::internal {
namespace {

// A round of a simulated block with every kind of e block: exterior orientations, a calibrated
// camera and an estimated lever arm; free gauge or GNSS.
struct RoundFixture {
  Block block;
  BundleAdjustmentConfig config;
  BundleAdjustmentOptions options;
  BundlePlan plan;
  BundleState state;
  BundleRound round;
};

void MakeRound(bool relative, RoundFixture* f, double tie_point_density_per_m2 = 0.02) {
  SyntheticBlockOptions o;
  o.seed = 5;
  o.num_lines = 3;
  o.images_per_line = 5;
  o.tie_point_density_per_m2 = tie_point_density_per_m2;
  o.gnss = !relative;
  o.num_control_points = relative ? 0 : 6;
  o.num_check_points = 0;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(o, &f->block, &truth).ok());
  ASSERT_TRUE(BundleAdjustmentConfig::FromCalibrationNames(f->block, {"FocalLength", "K1"},
                                                           &f->config)
                  .ok());
  if (!relative) {
    f->config.lever_arm_m = Eigen::Vector3d(0.0, 0.0, 0.1);
    f->config.estimate_lever_arm = true;
  }
  ASSERT_TRUE(
      MakeBundlePlan(PlanOptionsOf(f->options, f->config), f->config, f->block, &f->plan).ok());
  f->state = StartState(f->config, f->block);
  BuildBundleRound(f->options, f->config, f->block, f->plan, &f->state, &f->round);
  if (relative) ApplyRelativeGauge(f->plan, &f->state, &f->round);
  ASSERT_FALSE(f->round.residuals.empty());
}

// Every residual block's rows: residuals and tangent-space Jacobians as Ceres evaluates them.
void ExpectRowsAsCeres(bool relative) {
  RoundFixture f;
  MakeRound(relative, &f);
  ReducedNormals reduced;
  SelectedInversionOptions factor_only;
  factor_only.factor_only = true;
  BuildReducedNormals(f.round, factor_only, 1, &reduced);
  ceres::Problem& problem = *f.round.problem;
  int with_manifold = 0, compared = 0;
  BlockRows rows;
  for (const ResidualInfo& info : f.round.residuals) {
    ASSERT_TRUE(EvaluateBlockRows(f.round, reduced, info, &rows));
    std::vector<double*> parameters;
    problem.GetParameterBlocksForResidualBlock(info.id, &parameters);
    const int n = problem.GetCostFunctionForResidualBlock(info.id)->num_residuals();
    std::vector<std::vector<double>> storage(parameters.size());
    std::vector<double*> jacobians(parameters.size(), nullptr);
    for (size_t k = 0; k < parameters.size(); ++k) {
      if (problem.IsParameterBlockConstant(parameters[k])) continue;
      storage[k].assign(static_cast<size_t>(n) * problem.ParameterBlockTangentSize(parameters[k]),
                        0.0);
      jacobians[k] = storage[k].data();
    }
    std::vector<double> residuals(n);
    double cost = 0.0;
    ASSERT_TRUE(problem.EvaluateResidualBlock(info.id, false, &cost, residuals.data(),
                                              jacobians.data()));
    ASSERT_EQ(rows.rows, n);
    for (int r = 0; r < n; ++r) EXPECT_DOUBLE_EQ(rows.residuals[r], residuals[r]);
    int column = 0, part = 0;
    for (size_t k = 0; k < parameters.size(); ++k) {
      if (jacobians[k] == nullptr) continue;
      const int tangent = problem.ParameterBlockTangentSize(parameters[k]);
      if (problem.GetManifold(parameters[k]) != nullptr) ++with_manifold;
      const auto e = reduced.e_index.find(parameters[k]);
      for (int r = 0; r < n; ++r) {
        for (int c = 0; c < tangent; ++c) {
          const double expected = jacobians[k][r * tangent + c];
          const double got = e != reduced.e_index.end() ? rows.J_e(r, column + c) : rows.J_p(r, c);
          EXPECT_NEAR(got, expected, 1e-12 * (1.0 + std::abs(expected)))
              << "residual of group " << info.group << " item " << info.item << " block " << k;
        }
      }
      if (e != reduced.e_index.end()) {
        ASSERT_LT(part, static_cast<int>(rows.e_blocks.size()));
        EXPECT_EQ(rows.e_blocks[part++], e->second);
        column += tangent;
      } else {
        EXPECT_EQ(rows.point, reduced.point_index.at(parameters[k]));
      }
      ++compared;
    }
  }
  EXPECT_GT(compared, 100);
  // The exterior orientations (and the relative gauge's held components) go through manifolds.
  EXPECT_GT(with_manifold, 0);
}

TEST(ReducedNormals, RowsAreCeresOwnWithGnssCalibrationAndLeverArm) { ExpectRowsAsCeres(false); }
TEST(ReducedNormals, RowsAreCeresOwnInTheRelativeGauge) { ExpectRowsAsCeres(true); }

// The reduction and the inverse's entries do not depend on the number of threads.
TEST(ReducedNormals, TheSameBitForBitOnOneAndOnSeveralThreads) {
  for (const bool relative : {false, true}) {
    SCOPED_TRACE(relative ? "relative" : "gnss");
    RoundFixture f;
    // Points enough for several chunks of the reduction (1024 points each).
    MakeRound(relative, &f, 0.3);
    ASSERT_GT(f.round.point_blocks.size(), 3000u);
    ReducedNormals one, three;
    BuildReducedNormals(f.round, SelectedInversionOptions(), 1, &one);
    BuildReducedNormals(f.round, SelectedInversionOptions(), 3, &three);
    ASSERT_TRUE(one.ok) << one.message;
    ASSERT_TRUE(three.ok) << three.message;
    ASSERT_EQ(one.V_inverse.size(), three.V_inverse.size());
    EXPECT_EQ(one.S_nonzeros, three.S_nonzeros);
    EXPECT_EQ(one.point_order, three.point_order);
    for (size_t p = 0; p < one.V_inverse.size(); ++p) {
      EXPECT_EQ(one.V_inverse[p], three.V_inverse[p]) << "point " << p;
      EXPECT_EQ(one.W_blocks[p], three.W_blocks[p]) << "point " << p;
      EXPECT_EQ(one.W[p], three.W[p]) << "point " << p;
    }
    const int num_blocks = one.C.num_blocks();
    ASSERT_GT(num_blocks, 1);
    Eigen::MatrixXd a, b;
    for (int k = 0; k < num_blocks; ++k) {
      ASSERT_TRUE(one.C.Block(k, k, &a));
      ASSERT_TRUE(three.C.Block(k, k, &b));
      EXPECT_EQ(a, b) << "block " << k;
    }
    // Every residual block is grouped once: by its point, or after the points.
    std::vector<int> order = one.residual_order;
    std::sort(order.begin(), order.end());
    for (size_t r = 0; r < order.size(); ++r) ASSERT_EQ(order[r], static_cast<int>(r));
    EXPECT_EQ(order.size(), f.round.residuals.size());
  }
}

// The points are taken in the order of their first e block: neighbours share images.
TEST(ReducedNormals, PointsAreOrderedByTheirFirstImage) {
  RoundFixture f;
  MakeRound(false, &f);
  ReducedNormals reduced;
  BuildReducedNormals(f.round, SelectedInversionOptions(), 2, &reduced);
  ASSERT_TRUE(reduced.ok) << reduced.message;
  int previous = -1;
  for (const int p : reduced.point_order) {
    ASSERT_FALSE(reduced.W_blocks[p].empty());
    const int first = reduced.W_blocks[p].front();
    EXPECT_GE(first, previous) << "point " << p;
    previous = first;
  }
}

}  // namespace
}  // namespace photopose::internal
