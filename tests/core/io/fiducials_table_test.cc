#include "core/io/fiducials_table.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/support/temp_dir.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

constexpr char kHeader[] = "Raster,FiducialID,Column,Row\n";

TEST(FiducialsTable, RowsAreReadWithTheirLines) {
  testing::ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string path = dir.Write("fiducials.csv", std::string(kHeader) +
                                                          "scan_017.tif,1,448.8,10838.3\n"
                                                          "scan_017.tif,2,11047.2,10884.4\n"
                                                          "scan_018.tif,1,450.5,10836.0\n");
  std::vector<MeasuredFiducial> fiducials;
  ASSERT_TRUE(ReadMeasuredFiducials(path, &fiducials).ok());
  ASSERT_EQ(fiducials.size(), 3u);
  EXPECT_EQ(fiducials[0].raster, "scan_017.tif");
  EXPECT_EQ(fiducials[1].fiducial_id, 2);
  EXPECT_EQ(fiducials[1].line, 3);
  EXPECT_EQ(fiducials[1].column_row, Eigen::Vector2d(11047.2, 10884.4));
  // The same FiducialID in another image is another fiducial.
  EXPECT_EQ(fiducials[2].raster, "scan_018.tif");
  EXPECT_EQ(fiducials[2].fiducial_id, 1);
}

TEST(FiducialsTable, AFiducialMeasuredTwiceNamesBothLines) {
  testing::ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string path = dir.Write("fiducials.csv", std::string(kHeader) +
                                                          "scan_017.tif,1,448.8,10838.3\n"
                                                          "scan_017.tif,1,11047.2,10884.4\n");
  std::vector<MeasuredFiducial> fiducials;
  EXPECT_EQ(ReadMeasuredFiducials(path, &fiducials).message(),
            path + ":3: FiducialID: fiducial 1 of image 'scan_017.tif' is measured twice (first "
                   "on line 2)");
}

TEST(FiducialsTable, BadRowsAreRefusedAtTheirLineAndColumn) {
  testing::ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  std::vector<MeasuredFiducial> fiducials;
  // A FiducialID is a 1-based position in FilmFiducials: 0 and negative numbers are not.
  for (const char* id : {"0", "-2", "1001", "1.5"}) {
    const std::string path =
        dir.Write("fiducials.csv", std::string(kHeader) + "scan_017.tif," + id + ",448.8,10838.3\n");
    EXPECT_NE(ReadMeasuredFiducials(path, &fiducials).message().find(":2: FiducialID:"),
              std::string::npos)
        << id;
  }
  const std::string no_row =
      dir.Write("fiducials.csv", "Raster,FiducialID,Column\nscan_017.tif,1,448.8\n");
  EXPECT_NE(ReadMeasuredFiducials(no_row, &fiducials).message().find(":1: Row: required column"),
            std::string::npos);
  const std::string not_a_number =
      dir.Write("fiducials.csv", std::string(kHeader) + "scan_017.tif,1,448.8,row\n");
  EXPECT_NE(ReadMeasuredFiducials(not_a_number, &fiducials).message().find(":2: Row:"),
            std::string::npos);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
