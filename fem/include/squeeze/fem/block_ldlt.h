// squeeze::fem — sparse LDLᵀ factorisation of a symmetric matrix of 3×3 blocks (one block row per
// free vertex), the direct solver and preconditioner of the implicit integrator (implicit.h).
//
// The up-looking sparse LDLᵀ of T. A. Davis ("Algorithm 849: a concise sparse Cholesky
// factorization package", ACM TOMS 31(4), 2005, doi:10.1145/1114268.1114277; the algorithm of
// LDL and of Eigen's SimplicialLDLT) carried out on 3×3 blocks instead of scalars: the elimination
// tree, the row patterns and the fill are those of the vertex graph, every update is a 3×3 block
// product, and D is block diagonal (3×3 symmetric pivots, inverted). The fill-reducing ordering is
// approximate minimum degree (Amestoy, Davis, Duff 1996; Eigen's AMDOrdering) on the vertex graph.
// One index per 9 numbers instead of one per number: on the Hessians of the implicit step it
// factorises and solves faster than Eigen's scalar SimplicialLDLT (bench/README.md,
// "bench_integrators").
//
// Parallel and deterministic: analyze() cuts the elimination tree into disjoint subtrees, dealt to
// `parts` bins of about equal work (largest subtree first to the least loaded bin: Graham,
// "Bounds on multiprocessing timing anomalies", SIAM J. Appl. Math. 17(2), 1969), and a top (the rest: the ancestors of the cuts, the densest
// rows). factorize() and solve() run the bins in parallel (TBB) and the top after them (before them
// in the backward substitution); factorize() runs the top's rows on two threads, pipelined (row k
// beside row k − 1, waiting per column until the rows above it have put their blocks in it: the
// column entries arrive in row order, so every sum is the sequential one). A row of a subtree reads only its own subtree, and every row and
// every entry of x is summed in the same order as by the sequential algorithm, so the factors and
// solutions are bit for bit those of one part, whatever the number of parts or threads
// (FemBlockLDLT.PartsGiveBitIdenticalFactorsAndSolutions).
//
//   BlockLDLT f;
//   f.analyze(n, pairs);                  // once per pattern
//   if (f.factorize(diag, off)) f.solve(b, x);   // per matrix of that pattern
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace squeeze::fem {

class BlockLDLT {
 public:
  using Mat3 = Eigen::Matrix3d;

  /// Symbolic analysis of a pattern: the ordering, the elimination tree, the pattern of L.
  ///   n      block rows (and columns), >= 0
  ///   pairs  the off-diagonal blocks of the lower triangle, (I, J) with n > I > J >= 0, each once,
  ///          in any order; every diagonal block is present
  ///   parts  bins of subtrees run in parallel; 0: as many as TBB may run at once (its
  ///          global_control), 1: sequential. Patterns whose factorisation is too small to gain
  ///          (under kParallelUpdates block products), or whose elimination tree has no cut that
  ///          would take at least a tenth off the critical path, get one part.
  void analyze(int n, const std::vector<std::pair<int, int>>& pairs, int parts = 0);

  /// Numeric factorisation A = P⁻¹ L D Lᵀ P⁻ᵀ of a matrix of the analysed pattern.
  ///   diag  n symmetric 3×3 diagonal blocks
  ///   off   one 3×3 block per pair given to analyze, in that order: block (I, J) (rows of I, columns
  ///         of J; its transpose is block (J, I))
  /// Returns false if a pivot block is singular or not finite (A indefinite is fine otherwise: D
  /// may have negative eigenvalues). Before any successful factorisation solve must not be called.
  bool factorize(const std::vector<Mat3>& diag, const std::vector<Mat3>& off);

  /// x = A⁻¹ b with the last factorisation. b, x  3n (may not alias).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  /// x ≈ A⁻¹ b with L rounded to single precision (D and the arithmetic in double): about half the
  /// memory traffic of solve(), for preconditioning (relative error about 1e-7 × cond(L)).
  void precondition(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

  int blocks() const { return n_; }
  /// Off-diagonal 3×3 blocks of L (its fill).
  long long factor_blocks() const { return static_cast<long long>(Li_.size()); }
  /// 3×3 block products of one factorisation (Σ over the columns of L of c (c + 1) / 2, c the
  /// column's blocks): its cost, against 2 · factor_blocks() block-vector products of a solve.
  long long factor_updates() const { return updates_; }
  /// Bins of subtrees of the last analyze() (1: sequential).
  int parts() const { return std::max(1, static_cast<int>(bin_rows_.size())); }
  /// Block products of the factorisation's rows run after the bins (its sequential part), and the
  /// largest bin's: the critical path is their sum, against factor_updates() in sequence.
  long long top_updates() const { return top_updates_; }
  long long largest_bin_updates() const { return bin_updates_; }
  /// Whether factorize() runs the top's rows on two threads, pipelined: row k beside row k − 1,
  /// each waiting per column for the blocks of the rows above it (bit for bit the sequential
  /// factor). Chosen by analyze() when more than one part was asked for (or TBB allows more than
  /// one thread) and the top has at least kParallelUpdates block products.
  bool pipelined() const { return pipelined_; }
  /// The block rows (in the numbering of analyze's pairs) of the top, in elimination order.
  std::vector<int> top_vertices() const {
    std::vector<int> v;
    v.reserve(top_rows_.size());
    for (int k : top_rows_) v.push_back(perm_[static_cast<size_t>(k)]);
    return v;
  }

  /// Below this many block products per factorisation analyze() keeps one part.
  static constexpr long long kParallelUpdates = 200000;
  /// A factor (L in double) of at most this many bytes keeps its single-precision copy for
  /// precondition() as doubles: the same values, without a conversion per block and use.
  static constexpr size_t kRoundedInDouble = size_t{2} << 20;
  /// Replaces kRoundedInDouble from the next factorize() on (tests and benchmarks run either path
  /// with it; the results are the same bit for bit).
  void set_rounded_in_double(size_t bytes) { rounded_in_double_ = bytes; }

 private:
  void cut(int parts, const std::vector<long long>& row_cost);
  // kRight: the association of the single-precision factor's products (block_ldlt.cpp).
  // LT: the blocks' transposes (or null).
  template <bool kRight, class Block>
  void substitute(const std::vector<Block>& Lx, const std::vector<Mat3>* LT, const Eigen::VectorXd& b,
                  Eigen::VectorXd& x) const;

  int n_ = 0;
  long long updates_ = 0;    // factor_updates()
  std::vector<int> perm_;    // new block index -> old
  std::vector<int> iperm_;   // old -> new
  // The permuted upper triangle by column k: entries (row i <= k, source) where source >= 0 is
  // 2·q + t for pair q (t = 1: its transpose), and the diagonal is source −1 − old index.
  std::vector<int> Ap_, Ai_, Asrc_;
  std::vector<int> parent_;  // elimination tree
  std::vector<int> Lp_;      // column starts of L (block CSC, strictly lower)
  std::vector<int> Li_;      // row of each block of L
  std::vector<Mat3> Lx_;     // blocks of L: L(Li_[p], column)
  std::vector<Eigen::Matrix3f> Lf_;  // Lx_ in single precision (precondition), or empty and
  size_t rounded_in_double_ = kRoundedInDouble;
  std::vector<Mat3> Lr_, Lrt_;       // ... the same values as doubles, and their transposes, for a factor
                                     // of at most kRoundedInDouble bytes
  std::vector<Mat3> Dinv_;   // inverses of the pivot blocks
  // Workspace of factorize (mutable scratch of solve).
  std::vector<Mat3> y_;
  std::vector<int> flag_, pattern_, count_;
  // The pipelined top (factorize): the second thread's workspace, and per row whether D is known.
  bool pipelined_ = false;
  std::vector<Mat3> y2_;
  std::vector<int> flag2_, pattern2_, done_;
  mutable Eigen::VectorXd w_;
  // The parallel cut (analyze): the rows of each bin (ascending), the top rows (ascending), each
  // column's first block whose row is in the top (Lp_[j] for a top column), and the columns with
  // such blocks (ascending).
  std::vector<std::vector<int>> bin_rows_;
  std::vector<int> top_rows_, split_, split_cols_;
  std::vector<std::vector<int>> bin_pattern_;  // per-bin workspace of factorize
  long long top_updates_ = 0, bin_updates_ = 0;
};

}  // namespace squeeze::fem
