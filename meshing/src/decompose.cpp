#include "squeeze/meshing/decompose.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <queue>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/surface_analysis.h"
#include "squeeze/meshing/winding_number.h"

namespace squeeze::meshing {
namespace {

using Vec3 = Eigen::Vector3d;

// ---- voxel grid --------------------------------------------------------------------------------

enum : unsigned char { kExterior = 0, kSurface = 1, kInterior = 2 };

struct Grid {
  Vec3 origin;  // corner of voxel (0,0,0)
  double h;     // voxel size
  int nx, ny, nz;
  std::vector<unsigned char> state;

  size_t size() const { return state.size(); }
  int index(int i, int j, int k) const { return i + nx * (j + ny * k); }
  void coords(int v, int& i, int& j, int& k) const {
    i = v % nx;
    j = (v / nx) % ny;
    k = v / (nx * ny);
  }
  Vec3 centre(int v) const {
    int i, j, k;
    coords(v, i, j, k);
    return origin + h * Vec3(i + 0.5, j + 0.5, k + 0.5);
  }
  int locate(const Vec3& p) const {
    const int i = std::clamp(static_cast<int>(std::floor((p(0) - origin(0)) / h)), 0, nx - 1);
    const int j = std::clamp(static_cast<int>(std::floor((p(1) - origin(1)) / h)), 0, ny - 1);
    const int k = std::clamp(static_cast<int>(std::floor((p(2) - origin(2)) / h)), 0, nz - 1);
    return index(i, j, k);
  }
  template <class Fn>  // calls fn(u) for each 6-neighbour u of v inside the grid
  void neighbours6(int v, Fn fn) const {
    int i, j, k;
    coords(v, i, j, k);
    if (i > 0) fn(v - 1);
    if (i + 1 < nx) fn(v + 1);
    if (j > 0) fn(v - nx);
    if (j + 1 < ny) fn(v + nx);
    if (k > 0) fn(v - nx * ny);
    if (k + 1 < nz) fn(v + nx * ny);
  }
  template <class Fn>
  void neighbours26(int v, Fn fn) const {
    int i, j, k;
    coords(v, i, j, k);
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          if (!di && !dj && !dk) continue;
          const int a = i + di, b = j + dj, c = k + dk;
          if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
          fn(index(a, b, c));
        }
  }
};

// Sample points on triangle f with spacing at most h/2 and call fn(point).
template <class Fn>
void sample_triangle(const Vec3& a, const Vec3& b, const Vec3& c, double h, Fn fn) {
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  const int n = std::clamp(static_cast<int>(std::ceil(longest / (0.5 * h))), 1, 4096);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n - i; ++j) {
      const double u = static_cast<double>(i) / n, v = static_cast<double>(j) / n;
      fn(Vec3(a + u * (b - a) + v * (c - a)));
    }
}

// Sample points on a triangle with spacing at most s, about area / s² + perimeter / s of them, and
// call fn(point): rows parallel to the longest edge, at most s apart across the triangle, each row
// sampled at most s apart (its ends on the two other edges). Unlike sample_triangle, whose
// parametric grid takes (longest / spacing)² points, a sliver costs what its area does: a strip
// 1.5 m long and 2.6 cm wide is about 500 points at s = 6 mm, not 30,000.
template <class Fn>
void sample_triangle_rows(const Vec3& a, const Vec3& b, const Vec3& c, double s, Fn fn) {
  const Vec3* v[3] = {&a, &b, &c};
  int base = 0;  // the longest edge is v[base] -> v[base + 1]
  double longest = -1.0;
  for (int i = 0; i < 3; ++i) {
    const double l = (*v[(i + 1) % 3] - *v[i]).norm();
    if (l > longest) longest = l, base = i;
  }
  const Vec3 &p0 = *v[base], &p1 = *v[(base + 1) % 3], &q = *v[(base + 2) % 3];
  const double height = longest > 0 ? (p1 - p0).cross(q - p0).norm() / longest : 0.0;
  const int rows = std::clamp(static_cast<int>(std::ceil(height / s)), 1, 1 << 20);
  for (int k = 0; k <= rows; ++k) {
    const double t = static_cast<double>(k) / rows;
    const Vec3 l = p0 + t * (q - p0), r = p1 + t * (q - p1);
    const int m = std::clamp(static_cast<int>(std::ceil((1.0 - t) * longest / s)), 1, 1 << 20);
    for (int i = 0; i <= m; ++i) fn(Vec3(l + (static_cast<double>(i) / m) * (r - l)));
  }
}

Grid build_grid(const SurfaceMesh& mesh, const FastWindingNumber& wn, int resolution, Progress* progress) {
  Grid g;
  const Vec3 lo = mesh.V.colwise().minCoeff().transpose(), hi = mesh.V.colwise().maxCoeff().transpose();
  const double longest = std::max((hi - lo).maxCoeff(), 1e-300);
  g.h = longest / resolution;
  // Thin objects (a spinal cord, a plate) need voxels finer than the longest side suggests: at
  // least about two across their thickness, estimated as 3 V / A (the radius of a sphere, 1.5 times
  // that of a long tube), down to a quarter of the nominal size.
  double area = 0.0, volume = 0.0;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    const Vec3 a = mesh.V.row(mesh.F(f, 0)).transpose(), b = mesh.V.row(mesh.F(f, 1)).transpose(),
               c = mesh.V.row(mesh.F(f, 2)).transpose();
    area += 0.5 * (b - a).cross(c - a).norm();
    volume += (a - lo).dot((b - lo).cross(c - lo)) / 6.0;
  }
  const double thickness = area > 0 ? 3.0 * std::abs(volume) / area : longest;
  if (thickness > 0) g.h = std::min(g.h, std::max(thickness / 1.5, longest / (4.0 * resolution)));
  // At most 8 × resolution³ voxels (2.1 M at 64): an input thin by that estimate but spread over
  // all three dimensions (a soup of 100 triangles across a cube: 3 V / A of an open surface is no
  // thickness) had 193³ = 7.2 M and took 25 s of cutting; flat or long thin inputs stay under it.
  {
    const Vec3 extent = hi - lo;
    const double budget = 8.0 * resolution * static_cast<double>(resolution) * resolution;
    const double coarsest = std::cbrt(extent(0) * extent(1) * extent(2) / budget);
    if (coarsest > g.h) g.h = std::min(coarsest, longest / resolution);
  }
  g.origin = lo - Vec3::Constant(1.5 * g.h);
  g.nx = static_cast<int>(std::ceil((hi(0) - lo(0)) / g.h)) + 3;
  g.ny = static_cast<int>(std::ceil((hi(1) - lo(1)) / g.h)) + 3;
  g.nz = static_cast<int>(std::ceil((hi(2) - lo(2)) / g.h)) + 3;
  g.state.assign(static_cast<size_t>(g.nx) * g.ny * g.nz, kExterior);

  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    sample_triangle(mesh.V.row(mesh.F(f, 0)).transpose(), mesh.V.row(mesh.F(f, 1)).transpose(),
                    mesh.V.row(mesh.F(f, 2)).transpose(), g.h,
                    [&](const Vec3& p) { g.state[g.locate(p)] = kSurface; });

  // Regions of non-surface voxels (6-connected); classify each by the winding number at a few of
  // its voxels, or voxel by voxel where those disagree (a hole lets inside and outside touch).
  if (progress) progress->stage("inside/outside (winding number)");
  std::vector<int> region(g.size(), -1);
  std::vector<int> members, stack;
  for (int seed = 0; seed < static_cast<int>(g.size()); ++seed) {
    if (g.state[seed] == kSurface || region[seed] >= 0) continue;
    members.clear();
    region[seed] = seed;
    stack.push_back(seed);
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      members.push_back(v);
      g.neighbours6(v, [&](int u) {
        if (g.state[u] != kSurface && region[u] < 0) {
          region[u] = seed;
          stack.push_back(u);
        }
      });
    }
    std::sort(members.begin(), members.end());
    const int samples = static_cast<int>(std::min<size_t>(16, members.size()));
    int in = 0, out = 0;
    for (int s = 0; s < samples; ++s) {
      const double w = wn(g.centre(members[members.size() * s / samples]).transpose());
      if (w > 0.7) ++in;
      else if (w < 0.3) ++out;
    }
    if (out == samples) continue;  // exterior already
    if (in == samples) {
      for (int v : members) g.state[v] = kInterior;
      continue;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, members.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t m = r.begin(); m != r.end(); ++m)
        if (wn(g.centre(members[m]).transpose()) > 0.5) g.state[members[m]] = kInterior;
    });
  }
  return g;
}

// ---- pieces ------------------------------------------------------------------------------------

struct Polygon {
  std::vector<Vec3> p;
  bool outer;  // lies on the boundary of the solid (counts for concavity)
};

struct Piece {
  std::vector<Polygon> polys;
  std::vector<int> voxels;  // occupied voxels whose centre lies in the cell, sorted
  int part = 0;
  int order = 0;            // creation order, for deterministic tie-breaks
  ConvexHull hull;
  double concavity = 0.0;
  double voxel_volume = 0.0;  // interior voxels + half the surface voxels, times h³
  double volume = 0.0;        // exact piece volume for closed input (see piece_volume), else voxel_volume
  std::vector<Eigen::Vector4d> planes;  // the cell: n·x <= d for each (n, d)
  Vec3 deepest = Vec3::Zero();
};

// Whether q is within eps of the plane n·x = d (n a unit normal).
bool on_plane(const Vec3& q, const Vec3& n, double d, double eps) { return std::abs(n.dot(q) - d) <= eps; }

// Whether every corner of `poly` is within eps of the plane n·x = d.
bool lies_in_plane(const Polygon& poly, const Vec3& n, double d, double eps) {
  return std::all_of(poly.p.begin(), poly.p.end(), [&](const Vec3& q) { return on_plane(q, n, d, eps); });
}

// Volume of a piece of a closed, outward-oriented surface clipped to a convex cell, by the
// divergence theorem: the clipped polygons' fan terms about an origin O, plus one term per cut
// plane c for its cap, (d_c - n_c·O) A_c / 3. The cap's area comes from its boundary traversed
// counter-clockwise about n_c: the clipped polygons' edges lying on plane c, backwards, and,
// where the cap meets the cap of another plane j inside the solid, segments of the line
// L_cj = c ∩ j, in direction n_c × n_j. Their total length on L_cj is measured along the line
// within the cell: the surface crosses L_cj only at polygon vertices lying on both planes, and
// each interval between those is in the solid or not (winding number at its midpoint).
// A_c n_c = -1/2 Σ_edges (a - O) × (b - O) + 1/2 Σ_j length_cj (p_cj - O) × u_cj, p_cj on L_cj.
double piece_volume(const std::vector<Polygon>& polys, const std::vector<Eigen::Vector4d>& planes,
                    const FastWindingNumber& wn, double eps) {
  if (polys.empty()) return 0.0;
  const Vec3 o = polys.front().p.front();
  const size_t m = planes.size();
  double six_v = 0.0;
  std::vector<Vec3> cap(m, Vec3::Zero());
  std::vector<std::vector<Vec3>> on_two(m * m);  // polygon vertices on planes c and j (c < j)
  for (const Polygon& poly : polys) {
    const size_t k = poly.p.size();
    for (size_t i = 1; i + 1 < k; ++i) six_v += (poly.p[0] - o).dot((poly.p[i] - o).cross(poly.p[i + 1] - o));
    for (size_t c = 0; c < m; ++c) {
      const Vec3 n = planes[c].head<3>();
      const double d = planes[c](3);
      for (size_t i = 0; i < k; ++i) {
        const Vec3& a = poly.p[i];
        const Vec3& b = poly.p[(i + 1) % k];
        if (on_plane(a, n, d, eps) && on_plane(b, n, d, eps)) cap[c] -= 0.5 * (a - o).cross(b - o);
      }
    }
    if (m < 2) continue;
    for (const Vec3& a : poly.p)
      for (size_t c = 0; c < m; ++c) {
        if (!on_plane(a, planes[c].head<3>(), planes[c](3), eps)) continue;
        for (size_t j = c + 1; j < m; ++j)
          if (on_plane(a, planes[j].head<3>(), planes[j](3), eps)) on_two[c * m + j].push_back(a);
      }
  }
  for (size_t c = 0; c < m; ++c)
    for (size_t j = c + 1; j < m; ++j) {
      const Vec3 nc = planes[c].head<3>(), nj = planes[j].head<3>();
      const Vec3 w = nc.cross(nj);
      if (w.norm() < 1e-9) continue;  // parallel planes do not meet
      const Vec3 u = w.normalized();
      Eigen::Matrix3d A;
      A << nc.transpose(), nj.transpose(), u.transpose();
      const Vec3 p = A.partialPivLu().solve(Vec3(planes[c](3), planes[j](3), u.dot(o)));
      // The line within the cell: t in [t0, t1] for p + t u.
      double t0 = -INFINITY, t1 = INFINITY;
      for (size_t l = 0; l < m; ++l) {
        if (l == c || l == j) continue;
        const double nu = planes[l].head<3>().dot(u), gap = planes[l](3) - planes[l].head<3>().dot(p);
        if (std::abs(nu) < 1e-12) {
          if (gap < -eps) t0 = INFINITY;  // the line is outside this half-space
        } else if (nu > 0) {
          t1 = std::min(t1, gap / nu);
        } else {
          t0 = std::max(t0, gap / nu);
        }
      }
      std::vector<double> t;
      for (const Vec3& a : on_two[c * m + j]) t.push_back(u.dot(a - p));
      if (!(t0 < t1)) continue;
      // (The solid is bounded: an unbounded interval is outside it.)
      t.push_back(t0);
      t.push_back(t1);
      std::sort(t.begin(), t.end());
      double length = 0.0;
      for (size_t i = 0; i + 1 < t.size(); ++i) {
        const double a = std::max(t[i], t0), b = std::min(t[i + 1], t1);
        if (!(b - a > eps) || !std::isfinite(a) || !std::isfinite(b)) continue;
        if (wn((p + 0.5 * (a + b) * u).transpose()) > 0.5) length += b - a;
      }
      cap[c] += 0.5 * length * (p - o).cross(u);  // along n_c × n_j on cap c
      cap[j] -= 0.5 * length * (p - o).cross(u);  // and the other way on cap j
    }
  double v = six_v / 6.0;
  for (size_t c = 0; c < m; ++c) {
    const Vec3 n = planes[c].head<3>();
    v += (planes[c](3) - n.dot(o)) * cap[c].dot(n) / 3.0;
  }
  return v;
}

// Keeps the part of `poly` with side * (n·x - d) <= 0 (Sutherland–Hodgman). Points on the plane
// are kept by both sides, and both sides compute edge intersections with the same arithmetic, so
// the two halves share them bit for bit.
void clip(const std::vector<Vec3>& in, const Vec3& n, double d, double side, std::vector<Vec3>& out) {
  out.clear();
  const size_t m = in.size();
  for (size_t i = 0; i < m; ++i) {
    const Vec3& a = in[i];
    const Vec3& b = in[(i + 1) % m];
    const double sa = n.dot(a) - d, sb = n.dot(b) - d;
    const bool ina = side * sa <= 0;
    if (ina) out.push_back(a);
    if ((sa < 0 && sb > 0) || (sa > 0 && sb < 0)) {
      // Canonical direction (from the negative end) so both sides get the same point.
      const Vec3& p = sa < 0 ? a : b;
      const Vec3& q = sa < 0 ? b : a;
      const double sp = sa < 0 ? sa : sb, sq = sa < 0 ? sb : sa;
      out.push_back(p + (sp / (sp - sq)) * (q - p));
    }
  }
}

void thicken_if_flat(Eigen::MatrixX3d& pts, ConvexHull& hull, double thickness) {
  if (hull.V.rows() > 0 && hull.volume > 0) return;
  // Flat (or collinear) point set: offset it both ways along its least principal direction.
  const Eigen::RowVector3d mean = pts.colwise().mean();
  const Eigen::MatrixX3d c = pts.rowwise() - mean;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(c.transpose() * c);
  Vec3 n = es.eigenvectors().col(0);
  Eigen::MatrixX3d thick(pts.rows() * 2 + 2, 3);
  thick << pts.rowwise() + 0.5 * thickness * n.transpose(), pts.rowwise() - 0.5 * thickness * n.transpose(),
      mean + thickness * es.eigenvectors().col(1).transpose(), mean - thickness * es.eigenvectors().col(2).transpose();
  pts = thick;
  hull = convex_hull(pts);
}

// Corners of the piece's cell (three cutting planes meeting, within all the others) that lie
// inside the solid. Where three cuts meet inside the solid, the piece has a corner that is on no
// input triangle: without it the hull of the clipped triangles would miss the piece's corner and
// the shells would leave a gap inside the solid.
std::vector<Vec3> cell_corners_inside(const std::vector<Eigen::Vector4d>& planes, const FastWindingNumber& wn,
                                      double plane_eps) {
  std::vector<Vec3> out;
  const size_t m = planes.size();
  for (size_t a = 0; a < m; ++a)
    for (size_t b = a + 1; b < m; ++b)
      for (size_t c = b + 1; c < m; ++c) {
        Eigen::Matrix3d A;
        A << planes[a].head<3>().transpose(), planes[b].head<3>().transpose(), planes[c].head<3>().transpose();
        if (std::abs(A.determinant()) < 1e-9) continue;  // (nearly) parallel planes: no corner
        const Vec3 x = A.partialPivLu().solve(Vec3(planes[a](3), planes[b](3), planes[c](3)));
        bool in_cell = true;
        for (const Eigen::Vector4d& q : planes) in_cell = in_cell && q.head<3>().dot(x) <= q(3) + plane_eps;
        if (in_cell && wn(x.transpose()) > 0.5) out.push_back(x);
      }
  return out;
}

// Sets the piece's hull, concavity and deepest point; returns the number of points it sampled on
// its large polygons (for the decomposition's debug line).
size_t evaluate_piece(Piece& piece, const FastWindingNumber& wn, double flat_thickness, double sample_spacing,
                      double plane_eps, bool samples_by_area) {
  // Polygon corners, each once (neighbouring polygons share them). Kinds: 0 inner surface (not
  // ∂S, does not count), 1 outer, 2 on a cap: a polygon lying in one of the cell's cutting planes
  // (a cut through a face, e.g. the floor of a notch) is part of the piece's cap, which is a facet
  // of conv(P), so its points are on the hull and count zero (measured against the bridges alone
  // they would look as deep as the piece is wide). Cap wins over outer, outer over inner.
  struct Corner { double x, y, z; char kind; char sample; };
  std::vector<Corner> corners;
  size_t samples = 0;
  for (const auto& poly : piece.polys) {
    const bool cap = std::any_of(piece.planes.begin(), piece.planes.end(), [&](const Eigen::Vector4d& c) {
      return lies_in_plane(poly, c.head<3>(), c(3), plane_eps);
    });
    const char kind = cap ? 2 : poly.outer ? 1 : 0;
    for (const Vec3& p : poly.p) corners.push_back({p(0), p(1), p(2), kind, 0});
    // Large polygons are sampled too (spacing about a voxel): a concave edge of a prism has its
    // end points on hull faces, the depth is along it.
    for (size_t i = 2; i < poly.p.size(); ++i) {
      const Vec3 &a = poly.p[0], &b = poly.p[i - 1], &c = poly.p[i];
      if (std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}) <= sample_spacing * sample_spacing)
        continue;
      auto add = [&](const Vec3& q) {
        corners.push_back({q(0), q(1), q(2), kind, 1});
        ++samples;
      };
      if (samples_by_area)
        sample_triangle_rows(a, b, c, sample_spacing, add);
      else
        sample_triangle(a, b, c, 2.0 * sample_spacing, add);
    }
  }
  std::sort(corners.begin(), corners.end(), [](const Corner& a, const Corner& b) {
    return a.x != b.x         ? a.x < b.x
           : a.y != b.y       ? a.y < b.y
           : a.z != b.z       ? a.z < b.z
           : a.kind != b.kind ? a.kind > b.kind
                              : a.sample < b.sample;
  });
  corners.erase(std::unique(corners.begin(), corners.end(),
                            [](const Corner& a, const Corner& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }),
                corners.end());
  const size_t n = corners.size();
  Eigen::MatrixX3d pts(static_cast<Eigen::Index>(n), 3);
  std::vector<char> outer(n);
  size_t n_vertices = 0;
  for (size_t r = 0; r < n; ++r) {
    outer[r] = corners[r].kind == 1;
    n_vertices += !corners[r].sample;
    pts.row(static_cast<Eigen::Index>(r)) << corners[r].x, corners[r].y, corners[r].z;
  }
  // The hull of the polygon vertices (samples lie on the polygons: they add nothing but
  // near-coplanar facets); the depth is measured at vertices and samples alike.
  // Plus the cell's corners inside the solid (on cutting planes, not on the surface: their depth
  // is not measured).
  const std::vector<Vec3> cell_corners = cell_corners_inside(piece.planes, wn, plane_eps);
  Eigen::MatrixX3d hull_pts(static_cast<Eigen::Index>(n_vertices + cell_corners.size()), 3);
  size_t k = 0;
  for (size_t r = 0; r < n; ++r)
    if (!corners[r].sample) hull_pts.row(static_cast<Eigen::Index>(k++)) = pts.row(static_cast<Eigen::Index>(r));
  for (const Vec3& x : cell_corners) hull_pts.row(static_cast<Eigen::Index>(k++)) = x.transpose();
  piece.hull = convex_hull(hull_pts);
  thicken_if_flat(hull_pts, piece.hull, flat_thickness);
  // Depth is measured below the hull's *bridges*: facets that lie on a cutting plane are caps of
  // the piece itself, not lids over a pocket. (Otherwise slicing a piece thin would make any
  // notch look shallow: every point is near a slab's two cut faces.)
  Eigen::MatrixX4d bridges(piece.hull.planes.rows(), 4);
  Eigen::Index nb = 0;
  for (Eigen::Index k = 0; k < piece.hull.planes.rows(); ++k) {
    const Eigen::Vector4d h = piece.hull.planes.row(k).transpose();
    bool cap = false;
    for (const Eigen::Vector4d& c : piece.planes)
      cap = cap || ((h.head<3>() - c.head<3>()).norm() < 1e-9 && std::abs(h(3) - c(3)) <= 1e-9 * (1.0 + std::abs(c(3))));
    if (!cap) bridges.row(nb++) = h.transpose();
  }
  bridges.conservativeResize(nb, 4);
  // Deepest outer point: parallel max with ties to the lowest index (deterministic).
  struct Best { double depth = -1; size_t at = 0; };
  const size_t chunks = std::max<size_t>(1, std::min<size_t>(64, n / 2048));
  std::vector<Best> best(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
    const size_t b = n * c / chunks, e = n * (c + 1) / chunks;
    const Eigen::MatrixX4d& pl = bridges;
    for (size_t i = b; i < e; ++i) {
      if (!outer[i]) continue;
      // depth = min over planes of (d - n·p); stop as soon as it cannot beat the best so far.
      const Eigen::Index r = static_cast<Eigen::Index>(i);
      double d = pl.rows() ? INFINITY : 0.0;
      for (Eigen::Index k = 0; k < pl.rows() && d >= best[c].depth; ++k)
        d = std::min(d, pl(k, 3) - (pl(k, 0) * pts(r, 0) + pl(k, 1) * pts(r, 1) + pl(k, 2) * pts(r, 2)));
      d = std::max(d, 0.0);
      if (d > best[c].depth) best[c] = {d, i};
    }
  });
  Best all;
  for (const Best& b : best)
    if (b.depth > all.depth) all = b;
  piece.concavity = std::max(0.0, all.depth);
  if (all.depth >= 0) piece.deepest = pts.row(static_cast<Eigen::Index>(all.at)).transpose();
  return samples;
}

// The corners of the convex hull of points lying (up to a jitter) on the plane with unit normal
// n, in order (Andrew's monotone chain on in-plane coordinates; ties by input order, so the
// result is a pure function of the input).
std::vector<Vec3> section_hull(const std::vector<Vec3>& pts, const Vec3& n) {
  if (pts.size() < 4) return pts;
  int least;
  n.cwiseAbs().minCoeff(&least);
  const Vec3 u = n.cross(Vec3::Unit(least)).normalized(), v = n.cross(u);
  std::vector<std::array<double, 2>> uv(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) uv[i] = {u.dot(pts[i]), v.dot(pts[i])};
  std::vector<size_t> order(pts.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return uv[a] != uv[b] ? uv[a] < uv[b] : a < b; });
  auto turn = [&](size_t o, size_t a, size_t b) {
    return (uv[a][0] - uv[o][0]) * (uv[b][1] - uv[o][1]) - (uv[a][1] - uv[o][1]) * (uv[b][0] - uv[o][0]);
  };
  std::vector<size_t> chain(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < order.size(); ++i) {  // lower hull
    while (k >= 2 && turn(chain[k - 2], chain[k - 1], order[i]) <= 0) --k;
    chain[k++] = order[i];
  }
  for (size_t i = order.size() - 1, lower = k + 1; i-- > 0;) {  // upper hull
    while (k >= lower && turn(chain[k - 2], chain[k - 1], order[i]) <= 0) --k;
    chain[k++] = order[i];
  }
  std::vector<Vec3> out;
  for (size_t i = 0; i + 1 < k; ++i) out.push_back(pts[chain[i]]);  // the last repeats the first
  return out;
}

struct Candidate {
  Vec3 n;
  double d;
  bool notch = false;  // passes through the piece's deepest point
};

}  // namespace

Decomposition decompose(const SurfaceMesh& mesh, const DecompositionOptions& opt, Progress* progress) {
  if (!(opt.concavity > 0)) throw InputError("--concavity must be > 0 (a fraction of the bounding-box diagonal)");
  if (opt.max_hulls < 1) throw InputError("--max-hulls must be at least 1");
  if (opt.voxel_resolution < 8 || opt.voxel_resolution > 1024)
    throw InputError("--voxel-resolution must be between 8 and 1024");
  if (opt.cut_samples < 1) throw InputError("cut_samples must be at least 1");
  if (!(opt.notch_preference >= 0 && opt.notch_preference <= 1))
    throw InputError("notch_preference must be between 0 and 1");

  const double diag = bounding_box_diagonal(mesh.V);
  Decomposition result;
  result.threshold = opt.concavity * diag;
  const double thickness = opt.flat_thickness * diag;

  if (progress) progress->stage("voxelizing");
  const FastWindingNumber wn(mesh.V, mesh.F);
  Grid g = build_grid(mesh, wn, opt.voxel_resolution, progress);
  size_t interior = 0, surface = 0;
  spdlog::debug("voxel grid {}x{}x{}, h {:.17g}", g.nx, g.ny, g.nz, g.h);
  for (unsigned char s : g.state) interior += s == kInterior, surface += s == kSurface;
  spdlog::debug("voxels: {} interior, {} surface", interior, surface);
  result.solid_volume = (static_cast<double>(interior) + 0.5 * static_cast<double>(surface)) * g.h * g.h * g.h;

  // Connected parts: 26-connected components of occupied voxels.
  std::vector<int> part(g.size(), -1);
  int parts = 0;
  {
    std::vector<int> stack;
    for (int seed = 0; seed < static_cast<int>(g.size()); ++seed) {
      if (g.state[seed] == kExterior || part[seed] >= 0) continue;
      part[seed] = parts;
      stack.push_back(seed);
      while (!stack.empty()) {
        const int v = stack.back();
        stack.pop_back();
        g.neighbours26(v, [&](int u) {
          if (g.state[u] != kExterior && part[u] < 0) {
            part[u] = parts;
            stack.push_back(u);
          }
        });
      }
      ++parts;
    }
  }
  result.parts = parts;

  // Initial pieces, one per part; a triangle is outer if a voxel it touches neighbours the exterior.
  std::vector<Piece> pieces(static_cast<size_t>(parts));
  for (int p = 0; p < parts; ++p) pieces[p].part = p, pieces[p].order = p;
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    const Vec3 a = mesh.V.row(mesh.F(f, 0)).transpose(), b = mesh.V.row(mesh.F(f, 1)).transpose(),
               c = mesh.V.row(mesh.F(f, 2)).transpose();
    bool outer = false;
    sample_triangle(a, b, c, g.h, [&](const Vec3& p) {
      if (!outer) g.neighbours26(g.locate(p), [&](int u) { outer = outer || g.state[u] == kExterior; });
    });
    pieces[part[g.locate(a)]].polys.push_back({{a, b, c}, outer});
  }
  for (int v = 0; v < static_cast<int>(g.size()); ++v)
    if (part[v] >= 0) pieces[part[v]].voxels.push_back(v);

  if (progress) progress->stage("decomposing", opt.max_hulls);
  const bool closed = is_closed(mesh.F);
  const double plane_eps = 1e-9 * diag;  // a point this close to a cutting plane lies on it
  auto measure_voxels = [&](Piece& q) {
    double n = 0;
    for (int v : q.voxels) n += g.state[v] == kInterior ? 1.0 : 0.5;
    q.voxel_volume = n * g.h * g.h * g.h;
    q.volume = q.voxel_volume;
    if (closed) {
      const double exact = piece_volume(q.polys, q.planes, wn, plane_eps);
      if (exact > 0) q.volume = exact;
    }
  };
  size_t evaluations = 0, samples = 0;  // (for the debug line at the end)
  for (auto& piece : pieces) {
    samples += evaluate_piece(piece, wn, thickness, g.h, plane_eps, opt.samples_by_area);
    measure_voxels(piece);
    ++evaluations;
  }

  std::vector<char> alive(pieces.size(), 1);
  auto count_alive = [&] { return static_cast<int>(std::count(alive.begin(), alive.end(), 1)); };
  std::vector<char> splittable(pieces.size(), 1);
  int next_order = parts;

  while (count_alive() < opt.max_hulls) {
    // The worst splittable piece (ties: older first). A piece needs splitting when its concavity
    // is above the threshold, or when its hull is far larger than the piece (thin curved parts,
    // whose concavity can stay below a threshold measured against the whole diagonal).
    auto badness = [&](const Piece& q) {
      const double volume = q.volume > 0 ? q.volume : INFINITY;
      return std::max(q.concavity / result.threshold, q.hull.volume / (opt.max_hull_volume_ratio * volume));
    };
    int pick = -1;
    double pick_bad = 1.0;
    for (size_t i = 0; i < pieces.size(); ++i) {
      if (!alive[i] || !splittable[i]) continue;
      const double b = badness(pieces[i]);
      if (b <= 1.0) continue;
      if (pick < 0 || b > pick_bad || (b == pick_bad && pieces[i].order < pieces[pick].order)) {
        pick = static_cast<int>(i);
        pick_bad = b;
      }
    }
    if (pick < 0) break;
    Piece& P = pieces[pick];
    if (P.voxels.size() < 16) {
      splittable[pick] = 0;
      continue;
    }

    // Principal axes of the piece's voxels.
    Vec3 mean = Vec3::Zero();
    for (int v : P.voxels) mean += g.centre(v);
    mean /= static_cast<double>(P.voxels.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int v : P.voxels) {
      const Vec3 d = g.centre(v) - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    std::vector<Candidate> cand;
    for (int a = 2; a >= 0; --a) {
      Vec3 n = es.eigenvectors().col(a).normalized();
      int big;
      n.cwiseAbs().maxCoeff(&big);
      if (n(big) < 0) n = -n;
      double lo = INFINITY, hi = -INFINITY;
      for (int v : P.voxels) {
        const double s = n.dot(g.centre(v));
        lo = std::min(lo, s);
        hi = std::max(hi, s);
      }
      if (hi - lo < 2 * g.h) continue;
      for (int i = 1; i <= opt.cut_samples; ++i)
        cand.push_back({n, lo + (hi - lo) * i / (opt.cut_samples + 1), false});
      const double s = n.dot(P.deepest);
      if (s > lo + g.h && s < hi - g.h) cand.push_back({n, s, true});
    }
    if (cand.empty()) {
      splittable[pick] = 0;
      continue;
    }

    // Score: summed hull volumes of the two sides. A side's hull is spanned by the piece's own
    // hull vertices on that side plus its cross-section, which is all that can be extreme after
    // the cut: the side's voxels nearest the plane, projected onto it (only the corners of their
    // 2-D hull are kept). "Nearest": within max(|n|₁ / 2, |n|∞) voxels of the plane, which holds
    // the voxel nearest the plane of every lattice row along the normal's largest component, so
    // each side has its cross-section whatever the plane's offset from the lattice. (With a slab
    // of half a voxel, a plane normal to an axis had one voxel layer on one side only: the other
    // side's hull lost its cross-section, and a useless cut, e.g. slicing a slab of the U along
    // its thickness, looked like it removed volume.) Projected, the two sides' hulls reach the
    // plane: a cut that removes nothing scores the piece's own hull volume.
    // Voxel centres, jittered by a millionth of a voxel (a fixed hash of the voxel index): lattice
    // points are maximally degenerate (coplanar, cospherical) and would send every hull to exact
    // arithmetic; the scores do not notice the jitter.
    std::vector<Vec3> centres(P.voxels.size());
    for (size_t i = 0; i < P.voxels.size(); ++i) {
      uint64_t x = static_cast<uint64_t>(P.voxels[i]) * 0x9E3779B97F4A7C15ULL;
      Vec3 j;
      for (int k = 0; k < 3; ++k) {
        x ^= x >> 29;
        x *= 0xBF58476D1CE4E5B9ULL;
        x ^= x >> 32;
        j(k) = static_cast<double>(x & 0xFFFFF) / static_cast<double>(0xFFFFF) - 0.5;
      }
      centres[i] = g.centre(P.voxels[i]) + 2e-6 * g.h * j;
    }
    Eigen::MatrixX3d piece_hull_pts;
    double uncut_cost = 0.0;
    {
      // Only voxels with a 6-neighbour outside the piece can be hull corners (an inner voxel is
      // the midpoint of two neighbours, and the jitter is far too small to change that): the hull
      // of ~n^(2/3) points, not n. P.voxels is sorted: membership by binary search.
      std::vector<size_t> ends;
      for (size_t i = 0; i < P.voxels.size(); ++i) {
        bool boundary = false;
        int neighbours = 0;
        g.neighbours6(P.voxels[i], [&](int u) {
          ++neighbours;
          boundary = boundary || !std::binary_search(P.voxels.begin(), P.voxels.end(), u);
        });
        if (boundary || neighbours < 6) ends.push_back(i);
      }
      Eigen::MatrixX3d all(static_cast<Eigen::Index>(ends.size()), 3);
      for (size_t i = 0; i < ends.size(); ++i) all.row(static_cast<Eigen::Index>(i)) = centres[ends[i]].transpose();
      const ConvexHull voxel_hull = convex_hull(all);
      uncut_cost = voxel_hull.volume;
      piece_hull_pts = extreme_points(voxel_hull);
      if (piece_hull_pts.rows() == 0) piece_hull_pts = all;
    }
    std::vector<double> cost(cand.size(), INFINITY);
    auto eval_candidate = [&](size_t c) {
      const Candidate& k = cand[c];
      const double slab = g.h * std::max(0.5 * k.n.cwiseAbs().sum(), k.n.cwiseAbs().maxCoeff());
      std::vector<Vec3> side_pts[2], section[2];
      size_t counts[2] = {0, 0};
      for (size_t i = 0; i < centres.size(); ++i) {
        const int side = k.n.dot(centres[i]) < k.d ? 0 : 1;
        ++counts[side];
        const double s = k.n.dot(g.centre(P.voxels[i])) - k.d;  // unjittered: lands on the plane
        if (std::abs(s) <= slab) section[side].push_back(centres[i] - s * k.n);
      }
      if (counts[0] < 4 || counts[1] < 4) return;
      for (int side = 0; side < 2; ++side) side_pts[side] = section_hull(section[side], k.n);
      for (Eigen::Index i = 0; i < piece_hull_pts.rows(); ++i) {
        const Vec3 q = piece_hull_pts.row(i).transpose();
        side_pts[k.n.dot(q) < k.d ? 0 : 1].push_back(q);
      }
      double total = 0;
      for (int s = 0; s < 2; ++s) {
        Eigen::MatrixX3d m(static_cast<Eigen::Index>(side_pts[s].size()), 3);
        for (size_t i = 0; i < side_pts[s].size(); ++i) m.row(static_cast<Eigen::Index>(i)) = side_pts[s][i].transpose();
        total += convex_hull(m).volume;
      }
      cost[c] = total;
    };
    // Each candidate writes only its own score, and every hull is a pure function of its points
    // (the Delaunay-based hull reseeds CGAL's thread-local generator), so the choice below does
    // not depend on the thread count. (The quickhull used before corrupted memory and made scores
    // differ from run to run.)
    tbb::parallel_for(size_t(0), cand.size(), [&](size_t c) { eval_candidate(c); });
    size_t best = 0;
    for (size_t c = 1; c < cand.size(); ++c)
      if (cost[c] < cost[best]) best = c;
    // The cut through the notch along one of its faces (Lien & Amato cut through the notch;
    // Chazelle's cuts of a polyhedron are planes through its reflex edges) wins when it removes at
    // least (1 - notch_preference) of the best candidate's hull volume: a candidate through the
    // deepest point on whose plane a polygon of the piece lies. The summed volume cannot tell the
    // cuts of a U's base apart (every plane between the arms removes the same volume), nor, at the
    // voxels' resolution, the cut along the notch's wall from one beside it that leaves a sliver of
    // the base under an arm, a notch that takes further cuts. On curved input no polygon lies on a
    // candidate plane, and the summed volume decides alone.
    const double best_gain = uncut_cost - cost[best];
    size_t notch = cand.size();
    for (size_t c = 0; c < cand.size(); ++c) {
      if (!cand[c].notch || !std::isfinite(cost[c]) ||
          uncut_cost - cost[c] < (1.0 - opt.notch_preference) * best_gain ||
          (notch < cand.size() && cost[c] >= cost[notch]))
        continue;
      const bool along_face = std::any_of(P.polys.begin(), P.polys.end(), [&](const Polygon& poly) {
        return lies_in_plane(poly, cand[c].n, cand[c].d, plane_eps);
      });
      if (along_face) notch = c;
    }
    if (notch < cand.size()) best = notch;
    if (!std::isfinite(cost[best])) {
      splittable[pick] = 0;
      continue;
    }

    // Apply the cut.
    const Candidate k = cand[best];
    spdlog::debug("split piece {} (concavity {:.17g}, {} voxels): candidate {}/{} cost {:.17g}, plane {:.17g} {:.17g} "
                  "{:.17g} {:.17g}",
                  pieces[pick].order, pieces[pick].concavity, pieces[pick].voxels.size(), best, cand.size(), cost[best],
                  k.n(0), k.n(1), k.n(2), k.d);
    Piece children[2];
    std::vector<Vec3> clipped;
    for (int s = 0; s < 2; ++s) {
      children[s].part = P.part;
      children[s].order = next_order++;
      children[s].planes = P.planes;
      children[s].planes.push_back(s == 0 ? Eigen::Vector4d(k.n(0), k.n(1), k.n(2), k.d)
                                          : Eigen::Vector4d(-k.n(0), -k.n(1), -k.n(2), -k.d));
      for (const Polygon& poly : P.polys) {
        // A polygon lying in the plane (a cut through a face, as through the floor of a notch)
        // belongs to the side its solid is on, opposite its outward normal; clipping would keep
        // it on both, where the other side would get a stray face (and a hull over the notch).
        if (lies_in_plane(poly, k.n, k.d, plane_eps)) {
          Vec3 area = Vec3::Zero();  // Newell's normal, times twice the area
          for (size_t i = 0; i < poly.p.size(); ++i) area += poly.p[i].cross(poly.p[(i + 1) % poly.p.size()]);
          if ((area.dot(k.n) >= 0) == (s == 0)) children[s].polys.push_back(poly);
          continue;
        }
        clip(poly.p, k.n, k.d, s == 0 ? 1.0 : -1.0, clipped);
        if (clipped.size() >= 3) children[s].polys.push_back({clipped, poly.outer});
      }
    }
    if (children[0].polys.empty() || children[1].polys.empty()) {
      // The plane misses the piece's surface (it only cuts voxels): no progress, keep the piece.
      splittable[pick] = 0;
      continue;
    }
    for (int v : P.voxels) children[k.n.dot(g.centre(v)) < k.d ? 0 : 1].voxels.push_back(v);
    alive[pick] = 0;
    for (int s = 0; s < 2; ++s) {
      if (children[s].polys.empty()) {  // no surface on this side: its voxels join the other side
        children[1 - s].voxels.insert(children[1 - s].voxels.end(), children[s].voxels.begin(),
                                      children[s].voxels.end());
        std::sort(children[1 - s].voxels.begin(), children[1 - s].voxels.end());
        children[s].voxels.clear();
      }
    }
    for (int s = 0; s < 2; ++s) {
      if (children[s].polys.empty()) continue;
      samples += evaluate_piece(children[s], wn, thickness, g.h, plane_eps, opt.samples_by_area);
      measure_voxels(children[s]);
      ++evaluations;
      pieces.push_back(std::move(children[s]));
      alive.push_back(1);
      splittable.push_back(1);
    }
    pieces[pick].polys = {};
    pieces[pick].voxels = {};
    if (progress) progress->update(count_alive());
  }

  spdlog::debug("decomposition: {} pieces evaluated, {} points sampled on their large polygons", evaluations, samples);
  const bool at_budget = count_alive() >= opt.max_hulls;
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (!alive[i]) continue;
    if (at_budget && splittable[i] &&
        (pieces[i].concavity > result.threshold ||
         pieces[i].hull.volume > opt.max_hull_volume_ratio * pieces[i].volume))
      result.hit_max_hulls = true;
    result.max_concavity = std::max(result.max_concavity, pieces[i].concavity);
    result.shells.push_back({std::move(pieces[i].hull), pieces[i].concavity, pieces[i].part});
  }
  if (progress) progress->finish();
  return result;
}

int hold_points(Decomposition& d, const Eigen::MatrixX3d& P, double tolerance) {
  // Each point's shell: -1 where some shell holds it, else the one it lies least outside of.
  std::vector<int> to(static_cast<size_t>(P.rows()), -1);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, P.rows(), 1024), [&](const tbb::blocked_range<Eigen::Index>& range) {
    for (Eigen::Index i = range.begin(); i != range.end(); ++i) {
      double best = INFINITY;
      int arg = -1;
      for (size_t s = 0; s < d.shells.size() && best > tolerance; ++s) {
        if (!(d.shells[s].hull.volume > 0)) continue;
        const double v = d.shells[s].hull.signed_value(P.row(i));
        if (v < best) best = v, arg = static_cast<int>(s);
      }
      if (best > tolerance) to[static_cast<size_t>(i)] = arg;
    }
  });
  std::vector<std::vector<Eigen::Index>> taken(d.shells.size());
  int count = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (to[static_cast<size_t>(i)] >= 0) taken[static_cast<size_t>(to[static_cast<size_t>(i)])].push_back(i), ++count;
  for (size_t s = 0; s < d.shells.size(); ++s) {
    if (taken[s].empty()) continue;
    ConvexHull& hull = d.shells[s].hull;
    Eigen::MatrixX3d Q(hull.V.rows() + static_cast<Eigen::Index>(taken[s].size()), 3);
    Q.topRows(hull.V.rows()) = hull.V;
    for (size_t k = 0; k < taken[s].size(); ++k) Q.row(hull.V.rows() + static_cast<Eigen::Index>(k)) = P.row(taken[s][k]);
    ConvexHull grown = convex_hull(Q);
    if (grown.volume > 0) hull = std::move(grown);
  }
  return count;
}

}  // namespace squeeze::meshing
