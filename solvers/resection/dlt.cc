#include "solvers/resection/dlt.h"

#include "solvers/resection/point_configuration.h"

#include <Eigen/Dense>
#include <cmath>
#include <string>

namespace photopose {
namespace {

// The second-smallest singular value of the normalised design matrix relative to the largest:
// below it the null space is not one-dimensional and the solution is not unique.
constexpr double kMinSingularValueRatio = 1e-6;  // eigenvalues of A^T A resolve ~1e-8 of sigma_max

// The unit bearings and the centroid of the ground points; an error names a zero or non-finite
// bearing or a non-finite point.
Status UnitBearingsAndCentroid(const std::vector<Eigen::Vector3d>& bearings,
                               const std::vector<Eigen::Vector3d>& points_in_ground,
                               std::vector<Eigen::Vector3d>* unit_bearings, Eigen::Vector3d* centroid) {
  const int n = static_cast<int>(points_in_ground.size());
  unit_bearings->resize(n);
  *centroid = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const double norm = bearings[i].norm();
    if (!(norm > 0.0) || !std::isfinite(norm))
      return Status::Error("DLT: bearing " + std::to_string(i) + " is zero or not finite");
    if (!points_in_ground[i].allFinite())
      return Status::Error("DLT: point " + std::to_string(i) + " is not finite");
    (*unit_bearings)[i] = bearings[i] / norm;
    *centroid += points_in_ground[i];
  }
  *centroid /= n;
  return Status::Ok();
}

// Geometry of the ground points (solvers/resection/point_configuration.h): collinear or coplanar
// points leave the 12 entries of P undetermined (a plane leaves a three-dimensional null space),
// and near it the solution is set by rounding.
Status CheckSpread(const std::vector<Eigen::Vector3d>& points_in_ground) {
  const PointSpread spread = ComputePointSpread(points_in_ground);
  if (!(spread.extents_m[2] > 0.0)) return Status::Error("DLT: all points coincide");
  if (spread.collinear()) return Status::Error("DLT: the points are collinear");
  if (spread.coplanar())
    return Status::Error("DLT: the points are coplanar; the DLT needs a three-dimensional spread");
  return Status::Ok();
}

// (*AtA)(j, i) += row[i] * row[j] for j >= i: the lower triangle of row row^T added, term for term
// what Eigen's AtA.selfadjointView<Lower>().rankUpdate(row) adds (column i's tail plus
// (1 * row[i]) * row's tail, a multiplication then an addition per entry), without its
// dynamic-size blocks (a sixth of the DLT's time).
inline void AddToLowerTriangle(const Eigen::Matrix<double, 12, 1>& row,
                               Eigen::Matrix<double, 12, 12>* AtA) {
  for (int i = 0; i < 12; ++i) {
    const double row_i = row[i];
    for (int j = i; j < 12; ++j) (*AtA)(j, i) += row_i * row[j];
  }
}

// The projection P = [M | m] from the null vector of the design matrix, M acting on X - centroid
// (~ R up to scale) and m ~ t + R centroid, with the sign that puts most points in front.
Status LinearProjection(const std::vector<Eigen::Vector3d>& unit_bearings,
                        const std::vector<Eigen::Vector3d>& points_in_ground, const Eigen::Vector3d& centroid,
                        Eigen::Matrix3d* M, Eigen::Vector3d* m) {
  const int n = static_cast<int>(points_in_ground.size());
  double mean_distance = 0.0;
  for (const Eigen::Vector3d& X : points_in_ground) mean_distance += (X - centroid).norm();
  mean_distance /= n;

  // Hartley normalisation of the ground side: centroid at the origin, mean distance sqrt(3). The
  // bearing side needs none: unit vectors with an orthonormal tangent basis are already isotropic.
  const double scale = std::sqrt(3.0) / mean_distance;
  // The 12 x 12 normal matrix A^T A of the 2n x 12 design matrix, accumulated row by row: its
  // eigenvectors are A's right singular vectors and its eigenvalues the squared singular values.
  // After the normalisation A is well conditioned, so squaring costs no useful digits, and the
  // fixed-size eigensolver is far cheaper than an SVD of A (the DLT runs inside LO-RANSAC).
  Eigen::Matrix<double, 12, 12> AtA = Eigen::Matrix<double, 12, 12>::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& b = unit_bearings[i];
    Eigen::Vector4d X;
    X << scale * (points_in_ground[i] - centroid), 1.0;
    const Eigen::Vector3d e1 = b.unitOrthogonal();
    const Eigen::Vector3d e2 = b.cross(e1);
    Eigen::Matrix<double, 12, 1> row1, row2;
    for (int r = 0; r < 3; ++r) {
      row1.segment<4>(4 * r) = e1[r] * X;
      row2.segment<4>(4 * r) = e2[r] * X;
    }
    AddToLowerTriangle(row1, &AtA);
    AddToLowerTriangle(row2, &AtA);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eigen(
      AtA.selfadjointView<Eigen::Lower>());
  // Singular values of A, descending as an SVD would give them.
  const Eigen::Matrix<double, 12, 1> sv = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().reverse();
  if (!(sv[10] > kMinSingularValueRatio * sv[0]))
    return Status::Error("DLT: the linear system is rank deficient");
  // P_normalised, row-major in the null vector; P acting on centred, scaled points.
  Eigen::Matrix<double, 3, 4> P;
  for (int r = 0; r < 3; ++r) P.row(r) = eigen.eigenvectors().col(0).segment<4>(4 * r).transpose();
  *M = scale * P.leftCols<3>();
  *m = P.col(3);

  // The null vector's sign is arbitrary: take the one that puts most points in front.
  int front = 0;
  for (int i = 0; i < n; ++i)
    front += unit_bearings[i].dot(*M * (points_in_ground[i] - centroid) + *m) > 0.0 ? 1 : -1;
  if (front < 0) {
    *M = -*M;
    *m = -*m;
  }
  return Status::Ok();
}

// Translation for the rotation R: minimise sum_i |(I - b_i b_i^T)(R (X_i - centroid) + t')|^2, the
// components of the camera-frame point off its ray.
Eigen::Vector3d TranslationForRotation(const std::vector<Eigen::Vector3d>& unit_bearings,
                                       const std::vector<Eigen::Vector3d>& points_in_ground,
                                       const Eigen::Vector3d& centroid, const Eigen::Matrix3d& R) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < points_in_ground.size(); ++i) {
    const Eigen::Vector3d& b = unit_bearings[i];
    const Eigen::Matrix3d off_ray = Eigen::Matrix3d::Identity() - b * b.transpose();
    normal += off_ray;
    rhs -= off_ray * (R * (points_in_ground[i] - centroid));
  }
  return normal.ldlt().solve(rhs);
}

}  // namespace

Status SolveDlt(const std::vector<Eigen::Vector3d>& bearings,
                const std::vector<Eigen::Vector3d>& points_in_ground, PoseCandidate* pose) {
  const int n = static_cast<int>(points_in_ground.size());
  if (bearings.size() != points_in_ground.size())
    return Status::Error("DLT: " + std::to_string(bearings.size()) + " bearings for " +
                         std::to_string(n) + " points");
  if (n < kDltMinimumPoints)
    return Status::Error("DLT: needs at least " + std::to_string(kDltMinimumPoints) +
                         " points, got " + std::to_string(n));
  std::vector<Eigen::Vector3d> unit_bearings;
  Eigen::Vector3d centroid;
  PHOTOPOSE_RETURN_IF_ERROR(UnitBearingsAndCentroid(bearings, points_in_ground, &unit_bearings, &centroid));
  PHOTOPOSE_RETURN_IF_ERROR(CheckSpread(points_in_ground));
  Eigen::Matrix3d M;  // ~ R, acting on X - centroid
  Eigen::Vector3d m;  // ~ t + R centroid
  PHOTOPOSE_RETURN_IF_ERROR(LinearProjection(unit_bearings, points_in_ground, centroid, &M, &m));
  if (!(M.determinant() > 0.0))
    return Status::Error("DLT: the linear solution is a reflection, not a camera");
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd_m(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d R = svd_m.matrixU() * svd_m.matrixV().transpose();
  // Then centre = centroid - R^T t'.
  const Eigen::Vector3d t = TranslationForRotation(unit_bearings, points_in_ground, centroid, R);
  if (!t.allFinite()) return Status::Error("DLT: the translation is undetermined");

  int in_front = 0;
  for (int i = 0; i < n; ++i)
    if (unit_bearings[i].dot(R * (points_in_ground[i] - centroid) + t) > 0.0) ++in_front;
  if (2 * in_front <= n)
    return Status::Error("DLT: most points are behind the camera (" + std::to_string(in_front) +
                         " of " + std::to_string(n) + " in front)");

  pose->R_camera_from_ground = R;
  pose->center_in_ground = centroid - R.transpose() * t;
  return Status::Ok();
}

}  // namespace photopose
