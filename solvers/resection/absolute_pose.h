#pragma once
// Robust single-image resection: LO-RANSAC (solvers/resection/ransac.h) over Lambda Twist P3P
// (solvers/resection/p3p.h), MSAC-scored by image-plane residuals in micrometres. The local optimisation is a
// few Gauss-Newton iterations of the collinearity equations (core/collinearity.h), started also
// from the DLT (solvers/resection/dlt.h) of the inliers, the non-minimal solver, when they allow one. The
// result is an initial exterior orientation and an inlier set for the least-squares resection.
//
// Inputs are ideal image-plane points: micrometres from the principal point, distortion removed,
// Polarity applied (ImagePlaneFromPixel in core/camera.h), so that x = -c u / w, y = -c v / w (any
// unit works when c is in the same unit). Each datum may carry its standard deviation; residuals are
// then whitened (divided by it) before they are scored, and the inlier threshold is in standard
// deviations.
//
// Two scores: MSAC with a threshold (the marks' accuracy is known), and least median of squares
// (P. J. Rousseeuw, "Least median of squares regression", JASA 1984) when it is not: a model is
// scored by the h-th smallest squared residual, h = floor((n + 4) / 2), which needs no threshold,
// and its inliers are those within inlier_threshold robust standard deviations,
// sigma = (1 + 5 / (n - 3)) sqrt(r_h^2 / q), q the chi-square(2) quantile at h / (n + 1).

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/types.h"
#include "solvers/resection/p3p.h"
#include "solvers/resection/ransac.h"

namespace photopose {

enum class ConsensusScore {
  kMsac,         // truncated squared residuals; the threshold is known
  kLeastMedian,  // least median of squares; the threshold follows from each model's own scale
};

struct AbsolutePoseRansacOptions {
  RansacOptions ransac;
  ConsensusScore score = ConsensusScore::kMsac;
  // Largest residual norm of an inlier and the MSAC truncation, in standard deviations of the data
  // when they are given (a fraction exp(-k^2 / 2) of the inliers lies beyond k: 3.72 keeps 99.9 %),
  // otherwise in image-plane units (um). With kLeastMedian: in robust standard deviations.
  // The default is 4 sigma of 0.5 px marks with 6 um pixels, given as um.
  double inlier_threshold = 12.0;
  // Gauss-Newton iterations of each local-optimisation step, >= 1.
  int lo_gauss_newton_iterations = 2;
  // Gauss-Newton iterations on all inliers of the RANSAC pose before it is returned, >= 0 (the
  // local optimisation fits at most 96 inliers, so one iteration from its pose reaches the
  // all-inlier optimum to a small fraction of its uncertainty). 0 when a least-squares adjustment
  // follows anyway.
  int final_gauss_newton_iterations = 1;

  bool IsValid(std::string* why) const;
};

// The RANSAC estimator of resection (the concept of solvers/resection/ransac.h). Models are poses in the
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

  // sigmas: one standard deviation per datum (image-plane units), or empty for 1 each.
  AbsolutePoseEstimator(const std::vector<Eigen::Vector2d>& image_plane_um,
                        const std::vector<Eigen::Vector3d>& points_in_ground, double focal_um,
                        double inlier_threshold, int gauss_newton_iterations = 2,
                        const std::vector<double>& sigmas = {},
                        ConsensusScore score = ConsensusScore::kMsac);

  int num_data() const { return num_data_; }
  // Lambda Twist on the sample; up to four poses.
  void GenerateModels(const int* sample, std::vector<Model>* models) const;
  // kMsac: sum_i min(|r_i / s_i|^2, threshold^2), r_i the image-plane residual and s_i its
  // standard deviation; a point on or behind the camera plane (w >= 0) counts as an outlier. Returns
  // early, with a value >= best_score_so_far, once the partial sum reaches best_score_so_far, or when
  // a sequential probability ratio test (Matas and Chum, ICCV 2005) finds the model's inlier ratio
  // too low to beat it (a model that could beat it is rejected with probability <= 1e-6).
  // kLeastMedian: the h-th smallest |r_i / s_i|^2 (infinite for points behind the camera).
  double ScoreModel(const Model& model, double best_score_so_far) const;
  // Inliers: in front of the camera and |r_i / s_i| <= threshold (kLeastMedian: threshold times
  // the model's robust standard deviation).
  int Inliers(const Model& model, std::vector<char>* mask) const;
  // kLeastMedian: the robust standard deviation of the whitened residuals at the model (above).
  double RobustSigma(const Model& model) const;
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

  // Squared whitened residuals of every datum at a model, in data order (infinity behind).
  void WhitenedSquares(const Model& model, std::vector<double>* squares) const;

  int num_data_ = 0;
  double threshold_sq_ = 0.0;  // in whitened units
  // Squared threshold in image-plane units over c, for the typical datum (the RMS sigma): the
  // scale of Gauss-Newton's convergence test.
  double typical_threshold_sq_over_c2_ = 0.0;
  int gauss_newton_iterations_ = 2;
  ConsensusScore score_ = ConsensusScore::kMsac;
  int median_rank_ = 0;  // h - 1 of the least median
  Eigen::Vector3d origin_in_ground_ = Eigen::Vector3d::Zero();  // centroid of the points (m)
  std::vector<Eigen::Vector3d> centred_points_;                 // X - origin (m)
  std::vector<Eigen::Vector2d> observed_over_c_;                // image-plane point / c (unitless)
  std::vector<Eigen::Vector3d> unit_bearings_;                  // normalize(x / c, y / c, -1)
  // Scoring layout, in a fixed pseudo-random order of the data (datum order_[k] at position k):
  // centred X, Y, Z (m), the observations divided by c (x / c, y / c) and the squared weights
  // (c / s)^2 that whiten a residual over c.
  std::vector<int> order_;
  std::vector<double> x_, y_, z_, ox_, oy_, w2_;
  // Memos of the const methods (so an estimator is used by one thread at a time): ScoreModel's
  // sequential-test logarithms for the last best score, RefineModel's DLT start for the last
  // inlier set (its pose after Gauss-Newton and its score).
  mutable double sprt_best_score_ = std::numeric_limits<double>::quiet_NaN();
  mutable double sprt_log_per_inlier_ = 0.0;
  mutable double sprt_log_per_outlier_ = 0.0;
  struct DltMemo {
    bool valid = false;
    bool solved = false;
    std::vector<int> inliers;
    std::vector<Eigen::Vector3d> bearings, points;  // the DLT's input (scratch)
    Model model;
    double score = 0.0;
  };
  mutable DltMemo dlt_;
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
// points_in_ground[i] (m); sigmas[i] is its standard deviation (same unit; empty: 1 each, the
// threshold is then in image-plane units); focal_um is the principal distance c. On success writes
// *eo (seed angles), *inlier_mask (one entry per point, 1 for inliers; may be null) and *summary
// (may be null). Errors (summary->success = false, *eo untouched): invalid options, unequal sizes,
// non-finite input or sigmas, focal_um <= 0, fewer than 3 points, all ground points collinear, no
// pose with at least 3 inliers, or fewer than 3 points in front of the best pose.
Status EstimateAbsolutePoseRansac(const AbsolutePoseRansacOptions& options,
                                  const std::vector<Eigen::Vector2d>& image_plane_um,
                                  const std::vector<Eigen::Vector3d>& points_in_ground,
                                  const std::vector<double>& sigmas, double focal_um,
                                  ExteriorOrientation* eo, std::vector<char>* inlier_mask,
                                  RansacSummary* summary);
// The same with every sigma 1 (threshold in image-plane units).
Status EstimateAbsolutePoseRansac(const AbsolutePoseRansacOptions& options,
                                  const std::vector<Eigen::Vector2d>& image_plane_um,
                                  const std::vector<Eigen::Vector3d>& points_in_ground,
                                  double focal_um, ExteriorOrientation* eo,
                                  std::vector<char>* inlier_mask, RansacSummary* summary);

}  // namespace photopose
