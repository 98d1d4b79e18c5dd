// squeeze::meshing — a tetrahedral mesh as libigl-style matrices.
#pragma once
#include <Eigen/Core>

namespace squeeze::meshing {

/// A tetrahedral mesh.
///   V      #V by 3 vertex positions (model units)
///   T      #T by 4 vertex indices, positively oriented: (V1-V0)·((V2-V0)×(V3-V0)) > 0
///   label  #T subdomain label per tetrahedron (squeeze mesh: index of the convex shell whose
///          interior holds the tet's centroid, 1-based), or empty
struct TetMesh {
  Eigen::MatrixX3d V;
  Eigen::MatrixX4i T;
  Eigen::VectorXi label;
};

}  // namespace squeeze::meshing
