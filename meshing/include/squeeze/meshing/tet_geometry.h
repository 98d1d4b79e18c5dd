// squeeze::meshing — volume, orientation and dihedral angles of tetrahedra.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// Signed volume of the tetrahedron (a, b, c, d) (units³):
///   (b − a) · ((c − a) × (d − a)) / 6,
/// positive when (a, b, c, d) is positively oriented (d lies on the side of triangle (a, b, c)
/// that its normal (b − a) × (c − a) points to), negative when inverted, 0 when flat.
///   a, b, c, d  the four corners (units)
/// Inline, and every caller that computes this volume (the meshing stage, fem::Body's rest volumes
/// and fem::volume, the renderer's volume plot) calls this one expression, so their results agree
/// to the bit. (fem's volume-constraint kernels, constraints.h, keep their own copy: they share
/// the cross product with the gradient.)
inline double tet_volume(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b, const Eigen::RowVector3d& c,
                         const Eigen::RowVector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

/// Signed volume of every tetrahedron of `mesh` (tet_volume of its rows of T).
///   mesh  V #V by 3 (units), T #T by 4
/// Returns #T vector (units³).
Eigen::VectorXd tet_volumes(const TetMesh& mesh);

/// The six interior dihedral angles of the tetrahedron (a, b, c, d), in degrees, at its edges in
/// kTetEdge order (ab, ac, ad, bc, bd, cd): π minus the angle between the outward normals of the
/// two faces that meet at the edge. Either orientation gives the same angles. A face of zero area
/// has no normal (its angles come out as 90°).
///   a, b, c, d  the four corners (units)
std::array<double, 6> dihedral_angles(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b,
                                      const Eigen::RowVector3d& c, const Eigen::RowVector3d& d);

/// Makes every tetrahedron of `mesh` positively oriented: swaps T(t,2) and T(t,3) where
/// tet_volume < 0 (flat tetrahedra are left as they are). V and label are not touched.
///   mesh  V #V by 3, T #T by 4 (modified in place)
void orient_positively(TetMesh& mesh);

}  // namespace squeeze::meshing
