// squeeze::meshing — a closed, 2-manifold, self-intersection-free surface around any triangle soup.
#pragma once
#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

struct AlphaWrapOptions {
  double alpha = 0.015;   // fraction of the bounding-box diagonal: the radius of the ball carving
                          // the wrap; cavities, holes and gaps narrower than about this are closed
  double offset = 0.002;  // fraction of the bounding-box diagonal: how far outside the input the
                          // wrap lies
};

/// Wraps the triangle soup `input` (any: open, non-manifold, self-intersecting, many parts) in a
/// closed, outward-oriented, 2-manifold surface free of self-intersections that lies `offset`
/// outside it and follows it into every concavity wider than `alpha`: CGAL's 3D Alpha Wrapping
/// (C. Portaneri, M. Rouxel-Labbé, M. Hemmer, D. Cohen-Steiner, P. Alliez, "Alpha Wrapping with an
/// Offset", ACM Transactions on Graphics 41(4), 2022, doi:10.1145/3528223.3530152).
///   input  #V by 3 vertices (model units), #F by 3 faces (orientation irrelevant)
///   returns the wrap: its vertices (model units) and faces, outward
/// Deterministic. Throws InputError when `input` has no face or options are out of range.
SurfaceMesh alpha_wrap(const SurfaceMesh& input, const AlphaWrapOptions& options = {});

}  // namespace squeeze::meshing
