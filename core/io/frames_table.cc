// The frames table (exterior orientations): read and written (core/io/tables.h).
#include "core/io/tables.h"


#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <string_view>

#include "core/io/csv.h"
#include "core/io/text_scanner.h"
#include "core/io/internal/table_fields.h"

namespace photopose {
using namespace table_io;  // NOLINT: the shared table machinery of this folder
namespace {

// ------------------------------------------------------------------ frames table

// d(file parameters) / d(eo.parameters): identity for X0, Y0, Z0, and the angle Jacobian of the
// one boundary conversion (core/rotation.h).
Matrix6d FileFromSeedJacobian(RotationConvention convention, const AngleFlags& flags,
                              const Eigen::Vector3d& seed_angles_rad) {
  Matrix6d J = Matrix6d::Identity();
  J.bottomRightCorner<3, 3>() = ConventionFromSeedJacobian(convention, flags, seed_angles_rad);
  return J;
}

// The camera of a frame when cameras are given (nullptr otherwise); a CameraID that is not among
// them is an error "unknown camera '<id>'" for the caller to place.
Status FindCamera(const FramesTableOptions& options, const std::string& camera_id,
                  const FrameCamera** camera) {
  *camera = nullptr;
  if (options.cameras == nullptr) return Status::Ok();
  for (const FrameCamera& c : *options.cameras) {
    if (c.camera_id == camera_id) {
      *camera = &c;
      return Status::Ok();
    }
  }
  return Status::Error("unknown camera " + QuotedForMessage(camera_id));
}

AngleFlags FlagsOf(const FrameCamera* camera) {
  AngleFlags flags;
  if (camera != nullptr) flags.angle_direction = camera->angle_direction;
  return flags;
}

Status ReadFrameRotation(const CsvRowReader& row, const FramesTableOptions& options,
                         const FrameCamera* camera, Eigen::Vector3d* seed_angles_rad) {
  bool use_matrix;
  if (camera != nullptr) {
    use_matrix = camera->orientation_type == OrientationType::kMatrix;
  } else {
    use_matrix = !row.Has("Omega") && !row.Has("Phi") && !row.Has("Kappa") && row.Has("Matrix");
  }
  if (use_matrix) {
    std::vector<double> values;
    PHOTOPOSE_RETURN_IF_ERROR(ReadNumberList(row, "Matrix", &values));
    if (values.empty()) return row.Error("Matrix", "is empty");
    if (values.size() != 9) {
      return row.Error("Matrix", "has " + std::to_string(values.size()) +
                                     " numbers, expected 9 (a 3x3 matrix, row by row)");
    }
    const Eigen::Matrix3d R =
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values.data());
    const Status rotation = CheckRotationMatrix(R, kMatrixOrthonormalityTolerance);
    if (!rotation.ok()) return row.Error("Matrix", rotation.message());
    *seed_angles_rad = AnglesFromRotation(RotationConvention::kSeed, R);
    return Status::Ok();
  }
  Eigen::Vector3d angles_deg;
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "Omega", &angles_deg[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "Phi", &angles_deg[1]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "Kappa", &angles_deg[2]));
  *seed_angles_rad =
      SeedAnglesFromConvention(options.convention, FlagsOf(camera), angles_deg / kDegreesPerRadian);
  return Status::Ok();
}

// SigmaX..SigmaKappa (m, degrees of the file's angles) as a covariance of eo.parameters without
// correlations in the file's parameters: Sigma = J^-1 diag(sigma^2) J^-T.
Status ReadFrameSigmas(const CsvRowReader& row, const FramesTableOptions& options,
                       const FrameCamera* camera, FrameRecord* frame) {
  const Names& names = SigmaColumns();
  const auto given = std::count_if(names.begin(), names.end(),
                                   [&](std::string_view name) { return row.Has(name); });
  if (given == 0) return Status::Ok();
  Vector6d variances;
  for (int i = 0; i < 6; ++i) {
    if (!row.Has(names[i])) {
      return row.Error(names[i],
                       "is empty; SigmaX, SigmaY, SigmaZ, SigmaOmega, SigmaPhi, SigmaKappa are "
                       "given together");
    }
    double sigma = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, names[i], &sigma));
    if (sigma < 0.0)
      return row.Error(names[i], QuotedForMessage(row.Text(names[i])) + " is negative");
    if (i >= 3) sigma /= kDegreesPerRadian;
    variances[i] = sigma * sigma;
  }
  const Matrix6d J =
      FileFromSeedJacobian(options.convention, FlagsOf(camera), frame->eo.angles_seed_rad());
  const Eigen::FullPivLU<Matrix6d> lu(J);
  if (!lu.isInvertible()) {
    return row.Error("SigmaOmega",
                     "cannot be converted: the angles are at a gimbal lock of the convention");
  }
  const Matrix6d J_inverse = lu.inverse();
  frame->covariance = J_inverse * variances.asDiagonal() * J_inverse.transpose();
  return Status::Ok();
}

// `extra`: the header's columns that are not the frames table's.
Status ReadFrameRow(const CsvRowReader& row, const std::vector<size_t>& extra,
                    const FramesTableOptions& options, FrameRecord* frame) {
  FrameRecord f;
  f.line = row.line();
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("Raster", &f.raster));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("CameraID", &f.camera_id));
  const FrameCamera* camera = nullptr;
  const Status found = FindCamera(options, f.camera_id, &camera);
  if (!found.ok()) return row.Error("CameraID", found.message());
  Eigen::Vector3d center;
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "PerspectiveX", &center[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "PerspectiveY", &center[1]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "PerspectiveZ", &center[2]));
  f.eo.set_center_in_ground(center);
  Eigen::Vector3d seed_angles =
      Eigen::Vector3d::Zero();  // set below; zero quiets -Wmaybe-uninitialized
  PHOTOPOSE_RETURN_IF_ERROR(ReadFrameRotation(row, options, camera, &seed_angles));
  f.eo.set_angles_seed_rad(seed_angles);
  f.srs = std::string(row.Text("SRS"));
  PHOTOPOSE_RETURN_IF_ERROR(ReadFrameSigmas(row, options, camera, &f));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, "Sigma0", &f.sigma0));
  if (f.sigma0 && *f.sigma0 < 0.0)
    return row.Error("Sigma0", QuotedForMessage(row.Text("Sigma0")) + " is negative");
  PHOTOPOSE_RETURN_IF_ERROR(ReadAccuracyTriple(row, kAccuracyColumns, &f.center_accuracy_m));
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadAccuracyTriple(row, kAttitudeAccuracyColumns, &f.attitude_accuracy_deg));
  f.extra_columns = ReadExtraColumns(row, extra);
  *frame = std::move(f);
  return Status::Ok();
}


// The optional column groups of a frames table: each written when any frame needs it.
struct FramesColumnGroups {
  bool matrix = false;  // a frame's camera has OrientationType Matrix
  bool covariance = false;
  bool sigma0 = false;
  bool center_accuracy = false;
  bool attitude_accuracy = false;
};

// The camera of every frame (*cameras; nullptr: none in the options) and the optional column
// groups the frames need.
Status FrameCamerasAndGroups(const FramesTableOptions& options, const std::vector<FrameRecord>& frames,
                             const std::string& path, std::vector<const FrameCamera*>* cameras,
                             FramesColumnGroups* any) {
  cameras->assign(frames.size(), nullptr);
  for (size_t i = 0; i < frames.size(); ++i) {
    const Status found = FindCamera(options, frames[i].camera_id, &(*cameras)[i]);
    if (!found.ok())
      return Status::Error(path + ": raster " + QuotedForMessage(frames[i].raster) +
                           ": CameraID: " + found.message());
    any->matrix = any->matrix || ((*cameras)[i] != nullptr &&
                                  (*cameras)[i]->orientation_type == OrientationType::kMatrix);
    any->covariance = any->covariance || frames[i].covariance.has_value();
    any->sigma0 = any->sigma0 || frames[i].sigma0.has_value();
    any->center_accuracy = any->center_accuracy || frames[i].center_accuracy_m.has_value();
    any->attitude_accuracy = any->attitude_accuracy || frames[i].attitude_accuracy_deg.has_value();
  }
  return Status::Ok();
}

std::vector<std::string> FramesHeader(const FramesColumnGroups& any, const std::vector<std::string>& extra_names) {
  std::vector<std::string> header = {"Raster",       "CameraID", "PerspectiveX", "PerspectiveY",
                                     "PerspectiveZ", "Omega",    "Phi",          "Kappa"};
  if (any.matrix) header.push_back("Matrix");
  header.push_back("SRS");
  if (any.covariance) header.insert(header.end(), SigmaColumns().begin(), SigmaColumns().end());
  if (any.sigma0) header.push_back("Sigma0");
  if (any.center_accuracy)
    header.insert(header.end(), std::begin(kAccuracyColumns), std::end(kAccuracyColumns));
  if (any.attitude_accuracy)
    header.insert(header.end(), std::begin(kAttitudeAccuracyColumns),
                  std::end(kAttitudeAccuracyColumns));
  header.insert(header.end(), extra_names.begin(), extra_names.end());
  return header;
}

// The six standard deviations of a frame (m, then degrees in the table's convention) from its
// covariance in the seed's (m, rad); empty fields without one.
void AppendSigmas(const FramesTableOptions& options, const FrameRecord& f, const AngleFlags& flags,
                  RowFields* row) {
  if (!f.covariance) {
    for (int k = 0; k < 6; ++k) row->Text("");
    return;
  }
  if (!f.covariance->allFinite() || (f.covariance->diagonal().array() < 0.0).any())
    row->Fail("SigmaX", "covariance is not finite or has a negative variance");
  const Matrix6d J = FileFromSeedJacobian(options.convention, flags, f.eo.angles_seed_rad());
  const Vector6d variances = (J * *f.covariance * J.transpose()).diagonal();
  for (int k = 0; k < 6; ++k) {
    // Rounding can make a zero variance slightly negative.
    const double sigma = std::sqrt(std::max(variances[k], 0.0));
    row->Number(SigmaColumns()[k], k < 3 ? sigma : sigma * kDegreesPerRadian);
  }
}

// One frame's row in the columns of FramesHeader.
Status FrameRow(const FramesTableOptions& options, const FramesColumnGroups& any,
                const std::vector<std::string>& extra_names, const std::string& path, const FrameRecord& f,
                const FrameCamera* camera, std::vector<std::string>* fields) {
  const AngleFlags flags = FlagsOf(camera);
  const Eigen::Vector3d seed_angles = f.eo.angles_seed_rad();
  RowFields row("raster " + QuotedForMessage(f.raster));
  row.Text(f.raster);
  row.Text(f.camera_id);
  row.Number("PerspectiveX", f.eo.parameters[0]);
  row.Number("PerspectiveY", f.eo.parameters[1]);
  row.Number("PerspectiveZ", f.eo.parameters[2]);
  const Eigen::Vector3d angles_deg =
      ConventionAnglesFromSeed(options.convention, flags, seed_angles) * kDegreesPerRadian;
  row.Number("Omega", angles_deg[0]);
  row.Number("Phi", angles_deg[1]);
  row.Number("Kappa", angles_deg[2]);
  if (any.matrix) {
    std::vector<double> matrix;
    if (camera != nullptr && camera->orientation_type == OrientationType::kMatrix) {
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R =
          RotationFromAngles(RotationConvention::kSeed, seed_angles);
      matrix.assign(R.data(), R.data() + 9);
    }
    row.NumberList("Matrix", matrix);
  }
  row.Text(f.srs);
  if (any.covariance) AppendSigmas(options, f, flags, &row);
  if (any.sigma0) row.OptionalNumber("Sigma0", f.sigma0);
  const auto accuracies = [&row](const std::string_view(&columns)[3],
                                 const std::optional<Eigen::Vector3d>& values) {
    for (int k = 0; k < 3; ++k) {
      if (values && !((*values)[k] > 0.0)) row.Fail(columns[k], "must be positive");
      row.OptionalNumber(columns[k], values ? std::optional<double>((*values)[k]) : std::nullopt);
    }
  };
  if (any.center_accuracy) accuracies(kAccuracyColumns, f.center_accuracy_m);
  if (any.attitude_accuracy) accuracies(kAttitudeAccuracyColumns, f.attitude_accuracy_deg);
  AppendExtraColumns(f, extra_names, row.fields());
  PHOTOPOSE_RETURN_IF_ERROR(row.status(path));
  *fields = std::move(*row.fields());
  return Status::Ok();
}

}  // namespace

// ------------------------------------------------------------------ frames table

Status ParseFramesTable(std::string_view text, const std::string& file_name,
                        const FramesTableOptions& options, std::vector<FrameRecord>* frames) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, kTableCsvOptions));
  const CsvHeader& table = reader.header();
  PHOTOPOSE_RETURN_IF_ERROR(
      table.RequireColumns({"Raster", "CameraID", "PerspectiveX", "PerspectiveY", "PerspectiveZ"}));
  const bool any_angle_column =
      table.HasColumn("Omega") || table.HasColumn("Phi") || table.HasColumn("Kappa");
  if (any_angle_column) {
    PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"Omega", "Phi", "Kappa"}));
  } else if (!table.HasColumn("Matrix")) {
    return table.Error(table.header_line(), "Omega",
                       "required column is missing (give Omega, Phi, Kappa or Matrix)");
  }
  const Names& sigmas = SigmaColumns();
  if (std::any_of(sigmas.begin(), sigmas.end(),
                  [&](std::string_view name) { return table.HasColumn(name); }))
    PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns(sigmas));

  const std::vector<size_t> extra = table.ColumnsOtherThan(FrameColumns());
  std::vector<FrameRecord> result;
  FirstLines first_lines(text);
  PHOTOPOSE_RETURN_IF_ERROR(reader.ForEachRow([&](const CsvRowReader& row) {
    FrameRecord frame;
    PHOTOPOSE_RETURN_IF_ERROR(ReadFrameRow(row, extra, options, &frame));
    PHOTOPOSE_RETURN_IF_ERROR(
        CheckUnique(row, "Raster", row.Text("Raster"), "raster", &first_lines));
    result.push_back(std::move(frame));
    return Status::Ok();
  }));
  *frames = std::move(result);
  return Status::Ok();
}

Status FormatFramesTable(const FramesTableOptions& options, const std::vector<FrameRecord>& frames,
                         const std::string& path, std::string* text) {
  // The camera of every frame first: it decides the AngleDirection and whether Matrix is written.
  std::vector<const FrameCamera*> cameras;
  FramesColumnGroups any;
  PHOTOPOSE_RETURN_IF_ERROR(FrameCamerasAndGroups(options, frames, path, &cameras, &any));
  std::vector<std::string> extra_names;
  PHOTOPOSE_RETURN_IF_ERROR(CollectExtraColumnNames(path, frames, FrameColumns(), &extra_names));
  std::string contents = CsvLine(FramesHeader(any, extra_names));
  std::vector<std::string> fields;
  for (size_t i = 0; i < frames.size(); ++i) {
    PHOTOPOSE_RETURN_IF_ERROR(FrameRow(options, any, extra_names, path, frames[i], cameras[i], &fields));
    contents += CsvLine(fields);
  }
  *text = std::move(contents);
  return Status::Ok();
}


}  // namespace photopose
