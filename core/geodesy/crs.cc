#include "core/geodesy/crs.h"

#include <proj.h>
#include <proj_experimental.h>  // proj_crs_promote_to_3D

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>

namespace photopose {
namespace {

// The geographic 3D WGS84 CRS the local frame hangs from (longitude, latitude in degrees, height
// above the ellipsoid in metres, after normalisation to GIS order).
constexpr char kGeographic3d[] = "EPSG:4979";

struct ContextDeleter {
  void operator()(PJ_CONTEXT* context) const { proj_context_destroy(context); }
};
struct PjDeleter {
  void operator()(PJ* pj) const { proj_destroy(pj); }
};
using ContextPtr = std::unique_ptr<PJ_CONTEXT, ContextDeleter>;
using PjPtr = std::unique_ptr<PJ, PjDeleter>;

ContextPtr NewContext() {
  ContextPtr context(proj_context_create());
  if (context) proj_log_level(context.get(), PJ_LOG_NONE);
  return context;
}

// PROJ's reason for the context's last error. PROJ words its generic code (PROJ_ERR_OTHER, which
// it also gives for a database code it does not have) as "Unknown error (code 4096)": that is said
// as what it is.
std::string ProjReason(PJ_CONTEXT* context) {
  const int code = proj_context_errno(context);
  const char* text = code != 0 ? proj_context_errno_string(context, code) : nullptr;
  if (text == nullptr) return "PROJ does not know it";
  const std::string reason = text;
  if (reason.rfind("Unknown error", 0) == 0)
    return "PROJ gives no reason (its error code " + std::to_string(code) + ")";
  return reason;
}

// An AUTHORITY:CODE reference into PROJ's database (EPSG:32632, ESRI:102100, an OGC URN): one word
// with a colon, neither a "+proj=" string nor WKT.
bool IsDatabaseReference(const std::string& definition) {
  if (definition.empty() || definition.front() == '+' || definition.find(':') == std::string::npos)
    return false;
  return std::none_of(definition.begin(), definition.end(), [](char c) {
    return std::isspace(static_cast<unsigned char>(c)) || c == '[' || c == '(' || c == '=';
  });
}

std::string Lowercase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// ODM's "WGS84 UTM 32N" (any spacing and case) -> "EPSG:32632"; other texts as they are, a
// "+proj=" string made a CRS.
std::string ProjDefinition(const std::string& text) {
  std::string folded;
  for (char c : Lowercase(text))
    if (!std::isspace(static_cast<unsigned char>(c))) folded += c;
  if (folded.rfind("wgs84utm", 0) == 0 && folded.size() >= 10 && folded.size() <= 11) {
    const char hemisphere = folded.back();
    const std::string zone = folded.substr(8, folded.size() - 9);
    const bool digits = !zone.empty() && std::all_of(zone.begin(), zone.end(), [](char c) {
      return std::isdigit(static_cast<unsigned char>(c));
    });
    if (digits && (hemisphere == 'n' || hemisphere == 's')) {
      const int number = std::stoi(zone);
      if (number >= 1 && number <= 60)
        return "EPSG:" + std::to_string((hemisphere == 'n' ? 32600 : 32700) + number);
    }
  }
  std::string trimmed = text;
  while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.back()))) trimmed.pop_back();
  while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.front()))) trimmed.erase(0, 1);
  if (trimmed.rfind("+proj=", 0) == 0 && Lowercase(trimmed).find("+type=crs") == std::string::npos)
    trimmed += " +type=crs";
  return trimmed;
}

bool IsTwoDimensional(PJ_CONTEXT* context, PJ* crs) {
  PjPtr cs(proj_crs_get_coordinate_system(context, crs));
  return cs && proj_cs_get_axis_count(context, cs.get()) == 2;
}

// Creates the CRS of `text` and describes it; `crs_out` (optional) receives it, promoted to 3D when
// it is 2D so that heights pass through.
Status CreateCrs(PJ_CONTEXT* context, const std::string& text, CrsInfo* info, PjPtr* crs_out) {
  CrsInfo result;
  result.text = text;
  result.definition = ProjDefinition(text);
  const auto fail = [&](const std::string& why) {
    return Status::Error("CRS '" + text + "': " + why);
  };
  if (result.definition.empty()) return fail("empty");
  PjPtr crs(proj_create(context, result.definition.c_str()));
  if (!crs && IsDatabaseReference(result.definition)) {
    // PROJ answers a code its database lacks with its generic error: name the database.
    return Status::Error("CRS '" + text + "' is not known to PROJ (proj.db)" +
                         (result.definition != text ? " (read as '" + result.definition + "')" : std::string()));
  }
  if (!crs) return fail(ProjReason(context));
  if (!proj_is_crs(crs.get())) return fail("not a coordinate reference system");
  PJ* horizontal = crs.get();
  PjPtr sub;
  const PJ_TYPE type = proj_get_type(crs.get());
  if (type == PJ_TYPE_COMPOUND_CRS) {
    sub.reset(proj_crs_get_sub_crs(context, crs.get(), 0));
    if (!sub) return fail(ProjReason(context));
    horizontal = sub.get();
  } else if (type == PJ_TYPE_BOUND_CRS) {
    // "+towgs84=..." strings: described by their source CRS.
    sub.reset(proj_get_source_crs(context, crs.get()));
    if (!sub) return fail(ProjReason(context));
    horizontal = sub.get();
  }
  switch (proj_get_type(horizontal)) {
    case PJ_TYPE_GEOGRAPHIC_2D_CRS:
    case PJ_TYPE_GEOGRAPHIC_3D_CRS:
      result.geographic = true;
      break;
    case PJ_TYPE_PROJECTED_CRS:
      result.projected = true;
      break;
    case PJ_TYPE_GEOCENTRIC_CRS:
      result.geocentric = true;
      break;
    default:
      return fail("not a geographic, projected, geocentric or compound CRS");
  }
  if (const char* name = proj_get_name(crs.get())) result.name = name;
  result.heights_as_given = type != PJ_TYPE_COMPOUND_CRS && !result.geocentric &&
                            IsTwoDimensional(context, horizontal);
  if (crs_out != nullptr) {
    if (result.heights_as_given) {
      PjPtr promoted(proj_crs_promote_to_3D(context, nullptr, crs.get()));
      if (!promoted) return fail("cannot be given a height axis: " + ProjReason(context));
      crs = std::move(promoted);
    }
    *crs_out = std::move(crs);
  }
  if (info != nullptr) *info = std::move(result);
  return Status::Ok();
}

Status TransformPoints(PJ* transformation, PJ_DIRECTION direction, const std::string& what,
                       std::vector<Eigen::Vector3d>* points) {
  if (points->empty()) return Status::Ok();
  double* data = points->front().data();
  const size_t stride = sizeof(Eigen::Vector3d);
  const size_t n = points->size();
  proj_errno_reset(transformation);
  proj_trans_generic(transformation, direction, data, stride, n, data + 1, stride, n, data + 2,
                     stride, n, nullptr, 0, 0);
  for (size_t i = 0; i < n; ++i) {
    if (!(*points)[i].allFinite() || (*points)[i].cwiseAbs().maxCoeff() > 1e15) {
      return Status::Error(what + ": point " + std::to_string(i) +
                           " cannot be transformed (outside the CRS's area, or a grid PROJ does "
                           "not have)");
    }
  }
  return Status::Ok();
}

}  // namespace

Status ResolveCrs(const std::string& text, CrsInfo* info) {
  ContextPtr context = NewContext();
  if (!context) return Status::Error("PROJ: cannot create a context");
  return CreateCrs(context.get(), text, info, nullptr);
}

Status SameCrs(const std::string& a, const std::string& b, bool* same) {
  ContextPtr context = NewContext();
  if (!context) return Status::Error("PROJ: cannot create a context");
  PjPtr crs_a, crs_b;
  PHOTOPOSE_RETURN_IF_ERROR(CreateCrs(context.get(), a, nullptr, &crs_a));
  PHOTOPOSE_RETURN_IF_ERROR(CreateCrs(context.get(), b, nullptr, &crs_b));
  // Compared as CreateCrs hands them to the transformations (a 2D CRS promoted to 3D), so two
  // texts are the same exactly when photopose would transform their coordinates alike.
  *same = proj_is_equivalent_to_with_ctx(context.get(), crs_a.get(), crs_b.get(),
                                         PJ_COMP_EQUIVALENT_EXCEPT_AXIS_ORDER_GEOGCRS) != 0;
  return Status::Ok();
}

std::string UtmCrsFor(double longitude_deg, double latitude_deg) {
  int zone = static_cast<int>(std::floor((longitude_deg + 180.0) / 6.0)) + 1;
  zone = std::clamp(zone, 1, 60);
  return "EPSG:" + std::to_string((latitude_deg >= 0.0 ? 32600 : 32700) + zone);
}

// ------------------------------------------------------------------ CrsTransform

struct CrsTransform::Impl {
  ContextPtr context;
  PjPtr transformation;
  std::string what;  // "EPSG:32632 -> EPSG:4979", for messages
};

CrsTransform::CrsTransform() = default;
CrsTransform::~CrsTransform() = default;
CrsTransform::CrsTransform(CrsTransform&&) noexcept = default;
CrsTransform& CrsTransform::operator=(CrsTransform&&) noexcept = default;

Status CrsTransform::Create(const std::string& source, const std::string& target,
                            CrsTransform* out) {
  auto impl = std::make_unique<Impl>();
  impl->context = NewContext();
  if (!impl->context) return Status::Error("PROJ: cannot create a context");
  PJ_CONTEXT* context = impl->context.get();
  PjPtr source_crs, target_crs;
  PHOTOPOSE_RETURN_IF_ERROR(CreateCrs(context, source, nullptr, &source_crs));
  PHOTOPOSE_RETURN_IF_ERROR(CreateCrs(context, target, nullptr, &target_crs));
  PjPtr raw(proj_create_crs_to_crs_from_pj(context, source_crs.get(), target_crs.get(), nullptr,
                                           nullptr));
  if (!raw) {
    return Status::Error("no transformation from CRS '" + source + "' to '" + target +
                         "': " + ProjReason(context));
  }
  impl->transformation.reset(proj_normalize_for_visualization(context, raw.get()));
  if (!impl->transformation) {
    return Status::Error("no transformation from CRS '" + source + "' to '" + target +
                         "': " + ProjReason(context));
  }
  impl->what = source + " -> " + target;
  out->impl_ = std::move(impl);
  return Status::Ok();
}

Status CrsTransform::Forward(std::vector<Eigen::Vector3d>* points) const {
  if (!impl_) return Status::Error("CrsTransform used before Create");
  return TransformPoints(impl_->transformation.get(), PJ_FWD, impl_->what, points);
}

Status CrsTransform::Inverse(std::vector<Eigen::Vector3d>* points) const {
  if (!impl_) return Status::Error("CrsTransform used before Create");
  return TransformPoints(impl_->transformation.get(), PJ_INV, impl_->what, points);
}

// ------------------------------------------------------------------ LocalFrame

struct LocalFrame::Impl {
  ContextPtr context;
  PjPtr topocentric;  // EPSG:4979 (lon, lat deg, h) -> local ENU
  // CRS text -> its transformation to EPSG:4979, made on first use.
  mutable std::map<std::string, CrsTransform> to_geographic;

  Status ToGeographic(const std::string& crs, const CrsTransform** transform) const {
    auto it = to_geographic.find(crs);
    if (it == to_geographic.end()) {
      CrsTransform created;
      PHOTOPOSE_RETURN_IF_ERROR(CrsTransform::Create(crs, kGeographic3d, &created));
      it = to_geographic.emplace(crs, std::move(created)).first;
    }
    *transform = &it->second;
    return Status::Ok();
  }
};

LocalFrame::LocalFrame() = default;
LocalFrame::~LocalFrame() = default;
LocalFrame::LocalFrame(LocalFrame&&) noexcept = default;
LocalFrame& LocalFrame::operator=(LocalFrame&&) noexcept = default;

Status LocalFrame::Create(const std::string& crs, const Eigen::Vector3d& origin, LocalFrame* out) {
  LocalFrame frame;
  frame.impl_ = std::make_unique<Impl>();
  frame.impl_->context = NewContext();
  if (!frame.impl_->context) return Status::Error("PROJ: cannot create a context");
  const CrsTransform* to_geographic = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(frame.impl_->ToGeographic(crs, &to_geographic));
  std::vector<Eigen::Vector3d> origin_points{origin};
  PHOTOPOSE_RETURN_IF_ERROR(to_geographic->Forward(&origin_points));
  frame.origin_lon_lat_h_ = origin_points[0];
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer),
                "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step +proj=cart "
                "+ellps=WGS84 +step +proj=topocentric +ellps=WGS84 +lon_0=%.12f +lat_0=%.12f "
                "+h_0=%.6f",
                frame.origin_lon_lat_h_.x(), frame.origin_lon_lat_h_.y(),
                frame.origin_lon_lat_h_.z());
  frame.definition_ = buffer;
  frame.impl_->topocentric.reset(proj_create(frame.impl_->context.get(), buffer));
  if (!frame.impl_->topocentric) {
    return Status::Error("PROJ cannot make the local frame '" + frame.definition_ +
                         "': " + ProjReason(frame.impl_->context.get()));
  }
  *out = std::move(frame);
  return Status::Ok();
}

Status LocalFrame::ToLocal(const std::string& crs, std::vector<Eigen::Vector3d>* points) const {
  if (!impl_) return Status::Error("LocalFrame used before Create");
  const CrsTransform* to_geographic = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(impl_->ToGeographic(crs, &to_geographic));
  PHOTOPOSE_RETURN_IF_ERROR(to_geographic->Forward(points));
  return TransformPoints(impl_->topocentric.get(), PJ_FWD, crs + " -> local frame", points);
}

Status LocalFrame::FromLocal(const std::string& crs, std::vector<Eigen::Vector3d>* points) const {
  if (!impl_) return Status::Error("LocalFrame used before Create");
  const CrsTransform* to_geographic = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(impl_->ToGeographic(crs, &to_geographic));
  PHOTOPOSE_RETURN_IF_ERROR(
      TransformPoints(impl_->topocentric.get(), PJ_INV, "local frame -> " + crs, points));
  return to_geographic->Inverse(points);
}

Status LocalFrame::LevelFrames(const std::string& crs,
                               const std::vector<Eigen::Vector3d>& points_local,
                               std::vector<Eigen::Matrix3d>* R_level_from_local) const {
  CrsInfo info;
  PHOTOPOSE_RETURN_IF_ERROR(ResolveCrs(crs, &info));
  if (info.geocentric)
    return Status::Error("CRS '" + crs + "' is geocentric: it has no level frame for attitudes");
  // Central differences over +-1 m: the neglected terms are (1 m / Earth radius)^2 relative.
  constexpr double kStepM = 1.0;
  std::vector<Eigen::Vector3d> probes;
  probes.reserve(6 * points_local.size());
  for (const Eigen::Vector3d& p : points_local)
    for (int axis = 0; axis < 3; ++axis)
      for (double sign : {1.0, -1.0}) probes.push_back(p + sign * kStepM * Eigen::Vector3d::Unit(axis));
  PHOTOPOSE_RETURN_IF_ERROR(FromLocal(crs, &probes));
  R_level_from_local->resize(points_local.size());
  for (size_t i = 0; i < points_local.size(); ++i) {
    Eigen::Matrix3d J;  // J(r, c) = d crs_coordinate_r / d local_c
    for (int axis = 0; axis < 3; ++axis)
      J.col(axis) = (probes[6 * i + 2 * axis] - probes[6 * i + 2 * axis + 1]) / (2.0 * kStepM);
    const Eigen::Vector3d up = J.row(2).transpose().normalized();
    Eigen::Vector3d north = J.row(1).transpose();
    north = (north - north.dot(up) * up).normalized();
    const Eigen::Vector3d east = north.cross(up);
    if (!up.allFinite() || !north.allFinite())
      return Status::Error("CRS '" + crs + "': no level frame at point " + std::to_string(i));
    Eigen::Matrix3d& R = (*R_level_from_local)[i];
    R.row(0) = east.transpose();
    R.row(1) = north.transpose();
    R.row(2) = up.transpose();
  }
  return Status::Ok();
}

}  // namespace photopose
