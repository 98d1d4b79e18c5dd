// squeeze::meshing — one tetrahedral mesh of the solid a triangle soup encloses, by its generalized
// winding number: the route for inputs whose own boundary cannot be meshed as it is (open scans,
// welded, non-manifold or self-intersecting segments; meshing version 6, issue 16).
#pragma once
#include <Eigen/Core>

#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/tet_mesh.h"

namespace squeeze {
class Progress;
}

namespace squeeze::meshing {

struct WindingTetrahedralizeOptions {
  int target_tets = 1000;        // wanted tetrahedra: sets Mesh_3's cell and facet size; the facet
                                 // distance may need more on the boundary (the caller reports it)
  double facet_distance = 0.004; // fraction of the input's bounding-box diagonal: Mesh_3's bound on
                                 // the distance of a boundary facet from the solid's surface (measured
                                 // at one point per facet: the largest sag is about twice as deep)
  double dilation = 0.0045;      // fraction of the diagonal: the solid is {winding number ≥ ½} with
                                 // every point this close to the input surface added, so that boundary
                                 // facets (chords of that surface) sag less below the input
  int max_tets = 40000;          // a safety net: the refinement stops at twice this many vertices
  double min_dihedral = 5.0;     // degrees; boundary tetrahedra below it are peeled off
  double sliver_bound = 10.0;    // degrees; what Mesh_3's sliver exuder works on
  double optimize_seconds = 4.0; // time limit of the exuder (0: none); reaching it is warned
  double facet_size = 0.1;       // fraction of the diagonal: winding_number_surface's largest facet
                                 // (tetrahedralize_winding_number sizes facets by target_tets)
  double cover_tolerance = 0.003; // fraction of the diagonal: winding_number_surface seeds the
                                 // input's points left outside its surface by more than this (sharp
                                 // corners and edges the facets cut off) and refines again (0: not)
  bool cover_solid = true;       // tetrahedralize_winding_number does the same (meshing version 56:
                                 // a CAD part's solid at 150 lay 0.84 % of the diagonal in where its
                                 // facets cut off corners; false: as before, bench_mesh's A/B)
  bool seed_finer_if_no_facet = true;  // winding_number_surface: where the vertices' seeds, 8
                                 // facet distances apart, give Mesh_3 no facet (a long, thin scan),
                                 // seeds at the vertices a facet distance apart are tried (meshing
                                 // version 39; mesh_surface turns it off where a thin open scan's
                                 // narrow holes are capped instead, the dilated solid of a pipe
                                 // 4 mm across being 12 times its volume, and for the components
                                 // beside closed parts, seeded along their faces instead)
  bool seed_faces_if_no_facet = false;  // winding_number_surface: where the vertices' seeds give
                                 // Mesh_3 no facet (a part smaller than their spacing, a fin), seeds
                                 // along the input's faces too (a knot's tube 2 mm across with faces
                                 // 0.11 m long: minutes; so only where asked)
  int label_memo_log2_slots = 23;  // the solid's inside test remembers its answers in a table of
                                 // up to 2^this slots of 32 bytes, half of them filled: 2^23, 256
                                 // MiB at most, about 4.2 million points (meshing version 40; 2^22
                                 // before: the hollowed heart with holes asks about 3.0-3.6 million,
                                 // and each resumed refinement asked again about those not kept);
                                 // 12 to 30 (bench_mesh's A/B)
  bool cover_skip = true;        // that pass skips input points whose surface point could only land
                                 // near a point already taken (false: tests each; the same points,
                                 // slower: bench_mesh's A/B)
  double hollow_cell = 0;        // fraction of the diagonal, > 0: the solid is hollowed where the
                                 // outside reaches into it through holes (a flood of a grid this
                                 // fine from its border, across no triangle and through no point
                                 // within the dilation of the input): its points there farther than hollow_depth from the
                                 // input are left out, so that a holed segment is a shell around its
                                 // holes' rims, not capped (0: none hollowed)
  double hollow_depth = 0;       // fraction of the diagonal: how far inside the input that shell
                                 // reaches (less than the dilation: the dilation)

  unsigned seed = 1;             // CGAL's random generator: same input, same mesh
};

/// What tetrahedralize_winding_number() reports beside the mesh.
struct WindingTetrahedralizeStats {
  int attempts = 0;              // Mesh_3 runs (the cell size is corrected toward target_tets)
  double cell_size = 0;          // model units, of the mesh returned
  double facet_distance = 0;     // model units
  double dilation = 0;           // model units
  double hollow_depth = 0;       // model units: how far inside the input the hollowed shell reaches
                                 // (0: not hollowed, WindingTetrahedralizeOptions::hollow_cell)
  int seeds = 0;                 // surface points Mesh_3 started from
  int peeled_slivers = 0;        // boundary tetrahedra removed for a dihedral angle < min_dihedral
  int relocated = 0;             // vertex moves that raised the angles of an interior sliver
                                 // (relocate_sliver_vertices, tet_cleanup.h)
  int flips = 0;                 // 2-3 and 3-2 flips that removed a sliver (tet_cleanup.h flip_slivers)
  bool time_limit_reached = false;  // the exuder stopped at optimize_seconds
};

/// Meshes the solid of (V, F) — the points whose generalized winding number (winding_number.h) is
/// at least ½, dilated by `dilation` — with CGAL Mesh_3 (Delaunay refinement of a labeled implicit
/// domain, then sliver exudation, boundary slivers peeled and interior ones' vertices relocated,
/// tet_cleanup.h; Jamin, Alliez, Yvinec, Boissonnat, "CGALmesh",
/// ACM TOMS 41(4), 2015, doi:10.1145/2699463). The winding number takes welded or overlapping
/// segments as their union and closes small holes (Jacobson et al. 2013), so the mesh follows the
/// input's shape where its convex shells would inflate it. Mesh_3 starts from points on the
/// surface near the input's vertices (so that no part is missed), and the result, a subcomplex of
/// one Delaunay triangulation, is conforming. Tetrahedra come out positively oriented, labels 1.
///   V  #V by 3 input positions (units), F  #F by 3 triangles, oriented outward where they can be
///   volume  the solid's volume (units³), for the first cell-size guess
/// Throws InputError on an empty input or options out of range; returns an empty mesh when
/// Mesh_3 produced no tetrahedron (the caller reports it).
TetMesh tetrahedralize_winding_number(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double volume,
                                      const WindingTetrahedralizeOptions& options = {},
                                      WindingTetrahedralizeStats* stats = nullptr, Progress* progress = nullptr);

/// The boundary of the same solid (the points whose winding number is at least ½, dilated by
/// `dilation`) as a closed surface: the facets of Mesh_3's restricted Delaunay surface within
/// `facet_distance`, at most `facet_size` across, refined until the surface is a 2-manifold
/// (Mesh_3's manifold option: where two parts of the solid touch at a point or an edge it refines
/// until they part or join). Oriented outward (the faces of the cells inside the solid), no
/// self-intersection (faces of one Delaunay triangulation). The surface of meshing version 11's
/// route for inputs that are not closed parts, simplified against the input afterwards
/// (simplify_envelope with a target). Uses target_tets, min_dihedral, sliver_bound and
/// optimize_seconds not at all. Empty when Mesh_3 found no surface; the caller checks that it is a
/// closed 2-manifold (a refinement stopped by the max_tets net may leave it not). With
/// hollow_cell > 0 the solid is hollowed where the outside reaches in through holes (meshing
/// version 36): a shell (dilation + hollow_depth) thick around the holes' rims, not caps over them.
///   V  #V by 3 input positions (units), F  #F by 3 triangles; the result is in the same units,
///   the options' lengths are fractions of V's bounding-box diagonal
/// Throws InputError on an empty input or options out of range.
/// Source: Mesh_3's restricted Delaunay refinement (Jamin et al. 2015, above), whose facet
/// criteria follow J.-D. Boissonnat, S. Oudot, "Provably good sampling and meshing of surfaces",
/// Graphical Models 67(5), 2005, doi:10.1016/j.gmod.2005.01.004.
SurfaceMesh winding_number_surface(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                   const WindingTetrahedralizeOptions& options = {},
                                   WindingTetrahedralizeStats* stats = nullptr);

}  // namespace squeeze::meshing
