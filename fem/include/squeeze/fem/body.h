// squeeze::fem — one simulated object: a tetrahedral mesh with its material and rest data
// (rest lengths and volumes, lumped masses, edges, incidence lists, face adjacency, surface).
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::fem {

/// Row-major #N by 3 matrix: one vertex per contiguous row (positions, velocities, forces).
using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// Material of a deformable object (ignored for rigid ones but for nothing: rigid objects have no
/// mass and never move). Energies are ½ k C² with dimensionless C (see constraints.h), so
/// stiffnesses are in joules. A rule of thumb: an edge of rest length D0 behaves like a spring of
/// k_distance / D0² N/m.
struct Material {
  double density = 1000.0;        // kg/m³; lumped masses: each tet gives ¼ of its mass to each vertex
  double k_distance = 1000.0;     // J, distance constraint of every tet edge (paper eq. 3)
  double k_volume = 1000.0;       // J, volume constraint of every tet (paper eq. 4)
  double damping_distance = 0.0;  // J·s, Teschner 2004 damping of the distance constraints
  double damping_volume = 0.0;    // J·s, Teschner 2004 damping of the volume constraints
};

/// Rest data of one object. Build it from a TetMesh, a material and a rigid transform (the scene
/// loader's input); vertex and tet order are those of the mesh.
class Body {
 public:
  /// mesh       V (m) and positively oriented T of the object in its own frame
  /// transform  placement in the world: world = transform · V
  /// rigid      rigid objects never move but collide
  /// Throws InputError if the mesh has no tetrahedron, an index out of range, a non-finite
  /// coordinate, a tetrahedron of non-positive volume (after the transform), or the material has
  /// a non-positive density or a negative stiffness or damping.
  Body(const TetMesh& mesh, const Material& material, bool rigid = false,
       const Eigen::Affine3d& transform = Eigen::Affine3d::Identity());

  bool rigid = false;
  Material material;
  RowMatrixX3d rest;        // #V by 3 world positions at rest (m)
  Eigen::MatrixX4i T;       // #T by 4 tetrahedra
  Eigen::MatrixX2i E;       // #E by 2 unique edges of the tetrahedra, (i < j), sorted
  Eigen::VectorXd D0;       // #E rest lengths (m)
  Eigen::VectorXd V0;       // #T rest volumes (m³)
  Eigen::VectorXd mass;     // #V lumped masses (kg)
  Eigen::MatrixX4i neighbor;  // #T by 4: tet across the face opposite local vertex k, or -1
  Eigen::MatrixX4i boundary_face;  // #T by 4: row of F for the face opposite vertex k, or -1
  Eigen::MatrixX3i F;       // #F by 3 boundary triangles, oriented outward
  std::vector<char> on_boundary;  // #V: vertex lies on a boundary triangle
  // CSR incidence lists (vertex → elements), in increasing element order:
  //   edges of vertex i: edge_code[edge_start[i] .. edge_start[i+1]), code = 2·edge + local (0/1)
  //   tets of vertex i:  tet_code[tet_start[i] .. tet_start[i+1]),    code = 4·tet + local (0..3)
  std::vector<int> edge_start, edge_code, tet_start, tet_code;

  int vertices() const { return static_cast<int>(rest.rows()); }
  int tets() const { return static_cast<int>(T.rows()); }
  double mean_edge_length() const;  // m
  double total_volume() const;      // m³ at rest
};

/// Signed volume of every tetrahedron of `body` at positions X (#V by 3), m³.
double volume(const Body& body, const Eigen::Ref<const RowMatrixX3d>& X);

/// A box [lo, hi] split into n[0]×n[1]×n[2] cells of 6 tetrahedra each (Kuhn / Freudenthal
/// subdivision, conforming), positively oriented. Throws InputError if a count is < 1 or lo >= hi.
TetMesh box_tet_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n);

/// A voxelized ball of `radius` (m) centered at the origin: the cells of box_tet_mesh of
/// [−radius, radius]³ with n cells per axis whose center lies in the ball (about π n³ tets, all of
/// the same good shape). Throws InputError if radius <= 0 or no cell is kept.
TetMesh ball_tet_mesh(double radius, int n);

}  // namespace squeeze::fem
