// squeeze::meshing — the holes of an open scan, and how far a surface closing them would lie from
// the scan.
#pragma once
#include <vector>
#include <Eigen/Core>

namespace squeeze::meshing {

/// The boundary loops of a surface: each a closed chain of boundary edges (edges in one face).
///   F  #F by 3 vertex indices
/// Returns one vector of vertex indices per loop, in order along it (a loop's last vertex joins its
/// first). Where a vertex lies on more than two boundary edges (a bow tie), the chains through it
/// are cut there: the loops returned then need not be closed. Throws nothing.
std::vector<std::vector<int>> boundary_loops(const Eigen::MatrixX3i& F);

/// How far the middle of a surface spanning the loop lies from the loop: the radius of the largest
/// circle inside the loop projected onto its least-squares plane (the polygon's inscribed circle,
/// found on a 25 by 25 grid of centres, then a finer one around the best: the pole of
/// inaccessibility of the polygon, as Garcia-Castellanos and Lombardo 2007, Scottish Geographical
/// Journal 123(3), doi:10.1080/14702540801897809, search it on a refined grid). For a round hole of
/// radius r, about r: where the winding-number solid of a scan caps the hole (meshing version 8), its
/// cap lies about that far from the scan (the bunny with holes of 2 and 3 % of its diagonal: 1.74
/// and 2.57 % estimated, 1.8 and 2.6 % measured on the solid).
///   V  #V by 3 positions (units), loop  vertex indices in order (at least 3)
/// Returns units; 0 for fewer than 3 vertices or a loop with no area. Throws nothing.
double hole_cap_distance(const Eigen::MatrixX3d& V, const std::vector<int>& loop);

/// Whether the surface is only open scans: every edge in one or two faces, at least one boundary
/// edge, and every vertex on a boundary edge on exactly two (no bow tie, no welded segments).
/// Orientation is not asked (mesh_surface orients the faces first).
///   F  #F by 3 vertex indices (duplicate faces removed)
/// Returns false for a closed surface (no boundary edge) and for an empty one. Throws nothing.
bool is_open_two_manifold(const Eigen::MatrixX3i& F);

}  // namespace squeeze::meshing
