#include "core/io/exif_gps.h"

#include <exiv2/exiv2.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <sstream>

#include "core/io/csv.h"
#include "core/io/tables.h"

namespace photopose {
namespace {

constexpr const char* kDjiNamespace = "http://www.dji.com/drone-dji/1.0/";

// exiv2's global state: the XMP toolkit (not thread-safe to initialise lazily), DJI's namespace,
// and its log (silenced: every problem reaches the caller as a Status).
void InitialiseExiv2() {
  static std::once_flag once;
  std::call_once(once, [] {
    Exiv2::LogMsg::setLevel(Exiv2::LogMsg::mute);
    Exiv2::XmpParser::initialize();
    try {
      Exiv2::XmpProperties::registerNs(kDjiNamespace, "drone-dji");
    } catch (const std::exception&) {
      // Already registered by the host program under this prefix: nothing to do.
    }
  });
}

Status TagError(const std::string& path, const std::string& tag, const std::string& reason) {
  return Status::Error(path + ": " + tag + ": " + reason);
}

// A rational degrees/minutes/seconds triple -> decimal degrees.
Status DegreesOf(const std::string& path, const Exiv2::Exifdatum& datum, double* degrees) {
  if (datum.count() != 3)
    return TagError(path, datum.key(), "expected 3 rationals (degrees, minutes, seconds), found " +
                                           std::to_string(datum.count()));
  double value = 0.0;
  const double scale[3] = {1.0, 1.0 / 60.0, 1.0 / 3600.0};
  for (long i = 0; i < 3; ++i) {
    const Exiv2::Rational r = datum.toRational(i);
    if (r.second == 0) return TagError(path, datum.key(), "zero denominator");
    value += scale[i] * static_cast<double>(r.first) / static_cast<double>(r.second);
  }
  *degrees = value;
  return Status::Ok();
}

std::optional<std::string> ExifString(const Exiv2::ExifData& exif, const char* key) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  if (it == exif.end()) return std::nullopt;
  return it->toString();
}

// An XMP text value of the DJI namespace parsed as a number; nullopt when absent.
Status XmpNumber(const std::string& path, const Exiv2::XmpData& xmp, const std::string& name,
                 std::optional<double>* value) {
  value->reset();
  const auto it = xmp.findKey(Exiv2::XmpKey("Xmp.drone-dji." + name));
  if (it == xmp.end()) return Status::Ok();
  const std::string text = it->toString();
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  double number = 0.0;
  in >> number;
  if (in.fail() || !(in >> std::ws).eof() || !std::isfinite(number))
    return TagError(path, "Xmp.drone-dji." + name, "not a number: '" + TokenForMessage(text) + "'");
  *value = number;
  return Status::Ok();
}

Status CheckRange(const std::string& path, const std::string& tag, double value, double limit) {
  if (!(std::abs(value) <= limit))
    return TagError(path, tag, "outside [-" + std::to_string(static_cast<int>(limit)) + ", " +
                                   std::to_string(static_cast<int>(limit)) + "] degrees");
  return Status::Ok();
}

// A height (m) inside the documented range of coordinates (docs/formats.md, "Physical ranges").
Status CheckHeight(const std::string& path, const std::string& tag, double height_m) {
  if (!(std::abs(height_m) <= kMaxCoordinate)) return TagError(path, tag, "outside [-100000000, 100000000] m");
  return Status::Ok();
}

Status ReadFromExif(const std::string& path, const Exiv2::ExifData& exif, bool* found,
                    Eigen::Vector3d* lon_lat_height) {
  *found = false;
  const auto lat = exif.findKey(Exiv2::ExifKey("Exif.GPSInfo.GPSLatitude"));
  const auto lon = exif.findKey(Exiv2::ExifKey("Exif.GPSInfo.GPSLongitude"));
  if (lat == exif.end() && lon == exif.end()) return Status::Ok();
  if (lat == exif.end() || lon == exif.end())
    return TagError(path, lat == exif.end() ? "Exif.GPSInfo.GPSLatitude" : "Exif.GPSInfo.GPSLongitude",
                    "missing while the other coordinate is present");
  double latitude = 0.0, longitude = 0.0;
  PHOTOPOSE_RETURN_IF_ERROR(DegreesOf(path, *lat, &latitude));
  PHOTOPOSE_RETURN_IF_ERROR(DegreesOf(path, *lon, &longitude));
  const std::optional<std::string> lat_ref = ExifString(exif, "Exif.GPSInfo.GPSLatitudeRef");
  const std::optional<std::string> lon_ref = ExifString(exif, "Exif.GPSInfo.GPSLongitudeRef");
  if (!lat_ref || (*lat_ref != "N" && *lat_ref != "S"))
    return TagError(path, "Exif.GPSInfo.GPSLatitudeRef", "expected N or S, found '" + TokenForMessage(lat_ref.value_or("")) + "'");
  if (!lon_ref || (*lon_ref != "E" && *lon_ref != "W"))
    return TagError(path, "Exif.GPSInfo.GPSLongitudeRef", "expected E or W, found '" + TokenForMessage(lon_ref.value_or("")) + "'");
  if (*lat_ref == "S") latitude = -latitude;
  if (*lon_ref == "W") longitude = -longitude;
  PHOTOPOSE_RETURN_IF_ERROR(CheckRange(path, "Exif.GPSInfo.GPSLatitude", latitude, 90.0));
  PHOTOPOSE_RETURN_IF_ERROR(CheckRange(path, "Exif.GPSInfo.GPSLongitude", longitude, 180.0));

  const auto alt = exif.findKey(Exiv2::ExifKey("Exif.GPSInfo.GPSAltitude"));
  if (alt == exif.end())
    return TagError(path, "Exif.GPSInfo.GPSAltitude", "missing (a camera position needs its height)");
  if (alt->count() != 1) return TagError(path, alt->key(), "expected 1 rational");
  const Exiv2::Rational r = alt->toRational(0);
  if (r.second == 0) return TagError(path, alt->key(), "zero denominator");
  double height = static_cast<double>(r.first) / static_cast<double>(r.second);
  const auto alt_ref = exif.findKey(Exiv2::ExifKey("Exif.GPSInfo.GPSAltitudeRef"));
  if (alt_ref != exif.end()) {
    const long ref = alt_ref->toLong(0);
    if (ref != 0 && ref != 1)
      return TagError(path, alt_ref->key(), "expected 0 (above) or 1 (below), found " + std::to_string(ref));
    if (ref == 1) height = -height;
  }
  PHOTOPOSE_RETURN_IF_ERROR(CheckHeight(path, alt->key(), height));
  *lon_lat_height = Eigen::Vector3d(longitude, latitude, height);
  *found = true;
  return Status::Ok();
}

Status ReadFromDjiXmp(const std::string& path, const Exiv2::XmpData& xmp, bool* found,
                      Eigen::Vector3d* lon_lat_height) {
  *found = false;
  std::optional<double> latitude, longitude, height;
  PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "GpsLatitude", &latitude));
  PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "GpsLongitude", &longitude));
  if (!longitude) PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "GpsLongtitude", &longitude));
  PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "AbsoluteAltitude", &height));
  if (!latitude && !longitude) return Status::Ok();
  if (!latitude || !longitude || !height)
    return TagError(path, !latitude ? "Xmp.drone-dji.GpsLatitude"
                          : !longitude ? "Xmp.drone-dji.GpsLongitude" : "Xmp.drone-dji.AbsoluteAltitude",
                    "missing while the other DJI position tags are present");
  PHOTOPOSE_RETURN_IF_ERROR(CheckRange(path, "Xmp.drone-dji.GpsLatitude", *latitude, 90.0));
  PHOTOPOSE_RETURN_IF_ERROR(CheckRange(path, "Xmp.drone-dji.GpsLongitude", *longitude, 180.0));
  PHOTOPOSE_RETURN_IF_ERROR(CheckHeight(path, "Xmp.drone-dji.AbsoluteAltitude", *height));
  *lon_lat_height = Eigen::Vector3d(*longitude, *latitude, *height);
  *found = true;
  return Status::Ok();
}

Status ReadRtk(const std::string& path, const Exiv2::XmpData& xmp, ExifGps* gps) {
  std::optional<double> east, north, up, flag;
  PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "RtkStdLon", &east));
  PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "RtkStdLat", &north));
  PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "RtkStdHgt", &up));
  PHOTOPOSE_RETURN_IF_ERROR(XmpNumber(path, xmp, "RtkFlag", &flag));
  if (flag) {
    if (!(*flag >= 0.0 && *flag <= 255.0)) return TagError(path, "Xmp.drone-dji.RtkFlag", "outside [0, 255]");
    gps->rtk_flag = static_cast<int>(std::lround(*flag));
  }
  if (east && north && up) {
    // DJI writes 0 (or nothing) when there is no RTK solution: no stated accuracy then.
    if (*east < 0.0 || *north < 0.0 || *up < 0.0)
      return TagError(path, "Xmp.drone-dji.RtkStd*", "negative standard deviation");
    if (std::max({*east, *north, *up}) > kMaxCoordinate)
      return TagError(path, "Xmp.drone-dji.RtkStd*", "above 100000000 m");
    if (*east > 0.0 && *north > 0.0 && *up > 0.0) gps->rtk_sigma_enu_m = Eigen::Vector3d(*east, *north, *up);
  }
  return Status::Ok();
}

// exiv2's message (it may repeat bytes of the file) fit for a one-line message: cut, escaped.
std::string Exiv2Message(const char* what) {
  constexpr size_t kMaxBytes = 200;
  const std::string_view text(what);
  return EscapeForMessage(text.substr(0, kMaxBytes)) + (text.size() > kMaxBytes ? "..." : "");
}

// Reads the position from an opened image; *found false (and Ok) when it has no GPS tags at all.
// Every exception of exiv2 (Exiv2::Error on a corrupt file, std::bad_alloc, std::out_of_range of
// a value without elements) becomes an error naming the file.
template <typename OpenImage>
Status ReadImageGps(const std::string& name, OpenImage open_image, ExifGps* gps, bool* found) {
  InitialiseExiv2();
  *gps = ExifGps();
  *found = false;
  try {
    auto image = open_image();
    if (image.get() == nullptr) return Status::Error(name + ": not an image exiv2 can read");
    image->readMetadata();
    PHOTOPOSE_RETURN_IF_ERROR(ReadFromExif(name, image->exifData(), found, &gps->lon_lat_height));
    if (*found) {
      gps->source = ExifGpsSource::kExif;
    } else {
      PHOTOPOSE_RETURN_IF_ERROR(ReadFromDjiXmp(name, image->xmpData(), found, &gps->lon_lat_height));
      if (!*found) return Status::Ok();
      gps->source = ExifGpsSource::kDjiXmp;
    }
    return ReadRtk(name, image->xmpData(), gps);
  } catch (const std::exception& e) {
    *found = false;
    return Status::Error(name + ": exiv2: " + Exiv2Message(e.what()));
  } catch (...) {
    *found = false;
    return Status::Error(name + ": exiv2: an unknown exception");
  }
}

// exiv2 over bytes in memory (its MemIo: nothing is mapped).
// (The pointer's type is never named: exiv2 0.27 spells it std::auto_ptr, deprecated.)
auto OpenBytes(std::string_view bytes) {
  return Exiv2::ImageFactory::open(reinterpret_cast<const Exiv2::byte*>(bytes.data()),
                                   static_cast<long>(bytes.size()));
}

// exiv2 maps TIFF-based files (TIFF, DNG, most raw formats) while it parses them, and a file that
// shrinks meanwhile ends the process with SIGBUS. So the file is opened by path only to learn its
// format (exiv2 reads the magic number): a JPEG is parsed from the file, which exiv2 reads segment
// by segment up to the image data and never maps (a few dozen KB of a 10 MB photo, as before);
// every other format is read whole by ReadTextFile (regular files only, at most kMaxInputBytes,
// read rather than mapped) and parsed from memory.
Status ReadFileGps(const std::string& path, ExifGps* gps, bool* found) {
  // A FIFO would block exiv2's open until a writer comes; a folder or device is no image.
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    return Status::Error(EscapeForMessage(path) + ": not a regular file (an image file is needed)");
  std::string bytes;
  Status read;
  const auto open = [&]() {
    auto image = Exiv2::ImageFactory::open(path);
    if (image.get() != nullptr && image->imageType() == Exiv2::ImageType::jpeg) return image;
    image.reset();
    read = ReadTextFile(path == "-" ? "./-" : path, &bytes);  // "-" is a file here, not stdin
    if (!read.ok()) return image;  // null
    return OpenBytes(bytes);
  };
  const Status status = ReadImageGps(EscapeForMessage(path), open, gps, found);
  if (!read.ok()) {
    *found = false;
    return read;
  }
  return status;
}

Status NoGpsError(const std::string& name) {
  return Status::Error(name + ": no GPS position (neither EXIF GPSLatitude/GPSLongitude nor DJI XMP GpsLatitude/GpsLongitude)");
}

}  // namespace

Status ReadExifGps(const std::string& path, ExifGps* gps) {
  bool found = false;
  PHOTOPOSE_RETURN_IF_ERROR(ReadFileGps(path, gps, &found));
  if (!found) return NoGpsError(EscapeForMessage(path));
  return Status::Ok();
}

Status ParseExifGps(std::string_view bytes, const std::string& file_name, ExifGps* gps) {
  if (bytes.size() > kMaxInputBytes)
    return Status::Error(EscapeForMessage(file_name) + ": is larger than " + std::to_string(kMaxInputBytes) + " bytes");
  bool found = false;
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadImageGps(EscapeForMessage(file_name), [bytes] { return OpenBytes(bytes); }, gps, &found));
  if (!found) return NoGpsError(EscapeForMessage(file_name));
  return Status::Ok();
}

Status ReadExifGpsOfImages(const std::string& directory, const std::vector<std::string>& names,
                           std::vector<std::optional<ExifGps>>* positions,
                           std::vector<std::string>* missing) {
  positions->assign(names.size(), std::nullopt);
  missing->clear();
  std::error_code error;
  if (!std::filesystem::is_directory(directory, error))
    return Status::Error(directory + ": not a directory");
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string path = (std::filesystem::path(directory) / names[i]).string();
    if (!std::filesystem::is_regular_file(path, error))
      return Status::Error(path + ": no such image file (image '" + names[i] + "' of the block)");
    ExifGps gps;
    bool found = false;
    PHOTOPOSE_RETURN_IF_ERROR(ReadFileGps(path, &gps, &found));
    if (found) (*positions)[i] = gps;
    else missing->push_back(names[i]);
  }
  return Status::Ok();
}

}  // namespace photopose
