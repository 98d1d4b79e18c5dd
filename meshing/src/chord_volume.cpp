#include "squeeze/meshing/chord_volume.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

namespace squeeze::meshing {

double integrated_mean_curvature(const SurfaceMesh& s, double sharp_angle) {
  // Each undirected edge's two faces, found by its directed halfedges: (a, b) in one face and
  // (b, a) in the other.
  struct Side {
    int face = -1, count = 0;
  };
  std::unordered_map<long long, Side> half;  // key a * #V + b for the halfedge a -> b
  half.reserve(static_cast<size_t>(s.F.rows()) * 3);
  const long long nv = s.V.rows();
  for (Eigen::Index f = 0; f < s.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      Side& h = half[s.F(f, k) * nv + s.F(f, (k + 1) % 3)];
      h.face = static_cast<int>(f);
      ++h.count;
    }
  auto normal = [&](int f) -> Eigen::Vector3d {
    const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    return (b - a).cross(c - a);
  };
  const double sharp = sharp_angle * M_PI / 180.0;
  double m = 0;
  for (const auto& [key, h] : half) {
    const long long a = key / nv, b = key % nv;
    if (a > b || h.count != 1) continue;  // each edge once, from its lower end
    const auto twin = half.find(b * nv + a);
    if (twin == half.end() || twin->second.count != 1) continue;
    const Eigen::Vector3d n0 = normal(h.face), n1 = normal(twin->second.face);
    const double l0 = n0.norm(), l1 = n1.norm();
    if (!(l0 > 0 && l1 > 0)) continue;
    const Eigen::Vector3d e = s.V.row(b) - s.V.row(a);
    // Signed turn: positive where the surface is convex across the edge (the second face's normal
    // turns away from the first face, i.e. the first normal · the second face's far corner < 0).
    const double turn = std::atan2((n0 / l0).cross(n1 / l1).dot(e.normalized()), (n0 / l0).dot(n1 / l1));
    if (std::abs(turn) > sharp) continue;
    m += 0.5 * e.norm() * turn;
  }
  return m;
}

double chord_length_for_volume_loss(const SurfaceMesh& s, double volume, double volume_loss, double sharp_angle) {
  const double m = integrated_mean_curvature(s, sharp_angle);
  if (!(m > 0) || !(volume > 0) || !(volume_loss > 0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(8.0 * volume_loss * volume / m);
}

}  // namespace squeeze::meshing
