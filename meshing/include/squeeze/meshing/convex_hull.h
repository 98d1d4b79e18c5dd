// squeeze::meshing — 3-D convex hull (CGAL, exact predicates) as a small value type.
#pragma once
#include <Eigen/Core>
#include <vector>

namespace squeeze::meshing {

/// A convex polytope.
///   V       #V by 3 hull vertices: the input points on the hull's boundary (corners, and points
///           on its facets and edges; see extreme_points)
///   F       #F by 3 outward-oriented triangles
///   planes  #P by 4 facet planes (n, d), |n| = 1, n·x <= d inside; coplanar triangles merged
///   volume  enclosed volume (units³); 0 for a flat or degenerate hull
struct ConvexHull {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;
  Eigen::MatrixX4d planes;
  double volume = 0.0;
  /// Signed distance-like value: max over planes of n·p - d (negative inside, 0 on the boundary;
  /// outside, a lower bound of the Euclidean distance).
  double signed_value(const Eigen::RowVector3d& p) const;
  /// Distance from p (inside) to the hull boundary: -signed_value(p), clamped at 0.
  double depth(const Eigen::RowVector3d& p) const;
};

/// The corners of `hull`: vertices where at least three facet planes with different normals meet
/// (the hull's V also holds input points lying on its facets and edges). #C by 3.
Eigen::MatrixX3d extreme_points(const ConvexHull& hull);

/// Convex hull of the rows of P (#P by 3) with CGAL's convex_hull_3 (Epick, exact predicates).
/// Returns an empty hull (no vertices) for fewer than 4 points or all points coplanar; callers
/// decide how to thicken such input.
ConvexHull convex_hull(const Eigen::MatrixX3d& P);

}  // namespace squeeze::meshing
