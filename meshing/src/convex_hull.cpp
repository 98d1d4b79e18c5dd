// CGAL translation unit: convex hulls and the self-intersection test.
#include "squeeze/meshing/convex_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/box_intersection_d.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <vector>

#include "squeeze/meshing/surface_analysis.h"

namespace squeeze::meshing {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Delaunay = CGAL::Delaunay_triangulation_3<K>;
}  // namespace

double ConvexHull::signed_value(const Eigen::RowVector3d& p) const {
  double v = -INFINITY;
  for (Eigen::Index i = 0; i < planes.rows(); ++i)
    v = std::max(v, planes(i, 0) * p(0) + planes(i, 1) * p(1) + planes(i, 2) * p(2) - planes(i, 3));
  return v;
}

double ConvexHull::depth(const Eigen::RowVector3d& p) const { return std::max(0.0, -signed_value(p)); }

Eigen::MatrixX3d extreme_points(const ConvexHull& hull) {
  std::vector<std::vector<Eigen::Vector3d>> normals(static_cast<size_t>(hull.V.rows()));
  for (Eigen::Index f = 0; f < hull.F.rows(); ++f) {
    const Eigen::Vector3d p0 = hull.V.row(hull.F(f, 0)).transpose();
    Eigen::Vector3d n = (hull.V.row(hull.F(f, 1)).transpose() - p0).cross(hull.V.row(hull.F(f, 2)).transpose() - p0);
    if (n.norm() == 0) continue;
    n.normalize();
    for (int k = 0; k < 3; ++k) {
      auto& list = normals[static_cast<size_t>(hull.F(f, k))];
      if (list.size() < 3 && std::none_of(list.begin(), list.end(), [&](const Eigen::Vector3d& m) { return (m - n).norm() < 1e-9; }))
        list.push_back(n);
    }
  }
  std::vector<Eigen::Index> keep;
  for (Eigen::Index v = 0; v < hull.V.rows(); ++v)
    if (normals[static_cast<size_t>(v)].size() >= 3) keep.push_back(v);
  Eigen::MatrixX3d out(static_cast<Eigen::Index>(keep.size()), 3);
  for (size_t i = 0; i < keep.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = hull.V.row(keep[i]);
  return out;
}

namespace {

// Akl–Toussaint filter: the points extreme along 26 directions span a polytope inside the hull;
// points strictly inside it (by more than a rounding margin) are no hull points and are dropped.
// Returns the indices of the points kept (all of them when the filter does not apply).
std::vector<Eigen::Index> hull_candidates(const Eigen::MatrixX3d& P) {
  std::vector<Eigen::Index> keep;
  const Eigen::Index n = P.rows();
  if (n < 2000) {
    for (Eigen::Index i = 0; i < n; ++i) keep.push_back(i);
    return keep;
  }
  std::vector<Eigen::Vector3d> dirs;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z)
        if (x || y || z) dirs.emplace_back(x, y, z);
  std::vector<Eigen::Index> arg(dirs.size(), 0);
  std::vector<double> best(dirs.size(), -INFINITY);
  for (Eigen::Index i = 0; i < n; ++i)
    for (size_t d = 0; d < dirs.size(); ++d) {
      const double s = dirs[d].dot(P.row(i).transpose());
      if (s > best[d]) best[d] = s, arg[d] = i;  // ties: the first (deterministic)
    }
  std::sort(arg.begin(), arg.end());
  arg.erase(std::unique(arg.begin(), arg.end()), arg.end());
  Eigen::MatrixX3d E(static_cast<Eigen::Index>(arg.size()), 3);
  for (size_t k = 0; k < arg.size(); ++k) E.row(static_cast<Eigen::Index>(k)) = P.row(arg[k]);
  const ConvexHull inner = convex_hull(E);  // fewer than 2000 points: no recursion
  if (inner.planes.rows() == 0 || !(inner.volume > 0)) {
    for (Eigen::Index i = 0; i < n; ++i) keep.push_back(i);
    return keep;
  }
  const double scale = P.cwiseAbs().maxCoeff() + (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
  const double margin = 1e-9 * scale;
  for (Eigen::Index i = 0; i < n; ++i) {
    bool strictly_inside = true;
    for (Eigen::Index k = 0; k < inner.planes.rows() && strictly_inside; ++k)
      strictly_inside = inner.planes(k, 0) * P(i, 0) + inner.planes(k, 1) * P(i, 1) + inner.planes(k, 2) * P(i, 2) -
                            inner.planes(k, 3) < -margin;
    if (!strictly_inside) keep.push_back(i);
  }
  return keep;
}

}  // namespace

ConvexHull convex_hull(const Eigen::MatrixX3d& P) {
  ConvexHull hull;
  if (P.rows() < 4) return hull;
  std::vector<Point> pts;
  const std::vector<Eigen::Index> candidates = hull_candidates(P);
  pts.reserve(candidates.size());
  for (Eigen::Index i : candidates) pts.emplace_back(P(i, 0), P(i, 1), P(i, 2));
  if (pts.size() < 4) return hull;
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

  // The boundary of a Delaunay triangulation (CGAL, exact predicates) is the convex hull.
  // CGAL 5.5's convex_hull_3 (quickhull) erased the same list node twice on our inputs (valgrind:
  // use after free in ch_quickhull_face_graph, as in CGAL issues #6543 and #8761), which made the
  // hulls depend on the heap's state; the triangulation is slower but robust.
  CGAL::get_default_random() = CGAL::Random(0);  // spatial sort shuffles: keep it reproducible
  Delaunay dt(pts.begin(), pts.end());
  if (dt.dimension() < 3) return hull;
  std::map<Delaunay::Vertex_handle, int> index;
  std::vector<Eigen::RowVector3d> verts;
  std::vector<Eigen::Vector3i> faces;
  // Deterministic order: infinite cells in the triangulation's order, their finite vertices in
  // the order met.
  std::vector<Delaunay::Cell_handle> cells;
  dt.incident_cells(dt.infinite_vertex(), std::back_inserter(cells));
  std::sort(cells.begin(), cells.end(), [&](Delaunay::Cell_handle x, Delaunay::Cell_handle y) {
    // order by the smallest point of the finite facet, lexicographically (independent of memory)
    auto key = [&](Delaunay::Cell_handle c) {
      const int inf = c->index(dt.infinite_vertex());
      std::array<Point, 3> q;
      for (int k = 0, j = 0; k < 4; ++k)
        if (k != inf) q[j++] = c->vertex(k)->point();
      std::sort(q.begin(), q.end());
      return q;
    };
    return key(x) < key(y);
  });
  for (auto c : cells) {
    const int inf = c->index(dt.infinite_vertex());
    // The finite facet, seen from the infinite vertex (outside): CGAL's vertex_triple_index gives
    // the positively oriented order, i.e. an outward normal.
    const int idx[3] = {Delaunay::vertex_triple_index(inf, 0), Delaunay::vertex_triple_index(inf, 1),
                        Delaunay::vertex_triple_index(inf, 2)};
    Eigen::Vector3i f;
    for (int k = 0; k < 3; ++k) {
      auto v = c->vertex(idx[k]);
      auto [it, fresh] = index.emplace(v, static_cast<int>(verts.size()));
      if (fresh) verts.emplace_back(v->point().x(), v->point().y(), v->point().z());
      f(k) = it->second;
    }
    faces.push_back(f);
  }
  hull.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) hull.V.row(static_cast<Eigen::Index>(i)) = verts[i];
  hull.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) hull.F.row(static_cast<Eigen::Index>(i)) = faces[i].transpose();
  std::vector<Eigen::Vector4d> planes;
  const Eigen::RowVector3d c = hull.V.row(0);
  for (Eigen::Index f = 0; f < hull.F.rows(); ++f) {
    const Eigen::Vector3d p0 = hull.V.row(hull.F(f, 0)).transpose(), p1 = hull.V.row(hull.F(f, 1)).transpose(),
                          p2 = hull.V.row(hull.F(f, 2)).transpose();
    Eigen::Vector3d nrm = (p1 - p0).cross(p2 - p0);
    hull.volume += (p0 - c.transpose()).dot((p1 - c.transpose()).cross(p2 - c.transpose())) / 6.0;
    const double len = nrm.norm();
    // A (nearly) zero-area facet, e.g. over three (nearly) collinear points (clip points along
    // the line where two cutting planes meet), is no facet of the polytope, and its normal is
    // rounding noise: as a plane it would cut the hull. The other facets' planes bound the hull.
    const double longest2 = std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
    if (len > 1e-10 * longest2) {
      nrm /= len;
      planes.emplace_back(nrm(0), nrm(1), nrm(2), nrm.dot(p0));
    }
  }
  // Safety net: the orientation above is CGAL's convention; a negative volume would mean all
  // facets came out inward.
  if (hull.volume < 0) {
    hull.volume = -hull.volume;
    for (Eigen::Index f = 0; f < hull.F.rows(); ++f) std::swap(hull.F(f, 1), hull.F(f, 2));
    for (auto& p : planes) p = -p;
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

}  // namespace squeeze::meshing
