#pragma once
// The inside of the Taylor bundle adjustment (solvers/bundle/taylor_bundle.h) shared by its two
// files: the plan, the layout of a round's unknowns and of the sparse reduced normal matrix, the
// linearisation of the observation equations (eqs. 7-8, 17-28 of the seed), the elimination of the
// points, and the factorisation (taylor_bundle_normals.cc). taylor_bundle.cc runs
// the rounds and fills the results. Not part of the library's interface.

#include <Eigen/Core>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/block.h"
#include "core/camera_models.h"
#include "core/status.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/cholmod_factor.h"
#include "solvers/bundle/taylor_bundle.h"
#include "solvers/resection/taylor_resection.h"

namespace photopose::internal::taylor {

using Matrix63 = Eigen::Matrix<double, 6, 3>;
using Matrix26 = Eigen::Matrix<double, 2, 6>;
using Matrix23 = Eigen::Matrix<double, 2, 3>;
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// The free points are eliminated in this many chunks (contiguous, of about equal work), each
// with its own partial S and r, added in chunk order: the sums, and so the result, do not depend
// on how many threads run the chunks. 4 keeps two threads busy at a memory cost of three extra
// copies of S's blocks.
constexpr int kReductionChunks = 4;

// The ground-point partials.
// dF/dX = -dF/dX0: F depends on the point and the centre only through X - X0 (eqs. 7-8), so the
// point's three columns are the negated eqs. 17-19 and 23-25.
inline void PointPartialsFromCentrePartials(const double* row_u, const double* row_v,
                                            Matrix23* d_point) {
  for (int k = 0; k < 3; ++k) {
    (*d_point)(0, k) = -row_u[k];
    (*d_point)(1, k) = -row_v[k];
  }
}

// The decisions made before the first round (which marks, points and priors enter, with which
// sigmas, and how the block is tied to the ground) are BundleAdjust's plan
// (internal::MakeBundlePlan); the Taylor adjustment adds only what is its own.
struct Plan : BundlePlan {
  // Per mark: the corrected (ideal) image-plane point (um) of a kFrame camera's mark, constant
  // with its interior orientation; zero for a mark whose camera's model is evaluated per mark (a
  // forward model, or a self-calibrated kFrame camera: Frame::model_camera).
  std::vector<Eigen::Vector2d> ideal_um;
  bool estimate_lever = false;  // the lever arm's three unknowns (config.estimate_lever_arm)
  std::vector<char> image_constant;  // held constant (config or the relative gauge's first image)
  std::vector<char> point_constant;
  std::vector<std::array<bool, 6>> image_fixed;  // components held fixed of a free image
  // The robust loss of the tie marks (plan.mark_group kTieMarks) on their squared whitened
  // residual, as BundleAdjust applies it (cost_functions/losses.h MakeLoss); null: none. It
  // enters the normal equations as iteratively reweighted least squares: a mark's weight times
  // rho'(s) at the linearisation point, its cost rho(s).
  std::shared_ptr<const ceres::LossFunction> tie_loss;
};

// Plan::ideal_um of the marks now used (plan.mark_used), zero for the others.
void FillIdealPoints(const Block& block, Plan* plan);

// Lists of indices, one per item (a free point, an image), stored end to end: list i is
// items[start[i]] .. items[start[i + 1] - 1]. One allocation of exactly the entries, where a vector
// per item costs its 24-byte header, an allocation and the slack of its growth.
class IndexLists {
 public:
  // A list: iterable, indexable, sized.
  struct List {
    const int* first;
    const int* last;
    const int* begin() const { return first; }
    const int* end() const { return last; }
    size_t size() const { return static_cast<size_t>(last - first); }
    int operator[](size_t k) const { return first[k]; }
  };

  // Starts `num_lists` empty lists; then Count every entry, Allocate, and Add them in the same
  // order (each list keeps its entries in the order added).
  void Reset(size_t num_lists) {
    start_.assign(num_lists + 1, 0);
    items_.clear();
    fill_.clear();
  }
  void Count(size_t list, int entries = 1) { start_[list + 1] += entries; }
  void Allocate() {
    for (size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
    items_.assign(static_cast<size_t>(start_.back()), 0);
    fill_.assign(start_.begin(), start_.end() - 1);
  }
  void Add(size_t list, int item) { items_[static_cast<size_t>(fill_[list]++)] = item; }
  // After the last Add: frees the fill positions.
  void Finish() { std::vector<int>().swap(fill_); }
  // List i's entries to write in place (Count reserved them, Allocate made them).
  int* Entries(size_t i) { return items_.data() + start_[i]; }

  size_t size() const { return start_.empty() ? 0 : start_.size() - 1; }
  // The position of list i's first entry among all entries, end to end.
  size_t Offset(size_t i) const { return static_cast<size_t>(start_[i]); }
  List operator[](size_t i) const {
    return {items_.data() + start_[i], items_.data() + start_[i + 1]};
  }

 private:
  std::vector<int> start_;
  std::vector<int> items_;
  std::vector<int> fill_;
};

// What a mark's equation reads of the block and the plan besides the state: its index, image, ideal
// film point (Plan::ideal_um) and sigma (Plan::mark_sigma). Gathered per mark in the order of the
// points' mark lists (Layout::point_mark_inputs) so that the passes over the points read them in
// sequence: read from the block's and the plan's arrays in a point's order, a cache miss each,
// they took a third of the rounds' time once the rows were no longer kept.
struct MarkInput {
  int m = -1;  // index into Block::marks
  int image = -1;
  double ideal_um[2] = {0.0, 0.0};
  double sigma = 0.0;
};
MarkInput MarkInputOf(const Block& block, const Plan& plan, int m);

// The unknowns and the sparsity of the reduced normal matrix of one round. Camera block b is
// image free_images[b], columns 6 b .. 6 b + 5. The global unknowns (each self-calibrated camera's
// estimated parameters in plan.calibrated order, then the estimated lever arm) follow as the last
// num_global columns, 6 B + j (B camera blocks): a dense border of S that couples with every
// camera block and with the points (eliminated as the cameras' columns are). The reduced matrix
// is stored as its upper triangle
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
  IndexLists point_marks;      // per free point: positions in `marks` of its marks in free images
  IndexLists point_pairs;      // per free point: pair of each (a <= c) of those
  IndexLists point_all_marks;  // per free point: positions of all its marks
  // Per entry of point_all_marks, in its order (entry j of point q at Offset(q) + j): the mark's
  // input (32 bytes a mark).
  std::vector<MarkInput> point_mark_inputs;
  IndexLists image_marks;      // per image: positions in `marks` of its marks
  // Per entry of `marks`: its entry in point_mark_inputs (-1: a mark of a fixed point). Only for a
  // block that keeps its marks' W (KeepsMarkW; empty otherwise): where the image pass puts them.
  std::vector<int> point_position;
  std::vector<int> chunk_start;    // kReductionChunks + 1 boundaries in the free points
  std::vector<int> diagonal_pair;  // per camera block
  std::vector<std::pair<int, int>> pairs;
  std::vector<std::array<int, 6>> value_start;
  // The global columns: per camera the first of its estimated parameters (j, its column 6 B + j)
  // or -1; the lever arm's first or -1; their count. Per global column: its camera (-1: the lever
  // arm) and parameter index (the lever's axis).
  std::vector<int> camera_global;
  int lever_global = -1;
  int num_global = 0;
  std::vector<int> global_camera;
  std::vector<int> global_param;
  SparseMatrix S;
  int num_observations = 0;
  int num_unknowns = 0;
};

// The values being adjusted, relative to the block's centroid.
struct State {
  std::vector<Vector6d> eo;                  // per image
  std::vector<Eigen::Vector3d> points;       // per point
  std::vector<std::vector<double>> cameras;  // per camera: its parameters (core/camera_models.h)
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();  // the lever arm (m, camera frame)
};

// The block's fixed data in the centred frame.
struct Frame {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double extent_m = 1.0;                  // RMS distance of cameras and points from the centroid
  std::vector<Eigen::Vector3d> surveyed;  // per point (control points), centred
  std::vector<Eigen::Vector3d> measured;  // per image (camera positions), centred
  // Per image: the seed's focal length c (um) of a kFrame camera with fixed interior orientation,
  // whose marks enter as their ideal film points (Plan::ideal_um); 1 for a camera whose model is
  // evaluated per mark (model_camera), whose pose equations are written for the ray's normalised
  // coordinates (a, b) and mapped to the observation's unit per mark.
  std::vector<double> focal_um;
  // Per image: its camera when the camera's model is evaluated per mark (core/camera_models.h
  // CameraModelResidual, on State::cameras): a forward (COLMAP) model, or a self-calibrated
  // kFrame camera; null for a kFrame camera with fixed interior orientation. Points into the block.
  std::vector<const BlockCamera*> model_camera;
  std::vector<int> camera_index;  // per image: its camera (index into Block::cameras)
  // Per image: its camera's earth-curvature radius (m; BlockCamera::earth_curvature_radius_m),
  // 0 without ApplyECC. The drop depends on X - X0, Y - Y0 only: the centred frame keeps it.
  std::vector<double> earth_radius_m;
  bool use_lever = false;  // the camera-position priors apply State::lever
};

// Where a linearisation was made: the block's fixed data, a copy of the state (24 bytes a point:
// 3 MB at 1000 images), so that no step tried or taken since moves the point a mark's rows are
// made again at, and every image's pose linearisation at that state. Filled by Linearize; the
// block, plan and frame must outlive it.
struct LinearizationPoint {
  TaylorPartials partials = TaylorPartials::kCorrected;
  const Block* block = nullptr;
  const Plan* plan = nullptr;
  const Frame* frame = nullptr;
  State state;
  std::vector<TaylorPoseLinearization> poses;  // per image, at state.eo
  // Each mark's W (MarkW, 144 bytes) and its share of the point's right-hand side (MarkGp, 24
  // bytes), per entry of Layout::point_mark_inputs (the points' order), kept by Linearize when the
  // block is small enough (KeepsMarkW), empty otherwise. The image pass makes them from the rows it
  // makes anyway (kept_gp: only without global unknowns, whose couplings make the points' sums
  // make the rows again; then the points' sums keep W); the points' sums, the elimination and the
  // back-substitution read them there instead of making the rows again: the same function of the
  // same rows, so the same bits.
  std::vector<Matrix63> kept_W;
  std::vector<Eigen::Vector3d> kept_gp;
};

// Whether Linearize keeps every mark's W and g_p share (LinearizationPoint::kept_W, kept_gp) for a
// layout with `point_marks` entries in Layout::point_mark_inputs: while they take at most
// kKeptWBudgetBytes (49 932 marks). Made again, the rows cost the 12- and 60-image benchmark
// blocks up to a third of their iteration; the W kept from the points' sums took 11-23 % off it,
// and the image pass keeping W and g_p (the rows made once per linearisation) another 8 % of the
// 12-image call's instructions and 9-18 % of the 150-image block's iteration, whose 5.2 MB of W
// alone had gained nothing (docs/performance.md, "Nothing slower elsewhere"). A large block
// has not the memory to spare (1.7 million marks, 288 MB, at 1000 images).
constexpr size_t kKeptWBudgetBytes = size_t{8} << 20;
constexpr size_t kKeptBytesPerMark = sizeof(Matrix63) + sizeof(Eigen::Vector3d);
inline bool KeepsMarkW(size_t point_marks) {
  return point_marks <= kKeptWBudgetBytes / kKeptBytesPerMark;
}

// One mark's linearised observation equation: its rows dF/d(X0, Y0, Z0, omega, phi, kappa)
// (the point's rows are minus the first three: PointPartialsFromCentrePartials), F (the
// observation unit) and its weight w (1 / sigma^2 times the tie loss's rho' at the linearisation
// point; 1 / observation unit^2); for a self-calibrated camera's mark, its rows dF/d(the camera's
// estimated parameters, plan.calibrated order). Made by MarkRowsAt wherever a mark's rows are
// needed, never kept per mark (120 bytes a mark, 205 MB at 1.7 million marks); a small block keeps
// their W (LinearizationPoint::kept_W).
struct MarkRows {
  Matrix26 A_e;
  Eigen::Vector2d f;
  double weight = 0.0;
  double cost = 0.0;        // the mark's share of F^T P F (MarkCost: rho(s) under the tie loss)
  double w_m = 0.0;         // the point's w (m; the depth coordinate, negative in front)
  int num_calibration = 0;  // the camera's estimated parameters (0: none)
  std::array<double, kMaxCameraModelParams> calib_u, calib_v;
};

// A mark's rows (its input, MarkInputOf; `point` its point) at the linearisation point `at`: the
// one function the linearisation's sums, the points' sums, the elimination, the back-substitution
// and the dense rows all call, so that every use sees the same bits (the same arithmetic in the
// same order, from the same copy of the state). False when the point is not in front of the camera
// (rows->w_m) or F is not finite; never at a point where Linearize succeeded.
bool MarkRowsAt(const LinearizationPoint& at, const MarkInput& input, int point, MarkRows* rows);

// The mark's share of the camera-point block of N, w A_e^T A_p (6 x 3), of the point's
// right-hand side, w A_p^T F, and of a self-calibrated camera's coupling with the point,
// w A_g^T A_p: the same arithmetic wherever they are needed, so every use sees the same bits.
inline Matrix23 MarkPointRows(const MarkRows& rows) {
  return -rows.A_e.leftCols<3>();  // dF/dX = -dF/dX0 (PointPartialsFromCentrePartials)
}
inline Matrix63 MarkW(const MarkRows& rows) {
  const Eigen::Matrix<double, 6, 2> weighted_Ae_T = rows.weight * rows.A_e.transpose();
  Matrix63 W;
  W.noalias() = weighted_Ae_T * MarkPointRows(rows);
  return W;
}
inline Eigen::Vector3d MarkGp(const MarkRows& rows) {
  Eigen::Vector3d gp;
  gp.noalias() = rows.weight * MarkPointRows(rows).transpose() * rows.f;
  return gp;
}
// A_g (2 x the camera's estimated parameters) into *A_g, resized (kept storage: no allocation per
// mark of a camera).
inline void MarkCalibrationRows(const MarkRows& rows,
                                Eigen::Matrix<double, 2, Eigen::Dynamic>* A_g) {
  A_g->resize(2, rows.num_calibration);
  for (int j = 0; j < rows.num_calibration; ++j) {
    (*A_g)(0, j) = rows.calib_u[j];
    (*A_g)(1, j) = rows.calib_v[j];
  }
}
inline Eigen::MatrixX3d MarkWg(const MarkRows& rows,
                               Eigen::Matrix<double, 2, Eigen::Dynamic>* A_g) {
  MarkCalibrationRows(rows, A_g);
  Eigen::MatrixX3d Wg;
  Wg.noalias() = rows.weight * A_g->transpose() * MarkPointRows(rows);
  return Wg;
}

// The normal equations of one linearisation (seed sign: N d = A^T P F, p = p0 - d).
struct Normal {
  // Where they were made: every mark's rows are made again from it (MarkRowsAt) where they are
  // needed rather than kept per mark.
  LinearizationPoint at;
  std::vector<Matrix6d> U;  // per camera block
  std::vector<Vector6d> ge;
  std::vector<Eigen::Matrix3d> V;  // per free point
  std::vector<Eigen::Vector3d> gp;
  // The global columns (Layout::num_global, G; all empty when G = 0): per camera block its
  // 6 x G coupling w A_e^T A_g; their own G x G block and right-hand side; per free point the sum
  // of its marks' w A_g^T A_p at their columns (G x 3).
  std::vector<Eigen::MatrixXd> Ueg;
  Eigen::MatrixXd Ugg;
  Eigen::VectorXd gg;
  std::vector<Eigen::MatrixX3d> Wg_point;
  // Per global column: the correction's size measure (MeasureCorrections). A calibration
  // parameter: the RMS image shift of a unit correction over the camera's marks (sqrt of its
  // diagonal of N over the weight of those rows) divided by the camera's focal length in the
  // observation unit, i.e. rad of view per unit; the lever arm: 0 (a position, m).
  std::vector<double> global_angle_per_unit;
  double weighted_ssr = 0.0;             // F^T P F over every observation
  int behind_mark = -1;                  // a mark whose point is not in front of its camera
  double behind_w = 0.0;
};

// Optional dense copy of the whitened observation equations, for LinearizeTaylorBundle.
struct DenseRows {
  std::vector<int> image_columns;  // per image: first column or -1
  std::vector<int> point_columns;  // per point: first column or -1
  int global_column = -1;          // first global column (Layout's global column 0)
  int num_columns = 0;
  std::vector<Eigen::VectorXd> rows;
  std::vector<double> residuals;

  // One equation: sqrt_weight times (eo_row at the image's columns, point_row at the point's,
  // global_row's global_count entries at global columns global .. global + global_count - 1) and
  // times F. image / point / global -1 (or a null row): no such part.
  void Add(int image, const double* eo_row, int point, const double* point_row, double sqrt_weight,
           double f, int global = -1, const double* global_row = nullptr, int global_count = 0) {
    Eigen::VectorXd row = Eigen::VectorXd::Zero(num_columns);
    if (image >= 0 && eo_row != nullptr && image_columns[image] >= 0)
      for (int k = 0; k < 6; ++k) row[image_columns[image] + k] = sqrt_weight * eo_row[k];
    if (point >= 0 && point_row != nullptr && point_columns[point] >= 0)
      for (int k = 0; k < 3; ++k) row[point_columns[point] + k] = sqrt_weight * point_row[k];
    if (global >= 0 && global_row != nullptr)
      for (int k = 0; k < global_count; ++k)
        row[global_column + global + k] = sqrt_weight * global_row[k];
    rows.push_back(std::move(row));
    residuals.push_back(sqrt_weight * f);
  }
};

// The points eliminated, the reduced camera system factorised.
struct Reduction {
  TaylorLinearSolver solver = TaylorLinearSolver::kCholmodSupernodal;
  int num_threads = 1;
  double damping = 0.0;                    // lambda of the reduction (unitless)
  std::vector<Eigen::Matrix3d> V_inverse;  // per free point (of V_p + lambda diag V_p)
  // Per chunk but the first (which writes into blocks and r): partial S blocks and r; and per
  // chunk the scratch W and W V^-1 of the marks of one point.
  std::vector<std::vector<Matrix6d>> chunk_blocks;
  std::vector<Eigen::MatrixXd> chunk_border, chunk_corner;
  std::vector<Eigen::VectorXd> chunk_r;
  std::vector<std::vector<Matrix63>> W, Y;
  std::vector<Matrix6d> blocks;  // per pair: the reduced matrix S (unscaled)
  Eigen::MatrixXd border;        // S's camera x global block (6 B x G, unscaled)
  Eigen::MatrixXd corner;        // S's global x global block (G x G, unscaled)
  Eigen::VectorXd r;             // reduced right-hand side (unscaled; 6 B + G)
  Eigen::VectorXd scale;         // Jacobi scale 1 / sqrt(diag S); 1 where fixed
  // Natural order: the camera blocks are already in a fill-reducing order (BuildLayout).
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper, Eigen::NaturalOrdering<int>> ldlt;
  CholmodFactor cholmod;  // supernodal
  bool analysed = false;
  double pivot_ratio = 0.0;  // smallest / largest pivot of the scaled LDL^T
  bool singular = false;     // the last factorisation found S singular (SolveStep)
  // The last factorisation failed for a reason that says nothing about S (CHOLMOD out of memory,
  // say): that reason; empty otherwise.
  std::string failure;
};

inline bool IsFixed(const Plan& plan, const Layout& layout, int b, int component) {
  return plan.image_fixed[layout.free_images[b]][component];
}

// The Taylor adjustment's set-up (taylor_bundle.cc), declared here for the tests of the normal
// equations: its plan (internal::MakeBundlePlan, then the unknowns held, the tie loss and each
// mark's ideal film point; the options and config already checked), and the block's centred frame
// with the start state.
Status MakePlan(const TaylorBundleOptions& options, const BundleAdjustmentConfig& config,
                const Block& block, Plan* plan);
Frame MakeFrame(const BundleAdjustmentConfig& config, const Block& block, const Plan& plan,
                State* state);

// The layout of a round from the plan: free images (in a fill-reducing order) and points, the
// marks of the round, the block pairs of S and its sparse pattern, the observation count.
void BuildLayout(const Block& block, const Plan& plan, Layout* layout);

// Linearises every observation equation at `state` and accumulates the normal equations (and,
// when `dense` is not null, the whitened rows); normal->at keeps the linearisation point (a copy
// of `state`; pointers to block, plan and frame). False when a point is not in front of its camera
// (normal->behind_mark says which) or the residuals are not finite.
// On num_threads threads (the sums in a fixed order, the result the same for every count).
bool Linearize(TaylorPartials partials, const Block& block, const Plan& plan, const Layout& layout,
               const Frame& frame, const State& state, int num_threads, Normal* normal,
               DenseRows* dense);

// The weighted sum of squared residuals F^T P F at `state` alone (no partials), in the same order
// of summation as Linearize. False when a point is not in front of its camera (*behind_mark, as
// Linearize) or the sum is not finite.
bool EvaluateCost(TaylorPartials partials, const Block& block, const Plan& plan,
                  const Layout& layout, const Frame& frame, const State& state, int num_threads,
                  double* weighted_ssr, int* behind_mark);

// Eliminates the points, 3 x 3 at a time, from the normal matrix whose diagonal is scaled by
// (1 + lambda) (lambda = reduction->damping; 0: Gauss-Newton):
//   S = U - sum_p W_p V_p^-1 W_p^T,   r = g_e - sum_p W_p V_p^-1 g_p.
// Returns the first free point whose block V_p is singular (its rays fix no point), or -1.
int Reduce(const Normal& normal, const Layout& layout, Reduction* reduction);

// The decrease of 1/2 F^T P F the linearisation predicts for the correction (d_e, d_p) solved
// with damping lambda: 1/2 (d^T g + lambda d^T diag(N) d).
double PredictedDecrease(const Layout& layout, const Normal& normal, double lambda,
                         const Eigen::VectorXd& d_e, const std::vector<Eigen::Vector3d>& d_p);

// Writes the Jacobi-scaled S into layout->S (fixed components: their row and column zero, 1 on
// the diagonal, which removes them exactly) and sets the scale. Returns the first column of S
// without weight (a zero diagonal: 6 b + c a camera's, 6 B + j a global one), or -1.
int WriteScaled(const Plan& plan, Layout* layout, Reduction* reduction);

// Factorises the scaled S (reduction->solver). False when it is not positive definite to
// min_pivot_ratio.
bool Factorize(double min_pivot_ratio, const Layout& layout, Reduction* reduction);

// Solves S d_e = r (through the scaled factorisation; d_e: 6 B camera then G global components)
// and back-substitutes d_p = V_p^-1 (g_p - W_p^T d_e).
void SolveCorrections(const Plan& plan, const Layout& layout, const Normal& normal,
                      const Reduction& reduction, Eigen::VectorXd* d_e,
                      std::vector<Eigen::Vector3d>* d_p);

}  // namespace photopose::internal::taylor
