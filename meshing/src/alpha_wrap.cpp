// CGAL translation unit: 3D Alpha Wrapping.
#include "squeeze/meshing/alpha_wrap.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <array>
#include <cassert>
#include <vector>

#include "squeeze/common/error.h"

namespace squeeze::meshing {

SurfaceMesh alpha_wrap(const SurfaceMesh& input, const AlphaWrapOptions& options) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Point = K::Point_3;
  if (input.F.rows() == 0) throw InputError("alpha wrap: the input has no face");
  if (!(options.alpha > 0 && options.alpha < 1)) throw InputError("alpha wrap: alpha must be in (0, 1)");
  if (!(options.offset > 0 && options.offset < 1)) throw InputError("alpha wrap: offset must be in (0, 1)");
  const double diag = bounding_box_diagonal(input.V);
  if (!(diag > 0)) throw InputError("alpha wrap: the input has zero extent");
  std::vector<Point> points;
  points.reserve(static_cast<size_t>(input.V.rows()));
  for (Eigen::Index i = 0; i < input.V.rows(); ++i) points.emplace_back(input.V(i, 0), input.V(i, 1), input.V(i, 2));
  std::vector<std::array<size_t, 3>> faces;
  faces.reserve(static_cast<size_t>(input.F.rows()));
  for (Eigen::Index f = 0; f < input.F.rows(); ++f)
    faces.push_back({static_cast<size_t>(input.F(f, 0)), static_cast<size_t>(input.F(f, 1)),
                     static_cast<size_t>(input.F(f, 2))});
  CGAL::Surface_mesh<Point> wrap;
  CGAL::alpha_wrap_3(points, faces, options.alpha * diag, options.offset * diag, wrap);
  SurfaceMesh out;
  out.V.resize(static_cast<Eigen::Index>(wrap.number_of_vertices()), 3);
  out.F.resize(static_cast<Eigen::Index>(wrap.number_of_faces()), 3);
  std::vector<Eigen::Index> index(wrap.num_vertices(), -1);
  Eigen::Index n = 0;
  for (auto v : wrap.vertices()) {
    const Point& p = wrap.point(v);
    out.V.row(n) << p.x(), p.y(), p.z();
    index[static_cast<size_t>(v)] = n++;
  }
  Eigen::Index f = 0;
  for (auto face : wrap.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(wrap.halfedge(face), wrap)) {
      if (k < 3) out.F(f, k) = static_cast<int>(index[static_cast<size_t>(v)]);
      ++k;
    }
    assert(k == 3 && "alpha wrap: a face that is not a triangle");
    ++f;
  }
  return out;
}

}  // namespace squeeze::meshing
