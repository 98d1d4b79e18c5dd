// squeeze::meshing — a closed surface remeshed into rounder triangles of about one edge length,
// its sharp creases kept.
#pragma once
#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

struct RemeshOptions {
  double edge_length = 0.0;   // units: the target edge length (> 0)
  double sharp_angle = 40.0;  // degrees: edges whose two faces' normals turn by more than this are
                              // creases, kept as polylines (split and collapsed along themselves,
                              // never flipped or moved off their line)
  bool protect_creases = false;  // true: creases neither split (after a first split of those longer
                              // than edge_length) nor collapsed, so a hole's rim keeps its own short
                              // pieces (exact, but the triangles beside them stay thin); false:
                              // collapsed along themselves too, where a rim of pieces far shorter
                              // than edge_length becomes chords of it
  int iterations = 3;         // rounds of split, collapse, flip, relaxation and projection
};

/// Remeshes `surface` (a closed, consistently oriented 2-manifold: one part's boundary) with
/// triangles of edges about options.edge_length: splits of edges over 4/3 of it, collapses under
/// 4/5, flips toward valence 6, tangential relaxation, each vertex projected back onto `surface`
/// (Botsch, Kobbelt, "A remeshing approach to multiresolution modeling", SGP 2004,
/// doi:10.1145/1057432.1057457; CGAL's Polygon_mesh_processing::isotropic_remeshing). Creases
/// sharper than options.sharp_angle are polylines: those longer than the edge length are split
/// into equal pieces first; then they are split and collapsed only along themselves and never
/// flipped (protect_creases: not split or collapsed at all); their corners (where other than two
/// creases meet, or a crease turns by over 30°) do not move. The vertices lie on `surface`; faces
/// are chords of it (off it by their sagitta where it curves, and by up to about a third of the
/// edge length where a crease collapses across a feature shorter than that: the caller measures
/// how far). The topology is kept: through-holes narrower than the edge length stay, as thin
/// tunnels. Implemented in envelope.cpp (CGAL's surface mesh, beside the sheet's remeshing).
/// Used where a part's own triangles are long and thin (CAD tessellations: a fillet's strips
/// 0.6 mm wide and 10 mm long) and its tetrahedralization does not recover them.
///   surface  V #V by 3 (units), F #F by 3, outward
/// Returns the remeshed surface, outward; empty where CGAL does not take `surface` as a closed
/// polygon mesh or fails on it (the caller keeps what it had). Throws InputError when
/// options.edge_length is not positive and finite. Deterministic.
SurfaceMesh remesh_isotropic(const SurfaceMesh& surface, const RemeshOptions& options);

}  // namespace squeeze::meshing
