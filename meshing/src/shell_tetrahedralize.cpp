// CGAL translation unit: Mesh_3 (the convex shells' union and the winding-number solid share one
// instantiation). Keep other code out of it, it is the slowest file to compile.
#include "squeeze/meshing/shell_tetrahedralize.h"
#include "squeeze/meshing/winding_tetrahedralize.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/assertions_behaviour.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>
#include <CGAL/perturb_mesh_3.h>
#include <CGAL/exude_mesh_3.h>

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <mutex>
#include <numeric>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/tet_cleanup.h"
#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_geometry.h"
#include "squeeze/meshing/tet_locator.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/winding_number.h"
#include "label_memo.h"
#include "sigfpe_trap.h"

namespace squeeze::meshing {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
namespace params = CGAL::parameters;

// Union of the shells, dilated by `offset`, as an inside test. Shells whose (dilated) box does not
// hold p are skipped.
struct UnionFunction {
  struct Shell {
    Eigen::MatrixX4d planes;
    Eigen::Vector3d lo, hi;
  };
  std::vector<Shell> shells;
  double offset = 0.0;  // dilation

  explicit UnionFunction(const std::vector<ConvexShell>& in) {
    for (const auto& s : in) {
      Shell sh;
      sh.planes = s.hull.planes;
      sh.lo = s.hull.V.colwise().minCoeff().transpose();
      sh.hi = s.hull.V.colwise().maxCoeff().transpose();
      shells.push_back(std::move(sh));
    }
  }
  bool inside(double x, double y, double z) const {
    for (const Shell& s : shells) {
      if (x < s.lo(0) - offset || y < s.lo(1) - offset || z < s.lo(2) - offset || x > s.hi(0) + offset ||
          y > s.hi(1) + offset || z > s.hi(2) + offset)
        continue;
      bool in = true;
      for (Eigen::Index i = 0; i < s.planes.rows() && in; ++i)
        in = s.planes(i, 0) * x + s.planes(i, 1) * y + s.planes(i, 2) * z - s.planes(i, 3) < offset;
      if (in) return true;
    }
    return false;
  }
};

// Seconds from a to b (steady-clock time points), for the debug log.
double sec(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// The cells of the complex as a tet mesh (vertices in order of first use), positively oriented:
// in CGAL's vertex order, positive by its exact predicate. (Not by the sign of a floating-point
// volume, which can turn a nearly flat cell the wrong way round: the sliver moves then inflate it
// inverted, and its boundary faces face inward; meshing version 43. Callers apply
// orient_positively after their sliver moves, where no vertex moves any more.)
TetMesh to_tet_mesh(const C3t3& c3t3) {
  const Tr& tr = c3t3.triangulation();
  TetMesh mesh;
  std::map<Tr::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> pts;
  std::vector<Eigen::Vector4i> tets;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    Eigen::Vector4i t;
    for (int k = 0; k < 4; ++k) {
      auto v = c->vertex(k);
      auto [it, fresh] = index.emplace(v, static_cast<int>(pts.size()));
      if (fresh) {
        const auto& p = tr.point(v);
        pts.emplace_back(p.x(), p.y(), p.z());
      }
      t(k) = it->second;
    }
    tets.push_back(t);
  }
  mesh.V.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) mesh.V.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  mesh.T.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (size_t i = 0; i < tets.size(); ++i) mesh.T.row(static_cast<Eigen::Index>(i)) = tets[i].transpose();
  return mesh;
}

// Mesh_3's Delaunay refinement of `domain` (its surface patch (0, 1)) started from `seeds`,
// points on that surface inserted as surface vertices; no optimiser (the callers choose theirs).
// CGAL's random generator is reset to `seed`; at most 2 × max_tets vertices (a safety net
// against runaway refinement: memory).
void refine_from_seeds(C3t3& c3t3, const Domain& domain, const std::vector<Eigen::Vector3d>& seeds, double size,
                       double facet_distance, unsigned seed, int max_tets, bool surface_only = false) {
  // CGAL's warnings go to the debug log, not to stderr: where no seed lies on a facet of the
  // domain (a solid thinner than the seeds' spacing, a 1 mm bowl), refine_mesh_3 warns that it
  // cannot start and returns nothing, which the callers report in their own words.
  static std::once_flag quiet;
  std::call_once(quiet, [] {
    CGAL::set_warning_handler([](const char* what, const char* expr, const char* file, int line, const char* msg) {
      spdlog::debug("CGAL {}: {} ({}:{}) {}", what ? what : "warning", expr ? expr : "", file ? file : "", line, msg ? msg : "");
    });
  });
  const auto surface_index = domain.index_from_surface_patch_index(Domain::Surface_patch_index(0, 1));
  CGAL::get_default_random() = CGAL::Random(seed);
  Tr& tr = c3t3.triangulation();
  for (const Eigen::Vector3d& p : seeds) {
    auto v = tr.insert(Tr::Point(Point(p(0), p(1), p(2))));
    if (v == Tr::Vertex_handle()) continue;
    c3t3.set_dimension(v, 2);
    c3t3.set_index(v, surface_index);
  }
  if (surface_only) {  // facets only, a manifold surface (Mesh_3 refines where it pinches)
    Criteria criteria(params::facet_angle = 25, params::facet_size = size, params::facet_distance = facet_distance);
    CGAL::refine_mesh_3(c3t3, domain, criteria, params::no_lloyd(), params::no_odt(), params::no_perturb(),
                        params::no_exude(), params::manifold(),
                        params::mesh_3_options(params::maximal_number_of_vertices = static_cast<std::size_t>(2 * max_tets)));
    return;
  }
  Criteria criteria(params::facet_angle = 25, params::facet_size = size, params::facet_distance = facet_distance,
                    params::cell_radius_edge_ratio = 3, params::cell_size = size);
  CGAL::refine_mesh_3(c3t3, domain, criteria, params::no_lloyd(), params::no_odt(), params::no_perturb(),
                      params::no_exude(),
                      params::mesh_3_options(params::maximal_number_of_vertices = static_cast<std::size_t>(2 * max_tets)));
}

// CGAL's sliver exuder, stopped where it meets a NaN weight (detail::run_unless_sigfpe: beside a
// numerically flat cell, CGAL 5.5's exuder compares a NaN exactly and GMP raises SIGFPE); its
// earlier pumps are kept.
CGAL::Mesh_optimization_return_code exude_unless_nan(C3t3& c3t3, double seconds, double sliver_bound) {
  CGAL::Mesh_optimization_return_code code = CGAL::BOUND_REACHED;
  if (!detail::run_unless_sigfpe(
          [&] { code = CGAL::exude_mesh_3(c3t3, params::time_limit = seconds, params::sliver_bound = sliver_bound); }))
    spdlog::debug("Mesh_3's sliver exuder met a NaN weight (a numerically flat cell) and stopped there");
  return code;
}

}  // namespace

TetMesh tetrahedralize_shells(const std::vector<ConvexShell>& shells, const ShellTetrahedralizeOptions& opt,
                              ShellTetrahedralizeStats* stats, Progress* progress, const Eigen::MatrixX3d* cover) {
  if (shells.empty()) throw InputError("tetrahedralize_shells: no convex shells");
  if (opt.target_tets < 1) throw InputError("--target-tets must be at least 1");
  if (!(opt.facet_distance >= 0)) throw InputError("--facet-distance must be >= 0");
  if (!(opt.facet_distance_per_size > 0)) throw InputError("facet_distance_per_size must be > 0");

  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  double volume = 0.0;
  for (const auto& s : shells) {
    lo = lo.cwiseMin(s.hull.V.colwise().minCoeff().transpose());
    hi = hi.cwiseMax(s.hull.V.colwise().maxCoeff().transpose());
    volume += s.hull.volume;
  }
  const double diag = (hi - lo).norm();
  UnionFunction f(shells);
  const Eigen::Vector3d centre = 0.5 * (lo + hi);

  double hull_area = 0.0;
  for (const auto& s : shells)
    for (Eigen::Index t = 0; t < s.hull.F.rows(); ++t)
      hull_area += 0.5 * (s.hull.V.row(s.hull.F(t, 1)) - s.hull.V.row(s.hull.F(t, 0)))
                             .cross(s.hull.V.row(s.hull.F(t, 2)) - s.hull.V.row(s.hull.F(t, 0)))
                             .norm();
  const double thickness = hull_area > 0 ? 3.0 * volume / hull_area : diag;  // 3 V / A
  // Mesh_3's labeled domain only uses the sign: an inside test per shell that stops at the first
  // separating plane is far cheaper than the signed value.
  std::function<double(const Point&)> fn = [&f](const Point& p) { return f.inside(p.x(), p.y(), p.z()) ? -1.0 : 1.0; };

  const Eigen::Vector3d dirs[14] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1},
                                    {1, 1, 1}, {1, 1, -1}, {1, -1, 1}, {1, -1, -1}, {-1, 1, 1}, {-1, 1, -1},
                                    {-1, -1, 1}, {-1, -1, -1}};

  // One Mesh_3 run at the given cell size and facet distance, on the union dilated by f.offset.
  auto run = [&](double size, double fd) {
    // Half a cell, but at most a third of the thickness: the seeds on both sides of a thin (or
    // flat, thickened) part must all stay, or Mesh_3 finds no boundary facet to start from.
    const double seed_spacing = std::min(0.5 * size, thickness / 3.0);
    const double radius = 0.5 * diag * 1.05 + 2 * f.offset + 1e-12;
    Domain domain = Domain::create_implicit_mesh_domain(
        fn, K::Sphere_3(Point(centre(0), centre(1), centre(2)), radius * radius),
        params::relative_error_bound = 1e-7);
    // Initial surface points: from each shell's centre, bisect along 14 directions to the union's
    // boundary, so that every part of the union is seeded (random rays could miss a part). Seeds
    // closer than seed_spacing × size to an earlier one are dropped: Delaunay refinement never
    // removes a vertex, and two close seeds would leave an edge far shorter than the others.
    std::vector<Eigen::Vector3d> seeds;
    for (const auto& s : shells) {
      const Eigen::Vector3d c = s.hull.V.colwise().mean().transpose();
      if (!f.inside(c(0), c(1), c(2))) continue;
      for (const auto& d0 : dirs) {
        const Eigen::Vector3d d = d0.normalized();
        double a = 0.0, b = 2.0 * diag;
        for (int it = 0; it < 60; ++it) {
          const double m = 0.5 * (a + b);
          const Eigen::Vector3d p = c + m * d;
          (f.inside(p(0), p(1), p(2)) ? a : b) = m;
        }
        const Eigen::Vector3d p = c + b * d;
        bool near = false;
        for (const auto& q : seeds) near = near || (q - p).norm() < seed_spacing;
        if (!near) seeds.push_back(p);
      }
    }
    C3t3 c3t3;
    const auto t0 = std::chrono::steady_clock::now();
    refine_from_seeds(c3t3, domain, seeds, size, fd, opt.seed, opt.max_tets);
    const auto t1 = std::chrono::steady_clock::now();
    // Perturbation and exudation run to completion in practice; their time limit is a bound for
    // pathological inputs (reaching it makes the result depend on the machine's load: warned).
    if (opt.perturb &&
        CGAL::perturb_mesh_3(c3t3, domain, params::time_limit = opt.optimize_seconds,
                             params::sliver_bound = opt.sliver_bound) == CGAL::TIME_LIMIT_REACHED)
      spdlog::warn("tetrahedralize: Mesh_3's sliver perturber stopped at its time limit ({} s): the mesh may differ "
                   "from run to run",
                   opt.optimize_seconds);
    const auto t2 = std::chrono::steady_clock::now();
    if (exude_unless_nan(c3t3, opt.optimize_seconds, opt.sliver_bound) == CGAL::TIME_LIMIT_REACHED)
      spdlog::warn("tetrahedralize: Mesh_3's sliver exuder stopped at its time limit ({} s): the mesh may differ "
                   "from run to run",
                   opt.optimize_seconds);
    const auto t3 = std::chrono::steady_clock::now();
    spdlog::debug("Mesh_3 (convex shells): refine {:.2f} s, perturb {:.2f} s, exude {:.2f} s", sec(t0, t1), sec(t1, t2),
                  sec(t2, t3));
    return to_tet_mesh(c3t3);
  };

  // The points to cover: the caller's (the input's vertices), else the shells' vertices (the
  // input's most extreme points). Returns the fraction held and the extra dilation that would hold
  // 99.9% of them.
  Eigen::MatrixX3d corners;
  if (cover && cover->rows() > 0) {
    corners = *cover;
  } else {
    Eigen::Index n = 0;
    for (const auto& s : shells) n += s.hull.V.rows();
    corners.resize(n, 3);
    n = 0;
    for (const auto& s : shells) corners.middleRows(n, s.hull.V.rows()) = s.hull.V, n += s.hull.V.rows();
  }
  const double required = 0.999;
  auto coverage = [&](const TetMesh& mesh, double& needed) {
    const TetLocator locator(mesh);
    std::vector<double> out(static_cast<size_t>(corners.rows()), 0.0);
    tbb::parallel_for(Eigen::Index(0), corners.rows(), [&](Eigen::Index i) {
      if (locator.locate(corners.row(i)) < 0) locator.nearest(corners.row(i), &out[static_cast<size_t>(i)]);
    });
    std::vector<double> sorted = out;
    std::sort(sorted.begin(), sorted.end());
    const double tol = opt.coverage_tolerance * diag;
    needed = std::max(0.0, sorted[std::min(sorted.size() - 1, static_cast<size_t>(required * static_cast<double>(sorted.size())))] - tol) +
             0.1 * tol;
    return static_cast<double>(std::count_if(out.begin(), out.end(), [&](double d) { return d <= tol; })) /
           static_cast<double>(out.size());
  };

  // Shells of one connected part of the solid mesh into one component (at most as many as parts).
  int parts = 0;
  for (const auto& s : shells) parts = std::max(parts, s.part + 1);
  const double target = opt.target_tets;
  // First guess: Delaunay refinement with cell_size s gives about volume / (0.07 s³) tetrahedra
  // (measured on our corpus); then corrected from the count of each attempt.
  double size = std::cbrt(volume / (0.07 * target));
  double coarsen = 1.0;  // grows when the count exceeds max_tets with a fixed facet_distance bound
  auto facet_distance = [&](double s) {
    double d = opt.facet_distance_per_size * s;
    if (opt.facet_distance > 0) d = std::min(d, coarsen * opt.facet_distance * diag);
    return d;
  };
  // The dilation: `offset` (within 5% of the thickness for thin parts); boundary vertices are then
  // moved out locally where points stick out (inflate_to_cover). Where that is not enough, the
  // dilation grows, as a multiple of the facet distance (a chord of the dilated surface sinks
  // about that deep below it).
  double cover_factor = 0.0;
  const double base_offset = std::min(opt.offset * diag, 0.05 * thickness);
  constexpr double kMaxOffset = 0.05;  // fraction of the diagonal: the dilation's bound
  TetMesh best;
  double best_score = INFINITY;
  ShellTetrahedralizeStats st;
  const int max_attempts = 8;
  int offset_raises = 0;
  double previous = INFINITY;
  for (int attempt = 0; attempt < max_attempts; ++attempt) {
    if (progress) progress->update(attempt);
    const auto t0 = std::chrono::steady_clock::now();
    const double fd = facet_distance(size);
    // (At most 5 % of the diagonal: shells that leave the points farther out than that do not hold
    // the input, and dilating them as a multiple of a facet distance that grows with the cell size
    // made a blob: a Moebius strip's shells at 150 grew to 26 m around a 1 m strip, 8 attempts.)
    f.offset = std::max(base_offset, std::min(cover_factor * fd, kMaxOffset * diag));
    TetMesh mesh = run(size, fd);
    const double t_run = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // Mesh_3 may leave a few tetrahedra apart (a sliver of the union at a dilated corner): keep
    // the largest components, as many as the solid has parts (coverage is restored below).
    if (mesh.T.rows() > 0) {
      Eigen::VectorXi C;
      const int nc = tet_components(mesh, C);
      if (nc > parts) {
        std::vector<int> count(static_cast<size_t>(nc), 0), order(static_cast<size_t>(nc));
        for (Eigen::Index t = 0; t < C.size(); ++t) ++count[static_cast<size_t>(C(t))];
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return count[a] > count[b]; });
        std::vector<char> keep(static_cast<size_t>(nc), 0);
        for (int k = 0; k < parts; ++k) keep[static_cast<size_t>(order[static_cast<size_t>(k)])] = 1;
        Eigen::MatrixX4i T(mesh.T.rows(), 4);
        Eigen::Index n = 0;
        for (Eigen::Index t = 0; t < mesh.T.rows(); ++t)
          if (keep[static_cast<size_t>(C(t))]) T.row(n++) = mesh.T.row(t);
        mesh.T = T.topRows(n);
        spdlog::debug("dropped {} of {} tet-mesh components", nc - parts, nc);
      }
    }
    const int peeled = peel_boundary_slivers(mesh, opt.min_dihedral);
    remove_unused_vertices(mesh);
    const int moves =
        mesh.T.rows() > 0 ? inflate_to_cover(mesh, corners, 0.5 * opt.coverage_tolerance * diag, opt.min_dihedral) : 0;
    // Interior slivers the exuder left (the boundary's are peeled above).
    const int relocated = opt.perturb ? 0 : relocate_sliver_vertices(mesh, opt.min_dihedral);
    const int flips = opt.perturb ? 0 : flip_slivers(mesh, opt.min_dihedral);
    orient_positively(mesh);  // (a cell still nearly flat: its floating-point volume positive too)
    st.attempts = attempt + 1;
    const double n = static_cast<double>(mesh.T.rows());
    double needed = 0.0;
    const double held = n > 0 ? coverage(mesh, needed) : 0.0;
    Eigen::VectorXi C;
    const int components = n > 0 ? tet_components(mesh, C) : 0;
    spdlog::info("Mesh_3 attempt {}: cell_size {:.4g}, facet_distance {:.4g}, offset {:.4g}: {} tetrahedra "
                 "({} peeled, {} vertex moves, {} sliver moves, {} flips), {} component(s), {:.2f}% of points held, "
                 "{:.2f} s ({:.2f} s Mesh_3)",
                 attempt + 1, size, fd, f.offset, mesh.T.rows(), peeled, moves, relocated, flips, components, 100 * held,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), t_run);
    const bool covered = held >= required;
    const bool small_enough = n <= opt.max_tets;
    const bool connected = components >= 1 && components <= parts;
    // Score: invalid meshes rank after valid ones; among valid ones, the closest to the target.
    const double score = (covered ? 0 : 100) + (connected ? 0 : 100) + (small_enough ? 0 : 10) +
                         (n > 0 ? std::abs(std::log(n / target)) : 1e9);
    if (score < best_score) {
      best_score = score;
      best = mesh;
      st.cell_size = size;
      st.offset = f.offset;
      st.facet_distance = fd;
      st.covered = held;
      st.peeled_slivers = peeled;
      st.relocated = relocated;
      st.flips = flips;
    }
    if (!covered && n > 0 && offset_raises < 4) {  // dilate by what the missing points need
      cover_factor = (f.offset + needed) / fd;
      ++offset_raises;
      continue;
    }
    if (!small_enough) {  // coarser cells and boundary
      size *= 1.25;
      coarsen *= 1.5;
      continue;
    }
    if (!connected) {  // try a slightly different size
      size *= 0.97;
      continue;
    }
    if (n > 0.85 * target && n < 1.18 * target) break;
    // A fixed facet_distance bound can make the boundary, not the cell size, decide the count:
    // then a larger cell size gains nothing.
    if (opt.facet_distance > 0 && (n > 2.0 * target || (n > target && n > 0.9 * previous))) break;
    previous = n;
    size *= n > 0 ? std::clamp(std::cbrt(n / target), 0.5, 2.0) : 0.7;
  }

  if (best.T.rows() > 0) {
    // Label: the shell that holds the centroid (the most interior one).
    best.label.resize(best.T.rows());
    for (Eigen::Index t = 0; t < best.T.rows(); ++t) {
      const Eigen::RowVector3d c = (best.V.row(best.T(t, 0)) + best.V.row(best.T(t, 1)) + best.V.row(best.T(t, 2)) +
                                    best.V.row(best.T(t, 3))) / 4.0;
      int arg = 0;
      double v = INFINITY;
      for (size_t s = 0; s < shells.size(); ++s) {
        const double sv = shells[s].hull.signed_value(c);
        if (sv < v) v = sv, arg = static_cast<int>(s);
      }
      best.label(t) = arg + 1;
    }
  }
  if (stats) *stats = st;
  return best;
}

// ---------------------------------------------------------------------------------------------
// The winding-number solid (winding_tetrahedralize.h): the same Mesh_3 instantiation, another domain.

namespace {

// Points, with a hash grid of cells `apart` wide to tell whether a point has one within `apart`.
class SpacedPoints {
 public:
  SpacedPoints(const Eigen::Vector3d& origin, double apart) : origin_(origin), apart_(apart) {}
  bool near(const Eigen::Vector3d& p) const { return near_all(p, p, p); }
  // Whether one point lies within `apart` of each of p, q and r (of the whole triangle pqr, by
  // convexity), where p is within `apart` of q and r.
  bool near_all(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) const {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = grid_.find(key(p, dx, dy, dz));
          if (it == grid_.end()) continue;
          for (int s : it->second) {
            const Eigen::Vector3d& x = points[static_cast<size_t>(s)];
            if ((x - p).norm() < apart_ && (x - q).norm() < apart_ && (x - r).norm() < apart_) return true;
          }
        }
    return false;
  }
  void add(const Eigen::Vector3d& p) {
    grid_[key(p, 0, 0, 0)].push_back(static_cast<int>(points.size()));
    points.push_back(p);
  }
  std::vector<Eigen::Vector3d> points;  // in the order added

 private:
  std::int64_t key(const Eigen::Vector3d& p, int dx, int dy, int dz) const {
    const Eigen::Vector3d c = ((p - origin_) / apart_).array().floor();
    return ((static_cast<std::int64_t>(c(0)) + dx + 1) * 2097152 + static_cast<std::int64_t>(c(1)) + dy + 1) * 2097152 +
           static_cast<std::int64_t>(c(2)) + dz + 1;
  }
  Eigen::Vector3d origin_;
  double apart_;
  std::unordered_map<std::int64_t, std::vector<int>> grid_;
};

// The winding-number solid of (V, F), dilated, as Mesh_3's implicit domain, and the surface
// points it is refined from (tetrahedralize_winding_number and winding_number_surface).
class WindingSolid {
 public:
  WindingSolid(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const WindingTetrahedralizeOptions& opt)
      : V_(V), F_(F), winding_(V, F, 1.25), bvh_(V, F), memo_(memo_slots(opt.label_memo_log2_slots)) {
    if (F.rows() == 0 || V.rows() == 0) throw InputError("tetrahedralize_winding_number: no triangles");
    if (!(opt.facet_distance > 0 && opt.facet_distance < 1)) throw InputError("winding-number facet distance must be in (0, 1)");
    if (!(opt.dilation >= 0 && opt.dilation < 1)) throw InputError("winding-number dilation must be in [0, 1)");
    if (opt.max_tets < 1) throw InputError("winding-number max_tets must be at least 1");
    lo_ = V.colwise().minCoeff().transpose();
    const Eigen::Vector3d hi = V.colwise().maxCoeff().transpose();
    diag_ = (hi - lo_).norm();
    if (!(diag_ > 0)) throw InputError("tetrahedralize_winding_number: the input has zero extent");
    centre_ = 0.5 * (lo_ + hi);
    dil_ = opt.dilation * diag_;
    fd_ = opt.facet_distance * diag_;
    area_weighted_normals(V, F, FN_, N_);  // outward where the faces are oriented so
    if (opt.hollow_cell > 0) {
      if (!(opt.hollow_depth >= 0 && opt.hollow_depth < 1)) throw InputError("winding-number hollow depth must be in [0, 1)");
      if (!(opt.hollow_cell < 1)) throw InputError("winding-number hollow cell must be in [0, 1)");
      depth_ = std::max(opt.hollow_depth * diag_, dil_);
      const auto t0 = std::chrono::steady_clock::now();
      flood_outside(opt.hollow_cell * diag_);
      spdlog::debug("winding-number solid: hollowed where the outside reaches, flooded over {} x {} x {} cells {:.3g} wide "
                    "in {:.2f} s", n_(0), n_(1), n_(2), cell_, sec(t0, std::chrono::steady_clock::now()));
    }
  }
  static std::size_t memo_slots(int log2) {
    if (log2 < 12 || log2 > 30)
      throw InputError("winding-number label memo: 2^" + std::to_string(log2) + " slots is outside 2^12..2^30");
    return std::size_t{1} << log2;
  }
  double diag() const { return diag_; }
  double dilation() const { return dil_; }       // units
  double hollow_depth() const { return air_.empty() ? 0.0 : depth_; }  // units; 0: not hollowed
  double facet_distance() const { return fd_; }  // units

  // Inside: near the input surface (the dilation: a cheap, pruned BVH query), else by winding number.
  // Remembered per point (label_memo.h): Mesh_3 asks about the same points again and again.
  bool inside(const Eigen::Vector3d& p) const {
    return memo_(p, [this](const Eigen::Vector3d& q) {
      if (dil_ > 0 && bvh_.any_within(q, dil_)) return true;
      // (Hollowed: where the outside reaches, out whatever the winding number, which is the
      // costlier test.)
      if (!air_.empty() && reached_by_outside(q)) return false;
      return winding_(q.transpose()) >= 0.5;
    });
  }
  const detail::LabelMemo& memo() const { return memo_; }

  // The point of the solid's surface between a (inside) and b (outside): 40 bisections.
  Eigen::Vector3d bisect(Eigen::Vector3d a, Eigen::Vector3d b) const {
    for (int it = 0; it < 40; ++it) {
      const Eigen::Vector3d m = 0.5 * (a + b);
      (inside(m) ? a : b) = m;
    }
    return a;
  }

  Domain domain() const {
    std::function<double(const Point&)> fn = [this](const Point& p) {
      return inside(Eigen::Vector3d(p.x(), p.y(), p.z())) ? -1.0 : 1.0;
    };
    const double radius = 0.5 * diag_ * 1.05 + 2 * dil_ + 1e-12;
    return Domain::create_implicit_mesh_domain(fn, K::Sphere_3(Point(centre_(0), centre_(1), centre_(2)), radius * radius),
                                               params::relative_error_bound = 1e-4);
  }

  // Surface points to start from: at input vertices spaced `spacing` apart, the boundary point
  // along the vertex normal (bisected between a point inside and one outside; vertices of inner
  // walls, inside on both sides, give none). Every part of the solid with a vertex is seeded.
  std::vector<Eigen::Vector3d> seeds(double spacing) const {
    SpacedPoints seeds(lo_, spacing);
    const double probe = dil_ + 2e-3 * diag_;
    for (Eigen::Index i = 0; i < V_.rows(); ++i) {
      const double len = N_.row(i).norm();
      if (!(len > 0)) continue;
      const Eigen::Vector3d p = V_.row(i).transpose(), n = N_.row(i).transpose() / len;
      if (seeds.near(p)) continue;
      const Eigen::Vector3d a = p - probe * n, b = p + probe * n;
      if (!air_.empty() && inside(p)) {  // (hollowed: the shell's inner side too)
        for (const double side : {-1.0, 1.0}) {
          const Eigen::Vector3d s = p + side * (depth_ + 2e-3 * diag_) * n;  // (depth_: at least dil_)
          if (!inside(s)) seeds.add(bisect(p, s));
        }
        continue;
      }
      if (!inside(a) || inside(b)) continue;
      seeds.add(bisect(a, b));
    }
    return seeds.points;
  }

  // Surface points for the input's points that a surface mesh leaves outside (`covered` false):
  // its vertices and points of its faces `spacing` apart, each taken along its normal (the
  // vertex's, the face's) to the solid's surface, at least `apart` from each other. Inserted into
  // Mesh_3's triangulation as surface vertices, they pull its facets over the input's sharp
  // corners and edges, which the dilation rounds and a facet within the facet distance can cut
  // off (three welded boxes: corners and edges 0.55 % of the diagonal outside without them).
  std::vector<Eigen::Vector3d> cover_seeds(const std::function<bool(const Eigen::Vector3d&)>& covered, double spacing,
                                           double apart, bool skip) const {
    SpacedPoints out(lo_, apart), thin(lo_, std::min(apart, fd_));
    const double probe = dil_ + 2e-3 * diag_;
    // The surface point taken for x lies on the segment from x to x + probe n or to x - probe n:
    // where a point already taken lies within `apart` of both ends of each (or of the one taken),
    // x gives none, and neither the cover test nor the 40 bisections are needed (the same points:
    // trimesh's chair, 0.9 M lattice points, half of them outside the surface in the second pass,
    // took 77 s and 53 s). `skip` false: each point tested (bench_mesh's A/B).
    // Where the solid is thin at x (outside it at `probe` on both sides: a flap between holes, held
    // only by the dilation), both sides' surface points are taken, at least the facet distance
    // apart (the other side's lies nearer than `apart`): Mesh_3 follows a part thinner than its
    // facets only where it has surface vertices on both of its sides. With one side's, a flap of a
    // heart with four holes was left 0.76 % of the diagonal outside (meshing version 39).
    auto take = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& normal) {
      if (!(normal.norm() > 0)) return;
      const Eigen::Vector3d n = normal.normalized();
      if (skip && out.near_all(x, x + probe * n, x - probe * n)) return;
      if (covered(x) || !inside(x)) return;
      Eigen::Vector3d b = x + probe * n;
      if (inside(b)) b = x - probe * n;  // a face the file orients inward
      if (inside(b)) return;
      const Eigen::Vector3d c = 2 * x - b;
      if (!inside(c)) {
        for (const Eigen::Vector3d& e : {b, c}) {
          const Eigen::Vector3d a = bisect(x, e);
          if (!thin.near(a)) thin.add(a);
        }
        return;
      }
      if (skip && out.near_all(x, b, x)) return;
      const Eigen::Vector3d a = bisect(x, b);
      if (!out.near(a)) out.add(a);
    };
    for (Eigen::Index i = 0; i < V_.rows(); ++i) take(V_.row(i).transpose(), N_.row(i).transpose());
    for (Eigen::Index f = 0; f < F_.rows(); ++f) {
      const Eigen::Vector3d fn = FN_.row(f).transpose();
      for_each_lattice_point(V_.row(F_(f, 0)).transpose(), V_.row(F_(f, 1)).transpose(), V_.row(F_(f, 2)).transpose(),
                             spacing, [&](const Eigen::Vector3d& x) { take(x, fn); });
    }
    std::vector<Eigen::Vector3d> points = std::move(out.points);
    points.insert(points.end(), thin.points.begin(), thin.points.end());
    return points;
  }

 private:
  const Eigen::MatrixX3d& V_;
  const Eigen::MatrixX3i& F_;
  FastWindingNumber winding_;
  // Hollowing (options.hollow_cell): cells of a grid `cell_` wide from `grid_lo_` (its first
  // cell's centre), n_ per axis, that the outside reaches (1) through no point within the
  // dilation of the input.
  std::vector<char> air_;
  Eigen::Vector3d grid_lo_;
  Eigen::Vector3i n_;
  double cell_ = 0;
  size_t index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * static_cast<size_t>(n_(1)) + static_cast<size_t>(j)) * static_cast<size_t>(n_(0)) +
           static_cast<size_t>(i);
  }
  Eigen::Vector3d centre(int i, int j, int k) const { return grid_lo_ + cell_ * Eigen::Vector3d(i, j, k); }

  // The flood: from the grid's border cells (outside the input's bounding box), to each of the six
  // neighbours, where the segment between their centres crosses no triangle and no point of it
  // lies within the dilation of the input (points about a dilation apart along it; cells over a
  // cell width from the input pass at once). A hole wider than a few cells lets it in; a crack
  // narrower than twice the dilation does not.
  void flood_outside(double cell) {
    const Eigen::Vector3d hi = V_.colwise().maxCoeff().transpose();
    // (At most about 4 M cells: coarser where the bounding box asks for more.)
    const Eigen::Vector3d ext = hi - lo_;
    cell = std::max(cell, std::cbrt(ext.prod() / 4e6));
    cell_ = cell;
    grid_lo_ = lo_ - 1.5 * cell * Eigen::Vector3d::Ones();
    for (int a = 0; a < 3; ++a) n_(a) = static_cast<int>(std::ceil(ext(a) / cell)) + 4;
    const size_t total = static_cast<size_t>(n_(0)) * static_cast<size_t>(n_(1)) * static_cast<size_t>(n_(2));
    const double reach = std::max(dil_, 1e-9 * diag_);
    // Per cell: 2 where a triangle lies within a cell width of its centre (its segments are
    // sampled), 1 where one lies within the dilation (blocked), else 0.
    std::vector<char> near(total, 0);
    tbb::parallel_for(0, n_(2), [&](int k) {
      for (int j = 0; j < n_(1); ++j)
        for (int i = 0; i < n_(0); ++i) {
          const Eigen::Vector3d c = centre(i, j, k);
          char& m = near[index(i, j, k)];
          if (bvh_.any_within(c, cell)) m = bvh_.any_within(c, reach) ? 1 : 2;
        }
    });
    // (Samples at most 16 a segment, where the dilation is tiny; a wall is never crossed.)
    const int samples = static_cast<int>(std::min(16.0, std::ceil(cell / reach)));
    auto passable = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, char ma, char mb) {
      if (ma == 1 || mb == 1) return false;
      if (ma == 0 || mb == 0) return true;
      for (int s = 1; s < samples; ++s)
        if (bvh_.any_within(a + (b - a) * (static_cast<double>(s) / samples), reach)) return false;
      double t;
      return !bvh_.first_crossing(a, b, 0.0, &t);
    };
    air_.assign(total, 0);
    std::vector<Eigen::Vector3i> queue;
    for (int k = 0; k < n_(2); ++k)
      for (int j = 0; j < n_(1); ++j)
        for (int i = 0; i < n_(0); ++i)
          if (i == 0 || j == 0 || k == 0 || i == n_(0) - 1 || j == n_(1) - 1 || k == n_(2) - 1) {
            air_[index(i, j, k)] = 1;
            queue.emplace_back(i, j, k);
          }
    static const int step[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (size_t q = 0; q < queue.size(); ++q) {
      const Eigen::Vector3i c = queue[q];
      for (const auto& d : step) {
        const Eigen::Vector3i e = c + Eigen::Vector3i(d[0], d[1], d[2]);
        if ((e.array() < 0).any() || (e.array() >= n_.array()).any()) continue;
        const size_t ie = index(e(0), e(1), e(2)), ic = index(c(0), c(1), c(2));
        if (air_[ie]) continue;
        if (!passable(centre(c(0), c(1), c(2)), centre(e(0), e(1), e(2)), near[ic], near[ie])) continue;
        air_[ie] = 1;
        queue.push_back(e);
      }
    }
  }
  // Whether p (off the dilation) is where the outside reaches and farther than the hollow depth
  // from the input: one of the 64 cell centres around it (4 × 4 × 4) that the flood reached, with
  // no triangle between it and p.
  bool reached_by_outside(const Eigen::Vector3d& p) const {
    if (bvh_.any_within(p, depth_)) return false;
    const Eigen::Vector3d g = (p - grid_lo_) / cell_;
    const Eigen::Vector3i base = (g.array().floor() - 1.0).cast<int>().matrix();
    for (int c = 0; c < 64; ++c) {
      const Eigen::Vector3i e = base + Eigen::Vector3i(c & 3, (c >> 2) & 3, (c >> 4) & 3);
      if ((e.array() < 0).any() || (e.array() >= n_.array()).any()) continue;
      if (!air_[index(e(0), e(1), e(2))]) continue;
      double t;
      if (!bvh_.first_crossing(p, centre(e(0), e(1), e(2)), 0.0, &t)) return true;
    }
    return false;
  }
  TriangleBvh bvh_;
  mutable detail::LabelMemo memo_;  // inside()'s answers; one thread (Mesh_3 is Sequential_tag here)
  Eigen::MatrixX3d FN_, N_;
  Eigen::Vector3d lo_, centre_;
  double diag_ = 0, dil_ = 0, fd_ = 0, depth_ = 0;
};

// The input's points that the complex leaves outside by more than `tolerance` (sharp corners and
// edges its facets cut off, a crest they cut across): their surface points
// (WindingSolid::cover_seeds) as more seeds, and the refinement resumed; twice at most, the second
// time with seeds half as far apart. Returns the seeds added; `passes` (optional) gets the resumed
// refinements. surface_only: winding_number_surface's facets-only refinement, else
// tetrahedralize_winding_number's cells too.
int cover_outside(C3t3& c3t3, const Domain& domain, const WindingSolid& solid, double size, double tolerance,
                  const WindingTetrahedralizeOptions& opt, bool surface_only, std::chrono::steady_clock::time_point t0,
                  int* passes) {
  const Tr& tr = c3t3.triangulation();
  const double fd = solid.facet_distance();
  int added = 0, resumed = 0;
  for (int pass = 0; pass < 2 && tolerance > 0; ++pass) {
    const TetMesh inside = to_tet_mesh(c3t3);
    if (inside.T.rows() == 0) break;
    const TriangleBvh boundary(inside.V, boundary_faces(inside.T));
    Tr::Cell_handle hint;
    auto covered = [&](const Eigen::Vector3d& x) {
      hint = tr.locate(Tr::Point(Point(x(0), x(1), x(2))), hint);
      return c3t3.is_in_complex(hint) || boundary.nearest(x, nullptr, nullptr, tolerance) <= tolerance;
    };
    const std::vector<Eigen::Vector3d> more = solid.cover_seeds(covered, fd, (pass == 0 ? 4.0 : 2.0) * fd, opt.cover_skip);
    spdlog::debug("Mesh_3 (winding number{}): {} more seeds where the input lies outside by more than {:.3g} ({:.2f} s)",
                  surface_only ? ", surface" : "", more.size(), tolerance,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (more.empty()) break;
    added += static_cast<int>(more.size());
    ++resumed;
    refine_from_seeds(c3t3, domain, more, size, fd, opt.seed, opt.max_tets, surface_only);
  }
  if (passes) *passes = resumed;
  return added;
}

}  // namespace

TetMesh tetrahedralize_winding_number(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double volume,
                                      const WindingTetrahedralizeOptions& opt, WindingTetrahedralizeStats* stats,
                                      Progress* progress) {
  if (opt.target_tets < 1) throw InputError("--target-tets must be at least 1");
  const WindingSolid solid(V, F, opt);
  const double diag = solid.diag(), dil = solid.dilation(), fd = solid.facet_distance();

  WindingTetrahedralizeStats st;
  st.facet_distance = fd;
  st.dilation = dil;
  auto run = [&](double size) {
    const std::vector<Eigen::Vector3d> seeds = solid.seeds(std::min(0.5 * size, 8.0 * fd));
    st.seeds = static_cast<int>(seeds.size());
    const Domain domain = solid.domain();
    C3t3 c3t3;
    const auto t0 = std::chrono::steady_clock::now();
    refine_from_seeds(c3t3, domain, seeds, size, fd, opt.seed, opt.max_tets);
    // (As winding_number_surface's: corners and crests the facets cut off, seeded and refined again.)
    if (opt.cover_solid)
      st.seeds += cover_outside(c3t3, domain, solid, size, opt.cover_tolerance * diag, opt, false, t0, nullptr);
    const auto t1 = std::chrono::steady_clock::now();
    // No sliver perturbation: it moved boundary vertices enough to raise deviation_in from 0.41 to
    // 0.91 % of the diagonal on the heart, and took seconds; the exuder, then
    // relocate_sliver_vertices(), deal with the few slivers left.
    if (exude_unless_nan(c3t3, opt.optimize_seconds, opt.sliver_bound) == CGAL::TIME_LIMIT_REACHED)
      st.time_limit_reached = true;
    const auto t2 = std::chrono::steady_clock::now();
    spdlog::debug("Mesh_3 (winding number): refine {:.2f} s, exude {:.2f} s", sec(t0, t1), sec(t1, t2));
    return to_tet_mesh(c3t3);
  };

  // Cell size: Delaunay refinement with cell_size s gives about volume / (0.07 s³) tetrahedra
  // (measured), corrected from each attempt's count; at most three attempts. Where the facet
  // distance, not the cell size, sets the count (it does not fall with a larger size), the
  // attempts stop. (The volume's magnitude: an input whose faces mostly face inward has a
  // negative winding volume, -1.08e-6 m³ for the spinal cord with holes cut, which the floor of
  // 1e-12 diag³ made a cell size of 17 µm and each attempt 30 s for no tetrahedron.)
  const double target = opt.target_tets;
  double size = std::cbrt(std::max(std::abs(volume), 1e-12 * diag * diag * diag) / (0.07 * target));
  TetMesh best;
  double best_score = INFINITY, previous = INFINITY;
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (progress) progress->update(attempt);
    const auto t0 = std::chrono::steady_clock::now();
    TetMesh mesh = run(size);
    const double n = static_cast<double>(mesh.T.rows());
    spdlog::info("Mesh_3 (winding number) attempt {}: cell_size {:.4g}, facet_distance {:.4g}, dilation {:.4g}, "
                 "{} seeds: {} tetrahedra, {:.2f} s",
                 attempt + 1, size, fd, dil, st.seeds, mesh.T.rows(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    st.attempts = attempt + 1;
    const double boundary = n > 0 ? static_cast<double>(boundary_faces(mesh.T).rows()) : 0.0;
    const double score = n > 0 ? std::abs(std::log(n / target)) + (n > opt.max_tets ? 10 : 0) : 1e9;
    if (score < best_score) {
      best_score = score;
      best = std::move(mesh);
      st.cell_size = size;
    }
    if (n > 0.85 * target && n < 1.18 * target) break;
    // The boundary sets the count: its facets alone (bounded by the facet distance, not the cell
    // size) need more tetrahedra than the target (a tetrahedron has at most about 1.5 of them
    // in these meshes), or a larger cell size did not bring the count down.
    if (n > 1.35 * target && boundary / 1.5 > 1.35 * target) break;
    if (n > target && n > 0.8 * previous) break;
    previous = n;
    size *= n > 0 ? std::clamp(std::cbrt(n / target), 0.5, 2.0) : 0.7;
  }
  if (best.T.rows() > 0) {
    st.peeled_slivers = peel_boundary_slivers(best, opt.min_dihedral);
    remove_unused_vertices(best);
    st.relocated = relocate_sliver_vertices(best, opt.min_dihedral);
    st.flips = flip_slivers(best, opt.min_dihedral);
    orient_positively(best);  // (a cell still nearly flat: its floating-point volume positive too)
    best.label = Eigen::VectorXi::Ones(best.T.rows());
  }
  if (st.time_limit_reached)
    spdlog::warn("tetrahedralize: Mesh_3's sliver exuder stopped at its time limit ({} s): the mesh may "
                 "differ from run to run",
                 opt.optimize_seconds);
  if (stats) *stats = st;
  return best;
}

SurfaceMesh winding_number_surface(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                   const WindingTetrahedralizeOptions& opt, WindingTetrahedralizeStats* stats) {
  const WindingSolid solid(V, F, opt);
  const double fd = solid.facet_distance();
  WindingTetrahedralizeStats st;
  st.facet_distance = fd;
  st.dilation = solid.dilation();
  st.hollow_depth = solid.hollow_depth();
  st.attempts = 1;
  const std::vector<Eigen::Vector3d> seeds = solid.seeds(8.0 * fd);
  st.seeds = static_cast<int>(seeds.size());
  const Domain domain = solid.domain();
  C3t3 c3t3;
  const auto t0 = std::chrono::steady_clock::now();
  const double size = opt.facet_size * solid.diag();
  refine_from_seeds(c3t3, domain, seeds, size, fd, opt.seed, opt.max_tets, true);
  spdlog::debug("Mesh_3 (winding number, surface): {} seeds refined in {:.2f} s", seeds.size(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  // No facet from the vertices' seeds 8 facet distances apart: again, where asked, from the
  // vertices' seeds a facet distance apart (a long, thin input: the spinal cord with holes, 32
  // seeds along its 0.49 m and no facet among them; meshing version 39). Then, where asked, seeds
  // along the faces, a facet distance apart (a part smaller than the vertices' spacing has one or
  // two, a fin's seeds give no restricted facet).
  if (opt.seed_finer_if_no_facet && c3t3.number_of_facets_in_complex() == 0) {
    const std::vector<Eigen::Vector3d> more = solid.seeds(fd);
    spdlog::debug("Mesh_3 (winding number, surface): no facet; {} seeds a facet distance apart", more.size());
    st.seeds += static_cast<int>(more.size());
    ++st.attempts;
    refine_from_seeds(c3t3, domain, more, size, fd, opt.seed, opt.max_tets, true);
  }
  if (opt.seed_faces_if_no_facet && c3t3.number_of_facets_in_complex() == 0) {
    const std::vector<Eigen::Vector3d> more =
        solid.cover_seeds([](const Eigen::Vector3d&) { return false; }, fd, 4.0 * fd, opt.cover_skip);
    spdlog::debug("Mesh_3 (winding number, surface): no facet; {} more seeds along the input's faces", more.size());
    st.seeds += static_cast<int>(more.size());
    ++st.attempts;
    refine_from_seeds(c3t3, domain, more, size, fd, opt.seed, opt.max_tets, true);
  }
  // The input's points left outside the surface (sharp corners and edges cut off): their surface
  // points as more seeds, and the refinement resumed; twice at most.
  int passes = 0;
  st.seeds += cover_outside(c3t3, domain, solid, size, opt.cover_tolerance * solid.diag(), opt, true, t0, &passes);
  st.attempts += passes;
  const TetMesh cells = to_tet_mesh(c3t3);
  SurfaceMesh out;
  if (cells.T.rows() > 0) {
    const Eigen::MatrixX3i B = boundary_faces(cells.T);
    std::vector<int> index(static_cast<size_t>(cells.V.rows()), -1);
    std::vector<Eigen::Vector3d> pts;
    out.F.resize(B.rows(), 3);
    for (Eigen::Index f = 0; f < B.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        int& i = index[static_cast<size_t>(B(f, k))];
        if (i < 0) i = static_cast<int>(pts.size()), pts.push_back(cells.V.row(B(f, k)).transpose());
        out.F(f, k) = i;
      }
    out.V.resize(static_cast<Eigen::Index>(pts.size()), 3);
    for (size_t i = 0; i < pts.size(); ++i) out.V.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  }
  spdlog::debug("Mesh_3 (winding number, surface): {} seeds, {} facets, {:.2f} s; {} points tested, {} repeats "
                "answered from memory", st.seeds, out.F.rows(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), solid.memo().remembered(),
                solid.memo().hits());
  if (stats) *stats = st;
  return out;
}

}  // namespace squeeze::meshing
