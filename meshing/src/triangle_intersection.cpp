// CGAL translation unit (predicates only): whether two triangles of one surface cross.
#include "squeeze/meshing/triangle_intersection.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

namespace squeeze::meshing {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

Point point(const Eigen::Vector3d& x) { return Point(x.x(), x.y(), x.z()); }

// Whether x lies strictly inside the angle of (c, u, v) at c, all four in one plane.
bool inside_angle(const Point& c, const Point& u, const Point& v, const Point& x) {
  return CGAL::coplanar_orientation(c, u, x) == CGAL::coplanar_orientation(c, u, v) &&
         CGAL::coplanar_orientation(c, v, x) == CGAL::coplanar_orientation(c, v, u);
}
}  // namespace

bool triangles_cross(const std::array<Eigen::Vector3d, 3>& a, const std::array<std::int64_t, 3>& ia,
                     const std::array<Eigen::Vector3d, 3>& b, const std::array<std::int64_t, 3>& ib) {
  int shared = 0, sa = -1, sb = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (ia[static_cast<size_t>(i)] == ib[static_cast<size_t>(j)]) ++shared, sa = i, sb = j;
  if (shared >= 2) return false;
  const std::array<Point, 3> p{point(a[0]), point(a[1]), point(a[2])}, q{point(b[0]), point(b[1]), point(b[2])};
  const K::Triangle_3 tp(p[0], p[1], p[2]), tq(q[0], q[1], q[2]);
  if (tp.is_degenerate() || tq.is_degenerate()) return false;  // (CGAL's tests need triangles)
  if (shared == 0) return CGAL::do_intersect(tp, tq);
  const Point &c = p[static_cast<size_t>(sa)], &p1 = p[static_cast<size_t>((sa + 1) % 3)], &p2 = p[static_cast<size_t>((sa + 2) % 3)];
  const Point &q1 = q[static_cast<size_t>((sb + 1) % 3)], &q2 = q[static_cast<size_t>((sb + 2) % 3)];
  if (CGAL::do_intersect(K::Segment_3(p1, p2), tq) || CGAL::do_intersect(K::Segment_3(q1, q2), tp)) return true;
  if (CGAL::orientation(c, p1, p2, q1) != CGAL::COPLANAR || CGAL::orientation(c, p1, p2, q2) != CGAL::COPLANAR) return false;
  return inside_angle(c, p1, p2, q1) || inside_angle(c, p1, p2, q2) || inside_angle(c, q1, q2, p1) ||
         inside_angle(c, q1, q2, p2);
}

}  // namespace squeeze::meshing
