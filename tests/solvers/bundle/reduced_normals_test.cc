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
namespace PHOTOPOSE_UNITY_ID {

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

// S factorised only, or inverted densely (the test oracle).
SelectedInversionOptions InversionOptions(bool factor_only, bool dense) {
  SelectedInversionOptions options;
  options.factor_only = factor_only;
  options.dense = dense;
  return options;
}

// Every residual block's rows: residuals and tangent-space Jacobians as Ceres evaluates them.
void ExpectRowsAsCeres(bool relative) {
  RoundFixture f;
  MakeRound(relative, &f);
  ReducedNormals reduced;
  BuildReducedNormals(f.round, InversionOptions(/*factor_only=*/true, /*dense=*/false), 1,
                      &reduced);
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
    }
    // Every point's W, made again from its rows on 1 and on 3 threads.
    std::vector<Eigen::MatrixXd> W_one, W_three;
    ASSERT_TRUE(ForEachPointW(f.round, one, 1, [&](int p, const Eigen::MatrixXd& W) {
      ASSERT_EQ(p, static_cast<int>(W_one.size()));
      W_one.push_back(W);
    }));
    ASSERT_TRUE(ForEachPointW(f.round, three, 3, [&](int p, const Eigen::MatrixXd& W) {
      ASSERT_EQ(p, static_cast<int>(W_three.size()));
      W_three.push_back(W);
    }));
    ASSERT_EQ(W_one.size(), one.V_inverse.size());
    EXPECT_EQ(W_one, W_three);
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

// A point's W made again from its rows (PointW) against J_e^T J_p of the same rows written out
// densely on the round's e columns, and the reduced matrix against U - sum W V^-1 W^T from them.
TEST(ReducedNormals, PointWIsTheProductOfThePointsRows) {
  // Summation order only: the products of the same rows, summed in another order.
  constexpr double kSumAgreement = 1e-12;
  for (const bool relative : {false, true}) {
    SCOPED_TRACE(relative ? "relative" : "gnss");
    RoundFixture f;
    MakeRound(relative, &f);
    ReducedNormals reduced;
    BuildReducedNormals(f.round, InversionOptions(/*factor_only=*/false, /*dense=*/true), 2,
                        &reduced);
    ASSERT_TRUE(reduced.ok) << reduced.message;
    const int n = reduced.size;
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);  // U - sum W V^-1 W^T, densely
    BlockRows rows;
    for (const ResidualInfo& info : f.round.residuals) {
      ASSERT_TRUE(EvaluateBlockRows(f.round, reduced, info, &rows));
      for (size_t a = 0; a < rows.e_columns.size(); ++a)
        for (size_t b = 0; b < rows.e_columns.size(); ++b)
          S(rows.e_columns[a], rows.e_columns[b]) += rows.J_e.col(a).dot(rows.J_e.col(b));
    }
    std::vector<BlockRows> scratch;
    int compared = 0;
    for (int p = 0; p < static_cast<int>(reduced.V_inverse.size()); ++p) {
      Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(n, 3);  // J_e^T J_p on every e column
      for (int k = reduced.point_residual_start[p]; k < reduced.point_residual_start[p + 1]; ++k) {
        ASSERT_TRUE(EvaluateBlockRows(f.round, reduced,
                                      f.round.residuals[reduced.residual_order[k]], &rows));
        ASSERT_EQ(rows.point, p);
        for (size_t a = 0; a < rows.e_columns.size(); ++a)
          expected.row(rows.e_columns[a]) += rows.J_e.col(a).transpose() * rows.J_p;
      }
      Eigen::MatrixXd W;
      ASSERT_TRUE(EvaluatePointW(f.round, reduced, p, &scratch, &W));
      // W's rows are its W_blocks' columns, in that order.
      Eigen::MatrixXd placed = Eigen::MatrixXd::Zero(n, 3);
      int row = 0;
      for (const int b : reduced.W_blocks[p]) {
        const int size = f.round.e_sizes[b];
        placed.middleRows(reduced.e_offset[b], size) = W.middleRows(row, size);
        row += size;
      }
      ASSERT_EQ(row, W.rows());
      EXPECT_LE((placed - expected).norm(), kSumAgreement * expected.norm()) << "point " << p;
      S -= placed * reduced.V_inverse[p] * placed.transpose();
      ++compared;
    }
    EXPECT_GT(compared, 50);
    // The dense oracle's C is S^-1.
    Eigen::MatrixXd C(n, n);
    for (int a = 0; a < reduced.C.num_blocks(); ++a) {
      for (int b = 0; b < reduced.C.num_blocks(); ++b) {
        Eigen::MatrixXd block;
        ASSERT_TRUE(reduced.C.Block(a, b, &block));
        C.block(reduced.e_offset[a], reduced.e_offset[b], block.rows(), block.cols()) = block;
      }
    }
    // S C = I to rounding, norm-wise (an inverse's backward error: conditioning does not enter).
    // A W made otherwise (another order of its rows, a part left out) changes S by about W V^-1
    // W^T, far above this.
    constexpr double kInverseBackwardError = 1e-11;
    const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(n, n);
    EXPECT_LE((S * C - identity).norm(), kInverseBackwardError * S.norm() * C.norm());
  }
}

// A round of rows alone (no Ceres problem, its costs made when asked) has every row, variable
// block and entry of C of the round built into a problem, bit for bit.
TEST(ReducedNormals, ARoundOfRowsAloneIsTheRoundOfTheProblem) {
  for (const bool relative : {false, true}) {
    SCOPED_TRACE(relative ? "relative" : "gnss");
    RoundFixture f;
    MakeRound(relative, &f);
    // The plan's own gauge (the fixture's round is built without it and then moved into it).
    BuildBundleRound(f.options, f.config, f.block, f.plan, &f.state, &f.round);
    BundleRound rows_alone;
    BuildBundleRoundRows(f.options, f.config, f.block, f.plan, &f.state, &rows_alone);
    ASSERT_EQ(rows_alone.problem, nullptr);
    EXPECT_TRUE(rows_alone.costs.empty());
    ASSERT_EQ(rows_alone.residuals.size(), f.round.residuals.size());
    EXPECT_EQ(rows_alone.e_blocks, f.round.e_blocks);
    EXPECT_EQ(rows_alone.e_sizes, f.round.e_sizes);
    EXPECT_EQ(rows_alone.point_blocks, f.round.point_blocks);
    EXPECT_EQ(rows_alone.redundancy(), f.round.redundancy());
    for (size_t k = 0; k < f.round.e_blocks.size(); ++k) {
      EXPECT_EQ(rows_alone.e_ambient_sizes[k],
                f.round.problem->ParameterBlockSize(f.round.e_blocks[k]));
      EXPECT_EQ(f.round.e_manifolds[k], f.round.problem->GetManifold(f.round.e_blocks[k]));
    }
    ReducedNormals a, b;
    BuildReducedNormals(f.round, SelectedInversionOptions(), 2, &a);
    BuildReducedNormals(rows_alone, SelectedInversionOptions(), 2, &b);
    ASSERT_TRUE(a.ok) << a.message;
    ASSERT_TRUE(b.ok) << b.message;
    BlockRows rows_a, rows_b;
    for (size_t r = 0; r < f.round.residuals.size(); ++r) {
      const ResidualInfo& info = f.round.residuals[r];
      ASSERT_EQ(rows_alone.residuals[r].group, info.group);
      ASSERT_EQ(rows_alone.residuals[r].item, info.item);
      ASSERT_EQ(rows_alone.residuals[r].first_axis, info.first_axis);
      ASSERT_TRUE(EvaluateBlockRows(f.round, a, info, &rows_a));
      ASSERT_TRUE(EvaluateBlockRows(rows_alone, b, rows_alone.residuals[r], &rows_b));
      EXPECT_EQ(rows_a.residuals, rows_b.residuals) << "residual " << r;
      EXPECT_EQ(rows_a.e_columns, rows_b.e_columns) << "residual " << r;
      EXPECT_EQ(rows_a.J_e, rows_b.J_e) << "residual " << r;
      EXPECT_EQ(rows_a.point, rows_b.point) << "residual " << r;
      if (rows_a.point >= 0) EXPECT_EQ(rows_a.J_p, rows_b.J_p) << "residual " << r;
    }
    ASSERT_EQ(a.C.num_blocks(), b.C.num_blocks());
    Eigen::MatrixXd block_a, block_b;
    for (int k = 0; k < a.C.num_blocks(); ++k) {
      ASSERT_TRUE(a.C.Block(k, k, &block_a));
      ASSERT_TRUE(b.C.Block(k, k, &block_b));
      EXPECT_EQ(block_a, block_b) << "block " << k;
    }
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

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::internal
