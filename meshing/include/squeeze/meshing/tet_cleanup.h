// squeeze::meshing — clean-ups of tetrahedral meshes after Mesh_3 (tetrahedralize.cpp): unused
// vertices, boundary slivers, points sticking out of the boundary.
#pragma once
#include <Eigen/Core>
#include <cmath>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// Drops the vertices no tetrahedron uses and renumbers T; the others keep their order.
///   mesh  V #V by 3, T #T by 4 (modified in place; label unchanged)
void remove_unused_vertices(TetMesh& mesh);

/// Removes the face-connected components (tet_components) whose volume is below `max_fraction`
/// of the mesh's, unless that would remove every tetrahedron. For the mesh of one connected solid:
/// where its tetrahedra were classified by the winding number (a boundary not recovered), single
/// tetrahedra can stay attached to the mesh by an edge or a vertex only, a component each (35 of
/// them on a generated spider's legs). Vertices are kept (remove_unused_vertices drops the orphans).
///   mesh          V #V by 3, T #T by 4, label #T or empty (modified in place)
///   max_fraction  in [0, 1): components with a smaller share of the volume go
/// Throws nothing; returns how many tetrahedra were removed. Source: squeeze's own clean-up
/// (components by shared faces, tet_faces.h).
int drop_debris_components(TetMesh& mesh, double max_fraction);

/// Repeatedly removes the tetrahedra with a face on the boundary and a dihedral angle below
/// `min_degrees` (flat boundary slivers add no volume worth keeping), in up to 16 passes since
/// peeling exposes new boundary tetrahedra; it never removes the last one. Interior slivers are
/// left alone. Vertices are kept (remove_unused_vertices drops the orphans).
///   mesh         V #V by 3, T #T by 4 positively oriented, label #T or empty (modified in place)
///   min_degrees  dihedral-angle threshold (degrees)
///   max_height   units: a sliver is kept when peeling it would move the boundary farther than this
///                (its largest height over one of its boundary faces: a coarse mesh's sliver 4°
///                flat can still be 2 % of the diagonal thick); infinite by default
/// Returns how many tetrahedra were removed.
int peel_boundary_slivers(TetMesh& mesh, double min_degrees, double max_height = INFINITY);

/// Removes every tetrahedron with a dihedral angle below `min_degrees`, interior ones too (unlike
/// peel_boundary_slivers): for one layer of prisms over a sheet, where a few prisms at a fold or a
/// spike are flattened to slivers that no move or flip mends (meshing version 32). The mesh stays
/// conforming; it may open small holes and split off pieces (the caller checks both).
///   mesh         V #V by 3, T #T by 4 positively oriented, label #T or empty (T and label
///                modified in place; vertices kept: remove_unused_vertices drops the orphans)
///   min_degrees  dihedral-angle threshold (degrees)
/// Throws nothing; returns how many tetrahedra were removed. Source: squeeze's own clean-up (the
/// dihedral angles of tet_geometry.h).
int drop_slivers(TetMesh& mesh, double min_degrees);

/// Moves vertices of tetrahedra with a dihedral angle below `min_degrees` (the interior slivers
/// Mesh_3's exuder leaves, whose four vertices all lie on the boundary) to the best of a few nearby
/// positions (±axes and ± the sliver's height at the vertex, 5–20 % of its shortest edge; in the
/// tangent plane of the boundary for boundary vertices where the boundary is smooth, all its faces
/// there within 20° of their mean normal; corners and creases stay), keeping a move only if it raises the
/// smallest dihedral angle of the vertex's tetrahedra and inverts none. Deterministic; in up to
/// `passes` sweeps over the mesh. Source: squeeze's own local search, a greedy and deterministic
/// cousin of Mesh_3's sliver perturber (Tournois, Srinivasan, Alliez, "Perturbing slivers in 3D
/// Delaunay meshes", IMR 2009), which on these meshes moved the boundary too far (docs/meshing.md).
///   mesh         V #V by 3 (units, modified in place), T #T by 4 positively oriented
///   min_degrees  dihedral-angle threshold (degrees)
/// Throws nothing; returns how many vertex moves were made (0 where no tetrahedron is below the
/// threshold or no move helps).
int relocate_sliver_vertices(TetMesh& mesh, double min_degrees, int passes = 3);

/// Removes tetrahedra with a dihedral angle below `min_degrees` by topological flips, worst
/// first: a 2-3 flip (the tetrahedron and its neighbour across an interior face become three
/// around the edge joining their apexes) or a 3-2 flip (the three tetrahedra around an interior
/// edge of degree 3 become two), taken only where it is valid and raises the smallest dihedral
/// angle of the tetrahedra it replaces. The boundary, the vertices and the volume do not change;
/// tetrahedra of different labels are never flipped together. Such slivers are the ones whose
/// four vertices lie on opposite sides of a thin part, which relocate_sliver_vertices cannot move
/// without moving the boundary. Source: the flips of Joe (1995) as used by Klingner and Shewchuk,
/// "Aggressive tetrahedral mesh improvement", IMR 2007; greedy and deterministic here.
///   mesh         V #V by 3 (unchanged), T #T by 4 positively oriented, label #T or empty
///                (T and label modified in place: rows change and #T changes by ±1 per flip)
///   min_degrees  dihedral-angle threshold (degrees)
///   max_flips    at most this many flips
/// Throws nothing; returns how many flips were made.
int flip_slivers(TetMesh& mesh, double min_degrees, int max_flips = 1000);

/// Contracts short edges of the tetrahedra with a dihedral angle below `min_degrees`, worst
/// first: of a sliver's edges at most `max_length` long, shortest first, the first whose
/// contraction to one of its ends (the tetrahedra around the edge removed, the other end's
/// tetrahedra taking the kept end) keeps the mesh a manifold (the link condition of Dey,
/// Edelsbrunner, Guha and Nekhayev, "Topology preserving edge contraction", 1999, on the mesh
/// closed by a vertex joined to its boundary), inverts no tetrahedron and raises the smallest
/// dihedral angle of the tetrahedra it changes, with fewer of them below the floor. An interior
/// vertex goes into any neighbour; a boundary vertex only along a boundary edge, into its other
/// end (the boundary moves by at most that edge's length; an interior edge between two boundary
/// vertices is never contracted). For the interior slivers across a thin spike whose four
/// vertices all lie on the boundary, where neither relocate_sliver_vertices nor flip_slivers
/// reaches (meshing version 52). Source: edge contraction as in Klingner and Shewchuk,
/// "Aggressive tetrahedral mesh improvement", IMR 2007; greedy and deterministic here.
///   mesh              V #V by 3 (unchanged; vertices left unused: remove_unused_vertices drops
///                     them), T #T by 4 positively oriented, label #T or empty (modified in place)
///   min_degrees       dihedral-angle threshold (degrees)
///   max_length        units: longer edges are not contracted
///   max_contractions  at most this many
/// Throws nothing; returns how many edges were contracted.
int contract_sliver_edges(TetMesh& mesh, double min_degrees, double max_length, int max_contractions = 1000);

/// Moves boundary vertices outward (along their area-weighted normals) until the points P lie
/// inside the mesh or within `tolerance` of it: every point farther out pushes the three vertices of
/// its nearest boundary face by a share of its distance. A move is halved, then dropped, where a
/// tetrahedron would become inverted or get a dihedral angle below min(min_degrees, its own before).
/// Local moves cover a coarse mesh's chords at far less volume than dilating everything. Up to
/// `iterations` rounds; deterministic (any thread count).
///   mesh         V #V by 3 (units, modified in place), T #T by 4 positively oriented
///   P            #P by 3 points to cover (units)
///   tolerance    distance a point may stay outside (units)
///   min_degrees  dihedral-angle bound of moved tetrahedra (degrees)
/// Returns how many vertex moves were made.
int inflate_to_cover(TetMesh& mesh, const Eigen::MatrixX3d& P, double tolerance, double min_degrees,
                     int iterations = 6);

}  // namespace squeeze::meshing
