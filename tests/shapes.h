// Generated shapes shared by the meshing tests and benchmarks (no test framework: bench/ includes
// it too). Units: metres.
#pragma once
#include <Eigen/Core>

#include <cmath>
#include <vector>

#include "squeeze/meshing/surface.h"

namespace sqs {

// A faceted rod along z: `sides` vertices per ring, `rings` + 1 rings over `length`, capped by a
// fan around each end's centre (a CAD export's tube: side triangles length / rings long and
// 2 pi r / sides wide).
inline squeeze::meshing::SurfaceMesh ringed_rod(double r, double length, int sides, int rings) {
  squeeze::meshing::SurfaceMesh s;
  s.V.resize(sides * (rings + 1) + 2, 3);
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i < sides; ++i) {
      const double t = 2 * M_PI * i / sides;
      s.V.row(j * sides + i) << r * std::cos(t), r * std::sin(t), length * j / rings;
    }
  const int c0 = sides * (rings + 1), c1 = c0 + 1;
  s.V.row(c0) << 0, 0, 0;
  s.V.row(c1) << 0, 0, length;
  std::vector<Eigen::Vector3i> F;
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < sides; ++i) {
      const int a = j * sides + i, b = j * sides + (i + 1) % sides, c = a + sides, d = b + sides;
      F.emplace_back(a, b, d);
      F.emplace_back(a, d, c);
    }
  for (int i = 0; i < sides; ++i) {
    F.emplace_back(c0, (i + 1) % sides, i);
    F.emplace_back(c1, rings * sides + i, rings * sides + (i + 1) % sides);
  }
  s.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t f = 0; f < F.size(); ++f) s.F.row(static_cast<Eigen::Index>(f)) = F[f].transpose();
  return s;
}

}  // namespace sqs
