// Sparse LDLᵀ of a symmetric matrix of 3×3 blocks (block_ldlt.h).
#include "squeeze/fem/block_ldlt.h"

#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <tbb/global_control.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <thread>
#include <type_traits>

#include "block_kernels.h"

namespace squeeze::fem {
namespace {

// Column j of L into w: w(L_i(p)) −= L_p w(j) for p in [begin, end). The pointers are arguments,
// not a lambda's captures: the SSE2 stores may alias anything, and the loop reloaded captures
// from memory after each.
template <bool kRight, class Block>
void forward_column(const Block* L, const int* Li, double* w, int j, int begin, int end) {
  const double wj[3] = {w[3 * j], w[3 * j + 1], w[3 * j + 2]};
  for (int p = begin; p < end; ++p) blocks::product<blocks::Op::kSubtract, kRight>(L[p].data(), wj, w + 3 * static_cast<size_t>(Li[p]));
}

// w(j) −= Σ L_pᵀ w(L_i(p)) over p in [begin, end), in that order.
template <bool kRight, class Block>
void backward_column(const Block* L, const int* Li, double* w, int j, int begin, int end) {
  double wj[3] = {w[3 * j], w[3 * j + 1], w[3 * j + 2]};
  for (int p = begin; p < end; ++p) blocks::transposed_product<blocks::Op::kSubtract, kRight>(L[p].data(), w + 3 * static_cast<size_t>(Li[p]), wj);
  for (int c = 0; c < 3; ++c) w[3 * j + c] = wj[c];
}

// The same with the blocks' transposes given (LT_p = L_pᵀ, column-major): w(j) −= Σ LT_p w(L_i(p)),
// the product read by columns like the forward one (the same sums: entry c of L_pᵀ v is column c
// of L_p with v either way).
template <bool kRight>
void backward_column_transposed(const Eigen::Matrix3d* LT, const int* Li, double* w, int j, int begin, int end) {
  double wj[3] = {w[3 * j], w[3 * j + 1], w[3 * j + 2]};
  for (int p = begin; p < end; ++p) blocks::product<blocks::Op::kSubtract, kRight>(LT[p].data(), w + 3 * static_cast<size_t>(Li[p]), wj);
  for (int c = 0; c < 3; ++c) w[3 * j + c] = wj[c];
}

// Y(L_i(p)) −= L_p Y_i for p in [begin, end): factorize's updates of the rows below column i,
// column by column. (Loading L_p once per block instead of once per column, against the aliasing
// of the stores, did not help: GCC then spilled the broadcast entries of Y_i.)
void update_rows(const Eigen::Matrix3d* L, const int* Li, Eigen::Matrix3d* y, int begin, int end, const Eigen::Matrix3d& Yi) {
  const double yi[9] = {Yi(0, 0), Yi(1, 0), Yi(2, 0), Yi(0, 1), Yi(1, 1), Yi(2, 1), Yi(0, 2), Yi(1, 2), Yi(2, 2)};
  for (int p = begin; p < end; ++p) {
    double* t = y[Li[p]].data();
    for (int c = 0; c < 3; ++c) blocks::product<blocks::Op::kSubtract, false>(L[p].data(), yi + 3 * c, t + 3 * c);
  }
}

}  // namespace

void BlockLDLT::analyze(int n, const std::vector<std::pair<int, int>>& pairs, int parts) {
  assert(n >= 0);
  n_ = n;
  // Approximate minimum degree on the vertex graph (Eigen's AMD symmetrises the lower pattern).
  perm_.resize(static_cast<size_t>(n));
  iperm_.resize(static_cast<size_t>(n));
  if (n > 0) {
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> G(n, n);
    std::vector<Eigen::Triplet<double, int>> t;
    t.reserve(pairs.size() + static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) t.emplace_back(i, i, 1.0);
    for (const auto& p : pairs) {
      assert(p.first > p.second && p.second >= 0 && p.first < n);
      t.emplace_back(p.first, p.second, 1.0);
    }
    G.setFromTriplets(t.begin(), t.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;  // new -> old (Eigen's m_Pinv)
    Eigen::AMDOrdering<int>()(G, pinv);
    for (int k = 0; k < n; ++k) {
      perm_[k] = pinv.indices()[k];
      iperm_[perm_[k]] = k;
    }
  }
  // The permuted upper triangle by column, diagonal included.
  Ap_.assign(static_cast<size_t>(n) + 1, 0);
  for (int k = 0; k < n; ++k) ++Ap_[k + 1];
  for (const auto& p : pairs) ++Ap_[std::max(iperm_[p.first], iperm_[p.second]) + 1];
  for (int k = 0; k < n; ++k) Ap_[k + 1] += Ap_[k];
  Ai_.resize(static_cast<size_t>(Ap_[n]));
  Asrc_.resize(Ai_.size());
  std::vector<int> next(Ap_.begin(), Ap_.end() - 1);
  for (int k = 0; k < n; ++k) {
    const int at = next[iperm_[k]]++;
    Ai_[at] = iperm_[k];
    Asrc_[at] = -1 - k;
  }
  for (size_t q = 0; q < pairs.size(); ++q) {
    const int a = iperm_[pairs[q].first], b = iperm_[pairs[q].second];
    const int col = std::max(a, b), at = next[col]++;
    Ai_[at] = std::min(a, b);
    // Block (row, col) of the permuted matrix: (I, J) itself when I's new index is the row.
    Asrc_[at] = 2 * static_cast<int>(q) + (a > b ? 1 : 0);
  }
  // Elimination tree and column counts (Davis 2005, ldl_symbolic), and each row's cost in
  // factorize: a block product per block already in each column of its pattern, and one more.
  parent_.assign(static_cast<size_t>(n), -1);
  flag_.assign(static_cast<size_t>(n), -1);
  count_.assign(static_cast<size_t>(n), 0);
  std::vector<long long> row_cost(static_cast<size_t>(n), 0);
  for (int k = 0; k < n; ++k) {
    flag_[k] = k;
    for (int p = Ap_[k]; p < Ap_[k + 1]; ++p)
      for (int i = Ai_[p]; i < k && flag_[i] != k; i = parent_[i]) {
        if (parent_[i] == -1) parent_[i] = k;
        row_cost[k] += ++count_[i];
        flag_[i] = k;
      }
  }
  Lp_.assign(static_cast<size_t>(n) + 1, 0);
  updates_ = 0;
  for (int k = 0; k < n; ++k) {
    Lp_[k + 1] = Lp_[k] + count_[k];
    updates_ += static_cast<long long>(count_[k]) * (count_[k] + 1) / 2;
  }
  Li_.resize(static_cast<size_t>(Lp_[n]));
  // The pattern of L, each column's rows ascending (the order in which factorize appends them):
  // known here, so that the cut finds each column's blocks in the top's rows, and a row of the
  // pipelined top its slot in a column (its position among the column's rows) before the rows
  // above it have filled theirs.
  {
    std::vector<int> fill(Lp_.begin(), Lp_.end() - 1);
    std::fill(flag_.begin(), flag_.end(), -1);
    for (int k = 0; k < n; ++k) {
      flag_[k] = k;
      for (int p = Ap_[k]; p < Ap_[k + 1]; ++p)
        for (int i = Ai_[p]; i < k && flag_[i] != k; i = parent_[i]) {
          Li_[static_cast<size_t>(fill[i]++)] = k;
          flag_[i] = k;
        }
    }
  }
  Lx_.resize(Li_.size());
  Dinv_.resize(static_cast<size_t>(n));
  y_.assign(static_cast<size_t>(n), Mat3::Zero());
  pattern_.resize(static_cast<size_t>(n));
  if (parts <= 0) parts = static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  cut(parts, row_cost);
  // The top's rows on two threads, pipelined (factorize), where the top is large enough.
  pipelined_ = parts > 1 && top_updates_ >= kParallelUpdates && top_rows_.size() >= 2;
  if (pipelined_) {
    y2_.assign(static_cast<size_t>(n), Mat3::Zero());
    flag2_.assign(static_cast<size_t>(n), -1);
    pattern2_.resize(static_cast<size_t>(n));
  }
  done_.assign(static_cast<size_t>(n), 1);  // factorize clears the top's before it runs them
}

// The parallel cut of the elimination tree: greedily cut the subtree of most work (its root goes
// to the top, its children become subtrees) while the estimated critical path, the top's work plus
// max(largest subtree, subtrees' work / parts), falls; keep the best; deal the subtrees to the
// bins largest first, each to the least loaded bin (Graham's LPT rule). Ties go to the lower index:
// the cut is a function of the pattern and the number of parts (>= 1, resolved by analyze).
void BlockLDLT::cut(int parts, const std::vector<long long>& row_cost) {
  const int n = n_;
  bin_rows_.clear();
  bin_pattern_.clear();
  top_rows_.clear();
  top_updates_ = updates_;
  bin_updates_ = 0;
  std::vector<char> top(static_cast<size_t>(n), 1);
  std::vector<int> bin_of(static_cast<size_t>(n), -1);
  if (parts > 1 && updates_ >= kParallelUpdates) {
    std::vector<long long> work(row_cost);  // of each subtree
    for (int k = 0; k < n; ++k)
      if (parent_[k] >= 0) work[parent_[k]] += work[k];
    std::vector<int> head(static_cast<size_t>(n), -1), next(static_cast<size_t>(n), -1);
    for (int k = n - 1; k >= 0; --k)
      if (parent_[k] >= 0) {
        next[k] = head[parent_[k]];
        head[parent_[k]] = k;
      }
    // Max-heap of subtrees by work, the lower index first among equals.
    auto less = [&](int a, int b) { return work[a] < work[b] || (work[a] == work[b] && a > b); };
    std::vector<int> heap, cuts;
    for (int k = 0; k < n; ++k)
      if (parent_[k] < 0) heap.push_back(k);
    std::make_heap(heap.begin(), heap.end(), less);
    long long top_work = 0, rest = updates_, best = updates_;
    size_t best_cuts = 0;
    while (!heap.empty()) {
      const long long path = top_work + std::max(work[heap.front()], (rest + parts - 1) / parts);
      if (path < best) {
        best = path;
        best_cuts = cuts.size();
      }
      if (top_work >= best) break;
      std::pop_heap(heap.begin(), heap.end(), less);
      const int c = heap.back();
      heap.pop_back();
      cuts.push_back(c);
      top_work += row_cost[c];
      rest -= row_cost[c];
      for (int ch = head[c]; ch >= 0; ch = next[ch]) {
        heap.push_back(ch);
        std::push_heap(heap.begin(), heap.end(), less);
      }
    }
    if (best <= updates_ - updates_ / 10) {
      std::fill(top.begin(), top.end(), 0);
      for (size_t q = 0; q < best_cuts; ++q) top[cuts[q]] = 1;
      std::vector<int> roots;  // subtrees: not in the top, parent in the top or none
      for (int k = 0; k < n; ++k)
        if (!top[k] && (parent_[k] < 0 || top[parent_[k]])) roots.push_back(k);
      std::sort(roots.begin(), roots.end(), [&](int a, int b) { return less(b, a); });
      std::vector<long long> load(static_cast<size_t>(parts), 0);
      for (int r : roots) {
        const int b = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
        bin_of[r] = b;
        load[b] += work[r];
      }
      for (int k = n - 1; k >= 0; --k)
        if (!top[k] && bin_of[k] < 0) bin_of[k] = bin_of[parent_[k]];
      bin_rows_.resize(static_cast<size_t>(parts));
      for (int k = 0; k < n; ++k)
        if (!top[k]) bin_rows_[bin_of[k]].push_back(k);
      bin_rows_.erase(std::remove_if(bin_rows_.begin(), bin_rows_.end(), [](const std::vector<int>& r) { return r.empty(); }),
                      bin_rows_.end());
      top_updates_ = 0;
      for (int k = 0; k < n; ++k)
        if (top[k]) top_updates_ += row_cost[k];
      bin_updates_ = *std::max_element(load.begin(), load.end());
      bin_pattern_.assign(bin_rows_.size(), std::vector<int>(static_cast<size_t>(n)));
    }
  }
  for (int k = 0; k < n; ++k)
    if (top[k]) top_rows_.push_back(k);
  // Each column's blocks in top rows (from split_[j] on): the rows of a column are ancestors of it,
  // in ascending order (Li_, filled by analyze before the cut), and the top holds every ancestor of
  // its nodes, so these blocks are the column's last.
  split_.resize(static_cast<size_t>(n));
  split_cols_.clear();
  for (int j = 0; j < n; ++j) {
    int p = Lp_[j + 1];
    if (top[j])
      p = Lp_[j];
    else
      while (p > Lp_[j] && top[Li_[static_cast<size_t>(p - 1)]]) --p;
    split_[j] = p;
    if (split_[j] < Lp_[j + 1]) split_cols_.push_back(j);
  }
}

bool BlockLDLT::factorize(const std::vector<Mat3>& diag, const std::vector<Mat3>& off) {
  const int n = n_;
  assert(static_cast<int>(diag.size()) == n);
  std::fill(count_.begin(), count_.end(), 0);
  std::fill(flag_.begin(), flag_.end(), -1);
  std::atomic<bool> failed{false};
  // Davis 2005, ldl_numeric, on blocks: row k of L solves L(0:k,0:k) D Y = A(0:k, k) over the
  // pattern of row k (its reach in the elimination tree), Y(i) = block (i, k). A row of a bin
  // reaches only its own subtree: the bins touch disjoint entries of y_, flag_, count_ and L.
  // y, flag, pattern: the workspace of the thread running the row. pipelined: the row runs beside
  // the one before it (the top on two threads) and waits, for each column i of its pattern, until
  // the rows above it have put their blocks in column i (count_[i] reaches its slot's position)
  // and until D(i) is known (done_[i]); it then reads exactly what the sequential row would.
  auto row = [&](int k, Mat3* y, int* flag, int* pattern, auto pipelined_tag) {
    constexpr bool pipelined = decltype(pipelined_tag)::value;
    int top = n;
    flag[k] = k;
    for (int p = Ap_[k]; p < Ap_[k + 1]; ++p) {
      int i = Ai_[p];
      const int s = Asrc_[p];
      if (s < 0)
        y[i] += diag[static_cast<size_t>(-1 - s)];
      else if (s & 1)
        y[i] += off[static_cast<size_t>(s >> 1)].transpose();
      else
        y[i] += off[static_cast<size_t>(s >> 1)];
      int len = 0;
      for (; flag[i] != k; i = parent_[i]) {
        pattern[len++] = i;
        flag[i] = k;
      }
      while (len > 0) pattern[--top] = pattern[--len];
    }
    Mat3 d = y[k];
    y[k].setZero();
    for (; top < n; ++top) {
      const int i = pattern[top];
      int p2;
      if constexpr (pipelined) {
        p2 = static_cast<int>(std::lower_bound(Li_.begin() + Lp_[i], Li_.begin() + Lp_[i + 1], k) - Li_.begin());
        const int above = p2 - Lp_[i];
        for (int spins = 0; __atomic_load_n(&count_[i], __ATOMIC_ACQUIRE) != above ||
                            !__atomic_load_n(&done_[i], __ATOMIC_ACQUIRE);
             ++spins) {
          if (failed.load(std::memory_order_relaxed)) return false;
          if (spins > 64) std::this_thread::yield();
        }
      } else {
        p2 = Lp_[i] + count_[i];
      }
      const Mat3 yi = y[i];
      y[i].setZero();
      update_rows(Lx_.data(), Li_.data(), y, Lp_[i], p2, yi);
      const Mat3 lki = yi.transpose() * Dinv_[i];  // L(k, i) = Y(i)ᵀ D(i)⁻¹
      d.noalias() -= lki * yi;
      Lx_[p2] = lki;
      if constexpr (pipelined)
        __atomic_store_n(&count_[i], p2 - Lp_[i] + 1, __ATOMIC_RELEASE);
      else
        ++count_[i];
    }
    d = 0.5 * (d + d.transpose());  // symmetric in exact arithmetic
    const double det = d.determinant();
    if (!std::isfinite(det) || det == 0) return false;
    Dinv_[k] = d.inverse();
    if (!Dinv_[k].allFinite()) return false;
    if constexpr (pipelined) __atomic_store_n(&done_[k], 1, __ATOMIC_RELEASE);
    return true;
  };
  if (!bin_rows_.empty())
    tbb::parallel_for(0, static_cast<int>(bin_rows_.size()), [&](int b) {
      for (int k : bin_rows_[b])
        if (failed.load(std::memory_order_relaxed) || !row(k, y_.data(), flag_.data(), bin_pattern_[b].data(), std::false_type{})) {
          failed = true;
          return;
        }
    });
  if (!failed && pipelined_) {
    // The top's rows on two TBB tasks, each taking the next row not yet taken: a row waits only
    // for rows taken before it, which a running task holds, so one task alone also gets through
    // them all (TBB need not run both at once: inside the planner's parallel expansions it runs
    // the second only if a thread is idle). Each column receives its blocks in row order and every
    // sum runs in the sequential order: the factor is bit for bit the sequential one.
    std::fill(flag2_.begin(), flag2_.end(), -1);
    for (int k : top_rows_) done_[k] = 0;
    std::atomic<size_t> next{0};
    tbb::parallel_for(0, 2, [&](int lane) {
      Mat3* y = lane == 0 ? y_.data() : y2_.data();
      int* flag = lane == 0 ? flag_.data() : flag2_.data();
      int* pattern = lane == 0 ? pattern_.data() : pattern2_.data();
      for (size_t r = next++; r < top_rows_.size(); r = next++)
        if (failed.load(std::memory_order_relaxed) || !row(top_rows_[r], y, flag, pattern, std::true_type{})) {
          failed = true;
          return;
        }
    }, tbb::simple_partitioner());
  } else if (!failed) {
    for (int k : top_rows_)
      if (!row(k, y_.data(), flag_.data(), pattern_.data(), std::false_type{})) {
        failed = true;
        break;
      }
  }
  if (failed) {
    for (Mat3& y : y_) y.setZero();
    for (Mat3& y : y2_) y.setZero();
    return false;
  }
  // L rounded to single precision for precondition(): half the bytes per substitution. A factor
  // that fits in the cache keeps the rounded values as doubles (exactly the same numbers): its
  // substitutions are not memory-bound, and converting every block twice per substitution cost
  // more than the bytes saved (kRoundedInDouble).
  const bool in_double = Lx_.size() * sizeof(Mat3) <= rounded_in_double_;
  Lf_.resize(in_double ? 0 : Lx_.size());
  Lr_.resize(in_double ? Lx_.size() : 0);
  Lrt_.resize(Lr_.size());
  auto round = [&](size_t begin, size_t end) {
    if (in_double)
      for (size_t p = begin; p < end; ++p) {
        Lr_[p] = Lx_[p].cast<float>().cast<double>();
        Lrt_[p] = Lr_[p].transpose();
      }
    else
      for (size_t p = begin; p < end; ++p) Lf_[p] = Lx_[p].cast<float>();
  };
  if (bin_rows_.empty())
    round(0, Lx_.size());
  else
    tbb::parallel_for(tbb::blocked_range<size_t>(0, Lx_.size(), 16384), [&](const tbb::blocked_range<size_t>& r) { round(r.begin(), r.end()); });
  return true;
}

template <bool kRight, class Block>
void BlockLDLT::substitute(const std::vector<Block>& Lx, const std::vector<Mat3>* LT, const Eigen::VectorXd& b,
                           Eigen::VectorXd& x) const {
  const int n = n_;
  assert(b.size() == 3 * static_cast<Eigen::Index>(n));
  w_.resize(b.size());
  for (int k = 0; k < n; ++k) w_.segment<3>(3 * k) = b.segment<3>(3 * static_cast<Eigen::Index>(perm_[k]));
  // L w = b by columns: the bins' columns into their own rows, then every column into the top's
  // rows in ascending column order (each entry of w receives its terms in the sequential order).
  double* const w = w_.data();
  const Block* const L = Lx.data();
  auto forward = [&](int j, int begin, int end) { forward_column<kRight>(L, Li_.data(), w, j, begin, end); };
  // Lᵀ w = w by columns, each reading its ancestors (done before it: the top before the bins).
  auto backward = [&](int j) {
    if (LT)
      backward_column_transposed<kRight>(LT->data(), Li_.data(), w, j, Lp_[j], Lp_[j + 1]);
    else
      backward_column<kRight>(L, Li_.data(), w, j, Lp_[j], Lp_[j + 1]);
  };
  if (!bin_rows_.empty())
    tbb::parallel_for(0, static_cast<int>(bin_rows_.size()), [&](int bin) {
      for (int j : bin_rows_[bin]) forward(j, Lp_[j], split_[j]);
    });
  for (int j : split_cols_) forward(j, split_[j], Lp_[j + 1]);
  for (int j = 0; j < n; ++j) w_.segment<3>(3 * j) = Dinv_[j] * Eigen::Vector3d(w_.segment<3>(3 * j));  // D
  for (auto j = top_rows_.rbegin(); j != top_rows_.rend(); ++j) backward(*j);
  if (!bin_rows_.empty())
    tbb::parallel_for(0, static_cast<int>(bin_rows_.size()), [&](int bin) {
      for (auto j = bin_rows_[bin].rbegin(); j != bin_rows_[bin].rend(); ++j) backward(*j);
    });
  x.resize(b.size());
  for (int k = 0; k < n; ++k) x.segment<3>(3 * static_cast<Eigen::Index>(perm_[k])) = w_.segment<3>(3 * k);
}

void BlockLDLT::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const { substitute<false>(Lx_, nullptr, b, x); }

void BlockLDLT::precondition(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  if (Lr_.empty())
    substitute<true>(Lf_, nullptr, b, x);
  else
    substitute<true>(Lr_, &Lrt_, b, x);
}

}  // namespace squeeze::fem
