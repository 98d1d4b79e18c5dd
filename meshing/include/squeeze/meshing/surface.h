// squeeze::meshing — a triangle surface as libigl-style matrices.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

namespace squeeze::meshing {

/// A triangle soup or mesh.
///   V  #V by 3 vertex positions (model units; metres in scenes)
///   F  #F by 3 vertex indices into V (0-based); orientation not assumed consistent
struct SurfaceMesh {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;
};

/// Axis-aligned bounding box of the rows of V: min and max corners (#V must be > 0).
void bounding_box(const Eigen::MatrixX3d& V, Eigen::RowVector3d& lo, Eigen::RowVector3d& hi);

/// Length of the bounding-box diagonal of V (0 for an empty V).
double bounding_box_diagonal(const Eigen::MatrixX3d& V);

/// Calls visit(x) for the points of the triangle (a, b, c) on a barycentric lattice at most
/// `spacing` apart (at most 64 along an edge), its corners left out (they are vertices): none
/// where its longest edge is at most `spacing`.
///   spacing  units, > 0
template <typename Visit>
void for_each_lattice_point(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, double spacing,
                            Visit&& visit) {
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  const int n = std::min(64, static_cast<int>(std::ceil(longest / spacing)));
  if (n < 2) return;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n - i; ++j) {
      if ((i == 0 && j == 0) || (i == n && j == 0) || (i == 0 && j == n)) continue;
      visit(Eigen::Vector3d(a + (static_cast<double>(i) / n) * (b - a) + (static_cast<double>(j) / n) * (c - a)));
    }
}

/// Points of the triangles (V, F): every vertex a face uses, and points of each triangle at most
/// `spacing` apart (a barycentric lattice, at most 64 points along an edge). Deterministic order:
/// the vertices, then each face's lattice in face order.
///   spacing  units, > 0
std::vector<Eigen::Vector3d> surface_samples(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double spacing);

}  // namespace squeeze::meshing
