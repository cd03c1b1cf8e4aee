#include "core/geodesy/crs.h"

#include <gtest/gtest.h>

#include <cmath>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

constexpr double kPi = 3.14159265358979323846;

TEST(Crs, ResolvesEpsgOdmAndProjStrings) {
  CrsInfo utm;
  ASSERT_TRUE(ResolveCrs("WGS84 UTM 32N", &utm).ok());
  EXPECT_EQ(utm.definition, "EPSG:32632");
  EXPECT_TRUE(utm.projected);
  EXPECT_TRUE(utm.heights_as_given);
  EXPECT_EQ(utm.name, "WGS 84 / UTM zone 32N");
  CrsInfo south;
  ASSERT_TRUE(ResolveCrs("wgs84 utm 22s", &south).ok());
  EXPECT_EQ(south.definition, "EPSG:32722");
  CrsInfo geographic3d;
  ASSERT_TRUE(ResolveCrs("EPSG:4979", &geographic3d).ok());
  EXPECT_TRUE(geographic3d.geographic);
  EXPECT_FALSE(geographic3d.heights_as_given);
  CrsInfo proj_string;
  ASSERT_TRUE(ResolveCrs("+proj=utm +zone=33 +datum=WGS84 +units=m", &proj_string).ok());
  EXPECT_TRUE(proj_string.projected);
}

TEST(Crs, UnknownCrsIsAnErrorNamingIt) {
  CrsInfo info;
  const Status unknown = ResolveCrs("EPSG:999999", &info);
  ASSERT_FALSE(unknown.ok());
  // PROJ's own words for it are "Unknown error (code 4096)": the message says what it is.
  EXPECT_EQ(unknown.message(), "CRS 'EPSG:999999' is not known to PROJ (proj.db)");
  const Status other_authority = ResolveCrs("ESRI:999999", &info);
  EXPECT_EQ(other_authority.message(), "CRS 'ESRI:999999' is not known to PROJ (proj.db)");
  // Not a database code: PROJ's reason, never "Unknown error".
  const Status syntax = ResolveCrs("+proj=nosuchprojection", &info);
  ASSERT_FALSE(syntax.ok());
  EXPECT_EQ(syntax.message().rfind("CRS '+proj=nosuchprojection': ", 0), 0u) << syntax.message();
  EXPECT_EQ(syntax.message().find("Unknown error"), std::string::npos) << syntax.message();
  EXPECT_EQ(syntax.message().find("proj.db"), std::string::npos) << syntax.message();
  EXPECT_FALSE(ResolveCrs("", &info).ok());
  EXPECT_FALSE(ResolveCrs("WGS84 UTM 61N", &info).ok());
  // A conversion is not a CRS until PROJ is told so; a transformation pipeline never is.
  EXPECT_FALSE(ResolveCrs("+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad", &info).ok());
}

// Two texts are the same CRS when PROJ finds them equivalent as photopose uses them: spelled
// differently (ODM's zone, a WKT PROJ writes, a 2D CRS given its height axis) they are the same;
// a neighbouring zone, a datum or a vertical datum more is another CRS.
TEST(Crs, SameCrsComparesWhatTheTextsNameNotHowTheyAreSpelled) {
  const auto same = [](const std::string& a, const std::string& b) {
    bool result = false;
    const Status compared = SameCrs(a, b, &result);
    EXPECT_TRUE(compared.ok()) << a << " / " << b << ": " << compared.message();
    return result;
  };
  EXPECT_TRUE(same("EPSG:32632", "EPSG:32632"));
  EXPECT_TRUE(same("EPSG:32632", "WGS84 UTM 32N"));
  EXPECT_TRUE(same("epsg:32632", " EPSG:32632 "));
  EXPECT_TRUE(same("EPSG:4326", "EPSG:4979"));  // heights pass as ellipsoidal in both
  EXPECT_FALSE(same("EPSG:32632", "EPSG:32633"));
  EXPECT_FALSE(same("EPSG:32632", "EPSG:32732"));
  EXPECT_FALSE(same("EPSG:32632", "EPSG:25832"));       // ETRS89, not WGS84
  EXPECT_FALSE(same("EPSG:32632", "EPSG:32632+5773"));  // EGM96 heights
  EXPECT_FALSE(same("EPSG:4326", "EPSG:32632"));
  bool result = true;
  const Status unknown = SameCrs("EPSG:32632", "EPSG:999999", &result);
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.message().find("CRS 'EPSG:999999'"), std::string::npos) << unknown.message();
}

TEST(Crs, UtmZoneOfAPlace) {
  EXPECT_EQ(UtmCrsFor(11.2, 47.8), "EPSG:32632");
  EXPECT_EQ(UtmCrsFor(-70.6, -33.4), "EPSG:32719");
  EXPECT_EQ(UtmCrsFor(180.0, 1.0), "EPSG:32660");
}

class LocalFrameTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(LocalFrame::Create("EPSG:4979", Eigen::Vector3d(11.2, 47.8, 500.0), &frame_).ok());
  }
  LocalFrame frame_;
};

TEST_F(LocalFrameTest, RoundTripsThroughUtmAndGeographicToAMillimetre) {
  std::vector<Eigen::Vector3d> local;
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j) local.emplace_back(700.0 * i, 650.0 * j, 20.0 * (i - j));
  for (const char* crs : {"EPSG:32632", "EPSG:4326", "EPSG:4979", "EPSG:25832"}) {
    std::vector<Eigen::Vector3d> points = local;
    ASSERT_TRUE(frame_.FromLocal(crs, &points).ok()) << crs;
    ASSERT_TRUE(frame_.ToLocal(crs, &points).ok()) << crs;
    for (size_t k = 0; k < local.size(); ++k) EXPECT_LT((points[k] - local[k]).norm(), 1e-3) << crs << " " << k;
  }
}

TEST_F(LocalFrameTest, OriginIsZeroAndThePlaneRisesAboveTheEllipsoidWithDistance) {
  std::vector<Eigen::Vector3d> points = {Eigen::Vector3d(11.2, 47.8, 500.0)};
  ASSERT_TRUE(frame_.ToLocal("EPSG:4979", &points).ok());
  EXPECT_LT(points[0].norm(), 1e-6);
  // 1 km east on the tangent plane is d^2 / (2 R) above the ellipsoid (R ~ 6.38e6 m there).
  points = {Eigen::Vector3d(1000.0, 0.0, 0.0)};
  ASSERT_TRUE(frame_.FromLocal("EPSG:4979", &points).ok());
  EXPECT_NEAR(points[0].z() - 500.0, 1000.0 * 1000.0 / (2.0 * 6.38e6), 0.002);
  EXPECT_GT(points[0].x(), 11.2);
  EXPECT_NEAR(points[0].y(), 47.8, 1e-4);
}

TEST_F(LocalFrameTest, LevelFramesHoldTheGridConvergenceOfAProjection) {
  // East of UTM 32N's central meridian (9 E) grid north turns away from true north by
  // atan(tan(dlon) sin(lat)) = 1.63 degrees at 11.2 E, 47.8 N.
  std::vector<Eigen::Matrix3d> R;
  ASSERT_TRUE(frame_.LevelFrames("EPSG:32632", {Eigen::Vector3d::Zero()}, &R).ok());
  const double expected = std::atan(std::tan(2.2 * kPi / 180.0) * std::sin(47.8 * kPi / 180.0));
  const Eigen::Vector3d grid_north = R[0].row(1).transpose();
  EXPECT_NEAR(std::abs(std::atan2(grid_north.x(), grid_north.y())), expected, 1e-5);
  EXPECT_NEAR((R[0] * R[0].transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-9);
  // Geographic: the local ENU frame itself at the origin, tilted by the Earth's curvature away.
  ASSERT_TRUE(frame_.LevelFrames("EPSG:4326", {Eigen::Vector3d::Zero(), Eigen::Vector3d(5000.0, 0.0, 0.0)}, &R).ok());
  EXPECT_LT((R[0] - Eigen::Matrix3d::Identity()).norm(), 1e-6);
  const double tilt = std::acos(std::min(1.0, R[1].row(2).dot(Eigen::RowVector3d::UnitZ())));
  EXPECT_NEAR(tilt, 5000.0 / 6.38e6, 0.01 * 5000.0 / 6.38e6);
}

TEST_F(LocalFrameTest, UnknownCrsOrPointsOutsideItsAreaAreErrors) {
  std::vector<Eigen::Vector3d> points = {Eigen::Vector3d(0, 0, 0)};
  EXPECT_FALSE(frame_.ToLocal("EPSG:999999", &points).ok());
  points = {Eigen::Vector3d(11.2, 95.0, 0.0)};  // latitude beyond the pole
  EXPECT_FALSE(frame_.ToLocal("EPSG:4326", &points).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
