// The normal equations of the Taylor bundle adjustment (internal/taylor_normals.h): layout,
// linearisation, elimination of the points, factorisation. One file past ~800 lines on purpose:
// the one stage of the Taylor solver that touches every mark, each step a named function over the
// same layout (internal/taylor_normals.h), so that its memory per mark is visible in one place.
#include <ceres/jet.h>
#include <glog/logging.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "core/camera_models.h"
#include "core/parallel.h"
#include "core/rotation.h"
#include "solvers/bundle/internal/taylor_normals.h"
#include "solvers/resection/taylor_resection.h"

namespace photopose::internal::taylor {
namespace {

// A point's 3 x 3 normal block is singular (its rays meet at no definite point) when its smallest
// LDL^T pivot is at most this fraction of the largest.
constexpr double kPointPivotRatio = 1e-14;

// ------------------------------------------------------------------ one round's structure

int TriangleIndex(int a, int c, int n) { return a * n - a * (a - 1) / 2 + (c - a); }

// Renumbers the camera blocks in a fill-reducing order: approximate minimum degree on the image
// graph (images joined when they see a common point that is an unknown). Each image's 6 x 6 block
// of S is dense, so ordering images rather than scalars loses nothing (Ceres orders its Schur
// complement the same way), and the sparse LDL^T then runs in the natural order: the scalar AMD
// of a dense-ish S would cost more than a whole Gauss-Newton iteration.
void OrderImagesToReduceFill(const Block& block, const Plan& plan, Layout* layout) {
  const int num_blocks = static_cast<int>(layout->free_images.size());
  if (num_blocks < 3) return;
  // The graph's pattern: every two camera blocks that see a common free point, each pair once.
  // Taken image by image (a stamp per block marks the neighbours found), so the graph is made
  // from its ~100 neighbours per image; a triplet per pair of every point's images (the sum of
  // n^2 over the points: 27 million at 1000 images) held 0.8 GB for a second before the first
  // round. AMD reads only the pattern, so the order is the same.
  std::vector<Eigen::Triplet<double, int>> entries;
  std::vector<int> stamp(num_blocks, -1);
  for (size_t i = 0; i < block.images.size(); ++i) {
    const int b1 = layout->image_block[i];
    if (b1 < 0) continue;
    for (const int m : block.marks_of_image[i]) {
      const int p = block.marks[m].point;
      if (!plan.mark_used[m] || !plan.point_in_problem[p] || plan.point_constant[p]) continue;
      for (const int m2 : block.marks_of_point[p]) {
        const int b2 = layout->image_block[block.marks[m2].image];
        if (!plan.mark_used[m2] || b2 < 0 || stamp[b2] == b1) continue;
        stamp[b2] = b1;
        entries.emplace_back(b1, b2, 1.0);
      }
    }
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

// The camera blocks: every image whose pose is an unknown, in a fill-reducing order; six columns
// each, less the fixed components.
void NumberFreeImages(const Block& block, const Plan& plan, Layout* layout) {
  layout->image_block.assign(block.images.size(), -1);
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (plan.image_constant[i]) continue;
    layout->image_block[i] = static_cast<int>(layout->free_images.size());
    layout->free_images.push_back(static_cast<int>(i));
    layout->num_unknowns += 6;
    for (const bool fixed : plan.image_fixed[i]) layout->num_unknowns -= fixed;
  }
  OrderImagesToReduceFill(block, plan, layout);
}

// The global columns, after the camera blocks: each self-calibrated camera's parameters, then the
// lever arm.
void NumberGlobalColumns(const Block& block, const Plan& plan, Layout* layout) {
  layout->camera_global.assign(block.cameras.size(), -1);
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    if (plan.calibrated[c].empty()) continue;
    layout->camera_global[c] = layout->num_global;
    for (const int index : plan.calibrated[c]) {
      layout->global_camera.push_back(static_cast<int>(c));
      layout->global_param.push_back(index);
    }
    layout->num_global += static_cast<int>(plan.calibrated[c].size());
  }
  if (plan.estimate_lever) {
    layout->lever_global = layout->num_global;
    for (int axis = 0; axis < 3; ++axis) {
      layout->global_camera.push_back(-1);
      layout->global_param.push_back(axis);
    }
    layout->num_global += 3;
  }
  layout->num_unknowns += layout->num_global;
}

// The free points in the order of their first camera block (in the fill-reducing order), so that
// points eliminated one after another share images: their blocks of S stay in the cache. Counts
// the points' and images' prior rows.
void NumberFreePoints(const Block& block, const Plan& plan, Layout* layout) {
  layout->point_block.assign(block.points.size(), -1);
  std::vector<int> first_block(block.points.size(), std::numeric_limits<int>::max());
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const int b = layout->image_block[block.marks[m].image];
    int& first = first_block[block.marks[m].point];
    if (plan.mark_used[m] && b >= 0) first = std::min(first, b);
  }
  std::vector<int> points;
  for (size_t p = 0; p < block.points.size(); ++p)
    if (plan.point_in_problem[p] && !plan.point_constant[p]) points.push_back(static_cast<int>(p));
  std::stable_sort(points.begin(), points.end(),
                   [&](int a, int b) { return first_block[a] < first_block[b]; });
  for (const int p : points) {
    layout->point_block[p] = static_cast<int>(layout->free_points.size());
    layout->free_points.push_back(p);
    layout->num_unknowns += 3;
    if (plan.point_prior[p]) layout->num_observations += 3;
  }
  for (size_t i = 0; i < block.images.size(); ++i)
    layout->num_observations += ImagePriorRows(plan, i) + 3 * plan.image_attitude[i];
}

// The marks of the round and their lists per point and per image, in two passes over the marks:
// each list's length, then its entries.
void ListMarks(const Block& block, const Plan& plan, Layout* layout) {
  layout->point_marks.Reset(layout->free_points.size());
  layout->point_all_marks.Reset(layout->free_points.size());
  layout->image_marks.Reset(block.images.size());
  for (int pass = 0; pass < 2; ++pass) {
    size_t num_used = 0;
    for (size_t m = 0; m < block.marks.size(); ++m) {
      if (!plan.mark_used[m]) continue;
      const int image = block.marks[m].image;
      const int b = layout->image_block[image];
      const int q = layout->point_block[block.marks[m].point];
      if (pass == 0) {
        ++num_used;
        layout->image_marks.Count(image);
        if (q >= 0) layout->point_all_marks.Count(q);
        if (q >= 0 && b >= 0) layout->point_marks.Count(q);
        continue;
      }
      const int k = static_cast<int>(layout->marks.size());
      layout->marks.push_back(static_cast<int>(m));
      layout->num_observations += 2;
      layout->mark_block.push_back(b);
      layout->mark_point.push_back(q);
      layout->image_marks.Add(image, k);
      if (q >= 0) layout->point_all_marks.Add(q, k);
      if (q >= 0 && b >= 0) layout->point_marks.Add(q, k);
    }
    if (pass == 0) {
      layout->marks.reserve(num_used);
      layout->mark_block.reserve(num_used);
      layout->mark_point.reserve(num_used);
      layout->image_marks.Allocate();
      layout->point_all_marks.Allocate();
      layout->point_marks.Allocate();
    }
  }
  layout->image_marks.Finish();
  layout->point_all_marks.Finish();
  layout->point_marks.Finish();
  layout->point_mark_inputs.reserve(layout->marks.size());
  for (size_t q = 0; q < layout->point_all_marks.size(); ++q)
    for (const int k : layout->point_all_marks[q])
      layout->point_mark_inputs.push_back(MarkInputOf(block, plan, layout->marks[k]));
  if (!KeepsMarkW(layout->point_mark_inputs.size())) return;
  layout->point_position.assign(layout->marks.size(), -1);
  for (size_t q = 0; q < layout->point_all_marks.size(); ++q) {
    int position = static_cast<int>(layout->point_all_marks.Offset(q));
    for (const int k : layout->point_all_marks[q]) layout->point_position[k] = position++;
  }
}

// Chunks of the free points of about equal elimination work (a point's is about n^2 for its n
// marks).
void SplitPointsIntoChunks(Layout* layout) {
  double total_work = 0.0;
  for (size_t q = 0; q < layout->point_marks.size(); ++q)
    total_work += 1.0 + static_cast<double>(layout->point_marks[q].size()) *
                            layout->point_marks[q].size();
  layout->chunk_start.assign(1, 0);
  double work = 0.0;
  for (size_t q = 0; q < layout->point_marks.size(); ++q) {
    const int chunk = static_cast<int>(layout->chunk_start.size());
    if (chunk < kReductionChunks && work >= total_work * chunk / kReductionChunks)
      layout->chunk_start.push_back(static_cast<int>(q));
    work +=
        1.0 + static_cast<double>(layout->point_marks[q].size()) * layout->point_marks[q].size();
  }
  while (static_cast<int>(layout->chunk_start.size()) <= kReductionChunks)
    layout->chunk_start.push_back(static_cast<int>(layout->free_points.size()));
}

// Block pairs: the diagonal, and every two images that see a common free point; per free point
// the pair of each two of its marks.
void ListBlockPairs(Layout* layout) {
  std::unordered_map<long long, int> pair_index;
  const long long num_blocks = static_cast<long long>(layout->free_images.size());
  auto pair_of = [&](int b1, int b2) {
    if (b1 > b2) std::swap(b1, b2);
    // try_emplace: no node made for a pair already listed (most of the sum of n^2 over points).
    const auto [it, inserted] =
        pair_index.try_emplace(b1 * num_blocks + b2, static_cast<int>(layout->pairs.size()));
    if (inserted) layout->pairs.emplace_back(b1, b2);
    return it->second;
  };
  for (int b = 0; b < static_cast<int>(num_blocks); ++b)
    layout->diagonal_pair.push_back(pair_of(b, b));
  layout->point_pairs.Reset(layout->free_points.size());
  for (size_t q = 0; q < layout->free_points.size(); ++q) {
    const int n = static_cast<int>(layout->point_marks[q].size());
    layout->point_pairs.Count(q, n * (n + 1) / 2);
  }
  layout->point_pairs.Allocate();
  layout->point_pairs.Finish();
  for (size_t q = 0; q < layout->free_points.size(); ++q) {
    const IndexLists::List marks = layout->point_marks[q];
    const int n = static_cast<int>(marks.size());
    int* ids = layout->point_pairs.Entries(q);
    for (int a = 0; a < n; ++a)
      for (int c = a; c < n; ++c)
        ids[TriangleIndex(a, c, n)] =
            pair_of(layout->mark_block[marks[a]], layout->mark_block[marks[c]]);
  }
}

// The sparse pattern of S (upper triangle) and where each block's columns start in it. The global
// columns are dense: column 6 B + j holds rows 0 .. 6 B + j, in order.
void BuildPattern(Layout* layout) {
  const int cameras_size = 6 * static_cast<int>(layout->free_images.size());
  const int size = cameras_size + layout->num_global;
  std::vector<Eigen::Triplet<double, int>> entries;
  for (const auto& [b1, b2] : layout->pairs)
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < (b1 == b2 ? c + 1 : 6); ++r)
        entries.emplace_back(6 * b1 + r, 6 * b2 + c, 1.0);
  for (int column = cameras_size; column < size; ++column)
    for (int r = 0; r <= column; ++r) entries.emplace_back(r, column, 1.0);
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

}  // namespace

void BuildLayout(const Block& block, const Plan& plan, Layout* layout) {
  *layout = Layout();
  NumberFreeImages(block, plan, layout);
  NumberGlobalColumns(block, plan, layout);
  NumberFreePoints(block, plan, layout);
  ListMarks(block, plan, layout);
  SplitPointsIntoChunks(layout);
  ListBlockPairs(layout);
  BuildPattern(layout);
}

// ------------------------------------------------------------------ the linearisation

namespace {

// A mark's share of the cost, 1/2 of it: s = |F|^2 / sigma^2, or rho(s) for a tie mark under the
// robust loss; *weight_factor (when not null) its IRLS factor rho'(s) (1 without a loss). At a
// fixed point of the reweighted normal equations sum_m rho'(s_m) A_m^T F_m / sigma_m^2 = 0 (plus
// the priors): the gradient of the robust cost, so the minimum is Ceres'.
double MarkCost(const Plan& plan, int m, double s, double* weight_factor) {
  if (plan.tie_loss == nullptr || plan.mark_group[m] != kTieMarks) {
    if (weight_factor != nullptr) *weight_factor = 1.0;
    return s;
  }
  double rho[3];
  plan.tie_loss->Evaluate(s, rho);
  if (weight_factor != nullptr) *weight_factor = rho[1];
  return rho[0];
}

// A mark's equation through its camera's model (core/camera_models.h CameraModelResidual, r =
// observed - computed) at the ray's normalised coordinates (a, b) = (fu, fv) and its camera's
// current parameters: F = -r. With row_u, the rows of (a, b) in row_u, row_v become
// -dr/d(a, b) times them (a 2-derivative Jet); with calib_u too, calib_u, calib_v receive
// -dr/d(the estimated parameters, in `estimated` order) (a Jet with a derivative per parameter).
template <int kDerivatives>
void ModelEquationRows(const BlockCamera& camera, const double* params,
                       const std::vector<int>& estimated, const double* observation,
                       double* row_u, double* row_v, double* fu, double* fv, double* calib_u,
                       double* calib_v) {
  using Jet = ceres::Jet<double, kDerivatives>;
  const Jet ab[2] = {Jet(*fu, 0), Jet(*fv, 1)};
  Jet p[kMaxCameraModelParams];
  for (size_t k = 0; k < camera.params.size(); ++k) p[k] = Jet(params[k]);
  if (calib_u != nullptr)
    for (size_t j = 0; j < estimated.size(); ++j) p[estimated[j]].v[2 + j] = 1.0;
  Jet residual[2];
  CameraModelResidual(camera.model, p, ab, observation, camera.data(), residual);
  *fu = -residual[0].a;
  *fv = -residual[1].a;
  for (int c = 0; c < 6; ++c) {
    const double u = row_u[c], v = row_v[c];
    row_u[c] = -(residual[0].v[0] * u + residual[0].v[1] * v);
    row_v[c] = -(residual[1].v[0] * u + residual[1].v[1] * v);
  }
  if (calib_u != nullptr) {
    for (size_t j = 0; j < estimated.size(); ++j) {
      calib_u[j] = -residual[0].v[2 + j];
      calib_v[j] = -residual[1].v[2 + j];
    }
  }
}

// One mark's observation equation at the pose of its image, in the seed's sign (eqs. 7-8:
// F = computed - observed, p = p0 - d) and the camera model's unit (um for kFrame, pixels for a
// forward model), with, when row_u is not null, its rows dF/d(X0, Y0, Z0, omega, phi, kappa), and
// when calib_u is not null too, its rows dF/d(the camera's estimated parameters, plan.calibrated
// order). False when the point is not in front of the camera (*w_m: its w).
//   kFrame with fixed interior orientation: c (a, b) against the mark's ideal film point
//   (eqs. 17-28).
//   Through the camera's model (Frame::model_camera: the forward models, and a self-calibrated
//   kFrame camera): the pose's equation is written with c = 1 against the observation 0, so
//   F0 = (a, b), the ray's normalised coordinates, and rows0 = d(a, b)/dp; the mark's equation is
//   F = -r(a, b; calibration), r the residual "observed - computed" of the one model
//   (ModelEquationRows); its rows -J rows0 with J = dr/d(a, b), and the calibration's -dr/dk by
//   the same Jet. For kFrame, r = ideal(observation; k) - c (a, b): F = c (a, b) - ideal, whose
//   rows are the lecture's at c, and dF/dc = a, dF/dk = -d ideal/dk for the film correction's k.
bool MarkEquation(const TaylorPoseLinearization& pose, const Block& block, const Plan& plan,
                  const Frame& frame, const State& state, const MarkInput& input, int point_index,
                  double* row_u, double* row_v, double* fu, double* fv, double* w_m,
                  double* calib_u = nullptr, double* calib_v = nullptr) {
  const double* point = state.points[point_index].data();
  const bool in_front = row_u != nullptr
                            ? pose.Linearize(point, input.ideal_um, row_u, row_v, fu, fv, w_m)
                            : pose.Residual(point, input.ideal_um, fu, fv, w_m);
  const BlockCamera* camera = frame.model_camera[input.image];
  if (!in_front || camera == nullptr) return in_front;
  const BlockMark& mark = block.marks[input.m];
  const int c = frame.camera_index[input.image];
  const double* params = state.cameras[c].data();
  if (row_u == nullptr) {
    const double ab[2] = {*fu, *fv};
    double residual[2];
    CameraModelResidual(camera->model, params, ab, mark.observation.data(), camera->data(),
                        residual);
    *fu = -residual[0];
    *fv = -residual[1];
  } else if (calib_u != nullptr && !plan.calibrated[c].empty()) {
    ModelEquationRows<2 + kMaxCameraModelParams>(*camera, params, plan.calibrated[c],
                                                 mark.observation.data(), row_u, row_v, fu, fv,
                                                 calib_u, calib_v);
  } else {
    ModelEquationRows<2>(*camera, params, plan.calibrated[c], mark.observation.data(), row_u,
                         row_v, fu, fv, nullptr, nullptr);
  }
  return std::isfinite(*fu) && std::isfinite(*fv);
}

// The global column of mark k's camera's first estimated parameter, or -1.
int MarkGlobal(const Block& block, const Layout& layout, const Frame& frame, int k) {
  return layout.camera_global[frame.camera_index[block.marks[layout.marks[k]].image]];
}

// One image's share of its marks' normal equations, beside what LinearizeImageMarks writes into
// Normal directly.
struct ImageMarkSums {
  double ssr = 0.0;       // the marks' weighted sum of squares (their cost, MarkCost)
  int behind = -1;        // the first mark whose point is not in front of the camera, or -1
  double behind_w = 0.0;  // its w
  // A self-calibrated camera's image: its marks' share of the calibration's block and right-hand
  // side, and the weight of their rows (empty, 0 otherwise).
  Eigen::MatrixXd Ugg;
  Eigen::VectorXd gg;
  double weight = 0.0;
};

// Image i's marks (eqs. 7-8 with eqs. 17-28 for the camera, dF/dX = -dF/dX0 for the point, the
// model's calibration rows: MarkRowsAt at normal->at): its camera sums U, g_e and their coupling
// with the calibration into `normal`, the rest into `sums`. The marks' rows are not kept: the
// points' sums, the elimination and the back-substitution make them again, or, in a small block
// without global unknowns, read the W and g_p share this pass keeps (LinearizationPoint::kept_W,
// kept_gp: each mark's own entry, so images on other threads write elsewhere).
void LinearizeImageMarks(const Layout& layout, size_t i, Normal* normal, ImageMarkSums* sums) {
  const LinearizationPoint& at = normal->at;
  const bool keep = !at.kept_gp.empty();
  const int b = layout.image_block[i];
  const int camera = at.frame->camera_index[i];
  const int global = layout.camera_global[camera];
  const int K = global >= 0 ? static_cast<int>(at.plan->calibrated[camera].size()) : 0;
  Matrix6d U = Matrix6d::Zero();
  Vector6d ge = Vector6d::Zero();
  Eigen::Matrix<double, 6, Eigen::Dynamic> Ueg =
      Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, K);
  Eigen::MatrixXd Ugg = Eigen::MatrixXd::Zero(K, K);
  Eigen::VectorXd gg = Eigen::VectorXd::Zero(K);
  Eigen::Matrix<double, 2, Eigen::Dynamic> A_g(2, K);
  double ssr = 0.0, weight_rows = 0.0;
  MarkRows rows;
  for (const int k : layout.image_marks[i]) {
    const int m = layout.marks[k];
    if (!MarkRowsAt(at, MarkInputOf(*at.block, *at.plan, m), at.block->marks[m].point, &rows)) {
      sums->behind = m;
      sums->behind_w = rows.w_m;
      return;
    }
    ssr += rows.cost;
    if (keep && layout.point_position[k] >= 0) {
      normal->at.kept_W[layout.point_position[k]] = MarkW(rows);
      normal->at.kept_gp[layout.point_position[k]] = MarkGp(rows);
    }
    const Eigen::Matrix<double, 6, 2> weighted_Ae_T = rows.weight * rows.A_e.transpose();
    if (b >= 0) {
      U.noalias() += weighted_Ae_T * rows.A_e;
      ge.noalias() += weighted_Ae_T * rows.f;
    }
    if (K > 0) {
      MarkCalibrationRows(rows, &A_g);
      if (b >= 0) Ueg.noalias() += weighted_Ae_T * A_g;
      Ugg.noalias() += rows.weight * A_g.transpose() * A_g;
      gg.noalias() += rows.weight * A_g.transpose() * rows.f;
      weight_rows += 2.0 * rows.weight;
    }
  }
  if (b >= 0) {
    normal->U[b] = U;
    normal->ge[b] = ge;
    if (K > 0) normal->Ueg[b].middleCols(global, K) = Ueg;
  }
  if (K > 0) {
    sums->Ugg = std::move(Ugg);
    sums->gg = std::move(gg);
    sums->weight = weight_rows;
  }
  sums->ssr = ssr;
}

// The calibration's own sums in image order, and the size measure of its corrections.
void AddCalibrationSums(const Block& block, const Layout& layout, const Frame& frame,
                        const State& state, const std::vector<ImageMarkSums>& sums,
                        Normal* normal) {
  std::vector<double> camera_weight(block.cameras.size(), 0.0);
  for (size_t i = 0; i < sums.size(); ++i) {
    const int c = frame.camera_index[i];
    const int global = layout.camera_global[c];
    if (global < 0 || sums[i].Ugg.size() == 0) continue;
    const int K = static_cast<int>(sums[i].gg.size());
    normal->Ugg.block(global, global, K, K) += sums[i].Ugg;
    normal->gg.segment(global, K) += sums[i].gg;
    camera_weight[c] += sums[i].weight;
  }
  for (int j = 0; j < layout.num_global; ++j) {
    const int c = layout.global_camera[j];
    if (c < 0) continue;
    const double focal = CameraModelFocal(block.cameras[c].model, state.cameras[c].data());
    normal->global_angle_per_unit[j] =
        camera_weight[c] > 0.0 ? std::sqrt(normal->Ugg(j, j) / camera_weight[c]) / focal : 0.0;
  }
}

// Mark m's rows made again at the point where Linearize succeeded (so MarkRowsAt cannot fail:
// the same function of the same copy of the state).
void RowsAgain(const LinearizationPoint& at, const MarkInput& input, int point, MarkRows* rows) {
  CHECK(MarkRowsAt(at, input, point, rows))
      << "mark " << input.m << " failed where its linearisation succeeded";
}

// The W of the mark whose input is `input`, an entry of layout.point_mark_inputs (`point` its
// point): kept by Linearize (LinearizationPoint::kept_W), or made again from its rows (*rows: the
// caller's storage).
Matrix63 PointMarkW(const LinearizationPoint& at, const Layout& layout, const MarkInput* input,
                    int point, MarkRows* rows) {
  if (!at.kept_W.empty()) return at.kept_W[input - layout.point_mark_inputs.data()];
  RowsAgain(at, *input, point, rows);
  return MarkW(*rows);
}

// The point sums (V, g_p, the calibration's coupling) point by point over its marks in mark order,
// each mark's rows made again (MarkRowsAt), or its W and g_p share read where the image pass kept
// them (a small block without global unknowns). V_p = sum w A_p^T A_p: A_e's first three columns
// are -A_p, so it is minus the top of W. A small block with global unknowns keeps its marks' W on
// the way (KeepsMarkW).
void SumPointNormals(const Block& block, const Layout& layout, const Frame& frame, int num_threads,
                     Normal* normal) {
  const int G = layout.num_global;
  std::vector<Matrix63>& kept_W = normal->at.kept_W;
  const std::vector<Eigen::Vector3d>& kept_gp = normal->at.kept_gp;
  ParallelFor(layout.free_points.size(), num_threads, [&](size_t q) {
    Eigen::Matrix3d V = Eigen::Matrix3d::Zero();
    Eigen::Vector3d gp = Eigen::Vector3d::Zero();
    if (!kept_gp.empty()) {
      const size_t first = layout.point_all_marks.Offset(q);
      const size_t last = first + layout.point_all_marks[q].size();
      for (size_t position = first; position < last; ++position) {
        V -= kept_W[position].topRows<3>();
        gp += kept_gp[position];
      }
      normal->V[q] = V;
      normal->gp[q] = gp;
      return;
    }
    if (G > 0) normal->Wg_point[q].setZero(G, 3);
    MarkRows rows;
    Eigen::Matrix<double, 2, Eigen::Dynamic> A_g;
    const MarkInput* input = layout.point_mark_inputs.data() + layout.point_all_marks.Offset(q);
    const int point = layout.free_points[q];
    for (const int k : layout.point_all_marks[q]) {
      const size_t position = static_cast<size_t>(input - layout.point_mark_inputs.data());
      RowsAgain(normal->at, *input++, point, &rows);
      const Matrix63 W = MarkW(rows);
      if (!kept_W.empty()) kept_W[position] = W;
      V -= W.topRows<3>();
      gp += MarkGp(rows);
      const int global = G > 0 ? MarkGlobal(block, layout, frame, k) : -1;
      if (global >= 0)
        normal->Wg_point[q].middleRows(global, rows.num_calibration) += MarkWg(rows, &A_g);
    }
    normal->V[q] = V;
    normal->gp[q] = gp;
  });
}

// Marks: image by image on num_threads threads (LinearizeImageMarks: each image's camera sums and
// its marks' rows are its own), its calibration sums added in image order, then the point sums.
// False when a point is not in front of its camera (normal->behind_mark: the first such mark).
bool LinearizeMarks(const Block& block, const Layout& layout, const Frame& frame,
                    const State& state, int num_threads, Normal* normal) {
  const size_t num_images = block.images.size();
  std::vector<ImageMarkSums> sums(num_images);
  ParallelFor(num_images, num_threads,
              [&](size_t i) { LinearizeImageMarks(layout, i, normal, &sums[i]); });
  for (size_t i = 0; i < num_images; ++i) {
    if (sums[i].behind >= 0 && (normal->behind_mark < 0 || sums[i].behind < normal->behind_mark)) {
      normal->behind_mark = sums[i].behind;
      normal->behind_w = sums[i].behind_w;
    }
  }
  if (normal->behind_mark >= 0) {
    normal->at.kept_W.clear();  // some marks' W never made: none kept
    normal->at.kept_gp.clear();
    return false;
  }
  for (size_t i = 0; i < num_images; ++i) normal->weighted_ssr += sums[i].ssr;
  if (layout.num_global > 0) AddCalibrationSums(block, layout, frame, state, sums, normal);
  SumPointNormals(block, layout, frame, num_threads, normal);
  return true;
}

// The dense rows of the marks, in mark order (LinearizeTaylorBundle only: small blocks), from
// each mark's rows made again (MarkRowsAt), whitened by 1 / sigma.
void DenseMarkRows(const Block& block, const Plan& plan, const Layout& layout, const Frame& frame,
                   const LinearizationPoint& at, DenseRows* dense) {
  MarkRows rows;
  for (size_t k = 0; k < layout.marks.size(); ++k) {
    const int m = layout.marks[k];
    const BlockMark& mark = block.marks[m];
    RowsAgain(at, MarkInputOf(block, plan, m), mark.point, &rows);
    const Matrix23 A_p = MarkPointRows(rows);
    const double s = 1.0 / plan.mark_sigma[m];
    const Vector6d eo_u = rows.A_e.row(0).transpose(), eo_v = rows.A_e.row(1).transpose();
    const Eigen::Vector3d point_u = A_p.row(0).transpose(), point_v = A_p.row(1).transpose();
    const int global = MarkGlobal(block, layout, frame, static_cast<int>(k));
    dense->Add(mark.image, eo_u.data(), mark.point, point_u.data(), s, rows.f[0], global,
               rows.calib_u.data(), rows.num_calibration);
    dense->Add(mark.image, eo_v.data(), mark.point, point_v.data(), s, rows.f[1], global,
               rows.calib_v.data(), rows.num_calibration);
  }
}

// Control points: F = X - X_surveyed per axis, A = I.
// With cost_only, only normal->weighted_ssr is touched (EvaluateCost).
void LinearizeControlPoints(const Plan& plan, const Layout& layout, const Frame& frame,
                            const State& state, bool cost_only, Normal* normal, DenseRows* dense) {
  for (size_t q = 0; q < layout.free_points.size(); ++q) {
    const int p = layout.free_points[q];
    if (!plan.point_prior[p]) continue;
    const Eigen::Vector3d F = state.points[p] - frame.surveyed[p];
    const Eigen::Vector3d weight = plan.point_sigma[p].cwiseAbs2().cwiseInverse();
    normal->weighted_ssr += weight.dot(F.cwiseAbs2());
    if (cost_only) continue;
    normal->V[q].diagonal() += weight;
    normal->gp[q] += weight.cwiseProduct(F);
    if (dense != nullptr) {
      for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Vector3d row = Eigen::Vector3d::Unit(axis);
        dense->Add(-1, nullptr, p, row.data(), std::sqrt(weight[axis]), F[axis]);
      }
    }
  }
}

// Camera positions: F = X0 + R^T l - X_gnss, A = [I, d(R^T l)/d angles]. Attitudes: F = the
// angle differences (wrapped), A = [0, I]. With cost_only, only normal->weighted_ssr is touched.
void LinearizeImagePriors(const Block& block, const Plan& plan, const Layout& layout,
                          const Frame& frame, const State& state, bool cost_only, Normal* normal,
                          DenseRows* dense) {
  for (size_t i = 0; i < block.images.size(); ++i) {
    // An image held constant keeps its priors in the cost (as in BundleAdjust's problem) and its
    // position prior's rows in the lever arm's columns.
    const int b = layout.image_block[i];
    if (plan.image_prior[i]) {
      Eigen::Matrix<double, 3, 6> A = Eigen::Matrix<double, 3, 6>::Zero();
      A.leftCols<3>().setIdentity();
      Eigen::Vector3d antenna = state.eo[i].head<3>();
      Eigen::Matrix3d A_lever = Eigen::Matrix3d::Zero();  // d antenna / d lever = R^T
      if (frame.use_lever) {
        ExteriorOrientation eo;
        eo.parameters = state.eo[i];
        Eigen::Matrix3d d_angles;
        antenna = TaylorAntennaPosition(eo, state.lever, &d_angles);
        A.rightCols<3>() = d_angles;
        A_lever = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad()).transpose();
      }
      Eigen::Vector3d F = antenna - frame.measured[i];
      Eigen::Vector3d weight = plan.image_prior_sigma[i].cwiseAbs2().cwiseInverse();
      const int rows = ImagePriorRows(plan, i);  // 2: a position without height (X, Y only)
      if (rows < 3) F.z() = weight.z() = 0.0;
      normal->weighted_ssr += weight.dot(F.cwiseAbs2());
      const int lever = layout.lever_global;
      if (!cost_only && b >= 0) {
        normal->U[b].noalias() += A.transpose() * weight.asDiagonal() * A;
        normal->ge[b].noalias() += A.transpose() * weight.cwiseProduct(F);
        if (lever >= 0)
          normal->Ueg[b].middleCols<3>(lever).noalias() +=
              A.transpose() * weight.asDiagonal() * A_lever;
      }
      if (!cost_only && lever >= 0) {
        normal->Ugg.block<3, 3>(lever, lever).noalias() +=
            A_lever.transpose() * weight.asDiagonal() * A_lever;
        normal->gg.segment<3>(lever).noalias() += A_lever.transpose() * weight.cwiseProduct(F);
      }
      if (dense != nullptr) {
        for (int axis = 0; axis < rows; ++axis) {
          const Vector6d row = A.row(axis).transpose();
          const Eigen::Vector3d lever_row = A_lever.row(axis).transpose();
          dense->Add(static_cast<int>(i), row.data(), -1, nullptr, std::sqrt(weight[axis]),
                     F[axis], lever, lever_row.data(), 3);
        }
      }
    }
    if (plan.image_attitude[i]) {
      Eigen::Vector3d F;
      for (int k = 0; k < 3; ++k)
        F[k] = WrapAngle(state.eo[i][3 + k] - (*block.images[i].measured_angles_rad)[k]);
      const Eigen::Vector3d weight = plan.image_attitude_sigma[i].cwiseAbs2().cwiseInverse();
      normal->weighted_ssr += weight.dot(F.cwiseAbs2());
      if (!cost_only && b >= 0) {
        normal->U[b].bottomRightCorner<3, 3>().diagonal() += weight;
        normal->ge[b].tail<3>() += weight.cwiseProduct(F);
      }
      if (dense != nullptr) {
        for (int axis = 0; axis < 3; ++axis) {
          const Vector6d row = Vector6d::Unit(3 + axis);
          dense->Add(static_cast<int>(i), row.data(), -1, nullptr, std::sqrt(weight[axis]),
                     F[axis]);
        }
      }
    }
  }
}

}  // namespace

MarkInput MarkInputOf(const Block& block, const Plan& plan, int m) {
  MarkInput input;
  input.m = m;
  input.image = block.marks[m].image;
  input.ideal_um[0] = plan.ideal_um[m][0];
  input.ideal_um[1] = plan.ideal_um[m][1];
  input.sigma = plan.mark_sigma[m];
  return input;
}

bool MarkRowsAt(const LinearizationPoint& at, const MarkInput& input, int point, MarkRows* rows) {
  const Plan& plan = *at.plan;
  const int m = input.m;
  const int image = input.image;
  const int camera = at.frame->camera_index[image];
  // A self-calibrated camera's marks always through the Jet with the calibration's derivatives,
  // whoever asks: one path per mark, so that its rows have the same bits at every use.
  rows->num_calibration = static_cast<int>(plan.calibrated[camera].size());
  double row_u[6], row_v[6], fu, fv;
  if (!MarkEquation(at.poses[image], *at.block, plan, *at.frame, at.state, input, point, row_u,
                    row_v, &fu, &fv, &rows->w_m,
                    rows->num_calibration > 0 ? rows->calib_u.data() : nullptr,
                    rows->calib_v.data()))
    return false;
  rows->f = Eigen::Vector2d(fu, fv);
  const double weight = 1.0 / (input.sigma * input.sigma);
  double factor = 1.0;
  rows->cost = MarkCost(plan, m, weight * rows->f.squaredNorm(), &factor);
  rows->weight = weight * factor;
  for (int c = 0; c < 6; ++c) {
    rows->A_e(0, c) = row_u[c];
    rows->A_e(1, c) = row_v[c];
  }
  return true;
}

namespace {

// The linearisation point kept with the normal equations: the state copied (assigned into the
// previous copy's storage) and every image's pose linearisation at it.
void MakeLinearizationPoint(TaylorPartials partials, const Block& block, const Plan& plan,
                            const Layout& layout, const Frame& frame, const State& state,
                            LinearizationPoint* at) {
  at->partials = partials;
  at->block = &block;
  at->plan = &plan;
  at->frame = &frame;
  at->state = state;
  // Sized for the image pass (without global unknowns) or the points' sums to keep them again.
  const size_t kept = layout.point_position.empty() ? 0 : layout.point_mark_inputs.size();
  at->kept_W.clear();
  at->kept_W.resize(kept);
  at->kept_gp.clear();
  at->kept_gp.resize(layout.num_global == 0 ? kept : 0);
  at->poses.clear();
  at->poses.reserve(block.images.size());
  for (size_t i = 0; i < block.images.size(); ++i)
    at->poses.emplace_back(partials, state.eo[i].data(), frame.focal_um[i],
                           frame.earth_radius_m[i]);
}

}  // namespace

bool Linearize(TaylorPartials partials, const Block& block, const Plan& plan, const Layout& layout,
               const Frame& frame, const State& state, int num_threads, Normal* normal,
               DenseRows* dense) {
  const size_t num_blocks = layout.free_images.size();
  const size_t num_points = layout.free_points.size();
  normal->U.assign(num_blocks, Matrix6d::Zero());
  normal->ge.assign(num_blocks, Vector6d::Zero());
  normal->V.assign(num_points, Eigen::Matrix3d::Zero());
  normal->gp.assign(num_points, Eigen::Vector3d::Zero());
  MakeLinearizationPoint(partials, block, plan, layout, frame, state, &normal->at);
  const int G = layout.num_global;
  normal->Ueg.assign(G > 0 ? num_blocks : 0, Eigen::MatrixXd::Zero(6, G));
  normal->Ugg.setZero(G, G);
  normal->gg.setZero(G);
  normal->Wg_point.resize(G > 0 ? num_points : 0);
  normal->global_angle_per_unit.assign(G, 0.0);
  normal->weighted_ssr = 0.0;
  normal->behind_mark = -1;
  if (!LinearizeMarks(block, layout, frame, state, num_threads, normal)) return false;
  if (dense != nullptr) DenseMarkRows(block, plan, layout, frame, normal->at, dense);
  LinearizeControlPoints(plan, layout, frame, state, false, normal, dense);
  LinearizeImagePriors(block, plan, layout, frame, state, false, normal, dense);
  return std::isfinite(normal->weighted_ssr);
}

bool EvaluateCost(TaylorPartials partials, const Block& block, const Plan& plan,
                  const Layout& layout, const Frame& frame, const State& state, int num_threads,
                  double* weighted_ssr, int* behind_mark) {
  const size_t num_images = block.images.size();
  std::vector<double> image_ssr(num_images, 0.0);
  std::vector<int> image_behind(num_images, -1);
  ParallelFor(num_images, num_threads, [&](size_t i) {
    const TaylorPoseLinearization pose(partials, state.eo[i].data(), frame.focal_um[i],
                                       frame.earth_radius_m[i]);
    double ssr = 0.0;
    for (const int k : layout.image_marks[i]) {
      const int m = layout.marks[k];
      double fu, fv, w;
      if (!MarkEquation(pose, block, plan, frame, state, MarkInputOf(block, plan, m),
                        block.marks[m].point, nullptr, nullptr, &fu, &fv, &w)) {
        image_behind[i] = m;
        return;
      }
      const double weight = 1.0 / (plan.mark_sigma[m] * plan.mark_sigma[m]);
      ssr += MarkCost(plan, m, weight * Eigen::Vector2d(fu, fv).squaredNorm(), nullptr);
    }
    image_ssr[i] = ssr;
  });
  *behind_mark = -1;
  for (size_t i = 0; i < num_images; ++i)
    if (image_behind[i] >= 0 && (*behind_mark < 0 || image_behind[i] < *behind_mark))
      *behind_mark = image_behind[i];
  if (*behind_mark >= 0) return false;
  Normal sums;  // only its weighted_ssr
  for (size_t i = 0; i < num_images; ++i) sums.weighted_ssr += image_ssr[i];
  LinearizeControlPoints(plan, layout, frame, state, true, &sums, nullptr);
  LinearizeImagePriors(block, plan, layout, frame, state, true, &sums, nullptr);
  *weighted_ssr = sums.weighted_ssr;
  return std::isfinite(*weighted_ssr);
}

// ------------------------------------------------------------------ the reduced normal equations

namespace {

// The diagonal of a normal block scaled by (1 + lambda).
template <typename Matrix>
Matrix Damped(const Matrix& N, double lambda) {
  Matrix damped = N;
  if (lambda > 0.0) damped.diagonal() += lambda * N.diagonal();
  return damped;
}

// Eliminates the free points first .. last - 1 into (blocks, border, corner, r), which hold this
// chunk's sums. A point's rows in the global columns are the sum of its marks' (Wg_point): with
// W_p = [W_cameras; Wg_p], S's border loses W_a V^-1 Wg_p^T per mark a and its corner
// Wg_p V^-1 Wg_p^T. Returns the first singular free point, or -1.
int ReduceChunk(const Normal& normal, const Layout& layout, int first, int last, double lambda,
                std::vector<Matrix6d>* blocks, Eigen::MatrixXd* border, Eigen::MatrixXd* corner,
                Eigen::VectorXd* r, std::vector<Matrix63>* W, std::vector<Matrix63>* Y,
                std::vector<Eigen::Matrix3d>* V_inverses) {
  const int G = layout.num_global;
  const int cameras_size = 6 * static_cast<int>(layout.free_images.size());
  MarkRows rows;
  for (int q = first; q < last; ++q) {
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(Damped(normal.V[q], lambda));
    const Eigen::Vector3d d = ldlt.vectorD();
    if (ldlt.info() != Eigen::Success || !(d.minCoeff() > kPointPivotRatio * d.maxCoeff()))
      return q;
    const Eigen::Matrix3d V_inverse = ldlt.solve(Eigen::Matrix3d::Identity());
    (*V_inverses)[q] = V_inverse;
    const IndexLists::List marks = layout.point_marks[q];
    const IndexLists::List ids = layout.point_pairs[q];
    const int n = static_cast<int>(marks.size());
    W->resize(n);
    Y->resize(n);
    // The point's marks in free images: its inputs in order, those of held images skipped (the
    // same marks in the same order as point_marks).
    const MarkInput* input = layout.point_mark_inputs.data() + layout.point_all_marks.Offset(q);
    const int point = layout.free_points[q];
    for (int a = 0; a < n; ++input) {
      const int b = layout.image_block[input->image];
      if (b < 0) continue;
      (*W)[a] = PointMarkW(normal.at, layout, input, point, &rows);
      (*Y)[a].noalias() = (*W)[a] * V_inverse;
      r->segment<6>(6 * b).noalias() -= (*Y)[a] * normal.gp[q];
      ++a;
    }
    for (int a = 0; a < n; ++a) {
      const int ka = marks[a];
      const int ba = layout.mark_block[ka];
      for (int c = a; c < n; ++c) {
        const int kc = marks[c];
        const int bc = layout.mark_block[kc];
        Matrix6d& block = (*blocks)[ids[TriangleIndex(a, c, n)]];
        const Matrix6d M = (*Y)[a] * (*W)[c].transpose();  // W_a V^-1 W_c^T
        if (a == c || ba < bc) {
          block -= M;
        } else if (ba > bc) {
          block -= M.transpose();
        } else {  // two marks of the point in one image
          block -= M + M.transpose();
        }
      }
    }
    if (G > 0) {
      const Eigen::MatrixX3d& Wg = normal.Wg_point[q];
      const Eigen::MatrixX3d Yg = Wg * V_inverse;
      for (int a = 0; a < n; ++a)
        border->middleRows<6>(6 * layout.mark_block[marks[a]]).noalias() -=
            (*Y)[a] * Wg.transpose();
      corner->noalias() -= Yg * Wg.transpose();
      r->segment(cameras_size, G).noalias() -= Yg * normal.gp[q];
    }
  }
  return -1;
}

}  // namespace

// Eliminates the points, 3 x 3 at a time, in kReductionChunks chunks on num_threads threads:
//   S = U - sum_p W_p V_p^-1 W_p^T,   r = g_e - sum_p W_p V_p^-1 g_p.
// Chunk 0 sums into S and r directly, the others into their own copies, added in chunk order.
// Returns the first free point whose block V_p is singular (its rays fix no point), or -1.
int Reduce(const Normal& normal, const Layout& layout, Reduction* reduction) {
  const int num_blocks = static_cast<int>(layout.free_images.size());
  const int G = layout.num_global;
  const int cameras_size = 6 * num_blocks;
  const double lambda = reduction->damping;
  reduction->blocks.assign(layout.pairs.size(), Matrix6d::Zero());
  reduction->r.resize(cameras_size + G);
  reduction->border.resize(cameras_size, G);
  for (int b = 0; b < num_blocks; ++b) {
    reduction->blocks[layout.diagonal_pair[b]] = Damped(normal.U[b], lambda);
    reduction->r.segment<6>(6 * b) = normal.ge[b];
    if (G > 0) reduction->border.middleRows<6>(6 * b) = normal.Ueg[b];
  }
  reduction->corner = Damped(normal.Ugg, lambda);
  reduction->r.tail(G) = normal.gg;
  reduction->V_inverse.resize(layout.free_points.size());
  reduction->chunk_blocks.resize(kReductionChunks - 1);
  reduction->chunk_border.resize(kReductionChunks - 1);
  reduction->chunk_corner.resize(kReductionChunks - 1);
  reduction->chunk_r.resize(kReductionChunks - 1);
  reduction->W.resize(kReductionChunks);
  reduction->Y.resize(kReductionChunks);
  std::vector<int> singular(kReductionChunks, -1);
  ParallelFor(kReductionChunks, reduction->num_threads, [&](size_t chunk) {
    std::vector<Matrix6d>* blocks = &reduction->blocks;
    Eigen::MatrixXd* border = &reduction->border;
    Eigen::MatrixXd* corner = &reduction->corner;
    Eigen::VectorXd* r = &reduction->r;
    if (chunk > 0) {
      blocks = &reduction->chunk_blocks[chunk - 1];
      border = &reduction->chunk_border[chunk - 1];
      corner = &reduction->chunk_corner[chunk - 1];
      r = &reduction->chunk_r[chunk - 1];
      blocks->assign(layout.pairs.size(), Matrix6d::Zero());
      border->setZero(cameras_size, G);
      corner->setZero(G, G);
      r->setZero(cameras_size + G);
    }
    singular[chunk] = ReduceChunk(normal, layout, layout.chunk_start[chunk],
                                  layout.chunk_start[chunk + 1], lambda, blocks, border, corner,
                                  r, &reduction->W[chunk], &reduction->Y[chunk],
                                  &reduction->V_inverse);
  });
  for (int chunk = 0; chunk < kReductionChunks; ++chunk)
    if (singular[chunk] >= 0) return layout.free_points[singular[chunk]];
  // The partial sums in chunk order, pair by pair on the threads (each pair its own).
  ParallelFor(layout.pairs.size(), reduction->num_threads, [&](size_t k) {
    for (int chunk = 1; chunk < kReductionChunks; ++chunk)
      reduction->blocks[k] += reduction->chunk_blocks[chunk - 1][k];
  });
  for (int chunk = 1; chunk < kReductionChunks; ++chunk) {
    reduction->r += reduction->chunk_r[chunk - 1];
    if (G > 0) {
      reduction->border += reduction->chunk_border[chunk - 1];
      reduction->corner += reduction->chunk_corner[chunk - 1];
    }
  }
  return -1;
}

double PredictedDecrease(const Layout& layout, const Normal& normal, double lambda,
                         const Eigen::VectorXd& d_e, const std::vector<Eigen::Vector3d>& d_p) {
  double dg = 0.0, dDd = 0.0;
  for (size_t b = 0; b < layout.free_images.size(); ++b) {
    const Vector6d d = d_e.segment<6>(6 * b);
    dg += d.dot(normal.ge[b]);
    dDd += d.dot(normal.U[b].diagonal().cwiseProduct(d));
  }
  for (size_t q = 0; q < layout.free_points.size(); ++q) {
    dg += d_p[q].dot(normal.gp[q]);
    dDd += d_p[q].dot(normal.V[q].diagonal().cwiseProduct(d_p[q]));
  }
  const Eigen::VectorXd d_g = d_e.tail(layout.num_global);
  dg += d_g.dot(normal.gg);
  dDd += d_g.dot(normal.Ugg.diagonal().cwiseProduct(d_g));
  return 0.5 * (dg + lambda * dDd);
}

// Writes the Jacobi-scaled S into layout->S (fixed components: their row and column zero, 1 on
// the diagonal, which removes them exactly) and sets the scale. Returns the first column of S
// without weight (a zero diagonal), or -1.
int WriteScaled(const Plan& plan, Layout* layout, Reduction* reduction) {
  const int num_blocks = static_cast<int>(layout->free_images.size());
  const int G = layout->num_global;
  const int cameras_size = 6 * num_blocks;
  reduction->scale.resize(cameras_size + G);
  for (int j = 0; j < G; ++j) {
    const double d = reduction->corner(j, j);
    if (!(d > 0.0) || !std::isfinite(d)) return cameras_size + j;
    reduction->scale[cameras_size + j] = 1.0 / std::sqrt(d);
  }
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
  // The global columns, dense: rows 0 .. 6 B - 1 from the border, then the corner's upper part.
  const int* outer = layout->S.outerIndexPtr();
  for (int j = 0; j < G; ++j) {
    double* column = values + outer[cameras_size + j];
    const double s_j = s[cameras_size + j];
    for (int b = 0; b < num_blocks; ++b)
      for (int r = 0; r < 6; ++r)
        column[6 * b + r] = IsFixed(plan, *layout, b, r)
                                ? 0.0
                                : reduction->border(6 * b + r, j) * s[6 * b + r] * s_j;
    for (int i = 0; i <= j; ++i)
      column[cameras_size + i] = reduction->corner(i, j) * s[cameras_size + i] * s_j;
  }
  return -1;
}

// Factorises the scaled S. False when it is not positive definite to min_pivot_ratio.
bool Factorize(double min_pivot_ratio, const Layout& layout, Reduction* reduction) {
  if (reduction->solver == TaylorLinearSolver::kCholmodSupernodal) {
    reduction->failure.clear();
    if (!reduction->analysed) {
      const Status analysed = reduction->cholmod.Analyze(layout.S);
      if (!analysed.ok()) {
        reduction->pivot_ratio = 0.0;
        reduction->failure = analysed.message();
        return false;
      }
      reduction->analysed = true;
    }
    const Status factorized = reduction->cholmod.Factorize(layout.S);
    reduction->pivot_ratio = reduction->cholmod.pivot_ratio();  // 0 when not positive definite
    // A failure other than a matrix found not positive definite (out of memory, say) is no
    // verdict on the block.
    if (!factorized.ok() && !reduction->cholmod.not_positive_definite())
      reduction->failure = factorized.message();
    return factorized.ok() && reduction->pivot_ratio > min_pivot_ratio;
  }
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
  const int G = layout.num_global;
  const int cameras_size = 6 * static_cast<int>(layout.free_images.size());
  Eigen::VectorXd rhs = s.cwiseProduct(reduction.r);
  for (int b = 0; b < static_cast<int>(layout.free_images.size()); ++b)
    for (int c = 0; c < 6; ++c)
      if (IsFixed(plan, layout, b, c)) rhs[6 * b + c] = 0.0;
  *d_e = s.cwiseProduct(reduction.solver == TaylorLinearSolver::kCholmodSupernodal
                            ? reduction.cholmod.Solve(rhs)
                            : Eigen::VectorXd(reduction.ldlt.solve(rhs)));
  d_p->resize(layout.free_points.size());
  ParallelFor(layout.free_points.size(), reduction.num_threads, [&](size_t q) {
    Eigen::Vector3d t = normal.gp[q];
    MarkRows rows;
    const MarkInput* input = layout.point_mark_inputs.data() + layout.point_all_marks.Offset(q);
    const MarkInput* end = input + layout.point_all_marks[q].size();
    const int point = layout.free_points[q];
    for (; input != end; ++input) {
      const int b = layout.image_block[input->image];
      if (b < 0) continue;
      t.noalias() -=
          PointMarkW(normal.at, layout, input, point, &rows).transpose() * d_e->segment<6>(6 * b);
    }
    if (G > 0) t.noalias() -= normal.Wg_point[q].transpose() * d_e->segment(cameras_size, G);
    (*d_p)[q] = reduction.V_inverse[q] * t;
  });
}

}  // namespace photopose::internal::taylor
