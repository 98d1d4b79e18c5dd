// squeeze::meshing — area- and angle-weighted face and vertex normals of a triangle mesh: the one
// accumulation of squeeze (envelope gaps, the winding route's seeds, the tet clean-ups' boundary
// normals, the FFD's render normals).
#pragma once
#include <Eigen/Core>

namespace squeeze::meshing {

/// Area-weighted normals of the triangle mesh (V, F).
///   V   #V by 3 vertex positions (units)
///   F   #F by 3 vertex indices into V; the orientation of each face sets the side of its normal
///   FN  #F by 3 output: per face (v1 − v0) × (v2 − v0), twice its area times its unit normal (units²)
///   N   #V by 3 output: per vertex the sum of FN over its faces (not normalized; zero for a vertex
///       without a face of non-zero area)
/// FN is computed in parallel (TBB), N by a serial scatter in face order, so the result is the same
/// bit for bit with any thread count. Throws nothing; indices are not checked (asserted in debug).
void area_weighted_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, Eigen::MatrixX3d& FN,
                           Eigen::MatrixX3d& N);

/// Angle-weighted vertex normals of (V, F) (G. Thürmer, C. A. Wüthrich, "Computing vertex normals
/// from polygonal meshes", J. Graphics Tools 3(1), 1998): per vertex the sum of its faces' unit
/// normals, each weighted by the face's angle at the vertex (radians), not normalized. On a
/// straight crease it is the bisector whatever the triangles' sizes (a thin bent plate's mid-surface,
/// meshing version 15). Serial, deterministic. Throws nothing.
///   N  #V by 3 output (zero for a vertex without a face of non-zero area)
void angle_weighted_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, Eigen::MatrixX3d& N);

}  // namespace squeeze::meshing
