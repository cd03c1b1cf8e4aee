#pragma once
// Robust single-image resection: LO-RANSAC (solvers/ransac.h) over Lambda Twist P3P
// (solvers/p3p.h), MSAC-scored by image-plane residuals in micrometres. The local optimisation is a
// few Gauss-Newton iterations of the collinearity equations (core/collinearity.h), started also
// from the DLT (solvers/dlt.h) of the inliers, the non-minimal solver, when they allow one. The
// result is an initial exterior orientation and an inlier set for the least-squares resection.
//
// Inputs are ideal image-plane points: micrometres from the principal point, distortion removed,
// Polarity applied (ImagePlaneFromPixel in core/camera.h), so that x = -c u / w, y = -c v / w.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/types.h"
#include "solvers/p3p.h"
#include "solvers/ransac.h"

namespace photopose {

struct AbsolutePoseRansacOptions {
  RansacOptions ransac;
  // Largest image-plane residual of an inlier and the MSAC truncation (um, the Euclidean norm of
  // the (x, y) residual). Set it to 3.5-4 sigma of the marking noise (a fraction exp(-k^2 / 2) of
  // the inliers lies beyond k sigma): the default is 4 sigma of 0.5 px marks with 6 um pixels.
  double inlier_threshold_um = 12.0;
  // Gauss-Newton iterations of each local-optimisation step, >= 1.
  int lo_gauss_newton_iterations = 2;
  // Gauss-Newton iterations on all inliers of the RANSAC pose before it is returned, >= 0 (the
  // local optimisation fits at most 96 inliers, so one iteration from its pose reaches the
  // all-inlier optimum to a small fraction of its uncertainty). 0 when a least-squares adjustment
  // follows anyway.
  int final_gauss_newton_iterations = 1;

  bool IsValid(std::string* why) const;
};

// The RANSAC estimator of resection (the concept of solvers/ransac.h). Models are poses in the
// caller's ground frame; internally the points are centred on their centroid so large projected
// coordinates do not cost precision. The constructor copies and precomputes everything (centred
// points, observations over c, a structure-of-arrays copy for scoring); the per-model work involves
// no trigonometry and no allocation.
// Inputs must be valid (equal sizes, finite, focal_um > 0, threshold > 0):
// EstimateAbsolutePoseRansac checks them.
class AbsolutePoseEstimator {
 public:
  using Model = PoseCandidate;
  static constexpr int kMinimalSampleSize = 3;

  AbsolutePoseEstimator(const std::vector<Eigen::Vector2d>& image_plane_um,
                        const std::vector<Eigen::Vector3d>& points_in_ground, double focal_um,
                        double inlier_threshold_um, int gauss_newton_iterations = 2);

  int num_data() const { return num_data_; }
  // Lambda Twist on the sample; up to four poses.
  void GenerateModels(const int* sample, std::vector<Model>* models) const;
  // sum_i min(|r_i|^2, threshold^2) in um^2, r_i the image-plane residual; a point on or behind the
  // camera plane (w >= 0) counts as an outlier. Returns early, with a value >= best_score_so_far,
  // once the partial sum reaches best_score_so_far, or when a sequential probability ratio test
  // (Matas and Chum, ICCV 2005) finds the model's inlier ratio too low to beat it (a model that
  // could beat it is rejected with probability <= 1e-6).
  double ScoreModel(const Model& model, double best_score_so_far) const;
  // Inliers: in front of the camera and |r_i| <= threshold.
  int Inliers(const Model& model, std::vector<char>* mask) const;
  // Gauss-Newton on the collinearity equations of the given points (at most 96 of them, evenly
  // spread over the list), the rotation updated as R <- Rx(d_omega) Ry(d_phi) Rz(d_kappa) R (no
  // gimbal lock), the centre additively. Stops after the configured iterations or a step that
  // moves the projections by an RMS below 1e-4 of the threshold.
  void RefineModel(const std::vector<int>& inliers, Model* model) const;
  // The same on every listed point, for up to `iterations` iterations.
  void Polish(const std::vector<int>& inliers, int iterations, Model* model) const;

  // Unit bearing of datum i in the camera frame, normalize(x, y, -c).
  Eigen::Vector3d bearing(int i) const {
    return Eigen::Vector3d(observed_over_c_[i].x(), observed_over_c_[i].y(), -1.0).normalized();
  }

 private:
  void GaussNewton(const std::vector<int>& indices, int max_points, int iterations,
                   Model* model) const;

  int num_data_ = 0;
  double focal_um_ = 0.0;
  double threshold_sq_um2_ = 0.0;
  int gauss_newton_iterations_ = 2;
  Eigen::Vector3d origin_in_ground_ = Eigen::Vector3d::Zero();  // centroid of the points (m)
  std::vector<Eigen::Vector3d> centred_points_;                 // X - origin (m)
  std::vector<Eigen::Vector2d> observed_over_c_;                // image-plane point / c (unitless)
  // Scoring layout, in a fixed pseudo-random order of the data (datum order_[k] at position k):
  // centred X, Y, Z (m) and the observations divided by c (x / c, y / c).
  std::vector<int> order_;
  std::vector<double> x_, y_, z_, ox_, oy_;
};

namespace internal {

// One point's contribution to the Gauss-Newton normal equations of the exterior orientation at the
// identity pose (centre 0, omega = phi = kappa = 0), in image-plane units divided by c: with J the
// eo partials of ProjectWithJacobians (core/collinearity.h) at zero eo for camera_point and r the
// observed minus projected image-plane point, adds (J / c)^T (J / c) to the row-major upper
// triangle normal[21] and (J / c)^T (r / c) to gradient[6]. The trigonometry of the zero angles
// and the zeros of J are folded away for the local-optimisation inner loop. Returns false, adding
// nothing, when the point is not in front (w >= 0).
bool AddGaussNewtonTerms(const Eigen::Vector3d& camera_point, double observed_x_over_c,
                         double observed_y_over_c, double* normal, double* gradient);

}  // namespace internal

// Robust resection of one image. image_plane_um[i] (ideal image-plane point, um) observes
// points_in_ground[i] (m); focal_um is the principal distance c. On success writes *eo (seed
// angles), *inlier_mask (one entry per point, 1 for inliers; may be null) and *summary (may be
// null). Errors (summary->success = false, *eo untouched): invalid options, unequal sizes,
// non-finite input, focal_um <= 0, fewer than 3 points, all ground points collinear, no pose with
// at least 3 inliers, or fewer than 3 points in front of the best pose.
Status EstimateAbsolutePoseRansac(const AbsolutePoseRansacOptions& options,
                                  const std::vector<Eigen::Vector2d>& image_plane_um,
                                  const std::vector<Eigen::Vector3d>& points_in_ground,
                                  double focal_um, ExteriorOrientation* eo,
                                  std::vector<char>* inlier_mask, RansacSummary* summary);

}  // namespace photopose
