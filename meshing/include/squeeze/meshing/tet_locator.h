// squeeze::meshing — point location in a tetrahedral mesh (the tetrahedron containing a point, or
// the nearest one), used by the coverage measures of `squeeze mesh` and by the FFD binding.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// Point location with a uniform grid over the tetrahedra's bounding boxes (cell: the mean length
/// of the tetrahedra's v0v1 edges, at least 1/256 of the mesh's extent). Build O(#T);
/// queries O(1) expected for points near the mesh; candidates are culled by their (padded)
/// bounding boxes before any exact test. Const queries are thread-safe.
/// The locator keeps a reference to `mesh`, which must outlive it and not change.
class TetLocator {
 public:
  ///   mesh  V #V by 3 (units), T #T by 4 (either orientation; may be empty)
  explicit TetLocator(const TetMesh& mesh);
  /// The tetrahedron containing p: its four barycentric coordinates all >= -1e-10; ties go to the
  /// lowest index. Returns -1 if none (and for an empty mesh).
  ///   p     query point (units)
  ///   bary  optional; receives the four barycentric coordinates of p in the tetrahedron found
  int locate(const Eigen::RowVector3d& p, Eigen::Vector4d* bary = nullptr) const;
  /// The tetrahedron nearest to p (distance 0 inside), ties to the lowest index. Always succeeds for
  /// a non-empty mesh; -1 for an empty one.
  ///   p         query point (units)
  ///   distance  optional; receives the distance from p to that tetrahedron (units)
  int nearest(const Eigen::RowVector3d& p, double* distance = nullptr) const;
  /// Barycentric coordinates of p in tetrahedron t (negative ones outside it), 4 summing to 1, by
  /// Cramer's rule (triple products); not finite for a tetrahedron of no volume.
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

}  // namespace squeeze::meshing
