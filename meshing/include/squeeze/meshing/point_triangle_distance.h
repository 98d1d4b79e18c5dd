// squeeze::meshing — distance from a point to a triangle.
#pragma once
#include <Eigen/Core>

namespace squeeze::meshing {

/// The point of the closed triangle (a, b, c) nearest to p (vertex, edge or face region, told apart
/// by barycentric tests).
///   p, a, b, c  points (units)
/// Source: C. Ericson, Real-Time Collision Detection, Morgan Kaufmann 2005, §5.1.5 "Closest point
/// on triangle to point".
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c);

/// Euclidean distance from p to the closed triangle (a, b, c) (units): |p - closest_point_on_triangle|.
double point_triangle_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c);

}  // namespace squeeze::meshing
