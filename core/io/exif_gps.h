#pragma once
// Camera positions from the images themselves: the EXIF GPS tags every drone and most cameras
// write, and the XMP tags of DJI's RTK drones (read with libexiv2).
//
// What is read, per image file:
//   - EXIF GPSLatitude / GPSLatitudeRef, GPSLongitude / GPSLongitudeRef (degrees, minutes, seconds
//     as three rationals) and GPSAltitude / GPSAltitudeRef (m; Ref 1 = below the reference).
//   - Where the EXIF GPS tags are missing, DJI's XMP drone-dji:GpsLatitude, GpsLongitude (also as
//     DJI misspells it, GpsLongtitude) and AbsoluteAltitude (decimal degrees, m).
//   - DJI's RTK accuracy tags drone-dji:RtkStdLon, RtkStdLat, RtkStdHgt (one sigma, m, along east,
//     north, up) and drone-dji:RtkFlag (the fix: 50 fixed, 34 float, 16 single point, 0 none).
//     An image without them has no stated accuracy (the bundle's default camera accuracy applies).
//
// Heights. The EXIF standard defines GPSAltitude above sea level; drones write ellipsoidal or
// orthometric (EGM96) heights depending on make, model and firmware, and nothing in the file says
// which. The reader returns the number as written; the caller names its CRS (the bundle's
// --exif_crs, EPSG:4979 by default: WGS84 with ellipsoidal heights; EPSG:4326+5773 takes them as
// EGM96 heights through PROJ's egm96_15.gtx).
//
// Coordinates come in GIS order (longitude, latitude, height), as core/geodesy/crs.h expects.
// Errors name the file and the tag; a file exiv2 cannot read is an error, never a crash: every
// exception of exiv2 (Exiv2::Error on a corrupt file) becomes a Status naming the file, its text
// escaped and cut to 200 bytes. Ranges (docs/formats.md): latitude [-90, 90] and longitude
// [-180, 180] degrees, height and RTK sigmas within 1e8 m, RtkFlag [0, 255]. Only regular files
// are opened (a FIFO would block). No file is ever memory-mapped, so one that shrinks while it is
// read is an error, never SIGBUS: a JPEG is read by exiv2 segment by segment up to its image data;
// every other format (TIFF, DNG, raw, which exiv2 would map) is read whole into memory first,
// at most kMaxInputBytes (core/io/csv.h; a larger file is an error naming it).

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/enum_names.h"
#include "core/status.h"

namespace photopose {

// Where a position was read: the EXIF GPS tags or DJI's XMP (drone-dji:*).
enum class ExifGpsSource { kExif, kDjiXmp };
inline constexpr EnumNameEntry<ExifGpsSource> kExifGpsSourceNames[] = {
    {ExifGpsSource::kExif, "exif"}, {ExifGpsSource::kDjiXmp, "dji_xmp"}};
constexpr EnumNameTable<ExifGpsSource> EnumNames(ExifGpsSource) {
  return EnumNameTable<ExifGpsSource>(kExifGpsSourceNames);
}

struct ExifGps {
  // Longitude (deg, east positive), latitude (deg, north positive), height (m, as written).
  Eigen::Vector3d lon_lat_height = Eigen::Vector3d::Zero();
  ExifGpsSource source = ExifGpsSource::kExif;
  // DJI RTK: one sigma along east, north, up (m), when the three tags are present and positive.
  std::optional<Eigen::Vector3d> rtk_sigma_enu_m;
  std::optional<int> rtk_flag;  // drone-dji:RtkFlag as written
};

// Reads the GPS position of one image file. An image without GPS tags (neither EXIF nor DJI XMP)
// is an error saying so; a tag that is present but malformed (wrong count, zero denominator,
// latitude beyond 90 degrees) is an error naming it.
Status ReadExifGps(const std::string& path, ExifGps* gps);
// The same from the bytes of an image file held in memory; `file_name` names it in messages (the
// fuzz harness tests/fuzz/exif_fuzzer.cc feeds arbitrary bytes here).
Status ParseExifGps(std::string_view bytes, const std::string& file_name, ExifGps* gps);

// The positions of the named images in `directory` (names as the block gives them, relative to
// the directory; a name with sub-folders is followed). `missing` receives the names whose file
// has no GPS tags; any other failure (a file that does not exist or cannot be read, a malformed
// tag) is an error. Returns one entry per name, std::nullopt for the missing ones.
Status ReadExifGpsOfImages(const std::string& directory, const std::vector<std::string>& names,
                           std::vector<std::optional<ExifGps>>* positions,
                           std::vector<std::string>* missing);

}  // namespace photopose
