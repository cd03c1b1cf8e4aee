// Writes the seed images of exif_fuzzer.cc into the folder given as the only argument: blank
// JPEGs carrying EXIF GPS tags, DJI XMP position and RTK tags, both, and neither (made with
// tests/support/geotagged_jpeg.h, as the tests of core/io/exif_gps make theirs). Each stays well
// under the 8192 bytes CI's fuzz runs take.
#include <Eigen/Core>
#include <cstdio>
#include <exception>
#include <string>

#include "tests/support/geotagged_jpeg.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: exif_fuzzer_seeds FOLDER\n");
    return 2;
  }
  using photopose::testing::GeotagOptions;
  const std::string folder = argv[1];
  GeotagOptions exif;
  exif.exif_lon_lat_height = Eigen::Vector3d(-71.1234567, -33.4567891, -12.3456);
  GeotagOptions dji;
  dji.dji_lon_lat_height = Eigen::Vector3d(8.5432109876, 47.3765432109, 488.123);
  dji.dji_misspelt_longitude = true;
  dji.rtk_sigma_enu_m = Eigen::Vector3d(0.011, 0.012, 0.025);
  dji.rtk_flag = 50;
  GeotagOptions both = dji;
  both.dji_misspelt_longitude = false;
  both.exif_lon_lat_height = Eigen::Vector3d(11.2, 47.8, 612.5);
  try {
    photopose::testing::WriteGeotaggedJpeg(folder + "/exif_gps.jpg", exif);
    photopose::testing::WriteGeotaggedJpeg(folder + "/exif_dji_rtk.jpg", dji);
    photopose::testing::WriteGeotaggedJpeg(folder + "/exif_both.jpg", both);
    photopose::testing::WriteGeotaggedJpeg(folder + "/exif_none.jpg", GeotagOptions());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "exif_fuzzer_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
