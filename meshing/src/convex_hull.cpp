// CGAL translation unit: convex hulls and the self-intersection test.
#include "squeeze/meshing/convex_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/convex_hull_3.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <vector>

#include "squeeze/meshing/surface_analysis.h"

namespace squeeze {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
}  // namespace

double ConvexHull::signed_value(const Eigen::RowVector3d& p) const {
  double v = -INFINITY;
  for (Eigen::Index i = 0; i < planes.rows(); ++i)
    v = std::max(v, planes(i, 0) * p(0) + planes(i, 1) * p(1) + planes(i, 2) * p(2) - planes(i, 3));
  return v;
}

double ConvexHull::depth(const Eigen::RowVector3d& p) const { return std::max(0.0, -signed_value(p)); }

ConvexHull convex_hull(const Eigen::MatrixX3d& P) {
  ConvexHull hull;
  if (P.rows() < 4) return hull;
  std::vector<Point> pts;
  pts.reserve(static_cast<size_t>(P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i) pts.emplace_back(P(i, 0), P(i, 1), P(i, 2));
  Mesh sm;
  // Dimension check: all points coplanar?
  const Point& a = pts[0];
  size_t ib = 1;
  while (ib < pts.size() && pts[ib] == a) ++ib;
  if (ib == pts.size()) return hull;
  size_t ic = ib + 1;
  while (ic < pts.size() && CGAL::collinear(a, pts[ib], pts[ic])) ++ic;
  if (ic == pts.size()) return hull;
  size_t id = ic + 1;
  while (id < pts.size() && CGAL::coplanar(a, pts[ib], pts[ic], pts[id])) ++id;
  if (id == pts.size()) return hull;

  CGAL::convex_hull_3(pts.begin(), pts.end(), sm);
  std::map<Mesh::Vertex_index, int> index;
  hull.V.resize(static_cast<Eigen::Index>(sm.number_of_vertices()), 3);
  int n = 0;
  for (auto v : sm.vertices()) {
    const Point& q = sm.point(v);
    hull.V.row(n) << q.x(), q.y(), q.z();
    index[v] = n++;
  }
  hull.F.resize(static_cast<Eigen::Index>(sm.number_of_faces()), 3);
  int f = 0;
  std::vector<Eigen::Vector4d> planes;
  Eigen::RowVector3d c = hull.V.colwise().mean();
  for (auto face : sm.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(face), sm)) hull.F(f, k++) = index[v];
    const Eigen::Vector3d p0 = hull.V.row(hull.F(f, 0)).transpose(), p1 = hull.V.row(hull.F(f, 1)).transpose(),
                          p2 = hull.V.row(hull.F(f, 2)).transpose();
    Eigen::Vector3d nrm = (p1 - p0).cross(p2 - p0);
    hull.volume += (p0 - c.transpose()).dot((p1 - c.transpose()).cross(p2 - c.transpose())) / 6.0;
    const double len = nrm.norm();
    if (len > 0) {
      nrm /= len;
      planes.emplace_back(nrm(0), nrm(1), nrm(2), nrm.dot(p0));
    }
    ++f;
  }
  // Merge (nearly) coplanar facets: fewer planes make signed_value() cheaper.
  std::sort(planes.begin(), planes.end(), [](const Eigen::Vector4d& x, const Eigen::Vector4d& y) {
    return std::lexicographical_compare(x.data(), x.data() + 4, y.data(), y.data() + 4);
  });
  std::vector<Eigen::Vector4d> merged;
  for (const auto& p : planes) {
    bool dup = false;
    for (auto it = merged.rbegin(); it != merged.rend() && it - merged.rbegin() < 8; ++it)
      if ((it->head<3>() - p.head<3>()).norm() < 1e-9 && std::abs((*it)(3) - p(3)) < 1e-12 * (1 + std::abs(p(3)))) {
        dup = true;
        break;
      }
    if (!dup) merged.push_back(p);
  }
  hull.planes.resize(static_cast<Eigen::Index>(merged.size()), 4);
  for (size_t i = 0; i < merged.size(); ++i) hull.planes.row(static_cast<Eigen::Index>(i)) = merged[i].transpose();
  return hull;
}

bool does_self_intersect(const SurfaceMesh& mesh) {
  using Box = CGAL::Box_intersection_d::Box_with_handle_d<double, 3, int, CGAL::Box_intersection_d::ID_EXPLICIT>;
  std::vector<K::Triangle_3> tris;
  std::vector<Box> boxes;
  tris.reserve(static_cast<size_t>(mesh.F.rows()));
  boxes.reserve(static_cast<size_t>(mesh.F.rows()));
  for (int f = 0; f < mesh.F.rows(); ++f) {
    Point p[3];
    for (int k = 0; k < 3; ++k) p[k] = Point(mesh.V(mesh.F(f, k), 0), mesh.V(mesh.F(f, k), 1), mesh.V(mesh.F(f, k), 2));
    tris.emplace_back(p[0], p[1], p[2]);
    boxes.emplace_back(tris.back().bbox(), f);
  }
  bool found = false;
  struct Stop {};
  try {
    CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& x, const Box& y) {
      const int f = x.handle(), g = y.handle();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (mesh.F(f, i) == mesh.F(g, j)) return;
      if (tris[f].is_degenerate() || tris[g].is_degenerate()) return;
      if (CGAL::do_intersect(tris[f], tris[g])) {
        found = true;
        throw Stop{};
      }
    });
  } catch (const Stop&) {
  }
  return found;
}

}  // namespace squeeze
