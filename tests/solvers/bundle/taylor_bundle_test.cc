#include "solvers/bundle/taylor_bundle.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/rotation.h"
#include "core/simulation/synthetic_block.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// The blocks (core/simulation/synthetic_block.h, TaylorBlockOptions below) with their truth.
struct TestBlock {
  Block block;
  SyntheticBlockTruth truth;
  double size_m = 0.0;  // diagonal of the camera-centre rectangle plus the flying height (m)
};

// ------------------------------------------------------------------ tolerances
// Central differences with steps of 1e-4 of the camera-point distance have a truncation error
// ~ (h / D)^2 = 1e-8 relative and rounding ~ 1e-11; 1e-6 leaves two orders of margin (the worst
// case measured is printed).
constexpr double kPartialRelativeTolerance = 1e-6;
// Issue 12: Taylor and Ceres reach the same minimum, camera positions to 1e-6 of the block size.
// Both stop on their own tolerances (Taylor: corrections below 1 um and 1e-9 rad; Ceres: relative
// cost change 1e-10); the measured differences, printed, are ~1e-9 of the block size.
constexpr double kRelativeAgreement = 1e-6;
// The same statistic from two solvers: sigma0 from costs that agree to ~1e-12 relative.
constexpr double kSigma0RelativeAgreement = 1e-6;
// Exterior-orientation covariances: the same inverse normal matrix, reached through Euler angles
// (Taylor) and a rotation manifold mapped back (Ceres), at solutions ~1e-9 of the block size apart.
constexpr double kCovarianceRelativeAgreement = 1e-4;
// The reduced system against the full one (dense LDL^T of a ~300 x 300 normal matrix whose scaled
// condition is ~1e8): relative to the largest entry / correction.
constexpr double kReductionRelativeTolerance = 1e-9;

BundleAdjustmentOptions CeresOptions() {
  BundleAdjustmentOptions options;
  options.solver.num_threads = 1;
  options.robustness.rejection_threshold = 0.0;
  return options;
}

// Ceres with its tolerances at 1e-14, for comparisons at the minimum itself.
BundleAdjustmentOptions TightCeresOptions() {
  BundleAdjustmentOptions options = CeresOptions();
  options.solver.function_tolerance = 1e-14;
  options.solver.parameter_tolerance = 1e-14;
  options.solver.gradient_tolerance = 1e-14;
  return options;
}

TaylorBundleOptions TaylorOptions(TaylorPartials partials = TaylorPartials::kCorrected) {
  TaylorBundleOptions options;
  options.partials = partials;
  options.damping = DefaultTaylorDamping(partials);
  options.rejection_threshold = 0.0;
  return options;
}

// Issue 12's blocks: 3 lines x 4 images of a frame camera (24 mm, 6000 x 4000 pixels of 4 um,
// radial K1 = -2e-5 mm^-2) at 100 m over terrain with 10 m relief, 20 m forward and 30 m side
// spacing, every line flown the same way (so that a nominal tilt looks the same way in every
// image), omega, phi, kappa within +- 2 deg; 144 tie points seen twice or more, four control
// points at the corners of the camera-centre rectangle and two check points (surveyed and stated
// at 5 mm), GNSS centres (3 cm), marks with 0.5 px noise; the generator's perturbed start
// (Gaussian: centres 2 m, angles 1 deg, tie points 0.5 m). Local coordinates (origin 0, ground 0).
SyntheticBlockOptions TaylorBlockOptions() {
  SyntheticBlockOptions o;
  o.num_lines = 3;
  o.images_per_line = 4;
  o.forward_spacing_m = 20.0;
  o.side_spacing_m = 30.0;
  o.flying_height_m = 100.0;
  o.origin_m = Eigen::Vector2d::Zero();
  o.ground_height_m = 0.0;
  o.serpentine = false;
  o.position_jitter_m = 0.0;
  o.camera_params = {24000.0, 0.0, 0.0, 0.0, -2e-5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  o.num_tie_points = 144;
  o.num_control_points = 4;  // the corners
  o.check_layout = {{0.5, 0.5}, {0.25, 0.75}};
  o.control_sigma_m = o.control_accuracy_m = 0.005;
  o.mark_sigma_px = o.mark_accuracy_px = 0.5;
  o.gnss_sigma_m = o.gnss_accuracy_m = Eigen::Vector3d::Constant(0.03);
  return o;
}

// The oblique variant: every image tilted by `omega_deg` (35 or 55), looking south; control and
// check points inside the footprints (the images look away from their centres). The footprints
// are trapezoids, wide at their far (south) edge and narrow at the near one: the points near the
// north edge of the covered rectangle stay near its middle.
SyntheticBlockOptions ObliqueOptions(double omega_deg) {
  SyntheticBlockOptions o = TaylorBlockOptions();
  o.nominal_angles_deg = Eigen::Vector3d(omega_deg, 0.0, 0.0);
  o.num_tie_points = 256;
  o.survey_area = SyntheticBlockOptions::SurveyArea::kFootprints;
  o.control_layout = {{0.2, 0.2}, {0.8, 0.2}, {0.35, 0.8}, {0.65, 0.8}};
  o.check_layout = {{0.5, 0.5}, {0.4, 0.65}, {0.6, 0.35}};
  return o;
}

// Without noise, the stated accuracies kept.
SyntheticBlockOptions NoiseFree(SyntheticBlockOptions o) {
  o.mark_sigma_px = 0.0;
  o.gnss_sigma_m = Eigen::Vector3d::Zero();
  o.control_sigma_m = 0.0;
  return o;
}

// The small block of the linearisation tests: 2 lines x 3 images with `tie_points` tie points.
SyntheticBlockOptions SixImages(SyntheticBlockOptions o, int tie_points) {
  o.num_lines = 2;
  o.images_per_line = 3;
  o.num_tie_points = tie_points;
  return o;
}

TestBlock MakeTestBlock(const SyntheticBlockOptions& o) {
  TestBlock out;
  const Status status = MakeSyntheticBlock(o, &out.block, &out.truth);
  EXPECT_TRUE(status.ok()) << status.message();
  const double span = std::hypot((o.num_lines - 1) * out.truth.side_spacing_m,
                                 (o.images_per_line - 1) * out.truth.forward_spacing_m);
  out.size_m = std::hypot(span, o.flying_height_m);
  return out;
}

double RotationDifferenceRad(const ExteriorOrientation& a, const ExteriorOrientation& b) {
  const Eigen::Matrix3d Ra = RotationFromAngles(RotationConvention::kSeed, a.angles_seed_rad());
  const Eigen::Matrix3d Rb = RotationFromAngles(RotationConvention::kSeed, b.angles_seed_rad());
  return Eigen::AngleAxisd(Ra * Rb.transpose()).angle();
}

// ------------------------------------------------------------------ partial derivatives

// A hand-computed case: a vertical camera (R = I) at height H above the point X = (dx, 0, -H)
// relative to it. x = -c dx / dZ = c dx / H, y = 0, so dx/dX = c / H, dx/dZ = c dx / H^2 (from
// -c dX / dZ with dZ = Z - Z0 = -H), dy/dY = c / H, and every other point partial is zero.
TEST(TaylorBundlePartials, NominalVerticalCase) {
  const double c = 24000.0, H = 100.0, dx = 10.0;
  ExteriorOrientation eo;
  eo.set_center_in_ground({5.0, 7.0, H});
  const Eigen::Vector3d point(5.0 + dx, 7.0, 0.0);
  Eigen::Matrix<double, 2, 6> d_eo;
  Eigen::Matrix<double, 2, 3> d_point;
  Eigen::Vector2d f;
  ASSERT_TRUE(TaylorMarkPartials(TaylorPartials::kCorrected, eo, point, c, {1000.0, 0.0}, &d_eo,
                                 &d_point, &f));
  EXPECT_NEAR(f[0], c * dx / H - 1000.0, 1e-9);
  EXPECT_NEAR(f[1], 0.0, 1e-9);
  EXPECT_NEAR(d_point(0, 0), c / H, 1e-9);
  EXPECT_NEAR(d_point(0, 1), 0.0, 1e-9);
  EXPECT_NEAR(d_point(0, 2), c * dx / (H * H), 1e-9);
  EXPECT_NEAR(d_point(1, 0), 0.0, 1e-9);
  EXPECT_NEAR(d_point(1, 1), c / H, 1e-9);
  EXPECT_NEAR(d_point(1, 2), 0.0, 1e-9);
  EXPECT_TRUE(d_point.isApprox(-d_eo.leftCols<3>(), 1e-15));
  // Behind the camera: no partials.
  EXPECT_FALSE(TaylorMarkPartials(TaylorPartials::kCorrected, eo, Eigen::Vector3d(0, 0, 2 * H), c,
                                  {0.0, 0.0}, &d_eo, &d_point, &f));
}

// Random oblique poses and points: the ground-point partials against central differences of the
// seed's functions (TaylorFunctions, eqs. 7-8), for both variants (the misprint of eq. 21 does not
// touch them); and the pose-at-a-time linearisation equal to the point-by-point one.
TEST(TaylorBundlePartials, PointPartialsMatchCentralDifferences) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> angle(-60.0 / kDegreesPerRadian, 60.0 / kDegreesPerRadian);
  std::uniform_real_distribution<double> full(-kPi, kPi);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> depth(100.0, 3000.0);
  const double c = 150000.0;
  double worst = 0.0;
  int checked = 0;
  for (int pose = 0; pose < 500; ++pose) {
    ExteriorOrientation eo;
    eo.set_center_in_ground({1000.0 * unit(rng), 1000.0 * unit(rng), 1000.0 * unit(rng)});
    eo.set_angles_seed_rad({angle(rng), angle(rng), full(rng)});
    const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
    for (int k = 0; k < 8; ++k) {
      // A point imaged within +- 0.6 c, at a random depth in front of the camera.
      const double D = depth(rng);
      const Eigen::Vector3d ray = DrawLastFirst<3>([&](int i) { return i == 2 ? -1.0 : 0.6 * unit(rng); });
      const Eigen::Vector3d point = eo.center_in_ground() + R.transpose() * (D * ray.normalized());
      const Eigen::Vector2d observed = DrawLastFirst<2>([&](int) { return 100.0 * unit(rng); });
      for (const TaylorPartials partials :
           {TaylorPartials::kCorrected, TaylorPartials::kAsPrinted}) {
        Eigen::Matrix<double, 2, 6> d_eo;
        Eigen::Matrix<double, 2, 3> d_point;
        Eigen::Vector2d f;
        ASSERT_TRUE(TaylorMarkPartials(partials, eo, point, c, observed, &d_eo, &d_point, &f));
        const double h = 1e-4 * D;
        for (int axis = 0; axis < 3; ++axis) {
          Eigen::Vector3d plus = point, minus = point;
          plus[axis] += h;
          minus[axis] -= h;
          double fu_p, fv_p, fu_m, fv_m;
          ASSERT_TRUE(TaylorFunctions(eo, plus, c, observed, &fu_p, &fv_p));
          ASSERT_TRUE(TaylorFunctions(eo, minus, c, observed, &fu_m, &fv_m));
          const Eigen::Vector2d numeric((fu_p - fu_m) / (2 * h), (fv_p - fv_m) / (2 * h));
          // Floor c / D: partials near zero are not divided by ~0.
          for (int r = 0; r < 2; ++r) {
            const double error =
                std::abs(d_point(r, axis) - numeric[r]) / std::max(std::abs(numeric[r]), c / D);
            worst = std::max(worst, error);
            EXPECT_LT(error, kPartialRelativeTolerance);
          }
        }
        // The pose-at-a-time linearisation is the point-by-point one, to the bit.
        double row_u[6], row_v[6], fu, fv;
        ASSERT_TRUE(
            TaylorPartialsForPoint(partials, eo, point, c, observed, row_u, row_v, &fu, &fv));
        for (int col = 0; col < 6; ++col) {
          EXPECT_EQ(d_eo(0, col), row_u[col]);
          EXPECT_EQ(d_eo(1, col), row_v[col]);
        }
        EXPECT_EQ(f[0], fu);
        EXPECT_EQ(f[1], fv);
        ++checked;
      }
    }
  }
  std::printf("  ground-point partials: %d checked, max relative error %.2e\n", checked, worst);
}

TEST(TaylorBundlePartials, AntennaPartialsMatchCentralDifferences) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> angle(-1.2, 1.2);
  const Eigen::Vector3d lever(0.12, -0.35, 0.8);
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    ExteriorOrientation eo;
    eo.set_center_in_ground({10.0, -20.0, 300.0});
    eo.set_angles_seed_rad({angle(rng), angle(rng), 2.5 * angle(rng)});
    Eigen::Matrix3d d_angles;
    const Eigen::Vector3d antenna = TaylorAntennaPosition(eo, lever, &d_angles);
    const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
    EXPECT_LT((antenna - (eo.center_in_ground() + R.transpose() * lever)).norm(), 1e-12);
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      ExteriorOrientation plus = eo, minus = eo;
      plus.parameters[3 + k] += h;
      minus.parameters[3 + k] -= h;
      const Eigen::Vector3d numeric = (TaylorAntennaPosition(plus, lever, nullptr) -
                                       TaylorAntennaPosition(minus, lever, nullptr)) /
                                      (2 * h);
      const double error = (d_angles.col(k) - numeric).norm() / lever.norm();
      worst = std::max(worst, error);
      EXPECT_LT(error, kPartialRelativeTolerance);
    }
  }
  std::printf("  lever-arm partials: max relative error %.2e\n", worst);
}

// ------------------------------------------------------------------ the reduced normal equations

// The reduction (points eliminated 3 x 3 at a time, pairs accumulated into the sparse S, the sparse
// LDL^T and the back-substitution) against the plain full normal equations of the same dense
// Jacobian, on a small block with every kind of observation equation.
void CheckReductionAgainstFullSystem(
    const TestBlock& data, const TaylorBundleOptions& options,
    const BundleAdjustmentConfig& config = BundleAdjustmentConfig()) {
  TaylorBundleLinearSystem system;
  const Status status = LinearizeTaylorBundle(options, config, data.block, &system);
  ASSERT_TRUE(status.ok()) << status.message();
  const Eigen::MatrixXd& A = system.jacobian;
  const Eigen::MatrixXd N = A.transpose() * A;
  const Eigen::VectorXd g = A.transpose() * system.residual;
  const int ne = static_cast<int>(system.reduced_matrix.rows());
  ASSERT_GT(ne, 0);
  ASSERT_EQ(N.rows(), ne + 3 * (N.rows() - ne) / 3);
  // The Schur complement, densely: S = U - W V^-1 W^T, r = g_e - W V^-1 g_p.
  const Eigen::MatrixXd U = N.topLeftCorner(ne, ne);
  const Eigen::MatrixXd W = N.topRightCorner(ne, N.cols() - ne);
  const Eigen::MatrixXd V = N.bottomRightCorner(N.cols() - ne, N.cols() - ne);
  const Eigen::MatrixXd V_inverse_Wt = V.ldlt().solve(W.transpose());
  Eigen::MatrixXd S = U - W * V_inverse_Wt;
  Eigen::VectorXd r = g.head(ne) - W * V.ldlt().solve(g.tail(N.cols() - ne));
  // Columns held fixed (the relative gauge) are zero in A: S gets 1 on their diagonal, as the
  // solver does.
  for (int k = 0; k < ne; ++k)
    if (A.col(k).squaredNorm() == 0.0) S(k, k) = 1.0;
  const double s_scale = S.cwiseAbs().maxCoeff();
  const double s_error = (S - system.reduced_matrix).cwiseAbs().maxCoeff() / s_scale;
  const double r_error = (r - system.reduced_rhs).cwiseAbs().maxCoeff() / r.cwiseAbs().maxCoeff();
  // The full system solved directly (fixed columns: their correction is zero).
  Eigen::MatrixXd N_fixed = N;
  for (int k = 0; k < ne; ++k)
    if (A.col(k).squaredNorm() == 0.0) N_fixed(k, k) = 1.0;
  const Eigen::VectorXd d = N_fixed.ldlt().solve(g);
  const double d_error = (d - system.correction).cwiseAbs().maxCoeff() / d.cwiseAbs().maxCoeff();
  std::printf("  %d observations, %d unknowns (%d camera): S %.2e, r %.2e, correction %.2e\n",
              static_cast<int>(A.rows()), static_cast<int>(A.cols()), ne, s_error, r_error,
              d_error);
  EXPECT_LT(s_error, kReductionRelativeTolerance);
  EXPECT_LT(r_error, kReductionRelativeTolerance);
  EXPECT_LT(d_error, kReductionRelativeTolerance);
}

TEST(TaylorBundleNormalEquations, ReducedEqualTheFullOnes) {
  SyntheticBlockOptions o = SixImages(TaylorBlockOptions(), 49);
  TestBlock data = MakeTestBlock(o);
  // Attitude priors too, and a lever arm on the camera positions.
  for (size_t i = 0; i < data.block.images.size(); ++i) {
    data.block.images[i].measured_angles_rad = data.truth.eo[i].angles_seed_rad();
    data.block.images[i].attitude_accuracy_rad = Eigen::Vector3d::Constant(1e-3);
  }
  BundleAdjustmentConfig lever_config;
  lever_config.lever_arm_m = Eigen::Vector3d(0.1, 0.2, 0.3);
  CheckReductionAgainstFullSystem(data, TaylorOptions(), lever_config);
  // A relative block: the first image fixed, one coordinate of the second.
  o.gnss = false;
  o.num_control_points = 0;
  o.check_layout.clear();
  o.num_check_points = 0;
  CheckReductionAgainstFullSystem(MakeTestBlock(o), TaylorOptions());
}

// The COLMAP forward models, with distortion strong enough that their 2 x 2 derivative is far from
// a scaled identity at the image corners (in pixels, core/camera_models.h's order).
struct ForwardModel {
  CameraModelType type;
  std::vector<double> params;
};
std::vector<ForwardModel> ForwardModels() {
  return {
      {CameraModelType::kSimplePinhole, {6000.0, 3000.0, 2000.0}},
      {CameraModelType::kPinhole, {6000.0, 6030.0, 3010.0, 1990.0}},
      {CameraModelType::kSimpleRadial, {6000.0, 3000.0, 2000.0, -0.08}},
      {CameraModelType::kRadial, {6000.0, 3000.0, 2000.0, -0.08, 0.03}},
      {CameraModelType::kOpenCv, {6000.0, 6010.0, 3005.0, 1995.0, -0.06, 0.02, 3e-4, -2e-4}},
      {CameraModelType::kFullOpenCv,
       {6000.0, 6010.0, 3005.0, 1995.0, -0.06, 0.02, 3e-4, -2e-4, 0.01, 0.02, -0.01, 0.005}},
      {CameraModelType::kOpenCvFisheye, {6000.0, 6000.0, 3000.0, 2000.0, 0.05, -0.02, 0.01, 0.0}},
  };
}

SyntheticBlockOptions ForwardModelBlock(const ForwardModel& model) {
  SyntheticBlockOptions o = TaylorBlockOptions();
  o.camera_model = model.type;
  o.camera_params = model.params;
  return o;
}

// A forward model's rows (the lecture's rows of (a, b) chained through the model's derivative)
// against central differences of its whitened residual, for every unknown of a small block: a sign
// or a transposed 2 x 2 would show at once.
TEST(TaylorBundlePartials, ForwardModelRowsMatchCentralDifferences) {
  for (const ForwardModel& model : ForwardModels()) {
    SCOPED_TRACE(EnumName(model.type));
    const SyntheticBlockOptions o = SixImages(ForwardModelBlock(model), 30);
    const TestBlock data = MakeTestBlock(o);
    TaylorBundleLinearSystem system;
    ASSERT_TRUE(
        LinearizeTaylorBundle(TaylorOptions(), BundleAdjustmentConfig(), data.block, &system).ok());
    const auto residual_at = [&](const Block& block) {
      TaylorBundleLinearSystem moved;
      EXPECT_TRUE(
          LinearizeTaylorBundle(TaylorOptions(), BundleAdjustmentConfig(), block, &moved).ok());
      return moved.residual;
    };
    double worst = 0.0;
    const auto check_column = [&](int column, const Eigen::VectorXd& plus,
                                  const Eigen::VectorXd& minus, double h) {
      const Eigen::VectorXd numeric = (plus - minus) / (2.0 * h);
      const double scale = std::max(numeric.cwiseAbs().maxCoeff(), 1e-300);
      worst =
          std::max(worst, (numeric - system.jacobian.col(column)).cwiseAbs().maxCoeff() / scale);
    };
    for (size_t i = 0; i < data.block.images.size(); ++i) {
      if (system.image_columns[i] < 0) continue;
      for (int k = 0; k < 6; ++k) {
        const double h = k < 3 ? 1e-3 : 1e-6;  // m, rad
        Block plus = data.block, minus = data.block;
        plus.images[i].eo->parameters[k] += h;
        minus.images[i].eo->parameters[k] -= h;
        check_column(system.image_columns[i] + k, residual_at(plus), residual_at(minus), h);
      }
    }
    for (size_t p = 0; p < data.block.points.size(); p += 7) {
      if (system.point_columns[p] < 0 || !data.block.points[p].position_m) continue;
      for (int k = 0; k < 3; ++k) {
        Block plus = data.block, minus = data.block;
        (*plus.points[p].position_m)[k] += 1e-3;
        (*minus.points[p].position_m)[k] -= 1e-3;
        check_column(system.point_columns[p] + k, residual_at(plus), residual_at(minus), 1e-3);
      }
    }
    std::printf("  %-15s largest relative difference of a column %.2e\n",
                std::string(EnumName(model.type)).c_str(), worst);
    EXPECT_LT(worst, kPartialRelativeTolerance);
  }
}

// ------------------------------------------------------------------ the same minimum as Ceres

struct Agreement {
  double centre_m = 0.0;   // largest camera-centre difference (m)
  double angle_rad = 0.0;  // largest rotation difference (rad)
  double point_m = 0.0;    // largest tie/control point difference (m)
  double check_m = 0.0;    // largest check-point error difference (m)
  double sigma0_relative = 0.0;
  double covariance_relative = 0.0;  // largest relative difference of a covariance diagonal entry
  int taylor_iterations = 0, ceres_iterations = 0;
  double taylor_seconds = 0.0, ceres_seconds = 0.0;
};

// Adjusts copies of the block with Ceres and with the Taylor solver; both must converge.
Agreement CompareWithCeres(const TestBlock& data, const BundleAdjustmentOptions& ceres_options,
                           const TaylorBundleOptions& taylor_options,
                           const BundleAdjustmentConfig& config = BundleAdjustmentConfig()) {
  Agreement agreement;
  Block ceres_block = data.block, taylor_block = data.block;
  BundleAdjustmentResult ceres;
  TaylorBundleResult taylor;
  const Status ceres_status = BundleAdjust(ceres_options, config, &ceres_block, &ceres);
  const Status taylor_status = TaylorBundleAdjust(taylor_options, config, &taylor_block, &taylor);
  EXPECT_TRUE(ceres_status.ok()) << ceres_status.message();
  EXPECT_TRUE(taylor_status.ok()) << taylor_status.message();
  EXPECT_TRUE(ceres.summary.IsSolutionUsable()) << ceres.summary.BriefReport();
  EXPECT_TRUE(taylor.summary.IsSolutionUsable()) << taylor.summary.BriefReport();
  if (!ceres.summary.IsSolutionUsable() || !taylor.summary.IsSolutionUsable()) return agreement;
  EXPECT_EQ(taylor.summary.redundancy, ceres.summary.redundancy);
  EXPECT_EQ(taylor.summary.num_marks, ceres.summary.num_marks);
  EXPECT_EQ(taylor.summary.num_points, ceres.summary.num_points);
  EXPECT_EQ(taylor.summary.datum, ceres.summary.datum);
  EXPECT_EQ(taylor.adjustment.summary.termination, SolverTermination::kConverged);
  EXPECT_EQ(taylor.adjustment.num_check_points, ceres.num_check_points);
  for (size_t i = 0; i < data.block.images.size(); ++i) {
    const ExteriorOrientation& a = *ceres_block.images[i].eo;
    const ExteriorOrientation& b = *taylor_block.images[i].eo;
    agreement.centre_m =
        std::max(agreement.centre_m, (a.center_in_ground() - b.center_in_ground()).norm());
    agreement.angle_rad = std::max(agreement.angle_rad, RotationDifferenceRad(a, b));
    EXPECT_EQ(taylor.adjustment.images[i].num_marks, ceres.images[i].num_marks);
    EXPECT_EQ(taylor.adjustment.images[i].has_covariance, ceres.images[i].has_covariance);
    if (!ceres.images[i].has_covariance) continue;
    const Vector6d c = ceres.images[i].covariance.diagonal();
    const Vector6d t = taylor.adjustment.images[i].covariance.diagonal();
    for (int k = 0; k < 6; ++k)
      if (c[k] > 0.0)
        agreement.covariance_relative =
            std::max(agreement.covariance_relative, std::abs(t[k] - c[k]) / c[k]);
  }
  for (size_t p = 0; p < data.block.points.size(); ++p) {
    if (ceres_block.points[p].position_m && taylor_block.points[p].position_m)
      agreement.point_m =
          std::max(agreement.point_m,
                   (*ceres_block.points[p].position_m - *taylor_block.points[p].position_m).norm());
    const auto& ce = ceres.points[p].error_m;
    const auto& te = taylor.adjustment.points[p].error_m;
    EXPECT_EQ(ce.has_value(), te.has_value());
    if (ce && te && data.block.points[p].role == PointRole::kCheck)
      agreement.check_m = std::max(agreement.check_m, (*ce - *te).norm());
  }
  const double s_c = ceres.summary.sigma0, s_t = taylor.summary.sigma0;
  agreement.sigma0_relative = std::abs(s_t - s_c) / std::max(s_c, 1e-300);
  agreement.taylor_iterations = taylor.summary.iterations;
  agreement.ceres_iterations = ceres.summary.iterations;
  agreement.taylor_seconds = taylor.summary.time_seconds;
  agreement.ceres_seconds = ceres.summary.time_seconds;
  return agreement;
}

struct Scenario {
  const char* name;
  SyntheticBlockOptions block;
  bool attitudes = false;  // attitude priors (0.01 deg) on every image
  bool lever_arm = false;  // a GNSS lever arm
  bool noise_free = false;
};

std::vector<Scenario> AgreementScenarios() {
  std::vector<Scenario> scenarios;
  scenarios.push_back({"nadir, noise-free", TaylorBlockOptions(), false, false, true});
  for (unsigned seed = 1; seed <= 3; ++seed) {
    Scenario s{"nadir, 0.5 px", TaylorBlockOptions()};
    s.block.seed = seed;
    scenarios.push_back(s);
  }
  {
    Scenario s{"oblique 35 deg, 0.5 px", ObliqueOptions(35.0)};
    scenarios.push_back(s);
  }
  {
    Scenario s{"map coordinates (UTM-like offset)", TaylorBlockOptions()};
    s.block.origin_m = Eigen::Vector2d(512345.0, 4123456.0);
    s.block.ground_height_m = 250.0;
    scenarios.push_back(s);
  }
  {
    Scenario s{"attitude priors and lever arm", TaylorBlockOptions(), true, true};
    scenarios.push_back(s);
  }
  {
    Scenario s{"control points only", TaylorBlockOptions()};
    s.block.gnss = false;
    s.block.control_layout = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}};
    s.block.check_layout = {{0.25, 0.25}, {0.75, 0.75}};
    scenarios.push_back(s);
  }
  {
    Scenario s{"relative (COLMAP gauge)", TaylorBlockOptions()};
    s.block.gnss = false;
    s.block.num_control_points = 0;
    s.block.check_layout.clear();
    s.block.num_check_points = 0;
    scenarios.push_back(s);
  }
  {
    Scenario s{"few tie points (16)", TaylorBlockOptions()};
    s.block.num_tie_points = 16;
    scenarios.push_back(s);
  }
  {
    Scenario s{"larger block 5 x 8, 1 px", TaylorBlockOptions()};
    s.block.num_lines = 5;
    s.block.images_per_line = 8;
    s.block.num_tie_points = 900;
    s.block.mark_sigma_px = 1.0;
    s.block.mark_accuracy_px = 1.0;
    scenarios.push_back(s);
  }
  // The COLMAP forward models: marks in pixels, the residual after the model's distortion.
  for (const ForwardModel& model : ForwardModels()) {
    Scenario s{EnumName(model.type), ForwardModelBlock(model)};
    scenarios.push_back(s);
  }
  {
    Scenario s{"OPENCV, relative (free gauge)", ForwardModelBlock(ForwardModels()[4])};
    s.block.gnss = false;
    s.block.num_control_points = 0;
    s.block.check_layout.clear();
    s.block.num_check_points = 0;
    scenarios.push_back(s);
  }
  {
    Scenario s{"OPENCV_FISHEYE, control only", ForwardModelBlock(ForwardModels()[6])};
    s.block.gnss = false;
    s.block.control_layout = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}};
    s.block.check_layout = {{0.25, 0.25}, {0.75, 0.75}};
    scenarios.push_back(s);
  }
  return scenarios;
}

TEST(TaylorBundleVsCeres, SameMinimumOnSimulatedBlocks) {
  std::printf("  %-34s %10s %10s %10s %10s %9s %9s %6s\n", "block", "centre/size", "angle rad",
              "points m", "check m", "sigma0 rel", "cov rel", "iter T/C");
  for (const Scenario& scenario : AgreementScenarios()) {
    SCOPED_TRACE(scenario.name);
    TestBlock data =
        MakeTestBlock(scenario.noise_free ? NoiseFree(scenario.block) : scenario.block);
    BundleAdjustmentOptions ceres = CeresOptions();
    TaylorBundleOptions taylor = TaylorOptions();
    BundleAdjustmentConfig config;
    if (scenario.attitudes) {
      std::mt19937_64 rng(7);
      std::normal_distribution<double> gauss(0.0, 1.0);
      const double sigma = 0.01 / kDegreesPerRadian;
      for (size_t i = 0; i < data.block.images.size(); ++i) {
        data.block.images[i].measured_angles_rad =
            data.truth.eo[i].angles_seed_rad() +
            sigma * DrawLastFirst<3>([&](int) { return gauss(rng); });
        data.block.images[i].attitude_accuracy_rad = Eigen::Vector3d::Constant(sigma);
      }
    }
    if (scenario.lever_arm) {
      // The GNSS antenna 0.3 m above the projection centre and a little aside; the measured
      // positions are of the antenna.
      const Eigen::Vector3d lever(0.05, -0.1, 0.3);
      for (size_t i = 0; i < data.block.images.size(); ++i) {
        Eigen::Matrix3d unused;
        const Eigen::Vector3d offset = TaylorAntennaPosition(data.truth.eo[i], lever, &unused) -
                                       data.truth.eo[i].center_in_ground();
        *data.block.images[i].measured_center_m += offset;
      }
      config.lever_arm_m = lever;
    }
    const Agreement a = CompareWithCeres(data, ceres, taylor, config);
    std::printf("  %-34s %10.2e %10.2e %10.2e %10.2e %9.2e %9.2e %3d/%d\n", scenario.name,
                a.centre_m / data.size_m, a.angle_rad, a.point_m, a.check_m, a.sigma0_relative,
                a.covariance_relative, a.taylor_iterations, a.ceres_iterations);
    EXPECT_LT(a.centre_m, kRelativeAgreement * data.size_m);
    EXPECT_LT(a.point_m, kRelativeAgreement * data.size_m);
    EXPECT_LT(a.check_m, kRelativeAgreement * data.size_m);
    EXPECT_LT(a.angle_rad, kRelativeAgreement);
    if (!scenario.noise_free) {
      EXPECT_LT(a.sigma0_relative, kSigma0RelativeAgreement);
      EXPECT_LT(a.covariance_relative, kCovarianceRelativeAgreement);
    }
  }
}

// The lecture's method, undamped: Gauss-Newton's quadratic convergence.
TEST(TaylorBundle, NoiseFreeBlockReachesTheTruth) {
  TestBlock data = MakeTestBlock(NoiseFree(TaylorBlockOptions()));
  TaylorBundleResult result;
  TaylorBundleOptions options = TaylorOptions();
  options.damping = TaylorDamping::kNone;
  ASSERT_TRUE(TaylorBundleAdjust(options, BundleAdjustmentConfig(), &data.block, &result).ok());
  ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  for (size_t i = 0; i < data.truth.eo.size(); ++i) {
    EXPECT_LT(
        (data.block.images[i].eo->center_in_ground() - data.truth.eo[i].center_in_ground()).norm(),
        1e-6);
    EXPECT_LT(RotationDifferenceRad(*data.block.images[i].eo, data.truth.eo[i]), 1e-9);
  }
  EXPECT_LT(result.adjustment.check_rmse_total_m, 1e-6);
  // Quadratic convergence: from 2 m / 1 deg off, each correction at most about the square of the
  // previous one (in metres, times a modest constant), and few of them.
  EXPECT_LE(result.summary.iterations, 6);
  for (size_t k = 1; k < result.history.size(); ++k) {
    const double previous = result.history[k - 1].max_position_correction_m;
    EXPECT_LT(result.history[k].max_position_correction_m, std::max(1e-6, previous * previous));
  }
}

TEST(TaylorBundle, TiePointsWithoutStartAreLeftOutAndNamed) {
  // As in BundleAdjust: a tie point without initial coordinates leaves with its marks and is
  // named in the summary, instead of refusing the block.
  TestBlock data = MakeTestBlock(TaylorBlockOptions());
  std::vector<int> rays(data.block.points.size(), 0);
  for (const BlockMark& mark : data.block.marks) ++rays[mark.point];
  std::vector<std::string> removed;
  for (size_t p = 0; p < data.block.points.size(); ++p) {
    BlockPoint& point = data.block.points[p];
    if (point.role != PointRole::kTie || rays[p] < 3 || removed.size() == 3) continue;
    point.position_m.reset();
    removed.push_back(point.id);
  }
  ASSERT_EQ(removed.size(), 3u);
  TaylorBundleResult result;
  ASSERT_TRUE(
      TaylorBundleAdjust(TaylorOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
  ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  EXPECT_EQ(result.summary.tie_points_left_out, removed);
  EXPECT_EQ(result.adjustment.summary.tie_points_left_out, removed);
}

// Independent of Ceres: the covariance the Taylor solver reports is honest, the mean NEES of the
// adjusted camera centres against the truth in its chi-square band. The 12 centres of a block
// share its datum errors, so a block's mean NEES scatters widely (10 blocks, as with the former
// fixture, gave 4.17, 3.28, 3.31 and 2.62 for four sets of seeds): 100 blocks (0.3 s) give means
// of 3.14, 3.00, 2.84 and 3.25 for seeds 101, 1001, 2001 and 3001 on, a standard deviation of
// about 0.18, so the band +- 0.6 is over 3 of them.
TEST(TaylorBundle, CameraPositionCovarianceIsHonest) {
  constexpr int kNeesBlocks = 100;
  constexpr double kNeesBand = 0.6;
  double sum = 0.0;
  int count = 0;
  for (unsigned seed = 1; seed <= kNeesBlocks; ++seed) {
    SyntheticBlockOptions o = TaylorBlockOptions();
    o.seed = 100 + seed;
    TestBlock data = MakeTestBlock(o);
    TaylorBundleResult result;
    ASSERT_TRUE(
        TaylorBundleAdjust(TaylorOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
    ASSERT_TRUE(result.summary.IsSolutionUsable());
    for (size_t i = 0; i < data.truth.eo.size(); ++i) {
      ASSERT_TRUE(result.adjustment.images[i].has_covariance);
      const Eigen::Vector3d e =
          data.block.images[i].eo->center_in_ground() - data.truth.eo[i].center_in_ground();
      const Eigen::Matrix3d C = result.adjustment.images[i].covariance.topLeftCorner<3, 3>();
      sum += e.dot(C.ldlt().solve(e));
      ++count;
    }
  }
  std::printf("  mean NEES of the camera centres: %.3f (chi-square 3 dof: 3)\n", sum / count);
  EXPECT_NEAR(sum / count, 3.0, kNeesBand);
}

// Rejection rounds: after a round, per point its worst tie mark whose normalized residual exceeds
// 4.5 leaves (BundleAdjust's rule, internal/bundle_rounds.h) and the block is adjusted again.
// Checked against Ceres with the same rejection rounds: the same marks rejected in the same
// rounds, and the final adjustment equals Ceres' on the block without the rejected marks.
TEST(TaylorBundle, RejectionRoundsMatchCeresOnTheCleanedBlock) {
  TestBlock data = MakeTestBlock(TaylorBlockOptions());
  // A 25 px blunder on one tie mark of a point seen in several images.
  int blunder = -1;
  for (size_t m = 0; m < data.block.marks.size() && blunder < 0; ++m) {
    const BlockMark& mark = data.block.marks[m];
    if (data.block.points[mark.point].role == PointRole::kTie &&
        data.block.marks_of_point[mark.point].size() >= 4)
      blunder = static_cast<int>(m);
  }
  ASSERT_GE(blunder, 0);
  BlockMark& mark = data.block.marks[blunder];
  mark.measured += Eigen::Vector2d(25.0, -10.0);
  ASSERT_TRUE(FilmFromPixel(data.block.cameras[0].table, mark.measured, PixelOrigin::kCorner,
                            &mark.observation)
                  .ok());
  BundleAdjustmentOptions with_rejection = CeresOptions();
  with_rejection.robustness.rejection_threshold = 4.5;
  TaylorBundleOptions taylor_options;
  ASSERT_TRUE(TaylorBundleOptionsFromBundleOptions(with_rejection, TaylorPartials::kCorrected,
                                                   &taylor_options)
                  .ok());
  ASSERT_EQ(taylor_options.rejection_threshold, 4.5);
  Block taylor_block = data.block;
  TaylorBundleResult taylor;
  ASSERT_TRUE(
      TaylorBundleAdjust(taylor_options, BundleAdjustmentConfig(), &taylor_block, &taylor).ok());
  ASSERT_TRUE(taylor.summary.IsSolutionUsable()) << taylor.summary.BriefReport();
  std::printf("  %s\n", taylor.summary.BriefReport().c_str());

  // Ceres with the same rejection rounds: the same marks, round by round.
  Block ceres_block = data.block;
  BundleAdjustmentResult ceres;
  ASSERT_TRUE(BundleAdjust(with_rejection, BundleAdjustmentConfig(), &ceres_block, &ceres).ok());
  ASSERT_TRUE(ceres.summary.IsSolutionUsable()) << ceres.summary.BriefReport();
  std::vector<int> expected, first_round;
  ASSERT_EQ(ceres.rejected_marks.size(), taylor.adjustment.rejected_marks.size());
  for (size_t k = 0; k < ceres.rejected_marks.size(); ++k) {
    EXPECT_EQ(ceres.rejected_marks[k].mark, taylor.adjustment.rejected_marks[k].mark);
    EXPECT_EQ(ceres.rejected_marks[k].round, taylor.adjustment.rejected_marks[k].round);
    if (ceres.rejected_marks[k].round == 1) expected.push_back(ceres.rejected_marks[k].mark);
  }
  EXPECT_EQ(ceres.summary.rounds, taylor.summary.rounds);
  std::sort(expected.begin(), expected.end());
  for (const BundleRejectedMark& rejected : taylor.adjustment.rejected_marks) {
    if (rejected.round == 1) first_round.push_back(rejected.mark);
    const BlockMark& m = data.block.marks[rejected.mark];
    std::printf("  rejected after round %d: point %s in %s, %.1f sigma0%s\n", rejected.round,
                data.block.points[m.point].id.c_str(), data.block.images[m.image].name.c_str(),
                rejected.whitened_residual, rejected.mark == blunder ? " (the blunder)" : "");
  }
  std::sort(first_round.begin(), first_round.end());
  EXPECT_EQ(first_round, expected);
  EXPECT_NE(std::find(first_round.begin(), first_round.end(), blunder), first_round.end());
  EXPECT_EQ(taylor.summary.num_rejected_marks,
            static_cast<int>(taylor.adjustment.rejected_marks.size()));
  EXPECT_TRUE(std::isnan(taylor.adjustment.mark_residuals[blunder][0]));

  // Ceres on the block without every rejected mark: the same minimum.
  Block cleaned = data.block;
  std::vector<char> rejected(cleaned.marks.size(), 0);
  for (const BundleRejectedMark& r : taylor.adjustment.rejected_marks) rejected[r.mark] = 1;
  std::vector<BlockMark> kept;
  for (size_t m = 0; m < cleaned.marks.size(); ++m)
    if (!rejected[m]) kept.push_back(cleaned.marks[m]);
  cleaned.marks = kept;
  cleaned.BuildIndex();
  BundleAdjustmentResult reference;
  ASSERT_TRUE(BundleAdjust(CeresOptions(), BundleAdjustmentConfig(), &cleaned, &reference).ok());
  ASSERT_TRUE(reference.summary.IsSolutionUsable());
  EXPECT_EQ(reference.summary.redundancy, taylor.summary.redundancy);
  EXPECT_NEAR(reference.summary.sigma0, taylor.summary.sigma0,
              kSigma0RelativeAgreement * reference.summary.sigma0);
  for (size_t i = 0; i < data.block.images.size(); ++i)
    EXPECT_LT(
        (cleaned.images[i].eo->center_in_ground() - taylor_block.images[i].eo->center_in_ground())
            .norm(),
        kRelativeAgreement * data.size_m);
}

// ------------------------------------------------------------------ honest failures

// Nothing of a failed adjustment reaches the block: same orientations, no image marked adjusted.
void ExpectUntouched(const Block& before, const Block& after, const TaylorBundleResult& result) {
  for (size_t i = 0; i < before.images.size(); ++i)
    EXPECT_EQ(before.images[i].eo->parameters, after.images[i].eo->parameters);
  for (size_t p = 0; p < before.points.size(); ++p)
    EXPECT_EQ(before.points[p].position_m.has_value(), after.points[p].position_m.has_value());
  EXPECT_TRUE(result.adjustment.images.empty());
  EXPECT_FALSE(result.summary.IsSolutionUsable());
  EXPECT_FALSE(result.adjustment.summary.IsSolutionUsable());
  EXPECT_FALSE(result.summary.message.empty());
}

TEST(TaylorBundle, FailsCleanly) {
  const TestBlock data = MakeTestBlock(TaylorBlockOptions());
  {
    SCOPED_TRACE("an image starts below the ground: its points are behind it");
    Block block = data.block;
    block.images[5].eo->parameters[2] = -50.0;
    const Block before = block;
    TaylorBundleResult result;
    ASSERT_TRUE(
        TaylorBundleAdjust(TaylorOptions(), BundleAdjustmentConfig(), &block, &result).ok());
    EXPECT_EQ(result.summary.termination_type, SolverTermination::kFailure);
    EXPECT_NE(result.summary.message.find("not in front of the camera"), std::string::npos)
        << result.summary.message;
    ExpectUntouched(before, block, result);
  }
  {
    SCOPED_TRACE("one correction allowed: no convergence, no pose");
    Block block = data.block;
    TaylorBundleOptions options = TaylorOptions();
    options.max_iterations = 1;
    TaylorBundleResult result;
    ASSERT_TRUE(TaylorBundleAdjust(options, BundleAdjustmentConfig(), &block, &result).ok());
    EXPECT_EQ(result.summary.termination_type, SolverTermination::kNoConvergence);
    EXPECT_EQ(result.adjustment.summary.termination, SolverTermination::kNoConvergence);
    ExpectUntouched(data.block, block, result);
  }
  {
    SCOPED_TRACE("two control points and no GNSS: the rotation about their line is free");
    SyntheticBlockOptions o = TaylorBlockOptions();
    o.gnss = false;
    o.control_layout = {{0, 0}, {1, 1}};
    TestBlock two = MakeTestBlock(o);
    Block block = two.block;
    TaylorBundleResult result;
    ASSERT_TRUE(
        TaylorBundleAdjust(TaylorOptions(), BundleAdjustmentConfig(), &block, &result).ok());
    EXPECT_EQ(result.summary.termination_type, SolverTermination::kFailure);
    EXPECT_NE(result.summary.message.find("singular"), std::string::npos) << result.summary.message;
    ExpectUntouched(two.block, block, result);
  }
  {
    SCOPED_TRACE("far too poor a start: failure or no convergence, never a pose");
    Block block = data.block;
    for (BlockImage& image : block.images) image.eo->parameters[5] += 2.5;  // kappa 143 deg off
    TaylorBundleResult result;
    ASSERT_TRUE(
        TaylorBundleAdjust(TaylorOptions(), BundleAdjustmentConfig(), &block, &result).ok());
    std::printf("  kappa 143 deg off: %s\n", result.summary.BriefReport().c_str());
    if (!result.summary.IsSolutionUsable()) {
      Block before = data.block;
      for (BlockImage& image : before.images) image.eo->parameters[5] += 2.5;
      ExpectUntouched(before, block, result);
    } else {
      // If it converged it must be the truth (kappa is a full turn away from nothing).
      for (size_t i = 0; i < block.images.size(); ++i)
        EXPECT_LT(RotationDifferenceRad(*block.images[i].eo, data.truth.eo[i]), 1e-3);
    }
  }
}

// A progress hook that returns false stops the Taylor bundle as it stops BundleAdjust: after that
// correction, termination kCancelled (not a failure), the hook not called again, the block as
// given. For an absolute block (stopped after its second correction) and a relative one (stopped
// in its free-gauge solve, which must not go on in the gauge).
TEST(TaylorBundle, AProgressHookReturningFalseCancelsTheAdjustment) {
  SyntheticBlockOptions relative = TaylorBlockOptions();
  relative.gnss = false;
  relative.num_control_points = 0;
  relative.check_layout.clear();
  relative.num_check_points = 0;
  for (const SyntheticBlockOptions& o : {TaylorBlockOptions(), relative}) {
    const bool is_relative = o.num_control_points == 0;
    SCOPED_TRACE(is_relative ? "relative block" : "absolute block");
    const TestBlock data = MakeTestBlock(o);
    Block block = data.block;
    const int stop_after = is_relative ? 1 : 2;
    std::vector<BundleIterationInfo> calls;
    TaylorBundleOptions options = TaylorOptions();
    options.progress = [&](const BundleIterationInfo& info) {
      calls.push_back(info);
      return static_cast<int>(calls.size()) < stop_after;
    };
    TaylorBundleResult result;
    ASSERT_TRUE(TaylorBundleAdjust(options, BundleAdjustmentConfig(), &block, &result).ok());
    EXPECT_EQ(result.summary.termination_type, SolverTermination::kCancelled)
        << result.summary.message;
    EXPECT_EQ(result.adjustment.summary.termination, SolverTermination::kCancelled);
    EXPECT_NE(result.summary.message.find("round 1: cancelled by the progress hook after "
                                          "iteration " + std::to_string(stop_after)),
              std::string::npos)
        << result.summary.message;
    ASSERT_EQ(static_cast<int>(calls.size()), stop_after);
    EXPECT_EQ(calls.back().free_gauge, is_relative);
    // A cancellation in the free gauge says so; the cancelled round's time is kept either way.
    EXPECT_EQ(result.summary.message.find(" (free gauge)") != std::string::npos, is_relative)
        << result.summary.message;
    EXPECT_EQ(result.summary.round_seconds.size(), 1u);
    EXPECT_EQ(result.summary.rounds, 1);
    ExpectUntouched(data.block, block, result);
  }
}

// A relative block solved first without a gauge (as BundleAdjust does) reaches the minimum of
// COLMAP's gauge: the first image exactly at its given pose, the scale image's coordinate as given,
// the cost and every pose of the held-gauge solve, in fewer iterations. Here the first image's
// start is turned by 1 degree more, so that the held gauge has to turn the whole block about it.
TEST(TaylorBundle, FreeGaugeReachesTheHeldGaugeMinimum) {
  SyntheticBlockOptions o = ForwardModelBlock(ForwardModels()[0]);
  o.gnss = false;
  o.num_control_points = 0;
  o.check_layout.clear();
  o.num_check_points = 0;
  o.num_lines = 4;
  o.images_per_line = 6;
  o.num_tie_points = 400;
  TestBlock data = MakeTestBlock(o);
  data.block.images[0].eo->parameters[5] += 1.0 / kDegreesPerRadian;
  const Vector6d first_start = data.block.images[0].eo->parameters;
  TaylorBundleOptions free_options = TaylorOptions();
  TaylorBundleOptions held_options = TaylorOptions();
  held_options.free_gauge_for_relative_blocks = false;
  Block free_block = data.block, held_block = data.block;
  TaylorBundleResult free_result, held_result;
  ASSERT_TRUE(
      TaylorBundleAdjust(free_options, BundleAdjustmentConfig(), &free_block, &free_result).ok());
  ASSERT_TRUE(
      TaylorBundleAdjust(held_options, BundleAdjustmentConfig(), &held_block, &held_result).ok());
  ASSERT_TRUE(free_result.summary.IsSolutionUsable()) << free_result.summary.BriefReport();
  ASSERT_TRUE(held_result.summary.IsSolutionUsable()) << held_result.summary.BriefReport();
  std::printf("  free gauge: %d iterations (%d without a gauge); held: %d\n",
              free_result.summary.iterations, free_result.summary.free_gauge_iterations,
              held_result.summary.iterations);
  EXPECT_GT(free_result.summary.free_gauge_iterations, 0);
  EXPECT_EQ(held_result.summary.free_gauge_iterations, 0);
  EXPECT_LT(free_result.summary.iterations, held_result.summary.iterations);
  EXPECT_NEAR(free_result.summary.final_cost, held_result.summary.final_cost,
              1e-9 * held_result.summary.final_cost);
  EXPECT_EQ(free_block.images[0].eo->parameters, first_start);
  double centre_m = 0.0, angle_rad = 0.0;
  for (size_t i = 0; i < free_block.images.size(); ++i) {
    centre_m = std::max(centre_m, (free_block.images[i].eo->center_in_ground() -
                                   held_block.images[i].eo->center_in_ground())
                                      .norm());
    angle_rad = std::max(angle_rad,
                         RotationDifferenceRad(*free_block.images[i].eo, *held_block.images[i].eo));
  }
  EXPECT_LT(centre_m, kRelativeAgreement * data.size_m);
  EXPECT_LT(angle_rad, kRelativeAgreement);
}

TEST(TaylorBundle, RefusesWhatItDoesNotDo) {
  const TestBlock data = MakeTestBlock(TaylorBlockOptions());
  {
    Block block = data.block;
    block.cameras[0].model = CameraModelType::kSimpleRadial;
    block.cameras[0].params = {0.0, 3000.0, 2000.0, 0.0};
    TaylorBundleResult result;
    const Status status =
        TaylorBundleAdjust(TaylorOptions(), BundleAdjustmentConfig(), &block, &result);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("no positive focal length"), std::string::npos)
        << status.message();
  }
  {
    Block block = data.block;
    block.images[2].eo.reset();
    TaylorBundleResult result;
    EXPECT_FALSE(
        TaylorBundleAdjust(TaylorOptions(), BundleAdjustmentConfig(), &block, &result).ok());
  }
  {
    TaylorBundleOptions options = TaylorOptions();
    options.position_tolerance_m = 0.0;
    std::string why;
    EXPECT_FALSE(options.IsValid(&why));
    options = TaylorOptions();
    options.accuracies.tie_px = -1.0;
    EXPECT_FALSE(options.IsValid(&why));
    Block block = data.block;
    TaylorBundleResult result;
    EXPECT_FALSE(TaylorBundleAdjust(options, BundleAdjustmentConfig(), &block, &result).ok());
  }
  {
    // A robust tie loss is taken over (iteratively reweighted); one BundleAdjust does not offer
    // on tie marks is refused as there.
    BundleAdjustmentOptions ceres;
    ceres.robustness.tie_loss = LossType::kHuber;
    TaylorBundleOptions options;
    ASSERT_TRUE(
        TaylorBundleOptionsFromBundleOptions(ceres, TaylorPartials::kCorrected, &options).ok());
    EXPECT_EQ(options.tie_loss, LossType::kHuber);
    std::string loss_why;
    options.tie_loss = LossType::kTukey;
    EXPECT_FALSE(options.IsValid(&loss_why));
    EXPECT_NE(loss_why.find("tie loss"), std::string::npos) << loss_why;
    ceres = BundleAdjustmentOptions();
    ceres.accuracies.camera_m = Eigen::Vector3d(1.0, 2.0, 3.0);
    ASSERT_TRUE(
        TaylorBundleOptionsFromBundleOptions(ceres, TaylorPartials::kAsPrinted, &options).ok());
    EXPECT_EQ(options.partials, TaylorPartials::kAsPrinted);
    EXPECT_EQ(options.accuracies.camera_m, ceres.accuracies.camera_m);
  }
}

// ------------------------------------------------------------------ what the printed eq. 21 costs

// One block adjusted with the corrected and with the as-printed partials from the same start.
struct VariantPair {
  Block corrected, printed;
  TaylorBundleResult corrected_result, printed_result;
};

VariantPair AdjustBothVariants(const TestBlock& data) {
  VariantPair pair;
  pair.corrected = pair.printed = data.block;
  EXPECT_TRUE(TaylorBundleAdjust(TaylorOptions(TaylorPartials::kCorrected),
                                 BundleAdjustmentConfig(), &pair.corrected, &pair.corrected_result)
                  .ok());
  TaylorBundleOptions printed = TaylorOptions(TaylorPartials::kAsPrinted);
  printed.max_iterations = 200;  // linear convergence: let it finish where it can
  EXPECT_TRUE(
      TaylorBundleAdjust(printed, BundleAdjustmentConfig(), &pair.printed, &pair.printed_result)
          .ok());
  return pair;
}

// Over realisations of one block design: how far the printed partials move the camera centres and
// the check points from the least-squares solution, against that solution's own error.
struct PrintedOffset {
  int realisations = 0, printed_usable = 0;
  double centre_shift_rms_m = 0.0, centre_shift_max_m = 0.0;    // |printed - corrected|
  double centre_error_rms_m = 0.0;                              // |corrected - truth|
  double check_shift_rms_m = 0.0;                               // |printed - corrected| check error
  double check_error_rms_m = 0.0;                               // corrected check error
  double iterations_corrected = 0.0, iterations_printed = 0.0;  // means
  int iterations_printed_max = 0;
  double sigma0_corrected = 0.0, sigma0_printed = 0.0;  // means
  std::vector<double> per_image_shift_rms_m;
};

PrintedOffset MeasurePrintedOffset(SyntheticBlockOptions o, int realisations) {
  PrintedOffset out;
  double centre_ssq = 0.0, error_ssq = 0.0, check_ssq = 0.0, check_error_ssq = 0.0;
  int centre_count = 0, check_count = 0;
  for (int r = 0; r < realisations; ++r) {
    o.seed = 1000 + r;
    const TestBlock data = MakeTestBlock(o);
    const VariantPair pair = AdjustBothVariants(data);
    EXPECT_TRUE(pair.corrected_result.summary.IsSolutionUsable())
        << pair.corrected_result.summary.BriefReport();
    ++out.realisations;
    out.iterations_corrected += pair.corrected_result.summary.iterations;
    out.sigma0_corrected += pair.corrected_result.summary.sigma0;
    if (!pair.printed_result.summary.IsSolutionUsable()) continue;
    ++out.printed_usable;
    out.iterations_printed += pair.printed_result.summary.iterations;
    out.iterations_printed_max =
        std::max(out.iterations_printed_max, pair.printed_result.summary.iterations);
    out.sigma0_printed += pair.printed_result.summary.sigma0;
    // The corrected solution is the least-squares minimum: the printed fixed point cannot be lower.
    EXPECT_GE(pair.printed_result.summary.final_cost,
              pair.corrected_result.summary.final_cost * (1.0 - 1e-12));
    out.per_image_shift_rms_m.resize(data.block.images.size(), 0.0);
    for (size_t i = 0; i < data.block.images.size(); ++i) {
      const Eigen::Vector3d c = pair.corrected.images[i].eo->center_in_ground();
      const double shift2 = (pair.printed.images[i].eo->center_in_ground() - c).squaredNorm();
      centre_ssq += shift2;
      out.per_image_shift_rms_m[i] += shift2;
      out.centre_shift_max_m = std::max(out.centre_shift_max_m, std::sqrt(shift2));
      error_ssq += (c - data.truth.eo[i].center_in_ground()).squaredNorm();
      ++centre_count;
    }
    for (size_t p = 0; p < data.block.points.size(); ++p) {
      const auto& ce = pair.corrected_result.adjustment.points[p].error_m;
      const auto& pe = pair.printed_result.adjustment.points[p].error_m;
      if (data.block.points[p].role != PointRole::kCheck || !ce || !pe) continue;
      check_ssq += (*pe - *ce).squaredNorm();
      check_error_ssq += ce->squaredNorm();
      ++check_count;
    }
  }
  const int n = std::max(1, out.printed_usable);
  for (double& v : out.per_image_shift_rms_m) v = std::sqrt(v / n);
  out.centre_shift_rms_m = std::sqrt(centre_ssq / std::max(1, centre_count));
  out.centre_error_rms_m = std::sqrt(error_ssq / std::max(1, centre_count));
  out.check_shift_rms_m = std::sqrt(check_ssq / std::max(1, check_count));
  out.check_error_rms_m = std::sqrt(check_error_ssq / std::max(1, check_count));
  out.iterations_corrected /= out.realisations;
  out.iterations_printed /= n;
  out.sigma0_corrected /= out.realisations;
  out.sigma0_printed /= n;
  return out;
}

void PrintOffset(const char* name, const PrintedOffset& m) {
  std::printf(
      "  %-28s printed usable %d/%d; centres moved RMS %.3f mm (max %.3f) vs their error "
      "%.2f mm; check points moved RMS %.3f mm vs their error %.2f mm; iterations %.1f "
      "corrected, %.1f printed (max %d); sigma0 %.5f -> %.5f\n",
      name, m.printed_usable, m.realisations, 1e3 * m.centre_shift_rms_m,
      1e3 * m.centre_shift_max_m, 1e3 * m.centre_error_rms_m, 1e3 * m.check_shift_rms_m,
      1e3 * m.check_error_rms_m, m.iterations_corrected, m.iterations_printed,
      m.iterations_printed_max, m.sigma0_corrected, m.sigma0_printed);
}

constexpr int kOffsetRealisations = 40;

TEST(TaylorBundleAsPrinted, OffsetOfNadirAndObliqueBlocks) {
  // Noise-free: the solution is a zero of F whatever the partials; only the iteration changes.
  {
    const SyntheticBlockOptions o = NoiseFree(ObliqueOptions(35.0));
    const TestBlock data = MakeTestBlock(o);
    const VariantPair pair = AdjustBothVariants(data);
    ASSERT_TRUE(pair.printed_result.summary.IsSolutionUsable());
    double shift = 0.0;
    for (size_t i = 0; i < data.block.images.size(); ++i)
      shift = std::max(shift, (pair.printed.images[i].eo->center_in_ground() -
                               pair.corrected.images[i].eo->center_in_ground())
                                  .norm());
    std::printf("  oblique 35 deg, noise-free: printed %d iterations vs %d, centres %.2e m apart\n",
                pair.printed_result.summary.iterations, pair.corrected_result.summary.iterations,
                shift);
    EXPECT_LT(shift, 1e-5);
    EXPECT_GT(pair.printed_result.summary.iterations, pair.corrected_result.summary.iterations);
  }
  SyntheticBlockOptions nadir = TaylorBlockOptions();  // omega, phi, kappa within +- 2 deg
  const PrintedOffset n = MeasurePrintedOffset(nadir, kOffsetRealisations);
  PrintOffset("nadir (+-2 deg), 0.5 px", n);
  const PrintedOffset b = MeasurePrintedOffset(ObliqueOptions(35.0), kOffsetRealisations);
  PrintOffset("oblique 35 deg, 0.5 px", b);
  const PrintedOffset s = MeasurePrintedOffset(ObliqueOptions(55.0), kOffsetRealisations);
  PrintOffset("oblique 55 deg, 0.5 px", s);
  // Nadir: harmless, the shift a small fraction of the error; oblique: a shift of the same order
  // as a good part of the error, and many more iterations.
  EXPECT_EQ(n.printed_usable, n.realisations);
  EXPECT_LT(n.centre_shift_rms_m, 0.1 * n.centre_error_rms_m);
  EXPECT_GT(b.centre_shift_rms_m, n.centre_shift_rms_m);
  EXPECT_GT(b.iterations_printed, b.iterations_corrected + 2.0);
  EXPECT_GT(b.sigma0_printed, b.sigma0_corrected);
}

// One image of a nadir block tilted 30 deg in omega (about the X axis, across the lines: it looks
// along its line), every other image exactly vertical (omega = 0: their eq. 21 is exact as
// printed). The printed partials are wrong for that
// one image only; how far does the damage reach through the tie points?
TEST(TaylorBundleAsPrinted, OneObliqueImagePropagatesThroughTiePoints) {
  SyntheticBlockOptions o = TaylorBlockOptions();
  o.num_lines = 3;
  o.images_per_line = 7;
  o.forward_spacing_m = 0.0;  // 60 % forward overlap (66.7 m footprint along the lines)
  o.forward_overlap = 0.6;
  o.side_spacing_m = 0.0;  // 30 % side overlap (100 m footprint across them)
  o.side_overlap = 0.3;
  o.num_tie_points = 676;
  o.attitude_jitter_deg = 0.0;
  const int tilted = 1 * o.images_per_line + 3;  // the middle of the middle line
  o.extra_angles_deg = {{tilted, Eigen::Vector3d(30.0, 0.0, 0.0)}};
  o.check_layout = {{0.5, 0.5}, {0.5, 1.0}, {0.33, 0.75}, {0.67, 0.75}, {0.25, 0.25}, {0.75, 0.25}};
  const PrintedOffset m = MeasurePrintedOffset(o, kOffsetRealisations);
  PrintOffset("one image tilted 30 deg", m);
  // The same block with that image vertical too: what the other images' own small omegas do.
  SyntheticBlockOptions level = o;
  level.extra_angles_deg.clear();
  const PrintedOffset baseline = MeasurePrintedOffset(level, kOffsetRealisations);
  PrintOffset("the same, no image tilted", baseline);
  EXPECT_LT(baseline.centre_shift_rms_m, 0.1 * m.centre_shift_rms_m);
  // Tie points the tilted image shares with each other image (realisation 0's block).
  SyntheticBlockOptions first = o;
  first.seed = 1000;
  const TestBlock data = MakeTestBlock(first);
  std::vector<int> shared(data.block.images.size(), 0);
  for (const int mt : data.block.marks_of_image[tilted]) {
    const int p = data.block.marks[mt].point;
    for (const int other : data.block.marks_of_point[p]) ++shared[data.block.marks[other].image];
  }
  ASSERT_EQ(m.printed_usable, m.realisations);  // per_image_shift_rms_m is filled from them
  std::printf(
      "  centre moved RMS (mm) / tie points shared with the tilted image, by line and image:\n");
  for (int s = 0; s < o.num_lines; ++s) {
    std::printf("   ");
    for (int k = 0; k < o.images_per_line; ++k) {
      const int i = s * o.images_per_line + k;
      std::printf(" %7.3f/%-3d", 1e3 * m.per_image_shift_rms_m[i], i == tilted ? 0 : shared[i]);
    }
    std::printf("\n");
  }
  // The tilted image moves most; images sharing no tie point with it move far less.
  double unshared_max = 0.0;
  for (size_t i = 0; i < shared.size(); ++i) {
    if (static_cast<int>(i) == tilted) continue;
    EXPECT_LT(m.per_image_shift_rms_m[i], m.per_image_shift_rms_m[tilted]);
    if (shared[i] == 0) unshared_max = std::max(unshared_max, m.per_image_shift_rms_m[i]);
  }
  EXPECT_LT(unshared_max, 0.25 * m.per_image_shift_rms_m[tilted]);
}

// The --solver switch: each PoseSolver gives what the solver called directly gives.
TEST(TaylorBundle, BundleAdjustWithSolverDispatches) {
  const TestBlock data = MakeTestBlock(TaylorBlockOptions());
  const BundleAdjustmentOptions options = CeresOptions();
  for (const PoseSolver solver :
       {PoseSolver::kCeres, PoseSolver::kTaylor, PoseSolver::kTaylorAsPrinted}) {
    SCOPED_TRACE(EnumName(solver));
    Block via_switch = data.block, direct = data.block;
    BundleAdjustmentResult result;
    TaylorBundleResult taylor;
    ASSERT_TRUE(BundleAdjustWithSolver(solver, options, BundleAdjustmentConfig(), &via_switch,
                                       &result, &taylor)
                    .ok());
    ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
    if (solver == PoseSolver::kCeres) {
      BundleAdjustmentResult expected;
      ASSERT_TRUE(BundleAdjust(options, BundleAdjustmentConfig(), &direct, &expected).ok());
      EXPECT_EQ(result.summary.iterations, expected.summary.iterations);
    } else {
      TaylorBundleOptions taylor_options = TaylorOptions(
          solver == PoseSolver::kTaylor ? TaylorPartials::kCorrected : TaylorPartials::kAsPrinted);
      TaylorBundleResult expected;
      ASSERT_TRUE(
          TaylorBundleAdjust(taylor_options, BundleAdjustmentConfig(), &direct, &expected).ok());
      EXPECT_EQ(taylor.summary.partials, taylor_options.partials);
      EXPECT_EQ(result.summary.iterations, expected.summary.iterations);
      EXPECT_EQ(result.summary.sigma0, taylor.summary.sigma0);
      EXPECT_EQ(result.images.size(), data.block.images.size());
    }
    for (size_t i = 0; i < data.block.images.size(); ++i)
      EXPECT_EQ(via_switch.images[i].eo->parameters, direct.images[i].eo->parameters);
  }
  // A robust tie loss goes through to the Taylor path (TaylorBundleRobust tests its minimum).
  BundleAdjustmentOptions huber = options;
  huber.robustness.tie_loss = LossType::kHuber;
  Block block = data.block;
  BundleAdjustmentResult result;
  ASSERT_TRUE(
      BundleAdjustWithSolver(PoseSolver::kTaylor, huber, BundleAdjustmentConfig(), &block, &result)
          .ok());
  EXPECT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// The camera table's earth-curvature correction (ApplyECC) in the Taylor linearisation: on the
// block simulated with the drop (EarthCurvatureBlockOptions: 800 m high, 10 cm at an image corner)
// the Taylor solver reaches the Ceres adjustment's minimum of the same corrected model, and
// without the correction both reach another one (the flag is used by both, the same way).
TEST(TaylorBundle, HonoursTheEarthCurvatureCorrectionAsBundleAdjustDoes) {
  Block start;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(EarthCurvatureBlockOptions(), &start, &truth).ok());
  ASSERT_GT(start.cameras[0].earth_curvature_radius_m(), 0.0);
  BundleAdjustmentOptions options;
  options.solver.function_tolerance = 1e-14;
  options.solver.parameter_tolerance = 1e-14;
  options.solver.gradient_tolerance = 1e-14;
  for (const bool apply_ecc : {true, false}) {
    SCOPED_TRACE(apply_ecc ? "ApplyECC" : "no correction");
    Block ceres_block = start, taylor_block = start;
    ceres_block.cameras[0].table.apply_ecc = apply_ecc;
    taylor_block.cameras[0].table.apply_ecc = apply_ecc;
    BundleAdjustmentResult ceres, taylor;
    ASSERT_TRUE(BundleAdjustWithSolver(PoseSolver::kCeres, options, BundleAdjustmentConfig(),
                                       &ceres_block, &ceres)
                    .ok());
    ASSERT_TRUE(BundleAdjustWithSolver(PoseSolver::kTaylor, options, BundleAdjustmentConfig(),
                                       &taylor_block, &taylor)
                    .ok());
    ASSERT_TRUE(ceres.summary.IsSolutionUsable()) << ceres.summary.message;
    ASSERT_TRUE(taylor.summary.IsSolutionUsable()) << taylor.summary.message;
    EXPECT_NEAR(taylor.summary.final_cost, ceres.summary.final_cost,
                1e-7 * ceres.summary.final_cost);
    EXPECT_EQ(taylor.summary.num_rejected_marks, ceres.summary.num_rejected_marks);
    double largest = 0.0;
    for (size_t i = 0; i < start.images.size(); ++i) {
      largest = std::max(largest, (taylor_block.images[i].eo->center_in_ground() -
                                   ceres_block.images[i].eo->center_in_ground())
                                      .norm());
    }
    EXPECT_LT(largest, 1e-4);  // m; the corrected and the uncorrected minima are centimetres apart
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ self-calibration, lever arm

// A self-calibrating config: `names` (core/camera_models.h's, or COLMAP's) for every camera, and
// the lever arm estimated when asked (starting from `lever`).
BundleAdjustmentConfig CalibrationConfig(const Block& block, const std::vector<std::string>& names,
                                         bool estimate_lever = false,
                                         const Eigen::Vector3d& lever = Eigen::Vector3d::Zero()) {
  BundleAdjustmentConfig config;
  if (!names.empty()) {
    const Status parsed = BundleAdjustmentConfig::FromCalibrationNames(block, names, &config);
    EXPECT_TRUE(parsed.ok()) << parsed.message();
  }
  if (estimate_lever) {
    config.estimate_lever_arm = true;
    config.lever_arm_m = lever;
  }
  return config;
}

// kFrame: every parameter the tables' polynomial model has but K0 (equal to a change of c) and
// the affinity and skew (not in the seed's table).
const std::vector<std::string> kFrameCalibration = {"FocalLength", "PrincipalX", "PrincipalY",
                                                    "K1",          "K2",         "K3",
                                                    "P1",          "P2"};

// The whitened residual of a block linearised under `config`.
Eigen::VectorXd WhitenedResidual(const Block& block, const BundleAdjustmentConfig& config) {
  TaylorBundleLinearSystem system;
  const Status status = LinearizeTaylorBundle(TaylorOptions(), config, block, &system);
  EXPECT_TRUE(status.ok()) << status.message();
  return system.residual;
}

// Every column of the linearised system (exterior orientations, points, the camera's estimated
// parameters, the lever arm) against central differences of the whitened residual. The step of a
// calibration or lever column moves the residual by about 1e-3 of a sigma (h = 1e-3 / the
// column's largest entry): the parameters span twelve orders of magnitude (c in um, K3 in mm^-6).
// Returns the largest relative difference of a column.
double WorstColumnAgainstCentralDifferences(const Block& block,
                                            const BundleAdjustmentConfig& config) {
  TaylorBundleLinearSystem system;
  const Status status = LinearizeTaylorBundle(TaylorOptions(), config, block, &system);
  EXPECT_TRUE(status.ok()) << status.message();
  if (!status.ok()) return 1.0;
  double worst = 0.0;
  const auto check = [&](int column, const Eigen::VectorXd& plus, const Eigen::VectorXd& minus,
                         double h, const std::string& what) {
    const Eigen::VectorXd numeric = (plus - minus) / (2.0 * h);
    const double scale = std::max(numeric.cwiseAbs().maxCoeff(), 1e-300);
    const double error = (numeric - system.jacobian.col(column)).cwiseAbs().maxCoeff() / scale;
    EXPECT_LT(error, kPartialRelativeTolerance) << what;
    worst = std::max(worst, error);
  };
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (system.image_columns[i] < 0) continue;
    for (int k = 0; k < 6; ++k) {
      const double h = k < 3 ? 1e-3 : 1e-6;  // m, rad
      Block plus = block, minus = block;
      plus.images[i].eo->parameters[k] += h;
      minus.images[i].eo->parameters[k] -= h;
      check(system.image_columns[i] + k, WhitenedResidual(plus, config),
            WhitenedResidual(minus, config), h, "image " + std::to_string(i));
    }
  }
  for (size_t p = 0; p < block.points.size(); p += 7) {
    if (system.point_columns[p] < 0 || !block.points[p].position_m) continue;
    for (int k = 0; k < 3; ++k) {
      Block plus = block, minus = block;
      (*plus.points[p].position_m)[k] += 1e-3;
      (*minus.points[p].position_m)[k] -= 1e-3;
      check(system.point_columns[p] + k, WhitenedResidual(plus, config),
            WhitenedResidual(minus, config), 1e-3, "point " + std::to_string(p));
    }
  }
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    if (system.camera_columns[c] < 0) continue;
    for (size_t j = 0; j < config.calibrated_params[c].size(); ++j) {
      std::vector<int> indices = config.calibrated_params[c];
      std::sort(indices.begin(), indices.end());
      const int column = system.camera_columns[c] + static_cast<int>(j);
      const double h = 1e-3 / system.jacobian.col(column).cwiseAbs().maxCoeff();
      Block plus = block, minus = block;
      plus.cameras[c].params[indices[j]] += h;
      minus.cameras[c].params[indices[j]] -= h;
      check(column, WhitenedResidual(plus, config), WhitenedResidual(minus, config), h,
            "camera parameter " + std::to_string(indices[j]));
    }
  }
  if (system.lever_column >= 0) {
    for (int k = 0; k < 3; ++k) {
      const int column = system.lever_column + k;
      const double h = 1e-3 / system.jacobian.col(column).cwiseAbs().maxCoeff();
      BundleAdjustmentConfig plus = config, minus = config;
      (*plus.lever_arm_m)[k] += h;
      (*minus.lever_arm_m)[k] -= h;
      check(column, WhitenedResidual(block, plus), WhitenedResidual(block, minus), h,
            "lever arm " + std::to_string(k));
    }
  }
  return worst;
}

// The calibration's and the lever arm's columns: the kFrame film correction's partials (ideal
// point by a Jet of FrameCorrectFilmPoint inside CameraModelResidual, c on the collinearity
// side), the COLMAP models' (the same Jet with a derivative per parameter), and R^T for the lever
// arm; the exterior-orientation and point columns of the self-calibrated cameras again (they now
// go through the model per mark).
TEST(TaylorBundlePartials, CalibrationAndLeverArmColumnsMatchCentralDifferences) {
  struct Case {
    const char* name;
    SyntheticBlockOptions block;
    std::vector<std::string> calibrate;
    bool lever;
  };
  SyntheticBlockOptions frame = TaylorBlockOptions();
  frame.camera_params = {24000.0, 15.0, -10.0, 0.0, -2e-5, 3e-8, -1e-11, 2e-6, -1e-6, 0.0, 0.0};
  const std::vector<Case> cases = {
      {"kFrame, c, xp, yp, K1-K3, P1, P2, lever arm", frame, kFrameCalibration, true},
      {"OPENCV, f, cx, cy, k1, k2, p1, p2", ForwardModelBlock(ForwardModels()[4]),
       {"f", "cx", "cy", "k1", "k2", "p1", "p2"}, false},
      {"SIMPLE_RADIAL, f, k, lever arm", ForwardModelBlock(ForwardModels()[2]), {"f", "k"}, true},
  };
  std::printf("  %-46s %s\n", "camera, estimated", "largest relative difference of a column");
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const TestBlock data = MakeTestBlock(SixImages(c.block, 30));
    const BundleAdjustmentConfig config = CalibrationConfig(
        data.block, c.calibrate, c.lever, Eigen::Vector3d(0.05, -0.1, 0.3));
    const double worst = WorstColumnAgainstCentralDifferences(data.block, config);
    std::printf("  %-46s %.2e\n", c.name, worst);
    EXPECT_LT(worst, kPartialRelativeTolerance);
  }
}

// The border of global columns in the reduction (their coupling with every camera block, the
// points eliminated through them, the back-substitution) against the full normal equations.
TEST(TaylorBundleNormalEquations, ReducedEqualTheFullOnesWithCalibrationAndLeverArm) {
  SyntheticBlockOptions o = SixImages(TaylorBlockOptions(), 49);
  TestBlock data = MakeTestBlock(o);
  CheckReductionAgainstFullSystem(
      data, TaylorOptions(),
      CalibrationConfig(data.block, kFrameCalibration, true, Eigen::Vector3d(0.1, 0.2, 0.3)));
  // An image held constant: its marks still enter the calibration's columns, its camera-position
  // prior the lever arm's.
  BundleAdjustmentConfig held =
      CalibrationConfig(data.block, {"FocalLength", "K1"}, true, Eigen::Vector3d(0.1, 0.2, 0.3));
  held.constant_images = {0, 4};
  CheckReductionAgainstFullSystem(data, TaylorOptions(), held);
  // A relative COLMAP block with f and k.
  SyntheticBlockOptions colmap = SixImages(ForwardModelBlock(ForwardModels()[2]), 49);
  colmap.gnss = false;
  colmap.num_control_points = 0;
  colmap.check_layout.clear();
  colmap.num_check_points = 0;
  const TestBlock relative = MakeTestBlock(colmap);
  CheckReductionAgainstFullSystem(relative, TaylorOptions(),
                                  CalibrationConfig(relative.block, {"f", "k"}));
}

// Taylor against Ceres on self-calibrating blocks: the same minimum (cost, centres), the same
// calibration with the same sigmas and correlations, the same lever arm.
struct CalibrationScenario {
  const char* name;
  SyntheticBlockOptions block;
  std::vector<std::string> calibrate;
  bool lever = false;
  // The start's interior orientation off the simulated one: per parameter index, the offset.
  std::vector<std::pair<int, double>> offsets;
};

// The cost to 1e-9 relative: both solvers at their minimum, tolerances tightened.
constexpr double kCostRelativeAgreement = 1e-9;
// Calibration sigmas and correlations to 1e-6 relative (one code evaluated at solutions ~1e-9
// apart); the calibration Ceres reaches from the Taylor solution within 1e-6 of its sigmas (the
// Taylor solution is the minimum).
constexpr double kCalibrationRelativeAgreement = 1e-6;
// Calibration values of the two solvers from the same start, relative to max(|value|, sigma) (P1,
// P2 are zero in the simulation, their estimates noise): Ceres stops where the cost no longer
// resolves a step, with the 8 correlated frame parameters ~2e-6 of a sigma from the minimum (the
// worst measured: the principal point's y, 1e-5 um of 5.6 um).
constexpr double kCalibrationValueAgreement = 1e-5;

std::vector<CalibrationScenario> CalibrationScenarios() {
  std::vector<CalibrationScenario> scenarios;
  {
    // 4 lines of 6 images over 30 m of relief (c against the heights: the GNSS centres and the
    // relief separate them).
    CalibrationScenario s{"kFrame c, xp, yp, K1-K3, P1, P2", TaylorBlockOptions(),
                          kFrameCalibration};
    s.block.num_lines = 4;
    s.block.images_per_line = 6;
    s.block.num_tie_points = 600;
    s.block.terrain_relief_m = 30.0;
    s.offsets = {{kFrameFocal, 50.0}, {kFramePrincipalX, 20.0}, {kFrameK1, 5e-6}};
    scenarios.push_back(s);
  }
  {
    CalibrationScenario s{"kFrame c, K1, estimated lever arm", TaylorBlockOptions(),
                          {"FocalLength", "K1"}, true};
    s.block.num_lines = 4;
    s.block.images_per_line = 6;
    s.block.num_tie_points = 400;
    s.block.terrain_relief_m = 30.0;
    s.offsets = {{kFrameFocal, 30.0}};
    scenarios.push_back(s);
  }
  {
    CalibrationScenario s{"OPENCV fx, fy, k1, k2", ForwardModelBlock(ForwardModels()[4]),
                          {"f", "k1", "k2"}};
    s.block.num_lines = 4;
    s.block.images_per_line = 6;
    s.block.num_tie_points = 400;
    s.block.terrain_relief_m = 30.0;
    s.offsets = {{0, 20.0}, {1, -15.0}, {4, 0.01}};
    scenarios.push_back(s);
  }
  {
    CalibrationScenario s{"SIMPLE_RADIAL f, k, relative", ForwardModelBlock(ForwardModels()[2]),
                          {"f", "k"}};
    s.block.num_lines = 4;
    s.block.images_per_line = 6;
    s.block.num_tie_points = 400;
    s.block.terrain_relief_m = 30.0;
    s.block.gnss = false;
    s.block.num_control_points = 0;
    s.block.check_layout.clear();
    s.block.num_check_points = 0;
    s.offsets = {{0, 30.0}, {3, 0.01}};
    scenarios.push_back(s);
  }
  return scenarios;
}

TEST(TaylorBundleVsCeres, SameSelfCalibrationAndLeverArm) {
  std::printf("  %-36s %9s %9s %9s %9s %9s %9s %9s %7s %s\n", "block", "cost rel", "centre m",
              "calib rel", "polished", "sigma rel", "lever m", "cov rel", "iter", "s T/C");
  for (const CalibrationScenario& scenario : CalibrationScenarios()) {
    SCOPED_TRACE(scenario.name);
    TestBlock data = MakeTestBlock(scenario.block);
    for (const auto& [index, offset] : scenario.offsets)
      data.block.cameras[0].params[index] += offset;
    const Eigen::Vector3d lever(0.05, -0.1, 0.3);
    if (scenario.lever) {
      for (size_t i = 0; i < data.block.images.size(); ++i) {
        const Eigen::Vector3d offset = TaylorAntennaPosition(data.truth.eo[i], lever, nullptr) -
                                       data.truth.eo[i].center_in_ground();
        *data.block.images[i].measured_center_m += offset;
      }
    }
    // The lever arm starts at zero, 0.33 m off.
    const BundleAdjustmentConfig config =
        CalibrationConfig(data.block, scenario.calibrate, scenario.lever);
    const BundleAdjustmentOptions ceres_options = TightCeresOptions();
    Block ceres_block = data.block, taylor_block = data.block;
    BundleAdjustmentResult ceres;
    TaylorBundleResult taylor;
    const Status ceres_status = BundleAdjust(ceres_options, config, &ceres_block, &ceres);
    const Status taylor_status = TaylorBundleAdjust(TaylorOptions(), config, &taylor_block, &taylor);
    ASSERT_TRUE(ceres_status.ok()) << ceres_status.message();
    ASSERT_TRUE(taylor_status.ok()) << taylor_status.message();
    ASSERT_TRUE(ceres.summary.IsSolutionUsable()) << ceres.summary.BriefReport();
    ASSERT_TRUE(taylor.summary.IsSolutionUsable()) << taylor.summary.BriefReport();
    EXPECT_EQ(taylor.summary.redundancy, ceres.summary.redundancy);
    const double cost_relative =
        std::abs(taylor.summary.final_cost - ceres.summary.final_cost) / ceres.summary.final_cost;
    double centre = 0.0, covariance = 0.0;
    for (size_t i = 0; i < data.block.images.size(); ++i) {
      centre = std::max(centre, (ceres_block.images[i].eo->center_in_ground() -
                                 taylor_block.images[i].eo->center_in_ground())
                                    .norm());
      if (!ceres.images[i].has_covariance) continue;
      const Vector6d c = ceres.images[i].covariance.diagonal();
      const Vector6d t = taylor.adjustment.images[i].covariance.diagonal();
      for (int k = 0; k < 6; ++k)
        if (c[k] > 0.0) covariance = std::max(covariance, std::abs(t[k] - c[k]) / c[k]);
    }
    const std::vector<BundleCalibrationResult>& cc = ceres.calibration;
    const std::vector<BundleCalibrationResult>& tc = taylor.adjustment.calibration;
    ASSERT_EQ(tc.size(), cc.size());
    ASSERT_EQ(cc.size(), 1u);
    double calibration = 0.0, sigma = 0.0;
    ASSERT_EQ(tc[0].values.size(), cc[0].values.size());
    ASSERT_EQ(tc[0].sigmas.size(), cc[0].sigmas.size());
    for (size_t j = 0; j < cc[0].values.size(); ++j) {
      EXPECT_EQ(tc[0].names[j], cc[0].names[j]);
      EXPECT_EQ(taylor_block.cameras[0].params[cc[0].indices[j]], tc[0].values[j]);
      calibration = std::max(calibration, std::abs(tc[0].values[j] - cc[0].values[j]) /
                                              std::max(std::abs(cc[0].values[j]), cc[0].sigmas[j]));
      sigma = std::max(sigma, std::abs(tc[0].sigmas[j] - cc[0].sigmas[j]) / cc[0].sigmas[j]);
    }
    // Ceres started at the Taylor solution: how far it moves the calibration (in its sigmas).
    Block polished_block = taylor_block;
    BundleAdjustmentResult polished;
    ASSERT_TRUE(BundleAdjust(ceres_options, config, &polished_block, &polished).ok());
    ASSERT_TRUE(polished.summary.IsSolutionUsable()) << polished.summary.BriefReport();
    double moved = 0.0;
    for (size_t j = 0; j < cc[0].values.size(); ++j)
      moved = std::max(moved, std::abs(polished.calibration[0].values[j] - tc[0].values[j]) /
                                  cc[0].sigmas[j]);
    EXPECT_LT((tc[0].correlation - cc[0].correlation).cwiseAbs().maxCoeff(),
              kCalibrationRelativeAgreement);
    double lever_difference = 0.0;
    ASSERT_EQ(taylor.adjustment.lever_arm_m.has_value(), ceres.lever_arm_m.has_value());
    if (ceres.lever_arm_m) {
      lever_difference = (*taylor.adjustment.lever_arm_m - *ceres.lever_arm_m).norm();
      std::printf("  lever arm estimated from zero: %.3f %.3f %.3f m (simulated %.3f %.3f %.3f)\n",
                  (*taylor.adjustment.lever_arm_m)[0], (*taylor.adjustment.lever_arm_m)[1],
                  (*taylor.adjustment.lever_arm_m)[2], lever[0], lever[1], lever[2]);
    }
    std::printf("  %-36s %9.2e %9.2e %9.2e %9.2e %9.2e %9.2e %9.2e %3d/%-3d %.2f/%.2f\n",
                scenario.name, cost_relative, centre, calibration, moved, sigma, lever_difference,
                covariance, taylor.summary.iterations, ceres.summary.iterations,
                taylor.summary.time_seconds, ceres.summary.time_seconds);
    EXPECT_LT(cost_relative, kCostRelativeAgreement);
    EXPECT_LT(centre, kRelativeAgreement * data.size_m);
    EXPECT_LT(calibration, kCalibrationValueAgreement);
    EXPECT_LT(moved, kCalibrationRelativeAgreement);
    EXPECT_LT(sigma, kCalibrationRelativeAgreement);
    EXPECT_LT(lever_difference, kRelativeAgreement * data.size_m);
    EXPECT_LT(covariance, kCovarianceRelativeAgreement);
  }
}

// An image held constant keeps its camera-position prior in the cost, as in BundleAdjust's
// problem (a constant residual, but part of the cost, sigma0 and the estimated lever arm's rows).
TEST(TaylorBundleVsCeres, ImagesHeldConstantKeepTheirPriorsInTheCost) {
  const TestBlock data = MakeTestBlock(TaylorBlockOptions());
  for (const bool estimate_lever : {false, true}) {
    SCOPED_TRACE(estimate_lever ? "estimated lever arm" : "no lever arm");
    BundleAdjustmentConfig config = CalibrationConfig(data.block, {}, estimate_lever);
    config.constant_images = {0, 5};
    const BundleAdjustmentOptions ceres_options = TightCeresOptions();
    Block ceres_block = data.block, taylor_block = data.block;
    BundleAdjustmentResult ceres;
    TaylorBundleResult taylor;
    ASSERT_TRUE(BundleAdjust(ceres_options, config, &ceres_block, &ceres).ok());
    ASSERT_TRUE(TaylorBundleAdjust(TaylorOptions(), config, &taylor_block, &taylor).ok());
    ASSERT_TRUE(ceres.summary.IsSolutionUsable()) << ceres.summary.BriefReport();
    ASSERT_TRUE(taylor.summary.IsSolutionUsable()) << taylor.summary.BriefReport();
    EXPECT_EQ(taylor.summary.redundancy, ceres.summary.redundancy);
    EXPECT_NEAR(taylor.summary.final_cost, ceres.summary.final_cost,
                kCostRelativeAgreement * ceres.summary.final_cost);
    EXPECT_EQ(taylor_block.images[0].eo->parameters, data.block.images[0].eo->parameters);
  }
}

// What no observation determines fails the round and names it; nothing is written. The Taylor
// solver (its reduced system's weightless column) and BundleAdjust (its statistics' factorisation)
// find it by different means but name it with the same words (internal::UnknownName).
TEST(TaylorBundleVsCeres, AnUndeterminedLeverArmIsNamedAlikeByBoth) {
  SyntheticBlockOptions o = TaylorBlockOptions();
  o.gnss = false;  // no camera positions: nothing sees the lever arm
  const TestBlock data = MakeTestBlock(o);
  const BundleAdjustmentConfig config = CalibrationConfig(data.block, {}, true);
  Block taylor_block = data.block, ceres_block = data.block;
  TaylorBundleResult taylor;
  ASSERT_TRUE(TaylorBundleAdjust(TaylorOptions(), config, &taylor_block, &taylor).ok());
  EXPECT_EQ(taylor.summary.termination_type, SolverTermination::kFailure);
  EXPECT_NE(taylor.summary.message.find("the lever arm's x (camera frame) has no weight"),
            std::string::npos)
      << taylor.summary.message;
  ExpectUntouched(data.block, taylor_block, taylor);
  BundleAdjustmentResult ceres;
  ASSERT_TRUE(BundleAdjust(TightCeresOptions(), config, &ceres_block, &ceres).ok());
  EXPECT_EQ(ceres.summary.termination, SolverTermination::kFailure);
  EXPECT_NE(ceres.summary.message.find("the lever arm's x (camera frame) is not determined"),
            std::string::npos)
      << ceres.summary.message;
}

// A self-calibrated parameter no mark constrains (a camera with no image): both name it alike.
TEST(TaylorBundleVsCeres, AnUndeterminedCalibrationIsNamedAlikeByBoth) {
  const TestBlock data = MakeTestBlock(TaylorBlockOptions());
  Block block = data.block;
  BlockCamera unused = block.cameras[0];
  unused.camera_id = "unused";
  block.cameras.push_back(unused);
  BundleAdjustmentConfig config;
  config.calibrated_params.resize(block.cameras.size());
  config.calibrated_params.back() = {0};
  Block taylor_block = block, ceres_block = block;
  TaylorBundleResult taylor;
  BundleAdjustmentResult ceres;
  ASSERT_TRUE(TaylorBundleAdjust(TaylorOptions(), config, &taylor_block, &taylor).ok());
  ASSERT_TRUE(BundleAdjust(TightCeresOptions(), config, &ceres_block, &ceres).ok());
  const std::string name =
      "camera 'unused': the self-calibrated " + CameraModelParamNames(unused.model)[0];
  EXPECT_NE(taylor.summary.message.find(name), std::string::npos) << taylor.summary.message;
  EXPECT_NE(ceres.summary.message.find(name), std::string::npos) << ceres.summary.message;
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
