// squeeze::meshing — topology of a triangle soup: components, closedness, consistent orientation,
// enclosed volume, self-intersection.
#pragma once
#include <cstddef>
#include <vector>
#include <Eigen/Core>

#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

/// What squeeze mesh reports about its input.
struct SurfaceInfo {
  int vertices = 0;
  int faces = 0;
  int components = 0;          // face-connected components (faces sharing an edge)
  int boundary_edges = 0;      // edges with one incident face
  int nonmanifold_edges = 0;   // edges with three or more incident faces
  bool closed = false;         // no boundary edge
  bool self_intersecting = false;  // two faces that share no vertex intersect (exact predicates)
  double volume = 0.0;         // enclosed volume (units³): signed-volume sum over oriented
                               // components when closed, else by winding number (see report)
};

/// Face-connected components (through edges shared by exactly two faces, so non-manifold edges
/// separate). Returns the number of components; C  #F component id per face, 0-based, numbered in
/// order of their first face.
int face_components(const Eigen::MatrixX3i& F, Eigen::VectorXi& C);

/// When orient_outward keeps the file's own orientation of a component.
struct OrientOptions {
  long min_seamed_part = 16;  // faces: a component welded to others (non-manifold edges) keeps
                              // the file's orientation where every part the file orients
                              // consistently (split at the edges it turns) has at least this many
};

/// Orients the faces of every component consistently (breadth-first over manifold edges), then
/// flips each component whose signed volume (about its centroid) is negative, so closed
/// components face outward. A component welded to others (it has non-manifold edges) in which the
/// file turns some edges between large parts (see OrientOptions) keeps the file's orientation,
/// face by face, before that sign is taken: such an edge is a seam between segments of a welded
/// surface that lost its third face (a hole cut at a junction), and making the faces agree across
/// it turns one segment inside out. Other components are made consistent (an open scan whose
/// halves the file turns against each other; a stray flipped face).
///   V  #V by 3 positions;  F  #F by 3 faces
/// Returns the re-oriented F. Throws nothing. Source of the idea: Jacobson et al. 2013 (winding
/// numbers need consistent orientation); the propagation is the standard BFS.
Eigen::MatrixX3i orient_outward(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                const OrientOptions& opt = {});

/// True when every edge of F has exactly two incident faces.
bool is_closed(const Eigen::MatrixX3i& F);

/// True when F (consistently oriented) is a closed oriented 2-manifold: every edge has exactly two
/// faces, which traverse it in opposite directions, and the faces around every vertex form a
/// single fan (no two cones meeting at a vertex).
///   F         #F by 3 vertex indices
///   vertices  #V (vertices without faces are allowed)
bool is_oriented_two_manifold(const Eigen::MatrixX3i& F, int vertices);

/// The faces around each vertex: entry v lists, in increasing order, the faces of F that hold v.
///   F         #F by 3 vertex indices, each in [0, vertices)
///   vertices  #V (a vertex without faces gets an empty list)
/// Throws nothing; indices are not checked (asserted in debug).
std::vector<std::vector<int>> vertex_faces(const Eigen::MatrixX3i& F, Eigen::Index vertices);

/// One face's use of an undirected edge.
struct EdgeIncidence {
  int a, b;      // the edge's vertices, a < b
  int face;      // the face (row of F)
  bool forward;  // the face traverses a → b (else b → a)
};

/// Every face's three edges, sorted by (a, b, face): each undirected edge's faces are one run,
/// in increasing face order (for_each_edge visits the runs). Throws nothing.
///   F  #F by 3 vertex indices
/// Returns 3 #F incidences.
std::vector<EdgeIncidence> edge_incidences(const Eigen::MatrixX3i& F);

/// Calls fn(begin, end) for each undirected edge's run [begin, end) of `e` (edge_incidences').
template <class Fn>
void for_each_edge(const std::vector<EdgeIncidence>& e, Fn fn) {
  for (size_t i = 0; i < e.size();) {
    size_t j = i + 1;
    while (j < e.size() && e[j].a == e[i].a && e[j].b == e[i].b) ++j;
    fn(i, j);
    i = j;
  }
}

/// Edge counts, components, closedness and (for closed meshes) volume of `mesh`. The
/// self_intersecting flag is left false here; see does_self_intersect().
SurfaceInfo analyse_surface(const SurfaceMesh& mesh);

/// True when two faces that share no vertex intersect (CGAL exact predicates, box intersection).
/// Faces sharing a vertex are not tested (the usual approximation for soups).
bool does_self_intersect(const SurfaceMesh& mesh);

}  // namespace squeeze::meshing
