// CGAL translation unit: the envelope's edge collapses (Surface_mesh_simplification), and the
// isotropic remeshing of open sheets (sheet.h; Polygon_mesh_processing), on the same Surface_mesh.
#include "squeeze/meshing/envelope.h"
#include "squeeze/meshing/remesh.h"
#include "squeeze/meshing/sheet.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/Euler_operations.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Edge_length_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Edge_length_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <memory>
#include <cmath>
#include <string>
#include <vector>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/point_triangle_distance.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/triangle_intersection.h"
#include "squeeze/meshing/triangle_bvh.h"

namespace squeeze::meshing {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using VD = Mesh::Vertex_index;
using FD = Mesh::Face_index;
using HD = Mesh::Halfedge_index;
namespace SMS = CGAL::Surface_mesh_simplification;
using Vec3 = Eigen::Vector3d;

Vec3 vec(const Point& p) { return Vec3(p.x(), p.y(), p.z()); }

// What the filter and the visitor share.
struct State {
  const Mesh* mesh = nullptr;
  const TriangleBvh* reference = nullptr;  // the surface simplified, as it was (gaps, caps)
  const TriangleBvh* target = nullptr;     // the soup the bounds are measured against, when not
                                           // the reference (simplify_envelope with a target)
  double out = 0, in = 0;          // bounds (units)
  double cos_fold = 0, cos_turn = 0;
  double min_angle = 0;            // radians
  double max_edge = INFINITY;      // no new edge longer (units)
  bool no_crossings = false;       // EnvelopeOptions::no_local_crossings
  std::vector<FD> around;          // faces around the link, outside the region (scratch)
  std::vector<Vec3> samples;       // points of the reference surface
  std::vector<std::vector<int>> assigned;  // samples answerable to each face (by face index)
  std::vector<FD> sample_face;     // ... and the face each sample is answerable to
  std::vector<double> sample_bound; // per sample: min(in, out, a third of the local gap): it passes
                                   // within this of its own face
  std::vector<std::array<double, 3>> sample_limits;  // per sample: its distance from the new
                                   // surface where it lies outside it, inside it, and either way
  std::vector<double> face_gap;    // per reference face: a third of the smallest gap at its corners
  std::vector<int> pending;        // samples of the region of the collapse just accepted
  std::vector<FD> region;          // its faces
  std::vector<Vec3> later;         // the filter's points checked last (scratch)
  int collapses = 0;
  Progress* progress = nullptr;
  size_t initial_faces = 0;
};

// The faces around v (not the null face).
void faces_around(const Mesh& m, VD v, std::vector<FD>& out) {
  for (HD h : CGAL::halfedges_around_target(m.halfedge(v), m)) {
    const FD f = m.face(h);
    if (f != Mesh::null_face() && std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
  }
}

// Whether a point at signed position `side` (> 0: outside the surface it is measured against) and
// distance d keeps the bounds: outside by at most `outside`, inside by at most `inside`, and either
// at most `cap` (where the surface is thin, or nearly touches itself).
bool within(double d, double side, double outside, double inside, double cap) {
  return d <= std::min(cap, side > 0 ? outside : inside);
}

// Smallest angle of the triangle (radians).
double min_angle(const Vec3* q) {
  double m = M_PI;
  for (int k = 0; k < 3; ++k) {
    const Vec3 u = q[(k + 1) % 3] - q[k], v = q[(k + 2) % 3] - q[k];
    const double lu = u.norm(), lv = v.norm();
    if (!(lu > 0 && lv > 0)) return 0;
    m = std::min(m, std::acos(std::clamp(u.dot(v) / (lu * lv), -1.0, 1.0)));
  }
  return m;
}

// A face a collapse would make: its corners (the new point's handle is the null vertex).
struct Tri {
  Vec3 a, b, c, n;
  FD f;
  Vec3 centre;    // of a ball holding the triangle
  double radius;
  std::array<VD, 3> v;
};

// Whether a new face crosses a face around a vertex of the collapse's link (not one of the
// region's, which the collapse removes or replaces) or another new face.
template <typename Profile>
bool crosses_near(const Mesh& m, const Profile& profile, const std::vector<Tri>& tris, const std::vector<FD>& region,
                  std::vector<FD>& around) {
  around.clear();
  for (VD w : profile.link()) faces_around(m, w, around);
  around.erase(std::remove_if(around.begin(), around.end(),
                              [&](FD f) { return std::find(region.begin(), region.end(), f) != region.end(); }),
               around.end());
  auto box = [](const Vec3& a, const Vec3& b, const Vec3& c) {
    return std::array<Vec3, 2>{a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)};
  };
  auto overlap = [](const std::array<Vec3, 2>& x, const std::array<Vec3, 2>& y) {
    return (x[0].array() <= y[1].array()).all() && (y[0].array() <= x[1].array()).all();
  };
  // (Before the exact test: the corners of one triangle that it does not share, all on one side of
  // the other's plane by over a billionth of its size, cannot reach it.)
  auto apart = [](const Vec3& n, const Vec3& o, double size, const Vec3* x, const std::array<VD, 3>& xv,
                  const std::array<VD, 3>& shared_with) {
    const double eps = 1e-9 * size;
    int above = 0, below = 0, count = 0;
    for (int k = 0; k < 3; ++k) {
      if (std::find(shared_with.begin(), shared_with.end(), xv[static_cast<size_t>(k)]) != shared_with.end()) continue;
      const double d = n.dot(x[k] - o);
      above += d > eps, below += d < -eps, ++count;
    }
    return above == count || below == count;
  };
  // (Corner ids: the vertices' indices; the new point's, the null vertex's, is in every new face.)
  auto ids = [](const std::array<VD, 3>& v) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(v[0].idx()), static_cast<std::int64_t>(v[1].idx()),
                                       static_cast<std::int64_t>(v[2].idx())};
  };
  std::vector<std::array<Vec3, 2>> tbox;
  for (const Tri& t : tris) tbox.push_back(box(t.a, t.b, t.c));
  auto cross = [&](size_t i, const std::array<Vec3, 3>& x, const Vec3& xn, double xsize, const std::array<VD, 3>& w) {
    const Tri& t = tris[i];
    const Vec3 tc[3] = {t.a, t.b, t.c};
    if (apart(t.n, t.a, t.radius, x.data(), w, t.v) || apart(xn, x[0], xsize, tc, t.v, w)) return false;
    return triangles_cross({t.a, t.b, t.c}, ids(t.v), x, ids(w));
  };
  for (FD g : around) {
    std::array<Vec3, 3> x;
    std::array<VD, 3> w;
    size_t k = 0;
    for (VD u : CGAL::vertices_around_face(m.halfedge(g), m)) w[k] = u, x[k++] = vec(m.point(u));
    const Vec3 n = (x[1] - x[0]).cross(x[2] - x[0]);
    if (!(n.norm() > 0)) continue;  // (no area: no crossing to speak of)
    const auto gbox = box(x[0], x[1], x[2]);
    const double xsize = (gbox[1] - gbox[0]).norm();
    for (size_t i = 0; i < tris.size(); ++i)
      if (overlap(tbox[i], gbox) && cross(i, x, n.normalized(), xsize, w)) return true;
  }
  for (size_t i = 0; i < tris.size(); ++i)
    for (size_t j = i + 1; j < tris.size(); ++j)
      if (overlap(tbox[i], tbox[j]) && cross(i, {tris[j].a, tris[j].b, tris[j].c}, tris[j].n, tris[j].radius, tris[j].v))
        return true;
  return false;
}

struct Filter {
  State* s;

  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile,
                                                       boost::optional<typename Profile::Point> op) const {
    if (!op) return op;
    const Mesh& m = *s->mesh;
    const Vec3 p = vec(*op);
    const VD v0 = profile.v0(), v1 = profile.v1();
    std::vector<FD> region;
    faces_around(m, v0, region);
    faces_around(m, v1, region);
    // The new faces: the region's faces that do not hold both v0 and v1, with p for v0 or v1.
    std::vector<Tri> tris;
    for (FD f : region) {
      Vec3 q[3], old[3];
      std::array<VD, 3> vd;
      int k = 0, hits = 0;
      for (VD v : CGAL::vertices_around_face(m.halfedge(f), m)) {
        old[k] = vec(m.point(v));
        const bool moved = v == v0 || v == v1;
        q[k] = moved ? (++hits, p) : old[k];
        vd[static_cast<size_t>(k)] = moved ? Mesh::null_vertex() : v;
        ++k;
      }
      if (hits == 2) continue;  // removed by the collapse
      const Vec3 n_old = (old[1] - old[0]).cross(old[2] - old[0]);
      const Vec3 n = (q[1] - q[0]).cross(q[2] - q[0]);
      const double ln = n.norm(), lo = n_old.norm();
      if (!(ln > 0)) return boost::none;
      if (lo > 0 && n.dot(n_old) < s->cos_turn * ln * lo) return boost::none;
      // No new sliver triangle (unless the old one was worse): the tetrahedralization needs
      // splits around each.
      const double angle = min_angle(q);
      if (angle < s->min_angle && angle < min_angle(old)) return boost::none;
      const Vec3 centre = (q[0] + q[1] + q[2]) / 3.0;
      const double radius = std::max({(q[0] - centre).norm(), (q[1] - centre).norm(), (q[2] - centre).norm()});
      tris.push_back({q[0], q[1], q[2], n / ln, f, centre, radius, vd});
    }
    if (tris.empty()) return boost::none;
    // Folds: new faces sharing an edge, and each new face with its neighbours outside the region.
    for (size_t i = 0; i < tris.size(); ++i) {
      const Tri& t = tris[i];
      // Neighbours across each edge.
      for (HD h : CGAL::halfedges_around_face(m.halfedge(t.f), m)) {
        const FD g = m.face(m.opposite(h));
        if (g == Mesh::null_face()) continue;
        Vec3 gn;
        auto it = std::find_if(tris.begin(), tris.end(), [&](const Tri& x) { return x.f == g; });
        if (it != tris.end()) {
          gn = it->n;
        } else if (std::find(region.begin(), region.end(), g) != region.end()) {
          continue;  // one of the removed faces
        } else {
          Vec3 q[3];
          int k = 0;
          for (VD v : CGAL::vertices_around_face(m.halfedge(g), m)) q[k++] = vec(m.point(v));
          gn = (q[1] - q[0]).cross(q[2] - q[0]);
          if (!(gn.norm() > 0)) continue;
          gn.normalize();
        }
        if (t.n.dot(gn) < -s->cos_fold) return boost::none;
      }
      // New faces that will share an edge at p (across a removed face, the faces on its two
      // other sides meet).
      for (size_t j = i + 1; j < tris.size(); ++j) {
        const Tri& u = tris[j];
        int common = 0;
        for (const Vec3* a : {&t.a, &t.b, &t.c})
          for (const Vec3* b : {&u.a, &u.b, &u.c}) common += *a == *b;
        if (common >= 2 && t.n.dot(u.n) < -s->cos_fold) return boost::none;
      }
    }
    // The new surface against the reference: the new vertex, points along the new edges, the
    // centroids of the new faces.
    auto check_point = [&](const Vec3& x) {
      int f;
      Vec3 q;
      if (s->target) {  // within `out` of the target (either side), within the gap of the reference
        if (!s->target->any_within(x, s->out)) return false;
        // (The nearest face of the reference looked for within twice the bounds first, where it
        // usually is, the point being near the target and the reference too: the same face.)
        double d = s->reference->nearest(x, &f, &q, 2.0 * (s->out + s->in));
        if (f < 0) d = s->reference->nearest(x, &f, &q);
        return f < 0 || d <= s->face_gap[static_cast<size_t>(f)];
      }
      const double d = s->reference->nearest(x, &f, &q, s->out * 1.0001 + 1e-300);
      if (!(d <= s->out)) return false;
      return within(d, (x - q).dot(s->reference->normal(f)), s->out, s->in, s->face_gap[static_cast<size_t>(f)]);
    };
    if (!check_point(p)) return boost::none;
    // The reference's points answerable to the region, against the new faces.
    s->region = region;
    s->pending.clear();
    for (FD f : region) {
      const auto& list = s->assigned[static_cast<size_t>(f.idx())];
      s->pending.insert(s->pending.end(), list.begin(), list.end());
    }
    // A sample passes as soon as some new face is within the smaller bound (its own face first,
    // which usually is); else its nearest new face decides, by side.
    for (int i : s->pending) {
      const Vec3& x = s->samples[static_cast<size_t>(i)];
      const double sure = s->sample_bound[static_cast<size_t>(i)];
      const FD own = s->sample_face[static_cast<size_t>(i)];
      bool pass = false;
      for (const Tri& t : tris)
        if (t.f == own) pass = (x - closest_point_on_triangle(x, t.a, t.b, t.c)).norm() <= sure;
      if (pass) continue;
      double best = INFINITY, side = 0;
      for (const Tri& t : tris) {
        if ((x - t.centre).norm() - t.radius >= best) continue;
        const Vec3 q = closest_point_on_triangle(x, t.a, t.b, t.c);
        const double d = (x - q).norm();
        if (d < best) best = d, side = (x - q).dot(t.n);
        if (best <= sure) break;
      }
      const auto& lim = s->sample_limits[static_cast<size_t>(i)];
      if (!within(best, side, lim[0], lim[1], lim[2])) return boost::none;
    }
    // Points along the new edges and in the new faces, as far apart as twice the inner bound (up
    // to three per edge); where the new faces are small next to the inner bound, the reference's
    // own points (above) already pin them.
    for (VD w : profile.link())
      if ((vec(m.point(w)) - p).norm() > s->max_edge) return boost::none;
    for (VD w : profile.link()) {
      const Vec3 q = vec(m.point(w));
      const double len = (q - p).norm();
      if (len <= s->in) continue;
      const int k = std::min(3, static_cast<int>(std::ceil(len / (2.0 * s->in))));
      for (int j = 1; j <= k; ++j)
        if (!check_point(p + (static_cast<double>(j) / (k + 1)) * (q - p))) return boost::none;
    }
    std::vector<Vec3>& later = s->later;
    later.clear();
    for (const Tri& t : tris)
      if (t.radius > s->in) later.push_back(t.centre);
    // With a target, nothing else holds the new faces near it from outside (the surface's own
    // samples keep only the gap caps): points of each larger face, about twice the inner bound
    // apart (at most 8 along an edge).
    if (s->target)
      for (const Tri& t : tris) {
        if (t.radius <= s->in) continue;
        const int n = std::min(8, static_cast<int>(std::ceil(2.0 * t.radius / (2.0 * s->in))));
        for (int i = 1; i < n; ++i)
          for (int j = 1; i + j < n; ++j)
            later.push_back(t.a + (static_cast<double>(i) / n) * (t.b - t.a) + (static_cast<double>(j) / n) * (t.c - t.a));
      }
    // (Each point on its own, the collapse kept where all pass: many of them, two BVH queries each
    // with a target, are checked in parallel, the answer the same.)
    if (later.size() < 48) {
      for (const Vec3& x : later)
        if (!check_point(x)) return boost::none;
    } else {
      // (Isolated: a thread waiting here takes no other task, another part's meshing, and so no
      // thread-local state, CGAL's random generator, changes under it.)
      std::atomic<bool> fails{false};
      tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, later.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
          for (size_t i = range.begin(); i != range.end() && !fails.load(std::memory_order_relaxed); ++i)
            if (!check_point(later[i])) fails = true;
        });
      });
      if (fails) return boost::none;
    }
    // (Last: only the collapses every bound allows.)
    if (s->no_crossings && crosses_near(m, profile, tris, region, s->around)) return boost::none;
    return op;
  }
};

// Lindstrom and Turk's placement, snapped to the edge's nearer end where it lies within a
// thousandth of the edge's length of it. Where the optimum is not unique (a cap's centre collapsed
// into its rim, a vertex of a flat face), their linear solve lands next to an end, off it by
// rounding (2.6e-7 m on a 12 mm edge of a 10-sided cylinder): the flat faces then lie in no common
// plane, the tetrahedralization cannot treat them as one flat patch, and its boundary recovery
// split the leg of a spider model 300 times without recovering it (4.2° left). The filter checks
// the snapped point like any other.
struct SnappedPlacement {
  SMS::LindstromTurk_placement<Mesh> lt;
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile) const {
    // An open sheet's outline (simplify_sheet) keeps its vertices where they are: a collapse onto
    // an outline vertex keeps its point, along the outline onto one end, across (two outline
    // vertices joined through the sheet) none.
    const Mesh& m = profile.surface_mesh();
    const bool b0 = static_cast<bool>(CGAL::is_border(profile.v0(), m)), b1 = static_cast<bool>(CGAL::is_border(profile.v1(), m));
    if (b0 && b1 && !(m.is_border(profile.v0_v1()) || m.is_border(profile.v1_v0()))) return boost::none;
    if (b0 != b1) return b0 ? profile.p0() : profile.p1();
    const boost::optional<typename Profile::Point> op = lt(profile);
    if (!op) return op;
    if (b0 && b1) {
      const Vec3 p = vec(*op);
      return (p - vec(profile.p0())).norm() <= (p - vec(profile.p1())).norm() ? profile.p0() : profile.p1();
    }
    const Vec3 p = vec(*op), a = vec(profile.p0()), b = vec(profile.p1());
    const double tolerance = 1e-3 * (b - a).norm();
    const double da = (p - a).norm(), db = (p - b).norm();
    if (da <= tolerance && da <= db) return profile.p0();
    if (db <= tolerance) return profile.p1();
    return op;
  }
};

struct Visitor : SMS::Edge_collapse_visitor_base<Mesh> {
  State* s;
  explicit Visitor(State* state) : s(state) {}

  void OnCollapsed(const SMS::Edge_profile<Mesh>&, VD v) {
    const Mesh& m = *s->mesh;
    std::vector<FD> ring;
    faces_around(m, v, ring);
    // The faces that were around v0 and v1 now all have v, or were removed: clear them all and
    // give each pending sample to its nearest face around v.
    for (FD f : s->region) s->assigned[static_cast<size_t>(f.idx())].clear();
    std::vector<std::array<Vec3, 3>> tri(ring.size());
    for (size_t r = 0; r < ring.size(); ++r) {
      int k = 0;
      for (VD w : CGAL::vertices_around_face(m.halfedge(ring[r]), m)) tri[r][static_cast<size_t>(k++)] = vec(m.point(w));
      s->assigned[static_cast<size_t>(ring[r].idx())].clear();
    }
    for (int i : s->pending) {
      const Vec3& x = s->samples[static_cast<size_t>(i)];
      double best = INFINITY;
      size_t arg = 0;
      for (size_t r = 0; r < ring.size(); ++r) {
        const double d = point_triangle_distance(x, tri[r][0], tri[r][1], tri[r][2]);
        if (d < best) best = d, arg = r;
      }
      if (!ring.empty()) {
        s->assigned[static_cast<size_t>(ring[arg].idx())].push_back(i);
        s->sample_face[static_cast<size_t>(i)] = ring[arg];
      }
    }
    s->pending.clear();
    ++s->collapses;
    if (s->progress && (s->collapses & 1023) == 0) s->progress->update(static_cast<double>(s->collapses));
  }
};

struct Stop {
  size_t edges;  // stop when at most this many edges remain
  template <typename F, typename Profile>
  bool operator()(const F&, const Profile&, std::size_t, std::size_t current_edges) const {
    return current_edges <= edges;
  }
};

// `surface` as a CGAL Surface_mesh (same vertex order); InputError "`not_manifold` (face f)" where a
// face cannot be added (a non-manifold edge or vertex, or inconsistent orientation).
Mesh to_cgal(const SurfaceMesh& surface, const std::string& not_manifold) {
  Mesh m;
  std::vector<VD> vd;
  vd.reserve(static_cast<size_t>(surface.V.rows()));
  for (Eigen::Index i = 0; i < surface.V.rows(); ++i)
    vd.push_back(m.add_vertex(Point(surface.V(i, 0), surface.V(i, 1), surface.V(i, 2))));
  for (Eigen::Index f = 0; f < surface.F.rows(); ++f)
    if (m.add_face(vd[surface.F(f, 0)], vd[surface.F(f, 1)], vd[surface.F(f, 2)]) == Mesh::null_face())
      throw InputError(not_manifold + " (face " + std::to_string(f) + ")");
  return m;
}

// The Surface_mesh m (garbage collected first) as V, F.
SurfaceMesh from_cgal(Mesh& m) {
  m.collect_garbage();
  SurfaceMesh out;
  out.V.resize(static_cast<Eigen::Index>(m.number_of_vertices()), 3);
  for (VD v : m.vertices()) out.V.row(static_cast<Eigen::Index>(v.idx())) = vec(m.point(v)).transpose();
  out.F.resize(static_cast<Eigen::Index>(m.number_of_faces()), 3);
  Eigen::Index r = 0;
  for (FD f : m.faces()) {
    int k = 0;
    for (VD v : CGAL::vertices_around_face(m.halfedge(f), m)) out.F(r, k++) = static_cast<int>(v.idx());
    ++r;
  }
  return out;
}

}  // namespace

namespace {

// simplify_envelope with or without a target (nullptr: the surface is its own).
// open: `surface` may have borders (an open sheet, with a target): both bounds hold on either side.
SurfaceMesh simplify(const SurfaceMesh& surface, const SurfaceMesh* target_surface, const EnvelopeOptions& opt,
                     EnvelopeStats* stats, Progress* progress, bool open = false) {
  const std::string name = open ? "simplify_sheet" : "simplify_envelope";
  Mesh m = to_cgal(surface, name + ": the surface is not a 2-manifold");
  if (!open)
    for (HD h : m.halfedges())
      if (m.is_border(h)) throw InputError("simplify_envelope: the surface is not closed");

  const TriangleBvh reference(surface.V, surface.F);
  std::unique_ptr<TriangleBvh> target;
  if (target_surface) target = std::make_unique<TriangleBvh>(target_surface->V, target_surface->F);
  State s;
  s.mesh = &m;
  s.reference = &reference;
  s.target = target.get();
  s.out = opt.max_outside;
  s.in = opt.max_inside;
  s.cos_fold = std::cos(opt.min_fold_angle * M_PI / 180.0);
  s.cos_turn = std::cos(opt.max_normal_turn * M_PI / 180.0);
  s.min_angle = opt.min_triangle_angle * M_PI / 180.0;
  if (opt.max_edge > 0) s.max_edge = opt.max_edge;
  s.no_crossings = opt.no_local_crossings;
  s.progress = progress;
  s.assigned.resize(m.number_of_faces());
  // Local gaps: from each vertex along its normal, inwards (the thickness) and outwards (to another
  // part of the surface), up to three times the sum of the bounds. Within a third of the gap each
  // side of a thin part stays apart from the other.
  const double reach = 3.0 * (opt.max_inside + opt.max_outside);
  std::vector<double> gap(static_cast<size_t>(surface.V.rows()), INFINITY);
  {
    Eigen::MatrixX3d face_normal, normal;
    area_weighted_normals(surface.V, surface.F, face_normal, normal);
    tbb::parallel_for(size_t(0), gap.size(), [&](size_t v) {
      const Vec3 nv = normal.row(static_cast<Eigen::Index>(v)).transpose();
      const double len = nv.norm();
      if (!(len > 0) || !(reach > 0)) return;
      const Vec3 n = nv / len, x = surface.V.row(static_cast<Eigen::Index>(v)).transpose();
      for (double dir : {-1.0, 1.0}) {
        double t;
        if (reference.first_crossing(x, x + dir * reach * n, 1e-3, &t)) gap[v] = std::min(gap[v], t * reach);
      }
    });
  }
  s.face_gap.resize(static_cast<size_t>(surface.F.rows()));
  for (Eigen::Index f = 0; f < surface.F.rows(); ++f)
    s.face_gap[static_cast<size_t>(f)] =
        std::min({gap[static_cast<size_t>(surface.F(f, 0))], gap[static_cast<size_t>(surface.F(f, 1))],
                  gap[static_cast<size_t>(surface.F(f, 2))]}) / 3.0;
  // Samples: each passes within `sure` of its own face; else its nearest new face decides, by
  // side: limits {outside, inside, either way}. The surface's own (every vertex, to one face
  // around it, and points of faces larger than the inner bound, spaced by about it): outside the
  // new surface by at most the inner bound, inside it by at most the outer, either way by at most
  // its cap (a third of the local gap). With a target they keep only the cap (thin parts stay
  // apart), and the target's points (its vertices and samples of its larger faces, each to the
  // surface's face nearest it) may lie outside the new surface by at most the inner bound, inside
  // it at any depth (its inner walls, welded segments); the outer bound is then kept by
  // check_point against the target itself.
  auto add_sample = [&](const Vec3& x, FD f, double sure, const std::array<double, 3>& limits) {
    s.assigned[static_cast<size_t>(f.idx())].push_back(static_cast<int>(s.samples.size()));
    s.sample_face.push_back(f);
    s.sample_bound.push_back(sure);
    s.sample_limits.push_back(limits);
    s.samples.push_back(x);
  };
  auto add_own_sample = [&](const Vec3& x, FD f, double cap) {
    // (With a target, a sample whose cap is infinite, no other part of the surface within reach,
    // passes whatever the new faces: it is not kept.)
    if (target) return cap < INFINITY ? add_sample(x, f, cap, {INFINITY, INFINITY, cap}) : void();
    const double sure = std::min({opt.max_inside, opt.max_outside, cap});
    add_sample(x, f, sure, {opt.max_inside, opt.max_outside, sure});
  };
  for (VD v : m.vertices()) {
    FD f = Mesh::null_face();
    for (HD h : CGAL::halfedges_around_target(m.halfedge(v), m))
      if (m.face(h) != Mesh::null_face() && (f == Mesh::null_face() || m.face(h) < f)) f = m.face(h);
    add_own_sample(vec(m.point(v)), f, gap[static_cast<size_t>(v.idx())] / 3.0);
  }
  const double spacing = std::max(opt.max_inside, 1e-12);
  for (FD f : m.faces()) {
    Vec3 q[3];
    int k = 0;
    for (VD v : CGAL::vertices_around_face(m.halfedge(f), m)) q[k++] = vec(m.point(v));
    for_each_lattice_point(q[0], q[1], q[2], spacing,
                           [&](const Vec3& x) { add_own_sample(x, f, s.face_gap[static_cast<size_t>(f.idx())]); });
  }
  if (target) {
    const std::vector<Vec3> points = surface_samples(target_surface->V, target_surface->F, spacing);
    std::vector<int> nearest_face(points.size(), -1);  // faces of `surface`: the Mesh's in the same order
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) { reference.nearest(points[i], &nearest_face[i]); });
    for (size_t i = 0; i < points.size(); ++i)
      if (nearest_face[i] >= 0)
        add_sample(points[i], FD(static_cast<Mesh::size_type>(nearest_face[i])), opt.max_inside,
                   open ? std::array<double, 3>{opt.max_inside, opt.max_inside, opt.max_inside}
                        : std::array<double, 3>{opt.max_inside, INFINITY, INFINITY});
  }
  s.initial_faces = m.number_of_faces();
  if (progress) progress->stage("simplifying the boundary", static_cast<double>(m.number_of_faces() / 2));
  const size_t target_edges = static_cast<size_t>(std::max(4, opt.target_faces)) * 3 / 2;
  Filter filter{&s};
  Visitor visitor(&s);
  const SMS::LindstromTurk_cost<Mesh>::LindstromTurk_params lt(0.5, 0.5, opt.shape_weight);
  SMS::edge_collapse(m, Stop{target_edges},
                     CGAL::parameters::get_cost(SMS::LindstromTurk_cost<Mesh>(lt))
                         .get_placement(SnappedPlacement{SMS::LindstromTurk_placement<Mesh>(lt)})
                         .filter(filter)
                         .visitor(visitor));
  // Then the short edges the volume-driven order left (tetrahedra across a short edge next to long
  // ones are flat): shortest first, while shorter than a quarter of the median edge, within the
  // same bounds.
  {
    std::vector<double> len;
    for (auto e : m.edges()) len.push_back(std::sqrt(CGAL::squared_distance(m.point(m.vertex(e, 0)), m.point(m.vertex(e, 1)))));
    std::nth_element(len.begin(), len.begin() + static_cast<long>(len.size() / 2), len.end());
    const double threshold = opt.short_edge * (len.empty() ? 0.0 : len[len.size() / 2]);
    if (threshold > 0)
      SMS::edge_collapse(m, SMS::Edge_length_stop_predicate<double>(threshold),
                         CGAL::parameters::get_cost(SMS::Edge_length_cost<Mesh>())
                             .get_placement(SnappedPlacement{SMS::LindstromTurk_placement<Mesh>(lt)})
                             .filter(filter)
                             .visitor(visitor));
  }
  if (progress) progress->finish();
  const SurfaceMesh out = from_cgal(m);
  if (stats) {
    stats->faces = static_cast<int>(out.F.rows());
    stats->collapses = s.collapses;
    stats->bounded = out.F.rows() > std::max(4, opt.target_faces) + 2;
  }
  return out;
}

}  // namespace

namespace {
// The edges of m where its two faces meet at over `degrees` (the angle between their normals), as
// the property map "e:crease": the remeshers' constraints. Border edges are none; an edge beside a
// face of no area is one where `degenerate_is_crease` (its normal is unknown, so it may be sharp).
Mesh::Property_map<Mesh::Edge_index, bool> mark_creases(Mesh& m, double degrees, bool degenerate_is_crease) {
  auto crease = m.add_property_map<Mesh::Edge_index, bool>("e:crease", false).first;
  const double cos_crease = std::cos(degrees * M_PI / 180.0);
  for (auto e : m.edges()) {
    const HD h = m.halfedge(e);
    if (m.is_border(h) || m.is_border(m.opposite(h))) continue;
    const Vec3 a = vec(m.point(m.source(h))), b = vec(m.point(m.target(h)));
    const Vec3 c = vec(m.point(m.target(m.next(h)))), d = vec(m.point(m.target(m.next(m.opposite(h)))));
    const Vec3 n1 = (b - a).cross(c - a), n2 = (a - b).cross(d - b);
    const bool degenerate = !(n1.norm() > 0 && n2.norm() > 0);
    if (degenerate ? degenerate_is_crease : n1.dot(n2) < cos_crease * n1.norm() * n2.norm()) crease[e] = true;
  }
  return crease;
}
}  // namespace

SurfaceMesh simplify_envelope(const SurfaceMesh& surface, const EnvelopeOptions& options, EnvelopeStats* stats,
                              Progress* progress) {
  return simplify(surface, nullptr, options, stats, progress);
}

SurfaceMesh simplify_envelope(const SurfaceMesh& surface, const SurfaceMesh& target, const EnvelopeOptions& options,
                              EnvelopeStats* stats, Progress* progress) {
  if (target.F.rows() == 0) throw InputError("simplify_envelope: the target has no triangles");
  return simplify(surface, &target, options, stats, progress);
}

SurfaceMesh simplify_sheet(const SurfaceMesh& sheet, const SurfaceMesh& target, const EnvelopeOptions& options,
                           EnvelopeStats* stats, Progress* progress) {
  if (target.F.rows() == 0) throw InputError("simplify_sheet: the target has no triangles");
  EnvelopeOptions o = options;
  o.max_outside = o.max_inside = std::min(options.max_outside, options.max_inside);
  return simplify(sheet, &target, o, stats, progress, true);
}

SurfaceMesh remesh_sheet(const SurfaceMesh& sheet, double edge_length, int iterations, double max_border_sag) {
  if (!(edge_length > 0)) throw InputError("remesh_sheet: the edge length must be positive");
  Mesh m = to_cgal(sheet, "remesh_sheet: the sheet is not an oriented 2-manifold");
  // Boundary edges are constraints by default: split and collapsed along the border polylines,
  // their vertices kept on them; the others projected back onto the input sheet. The border's
  // corners (where it turns by more than 20°) stay where they are, or the border would cut them.
  auto corner = m.add_property_map<VD, bool>("v:corner", false).first;
  const double cos_turn = std::cos(20.0 * M_PI / 180.0);
  for (HD h : m.halfedges()) {
    if (!m.is_border(h)) continue;
    const HD next = m.next(h);  // the border continues from target(h)
    const Vec3 a = vec(m.point(m.source(h))), b = vec(m.point(m.target(h))), c = vec(m.point(m.target(next)));
    const Vec3 u = b - a, w = c - b;
    if (!(u.norm() > 0 && w.norm() > 0) || u.dot(w) < cos_turn * u.norm() * w.norm()) corner[m.target(h)] = true;
  }
  // A curved outline keeps its sag (max_border_sag): along each border loop, from a corner where
  // it has one, the chord from the last vertex kept is extended vertex by vertex while it passes
  // within the sag of the vertices between and is at most edge_length long; the last vertex it
  // held to is kept, as a corner (greedy, as in polyline simplification).
  auto sag_kept = m.add_property_map<VD, bool>("v:sag_kept", false).first;
  if (std::isfinite(max_border_sag) && max_border_sag > 0) {
    std::vector<char> done(m.number_of_halfedges(), 0);
    for (HD h0 : m.halfedges()) {
      if (!m.is_border(h0) || done[h0.idx()]) continue;
      std::vector<HD> loop;  // loop[i]: the border halfedge whose source is the i-th vertex
      for (HD h = h0; !done[h.idx()]; h = m.next(h)) done[h.idx()] = 1, loop.push_back(h);
      const size_t n = loop.size();
      size_t start = 0;
      for (size_t i = 0; i < n; ++i)
        if (corner[m.source(loop[i])]) {
          start = i;
          break;
        }
      auto at = [&](size_t i) { return vec(m.point(m.source(loop[(start + i) % n]))); };
      auto chord_holds = [&](size_t a, size_t b) {  // (b > a, indices from start)
        const Vec3 p = at(a), q = at(b), d = q - p;
        const double len2 = d.squaredNorm();
        if (len2 > edge_length * edge_length) return false;
        for (size_t k = a + 1; k < b; ++k) {
          const Vec3 x = at(k) - p;
          const double t = len2 > 0 ? std::clamp(x.dot(d) / len2, 0.0, 1.0) : 0.0;
          if ((x - t * d).norm() > max_border_sag) return false;
        }
        return true;
      };
      size_t kept = 0;
      while (kept < n) {
        const VD v = m.source(loop[(start + kept) % n]);
        corner[v] = sag_kept[v] = true;
        size_t next = kept + 1;
        while (next + 1 <= n && chord_holds(kept, next + 1)) ++next;
        kept = next;
      }
    }
  }
  // Creases (faces meeting at over 60°: a bent bracket's bend) are constraints too: split and
  // collapsed along themselves, their vertices kept on them, so the remeshed sheet keeps its bends
  // instead of cutting them by up to half an edge (meshing version 15).
  // With max_border_sag, creases over the angle at which a chord of edge_length across them would
  // cut them by more than the sag are (at least 20°, where tessellations of smooth surfaces turn;
  // at most 60°): a bottle's 32° shoulder, cut by 1.7 mm at 12 mm edges (meshing version 24).
  double crease_degrees = 60.0;
  if (std::isfinite(max_border_sag) && max_border_sag > 0)
    crease_degrees = std::clamp(2.0 * std::asin(std::min(1.0, 2.0 * max_border_sag / edge_length)) * 180.0 / M_PI, 20.0, 60.0);
  auto crease = mark_creases(m, crease_degrees, false);
  CGAL::Polygon_mesh_processing::isotropic_remeshing(
      faces(m), edge_length, m,
      CGAL::parameters::number_of_iterations(iterations).vertex_is_constrained_map(corner).edge_is_constrained_map(crease));
  // Border edges under a quarter of the edge length that the remeshing kept (between two corners,
  // or a corner and a border vertex: a jagged outline, as models in integer coordinates have,
  // turns by more than 20° at nearly every vertex) make needle triangles, and the slab's prisms
  // over them slivers. They are collapsed, shortest first: to their midpoint between two corners,
  // else onto the corner (the caller measures how far the remeshed sheet strays from the input).
  std::vector<std::pair<double, HD>> short_border;
  for (HD h : m.halfedges())
    if (m.is_border(h)) {
      const double len = (vec(m.point(m.source(h))) - vec(m.point(m.target(h)))).norm();
      if (len < 0.25 * edge_length) short_border.emplace_back(len, h);
    }
  std::sort(short_border.begin(), short_border.end());
  for (const auto& [len, h] : short_border) {
    if (m.is_removed(h) || !m.is_border(h)) continue;
    const VD a = m.source(h), b = m.target(h);
    if (!((vec(m.point(a)) - vec(m.point(b))).norm() < 0.25 * edge_length)) continue;
    if (sag_kept[a] || sag_kept[b]) continue;  // (the sag needs them where they are)
    if (!CGAL::Euler::does_satisfy_link_condition(m.edge(h), m)) continue;
    const bool ca = corner[a], cb = corner[b];
    const Point at = ca == cb ? CGAL::midpoint(m.point(a), m.point(b)) : ca ? m.point(a) : m.point(b);
    const VD kept = CGAL::Euler::collapse_edge(m.edge(h), m);
    m.point(kept) = at;
    corner[kept] = ca || cb;
  }
  m.collect_garbage();
  return from_cgal(m);
}

SurfaceMesh remesh_isotropic(const SurfaceMesh& surface, const RemeshOptions& options) {
  if (!(options.edge_length > 0) || !std::isfinite(options.edge_length))
    throw InputError("remesh_isotropic: the edge length must be positive and finite");
  Mesh m;
  try {
    m = to_cgal(surface, "remesh_isotropic: the surface is not a 2-manifold");
  } catch (const InputError& e) {
    spdlog::debug("{}", e.what());
    return {};
  }
  if (!CGAL::is_closed(m)) {
    spdlog::debug("remesh_isotropic: the surface is not closed");
    return {};
  }
  // Creases: split and collapsed along themselves, never flipped, their vertices kept on them.
  auto crease = mark_creases(m, options.sharp_angle, true);  // (closed: no border edges)
  // Corners: where other than two creases meet, or two meet turning by over 30° (a pocket's
  // corner): they stay where they are, or collapses along the creases would cut them.
  auto corner = m.add_property_map<VD, bool>("v:corner", false).first;
  {
    const double cos_turn = std::cos(30.0 * M_PI / 180.0);
    for (VD v : m.vertices()) {
      std::vector<Vec3> dirs;
      for (HD h : CGAL::halfedges_around_target(m.halfedge(v), m))
        if (crease[m.edge(h)]) dirs.push_back(vec(m.point(m.source(h))) - vec(m.point(v)));
      if (dirs.empty()) continue;
      if (dirs.size() != 2) corner[v] = true;
      else {
        const Vec3 u = -dirs[0], w = dirs[1];  // along the crease through v
        if (!(u.norm() > 0 && w.norm() > 0) || u.dot(w) < cos_turn * u.norm() * w.norm()) corner[v] = true;
      }
    }
  }
  // Creases longer than the edge length split into equal pieces first (their new vertices on them).
  std::vector<Mesh::Edge_index> creases;
  for (auto e : m.edges())
    if (crease[e]) creases.push_back(e);
  try {
    CGAL::Polygon_mesh_processing::split_long_edges(creases, options.edge_length, m,
                                                    CGAL::parameters::edge_is_constrained_map(crease));
    CGAL::Polygon_mesh_processing::isotropic_remeshing(
        faces(m), options.edge_length, m,
        CGAL::parameters::number_of_iterations(options.iterations).edge_is_constrained_map(crease).vertex_is_constrained_map(corner).protect_constraints(options.protect_creases));
  } catch (const std::exception& e) {
    spdlog::debug("remesh_isotropic: CGAL failed: {}", e.what());
    return {};
  }
  m.collect_garbage();
  return from_cgal(m);
}

}  // namespace squeeze::meshing
