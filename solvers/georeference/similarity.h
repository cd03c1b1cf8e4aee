#pragma once
// A 3D similarity (scale, rotation, translation) between two frames, fitted in closed form
// (Umeyama's weighted least squares) and robustly (least median of squares over minimal samples,
// then iterated reweighted refits on the inliers): the first step of tying an SfM reconstruction
// in an arbitrary frame to measured camera positions and ground control (georeference.h), the
// same role as COLMAP's model_aligner.
//
// Deterministic: the minimal samples are every triple when there are at most
// RobustSimilarityOptions::max_samples of them, else a fixed sequence of triples (a fixed seed of
// core/simulation/portable_random.h); the final fit is the least-squares fit on the inliers, so
// the outcome does not hang on which sample won.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/status.h"

namespace photopose {

// target = scale * R_target_from_source * source + translation.
struct Similarity3 {
  double scale = 1.0;
  Eigen::Matrix3d R_target_from_source = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d Apply(const Eigen::Vector3d& source) const {
    return scale * R_target_from_source * source + translation;
  }
};

// One pair of corresponding points and the accuracy of the target (m, one sigma, isotropic).
// Pairs of one group (say camera positions, or control points) share one robust scale.
struct SimilarityCorrespondence {
  Eigen::Vector3d source = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  double sigma_m = 1.0;
  int group = 0;
};

// Weighted least squares (weights 1 / sigma^2) over the pairs with use[i] != 0 (all when `use`
// is null). Fails with fewer than 3 pairs or when they lie on a line (relative spread of the
// second principal direction below 1e-6).
Status FitSimilarity(const std::vector<SimilarityCorrespondence>& pairs,
                     const std::vector<char>* use, Similarity3* similarity);

struct RobustSimilarityOptions {
  // A pair is an outlier when its residual exceeds this many robust sigmas of its group (the
  // scale of the group's normalised residuals, from the median) and also this many of its own
  // stated sigmas (so that consistent data keep every pair).
  double outlier_sigmas = 5.0;
  int max_samples = 3000;  // minimal samples (triples) tried, at most
  int refinement_rounds = 5;
};

struct RobustSimilaritySummary {
  bool success = false;
  std::string message;                // why not, when not
  std::vector<char> inlier;           // per pair
  std::vector<double> residual_m;     // per pair: |target - similarity(source)| (m)
  std::vector<double> group_scale;    // per group: robust scale of the normalised residuals
  int num_inliers = 0;
  int num_samples = 0;                // minimal samples tried
};

Status RobustSimilarity(const RobustSimilarityOptions& options,
                        const std::vector<SimilarityCorrespondence>& pairs,
                        Similarity3* similarity, RobustSimilaritySummary* summary);

}  // namespace photopose
