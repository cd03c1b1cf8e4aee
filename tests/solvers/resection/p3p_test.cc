#include "solvers/resection/p3p.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/rotation.h"
#include "core/types.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ tolerances
// The brief's accuracy for noise-free data: rotation (Frobenius norm of the difference) and centre
// (relative to the scene scale, the camera-to-point distance). Lambda Twist with Newton-polished
// depths reaches ~1e-13 typically; rare triangles close to the "danger cylinder" (two nearly
// coincident solutions, where the depths are ill-conditioned) lose a few digits, about one case in
// 1e5 of the distribution below exceeds 1e-9.
constexpr double kRotationTolerance = 1e-9;
constexpr double kRelativeCenterTolerance = 1e-9;
// Every returned solution must satisfy the three observations: angle (rad) between a bearing and
// the camera-frame direction of its point. Spurious roots would be off by far more.
constexpr double kBearingAngleTolerance = 1e-8;
// A returned rotation must be orthonormal with determinant +1 to rounding.
constexpr double kOrthonormalityTolerance = 1e-12;

constexpr int kRandomCases = 3000;

struct Case {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 3> bearings;
  std::array<Eigen::Vector3d, 3> points;
  double scale = 1.0;  // typical camera-to-point distance (m)
};

// A random pose with omega, phi up to +-60 deg (oblique) and kappa over the full circle, a centre
// anywhere in a 2 km square at 300-1500 m, and three points in front of the camera inside a
// +-40 deg cone around the optical axis (-w) at 0.5-1.5x the flying height.
Case RandomCase(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(*rng); };
  Case c;
  const Eigen::Vector3d angles(DegreesToRadians(uniform(-60, 60)),
                               DegreesToRadians(uniform(-60, 60)), uniform(-kPi, kPi));
  c.R = RotationFromAngles(RotationConvention::kSeed, angles);
  const double height = uniform(300, 1500);
  c.center = Eigen::Vector3d(uniform(-1000, 1000), uniform(-1000, 1000), height);
  c.scale = height;
  const double tan_cone = std::tan(DegreesToRadians(40.0));
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d direction =
        Eigen::Vector3d(uniform(-tan_cone, tan_cone), uniform(-tan_cone, tan_cone), -1.0)
            .normalized();
    const double depth = height * uniform(0.5, 1.5);
    c.bearings[i] = direction;
    c.points[i] = c.center + c.R.transpose() * (depth * direction);
  }
  return c;
}

double BestMatch(const Case& c, const std::vector<PoseCandidate>& solutions, double* rotation_error,
                 double* center_error) {
  double best = std::numeric_limits<double>::infinity();
  for (const PoseCandidate& s : solutions) {
    const double dr = (s.R_camera_from_ground - c.R).norm();
    const double dc = (s.center_in_ground - c.center).norm() / c.scale;
    if (std::max(dr, dc) < best) {
      best = std::max(dr, dc);
      *rotation_error = dr;
      *center_error = dc;
    }
  }
  return best;
}

void ExpectConsistent(const Case& c, const PoseCandidate& s) {
  const Eigen::Matrix3d& R = s.R_camera_from_ground;
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), kOrthonormalityTolerance);
  EXPECT_NEAR(R.determinant(), 1.0, kOrthonormalityTolerance);
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d direction = (R * (c.points[i] - s.center_in_ground)).normalized();
    const double angle = std::atan2(direction.cross(c.bearings[i].normalized()).norm(),
                                    direction.dot(c.bearings[i].normalized()));
    EXPECT_LT(angle, kBearingAngleTolerance) << "point " << i;
  }
}

// ------------------------------------------------------------------ tests

TEST(P3PTest, HandComputedIdentityPose) {
  // Camera at the origin with R = I looking down -w at a triangle 10-12 m away: the bearings are
  // the points themselves, normalised. The true pose must be among the solutions. (The triangle is
  // chosen off the "danger cylinder": a right triangle with the camera above its right-angle
  // corner would put the centre on the cylinder through the points, where two solutions merge
  // into a double root that no P3P solver resolves better than sqrt(machine epsilon).)
  Case c;
  c.points = {Eigen::Vector3d(1, 0, -10), Eigen::Vector3d(-1, 1, -11), Eigen::Vector3d(0, -2, -12)};
  for (int i = 0; i < 3; ++i) c.bearings[i] = c.points[i].normalized();
  c.scale = 10.0;
  std::vector<PoseCandidate> solutions;
  const int n = SolveP3P(c.bearings, c.points, &solutions);
  ASSERT_GE(n, 1);
  ASSERT_LE(n, 4);
  ASSERT_EQ(static_cast<int>(solutions.size()), n);
  double dr = 0, dc = 0;
  EXPECT_LT(BestMatch(c, solutions, &dr, &dc), kRotationTolerance);
  for (const PoseCandidate& s : solutions) ExpectConsistent(c, s);
}

TEST(P3PTest, RandomPosesIncludingObliqueAndFullKappa) {
  std::mt19937_64 rng(20240601);
  double worst = 0.0;
  int counts[5] = {0, 0, 0, 0, 0};
  for (int k = 0; k < kRandomCases; ++k) {
    const Case c = RandomCase(&rng);
    std::vector<PoseCandidate> solutions;
    const int n = SolveP3P(c.bearings, c.points, &solutions);
    ASSERT_GE(n, 1) << "case " << k;
    ASSERT_LE(n, 4) << "case " << k;
    ASSERT_EQ(static_cast<int>(solutions.size()), n);
    ++counts[n];
    double dr = 0, dc = 0;
    const double error = BestMatch(c, solutions, &dr, &dc);
    EXPECT_LT(dr, kRotationTolerance) << "case " << k;
    EXPECT_LT(dc, kRelativeCenterTolerance) << "case " << k;
    worst = std::max(worst, error);
    for (const PoseCandidate& s : solutions) ExpectConsistent(c, s);
  }
  std::printf("[ P3P ] worst matching error %.2e; solutions 1/2/3/4: %d/%d/%d/%d\n", worst,
              counts[1], counts[2], counts[3], counts[4]);
}

TEST(P3PTest, AcceptsUnnormalisedBearingsAndAppends) {
  std::mt19937_64 rng(7);
  Case c = RandomCase(&rng);
  std::vector<PoseCandidate> reference;
  const int n = SolveP3P(c.bearings, c.points, &reference);
  ASSERT_GE(n, 1);

  // Positive multiples of the bearings give the same poses.
  std::array<Eigen::Vector3d, 3> scaled = c.bearings;
  scaled[0] *= 3.0;
  scaled[1] *= 0.01;
  scaled[2] *= 250.0;
  // Existing entries are kept; the new ones are appended.
  std::vector<PoseCandidate> solutions(2);
  const int m = SolveP3P(scaled, c.points, &solutions);
  ASSERT_EQ(m, n);
  ASSERT_EQ(static_cast<int>(solutions.size()), 2 + n);
  EXPECT_TRUE(solutions[0].R_camera_from_ground.isIdentity());
  for (int i = 0; i < n; ++i) {
    EXPECT_LT((solutions[2 + i].R_camera_from_ground - reference[i].R_camera_from_ground).norm(),
              kRotationTolerance);
    EXPECT_LT((solutions[2 + i].center_in_ground - reference[i].center_in_ground).norm() / c.scale,
              kRelativeCenterTolerance);
  }
}

TEST(P3PTest, LargeGroundCoordinates) {
  // Projected coordinates (UTM-like) must not cost accuracy: only differences of points enter.
  std::mt19937_64 rng(11);
  const Eigen::Vector3d offset(500000.0, 4100000.0, 0.0);
  for (int k = 0; k < 200; ++k) {
    Case c = RandomCase(&rng);
    c.center += offset;
    for (Eigen::Vector3d& p : c.points) p += offset;
    std::vector<PoseCandidate> solutions;
    ASSERT_GE(SolveP3P(c.bearings, c.points, &solutions), 1);
    double dr = 0, dc = 0;
    BestMatch(c, solutions, &dr, &dc);
    // Coordinates of 4e6 m carry rounding of ~1e-9 m; relative to the scene scale well below.
    EXPECT_LT(dr, kRotationTolerance) << "case " << k;
    EXPECT_LT(dc, kRelativeCenterTolerance) << "case " << k;
  }
}

TEST(P3PTest, DegenerateInputsReturnZero) {
  std::mt19937_64 rng(3);
  const Case c = RandomCase(&rng);
  std::vector<PoseCandidate> solutions;

  // Collinear points (the third on the line through the first two).
  std::array<Eigen::Vector3d, 3> collinear = c.points;
  collinear[2] = c.points[0] + 2.5 * (c.points[1] - c.points[0]);
  EXPECT_EQ(SolveP3P(c.bearings, collinear, &solutions), 0);

  // Coincident points.
  std::array<Eigen::Vector3d, 3> coincident = c.points;
  coincident[1] = coincident[0];
  EXPECT_EQ(SolveP3P(c.bearings, coincident, &solutions), 0);

  // A zero bearing and a non-finite one.
  std::array<Eigen::Vector3d, 3> zero = c.bearings;
  zero[1].setZero();
  EXPECT_EQ(SolveP3P(zero, c.points, &solutions), 0);
  std::array<Eigen::Vector3d, 3> nan = c.bearings;
  nan[2].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(SolveP3P(nan, c.points, &solutions), 0);
  std::array<Eigen::Vector3d, 3> nan_point = c.points;
  nan_point[0].z() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(SolveP3P(c.bearings, nan_point, &solutions), 0);

  EXPECT_TRUE(solutions.empty());
}

TEST(P3PTest, IdenticalBearingsReturnZero) {
  // Points at three depths along one ray are collinear in the camera frame, so they cannot match a
  // proper ground triangle: nothing may be returned.
  std::mt19937_64 rng(5);
  Case c = RandomCase(&rng);
  c.bearings = {c.bearings[0], c.bearings[0], c.bearings[0]};
  std::vector<PoseCandidate> solutions;
  EXPECT_EQ(SolveP3P(c.bearings, c.points, &solutions), 0);
  EXPECT_TRUE(solutions.empty());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
