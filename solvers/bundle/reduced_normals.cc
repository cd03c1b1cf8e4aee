// The reduced normal matrix of a bundle round (solvers/bundle/internal/reduced_normals.h): rows
// evaluated without Ceres' per-problem state, the points eliminated in parallel chunks summed in a
// fixed order, S assembled and selectively inverted, and the per-point quantities the statistics
// take from it.
#include "solvers/bundle/internal/reduced_normals.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <numeric>
#include <utility>

#include "core/parallel.h"
#include "core/types.h"

namespace photopose::internal {

bool EvaluateBlockRows(const BundleRound& round, const ReducedNormals& reduced,
                       const ResidualInfo& info, BlockRows* out) {
  const ceres::CostFunction* cost = ResidualBlockOf(round, info, &out->made, &out->parameters);
  const int num_residuals = cost->num_residuals();
  const size_t num_parameters = out->parameters.size();
  // The ambient Jacobian of each variable block, one after another in out->ambient.
  std::vector<const VariableBlock*> variable(num_parameters, nullptr);
  size_t ambient_size = 0;
  for (size_t k = 0; k < num_parameters; ++k) {
    const auto found = reduced.variables.find(out->parameters[k]);
    if (found == reduced.variables.end()) continue;  // held constant
    variable[k] = &found->second;
    ambient_size += static_cast<size_t>(num_residuals) * found->second.ambient;
  }
  out->ambient.resize(ambient_size);
  out->jacobians.assign(num_parameters, nullptr);
  size_t at = 0;
  for (size_t k = 0; k < num_parameters; ++k) {
    if (variable[k] == nullptr) continue;
    out->jacobians[k] = out->ambient.data() + at;
    at += static_cast<size_t>(num_residuals) * variable[k]->ambient;
  }
  out->residuals.resize(num_residuals);
  if (!cost->Evaluate(out->parameters.data(), out->residuals.data(), out->jacobians.data()))
    return false;
  out->rows = num_residuals;
  out->e_columns.clear();
  out->e_blocks.clear();
  out->point = -1;
  int num_e_columns = 0;
  for (size_t k = 0; k < num_parameters; ++k)
    if (variable[k] != nullptr && variable[k]->e_block >= 0) num_e_columns += variable[k]->tangent;
  out->J_e.resize(num_residuals, num_e_columns);
  int column = 0;
  for (size_t k = 0; k < num_parameters; ++k) {
    const VariableBlock* v = variable[k];
    if (v == nullptr) continue;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const Eigen::Map<const RowMajor> ambient(out->jacobians[k], num_residuals, v->ambient);
    // The tangent-space Jacobian: the ambient one times the manifold's (Ceres' own rule).
    const auto tangent_of = [&](auto&& destination) {
      if (v->plus_jacobian.empty())
        destination = ambient;
      else
        destination.noalias() =
            ambient * Eigen::Map<const RowMajor>(v->plus_jacobian.data(), v->ambient, v->tangent);
    };
    if (v->e_block >= 0) {
      for (int c = 0; c < v->tangent; ++c) out->e_columns.push_back(reduced.e_offset[v->e_block] + c);
      out->e_blocks.push_back(v->e_block);
      tangent_of(out->J_e.middleCols(column, v->tangent));
      column += v->tangent;
    } else if (v->point >= 0) {
      out->point = v->point;
      out->J_p.resize(num_residuals, 3);
      tangent_of(out->J_p);
    }
  }
  return true;
}

namespace {

using Matrix26 = Eigen::Matrix<double, 2, 6>;
using Matrix23 = Eigen::Matrix<double, 2, 3>;
using Matrix63 = Eigen::Matrix<double, 6, 3>;

// Sums of 6 x 6 (generally e_size x e_size) blocks of S by pair (a, b), a <= b of e blocks.
class PairSums {
 public:
  PairSums(const std::vector<int>& e_sizes, int num_blocks) : e_sizes_(&e_sizes), num_blocks_(num_blocks) {}
  Eigen::MatrixXd& operator()(int a, int b) {
    const auto [it, inserted] = index_.emplace(Key(a, b), static_cast<int>(value_.size()));
    if (inserted) value_.push_back(Eigen::MatrixXd::Zero((*e_sizes_)[a], (*e_sizes_)[b]));
    return value_[it->second];
  }
  // Adds other's sums into these, in other's order of first use.
  void Add(PairSums&& other) {
    std::vector<std::pair<int, int64_t>> order;
    order.reserve(other.index_.size());
    for (const auto& [key, index] : other.index_) order.push_back({index, key});
    std::sort(order.begin(), order.end());
    for (const auto& [index, key] : order) {
      const auto [it, inserted] = index_.emplace(key, static_cast<int>(value_.size()));
      if (inserted)
        value_.push_back(std::move(other.value_[index]));
      else
        value_[it->second] += other.value_[index];
    }
    other.index_.clear();
    other.value_.clear();
  }
  // The upper triangle of S, block_start the first column of each e block.
  void Triplets(const std::vector<int>& block_start,
                std::vector<Eigen::Triplet<double, int>>* entries) const {
    for (const auto& [key, index] : index_) {
      const int a = static_cast<int>(key / num_blocks_), b = static_cast<int>(key % num_blocks_);
      const Eigen::MatrixXd& value = value_[index];
      for (int r = 0; r < value.rows(); ++r)
        for (int c = 0; c < value.cols(); ++c)
          entries->emplace_back(block_start[a] + r, block_start[b] + c, value(r, c));
    }
  }

 private:
  int64_t Key(int a, int b) const { return static_cast<int64_t>(a) * num_blocks_ + b; }
  const std::vector<int>* e_sizes_;
  int num_blocks_;
  std::unordered_map<int64_t, int> index_;
  std::vector<Eigen::MatrixXd> value_;
};

// J_e^T J_e of one residual block's rows into the pair sums.
void AddCameraPart(const BlockRows& rows, const std::vector<int>& e_sizes, PairSums* pairs) {
  const int num_parts = static_cast<int>(rows.e_blocks.size());
  int column_k = 0;
  for (int k = 0; k < num_parts; ++k) {
    const int size_k = e_sizes[rows.e_blocks[k]];
    int column_l = 0;
    for (int l = 0; l < num_parts; ++l) {
      const int size_l = e_sizes[rows.e_blocks[l]];
      const int a = rows.e_blocks[k], b = rows.e_blocks[l];
      if (a > b) {
        // Its transpose is the (b, a) term.
      } else if (rows.rows == 2 && size_k == 6 && size_l == 6) {
        // A mark on an image (J_e column-major with 2 rows: a column's pair at data + 2 c).
        Eigen::Map<Matrix6d>((*pairs)(a, b).data()).noalias() +=
            Eigen::Map<const Matrix26>(rows.J_e.data() + 2 * column_k).transpose() *
            Eigen::Map<const Matrix26>(rows.J_e.data() + 2 * column_l);
      } else {
        (*pairs)(a, b).noalias() +=
            rows.J_e.middleCols(column_k, size_k).transpose() * rows.J_e.middleCols(column_l, size_l);
      }
      column_l += size_l;
    }
    column_k += size_k;
  }
}

// The rows of residual blocks sharing a point: the residuals grouped by point, each residual
// block's point found once; and the points in the order of their first e block, so that points
// taken one after another share images (their blocks of S and of C stay in the cache).
void GroupResidualsByPoint(const BundleRound& round, int num_threads, ReducedNormals* reduced) {
  const size_t num_residuals = round.residuals.size();
  const int num_blocks = static_cast<int>(round.e_blocks.size());
  std::vector<int> point_of(num_residuals, -1), first_e_of(num_residuals, num_blocks);
  ParallelForChunks(num_residuals, num_threads, 4096, [&](size_t r) {
    thread_local std::vector<double*> parameters;
    ResidualParameters(round, round.residuals[r], &parameters);
    for (const double* block_ptr : parameters) {
      const auto p = reduced->point_index.find(block_ptr);
      if (p != reduced->point_index.end()) point_of[r] = p->second;
      const auto e = reduced->e_index.find(block_ptr);
      if (e != reduced->e_index.end()) first_e_of[r] = std::min(first_e_of[r], e->second);
    }
  });
  const size_t num_points = round.point_blocks.size();
  std::vector<int>& start = reduced->point_residual_start;
  start.assign(num_points + 2, 0);
  std::vector<int> first_e(num_points, num_blocks);
  for (size_t r = 0; r < num_residuals; ++r) {
    const int p = point_of[r];
    ++start[(p >= 0 ? p : static_cast<int>(num_points)) + 1];
    if (p >= 0) first_e[p] = std::min(first_e[p], first_e_of[r]);
  }
  for (size_t p = 0; p <= num_points; ++p) start[p + 1] += start[p];
  std::vector<int> next(start.begin(), start.end() - 1);
  reduced->residual_order.assign(num_residuals, -1);
  for (size_t r = 0; r < num_residuals; ++r) {
    const int p = point_of[r] >= 0 ? point_of[r] : static_cast<int>(num_points);
    reduced->residual_order[next[p]++] = static_cast<int>(r);
  }
  start.pop_back();  // start[num_points]: the first residual without a point
  reduced->point_order.resize(num_points);
  std::iota(reduced->point_order.begin(), reduced->point_order.end(), 0);
  std::stable_sort(reduced->point_order.begin(), reduced->point_order.end(),
                   [&](int a, int b) { return first_e[a] < first_e[b]; });
}

// Points per chunk of the reduction: the sums are made chunk by chunk and added in chunk order,
// whatever the number of threads.
constexpr int kPointsPerChunk = 1024;

// Every variable block of the round: the e blocks, their columns one after another, then the
// points. Returns the first column of each e block, and S's size after the last.
std::vector<int> IndexVariables(const BundleRound& round, ReducedNormals* reduced) {
  const auto add_variable = [&](double* values, int e_block, int point, int ambient,
                                const ceres::Manifold* manifold) {
    VariableBlock& v = reduced->variables[values];
    v.e_block = e_block;
    v.point = point;
    v.ambient = ambient;
    v.tangent = manifold != nullptr ? manifold->TangentSize() : v.ambient;
    if (manifold != nullptr) {
      v.plus_jacobian.assign(static_cast<size_t>(v.ambient) * v.tangent, 0.0);
      manifold->PlusJacobian(values, v.plus_jacobian.data());
    }
  };
  int offset = 0;
  std::vector<int> block_start;
  for (int b = 0; b < static_cast<int>(round.e_blocks.size()); ++b) {
    reduced->e_index[round.e_blocks[b]] = b;
    reduced->e_offset.push_back(offset);
    block_start.push_back(offset);
    offset += round.e_sizes[b];
    add_variable(round.e_blocks[b], b, -1, round.e_ambient_sizes[b], round.e_manifolds[b]);
  }
  block_start.push_back(offset);
  reduced->size = offset;
  for (int p = 0; p < static_cast<int>(round.point_blocks.size()); ++p) {
    reduced->point_index[round.point_blocks[p]] = p;
    add_variable(round.point_blocks[p], -1, p, kPointSize, nullptr);
  }
  return block_start;
}

// A point's rows of J_e^T J_p per e block (e block, e_size x 3); kept across points for their
// memory.
using PointParts = std::vector<std::pair<int, Eigen::MatrixXd>>;

// One residual block's J_e^T J_p added to the point's parts (the part of an e block made at its
// first residual block). The one arithmetic of W: the elimination and PointW.
void AddPointParts(const BlockRows& rows, const std::vector<int>& e_sizes, PointParts* parts) {
  const bool mark = rows.rows == 2;  // 2 x 6 on an image, 2 x 3 on the point: unrolled
  int column = 0;
  for (const int e : rows.e_blocks) {
    const int size = e_sizes[e];
    auto found = std::find_if(parts->begin(), parts->end(),
                              [&](const auto& part) { return part.first == e; });
    if (found == parts->end()) {
      parts->emplace_back(e, Eigen::MatrixXd::Zero(size, 3));
      found = parts->end() - 1;
    }
    if (mark && size == 6)
      Eigen::Map<Matrix63>(found->second.data()).noalias() +=
          Eigen::Map<const Matrix26>(rows.J_e.data() + 2 * column).transpose() *
          Eigen::Map<const Matrix23>(rows.J_p.data());
    else
      found->second.noalias() += rows.J_e.middleCols(column, size).transpose() * rows.J_p;
    column += size;
  }
}

// The parts in ascending e block order, one under another: W (their rows x 3); *blocks (may be
// null) receives their e blocks, *start (may be null) each one's first row of W and the end.
void StackParts(PointParts* parts, std::vector<int>* blocks, std::vector<int>* start,
                Eigen::MatrixXd* W) {
  std::sort(parts->begin(), parts->end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  int rows = 0;
  for (const auto& part : *parts) rows += static_cast<int>(part.second.rows());
  W->resize(rows, 3);
  if (start != nullptr) start->assign(1, 0);
  int at = 0;
  for (const auto& [e, part] : *parts) {
    if (blocks != nullptr) blocks->push_back(e);
    W->middleRows(at, part.rows()) = part;
    at += static_cast<int>(part.rows());
    if (start != nullptr) start->push_back(at);
  }
}

// Point p's residual blocks: their J_e^T J_e into the pair sums, *V = J_p^T J_p and *parts. False
// when one cannot be evaluated. One loop on purpose: each residual block's rows are evaluated
// once and used at once, while they are in the cache.
bool AccumulatePointRows(const BundleRound& round, const ReducedNormals& reduced, int p,
                         BlockRows* rows, PairSums* pairs, Eigen::Matrix3d* V, PointParts* parts) {
  *V = Eigen::Matrix3d::Zero();
  parts->clear();
  for (int k = reduced.point_residual_start[p]; k < reduced.point_residual_start[p + 1]; ++k) {
    if (!EvaluateBlockRows(round, reduced, round.residuals[reduced.residual_order[k]], rows))
      return false;
    AddCameraPart(*rows, round.e_sizes, pairs);
    if (rows->rows == 2) {  // a mark: unrolled
      const Eigen::Map<const Matrix23> J_p(rows->J_p.data());
      V->noalias() += J_p.transpose() * J_p;
    } else {
      V->noalias() += rows->J_p.transpose() * rows->J_p;
    }
    AddPointParts(*rows, round.e_sizes, parts);
  }
  return true;
}

// Point p eliminated: V^-1 (false when V is not positive definite), W = its parts in ascending e
// block order (not kept: PointW makes it again), and W V^-1 W^T subtracted from the pair sums.
bool EliminatePoint(int p, const Eigen::Matrix3d& V, PointParts* parts, ReducedNormals* reduced,
                    PairSums* pairs) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(V);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return false;
  reduced->V_inverse[p] = ldlt.solve(Eigen::Matrix3d::Identity());
  std::vector<int> start;
  Eigen::MatrixXd W;
  StackParts(parts, &reduced->W_blocks[p], &start, &W);
  const Eigen::MatrixXd WV = W * reduced->V_inverse[p];
  for (size_t k = 0; k < parts->size(); ++k) {
    for (size_t l = k; l < parts->size(); ++l) {
      Eigen::MatrixXd& block = (*pairs)((*parts)[k].first, (*parts)[l].first);
      if (block.rows() == 6 && block.cols() == 6)  // two images: unrolled
        Eigen::Map<Matrix6d>(block.data()).noalias() -=
            WV.block<6, 3>(start[k], 0) * W.block<6, 3>(start[l], 0).transpose();
      else
        block.noalias() -= WV.middleRows(start[k], start[k + 1] - start[k]) *
                           W.middleRows(start[l], start[l + 1] - start[l]).transpose();
    }
  }
  return true;
}

// The points chunk by chunk, a wave of chunks at a time on the threads; each chunk's sums of S
// (J_e^T J_e of its rows less W V^-1 W^T of its points) added to *total in chunk order. Per point:
// whether its rows were evaluated, and whether it is determined.
void ReducePoints(const BundleRound& round, int num_threads, ReducedNormals* reduced,
                  PairSums* total, std::vector<char>* evaluated, std::vector<char>* determined) {
  const int num_blocks = static_cast<int>(round.e_blocks.size());
  const int num_points = static_cast<int>(round.point_blocks.size());
  reduced->V_inverse.resize(num_points);
  reduced->W_blocks.resize(num_points);
  evaluated->assign(num_points, 1);
  determined->assign(num_points, 1);
  const int num_chunks = (num_points + kPointsPerChunk - 1) / kPointsPerChunk;
  const int wave = ResolveThreadCount(num_threads);
  for (int first_chunk = 0; first_chunk < num_chunks; first_chunk += wave) {
    const int chunks = std::min(wave, num_chunks - first_chunk);
    std::vector<PairSums> sums(chunks, PairSums(round.e_sizes, num_blocks));
    ParallelFor(chunks, num_threads, [&](size_t c) {
      BlockRows rows;
      PointParts parts;
      const int begin = (first_chunk + static_cast<int>(c)) * kPointsPerChunk;
      const int end = std::min(num_points, begin + kPointsPerChunk);
      for (int at = begin; at < end; ++at) {
        const int p = reduced->point_order[at];
        Eigen::Matrix3d V;
        if (!AccumulatePointRows(round, *reduced, p, &rows, &sums[c], &V, &parts))
          (*evaluated)[p] = 0;
        else if (!EliminatePoint(p, V, &parts, reduced, &sums[c]))
          (*determined)[p] = 0;
      }
    });
    for (PairSums& chunk : sums) total->Add(std::move(chunk));
  }
}

// The residual blocks without a point (priors on e blocks), in round order, into the sums. False
// when one cannot be evaluated.
bool AddRowsWithoutPoint(const BundleRound& round, const ReducedNormals& reduced, PairSums* total) {
  BlockRows rows;
  const size_t num_points = round.point_blocks.size();
  for (size_t k = reduced.point_residual_start[num_points]; k < reduced.residual_order.size();
       ++k) {
    if (!EvaluateBlockRows(round, reduced, round.residuals[reduced.residual_order[k]], &rows))
      return false;
    AddCameraPart(rows, round.e_sizes, total);
  }
  return true;
}

// S from the sums (which are emptied) and its selected inverse; a singular S's block and
// component named.
void FactorReducedNormals(const BundleRound& round, const std::vector<int>& block_start,
                          const SelectedInversionOptions& options, PairSums* total,
                          ReducedNormals* reduced) {
  const int size = reduced->size;
  std::vector<Eigen::Triplet<double, int>> entries;
  total->Triplets(block_start, &entries);
  *total = PairSums(round.e_sizes, static_cast<int>(round.e_blocks.size()));
  SelectedInverse::SparseMatrix S(size, size);
  S.setFromTriplets(entries.begin(), entries.end());
  std::vector<Eigen::Triplet<double, int>>().swap(entries);
  reduced->S_nonzeros = 2 * S.nonZeros() - size;
  const Status status = reduced->C.Compute(S, block_start, options);
  if (!status.ok()) {
    reduced->message = status.message();
    reduced->singular = reduced->C.singular();
    const int column = reduced->C.singular_column();
    if (column >= 0) {
      const int b =
          static_cast<int>(std::upper_bound(block_start.begin(), block_start.end(), column) -
                           block_start.begin()) -
          1;
      reduced->singular_block = b;
      reduced->singular_component = column - block_start[b];
    }
    return;
  }
  reduced->ok = true;
}

}  // namespace

void BuildReducedNormals(const BundleRound& round, const SelectedInversionOptions& options,
                         int num_threads, ReducedNormals* reduced) {
  *reduced = ReducedNormals();
  const std::vector<int> block_start = IndexVariables(round, reduced);
  GroupResidualsByPoint(round, num_threads, reduced);
  PairSums total(round.e_sizes, static_cast<int>(round.e_blocks.size()));
  std::vector<char> evaluated, determined;
  ReducePoints(round, num_threads, reduced, &total, &evaluated, &determined);
  const bool all_evaluated = std::find(evaluated.begin(), evaluated.end(), 0) == evaluated.end() &&
                             AddRowsWithoutPoint(round, *reduced, &total);
  if (!all_evaluated) {
    reduced->message = "a residual could not be evaluated at the solution";
    return;
  }
  const auto undetermined = std::find(determined.begin(), determined.end(), 0);
  if (undetermined != determined.end()) {
    reduced->message = "a point is not determined by its rays";
    reduced->singular = true;
    reduced->undetermined_point = static_cast<int>(undetermined - determined.begin());
    return;
  }
  if (reduced->size == 0) {
    reduced->ok = true;
    return;
  }
  FactorReducedNormals(round, block_start, options, &total, reduced);
}

void PointW(const BundleRound& round, const ReducedNormals& reduced, int p, const BlockRows* rows,
            Eigen::MatrixXd* W) {
  thread_local PointParts parts;
  parts.clear();
  const int count = reduced.point_residual_start[p + 1] - reduced.point_residual_start[p];
  for (int k = 0; k < count; ++k) AddPointParts(rows[k], round.e_sizes, &parts);
  StackParts(&parts, nullptr, nullptr, W);
}

bool EvaluatePointW(const BundleRound& round, const ReducedNormals& reduced, int p,
                    std::vector<BlockRows>* scratch, Eigen::MatrixXd* W) {
  const int begin = reduced.point_residual_start[p];
  const int count = reduced.point_residual_start[p + 1] - begin;
  if (scratch->size() < static_cast<size_t>(count)) scratch->resize(count);
  for (int k = 0; k < count; ++k) {
    if (!EvaluateBlockRows(round, reduced, round.residuals[reduced.residual_order[begin + k]],
                           &(*scratch)[k]))
      return false;
  }
  PointW(round, reduced, p, scratch->data(), W);
  return true;
}

bool ForEachPointW(const BundleRound& round, const ReducedNormals& reduced, int num_threads,
                   const std::function<void(int p, const Eigen::MatrixXd& W)>& use) {
  const int num_points = static_cast<int>(reduced.V_inverse.size());
  const int wave = ResolveThreadCount(num_threads) * kPointsPerChunk;
  std::vector<Eigen::MatrixXd> W(std::min(wave, num_points));
  for (int first = 0; first < num_points; first += wave) {
    const int count = std::min(wave, num_points - first);
    std::vector<char> evaluated(count, 1);
    ParallelForChunks(count, num_threads, kPointsPerChunk, [&](size_t k) {
      thread_local std::vector<BlockRows> scratch;
      evaluated[k] = EvaluatePointW(round, reduced, first + static_cast<int>(k), &scratch, &W[k]);
    });
    for (int k = 0; k < count; ++k) {
      if (!evaluated[k]) return false;
      use(first + k, W[k]);
    }
  }
  return true;
}

int SupportCovariance::Offset(int e_block) const {
  const auto found = std::lower_bound(blocks.begin(), blocks.end(), e_block);
  if (found == blocks.end() || *found != e_block) return -1;
  return block_offset[found - blocks.begin()];
}

bool MakeSupportCovariance(const ReducedNormals& reduced, int p, const Eigen::MatrixXd* W,
                           const std::vector<int>& blocks, SupportCovariance* support) {
  support->blocks = p >= 0 ? reduced.W_blocks[p] : blocks;
  std::sort(support->blocks.begin(), support->blocks.end());
  support->block_offset.assign(support->blocks.size(), 0);
  int k = 0;
  for (size_t b = 0; b < support->blocks.size(); ++b) {
    support->block_offset[b] = k;
    k += reduced.C.block_size(support->blocks[b]);
  }
  if (!reduced.C.Blocks(support->blocks, &support->C)) return false;
  if (p >= 0) {
    support->WV = *W * reduced.V_inverse[p];
    support->T = support->C * support->WV;
    support->Q = support->WV.transpose() * support->T;
  } else {
    support->WV.resize(k, 0);
    support->T.resize(k, 0);
    support->Q.setZero();
  }
  return true;
}

Eigen::Matrix3d PointCovariance(const ReducedNormals& reduced, const SupportCovariance& support,
                                int p) {
  return reduced.V_inverse[p] + support.Q;
}

// h_i = g_i^T C g_i + J_p,i V^-1 J_p,i^T with g_i = E_i - W V^-1 J_p,i^T in the support's
// columns (E_i: the row's own e part): the point's own part and its elimination folded in. With
// T = C W V^-1 and Q = V^-1 W^T C W V^-1 once per point, g^T C g = E^T C E - 2 E^T T q + q^T Q q
// (q = J_p,i^T) costs a row only its own columns; C g = C E - T q is the parameters' response.
Eigen::VectorXd Leverages(const ReducedNormals& reduced, const SupportCovariance& support,
                          const BlockRows& rows, const std::vector<int>* centres,
                          Eigen::VectorXd* largest_shift) {
  // The support positions of the row's own columns.
  std::vector<int> own;
  own.reserve(rows.e_columns.size());
  for (const int b : rows.e_blocks) {
    const int at = support.Offset(b);
    for (int c = 0; c < reduced.C.block_size(b); ++c) own.push_back(at + c);
  }
  const int ne = static_cast<int>(own.size());
  const int k = static_cast<int>(support.C.rows());
  Eigen::MatrixXd C_own(ne, ne);
  for (int a = 0; a < ne; ++a)
    for (int b = 0; b < ne; ++b) C_own(a, b) = support.C(own[a], own[b]);
  const bool with_point = rows.point >= 0;
  Eigen::VectorXd h(rows.rows);
  if (largest_shift != nullptr) largest_shift->resize(rows.rows);
  for (int r = 0; r < rows.rows; ++r) {
    // A row with no camera columns (a control point's prior) has an empty J_e: no row view of it
    // (Eigen would offset a null pointer).
    const Eigen::VectorXd e = rows.J_e.cols() > 0 ? Eigen::VectorXd(rows.J_e.row(r).transpose()) : Eigen::VectorXd();
    double value = e.dot(C_own * e);
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    if (with_point) {
      q = rows.J_p.row(r).transpose();
      double e_Tq = 0.0;
      const Eigen::VectorXd Tq = support.T * q;
      for (int a = 0; a < ne; ++a) e_Tq += e[a] * Tq[own[a]];
      value += -2.0 * e_Tq + q.dot(support.Q * q) + q.dot(reduced.V_inverse[rows.point] * q);
    }
    h[r] = value;
    if (largest_shift == nullptr) continue;
    Eigen::VectorXd Cg = Eigen::VectorXd::Zero(k);
    for (int a = 0; a < ne; ++a) Cg += support.C.col(own[a]) * e[a];
    if (with_point) Cg -= support.T * q;
    double largest = 0.0;
    for (size_t b = 0; b < support.blocks.size(); ++b) {
      const int count = (*centres)[support.blocks[b]];
      if (count > 0) largest = std::max(largest, Cg.segment(support.block_offset[b], count).norm());
    }
    (*largest_shift)[r] = largest;
  }
  return h;
}

}  // namespace photopose::internal
