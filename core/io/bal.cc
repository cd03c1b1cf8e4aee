#include "core/io/bal.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/collinearity.h"
#include "core/io/csv.h"
#include "core/rotation.h"
#include "core/io/tables.h"
#include "core/io/text_scanner.h"

namespace photopose {
namespace {

constexpr long long kMaxCount = std::numeric_limits<int>::max();
// A Bundler R is printed with ten digits: rows orthonormal to about 1e-10. Anything worse than
// this is no rotation at all.
constexpr double kRotationTolerance = 1e-6;

// The nearest rotation (SVD), refusing a matrix that is not close to one.
Status NearestRotation(const Eigen::Matrix3d& M, Eigen::Matrix3d* R) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckRotationMatrix(M, kRotationTolerance));
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  *R = svd.matrixU() * svd.matrixV().transpose();
  return Status::Ok();
}

// Adds image and RADIAL camera `name` with world -> camera R, t (R a rotation).
void AddCamera(const std::string& name, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
               double f, double k1, double k2, Block* block) {
  BlockCamera camera;
  camera.camera_id = name;
  camera.model = CameraModelType::kRadial;
  camera.params = {f, 0.0, 0.0, k1, k2};
  camera.table.camera_id = name;
  BlockImage image;
  image.name = name;
  image.camera = static_cast<int>(block->cameras.size());
  ExteriorOrientation eo;
  eo.set_center_in_ground(-R.transpose() * t);
  eo.set_angles_seed_rad(AnglesFromRotation(RotationConvention::kSeed, R));
  image.eo = eo;
  block->cameras.push_back(std::move(camera));
  block->images.push_back(std::move(image));
}

void AddMark(int image, int point, double x, double y, int line, Block* block) {
  block->marks.push_back(MakePixelMark(image, point, Eigen::Vector2d(x, -y), line));
}

BlockPoint TiePoint(long long index, const Eigen::Vector3d& position, int line) {
  BlockPoint point;
  point.id = std::to_string(index);
  point.role = PointRole::kTie;
  point.position_m = position;
  point.line = line;
  return point;
}

// Three numbers of magnitude at most `max_magnitude`.
Status Vector3(TokenScanner* scanner, const char* field, double max_magnitude, const char* unit,
               Eigen::Vector3d* v) {
  for (int k = 0; k < 3; ++k)
    PHOTOPOSE_RETURN_IF_ERROR(scanner->NumberWithin(field, max_magnitude, unit, &(*v)[k]));
  return Status::Ok();
}

// A BAL focal length: at least kMinFocalLengthPx and at most kMaxCoordinate in magnitude.
Status FocalLength(TokenScanner* scanner, double* f) {
  PHOTOPOSE_RETURN_IF_ERROR(scanner->NumberWithin("f", kMaxCoordinate, "px", f));
  if (!(std::abs(*f) >= kMinFocalLengthPx)) {
    return scanner->Error("f", FormatNumber(*f) + " is no focal length: its magnitude must be at least " +
                                   FormatNumber(kMinFocalLengthPx) + " px");
  }
  return Status::Ok();
}

}  // namespace

Status ReadBalProblem(const std::string& path, Block* block) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &text));
  return ParseBalProblem(text, InputName(path), block);
}

Status ParseBalProblem(std::string_view text, const std::string& path, Block* block) {
  TokenScanner scanner(text, path, 1);
  long long num_cameras = 0, num_points = 0, num_observations = 0;
  PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("num_cameras", 1, kMaxCount, &num_cameras));
  PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("num_points", 1, kMaxCount, &num_points));
  PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("num_observations", 1, kMaxCount, &num_observations));
  // Each number needs at least two characters: a header promising more is not this file's.
  if (2 * (4 * num_observations + 9 * num_cameras + 3 * num_points) >
      static_cast<long long>(text.size()) + 2) {
    return scanner.Error("num_observations",
                         "the header promises more numbers than the file can hold");
  }
  Block result;
  result.marks.reserve(static_cast<size_t>(num_observations));
  for (long long k = 0; k < num_observations; ++k) {
    const int line = scanner.line();
    long long camera = 0, point = 0;
    double x = 0.0, y = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("camera", 0, num_cameras - 1, &camera));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("point", 0, num_points - 1, &point));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.NumberWithin("x", kMaxCoordinate, "px", &x));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.NumberWithin("y", kMaxCoordinate, "px", &y));
    AddMark(static_cast<int>(camera), static_cast<int>(point), x, y, line, &result);
  }
  for (long long c = 0; c < num_cameras; ++c) {
    Eigen::Vector3d r, t;
    double f = 0.0, k1 = 0.0, k2 = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(Vector3(&scanner, "r", kMaxRotationVectorRad, "rad", &r));
    PHOTOPOSE_RETURN_IF_ERROR(Vector3(&scanner, "t", kMaxCoordinate, "", &t));
    PHOTOPOSE_RETURN_IF_ERROR(FocalLength(&scanner, &f));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("k1", &k1));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("k2", &k2));
    AddCamera(std::to_string(c), RotationFromRotationVector(r), t, f, k1, k2, &result);
  }
  result.points.reserve(static_cast<size_t>(num_points));
  for (long long j = 0; j < num_points; ++j) {
    const int line = scanner.line();
    Eigen::Vector3d X;
    PHOTOPOSE_RETURN_IF_ERROR(Vector3(&scanner, "point coordinate", kMaxCoordinate, "", &X));
    result.points.push_back(TiePoint(j, X, line));
  }
  if (!scanner.AtEnd()) return scanner.Error("", "unexpected text after the last point");
  result.marks_source = path;
  result.BuildIndex();
  *block = std::move(result);
  return Status::Ok();
}

Status ReadBundlerFile(const std::string& path, Block* block, int* num_unregistered) {
  std::string contents;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &contents));
  const std::string_view text = contents;
  // The header line, then a token stream.
  const size_t first_end = text.find('\n');
  const std::string_view header =
      text.substr(0, first_end == std::string_view::npos ? text.size() : first_end);
  if (header.rfind("# Bundle file v0.3", 0) != 0)
    return TextError(path, 1, "", "not a Bundler v0.3 file (the first line is not '# Bundle file v0.3')");
  TokenScanner scanner(text.substr(header.size()), path, 1);
  long long num_cameras = 0, num_points = 0;
  PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("num_cameras", 1, kMaxCount, &num_cameras));
  PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("num_points", 0, kMaxCount, &num_points));
  if (2 * (15 * num_cameras + 7 * num_points) > static_cast<long long>(text.size()) + 2)
    return scanner.Error("num_points", "the header promises more numbers than the file can hold");
  Block result;
  std::vector<int> image_of_camera(static_cast<size_t>(num_cameras), -1);
  int unregistered = 0;
  for (long long c = 0; c < num_cameras; ++c) {
    const int line = scanner.line();
    double f = 0.0, k1 = 0.0, k2 = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("f", &f));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("k1", &k1));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("k2", &k2));
    Eigen::Matrix3d M;
    for (int row = 0; row < 3; ++row) {
      Eigen::Vector3d r;
      PHOTOPOSE_RETURN_IF_ERROR(Vector3(&scanner, "R", kMaxCoordinate, "", &r));
      M.row(row) = r.transpose();
    }
    Eigen::Vector3d t;
    PHOTOPOSE_RETURN_IF_ERROR(Vector3(&scanner, "t", kMaxCoordinate, "", &t));
    if (f == 0.0) {
      ++unregistered;
      continue;
    }
    Eigen::Matrix3d R;
    const Status rotation = NearestRotation(M, &R);
    if (!rotation.ok()) return TextError(path, line, "R", rotation.message());
    image_of_camera[c] = static_cast<int>(result.images.size());
    AddCamera(std::to_string(c), R, t, f, k1, k2, &result);
  }
  result.points.reserve(static_cast<size_t>(num_points));
  for (long long j = 0; j < num_points; ++j) {
    const int line = scanner.line();
    Eigen::Vector3d X;
    PHOTOPOSE_RETURN_IF_ERROR(Vector3(&scanner, "position", kMaxCoordinate, "", &X));
    for (int k = 0; k < 3; ++k) {
      long long colour = 0;
      PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("colour", 0, 255, &colour));
    }
    long long views = 0;
    PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("view list length", 0, num_cameras, &views));
    for (long long v = 0; v < views; ++v) {
      const int view_line = scanner.line();
      long long camera = 0, key = 0;
      double x = 0.0, y = 0.0;
      PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("camera", 0, num_cameras - 1, &camera));
      PHOTOPOSE_RETURN_IF_ERROR(scanner.Integer("key", &key));
      PHOTOPOSE_RETURN_IF_ERROR(scanner.NumberWithin("x", kMaxCoordinate, "px", &x));
      PHOTOPOSE_RETURN_IF_ERROR(scanner.NumberWithin("y", kMaxCoordinate, "px", &y));
      if (image_of_camera[camera] < 0) {
        return TextError(path, view_line, "camera",
                         "camera " + std::to_string(camera) + " has f = 0 (not reconstructed)");
      }
      AddMark(image_of_camera[camera], static_cast<int>(j), x, y, view_line, &result);
    }
    result.points.push_back(TiePoint(j, X, line));
  }
  if (!scanner.AtEnd()) return scanner.Error("", "unexpected text after the last point");
  result.marks_source = path;
  result.BuildIndex();
  *block = std::move(result);
  if (num_unregistered != nullptr) *num_unregistered = unregistered;
  return Status::Ok();
}

Status ReprojectionCost(const Block& block, double* cost, int* num_behind) {
  std::vector<CameraModelData> data(block.cameras.size());
  for (size_t c = 0; c < block.cameras.size(); ++c) data[c] = block.cameras[c].data();
  double sum = 0.0;
  int behind = 0;
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    const BlockImage& image = block.images[mark.image];
    const BlockPoint& point = block.points[mark.point];
    if (!image.eo || !point.position_m) {
      return Status::Error("mark " + std::to_string(m + 1) +
                           ": its image has no orientation or its point no position");
    }
    double uvw[3];
    CameraFromGround(image.eo->data(), point.position_m->data(), uvw);
    if (!(uvw[2] < 0.0)) ++behind;
    const double ab[2] = {-uvw[0] / uvw[2], -uvw[1] / uvw[2]};
    const BlockCamera& camera = block.cameras[image.camera];
    double r[2];
    CameraModelResidual(camera.model, camera.params.data(), ab, mark.observation.data(),
                        data[image.camera], r);
    sum += r[0] * r[0] + r[1] * r[1];
  }
  *cost = 0.5 * sum;
  if (num_behind != nullptr) *num_behind = behind;
  return Status::Ok();
}

}  // namespace photopose
