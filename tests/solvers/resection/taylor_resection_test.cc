#include "solvers/resection/taylor_resection.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/collinearity.h"
#include "core/rotation.h"
#include "test_data.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ tolerances
// Central differences with the steps below have truncation ~ (h / D)^2 ~ 1e-8 relative and rounding
// ~ 1e-11; 1e-6 leaves two orders of margin (the measured worst case is printed by the test).
constexpr double kPartialRelativeTolerance = 1e-6;
// The misprinted eq. 21 must be off by far more than the difference noise: its error is
// |(y - x) sin(omega)|, a good fraction of c for oblique views.
constexpr double kPrintedEq21MinRelativeError = 1e-2;
// Two closed-form evaluations of the same formula by different code: rounding only.
constexpr double kSameFormulaRelativeTolerance = 1e-9;
// Noise-free synthetic data are recovered to the brief's 1e-9 m / 1e-9 rad; Gauss-Newton converges
// quadratically, so the reached error is ~1e-12, far below this.
constexpr double kNoiseFreePositionTolerance = 1e-9;  // m
constexpr double kNoiseFreeAngleTolerance = 1e-9;     // rad

constexpr int kPartialCheckPoses = 500;  // random poses for the partial-derivative checks
constexpr int kPointsPerPose = 8;

// ------------------------------------------------------------------ synthetic scenes

struct Scene {
  ExteriorOrientation truth;
  std::vector<Eigen::Vector2d> image_um;
  std::vector<Eigen::Vector3d> ground_m;
  double focal_um = 0.0;
};

// A frame at `center` with seed angles, and n ground points whose images are uniform in the square
// format +- half_format_um and whose heights are uniform in +- relief_m / 2 around 0.
Scene MakeScene(std::mt19937_64* rng, const Eigen::Vector3d& center, const Eigen::Vector3d& angles,
                int n, double focal_um, double half_format_um, double relief_m) {
  Scene scene;
  scene.focal_um = focal_um;
  scene.truth.set_center_in_ground(center);
  scene.truth.set_angles_seed_rad(angles);
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, angles);
  std::uniform_real_distribution<double> image(-half_format_um, half_format_um);
  std::uniform_real_distribution<double> height(-0.5 * relief_m, 0.5 * relief_m);
  while (static_cast<int>(scene.ground_m.size()) < n) {
    const Eigen::Vector3d ray =
        R.transpose() * DrawLastFirst<3>([&](int i) { return i == 2 ? -focal_um : image(*rng); });
    if (!(ray.z() < -1e-3 * ray.norm())) continue;
    const double z = height(*rng);
    const double t = (z - center.z()) / ray.z();
    if (!(t > 0.0)) continue;
    const Eigen::Vector3d point = center + t * ray;
    double xy[2];
    if (!ProjectToImagePlane(scene.truth.data(), point.data(), focal_um, xy)) continue;
    scene.ground_m.push_back(point);
    scene.image_um.emplace_back(xy[0], xy[1]);
  }
  return scene;
}

// The camera of the synthetic tests: 100.5 mm lens, 6 um pixels, +- 34 mm format.
constexpr double kFocalUm = 100500.0;
constexpr double kPixelUm = 6.0;
constexpr double kHalfFormatUm = 34000.0;

Scene NadirScene(std::mt19937_64* rng, int n) {
  return MakeScene(
      rng, Eigen::Vector3d(500.0, 300.0, 800.0),
      Eigen::Vector3d(DegreesToRadians(0.7), DegreesToRadians(-1.1), DegreesToRadians(37.0)), n,
      kFocalUm, kHalfFormatUm, 30.0);
}

// Tilted 45 deg about the flight axis (omega, the seed's roll), the case where eq. 21 matters most.
Scene ObliqueScene(std::mt19937_64* rng, int n) {
  return MakeScene(
      rng, Eigen::Vector3d(500.0, 300.0, 800.0),
      Eigen::Vector3d(DegreesToRadians(45.0), DegreesToRadians(2.0), DegreesToRadians(-120.0)), n,
      kFocalUm, kHalfFormatUm, 30.0);
}

ExteriorOrientation Perturb(const ExteriorOrientation& eo, double position_m, double angle_deg) {
  ExteriorOrientation out = eo;
  out.parameters.head<3>() += Eigen::Vector3d(position_m, -0.8 * position_m, 0.6 * position_m);
  out.parameters.tail<3>() +=
      Eigen::Vector3d(-angle_deg, 0.7 * angle_deg, angle_deg) * (1.0 / kDegreesPerRadian);
  return out;
}

double PositionError(const ExteriorOrientation& a, const ExteriorOrientation& b) {
  return (a.center_in_ground() - b.center_in_ground()).cwiseAbs().maxCoeff();
}

double AngleError(const ExteriorOrientation& a, const ExteriorOrientation& b) {
  double worst = 0.0;
  for (int k = 3; k < 6; ++k) {
    worst = std::max(worst, std::abs(WrapAngle(a.parameters[k] - b.parameters[k])));
  }
  return worst;
}

// ------------------------------------------------------------------ numerical differentiation

// Central differences of (Fu, Fv) (eqs. 7-8) with respect to the six parameters. Steps: 1e-4 of the
// camera-point distance for positions, 1e-6 rad for angles.
bool CentralDifferences(const ExteriorOrientation& eo, const Eigen::Vector3d& point, double focal,
                        double numeric_u[6], double numeric_v[6]) {
  const double distance = (point - eo.center_in_ground()).norm();
  for (int k = 0; k < 6; ++k) {
    const double h = k < 3 ? 1e-4 * distance : 1e-6;
    ExteriorOrientation plus = eo, minus = eo;
    plus.parameters[k] += h;
    minus.parameters[k] -= h;
    double fu_p, fv_p, fu_m, fv_m;
    if (!TaylorFunctions(plus, point, focal, Eigen::Vector2d::Zero(), &fu_p, &fv_p)) return false;
    if (!TaylorFunctions(minus, point, focal, Eigen::Vector2d::Zero(), &fu_m, &fv_m)) return false;
    numeric_u[k] = (fu_p - fu_m) / (2.0 * h);
    numeric_v[k] = (fv_p - fv_m) / (2.0 * h);
  }
  return true;
}

// A random pose with omega, phi in +-60 deg, kappa over the whole circle, and points in front of it
// at 100 m to 3 km, imaged anywhere in a +-0.6 c format.
Scene RandomPoseScene(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> tilt(-DegreesToRadians(60.0), DegreesToRadians(60.0));
  std::uniform_real_distribution<double> kappa(-kPi, kPi);
  std::uniform_real_distribution<double> coordinate(-1000.0, 1000.0);
  std::uniform_real_distribution<double> depth(100.0, 3000.0);
  Scene scene;
  scene.focal_um = 150000.0;
  scene.truth.set_center_in_ground(
      DrawLastFirst<3>([&](int) { return coordinate(*rng); }));
  scene.truth.set_angles_seed_rad(DrawLastFirst<3>([&](int i) { return i == 2 ? kappa(*rng) : tilt(*rng); }));
  const Eigen::Matrix3d R =
      RotationFromAngles(RotationConvention::kSeed, scene.truth.angles_seed_rad());
  std::uniform_real_distribution<double> image(-0.6 * scene.focal_um, 0.6 * scene.focal_um);
  for (int i = 0; i < kPointsPerPose; ++i) {
    const Eigen::Vector3d ray_in_camera = DrawLastFirst<3>([&](int i) { return i == 2 ? -scene.focal_um : image(*rng); });
    const Eigen::Vector3d point =
        scene.truth.center_in_ground() + depth(*rng) * (R.transpose() * ray_in_camera.normalized());
    scene.ground_m.push_back(point);
  }
  return scene;
}

// Natural magnitude of a column of the Jacobian, used as the floor of relative errors so that
// partials that happen to be near zero (e.g. uv/c on an axis) are not divided by ~0: c/D (um per m)
// for the position columns, c (um per rad) for the angle columns.
double ColumnScale(int k, double focal, double distance) {
  return k < 3 ? focal / distance : focal;
}

const char* kPartialNames[2][6] = {{"eq17 dFu/dX0", "eq18 dFu/dY0", "eq19 dFu/dZ0",
                                    "eq20 dFu/domega", "eq21 dFu/dphi", "eq22 dFu/dkappa"},
                                   {"eq23 dFv/dX0", "eq24 dFv/dY0", "eq25 dFv/dZ0",
                                    "eq26 dFv/domega", "eq27 dFv/dphi", "eq28 dFv/dkappa"}};

// Maximum relative error of every partial (row r, column k) over the random poses.
void MaxPartialErrors(TaylorPartials partials, double max_error[2][6]) {
  std::mt19937_64 rng(20240601);
  for (int r = 0; r < 2; ++r) std::fill(max_error[r], max_error[r] + 6, 0.0);
  for (int pose = 0; pose < kPartialCheckPoses; ++pose) {
    const Scene scene = RandomPoseScene(&rng);
    for (const Eigen::Vector3d& point : scene.ground_m) {
      double rows[2][6], numeric[2][6];
      ASSERT_TRUE(TaylorPartialsForPoint(partials, scene.truth, point, scene.focal_um,
                                         Eigen::Vector2d::Zero(), rows[0], rows[1], nullptr,
                                         nullptr));
      ASSERT_TRUE(CentralDifferences(scene.truth, point, scene.focal_um, numeric[0], numeric[1]));
      const double distance = (point - scene.truth.center_in_ground()).norm();
      for (int r = 0; r < 2; ++r) {
        for (int k = 0; k < 6; ++k) {
          const double scale =
              std::max(std::abs(numeric[r][k]), ColumnScale(k, scene.focal_um, distance));
          max_error[r][k] = std::max(max_error[r][k], std::abs(rows[r][k] - numeric[r][k]) / scale);
        }
      }
    }
  }
}

// ------------------------------------------------------------------ hand-computed nominal case

// Vertical camera 1000 m above the origin, kappa = 0, c = 100 mm; point (100, 50, 0):
// (u, v, w) = (100, 50, -1000), x = -c u / w = 10000 um, y = 5000 um. By hand from eqs. 17-28:
//   dFu/dX0 = (c a11 + x a31) / w = 1e5 / -1000 = -100      dFv/dX0 = (c a21 + y a31) / w = 0
//   dFu/dY0 = 0                                             dFv/dY0 = -100
//   dFu/dZ0 = (c a13 + x a33) / w = 1e4 / -1000 = -10       dFv/dZ0 = 5e3 / -1000 = -5
//   dFu/domega = x y / c = 500                              dFv/domega = c + y^2 / c = 100250
//   dFu/dphi = -x^2/c - c = -101000                         dFv/dphi = -x y / c = -500
//   dFu/dkappa = -100 * 50 - 0 * 100 = -5000                dFv/dkappa = 0 * 50 + 100 * 100 = 10000
TEST(TaylorPartials, HandComputedNominalCase) {
  ExteriorOrientation eo;
  eo.set_center_in_ground(Eigen::Vector3d(0.0, 0.0, 1000.0));
  const Eigen::Vector3d point(100.0, 50.0, 0.0);
  const Eigen::Vector2d observed(9990.0, 5003.0);
  double row_u[6], row_v[6], fu, fv;
  ASSERT_TRUE(TaylorPartialsForPoint(TaylorPartials::kCorrected, eo, point, 100000.0, observed,
                                     row_u, row_v, &fu, &fv));
  constexpr double kExact = 1e-9;  // all values are exact in binary up to a few ulps
  EXPECT_NEAR(fu, 10.0, kExact);
  EXPECT_NEAR(fv, -3.0, kExact);
  const double expected_u[6] = {-100.0, 0.0, -10.0, 500.0, -101000.0, -5000.0};
  const double expected_v[6] = {0.0, -100.0, -5.0, 100250.0, -500.0, 10000.0};
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(row_u[k], expected_u[k], kExact) << kPartialNames[0][k];
    EXPECT_NEAR(row_v[k], expected_v[k], kExact) << kPartialNames[1][k];
  }
  // With omega = 0 the misprint of eq. 21 is invisible.
  double printed_u[6], printed_v[6];
  ASSERT_TRUE(TaylorPartialsForPoint(TaylorPartials::kAsPrinted, eo, point, 100000.0, observed,
                                     printed_u, printed_v, nullptr, nullptr));
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(printed_u[k], row_u[k]);
    EXPECT_EQ(printed_v[k], row_v[k]);
  }
}

TEST(TaylorPartials, FunctionsAreTheCollinearityEquations) {
  std::mt19937_64 rng(7);
  for (int pose = 0; pose < 50; ++pose) {
    const Scene scene = RandomPoseScene(&rng);
    for (const Eigen::Vector3d& point : scene.ground_m) {
      double xy[2], fu, fv;
      ASSERT_TRUE(ProjectToImagePlane(scene.truth.data(), point.data(), scene.focal_um, xy));
      ASSERT_TRUE(TaylorFunctions(scene.truth, point, scene.focal_um, Eigen::Vector2d(1.0, -2.0),
                                  &fu, &fv));
      EXPECT_NEAR(fu, xy[0] - 1.0, kSameFormulaRelativeTolerance * scene.focal_um);
      EXPECT_NEAR(fv, xy[1] + 2.0, kSameFormulaRelativeTolerance * scene.focal_um);
    }
  }
}

TEST(TaylorPartials, CorrectedPartialsMatchCentralDifferences) {
  double max_error[2][6];
  MaxPartialErrors(TaylorPartials::kCorrected, max_error);
  for (int r = 0; r < 2; ++r) {
    for (int k = 0; k < 6; ++k) {
      EXPECT_LT(max_error[r][k], kPartialRelativeTolerance) << kPartialNames[r][k];
      std::printf("  corrected  %-16s max relative error %.2e\n", kPartialNames[r][k],
                  max_error[r][k]);
    }
  }
}

// Exactly one printed partial is wrong: eq. 21. The test fails if another printed formula turns out
// wrong or if the as-printed variant stops reproducing the misprint.
TEST(TaylorPartials, AsPrintedPartialsWrongExactlyInEquation21) {
  double max_error[2][6];
  MaxPartialErrors(TaylorPartials::kAsPrinted, max_error);
  for (int r = 0; r < 2; ++r) {
    for (int k = 0; k < 6; ++k) {
      std::printf("  as printed %-16s max relative error %.2e\n", kPartialNames[r][k],
                  max_error[r][k]);
      const bool is_eq21 = (r == 0 && k == 4);
      if (is_eq21) {
        EXPECT_GT(max_error[r][k], kPrintedEq21MinRelativeError) << kPartialNames[r][k];
      } else {
        EXPECT_LT(max_error[r][k], kPartialRelativeTolerance) << kPartialNames[r][k];
      }
    }
  }
}

// The as-printed eq. 21 is literally -(u^2/c) cos(omega) - u sin(omega) - c cos(omega), and differs
// from the corrected one by (v - u) sin(omega).
TEST(TaylorPartials, AsPrintedEquation21IsTheLiteralFormula) {
  std::mt19937_64 rng(11);
  for (int pose = 0; pose < 100; ++pose) {
    const Scene scene = RandomPoseScene(&rng);
    const double c = scene.focal_um;
    const double omega = scene.truth.parameters[3];
    for (const Eigen::Vector3d& point : scene.ground_m) {
      double printed_u[6], printed_v[6], corrected_u[6], corrected_v[6], xy[2];
      ASSERT_TRUE(ProjectToImagePlane(scene.truth.data(), point.data(), c, xy));
      ASSERT_TRUE(TaylorPartialsForPoint(TaylorPartials::kAsPrinted, scene.truth, point, c,
                                         Eigen::Vector2d::Zero(), printed_u, printed_v, nullptr,
                                         nullptr));
      ASSERT_TRUE(TaylorPartialsForPoint(TaylorPartials::kCorrected, scene.truth, point, c,
                                         Eigen::Vector2d::Zero(), corrected_u, corrected_v, nullptr,
                                         nullptr));
      const double u = xy[0], v = xy[1];
      const double literal =
          -u * u / c * std::cos(omega) - u * std::sin(omega) - c * std::cos(omega);
      EXPECT_NEAR(printed_u[4], literal, kSameFormulaRelativeTolerance * c);
      EXPECT_NEAR(printed_u[4] - corrected_u[4], (v - u) * std::sin(omega),
                  kSameFormulaRelativeTolerance * c);
      for (int k = 0; k < 6; ++k) {
        if (k != 4) {
          EXPECT_EQ(printed_u[k], corrected_u[k]) << k;
        }
        EXPECT_EQ(printed_v[k], corrected_v[k]) << k;
      }
    }
  }
}

TEST(TaylorPartials, CorrectedPartialsEqualProjectWithJacobians) {
  std::mt19937_64 rng(13);
  for (int pose = 0; pose < kPartialCheckPoses; ++pose) {
    const Scene scene = RandomPoseScene(&rng);
    for (const Eigen::Vector3d& point : scene.ground_m) {
      double row_u[6], row_v[6], xy[2], d_eo[12];
      ASSERT_TRUE(TaylorPartialsForPoint(TaylorPartials::kCorrected, scene.truth, point,
                                         scene.focal_um, Eigen::Vector2d::Zero(), row_u, row_v,
                                         nullptr, nullptr));
      ASSERT_TRUE(ProjectWithJacobians(scene.truth.data(), point.data(), scene.focal_um, xy, d_eo,
                                       nullptr, nullptr));
      const double distance = (point - scene.truth.center_in_ground()).norm();
      for (int k = 0; k < 6; ++k) {
        const double scale = std::max(std::abs(d_eo[k]), ColumnScale(k, scene.focal_um, distance));
        EXPECT_LE(std::abs(row_u[k] - d_eo[k]) / scale, kSameFormulaRelativeTolerance)
            << kPartialNames[0][k];
        const double scale_v =
            std::max(std::abs(d_eo[6 + k]), ColumnScale(k, scene.focal_um, distance));
        EXPECT_LE(std::abs(row_v[k] - d_eo[6 + k]) / scale_v, kSameFormulaRelativeTolerance)
            << kPartialNames[1][k];
      }
    }
  }
}

TEST(TaylorPartials, PointBehindCameraIsRejected) {
  ExteriorOrientation eo;
  eo.set_center_in_ground(Eigen::Vector3d(0.0, 0.0, 100.0));
  double row_u[6], row_v[6], fu = 7.0, fv = 7.0;
  EXPECT_FALSE(TaylorPartialsForPoint(TaylorPartials::kCorrected, eo,
                                      Eigen::Vector3d(1.0, 2.0, 150.0), 1e5,
                                      Eigen::Vector2d::Zero(), row_u, row_v, &fu, &fv));
  EXPECT_FALSE(TaylorFunctions(eo, Eigen::Vector3d(1.0, 2.0, 100.0), 1e5, Eigen::Vector2d::Zero(),
                               &fu, &fv));
  EXPECT_EQ(fu, 7.0);
}

// ------------------------------------------------------------------ options and names

TEST(TaylorResectionOptions, Validation) {
  TaylorResectionOptions options;
  std::string why;
  EXPECT_TRUE(options.IsValid(&why));
  options.max_iterations = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("max_iterations"), std::string::npos);
  options = TaylorResectionOptions();
  options.position_tolerance_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(options.IsValid(nullptr));
  options = TaylorResectionOptions();
  options.angle_tolerance_rad = -1.0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_EQ(ParseEnum<TaylorPartials>("As-Printed"), TaylorPartials::kAsPrinted);
  EXPECT_EQ(ParseEnum<TaylorPartials>("corrected"), TaylorPartials::kCorrected);
  EXPECT_FALSE(ParseEnum<TaylorPartials>("autodiff").has_value());
  EXPECT_STREQ(EnumName(TaylorPartials::kAsPrinted), "as_printed");
  EXPECT_STREQ(EnumName(SolverTermination::kNoConvergence), "no_convergence");
}

// ------------------------------------------------------------------ Wolf & Dewitt textbook data

// README.txt beside the data: f = 152.916 mm, photo x right y up, principal point at 0.
constexpr double kWolfFocalMm = 152.916;

struct TextbookBlock {
  double focal_mm = kWolfFocalMm;
  std::vector<std::string> names;
  std::vector<Eigen::Vector2d> image_um;
  std::vector<Eigen::Vector3d> ground_m;
};

// The first block is the four-point book example; a line holding a single number (the focal length)
// starts the second block, Dewitt's resect.c sample. '#' lines are comments.
bool ParseWolfDewitt(const std::string& path, TextbookBlock* four, TextbookBlock* five) {
  std::ifstream in(path);
  if (!in) return false;
  TextbookBlock* block = four;
  std::string line;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::vector<std::string> tokens;
    for (std::string token; fields >> token;) tokens.push_back(token);
    if (tokens.size() == 1) {
      block = five;
      block->focal_mm = std::stod(tokens[0]);
    } else if (tokens.size() == 6) {
      block->names.push_back(tokens[0]);
      block->image_um.emplace_back(std::stod(tokens[1]) * 1e3, std::stod(tokens[2]) * 1e3);
      block->ground_m.emplace_back(std::stod(tokens[3]), std::stod(tokens[4]),
                                   std::stod(tokens[5]));
    } else {
      return false;
    }
  }
  return four->names.size() == 4 && five->names.size() == 5;
}

// A published answer: omega, phi, kappa in the opk convention (deg), XL, YL, ZL (m), s0 (mm).
struct TextbookAnswer {
  double omega_deg, phi_deg, kappa_deg, x_m, y_m, z_m, sigma0_mm;
};
constexpr TextbookAnswer kWolfFourPoints = {-0.4109,  1.2101,  102.8003, 1027.857,
                                            1044.114, 648.197, 0.0033};
constexpr TextbookAnswer kDewittFivePoints = {-0.4109,  1.2108,  102.8003, 1027.870,
                                              1044.114, 611.197, 0.0028};

// The answers are printed to 1e-4 deg, 1 mm and 0.1 um, so a correct solution can differ from them
// by half a unit of the last digit; the margin covers our own convergence (~1e-10).
constexpr double kPrintedAngleToleranceDeg = 0.5e-4 + 1e-8;  // 8.7e-7 rad
constexpr double kPrintedPositionToleranceM = 0.5e-3 + 1e-8;
constexpr double kPrintedSigma0ToleranceUm = 0.05 + 1e-8;

void ExpectMatchesTextbook(const TaylorResectionResult& result, const TextbookAnswer& answer) {
  const Eigen::Matrix3d R =
      RotationFromAngles(RotationConvention::kSeed, result.eo.angles_seed_rad());
  const Eigen::Vector3d opk_deg =
      AnglesFromRotation(RotationConvention::kOpk, R) * kDegreesPerRadian;
  EXPECT_NEAR(opk_deg[0], answer.omega_deg, kPrintedAngleToleranceDeg);
  EXPECT_NEAR(opk_deg[1], answer.phi_deg, kPrintedAngleToleranceDeg);
  EXPECT_NEAR(opk_deg[2], answer.kappa_deg, kPrintedAngleToleranceDeg);
  EXPECT_NEAR(result.eo.parameters[0], answer.x_m, kPrintedPositionToleranceM);
  EXPECT_NEAR(result.eo.parameters[1], answer.y_m, kPrintedPositionToleranceM);
  EXPECT_NEAR(result.eo.parameters[2], answer.z_m, kPrintedPositionToleranceM);
  EXPECT_NEAR(result.summary.sigma0, answer.sigma0_mm * 1e3, kPrintedSigma0ToleranceUm);
  std::printf("  opk %.6f %.6f %.6f deg, X0 %.5f %.5f %.5f m, sigma0 %.4f um, %d iterations\n",
              opk_deg[0], opk_deg[1], opk_deg[2], result.eo.parameters[0], result.eo.parameters[1],
              result.eo.parameters[2], result.summary.sigma0, result.summary.iterations);
}

class WolfDewittTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(
        ParseWolfDewitt(testing::SharedDataPath("textbook/wolf_dewitt.txt"), &four_, &five_));
    ASSERT_EQ(five_.focal_mm, kWolfFocalMm);
  }
  TextbookBlock four_, five_;
};

TEST_F(WolfDewittTest, FourPointsFromAutomaticVerticalGuess) {
  ExteriorOrientation initial;
  ASSERT_TRUE(
      ApproximateVerticalOrientation(four_.image_um, four_.ground_m, kWolfFocalMm * 1e3, &initial)
          .ok());
  TaylorResectionResult result;
  const Status status = TaylorResection(TaylorResectionOptions(), four_.image_um, four_.ground_m,
                                        {}, kWolfFocalMm * 1e3, initial, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_TRUE(result.summary.IsSolutionUsable());
  EXPECT_EQ(result.summary.degrees_of_freedom, 2);
  ExpectMatchesTextbook(result, kWolfFourPoints);
}

TEST_F(WolfDewittTest, FivePointResectSample) {
  ExteriorOrientation initial;
  ASSERT_TRUE(
      ApproximateVerticalOrientation(five_.image_um, five_.ground_m, five_.focal_mm * 1e3, &initial)
          .ok());
  TaylorResectionResult result;
  const Status status = TaylorResection(TaylorResectionOptions(), five_.image_um, five_.ground_m,
                                        {}, five_.focal_mm * 1e3, initial, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(result.summary.degrees_of_freedom, 4);
  ExpectMatchesTextbook(result, kDewittFivePoints);
}

// Poor start: the centre above the centroid of the points at c times the image-to-ground scale,
// all angles zero although the truth has kappa = 102.8 deg (seed kappa = -102.8 deg).
ExteriorOrientation PoorStart(const TextbookBlock& block) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector2d image_centroid = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < block.ground_m.size(); ++i) {
    centroid += block.ground_m[i];
    image_centroid += block.image_um[i];
  }
  centroid /= block.ground_m.size();
  image_centroid /= block.image_um.size();
  double ground_spread = 0.0, image_spread = 0.0;
  for (size_t i = 0; i < block.ground_m.size(); ++i) {
    ground_spread += (block.ground_m[i] - centroid).head<2>().norm();
    image_spread += (block.image_um[i] - image_centroid).norm();
  }
  ExteriorOrientation eo;
  eo.set_center_in_ground(
      centroid + Eigen::Vector3d(0.0, 0.0, block.focal_mm * 1e3 * ground_spread / image_spread));
  return eo;
}

TEST_F(WolfDewittTest, FourPointsFromPoorStartKappaZero) {
  TaylorResectionResult result;
  const Status status = TaylorResection(TaylorResectionOptions(), four_.image_um, four_.ground_m,
                                        {}, kWolfFocalMm * 1e3, PoorStart(four_), &result);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectMatchesTextbook(result, kWolfFourPoints);
}

// The basin of convergence from the vertical guess's centre: kappa offsets of up to +-110 deg from
// the truth converge (both variants); from +-120 deg on the iteration diverges (a point goes behind
// the camera or the camera runs away) and the solver fails cleanly. Measured with 10 deg steps, see
// docs/taylor_derivatives.md.
TEST_F(WolfDewittTest, KappaBasinOfConvergence) {
  const ExteriorOrientation poor = PoorStart(four_);
  const double truth_kappa_seed = DegreesToRadians(-102.8003);
  for (const TaylorPartials partials : {TaylorPartials::kCorrected, TaylorPartials::kAsPrinted}) {
    TaylorResectionOptions options;
    options.partials = partials;
    std::printf("  %-10s kappa offset (deg): iterations", EnumName(partials));
    for (int offset_deg = -180; offset_deg <= 180; offset_deg += 10) {
      ExteriorOrientation start = poor;
      start.parameters[5] = truth_kappa_seed + DegreesToRadians(offset_deg);
      TaylorResectionResult result;
      const Status status = TaylorResection(options, four_.image_um, four_.ground_m, {},
                                            kWolfFocalMm * 1e3, start, &result);
      if (std::abs(offset_deg) <= 110) {
        ASSERT_TRUE(status.ok()) << offset_deg << ": " << status.message();
        EXPECT_NEAR(result.eo.parameters[2], kWolfFourPoints.z_m, kPrintedPositionToleranceM);
        std::printf(" %d:%d", offset_deg, result.summary.iterations);
      } else {
        ASSERT_FALSE(status.ok()) << offset_deg;
        EXPECT_EQ(result.summary.termination_type, SolverTermination::kFailure);
        // Either a point goes behind the camera or the camera runs away: both are "diverged".
        EXPECT_NE(status.message().find("diverged"), std::string::npos) << status.message();
        EXPECT_TRUE(result.eo.parameters.array().isNaN().all());
      }
    }
    std::printf("\n");
  }
}

// Near-vertical textbook frame (omega = -0.41 deg): the misprint hardly matters; both variants
// reach the published answer, the as-printed one a little slower and not exactly at the minimum.
TEST_F(WolfDewittTest, AsPrintedVariantOnTextbookData) {
  ExteriorOrientation initial;
  ASSERT_TRUE(
      ApproximateVerticalOrientation(four_.image_um, four_.ground_m, kWolfFocalMm * 1e3, &initial)
          .ok());
  TaylorResectionOptions options;
  TaylorResectionResult corrected, printed;
  ASSERT_TRUE(TaylorResection(options, four_.image_um, four_.ground_m, {}, kWolfFocalMm * 1e3,
                              initial, &corrected)
                  .ok());
  options.partials = TaylorPartials::kAsPrinted;
  ASSERT_TRUE(TaylorResection(options, four_.image_um, four_.ground_m, {}, kWolfFocalMm * 1e3,
                              initial, &printed)
                  .ok());
  ExpectMatchesTextbook(printed, kWolfFourPoints);
  EXPECT_GE(printed.summary.iterations, corrected.summary.iterations);
  // The corrected solution is the least-squares minimum; the printed one can only cost more.
  EXPECT_GE(printed.summary.final_cost, corrected.summary.final_cost * (1.0 - 1e-12));
  std::printf(
      "  as printed - corrected: %.3e m, %.3e rad; iterations %d vs %d; sigma0 %.6f vs %.6f um\n",
      PositionError(printed.eo, corrected.eo), AngleError(printed.eo, corrected.eo),
      printed.summary.iterations, corrected.summary.iterations, printed.summary.sigma0,
      corrected.summary.sigma0);
}

// ------------------------------------------------------------------ synthetic scenes

Status Solve(TaylorPartials partials, const Scene& scene, const std::vector<Eigen::Vector2d>& image,
             const ExteriorOrientation& initial, TaylorResectionResult* result,
             const std::vector<double>& sigmas = {}) {
  TaylorResectionOptions options;
  options.partials = partials;
  return TaylorResection(options, image, scene.ground_m, sigmas, scene.focal_um, initial, result);
}

std::vector<Eigen::Vector2d> AddNoise(std::mt19937_64* rng,
                                      const std::vector<Eigen::Vector2d>& image, double sigma_um) {
  std::normal_distribution<double> noise(0.0, sigma_um);
  std::vector<Eigen::Vector2d> noisy = image;
  for (Eigen::Vector2d& p : noisy) p += DrawLastFirst<2>([&](int) { return noise(*rng); });
  return noisy;
}

// Asymptotic linear rate of the as-printed iteration at a noise-free solution: the spectral radius
// of the Jacobian of p -> p - (A~^T A~)^-1 A~^T F(p), i.e. of I - (A~^T A~)^-1 A~^T A, A~ the
// printed and A the true partials. 0 means quadratic convergence; >= 1 means the solution repels
// the iteration.
double AsPrintedRate(const Scene& scene) {
  Matrix6d printed_normal = Matrix6d::Zero(), mixed = Matrix6d::Zero();
  for (size_t i = 0; i < scene.ground_m.size(); ++i) {
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> A, printed;
    TaylorPartialsForPoint(TaylorPartials::kCorrected, scene.truth, scene.ground_m[i],
                           scene.focal_um, scene.image_um[i], A.data(), A.data() + 6, nullptr,
                           nullptr);
    TaylorPartialsForPoint(TaylorPartials::kAsPrinted, scene.truth, scene.ground_m[i],
                           scene.focal_um, scene.image_um[i], printed.data(), printed.data() + 6,
                           nullptr, nullptr);
    printed_normal += printed.transpose() * printed;
    mixed += printed.transpose() * A;
  }
  const Matrix6d J = Matrix6d::Identity() - printed_normal.inverse() * mixed;
  return J.eigenvalues().cwiseAbs().maxCoeff();
}

// The corrected variant converges quadratically: from 5 m / 3 deg, 5 corrections (measured; 6
// allowed).
constexpr int kCorrectedMaxIterations = 6;
// The as-printed variant converges linearly with rate rho; it stops after a correction below 1e-9
// m, leaving an error up to rho / (1 - rho) times that (measured <= 7e-10 m, 4e-13 rad for rho <=
// 0.56).
constexpr double kAsPrintedNoiseFreePositionTolerance = 5e-9;  // m
constexpr double kAsPrintedNoiseFreeAngleTolerance = 5e-12;    // rad

TEST(TaylorResectionSynthetic, NoiseFreePoseRecovered) {
  for (const bool oblique : {false, true}) {
    for (const int n : {6, 12, 50}) {
      for (const double start_deg : {3.0, 10.0}) {
        std::mt19937_64 rng(100 + n);
        const Scene scene = oblique ? ObliqueScene(&rng, n) : NadirScene(&rng, n);
        const ExteriorOrientation initial = Perturb(scene.truth, start_deg, start_deg);
        TaylorResectionResult corrected, printed;
        const Status status =
            Solve(TaylorPartials::kCorrected, scene, scene.image_um, initial, &corrected);
        ASSERT_TRUE(status.ok()) << status.message();
        EXPECT_LE(PositionError(corrected.eo, scene.truth), kNoiseFreePositionTolerance);
        EXPECT_LE(AngleError(corrected.eo, scene.truth), kNoiseFreeAngleTolerance);
        EXPECT_LE(corrected.summary.iterations,
                  kCorrectedMaxIterations + (start_deg > 5.0 ? 1 : 0));
        EXPECT_EQ(corrected.summary.degrees_of_freedom, 2 * n - 6);
        EXPECT_EQ(corrected.residuals_um.size(), static_cast<size_t>(n));
        for (const Eigen::Vector2d& v : corrected.residuals_um) EXPECT_LT(v.norm(), 1e-6);

        // The misprint moves neither the noise-free solution nor (in exact arithmetic) its fixed
        // point: F = 0 there whatever A is. It only slows the iteration down.
        const Status printed_status =
            Solve(TaylorPartials::kAsPrinted, scene, scene.image_um, initial, &printed);
        ASSERT_TRUE(printed_status.ok()) << printed_status.message();
        EXPECT_LE(PositionError(printed.eo, scene.truth), kAsPrintedNoiseFreePositionTolerance);
        EXPECT_LE(AngleError(printed.eo, scene.truth), kAsPrintedNoiseFreeAngleTolerance);
        const double rate = AsPrintedRate(scene);
        if (oblique) {
          // omega = 45 deg: measured rate 0.35-0.40, 25-29 corrections instead of 5.
          EXPECT_GT(rate, 0.2);
          EXPECT_GE(printed.summary.iterations, 3 * corrected.summary.iterations);
        } else {
          // omega = 0.7 deg: rate <= 0.01, one to three corrections more.
          EXPECT_LT(rate, 0.05);
          EXPECT_GE(printed.summary.iterations, corrected.summary.iterations);
          EXPECT_LE(printed.summary.iterations, corrected.summary.iterations + 4);
        }
        std::printf(
            "  %-7s n=%2d start %2.0f m/%2.0f deg: corrected %d it (%.1e m, %.1e rad), "
            "as printed %2d it (%.1e m, %.1e rad), rate %.3f\n",
            oblique ? "oblique" : "nadir", n, start_deg, start_deg, corrected.summary.iterations,
            PositionError(corrected.eo, scene.truth), AngleError(corrected.eo, scene.truth),
            printed.summary.iterations, PositionError(printed.eo, scene.truth),
            AngleError(printed.eo, scene.truth), rate);
      }
    }
  }
}

// How the misprint's damage grows with omega (the error of eq. 21 is (v - u) sin(omega)): one
// 12-point scene per omega, phi = 2 deg, kappa = -120 deg, noise-free, started 5 m / 3 deg off.
// Measured rates 0, 0.17, 0.55, 0.56, 0.48, 0.41 and 5, 15, 41, 42, 34, 29 corrections for omega =
// 0, 5, 15, 30, 45, 60 deg; the corrected variant needs 5 throughout.
TEST(TaylorResectionSynthetic, AsPrintedSlowdownVersusOmega) {
  for (const double omega_deg : {0.0, 5.0, 15.0, 30.0, 45.0, 60.0}) {
    std::mt19937_64 rng(91);
    const Scene scene = MakeScene(&rng, Eigen::Vector3d(500.0, 300.0, 800.0),
                                  Eigen::Vector3d(DegreesToRadians(omega_deg),
                                                  DegreesToRadians(2.0), DegreesToRadians(-120.0)),
                                  12, kFocalUm, kHalfFormatUm, 30.0);
    const ExteriorOrientation initial = Perturb(scene.truth, 5.0, 3.0);
    TaylorResectionResult corrected, printed;
    ASSERT_TRUE(Solve(TaylorPartials::kCorrected, scene, scene.image_um, initial, &corrected).ok());
    const Status status =
        Solve(TaylorPartials::kAsPrinted, scene, scene.image_um, initial, &printed);
    ASSERT_TRUE(status.ok()) << omega_deg << ": " << status.message();
    EXPECT_LE(PositionError(printed.eo, scene.truth), kAsPrintedNoiseFreePositionTolerance);
    const double rate = AsPrintedRate(scene);
    EXPECT_LE(corrected.summary.iterations, kCorrectedMaxIterations);
    if (omega_deg == 0.0) {
      EXPECT_LT(rate, 1e-9);
      EXPECT_EQ(printed.summary.iterations, corrected.summary.iterations);
    } else if (omega_deg >= 15.0) {
      EXPECT_GT(rate, 0.3);
      EXPECT_GE(printed.summary.iterations, 5 * corrected.summary.iterations);
    }
    std::printf("  omega %2.0f deg: as-printed rate %.3f, %2d corrections (corrected %d)\n",
                omega_deg, rate, printed.summary.iterations, corrected.summary.iterations);
  }
}

// Large map coordinates (UTM-like, 5e6 m) do not limit convergence: the solver works relative to
// the centroid. The truth itself is only representable to 9.3e-10 m at 5e6 m, hence 1e-8.
TEST(TaylorResectionSynthetic, LargeMapCoordinates) {
  std::mt19937_64 rng(3);
  Scene scene = ObliqueScene(&rng, 12);
  const Eigen::Vector3d offset(512345.678, 5412345.678, 250.0);
  for (Eigen::Vector3d& p : scene.ground_m) p += offset;
  scene.truth.parameters.head<3>() += offset;
  TaylorResectionResult result;
  const Status status = Solve(TaylorPartials::kCorrected, scene, scene.image_um,
                              Perturb(scene.truth, 5.0, 3.0), &result);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_LE(PositionError(result.eo, scene.truth), 1e-8);
  EXPECT_LE(AngleError(result.eo, scene.truth), kNoiseFreeAngleTolerance);
}

// 1 px (6 um) noise, 500 trials on one oblique scene: the corrected variant is the least-squares
// estimate and its covariance matches the scatter; the as-printed one converges to a different
// point (its fixed point solves A~^T P F = 0, not A^T P F = 0): no bias, but extra scatter and a
// higher cost.
TEST(TaylorResectionSynthetic, NoisyDataAsPrintedIsNotLeastSquares) {
  constexpr int kTrials = 500;
  for (const bool oblique : {false, true}) {
    std::mt19937_64 rng(312);
    const Scene scene = oblique ? ObliqueScene(&rng, 12) : NadirScene(&rng, 12);
    Vector6d sum_diff = Vector6d::Zero(), sq_diff = Vector6d::Zero(), sq_err = Vector6d::Zero(),
             sq_err_printed = Vector6d::Zero(), sum_err = Vector6d::Zero();
    Matrix6d sum_covariance = Matrix6d::Zero();
    double sum_sigma0 = 0.0, sum_sigma0_printed = 0.0;
    int iterations = 0, iterations_printed = 0;
    for (int trial = 0; trial < kTrials; ++trial) {
      const std::vector<Eigen::Vector2d> image = AddNoise(&rng, scene.image_um, kPixelUm);
      const ExteriorOrientation initial = Perturb(scene.truth, 5.0, 3.0);
      TaylorResectionResult corrected, printed;
      ASSERT_TRUE(Solve(TaylorPartials::kCorrected, scene, image, initial, &corrected).ok());
      ASSERT_TRUE(Solve(TaylorPartials::kAsPrinted, scene, image, initial, &printed).ok());
      // Least squares: no other pose has a lower cost.
      EXPECT_GE(printed.summary.final_cost, corrected.summary.final_cost * (1.0 - 1e-12));
      Vector6d err = corrected.eo.parameters - scene.truth.parameters;
      Vector6d err_printed = printed.eo.parameters - scene.truth.parameters;
      for (int k = 3; k < 6; ++k) {
        err[k] = WrapAngle(err[k]);
        err_printed[k] = WrapAngle(err_printed[k]);
      }
      const Vector6d diff = err_printed - err;
      sum_diff += diff;
      sq_diff += diff.cwiseAbs2();
      sum_err += err;
      sq_err += err.cwiseAbs2();
      sq_err_printed += err_printed.cwiseAbs2();
      sum_covariance += corrected.covariance;
      sum_sigma0 += corrected.summary.sigma0;
      sum_sigma0_printed += printed.summary.sigma0;
      iterations += corrected.summary.iterations;
      iterations_printed += printed.summary.iterations;
    }
    const Vector6d rms_diff = (sq_diff / kTrials).cwiseSqrt();
    const Vector6d rms_err = (sq_err / kTrials).cwiseSqrt();
    const Vector6d rms_err_printed = (sq_err_printed / kTrials).cwiseSqrt();
    const Vector6d mean_diff = sum_diff / kTrials;
    const Vector6d predicted = (sum_covariance / kTrials).diagonal().cwiseSqrt();
    for (int k = 0; k < 6; ++k) {
      // No bias: the mean difference is within 4 standard errors of zero.
      EXPECT_LT(std::abs(mean_diff[k]), 4.0 * rms_diff[k] / std::sqrt(double(kTrials))) << k;
      // The covariance sigma0^2 (A^T P A)^-1 predicts the scatter; 500 trials estimate an RMS to
      // ~3 %, the remainder is non-linearity (measured ratios 0.95-1.04).
      EXPECT_GT(rms_err[k] / predicted[k], 0.85) << k;
      EXPECT_LT(rms_err[k] / predicted[k], 1.18) << k;
    }
    // Extra scatter: at omega = 45 deg the printed solution is off the least-squares one by ~25 %
    // of the least-squares error in X0, Y0 and phi (measured 0.26-0.30); at 0.7 deg by ~3 %.
    const double relative_phi = rms_diff[4] / rms_err[4];
    const double relative_x = rms_diff[0] / rms_err[0];
    if (oblique) {
      EXPECT_GT(relative_phi, 0.15);
      EXPECT_GT(relative_x, 0.15);
    } else {
      EXPECT_GT(relative_phi, 0.01);
      EXPECT_LT(relative_phi, 0.1);
    }
    EXPECT_GE(sum_sigma0_printed, sum_sigma0);
    const Vector6d unit = (Vector6d() << 1e3, 1e3, 1e3, 1e6, 1e6, 1e6).finished();  // mm, urad
    auto print = [&](const char* name, const Vector6d& v) {
      const Vector6d x = v.cwiseProduct(unit);
      std::printf("    %-26s %8.2f %8.2f %8.2f mm %8.2f %8.2f %8.2f urad\n", name, x[0], x[1], x[2],
                  x[3], x[4], x[5]);
    };
    std::printf(
        "  %s n=12, 1 px noise, %d trials: iterations %.2f (corrected) / %.2f (as printed), "
        "mean sigma0 %.4f / %.4f um, rate %.3f\n",
        oblique ? "oblique" : "nadir", kTrials, double(iterations) / kTrials,
        double(iterations_printed) / kTrials, sum_sigma0 / kTrials, sum_sigma0_printed / kTrials,
        AsPrintedRate(scene));
    print("RMS error, corrected", rms_err);
    print("sqrt(mean covariance)", predicted);
    print("RMS error, as printed", rms_err_printed);
    print("RMS(printed - corrected)", rms_diff);
    print("mean(printed - corrected)", mean_diff);
    print("mean error, corrected", sum_err / kTrials);
  }
}

// Random poses with omega, phi in +-60 deg and kappa anywhere, noise-free, started 5 m / 3 deg off:
// the corrected variant always converges in a few iterations. For some poses the true solution
// repels the as-printed iteration (rate >= 1); it then does not converge, or worse, stops at a
// spurious fixed point (A~^T F = 0 with F != 0) and reports converged at a wrong pose,
// recognisable only by its sigma0. Measured over these 1000 poses: rate >= 1 for 25, no convergence
// in 50 iterations for 65, one spurious "convergence" 85 m off with sigma0 = 1101 um.
TEST(TaylorResectionSynthetic, RandomObliquePosesAsPrintedSometimesFails) {
  constexpr int kPoses = 1000;
  // A spurious fixed point leaves residuals of hundreds of um on noise-free data.
  constexpr double kSpuriousMinSigma0Um = 100.0;
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> tilt(-60.0, 60.0), kappa(-180.0, 180.0);
  std::vector<double> rates;
  std::vector<int> printed_iterations;
  int corrected_max_iterations = 0, printed_not_converged = 0, printed_failed = 0,
      printed_spurious = 0;
  for (int pose = 0; pose < kPoses; ++pose) {
    const Eigen::Vector3d angles =
        DrawLastFirst<3>([&](int i) { return DegreesToRadians(i == 2 ? kappa(rng) : tilt(rng)); });
    const Scene scene = MakeScene(&rng, Eigen::Vector3d(500.0, 300.0, 800.0), angles, 12, kFocalUm,
                                  kHalfFormatUm, 30.0);
    rates.push_back(AsPrintedRate(scene));
    const ExteriorOrientation initial = Perturb(scene.truth, 5.0, 3.0);
    TaylorResectionResult corrected, printed;
    const Status status =
        Solve(TaylorPartials::kCorrected, scene, scene.image_um, initial, &corrected);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_LE(PositionError(corrected.eo, scene.truth), kNoiseFreePositionTolerance);
    corrected_max_iterations = std::max(corrected_max_iterations, corrected.summary.iterations);
    if (Solve(TaylorPartials::kAsPrinted, scene, scene.image_um, initial, &printed).ok()) {
      if (PositionError(printed.eo, scene.truth) <= kAsPrintedNoiseFreePositionTolerance) {
        printed_iterations.push_back(printed.summary.iterations);
        continue;
      }
      ++printed_spurious;
      EXPECT_GT(printed.summary.sigma0, kSpuriousMinSigma0Um);
      EXPECT_GT(rates.back(), 1.0);
      std::printf(
          "  spurious as-printed fixed point: seed angles (%.2f, %.2f, %.2f) deg, rate %.3f, "
          "%d iterations, %.1f m / %.2f deg off, sigma0 %.1f um\n",
          angles[0] * kDegreesPerRadian, angles[1] * kDegreesPerRadian,
          angles[2] * kDegreesPerRadian, rates.back(), printed.summary.iterations,
          PositionError(printed.eo, scene.truth),
          AngleError(printed.eo, scene.truth) * kDegreesPerRadian, printed.summary.sigma0);
      // The corrected partials leave the spurious point at once.
      TaylorResectionResult rescued;
      ASSERT_TRUE(
          Solve(TaylorPartials::kCorrected, scene, scene.image_um, printed.eo, &rescued).ok());
      EXPECT_LE(PositionError(rescued.eo, scene.truth), kNoiseFreePositionTolerance);
    } else if (printed.summary.termination_type == SolverTermination::kNoConvergence) {
      ++printed_not_converged;
    } else {
      ++printed_failed;
    }
  }
  std::sort(rates.begin(), rates.end());
  std::sort(printed_iterations.begin(), printed_iterations.end());
  const int repelled = static_cast<int>(
      std::count_if(rates.begin(), rates.end(), [](double r) { return r >= 1.0; }));
  EXPECT_LE(corrected_max_iterations, kCorrectedMaxIterations);
  EXPECT_GE(repelled, kPoses / 100);
  const int printed_bad = printed_not_converged + printed_failed + printed_spurious;
  EXPECT_GE(printed_bad, kPoses / 50);
  EXPECT_GE(printed_bad, repelled);
  std::printf(
      "  %d random poses: corrected <= %d iterations; as printed: rate median %.3f, 90 %% %.3f, "
      "99 %% %.3f, max %.3f, rate >= 1 in %d; converged %zu (median %d, 90 %% %d, max %d "
      "iterations), no convergence %d, failure %d, spurious convergence %d\n",
      kPoses, corrected_max_iterations, rates[kPoses / 2], rates[kPoses * 9 / 10],
      rates[kPoses * 99 / 100], rates.back(), repelled, printed_iterations.size(),
      printed_iterations[printed_iterations.size() / 2],
      printed_iterations[printed_iterations.size() * 9 / 10], printed_iterations.back(),
      printed_not_converged, printed_failed, printed_spurious);
}

// Weights: scaling every sigma leaves the pose unchanged and scales sigma0; with the true sigma,
// sigma0 estimates 1 (dof 94: its own standard deviation is ~7 %). The covariance follows
// PoseCovarianceFactor: sigma0^2 (A^T A)^-1 with unit weights, the a-priori (A^T P A)^-1 with
// stated sigmas, so the two differ by the stated sigmas' sigma0^2.
TEST(TaylorResectionSynthetic, WeightsAndSigma0) {
  std::mt19937_64 rng(8);
  const Scene scene = NadirScene(&rng, 50);
  const std::vector<Eigen::Vector2d> image = AddNoise(&rng, scene.image_um, kPixelUm);
  const ExteriorOrientation initial = Perturb(scene.truth, 5.0, 3.0);
  TaylorResectionResult unit, weighted;
  ASSERT_TRUE(Solve(TaylorPartials::kCorrected, scene, image, initial, &unit).ok());
  ASSERT_TRUE(Solve(TaylorPartials::kCorrected, scene, image, initial, &weighted,
                    std::vector<double>(50, kPixelUm))
                  .ok());
  EXPECT_LE(PositionError(unit.eo, weighted.eo), 1e-9);
  EXPECT_NEAR(weighted.summary.sigma0, unit.summary.sigma0 / kPixelUm, 1e-9);
  EXPECT_NEAR(weighted.summary.sigma0, 1.0, 0.3);
  const double s0_squared = weighted.summary.sigma0 * weighted.summary.sigma0;
  EXPECT_GT(std::abs(s0_squared - 1.0), 1e-3);  // the two rules differ on this noise
  EXPECT_LE((s0_squared * weighted.covariance - unit.covariance).cwiseAbs().maxCoeff(),
            1e-9 * unit.covariance.cwiseAbs().maxCoeff());
  // The covariance is symmetric positive definite.
  EXPECT_LE((unit.covariance - unit.covariance.transpose()).cwiseAbs().maxCoeff(),
            1e-12 * unit.covariance.cwiseAbs().maxCoeff());
  EXPECT_EQ(Eigen::LLT<Matrix6d>(unit.covariance).info(), Eigen::Success);

  // A gross error on one point, down-weighted by a large sigma, hardly moves the pose.
  std::vector<Eigen::Vector2d> blunder = image;
  blunder[7] += Eigen::Vector2d(300.0, -200.0);
  std::vector<double> sigmas(50, kPixelUm);
  sigmas[7] = 1e5;
  TaylorResectionResult robust;
  ASSERT_TRUE(Solve(TaylorPartials::kCorrected, scene, blunder, initial, &robust, sigmas).ok());
  EXPECT_LE(PositionError(robust.eo, unit.eo), 0.05 * std::sqrt(unit.covariance(0, 0)));
  // Residuals are observed minus computed.
  double xy[2];
  ASSERT_TRUE(ProjectToImagePlane(unit.eo.data(), scene.ground_m[3].data(), kFocalUm, xy));
  EXPECT_NEAR(unit.residuals_um[3].x(), image[3].x() - xy[0], 1e-9);
  EXPECT_NEAR(unit.residuals_um[3].y(), image[3].y() - xy[1], 1e-9);
}

// Three points: zero redundancy, sigma0 is NaN and the covariance is the a-priori (A^T P A)^-1.
TEST(TaylorResectionSynthetic, ThreePointsZeroRedundancy) {
  std::mt19937_64 rng(21);
  const Scene scene = NadirScene(&rng, 3);
  TaylorResectionResult result;
  const Status status = Solve(TaylorPartials::kCorrected, scene, scene.image_um,
                              Perturb(scene.truth, 2.0, 1.0), &result);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_TRUE(result.summary.IsSolutionUsable());
  EXPECT_EQ(result.summary.degrees_of_freedom, 0);
  EXPECT_TRUE(std::isnan(result.summary.sigma0));
  EXPECT_TRUE(result.covariance.allFinite());
  EXPECT_LE(PositionError(result.eo, scene.truth), kNoiseFreePositionTolerance);
}

TEST(TaylorResectionSynthetic, VerticalGuessIsCloseForNadirFrames) {
  std::mt19937_64 rng(17);
  const Scene scene = NadirScene(&rng, 20);
  ExteriorOrientation guess;
  ASSERT_TRUE(
      ApproximateVerticalOrientation(scene.image_um, scene.ground_m, kFocalUm, &guess).ok());
  std::printf("  vertical guess: %.2f m, %.3f deg off\n", PositionError(guess, scene.truth),
              AngleError(guess, scene.truth) * kDegreesPerRadian);
  // The guess ignores omega = 0.7 deg and phi = -1.1 deg: 1.1 deg of tilt at 800 m moves the ground
  // nadir by ~15 m, so it is off by tens of metres and about the tilt (measured 18.8 m, 1.10 deg),
  // well inside the basin of convergence.
  EXPECT_LE(PositionError(guess, scene.truth), 30.0);
  EXPECT_LE(AngleError(guess, scene.truth), DegreesToRadians(2.0));
  EXPECT_FALSE(
      ApproximateVerticalOrientation({scene.image_um[0]}, {scene.ground_m[0]}, kFocalUm, &guess)
          .ok());
  EXPECT_FALSE(ApproximateVerticalOrientation(scene.image_um, scene.ground_m, -1.0, &guess).ok());
}

// ------------------------------------------------------------------ failures

class TaylorResectionFailureTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(29);
    scene_ = NadirScene(&rng, 8);
    initial_ = Perturb(scene_.truth, 5.0, 3.0);
  }
  // Runs and checks that the failure is clean: an error, a summary saying why, no pose.
  std::string ExpectFailure(const std::vector<Eigen::Vector2d>& image,
                            const std::vector<Eigen::Vector3d>& ground,
                            const std::vector<double>& sigmas, double focal,
                            const ExteriorOrientation& initial,
                            const TaylorResectionOptions& options = TaylorResectionOptions(),
                            SolverTermination type = SolverTermination::kFailure) {
    TaylorResectionResult result;
    const Status status = TaylorResection(options, image, ground, sigmas, focal, initial, &result);
    EXPECT_FALSE(status.ok());
    EXPECT_EQ(result.summary.termination_type, type);
    EXPECT_FALSE(result.summary.IsSolutionUsable());
    EXPECT_EQ(result.summary.message, status.message());
    EXPECT_TRUE(result.eo.parameters.array().isNaN().all());
    EXPECT_TRUE(result.covariance.array().isNaN().all());
    EXPECT_TRUE(result.residuals_um.empty());
    return status.message();
  }
  Scene scene_;
  ExteriorOrientation initial_;
};

TEST_F(TaylorResectionFailureTest, TwoPoints) {
  const std::vector<Eigen::Vector2d> image(scene_.image_um.begin(), scene_.image_um.begin() + 2);
  const std::vector<Eigen::Vector3d> ground(scene_.ground_m.begin(), scene_.ground_m.begin() + 2);
  EXPECT_NE(ExpectFailure(image, ground, {}, kFocalUm, initial_).find("at least 3 points"),
            std::string::npos);
}

TEST_F(TaylorResectionFailureTest, CollinearPoints) {
  // Five points on a sloping line, exactly and with 1e-9 m jitter (far below the 1e-6 tolerance).
  std::vector<Eigen::Vector3d> ground;
  std::vector<Eigen::Vector2d> image;
  for (int i = 0; i < 5; ++i) {
    Eigen::Vector3d p(400.0 + 50.0 * i, 250.0 + 20.0 * i, 3.0 * i);
    if (i == 2) p.y() += 1e-9;
    double xy[2];
    ASSERT_TRUE(ProjectToImagePlane(scene_.truth.data(), p.data(), kFocalUm, xy));
    ground.push_back(p);
    image.emplace_back(xy[0], xy[1]);
  }
  EXPECT_NE(ExpectFailure(image, ground, {}, kFocalUm, initial_).find("collinear"),
            std::string::npos);
  // Coincident points are a degenerate line too.
  const std::vector<Eigen::Vector3d> same(4, scene_.ground_m[0]);
  const std::vector<Eigen::Vector2d> same_image(4, scene_.image_um[0]);
  EXPECT_NE(ExpectFailure(same_image, same, {}, kFocalUm, initial_).find("collinear"),
            std::string::npos);
}

TEST_F(TaylorResectionFailureTest, PointBehindCameraAtStart) {
  std::vector<Eigen::Vector3d> ground = scene_.ground_m;
  ground[4].z() = 2000.0;  // above the camera at 800 m
  const std::string message = ExpectFailure(scene_.image_um, ground, {}, kFocalUm, initial_);
  // The whole sentence: the point, where, and its w (positive: in front is w < 0).
  EXPECT_TRUE(std::regex_match(
      message, std::regex(R"(point 4 is not in front of the camera at the initial orientation \(w = [0-9.e+]+ m\))")))
      << message;
}

TEST_F(TaylorResectionFailureTest, PointBehindCameraDuringIteration) {
  // A start rotated by 180 deg in kappa: the iteration throws the camera below the points.
  ExteriorOrientation start = scene_.truth;
  start.parameters[5] += kPi;
  const std::string message = ExpectFailure(scene_.image_um, scene_.ground_m, {}, kFocalUm, start);
  EXPECT_TRUE(std::regex_match(
      message, std::regex(R"(point [0-9]+ went behind the camera at iteration [1-9][0-9]* \(w = [0-9.e+-]+ m\): diverged)")))
      << message;
}

TEST_F(TaylorResectionFailureTest, NonFiniteInput) {
  std::vector<Eigen::Vector2d> image = scene_.image_um;
  image[2].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(ExpectFailure(image, scene_.ground_m, {}, kFocalUm, initial_).find("not finite"),
            std::string::npos);
  std::vector<Eigen::Vector3d> ground = scene_.ground_m;
  ground[1].z() = std::numeric_limits<double>::infinity();
  EXPECT_NE(ExpectFailure(scene_.image_um, ground, {}, kFocalUm, initial_).find("not finite"),
            std::string::npos);
  ExteriorOrientation bad = initial_;
  bad.parameters[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(ExpectFailure(scene_.image_um, scene_.ground_m, {}, kFocalUm, bad).find("not finite"),
            std::string::npos);
  ExpectFailure(scene_.image_um, scene_.ground_m, {}, std::numeric_limits<double>::quiet_NaN(),
                initial_);
}

TEST_F(TaylorResectionFailureTest, InvalidArguments) {
  ExpectFailure(scene_.image_um, scene_.ground_m, {}, 0.0, initial_);
  ExpectFailure(scene_.image_um, scene_.ground_m, {1.0, 2.0}, kFocalUm, initial_);
  std::vector<double> sigmas(scene_.ground_m.size(), 1.0);
  sigmas[3] = 0.0;
  ExpectFailure(scene_.image_um, scene_.ground_m, sigmas, kFocalUm, initial_);
  const std::vector<Eigen::Vector2d> short_image(scene_.image_um.begin(),
                                                 scene_.image_um.end() - 1);
  ExpectFailure(short_image, scene_.ground_m, {}, kFocalUm, initial_);
  TaylorResectionOptions options;
  options.max_iterations = -3;
  EXPECT_NE(ExpectFailure(scene_.image_um, scene_.ground_m, {}, kFocalUm, initial_, options)
                .find("invalid options"),
            std::string::npos);
}

TEST_F(TaylorResectionFailureTest, NoConvergenceWithinMaxIterations) {
  TaylorResectionOptions options;
  options.max_iterations = 2;
  const std::string message =
      ExpectFailure(scene_.image_um, scene_.ground_m, {}, kFocalUm, initial_, options,
                    SolverTermination::kNoConvergence);
  EXPECT_NE(message.find("no convergence in 2 iterations"), std::string::npos) << message;
}

// Three points on a circle with the camera straight above one of them: the camera is on the
// "danger cylinder" through the points, where the Jacobian loses rank.
TEST_F(TaylorResectionFailureTest, SingularNormalMatrixOnDangerCylinder) {
  ExteriorOrientation truth;
  truth.set_center_in_ground(Eigen::Vector3d(300.0, 0.0, 900.0));
  std::vector<Eigen::Vector3d> ground;
  std::vector<Eigen::Vector2d> image;
  for (int i = 0; i < 3; ++i) {
    const double a = 2.0 * kPi * i / 3.0;
    ground.emplace_back(300.0 * std::cos(a), 300.0 * std::sin(a), 0.0);
    double xy[2];
    ASSERT_TRUE(ProjectToImagePlane(truth.data(), ground.back().data(), kFocalUm, xy));
    image.emplace_back(xy[0], xy[1]);
  }
  const std::string message = ExpectFailure(image, ground, {}, kFocalUm, truth);
  EXPECT_NE(message.find("ill-conditioned"), std::string::npos) << message;
}

// ------------------------------------------------------------------ timing

// Not a benchmark; prints the time of a clean 50-point resection (docs quote it) and guards only
// against a gross regression in optimised builds.

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
