// squeeze::meshing — approximate convex decomposition by plane cuts.
//
// The solid bounded by a (possibly open, self-intersecting) surface is cut recursively by planes
// until every piece's concavity is at most a threshold or a hull budget is reached; each piece's
// convex hull is a "convex shell". Because every cut is a plane, the hulls of the two sides lie in
// opposite closed half-spaces: the shells are interior-disjoint and meet on the cutting planes.
//
// Concavity (exactly what is measured): for a piece P = S ∩ C, where S is the solid and C the
// convex cell bounded by the cutting planes so far,
//     concavity(P) = max over points x of ∂S ∩ C of  min over bridges f of dist(x, plane(f))
// i.e. the depth, below the hull's lids, of the deepest point of the piece's outer surface, where
// the bridges are the hull facets that do not lie on a cutting plane (those are the piece's own
// caps) — the concavity of Lien & Amato's ACD (the paper's [15]: J.-M. Lien, N. M. Amato, "Approximate convex
// decomposition of polyhedra", SPM 2007, doi:10.1145/1236246.1236265). dist to the boundary of a
// convex polytope from inside is the minimum over its facet planes, so it is exact. Surface lying
// in a cutting plane (a cut along a face, e.g. the floor of a notch) is part of a cap, a facet of
// conv(P), and counts zero; where the surface crosses a cutting plane it is measured like the rest
// (a notch the cut crosses goes on there). The points x are the vertices of the input
// triangles clipped to C (original vertices plus edge/plane intersections) and, on clipped
// polygons with an edge over a voxel long, samples about a voxel apart; surface that lies
// inside the solid (walls between touching parts, self-intersections) is not ∂S and is excluded,
// as judged on the voxel grid below. Units: model units (the threshold is given as a fraction of the
// bounding-box diagonal).
//
// The shell of P is the convex hull of the clipped triangles' vertices and of the corners of C
// (three cutting planes meeting) that lie inside the solid: P's corners that are on no triangle.
// The shells therefore cover the solid, not only the input's vertices. A triangle lying in a
// cutting plane goes to the side its solid is on (opposite its outward normal).
//
// Inside/outside: voxels of a grid (voxel_resolution along the longest side) are surface voxels
// (touched by a triangle) or classified by the generalized winding number at their centre
// (> 0.5 inside); no closedness is assumed. Connected parts of the solid are 26-connected
// components of the occupied voxels: parts that touch or overlap (organs made of several closed
// pieces) form one part; parts farther apart than a voxel stay apart.
//
// A second, volumetric criterion catches thin curved parts (a spinal cord, a tube) whose
// concavity stays below a threshold measured against the whole diagonal: a piece is also split when
// vol(conv(P)) > max_hull_volume_ratio × vol(P). For a closed input vol(P) is exact (divergence
// theorem over the clipped polygons and the caps on the cut planes, whose areas come from their
// boundaries: the polygons' edges on those planes and, where two caps meet inside the solid, the
// part of their common line that is in the solid); otherwise it is estimated on the voxel grid
// (interior voxels plus half the surface voxels).
//
// Choosing a cut (in the family of V-HACD, K. Mamou 2009/2016, and CoACD, X. Wei et al. 2022,
// doi:10.1145/3528223.3530103): the piece that exceeds its bounds the most (concavity over
// threshold, or hull volume over ratio × volume) is split next. Candidate
// planes are normal to the piece's three principal axes, at cut_samples even positions and
// through the deepest point; each candidate is scored by the summed volume of the convex hulls of
// the two sides (the piece's hull corners on that side plus the side's voxels nearest the plane
// projected onto it, its cross-section: the excess volume the shells would add), the lowest wins,
// ties by candidate order; except that a cut through the deepest point along a face of the
// surface (the wall or floor of a notch: Lien & Amato's cut through the notch) wins when it
// removes at least 1 - notch_preference of the best one's volume, which cannot tell it from cuts
// beside it that leave a sliver of notch. Everything is deterministic and independent of the number
// of threads.
#pragma once
#include <vector>

#include "squeeze/meshing/convex_hull.h"
#include "squeeze/meshing/surface.h"

namespace squeeze {
class Progress;
}

namespace squeeze::meshing {

struct DecompositionOptions {
  double concavity = 0.02;       // threshold, as a fraction of the input's bounding-box diagonal
  int max_hulls = 32;            // at most this many shells (splitting stops there)
  double max_hull_volume_ratio = 1.3;  // also split a piece whose hull volume exceeds this multiple
                                 // of its volume: thin curved parts, knots
  int voxel_resolution = 64;     // voxels along the longest bounding-box side
  int cut_samples = 10;          // candidate positions per principal axis per split
  double notch_preference = 0.1; // a cut through the deepest point along a face of the surface
                                 // wins when it removes at least (1 - this) of the best
                                 // candidate's hull volume
  double flat_thickness = 0.004; // fraction of the diagonal given to flat (zero-volume) pieces
  bool samples_by_area = true;   // a polygon's samples (points of large polygons whose depth is
                                 // measured too) in rows about a voxel apart along its longest
                                 // edge: about area / voxel² of them; false: a grid of
                                 // (longest edge / voxel)² per triangle (before meshing version 29:
                                 // 30,000 on a sliver 1.5 m by 2.6 cm)
};

struct ConvexShell {
  ConvexHull hull;      // the convex shell
  double concavity;     // concavity of its piece (model units)
  int part;             // connected part of the solid it belongs to (0-based)
};

struct Decomposition {
  std::vector<ConvexShell> shells;
  int parts = 0;                 // connected parts of the solid (see above)
  double threshold = 0.0;        // concavity threshold used (model units)
  double max_concavity = 0.0;    // largest concavity over the shells (model units)
  double solid_volume = 0.0;     // volume of the solid by winding number on the voxel grid
  bool hit_max_hulls = false;    // stopped by max_hulls with a piece still above threshold
};

/// Decomposes the solid bounded by `mesh` (faces oriented outward per component, see
/// orient_outward) into convex shells.
///   mesh  V #V by 3, F #F by 3 (model units)
/// Returns the shells; together they contain every vertex of `mesh`.
/// Throws InputError on impossible options (concavity <= 0, max_hulls < 1, resolution < 8).
Decomposition decompose(const SurfaceMesh& mesh, const DecompositionOptions& options = {},
                        Progress* progress = nullptr);

/// Grows the shells of `d` so that together they hold every row of P: a point outside every shell
/// by more than `tolerance` is taken into the hull of the shell it lies least outside of (the
/// smallest ConvexHull::signed_value), and that hull is made again. For a decomposition made of an
/// approximation of a surface (a dense input's decimated proxy, mesh_pipeline.h) and the
/// surface's own vertices, which lie within the approximation's error of it: the shells then grow
/// by at most that error, and may overlap by as much across the cuts. Shells without volume are
/// left as they are.
///   P          #P by 3 points (model units)
///   tolerance  how far outside a shell a point may lie and count as held (model units)
/// Returns the number of points taken in.
int hold_points(Decomposition& d, const Eigen::MatrixX3d& P, double tolerance);

}  // namespace squeeze::meshing
