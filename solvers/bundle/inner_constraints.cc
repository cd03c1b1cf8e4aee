// The S-transformation of a relative block's covariances into an inner-constraint datum
// (solvers/bundle/internal/inner_constraints.h).

#include "solvers/bundle/internal/inner_constraints.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

#include "core/rotation.h"

namespace photopose::internal {
Eigen::Matrix<double, 6, 7> OrientationSimilarityRows(const Vector6d& eo,
                                                      const Eigen::Vector3d& centroid,
                                                      double extent) {
  Eigen::Matrix<double, 6, 7> G = Eigen::Matrix<double, 6, 7>::Zero();
  G.topRows<3>() = SimilarityRows(eo.head<3>(), centroid, extent);
  const Eigen::Matrix3d R_camera_from_ground =
      RotationFromAngles(RotationConvention::kSeed, eo.tail<3>());
  G.block<3, 3>(3, 3) = -R_camera_from_ground / extent;
  return G;
}

namespace {

// The datum's positions: the round's points, or the centres of the images in the round (the held
// first image too).
std::vector<Eigen::Vector3d> DatumPositions(bool on_points, const Block& block,
                                            const BundlePlan& plan, const BundleState& state,
                                            const BundleRound& round,
                                            const ReducedNormals& reduced) {
  std::vector<Eigen::Vector3d> positions;
  if (on_points) {
    for (const double* X : round.point_blocks) positions.emplace_back(X[0], X[1], X[2]);
    return positions;
  }
  for (size_t i = 0; i < block.images.size(); ++i) {
    const bool in_round = reduced.e_index.count(state.eo[i].data()) ||
                          static_cast<int>(i) == plan.relative_fixed_image;
    if (in_round) positions.push_back(state.eo[i].head<3>());
  }
  return positions;
}

// The positions' centroid and RMS spread (1 when they coincide), which condition G.
void CentroidAndExtent(const std::vector<Eigen::Vector3d>& positions, Eigen::Vector3d* centroid,
                       double* extent) {
  *centroid = Eigen::Vector3d::Zero();
  for (const auto& p : positions) *centroid += p;
  *centroid /= static_cast<double>(positions.size());
  *extent = 0.0;
  for (const auto& p : positions) *extent += (p - *centroid).squaredNorm();
  *extent = std::sqrt(*extent / positions.size());
  if (!(*extent > 0.0)) *extent = 1.0;
}

// Per image of the block: its e block in the round, or -1.
std::vector<int> ImageBlocks(const Block& block, const BundleState& state,
                             const ReducedNormals& reduced) {
  std::vector<int> image_block(block.images.size(), -1);
  for (size_t i = 0; i < block.images.size(); ++i) {
    const auto found = reduced.e_index.find(state.eo[i].data());
    if (found != reduced.e_index.end()) image_block[i] = found->second;
  }
  return image_block;
}

}  // namespace

bool InnerConstraintTransform::RightHandSide(bool on_points, const BundlePlan& plan,
                                             const BundleRound& round,
                                             const ReducedNormals& reduced,
                                             const std::vector<int>& image_block, int num_threads,
                                             Eigen::MatrixXd* rhs,
                                             Eigen::Matrix<double, 7, 7>* GtWG) const {
  *rhs = Eigen::MatrixXd::Zero(reduced.size, 7);
  *GtWG = Eigen::Matrix<double, 7, 7>::Zero();
  if (on_points) {
    // In point order, whatever the threads that make the points' W.
    return ForEachPointW(round, reduced, num_threads, [&](int k, const Eigen::MatrixXd& W) {
      const Eigen::Matrix<double, 3, 7> G = PointRows(k);
      *GtWG += G.transpose() * G;
      const Eigen::MatrixXd WV_b = W * (reduced.V_inverse[k] * G);
      SubtractAtPointBlocks(reduced, k, WV_b, *rhs);
    });
  }
  for (size_t i = 0; i < image_block.size(); ++i) {
    const bool in_round = image_block[i] >= 0 || static_cast<int>(i) == plan.relative_fixed_image;
    if (!in_round) continue;
    *GtWG += image_G_[i].topRows<3>().transpose() * image_G_[i].topRows<3>();
    if (image_block[i] < 0) continue;
    const int b = image_block[i];
    for (int c = 0; c < round.e_sizes[b]; ++c) {
      const int k = OrientationComponent(plan, static_cast<int>(i), c);
      if (k < 3) rhs->row(reduced.e_offset[b] + c) = image_G_[i].row(k);
    }
  }
  return true;
}

Eigen::Matrix<double, 3, 7> InnerConstraintTransform::PointY(int p,
                                                             const Eigen::MatrixXd& W) const {
  const ReducedNormals& reduced = *reduced_;
  Eigen::Matrix<double, 3, 7> b = on_points_ ? PointRows(p) : Eigen::Matrix<double, 3, 7>::Zero();
  int row = 0;
  for (const int block_index : reduced.W_blocks[p]) {
    const int size = reduced.C.block_size(block_index);
    b -= W.middleRows(row, size).transpose() * y_e_.middleRows(reduced.e_offset[block_index], size);
    row += size;
  }
  return reduced.V_inverse[p] * b;
}

bool InnerConstraintTransform::BackSubstitutePoints(const BundleRound& round,
                                                    const ReducedNormals& reduced, int num_threads,
                                                    Eigen::Matrix<double, 7, 7>* GtWY) const {
  *GtWY = Eigen::Matrix<double, 7, 7>::Zero();
  if (!on_points_) return true;
  // In point order, whatever the threads that make the points' W.
  return ForEachPointW(round, reduced, num_threads, [&](int k, const Eigen::MatrixXd& W) {
    const Eigen::Matrix<double, 3, 7> y_p = PointY(k, W);
    *GtWY += PointRows(k).transpose() * y_p;
  });
}

void InnerConstraintTransform::MakeTransform(const BundlePlan& plan, const BundleRound& round,
                                             const ReducedNormals& reduced,
                                             const std::vector<int>& image_block,
                                             Eigen::Matrix<double, 7, 7> GtWY) {
  for (size_t i = 0; i < image_block.size(); ++i) {
    const int b = image_block[i];
    if (b < 0) continue;
    Eigen::Matrix<double, 6, 7> Y = Eigen::Matrix<double, 6, 7>::Zero();
    for (int c = 0; c < round.e_sizes[b]; ++c)
      Y.row(OrientationComponent(plan, static_cast<int>(i), c)) = y_e_.row(reduced.e_offset[b] + c);
    if (!on_points_) GtWY += image_G_[i].topRows<3>().transpose() * Y.topRows<3>();
    image_M_[i] = Y * A_;
  }
  Q_ = A_ * GtWY * A_;
  Q_ = 0.5 * (Q_ + Q_.transpose()).eval();
}

Status InnerConstraintTransform::Compute(BundleRelativeCovariance datum, const Block& block,
                                         const BundlePlan& plan, const BundleState& state,
                                         const BundleRound& round, const ReducedNormals& reduced,
                                         int num_threads) {
  const bool on_points = datum == BundleRelativeCovariance::kInnerPoints;
  const std::vector<Eigen::Vector3d> positions =
      DatumPositions(on_points, block, plan, state, round, reduced);
  const char* what = on_points ? "adjusted points" : "camera centres";
  if (positions.size() < 3)
    return Status::Error(std::string("the inner constraints on the ") + what +
                         " need three of them, the block has " + std::to_string(positions.size()));
  Eigen::Vector3d centroid;
  double extent = 1.0;
  CentroidAndExtent(positions, &centroid, &extent);

  // G per image (the held first image too) and per point.
  image_G_.assign(block.images.size(), Eigen::Matrix<double, 6, 7>::Zero());
  image_M_.assign(block.images.size(), Eigen::Matrix<double, 6, 7>::Zero());
  for (size_t i = 0; i < block.images.size(); ++i)
    image_G_[i] = OrientationSimilarityRows(state.eo[i], centroid, extent);
  centroid_ = centroid;
  extent_ = extent;
  point_blocks_ = &round.point_blocks;
  reduced_ = &reduced;
  on_points_ = on_points;

  // Y = C_g W G: the right-hand side W G on the round's parameters, the points eliminated
  // (r_e = b_e - sum_p W_p V_p^-1 b_p), the reduced system solved, the points back-substituted
  // (y_p = V_p^-1 (b_p - W_p^T y_e)). Held parameters have no rows in C_g: Y is zero there.
  const std::vector<int> image_block = ImageBlocks(block, state, reduced);
  Eigen::MatrixXd rhs;
  Eigen::Matrix<double, 7, 7> GtWG;
  if (!RightHandSide(on_points, plan, round, reduced, image_block, num_threads, &rhs, &GtWG))
    return Status::Error("a residual could not be evaluated at the solution");
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 7, 7>> eigen(GtWG);
  // G^T W G's eigenvalues are the squared singular values of the datum check's Jacobian.
  if (!(eigen.eigenvalues()[0] > kDatumConditioning * kDatumConditioning * eigen.eigenvalues()[6]))
    return Status::Error(std::string("the inner constraints on the ") + what +
                         " do not fix the seven similarity parameters (they lie on one line)");
  const Eigen::Matrix<double, 7, 7> A = eigen.eigenvectors() *
                                        eigen.eigenvalues().cwiseInverse().asDiagonal() *
                                        eigen.eigenvectors().transpose();
  y_e_ = reduced.C.Solve(rhs);
  if (!y_e_.allFinite())
    return Status::Error("the reduced system could not be solved for the datum");
  A_ = A;
  // G^T W Y (the points' y_p made and summed, not kept), then Q = A G^T W Y A and M = Y A.
  Eigen::Matrix<double, 7, 7> GtWY;
  if (!BackSubstitutePoints(round, reduced, num_threads, &GtWY))
    return Status::Error("a residual could not be evaluated at the solution");
  MakeTransform(plan, round, reduced, image_block, GtWY);

  std::ostringstream words;
  words << "inner constraints on the " << positions.size() << " " << what
        << " (minimum trace of their covariance; the block is relative)";
  description_ = words.str();
  return Status::Ok();
}

Matrix6d InnerConstraintTransform::Image(int image, const Matrix6d& gauge) const {
  const Eigen::Matrix<double, 6, 7>& G = image_G_[image];
  const Eigen::Matrix<double, 6, 7>& M = image_M_[image];
  const Matrix6d C = gauge - G * M.transpose() - M * G.transpose() + G * Q_ * G.transpose();
  return 0.5 * (C + C.transpose());
}

Eigen::Matrix<double, 3, 7> InnerConstraintTransform::PointRows(int p) const {
  const double* X = (*point_blocks_)[p];
  return SimilarityRows(Eigen::Vector3d(X[0], X[1], X[2]), centroid_, extent_);
}

Eigen::Matrix3d InnerConstraintTransform::Point(int p, const Eigen::Matrix3d& gauge,
                                                const Eigen::MatrixXd& W) const {
  const Eigen::Matrix<double, 3, 7> G = PointRows(p);
  const Eigen::Matrix<double, 3, 7> y_p = PointY(p, W);
  const Eigen::Matrix<double, 3, 7> M = y_p * A_;
  const Eigen::Matrix3d C = gauge - G * M.transpose() - M * G.transpose() + G * Q_ * G.transpose();
  return 0.5 * (C + C.transpose());
}

}  // namespace photopose::internal
