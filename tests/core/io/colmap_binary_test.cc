// Binary COLMAP models (core/io/colmap_binary.cc, through the public API of core/io/colmap.h):
// byte layout, round trips with the text format, refusals, and COLMAP's own tools as the peer.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/io/colmap.h"
#include "core/io/csv.h"
#include "tests/support/temp_dir.h"
#include "tests/test_data.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::ScopedTempDir;

std::string Ar7() { return testing::SharedDataPath("colmap_ar7"); }

// Little-endian pieces of hand-made files.
void PutU(uint64_t value, int bytes, std::string* out) {
  for (int k = 0; k < bytes; ++k) out->push_back(static_cast<char>((value >> (8 * k)) & 0xff));
}
void PutD(double value, std::string* out) {
  uint64_t bits;
  std::memcpy(&bits, &value, 8);
  PutU(bits, 8, out);
}

// One SIMPLE_PINHOLE camera 1 (100 x 80, f 100, c (50, 40)); image 1 "a.jpg" at the identity
// pose with keypoints (60, 60) -> point 3 and (10, 10) -> none; point 3 at (1, 2, 10) seen by
// (1, 0). The same model as text: "1 SIMPLE_PINHOLE 100 80 100 50 40", "1 1 0 0 0 0 0 0 1 a.jpg",
// "60 60 3 10 10 -1", "3 1 2 10 10 20 30 0.5 1 0".
struct SmallModel {
  std::string cameras, images, points;
  SmallModel() {
    PutU(1, 8, &cameras);
    PutU(1, 4, &cameras);
    PutU(0, 4, &cameras);  // SIMPLE_PINHOLE
    PutU(100, 8, &cameras);
    PutU(80, 8, &cameras);
    for (const double p : {100.0, 50.0, 40.0}) PutD(p, &cameras);
    PutU(1, 8, &images);
    PutU(1, 4, &images);
    for (const double v : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}) PutD(v, &images);
    PutU(1, 4, &images);
    images += std::string("a.jpg") + '\0';
    PutU(2, 8, &images);
    PutD(60.0, &images);
    PutD(60.0, &images);
    PutU(3, 8, &images);
    PutD(10.0, &images);
    PutD(10.0, &images);
    PutU(UINT64_MAX, 8, &images);
    PutU(1, 8, &points);
    PutU(3, 8, &points);
    for (const double v : {1.0, 2.0, 10.0}) PutD(v, &points);
    points += std::string("\x0a\x14\x1e", 3);
    PutD(0.5, &points);
    PutU(1, 8, &points);
    PutU(1, 4, &points);
    PutU(0, 4, &points);
  }
  ColmapModelFiles Files() const { return {ColmapFormat::kBinary, cameras, images, points}; }
};

// A model's content keyed by its ids and names, whatever the order of its records (COLMAP writes
// images and points in an order of its own), every double as read: compared with ==, to the last
// bit.
struct ModelContent {
  using Doubles = std::vector<double>;
  std::map<std::string, std::tuple<int, int, int, Doubles>> cameras;     // id: model, w, h, params
  std::map<std::string, std::pair<std::string, Doubles>> images;         // name: camera id, eo
  std::map<std::string, Doubles> points;                                 // id: X Y Z
  std::set<std::tuple<std::string, std::string, double, double>> marks;  // image, point, x, y
  // With the extras: image name -> (IMAGE_ID, number of keypoints); marks with their POINT2D
  // index; unmatched keypoints; colour and ERROR per point id.
  std::map<std::string, std::pair<long long, int>> image_ids;
  std::set<std::tuple<std::string, std::string, int>> mark_indices;
  std::set<std::tuple<std::string, int, double, double>> unmatched;
  std::map<std::string, std::pair<std::array<unsigned char, 3>, double>> point_extras;

  ModelContent(const Block& block, const ColmapModelExtras& extras) {
    for (const BlockCamera& c : block.cameras) {
      cameras[c.camera_id] = {static_cast<int>(c.model), c.table.n_columns, c.table.n_rows,
                              c.params};
    }
    for (size_t i = 0; i < block.images.size(); ++i) {
      const BlockImage& image = block.images[i];
      const auto& eo = image.eo->parameters;
      images[image.name] = {block.cameras[image.camera].camera_id,
                            Doubles(eo.data(), eo.data() + eo.size())};
      image_ids[image.name] = {extras.image_ids[i], extras.num_keypoints[i]};
    }
    for (size_t p = 0; p < block.points.size(); ++p) {
      const Eigen::Vector3d& X = *block.points[p].position_m;
      points[block.points[p].id] = {X.x(), X.y(), X.z()};
      point_extras[block.points[p].id] = {extras.point_rgb[p], extras.point_error_px[p]};
    }
    for (size_t m = 0; m < block.marks.size(); ++m) {
      const BlockMark& mark = block.marks[m];
      const std::string& image = block.images[mark.image].name;
      const std::string& point = block.points[mark.point].id;
      marks.insert({image, point, mark.observation.x(), mark.observation.y()});
      mark_indices.insert({image, point, extras.mark_keypoint_index[m]});
    }
    for (const ColmapKeypoint& k : extras.unmatched)
      unmatched.insert({block.images[k.image].name, k.index, k.xy.x(), k.xy.y()});
  }
};

// Two models with the same content; the poses and the ERROR column to `relative` of their
// magnitude (at least 1), everything else to the last bit (0: all of it).
void ExpectSameModel(const Block& a, const ColmapModelExtras& a_extras, const Block& b,
                     const ColmapModelExtras& b_extras, double relative = 0.0) {
  ModelContent x(a, a_extras), y(b, b_extras);
  ASSERT_EQ(x.images.size(), y.images.size());
  for (auto& [name, image] : x.images) {
    ASSERT_EQ(y.images.count(name), 1u) << name;
    auto& other = y.images.at(name);
    EXPECT_EQ(image.first, other.first);
    for (size_t k = 0; k < image.second.size(); ++k) {
      EXPECT_NEAR(image.second[k], other.second[k],
                  relative * std::max(1.0, std::abs(image.second[k])))
          << name << " " << k;
    }
    other.second = image.second;
  }
  for (auto& [id, extras] : x.point_extras) {
    ASSERT_EQ(y.point_extras.count(id), 1u) << id;
    auto& other = y.point_extras.at(id);
    EXPECT_NEAR(extras.second, other.second, relative * std::max(1.0, std::abs(extras.second)));
    other.second = extras.second;
  }
  EXPECT_EQ(x.cameras, y.cameras);
  EXPECT_EQ(x.images, y.images);
  EXPECT_EQ(x.points, y.points);
  EXPECT_EQ(x.marks, y.marks);
  EXPECT_EQ(x.image_ids, y.image_ids);
  EXPECT_EQ(x.mark_indices, y.mark_indices);
  EXPECT_EQ(x.unmatched, y.unmatched);
  EXPECT_EQ(x.point_extras, y.point_extras);
}

TEST(ColmapBinary, HandMadeModelReadsAsItsText) {
  const SmallModel binary;
  Block from_binary, from_text;
  ColmapModelExtras extras_binary, extras_text;
  Status status = ParseColmapModel(binary.Files(), "m", &from_binary, &extras_binary);
  ASSERT_TRUE(status.ok()) << status.message();
  const ColmapModelFiles text{ColmapFormat::kText, "1 SIMPLE_PINHOLE 100 80 100 50 40\n",
                              "1 1 0 0 0 0 0 0 1 a.jpg\n60 60 3 10 10 -1\n",
                              "3 1 2 10 10 20 30 0.5 1 0\n"};
  status = ParseColmapModel(text, "m", &from_text, &extras_text);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectSameModel(from_binary, extras_binary, from_text, extras_text);
  ASSERT_EQ(from_binary.marks.size(), 1u);
  EXPECT_EQ(from_binary.marks[0].observation, Eigen::Vector2d(60.0, 60.0));
  ASSERT_EQ(extras_binary.unmatched.size(), 1u);
  EXPECT_EQ(extras_binary.unmatched[0].index, 1);
  EXPECT_EQ(extras_binary.point_rgb[0], (std::array<unsigned char, 3>{10, 20, 30}));
  EXPECT_EQ(extras_binary.point_error_px[0], 0.5);

  // Written back: the same bytes but for the pose (through the block's angles: the quaternion
  // comes back to about 1e-16) and ERROR (recomputed: about 1e-14 px where the file says 0.5).
  ColmapModelFiles written;
  ColmapWriteOptions options;
  options.format = ColmapFormat::kBinary;
  status = FormatColmapModel(from_binary, &extras_binary, options, &written);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(written.cameras, binary.cameras);
  constexpr size_t kPoseBegin = 12, kPoseEnd = 68, kErrorBegin = 43, kErrorEnd = 51;
  ASSERT_EQ(written.images.size(), binary.images.size());
  EXPECT_EQ(written.images.substr(0, kPoseBegin), binary.images.substr(0, kPoseBegin));
  EXPECT_EQ(written.images.substr(kPoseEnd), binary.images.substr(kPoseEnd));
  ASSERT_EQ(written.points3D.size(), binary.points.size());
  EXPECT_EQ(written.points3D.substr(0, kErrorBegin), binary.points.substr(0, kErrorBegin));
  EXPECT_EQ(written.points3D.substr(kErrorEnd), binary.points.substr(kErrorEnd));
  Block again;
  ASSERT_TRUE(ParseColmapModel(written, "m", &again).ok());
  EXPECT_LT(
      (again.images[0].eo->parameters - from_binary.images[0].eo->parameters).cwiseAbs().maxCoeff(),
      1e-15);
}

TEST(ColmapBinary, Ar7TextAndBinaryRoundTripsAreBitExact) {
  Block block;
  ColmapModelExtras extras;
  ASSERT_TRUE(ReadColmapModel(Ar7(), &block, &extras).ok());
  // The block as text and as binary: both read back as the same block, to the last bit.
  ColmapWriteOptions as_text, as_binary;
  as_binary.format = ColmapFormat::kBinary;
  ColmapModelFiles text, binary;
  ASSERT_TRUE(FormatColmapModel(block, &extras, as_text, &text).ok());
  ASSERT_TRUE(FormatColmapModel(block, &extras, as_binary, &binary).ok());
  Block from_text, from_binary;
  ColmapModelExtras extras_text, extras_binary;
  ASSERT_TRUE(ParseColmapModel(text, "t", &from_text, &extras_text).ok());
  Status status = ParseColmapModel(binary, "b", &from_binary, &extras_binary);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectSameModel(from_text, extras_text, from_binary, extras_binary);

  // Through the folder: ReadColmapModel finds the binary files and says so.
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  status = WriteColmapModel(dir.path(), block, &extras, as_binary);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_TRUE(std::filesystem::exists(dir.Path("images.bin")));
  EXPECT_FALSE(std::filesystem::exists(dir.Path("images.txt")));
  Block read;
  ColmapModelExtras read_extras;
  ColmapFormat format = ColmapFormat::kText;
  ASSERT_TRUE(ReadColmapModel(dir.path(), &read, &read_extras, &format).ok());
  EXPECT_EQ(format, ColmapFormat::kBinary);
  ExpectSameModel(read, read_extras, from_binary, extras_binary);
}

TEST(ColmapBinary, BinaryIsPreferredAndAnIncompleteFolderIsNamed) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const SmallModel binary;
  dir.Write("cameras.txt", "1 PINHOLE 100 80 100 100 50 40\n");
  dir.Write("images.txt", "\n");
  dir.Write("points3D.txt", "");
  Block block;
  ColmapFormat format = ColmapFormat::kBinary;
  ASSERT_TRUE(ReadColmapModel(dir.path(), &block, nullptr, &format).ok());
  EXPECT_EQ(format, ColmapFormat::kText);
  EXPECT_EQ(block.cameras[0].model, CameraModelType::kPinhole);
  dir.Write("cameras.bin", binary.cameras);
  dir.Write("images.bin", binary.images);
  dir.Write("points3D.bin", binary.points);
  ASSERT_TRUE(ReadColmapModel(dir.path(), &block, nullptr, &format).ok());
  EXPECT_EQ(format, ColmapFormat::kBinary);
  EXPECT_EQ(block.cameras[0].model, CameraModelType::kSimplePinhole);

  std::filesystem::remove(dir.Path("images.bin"));
  std::filesystem::remove(dir.Path("points3D.txt"));
  EXPECT_EQ(ReadColmapModel(dir.path(), &block).message(),
            dir.path() +
                ": no complete COLMAP model (cameras, images and points3D, all .bin or all "
                ".txt): points3D.txt missing");
  EXPECT_EQ(ReadColmapModel(dir.Path("nowhere"), &block).message(),
            dir.Path("nowhere") +
                ": is no folder; a COLMAP model is a folder with cameras, images and points3D "
                "files (.bin or .txt)");
}

struct BadBinary {
  const char* name;
  int file;         // 0 cameras, 1 images, 2 points3D
  size_t cut;       // keep the first `cut` bytes (0: all)
  size_t patch_at;  // then write `patch` there (when not empty)
  std::string patch;
  std::string append;  // then append this
  const char* message;
};

std::string U64(uint64_t v) {
  std::string s;
  PutU(v, 8, &s);
  return s;
}
std::string U32(uint64_t v) {
  std::string s;
  PutU(v, 4, &s);
  return s;
}

class ColmapBinaryBadInput : public ::testing::TestWithParam<BadBinary> {};

TEST_P(ColmapBinaryBadInput, ClearMessage) {
  const BadBinary& bad = GetParam();
  SmallModel model;
  std::string* file[] = {&model.cameras, &model.images, &model.points};
  std::string& bytes = *file[bad.file];
  if (bad.cut > 0) bytes.resize(bad.cut);
  if (!bad.patch.empty()) bytes.replace(bad.patch_at, bad.patch.size(), bad.patch);
  bytes += bad.append;
  Block block;
  const Status status = ParseColmapModel(model.Files(), "m", &block);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), std::string("m/") + bad.message);
}

// Offsets in SmallModel: cameras.bin: camera at 8 (MODEL_ID 12, WIDTH 16, PARAMS at 32);
// images.bin: image at 8 (CAMERA_ID 68, NAME 72, count 78, POINTS2D at 86, second entry 110);
// points3D.bin: point at 8 (X 16, ERROR 43, track length 51, TRACK at 59).
INSTANTIATE_TEST_SUITE_P(
    Cases, ColmapBinaryBadInput,
    ::testing::Values(
        BadBinary{"Truncated", 0, 50, 0, "", "",
                  "cameras.bin: byte 48: PARAMS cy: the file ends inside it (2 bytes left, 8 "
                  "needed)"},
        BadBinary{"HugeCount", 1, 0, 0, U64(uint64_t{1} << 62), "",
                  "images.bin: byte 0: number of images: 4611686018427387904 records of at least "
                  "73 bytes do not fit in the 126 bytes left in the file"},
        BadBinary{"HugeTrack", 2, 0, 51, U64(1000), "",
                  "points3D.bin: byte 51: track length: 1000 records of at least 8 bytes do not "
                  "fit in the 8 bytes left in the file"},
        BadBinary{"UnsupportedModel", 0, 0, 12, U32(7), "",
                  "cameras.bin: byte 12: MODEL_ID: camera model 7 (FOV) is not supported "
                  "(supported: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, "
                  "OPENCV_FISHEYE, FULL_OPENCV)"},
        BadBinary{"UnknownModel", 0, 0, 12, U32(0xffffffff), "",
                  "cameras.bin: byte 12: MODEL_ID: -1 is no COLMAP camera model"},
        BadBinary{"NameWithoutNul", 1, 72, 0, "", "abcdefghijklmnopqrstu",
                  "images.bin: byte 72: NAME: no NUL byte ends it before the end of the file (21 "
                  "bytes left)"},
        BadBinary{"CutInsideTheName", 1, 77, 0, "", "",
                  "images.bin: byte 0: number of images: 1 records of at least 73 bytes do not "
                  "fit in the 69 bytes left in the file"},
        BadBinary{"TrackNamesMissingImage", 2, 0, 59, U32(9), "",
                  "points3D.bin: byte 59: TRACK: entry (9, 0): image 9 is not in images.bin"},
        BadBinary{"UnknownPoint", 1, 0, 126, U64(4), "",
                  "images.bin: byte 110: POINTS2D POINT3D_ID: point 4 is not in points3D.bin"},
        BadBinary{"TrailingBytes", 0, 0, 0, "", "xyz",
                  "cameras.bin: byte 56: end: 3 bytes after the last record"},
        BadBinary{"ZeroWidth", 0, 0, 16, U64(0), "",
                  "cameras.bin: byte 8: WIDTH: 0 is out of range [1, 2147483647]"},
        BadBinary{"NanTranslation", 1, 0, 60, U64(0x7ff8000000000000ULL), "",
                  "images.bin: byte 8: TZ: nan is not a finite number"},
        BadBinary{"HugePoint", 2, 0, 24, U64(0x7fe0000000000000ULL), "",
                  "points3D.bin: byte 8: Y: 8.98846567431158e+307 is outside [-100000000, "
                  "100000000] m"},
        BadBinary{"PointIdAbove63Bits", 2, 0, 8, U64(UINT64_MAX), "",
                  "points3D.bin: byte 8: POINT3D_ID: 18446744073709551615 is out of range [0, "
                  "2^63 - 1]"}),
    [](const ::testing::TestParamInfo<BadBinary>& info) { return std::string(info.param.name); });

TEST(ColmapBinary, EmptyFileIsTruncatedAtItsCount) {
  SmallModel model;
  model.points.clear();
  Block block;
  EXPECT_EQ(ParseColmapModel(model.Files(), "m", &block).message(),
            "m/points3D.bin: byte 0: number of points: the file ends inside it (0 bytes left, 8 "
            "needed)");
}

TEST(ColmapBinary, AFifoOrAFileOverTheLimitIsRefusedWithoutWaitingOrReading) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const SmallModel model;
  dir.Write("cameras.bin", model.cameras);
  dir.Write("points3D.bin", model.points);
  ASSERT_EQ(mkfifo(dir.Path("images.bin").c_str(), 0644), 0);
  Block block;
  EXPECT_EQ(ReadColmapModel(dir.path(), &block).message(),
            dir.Path("images.bin") +
                ": is a FIFO (named pipe), not a regular file; photopose reads regular files, or "
                "standard input for '-'");
  std::filesystem::remove(dir.Path("images.bin"));
  dir.Write("images.bin", model.images);
  std::filesystem::resize_file(dir.Path("points3D.bin"), kMaxInputBytes + 1);  // sparse
  EXPECT_EQ(ReadColmapModel(dir.path(), &block).message(),
            dir.Path("points3D.bin") +
                ": is larger than 268435456 bytes, the largest input photopose reads");
}

// ------------------------------------------------------------------ COLMAP itself as the peer

bool HaveColmap() { return std::system("command -v colmap > /dev/null 2>&1") == 0; }

int RunQuietly(const std::string& command) {
  return std::system((command + " > /dev/null 2>&1").c_str());
}

TEST(ColmapBinary, ColmapReadsOurBinaryAsWeDo) {
  if (!HaveColmap()) GTEST_SKIP() << "colmap is not on the PATH: no peer to check against";
  Block block;
  ColmapModelExtras extras;
  ASSERT_TRUE(ReadColmapModel(Ar7(), &block, &extras).ok());
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  ColmapWriteOptions options;
  options.format = ColmapFormat::kBinary;
  ASSERT_TRUE(WriteColmapModel(dir.Path("ours"), block, &extras, options).ok());
  Block ours;
  ColmapModelExtras ours_extras;
  ASSERT_TRUE(ReadColmapModel(dir.Path("ours"), &ours, &ours_extras).ok());

  EXPECT_EQ(RunQuietly("colmap model_analyzer --path " + dir.Path("ours")), 0);
  std::filesystem::create_directories(dir.Path("converted"));
  ASSERT_EQ(RunQuietly("colmap model_converter --input_path " + dir.Path("ours") +
                       " --output_path " + dir.Path("converted") + " --output_type TXT"),
            0);
  ASSERT_TRUE(std::filesystem::exists(dir.Path("converted/images.txt")));
  Block converted;
  ColmapModelExtras converted_extras;
  const Status status = ReadColmapModel(dir.Path("converted"), &converted, &converted_extras);
  ASSERT_TRUE(status.ok()) << status.message();
  // COLMAP writes text with 17 significant digits: every double comes back to the last bit.
  ExpectSameModel(converted, converted_extras, ours, ours_extras);
}

TEST(ColmapBinary, ColmapsBinaryOfTheSharedModelReadsAsItsText) {
  if (!HaveColmap()) GTEST_SKIP() << "colmap is not on the PATH: no peer to check against";
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  std::filesystem::create_directories(dir.Path("bin"));
  ASSERT_EQ(RunQuietly("colmap model_converter --input_path " + Ar7() + " --output_path " +
                       dir.Path("bin") + " --output_type BIN"),
            0);
  Block text, binary;
  ColmapModelExtras text_extras, binary_extras;
  ColmapFormat format = ColmapFormat::kText;
  ASSERT_TRUE(ReadColmapModel(Ar7(), &text, &text_extras).ok());
  const Status status = ReadColmapModel(dir.Path("bin"), &binary, &binary_extras, &format);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(format, ColmapFormat::kBinary);
  // COLMAP normalises each quaternion as it reads the text and writes that (our reader normalises
  // again: a few ulp of the pose), and its text parser reads one ERROR of the 2707,
  // 0.781028, as 0.7810280000000001 (one ulp off). Everything else to the last bit.
  constexpr double kColmapsReadingUlps = 1e-15;
  ExpectSameModel(binary, binary_extras, text, text_extras, kColmapsReadingUlps);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
