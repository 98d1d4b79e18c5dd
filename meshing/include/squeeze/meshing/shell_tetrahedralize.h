// squeeze::meshing — one conforming tetrahedral mesh of the union of convex shells (meshing
// version 3; since version 4 the fallback for inputs whose boundary cannot be meshed as it is).
#pragma once
#include <Eigen/Core>
#include <vector>

#include "squeeze/meshing/decompose.h"
#include "squeeze/meshing/tet_mesh.h"

namespace squeeze {
class Progress;
}

namespace squeeze::meshing {

struct ShellTetrahedralizeOptions {
  int target_tets = 1000;         // desired tetrahedron count, met within about ±35%: Mesh_3's cell
                                  // size (and with it the facet size and facet distance) is
                                  // re-estimated from each attempt's count
  double facet_distance = 0.0;    // fraction of the shells' bounding-box diagonal: an upper bound on
                                  // how far boundary facets may stray from the shells' surface; 0: no
                                  // bound beyond facet_distance_per_size (a bound finer than the
                                  // target allows makes the boundary, not the target, set the count)
  double facet_distance_per_size = 0.2;  // the facet distance used is this fraction of the cell size
                                  // (so a coarse target gets a coarse boundary)
  double offset = 0.003;          // fraction of the diagonal: the shells are dilated by at least this
                                  // much before meshing, so that boundary facets (chords of the
                                  // shells' surface) still enclose the shells' corners
  int max_tets = 5000;            // never more: the cell size grows until the count fits
  double coverage_tolerance = 0.004;  // fraction of the diagonal: the points to cover (the input's
                                  // vertices, or the shells' corners) must lie inside the mesh or this
                                  // close to it, 99.9% of them; the dilation grows until they do
  double min_dihedral = 10.0;     // degrees; boundary tetrahedra below it are peeled off afterwards
  double sliver_bound = 10.0;     // degrees; Mesh_3's sliver perturber and exuder work on tetrahedra
                                  // whose smallest dihedral angle is below this
  bool perturb = false;           // Mesh_3's sliver perturber before the exuder (before version 17): on
                                  // the union's inside test it spends its time in the domain's function
                                  // (the heart's shells at 300: 26.5 s of a 26.6 s run, Delaunay
                                  // refinement 0.01 s); instead, slivers left by the exuder have their
                                  // vertices relocated and are flipped (tet_cleanup.h), as the
                                  // winding-number route's are
  double optimize_seconds = 30.0; // time limit of each of Mesh_3's sliver perturber and exuder (0: none):
                                  // a bound for pathological inputs, far above what they take on real
                                  // meshes (reaching it is warned: the result then depends on load)
  unsigned seed = 1;              // CGAL's random generator, for run-to-run determinism
};

/// What tetrahedralize_shells() reports beside the mesh.
struct ShellTetrahedralizeStats {
  int attempts = 0;            // Mesh_3 runs needed to land near target_tets
  double cell_size = 0.0;      // Mesh_3 cell_size used (model units)
  double offset = 0.0;         // dilation of the shells used (model units)
  int peeled_slivers = 0;      // boundary tetrahedra removed for a dihedral angle < min_dihedral
  double facet_distance = 0.0; // Mesh_3 facet_distance used (model units)
  double covered = 0.0;        // fraction of the points to cover held (within coverage_tolerance)
  int relocated = 0;           // vertex moves that raised an interior sliver's angles (tet_cleanup.h)
  int flips = 0;               // 2-3 and 3-2 flips that removed a sliver (tet_cleanup.h)
};

/// Meshes the union of the shells as one domain with CGAL Mesh_3 (Delaunay refinement of a
/// labeled implicit domain whose function is the union's inside test, followed by sliver exudation;
/// Jamin, Alliez, Yvinec, Boissonnat, "CGALmesh", ACM TOMS 41(4), 2015, doi:10.1145/2699463), then
/// slivers' vertices relocated and slivers flipped (tet_cleanup.h). Being a subcomplex of one
/// Delaunay triangulation, the
/// result is conforming: shells that meet share vertices and faces, every interior face has
/// exactly two tetrahedra. Tetrahedra come out positively oriented; each is labelled with the
/// (1-based) shell that holds its centroid; unused vertices are dropped.
/// Boundary tetrahedra with a dihedral angle below min_dihedral are peeled off (tet_cleanup.h).
///   cover  #C by 3 points the mesh must hold (within coverage_tolerance × diagonal, 99.9% of
///          them; the pipeline passes the input's vertices), or nullptr: the shells' corners
/// Throws InputError if shells is empty or target_tets < 1; returns an empty mesh if Mesh_3
/// produced no tetrahedron (the caller reports it).
TetMesh tetrahedralize_shells(const std::vector<ConvexShell>& shells, const ShellTetrahedralizeOptions& options = {},
                              ShellTetrahedralizeStats* stats = nullptr, Progress* progress = nullptr,
                              const Eigen::MatrixX3d* cover = nullptr);

}  // namespace squeeze::meshing
