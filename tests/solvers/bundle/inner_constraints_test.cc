// The covariances of a relative block in an inner-constraint datum
// (solvers/bundle/internal/inner_constraints.h): the S-transformation against an oracle that
// knows nothing of it (the dense normal matrix of the whole block, its null space from an
// eigendecomposition, the constrained inverse from the bordered system), the similarity's
// tangent against the manifold, the minimum-trace property and the options around it.

#include "solvers/bundle/internal/inner_constraints.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/mark_weight.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_block.h"
#include "cost_functions/exterior_orientation_manifold.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/taylor_bundle.h"
#include "solvers/bundle/triangulation.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// A relative block small enough for a dense oracle (about 1000 unknowns).
SyntheticBlockOptions RelativeBlockOptions() {
  SyntheticBlockOptions o;
  o.seed = 5;
  o.num_lines = 3;
  o.images_per_line = 4;
  o.tie_point_density_per_m2 = 0.006;
  o.gnss = false;
  o.num_control_points = 0;
  o.num_check_points = 0;
  o.mark_sigma_px = 0.5;
  return o;
}

BundleAdjustmentOptions Options(BundleRelativeCovariance datum) {
  BundleAdjustmentOptions options;
  options.statistics.relative_covariance = datum;
  options.statistics.covariances = BundleCovarianceMethod::kSelectedInversion;
  options.robustness.max_rejection_rounds = 0;
  options.solver.num_threads = 1;
  return options;
}

struct Adjusted {
  Block block;  // adjusted
  BundleAdjustmentResult result;
};

Adjusted Adjust(const Block& input, BundleRelativeCovariance datum) {
  Adjusted a;
  a.block = input;
  EXPECT_TRUE(BundleAdjust(Options(datum), BundleAdjustmentConfig(), &a.block, &a.result).ok());
  EXPECT_TRUE(a.result.summary.IsSolutionUsable()) << a.result.summary.BriefReport();
  EXPECT_EQ(a.result.summary.datum, BundleDatum::kRelative);
  return a;
}

// The oracle: N = J^T J of every mark over every image (all six tangent components, the first
// image too) and every point; its null space from the 7 smallest eigenvalues (Jacobi-scaled);
// the covariance under the constraints B^T x = 0 (B: the null space on the datum's parameters)
// the top-left block of [[N, B], [B^T, 0]]^-1. Unscaled, in the tangent space; images first.
struct Oracle {
  Eigen::MatrixXd C;
  std::vector<int> point_column;  // per block point, its first column (-1: not in the problem)
  int num_images = 0;
  double null_gap = 0.0;  // 8th smallest / 7th smallest eigenvalue of the scaled N
};

Oracle MakeOracle(const Block& block, BundleRelativeCovariance datum) {
  Oracle o;
  o.num_images = static_cast<int>(block.images.size());
  int columns = 6 * o.num_images;
  o.point_column.assign(block.points.size(), -1);
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!block.points[p].position_m || block.marks_of_point[p].size() < 2) continue;
    o.point_column[p] = columns;
    columns += 3;
  }
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(columns, columns);
  const ExteriorOrientationManifold manifold;
  MarkSigmaDefaults defaults;
  defaults.pixel_px = 1.0;  // the bundle's default tie accuracy
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (o.point_column[p] < 0) continue;
    for (const int m : block.marks_of_point[p]) {
      const BlockMark& mark = block.marks[m];
      const BlockImage& image = block.images[mark.image];
      const BlockCamera& camera = block.cameras[image.camera];
      RayObservation ray;
      ray.camera = &camera;
      ray.eo = *image.eo;
      ray.observation = mark.observation;
      ray.sigma = MarkSigma(mark, camera, defaults);
      const std::unique_ptr<ceres::CostFunction> cost(CreateRayCost(ray));
      const Vector6d eo = image.eo->parameters;
      const Eigen::Vector3d X = *block.points[p].position_m;
      const int n = static_cast<int>(camera.params.size());
      Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J_eo;
      Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J_X;
      Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor> J_cam(2, n);
      const double* parameters[] = {eo.data(), X.data(), camera.params.data()};
      double residual[2];
      double* jacobians[] = {J_eo.data(), J_X.data(), J_cam.data()};
      EXPECT_TRUE(cost->Evaluate(parameters, residual, jacobians));
      Eigen::Matrix<double, 6, 6, Eigen::RowMajor> P;
      manifold.PlusJacobian(eo.data(), P.data());
      Eigen::Matrix<double, 2, Eigen::Dynamic> J = Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, columns);
      J.middleCols<6>(6 * mark.image) = J_eo * P;
      J.middleCols<3>(o.point_column[p]) = J_X;
      N.noalias() += J.transpose() * J;
    }
  }
  const Eigen::VectorXd d = N.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = d.asDiagonal() * N * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  o.null_gap = eigen.eigenvalues()[7] / std::abs(eigen.eigenvalues()[6]);
  const Eigen::MatrixXd null_space = d.asDiagonal() * eigen.eigenvectors().leftCols(7);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(columns, 7);
  for (int c = 0; c < columns; ++c) {
    const bool image_column = c < 6 * o.num_images;
    const bool selected = datum == BundleRelativeCovariance::kInnerPoints
                              ? !image_column
                              : image_column && c % 6 < 3;
    if (selected) B.row(c) = null_space.row(c);
  }
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(columns + 7, columns + 7);
  K.topLeftCorner(columns, columns) = N;
  K.topRightCorner(columns, 7) = B;
  K.bottomLeftCorner(7, columns) = B.transpose();
  const Eigen::MatrixXd rhs = Eigen::MatrixXd::Identity(columns + 7, columns);
  o.C = K.partialPivLu().solve(rhs).topRows(columns);
  return o;
}

// |a - b| within `tolerance` of sqrt(a_rr a_cc) for every entry.
void ExpectSameCovariance(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double tolerance,
                          const std::string& what) {
  for (int r = 0; r < b.rows(); ++r)
    for (int c = 0; c < b.cols(); ++c)
      EXPECT_NEAR(a(r, c), b(r, c), tolerance * std::sqrt(std::abs(b(r, r) * b(c, c))))
          << what << " (" << r << "," << c << ")";
}

void CompareWithOracle(BundleRelativeCovariance datum) {
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(RelativeBlockOptions(), &block, &truth).ok());
  const Adjusted a = Adjust(block, datum);
  const Oracle o = MakeOracle(a.block, datum);
  ASSERT_GT(o.null_gap, 1e6) << "the block's normal matrix has more than 7 free directions";
  const double variance_factor = a.result.summary.sigma0 * a.result.summary.sigma0;
  const ExteriorOrientationManifold manifold;
  for (int i = 0; i < o.num_images; ++i) {
    ASSERT_TRUE(a.result.images[i].has_covariance) << "image " << i;
    const Vector6d eo = a.block.images[i].eo->parameters;
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> P;
    manifold.PlusJacobian(eo.data(), P.data());
    const Matrix6d expected = variance_factor * P * o.C.block<6, 6>(6 * i, 6 * i) * P.transpose();
    ExpectSameCovariance(a.result.images[i].covariance, expected, 1e-8,
                         "image " + std::to_string(i));
  }
  int points = 0;
  for (size_t p = 0; p < a.block.points.size(); ++p) {
    if (o.point_column[p] < 0) continue;
    ASSERT_TRUE(a.result.points[p].has_covariance) << "point " << p;
    const int c = o.point_column[p];
    ExpectSameCovariance(a.result.points[p].covariance,
                         variance_factor * o.C.block<3, 3>(c, c), 1e-8,
                         "point " + std::to_string(p));
    ++points;
  }
  EXPECT_GT(points, 50);
}

TEST(InnerConstraints, PointDatumEqualsTheDenseConstrainedInverse) {
  CompareWithOracle(BundleRelativeCovariance::kInnerPoints);
}

TEST(InnerConstraints, CentreDatumEqualsTheDenseConstrainedInverse) {
  CompareWithOracle(BundleRelativeCovariance::kInnerCentres);
}

double TraceOfPoints(const BundleAdjustmentResult& r) {
  double trace = 0.0;
  for (const auto& p : r.points)
    if (p.has_covariance) trace += p.covariance.trace();
  return trace;
}

double TraceOfCentres(const BundleAdjustmentResult& r) {
  double trace = 0.0;
  for (const auto& i : r.images)
    if (i.has_covariance) trace += i.covariance.topLeftCorner<3, 3>().trace();
  return trace;
}

TEST(InnerConstraints, EachDatumHasTheSmallestTraceOfItsOwnParameters) {
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(RelativeBlockOptions(), &block, &truth).ok());
  const Adjusted on_points = Adjust(block, BundleRelativeCovariance::kInnerPoints);
  const Adjusted on_centres = Adjust(block, BundleRelativeCovariance::kInnerCentres);
  const Adjusted gauge = Adjust(block, BundleRelativeCovariance::kFirstImage);
  EXPECT_LT(TraceOfPoints(on_points.result), TraceOfPoints(on_centres.result));
  EXPECT_LT(TraceOfPoints(on_points.result), TraceOfPoints(gauge.result));
  EXPECT_LT(TraceOfCentres(on_centres.result), TraceOfCentres(on_points.result));
  EXPECT_LT(TraceOfCentres(on_centres.result), TraceOfCentres(gauge.result));
  // The adjustment's gauge holds its first image; an inner-constraint datum holds none.
  EXPECT_FALSE(gauge.result.images[0].has_covariance);
  EXPECT_TRUE(on_points.result.images[0].has_covariance);
  EXPECT_GT(on_points.result.images[0].covariance(0, 0), 0.0);
  // Residuals and redundancy numbers do not depend on the datum.
  ASSERT_EQ(on_points.result.observations.size(), gauge.result.observations.size());
  for (size_t k = 0; k < gauge.result.observations.size(); ++k)
    EXPECT_NEAR(on_points.result.observations[k].redundancy,
                gauge.result.observations[k].redundancy, 1e-9);
  EXPECT_NE(on_points.result.summary.covariance_datum.find("inner constraints on the"),
            std::string::npos)
      << on_points.result.summary.covariance_datum;
  EXPECT_NE(gauge.result.summary.covariance_datum.find("held"), std::string::npos)
      << gauge.result.summary.covariance_datum;
}

TEST(InnerConstraints, TaylorAdjustmentGivesTheSameCovariances) {
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(RelativeBlockOptions(), &block, &truth).ok());
  const Adjusted ceres = Adjust(block, BundleRelativeCovariance::kInnerPoints);
  Block taylor_block = block;
  BundleAdjustmentResult taylor;
  ASSERT_TRUE(BundleAdjustWithSolver(PoseSolver::kTaylor,
                                     Options(BundleRelativeCovariance::kInnerPoints),
                                     BundleAdjustmentConfig(), &taylor_block, &taylor)
                  .ok());
  ASSERT_TRUE(taylor.summary.IsSolutionUsable()) << taylor.summary.BriefReport();
  for (size_t i = 0; i < block.images.size(); ++i)
    ExpectSameCovariance(taylor.images[i].covariance, ceres.result.images[i].covariance, 1e-4,
                         "image " + std::to_string(i));
}

TEST(InnerConstraints, AnAbsoluteBlockKeepsItsOwnDatum) {
  SyntheticBlockOptions options = RelativeBlockOptions();
  options.gnss = true;
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(options, &block, &truth).ok());
  Block a = block, b = block;
  BundleAdjustmentResult on_points, gauge;
  ASSERT_TRUE(BundleAdjust(Options(BundleRelativeCovariance::kInnerPoints),
                           BundleAdjustmentConfig(), &a, &on_points).ok());
  ASSERT_TRUE(BundleAdjust(Options(BundleRelativeCovariance::kFirstImage),
                           BundleAdjustmentConfig(), &b, &gauge).ok());
  EXPECT_EQ(on_points.summary.datum, BundleDatum::kControl);
  EXPECT_EQ(on_points.summary.covariance_datum, "the block's datum (absolute)");
  for (size_t i = 0; i < block.images.size(); ++i)
    EXPECT_EQ(on_points.images[i].covariance, gauge.images[i].covariance);
}

// The similarity's rows are the manifold's tangent of the moved orientation: the ground frame
// turned by w about the centroid, scaled by s and shifted by t moves the centre as the rows say,
// and the camera's rotation R by R Omega^T, whose tangent (the manifold's Minus) is -R w.
TEST(InnerConstraints, OrientationRowsAreTheManifoldsTangentOfASimilarity) {
  const ExteriorOrientationManifold manifold;
  const Eigen::Vector3d centroid(100.0, -50.0, 20.0);
  const double extent = 80.0;
  Vector6d eo;
  eo << 130.0, -20.0, 400.0, 0.3, -0.2, 1.1;
  const Eigen::Matrix<double, 6, 7> G = internal::OrientationSimilarityRows(eo, centroid, extent);
  const double h = 1e-6;
  for (int k = 0; k < 7; ++k) {
    Eigen::Matrix<double, 7, 1> theta = Eigen::Matrix<double, 7, 1>::Zero();
    theta[k] = h;
    const Eigen::Vector3d t = theta.head<3>(), w = theta.segment<3>(3) / extent;
    const double s = theta[6] / extent;
    // The ground frame's rotation by the small vector w (Rodrigues).
    const Eigen::Matrix3d Omega =
        w.norm() > 0.0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                       : Eigen::Matrix3d::Identity();
    const Eigen::Vector3d C = eo.head<3>();
    Vector6d moved;
    moved.head<3>() = centroid + (1.0 + s) * Omega * (C - centroid) + t;
    const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.tail<3>());
    moved.tail<3>() = AnglesFromRotation(RotationConvention::kSeed, R * Omega.transpose());
    Vector6d tangent;
    manifold.Minus(moved.data(), eo.data(), tangent.data());
    for (int r = 0; r < 6; ++r)
      EXPECT_NEAR(tangent[r] / h, G(r, k), 1e-5 * (1.0 + G.col(k).norm())) << r << "," << k;
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
