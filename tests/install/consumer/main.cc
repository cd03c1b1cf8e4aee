// An outside program built against the installed photopose (find_package): simulates a scene with
// the core library and resects it with the solvers library (Ceres underneath).
#include <cmath>
#include <iostream>
#include <map>

#include <photopose/core/synthetic_scene.h>
#include <photopose/solvers/resection.h>

int main() {
  photopose::SyntheticSceneOptions options;
  options.noise_px = 0.0;
  photopose::SyntheticScene scene;
  if (!photopose::MakeSyntheticScene(options, &scene).ok()) return 1;
  const photopose::FrameCamera& camera = scene.cameras.front();
  std::map<std::string, Eigen::Vector3d> points;
  for (const auto& p : scene.points) points[p.point_id] = p.position;
  photopose::ResectionInput input;
  input.focal_length_um = camera.focal_length_um;
  input.pixel_size_um = camera.pixel_size_um;
  for (const auto& mark : scene.marks) {
    Eigen::Vector2d xy;
    if (!photopose::ImagePlaneFromPixel(camera, *mark.column_row, photopose::PixelOrigin::kCorner, &xy).ok())
      return 1;
    input.image_plane_um.push_back(xy);
    input.points_in_ground.push_back(points.at(mark.point_id));
    input.sigma_px.push_back(1.0);
  }
  const photopose::ResectionResult result = photopose::ResectImage(photopose::ResectionOptions(), input);
  const double error =
      (result.eo.center_in_ground() - scene.true_frames.front().eo.center_in_ground()).norm();
  std::cout << "resected " << input.image_plane_um.size() << " marks, position error " << error << " m\n";
  return result.success && error < 1e-6 ? 0 : 1;
}
