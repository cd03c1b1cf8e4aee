#pragma once
// The orientation and point covariances of a relative block in an inner-constraint datum
// (BundleRelativeCovariance::kInnerPoints, kInnerCentres), from their covariance in the
// adjustment's own gauge (first image held, one centre coordinate of the second), by Baarda's
// S-transformation. Not part of the library's interface.
//
// The normal matrix N of a relative block is singular along the seven directions G of a
// similarity of the ground frame (every point and centre moves by t + w x d + s d, every camera
// turns by -w; residuals do not change). Any covariance C_g of one gauge is a generalised inverse
// of N; with W the selector of the datum's parameters (the points' coordinates, or the centres'),
//
//   C_W = P C_g P^T,  P = I - G (G^T W G)^-1 G^T W,
//
// is the covariance whose W-part has the smallest trace of all datums (inner constraints
// G^T W x = 0; with W = I it is the pseudo-inverse N^+). P is the same for every gauge, so C_W is
// too. Per block, with Y = C_g W G (seven solves with the reduced system's factor, points by back
// substitution), A = (G^T W G)^-1, M = Y A and Q = A G^T W Y A:
//
//   C_W(i, j) = C_g(i, j) - G_i M_j^T - M_i G_j^T + G_i Q G_j^T.
//
// The cost is seven solves and a pass over the points: nothing of C_g beyond the blocks the
// statistics already need. Calibration parameters do not move with a similarity (their rows of G
// are zero) and keep their covariance.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/types.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/bundle_statistics.h"

namespace photopose::internal {

// How a small similarity of the ground frame moves an exterior orientation, in the tangent space
// of cost_functions/exterior_orientation_manifold.h (centre X, Y, Z in m; the small rotation on
// the camera side, rad): the centre's rows are SimilarityRows, the rotation's -R_camera_from_ground
// per `extent` (the ground turns by w, the camera by R w the other way).
Eigen::Matrix<double, 6, 7> OrientationSimilarityRows(const Vector6d& eo,
                                                      const Eigen::Vector3d& centroid,
                                                      double extent);

class InnerConstraintTransform {
 public:
  // The transform of a relative round (plan.datum kRelative) into `datum` (kInnerPoints or
  // kInnerCentres), from `reduced` with its inverse computed. An error when the datum's positions
  // cannot fix the seven parameters (fewer than three, or all on one line).
  [[nodiscard]] Status Compute(BundleRelativeCovariance datum, const Block& block,
                               const BundlePlan& plan, const BundleState& state,
                               const BundleRound& round, const ReducedNormals& reduced,
                               int num_threads);

  // Image i's covariance in the datum (unscaled; the full 6-d tangent space: centre, small
  // rotation), given its covariance in the adjustment's gauge in the same space (zero rows and
  // columns where the gauge holds it).
  Matrix6d Image(int image, const Matrix6d& gauge) const;
  // A point's (index into the round's point data), given its covariance in the adjustment's gauge
  // and its W (J_e^T J_p on reduced.W_blocks[p], PointW). The round and the reduced normals must
  // outlive the transform: a point's G and M are formed when needed, not stored (168 bytes a
  // point each, 20 MB at 120 000 points).
  Eigen::Matrix3d Point(int p, const Eigen::Matrix3d& gauge, const Eigen::MatrixXd& W) const;

  // What the covariances refer to, in words, for the summary.
  const std::string& description() const { return description_; }

 private:
  Eigen::Matrix<double, 3, 7> PointRows(int p) const;  // G of point p
  // Compute's steps once G is known (image_G_, PointRows): the right-hand side W G on the round's
  // parameters with the points eliminated, and G^T W G; the points' y_p = V_p^-1 (b_p - W_p^T y_e)
  // summed into G^T W Y (PointY makes a point's again for Point); then M = Y A of the images and
  // Q = A G^T W Y A. image_block: per image its e block or -1.
  // The points' W_p made again from their rows (ForEachPointW, on num_threads threads); false
  // when a row cannot be evaluated.
  bool RightHandSide(bool on_points, const BundlePlan& plan, const BundleRound& round,
                     const ReducedNormals& reduced, const std::vector<int>& image_block,
                     int num_threads, Eigen::MatrixXd* rhs,
                     Eigen::Matrix<double, 7, 7>* GtWG) const;
  // The points' share of G^T W Y (on the points' datum; zero otherwise), point after point.
  bool BackSubstitutePoints(const BundleRound& round, const ReducedNormals& reduced,
                            int num_threads, Eigen::Matrix<double, 7, 7>* GtWY) const;
  // y_p = V_p^-1 (b_p - W_p^T y_e) of point p from its W.
  Eigen::Matrix<double, 3, 7> PointY(int p, const Eigen::MatrixXd& W) const;
  void MakeTransform(const BundlePlan& plan, const BundleRound& round,
                     const ReducedNormals& reduced, const std::vector<int>& image_block,
                     Eigen::Matrix<double, 7, 7> GtWY);

  bool on_points_ = false;  // the datum is the points' (kInnerPoints), else the centres'
  Eigen::Matrix<double, 7, 7> Q_ = Eigen::Matrix<double, 7, 7>::Zero();
  Eigen::Matrix<double, 7, 7> A_ = Eigen::Matrix<double, 7, 7>::Zero();  // (G^T W G)^-1
  Eigen::MatrixXd y_e_;                                                  // C_g W G on the e columns
  std::vector<Eigen::Matrix<double, 6, 7>> image_G_, image_M_;           // per image of the block
  const std::vector<double*>* point_blocks_ = nullptr;          // the round's points
  const ReducedNormals* reduced_ = nullptr;
  Eigen::Vector3d centroid_ = Eigen::Vector3d::Zero();          // of the datum's positions (m)
  double extent_ = 1.0;                                         // their RMS spread (m)
  std::string description_;
};

}  // namespace photopose::internal
