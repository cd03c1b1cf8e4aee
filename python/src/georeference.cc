// Georeferencing an SfM model (solvers/georeference/georeference.h): its inputs from ODM's
// geo.txt / gcp_list.txt, the images' GPS tags (core/io/exif_gps.h) or numpy arrays with a CRS;
// the robust similarity and the weighted adjustment in the local East-North-Up frame; the errors
// and the outputs in the output CRS.

#include "solvers/georeference/georeference.h"

#include <cmath>

#include "common.h"
#include "core/io/exif_gps.h"
#include "core/io/tables.h"
#include "solvers/georeference/adjusted_colmap_model.h"

namespace photopose::python {
namespace {

// count, rmse_m, total_m; without a point (count 0) the figures are None, never a zero.
py::dict RmseDict(const GeoreferenceRmse& r) {
  py::dict d;
  d["count"] = r.count;
  d["rmse_m"] = py::none();
  d["total_m"] = py::none();
  if (r.count > 0) {
    d["rmse_m"] = r.rmse_m;
    d["total_m"] = r.total_m;
  }
  return d;
}

// Camera positions from files: ODM's geo.txt, the images' GPS tags.
void BindPositionFiles(py::module_& m) {
  auto geo_record = BindStruct<GeoTxtRecord>(m, "GeoTxtRecord", "A line of ODM's geo.txt.");
  geo_record.def_readwrite("image", &GeoTxtRecord::image)
      .def_readwrite(
          "position", &GeoTxtRecord::position,
          "x, y, z in the file's CRS (GIS order: easting or longitude first); z NaN without height")
      .def_readwrite("has_height", &GeoTxtRecord::has_height,
                     "False for a line 'image x y': horizontal only")
      .def_readwrite("yaw_pitch_roll_deg", &GeoTxtRecord::yaw_pitch_roll_deg, "deg, or None")
      .def_readwrite("horizontal_accuracy_m", &GeoTxtRecord::horizontal_accuracy_m, "m, or None")
      .def_readwrite("vertical_accuracy_m", &GeoTxtRecord::vertical_accuracy_m, "m, or None")
      .def_readwrite("line", &GeoTxtRecord::line);
  auto geo = BindStruct<GeoTxt>(m, "GeoTxt", "OpenDroneMap's geo.txt: CRS and camera positions.");
  geo.def_readwrite("crs", &GeoTxt::crs).def_readwrite("records", &GeoTxt::records);
  m.def(
      "read_geo_txt",
      [](const py::object& path) {
        GeoTxt out;
        ThrowIfError(ReadGeoTxt(PathArgument(path, "path"), &out));
        return out;
      },
      py::arg("path"), "OpenDroneMap's geo.txt (first line the CRS).");

  py::class_<ExifGps> exif(m, "ExifGps",
                           "The GPS position an image file carries (EXIF or DJI XMP).");
  exif.def_readonly("lon_lat_height", &ExifGps::lon_lat_height,
                    "longitude, latitude (deg), height (m, as written: the CRS decides what it is)")
      .def_property_readonly(
          "source", [](const ExifGps& g) { return EnumName(g.source); }, "'exif' or 'dji_xmp'")
      .def_readonly("rtk_sigma_enu_m", &ExifGps::rtk_sigma_enu_m,
                    "DJI RTK one sigma east, north, up (m), or None")
      .def_readonly("rtk_flag", &ExifGps::rtk_flag, "DJI RtkFlag (50 fixed), or None")
      .def("__repr__", [](const py::object& self) { return PropertiesRepr(self); });
  m.def(
      "read_image_gps",
      [](const py::object& path) {
        ExifGps out;
        ThrowIfError(ReadExifGps(PathArgument(path, "path"), &out));
        return out;
      },
      py::arg("path"),
      "The GPS tags of one image file (libexiv2); raises photopose.Error when it has none.");
  m.def(
      "parse_image_gps",
      [](const py::bytes& data, const std::string& name) {
        ExifGps out;
        const std::string_view bytes(data);
        CallWithoutGil([&] { return ParseExifGps(bytes, name, &out); });
        return out;
      },
      py::arg("data"), py::arg("name") = "<bytes>",
      "The GPS tags of an image file held in memory (its bytes, e.g. from a zip or an HTTP "
      "response); name names it in messages. Raises photopose.Error as read_image_gps does.");
  m.def(
      "read_images_gps",
      [](const py::object& directory, const std::vector<std::string>& names) {
        std::vector<std::optional<ExifGps>> positions;
        std::vector<std::string> missing;
        const std::string dir = PathArgument(directory, "directory");
        CallWithoutGil([&] { return ReadExifGpsOfImages(dir, names, &positions, &missing); });
        return py::make_tuple(positions, missing);
      },
      py::arg("directory"), py::arg("names"),
      "(positions, missing): per name its ExifGps or None, and the names without GPS tags.");
}

// What ties a model to the ground, from files or arrays, and how it is georeferenced.
// GeoreferenceInputs.set_positions: camera positions from arrays (a NaN z: no height; a NaN row of
// accuracies: none stated).
void SetPositionsFromArrays(GeoreferenceInputs& self, const std::string& crs,
                            const std::vector<std::string>& images, const py::object& positions,
                            const py::object& accuracies_m, const std::string& source) {
  const std::vector<Eigen::Vector3d> xyz = Points3(positions, "positions");
  if (xyz.size() != images.size())
    throw py::value_error("positions: " + std::to_string(xyz.size()) + " rows for " +
                          std::to_string(images.size()) + " images");
  std::vector<Eigen::Vector3d> sigma;
  if (!accuracies_m.is_none()) {
    sigma = Points3(accuracies_m, "accuracies_m");
    if (sigma.size() != images.size())
      throw py::value_error("accuracies_m: " + std::to_string(sigma.size()) + " rows for " +
                            std::to_string(images.size()) + " images");
  }
  self.positions_crs = crs;
  self.positions_source = source;
  self.positions_crs_line = 0;
  self.positions.clear();
  for (size_t i = 0; i < images.size(); ++i) {
    CameraPositionMeasurement p;
    p.image = images[i];
    p.position = xyz[i];
    p.has_height = !std::isnan(xyz[i].z());  // a NaN z: no height, as a geo.txt line "image x y"
    if (!sigma.empty() && sigma[i].allFinite()) p.accuracy_m = sigma[i];
    self.positions.push_back(p);
  }
}

void BindCameraPositionMeasurement(py::module_& m) {
  auto position = BindStruct<CameraPositionMeasurement>(
      m, "CameraPositionMeasurement",
      "A measured projection centre (GNSS) of an image, named as the block names it.");
  position.def_readwrite("image", &CameraPositionMeasurement::image)
      .def_readwrite("position", &CameraPositionMeasurement::position,
                     "in GeoreferenceInputs.positions_crs")
      .def_readwrite("has_height", &CameraPositionMeasurement::has_height,
                     "False: position[2] is not read; the position constrains the horizontal only")
      .def_readwrite("accuracy_m", &CameraPositionMeasurement::accuracy_m,
                     "one sigma east, north, up (m), or None")
      .def_readwrite("line", &CameraPositionMeasurement::line);
}

void BindGeoreferenceInputsClass(py::module_& m) {
  auto inputs = BindStruct<GeoreferenceInputs>(m, "GeoreferenceInputs", R"doc(
What ties a model to the ground: camera positions in positions_crs and control / check points in
control_crs with their marks (px, (0, 0) the top-left corner of the image). Fill it from files
(set_positions_from_geo_txt, set_positions_from_frames, set_positions_from_images_gps,
set_control_from_gcp_list) or from
arrays (set_positions).)doc");
  inputs.def_readwrite("positions_crs", &GeoreferenceInputs::positions_crs)
      .def_readwrite("positions_source", &GeoreferenceInputs::positions_source)
      .def_readwrite("positions", &GeoreferenceInputs::positions)
      .def_readwrite("control_crs", &GeoreferenceInputs::control_crs)
      .def_readwrite("control_source", &GeoreferenceInputs::control_source)
      .def_readwrite("control_points", &GeoreferenceInputs::control_points)
      .def_readwrite("control_marks", &GeoreferenceInputs::control_marks)
      .def_readwrite("attitudes_not_used", &GeoreferenceInputs::attitudes_not_used,
                     "geo.txt yaw/pitch/roll read and not used (count)");
  inputs.def(
      "set_positions", &SetPositionsFromArrays, py::arg("crs"), py::arg("images"),
      py::arg("positions"), py::arg("accuracies_m") = py::none(), py::arg("source") = "arrays",
      "Camera positions: N image names, N x 3 coordinates in crs (GIS order; a NaN z: no height, "
      "the position horizontal only), optional N x 3 one-sigma accuracies east, north, up (m; a "
      "NaN "
      "row: none stated).");
  inputs.def(
      "set_positions_from_geo_txt",
      [](GeoreferenceInputs& self, const GeoTxt& geo, const std::string& source) {
        SetPositionsFromGeoTxt(geo, source, &self);
      },
      py::arg("geo"), py::arg("source") = "geo.txt",
      "The camera positions of a geo.txt (its yaw/pitch/roll are not used).");
  inputs.def(
      "set_positions_from_frames",
      [](GeoreferenceInputs& self, const std::vector<FrameRecord>& frames, const std::string& crs,
         const std::string& source) {
        ThrowIfError(SetPositionsFromFrames(frames, crs, "crs", source, &self));
      },
      py::arg("frames"), py::arg("crs") = "", py::arg("source") = "frames table",
      "The camera positions of a frames table (read_frames_table; PerspectiveX/Y/Z, AccuracyX/Y/Z "
      "when given; Omega/Phi/Kappa counted in attitudes_not_used). Their CRS is each row's SRS, "
      "else crs, and one for all rows: a row in another CRS, a row without SRS beside rows with "
      "one "
      "and no crs, an SRS PROJ does not know, or no SRS and no crs raise photopose.Error naming "
      "source, the line and SRS.");
  inputs.def(
      "set_positions_from_images_gps",
      [](GeoreferenceInputs& self, const std::vector<std::string>& images,
         const std::vector<std::optional<ExifGps>>& gps, const std::string& crs) {
        if (gps.size() != images.size())
          throw py::value_error("gps: " + std::to_string(gps.size()) + " entries for " +
                                std::to_string(images.size()) + " images");
        SetPositionsFromGps(images, gps, crs, "GPS tags", &self);
      },
      py::arg("images"), py::arg("gps"), py::arg("crs") = "EPSG:4979",
      "The positions read_images_gps returned (None entries skipped), in crs: EPSG:4979 takes the "
      "heights as ellipsoidal, EPSG:4326+5773 as EGM96 (docs/formats.md).");
  inputs.def(
      "set_control_from_gcp_list",
      [](GeoreferenceInputs& self, const GcpList& list,
         const std::vector<std::string>& check_points, const std::string& source) {
        ThrowIfError(SetControlFromGcpList(list, check_points, source, &self));
      },
      py::arg("gcp_list"), py::arg("check_points") = std::vector<std::string>(),
      py::arg("source") = "gcp_list.txt", "Control (and check, as named) points with their marks.");
}

void BindGeoreferenceOptions(py::module_& m) {
  auto options =
      BindStruct<GeoreferenceOptions>(m, "GeoreferenceOptions", "How a model is georeferenced.");
  options
      .def_readwrite("out_crs", &GeoreferenceOptions::out_crs,
                     "empty: the control's CRS, else the positions' when projected, else the UTM "
                     "zone of the centre")
      .def_readwrite("default_camera_accuracy_m", &GeoreferenceOptions::default_camera_accuracy_m,
                     "m")
      .def_readwrite("default_marker_accuracy_m", &GeoreferenceOptions::default_marker_accuracy_m,
                     "m");
}

// The control and check errors: the RMSE per axis and each surveyed point's error, after the
// similarity and after the adjustment.
void BindGeoreferenceErrors(py::class_<GeoreferenceResult>& result) {
  result
      .def_property_readonly(
          "control_after_similarity",
          [](const GeoreferenceResult& r) { return RmseDict(r.control_after_similarity); })
      .def_property_readonly(
          "check_after_similarity",
          [](const GeoreferenceResult& r) { return RmseDict(r.check_after_similarity); })
      .def_property_readonly(
          "control_after_adjustment",
          [](const GeoreferenceResult& r) { return RmseDict(r.control_after_adjustment); })
      .def_property_readonly(
          "check_after_adjustment",
          [](const GeoreferenceResult& r) { return RmseDict(r.check_after_adjustment); })
      .def_property_readonly(
          "error_points",
          [](const GeoreferenceResult& r) {
            std::vector<int> points;
            for (const GeoreferencePointError& e : r.point_errors) points.push_back(e.point);
            return ToArray(points);
          },
          "indices into the block's points of the surveyed points below")
      .def_property_readonly(
          "errors_after_similarity_m",
          [](const GeoreferenceResult& r) {
            return OptionalRowsArray(r.point_errors.size(), 3, [&](size_t i) {
              return r.point_errors[i].after_similarity_m;
            });
          },
          "K x 3 estimate - surveyed (m, level axes), NaN where not computed")
      .def_property_readonly(
          "errors_after_adjustment_m",
          [](const GeoreferenceResult& r) {
            return OptionalRowsArray(r.point_errors.size(), 3, [&](size_t i) {
              return r.point_errors[i].after_adjustment_m;
            });
          },
          "K x 3 estimate - surveyed (m, level axes), NaN where not computed");
}

// The adjusted block (local ENU frame) -> the output CRS: coordinates and poses.
void BindOutputCrsConversions(py::class_<GeoreferenceResult>& result) {
  result
      .def(
          "to_output_crs",
          [](const GeoreferenceResult& r, const py::object& points_local) {
            std::vector<Eigen::Vector3d> points = Points3(points_local, "points_local");
            ThrowIfError(ToOutputCrs(r, &points));
            return ToArray(points);
          },
          py::arg("points_local"), "N x 3 coordinates of the local ENU frame -> the output CRS.")
      .def(
          "output_poses",
          [](const GeoreferenceResult& r, const PythonBlock& block) {
            std::vector<FrameRecord> frames;
            for (const BlockImage& image : block.block.images) {
              FrameRecord f;
              f.raster = image.name;
              f.eo = image.eo ? *image.eo : ExteriorOrientation();
              frames.push_back(f);
            }
            ThrowIfError(GeoreferencedFrames(r, &frames));
            py::array_t<double> out({static_cast<py::ssize_t>(frames.size()), py::ssize_t(6)});
            for (size_t i = 0; i < frames.size(); ++i) {
              const bool has = block.block.images[i].eo.has_value();
              for (int k = 0; k < 6; ++k)
                out.mutable_at(i, k) = has ? frames[i].eo.parameters[k] : NaN();
            }
            return out;
          },
          py::arg("block"),
          "N x 6 [X0, Y0, Z0 in the output CRS, omega, phi, kappa (rad, seed) relative to the "
          "output "
          "CRS's level frame at each camera]; NaN rows for images without an orientation.");
}

// The result: the similarity, the control and check errors, the outputs in the output CRS.
void BindGeoreferenceResult(py::module_& m) {
  py::class_<GeoreferenceResult> result(m, "GeoreferenceResult", R"doc(
How the model was tied to the ground: the output CRS and why, the matching of names, the robust
similarity (model -> local ENU frame), the control and check errors after the similarity and after
the adjustment (per axis along the output CRS's level axes, m). The block itself is in the local
ENU frame; to_output_crs and output_poses bring coordinates and poses into the output CRS.)doc");
  result.def_readonly("out_crs", &GeoreferenceResult::out_crs)
      .def_property_readonly("out_crs_name",
                             [](const GeoreferenceResult& r) { return r.out_crs_info.name; })
      .def_readonly("out_crs_reason", &GeoreferenceResult::out_crs_reason)
      .def_readonly("heights_notes", &GeoreferenceResult::heights_notes)
      .def_readonly("inputs_not_used", &GeoreferenceResult::inputs_not_used,
                    "inputs read and not used, each with the reason")
      .def_readonly("positions_matched", &GeoreferenceResult::positions_matched)
      .def_readonly("positions_without_height", &GeoreferenceResult::positions_without_height,
                    "of the matched positions, those without height (horizontal only)")
      .def_readonly("positions_unmatched", &GeoreferenceResult::positions_unmatched)
      .def_readonly("images_without_position", &GeoreferenceResult::images_without_position)
      .def_readonly("control_marks_matched", &GeoreferenceResult::control_marks_matched)
      .def_readonly("control_marks_unmatched", &GeoreferenceResult::control_marks_unmatched)
      .def_readonly("control_points_without_marks",
                    &GeoreferenceResult::control_points_without_marks)
      .def_property_readonly("similarity_scale",
                             [](const GeoreferenceResult& r) { return r.model_to_local.scale; })
      .def_property_readonly(
          "similarity_rotation",
          [](const GeoreferenceResult& r) { return r.model_to_local.R_target_from_source; },
          "R_local_from_model (3 x 3)")
      .def_property_readonly(
          "similarity_translation",
          [](const GeoreferenceResult& r) { return r.model_to_local.translation; }, "m")
      .def_property_readonly("similarity_inliers",
                             [](const GeoreferenceResult& r) { return r.similarity.num_inliers; })
      .def_property_readonly("similarity_pairs",
                             [](const GeoreferenceResult& r) { return r.similarity_labels; })
      .def_property_readonly(
          "similarity_residuals_m",
          [](const GeoreferenceResult& r) { return ToArray(r.similarity.residual_m); })
      .def_readonly("model_points", &GeoreferenceResult::model_points,
                    "the model's own points: the block's first ones (the control follows)")
      .def_readonly("model_marks", &GeoreferenceResult::model_marks,
                    "the model's own marks: the block's first ones (the control marks follow)")
      .def_readonly("evaluated", &GeoreferenceResult::evaluated)
      .def_readonly("prepare_seconds", &GeoreferenceResult::prepare_seconds)
      .def_readonly("evaluate_seconds", &GeoreferenceResult::evaluate_seconds);
  BindGeoreferenceErrors(result);
  BindOutputCrsConversions(result);
  result.def("__repr__", [](const GeoreferenceResult& r) {
    std::string s = "GeoreferenceResult(out_crs='" + r.out_crs +
                    "', positions_matched=" + std::to_string(r.positions_matched) +
                    ", control=" + std::to_string(r.control_after_similarity.count) +
                    ", check=" + std::to_string(r.check_after_similarity.count);
    if (r.check_after_adjustment.count > 0)
      s += ", check_rmse_m=" + std::to_string(r.check_after_adjustment.total_m);
    return s + ")";
  });
}

// The steps of georeferencing, and all of them with the adjustment.
void BindGeoreferenceCalls(py::module_& m) {
  m.def(
      "prepare_georeference",
      [](PythonBlock& block, const GeoreferenceInputs& in,
         std::optional<GeoreferenceOptions> options) {
        GeoreferenceResult out;
        CallWithoutGil([&] {
          return PrepareGeoreference(options.value_or(GeoreferenceOptions()), in, &block.block,
                                     &out);
        });
        return out;
      },
      py::arg("block"), py::arg("inputs"), py::arg("options") = py::none(),
      "Steps 1-3 (PrepareGeoreference): the model moved in place into the local ENU frame by the "
      "robust similarity, with the positions as measured centres and the control joined.");
  m.def(
      "evaluate_georeference",
      [](const PythonBlock& block, const BundleAdjustmentResult& adjustment,
         GeoreferenceResult& result) {
        ThrowIfError(EvaluateGeoreference(block.block, adjustment, &result));
      },
      py::arg("block"), py::arg("adjustment"), py::arg("result"),
      "Step 5: the control and check errors after the adjustment, into result (in place).");
  m.def(
      "georeference_block",
      [](PythonBlock& block, const GeoreferenceInputs& in,
         std::optional<GeoreferenceOptions> options,
         std::optional<BundleAdjustmentOptions> bundle_options,
         std::optional<BundleAdjustmentConfig> config, const py::object& progress) {
        BundleAdjustmentOptions o = bundle_options.value_or(BundleAdjustmentOptions());
        ProgressRelay relay(progress);
        o.solver.progress = relay.Function();
        GeoreferenceResult out;
        BundleAdjustmentResult adjustment;
        CallWithoutGil(
            [&] {
              return GeoreferenceBlock(options.value_or(GeoreferenceOptions()), in, o,
                                       config.value_or(BundleAdjustmentConfig()), &block.block,
                                       &out, &adjustment);
            },
            &relay);
        return py::make_tuple(std::move(out), std::move(adjustment));
      },
      py::arg("block"), py::arg("inputs"), py::arg("options") = py::none(),
      py::arg("bundle_options") = py::none(), py::arg("config") = py::none(), py::kw_only(),
      py::arg("progress") = py::none(), R"doc(
Georeferences and adjusts a model in place (GeoreferenceBlock): (GeoreferenceResult,
BundleAdjustmentResult). The block ends in the local ENU frame; result.to_output_crs and
result.output_poses give the output CRS. Raises photopose.Error on unknown CRSs, fewer than three
usable pairs, pairs on a line, or a block the adjustment cannot use.)doc");
  m.def(
      "write_adjusted_colmap_model",
      [](const PythonBlock& block, const py::object& directory,
         const BundleAdjustmentResult& adjustment, const GeoreferenceResult* georeference,
         ColmapFormat format) {
        const std::string path = PathArgument(directory, "directory");
        CallWithoutGil([&] {
          return WriteAdjustedColmapModel(path, block.block, adjustment, georeference,
                                          block.colmap ? &*block.colmap : nullptr, format);
        });
      },
      py::arg("block"), py::arg("directory"), py::arg("adjustment"),
      py::arg("georeference") = py::none(), py::kw_only(), py::arg("format") = ColmapFormat::kText,
      R"doc(
Writes an adjusted block as the COLMAP model it was read from (WriteAdjustedColmapModel, the writer
of `photopose bundle --out_colmap`): the marks the adjustment left out (rejected, snooped) leave
the tracks; with a georeference (georeference_block's or prepare_georeference's result) the control
points and marks it added are left out and georeference.json beside the model names its local
East-North-Up frame. format is 'text' or 'binary'; ids, keypoints and colours of a model read with
read_colmap_model are kept.)doc");
}

}  // namespace

// In this order: a function's signature names the classes bound before it.
void BindGeoreference(py::module_& m) {
  BindPositionFiles(m);
  BindCameraPositionMeasurement(m);
  BindGeoreferenceInputsClass(m);
  BindGeoreferenceOptions(m);
  BindGeoreferenceResult(m);
  BindGeoreferenceCalls(m);
}

}  // namespace photopose::python
