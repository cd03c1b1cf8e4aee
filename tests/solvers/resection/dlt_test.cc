#include "solvers/resection/dlt.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/rotation.h"
#include "core/types.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ tolerances
// The brief's accuracy for noise-free data: rotation (Frobenius norm of the difference) and centre
// (relative to the scene scale). The SVD of the Hartley-normalised system loses about
// cond(A) * 1e-16 ~ 1e-13 here; the re-solved translation adds nothing worse.
constexpr double kRotationTolerance = 1e-8;
constexpr double kRelativeCenterTolerance = 1e-8;
// With noise the DLT is only an initial value: 0.5 px of a 100 mm / 6 um aerial camera gives
// pose errors of order 1e-4 rad and 1e-4 of the scene scale; 1e-2 only checks that it is sane.
constexpr double kNoisyTolerance = 1e-2;

struct Scene {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> bearings;
  std::vector<Eigen::Vector3d> points;
  double scale = 1.0;  // flying height (m)
};

// A random pose (omega, phi up to +-60 deg, kappa full circle) and n points in front of it inside a
// +-40 deg cone at 0.6-1.4x the flying height: a genuinely three-dimensional cloud.
Scene RandomScene(std::mt19937_64* rng, int n) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(*rng); };
  Scene s;
  s.R = RotationFromAngles(RotationConvention::kSeed,
                           Eigen::Vector3d(DegreesToRadians(uniform(-60, 60)),
                                           DegreesToRadians(uniform(-60, 60)), uniform(-kPi, kPi)));
  const double height = uniform(200, 1200);
  s.scale = height;
  s.center = Eigen::Vector3d(uniform(-500, 500), uniform(-500, 500), height);
  const double t = std::tan(DegreesToRadians(40.0));
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d direction =
        Eigen::Vector3d(uniform(-t, t), uniform(-t, t), -1.0).normalized();
    s.bearings.push_back(direction);
    s.points.push_back(s.center + s.R.transpose() * (height * uniform(0.6, 1.4) * direction));
  }
  return s;
}

void ExpectPose(const Scene& s, const PoseCandidate& pose, double tolerance) {
  EXPECT_LT((pose.R_camera_from_ground - s.R).norm(), tolerance);
  EXPECT_LT((pose.center_in_ground - s.center).norm() / s.scale, tolerance);
  EXPECT_NEAR(pose.R_camera_from_ground.determinant(), 1.0, 1e-12);
}

// ------------------------------------------------------------------ tests

TEST(DltTest, HandComputedIdentityPose) {
  // Camera at the origin, R = I, looking down -w at the corners of a box 10-12 m away.
  Scene s;
  s.scale = 10.0;
  for (double x : {-1.0, 1.0})
    for (double y : {-1.0, 1.0})
      for (double z : {-10.0, -12.0}) s.points.emplace_back(x, y, z);
  for (const Eigen::Vector3d& p : s.points) s.bearings.push_back(p.normalized());
  PoseCandidate pose;
  const Status status = SolveDlt(s.bearings, s.points, &pose);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectPose(s, pose, kRotationTolerance);
}

TEST(DltTest, RandomNoiseFreePoses) {
  std::mt19937_64 rng(42);
  for (int n : {6, 7, 10, 50, 500}) {
    for (int k = 0; k < 100; ++k) {
      const Scene s = RandomScene(&rng, n);
      PoseCandidate pose;
      const Status status = SolveDlt(s.bearings, s.points, &pose);
      ASSERT_TRUE(status.ok()) << "n = " << n << " case " << k << ": " << status.message();
      SCOPED_TRACE(::testing::Message() << "n = " << n << " case " << k);
      ExpectPose(s, pose, kRotationTolerance);
    }
  }
}

TEST(DltTest, LargeCoordinatesAndScaledBearings) {
  std::mt19937_64 rng(43);
  Scene s = RandomScene(&rng, 12);
  const Eigen::Vector3d offset(500000.0, 4100000.0, 300.0);
  s.center += offset;
  for (Eigen::Vector3d& p : s.points) p += offset;
  for (size_t i = 0; i < s.bearings.size(); ++i) s.bearings[i] *= 0.5 + static_cast<double>(i);
  PoseCandidate pose;
  ASSERT_TRUE(SolveDlt(s.bearings, s.points, &pose).ok());
  ExpectPose(s, pose, kRotationTolerance);
}

TEST(DltTest, NoisyBearingsGiveAnInitialValue) {
  std::mt19937_64 rng(44);
  std::normal_distribution<double> noise(0.0, 3.0 / 100500.0);  // 0.5 px of 6 um at c = 100.5 mm
  Scene s = RandomScene(&rng, 100);
  for (Eigen::Vector3d& b : s.bearings)
    b = (b + DrawLastFirst<3>([&](int i) { return i == 2 ? 0.0 : noise(rng); })).normalized();
  PoseCandidate pose;
  ASSERT_TRUE(SolveDlt(s.bearings, s.points, &pose).ok());
  ExpectPose(s, pose, kNoisyTolerance);
}

TEST(DltTest, TooFewPointsIsAnError) {
  std::mt19937_64 rng(45);
  for (int n : {0, 1, 3, 5}) {
    const Scene s = RandomScene(&rng, n);
    PoseCandidate pose;
    const Status status = SolveDlt(s.bearings, s.points, &pose);
    EXPECT_FALSE(status.ok()) << n;
    EXPECT_NE(status.message().find("at least 6"), std::string::npos) << status.message();
  }
}

TEST(DltTest, CoplanarPointsAreAnError) {
  // Points on the ground plane Z = 50 seen by a tilted camera: a perfectly valid view, but the DLT
  // of a plane is a homography and leaves P undetermined.
  std::mt19937_64 rng(46);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Scene s;
  s.R = RotationFromAngles(RotationConvention::kSeed, Eigen::Vector3d(0.2, -0.1, 1.0));
  s.center = Eigen::Vector3d(10, 20, 850);
  s.scale = 800;
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector3d p = DrawLastFirst<3>([&](int i) { return i == 2 ? 50.0 : (i == 0 ? 10 : 20) + 300 * unit(rng); });
    s.points.push_back(p);
    s.bearings.push_back((s.R * (p - s.center)).normalized());
  }
  PoseCandidate pose;
  const Status status = SolveDlt(s.bearings, s.points, &pose);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("coplanar"), std::string::npos) << status.message();

  // A tilted plane is just as degenerate.
  for (Eigen::Vector3d& p : s.points) p.z() = 50.0 + 0.3 * p.x() - 0.7 * p.y();
  for (size_t i = 0; i < s.points.size(); ++i)
    s.bearings[i] = (s.R * (s.points[i] - s.center)).normalized();
  EXPECT_FALSE(SolveDlt(s.bearings, s.points, &pose).ok());
}

TEST(DltTest, CollinearPointsAreAnError) {
  std::mt19937_64 rng(47);
  Scene s = RandomScene(&rng, 10);
  const Eigen::Vector3d a = s.points[0], d = s.points[1] - s.points[0];
  for (size_t i = 0; i < s.points.size(); ++i) {
    s.points[i] = a + (0.1 * static_cast<double>(i)) * d;
    s.bearings[i] = (s.R * (s.points[i] - s.center)).normalized();
  }
  PoseCandidate pose;
  const Status status = SolveDlt(s.bearings, s.points, &pose);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("collinear"), std::string::npos) << status.message();
}

TEST(DltTest, MalformedInputIsAnError) {
  std::mt19937_64 rng(48);
  Scene s = RandomScene(&rng, 10);
  PoseCandidate pose;
  std::vector<Eigen::Vector3d> fewer_bearings(s.bearings.begin(), s.bearings.end() - 1);
  EXPECT_FALSE(SolveDlt(fewer_bearings, s.points, &pose).ok());
  Scene zero = s;
  zero.bearings[3].setZero();
  EXPECT_FALSE(SolveDlt(zero.bearings, zero.points, &pose).ok());
  Scene nan = s;
  nan.points[4].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(SolveDlt(nan.bearings, nan.points, &pose).ok());
}

TEST(DltTest, PointsBehindTheCameraAreAnError) {
  // Every bearing reversed: the only consistent projective solution puts the points behind.
  std::mt19937_64 rng(49);
  Scene s = RandomScene(&rng, 20);
  for (Eigen::Vector3d& b : s.bearings) b = -b;
  PoseCandidate pose;
  EXPECT_FALSE(SolveDlt(s.bearings, s.points, &pose).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
