#include "squeeze/meshing/chord_volume.h"

#include "squeeze/meshing/surface_analysis.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace squeeze::meshing {

double integrated_mean_curvature(const SurfaceMesh& s, double sharp_angle) {
  auto normal = [&](int f) -> Eigen::Vector3d {
    const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    return (b - a).cross(c - a);
  };
  const double sharp = sharp_angle * M_PI / 180.0;
  double m = 0;
  const std::vector<EdgeIncidence> e = edge_incidences(s.F);
  for_each_edge(e, [&](size_t i, size_t j) {
    // Each edge with two faces along it in opposite directions, the first going a → b.
    if (j - i != 2 || e[i].forward == e[i + 1].forward) return;
    const EdgeIncidence& h = e[i].forward ? e[i] : e[i + 1];
    const EdgeIncidence& twin = e[i].forward ? e[i + 1] : e[i];
    const Eigen::Vector3d n0 = normal(h.face), n1 = normal(twin.face);
    const double l0 = n0.norm(), l1 = n1.norm();
    if (!(l0 > 0 && l1 > 0)) return;
    const Eigen::Vector3d d = s.V.row(h.b) - s.V.row(h.a);
    // Signed turn: positive where the surface is convex across the edge (the second face's normal
    // turns away from the first face, i.e. the first normal · the second face's far corner < 0).
    const double turn = std::atan2((n0 / l0).cross(n1 / l1).dot(d.normalized()), (n0 / l0).dot(n1 / l1));
    if (std::abs(turn) > sharp) return;
    m += 0.5 * d.norm() * turn;
  });
  return m;
}

double chord_length_for_volume_loss(const SurfaceMesh& s, double volume, double volume_loss, double sharp_angle) {
  const double m = integrated_mean_curvature(s, sharp_angle);
  if (!(m > 0) || !(volume > 0) || !(volume_loss > 0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(8.0 * volume_loss * volume / m);
}

}  // namespace squeeze::meshing
