// squeeze::meshing — whether two triangles of one surface cross.
#pragma once
#include <Eigen/Core>

#include <array>
#include <cstdint>

namespace squeeze::meshing {

/// Whether the triangles A = (a[0], a[1], a[2]) and B = (b[0], b[1], b[2]) of one surface meet
/// anywhere but at the corners and the edge they share: the test a simplification needs to keep a
/// surface free of self-intersections (does_self_intersect() tests only faces that share no
/// vertex).
///   a, b    corners (units); a degenerate triangle (its corners on one line, exactly) crosses
///           nothing: false
///   ia, ib  corner ids: equal ids name the same corner (a vertex both faces hold)
/// Two triangles that share an edge (two ids) are not tested: false (their dihedral angle is the
/// fold test's). Sharing no corner: CGAL's exact triangle–triangle test. Sharing one corner c:
/// they meet elsewhere where the edge of one opposite c crosses the other, or, both in one plane,
/// where an edge of one from c points strictly into the other's angle at c (a meeting along a line
/// through c in two planes ends on an opposite edge). Exact predicates (CGAL's
/// Exact_predicates_inexact_constructions_kernel); no constructions; throws nothing.
/// Source: the triangle–triangle test is CGAL's do_intersect (P. Guigue, O. Devillers, "Fast and
/// robust triangle-triangle overlap test using orientation predicates", Journal of Graphics Tools
/// 8(1), 2003); the shared-corner cases are this function's own.
bool triangles_cross(const std::array<Eigen::Vector3d, 3>& a, const std::array<std::int64_t, 3>& ia,
                     const std::array<Eigen::Vector3d, 3>& b, const std::array<std::int64_t, 3>& ib);

}  // namespace squeeze::meshing
