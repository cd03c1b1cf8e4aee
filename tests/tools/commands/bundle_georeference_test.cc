// End-to-end: `photopose bundle --colmap_model --geo --gcp_list` georeferences a domed model, as
// a user with a COLMAP reconstruction, a geo.txt and a gcp_list.txt runs it.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/io/colmap.h"
#include "core/io/csv.h"
#include "tests/support/georeference_scene.h"
#include "tests/tools/cli_test_util.h"

namespace photopose {
namespace {

using testing::CliRun;
using testing::ReadFile;
using testing::RunCli;
using testing::ScratchDir;
using testing::WriteFile;

std::string Number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.10f", value);
  return buffer;
}

// dir/model (COLMAP text), dir/geo.txt, dir/gcp_list.txt; returns the check point names.
std::string WriteScene(const testing::GeoreferenceScene& scene, const std::string& dir) {
  EXPECT_TRUE(WriteColmapModel(dir + "/model", scene.model).ok());
  std::string geo = "EPSG:4326\n";
  for (const CameraPositionMeasurement& m : scene.inputs.positions)
    geo += m.image + " " + Number(m.position.x()) + " " + Number(m.position.y()) + " " + Number(m.position.z()) +
           " 0 0 0 " + Number(m.accuracy_m->x()) + " " + Number(m.accuracy_m->z()) + "\n";
  WriteFile(dir + "/geo.txt", geo);
  std::string gcp = "WGS84 UTM 32N\n", checks;
  for (const ImageMark& mark : scene.inputs.control_marks) {
    for (const GroundPoint& p : scene.inputs.control_points) {
      if (p.point_id != mark.point_id) continue;
      gcp += Number(p.position.x()) + " " + Number(p.position.y()) + " " + Number(p.position.z()) + " " +
             Number(mark.column_row->x()) + " " + Number(mark.column_row->y()) + " " + mark.raster + " " + p.point_id + "\n";
    }
  }
  for (const GroundPoint& p : scene.inputs.control_points)
    if (p.role == PointRole::kCheck) checks += (checks.empty() ? "" : ",") + p.point_id;
  WriteFile(dir + "/gcp_list.txt", gcp);
  return checks;
}

TEST(BundleGeoreference, DomedColmapModelWithGeoTxtAndGcpListComesOutInUtm) {
  const testing::GeoreferenceScene scene = testing::MakeGeoreferenceScene(2.0);
  const std::string dir = ScratchDir();
  const std::string checks = WriteScene(scene, dir);
  const CliRun run = RunCli("bundle --colmap_model=" + dir + "/model --geo=" + dir + "/geo.txt --gcp_list=" + dir +
                                "/gcp_list.txt --check_points=" + checks + " --out=" + dir + "/frames.csv --out_points=" +
                                dir + "/points.csv --out_colmap=" + dir + "/out --report=" + dir + "/report.json --html=" + dir + "/report.html --quiet",
                            dir);
  ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
  EXPECT_NE(run.out.find("georeferenced in WGS84 UTM 32N"), std::string::npos) << run.out;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir + "/report.json"));
  const nlohmann::json& g = report.at("georeference");
  EXPECT_EQ(g.at("out_crs_name"), "WGS 84 / UTM zone 32N");
  EXPECT_EQ(g.at("positions_matched"), 24);
  EXPECT_EQ(g.at("check_after_adjustment").at("count"), 4);
  const double before = g.at("check_after_similarity").at("rmse_total_m");
  const double after = g.at("check_after_adjustment").at("rmse_total_m");
  EXPECT_GT(before, 0.1);
  EXPECT_LT(after, 0.03);

  // The points table: UTM coordinates; check points with their survey beside the intersection.
  const std::string points = ReadFile(dir + "/points.csv");
  std::istringstream lines(points);
  std::string header;
  std::getline(lines, header);
  EXPECT_EQ(header, "PointID,X,Y,Z,SigmaX,SigmaY,SigmaZ,Role,NumObservations,SurveyedX,SurveyedY,SurveyedZ,ErrorX,ErrorY,ErrorZ");
  int checks_seen = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.find(",check,") == std::string::npos) continue;
    std::vector<double> v;
    std::stringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) v.push_back(field.empty() || !std::isdigit(static_cast<unsigned char>(field.back())) ? 0.0 : std::atof(field.c_str()));
    ASSERT_EQ(v.size(), 15u) << line;
    EXPECT_GT(v[1], 600000.0);    // easting of 11.2 E in zone 32
    EXPECT_GT(v[2], 5290000.0);   // northing of 47.8 N
    EXPECT_NEAR(v[1] - v[9], v[12], 0.002) << line;  // X - SurveyedX = ErrorX (grid and metres agree to k)
    EXPECT_LT(std::hypot(v[12], v[13]), 0.05) << line;
    ++checks_seen;
  }
  EXPECT_EQ(checks_seen, 4);
  EXPECT_NE(ReadFile(dir + "/frames.csv").find("EPSG:32632"), std::string::npos);
  EXPECT_NE(ReadFile(dir + "/out/georeference.json").find("+proj=topocentric"), std::string::npos);
  // The page's plan view is drawn in the grid, its corners in UTM coordinates.
  const std::string html = ReadFile(dir + "/report.html");
  EXPECT_NE(html.find("Grid of WGS 84 / UTM zone 32N (WGS84 UTM 32N): easting and northing (m). Lower left 66"), std::string::npos);
  Block written;
  ASSERT_TRUE(ReadColmapModel(dir + "/out", &written).ok());
  EXPECT_EQ(written.points.size(), scene.model.points.size());  // the model's points, no control added
}

TEST(BundleGeoreference, RefusesWhatItCannotUseBeforeAnyWork) {
  const testing::GeoreferenceScene scene = testing::MakeGeoreferenceScene(0.0, 2, 5);
  const std::string dir = ScratchDir();
  WriteScene(scene, dir);
  const std::string model = " --colmap_model=" + dir + "/model --out=" + dir + "/f.csv";
  struct Case {
    std::string arguments;
    std::string message;
  };
  WriteFile(dir + "/bad_geo.txt", "EPSG:999999\na.jpg 1 2 3\n");
  WriteFile(dir + "/frames.csv", "Raster,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa\na.jpg,1,2,3,0,0,0\n");
  const std::vector<Case> cases = {
      {model + " --frames=" + dir + "/frames.csv", "--crs is needed"},
      {model + " --geo=" + dir + "/bad_geo.txt", "CRS 'EPSG:999999'"},
      {model + " --geo=" + dir + "/geo.txt --frames=" + dir + "/frames.csv --crs=EPSG:4326", "not both"},
      {model + " --out_crs=EPSG:32632", "nothing is georeferenced"},
      {model + " --geo=" + dir + "/geo.txt --check_points=GCP_1", "--check_points names points of --gcp_list"},
      {model + " --gcp_list=" + dir + "/gcp_list.txt --check_points=nope", "'nope' is not a point of"},
      {model + " --crs=EPSG:4326", "neither is given"},
  };
  for (const Case& c : cases) {
    const CliRun run = RunCli("bundle" + c.arguments + " --quiet", dir);
    EXPECT_EQ(run.exit_code, 2) << c.arguments << "\n" << run.err;
    EXPECT_NE(run.err.find(c.message), std::string::npos) << c.arguments << "\n" << run.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/f.csv")) << c.arguments;
  }
}

}  // namespace
}  // namespace photopose
