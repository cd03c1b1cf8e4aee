// The block (core/block.h) from numpy arrays, from the tables' records or files, a COLMAP model,
// a BAL or Bundler problem, or the synthetic generator; its contents as numpy arrays; the table
// readers and writers (core/io/tables.h, core/io/block_tables.h, core/io/colmap.h, core/io/bal.h).

#include <cmath>

#include "common.h"
#include "core/io/bal.h"
#include "core/io/block_tables.h"
#include "core/io/colmap.h"
#include "core/io/csv.h"
#include "core/io/tables.h"
#include "core/simulation/synthetic_block.h"
#include "solvers/resection/resection.h"

namespace photopose::python {
namespace {

// The names AssembleBlock's messages give the in-memory tables ("marks:4: PointID: ...": row 4,
// counted from 1).
constexpr const char* kCamerasName = "cameras";
constexpr const char* kPointsName = "points";
constexpr const char* kMarksName = "marks";
constexpr const char* kFramesName = "frames";

// A number that comes in as a double (an array element, a record's field), refused by the rule the
// table readers apply to a field's text (ParseFiniteNumber, core/io/csv.h): a NaN Row of the
// fourth mark reads "marks:4: Row: 'nan' is not a finite number", as the marks table says it.
// Checked before the block is assembled, whose own checks would misname a NaN (a mark "outside
// the image", at its Column).
void CheckFinite(double value, const char* table, int line, const char* column) {
  if (std::isfinite(value)) return;
  double number = 0.0;
  std::string why;
  ParseFiniteNumber(FormatNumber(value), &number, &why);
  throw StatusError(std::string(table) + (line > 0 ? ":" + std::to_string(line) : "") + ": " +
                    column + ": " + why);
}

template <int N>
void CheckFinite(const Eigen::Matrix<double, N, 1>& values, const char* table, int line,
                 const char* const (&columns)[N]) {
  for (int k = 0; k < N; ++k) CheckFinite(values[k], table, line, columns[k]);
}

// Every number of a record, under its table's column names (docs/formats.md).
void CheckFiniteRecord(const GroundPoint& p) {
  CheckFinite(p.position, kPointsName, p.line, {"X", "Y", "Z"});
  if (p.accuracy_m)
    CheckFinite(*p.accuracy_m, kPointsName, p.line, {"AccuracyX", "AccuracyY", "AccuracyZ"});
}

void CheckFiniteRecord(const ImageMark& m) {
  if (m.column_row) CheckFinite(*m.column_row, kMarksName, m.line, {"Column", "Row"});
  if (m.film_um) CheckFinite(*m.film_um, kMarksName, m.line, {"FilmX", "FilmY"});
  if (m.accuracy_px) CheckFinite(*m.accuracy_px, kMarksName, m.line, "Accuracy");
}

void CheckFiniteRecord(const FrameRecord& f) {
  CheckFinite(f.eo.center_in_ground(), kFramesName, f.line,
              {"PerspectiveX", "PerspectiveY", "PerspectiveZ"});
  CheckFinite(f.eo.angles_seed_rad(), kFramesName, f.line, {"Omega", "Phi", "Kappa"});
  if (f.center_accuracy_m)
    CheckFinite(*f.center_accuracy_m, kFramesName, f.line, {"AccuracyX", "AccuracyY", "AccuracyZ"});
  if (f.attitude_accuracy_deg)
    CheckFinite(*f.attitude_accuracy_deg, kFramesName, f.line,
                {"AccuracyOmega", "AccuracyPhi", "AccuracyKappa"});
}

void CheckFiniteRecords(const std::vector<GroundPoint>& points,
                        const std::vector<ImageMark>& marks,
                        const std::vector<FrameRecord>& frames) {
  for (const GroundPoint& p : points) CheckFiniteRecord(p);
  for (const ImageMark& m : marks) CheckFiniteRecord(m);
  for (const FrameRecord& f : frames) CheckFiniteRecord(f);
}

PythonBlock Assemble(BlockTables tables) {
  PythonBlock out;
  CallWithoutGil([&] { return AssembleBlock(tables, &out.block); });
  return out;
}

PythonBlock FromTables(std::vector<FrameCamera> cameras, std::vector<GroundPoint> points,
                       std::vector<ImageMark> marks, std::vector<FrameRecord> frames,
                       RotationConvention frames_rotation, PixelOrigin pixel_origin,
                       const std::string& crs, PixelRows pixel_rows) {
  CheckFiniteRecords(points, marks, frames);
  BlockTables tables;
  tables.cameras = std::move(cameras);
  tables.points = std::move(points);
  tables.marks = std::move(marks);
  tables.frames = std::move(frames);
  tables.frames_rotation = frames_rotation;
  tables.pixel_origin = pixel_origin;
  tables.pixel_rows = pixel_rows;
  tables.crs = crs;
  tables.cameras_file = kCamerasName;
  tables.points_file = kPointsName;
  tables.marks_file = kMarksName;
  tables.frames_file = kFramesName;
  return Assemble(std::move(tables));
}

// Per-row optional values: N x 3 / N / scalar, NaN meaning "not stated".
std::vector<std::optional<Eigen::Vector3d>> OptionalRows3(const py::handle& value, const char* name,
                                                          size_t n) {
  std::vector<std::optional<Eigen::Vector3d>> out(n);
  if (value.is_none()) return out;
  py::array a = py::array::ensure(value);
  std::vector<Eigen::Vector3d> rows;
  if (a && a.ndim() == 2) {
    rows = Points3(value, name);
  } else {
    for (const double v : Vector(value, name, static_cast<long>(n), true))
      rows.push_back(Eigen::Vector3d::Constant(v));
  }
  if (rows.size() != n)
    throw py::value_error(std::string(name) + ": expected " + std::to_string(n) + " rows, got " +
                          std::to_string(rows.size()));
  for (size_t i = 0; i < n; ++i)
    if (!rows[i].hasNaN()) out[i] = rows[i];
  return out;
}

PythonBlock FromArrays(const std::vector<FrameCamera>& cameras, const py::object& point_ids_value,
                       const py::object& points_value, const py::object& mark_rasters_value,
                       const py::object& mark_point_ids_value, const py::object& marks_value,
                       const py::object& point_roles, const py::object& point_accuracy,
                       MarkUnit mark_unit, const py::object& mark_accuracy,
                       const py::object& mark_camera_ids_value, std::vector<FrameRecord> frames,
                       RotationConvention frames_rotation, PixelOrigin pixel_origin,
                       PixelRows pixel_rows, const std::string& crs) {
  const std::vector<std::string> point_ids = Strings(point_ids_value, "point_ids");
  const std::vector<Eigen::Vector3d> positions = Points3(points_value, "points_in_ground");
  if (positions.size() != point_ids.size())
    throw py::value_error("points_in_ground has " + std::to_string(positions.size()) +
                          " rows but point_ids " + std::to_string(point_ids.size()));
  std::vector<PointRole> roles(point_ids.size(), PointRole::kControl);
  if (!point_roles.is_none()) {
    if (py::isinstance<py::str>(point_roles)) {
      roles.assign(point_ids.size(), point_roles.cast<PointRole>());
    } else {
      roles = point_roles.cast<std::vector<PointRole>>();
      if (roles.size() != point_ids.size())
        throw py::value_error("point_roles: expected " + std::to_string(point_ids.size()) +
                              " names, got " + std::to_string(roles.size()));
    }
  }
  const auto accuracies = OptionalRows3(point_accuracy, "point_accuracy_m", point_ids.size());
  std::vector<GroundPoint> points(point_ids.size());
  for (size_t i = 0; i < points.size(); ++i) {
    points[i].point_id = point_ids[i];
    points[i].position = positions[i];
    points[i].accuracy_m = accuracies[i];
    points[i].role = roles[i];
    points[i].line = static_cast<int>(i) + 1;
    CheckFiniteRecord(points[i]);  // before the accuracy's sign: an infinite one is not finite
    if (accuracies[i] && InvalidPointAccuracyAxis(*accuracies[i]) >= 0)
      throw py::value_error("point_accuracy_m: row " + std::to_string(i) +
                            " is neither positive on every axis nor 0 on all three (held fixed)");
  }

  const std::vector<std::string> rasters = Strings(mark_rasters_value, "mark_rasters");
  const std::vector<std::string> mark_point_ids = Strings(mark_point_ids_value, "mark_point_ids");
  const std::vector<Eigen::Vector2d> measured = Points2(marks_value, "marks");
  const size_t n = measured.size();
  if (rasters.size() != n || mark_point_ids.size() != n)
    throw py::value_error("marks has " + std::to_string(n) + " rows, mark_rasters " +
                          std::to_string(rasters.size()) + ", mark_point_ids " +
                          std::to_string(mark_point_ids.size()) + ": they must be equal");
  std::vector<double> sigma;
  if (!mark_accuracy.is_none()) sigma = Vector(mark_accuracy, "mark_accuracy", static_cast<long>(n), true);
  std::vector<std::string> camera_ids = Strings(mark_camera_ids_value, "mark_camera_ids");
  if (!camera_ids.empty() && camera_ids.size() != n)
    throw py::value_error("mark_camera_ids: expected " + std::to_string(n) + " names, got " +
                          std::to_string(camera_ids.size()));
  std::vector<ImageMark> marks(n);
  for (size_t i = 0; i < n; ++i) {
    marks[i].raster = rasters[i];
    marks[i].point_id = mark_point_ids[i];
    if (mark_unit == MarkUnit::kPixel) {
      marks[i].column_row = measured[i];
    } else {
      marks[i].film_um = measured[i];
    }
    if (!sigma.empty() && !std::isnan(sigma[i])) marks[i].accuracy_px = sigma[i];
    if (!camera_ids.empty()) marks[i].camera_id = camera_ids[i];
    marks[i].line = static_cast<int>(i) + 1;
  }
  for (size_t i = 0; i < frames.size(); ++i) frames[i].line = static_cast<int>(i) + 1;
  return FromTables(cameras, std::move(points), std::move(marks), std::move(frames),
                    frames_rotation, pixel_origin, crs, pixel_rows);
}

const Block& B(const PythonBlock& b) { return b.block; }

void CheckImage(const Block& block, int image) {
  if (image < 0 || image >= static_cast<int>(block.images.size()))
    throw py::index_error("no image " + std::to_string(image) + " in the block (" +
                          std::to_string(block.images.size()) + " images)");
}

std::string BlockRepr(const PythonBlock& b) {
  const Block& block = b.block;
  int roles[3] = {0, 0, 0};
  for (const BlockPoint& p : block.points) ++roles[static_cast<int>(p.role)];
  std::string text = "Block(" + std::to_string(block.cameras.size()) + " cameras, " +
                     std::to_string(block.images.size()) + " images, " +
                     std::to_string(block.points.size()) + " points (" + std::to_string(roles[0]) +
                     " control, " + std::to_string(roles[1]) + " check, " +
                     std::to_string(roles[2]) + " tie), " + std::to_string(block.marks.size()) +
                     " marks";
  if (!block.crs.empty()) text += ", crs='" + block.crs + "'";
  return text + ")";
}

// ---------------------------------------------------------------- the tables' records
void BindTableRecords(py::module_& m) {
  auto point = BindStruct<GroundPoint>(m, "GroundPoint", "A row of the ground points table.");
  point.def_readwrite("point_id", &GroundPoint::point_id)
      .def_readwrite("position", &GroundPoint::position, "X, Y, Z (m)")
      .def_readwrite("accuracy_m", &GroundPoint::accuracy_m, "AccuracyX/Y/Z (m) or None")
      .def_readwrite("role", &GroundPoint::role, "'control', 'check' or 'tie'")
      .def_readwrite("line", &GroundPoint::line);

  auto mark = BindStruct<ImageMark>(m, "ImageMark", "A row of the image marks table.");
  mark.def_readwrite("raster", &ImageMark::raster)
      .def_readwrite("point_id", &ImageMark::point_id)
      .def_readwrite("column_row", &ImageMark::column_row, "Column, Row (px) or None")
      .def_readwrite("film_um", &ImageMark::film_um, "FilmX, FilmY (um) or None")
      .def_readwrite("accuracy", &ImageMark::accuracy_px, "one sigma in the mark's unit, or None")
      .def_readwrite("camera_id", &ImageMark::camera_id)
      .def_readwrite("line", &ImageMark::line);

  auto frame = BindStruct<FrameRecord>(m, "FrameRecord", R"doc(
A row of the frames table: the exterior orientation (seed angles inside; the file's convention is
applied on reading and writing), optional covariance (6 x 6, m and rad), sigma0, measured
accuracies AccuracyX/Y/Z (m) and AccuracyOmega/Phi/Kappa (deg).)doc");
  frame.def_readwrite("raster", &FrameRecord::raster)
      .def_readwrite("camera_id", &FrameRecord::camera_id)
      .def_readwrite("eo", &FrameRecord::eo)
      .def_readwrite("srs", &FrameRecord::srs)
      .def_readwrite("covariance", &FrameRecord::covariance)
      .def_readwrite("sigma0", &FrameRecord::sigma0)
      .def_readwrite("center_accuracy_m", &FrameRecord::center_accuracy_m)
      .def_readwrite("attitude_accuracy_deg", &FrameRecord::attitude_accuracy_deg)
      .def_readwrite("extra_columns", &FrameRecord::extra_columns)
      .def_readwrite("line", &FrameRecord::line);

  auto gcp = BindStruct<GcpList>(m, "GcpList", "OpenDroneMap's gcp_list.txt: CRS, points, marks.");
  gcp.def_readwrite("crs", &GcpList::crs)
      .def_readwrite("points", &GcpList::points)
      .def_readwrite("marks", &GcpList::marks);
}

// ---------------------------------------------------------------- table files

// read_<table>(path) -> [rows] and write_<table>(path, <rows>) over a table's reader and writer.
template <typename Row>
void DefTableFile(py::module_& m, const std::string& table, const char* rows,
                  Status (*read)(const std::string&, std::vector<Row>*),
                  Status (*write)(const std::string&, const std::vector<Row>&),
                  const char* read_doc = nullptr) {
  m.def(
      ("read_" + table).c_str(),
      [read](const py::object& path) {
        std::vector<Row> out;
        ThrowIfError(read(PathArgument(path, "path"), &out));
        return out;
      },
      py::arg("path"), read_doc);
  m.def(
      ("write_" + table).c_str(),
      [write](const py::object& path, const std::vector<Row>& values) {
        ThrowIfError(write(PathArgument(path, "path"), values));
      },
      py::arg("path"), py::arg(rows));
}

void BindTableFiles(py::module_& m) {
  DefTableFile(m, "camera_table", "cameras", &ReadCameraTable, &WriteCameraTable,
               "The rows of a camera table (CSV).");
  m.def("read_frames_table",
        [](const py::object& path, RotationConvention rotation,
           std::optional<std::vector<FrameCamera>> cameras) {
          FramesTableOptions options;
          options.convention = rotation;
          if (cameras) options.cameras = &*cameras;
          std::vector<FrameRecord> frames;
          ThrowIfError(ReadFramesTable(PathArgument(path, "path"), options, &frames));
          return frames;
        },
        py::arg("path"), py::arg("rotation") = RotationConvention::kSeed,
        py::arg("cameras") = py::none(),
        "The rows of a frames table; Omega/Phi/Kappa (deg) in `rotation`, with the AngleDirection "
        "of the cameras' table when given.");
  m.def("write_frames_table",
        [](const py::object& path, const std::vector<FrameRecord>& frames,
           RotationConvention rotation, std::optional<std::vector<FrameCamera>> cameras) {
          FramesTableOptions options;
          options.convention = rotation;
          if (cameras) options.cameras = &*cameras;
          ThrowIfError(WriteFramesTable(PathArgument(path, "path"), options, frames));
        },
        py::arg("path"), py::arg("frames"), py::arg("rotation") = RotationConvention::kSeed,
        py::arg("cameras") = py::none());
  DefTableFile(m, "ground_points", "points", &ReadGroundPoints, &WriteGroundPoints);
  DefTableFile(m, "image_marks", "marks", &ReadImageMarks, &WriteImageMarks);
  m.def("read_gcp_list", [](const py::object& path) {
    GcpList list;
    ThrowIfError(ReadGcpList(PathArgument(path, "path"), &list));
    return list;
  }, py::arg("path"), "OpenDroneMap's gcp_list.txt.");
}

// ---------------------------------------------------------------- the block
py::class_<PythonBlock> BindBlockClass(py::module_& m) {
  py::class_<PythonBlock> block(m, "Block", R"doc(
A photogrammetric block: cameras, images (with their exterior orientation when known), ground
points (control, check, tie) and image marks. Arrays come out as copies: N x 3 points (m, ground
frame), N x 2 marks in their own unit (px: Column/Row, (0, 0) the image's top-left corner, Row
down, also when read with pixel_rows='up'; um: film), N x 6 poses [X0, Y0, Z0 (m), omega, phi, kappa (rad, seed: R_camera_from_ground
= Rx Ry Rz)], NaN where a value is unset. Build one with Block.from_arrays, Block.from_tables,
read_block, read_colmap_model, read_bal_problem, read_bundler_file or simulate_block.)doc");
  block.def_static("from_tables", &FromTables, py::arg("cameras"), py::arg("points"),
                   py::arg("marks"), py::arg("frames") = std::vector<FrameRecord>(),
                   py::arg("frames_rotation") = RotationConvention::kSeed,
                   py::arg("pixel_origin") = PixelOrigin::kCorner, py::arg("crs") = "",
                   py::arg("pixel_rows") = PixelRows::kDown,
                   "Assembles the tables' records (AssembleBlock): marks paired with points, images "
                   "with cameras and frames, every mark in its camera model's unit; with "
                   "pixel_rows='up' the marks' Row and the cameras' A0-B2 count rows up from the "
                   "bottom edge and are turned to rows counted down (NRows needed).");
  block.def_static("from_arrays", &FromArrays, py::arg("cameras"), py::arg("point_ids"),
                   py::arg("points_in_ground"), py::arg("mark_rasters"), py::arg("mark_point_ids"),
                   py::arg("marks"), py::kw_only(), py::arg("point_roles") = py::none(),
                   py::arg("point_accuracy_m") = py::none(), py::arg("mark_unit") = MarkUnit::kPixel,
                   py::arg("mark_accuracy") = py::none(), py::arg("mark_camera_ids") = py::none(),
                   py::arg("frames") = std::vector<FrameRecord>(),
                   py::arg("frames_rotation") = RotationConvention::kSeed,
                   py::arg("pixel_origin") = PixelOrigin::kCorner,
                   py::arg("pixel_rows") = PixelRows::kDown, py::arg("crs") = "", R"doc(
A block from numpy arrays, assembled as the tables are (AssembleBlock): camera-table rows; N point
ids with their N x 3 ground coordinates (m), roles ('control' by default; 'check', 'tie') and
accuracies (N x 3, N or a scalar, m; NaN: not stated); M marks: raster names, point ids and the
M x 2 measurements, in pixels (mark_unit 'px', Column/Row) or film micrometres ('um'), with their
accuracy (M or a scalar, the mark's unit; NaN: not stated); pixel_rows 'up' for a Row counted up
from the bottom edge (turned to rows counted down with the cameras' NRows, as are their A0-B2).
Errors name the row and the table's column: "marks:4: Row: 'nan' is not a finite number" is the
fourth mark, "frames:2: ..." the second frames record; every number must be finite (NaN only
where it means "not stated").)doc");
  block.def("copy", [](const PythonBlock& b) { return PythonBlock(b); }, "A deep copy.");
  block.def("__copy__", [](const PythonBlock& b) { return PythonBlock(b); });
  block.def("__deepcopy__", [](const PythonBlock& b, const py::dict&) { return PythonBlock(b); });
  block.def("__repr__", &BlockRepr);
  block.def("check", [](const PythonBlock& b) { ThrowIfError(CheckBlock(b.block)); },
            "CheckBlock: raises photopose.Error naming the first offence.");
  return block;
}

// The images' contents as arrays.
void BindImageArrays(py::class_<PythonBlock>& block) {
  block.def_property_readonly("num_cameras", [](const PythonBlock& b) { return B(b).cameras.size(); })
      .def_property_readonly("num_images", [](const PythonBlock& b) { return B(b).images.size(); })
      .def_property_readonly("num_points", [](const PythonBlock& b) { return B(b).points.size(); })
      .def_property_readonly("num_marks", [](const PythonBlock& b) { return B(b).marks.size(); })
      .def_property_readonly("crs", [](const PythonBlock& b) { return B(b).crs; })
      .def_property_readonly("pixel_origin", [](const PythonBlock& b) { return B(b).pixel_origin; })
      .def_property_readonly("cameras", [](const PythonBlock& b) { return B(b).cameras; },
                             "The cameras (copies; set_camera_params changes the block's).")
      .def_property_readonly("image_names",
                             [](const PythonBlock& b) { return Column(B(b).images, &BlockImage::name); })
      .def_property_readonly(
          "image_cameras",
          [](const PythonBlock& b) { return ToArray(Column(B(b).images, &BlockImage::camera)); },
          "Per image, the index of its camera.")
      .def_property_readonly("image_parameters", [](const PythonBlock& b) {
        const auto& images = B(b).images;
        return OptionalRowsArray(images.size(), 6, [&](size_t i) -> std::optional<Vector6d> {
          if (!images[i].eo) return std::nullopt;
          return images[i].eo->parameters;
        });
      }, "N x 6 [X0, Y0, Z0 (m), omega, phi, kappa (rad, seed)]; NaN rows: no orientation.")
      .def_property_readonly("image_centers", [](const PythonBlock& b) {
        const auto& images = B(b).images;
        return OptionalRowsArray(images.size(), 3, [&](size_t i) -> std::optional<Eigen::Vector3d> {
          if (!images[i].eo) return std::nullopt;
          return images[i].eo->center_in_ground();
        });
      }, "N x 3 projection centres (m); NaN rows: no orientation.")
      .def_property_readonly("T_camera_from_ground", [](const PythonBlock& b) {
        const auto& images = B(b).images;
        return StackOrNaN(images.size(), 4, 4, [&](size_t i) -> std::optional<Eigen::Matrix4d> {
          if (!images[i].eo) return std::nullopt;
          return PoseMatrix(*images[i].eo);
        });
      }, "N x 4 x 4 ground -> camera (u, v, w) transforms; NaN for images without orientation.")
      .def_property_readonly("measured_centers", [](const PythonBlock& b) {
        const auto& images = B(b).images;
        return OptionalRowsArray(images.size(), 3, [&](size_t i) { return images[i].measured_center_m; });
      }, "N x 3 measured (GNSS) centres (m); NaN rows: none.")
      .def_property_readonly("center_accuracies_m", [](const PythonBlock& b) {
        const auto& images = B(b).images;
        return OptionalRowsArray(images.size(), 3, [&](size_t i) { return images[i].center_accuracy_m; });
      }, "N x 3 per-image accuracy of the measured centres (m); NaN rows: the adjustment's default.");
}

// The points' and marks' contents as arrays.
void BindPointAndMarkArrays(py::class_<PythonBlock>& block) {
  block.def_property_readonly("point_ids",
                             [](const PythonBlock& b) { return Column(B(b).points, &BlockPoint::id); })
      .def_property_readonly(
          "point_roles", [](const PythonBlock& b) { return Column(B(b).points, &BlockPoint::role); },
          "Per point: 'control', 'check' or 'tie'.")
      .def_property_readonly("point_positions", [](const PythonBlock& b) {
        const auto& points = B(b).points;
        return OptionalRowsArray(points.size(), 3, [&](size_t i) { return points[i].position_m; });
      }, "N x 3 current estimates (m); NaN rows: unknown.")
      .def_property_readonly("surveyed_positions", [](const PythonBlock& b) {
        const auto& points = B(b).points;
        return OptionalRowsArray(points.size(), 3, [&](size_t i) { return points[i].surveyed_m; });
      }, "N x 3 surveyed coordinates of control and check points (m); NaN rows: tie points.")
      .def_property_readonly(
          "mark_images",
          [](const PythonBlock& b) { return ToArray(Column(B(b).marks, &BlockMark::image)); })
      .def_property_readonly(
          "mark_points",
          [](const PythonBlock& b) { return ToArray(Column(B(b).marks, &BlockMark::point)); })
      .def_property_readonly(
          "mark_measured",
          [](const PythonBlock& b) { return ToArray(Column(B(b).marks, &BlockMark::measured)); },
          "M x 2 as read, in each mark's unit (mark_units).")
      .def_property_readonly("mark_units",
                             [](const PythonBlock& b) { return Column(B(b).marks, &BlockMark::unit); })
      .def_property_readonly(
          "mark_observations",
          [](const PythonBlock& b) { return ToArray(Column(B(b).marks, &BlockMark::observation)); },
          "M x 2 in the camera model's unit (film um for FRAME, px for the COLMAP models).");
}

// Finding images and points; setting orientations, positions, measured centres, camera parameters.
void BindBlockEditing(py::class_<PythonBlock>& block) {
  block.def("find_image", [](const PythonBlock& b, const std::string& n) { return B(b).FindImage(n); },
            py::arg("name"), "Index of an image by name, -1 when absent.");
  block.def("find_point", [](const PythonBlock& b, const std::string& n) { return B(b).FindPoint(n); },
            py::arg("point_id"));
  block.def("image_eo", [](const PythonBlock& b, int image) {
    CheckImage(b.block, image);
    return b.block.images[image].eo;
  }, py::arg("image"), "The image's ExteriorOrientation, or None.");
  block.def("set_image_eo", [](PythonBlock& b, int image, std::optional<ExteriorOrientation> eo) {
    CheckImage(b.block, image);
    b.block.images[image].eo = eo;
  }, py::arg("image"), py::arg("eo"), "Sets (or, with None, clears) an image's orientation.");
  block.def("set_image_parameters", [](PythonBlock& b, const py::object& value) {
    auto a = Matrix(value, "parameters", 6);
    if (a.shape(0) != static_cast<py::ssize_t>(b.block.images.size()))
      throw py::value_error("parameters: expected " + std::to_string(b.block.images.size()) +
                            " rows (one per image), got " + std::to_string(a.shape(0)));
    for (size_t i = 0; i < b.block.images.size(); ++i) {
      Vector6d p;
      for (int k = 0; k < 6; ++k) p[k] = a.at(i, k);
      if (p.hasNaN()) {
        b.block.images[i].eo.reset();
      } else {
        ExteriorOrientation eo;
        eo.parameters = p;
        b.block.images[i].eo = eo;
      }
    }
  }, py::arg("parameters"), "All orientations from N x 6 [X0, Y0, Z0, omega, phi, kappa] (m, rad, seed); NaN rows clear.");
  block.def("set_point_positions", [](PythonBlock& b, const py::object& value) {
    const std::vector<Eigen::Vector3d> rows = Points3(value, "positions");
    if (rows.size() != b.block.points.size())
      throw py::value_error("positions: expected " + std::to_string(b.block.points.size()) +
                            " rows (one per point), got " + std::to_string(rows.size()));
    for (size_t i = 0; i < rows.size(); ++i) {
      if (rows[i].hasNaN()) {
        b.block.points[i].position_m.reset();
      } else {
        b.block.points[i].position_m = rows[i];
      }
    }
  }, py::arg("positions"), "All point estimates from N x 3 (m); NaN rows clear (not the surveyed coordinates).");
  block.def("set_measured_centers", [](PythonBlock& b, const py::object& centers, const py::object& accuracy) {
    const size_t n = b.block.images.size();
    const auto rows = OptionalRows3(centers, "centers", n);
    const auto sigmas = OptionalRows3(accuracy, "accuracy_m", n);
    for (size_t i = 0; i < n; ++i) {
      if (sigmas[i] && !((*sigmas[i]).array() > 0.0).all())
        throw py::value_error("accuracy_m: row " + std::to_string(i) + " is not positive");
      b.block.images[i].measured_center_m = rows[i];
      b.block.images[i].center_accuracy_m = rows[i] ? sigmas[i] : std::nullopt;
    }
  }, py::arg("centers"), py::arg("accuracy_m") = py::none(),
     "Measured (GNSS) centres, N x 3 (m, the block's ground frame; NaN rows: none), and their "
     "accuracy (N x 3, N or a scalar, m; None: the adjustment's default, a prior when "
     "BundleAccuracies.camera_positions_are_priors).");
  block.def("set_camera_params", [](PythonBlock& b, int camera, const py::object& params) {
    if (camera < 0 || camera >= static_cast<int>(b.block.cameras.size()))
      throw py::index_error("no camera " + std::to_string(camera) + " in the block");
    BlockCamera& c = b.block.cameras[camera];
    const std::vector<double> p = Vector(params, "params", CameraModelNumParams(c.model), false);
    c.params = p;
  }, py::arg("camera"), py::arg("params"));
}

// An image's marks as the input of a resection (solvers/resection/resection.h).
void BindResectionInputs(py::class_<PythonBlock>& block) {
  block.def("resection_input", [](const PythonBlock& b, int image, double default_accuracy,
                                  double default_film_accuracy_um, bool include_tie_points) {
    CheckImage(b.block, image);
    ResectionInputOptions options;
    options.default_accuracy = default_accuracy;
    options.default_film_accuracy_um = default_film_accuracy_um;
    options.include_tie_points_with_positions = include_tie_points;
    ResectionInput input;
    ThrowIfError(MakeResectionInput(b.block, image, options, &input, nullptr));
    return input;
  }, py::arg("image"), py::kw_only(), py::arg("default_accuracy") = 1.0,
     py::arg("default_film_accuracy_um") = 5.0, py::arg("include_tie_points_with_positions") = false,
     "The image's control marks as a ResectionInput (MakeResectionInput): marks without an "
     "Accuracy take default_accuracy (px) or default_film_accuracy_um (um); the image's "
     "orientation, when set, as approximate values.");
  block.def("resection_inputs", [](const PythonBlock& b, double default_accuracy,
                                   double default_film_accuracy_um) {
    ResectionInputOptions options;
    options.default_accuracy = default_accuracy;
    options.default_film_accuracy_um = default_film_accuracy_um;
    std::vector<int> images;
    std::vector<ResectionInput> inputs;
    for (size_t i = 0; i < b.block.images.size(); ++i) {
      if (b.block.marks_of_image[i].empty()) continue;  // a frames row only: nothing to resect
      ResectionInput input;
      ThrowIfError(MakeResectionInput(b.block, static_cast<int>(i), options, &input, nullptr));
      images.push_back(static_cast<int>(i));
      inputs.push_back(std::move(input));
    }
    return py::make_tuple(ToArray(images), py::cast(std::move(inputs)));
  }, py::kw_only(), py::arg("default_accuracy") = 1.0, py::arg("default_film_accuracy_um") = 5.0,
     "(images, inputs): the resection input of every image that has marks, in block order, as "
     "`photopose resect` builds them.");
}

// ---------------------------------------------------------------- block files
void BindBlockReaders(py::module_& m) {
  m.def("read_block",
        [](const py::object& cameras, const py::object& points, const py::object& marks,
           const py::object& gcp_list, const py::object& frames, const py::object& fiducials,
           RotationConvention rotation, PixelOrigin pixel_origin, PixelRows pixel_rows,
           double max_fiducial_residual_um) {
          BlockFiles files;
          files.cameras = PathArgument(cameras, "cameras");
          files.points = OptionalPathArgument(points, "points");
          files.marks = OptionalPathArgument(marks, "marks");
          files.gcp_list = OptionalPathArgument(gcp_list, "gcp_list");
          files.frames = OptionalPathArgument(frames, "frames");
          files.fiducials = OptionalPathArgument(fiducials, "fiducials");
          files.rotation = rotation;
          files.pixel_origin = pixel_origin;
          files.pixel_rows = pixel_rows;
          files.max_fiducial_residual_um = max_fiducial_residual_um;
          PythonBlock out;
          CallWithoutGil([&] { return ReadBlock(files, &out.block); });
          return out;
        },
        py::arg("cameras"), py::arg("points") = py::none(), py::arg("marks") = py::none(),
        py::kw_only(), py::arg("gcp_list") = py::none(), py::arg("frames") = py::none(),
        py::arg("fiducials") = py::none(), py::arg("rotation") = RotationConvention::kSeed,
        py::arg("pixel_origin") = PixelOrigin::kCorner, py::arg("pixel_rows") = PixelRows::kDown,
        py::arg("max_fiducial_residual_um") = 30.0,
        "Reads the tables (camera table, points + marks or an ODM gcp_list, optional frames table "
        "in `rotation` and measured fiducials) into a Block (ReadBlock); pixel_rows='up' reads the "
        "marks', fiducials' and A0-B2's Row counted up from the bottom edge (NRows needed) and "
        "turns it down.");
  m.def("read_colmap_model", [](const py::object& directory) {
    PythonBlock out;
    out.colmap.emplace();
    const std::string path = PathArgument(directory, "directory");
    CallWithoutGil([&] { return ReadColmapModel(path, &out.block, &*out.colmap); });
    return out;
  }, py::arg("directory"),
        "A COLMAP model, binary (cameras.bin, images.bin, points3D.bin) when those are there, else "
        "text (cameras.txt, images.txt, points3D.txt).");
  m.def("read_bal_problem", [](const py::object& path) {
    PythonBlock out;
    const std::string p = PathArgument(path, "path");
    CallWithoutGil([&] { return ReadBalProblem(p, &out.block); });
    return out;
  }, py::arg("path"), "A BAL problem file (Agarwal et al. 2010).");
  m.def("read_bundler_file", [](const py::object& path) {
    PythonBlock out;
    const std::string p = PathArgument(path, "path");
    CallWithoutGil([&] { return ReadBundlerFile(p, &out.block); });
    return out;
  }, py::arg("path"), "A Bundler v0.3 .out file.");
}

void BindBlockWriters(py::module_& m) {
  m.def("write_colmap_model", [](const PythonBlock& b, const py::object& directory) {
    const std::string path = PathArgument(directory, "directory");
    // Control joined by georeferencing: the extras describe the model's part alone.
    if (b.colmap && (b.colmap->point_rgb.size() != b.block.points.size() ||
                     b.colmap->mark_keypoint_index.size() != b.block.marks.size())) {
      ThrowIfError(Status::Error(
          "write_colmap_model: the block has " + std::to_string(b.block.points.size()) +
          " points and " + std::to_string(b.block.marks.size()) + " marks, the COLMAP model it was read from " +
          std::to_string(b.colmap->point_rgb.size()) + " and " + std::to_string(b.colmap->mark_keypoint_index.size()) +
          " (georeferencing joined control to it): write it with write_adjusted_colmap_model(block, directory, "
          "adjustment, georeference), which leaves the control out"));
    }
    CallWithoutGil([&] { return WriteColmapModel(path, b.block, b.colmap ? &*b.colmap : nullptr); });
  }, py::arg("block"), py::arg("directory"),
     "Writes the block as a COLMAP text model (ids, keypoints and colours of a model read with "
     "read_colmap_model kept).");
  m.def("write_block_tables",
        [](const PythonBlock& b, const py::object& cameras, const py::object& points,
           const py::object& marks, const py::object& frames, RotationConvention rotation,
           bool write_tie_points) {
          BlockTableFiles files;
          files.cameras = OptionalPathArgument(cameras, "cameras");
          files.points = OptionalPathArgument(points, "points");
          files.marks = OptionalPathArgument(marks, "marks");
          files.frames = OptionalPathArgument(frames, "frames");
          BlockTableWriteOptions options;
          options.rotation = rotation;
          options.write_tie_points = write_tie_points;
          CallWithoutGil([&] { return WriteBlockTables(b.block, files, options); });
        },
        py::arg("block"), py::kw_only(), py::arg("cameras") = py::none(),
        py::arg("points") = py::none(), py::arg("marks") = py::none(),
        py::arg("frames") = py::none(), py::arg("rotation") = RotationConvention::kSeed,
        py::arg("write_tie_points") = true,
        "Writes the block as the tables photopose reads back (None leaves a table out).");
}

// ---------------------------------------------------------------- synthetic blocks
void BindSyntheticBlockOptions(py::module_& m) {
  auto sim = BindStruct<SyntheticBlockOptions>(m, "SyntheticBlockOptions", R"doc(
The seeded synthetic aerial block of tests, benchmarks and `photopose simulate --scenario=block`
(core/simulation/synthetic_block.h): flight lines, terrain, camera, points, noise, blunders, a
perturbed start.)doc");
  sim.def_readwrite("seed", &SyntheticBlockOptions::seed)
      .def_readwrite("num_lines", &SyntheticBlockOptions::num_lines)
      .def_readwrite("images_per_line", &SyntheticBlockOptions::images_per_line)
      .def_readwrite("forward_spacing_m", &SyntheticBlockOptions::forward_spacing_m)
      .def_readwrite("side_spacing_m", &SyntheticBlockOptions::side_spacing_m)
      .def_readwrite("forward_overlap", &SyntheticBlockOptions::forward_overlap)
      .def_readwrite("side_overlap", &SyntheticBlockOptions::side_overlap)
      .def_readwrite("flying_height_m", &SyntheticBlockOptions::flying_height_m)
      .def_readwrite("origin_m", &SyntheticBlockOptions::origin_m)
      .def_readwrite("serpentine", &SyntheticBlockOptions::serpentine)
      .def_readwrite("position_jitter_m", &SyntheticBlockOptions::position_jitter_m)
      .def_readwrite("attitude_jitter_deg", &SyntheticBlockOptions::attitude_jitter_deg)
      .def_readwrite("nominal_angles_deg", &SyntheticBlockOptions::nominal_angles_deg)
      .def_readwrite("ground_height_m", &SyntheticBlockOptions::ground_height_m)
      .def_readwrite("terrain_relief_m", &SyntheticBlockOptions::terrain_relief_m)
      .def_readwrite("camera_model", &SyntheticBlockOptions::camera_model)
      .def_readwrite("focal_length_mm", &SyntheticBlockOptions::focal_length_mm)
      .def_readwrite("pixel_size_um", &SyntheticBlockOptions::pixel_size_um)
      .def_readwrite("image_width_px", &SyntheticBlockOptions::image_width_px)
      .def_readwrite("image_height_px", &SyntheticBlockOptions::image_height_px)
      .def_readwrite("camera_params", &SyntheticBlockOptions::camera_params)
      .def_readwrite("earth_curvature", &SyntheticBlockOptions::earth_curvature)
      .def_readwrite("num_tie_points", &SyntheticBlockOptions::num_tie_points)
      .def_readwrite("tie_point_density_per_m2", &SyntheticBlockOptions::tie_point_density_per_m2)
      .def_readwrite("min_tie_views", &SyntheticBlockOptions::min_tie_views)
      .def_readwrite("num_control_points", &SyntheticBlockOptions::num_control_points)
      .def_readwrite("num_check_points", &SyntheticBlockOptions::num_check_points)
      .def_readwrite("control_sigma_m", &SyntheticBlockOptions::control_sigma_m)
      .def_readwrite("control_accuracy_m", &SyntheticBlockOptions::control_accuracy_m)
      .def_readwrite("mark_sigma_px", &SyntheticBlockOptions::mark_sigma_px)
      .def_readwrite("mark_accuracy_px", &SyntheticBlockOptions::mark_accuracy_px)
      .def_readwrite("gnss", &SyntheticBlockOptions::gnss)
      .def_readwrite("gnss_sigma_m", &SyntheticBlockOptions::gnss_sigma_m)
      .def_readwrite("gnss_accuracy_m", &SyntheticBlockOptions::gnss_accuracy_m)
      .def_readwrite("attitude", &SyntheticBlockOptions::attitude)
      .def_readwrite("attitude_sigma_deg", &SyntheticBlockOptions::attitude_sigma_deg)
      .def_readwrite("attitude_accuracy_deg", &SyntheticBlockOptions::attitude_accuracy_deg)
      .def_readwrite("num_tie_blunders", &SyntheticBlockOptions::num_tie_blunders)
      .def_readwrite("tie_blunder_px", &SyntheticBlockOptions::tie_blunder_px)
      .def_readwrite("num_control_blunders", &SyntheticBlockOptions::num_control_blunders)
      .def_readwrite("control_blunder_m", &SyntheticBlockOptions::control_blunder_m)
      .def_readwrite("num_gnss_blunders", &SyntheticBlockOptions::num_gnss_blunders)
      .def_readwrite("gnss_blunder_m", &SyntheticBlockOptions::gnss_blunder_m)
      .def_readwrite("start_position_sigma_m", &SyntheticBlockOptions::start_position_sigma_m)
      .def_readwrite("start_angle_sigma_deg", &SyntheticBlockOptions::start_angle_sigma_deg)
      .def_readwrite("start_point_sigma_m", &SyntheticBlockOptions::start_point_sigma_m)
      .def_readwrite("tie_point_start", &SyntheticBlockOptions::tie_point_start);
  sim.def("validate", [](const SyntheticBlockOptions& o) { ThrowIfError(o.IsValid()); });
}

void BindSyntheticBlock(py::module_& m) {
  py::class_<SyntheticBlockTruth> truth(m, "SyntheticBlockTruth", "The truth of a synthetic block.");
  truth.def_property_readonly("image_parameters", [](const SyntheticBlockTruth& t) {
         std::vector<Vector6d> rows;
         for (const ExteriorOrientation& eo : t.eo) rows.push_back(eo.parameters);
         py::array_t<double> out({static_cast<py::ssize_t>(rows.size()), py::ssize_t(6)});
         for (size_t i = 0; i < rows.size(); ++i)
           for (int k = 0; k < 6; ++k) out.mutable_at(i, k) = rows[i][k];
         return out;
       }, "N x 6 true orientations (m, rad, seed).")
      .def_property_readonly("points_m", [](const SyntheticBlockTruth& t) { return ToArray(t.points_m); })
      .def_property_readonly("blunder_marks", [](const SyntheticBlockTruth& t) { return ToArray(t.blunder_marks); })
      .def_property_readonly("blunder_control_points",
                             [](const SyntheticBlockTruth& t) { return ToArray(t.blunder_control_points); })
      .def_property_readonly("blunder_gnss_images",
                             [](const SyntheticBlockTruth& t) { return ToArray(t.blunder_gnss_images); });

  m.def("simulate_block", [](std::optional<SyntheticBlockOptions> options, const py::kwargs& kwargs) {
    SyntheticBlockOptions o = options.value_or(SyntheticBlockOptions());
    if (kwargs.size() > 0) {
      py::object holder = py::cast(o);
      SetKeywordAttributes(holder, kwargs);
      o = holder.cast<SyntheticBlockOptions>();
    }
    PythonBlock out;
    SyntheticBlockTruth t;
    CallWithoutGil([&] { return MakeSyntheticBlock(o, &out.block, &t); });
    return py::make_tuple(py::cast(std::move(out)), py::cast(std::move(t)));
  }, py::arg("options") = py::none(),
     "(block, truth): a seeded synthetic block; options as a SyntheticBlockOptions or as keywords.");
}

}  // namespace

// In this order: a function's signature names the classes bound before it.
void BindBlock(py::module_& m) {
  BindTableRecords(m);
  BindTableFiles(m);
  py::class_<PythonBlock> block = BindBlockClass(m);
  BindImageArrays(block);
  BindPointAndMarkArrays(block);
  BindBlockEditing(block);
  BindResectionInputs(block);
  BindBlockReaders(m);
  BindBlockWriters(m);
  BindSyntheticBlockOptions(m);
  BindSyntheticBlock(m);
}

}  // namespace photopose::python
