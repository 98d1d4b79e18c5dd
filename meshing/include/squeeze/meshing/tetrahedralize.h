// squeeze::meshing — one conforming tetrahedral mesh of the solid bounded by a closed surface,
// whose boundary is that surface exactly.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <string>

#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/tet_mesh.h"

namespace squeeze {
class Progress;
}

namespace squeeze::meshing {

struct TetrahedralizeOptions {
  int target_tets = 1000;         // desired tetrahedron count, met within about ±35% when the
                                  // boundary allows it: the interior edge length is re-estimated
                                  // from each attempt's count (a boundary that needs more
                                  // tetrahedra than this gets them; see TetrahedralizeStats)
  double refine_dihedral = 6.0;   // degrees: tetrahedra with a smaller dihedral angle are refined
                                  // (a Steiner point at their circumcentre, or a split of the boundary
                                  // edge it would cut); where a part is thinner than the edge
                                  // length this decides how finely its faces are split
  double sliver_bound = 12.0;     // degrees: CGAL's sliver exuder then works on tetrahedra below this
  bool exude = true;              // run the exuder (off for a sheet's slab: one layer of tetrahedra
                                  // flatter than sliver_bound by its thinness, which exuding cannot
                                  // improve and on which it ran into exude_seconds)
  double exude_seconds = 30.0;    // the exuder's time limit (0: none): a bound for pathological inputs,
                                  // far above what it takes on real meshes (reaching it is warned)
  long exude_pumps_per_sliver = 5;  // the exuder stops after this many pumps per tetrahedron under
                                  // sliver_bound (1,000 at least): a deterministic bound where it
                                  // would pump round in a circle to exude_seconds (thin walls whose
                                  // flat tetrahedra it cannot lift); real meshes take about one
                                  // per sliver. 0: no bound. (20 in meshing versions 25-42: a 4 mm
                                  // plate turned in space spent 6.4 s of 8.5 in such pumps at 2000)
  double min_dihedral = 5.0;      // degrees: the floor the result is checked against (stats)
  double peel_max_height = INFINITY;  // units: boundary slivers are peeled off only where that moves the
                                  // boundary by at most this (peel_boundary_slivers); thicker ones
                                  // are left to the sliver moves and flips (squeeze mesh: the
                                  // inner deviation bound)
  double contract_max_length = 0.25;  // the slivers left after the moves and flips (four boundary
                                  // vertices across a thin spike) have their edges contracted
                                  // (contract_sliver_edges) before the last peeling, edges at most
                                  // this × the interior edge length and peel_max_height long (the
                                  // boundary moves by as much at most); 0: never (meshing version 52)
  int max_tets = 100000;          // a safety net: refinement stops when the mesh reaches this
                                  // (in points: a third of it, but at least twice the points of the
                                  // recovered boundary, so that a small part's own boundary is refined)
  double long_edge = 3.0;         // boundary edges longer than this × the boundary's median edge (and
                                  // than 1/20 of its bounding-box diagonal) are split at their
                                  // midpoints first (split_long_edges: the side of a cylinder of few
                                  // segments is a triangle 30 times longer than wide, which
                                  // conformity recovery cannot split down); 0: never
  int max_attempts = 6;           // meshing runs at most, each at an interior edge length corrected
                                  // toward target_tets (squeeze mesh's retries take 2)
  bool skip_repeated_attempts = true;  // skip the next attempt where it would repeat the last: the
                                  // last one's edge length shaped nothing but its starting points
                                  // and the next starts from the same points (same mesh, since
                                  // every step is deterministic); false runs it (tests pin that it
                                  // gives the same mesh kept)
  unsigned seed = 1;              // CGAL's random generator, for run-to-run determinism
  bool remember_facet_cells = true;  // conformity recovery remembers, per boundary triangle, a
                                  // cell that had it as a facet, and asks the triangulation again
                                  // only where that cell is gone (false: asks each time; the same
                                  // mesh, slower: bench_mesh's A/B; meshing version 40)
  bool flip_flat_surface_cells = true;  // an inside cell of no volume on the surface (four points of
                                  // one flat patch, two of its faces surface triangles) has the
                                  // surface's diagonal there flipped to its other one, which puts
                                  // the cell outside (false: refined like any flat cell, which asks
                                  // for surface splits that make more of them: a plate turned in
                                  // space, coplanar only up to rounding; bench_mesh's A/B; meshing
                                  // version 43)
  bool recovery_cap_on_own_splits = true;  // conformity recovery's cap (four points per point of
                                  // the recovered boundary) is raised by the points each refinement
                                  // round adds (false: it counts every point, as before meshing
                                  // version 45: a plate with 3 mm ribs lost its boundary at the cap
                                  // and was remeshed; bench_mesh's A/B)
  double recovery_splits_per_face = 4.0;  // the first conformity recovery of a run gives up once
                                  // it would split more boundary edges than this × the boundary's
                                  // faces (as given, before its long edges are split) in a round
                                  // that does not converge (no fewer splits than 0.9 of the fewest
                                  // a round so far: a plate of 60 large faces converges through
                                  // over 1,000), and such a run is not refined (its mesh: the Delaunay tetrahedra of its
                                  // points, classified by the winding number). squeeze mesh retries
                                  // no such boundary but its remeshed surface (mesh_pipeline.cpp:
                                  // a first attempt over four splits per face that does not hold),
                                  // and trimesh's ADIS16480.STL at 150 spent 7 s in recovery, 8 s
                                  // refining and 14 s moving slivers in one, for 21,456 splits of
                                  // 1,614 faces (meshing version 55). 0: no bound
  double max_refine_work = 0;     // cells of the conflict zones refinement may search in all attempts
                                  // (its work, a deterministic measure of its time: about 4 million
                                  // per second here); beyond it refinement stops and no further
                                  // attempt runs (TetrahedralizeStats::work_exceeded). 0: no bound.
                                  // Real meshes search under 0.2 million per attempt; a rod of long,
                                  // thin triangles 21 million in its first (squeeze mesh bounds the
                                  // parts it has a rounder boundary for: mesh_pipeline.h)
  double unrecovered_refine_work = 1e6;  // cells of the conflict zones the refinement of one run
                                  // may search where its boundary was not recovered before
                                  // refinement (its tetrahedra classified by the winding number, a
                                  // mesh retries usually replace): its rounds stop beyond it. Such
                                  // runs searched up to 27 million in their 8 rounds (trimesh's
                                  // plate_holes.STL: 18 s of a 35 s row). 0: no bound
  double edge_length_scale = 1.0; // the first attempt's interior edge length, × this: below 1 its
                                  // boundary points (crease points and the lattice on flat patches,
                                  // spaced by the length) start denser (squeeze mesh: a part whose
                                  // boundary no attempt recovered, at 1/2 then 1/4)
  double run_refine_work = 4e7;   // cells of the conflict zones the refinement of any one run may
                                  // search: a safety net against runs that do not end (its rounds
                                  // and its last round stop beyond it, warned). The most measured
                                  // in a run that held: 10.6 million (trimesh's tray, version 23);
                                  // the corpus's and organs' under 60,000. 0: no bound
};

/// What tetrahedralize() reports beside the mesh.
struct TetrahedralizeStats {
  int attempts = 0;              // meshing runs (each at one interior edge length)
  double edge_length = 0.0;      // interior target edge length of the mesh kept (model units)
  int minimum_tets = 0;          // tetrahedra of the coarsest mesh the boundary allows (quality
                                 // refinement only, no size bound); 0 when not measured
  int boundary_splits = 0;       // boundary edges split (for conformity and quality) in the mesh kept
  int steiner_points = 0;        // interior points inserted in the mesh kept
  int peeled = 0;                // boundary tetrahedra under min_dihedral removed (peel_max_height)
  int relocated = 0;             // vertex moves of relocate_sliver_vertices at the end (tet_cleanup.h)
  int flat_cells_flipped = 0;    // surface diagonals flipped to put flat cells outside, all attempts
                                 // (TetrahedralizeOptions::flip_flat_surface_cells)
  int flips = 0;                 // 2-3 and 3-2 flips of interior slivers under min_dihedral at the
                                 // end (tet_cleanup.h: flip_slivers; boundary and volume unchanged)
  int contractions = 0;          // sliver edges contracted at the very end (contract_sliver_edges)
  bool conforming = true;        // every boundary triangle (after splits) is a face of the mesh
  bool recovered = true;         // ... already before refinement, in the run kept (not so: its
                                 // refinement was bounded by unrecovered_refine_work, its
                                 // tetrahedra classified by the winding number)
  bool recovery_abandoned = false;  // ... the first recovery of the run kept gave up at
                                 // TetrahedralizeOptions::recovery_splits_per_face (not refined)
  int exuder_nan_stops = 0;      // attempts whose CGAL exuder met a NaN weight beside a numerically flat
                                 // cell and stopped there, instead of the process dying of SIGFPE
  int exuder_pump_bounds = 0;    // attempts whose exuder stopped at exude_pumps_per_sliver
  int runs_at_work_bound = 0;    // runs whose refinement stopped at run_refine_work (all attempts)
  double refine_work = 0;        // cells of the conflict zones refinement searched, all attempts
  bool work_exceeded = false;    // refinement stopped at TetrahedralizeOptions::max_refine_work
};

/// Tetrahedralizes the solid bounded by `boundary`, a closed, consistently outward-oriented,
/// non-self-intersecting triangle surface (one or several components; nested components bound
/// cavities), so that the mesh's boundary is that surface: every boundary face of the result
/// lies in a face of `boundary`, every vertex of `boundary` is a vertex of the result. Method: the
/// Delaunay tetrahedralization (CGAL, exact predicates) of the surface's vertices, made conforming by
/// splitting surface edges at their midpoints (points on the surface), then Delaunay refinement
/// of the inside (Shewchuk, "Tetrahedral mesh generation by Delaunay refinement", SoCG 1998,
/// doi:10.1145/276884.276889): a tetrahedron with a dihedral angle below refine_dihedral or too
/// large for the target gets its circumcentre, unless that would destroy a surface face, which
/// is split instead; finally CGAL's sliver exudation (Cheng, Dey, Edelsbrunner, Facello, Teng,
/// J. ACM 47(5), 2000, doi:10.1145/355483.355487), which changes weights only and never a surface
/// face. Where tetrahedra below min_dihedral are left in the mesh kept (four corners on the boundary
/// across a thin part), relocate_sliver_vertices then flip_slivers (tet_cleanup.h) follow: the
/// first may move a sliver's boundary vertex within the tangent plane of a smooth boundary (all
/// its faces within 20° of their mean normal; by 5–20 % of the sliver's shortest edge), so such a
/// vertex can leave the surface by that much where the surface curves; the flips change no vertex.
/// (Before them, boundary slivers at most peel_max_height thick are peeled off; after them, the
/// boundary slivers still below min_dihedral are, whatever their height; before that, the slivers
/// still left have their short edges contracted, contract_sliver_edges and contract_max_length,
/// with the moves and flips again between rounds of contractions.)
/// Tetrahedra come out positively oriented, vertices without tetrahedron dropped; label
/// is empty. Deterministic (no threads, fixed seeds).
/// Throws InputError if the surface has no face or target_tets < 1; returns an empty mesh when no
/// tetrahedron is inside (the caller reports it).
TetMesh tetrahedralize(const SurfaceMesh& boundary, const TetrahedralizeOptions& options = {},
                       TetrahedralizeStats* stats = nullptr, Progress* progress = nullptr);

}  // namespace squeeze::meshing
