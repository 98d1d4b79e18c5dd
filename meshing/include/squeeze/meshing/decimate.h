// squeeze::meshing — a dense surface decimated by quadric error within a distance bound: the proxy
// that the pipeline meshes in place of a scan of hundreds of thousands of triangles (meshing
// version 49), its results measured against the scan itself.
#pragma once
#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

struct DecimateOptions {
  double max_error = 0.0;        // units: no vertex may end farther than this from the plane of any
                                 // input face it took in (0: only collapses of no error, coplanar)
  int target_faces = 0;          // stop at this many faces (0: as far as max_error allows)
  double max_normal_turn = 60.0; // degrees: no collapse turns a face's normal further
  bool plane_by_plane = true;    // where the root of the summed quadric is over max_error, check the
                                 // planes one by one (false: the root alone, as in meshing version 49:
                                 // faster per collapse, far fewer collapses on a noisy scan)
};

/// What decimate_quadric() did.
struct DecimateStats {
  int faces = 0;             // faces of the result
  int collapses = 0;         // edge collapses made
  int frozen_vertices = 0;   // input vertices kept where they are (see decimate_quadric)
  double max_error = 0;      // units: the largest error of a collapse made (at most the bound: the
                             // largest plane distance, or the root of the quadric where that was within)
};

/// Decimates `surface` by edge collapses, cheapest first, with quadric error metrics (M. Garland,
/// P. Heckbert, "Surface simplification using quadric error metrics", SIGGRAPH 1997,
/// doi:10.1145/258734.258849). Each vertex carries the sum of the squared-distance quadrics of the
/// planes of the input faces around it, one per face, unweighted, and the list of those faces. A
/// collapse merges the two quadrics and lists and places the vertex at the quadric's minimiser
/// nearest the edge's midpoint (small eigenvalues cut, as Lindstrom and Turk's placement does where
/// the optimum is not unique: a flat region keeps its vertices in its plane), else at an end of the
/// edge; cheapest (the quadric there) first. It is made when
///   * the point lies within max_error of the plane of every input face the two ends took in: the
///     square root of the merged quadric bounds those distances, and where it is over max_error
///     they are checked one by one (a scan's noise fills the sum of squares long before any one
///     plane is near the bound; meshing version 50);
///   * the link condition holds (the two ends share exactly the edge's two opposite vertices as
///     neighbours: no handle closed, no component collapsed) and each opposite vertex keeps three
///     neighbours;
///   * no face turns its normal by more than max_normal_turn or loses its area, and no new face
///     has a shape (4√3 area / its edges' squares summed) under 0.05 unless the face was worse.
/// An edge whose collapse fails the checks is tried again once the faces around either end change.
/// Vertices on a border, on an edge of other than two faces or of two faces that do not run along
/// it in opposite directions, on a face of no area, or where faces meet at the vertex only (a
/// non-manifold vertex) stay where they are and are never removed (edges from them collapse onto
/// them): the input's borders, seams and topology are the result's. Single-threaded and
/// deterministic (ties broken by vertex index). The quadrics are formed about the bounding box's
/// centre (an input far from the origin keeps its precision).
///   surface  V #V by 3 (units), F #F by 3 (0-based); any triangle soup
/// Returns V #V' by 3, F #F' by 3: the faces left, their vertices renumbered in order of first use
/// (unreferenced vertices dropped), each face's orientation the input's.
/// Throws InputError where max_error is negative or not finite, or where `surface` has a vertex
/// index out of range or a coordinate that is not finite.
SurfaceMesh decimate_quadric(const SurfaceMesh& surface, const DecimateOptions& options, DecimateStats* stats = nullptr);

}  // namespace squeeze::meshing
