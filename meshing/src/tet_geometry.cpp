#include "squeeze/meshing/tet_geometry.h"

#include <algorithm>
#include <cmath>

#include "squeeze/meshing/tet_faces.h"

namespace squeeze::meshing {

using Vec3 = Eigen::Vector3d;

Eigen::VectorXd tet_volumes(const TetMesh& m) {
  Eigen::VectorXd v(m.T.rows());
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    v(t) = tet_volume(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3)));
  return v;
}

std::array<double, 6> dihedral_angles(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b,
                                      const Eigen::RowVector3d& c, const Eigen::RowVector3d& d) {
  const Vec3 p[4] = {a.transpose(), b.transpose(), c.transpose(), d.transpose()};
  // Outward face normals; the dihedral angle at edge (i,j) is pi minus the angle between the
  // normals of the two faces that contain it.
  Vec3 n[4];
  for (int k = 0; k < 4; ++k) {
    const Vec3 u = p[kTetFace[k][1]] - p[kTetFace[k][0]], v = p[kTetFace[k][2]] - p[kTetFace[k][0]];
    n[k] = u.cross(v);
    const double len = n[k].norm();
    if (len > 0) n[k] /= len;
  }
  // Face k is opposite vertex k; edge (i,j) is shared by the faces opposite the other two vertices.
  std::array<double, 6> out{};
  for (int e = 0; e < 6; ++e) {
    int f[2], q = 0;
    for (int k = 0; k < 4; ++k)
      if (k != kTetEdge[e][0] && k != kTetEdge[e][1]) f[q++] = k;
    const double cosang = std::clamp(-n[f[0]].dot(n[f[1]]), -1.0, 1.0);
    out[e] = std::acos(cosang) * 180.0 / M_PI;
  }
  return out;
}

void orient_positively(TetMesh& m) {
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    if (tet_volume(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3))) < 0)
      std::swap(m.T(t, 2), m.T(t, 3));
}

}  // namespace squeeze::meshing
