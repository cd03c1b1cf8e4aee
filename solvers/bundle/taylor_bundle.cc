#include "solvers/bundle/taylor_bundle.h"

#include <glog/logging.h>

#include <Eigen/Dense>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "core/camera_models.h"
#include "core/rotation.h"
#include "solvers/bundle/check_points.h"
#include "solvers/bundle/triangulation.h"

namespace photopose {
namespace {

using Clock = std::chrono::steady_clock;
using Matrix63 = Eigen::Matrix<double, 6, 3>;
using Matrix26 = Eigen::Matrix<double, 2, 6>;
using Matrix23 = Eigen::Matrix<double, 2, 3>;
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// Multiple of epsilon times the block's size below which a position correction is rounding noise.
constexpr double kPositionResolutionFactor = 256.0;
// An image needs at least this many marks for its six unknowns (BundleAdjust's rule).
constexpr int kMinMarksPerImage = 3;
// A point's 3 x 3 normal block is singular (its rays meet at no definite point) when its smallest
// LDL^T pivot is at most this fraction of the largest.
constexpr double kPointPivotRatio = 1e-14;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string Quoted(const std::string& name) { return "'" + name + "'"; }

// ------------------------------------------------------------------ the ground-point partials

// dF/dX = -dF/dX0: F depends on the point and the centre only through X - X0 (eqs. 7-8), so the
// point's three columns are the negated eqs. 17-19 and 23-25.
inline void PointPartialsFromCentrePartials(const double* row_u, const double* row_v,
                                            Matrix23* d_point) {
  for (int k = 0; k < 3; ++k) {
    (*d_point)(0, k) = -row_u[k];
    (*d_point)(1, k) = -row_v[k];
  }
}

// ------------------------------------------------------------------ what the adjustment holds

// The decisions made before the first round: which marks, points and priors enter, with which
// sigmas, and how the block is tied to the ground. They follow BundleAdjust's rules (see the
// report of issue 12 for the shared function proposed in their place).
struct Plan {
  std::vector<char> mark_used;            // per mark
  std::vector<double> mark_sigma;         // per mark, observation unit
  std::vector<Eigen::Vector2d> ideal_um;  // per mark: the corrected (ideal) image-plane point
  std::vector<char> point_in_problem;
  std::vector<Eigen::Vector3d> point_sigma;  // control points (m)
  std::vector<char> position_prior;
  std::vector<Eigen::Vector3d> position_sigma;  // m
  std::vector<char> attitude_prior;
  std::vector<Eigen::Vector3d> attitude_sigma;  // rad
  std::vector<char> image_constant;  // held constant (config or the relative gauge's first image)
  std::vector<char> point_constant;
  std::vector<std::array<bool, 6>> image_fixed;  // components held fixed of a free image
  BundleDatum datum = BundleDatum::kControl;
  std::string datum_description;
  std::vector<std::string> tie_points_left_out;  // seen twice or more, no initial coordinates
};

int CountUsedMarks(const std::vector<int>& marks, const std::vector<char>& used) {
  int count = 0;
  for (const int m : marks) count += used[m];
  return count;
}

// Tie points seen in fewer than two images add nothing: they and their marks leave.
void DropSingleRayTiePoints(const Block& block, Plan* plan) {
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (block.points[p].role != PointRole::kTie) continue;
    if (CountUsedMarks(block.marks_of_point[p], plan->mark_used) >= 2) continue;
    for (const int m : block.marks_of_point[p]) plan->mark_used[m] = 0;
    plan->point_in_problem[p] = 0;
  }
}

// The first image with fewer than kMinMarksPerImage marks in the adjustment, or -1.
int ImageWithTooFewMarks(const Block& block, const Plan& plan, int* count) {
  for (size_t i = 0; i < block.images.size(); ++i) {
    *count = CountUsedMarks(block.marks_of_image[i], plan.mark_used);
    if (*count < kMinMarksPerImage) return static_cast<int>(i);
  }
  return -1;
}

Status CheckSupported(const BundleAdjustmentConfig& config, const Block& block) {
  for (const std::vector<int>& params : config.calibrated_params) {
    if (!params.empty()) {
      return Status::Error(
          "the Taylor bundle adjustment holds the interior orientation fixed: self-calibration "
          "is done by the Ceres adjustment");
    }
  }
  for (const BlockImage& image : block.images) {
    const BlockCamera& camera = block.cameras[image.camera];
    if (camera.model != CameraModelType::kFrame) {
      return Status::Error("camera " + Quoted(camera.camera_id) + " is a " +
                           EnumName(camera.model) +
                           " model: the Taylor bundle adjustment takes the ArcGIS frame model "
                           "(FRAME) only; use the Ceres adjustment");
    }
  }
  for (const int i : config.constant_images)
    if (i < 0 || i >= static_cast<int>(block.images.size()))
      return Status::Error("the config holds a non-existent image constant");
  for (const int p : config.constant_points)
    if (p < 0 || p >= static_cast<int>(block.points.size()))
      return Status::Error("the config holds a non-existent point constant");
  return Status::Ok();
}

// Connected parts of the image graph (images joined by the points they share), as lists of image
// names; one entry for a connected block.
std::vector<std::vector<std::string>> ConnectedParts(const Block& block, const Plan& plan) {
  const int n = static_cast<int>(block.images.size());
  std::vector<int> label(n, -1);
  std::vector<std::vector<std::string>> parts;
  for (int seed = 0; seed < n; ++seed) {
    if (label[seed] >= 0) continue;
    const int part = static_cast<int>(parts.size());
    parts.emplace_back();
    std::vector<int> stack = {seed};
    label[seed] = part;
    while (!stack.empty()) {
      const int image = stack.back();
      stack.pop_back();
      parts[part].push_back(block.images[image].name);
      for (const int m : block.marks_of_image[image]) {
        if (!plan.mark_used[m] || !plan.point_in_problem[block.marks[m].point]) continue;
        for (const int other : block.marks_of_point[block.marks[m].point]) {
          const int j = block.marks[other].image;
          if (!plan.mark_used[other] || label[j] >= 0) continue;
          label[j] = part;
          stack.push_back(j);
        }
      }
    }
  }
  return parts;
}

std::string ListNames(const std::vector<std::string>& names, size_t most) {
  std::string text;
  for (size_t k = 0; k < names.size() && k < most; ++k) text += (k ? ", " : "") + Quoted(names[k]);
  if (names.size() > most) text += ", ... (" + std::to_string(names.size()) + " in all)";
  return text;
}

Status MakePlan(const TaylorBundleOptions& options, const BundleAdjustmentConfig& config,
                const Block& block, Plan* plan) {
  const BundleAccuracies& acc = options.accuracies;
  const size_t num_marks = block.marks.size();
  plan->mark_used.assign(num_marks, 0);
  plan->mark_sigma.assign(num_marks, 1.0);
  plan->ideal_um.assign(num_marks, Eigen::Vector2d::Zero());
  plan->point_in_problem.assign(block.points.size(), 0);
  plan->point_sigma.assign(block.points.size(), Eigen::Vector3d::Constant(acc.marker_m));
  plan->image_constant.assign(block.images.size(), 0);
  plan->point_constant.assign(block.points.size(), 0);
  plan->image_fixed.assign(block.images.size(), std::array<bool, 6>{});
  for (const int i : config.constant_images) plan->image_constant[i] = 1;
  for (const int p : config.constant_points) plan->point_constant[p] = 1;

  std::vector<std::string> missing;
  for (const BlockImage& image : block.images)
    if (!image.eo) missing.push_back(image.name);
  if (!missing.empty()) {
    return Status::Error("images without initial exterior orientation: " + ListNames(missing, 5) +
                         " (give a frames table or let the initialisation orient them)");
  }

  // Marks of control and tie points, with their sigma and their ideal image-plane point: the
  // frame model's correction of the measured film point, constant with the interior orientation.
  for (size_t m = 0; m < num_marks; ++m) {
    const BlockMark& mark = block.marks[m];
    const PointRole role = block.points[mark.point].role;
    if (role == PointRole::kCheck) continue;
    const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
    const bool control = role == PointRole::kControl;
    const double sigma_px = control ? acc.marker_projection_px : acc.tie_px;
    const double sigma_film_um = DefaultFilmMarkSigmaUm(
        camera, sigma_px, control ? acc.marker_projection_film_um : acc.tie_film_um);
    plan->mark_sigma[m] = MarkSigma(mark, sigma_px, sigma_film_um);
    plan->mark_used[m] = 1;
    FrameCorrectFilmPoint(camera.params.data(), mark.observation.data(), camera.data(),
                          plan->ideal_um[m].data());
  }
  for (size_t p = 0; p < block.points.size(); ++p)
    if (block.points[p].role != PointRole::kCheck) plan->point_in_problem[p] = 1;
  DropSingleRayTiePoints(block, plan);
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (!plan->point_in_problem[p]) continue;
    if (CountUsedMarks(block.marks_of_point[p], plan->mark_used) == 0) {
      plan->point_in_problem[p] = 0;  // a control point nobody sees
      continue;
    }
    if (point.role == PointRole::kTie && !point.position_m) {
      // Not intersected by the initialisation: left out with its marks, as BundleAdjust does.
      plan->point_in_problem[p] = 0;
      for (const int m : block.marks_of_point[p]) plan->mark_used[m] = 0;
      plan->tie_points_left_out.push_back(point.id);
      continue;
    }
    if (point.role == PointRole::kControl && point.accuracy_m)
      plan->point_sigma[p] = *point.accuracy_m;
  }
  int count = 0;
  const int weak = ImageWithTooFewMarks(block, *plan, &count);
  if (weak >= 0) {
    return Status::Error("image " + Quoted(block.images[weak].name) + " has " +
                         std::to_string(count) + " usable marks; an image needs at least " +
                         std::to_string(kMinMarksPerImage) +
                         " (marks of control points and of tie points seen in two images)");
  }

  // Priors of the images that are adjusted.
  plan->position_prior.assign(block.images.size(), 0);
  plan->position_sigma.assign(block.images.size(), acc.camera_m);
  plan->attitude_prior.assign(block.images.size(), 0);
  plan->attitude_sigma.assign(block.images.size(), Eigen::Vector3d::Zero());
  int num_positions = 0, num_attitudes = 0;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    if (plan->image_constant[i]) continue;
    if (image.measured_center_m && (image.center_accuracy_m || acc.camera_positions_are_priors)) {
      plan->position_prior[i] = 1;
      if (image.center_accuracy_m) plan->position_sigma[i] = *image.center_accuracy_m;
      ++num_positions;
    }
    if (image.measured_angles_rad && (image.attitude_accuracy_rad || acc.attitude_deg)) {
      plan->attitude_prior[i] = 1;
      plan->attitude_sigma[i] =
          image.attitude_accuracy_rad
              ? *image.attitude_accuracy_rad
              : Eigen::Vector3d::Constant(DegreesToRadians(*acc.attitude_deg));
      ++num_attitudes;
    }
  }

  const std::vector<std::vector<std::string>> parts = ConnectedParts(block, *plan);
  if (parts.size() > 1) {
    std::string text;
    for (size_t k = 0; k < parts.size() && k < 3; ++k)
      text += (k ? "; " : "") + std::to_string(parts[k].size()) + " image" +
              (parts[k].size() == 1 ? "" : "s") + " (" + ListNames(parts[k], 3) + ")";
    if (parts.size() > 3) text += "; ...";
    return Status::Error("the block falls apart into " + std::to_string(parts.size()) +
                         " parts that share no point: " + text);
  }

  // Datum. Ground-fixed when anything ties the block to the ground: control points (or points
  // held constant), camera positions, attitudes, images held constant. Otherwise COLMAP's gauge.
  int num_control = 0;
  for (size_t p = 0; p < block.points.size(); ++p)
    if (plan->point_in_problem[p] &&
        (block.points[p].role == PointRole::kControl || plan->point_constant[p]))
      ++num_control;
  const int num_constant_images = static_cast<int>(config.constant_images.size());
  if (num_control + num_positions + num_attitudes + num_constant_images > 0) {
    plan->datum = BundleDatum::kControl;
    std::ostringstream os;
    os << "absolute: " << num_control << " control point" << (num_control == 1 ? "" : "s") << ", "
       << num_positions << " camera position" << (num_positions == 1 ? "" : "s");
    if (num_attitudes > 0)
      os << ", " << num_attitudes << " attitude" << (num_attitudes == 1 ? "" : "s");
    if (num_constant_images > 0) os << ", " << num_constant_images << " image(s) held constant";
    os << " weighted as stated (a datum defect shows as a singular reduced normal matrix)";
    plan->datum_description = os.str();
    return Status::Ok();
  }
  plan->datum = BundleDatum::kRelative;
  if (block.images.size() < 2) return Status::Error("a relative block needs two images");
  const Eigen::Vector3d baseline =
      block.images[1].eo->center_in_ground() - block.images[0].eo->center_in_ground();
  if (!(baseline.norm() > 0.0))
    return Status::Error("a relative block needs its first two images at different positions");
  int axis = 0;
  baseline.cwiseAbs().maxCoeff(&axis);
  plan->image_constant[0] = 1;
  plan->image_fixed[1][axis] = true;
  plan->datum_description = "relative: no control points and no camera positions; image " +
                            Quoted(block.images[0].name) + " held fixed and the " +
                            std::string(1, "XYZ"[axis]) + " coordinate of image " +
                            Quoted(block.images[1].name) +
                            " fixes the scale (COLMAP's convention); coordinates are in the "
                            "frame of the input";
  return Status::Ok();
}

// ------------------------------------------------------------------ one round's structure

// The unknowns and the sparsity of the reduced normal matrix of one round. Camera block b is
// image free_images[b], columns 6 b .. 6 b + 5. The reduced matrix is stored as its upper triangle
// in a compressed sparse column matrix whose pattern is built once per round; pairs[k] = (b1, b2),
// b1 <= b2, is a 6 x 6 block of it and value_start[k][c] the position in its value array of row
// 6 b1 of column 6 b2 + c (the block's rows of a column are contiguous).
struct Layout {
  std::vector<int> image_block;  // per image: camera block or -1
  std::vector<int> point_block;  // per point: free point or -1
  std::vector<int> free_images;
  std::vector<int> free_points;
  std::vector<int> marks;                     // the marks of the round (indices into Block::marks)
  std::vector<int> mark_block;                // per mark of the round: camera block or -1
  std::vector<int> mark_point;                // per mark of the round: free point or -1
  std::vector<std::vector<int>> point_marks;  // per free point: positions in `marks` of its
                                              // marks in free images
  std::vector<std::vector<int>> point_pairs;  // per free point: pair of each (a <= c) of those
  std::vector<int> diagonal_pair;             // per camera block
  std::vector<std::pair<int, int>> pairs;
  std::vector<std::array<int, 6>> value_start;
  SparseMatrix S;
  int num_observations = 0;
  int num_unknowns = 0;
};

int TriangleIndex(int a, int c, int n) { return a * n - a * (a - 1) / 2 + (c - a); }

// Renumbers the camera blocks in a fill-reducing order: approximate minimum degree on the image
// graph (images joined when they see a common point that is an unknown). Each image's 6 x 6 block
// of S is dense, so ordering images rather than scalars loses nothing (Ceres orders its Schur
// complement the same way), and the sparse LDL^T then runs in the natural order: the scalar AMD
// of a dense-ish S would cost more than a whole Gauss-Newton iteration.
void OrderImagesToReduceFill(const Block& block, const Plan& plan, Layout* layout) {
  const int num_blocks = static_cast<int>(layout->free_images.size());
  if (num_blocks < 3) return;
  std::vector<Eigen::Triplet<double, int>> entries;
  std::vector<int> seen;
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p] || plan.point_constant[p]) continue;
    seen.clear();
    for (const int m : block.marks_of_point[p]) {
      const int b = layout->image_block[block.marks[m].image];
      if (plan.mark_used[m] && b >= 0) seen.push_back(b);
    }
    for (const int b1 : seen)
      for (const int b2 : seen) entries.emplace_back(b1, b2, 1.0);
  }
  for (int b = 0; b < num_blocks; ++b) entries.emplace_back(b, b, 1.0);
  SparseMatrix graph(num_blocks, num_blocks);
  graph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;
  Eigen::AMDOrdering<int>()(graph, order);  // order.indices()[new] = old
  std::vector<int> images(num_blocks);
  for (int k = 0; k < num_blocks; ++k) {
    images[k] = layout->free_images[order.indices()[k]];
    layout->image_block[images[k]] = k;
  }
  layout->free_images = std::move(images);
}

void BuildLayout(const Block& block, const Plan& plan, Layout* layout) {
  *layout = Layout();
  layout->image_block.assign(block.images.size(), -1);
  layout->point_block.assign(block.points.size(), -1);
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (plan.image_constant[i]) continue;
    layout->image_block[i] = static_cast<int>(layout->free_images.size());
    layout->free_images.push_back(static_cast<int>(i));
    layout->num_unknowns += 6;
    for (const bool fixed : plan.image_fixed[i]) layout->num_unknowns -= fixed;
  }
  OrderImagesToReduceFill(block, plan, layout);
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!plan.point_in_problem[p] || plan.point_constant[p]) continue;
    layout->point_block[p] = static_cast<int>(layout->free_points.size());
    layout->free_points.push_back(static_cast<int>(p));
    layout->num_unknowns += 3;
    if (block.points[p].role == PointRole::kControl) layout->num_observations += 3;
  }
  for (size_t i = 0; i < block.images.size(); ++i)
    layout->num_observations += 3 * (plan.position_prior[i] + plan.attitude_prior[i]);
  layout->point_marks.assign(layout->free_points.size(), {});
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!plan.mark_used[m]) continue;
    const int k = static_cast<int>(layout->marks.size());
    layout->marks.push_back(static_cast<int>(m));
    layout->num_observations += 2;
    const int b = layout->image_block[block.marks[m].image];
    const int q = layout->point_block[block.marks[m].point];
    layout->mark_block.push_back(b);
    layout->mark_point.push_back(q);
    if (q >= 0 && b >= 0) layout->point_marks[q].push_back(k);
  }

  // Block pairs: the diagonal, and every two images that see a common free point.
  std::unordered_map<long long, int> pair_index;
  const long long num_blocks = static_cast<long long>(layout->free_images.size());
  auto pair_of = [&](int b1, int b2) {
    if (b1 > b2) std::swap(b1, b2);
    const auto [it, inserted] =
        pair_index.emplace(b1 * num_blocks + b2, static_cast<int>(layout->pairs.size()));
    if (inserted) layout->pairs.emplace_back(b1, b2);
    return it->second;
  };
  for (int b = 0; b < static_cast<int>(num_blocks); ++b)
    layout->diagonal_pair.push_back(pair_of(b, b));
  layout->point_pairs.assign(layout->free_points.size(), {});
  for (size_t q = 0; q < layout->free_points.size(); ++q) {
    const std::vector<int>& marks = layout->point_marks[q];
    const int n = static_cast<int>(marks.size());
    std::vector<int>& ids = layout->point_pairs[q];
    ids.resize(n * (n + 1) / 2);
    for (int a = 0; a < n; ++a)
      for (int c = a; c < n; ++c)
        ids[TriangleIndex(a, c, n)] =
            pair_of(layout->mark_block[marks[a]], layout->mark_block[marks[c]]);
  }

  // The sparse pattern (upper triangle) and where each block's columns start in it.
  const int size = 6 * static_cast<int>(num_blocks);
  std::vector<Eigen::Triplet<double, int>> entries;
  for (const auto& [b1, b2] : layout->pairs)
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < (b1 == b2 ? c + 1 : 6); ++r)
        entries.emplace_back(6 * b1 + r, 6 * b2 + c, 1.0);
  layout->S.resize(size, size);
  layout->S.setFromTriplets(entries.begin(), entries.end());
  layout->S.makeCompressed();
  const int* outer = layout->S.outerIndexPtr();
  const int* inner = layout->S.innerIndexPtr();
  layout->value_start.resize(layout->pairs.size());
  for (size_t k = 0; k < layout->pairs.size(); ++k) {
    const auto [b1, b2] = layout->pairs[k];
    for (int c = 0; c < 6; ++c) {
      const int column = 6 * b2 + c;
      const int* begin = inner + outer[column];
      const int* end = inner + outer[column + 1];
      layout->value_start[k][c] = static_cast<int>(std::lower_bound(begin, end, 6 * b1) - inner);
    }
  }
}

// ------------------------------------------------------------------ the linearisation

// The values being adjusted, relative to the block's centroid.
struct State {
  std::vector<Vector6d> eo;             // per image
  std::vector<Eigen::Vector3d> points;  // per point
};

// The block's fixed data in the centred frame.
struct Frame {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double extent_m = 1.0;                  // RMS distance of cameras and points from the centroid
  std::vector<Eigen::Vector3d> surveyed;  // per point (control points), centred
  std::vector<Eigen::Vector3d> measured;  // per image (camera positions), centred
  std::vector<double> focal_um;           // per image
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();
  bool use_lever = false;
};

// The normal equations of one linearisation (seed sign: N d = A^T P F, p = p0 - d).
struct Normal {
  std::vector<Matrix6d> U;  // per camera block
  std::vector<Vector6d> ge;
  std::vector<Eigen::Matrix3d> V;  // per free point
  std::vector<Eigen::Vector3d> gp;
  std::vector<Matrix63> W;         // per mark of the round (zero unless image and point free)
  std::vector<Eigen::Vector2d> f;  // per mark of the round: F (um)
  double weighted_ssr = 0.0;       // F^T P F over every observation
  int behind_mark = -1;            // a mark whose point is not in front of its camera
  double behind_w = 0.0;
};

// Optional dense copy of the whitened observation equations, for LinearizeTaylorBundle.
struct DenseRows {
  std::vector<int> image_columns;  // per image: first column or -1
  std::vector<int> point_columns;  // per point: first column or -1
  int num_columns = 0;
  std::vector<Eigen::VectorXd> rows;
  std::vector<double> residuals;

  // One equation: sqrt_weight times (eo_row at the image's columns, point_row at the point's) and
  // times F. image / point -1 (or a null row): no such part.
  void Add(int image, const double* eo_row, int point, const double* point_row, double sqrt_weight,
           double f) {
    Eigen::VectorXd row = Eigen::VectorXd::Zero(num_columns);
    if (image >= 0 && eo_row != nullptr && image_columns[image] >= 0)
      for (int k = 0; k < 6; ++k) row[image_columns[image] + k] = sqrt_weight * eo_row[k];
    if (point >= 0 && point_row != nullptr && point_columns[point] >= 0)
      for (int k = 0; k < 3; ++k) row[point_columns[point] + k] = sqrt_weight * point_row[k];
    rows.push_back(std::move(row));
    residuals.push_back(sqrt_weight * f);
  }
};

// Linearises every observation equation at `state` and accumulates the normal equations. False
// when a point is not in front of its camera (normal->behind_mark says which) or the residuals
// are not finite.
bool Linearize(TaylorPartials partials, const Block& block, const Plan& plan, const Layout& layout,
               const Frame& frame, const State& state, Normal* normal, DenseRows* dense) {
  const size_t num_blocks = layout.free_images.size();
  const size_t num_points = layout.free_points.size();
  normal->U.assign(num_blocks, Matrix6d::Zero());
  normal->ge.assign(num_blocks, Vector6d::Zero());
  normal->V.assign(num_points, Eigen::Matrix3d::Zero());
  normal->gp.assign(num_points, Eigen::Vector3d::Zero());
  normal->W.resize(layout.marks.size());
  normal->f.resize(layout.marks.size());
  normal->weighted_ssr = 0.0;
  normal->behind_mark = -1;

  std::vector<TaylorPoseLinearization> poses;
  poses.reserve(block.images.size());
  for (size_t i = 0; i < block.images.size(); ++i)
    poses.emplace_back(partials, state.eo[i].data(), frame.focal_um[i]);

  // Marks: eqs. 7-8 with eqs. 17-28 for the camera and dF/dX = -dF/dX0 for the point.
  for (size_t k = 0; k < layout.marks.size(); ++k) {
    const int m = layout.marks[k];
    const BlockMark& mark = block.marks[m];
    double row_u[6], row_v[6], fu, fv, w;
    if (!poses[mark.image].Linearize(state.points[mark.point].data(), plan.ideal_um[m].data(),
                                     row_u, row_v, &fu, &fv, &w)) {
      normal->behind_mark = m;
      normal->behind_w = w;
      return false;
    }
    const double weight = 1.0 / (plan.mark_sigma[m] * plan.mark_sigma[m]);
    const Eigen::Vector2d F(fu, fv);
    normal->f[k] = F;
    normal->weighted_ssr += weight * F.squaredNorm();
    Matrix26 A_e;
    for (int c = 0; c < 6; ++c) {
      A_e(0, c) = row_u[c];
      A_e(1, c) = row_v[c];
    }
    Matrix23 A_p;
    PointPartialsFromCentrePartials(row_u, row_v, &A_p);
    const int b = layout.mark_block[k];
    const int q = layout.mark_point[k];
    if (b >= 0) {
      normal->U[b].noalias() += weight * A_e.transpose() * A_e;
      normal->ge[b].noalias() += weight * A_e.transpose() * F;
    }
    if (q >= 0) {
      normal->V[q].noalias() += weight * A_p.transpose() * A_p;
      normal->gp[q].noalias() += weight * A_p.transpose() * F;
    }
    if (b >= 0 && q >= 0) {
      normal->W[k].noalias() = weight * A_e.transpose() * A_p;
    } else {
      normal->W[k].setZero();
    }
    if (dense != nullptr) {
      const double s = std::sqrt(weight);
      const double point_u[3] = {A_p(0, 0), A_p(0, 1), A_p(0, 2)};
      const double point_v[3] = {A_p(1, 0), A_p(1, 1), A_p(1, 2)};
      dense->Add(mark.image, row_u, mark.point, point_u, s, fu);
      dense->Add(mark.image, row_v, mark.point, point_v, s, fv);
    }
  }

  // Control points: F = X - X_surveyed per axis, A = I.
  for (size_t q = 0; q < num_points; ++q) {
    const int p = layout.free_points[q];
    if (block.points[p].role != PointRole::kControl) continue;
    const Eigen::Vector3d F = state.points[p] - frame.surveyed[p];
    const Eigen::Vector3d weight = plan.point_sigma[p].cwiseAbs2().cwiseInverse();
    normal->V[q].diagonal() += weight;
    normal->gp[q] += weight.cwiseProduct(F);
    normal->weighted_ssr += weight.dot(F.cwiseAbs2());
    if (dense != nullptr) {
      for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Vector3d row = Eigen::Vector3d::Unit(axis);
        dense->Add(-1, nullptr, p, row.data(), std::sqrt(weight[axis]), F[axis]);
      }
    }
  }
  // Camera positions: F = X0 + R^T l - X_gnss, A = [I, d(R^T l)/d angles]. Attitudes: F = the
  // angle differences (wrapped), A = [0, I].
  for (size_t i = 0; i < block.images.size(); ++i) {
    const int b = layout.image_block[i];
    if (b < 0) continue;
    if (plan.position_prior[i]) {
      Eigen::Matrix<double, 3, 6> A = Eigen::Matrix<double, 3, 6>::Zero();
      A.leftCols<3>().setIdentity();
      Eigen::Vector3d antenna = state.eo[i].head<3>();
      if (frame.use_lever) {
        ExteriorOrientation eo;
        eo.parameters = state.eo[i];
        Eigen::Matrix3d d_angles;
        antenna = TaylorAntennaPosition(eo, frame.lever, &d_angles);
        A.rightCols<3>() = d_angles;
      }
      const Eigen::Vector3d F = antenna - frame.measured[i];
      const Eigen::Vector3d weight = plan.position_sigma[i].cwiseAbs2().cwiseInverse();
      normal->U[b].noalias() += A.transpose() * weight.asDiagonal() * A;
      normal->ge[b].noalias() += A.transpose() * weight.cwiseProduct(F);
      normal->weighted_ssr += weight.dot(F.cwiseAbs2());
      if (dense != nullptr) {
        for (int axis = 0; axis < 3; ++axis) {
          const Vector6d row = A.row(axis).transpose();
          dense->Add(static_cast<int>(i), row.data(), -1, nullptr, std::sqrt(weight[axis]),
                     F[axis]);
        }
      }
    }
    if (plan.attitude_prior[i]) {
      Eigen::Vector3d F;
      for (int k = 0; k < 3; ++k)
        F[k] = WrapAngle(state.eo[i][3 + k] - (*block.images[i].measured_angles_rad)[k]);
      const Eigen::Vector3d weight = plan.attitude_sigma[i].cwiseAbs2().cwiseInverse();
      normal->U[b].bottomRightCorner<3, 3>().diagonal() += weight;
      normal->ge[b].tail<3>() += weight.cwiseProduct(F);
      normal->weighted_ssr += weight.dot(F.cwiseAbs2());
      if (dense != nullptr) {
        for (int axis = 0; axis < 3; ++axis) {
          const Vector6d row = Vector6d::Unit(3 + axis);
          dense->Add(static_cast<int>(i), row.data(), -1, nullptr, std::sqrt(weight[axis]),
                     F[axis]);
        }
      }
    }
  }
  return std::isfinite(normal->weighted_ssr);
}

// ------------------------------------------------------------------ the reduced normal equations

// The points eliminated, the reduced camera system factorised.
struct Reduction {
  std::vector<Eigen::Matrix3d> V_inverse;  // per free point
  std::vector<Matrix63> Y;                 // scratch: W V^-1 of the marks of one point
  std::vector<Matrix6d> blocks;            // per pair: the reduced matrix S (unscaled)
  Eigen::VectorXd r;                       // reduced right-hand side (unscaled)
  Eigen::VectorXd scale;                   // Jacobi scale 1 / sqrt(diag S); 1 where fixed
  // Natural order: the camera blocks are already in a fill-reducing order (BuildLayout).
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper, Eigen::NaturalOrdering<int>> ldlt;
  bool analysed = false;
  double pivot_ratio = 0.0;  // smallest / largest pivot of the scaled LDL^T
};

bool IsFixed(const Plan& plan, const Layout& layout, int b, int component) {
  return plan.image_fixed[layout.free_images[b]][component];
}

// Eliminates the points, 3 x 3 at a time:
//   S = U - sum_p W_p V_p^-1 W_p^T,   r = g_e - sum_p W_p V_p^-1 g_p.
// Returns the first free point whose block V_p is singular (its rays fix no point), or -1.
int Reduce(const Normal& normal, const Layout& layout, Reduction* reduction) {
  const int num_blocks = static_cast<int>(layout.free_images.size());
  reduction->blocks.assign(layout.pairs.size(), Matrix6d::Zero());
  reduction->r.resize(6 * num_blocks);
  for (int b = 0; b < num_blocks; ++b) {
    reduction->blocks[layout.diagonal_pair[b]] = normal.U[b];
    reduction->r.segment<6>(6 * b) = normal.ge[b];
  }
  reduction->V_inverse.resize(layout.free_points.size());
  for (size_t q = 0; q < layout.free_points.size(); ++q) {
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal.V[q]);
    const Eigen::Vector3d d = ldlt.vectorD();
    if (ldlt.info() != Eigen::Success || !(d.minCoeff() > kPointPivotRatio * d.maxCoeff()))
      return layout.free_points[q];
    const Eigen::Matrix3d V_inverse = ldlt.solve(Eigen::Matrix3d::Identity());
    reduction->V_inverse[q] = V_inverse;
    const std::vector<int>& marks = layout.point_marks[q];
    const std::vector<int>& ids = layout.point_pairs[q];
    const int n = static_cast<int>(marks.size());
    std::vector<Matrix63>& Y = reduction->Y;
    Y.resize(n);
    for (int a = 0; a < n; ++a) {
      Y[a].noalias() = normal.W[marks[a]] * V_inverse;
      reduction->r.segment<6>(6 * layout.mark_block[marks[a]]).noalias() -= Y[a] * normal.gp[q];
    }
    for (int a = 0; a < n; ++a) {
      const int ka = marks[a];
      const int ba = layout.mark_block[ka];
      for (int c = a; c < n; ++c) {
        const int kc = marks[c];
        const int bc = layout.mark_block[kc];
        Matrix6d& block = reduction->blocks[ids[TriangleIndex(a, c, n)]];
        const Matrix6d M = Y[a] * normal.W[kc].transpose();  // W_a V^-1 W_c^T
        if (a == c || ba < bc) {
          block -= M;
        } else if (ba > bc) {
          block -= M.transpose();
        } else {  // two marks of the point in one image
          block -= M + M.transpose();
        }
      }
    }
  }
  return -1;
}

// Writes the Jacobi-scaled S into layout->S (fixed components: their row and column zero, 1 on
// the diagonal, which removes them exactly) and sets the scale. Returns the first camera column
// without weight (a zero diagonal), or -1.
int WriteScaled(const Plan& plan, Layout* layout, Reduction* reduction) {
  const int num_blocks = static_cast<int>(layout->free_images.size());
  reduction->scale.resize(6 * num_blocks);
  for (int b = 0; b < num_blocks; ++b) {
    const Matrix6d& diagonal = reduction->blocks[layout->diagonal_pair[b]];
    for (int r = 0; r < 6; ++r) {
      if (IsFixed(plan, *layout, b, r)) {
        reduction->scale[6 * b + r] = 1.0;
        continue;
      }
      const double d = diagonal(r, r);
      if (!(d > 0.0) || !std::isfinite(d)) return 6 * b + r;
      reduction->scale[6 * b + r] = 1.0 / std::sqrt(d);
    }
  }
  double* values = layout->S.valuePtr();
  const Eigen::VectorXd& s = reduction->scale;
  for (size_t k = 0; k < layout->pairs.size(); ++k) {
    const auto [b1, b2] = layout->pairs[k];
    const Matrix6d& block = reduction->blocks[k];
    for (int c = 0; c < 6; ++c) {
      const bool fixed_c = IsFixed(plan, *layout, b2, c);
      double* column = values + layout->value_start[k][c];
      const int rows = b1 == b2 ? c + 1 : 6;
      for (int r = 0; r < rows; ++r) {
        if (fixed_c || IsFixed(plan, *layout, b1, r)) {
          column[r] = (b1 == b2 && r == c) ? 1.0 : 0.0;
        } else {
          column[r] = block(r, c) * s[6 * b1 + r] * s[6 * b2 + c];
        }
      }
    }
  }
  return -1;
}

// Factorises the scaled S. False when it is not positive definite to min_pivot_ratio.
bool Factorize(double min_pivot_ratio, const Layout& layout, Reduction* reduction) {
  if (!reduction->analysed) {
    reduction->ldlt.analyzePattern(layout.S);
    reduction->analysed = true;
  }
  reduction->ldlt.factorize(layout.S);
  if (reduction->ldlt.info() != Eigen::Success) {
    reduction->pivot_ratio = 0.0;
    return false;
  }
  const Eigen::VectorXd d = reduction->ldlt.vectorD();
  if (d.size() == 0) {
    reduction->pivot_ratio = 1.0;
    return true;
  }
  reduction->pivot_ratio = d.minCoeff() / d.maxCoeff();
  return d.minCoeff() > 0.0 && reduction->pivot_ratio > min_pivot_ratio;
}

// Solves S d_e = r (through the scaled factorisation) and back-substitutes
// d_p = V_p^-1 (g_p - W_p^T d_e).
void SolveCorrections(const Plan& plan, const Layout& layout, const Normal& normal,
                      const Reduction& reduction, Eigen::VectorXd* d_e,
                      std::vector<Eigen::Vector3d>* d_p) {
  const Eigen::VectorXd& s = reduction.scale;
  Eigen::VectorXd rhs = s.cwiseProduct(reduction.r);
  for (int b = 0; b < static_cast<int>(layout.free_images.size()); ++b)
    for (int c = 0; c < 6; ++c)
      if (IsFixed(plan, layout, b, c)) rhs[6 * b + c] = 0.0;
  *d_e = s.cwiseProduct(reduction.ldlt.solve(rhs));
  d_p->resize(layout.free_points.size());
  for (size_t q = 0; q < layout.free_points.size(); ++q) {
    Eigen::Vector3d t = normal.gp[q];
    for (const int k : layout.point_marks[q])
      t.noalias() -= normal.W[k].transpose() * d_e->segment<6>(6 * layout.mark_block[k]);
    (*d_p)[q] = reduction.V_inverse[q] * t;
  }
}

// ------------------------------------------------------------------ set-up shared by both entries

Frame MakeFrame(const TaylorBundleOptions& options, const Block& block, const Plan& plan,
                State* state) {
  Frame frame;
  state->eo.clear();
  state->points.assign(block.points.size(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> positions;
  for (const BlockImage& image : block.images) {
    state->eo.push_back(image.eo->parameters);
    positions.push_back(image.eo->center_in_ground());
  }
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    state->points[p] = point.position_m   ? *point.position_m
                       : point.surveyed_m ? *point.surveyed_m
                                          : Eigen::Vector3d::Zero();
    if (plan.point_in_problem[p]) positions.push_back(state->points[p]);
  }
  for (const Eigen::Vector3d& x : positions) frame.centroid += x;
  frame.centroid /= static_cast<double>(positions.size());
  double ssq = 0.0;
  for (const Eigen::Vector3d& x : positions) ssq += (x - frame.centroid).squaredNorm();
  frame.extent_m = std::sqrt(ssq / positions.size());
  if (!(frame.extent_m > 0.0)) frame.extent_m = 1.0;
  for (Vector6d& eo : state->eo) eo.head<3>() -= frame.centroid;
  for (Eigen::Vector3d& x : state->points) x -= frame.centroid;
  frame.surveyed.assign(block.points.size(), Eigen::Vector3d::Zero());
  for (size_t p = 0; p < block.points.size(); ++p)
    if (block.points[p].surveyed_m)
      frame.surveyed[p] = *block.points[p].surveyed_m - frame.centroid;
  frame.measured.assign(block.images.size(), Eigen::Vector3d::Zero());
  frame.focal_um.assign(block.images.size(), 0.0);
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (block.images[i].measured_center_m)
      frame.measured[i] = *block.images[i].measured_center_m - frame.centroid;
    frame.focal_um[i] = block.cameras[block.images[i].camera].params[kFrameFocal];
  }
  frame.use_lever = options.lever_arm_m.has_value();
  if (frame.use_lever) frame.lever = *options.lever_arm_m;
  return frame;
}

Status Prepare(const TaylorBundleOptions& options, const BundleAdjustmentConfig& config,
               const Block& block, Plan* plan) {
  std::string why;
  if (!options.IsValid(&why)) return Status::Error("invalid options: " + why);
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(block));
  PHOTOPOSE_RETURN_IF_ERROR(CheckSupported(config, block));
  for (const BlockCamera& camera : block.cameras)
    if (!(camera.model != CameraModelType::kFrame || camera.params[kFrameFocal] > 0.0))
      return Status::Error("camera " + Quoted(camera.camera_id) + " has no positive focal length");
  return MakePlan(options, config, block, plan);
}

std::string MarkName(const Block& block, int m) {
  const BlockMark& mark = block.marks[m];
  return "point " + Quoted(block.points[mark.point].id) + " in image " +
         Quoted(block.images[mark.image].name);
}

std::string Format(const char* format, double a, double b = 0.0) {
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), format, a, b);
  return buffer;
}

// What one round needs besides its own structures.
struct Context {
  const TaylorBundleOptions& options;
  const Block& block;
  const Plan& plan;
  const Frame& frame;
  Clock::time_point start;
};

std::string PointName(const Block& block, int p) { return "point " + Quoted(block.points[p].id); }

std::string BehindMessage(const Block& block, const Normal& normal, const std::string& when) {
  std::ostringstream os;
  os << MarkName(block, normal.behind_mark) << ": the point is not in front of the camera " << when
     << " (w = " << normal.behind_w << " m)";
  return os.str();
}

// Gauss-Newton (eqs. 9-16) of one round from *state. On kConverged *state is the solution and
// *normal its linearisation; otherwise *message says why it stopped.
SolverTermination RunRound(const Context& ctx, int round, Layout* layout, State* state,
                           Normal* normal, Reduction* reduction, TaylorBundleResult* result,
                           std::string* message) {
  const TaylorBundleOptions& options = ctx.options;
  TaylorBundleSummary& summary = result->summary;
  const int redundancy = layout->num_observations - layout->num_unknowns;
  double max_norm = 0.0;
  for (const int i : layout->free_images)
    max_norm = std::max(max_norm, state->eo[i].head<3>().norm());
  for (const int p : layout->free_points) max_norm = std::max(max_norm, state->points[p].norm());
  const double position_tolerance_m =
      std::max(options.position_tolerance_m,
               kPositionResolutionFactor * kEpsilon * (ctx.frame.extent_m + max_norm));
  const double divergence_m =
      options.divergence_distance_factor * std::max(ctx.frame.extent_m, max_norm);

  if (!Linearize(options.partials, ctx.block, ctx.plan, *layout, ctx.frame, *state, normal,
                 nullptr)) {
    *message =
        normal->behind_mark >= 0
            ? BehindMessage(ctx.block, *normal, "at the start of round " + std::to_string(round))
            : "the residuals at the start are not finite";
    return SolverTermination::kFailure;
  }
  if (round == 1) summary.initial_cost = 0.5 * normal->weighted_ssr;
  summary.final_cost = 0.5 * normal->weighted_ssr;

  Eigen::VectorXd d_e;
  std::vector<Eigen::Vector3d> d_p;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    const Clock::time_point iteration_start = Clock::now();
    const double cost = 0.5 * normal->weighted_ssr;
    const std::string at = " at iteration " + std::to_string(iteration);
    const int singular_point = Reduce(*normal, *layout, reduction);
    if (singular_point >= 0) {
      *message = PointName(ctx.block, singular_point) +
                 " is not determined by its rays (its 3 x 3 normal block is singular)" + at;
      return SolverTermination::kFailure;
    }
    const int weightless = WriteScaled(ctx.plan, layout, reduction);
    if (weightless >= 0) {
      *message = "image " + Quoted(ctx.block.images[layout->free_images[weightless / 6]].name) +
                 ": parameter " + std::to_string(weightless % 6 + 1) +
                 " of its exterior orientation has no weight" + at;
      return SolverTermination::kFailure;
    }
    if (!Factorize(options.min_pivot_ratio, *layout, reduction)) {
      *message = Format("the reduced normal matrix is singular (pivot ratio %.3g)",
                        reduction->pivot_ratio) +
                 at +
                 ": a datum defect (too few control points and camera positions, or all on one "
                 "line) or an image its marks do not determine";
      return SolverTermination::kFailure;
    }
    SolveCorrections(ctx.plan, *layout, *normal, *reduction, &d_e, &d_p);
    // Eqs. 9-14: unknown = approximation - correction.
    double max_position = 0.0, max_angle = 0.0, step_squared = d_e.squaredNorm();
    for (size_t b = 0; b < layout->free_images.size(); ++b) {
      const Vector6d delta = d_e.segment<6>(6 * b);
      state->eo[layout->free_images[b]] -= delta;
      max_position = std::max(max_position, delta.head<3>().cwiseAbs().maxCoeff());
      max_angle = std::max(max_angle, delta.tail<3>().cwiseAbs().maxCoeff());
    }
    for (size_t q = 0; q < layout->free_points.size(); ++q) {
      state->points[layout->free_points[q]] -= d_p[q];
      max_position = std::max(max_position, d_p[q].cwiseAbs().maxCoeff());
      step_squared += d_p[q].squaredNorm();
    }
    summary.iterations += 1;
    summary.last_position_correction_m = max_position;
    summary.last_angle_correction_rad = max_angle;
    if (!std::isfinite(step_squared)) {
      *message = "the correction is not finite" + at;
      return SolverTermination::kFailure;
    }
    for (const int i : layout->free_images) {
      const double distance = state->eo[i].head<3>().norm();
      if (!(distance <= divergence_m)) {
        *message = "diverged" + at + ": image " + Quoted(ctx.block.images[i].name) +
                   Format(" moved %.3g m from the block's centroid", distance);
        return SolverTermination::kFailure;
      }
    }
    for (const int p : layout->free_points) {
      const double distance = state->points[p].norm();
      if (!(distance <= divergence_m)) {
        *message = "diverged" + at + ": " + PointName(ctx.block, p) +
                   Format(" moved %.3g m from the block's centroid", distance);
        return SolverTermination::kFailure;
      }
    }
    const bool converged =
        max_position <= position_tolerance_m && max_angle <= options.angle_tolerance_rad;
    if (!Linearize(options.partials, ctx.block, ctx.plan, *layout, ctx.frame, *state, normal,
                   nullptr)) {
      *message = normal->behind_mark >= 0
                     ? BehindMessage(ctx.block, *normal,
                                     "after iteration " + std::to_string(iteration) + " (diverged)")
                     : "the residuals are not finite after iteration " + std::to_string(iteration);
      return SolverTermination::kFailure;
    }
    summary.final_cost = 0.5 * normal->weighted_ssr;
    const double seconds = SecondsSince(iteration_start);
    summary.iteration_seconds += seconds;
    result->history.push_back({round, iteration, cost, max_position, max_angle, seconds});
    if (options.progress) {
      BundleIterationInfo info;
      info.round = round;
      info.iteration = iteration;
      info.cost = summary.final_cost;
      info.sigma0 = redundancy > 0 ? std::sqrt(normal->weighted_ssr / redundancy) : kNaN;
      info.step_norm = std::sqrt(step_squared);
      info.elapsed_seconds = SecondsSince(ctx.start);
      options.progress(info);
    }
    if (converged) {
      *message = Format("corrections below tolerance (%.3g m, %.3g rad)", max_position, max_angle);
      return SolverTermination::kConverged;
    }
  }
  std::ostringstream os;
  os << "no convergence in " << options.max_iterations << " iterations of round " << round
     << " (last correction " << summary.last_position_correction_m << " m, "
     << summary.last_angle_correction_rad << " rad)";
  *message = os.str();
  return SolverTermination::kNoConvergence;
}

// The blocks of S^-1 the statistics need, unscaled (the whitened system's inverse): per camera
// block its 6 x 6 diagonal block, and per free control point its 3 x 3 covariance
// V^-1 + sum_a sum_c Y_a^T C(a, c) Y_c (a, c over its marks in free images). Column block by
// column block through the sparse factorisation, so memory stays O(n).
void Covariances(const Block& block, const Plan& plan, const Layout& layout, const Normal& normal,
                 const Reduction& reduction, std::vector<Matrix6d>* cameras,
                 std::vector<Eigen::Matrix3d>* points, std::vector<char>* has_point) {
  const int num_blocks = static_cast<int>(layout.free_images.size());
  const int n = 6 * num_blocks;
  cameras->assign(num_blocks, Matrix6d::Zero());
  points->assign(layout.free_points.size(), Eigen::Matrix3d::Zero());
  has_point->assign(layout.free_points.size(), 0);
  std::vector<std::vector<std::pair<int, int>>> control_of_block(num_blocks);
  for (size_t q = 0; q < layout.free_points.size(); ++q) {
    if (block.points[layout.free_points[q]].role != PointRole::kControl) continue;
    (*points)[q] = reduction.V_inverse[q];
    (*has_point)[q] = 1;
    const std::vector<int>& marks = layout.point_marks[q];
    for (size_t c = 0; c < marks.size(); ++c)
      control_of_block[layout.mark_block[marks[c]]].emplace_back(static_cast<int>(q),
                                                                 static_cast<int>(c));
  }
  const Eigen::VectorXd& s = reduction.scale;
  Eigen::MatrixXd rhs(n, 6);
  for (int b = 0; b < num_blocks; ++b) {
    rhs.setZero();
    // A fixed component has a zero right-hand side and (being decoupled) a zero solution row:
    // its variance and covariances are zero.
    for (int c = 0; c < 6; ++c)
      if (!IsFixed(plan, layout, b, c)) rhs(6 * b + c, c) = s[6 * b + c];
    Eigen::MatrixXd X = reduction.ldlt.solve(rhs);
    X = s.asDiagonal() * X;  // C(:, b)
    (*cameras)[b] = X.middleRows<6>(6 * b);
    for (const auto& [q, c] : control_of_block[b]) {
      const std::vector<int>& marks = layout.point_marks[q];
      const Eigen::Matrix3d& V_inverse = reduction.V_inverse[q];
      const Matrix63 Y_c = normal.W[marks[c]] * V_inverse;
      for (const int ka : marks) {
        const Matrix6d C_ac = X.middleRows<6>(6 * layout.mark_block[ka]);
        const Matrix63 Y_a = normal.W[ka] * V_inverse;
        (*points)[q].noalias() += Y_a.transpose() * C_ac * Y_c;
      }
    }
  }
}

// BundleAdjust's summary, from the Taylor one (the single source of these numbers).
void FillBundleSummary(const TaylorBundleSummary& taylor, BundleAdjustmentSummary* out) {
  out->termination = taylor.termination_type;
  out->message = taylor.message;
  out->datum = taylor.datum;
  out->datum_description = taylor.datum_description;
  out->tie_points_left_out = taylor.tie_points_left_out;
  out->rounds = taylor.rounds;
  out->iterations = taylor.iterations;
  out->initial_cost = taylor.initial_cost;
  out->final_cost = taylor.final_cost;
  out->sigma0 = taylor.sigma0;
  out->redundancy = taylor.redundancy;
  out->num_images = taylor.num_images;
  out->num_points = taylor.num_points;
  out->num_marks = taylor.num_marks;
  out->num_rejected_marks = taylor.num_rejected_marks;
  out->time_seconds = taylor.time_seconds;
  out->statistics_seconds = taylor.statistics_seconds;
}

}  // namespace

bool TaylorBundleOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (partials != TaylorPartials::kCorrected && partials != TaylorPartials::kAsPrinted)
    return fail("partials is not a TaylorPartials value");
  // The accuracies are checked by the rule BundleAdjust applies to the same struct.
  BundleAdjustmentOptions objective;
  objective.accuracies = accuracies;
  std::string accuracy_why;
  if (!objective.IsValid(&accuracy_why)) return fail(accuracy_why);
  if (lever_arm_m && !lever_arm_m->allFinite()) return fail("the lever arm must be finite");
  if (!(rejection_threshold >= 0.0) || !std::isfinite(rejection_threshold))
    return fail("the rejection threshold must be >= 0 (0: no rejection)");
  if (max_rejection_rounds < 0) return fail("max_rejection_rounds must be >= 0");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (!positive(position_tolerance_m))
    return fail("position_tolerance_m must be positive and finite");
  if (!positive(angle_tolerance_rad))
    return fail("angle_tolerance_rad must be positive and finite");
  if (!(divergence_distance_factor > 1.0) || !std::isfinite(divergence_distance_factor))
    return fail("divergence_distance_factor must be finite and greater than 1");
  if (!(min_pivot_ratio >= 0.0 && min_pivot_ratio < 1.0))
    return fail("min_pivot_ratio must be in [0, 1)");
  if (max_covariance_parameters < 0) return fail("max_covariance_parameters must be >= 0");
  return true;
}

Status TaylorBundleOptionsFromBundleOptions(const BundleAdjustmentOptions& ceres,
                                            TaylorPartials partials, TaylorBundleOptions* options) {
  if (ceres.tie_loss != LossType::kNone) {
    return Status::Error(
        "the Taylor bundle adjustment is plain least squares: a robust tie loss is done by the "
        "Ceres adjustment");
  }
  if (ceres.estimate_lever_arm) {
    return Status::Error(
        "the Taylor bundle adjustment applies a given lever arm but does not estimate it");
  }
  *options = TaylorBundleOptions();
  options->partials = partials;
  options->accuracies = ceres.accuracies;
  options->lever_arm_m = ceres.lever_arm_m;
  options->rejection_threshold = ceres.rejection_threshold;
  options->max_rejection_rounds = ceres.max_rejection_rounds;
  options->max_covariance_parameters = ceres.max_covariance_parameters;
  options->progress = ceres.progress;
  return Status::Ok();
}

std::string TaylorBundleSummary::BriefReport() const {
  std::ostringstream os;
  os << "Taylor bundle adjustment (" << EnumName(partials) << " partials), "
     << EnumName(termination_type) << ": " << num_images << " images, "
     << num_points << " points, " << num_marks << " marks, " << rounds << " round"
     << (rounds == 1 ? "" : "s") << ", " << iterations << " iterations, cost " << initial_cost
     << " -> " << final_cost << ", sigma0 " << sigma0 << " (redundancy " << redundancy << ")";
  if (num_rejected_marks > 0) os << ", " << num_rejected_marks << " marks rejected";
  os << ", " << time_seconds << " s";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

bool TaylorBundleSummary::IsSolutionUsable() const {
  return termination_type == SolverTermination::kConverged;
}

bool TaylorMarkPartials(TaylorPartials partials, const ExteriorOrientation& eo,
                        const Eigen::Vector3d& point_in_ground, double focal_um,
                        const Eigen::Vector2d& observed_um, Eigen::Matrix<double, 2, 6>* d_eo,
                        Eigen::Matrix<double, 2, 3>* d_point, Eigen::Vector2d* f_um) {
  const TaylorPoseLinearization pose(partials, eo.data(), focal_um);
  double row_u[6], row_v[6], fu, fv, w;
  if (!pose.Linearize(point_in_ground.data(), observed_um.data(), row_u, row_v, &fu, &fv, &w))
    return false;
  if (d_eo != nullptr) {
    for (int c = 0; c < 6; ++c) {
      (*d_eo)(0, c) = row_u[c];
      (*d_eo)(1, c) = row_v[c];
    }
  }
  if (d_point != nullptr) PointPartialsFromCentrePartials(row_u, row_v, d_point);
  if (f_um != nullptr) *f_um = Eigen::Vector2d(fu, fv);
  return true;
}

Eigen::Vector3d TaylorAntennaPosition(const ExteriorOrientation& eo, const Eigen::Vector3d& lever_m,
                                      Eigen::Matrix3d* d_angles) {
  const double omega = eo.parameters[3];
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
  const Eigen::Vector3d offset = R.transpose() * lever_m;  // R^T l, ground frame
  if (d_angles != nullptr) {
    // d(R^T l) = (dR)^T l: dR = [a]x R gives -R^T (a x l); dR = R [e3]x gives -e3 x (R^T l).
    const Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
    const Eigen::Vector3d a(0.0, std::cos(omega), std::sin(omega));  // Rx(omega) e2
    d_angles->col(0) = -R.transpose() * e1.cross(lever_m);
    d_angles->col(1) = -R.transpose() * a.cross(lever_m);
    d_angles->col(2) = -Eigen::Vector3d::UnitZ().cross(offset);
  }
  return eo.center_in_ground() + offset;
}

Status LinearizeTaylorBundle(const TaylorBundleOptions& options,
                             const BundleAdjustmentConfig& config, const Block& input,
                             TaylorBundleLinearSystem* system) {
  CHECK(system != nullptr);
  *system = TaylorBundleLinearSystem();
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(input));
  Block block = input;
  block.BuildIndex();
  Plan plan;
  PHOTOPOSE_RETURN_IF_ERROR(Prepare(options, config, block, &plan));
  State state;
  const Frame frame = MakeFrame(options, block, plan, &state);
  Layout layout;
  BuildLayout(block, plan, &layout);

  DenseRows dense;
  dense.image_columns.assign(block.images.size(), -1);
  dense.point_columns.assign(block.points.size(), -1);
  for (const int i : layout.free_images) {
    dense.image_columns[i] = dense.num_columns;
    dense.num_columns += 6;
  }
  for (const int p : layout.free_points) {
    dense.point_columns[p] = dense.num_columns;
    dense.num_columns += 3;
  }
  Normal normal;
  if (!Linearize(options.partials, block, plan, layout, frame, state, &normal, &dense)) {
    return Status::Error(normal.behind_mark >= 0 ? BehindMessage(block, normal, "")
                                                 : "the residuals are not finite");
  }
  system->image_columns = dense.image_columns;
  system->point_columns = dense.point_columns;
  system->jacobian.resize(static_cast<int>(dense.rows.size()), dense.num_columns);
  system->residual.resize(static_cast<int>(dense.rows.size()));
  for (size_t row = 0; row < dense.rows.size(); ++row) {
    system->jacobian.row(row) = dense.rows[row].transpose();
    system->residual[row] = dense.residuals[row];
  }
  for (size_t b = 0; b < layout.free_images.size(); ++b)
    for (int c = 0; c < 6; ++c)
      if (IsFixed(plan, layout, static_cast<int>(b), c))
        system->jacobian.col(dense.image_columns[layout.free_images[b]] + c).setZero();

  Reduction reduction;
  const int singular_point = Reduce(normal, layout, &reduction);
  if (singular_point >= 0)
    return Status::Error(PointName(block, singular_point) + " is not determined by its rays");
  if (WriteScaled(plan, &layout, &reduction) >= 0)
    return Status::Error("an exterior-orientation parameter has no weight");
  const int n = 6 * static_cast<int>(layout.free_images.size());
  system->reduced_matrix = Eigen::MatrixXd::Zero(n, n);
  for (size_t k = 0; k < layout.pairs.size(); ++k) {
    const auto [b1, b2] = layout.pairs[k];
    system->reduced_matrix.block<6, 6>(6 * b1, 6 * b2) = reduction.blocks[k];
    system->reduced_matrix.block<6, 6>(6 * b2, 6 * b1) = reduction.blocks[k].transpose();
  }
  system->reduced_rhs = reduction.r;
  for (size_t b = 0; b < layout.free_images.size(); ++b) {
    for (int c = 0; c < 6; ++c) {
      if (!IsFixed(plan, layout, static_cast<int>(b), c)) continue;
      const int column = 6 * static_cast<int>(b) + c;
      system->reduced_matrix.row(column).setZero();
      system->reduced_matrix.col(column).setZero();
      system->reduced_matrix(column, column) = 1.0;
      system->reduced_rhs[column] = 0.0;
    }
  }
  if (!Factorize(options.min_pivot_ratio, layout, &reduction))
    return Status::Error(
        Format("the reduced normal matrix is singular (pivot ratio %.3g)", reduction.pivot_ratio));
  Eigen::VectorXd d_e;
  std::vector<Eigen::Vector3d> d_p;
  SolveCorrections(plan, layout, normal, reduction, &d_e, &d_p);
  system->correction.resize(dense.num_columns);
  for (size_t b = 0; b < layout.free_images.size(); ++b)
    system->correction.segment<6>(dense.image_columns[layout.free_images[b]]) =
        d_e.segment<6>(6 * b);
  for (size_t q = 0; q < layout.free_points.size(); ++q)
    system->correction.segment<3>(dense.point_columns[layout.free_points[q]]) = d_p[q];
  return Status::Ok();
}

Status TaylorBundleAdjust(const TaylorBundleOptions& options, const BundleAdjustmentConfig& config,
                          Block* block, TaylorBundleResult* result) {
  CHECK(block != nullptr);
  CHECK(result != nullptr);
  const Clock::time_point start = Clock::now();
  *result = TaylorBundleResult();
  TaylorBundleSummary& summary = result->summary;
  summary.partials = options.partials;
  summary.sigma0 = kNaN;
  auto refuse = [&](const Status& status) {
    summary.message = status.message();
    summary.time_seconds = SecondsSince(start);
    FillBundleSummary(summary, &result->adjustment.summary);
    return status;
  };
  const Status checked = CheckBlock(*block);
  if (!checked.ok()) return refuse(checked);
  block->BuildIndex();
  Plan plan;
  const Status prepared = Prepare(options, config, *block, &plan);
  if (!prepared.ok()) return refuse(prepared);
  summary.datum = plan.datum;
  summary.datum_description = plan.datum_description;
  summary.tie_points_left_out = plan.tie_points_left_out;
  summary.message.clear();

  State state;
  const Frame frame = MakeFrame(options, *block, plan, &state);
  const Context context{options, *block, plan, frame, start};
  BundleAdjustmentResult& out = result->adjustment;
  auto finish = [&](SolverTermination type, const std::string& message) {
    summary.termination_type = type;
    summary.message = message;
    summary.time_seconds = SecondsSince(start);
    FillBundleSummary(summary, &out.summary);
    return Status::Ok();
  };

  // Rounds: adjust, reject the marks beyond the threshold, adjust again.
  Layout layout;
  Normal normal;
  std::unique_ptr<Reduction> reduction;
  const int max_rounds = options.rejection_threshold > 0.0 ? options.max_rejection_rounds + 1 : 1;
  for (int round = 1; round <= max_rounds; ++round) {
    BuildLayout(*block, plan, &layout);
    summary.rounds = round;
    summary.redundancy = layout.num_observations - layout.num_unknowns;
    summary.num_images = static_cast<int>(block->images.size());
    summary.num_marks = static_cast<int>(layout.marks.size());
    summary.num_points =
        static_cast<int>(std::count(plan.point_in_problem.begin(), plan.point_in_problem.end(), 1));
    summary.num_camera_unknowns =
        layout.num_unknowns - 3 * static_cast<int>(layout.free_points.size());
    summary.reduced_nonzeros = static_cast<int>(layout.S.nonZeros());
    reduction = std::make_unique<Reduction>();
    std::string message;
    const SolverTermination type =
        RunRound(context, round, &layout, &state, &normal, reduction.get(), result, &message);
    if (type != SolverTermination::kConverged) {
      summary.sigma0 = kNaN;
      return finish(type, "round " + std::to_string(round) + ": " + message);
    }
    summary.message = message;
    summary.sigma0 =
        summary.redundancy > 0 ? std::sqrt(normal.weighted_ssr / summary.redundancy) : kNaN;
    if (round == max_rounds) break;
    // Reject the marks beyond the threshold (in units of sigma0, never below the stated sigma).
    const double limit = options.rejection_threshold * std::max(1.0, summary.sigma0);
    // One mark per point and round, its worst (as BundleAdjust does: a blunder raises the other
    // marks of its track too).
    std::vector<int> worst_of_point(block->points.size(), -1);
    std::vector<double> worst_whitened(block->points.size(), 0.0);
    for (size_t k = 0; k < layout.marks.size(); ++k) {
      const int m = layout.marks[k];
      const double whitened = normal.f[k].norm() / plan.mark_sigma[m];
      if (!(whitened > limit)) continue;
      const int p = block->marks[m].point;
      if (worst_of_point[p] < 0 || whitened > worst_whitened[p]) {
        worst_of_point[p] = m;
        worst_whitened[p] = whitened;
      }
    }
    int rejected = 0;
    for (size_t p = 0; p < worst_of_point.size(); ++p) {
      const int m = worst_of_point[p];
      if (m < 0) continue;
      plan.mark_used[m] = 0;
      out.rejected_marks.push_back({m, round, worst_whitened[p] / summary.sigma0});
      ++rejected;
    }
    if (rejected == 0) break;
    DropSingleRayTiePoints(*block, &plan);
    int count = 0;
    const int weak = ImageWithTooFewMarks(*block, plan, &count);
    if (weak >= 0) {
      return finish(SolverTermination::kFailure,
                    "after rejecting " + std::to_string(out.rejected_marks.size()) +
                        " marks as blunders, image " + Quoted(block->images[weak].name) +
                        " keeps " + std::to_string(count) + " marks: too few to orient it");
    }
  }
  summary.num_rejected_marks = static_cast<int>(out.rejected_marks.size());

  // ------------------------------------------------------------ statistics at the solution
  const Clock::time_point statistics_start = Clock::now();
  const double variance_factor =
      std::isfinite(summary.sigma0) ? summary.sigma0 * summary.sigma0 : 1.0;
  const size_t num_images = block->images.size();
  out.images.assign(num_images, BundleImageResult());
  out.points.assign(block->points.size(), BundlePointResult());
  out.mark_residuals.assign(block->marks.size(), Eigen::Vector2d::Constant(kNaN));

  // Marks: observed - computed = -F, in the mark's own unit.
  std::vector<double> image_ssq(num_images, 0.0);
  for (size_t k = 0; k < layout.marks.size(); ++k) {
    const BlockMark& mark = block->marks[layout.marks[k]];
    const Eigen::Vector2d residual = -normal.f[k] / mark.observation_units_per_unit;
    out.mark_residuals[layout.marks[k]] = residual;
    BundleImageResult& image = out.images[mark.image];
    ++image.num_marks;
    image_ssq[mark.image] += residual.squaredNorm();
    image.unit = EnumName(mark.unit);
    ++out.points[mark.point].num_observations;
  }
  for (size_t i = 0; i < num_images; ++i) {
    BundleImageResult& image = out.images[i];
    image.adjusted = true;
    image.rms_residual = image.num_marks > 0 ? std::sqrt(image_ssq[i] / image.num_marks) : 0.0;
  }

  // Covariances from the reduced normal matrix at the solution.
  const int num_blocks = static_cast<int>(layout.free_images.size());
  bool covariance = 6 * num_blocks <= options.max_covariance_parameters;
  if (covariance) {
    covariance = Reduce(normal, layout, reduction.get()) < 0 &&
                 WriteScaled(plan, &layout, reduction.get()) < 0 &&
                 Factorize(options.min_pivot_ratio, layout, reduction.get());
    if (!covariance)
      summary.message += "; the normal matrix at the solution is singular: no covariances";
  } else {
    summary.message += "; covariances skipped (more than " +
                       std::to_string(options.max_covariance_parameters) + " camera unknowns)";
  }
  if (covariance) {
    std::vector<Matrix6d> cameras;
    std::vector<Eigen::Matrix3d> points;
    std::vector<char> has_point;
    Covariances(*block, plan, layout, normal, *reduction, &cameras, &points, &has_point);
    for (int b = 0; b < num_blocks; ++b) {
      BundleImageResult& image = out.images[layout.free_images[b]];
      image.covariance = variance_factor * cameras[b];
      image.has_covariance = true;
    }
    for (size_t q = 0; q < layout.free_points.size(); ++q) {
      if (!has_point[q]) continue;
      BundlePointResult& point = out.points[layout.free_points[q]];
      point.covariance = variance_factor * points[q];
      point.has_covariance = true;
    }
  }

  // The adjusted values, back in the ground frame, written into the block.
  for (size_t i = 0; i < num_images; ++i) {
    ExteriorOrientation eo;
    eo.parameters = state.eo[i];
    eo.parameters.head<3>() += frame.centroid;
    for (int k = 3; k < 6; ++k) eo.parameters[k] = WrapAngle(eo.parameters[k]);
    block->images[i].eo = eo;
  }
  for (size_t p = 0; p < block->points.size(); ++p)
    if (plan.point_in_problem[p]) block->points[p].position_m = state.points[p] + frame.centroid;

  // Control points: adjusted - surveyed. Check points: intersected from the adjusted images as
  // BundleAdjust does, so both solvers are measured with one yardstick.
  for (size_t p = 0; p < block->points.size(); ++p)
    if (block->points[p].role == PointRole::kControl && plan.point_in_problem[p])
      out.points[p].error_m = *block->points[p].position_m - *block->points[p].surveyed_m;
  TabulateControlAndCheckPoints(*block, options.accuracies, variance_factor, &out);
  if (frame.use_lever) out.lever_arm_m = frame.lever;
  summary.statistics_seconds = SecondsSince(statistics_start);
  return finish(SolverTermination::kConverged, summary.message);
}

Status BundleAdjustWithSolver(PoseSolver solver, const BundleAdjustmentOptions& options,
                              const BundleAdjustmentConfig& config, Block* block,
                              BundleAdjustmentResult* result, TaylorBundleResult* taylor_result) {
  CHECK(result != nullptr);
  if (solver == PoseSolver::kCeres) return BundleAdjust(options, config, block, result);
  TaylorBundleOptions taylor_options;
  const TaylorPartials partials = solver == PoseSolver::kTaylorAsPrinted
                                      ? TaylorPartials::kAsPrinted
                                      : TaylorPartials::kCorrected;
  PHOTOPOSE_RETURN_IF_ERROR(
      TaylorBundleOptionsFromBundleOptions(options, partials, &taylor_options));
  TaylorBundleResult local;
  TaylorBundleResult& taylor = taylor_result != nullptr ? *taylor_result : local;
  const Status status = TaylorBundleAdjust(taylor_options, config, block, &taylor);
  *result = taylor.adjustment;
  return status;
}

}  // namespace photopose
