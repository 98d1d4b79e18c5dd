// squeeze::meshing — measures and clean-ups of tetrahedral meshes (used by `squeeze mesh`, its
// report and the tests).
#pragma once
#include <Eigen/Core>
#include <vector>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// Signed volume of tetrahedron (a,b,c,d): (b-a)·((c-a)×(d-a)) / 6 (units³).
double tet_volume(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b, const Eigen::RowVector3d& c,
                  const Eigen::RowVector3d& d);

/// Signed volume of every tetrahedron. Returns #T vector (units³).
Eigen::VectorXd tet_volumes(const TetMesh& mesh);

/// The six interior dihedral angles of tetrahedron (a,b,c,d), in degrees.
std::array<double, 6> dihedral_angles(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b,
                                      const Eigen::RowVector3d& c, const Eigen::RowVector3d& d);

/// Swaps two vertices of every negatively oriented tetrahedron so all volumes are >= 0.
void orient_positively(TetMesh& mesh);

/// Drops vertices no tetrahedron uses and renumbers T (order of the rest kept).
void remove_unused_vertices(TetMesh& mesh);

/// Repeatedly removes tetrahedra with a face on the boundary and a dihedral angle below
/// `min_degrees` (flat boundary slivers add no volume worth keeping), in up to 16 passes since
/// peeling exposes new boundary tetrahedra; it never removes the last one. Interior slivers are
/// left alone. Returns how many were removed.
int peel_boundary_slivers(TetMesh& mesh, double min_degrees);

/// Moves boundary vertices outward (along their area-weighted normals) until the points P lie
/// inside the mesh or within `tolerance` of it: every point farther out pushes the three vertices of
/// its nearest boundary face by its distance. A move is halved, then dropped, where a tetrahedron
/// would become inverted or get a dihedral angle below min(min_degrees, its own before). Local
/// moves cover a coarse mesh's chords at far less volume than dilating everything. Up to
/// `iterations` rounds; deterministic. Returns how many vertex moves were made.
///   P  #P by 3 points (units); tolerance in units
int inflate_to_cover(TetMesh& mesh, const Eigen::MatrixX3d& P, double tolerance, double min_degrees,
                     int iterations = 6);

/// Faces of the mesh with how many tetrahedra share them.
struct FaceCensus {
  Eigen::MatrixX3i boundary;   // #B by 3 boundary faces, oriented outward
  int interior = 0;            // faces shared by exactly two tetrahedra
  int overshared = 0;          // faces shared by three or more (must be 0)
};
FaceCensus face_census(const TetMesh& mesh);

/// Face-connected components. Returns their number; C  #T component id per tetrahedron.
int tet_components(const TetMesh& mesh, Eigen::VectorXi& C);

/// Quality figures reported by `squeeze mesh`.
struct TetQuality {
  int tets = 0, vertices = 0;
  double min_volume = 0, volume = 0;         // units³
  double min_dihedral = 0, max_dihedral = 0; // degrees
  double min_edge = 0, mean_edge = 0;         // units, over the mesh's unique edges
  int components = 0;
  int overshared_faces = 0;
};
TetQuality tet_quality(const TetMesh& mesh);

/// Point location in a tetrahedral mesh with a uniform grid over the tetrahedra's bounding boxes
/// (cell about the mean edge length). Build O(#T), queries O(1) expected for points near the mesh;
/// candidates are culled by their (padded) bounding boxes before any exact test. Const queries are
/// thread-safe.
class TetLocator {
 public:
  explicit TetLocator(const TetMesh& mesh);
  /// The tetrahedron containing p (barycentric coordinates all >= -eps, eps = 1e-10), or -1;
  /// bary receives its four barycentric coordinates. Ties go to the lowest index.
  int locate(const Eigen::RowVector3d& p, Eigen::Vector4d* bary = nullptr) const;
  /// The tetrahedron nearest to p (0 distance when inside), ties to the lowest index; distance in
  /// units. Always succeeds for a non-empty mesh.
  int nearest(const Eigen::RowVector3d& p, double* distance = nullptr) const;
  /// Barycentric coordinates of p in tetrahedron t (may be negative outside it).
  Eigen::Vector4d barycentric(int t, const Eigen::RowVector3d& p) const;

 private:
  const TetMesh& mesh_;
  Eigen::Vector3d origin_;
  double cell_ = 1;
  int n_[3] = {1, 1, 1};
  std::vector<int> start_, items_;  // CSR: tets per cell
  std::vector<double> box_;         // 6 per tet: min xyz, max xyz, padded by 1e-9 of its extent
  bool in_box(int t, const Eigen::Vector3d& p) const;
  double box_distance(int t, const Eigen::Vector3d& p) const;  // lower bound of distance_to
  double distance_to(int t, const Eigen::Vector3d& p) const;
};

/// Distance from p to triangle (a,b,c) (units).
double point_triangle_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c);

}  // namespace squeeze::meshing
