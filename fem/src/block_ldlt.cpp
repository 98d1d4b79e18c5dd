// Sparse LDLᵀ of a symmetric matrix of 3×3 blocks (block_ldlt.h).
#include "squeeze/fem/block_ldlt.h"

#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cassert>
#include <cmath>

namespace squeeze::fem {

void BlockLDLT::analyze(int n, const std::vector<std::pair<int, int>>& pairs) {
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
  // Elimination tree and column counts (Davis 2005, ldl_symbolic).
  parent_.assign(static_cast<size_t>(n), -1);
  flag_.assign(static_cast<size_t>(n), -1);
  count_.assign(static_cast<size_t>(n), 0);
  for (int k = 0; k < n; ++k) {
    flag_[k] = k;
    for (int p = Ap_[k]; p < Ap_[k + 1]; ++p)
      for (int i = Ai_[p]; i < k && flag_[i] != k; i = parent_[i]) {
        if (parent_[i] == -1) parent_[i] = k;
        ++count_[i];
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
  Lx_.resize(Li_.size());
  Dinv_.resize(static_cast<size_t>(n));
  y_.assign(static_cast<size_t>(n), Mat3::Zero());
  pattern_.resize(static_cast<size_t>(n));
}

bool BlockLDLT::factorize(const std::vector<Mat3>& diag, const std::vector<Mat3>& off) {
  const int n = n_;
  assert(static_cast<int>(diag.size()) == n);
  std::fill(count_.begin(), count_.end(), 0);
  std::fill(flag_.begin(), flag_.end(), -1);
  // Davis 2005, ldl_numeric, on blocks: row k of L solves L(0:k,0:k) D Y = A(0:k, k) over the
  // pattern of row k (its reach in the elimination tree), Y(i) = block (i, k).
  for (int k = 0; k < n; ++k) {
    int top = n;
    flag_[k] = k;
    for (int p = Ap_[k]; p < Ap_[k + 1]; ++p) {
      int i = Ai_[p];
      const int s = Asrc_[p];
      if (s < 0)
        y_[i] += diag[static_cast<size_t>(-1 - s)];
      else if (s & 1)
        y_[i] += off[static_cast<size_t>(s >> 1)].transpose();
      else
        y_[i] += off[static_cast<size_t>(s >> 1)];
      int len = 0;
      for (; flag_[i] != k; i = parent_[i]) {
        pattern_[len++] = i;
        flag_[i] = k;
      }
      while (len > 0) pattern_[--top] = pattern_[--len];
    }
    Mat3 d = y_[k];
    y_[k].setZero();
    for (; top < n; ++top) {
      const int i = pattern_[top];
      const Mat3 yi = y_[i];
      y_[i].setZero();
      const int p2 = Lp_[i] + count_[i];
      for (int p = Lp_[i]; p < p2; ++p) y_[Li_[p]].noalias() -= Lx_[p] * yi;
      const Mat3 lki = yi.transpose() * Dinv_[i];  // L(k, i) = Y(i)ᵀ D(i)⁻¹
      d.noalias() -= lki * yi;
      Li_[p2] = k;
      Lx_[p2] = lki;
      ++count_[i];
    }
    d = 0.5 * (d + d.transpose());  // symmetric in exact arithmetic
    const double det = d.determinant();
    if (!std::isfinite(det) || det == 0) {
      for (Mat3& y : y_) y.setZero();
      return false;
    }
    Dinv_[k] = d.inverse();
    if (!Dinv_[k].allFinite()) {
      for (Mat3& y : y_) y.setZero();
      return false;
    }
  }
  return true;
}

void BlockLDLT::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  const int n = n_;
  assert(b.size() == 3 * static_cast<Eigen::Index>(n));
  w_.resize(b.size());
  for (int k = 0; k < n; ++k) w_.segment<3>(3 * k) = b.segment<3>(3 * static_cast<Eigen::Index>(perm_[k]));
  for (int j = 0; j < n; ++j) {  // L w = b
    const Eigen::Vector3d wj = w_.segment<3>(3 * j);
    for (int p = Lp_[j]; p < Lp_[j + 1]; ++p) w_.segment<3>(3 * static_cast<Eigen::Index>(Li_[p])).noalias() -= Lx_[p] * wj;
  }
  for (int j = 0; j < n; ++j) w_.segment<3>(3 * j) = Dinv_[j] * Eigen::Vector3d(w_.segment<3>(3 * j));  // D
  for (int j = n - 1; j >= 0; --j) {  // Lᵀ w = w
    Eigen::Vector3d wj = w_.segment<3>(3 * j);
    for (int p = Lp_[j]; p < Lp_[j + 1]; ++p) wj.noalias() -= Lx_[p].transpose() * w_.segment<3>(3 * static_cast<Eigen::Index>(Li_[p]));
    w_.segment<3>(3 * j) = wj;
  }
  x.resize(b.size());
  for (int k = 0; k < n; ++k) x.segment<3>(3 * static_cast<Eigen::Index>(perm_[k])) = w_.segment<3>(3 * k);
}

}  // namespace squeeze::fem
