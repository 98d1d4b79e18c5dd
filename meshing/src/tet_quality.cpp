#include "squeeze/meshing/tet_quality.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_geometry.h"

namespace squeeze::meshing {

TetQuality tet_quality(const TetMesh& m) {
  TetQuality q;
  q.tets = static_cast<int>(m.T.rows());
  q.vertices = static_cast<int>(m.V.rows());
  if (q.tets == 0) return q;
  const Eigen::VectorXd vol = tet_volumes(m);
  q.min_volume = vol.minCoeff();
  q.volume = vol.sum();
  q.min_dihedral = 180.0;
  q.max_dihedral = 0.0;
  for (int t = 0; t < q.tets; ++t) {
    const auto a = dihedral_angles(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3)));
    q.min_dihedral = std::min(q.min_dihedral, *std::min_element(a.begin(), a.end()));
    q.max_dihedral = std::max(q.max_dihedral, *std::max_element(a.begin(), a.end()));
  }
  // Unique edges: (min, max) vertex pairs of the six edges of every tet.
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<size_t>(q.tets) * 6);
  for (int t = 0; t < q.tets; ++t)
    for (const auto& e : kTetEdge)
      edges.emplace_back(std::min(m.T(t, e[0]), m.T(t, e[1])), std::max(m.T(t, e[0]), m.T(t, e[1])));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  q.min_edge = INFINITY;
  double sum = 0;
  for (const auto& [a, b] : edges) {
    const double l = (m.V.row(a) - m.V.row(b)).norm();
    q.min_edge = std::min(q.min_edge, l);
    sum += l;
  }
  q.mean_edge = sum / static_cast<double>(edges.size());
  Eigen::VectorXi C;
  q.components = tet_components(m, C);
  q.overshared_faces = tet_faces(m.T).overshared;
  return q;
}

}  // namespace squeeze::meshing
