// squeeze::meshing — the coarse boundary of the simulation mesh: a closed surface simplified from
// the input's as far as a two-sided distance bound (and the target size) allow.
#pragma once
#include "squeeze/meshing/surface.h"

namespace squeeze {
class Progress;
}

namespace squeeze::meshing {

struct EnvelopeOptions {
  double max_outside = 0.0;   // units: the envelope may lie this far outside the surface (over a
                              // concavity, say); the pipeline passes max_deviation × diagonal
  double max_inside = 0.0;    // units: points of the surface may lie this far outside the envelope
                              // (where it cuts a convex bulge); the pipeline passes a third of the above
  int target_faces = 0;       // stop simplifying at this many faces (0: as far as the bounds allow)
  double min_fold_angle = 20.0;  // degrees: two adjacent faces may not meet at a sharper angle
                              // (a tetrahedron holding both could be no less flat)
  double max_normal_turn = 75.0; // degrees: a collapse may not turn a face's normal further
  double min_triangle_angle = 5.0; // degrees: nor make a face with a smaller angle (unless the
                              // face it replaces had one)
  double shape_weight = 1.0;  // Lindstrom–Turk's shape term (their default is 0): rounder triangles,
                              // which the tetrahedralization needs far fewer extra points to follow
  double short_edge = 0.25;   // then edges shorter than this share of the median edge are collapsed,
                              // shortest first, within the same bounds (0: not)
  double max_edge = 0.0;      // units: no collapse makes an edge longer than this (0: no bound)
  bool no_local_crossings = true;  // nor makes a face that crosses a face around the collapse's link
                              // (the faces its new faces' corners touch) or another new face (false:
                              // meshing version 50 and before, folds checked between neighbours only)
};

/// What simplify_envelope() did.
struct EnvelopeStats {
  int faces = 0;          // faces of the result
  int collapses = 0;      // edge collapses made
  bool bounded = false;   // stopped above target_faces because no collapse within the bounds was left
};

/// Simplifies the closed surface `surface` (consistently outward-oriented 2-manifold, no
/// self-intersection; it is also the reference the bounds are measured against) by edge collapses,
/// cheapest first by Lindstrom and Turk's volume- and boundary-preserving cost and placement
/// (P. Lindstrom, G. Turk, "Fast and memory efficient polygonal simplification", IEEE Visualization
/// 1998, doi:10.1109/VISUAL.1998.745314; CGAL's Surface_mesh_simplification), accepting a collapse
/// only when
///   * the new vertex and points along its new edges and in its new faces lie within max_outside of
///     the reference surface where they are outside it, within max_inside where they are inside;
///   * every point of the reference it is answerable for (the reference's vertices and samples of
///     its larger faces, each assigned to the face of the simplified surface nearest it after each
///     collapse, in the manner of Klein, Liebich, Straßer, "Mesh reduction with error control", IEEE
///     Visualization 1996) lies within max_inside of the new faces where it is outside them, within
///     max_outside where it is inside;
///   * no new face turns its normal by more than max_normal_turn nor folds against a neighbour
///     sharper than min_fold_angle;
///   * (no_local_crossings) no new face intersects a face around a vertex of the collapse's link,
///     other than at the corners and edge they share, nor another new face (exact predicates):
///     a fold across a small bump is no sharp fold between neighbours, yet its faces cross (a scanned
///     bust of 99,938 faces simplified to 1,506 kept one face through a fan of three).
/// It stops at target_faces or when no collapse is acceptable. Deterministic.
/// Throws InputError when `surface` is not a closed 2-manifold.
SurfaceMesh simplify_envelope(const SurfaceMesh& surface, const EnvelopeOptions& options, EnvelopeStats* stats = nullptr,
                              Progress* progress = nullptr);

/// The same with the bounds measured against `target`, a triangle soup the closed `surface` was
/// made from (open, welded, non-manifold or self-intersecting segments: its winding-number solid's
/// boundary, say; meshing version 11). A collapse is accepted only when points of the new faces
/// (as above) lie within max_outside of the target, on either side, and every point of the target
/// (its vertices and samples of its larger faces, each answerable to the face of the simplified
/// surface nearest it) lies outside the new faces by at most max_inside; inside them at any depth
/// (the target's inner walls). `surface` keeps the thin-part caps (a third of the local gap
/// between its sides) and is what is simplified. Points of the target already farther out than
/// max_inside keep their faces as they are. Throws InputError as above, and when `target` is empty.
/// The bounds make an envelope of the soup itself, as fTetWild's (Y. Hu, T. Schneider, B. Wang,
/// D. Zorin, D. Panozzo, "Fast tetrahedral meshing in the wild", ACM TOG 39(4), 2020,
/// doi:10.1145/3386569.3392385), here two-sided with different widths.
///   target  V #V by 3, F #F by 3 (units; orientation not used)
SurfaceMesh simplify_envelope(const SurfaceMesh& surface, const SurfaceMesh& target, const EnvelopeOptions& options,
                              EnvelopeStats* stats = nullptr, Progress* progress = nullptr);

/// The same for an open sheet (an oriented 2-manifold with borders: a curtain, or a scan with holes
/// remeshed by remesh_sheet), measured against `target`, the sheet it was made from: points of the
/// new faces within the bound of the target, and every point of the target (its vertices and
/// samples of its larger faces) within the bound of the new faces, on either side; the bound is the
/// smaller of max_outside and max_inside. Borders move as collapses take them, within the same
/// bound. The result is graded: large triangles where the sheet is flat, small where it curves
/// (with max_edge, none longer), as one layer of prisms over it needs (meshing version 15).
///   sheet, target  V #V by 3, F #F by 3 (units); `sheet` oriented, 2-manifold
/// Throws InputError when `sheet` is not an oriented 2-manifold or `target` is empty.
SurfaceMesh simplify_sheet(const SurfaceMesh& sheet, const SurfaceMesh& target, const EnvelopeOptions& options,
                           EnvelopeStats* stats = nullptr, Progress* progress = nullptr);

}  // namespace squeeze::meshing
