#include "core/io/opensfm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/collinearity.h"
#include "core/io/csv.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_block.h"
#include "tests/support/temp_dir.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::ScopedTempDir;

// A write -> read round trip of a pose goes through the rotation vector and the seed angles, each
// exact to a few ulp of O(1) numbers.
constexpr double kPoseRoundTrip = 1e-12;
// A pixel written as (pixel - w / 2) / s and read back as s x + w / 2 (s = 6000 px) moves by a
// few ulp of the pixel (~1e-12 px).
constexpr double kNormalisationRoundTripPx = 1e-9;
// Parameters divided by s and multiplied back: a few ulp, relative.
constexpr double kParamRoundTripRelative = 1e-14;
// OpenSfM's documented projection evaluated here and the block's model agree to rounding of
// O(1000) px through a handful of operations (the fisheye's atan included).
constexpr double kIndependentPx = 1e-8;

const char kPath[] = "/p/reconstruction.json";

// ------------------------------------------------------------------ a synthetic block

SyntheticBlockOptions SmallOptions(CameraModelType model, std::vector<double> params) {
  SyntheticBlockOptions o;
  o.num_lines = 2;
  o.images_per_line = 4;
  o.num_tie_points = 60;
  o.num_control_points = 0;
  o.num_check_points = 0;
  o.camera_model = model;
  o.camera_params = std::move(params);
  return o;
}

// The block read back equals the one written (matched by name: OpenSfM orders shots and points by
// their ids): poses to 1e-12, camera parameters to a few ulp, marks after the normalisation.
void ExpectSameBlock(const Block& written, const Block& read) {
  ASSERT_EQ(read.cameras.size(), written.cameras.size());
  for (size_t c = 0; c < written.cameras.size(); ++c) {
    const BlockCamera& a = written.cameras[c];
    const BlockCamera& b = read.cameras[read.FindCamera(a.camera_id)];
    EXPECT_EQ(b.model, a.model);
    EXPECT_EQ(b.table.n_columns, a.table.n_columns);
    EXPECT_EQ(b.table.n_rows, a.table.n_rows);
    ASSERT_EQ(b.params.size(), a.params.size());
    for (size_t k = 0; k < a.params.size(); ++k)
      EXPECT_NEAR(b.params[k], a.params[k], kParamRoundTripRelative * std::abs(a.params[k])) << k;
  }
  ASSERT_EQ(read.images.size(), written.images.size());
  for (const BlockImage& a : written.images) {
    const int i = read.FindImage(a.name);
    ASSERT_GE(i, 0) << a.name;
    const BlockImage& b = read.images[i];
    EXPECT_EQ(read.cameras[b.camera].camera_id, written.cameras[a.camera].camera_id);
    const Eigen::Matrix3d Ra =
        RotationFromAngles(RotationConvention::kSeed, a.eo->angles_seed_rad());
    const Eigen::Matrix3d Rb =
        RotationFromAngles(RotationConvention::kSeed, b.eo->angles_seed_rad());
    EXPECT_LT((Ra - Rb).cwiseAbs().maxCoeff(), kPoseRoundTrip) << a.name;
    const Eigen::Vector3d ca = a.eo->center_in_ground();
    EXPECT_LT((ca - b.eo->center_in_ground()).norm(), kPoseRoundTrip * std::max(1.0, ca.norm()))
        << a.name;
  }
  ASSERT_EQ(read.points.size(), written.points.size());
  for (const BlockPoint& a : written.points) {
    const int p = read.FindPoint(a.id);
    ASSERT_GE(p, 0) << a.id;
    EXPECT_EQ(*read.points[p].position_m, *a.position_m);
  }
  ASSERT_EQ(read.marks.size(), written.marks.size());
  // tracks.csv keeps the block's mark order.
  for (size_t m = 0; m < written.marks.size(); ++m) {
    const BlockMark& a = written.marks[m];
    const BlockMark& b = read.marks[m];
    EXPECT_EQ(read.images[b.image].name, written.images[a.image].name);
    EXPECT_EQ(read.points[b.point].id, written.points[a.point].id);
    EXPECT_LT((b.observation - a.observation).norm(), kNormalisationRoundTripPx) << m;
    EXPECT_EQ(b.measured, b.observation);
    EXPECT_EQ(b.unit, MarkUnit::kPixel);
  }
}

TEST(OpenSfmIo, SyntheticBlocksRoundTrip) {
  // One block per projection the writer chooses: perspective (RADIAL, centred), brown
  // (FULL_OPENCV), fisheye (OPENCV_FISHEYE, centred, square) and fisheye_opencv.
  const double f = 6000.0, cx = 3000.0, cy = 2000.0;
  const std::vector<std::pair<CameraModelType, std::vector<double>>> cameras = {
      {CameraModelType::kRadial, {f, cx, cy, -0.05, 0.01}},
      {CameraModelType::kFullOpenCv,
       {f, f * 1.001, cx + 12.5, cy - 7.25, -0.05, 0.01, 1e-4, -2e-4, 0.002, 0.0, 0.0, 0.0}},
      {CameraModelType::kOpenCvFisheye, {f, f, cx, cy, 0.02, -0.003, 0.0, 0.0}},
      {CameraModelType::kOpenCvFisheye, {f, f * 0.999, cx + 3.0, cy, 0.02, -0.003, 4e-4, -1e-5}},
  };
  const char* const kExpectedType[] = {"perspective", "brown", "fisheye", "fisheye_opencv"};
  for (size_t c = 0; c < cameras.size(); ++c) {
    SCOPED_TRACE(kExpectedType[c]);
    Block block;
    SyntheticBlockTruth truth;
    const Status made =
        MakeSyntheticBlock(SmallOptions(cameras[c].first, cameras[c].second), &block, &truth);
    ASSERT_TRUE(made.ok()) << made.message();
    ASSERT_GT(block.marks.size(), 100u);
    ScopedTempDir dir;
    ASSERT_TRUE(dir.ok());
    const Status written = WriteOpenSfmReconstruction(dir.path(), block);
    ASSERT_TRUE(written.ok()) << written.message();
    Block read;
    OpenSfmExtras extras;
    // The folder and the file name the same reconstruction.
    const Status status = ReadOpenSfmReconstruction(dir.path(), &read, &extras);
    ASSERT_TRUE(status.ok()) << status.message();
    ExpectSameBlock(block, read);
    ASSERT_EQ(extras.projection_types.size(), 1u);
    EXPECT_EQ(extras.projection_types[0], kExpectedType[c]);
    EXPECT_EQ(extras.tracks_version, 2);
    EXPECT_EQ(extras.further_reconstructions, 0);
    EXPECT_EQ(extras.tracks_of_other_images + extras.tracks_of_other_points, 0);
    Block by_file;
    ASSERT_TRUE(ReadOpenSfmReconstruction(dir.Path("reconstruction.json"), &by_file).ok());
    EXPECT_EQ(by_file.marks.size(), read.marks.size());
    // Written again with the extras read, the texts are the same.
    OpenSfmText first, second;
    first.reconstruction_json = ScopedTempDir::Read(dir.Path("reconstruction.json"));
    first.tracks_csv = ScopedTempDir::Read(dir.Path("tracks.csv"));
    ASSERT_TRUE(FormatOpenSfmReconstruction(read, &extras, &second).ok());
    EXPECT_EQ(second.tracks_csv.substr(0, 26), "OPENSFM_TRACKS_VERSION_v2\n");
    Block again;
    ASSERT_TRUE(ParseOpenSfmReconstruction(second, kPath, &again).ok());
    ExpectSameBlock(read, again);
  }
}

// ------------------------------------------------------------------ OpenSfM's own formulas

// Rodrigues' formula, written here from its definition: R = cos t I + sin t [k]x + (1 - cos t) k
// k^T.
Eigen::Matrix3d Rodrigues(const Eigen::Vector3d& r) {
  const double t = r.norm();
  if (t == 0.0) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d k = r / t;
  Eigen::Matrix3d K;
  K << 0.0, -k.z(), k.y(), k.z(), 0.0, -k.x(), -k.y(), k.x(), 0.0;
  return std::cos(t) * Eigen::Matrix3d::Identity() + std::sin(t) * K +
         (1.0 - std::cos(t)) * k * k.transpose();
}

struct DocCamera {
  std::string id, type;
  int width, height;
  std::map<std::string, double> p;  // OpenSfM's JSON fields
};

// OpenSfM's documented projection ("Geometric models", Camera Models) of a point in camera
// coordinates into normalised image coordinates.
Eigen::Vector2d DocProject(const DocCamera& c, const Eigen::Vector3d& x) {
  const auto p = [&c](const char* name) {
    const auto found = c.p.find(name);
    return found == c.p.end() ? 0.0 : found->second;
  };
  if (c.type == "fisheye") {
    const double r = std::hypot(x.x(), x.y());
    const double theta = std::atan(r / x.z());
    const double d = 1.0 + p("k1") * theta * theta + p("k2") * std::pow(theta, 4);
    return {p("focal") * d * theta * x.x() / r, p("focal") * d * theta * x.y() / r};
  }
  const double xn = x.x() / x.z(), yn = x.y() / x.z(), r2 = xn * xn + yn * yn;
  if (c.type == "perspective") {
    const double d = 1.0 + p("k1") * r2 + p("k2") * r2 * r2;
    return {p("focal") * d * xn, p("focal") * d * yn};
  }
  // brown
  const double dr = 1.0 + p("k1") * r2 + p("k2") * r2 * r2 + p("k3") * r2 * r2 * r2;
  const double dtx = 2.0 * p("p1") * xn * yn + p("p2") * (r2 + 2.0 * xn * xn);
  const double dty = 2.0 * p("p2") * xn * yn + p("p1") * (r2 + 2.0 * yn * yn);
  return {p("focal_x") * (dr * xn + dtx) + p("c_x"), p("focal_y") * (dr * yn + dty) + p("c_y")};
}

// Normalised -> pixels: OpenSfM's H (OpenCV pixels, the first pixel's centre at 0), then the
// block's convention (the image's corner at 0): half a pixel more.
Eigen::Vector2d DocPixel(const DocCamera& c, const Eigen::Vector2d& normalized) {
  const double s = std::max(c.width, c.height);
  const Eigen::Vector2d opencv(s * normalized.x() + (c.width - 1) / 2.0,
                               s * normalized.y() + (c.height - 1) / 2.0);
  return opencv + Eigen::Vector2d(0.5, 0.5);
}

std::string Numbers(std::initializer_list<double> values) {
  std::string text = "[";
  for (const double v : values) text += (text.size() > 1 ? ", " : "") + FormatNumber(v);
  return text + "]";
}

struct DocShot {
  std::string name;
  int camera;
  Eigen::Vector3d rotation, translation;
};

TEST(OpenSfmIo, MarksAndProjectionsFollowOpenSfmsDocumentedFormulas) {
  const std::vector<DocCamera> cameras = {
      {"v2 brown 4000 3000",
       "brown",
       4000,
       3000,
       {{"focal_x", 0.85},
        {"focal_y", 0.86},
        {"c_x", 0.004},
        {"c_y", -0.003},
        {"k1", -0.1},
        {"k2", 0.02},
        {"p1", 0.001},
        {"p2", -0.0005},
        {"k3", 0.003}}},
      {"v2 portrait perspective",
       "perspective",
       3000,
       4000,
       {{"focal", 0.9}, {"k1", -0.05}, {"k2", 0.01}}},
      {"v2 fisheye", "fisheye", 2000, 1500, {{"focal", 0.5}, {"k1", 0.03}, {"k2", -0.004}}},
  };
  const std::vector<DocShot> shots = {
      {"a.jpg", 0, {0.05, -0.1, 0.2}, {0.3, -0.2, 1.0}},
      {"b.jpg", 1, {-0.08, 0.04, -1.3}, {-0.5, 0.1, 0.5}},
      {"c.jpg", 2, {0.02, 0.12, 2.9}, {0.1, 0.4, -0.3}},
      {"d e.jpg", 0, {-0.1, 0.0, 0.7}, {0.0, 0.0, 0.0}},
  };
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 7; ++k) points.emplace_back(-1.5 + 0.5 * k, 1.2 - 0.4 * k, 9.0 + 0.3 * k);

  std::string json = "[{\"cameras\": {";
  for (size_t c = 0; c < cameras.size(); ++c) {
    json += (c > 0 ? ", \"" : "\"") + cameras[c].id + "\": {\"projection_type\": \"" +
            cameras[c].type + "\", \"width\": " + std::to_string(cameras[c].width) +
            ", \"height\": " + std::to_string(cameras[c].height);
    for (const auto& [name, value] : cameras[c].p)
      json += ", \"" + name + "\": " + FormatNumber(value);
    json += "}";
  }
  json += "}, \"shots\": {";
  for (size_t i = 0; i < shots.size(); ++i) {
    const DocShot& s = shots[i];
    json +=
        (i > 0 ? ", \"" : "\"") + s.name +
        "\": {\"rotation\": " + Numbers({s.rotation.x(), s.rotation.y(), s.rotation.z()}) +
        ", \"translation\": " + Numbers({s.translation.x(), s.translation.y(), s.translation.z()}) +
        ", \"camera\": \"" + cameras[s.camera].id +
        "\", \"gps_position\": [1, 2, 3], \"gps_dop\": 5}";
  }
  json += "}, \"points\": {";
  for (size_t p = 0; p < points.size(); ++p) {
    json += (p > 0 ? ", \"" : "\"") + std::to_string(100 + p) +
            "\": {\"coordinates\": " + Numbers({points[p].x(), points[p].y(), points[p].z()}) +
            ", \"color\": [10, 20, 30]}";
  }
  json +=
      "}, \"reference_lla\": {\"latitude\": -22.5, \"longitude\": -47.25, \"altitude\": 610}},"
      " {\"cameras\": {}, \"shots\": {}}]";

  // tracks.csv with every (shot, point) pair, the observation from the formulas above.
  std::string tracks = "OPENSFM_TRACKS_VERSION_v2\n";
  std::map<std::pair<std::string, std::string>, Eigen::Vector2d> expected;
  for (const DocShot& s : shots) {
    for (size_t p = 0; p < points.size(); ++p) {
      const Eigen::Vector3d x = Rodrigues(s.rotation) * points[p] + s.translation;
      ASSERT_GT(x.z(), 0.0);
      const Eigen::Vector2d n = DocProject(cameras[s.camera], x);
      const std::string id = std::to_string(100 + p);
      expected[{s.name, id}] = DocPixel(cameras[s.camera], n);
      tracks += s.name + "\t" + id + "\t" + std::to_string(p) + "\t" + FormatNumber(n.x()) + "\t" +
                FormatNumber(n.y()) + "\t0.004\t1\t2\t3\t-1\t-1\n";
    }
  }
  // An image that is no shot and a track that is no point: counted, no marks.
  tracks += "other.jpg\t100\t0\t0.1\t0.1\t0.004\t1\t2\t3\t-1\t-1\n";
  tracks += "a.jpg\t999\t0\t0.1\t0.1\t0.004\t1\t2\t3\t-1\t-1\n";
  tracks += "a.jpg\t998\t0\t0.1\t0.1\t0.004\t1\t2\t3\t-1\t-1\n";

  Block block;
  OpenSfmExtras extras;
  OpenSfmText text{json, tracks, std::nullopt};
  const Status status = ParseOpenSfmReconstruction(text, kPath, &block, &extras);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(block.marks_source, "/p/tracks.csv");
  EXPECT_EQ(extras.further_reconstructions, 1);
  EXPECT_EQ(extras.tracks_of_other_images, 1);
  EXPECT_EQ(extras.tracks_of_other_points, 2);
  ASSERT_TRUE(extras.reference_lla.has_value());
  EXPECT_EQ(extras.reference_lla->latitude_deg, -22.5);
  EXPECT_EQ(extras.reference_lla->longitude_deg, -47.25);
  EXPECT_EQ(extras.reference_lla->altitude_m, 610.0);
  EXPECT_EQ(extras.reference_lla_source, kPath);
  ASSERT_EQ(block.images.size(), shots.size());
  ASSERT_EQ(extras.gps_position_m.size(), shots.size());
  EXPECT_EQ(*extras.gps_position_m[0], Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_EQ(*extras.gps_dop_m[0], 5.0);
  EXPECT_EQ(block.cameras[block.FindCamera("v2 brown 4000 3000")].model,
            CameraModelType::kFullOpenCv);
  EXPECT_EQ(block.cameras[block.FindCamera("v2 portrait perspective")].model,
            CameraModelType::kRadial);
  EXPECT_EQ(block.cameras[block.FindCamera("v2 fisheye")].model, CameraModelType::kOpenCvFisheye);
  ASSERT_EQ(block.marks.size(), shots.size() * points.size());
  for (const BlockMark& mark : block.marks) {
    const std::string& name = block.images[mark.image].name;
    const std::string& id = block.points[mark.point].id;
    SCOPED_TRACE(name + " " + id);
    const Eigen::Vector2d pixel = expected.at({name, id});
    EXPECT_LT((mark.observation - pixel).norm(), kIndependentPx);
    // The block's pose and camera model reproject the point onto OpenSfM's pixel.
    double ab[2], residual[2];
    ASSERT_TRUE(ProjectToNormalized(block.images[mark.image].eo->data(),
                                    block.points[mark.point].position_m->data(), ab));
    const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
    CameraModelResidual(camera.model, camera.params.data(), ab, pixel.data(), camera.data(),
                        residual);
    EXPECT_LT(std::hypot(residual[0], residual[1]), kIndependentPx);
  }

  // Versions 1 (no segmentation, instance) and 0 (no scale either) give the same marks.
  for (const int version : {1, 0}) {
    std::string old_tracks = version == 1 ? "OPENSFM_TRACKS_VERSION_v1\n" : "";
    size_t start = tracks.find('\n') + 1;
    while (start < tracks.size()) {
      const size_t end = tracks.find('\n', start);
      std::vector<std::string> fields;
      size_t from = start;
      for (size_t tab; (tab = tracks.find('\t', from)) < end; from = tab + 1)
        fields.push_back(tracks.substr(from, tab - from));
      fields.push_back(tracks.substr(from, end - from));
      fields.resize(9);                                    // no segmentation, instance
      if (version == 0) fields.erase(fields.begin() + 5);  // no scale
      std::string line;
      for (const std::string& field : fields) line += (line.empty() ? "" : "\t") + field;
      old_tracks += line + "\n";
      start = end + 1;
    }
    Block old;
    OpenSfmExtras old_extras;
    const Status read =
        ParseOpenSfmReconstruction({json, old_tracks, std::nullopt}, kPath, &old, &old_extras);
    ASSERT_TRUE(read.ok()) << read.message();
    EXPECT_EQ(old_extras.tracks_version, version);
    ASSERT_EQ(old.marks.size(), block.marks.size());
    for (size_t m = 0; m < block.marks.size(); ++m)
      EXPECT_EQ(old.marks[m].observation, block.marks[m].observation);
    EXPECT_EQ(old_extras.mark_features[0].scale, version == 1 ? 0.004 : 0.0);
  }

  // Written back with the extras, every camera keeps its projection type.
  OpenSfmText written;
  ASSERT_TRUE(FormatOpenSfmReconstruction(block, &extras, &written).ok());
  Block again;
  OpenSfmExtras again_extras;
  ASSERT_TRUE(ParseOpenSfmReconstruction(written, kPath, &again, &again_extras).ok());
  EXPECT_EQ(again_extras.projection_types, extras.projection_types);
  EXPECT_EQ(again_extras.reference_lla->latitude_deg, -22.5);
  EXPECT_EQ(*again_extras.gps_dop_m[1], 5.0);
  ExpectSameBlock(block, again);
}

TEST(OpenSfmIo, RadialAndSimpleRadialAreOpenCvCameras) {
  const std::string json =
      "[{\"cameras\": {\"r\": {\"projection_type\": \"radial\", \"width\": 1000, \"height\": 800, "
      "\"focal_x\": 0.9, \"focal_y\": 0.8, \"c_x\": 0.01, \"c_y\": -0.02, \"k1\": 0.1, \"k2\": "
      "0.2}, "
      "\"s\": {\"projection_type\": \"simple_radial\", \"width\": 1000, \"height\": 800, "
      "\"focal_x\": 0.9, \"focal_y\": 0.9, \"k1\": 0.1}}, \"shots\": {}}]";
  Block block;
  OpenSfmExtras extras;
  const Status status =
      ParseOpenSfmReconstruction({json, "", std::nullopt}, kPath, &block, &extras);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(block.cameras.size(), 2u);
  EXPECT_EQ(block.cameras[0].model, CameraModelType::kOpenCv);
  EXPECT_EQ(block.cameras[0].params,
            (std::vector<double>{900.0, 800.0, 510.0, 380.0, 0.1, 0.2, 0.0, 0.0}));
  EXPECT_EQ(block.cameras[1].params,
            (std::vector<double>{900.0, 900.0, 500.0, 400.0, 0.1, 0.0, 0.0, 0.0}));
  EXPECT_EQ(extras.tracks_version, 0);
  OpenSfmText written;
  ASSERT_TRUE(FormatOpenSfmReconstruction(block, &extras, &written).ok());
  EXPECT_NE(written.reconstruction_json.find("\"projection_type\":\"radial\""), std::string::npos);
  EXPECT_NE(written.reconstruction_json.find("\"projection_type\":\"simple_radial\""),
            std::string::npos);
}

TEST(OpenSfmIo, ReferenceLlaFileBesideTheReconstruction) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  dir.Write("reconstruction.json", "[{\"cameras\": {}, \"shots\": {}, \"points\": {}}, {}, {}]");
  dir.Write("tracks.csv", "OPENSFM_TRACKS_VERSION_v2\n");
  dir.Write("reference_lla.json", "{\"latitude\": 52.5, \"longitude\": 13.4, \"altitude\": 40.0}");
  Block block;
  OpenSfmExtras extras;
  const Status status = ReadOpenSfmReconstruction(dir.path(), &block, &extras);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(extras.reference_lla.has_value());
  EXPECT_EQ(extras.reference_lla->latitude_deg, 52.5);
  EXPECT_EQ(extras.reference_lla->longitude_deg, 13.4);
  EXPECT_EQ(extras.reference_lla->altitude_m, 40.0);
  EXPECT_EQ(extras.reference_lla_source, dir.Path("reference_lla.json"));
  EXPECT_EQ(extras.further_reconstructions, 2);
  // A bad reference file is named.
  dir.Write("reference_lla.json", "{\"latitude\": 152.5, \"longitude\": 13.4, \"altitude\": 40}");
  const Status bad = ReadOpenSfmReconstruction(dir.path(), &block, &extras);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.message(),
            dir.Path("reference_lla.json") + ": latitude: 152.5 is outside [-90, 90] deg");
  // No tracks.csv: an error naming it.
  std::filesystem::remove(dir.Path("tracks.csv"));
  const Status missing = ReadOpenSfmReconstruction(dir.path(), &block, &extras);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find(dir.Path("tracks.csv")), std::string::npos) << missing.message();
}

// ------------------------------------------------------------------ refusals

const char kCameras[] =
    "\"cameras\": {\"c\": {\"projection_type\": \"perspective\", \"width\": 400, \"height\": 300, "
    "\"focal\": 1.0}}";
const char kShots[] =
    "\"shots\": {\"a.jpg\": {\"rotation\": [0, 0, 0], \"translation\": [0, 0, 0], \"camera\": "
    "\"c\"}}";
const char kPoints[] = "\"points\": {\"1\": {\"coordinates\": [0, 0, 10], \"color\": [1, 2, 3]}}";
const char kTracks[] =
    "OPENSFM_TRACKS_VERSION_v2\na.jpg\t1\t0\t0.1\t0.05\t0.004\t1\t2\t3\t-1\t-1\n";

std::string Reconstruction(const std::string& cameras, const std::string& shots,
                           const std::string& points) {
  return "[{" + cameras + ", " + shots + ", " + points + "}]";
}

struct BadInput {
  const char* name;
  std::string json;
  std::string tracks;
  std::string message;  // the whole message, or its start when it ends with "..."
};

class OpenSfmBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(OpenSfmBadInput, IsRefusedWithFileAndPlace) {
  const BadInput& bad = GetParam();
  Block block;
  OpenSfmExtras extras;
  const Status status =
      ParseOpenSfmReconstruction({bad.json, bad.tracks, std::nullopt}, kPath, &block, &extras);
  ASSERT_FALSE(status.ok());
  const std::string& expected = bad.message;
  if (expected.size() > 3 && expected.substr(expected.size() - 3) == "...") {
    EXPECT_EQ(status.message().substr(0, expected.size() - 3),
              expected.substr(0, expected.size() - 3))
        << status.message();
  } else {
    EXPECT_EQ(status.message(), expected);
  }
  EXPECT_EQ(status.message().find('\n'), std::string::npos);
}

std::string WithShot(const std::string& shot) {
  return Reconstruction(kCameras, "\"shots\": {\"a.jpg\": " + shot + "}", kPoints);
}
std::string WithCamera(const std::string& camera) {
  return Reconstruction("\"cameras\": {\"c\": " + camera + "}", kShots, kPoints);
}
std::string WithTrackLine(const std::string& line) { return std::string(kTracks) + line + "\n"; }

INSTANTIATE_TEST_SUITE_P(
    Cases, OpenSfmBadInput,
    ::testing::Values(
        BadInput{"EmptyArray", "[]", kTracks,
                 "/p/reconstruction.json: holds no reconstruction (the array is empty)"},
        BadInput{"NotAnArray", "{\"cameras\": {}}", kTracks,
                 "/p/reconstruction.json: expected an array of reconstructions, found an object"},
        BadInput{"NotJson", "[{\"cameras\": ", kTracks,
                 "/p/reconstruction.json: not valid JSON: parse error at line 1, column 14..."},
        BadInput{"TooDeep", std::string(100, '[') + std::string(100, ']'), kTracks,
                 "/p/reconstruction.json: arrays and objects nest deeper than 64 levels"},
        BadInput{"MissingShots", "[{" + std::string(kCameras) + "}]", kTracks,
                 "/p/reconstruction.json: shots: is missing"},
        BadInput{"ShotsNotAnObject", "[{" + std::string(kCameras) + ", \"shots\": []}]", kTracks,
                 "/p/reconstruction.json: shots: expected an object, found an array"},
        BadInput{"MissingRotation", WithShot("{\"translation\": [0, 0, 0], \"camera\": \"c\"}"),
                 kTracks, "/p/reconstruction.json: shots.\"a.jpg\".rotation: is missing"},
        BadInput{"RotationNotNumbers", WithShot("{\"rotation\": \"0 0 0\", \"camera\": \"c\"}"),
                 kTracks,
                 "/p/reconstruction.json: shots.\"a.jpg\".rotation: expected 3 numbers, found a "
                 "string"},
        BadInput{"RotationTwoNumbers", WithShot("{\"rotation\": [0, 1], \"camera\": \"c\"}"),
                 kTracks,
                 "/p/reconstruction.json: shots.\"a.jpg\".rotation: expected 3 numbers, found 2 "
                 "values"},
        BadInput{"HugeTranslation",
                 WithShot("{\"rotation\": [0, 0, 0], \"translation\": [0, 1e300, 0], \"camera\": "
                          "\"c\"}"),
                 kTracks,
                 "/p/reconstruction.json: shots.\"a.jpg\".translation: value 2: 1e+300 is "
                 "outside [-100000000, 100000000] m"},
        BadInput{"UnknownCamera", WithShot("{\"rotation\": [0, 0, 0], \"camera\": \"x\"}"), kTracks,
                 "/p/reconstruction.json: shots.\"a.jpg\".camera: camera \"x\" is not in the "
                 "reconstruction's cameras"},
        BadInput{"CameraIdNotAString", WithShot("{\"rotation\": [0, 0, 0], \"camera\": 3}"),
                 kTracks,
                 "/p/reconstruction.json: shots.\"a.jpg\".camera: expected a string, found a "
                 "number"},
        BadInput{
            "UnknownProjection",
            WithCamera("{\"projection_type\": \"spherical\", \"width\": 400, \"height\": 200}"),
            kTracks,
            "/p/reconstruction.json: cameras.\"c\".projection_type: camera \"c\" has "
            "projection type 'spherical', which photopose does not read (it reads "
            "perspective, brown, radial, simple_radial, fisheye and fisheye_opencv)"},
        BadInput{"MissingWidth", WithCamera("{\"height\": 300, \"focal\": 1}"), kTracks,
                 "/p/reconstruction.json: cameras.\"c\".width: is missing"},
        BadInput{"FractionalHeight",
                 WithCamera("{\"width\": 400, \"height\": 300.5, \"focal\": 1}"), kTracks,
                 "/p/reconstruction.json: cameras.\"c\".height: 300.5 is no image size: a whole "
                 "number of pixels in [1, 1000000] is"},
        BadInput{"FocalNotANumber",
                 WithCamera("{\"width\": 400, \"height\": 300, \"focal\": \"1\"}"), kTracks,
                 "/p/reconstruction.json: cameras.\"c\".focal: expected a number, found a string"},
        BadInput{"ZeroFocal", WithCamera("{\"width\": 400, \"height\": 300, \"focal\": 0}"),
                 kTracks,
                 "/p/reconstruction.json: cameras.\"c\".focal: 0 is no focal length: times the "
                 "image size (400 px) it must lie in [0.001, 100000000] px"},
        BadInput{"BrownWithoutFocalY",
                 WithCamera("{\"projection_type\": \"brown\", \"width\": 400, \"height\": 300, "
                            "\"focal_x\": 1}"),
                 kTracks, "/p/reconstruction.json: cameras.\"c\".focal_y: is missing"},
        BadInput{"MissingCoordinates",
                 Reconstruction(kCameras, kShots, "\"points\": {\"1\": {\"color\": [1, 2, 3]}}"),
                 kTracks, "/p/reconstruction.json: points.\"1\".coordinates: is missing"},
        BadInput{"BadReference",
                 "[{" + std::string(kCameras) + ", " + kShots +
                     ", \"reference_lla\": {\"latitude\": 1, \"longitude\": \"east\"}}]",
                 kTracks,
                 "/p/reconstruction.json: reference_lla.longitude: expected a number, found a "
                 "string"},
        BadInput{"UnknownTracksVersion", Reconstruction(kCameras, kShots, kPoints),
                 "OPENSFM_TRACKS_VERSION_v7\n",
                 "/p/tracks.csv:1: tracks version '7' is not one photopose reads (1 or 2; no "
                 "header: 0)"},
        BadInput{"TracksFieldCount", Reconstruction(kCameras, kShots, kPoints),
                 WithTrackLine("a.jpg\t1\t0"),
                 "/p/tracks.csv:3: expected 11 tab-separated fields (tracks version 2), found 3"},
        BadInput{"TracksNotANumber", Reconstruction(kCameras, kShots, kPoints),
                 "OPENSFM_TRACKS_VERSION_v2\na.jpg\t1\t0\tabc\t0.05\t0.004\t1\t2\t3\t-1\t-1\n",
                 "/p/tracks.csv:2: x: 'abc' is not a number"},
        BadInput{"TracksFeatureId", Reconstruction(kCameras, kShots, kPoints),
                 "OPENSFM_TRACKS_VERSION_v2\na.jpg\t1\t0.5\t0.1\t0.05\t0.004\t1\t2\t3\t-1\t-1\n",
                 "/p/tracks.csv:2: feature_id: ..."},
        BadInput{"TracksColour", Reconstruction(kCameras, kShots, kPoints),
                 "OPENSFM_TRACKS_VERSION_v2\na.jpg\t1\t0\t0.1\t0.05\t0.004\t1\t300\t3\t-1\t-1\n",
                 "/p/tracks.csv:2: g: 300 is out of range [0, 255]"},
        BadInput{"TracksHugePixel", Reconstruction(kCameras, kShots, kPoints),
                 "OPENSFM_TRACKS_VERSION_v2\na.jpg\t1\t0\t1e300\t0.05\t0.004\t1\t2\t3\t-1\t-1\n",
                 "/p/tracks.csv:2: x: 1e+300 is 4e+302 px, outside [-100000000, 100000000] px"},
        BadInput{"TracksTwiceInOneImage", Reconstruction(kCameras, kShots, kPoints),
                 WithTrackLine("a.jpg\t1\t5\t0.2\t0.05\t0.004\t1\t2\t3\t-1\t-1"),
                 "/p/tracks.csv:3: track_id: track '1' is observed twice in image 'a.jpg' (first "
                 "at line 2)"}),
    [](const ::testing::TestParamInfo<BadInput>& info) { return std::string(info.param.name); });

TEST(OpenSfmIo, TheWriterRefusesWhatOpenSfmCannotHold) {
  Block block;
  ASSERT_TRUE(ParseOpenSfmReconstruction(
                  {Reconstruction(kCameras, kShots, kPoints), kTracks, std::nullopt}, kPath, &block)
                  .ok());
  OpenSfmText text;
  {
    Block rational = block;
    rational.cameras[0].model = CameraModelType::kFullOpenCv;
    rational.cameras[0].params = {400, 400, 200, 150, 0, 0, 0, 0, 0, 0.1, 0, 0};
    const Status status = FormatOpenSfmReconstruction(rational, nullptr, &text);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.message(),
              "camera 'c' (FULL_OPENCV with k4, k5 or k6) is no OpenSfM projection");
  }
  {
    Block frame = block;
    frame.cameras[0].model = CameraModelType::kFrame;
    frame.cameras[0].params.assign(kFrameNumParams, 0.0);
    frame.cameras[0].params[kFrameFocal] = 1000.0;
    const Status status = FormatOpenSfmReconstruction(frame, nullptr, &text);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("camera 'c' is a frame camera"), std::string::npos);
  }
  {
    Block unoriented = block;
    unoriented.images[0].eo.reset();
    const Status status = FormatOpenSfmReconstruction(unoriented, nullptr, &text);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.message(),
              "image 'a.jpg' has no exterior orientation: an OpenSfM reconstruction holds oriented "
              "images only");
  }
  {
    Block tab = block;
    tab.images[0].name = "a\tb.jpg";
    EXPECT_FALSE(FormatOpenSfmReconstruction(tab, nullptr, &text).ok());
  }
  // Nothing is written when formatting fails.
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  Block unoriented = block;
  unoriented.images[0].eo.reset();
  EXPECT_FALSE(WriteOpenSfmReconstruction(dir.path(), unoriented).ok());
  EXPECT_FALSE(std::filesystem::exists(dir.Path("reconstruction.json")));
  EXPECT_FALSE(std::filesystem::exists(dir.Path("tracks.csv")));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
