// squeeze::meshing — a closed 2-manifold surface of the solid a triangle soup bounds, for inputs
// that are not one themselves (holes, self-intersections, overlapping parts).
#pragma once
#include "squeeze/meshing/surface.h"

namespace squeeze {
class Progress;
}

namespace squeeze::meshing {

class FastWindingNumber;
class TriangleBvh;

/// The boundary of the solid { x : w(x) > 1/2 }, w the generalized winding number of `input`,
/// by marching tetrahedra (each cube of a grid of spacing h split into six tetrahedra along its
/// main diagonal, so that neighbouring cubes agree and the result is a closed 2-manifold whatever
/// the input). The grid's nodes are classified by w: nodes of cubes a triangle passes through
/// one by one, the others by the 6-connected region of such nodes they lie in (a few samples
/// per region; every node of a region whose samples disagree). Each vertex lies on a grid edge
/// between an inside and an outside node, where that edge crosses the input surface (the crossing
/// nearest its middle; the middle where it crosses none, over a hole). Triangles face outward.
/// Parts thinner than about h may be lost or thickened to about h; the caller picks h.
///   input  V #V by 3, F #F by 3, faces oriented outward per component (orient_outward)
///   wn     winding numbers of `input`;  bvh  the triangles of `input`
///   h      grid spacing (units)
/// Deterministic for any thread count.
SurfaceMesh solid_surface(const SurfaceMesh& input, const FastWindingNumber& wn, const TriangleBvh& bvh, double h,
                          Progress* progress = nullptr);

}  // namespace squeeze::meshing
