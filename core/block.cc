#include "core/block.h"

#include <Eigen/LU>
#include <cmath>


namespace photopose {
namespace {

template <typename Items, typename Name>
int FindByName(const Items& items, const std::string& name, Name name_of) {
  for (size_t i = 0; i < items.size(); ++i)
    if (name_of(items[i]) == name) return static_cast<int>(i);
  return -1;
}

bool Finite(const std::optional<Eigen::Vector3d>& v) { return !v || v->allFinite(); }

}  // namespace

int InvalidPointAccuracyAxis(const Eigen::Vector3d& accuracy_m) {
  const bool zero = accuracy_m[0] == 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double sigma = accuracy_m[axis];
    if (!std::isfinite(sigma) || sigma < 0.0 || (sigma == 0.0) != zero) return axis;
  }
  return -1;
}

bool IsHeldFixed(const BlockPoint& point) {
  return point.role == PointRole::kControl && point.accuracy_m &&
         (point.accuracy_m->array() == 0.0).all();
}

CameraModelData BlockCamera::data() const {
  if (model == CameraModelType::kFrame) return FrameModelData(table);
  return CameraModelData();
}

double BlockCamera::earth_curvature_radius_m() const {
  return model == CameraModelType::kFrame && table.apply_ecc ? table.earth_radius_m : 0.0;
}

void Block::BuildIndex() {
  marks_of_image.assign(images.size(), {});
  marks_of_point.assign(points.size(), {});
  // Counted first, so that each list holds exactly its marks (growing by doubling left up to half
  // of the 8 bytes a mark unused: 10 MB at a thousand images).
  std::vector<int> image_count(images.size(), 0), point_count(points.size(), 0);
  for (const BlockMark& mark : marks) {
    if (mark.image >= 0 && mark.image < static_cast<int>(images.size())) ++image_count[mark.image];
    if (mark.point >= 0 && mark.point < static_cast<int>(points.size())) ++point_count[mark.point];
  }
  for (size_t i = 0; i < images.size(); ++i) marks_of_image[i].reserve(image_count[i]);
  for (size_t p = 0; p < points.size(); ++p) marks_of_point[p].reserve(point_count[p]);
  for (size_t m = 0; m < marks.size(); ++m) {
    const BlockMark& mark = marks[m];
    if (mark.image >= 0 && mark.image < static_cast<int>(images.size()))
      marks_of_image[mark.image].push_back(static_cast<int>(m));
    if (mark.point >= 0 && mark.point < static_cast<int>(points.size()))
      marks_of_point[mark.point].push_back(static_cast<int>(m));
  }
}

int Block::FindCamera(const std::string& camera_id) const {
  return FindByName(cameras, camera_id, [](const BlockCamera& c) { return c.camera_id; });
}

int Block::FindImage(const std::string& name) const {
  return FindByName(images, name, [](const BlockImage& i) { return i.name; });
}

int Block::FindPoint(const std::string& id) const {
  return FindByName(points, id, [](const BlockPoint& p) { return p.id; });
}

Status CheckBlock(const Block& block) {
  for (const BlockCamera& camera : block.cameras) {
    const int expected = CameraModelNumParams(camera.model);
    if (static_cast<int>(camera.params.size()) != expected) {
      return Status::Error("camera '" + camera.camera_id + "' has " +
                           std::to_string(camera.params.size()) + " parameters; the " +
                           EnumName(camera.model) + " model has " +
                           std::to_string(expected));
    }
    for (const double value : camera.params)
      if (!std::isfinite(value))
        return Status::Error("camera '" + camera.camera_id + "' has a non-finite parameter");
  }
  const int num_cameras = static_cast<int>(block.cameras.size());
  for (const BlockImage& image : block.images) {
    if (image.camera < 0 || image.camera >= num_cameras)
      return Status::Error("image '" + image.name + "' has no camera");
    if ((image.eo && !image.eo->parameters.allFinite()) || !Finite(image.measured_center_m) ||
        !Finite(image.center_accuracy_m) || !Finite(image.measured_angles_rad) ||
        !Finite(image.attitude_accuracy_rad))
      return Status::Error("image '" + image.name + "' has a non-finite value");
  }
  for (const BlockPoint& point : block.points) {
    if (!Finite(point.surveyed_m) || !Finite(point.accuracy_m) || !Finite(point.position_m))
      return Status::Error("point '" + point.id + "' has a non-finite coordinate");
    if (point.role != PointRole::kTie && !point.surveyed_m)
      return Status::Error("point '" + point.id + "' is a control or check point without coordinates");
    if (point.accuracy_m && InvalidPointAccuracyAxis(*point.accuracy_m) >= 0)
      return Status::Error("point '" + point.id +
                           "' has an accuracy that is neither positive on every axis nor 0 on all "
                           "three (held fixed)");
  }
  const int num_images = static_cast<int>(block.images.size());
  const int num_points = static_cast<int>(block.points.size());
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    if (mark.image < 0 || mark.image >= num_images || mark.point < 0 || mark.point >= num_points)
      return Status::Error("mark " + std::to_string(m + 1) + " names no image or point");
    if (!mark.measured.allFinite() || !mark.observation.allFinite() ||
        !(mark.observation_units_per_unit > 0.0) || (mark.accuracy && !(*mark.accuracy > 0.0)))
      return Status::Error("mark " + std::to_string(m + 1) + " has a non-finite or non-positive value");
  }
  return Status::Ok();
}

BlockMark MakePixelMark(int image, int point, const Eigen::Vector2d& pixel_px, int line) {
  BlockMark mark;
  mark.image = image;
  mark.point = point;
  mark.unit = MarkUnit::kPixel;
  mark.measured = pixel_px;
  mark.observation = pixel_px;
  mark.line = line;
  return mark;
}

FrameCamera PixelToFilmCamera(const Block& block, int image) {
  const BlockImage& i = block.images[image];
  const FrameCamera& camera = block.cameras[i.camera].table;
  return i.fiducial_fit ? WithFiducialAffine(camera, *i.fiducial_fit) : camera;
}


}  // namespace photopose
