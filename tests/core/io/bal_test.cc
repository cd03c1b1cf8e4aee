#include "core/io/bal.h"

#include <gtest/gtest.h>

#include <ceres/rotation.h>

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/collinearity.h"
#include "tests/support/temp_dir.h"
#include "tests/test_data.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::ScopedTempDir;

// Closed forms evaluated in double precision on O(1000) px.
constexpr double kExactPx = 1e-9;
// Bundler prints R with ten digits; the reader uses its nearest rotation, which moves a
// projection by about 1e-10 rad x 500 px (the printed residuals themselves are rounded to 1e-4).
constexpr double kBundlerRotationPx = 1e-6;

// BAL's residual "predicted - observed" as the BAL page defines it, written independently of the
// reader with Ceres' angle-axis rotation: P = R(r) X + t, p = -P / P.z,
// predicted = f (1 + k1 |p|^2 + k2 |p|^4) p.
Eigen::Vector2d BalResidual(const double* camera, const Eigen::Vector3d& X, const Eigen::Vector2d& xy) {
  double P[3];
  ceres::AngleAxisRotatePoint(camera, X.data(), P);
  for (int k = 0; k < 3; ++k) P[k] += camera[3 + k];
  const double px = -P[0] / P[2], py = -P[1] / P[2];
  const double r2 = px * px + py * py;
  const double scale = camera[6] * (1.0 + camera[7] * r2 + camera[8] * r2 * r2);
  return {scale * px - xy.x(), scale * py - xy.y()};
}

// The raw numbers of a BAL file.
struct BalFile {
  std::vector<int> camera, point;
  std::vector<Eigen::Vector2d> xy;
  std::vector<std::array<double, 9>> cameras;
  std::vector<Eigen::Vector3d> points;
};

BalFile ParseBal(const std::string& path) {
  std::ifstream in(path);
  BalFile f;
  int nc, np, no;
  in >> nc >> np >> no;
  for (int k = 0; k < no; ++k) {
    int c, p;
    double x, y;
    in >> c >> p >> x >> y;
    f.camera.push_back(c);
    f.point.push_back(p);
    f.xy.emplace_back(x, y);
  }
  f.cameras.resize(nc);
  for (auto& camera : f.cameras)
    for (double& v : camera) in >> v;
  f.points.resize(np);
  for (auto& p : f.points) in >> p.x() >> p.y() >> p.z();
  return f;
}

// The residual of mark m through core/camera_models.h.
Eigen::Vector2d BlockResidual(const Block& block, size_t m) {
  const BlockMark& mark = block.marks[m];
  const BlockImage& image = block.images[mark.image];
  double ab[2], r[2];
  EXPECT_TRUE(ProjectToNormalized(image.eo->data(), block.points[mark.point].position_m->data(), ab));
  const BlockCamera& camera = block.cameras[image.camera];
  CameraModelResidual(camera.model, camera.params.data(), ab, mark.observation.data(), camera.data(),
                      r);
  return {r[0], r[1]};
}

TEST(BalIo, NominalCase) {
  // r = 0 (R = I), t = 0, f = 100, k1 = 0.1: the point (1, 2, -10) is p = (0.1, 0.2), r2 = 0.05,
  // predicted = 100 * 1.005 * p = (10.05, 20.1). Observed (10, 20): BAL residual (0.05, 0.1);
  // the mark is (10, -20) and its residual (-0.05, 0.1).
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string path =
      dir.Write("p.txt", "1 1 1\n0 0 10 20\n0\n0\n0\n0\n0\n0\n100\n0.1\n0\n1\n2\n-10\n");
  Block block;
  const Status status = ReadBalProblem(path, &block);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(block.cameras.size(), 1u);
  EXPECT_EQ(block.cameras[0].model, CameraModelType::kRadial);
  EXPECT_EQ(block.cameras[0].params, (std::vector<double>{100.0, 0.0, 0.0, 0.1, 0.0}));
  EXPECT_EQ(block.marks[0].observation, Eigen::Vector2d(10.0, -20.0));
  const Eigen::Vector2d r = BlockResidual(block, 0);
  EXPECT_NEAR(r.x(), -0.05, kExactPx);
  EXPECT_NEAR(r.y(), 0.1, kExactPx);
  double cost = 0.0;
  ASSERT_TRUE(ReprojectionCost(block, &cost).ok());
  EXPECT_NEAR(cost, 0.5 * (0.05 * 0.05 + 0.1 * 0.1), kExactPx);
}

class BalDubrovnik : public ::testing::TestWithParam<const char*> {};

TEST_P(BalDubrovnik, ResidualsAreBalsOwn) {
  const std::string path = testing::SharedDataPath(std::string("bal_dubrovnik/") + GetParam());
  Block block;
  const Status status = ReadBalProblem(path, &block);
  ASSERT_TRUE(status.ok()) << status.message();
  const BalFile file = ParseBal(path);
  ASSERT_EQ(block.marks.size(), file.xy.size());
  ASSERT_EQ(block.images.size(), file.cameras.size());
  ASSERT_EQ(block.points.size(), file.points.size());
  double bal_cost = 0.0;
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const Eigen::Vector2d bal =
        BalResidual(file.cameras[file.camera[m]].data(), file.points[file.point[m]], file.xy[m]);
    const Eigen::Vector2d mine = BlockResidual(block, m);
    const double scale = std::max(1.0, bal.norm());
    EXPECT_NEAR(mine.x(), -bal.x(), kExactPx * scale);
    EXPECT_NEAR(mine.y(), bal.y(), kExactPx * scale);
    bal_cost += 0.5 * bal.squaredNorm();
  }
  double cost = 0.0;
  int behind = -1;
  ASSERT_TRUE(ReprojectionCost(block, &cost, &behind).ok());
  EXPECT_NEAR(cost, bal_cost, 1e-9 * bal_cost);
  EXPECT_EQ(behind, 0);
  std::printf("%s: %zu cameras, %zu points, %zu observations, initial cost %.10g px^2\n",
              GetParam(), block.images.size(), block.points.size(), block.marks.size(), cost);
}

INSTANTIATE_TEST_SUITE_P(SharedData, BalDubrovnik,
                         ::testing::Values("dubrovnik-1-1-pre.txt", "dubrovnik-3-7-pre.txt",
                                           "dubrovnik-3-7-18-pre.txt"));

TEST(BalIo, BundlerBalbianelloResidualsAreBundlersOwn) {
  const std::string path = testing::SharedDataPath("bundler_balbianello/Balbianello.out");
  Block block;
  int unregistered = -1;
  const Status status = ReadBundlerFile(path, &block, &unregistered);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(unregistered, 0);
  ASSERT_EQ(block.images.size(), 5u);
  ASSERT_EQ(block.points.size(), 544u);
  // The file's cameras, parsed here independently: f k1 k2, R, t.
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  int nc, np;
  in >> nc >> np;
  std::vector<std::array<double, 3>> intrinsics(nc);
  std::vector<Eigen::Matrix3d> rotations(nc);
  std::vector<Eigen::Vector3d> translations(nc);
  for (int c = 0; c < nc; ++c) {
    in >> intrinsics[c][0] >> intrinsics[c][1] >> intrinsics[c][2];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) in >> rotations[c](i, j);
    in >> translations[c].x() >> translations[c].y() >> translations[c].z();
  }
  double cost = 0.0, bundler_cost = 0.0;
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    const int c = mark.image;  // no camera left out: image i is camera i
    const Eigen::Vector3d P =
        rotations[c] * *block.points[mark.point].position_m + translations[c];
    const Eigen::Vector2d p(-P.x() / P.z(), -P.y() / P.z());
    const double r2 = p.squaredNorm();
    const Eigen::Vector2d predicted =
        intrinsics[c][0] * (1.0 + intrinsics[c][1] * r2 + intrinsics[c][2] * r2 * r2) * p;
    const Eigen::Vector2d observed(mark.observation.x(), -mark.observation.y());  // file's (x, y)
    const Eigen::Vector2d bundler = predicted - observed;
    const Eigen::Vector2d mine = BlockResidual(block, m);
    EXPECT_NEAR(mine.x(), -bundler.x(), kBundlerRotationPx);
    EXPECT_NEAR(mine.y(), bundler.y(), kBundlerRotationPx);
    bundler_cost += 0.5 * bundler.squaredNorm();
  }
  ASSERT_TRUE(ReprojectionCost(block, &cost).ok());
  EXPECT_NEAR(cost, bundler_cost, 1e-6 * bundler_cost);
  std::printf("Balbianello.out: %zu cameras, %zu points, %zu observations, initial cost %.10g px^2\n",
              block.images.size(), block.points.size(), block.marks.size(), cost);
}

TEST(BalIo, UnregisteredBundlerCameraIsLeftOut) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string camera_ok = "100 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n";
  const std::string camera_zero = "0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n";
  const std::string path = dir.Write(
      "b.out", "# Bundle file v0.3\n3 1\n" + camera_ok + camera_zero + camera_ok +
                   "1 2 -10\n255 0 0\n2 0 7 10 20 2 8 11 21\n");
  Block block;
  int unregistered = 0;
  const Status status = ReadBundlerFile(path, &block, &unregistered);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(unregistered, 1);
  ASSERT_EQ(block.images.size(), 2u);
  EXPECT_EQ(block.images[1].name, "2");
  EXPECT_EQ(block.marks[1].image, 1);
  // A view of the left-out camera is an error naming it.
  const std::string bad = dir.Write(
      "c.out", "# Bundle file v0.3\n3 1\n" + camera_ok + camera_zero + camera_ok +
                   "1 2 -10\n255 0 0\n1 1 7 10 20\n");
  const Status error = ReadBundlerFile(bad, &block);
  ASSERT_FALSE(error.ok());
  EXPECT_EQ(error.message(), bad + ":20: camera: camera 1 has f = 0 (not reconstructed)");
}

// A file cut short and grown again while it is read, over and over: a mapping of it would die of
// SIGBUS at the first page past the new end; read, it gives an error (or the problem) every time.
TEST(BalIo, AFileThatShrinksWhileItIsReadIsNeverACrash) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  std::string text = "1 100000 100000\n";
  for (int k = 0; k < 100000; ++k) text += "0 " + std::to_string(k) + " 1.5 2.5\n";
  text += "0 0 0 0 0 -10 100 0 0\n";
  for (int k = 0; k < 100000; ++k) text += "1 2 3\n";
  const std::string path = dir.Write("p.txt", text);  // 2.6 MB
  const int fd = open(path.c_str(), O_WRONLY);
  ASSERT_GE(fd, 0);
  std::atomic<bool> done{false};
  std::thread cutter([&] {
    while (!done) {
      if (ftruncate(fd, 0) != 0 || ftruncate(fd, static_cast<off_t>(text.size())) != 0) return;
    }
  });
  int read_whole = 0, refused = 0;
  for (int k = 0; k < 200; ++k) {
    Block block;
    const Status status = ReadBalProblem(path, &block);
    if (status.ok()) {
      ++read_whole;
    } else {
      ++refused;
      EXPECT_EQ(status.message().rfind(path + ":", 0), 0u) << status.message();
    }
  }
  done = true;
  cutter.join();
  close(fd);
  EXPECT_EQ(read_whole + refused, 200);
}

struct BadFile {
  const char* name;
  bool bundler;
  const char* text;
  const char* message;  // after "path:"
};

class BalIoBadInput : public ::testing::TestWithParam<BadFile> {};

TEST_P(BalIoBadInput, ClearMessage) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string path = dir.Write("f.txt", GetParam().text);
  Block block;
  const Status status =
      GetParam().bundler ? ReadBundlerFile(path, &block) : ReadBalProblem(path, &block);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), path + ":" + GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BalIoBadInput,
    ::testing::Values(
        BadFile{"CameraOutOfRange", false, "1 1 1\n3 0 1 2\n0 0 0 0 0 0 100 0 0\n1 2 3\n",
                "2: camera: 3 is out of range [0, 0]"},
        BadFile{"Truncated", false, "1 1 1\n0 0 1 2\n0 0 0 0 0 0 100 0 0\n1 2\n",
                "4: point coordinate: is missing"},
        BadFile{"NotANumber", false, "1 1 1\n0 0 1 y\n0 0 0 0 0 0 100 0 0\n1 2 3\n",
                "2: y: 'y' is not a number"},
        BadFile{"Trailing", false, "1 1 1\n0 0 1 2\n0 0 0 0 0 0 100 0 0\n1 2 3\n4\n",
                "5: unexpected text after the last point"},
        BadFile{"HugeHeader", false, "1000000 1 1\n", "1: num_observations: the header promises "
                                                       "more numbers than the file can hold"},
        BadFile{"NotBundler", true, "# Bundle file v0.2\n", "1: not a Bundler v0.3 file (the first "
                                                            "line is not '# Bundle file v0.3')"},
        BadFile{"NotARotation", true,
                "# Bundle file v0.3\n1 0\n100 0 0\n2 0 0\n0 1 0\n0 0 1\n0 0 0\n"
                "                                                            \n",
                "3: R: rotation matrix is not orthonormal (max |R R^T - I| = 3)"},
        // Absurd values: refused at their line, before any work (issue 20).
        BadFile{"ZeroFocalLength", false, "1 1 1\n0 0 1 2\n0 0 0 0 0 0 0 0 0\n1 2 3\n",
                "3: f: 0 is no focal length: its magnitude must be at least 0.001 px"},
        BadFile{"HugeFocalLength", false, "1 1 1\n0 0 1 2\n0 0 0 0 0 0 -1e300 0 0\n1 2 3\n",
                "3: f: '-1e300' is outside [-100000000, 100000000] px"},
        BadFile{"HugeRotation", false, "1 1 1\n0 0 1 2\n0 1e300 0 0 0 0 100 0 0\n1 2 3\n",
                "3: r: '1e300' is outside [-1000, 1000] rad"},
        BadFile{"HugeTranslation", false, "1 1 1\n0 0 1 2\n0 0 0 0 0 1e9 100 0 0\n1 2 3\n",
                "3: t: '1e9' is outside [-100000000, 100000000]"},
        BadFile{"HugePoint", false, "1 1 1\n0 0 1 2\n0 0 0 0 0 0 100 0 0\n1 1e300 3\n",
                "4: point coordinate: '1e300' is outside [-100000000, 100000000]"},
        BadFile{"HugeObservation", false, "1 1 1\n0 0 1e300 2\n0 0 0 0 0 0 100 0 0\n1 2 3\n",
                "2: x: '1e300' is outside [-100000000, 100000000] px"}),
    [](const ::testing::TestParamInfo<BadFile>& info) { return std::string(info.param.name); });

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
