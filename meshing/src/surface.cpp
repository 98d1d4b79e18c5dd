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
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for_each_lattice_point(V.row(F(f, 0)).transpose(), V.row(F(f, 1)).transpose(), V.row(F(f, 2)).transpose(), spacing,
                           [&](const Eigen::Vector3d& x) { out.push_back(x); });
  return out;
}

}  // namespace squeeze::meshing
