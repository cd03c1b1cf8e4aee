// libFuzzer harness: the EXIF / XMP GPS reader (core/io/exif_gps.h) on arbitrary bytes taken as an
// image file (any format libexiv2 recognises: JPEG, TIFF, PNG, ...). exiv2 throws on corrupt files;
// no exception may escape, and a message must be one clean line of bounded length naming the file.
// A position the reader accepts must be inside its documented ranges. Seeds: small JPEGs with EXIF
// GPS, DJI XMP and RTK tags, written at build time by exif_fuzzer_seeds.cc.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/io/exif_gps.h"
#include "core/io/tables.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

void Require(bool condition) {
  if (!condition) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  photopose::ExifGps gps;
  const photopose::Status status = photopose::ParseExifGps(bytes, "image.jpg", &gps);
  photopose::fuzz::CheckMessage(status);
  photopose::fuzz::CheckMessageLength(status);
  if (!status.ok()) {
    Require(status.message().rfind("image.jpg: ", 0) == 0);
    return 0;
  }
  const Eigen::Vector3d& p = gps.lon_lat_height;
  Require(std::abs(p.x()) <= 180.0 && std::abs(p.y()) <= 90.0 && std::abs(p.z()) <= photopose::kMaxCoordinate);
  if (gps.rtk_sigma_enu_m)
    Require(gps.rtk_sigma_enu_m->minCoeff() > 0.0 && gps.rtk_sigma_enu_m->maxCoeff() <= photopose::kMaxCoordinate);
  if (gps.rtk_flag) Require(*gps.rtk_flag >= 0 && *gps.rtk_flag <= 255);
  return 0;
}
