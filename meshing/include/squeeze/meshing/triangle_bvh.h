// squeeze::meshing — nearest points on, and segment crossings with, a set of triangles: a bounding
// volume hierarchy for the distance measures of `squeeze mesh` (envelope bounds, deviations).
#pragma once
#include <Eigen/Core>
#include <array>
#include <vector>

namespace squeeze::meshing {

/// A bounding-volume hierarchy (axis-aligned boxes, median splits along the longest axis of the
/// triangle centroids, leaves of up to 4 triangles) over the triangles (V, F). Build O(#F log #F);
/// queries O(log #F) expected for points near the surface. Keeps copies of V and F. Const queries
/// are thread-safe and deterministic (ties go to the lower triangle index).
class TriangleBvh {
 public:
  ///   V  #V by 3 positions (units), F  #F by 3 vertex indices (may be empty: queries then find
  ///   nothing)
  TriangleBvh(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

  /// Distance from p to the nearest triangle (units), +infinity when there is none or none is
  /// nearer than `bound` (a triangle at exactly `bound` is not found).
  ///   face     optional; receives the index of that triangle (-1 if none)
  ///   closest  optional; receives the nearest point on it
  double nearest(const Eigen::Vector3d& p, int* face = nullptr, Eigen::Vector3d* closest = nullptr,
                 double bound = INFINITY) const;

  /// Whether some triangle lies within r of p (distance <= r): stops at the first found, so it is
  /// much cheaper than nearest() where one is near (a one-sided Hausdorff distance skips the
  /// samples that cannot raise its maximum).
  bool any_within(const Eigen::Vector3d& p, double r) const;

  /// Of the points where the segment a→b crosses a triangle (Möller–Trumbore; parameter t in
  /// [0, 1]), the parameter nearest to `hint`. Returns false when the segment crosses none. A
  /// segment in a triangle's plane (up to rounding: the determinant under 1e-12 of |d| |e1| |e2|;
  /// or up to a file's digits: both ends within 1e-5 |d| of the plane) crosses nothing there
  /// (meshing versions 42 and 46).
  bool crossing_nearest(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double hint, double* t) const;

  /// The first crossing of the segment a→b at parameter t >= t_min (see crossing_nearest).
  bool first_crossing(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double t_min, double* t) const;

  /// Outward unit normal of triangle f (zero for a degenerate one).
  Eigen::Vector3d normal(int f) const;

  int triangles() const { return static_cast<int>(F_.rows()); }

 private:
  struct Node {
    Eigen::Vector3d lo, hi;
    int left = -1, right = -1;  // children (internal node)
    int begin = 0, end = 0;     // range of order_ (leaf)
  };
  Eigen::MatrixX3d V_;
  Eigen::MatrixX3i F_;
  std::vector<int> order_;
  std::vector<std::array<Eigen::Vector3d, 3>> corner_;  // the corners of order_[i]'s triangle, in
                                                        // order_'s order (a leaf's are contiguous)
  std::vector<Node> nodes_;
  int build(int begin, int end, std::vector<Eigen::Vector3d>& centroid);
  bool crossing(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double hint, bool after, double* t) const;
};

}  // namespace squeeze::meshing
