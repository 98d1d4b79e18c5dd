#include "squeeze/meshing/surface.h"

#include <algorithm>
#include <cmath>

namespace squeeze::meshing {

void bounding_box(const Eigen::MatrixX3d& V, Eigen::RowVector3d& lo, Eigen::RowVector3d& hi) {
  lo = V.colwise().minCoeff();
  hi = V.colwise().maxCoeff();
}

double bounding_box_diagonal(const Eigen::MatrixX3d& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

std::vector<Eigen::Vector3d> surface_samples(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double spacing) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<size_t>(V.rows()));
  std::vector<char> used(static_cast<size_t>(V.rows()), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) used[static_cast<size_t>(F(f, k))] = 1;
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    if (used[static_cast<size_t>(i)]) out.push_back(V.row(i).transpose());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)).transpose(), b = V.row(F(f, 1)).transpose(), c = V.row(F(f, 2)).transpose();
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int n = std::min(64, static_cast<int>(std::ceil(longest / spacing)));
    if (n < 2) continue;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n - i; ++j) {
        if ((i == 0 && j == 0) || (i == n && j == 0) || (i == 0 && j == n)) continue;
        out.push_back(a + (static_cast<double>(i) / n) * (b - a) + (static_cast<double>(j) / n) * (c - a));
      }
  }
  return out;
}

}  // namespace squeeze::meshing
