// squeeze::meshing — the faces of a tetrahedral mesh: the local face and edge tables of a
// tetrahedron, the boundary triangles, face adjacency, and face-connected components. The one
// face extraction of squeeze: the meshing stage, fem::Body (boundary F, boundary_face, neighbor)
// and the renderer all call tet_faces.
#pragma once
#include <Eigen/Core>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// Local faces of the tetrahedron (v0, v1, v2, v3): row k holds the three local vertices of the
/// face opposite vertex k, ordered so that the face's normal (v[1] − v[0]) × (v[2] − v[0]) points
/// out of a positively oriented tetrahedron (see TetMesh), into a negatively oriented one.
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/// Local edges of a tetrahedron, (i, j) with i < j, in lexicographic order: 01 02 03 12 13 23.
inline constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/// The faces of a tetrahedral mesh, by how many tetrahedra share them.
struct TetFaces {
  /// #B by 3 boundary triangles (faces of exactly one tetrahedron), as kTetFace gives them: outward
  /// for positively oriented tetrahedra. Ordered by their sorted vertex triples (ascending).
  Eigen::MatrixX3i boundary;
  /// #T by 4: row of `boundary` of the face opposite local vertex k of tetrahedron t, or -1.
  Eigen::MatrixX4i boundary_face;
  /// #T by 4: the tetrahedron across the face opposite local vertex k of tetrahedron t, or -1 on
  /// the boundary and at faces shared by three or more tetrahedra (left unconnected).
  Eigen::MatrixX4i neighbor;
  int interior = 0;    // faces shared by exactly two tetrahedra
  int overshared = 0;  // faces shared by three or more (non-manifold; 0 for a valid mesh)
};

/// Faces of the tetrahedra T (any orientation; faces are matched by their vertex sets).
///   T  #T by 4 vertex indices
/// Deterministic; O(#T log #T).
TetFaces tet_faces(const Eigen::MatrixX4i& T);

/// tet_faces(T).boundary: #B by 3 outward boundary triangles of positively oriented T.
Eigen::MatrixX3i boundary_faces(const Eigen::MatrixX4i& T);

/// Face-connected components of `mesh`: tetrahedra sharing a face (also one shared by three or
/// more) are in one component. Ids are numbered in order of their lowest tetrahedron.
///   mesh  T #T by 4 (V is not used)
///   C     receives #T component id per tetrahedron, 0-based
/// Returns the number of components.
int tet_components(const TetMesh& mesh, Eigen::VectorXi& C);

}  // namespace squeeze::meshing
