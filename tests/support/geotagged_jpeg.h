#pragma once
// Writes small JPEG (or TIFF) files carrying GPS tags, as a drone writes them, for the tests of
// core/io/exif_gps: EXIF GPS (degrees, minutes, seconds as rationals; altitude with its Ref) and/or
// DJI's XMP drone-dji tags with the RTK accuracies.
#include <exiv2/exiv2.hpp>

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

namespace photopose::testing {

struct GeotagOptions {
  // Longitude, latitude (deg), height (m) in the EXIF GPS tags; none: no EXIF GPS.
  std::optional<Eigen::Vector3d> exif_lon_lat_height;
  // Longitude, latitude, height in DJI's XMP tags; none: no DJI position tags.
  std::optional<Eigen::Vector3d> dji_lon_lat_height;
  bool dji_misspelt_longitude = false;  // GpsLongtitude, as some DJI firmware writes it
  std::optional<Eigen::Vector3d> rtk_sigma_enu_m;  // RtkStdLon, RtkStdLat, RtkStdHgt
  std::optional<int> rtk_flag;
  // Bytes of an ImageDescription tag (0: none), to make a file larger than its metadata alone.
  size_t description_bytes = 0;
};

// Degrees -> "d/1 m/1 s*1e6/1e6" rationals (seconds to 1e-6", 3 cm of a millimetre).
inline Exiv2::URationalValue DmsValue(double degrees) {
  degrees = std::abs(degrees);
  const int d = static_cast<int>(std::floor(degrees));
  const double minutes = (degrees - d) * 60.0;
  const int m = static_cast<int>(std::floor(minutes));
  const double seconds = (minutes - m) * 60.0;
  Exiv2::URationalValue value;
  value.value_.push_back({static_cast<uint32_t>(d), 1u});
  value.value_.push_back({static_cast<uint32_t>(m), 1u});
  value.value_.push_back({static_cast<uint32_t>(std::llround(seconds * 1e6)), 1000000u});
  return value;
}

inline std::string Decimal(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.10f", value);
  return buffer;
}

// Creates `path` as a blank image of `type` (Exiv2::ImageType::jpeg or tiff) with the tags of
// `options`. exiv2 creates blank JPEGs only: a TIFF starts as a 1 x 1 grey image (little-endian,
// one uncompressed strip), whose first directory exiv2 then fills.
inline void WriteGeotaggedImage(const std::string& path, const GeotagOptions& options, int type) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  Exiv2::XmpParser::initialize();
  try {
    Exiv2::XmpProperties::registerNs("http://www.dji.com/drone-dji/1.0/", "drone-dji");
  } catch (const std::exception&) {
  }
  if (type == Exiv2::ImageType::tiff) {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    static const unsigned char kBlankTiff[] = {
        'I', 'I', 42, 0, 8, 0, 0, 0,                  // header: first directory at byte 8
        8, 0,                                         // 8 entries (tag, type, count, value)
        0x00, 0x01, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,     // ImageWidth 1
        0x01, 0x01, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,     // ImageLength 1
        0x02, 0x01, 3, 0, 1, 0, 0, 0, 8, 0, 0, 0,     // BitsPerSample 8
        0x03, 0x01, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,     // Compression: none
        0x06, 0x01, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,     // PhotometricInterpretation: black is 0
        0x11, 0x01, 4, 0, 1, 0, 0, 0, 110, 0, 0, 0,   // StripOffsets 110
        0x16, 0x01, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0,     // RowsPerStrip 1
        0x17, 0x01, 4, 0, 1, 0, 0, 0, 1, 0, 0, 0,     // StripByteCounts 1
        0, 0, 0, 0,                                   // no next directory
        128};                                         // the pixel, at byte 110
    std::fwrite(kBlankTiff, 1, sizeof(kBlankTiff), file);
    std::fclose(file);
  }
  auto image = type == Exiv2::ImageType::tiff ? Exiv2::ImageFactory::open(path)
                                               : Exiv2::ImageFactory::create(type, path);
  Exiv2::ExifData exif;  // a TIFF's image tags kept
  if (type == Exiv2::ImageType::tiff) {
    image->readMetadata();
    exif = image->exifData();
  }
  if (options.description_bytes > 0)
    exif["Exif.Image.ImageDescription"] = std::string(options.description_bytes, 'd');
  if (options.exif_lon_lat_height) {
    const Eigen::Vector3d& p = *options.exif_lon_lat_height;
    exif["Exif.GPSInfo.GPSVersionID"] = "2 3 0 0";
    exif["Exif.GPSInfo.GPSLatitudeRef"] = p.y() >= 0 ? "N" : "S";
    exif["Exif.GPSInfo.GPSLatitude"] = DmsValue(p.y());
    exif["Exif.GPSInfo.GPSLongitudeRef"] = p.x() >= 0 ? "E" : "W";
    exif["Exif.GPSInfo.GPSLongitude"] = DmsValue(p.x());
    Exiv2::URationalValue altitude;
    altitude.value_.push_back({static_cast<uint32_t>(std::llround(std::abs(p.z()) * 10000.0)), 10000u});
    exif["Exif.GPSInfo.GPSAltitude"] = altitude;
    Exiv2::DataValue ref(Exiv2::unsignedByte);
    ref.read(p.z() >= 0 ? "0" : "1");
    exif["Exif.GPSInfo.GPSAltitudeRef"] = ref;
  }
  Exiv2::XmpData xmp;
  if (options.dji_lon_lat_height) {
    const Eigen::Vector3d& p = *options.dji_lon_lat_height;
    xmp["Xmp.drone-dji.GpsLatitude"] = Decimal(p.y());
    xmp[options.dji_misspelt_longitude ? "Xmp.drone-dji.GpsLongtitude" : "Xmp.drone-dji.GpsLongitude"] = Decimal(p.x());
    xmp["Xmp.drone-dji.AbsoluteAltitude"] = Decimal(p.z());
  }
  if (options.rtk_sigma_enu_m) {
    xmp["Xmp.drone-dji.RtkStdLon"] = Decimal(options.rtk_sigma_enu_m->x());
    xmp["Xmp.drone-dji.RtkStdLat"] = Decimal(options.rtk_sigma_enu_m->y());
    xmp["Xmp.drone-dji.RtkStdHgt"] = Decimal(options.rtk_sigma_enu_m->z());
  }
  if (options.rtk_flag) xmp["Xmp.drone-dji.RtkFlag"] = std::to_string(*options.rtk_flag);
  image->setExifData(exif);
  image->setXmpData(xmp);
  image->writeMetadata();
}

inline void WriteGeotaggedJpeg(const std::string& path, const GeotagOptions& options) {
  WriteGeotaggedImage(path, options, Exiv2::ImageType::jpeg);
}

inline void WriteGeotaggedTiff(const std::string& path, const GeotagOptions& options) {
  WriteGeotaggedImage(path, options, Exiv2::ImageType::tiff);
}

// Sets one XMP text tag of an existing image file (e.g. a malformed DJI value).
inline void SetXmpText(const std::string& path, const std::string& key, const std::string& value) {
  auto image = Exiv2::ImageFactory::open(path);
  image->readMetadata();
  Exiv2::XmpData xmp = image->xmpData();
  xmp[key] = value;
  image->setXmpData(xmp);
  image->writeMetadata();
}

}  // namespace photopose::testing
