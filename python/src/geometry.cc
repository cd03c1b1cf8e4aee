// The model: exterior orientation and the rotation conventions (core/types.h, core/rotation.h),
// the camera table's row and the camera models (core/camera.h, core/camera_models.h), the
// collinearity projection (core/collinearity.h).

#include "core/collinearity.h"

#include "common.h"
#include "core/camera.h"
#include "core/camera_models.h"
#include "core/rotation.h"
#include "core/types.h"

namespace photopose::python {

Eigen::Matrix4d PoseMatrix(const ExteriorOrientation& eo) {
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = -R * eo.center_in_ground();
  return T;
}

namespace {

ExteriorOrientation FromRotation(const Eigen::Matrix3d& R, const Eigen::Vector3d& center) {
  ThrowIfError(CheckRotationMatrix(R));
  ExteriorOrientation eo;
  eo.set_center_in_ground(center);
  eo.set_angles_seed_rad(AnglesFromRotation(RotationConvention::kSeed, R));
  return eo;
}

std::string EoRepr(const ExteriorOrientation& eo) {
  const Eigen::Vector3d c = eo.center_in_ground();
  const Eigen::Vector3d a = eo.angles_seed_rad() * kDegreesPerRadian;
  char text[256];
  std::snprintf(text, sizeof(text),
                "ExteriorOrientation(center_in_ground=[%.6f, %.6f, %.6f], "
                "angles_rxryrz_deg=[%.8f, %.8f, %.8f])",
                c.x(), c.y(), c.z(), a.x(), a.y(), a.z());
  return text;
}

// The six parameters [X0, Y0, Z0, omega, phi, kappa] as a list, and back.
std::vector<double> ParametersOf(const ExteriorOrientation& eo) {
  return std::vector<double>(eo.parameters.data(), eo.parameters.data() + 6);
}
void SetParameters(const std::vector<double>& p, ExteriorOrientation* eo) {
  for (int i = 0; i < 6; ++i) eo->parameters[i] = p[i];
}

// N x 2: each row mapped by map(row, &out) (false: no value), NaN rows where it gives none.
template <typename Row, typename Map>
py::array_t<double> MapRowsOrNaN(const std::vector<Row>& rows, Map map) {
  std::vector<Eigen::Vector2d> out(rows.size(), Eigen::Vector2d::Constant(NaN()));
  for (size_t i = 0; i < rows.size(); ++i) {
    Eigen::Vector2d value;
    if (map(rows[i], &value)) out[i] = value;
  }
  return ToArray(out);
}

std::string ParamNamesText(CameraModelType model) {
  std::string text;
  for (const std::string& name : CameraModelParamNames(model))
    text += (text.empty() ? "" : ", ") + name;
  return text;
}

void SetCameraParams(BlockCamera* camera, const py::handle& value) {
  const int n = CameraModelNumParams(camera->model);
  auto a = Vector(value, "params", -1, false);
  if (static_cast<int>(a.size()) != n)
    throw py::value_error("params: model " + std::string(EnumName(camera->model)) + " takes " +
                          std::to_string(n) + " parameters (" + ParamNamesText(camera->model) +
                          "), got " + std::to_string(a.size()));
  camera->params = a;
}

// Observations (model unit) of ground points: NaN rows for points not in front of the camera or
// where the model's inverse does not converge.
py::array_t<double> ProjectThroughCamera(const BlockCamera& camera, const ExteriorOrientation& eo,
                                         const py::handle& points_value) {
  const std::vector<Eigen::Vector3d> points = Points3(points_value, "points_in_ground");
  std::vector<Eigen::Vector2d> out(points.size(), Eigen::Vector2d::Constant(NaN()));
  const CameraModelData data = camera.data();
  {
    py::gil_scoped_release release;
    for (size_t i = 0; i < points.size(); ++i) {
      Eigen::Vector2d ab;
      if (!ProjectToNormalized(eo.data(), points[i].data(), ab.data())) continue;
      Eigen::Vector2d observation;
      if (ObservationFromNormalized(camera.model, camera.params.data(), data, ab, &observation).ok())
        out[i] = observation;
    }
  }
  return ToArray(out);
}

// kDegreesPerRadian, and the pose of an image in the seed convention: its constructors.
py::class_<ExteriorOrientation> BindExteriorOrientation(py::module_& m) {
  m.attr("kDegreesPerRadian") = kDegreesPerRadian;

  // ---------------------------------------------------------------- exterior orientation
  py::class_<ExteriorOrientation> eo(m, "ExteriorOrientation", R"doc(
The pose of an image in the seed convention: the projection centre in the ground frame (m) and
the angles (omega, phi, kappa) (rad) of R_camera_from_ground = Rx(omega) Ry(phi) Rz(kappa), so that
(u, v, w) = R_camera_from_ground (X - X0). The camera frame (u, v, w) has u along film x, v along
film y and w towards the viewer: visible points have w < 0.)doc");
  eo.def(py::init([](const py::object& center, const py::object& angles,
                     RotationConvention convention) {
           ExteriorOrientation out;
           out.set_center_in_ground(Vector3(center, "center_in_ground"));
           const Eigen::Vector3d given = Vector3(angles, "angles_rad");
           // Seed angles are stored as given (not through the matrix and back, which may move
           // them by an ulp); the others are converted.
           out.set_angles_seed_rad(convention == RotationConvention::kSeed
                                       ? given
                                       : SeedAnglesFromConvention(convention, AngleFlags(), given));
           return out;
         }),
         py::arg("center_in_ground") = py::make_tuple(0.0, 0.0, 0.0),
         py::arg("angles_rad") = py::make_tuple(0.0, 0.0, 0.0),
         py::arg("convention") = RotationConvention::kSeed,
         "Centre (m) and three angles (rad) in the named convention ('rxryrz' = seed, 'opk', "
         "'pok'), converted to the seed angles.");
  eo.def_static(
      "from_matrix",
      [](const py::object& R, const py::object& center) {
        return FromRotation(Matrix3(R, "R_camera_from_ground"), Vector3(center, "center_in_ground"));
      },
      py::arg("R_camera_from_ground"), py::arg("center_in_ground"),
      "From the 3 x 3 rotation ground -> camera (u, v, w) and the centre (m).");
  eo.def_static(
      "from_pose_matrix",
      [](const py::object& value) {
        auto a = Matrix(value, "T_camera_from_ground", 4);
        if (a.shape(0) != 3 && a.shape(0) != 4)
          throw py::value_error("T_camera_from_ground: expected a 4 x 4 or 3 x 4 array, got " +
                                std::to_string(a.shape(0)) + " x 4");
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) R(r, c) = a.at(r, c);
          t[r] = a.at(r, 3);
        }
        return FromRotation(R, -R.transpose() * t);
      },
      py::arg("T_camera_from_ground"),
      "From [R | t] (4 x 4 or 3 x 4) with (u, v, w) = R X + t, t = -R X0.");
  return eo;
}

// Its parameters, centre, angles in every convention, rotation and pose matrix; copy and pickle.
void BindExteriorOrientationAccess(py::class_<ExteriorOrientation>& eo) {
  eo.def_property(
      "parameters", [](const ExteriorOrientation& e) { return ToArray(ParametersOf(e)); },
      [](ExteriorOrientation& e, const py::object& v) {
        SetParameters(Vector(v, "parameters", 6, false), &e);
      },
      "[X0, Y0, Z0 (m), omega, phi, kappa (rad, seed)], a copy.");
  eo.def_property(
      "center_in_ground", [](const ExteriorOrientation& e) { return Eigen::Vector3d(e.center_in_ground()); },
      [](ExteriorOrientation& e, const py::object& v) { e.set_center_in_ground(Vector3(v, "center_in_ground")); },
      "Projection centre X0, Y0, Z0 (m, ground frame).");
  eo.def_property(
      "angles_seed_rad", [](const ExteriorOrientation& e) { return Eigen::Vector3d(e.angles_seed_rad()); },
      [](ExteriorOrientation& e, const py::object& v) { e.set_angles_seed_rad(Vector3(v, "angles_seed_rad")); },
      "omega, phi, kappa (rad) of R = Rx(omega) Ry(phi) Rz(kappa) ('rxryrz').");
  eo.def_property_readonly(
      "R_camera_from_ground",
      [](const ExteriorOrientation& e) {
        return Eigen::Matrix3d(RotationFromAngles(RotationConvention::kSeed, e.angles_seed_rad()));
      },
      "3 x 3 rotation ground -> camera (u, v, w).");
  eo.def_property_readonly(
      "T_camera_from_ground", [](const ExteriorOrientation& e) { return PoseMatrix(e); },
      "4 x 4 [R | -R X0; 0 0 0 1]: ground (m) -> camera (u, v, w) (m).");
  eo.def(
      "angles_rad",
      [](const ExteriorOrientation& e, RotationConvention convention, int angle_direction) {
        return Eigen::Vector3d(
            ConventionAnglesFromSeed(convention, AngleFlags{angle_direction}, e.angles_seed_rad()));
      },
      py::arg("convention") = RotationConvention::kSeed, py::arg("angle_direction") = -1,
      "The three angles (rad) in a convention, with a camera table's AngleDirection applied.");
  eo.def(
      "angles_deg",
      [](const ExteriorOrientation& e, RotationConvention convention, int angle_direction) {
        return Eigen::Vector3d(
            ConventionAnglesFromSeed(convention, AngleFlags{angle_direction}, e.angles_seed_rad()) *
            kDegreesPerRadian);
      },
      py::arg("convention") = RotationConvention::kSeed, py::arg("angle_direction") = -1,
      "The same in degrees (the frames table's Omega, Phi, Kappa).");
  eo.def("__repr__", &EoRepr);
  eo.def("__copy__", [](const ExteriorOrientation& e) { return e; });
  eo.def("__deepcopy__", [](const ExteriorOrientation& e, const py::dict&) { return e; });
  eo.def(py::pickle([](const ExteriorOrientation& e) { return py::make_tuple(ParametersOf(e)); },
                    [](const py::tuple& t) {
                      ExteriorOrientation e;
                      SetParameters(t[0].cast<std::vector<double>>(), &e);
                      return e;
                    }));
}

// The rotation conventions (core/rotation.h).
void BindRotationConventions(py::module_& m) {
  m.def(
      "rotation_from_angles",
      [](const py::object& angles, RotationConvention convention) {
        return RotationFromAngles(convention, Vector3(angles, "angles_rad"));
      },
      py::arg("angles_rad"), py::arg("convention") = RotationConvention::kSeed,
      "R_camera_from_ground (3 x 3) of three angles (rad): 'rxryrz' (seed, R = Rx Ry Rz), "
      "'opk' (Wolf & Dewitt / PATB: the transpose for the same numbers) or 'pok'.");
  m.def(
      "angles_from_rotation",
      [](const py::object& R, RotationConvention convention) {
        const Eigen::Matrix3d matrix = Matrix3(R, "R_camera_from_ground");
        ThrowIfError(CheckRotationMatrix(matrix));
        return AnglesFromRotation(convention, matrix);
      },
      py::arg("R_camera_from_ground"), py::arg("convention") = RotationConvention::kSeed,
      "The three angles (rad) of a rotation in a convention (middle angle in [-pi/2, pi/2]).");
  m.def(
      "convention_angles_from_seed",
      [](const py::object& angles, RotationConvention convention, int angle_direction) {
        return ConventionAnglesFromSeed(convention, AngleFlags{angle_direction},
                                        Vector3(angles, "seed_angles_rad"));
      },
      py::arg("seed_angles_rad"), py::arg("convention"), py::arg("angle_direction") = -1,
      "Seed angles (rad) -> the angles (rad) of a convention, AngleDirection applied: what the "
      "frames tables and reports print.");
  m.def(
      "seed_angles_from_convention",
      [](const py::object& angles, RotationConvention convention, int angle_direction) {
        return SeedAnglesFromConvention(convention, AngleFlags{angle_direction},
                                        Vector3(angles, "convention_angles_rad"));
      },
      py::arg("convention_angles_rad"), py::arg("convention"), py::arg("angle_direction") = -1,
      "The inverse of convention_angles_from_seed.");
}

// The collinearity projection (core/collinearity.h).
void BindCollinearity(py::module_& m) {
  m.def(
      "project_to_normalized",
      [](const ExteriorOrientation& e, const py::object& points_value) {
        return MapRowsOrNaN(Points3(points_value, "points_in_ground"),
                            [&](const Eigen::Vector3d& point, Eigen::Vector2d* ab) {
                              return ProjectToNormalized(e.data(), point.data(), ab->data());
                            });
      },
      py::arg("eo"), py::arg("points_in_ground"),
      "The seed's normalised image coordinates (a, b) = (-u / w, -v / w) of N x 3 ground points "
      "(m): N x 2, x right and y up; NaN rows for points not in front of the camera (w >= 0).");
  m.def(
      "project_to_image_plane",
      [](const ExteriorOrientation& e, const py::object& points_value, double focal) {
        return MapRowsOrNaN(Points3(points_value, "points_in_ground"),
                            [&](const Eigen::Vector3d& point, Eigen::Vector2d* xy) {
                              return ProjectToImagePlane(e.data(), point.data(), focal, xy->data());
                            });
      },
      py::arg("eo"), py::arg("points_in_ground"), py::arg("focal_length"),
      "The seed's equations 4-5: x = -c u / w, y = -c v / w (unit of c, e.g. um), N x 2; NaN rows "
      "for points not in front of the camera.");
}

// The camera table's row and its fields.
py::class_<FrameCamera> BindFrameCamera(py::module_& m) {
  auto fc = BindStruct<FrameCamera>(m, "FrameCamera", R"doc(
One row of an ArcGIS frame-camera table (docs/formats.md): focal length, principal point and
distortion in micrometres and the table's mm-based coefficients, the pixel -> film mapping, flags.)doc");
  fc.def_readwrite("camera_id", &FrameCamera::camera_id)
      .def_readwrite("focal_length_um", &FrameCamera::focal_length_um)
      .def_readwrite("principal_x_um", &FrameCamera::principal_x_um)
      .def_readwrite("principal_y_um", &FrameCamera::principal_y_um)
      .def_readwrite("pixel_size_um", &FrameCamera::pixel_size_um)
      .def_readwrite("n_rows", &FrameCamera::n_rows)
      .def_readwrite("n_columns", &FrameCamera::n_columns)
      .def_property(
          "film_coordinate_system",
          [](const FrameCamera& c) { return static_cast<int>(c.film_coordinate_system); },
          [](FrameCamera& c, int v) {
            if (v < 1 || v > 4) throw py::value_error("film_coordinate_system: expected 1, 2, 3 or 4");
            c.film_coordinate_system = static_cast<FilmCoordinateSystem>(v);
          },
          "FilmCoordinateSystem 1-4 (1: x right, y up).")
      .def_readwrite("has_affine", &FrameCamera::has_affine)
      .def_readwrite("affine_a", &FrameCamera::affine_a, "A0, A1, A2")
      .def_readwrite("affine_b", &FrameCamera::affine_b, "B0, B1, B2")
      .def_readwrite("affine_direction", &FrameCamera::affine_direction)
      .def_readwrite("radial_k", &FrameCamera::radial_k, "K0 (1), K1 (mm^-2), K2 (mm^-4), K3 (mm^-6)")
      .def_readwrite("tangential_p", &FrameCamera::tangential_p, "P1, P2 (mm^-1)")
      .def_property(
          "distortion_table",
          [](const FrameCamera& c) { return c.distortion_type == DistortionType::kDistortionTable; },
          [](FrameCamera& c, bool v) {
            c.distortion_type = v ? DistortionType::kDistortionTable : DistortionType::kDistortionModel;
          },
          "DistortionType: True for DistortionTable (radial_distances_um / radial_distortions_um).")
      .def_readwrite("radial_distances_um", &FrameCamera::radial_distances_um)
      .def_readwrite("radial_distortions_um", &FrameCamera::radial_distortions_um)
      .def_readwrite("angle_direction", &FrameCamera::angle_direction)
      .def_readwrite("polarity", &FrameCamera::polarity)
      .def_readwrite("average_z_m", &FrameCamera::average_z_m)
      .def_readwrite("apply_ecc", &FrameCamera::apply_ecc)
      .def_readwrite("earth_radius_m", &FrameCamera::earth_radius_m)
      .def_readwrite("srs", &FrameCamera::srs)
      .def_readwrite("block_name", &FrameCamera::block_name);
  return fc;
}

// Its checks and mappings: pixels <-> film, ground -> pixels.
void BindFrameCameraMethods(py::class_<FrameCamera>& fc) {
  fc.def(
      "validate", [](const FrameCamera& c) { ThrowIfError(c.IsValid()); },
      "Raises photopose.Error naming the first inconsistent field.");
  fc.def(
      "film_from_pixel",
      [](const FrameCamera& c, const py::object& value, PixelOrigin origin) {
        const std::vector<Eigen::Vector2d> pixels = Points2(value, "column_row");
        std::vector<Eigen::Vector2d> out(pixels.size());
        for (size_t i = 0; i < pixels.size(); ++i)
          ThrowIfError(FilmFromPixel(c, pixels[i], origin, &out[i]));
        return ToArray(out);
      },
      py::arg("column_row"), py::arg("pixel_origin") = PixelOrigin::kCorner,
      "N x 2 pixels (Column, Row) -> film (um).");
  fc.def(
      "pixel_from_film",
      [](const FrameCamera& c, const py::object& value, PixelOrigin origin) {
        const std::vector<Eigen::Vector2d> film = Points2(value, "film_um");
        std::vector<Eigen::Vector2d> out(film.size());
        for (size_t i = 0; i < film.size(); ++i)
          ThrowIfError(PixelFromFilm(c, film[i], origin, &out[i]));
        return ToArray(out);
      },
      py::arg("film_um"), py::arg("pixel_origin") = PixelOrigin::kCorner,
      "N x 2 film (um) -> pixels (Column, Row).");
  fc.def(
      "project",
      [](const FrameCamera& c, const ExteriorOrientation& e, const py::object& points_value,
         PixelOrigin origin) {
        return MapRowsOrNaN(Points3(points_value, "points_in_ground"),
                            [&](const Eigen::Vector3d& point, Eigen::Vector2d* pixel) {
                              return ProjectGroundPoint(c, e, point, origin, pixel).ok();
                            });
      },
      py::arg("eo"), py::arg("points_in_ground"), py::arg("pixel_origin") = PixelOrigin::kCorner,
      "N x 3 ground points (m) -> N x 2 pixels (Column, Row) through the whole camera "
      "(collinearity, Polarity, distortion, film, pixel; earth curvature with apply_ecc). NaN rows "
      "for points not in front of the camera.");
}

// A block's camera (core/camera_models.h): its constructors and parameters.
py::class_<BlockCamera> BindCamera(py::module_& m) {
  py::class_<BlockCamera> cam(m, "Camera", R"doc(
The interior orientation of one camera of a block: a model of core/camera_models.h ('FRAME', the
camera table's backward model with observations in film um; or COLMAP's 'SIMPLE_PINHOLE',
'PINHOLE', 'SIMPLE_RADIAL', 'RADIAL', 'OPENCV' with observations in pixels, (0, 0) the top-left
corner of the image) and its parameters in that model's order and units.)doc");
  cam.def(py::init([](CameraModelType model, const py::object& params, const std::string& id,
                      int width, int height) {
            if (model == CameraModelType::kFrame)
              throw py::value_error("model FRAME: use Camera.from_frame_camera(FrameCamera(...))");
            BlockCamera c;
            c.model = model;
            c.camera_id = id;
            c.table.camera_id = id;
            c.table.n_columns = width;
            c.table.n_rows = height;
            SetCameraParams(&c, params);
            return c;
          }),
          py::arg("model"), py::arg("params"), py::arg("camera_id") = "", py::arg("width") = 0,
          py::arg("height") = 0);
  cam.def_static(
      "from_frame_camera",
      [](const FrameCamera& table) {
        ThrowIfError(table.IsValid());
        BlockCamera c;
        c.model = CameraModelType::kFrame;
        c.camera_id = table.camera_id;
        c.table = table;
        const auto p = FrameModelParams(table);
        c.params.assign(p.begin(), p.end());
        return c;
      },
      py::arg("frame_camera"), "The FRAME model of a camera-table row.");
  cam.def_readwrite("camera_id", &BlockCamera::camera_id)
      .def_property_readonly("model", [](const BlockCamera& c) { return c.model; })
      .def_property(
          "params", [](const BlockCamera& c) { return ToArray(c.params); },
          [](BlockCamera& c, const py::object& v) { SetCameraParams(&c, v); },
          "The model's parameters (a copy; assign an array to change them).")
      .def_property_readonly(
          "param_names", [](const BlockCamera& c) { return CameraModelParamNames(c.model); })
      .def_property_readonly("frame_camera", [](const BlockCamera& c) { return c.table; },
                             "The camera-table row (FRAME; a copy).")
      .def_property_readonly("width", [](const BlockCamera& c) { return c.table.n_columns; })
      .def_property_readonly("height", [](const BlockCamera& c) { return c.table.n_rows; })
      .def_property_readonly(
          "observation_unit",
          [](const BlockCamera& c) { return c.model == CameraModelType::kFrame ? "um" : "px"; },
          "'um' (film micrometres) for FRAME, 'px' for the COLMAP models.");
  return cam;
}

// Ground -> observations and observations -> rays through a camera model.
void BindCameraProjection(py::class_<BlockCamera>& cam) {
  cam.def("project", &ProjectThroughCamera, py::arg("eo"), py::arg("points_in_ground"),
          "N x 3 ground points (m) -> N x 2 observations in the model's unit (film um for FRAME, "
          "pixels for the COLMAP models); NaN rows for points not in front of the camera.");
  cam.def(
      "normalized_from_observations",
      [](const BlockCamera& c, const py::object& value) {
        const CameraModelData data = c.data();
        return MapRowsOrNaN(Points2(value, "observations"),
                            [&](const Eigen::Vector2d& observation, Eigen::Vector2d* ab) {
                              return NormalizedFromObservation(c.model, c.params.data(), data,
                                                               observation, ab)
                                  .ok();
                            });
      },
      py::arg("observations"),
      "The rays (a, b) (seed's normalised coordinates, x right, y up) of N x 2 observations; NaN "
      "where the model cannot be inverted.");
  cam.def("__repr__", [](const BlockCamera& c) {
    std::string text = "Camera(model='" + std::string(EnumName(c.model)) + "', camera_id='" +
                       c.camera_id + "', params=[";
    for (size_t i = 0; i < c.params.size(); ++i) {
      if (i > 0) text += ", ";
      text += py::repr(py::float_(c.params[i])).cast<std::string>();
    }
    return text + "])";
  });
}

}  // namespace

// In this order: a function's signature names the classes bound before it.
void BindGeometry(py::module_& m) {
  py::class_<ExteriorOrientation> eo = BindExteriorOrientation(m);
  BindExteriorOrientationAccess(eo);
  BindRotationConventions(m);
  BindCollinearity(m);
  py::class_<FrameCamera> fc = BindFrameCamera(m);
  BindFrameCameraMethods(fc);
  py::class_<BlockCamera> cam = BindCamera(m);
  BindCameraProjection(cam);
}

}  // namespace photopose::python
