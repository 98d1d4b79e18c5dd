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

namespace squeeze {
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

Grid build_grid(const SurfaceMesh& mesh, int resolution, Progress* progress) {
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
  const FastWindingNumber wn(mesh.V, mesh.F);
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

// Volume of a piece of a closed, outward-oriented surface clipped to a convex cell, by the
// divergence theorem: the clipped polygons' fan terms about an origin O, plus one term per cut
// plane c for its cap, (d_c - n_c·O) A_c / 3. The cap's area comes from its boundary, which is the
// clipped polygons' edges lying on plane c traversed backwards: A_c n_c = -1/2 Σ (a × b).
double piece_volume(const std::vector<Polygon>& polys, const std::vector<Eigen::Vector4d>& planes, double eps) {
  if (polys.empty()) return 0.0;
  const Vec3 o = polys.front().p.front();
  double six_v = 0.0;
  std::vector<Vec3> cap(planes.size(), Vec3::Zero());
  for (const Polygon& poly : polys) {
    const size_t m = poly.p.size();
    for (size_t i = 1; i + 1 < m; ++i) six_v += (poly.p[0] - o).dot((poly.p[i] - o).cross(poly.p[i + 1] - o));
    for (size_t c = 0; c < planes.size(); ++c) {
      const Vec3 n = planes[c].head<3>();
      const double d = planes[c](3);
      for (size_t i = 0; i < m; ++i) {
        const Vec3& a = poly.p[i];
        const Vec3& b = poly.p[(i + 1) % m];
        if (std::abs(n.dot(a) - d) <= eps && std::abs(n.dot(b) - d) <= eps) cap[c] -= 0.5 * (a - o).cross(b - o);
      }
    }
  }
  double v = six_v / 6.0;
  for (size_t c = 0; c < planes.size(); ++c) {
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

void evaluate_piece(Piece& piece, double flat_thickness, double sample_spacing) {
  // Polygon corners, each once (neighbouring polygons share them); outer wins over inner.
  struct Corner { double x, y, z; char outer; char sample; };
  std::vector<Corner> corners;
  for (const auto& poly : piece.polys) {
    for (const Vec3& p : poly.p) corners.push_back({p(0), p(1), p(2), static_cast<char>(poly.outer), 0});
    // Large polygons are sampled too (spacing about a voxel): a concave edge of a prism has its
    // end points on hull faces, the depth is along it.
    for (size_t i = 2; i < poly.p.size(); ++i) {
      const Vec3 &a = poly.p[0], &b = poly.p[i - 1], &c = poly.p[i];
      if (std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}) <= sample_spacing * sample_spacing)
        continue;
      sample_triangle(a, b, c, 2.0 * sample_spacing, [&](const Vec3& q) {
        corners.push_back({q(0), q(1), q(2), static_cast<char>(poly.outer), 1});
      });
    }
  }
  std::sort(corners.begin(), corners.end(), [](const Corner& a, const Corner& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z != b.z ? a.z < b.z : a.outer != b.outer ? a.outer > b.outer : a.sample < b.sample;
  });
  corners.erase(std::unique(corners.begin(), corners.end(),
                            [](const Corner& a, const Corner& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }),
                corners.end());
  const size_t n = corners.size();
  Eigen::MatrixX3d pts(static_cast<Eigen::Index>(n), 3);
  std::vector<char> outer(n);
  size_t n_vertices = 0;
  for (size_t r = 0; r < n; ++r) {
    outer[r] = corners[r].outer;
    n_vertices += !corners[r].sample;
    pts.row(static_cast<Eigen::Index>(r)) << corners[r].x, corners[r].y, corners[r].z;
  }
  // The hull of the polygon vertices (samples lie on the polygons: they add nothing but
  // near-coplanar facets); the depth is measured at vertices and samples alike.
  Eigen::MatrixX3d hull_pts(static_cast<Eigen::Index>(n_vertices), 3);
  for (size_t r = 0, k = 0; r < n; ++r)
    if (!corners[r].sample) hull_pts.row(static_cast<Eigen::Index>(k++)) = pts.row(static_cast<Eigen::Index>(r));
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

  const double diag = bounding_box_diagonal(mesh.V);
  Decomposition result;
  result.threshold = opt.concavity * diag;
  const double thickness = opt.flat_thickness * diag;

  if (progress) progress->stage("voxelizing");
  Grid g = build_grid(mesh, opt.voxel_resolution, progress);
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
  auto measure_voxels = [&](Piece& q) {
    double n = 0;
    for (int v : q.voxels) n += g.state[v] == kInterior ? 1.0 : 0.5;
    q.voxel_volume = n * g.h * g.h * g.h;
    q.volume = q.voxel_volume;
    if (closed) {
      const double exact = piece_volume(q.polys, q.planes, 1e-9 * diag);
      if (exact > 0) q.volume = exact;
    }
  };
  for (auto& piece : pieces) evaluate_piece(piece, thickness, g.h), measure_voxels(piece);

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
    // hull vertices on that side plus the voxels in a one-voxel slab along the plane (its cross
    // section), which is all that can be extreme after the cut.
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
      piece_hull_pts = extreme_points(convex_hull(all));
      if (piece_hull_pts.rows() == 0) piece_hull_pts = all;
    }
    std::vector<double> cost(cand.size(), INFINITY);
    auto eval_candidate = [&](size_t c) {
      const Candidate& k = cand[c];
      const double slab = 0.5 * g.h * k.n.cwiseAbs().sum();
      std::vector<Vec3> side_pts[2];
      size_t counts[2] = {0, 0};
      for (const Vec3& q : centres) {
        const double s = k.n.dot(q) - k.d;
        ++counts[s < 0 ? 0 : 1];
        if (std::abs(s) <= slab) side_pts[s < 0 ? 0 : 1].push_back(q);
      }
      if (counts[0] < 4 || counts[1] < 4) return;
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
    if (!std::isfinite(cost[best])) {
      splittable[pick] = 0;
      continue;
    }

    // Apply the cut.
    const Candidate k = cand[best];
    spdlog::debug("split piece {} (concavity {:.17g}, {} voxels): candidate {}/{} cost {:.17g}", pieces[pick].order,
                  pieces[pick].concavity, pieces[pick].voxels.size(), best, cand.size(), cost[best]);
    Piece children[2];
    std::vector<Vec3> clipped;
    for (int s = 0; s < 2; ++s) {
      children[s].part = P.part;
      children[s].order = next_order++;
      children[s].planes = P.planes;
      children[s].planes.push_back(s == 0 ? Eigen::Vector4d(k.n(0), k.n(1), k.n(2), k.d)
                                          : Eigen::Vector4d(-k.n(0), -k.n(1), -k.n(2), -k.d));
      for (const Polygon& poly : P.polys) {
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
      evaluate_piece(children[s], thickness, g.h);
      measure_voxels(children[s]);
      pieces.push_back(std::move(children[s]));
      alive.push_back(1);
      splittable.push_back(1);
    }
    pieces[pick].polys = {};
    pieces[pick].voxels = {};
    if (progress) progress->update(count_alive());
  }

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

}  // namespace squeeze
