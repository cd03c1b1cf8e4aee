#include "core/io/exif_gps.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include "core/io/csv.h"

#include "tests/support/geotagged_jpeg.h"
#include "tests/support/temp_dir.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::GeotagOptions;
using testing::ScopedTempDir;
using testing::SetXmpText;
using testing::WriteGeotaggedJpeg;
using testing::WriteGeotaggedTiff;

TEST(ExifGps, ReadsTheExifGpsTagsWithTheirHemispheresAndAltitudeReference) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  GeotagOptions tags;
  tags.exif_lon_lat_height = Eigen::Vector3d(-71.1234567, -33.4567891, -12.3456);  // W, S, below
  WriteGeotaggedJpeg(dir.Path("a.jpg"), tags);
  ExifGps gps;
  const Status read = ReadExifGps(dir.Path("a.jpg"), &gps);
  ASSERT_TRUE(read.ok()) << read.message();
  EXPECT_EQ(gps.source, ExifGpsSource::kExif);
  EXPECT_NEAR(gps.lon_lat_height.x(), -71.1234567, 1e-9);  // 1e-6 arc seconds written
  EXPECT_NEAR(gps.lon_lat_height.y(), -33.4567891, 1e-9);
  EXPECT_NEAR(gps.lon_lat_height.z(), -12.3456, 1e-9);
  EXPECT_FALSE(gps.rtk_sigma_enu_m.has_value());
  EXPECT_FALSE(gps.rtk_flag.has_value());
}

TEST(ExifGps, ExifWinsOverDjiXmpAndRtkAccuraciesAreReadAlongEastNorthUp) {
  ScopedTempDir dir;
  GeotagOptions tags;
  tags.exif_lon_lat_height = Eigen::Vector3d(11.2, 47.8, 612.5);
  tags.dji_lon_lat_height = Eigen::Vector3d(11.3, 47.9, 600.0);
  tags.rtk_sigma_enu_m = Eigen::Vector3d(0.011, 0.012, 0.025);
  tags.rtk_flag = 50;
  WriteGeotaggedJpeg(dir.Path("a.jpg"), tags);
  ExifGps gps;
  ASSERT_TRUE(ReadExifGps(dir.Path("a.jpg"), &gps).ok());
  EXPECT_EQ(gps.source, ExifGpsSource::kExif);
  EXPECT_NEAR(gps.lon_lat_height.x(), 11.2, 1e-9);
  EXPECT_NEAR(gps.lon_lat_height.z(), 612.5, 1e-9);
  ASSERT_TRUE(gps.rtk_sigma_enu_m.has_value());
  EXPECT_DOUBLE_EQ(gps.rtk_sigma_enu_m->x(), 0.011);
  EXPECT_DOUBLE_EQ(gps.rtk_sigma_enu_m->y(), 0.012);
  EXPECT_DOUBLE_EQ(gps.rtk_sigma_enu_m->z(), 0.025);
  EXPECT_EQ(gps.rtk_flag, 50);
}

TEST(ExifGps, FallsBackToDjiXmpIncludingItsMisspeltLongitude) {
  ScopedTempDir dir;
  GeotagOptions tags;
  tags.dji_lon_lat_height = Eigen::Vector3d(8.5432109876, 47.3765432109, 488.123);
  tags.dji_misspelt_longitude = true;
  tags.rtk_sigma_enu_m = Eigen::Vector3d(0.0, 0.0, 0.0);  // no RTK solution: no accuracy
  WriteGeotaggedJpeg(dir.Path("dji.jpg"), tags);
  ExifGps gps;
  const Status read = ReadExifGps(dir.Path("dji.jpg"), &gps);
  ASSERT_TRUE(read.ok()) << read.message();
  EXPECT_EQ(gps.source, ExifGpsSource::kDjiXmp);
  EXPECT_NEAR(gps.lon_lat_height.x(), 8.5432109876, 1e-10);
  EXPECT_NEAR(gps.lon_lat_height.y(), 47.3765432109, 1e-10);
  EXPECT_NEAR(gps.lon_lat_height.z(), 488.123, 1e-10);
  EXPECT_FALSE(gps.rtk_sigma_enu_m.has_value());
}

TEST(ExifGps, ImagesWithoutGpsAreListedOtherFailuresAreErrors) {
  ScopedTempDir dir;
  GeotagOptions tagged;
  tagged.exif_lon_lat_height = Eigen::Vector3d(11.2, 47.8, 500.0);
  WriteGeotaggedJpeg(dir.Path("sub/a.jpg"), tagged);
  WriteGeotaggedJpeg(dir.Path("b.jpg"), GeotagOptions());
  std::vector<std::optional<ExifGps>> positions;
  std::vector<std::string> missing;
  const Status read = ReadExifGpsOfImages(dir.path(), {"sub/a.jpg", "b.jpg"}, &positions, &missing);
  ASSERT_TRUE(read.ok()) << read.message();
  ASSERT_EQ(positions.size(), 2u);
  EXPECT_TRUE(positions[0].has_value());
  EXPECT_FALSE(positions[1].has_value());
  EXPECT_EQ(missing, std::vector<std::string>{"b.jpg"});

  ExifGps gps;
  const Status none = ReadExifGps(dir.Path("b.jpg"), &gps);
  EXPECT_FALSE(none.ok());
  EXPECT_NE(none.message().find("no GPS position"), std::string::npos) << none.message();

  const Status absent = ReadExifGpsOfImages(dir.path(), {"c.jpg"}, &positions, &missing);
  EXPECT_FALSE(absent.ok());
  EXPECT_NE(absent.message().find("c.jpg: no such image file"), std::string::npos) << absent.message();
}

TEST(ExifGps, GarbageAndMalformedTagsAreErrorsNamingFileAndTag) {
  ScopedTempDir dir;
  const std::string garbage = dir.Write("garbage.jpg", std::string("\xff\xd8\xff\xe1\x00\x10" "Exif\0\0II*\0\x08\0\0\0\xff\xff", 22));
  ExifGps gps;
  const Status g = ReadExifGps(garbage, &gps);
  EXPECT_FALSE(g.ok());
  EXPECT_NE(g.message().find("garbage.jpg"), std::string::npos) << g.message();
  const std::string text = dir.Write("notes.jpg", "not an image at all\n");
  EXPECT_FALSE(ReadExifGps(text, &gps).ok());

  // A latitude of 95 degrees.
  GeotagOptions tags;
  tags.exif_lon_lat_height = Eigen::Vector3d(11.2, 95.0, 500.0);
  WriteGeotaggedJpeg(dir.Path("polar.jpg"), tags);
  const Status polar = ReadExifGps(dir.Path("polar.jpg"), &gps);
  EXPECT_FALSE(polar.ok());
  EXPECT_NE(polar.message().find("Exif.GPSInfo.GPSLatitude"), std::string::npos) << polar.message();

  // A DJI latitude that is not a number.
  GeotagOptions dji;
  dji.dji_lon_lat_height = Eigen::Vector3d(11.2, 47.8, 500.0);
  WriteGeotaggedJpeg(dir.Path("dji.jpg"), dji);
  SetXmpText(dir.Path("dji.jpg"), "Xmp.drone-dji.GpsLatitude", "47.8N");
  const Status bad = ReadExifGps(dir.Path("dji.jpg"), &gps);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("Xmp.drone-dji.GpsLatitude: not a number: '47.8N'"), std::string::npos) << bad.message();
}

std::string FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(ExifGps, BytesInMemoryReadAsTheFileDoes) {
  ScopedTempDir dir;
  GeotagOptions tags;
  tags.dji_lon_lat_height = Eigen::Vector3d(8.5432109876, 47.3765432109, 488.123);
  tags.rtk_sigma_enu_m = Eigen::Vector3d(0.011, 0.012, 0.025);
  tags.rtk_flag = 50;
  WriteGeotaggedJpeg(dir.Path("dji.jpg"), tags);
  ExifGps from_file, from_memory;
  ASSERT_TRUE(ReadExifGps(dir.Path("dji.jpg"), &from_file).ok());
  const Status parsed = ParseExifGps(FileBytes(dir.Path("dji.jpg")), "dji.jpg", &from_memory);
  ASSERT_TRUE(parsed.ok()) << parsed.message();
  EXPECT_EQ(from_memory.lon_lat_height, from_file.lon_lat_height);
  EXPECT_EQ(from_memory.source, ExifGpsSource::kDjiXmp);
  EXPECT_EQ(from_memory.rtk_sigma_enu_m, from_file.rtk_sigma_enu_m);
  EXPECT_EQ(from_memory.rtk_flag, 50);
  const Status none = ParseExifGps("", "empty.jpg", &from_memory);
  EXPECT_EQ(none.message().rfind("empty.jpg: ", 0), 0u) << none.message();
}

// exiv2 throws Exiv2::Error on corrupt files: every cut of a geotagged JPEG is read or refused with
// one line naming the file, never an exception.
TEST(ExifGps, EveryTruncationOfAGeotaggedJpegIsAPositionOrAnErrorNamingTheFile) {
  ScopedTempDir dir;
  GeotagOptions tags;
  tags.exif_lon_lat_height = Eigen::Vector3d(11.2, 47.8, 612.5);
  tags.dji_lon_lat_height = Eigen::Vector3d(11.3, 47.9, 600.0);
  tags.rtk_sigma_enu_m = Eigen::Vector3d(0.011, 0.012, 0.025);
  WriteGeotaggedJpeg(dir.Path("a.jpg"), tags);
  const std::string bytes = FileBytes(dir.Path("a.jpg"));
  ASSERT_GT(bytes.size(), 100u);
  int errors = 0;
  for (size_t size = 0; size < bytes.size(); size += 7) {
    ExifGps gps;
    Status status;
    ASSERT_NO_THROW(status = ParseExifGps(std::string_view(bytes).substr(0, size), "cut.jpg", &gps));
    if (status.ok()) {
      EXPECT_NEAR(gps.lon_lat_height.y(), 47.8, 1e-9);
      continue;
    }
    ++errors;
    EXPECT_EQ(status.message().rfind("cut.jpg: ", 0), 0u) << status.message();
    EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
    EXPECT_LT(status.message().size(), 400u) << status.message();
  }
  EXPECT_GT(errors, 0);
}

TEST(ExifGps, AFifoIsRefusedWithoutWaitingAndLongValuesAreEchoedCut) {
  ScopedTempDir dir;
  ASSERT_EQ(mkfifo(dir.Path("pipe.jpg").c_str(), 0600), 0);
  ExifGps gps;
  const Status fifo = ReadExifGps(dir.Path("pipe.jpg"), &gps);
  EXPECT_NE(fifo.message().find("pipe.jpg: not a regular file"), std::string::npos) << fifo.message();

  GeotagOptions dji;
  dji.dji_lon_lat_height = Eigen::Vector3d(11.2, 47.8, 500.0);
  WriteGeotaggedJpeg(dir.Path("dji.jpg"), dji);
  SetXmpText(dir.Path("dji.jpg"), "Xmp.drone-dji.AbsoluteAltitude", std::string(5000, '9') + "x");
  const Status long_value = ReadExifGps(dir.Path("dji.jpg"), &gps);
  EXPECT_NE(long_value.message().find("Xmp.drone-dji.AbsoluteAltitude: not a number: '" + std::string(40, '9') +
                                      "\u2026(5001 bytes)'"),
            std::string::npos)
      << long_value.message();
  // A height beyond the documented 1e8 m.
  SetXmpText(dir.Path("dji.jpg"), "Xmp.drone-dji.AbsoluteAltitude", "1e300");
  EXPECT_NE(ReadExifGps(dir.Path("dji.jpg"), &gps).message().find("AbsoluteAltitude: outside [-100000000, 100000000] m"),
            std::string::npos);
}

// A TIFF (as DNG and most raw formats are) carrying the tags a drone writes: the GPS position
// and DJI's RTK accuracies, read from the file and from its bytes alike.
GeotagOptions DroneTags() {
  GeotagOptions tags;
  tags.exif_lon_lat_height = Eigen::Vector3d(-71.1234567, -33.4567891, 812.3456);
  tags.rtk_sigma_enu_m = Eigen::Vector3d(0.011, 0.012, 0.025);
  tags.rtk_flag = 50;
  return tags;
}

TEST(ExifGps, ReadsATiffFromItsBytesAsAJpeg) {
  ScopedTempDir dir;
  WriteGeotaggedTiff(dir.Path("a.tif"), DroneTags());
  WriteGeotaggedJpeg(dir.Path("a.jpg"), DroneTags());
  ASSERT_EQ(FileBytes(dir.Path("a.tif")).substr(0, 4), std::string("II*\0", 4));  // a TIFF
  ExifGps tiff, jpeg, memory;
  const Status read = ReadExifGps(dir.Path("a.tif"), &tiff);
  ASSERT_TRUE(read.ok()) << read.message();
  ASSERT_TRUE(ReadExifGps(dir.Path("a.jpg"), &jpeg).ok());
  EXPECT_EQ(tiff.source, ExifGpsSource::kExif);
  EXPECT_NEAR(tiff.lon_lat_height.x(), -71.1234567, 1e-9);  // 1e-6 arc seconds written
  EXPECT_NEAR(tiff.lon_lat_height.y(), -33.4567891, 1e-9);
  EXPECT_NEAR(tiff.lon_lat_height.z(), 812.3456, 1e-9);
  EXPECT_EQ(tiff.lon_lat_height, jpeg.lon_lat_height);
  EXPECT_EQ(tiff.rtk_sigma_enu_m, jpeg.rtk_sigma_enu_m);
  EXPECT_EQ(tiff.rtk_flag, 50);
  ASSERT_TRUE(ParseExifGps(FileBytes(dir.Path("a.tif")), "a.tif", &memory).ok());
  EXPECT_EQ(memory.lon_lat_height, tiff.lon_lat_height);
}

TEST(ExifGps, EveryTruncatedTiffIsAPositionOrAnErrorNamingTheFile) {
  ScopedTempDir dir;
  WriteGeotaggedTiff(dir.Path("a.tif"), DroneTags());
  const std::string bytes = FileBytes(dir.Path("a.tif"));
  ASSERT_GT(bytes.size(), 100u);
  int errors = 0;
  for (size_t size = 0; size < bytes.size(); size += 5) {
    const std::string cut = dir.Write("cut.tif", bytes.substr(0, size));
    ExifGps gps;
    Status status;
    ASSERT_NO_THROW(status = ReadExifGps(cut, &gps));
    if (status.ok()) {
      EXPECT_NEAR(gps.lon_lat_height.y(), -33.4567891, 1e-9) << size;
      continue;
    }
    ++errors;
    EXPECT_EQ(status.message().rfind(cut + ": ", 0), 0u) << status.message();
    EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
  }
  EXPECT_GT(errors, 0);
}

TEST(ExifGps, ATiffOverTheInputLimitIsAnErrorNamingTheFile) {
  // A sparse file: a TIFF's first bytes, then zeros up to one byte over the limit.
  ScopedTempDir dir;
  WriteGeotaggedTiff(dir.Path("huge.tif"), DroneTags());
  ASSERT_EQ(truncate(dir.Path("huge.tif").c_str(), static_cast<off_t>(kMaxInputBytes) + 1), 0);
  ExifGps gps;
  const Status huge = ReadExifGps(dir.Path("huge.tif"), &gps);
  EXPECT_EQ(huge.message(), dir.Path("huge.tif") + ": is larger than 268435456 bytes, the largest "
                                                   "input photopose reads");
  // An unreadable one.
  WriteGeotaggedTiff(dir.Path("locked.tif"), DroneTags());
  ASSERT_EQ(chmod(dir.Path("locked.tif").c_str(), 0), 0);
  if (geteuid() != 0) {  // root reads it anyway
    const Status locked = ReadExifGps(dir.Path("locked.tif"), &gps);
    EXPECT_FALSE(locked.ok());
    EXPECT_EQ(locked.message().rfind(dir.Path("locked.tif") + ": ", 0), 0u) << locked.message();
  }
}

// The SIGBUS of issue 20: exiv2 maps a TIFF while it parses it, and dies when the file shrinks
// meanwhile. A thread cuts a 4 MB TIFF (its GPS directory after the 4 MB description) to 64 bytes
// and writes it back, again and again, while this one reads it: every read is the position or an
// error naming the file, and the process lives.
TEST(ExifGps, ATiffThatShrinksWhileReadIsNeverACrash) {
  ScopedTempDir dir;
  GeotagOptions tags = DroneTags();
  tags.description_bytes = size_t{4} << 20;
  const std::string path = dir.Path("shrinking.tif");
  WriteGeotaggedTiff(path, tags);
  const std::string bytes = FileBytes(path);
  ASSERT_GT(bytes.size(), tags.description_bytes);
  std::atomic<bool> done{false};
  std::thread cutter([&] {
    const int fd = open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return;
    while (!done.load()) {
      if (ftruncate(fd, 64) != 0) break;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      if (pwrite(fd, bytes.data(), bytes.size(), 0) != static_cast<ssize_t>(bytes.size())) break;
    }
    close(fd);
  });
  int positions = 0, errors = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  while (std::chrono::steady_clock::now() < end || positions + errors < 20) {
    ExifGps gps;
    const Status status = ReadExifGps(path, &gps);
    if (status.ok()) {
      ++positions;
      EXPECT_NEAR(gps.lon_lat_height.y(), -33.4567891, 1e-9);
    } else {
      ++errors;
      EXPECT_EQ(status.message().rfind(path + ": ", 0), 0u) << status.message();
    }
  }
  done = true;
  cutter.join();
  EXPECT_GT(positions + errors, 0);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
