#pragma once
// Coordinate reference systems, resolved and transformed by PROJ (libproj), and the local
// Cartesian frame the adjustments of georeferenced blocks run in.
//
// Why a local frame (docs/conventions.md, "Georeferenced blocks"): the collinearity equations
// need a Cartesian frame with metres on every axis. A projected grid (UTM, a national grid) is not
// one: its horizontal scale differs from 1 by up to 1e-3 (4e-4 in UTM), varies across the block,
// and its heights are not along its grid normal. A geographic CRS is not even metric. So a
// georeferenced block is adjusted in a topocentric East-North-Up frame whose origin lies on the
// WGS84 ellipsoid at the block's centre (PROJ's "topocentric" conversion after "cart"); every
// input is transformed into it and every output back out of it, by PROJ, nothing hand-written.
//
// Axis order: coordinates cross this boundary in GIS order, X = easting or longitude (degrees),
// Y = northing or latitude (degrees), Z = height (m) — the order ODM's geo.txt / gcp_list.txt and
// ArcGIS tables use — whatever the authority's axis order of the CRS (EPSG:4326 is latitude-first
// by the authority).
//
// Heights: a CRS with a vertical axis (3D geographic, compound with a vertical CRS) is
// transformed as PROJ defines it (a compound CRS with orthometric heights needs PROJ's geoid grid;
// without it the transformation fails with a message). A 2D CRS (a projected grid, EPSG:4326) is
// promoted to 3D: its Z passes through as the height above the ellipsoid, so heights stay as given
// and come back unchanged; what they are (ellipsoidal or orthometric) is the user's, and the
// reports say that they were taken as given (CrsInfo::heights_as_given).
//
// Thread safety: a CrsTransform or LocalFrame is used by one thread at a time (PROJ objects keep
// state); create one per thread.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"

namespace photopose {

// What PROJ says about a CRS given by a user.
struct CrsInfo {
  std::string text;        // as given ("EPSG:32632", "WGS84 UTM 32N", a +proj string, WKT)
  std::string definition;  // what is handed to PROJ (ODM's "WGS84 UTM 32N" -> "EPSG:32632")
  std::string name;        // PROJ's name, e.g. "WGS 84 / UTM zone 32N"
  bool geographic = false; // X, Y are longitude, latitude in degrees
  bool projected = false;  // X, Y are easting, northing of a map projection (metres or feet)
  bool geocentric = false; // X, Y, Z Earth-centred Cartesian (m)
  // The CRS has no vertical axis: its Z is carried through as height above the ellipsoid.
  bool heights_as_given = false;
};

// Resolves a CRS: EPSG:<code>, another AUTHORITY:CODE, a "+proj=..." string (made a CRS), WKT, or
// ODM's "WGS84 UTM <zone><N|S>". Errors name the text and PROJ's reason.
Status ResolveCrs(const std::string& text, CrsInfo* info);

// Whether two CRS texts name the same CRS as photopose uses it: PROJ's equivalence
// (proj_is_equivalent_to, names and the authority's axis order of a geographic CRS aside) of the
// two CRSs after a 2D one is given its height axis ("EPSG:32632" and "WGS84 UTM 32N" are the same;
// so are EPSG:4326 and EPSG:4979, whose heights both pass as ellipsoidal). Errors as ResolveCrs,
// naming the text PROJ does not know.
Status SameCrs(const std::string& a, const std::string& b, bool* same);

// "EPSG:326zz" (north) or "EPSG:327zz" (south): the WGS84 UTM zone of a longitude / latitude
// (degrees); the Norway and Svalbard exceptions are not applied.
std::string UtmCrsFor(double longitude_deg, double latitude_deg);

// A transformation between two CRSs (GIS axis order on both sides, see above), in place.
class CrsTransform {
 public:
  CrsTransform();
  ~CrsTransform();
  CrsTransform(CrsTransform&&) noexcept;
  CrsTransform& operator=(CrsTransform&&) noexcept;

  // From `source` to `target` (texts as for ResolveCrs).
  static Status Create(const std::string& source, const std::string& target, CrsTransform* out);
  // Transforms every point; a point PROJ cannot transform (outside the area of a grid, a missing
  // grid, a latitude beyond 90 degrees) is an error naming its index.
  Status Forward(std::vector<Eigen::Vector3d>* points) const;
  Status Inverse(std::vector<Eigen::Vector3d>* points) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The topocentric East-North-Up frame at an origin on the WGS84 ellipsoid (metres; x east,
// y north, z up along the ellipsoid normal at the origin).
class LocalFrame {
 public:
  LocalFrame();
  ~LocalFrame();
  LocalFrame(LocalFrame&&) noexcept;
  LocalFrame& operator=(LocalFrame&&) noexcept;

  // The frame at `origin` given in `crs` (its height is used as the origin's ellipsoidal height
  // after the transformation).
  static Status Create(const std::string& crs, const Eigen::Vector3d& origin, LocalFrame* out);

  // The origin: longitude, latitude (degrees), ellipsoidal height (m) on WGS84 (EPSG:4979).
  const Eigen::Vector3d& origin_lon_lat_h() const { return origin_lon_lat_h_; }
  // The PROJ pipeline from EPSG:4979 (lon, lat in degrees, h in m) to this frame.
  const std::string& definition() const { return definition_; }

  // Points of `crs` -> this frame, and back.
  Status ToLocal(const std::string& crs, std::vector<Eigen::Vector3d>* points) const;
  Status FromLocal(const std::string& crs, std::vector<Eigen::Vector3d>* points) const;

  // At each point (given in this frame), the rotation from this frame to the level frame of `crs`
  // there: rows are the directions, in this frame, of the CRS's first horizontal axis (grid east
  // or east), its second (grid north or north), and the up direction of the ellipsoid normal.
  // Derived numerically from PROJ's own transformation (the horizontal gradients of the CRS's X
  // and Y made orthogonal to the up direction), so the grid convergence of a projection and the
  // curvature of the Earth across the block are both in it. Errors, vectors, attitudes and
  // sigmas of the outputs are expressed along these axes (in metres).
  Status LevelFrames(const std::string& crs, const std::vector<Eigen::Vector3d>& points_local,
                     std::vector<Eigen::Matrix3d>* R_level_from_local) const;

 private:
  Eigen::Vector3d origin_lon_lat_h_ = Eigen::Vector3d::Zero();
  std::string definition_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace photopose
