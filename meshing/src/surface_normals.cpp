// Area-weighted face and vertex normals (surface_normals.h).
#include "squeeze/meshing/surface_normals.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <cassert>

namespace squeeze::meshing {

void area_weighted_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, Eigen::MatrixX3d& FN,
                           Eigen::MatrixX3d& N) {
  const Eigen::Index nf = F.rows();
  assert(nf == 0 || (F.minCoeff() >= 0 && F.maxCoeff() < V.rows()));
  FN.resize(nf, 3);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, nf, 8192), [&](const tbb::blocked_range<Eigen::Index>& r) {
    for (Eigen::Index f = r.begin(); f != r.end(); ++f) {
      const Eigen::RowVector3d a = V.row(F(f, 0));
      FN.row(f) = (V.row(F(f, 1)) - a).cross(V.row(F(f, 2)) - a);
    }
  });
  // Scatter in face order (serial: deterministic sums).
  N = Eigen::MatrixX3d::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += FN.row(f);
}

void angle_weighted_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, Eigen::MatrixX3d& N) {
  assert(F.rows() == 0 || (F.minCoeff() >= 0 && F.maxCoeff() < V.rows()));
  N = Eigen::MatrixX3d::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::RowVector3d n = (V.row(F(f, 1)) - V.row(F(f, 0))).cross(V.row(F(f, 2)) - V.row(F(f, 0)));
    const double len = n.norm();
    if (!(len > 0)) continue;
    for (int k = 0; k < 3; ++k) {
      const Eigen::RowVector3d u = V.row(F(f, (k + 1) % 3)) - V.row(F(f, k)), w = V.row(F(f, (k + 2) % 3)) - V.row(F(f, k));
      const double lu = u.norm(), lw = w.norm();
      if (!(lu > 0 && lw > 0)) continue;
      N.row(F(f, k)) += std::acos(std::clamp(u.dot(w) / (lu * lw), -1.0, 1.0)) * n / len;
    }
  }
}

}  // namespace squeeze::meshing
