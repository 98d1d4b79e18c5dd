#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

void bounding_box(const Eigen::MatrixX3d& V, Eigen::RowVector3d& lo, Eigen::RowVector3d& hi) {
  lo = V.colwise().minCoeff();
  hi = V.colwise().maxCoeff();
}

double bounding_box_diagonal(const Eigen::MatrixX3d& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

}  // namespace squeeze::meshing
