#include "squeeze/meshing/mesh_pipeline.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <cmath>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/solid_surface.h"
#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_locator.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/winding_number.h"

namespace squeeze::meshing {
namespace {

class StageTimer {
 public:
  StageTimer(MeshResult& r, Progress* p) : r_(r), p_(p) {}
  void start(const std::string& name) {
    stop();
    name_ = name;
    t0_ = std::chrono::steady_clock::now();
    if (p_) p_->stage(name);
  }
  void stop() {
    if (name_.empty()) return;
    r_.seconds.emplace_back(name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count());
    if (p_) p_->finish();
    name_.clear();
  }

 private:
  MeshResult& r_;
  Progress* p_;
  std::string name_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace

int hull_budget(const MeshOptions& opt) {
  const double per_hull = opt.tets_per_hull;
  if (per_hull <= 0) return opt.decomposition.max_hulls;
  const double n = std::round(static_cast<double>(opt.tetrahedralize.target_tets) / per_hull);
  return static_cast<int>(std::clamp(n, 1.0, static_cast<double>(std::max(1, opt.decomposition.max_hulls))));
}

namespace {

// Samples of the triangles (V, F): every vertex, and points of each triangle at most `spacing`
// apart (barycentric lattice), at most 64 along an edge.
std::vector<Eigen::Vector3d> surface_samples(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double spacing) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<size_t>(V.rows()));
  std::vector<char> used(static_cast<size_t>(V.rows()), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) used[static_cast<size_t>(F(f, k))] = 1;
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    if (used[static_cast<size_t>(i)]) out.push_back(V.row(i).transpose());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)).transpose(), b = V.row(F(f, 1)).transpose(), c = V.row(F(f, 2)).transpose();
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int n = std::min(64, static_cast<int>(std::ceil(longest / spacing)));
    if (n < 2) continue;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n - i; ++j) {
        if ((i == 0 && j == 0) || (i == n && j == 0) || (i == 0 && j == n)) continue;
        out.push_back(a + (static_cast<double>(i) / n) * (b - a) + (static_cast<double>(j) / n) * (c - a));
      }
  }
  return out;
}

double signed_volume(const SurfaceMesh& m) {
  if (m.V.rows() == 0) return 0;
  const Eigen::RowVector3d o = m.V.colwise().mean();
  double v = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    v += (m.V.row(m.F(f, 0)) - o).dot((m.V.row(m.F(f, 1)) - o).cross(m.V.row(m.F(f, 2)) - o)) / 6.0;
  return v;
}

double area(const SurfaceMesh& m) {
  double a = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    a += 0.5 * (m.V.row(m.F(f, 1)) - m.V.row(m.F(f, 0))).cross(m.V.row(m.F(f, 2)) - m.V.row(m.F(f, 0))).norm();
  return a;
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g%%", 100.0 * x);
  return buf;
}

}  // namespace

MeshResult mesh_surface(const SurfaceMesh& surface, const MeshOptions& opt, Progress* progress) {
  if (!(opt.coverage_tolerance >= 0)) throw InputError("coverage tolerance must be >= 0");
  if (!(opt.tets_per_hull >= 0)) throw InputError("tets_per_hull must be >= 0");
  if (opt.tetrahedralize.target_tets < 1) throw InputError("--target-tets must be at least 1");
  if (!(opt.max_deviation > 0 && opt.max_deviation < 1)) throw InputError("--max-deviation must be between 0 and 1");
  if (!(opt.inner_deviation > 0 && opt.inner_deviation <= 1)) throw InputError("inner_deviation must be in (0, 1]");
  if (!(opt.solid_grid > 0)) throw InputError("solid_grid must be > 0");
  MeshResult r;
  r.target_tets = opt.tetrahedralize.target_tets;
  StageTimer timer(r, progress);
  timer.start("analysing input");
  r.input.V = surface.V;
  r.input.F = orient_outward(surface.V, surface.F);
  r.info = analyse_surface(r.input);
  r.info.self_intersecting = does_self_intersect(r.input);
  const double diag = bounding_box_diagonal(r.input.V);
  if (!(diag > 0)) throw InputError("input has zero extent (all vertices coincide)");

  timer.start("decomposing");
  DecompositionOptions dopt = opt.decomposition;
  if (dopt.max_hulls >= 1) dopt.max_hulls = hull_budget(opt);
  r.hull_budget = dopt.max_hulls;
  r.decomposition = decompose(r.input, dopt, progress);

  // The boundary: the input itself when it bounds its solid cleanly, else the solid's surface.
  timer.start("boundary");
  r.boundary_from_input = r.info.closed && !r.info.self_intersecting &&
                          is_oriented_two_manifold(r.input.F, static_cast<int>(r.input.V.rows()));
  SurfaceMesh solid;
  if (r.boundary_from_input) {
    solid = r.input;
  } else {
    const FastWindingNumber wn(r.input.V, r.input.F);
    const TriangleBvh bvh(r.input.V, r.input.F);
    solid = solid_surface(r.input, wn, bvh, opt.solid_grid * diag, progress);
  }
  r.solid_surface_faces = static_cast<int>(solid.F.rows());
  if (solid.F.rows() == 0 || !(signed_volume(solid) > 0))
    throw InputError("the surface encloses no volume (winding number above 1/2 nowhere)");
  r.input_volume_from_winding_number = !r.info.closed;
  if (r.info.closed && !r.info.self_intersecting) r.input_volume = r.info.volume;
  else r.input_volume = signed_volume(solid);  // overlapping closed parts: their union's volume
  if (r.info.closed) r.info.volume = r.input_volume;
  else r.info.volume = r.input_volume;

  // As many boundary faces as a mesh of target_tets tetrahedra has (edge length from the volume;
  // a regular tetrahedron of edge L has volume L³/(6√2), Delaunay meshes average about half),
  // fewer where the deviation bounds allow nothing coarser.
  const double target = opt.tetrahedralize.target_tets;
  const double L = std::cbrt(6.0 * std::sqrt(2.0) * r.input_volume / (0.5 * target));
  EnvelopeOptions eopt;
  eopt.max_outside = opt.max_deviation * diag;
  eopt.max_inside = opt.inner_deviation * opt.max_deviation * diag;
  eopt.target_faces = std::max(8, static_cast<int>(std::lround(area(solid) / (0.433 * L * L))));
  r.boundary = simplify_envelope(solid, eopt, &r.envelope, progress);

  if (const char* dbg = std::getenv("SQUEEZE_DEBUG_BOUNDARY")) save_surface(dbg, r.boundary);  // TEMP
  timer.start("tetrahedralizing");
  r.tets = tetrahedralize(r.boundary, opt.tetrahedralize, &r.tet_stats, progress);
  if (r.tets.T.rows() == 0) throw InputError("tetrahedralization produced no tetrahedra");
  // Label: the convex shell that holds the centroid (the most interior one).
  r.tets.label.resize(r.tets.T.rows());
  for (Eigen::Index t = 0; t < r.tets.T.rows(); ++t) {
    const Eigen::RowVector3d c = (r.tets.V.row(r.tets.T(t, 0)) + r.tets.V.row(r.tets.T(t, 1)) +
                                  r.tets.V.row(r.tets.T(t, 2)) + r.tets.V.row(r.tets.T(t, 3))) / 4.0;
    int arg = 0;
    double v = INFINITY;
    for (size_t s = 0; s < r.decomposition.shells.size(); ++s) {
      const double sv = r.decomposition.shells[s].hull.signed_value(c);
      if (sv < v) v = sv, arg = static_cast<int>(s);
    }
    r.tets.label(t) = arg + 1;
  }

  timer.start("measuring");
  r.quality = tet_quality(r.tets);
  if (r.info.closed && r.input_volume > 0) r.volume_ratio = r.quality.volume / r.input_volume;
  const TetLocator locator(r.tets);
  const Eigen::MatrixX3i tet_boundary = boundary_faces(r.tets.T);
  const TriangleBvh tet_surface(r.tets.V, tet_boundary);
  const TriangleBvh input_surface(r.input.V, r.input.F);
  // Deviations, at points at most 0.2% of the diagonal apart (coarser if that would be more than
  // about 200,000 points on either surface): the largest distance is then found to within
  // spacing / √3 (0.12% of the diagonal).
  const double spacing = std::max({2e-3 * diag, std::sqrt(area(r.input) / 2e5), std::sqrt(area(SurfaceMesh{r.tets.V, tet_boundary}) / 2e5)});
  r.deviation_sample_spacing = spacing;
  {
    const auto pts = surface_samples(r.tets.V, tet_boundary, spacing);
    std::vector<double> d(pts.size(), 0.0);
    tbb::parallel_for(size_t(0), pts.size(), [&](size_t i) { d[i] = input_surface.nearest(pts[i]); });
    for (double x : d) r.deviation_out = std::max(r.deviation_out, x);
  }
  {
    const auto pts = surface_samples(r.input.V, r.input.F, spacing);
    std::vector<double> d(pts.size(), 0.0);
    tbb::parallel_for(size_t(0), pts.size(), [&](size_t i) {
      if (locator.locate(pts[i].transpose()) < 0) d[i] = tet_surface.nearest(pts[i]);
    });
    for (double x : d) r.deviation_in = std::max(r.deviation_in, x);
  }
  const Eigen::Index n = r.input.V.rows();
  std::vector<double> dist(static_cast<size_t>(n), 0.0);
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    if (locator.locate(r.input.V.row(i)) >= 0) return;
    dist[static_cast<size_t>(i)] = tet_surface.nearest(r.input.V.row(i).transpose());
  });
  Eigen::Index inside = 0, covered = 0;
  for (double d : dist) {
    inside += d == 0.0;
    covered += d <= opt.coverage_tolerance * diag;
    r.max_outside_distance = std::max(r.max_outside_distance, d);
  }
  r.inside_fraction = static_cast<double>(inside) / static_cast<double>(n);
  r.covered_fraction = static_cast<double>(covered) / static_cast<double>(n);

  // Why the count is off the target, when it is by more than 35%.
  const double tets = r.quality.tets;
  if (tets > 1.35 * target) {
    if (r.envelope.bounded)
      r.target_exceeded_because =
          "keeping the boundary within " + percent(opt.max_deviation) + " of the bounding-box diagonal outside and " +
          percent(opt.inner_deviation * opt.max_deviation) + " inside the input surface takes " +
          std::to_string(r.boundary.F.rows()) + " boundary triangles (a mesh of " + std::to_string(r.target_tets) +
          " tetrahedra has about " + std::to_string(eopt.target_faces) + "), and tetrahedra with dihedral angles of at least " +
          std::to_string(static_cast<int>(opt.tetrahedralize.refine_dihedral)) + " degrees between them need " +
          std::to_string(r.quality.tets);
    else
      r.target_exceeded_because = "the boundary's " + std::to_string(r.boundary.F.rows()) +
                                  " triangles and tetrahedra with dihedral angles of at least " +
                                  std::to_string(static_cast<int>(opt.tetrahedralize.refine_dihedral)) +
                                  " degrees (flatter where the solid is thinner than the edge length) need " +
                                  std::to_string(r.quality.tets) + " tetrahedra";
  } else if (tets < 0.65 * target) {
    r.target_exceeded_because = "the solid's boundary holds only " + std::to_string(r.boundary.F.rows()) +
                                " triangles and refining the inside stopped at " + std::to_string(r.quality.tets) +
                                " tetrahedra";
  }
  timer.stop();
  return r;
}

MeshResult mesh_file(const std::filesystem::path& path, const MeshOptions& opt, Progress* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (progress) progress->stage("loading " + path.filename().string());
  const SurfaceMesh s = load_surface(path);
  const double load = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  MeshResult r = mesh_surface(s, opt, progress);
  r.seconds.insert(r.seconds.begin(), {"loading", load});
  return r;
}

SurfaceMesh shells_surface(const Decomposition& d) {
  Eigen::Index nv = 0, nf = 0;
  for (const auto& s : d.shells) nv += s.hull.V.rows(), nf += s.hull.F.rows();
  SurfaceMesh m;
  m.V.resize(nv, 3);
  m.F.resize(nf, 3);
  Eigen::Index v = 0, f = 0;
  for (const auto& s : d.shells) {
    m.V.middleRows(v, s.hull.V.rows()) = s.hull.V;
    m.F.middleRows(f, s.hull.F.rows()) = s.hull.F.array() + static_cast<int>(v);
    v += s.hull.V.rows();
    f += s.hull.F.rows();
  }
  return m;
}

nlohmann::json mesh_report(const MeshResult& r, const std::string& input_name) {
  using nlohmann::json;
  json seconds = json::object();
  double total = 0;
  for (const auto& [name, s] : r.seconds) {
    seconds[name] = s;
    total += s;
  }
  seconds["total"] = total;
  const double diag = bounding_box_diagonal(r.input.V);
  auto frac = [&](double x) { return diag > 0 ? x / diag : 0.0; };
  return json{
      {"deviation_out", frac(r.deviation_out)},
      {"deviation_in", frac(r.deviation_in)},
      {"volume_ratio", r.volume_ratio ? json(*r.volume_ratio) : json(nullptr)},
      {"target_tets", r.target_tets},
      {"target_exceeded_because", r.target_exceeded_because.empty() ? json(nullptr) : json(r.target_exceeded_because)},
      {"input",
       {{"file", input_name},
        {"vertices", r.info.vertices},
        {"faces", r.info.faces},
        {"components", r.info.components},
        {"connected_parts", r.decomposition.parts},
        {"closed", r.info.closed},
        {"boundary_edges", r.info.boundary_edges},
        {"nonmanifold_edges", r.info.nonmanifold_edges},
        {"self_intersecting", r.info.self_intersecting},
        {"bbox_diagonal", diag},
        {"volume", r.input_volume},
        {"volume_method", r.input_volume_from_winding_number ? "winding_number"
                          : r.boundary_from_input                ? "divergence"
                                                                 : "solid_surface"}}},
      {"decomposition",
       {{"hulls", r.decomposition.shells.size()},
        {"max_concavity", r.decomposition.max_concavity},
        {"max_concavity_fraction", frac(r.decomposition.max_concavity)},
        {"concavity_threshold", r.decomposition.threshold},
        {"hit_max_hulls", r.decomposition.hit_max_hulls},
        {"hull_budget", r.hull_budget}}},
      {"boundary",
       {{"source", r.boundary_from_input ? "input" : "solid_surface"},
        {"faces_before", r.solid_surface_faces},
        {"faces", r.boundary.F.rows()},
        {"collapses", r.envelope.collapses},
        {"stopped_by_deviation", r.envelope.bounded}}},
      {"tets",
       {{"tets", r.quality.tets},
        {"vertices", r.quality.vertices},
        {"min_dihedral_deg", r.quality.min_dihedral},
        {"max_dihedral_deg", r.quality.max_dihedral},
        {"min_tet_volume", r.quality.min_volume},
        {"min_edge", r.quality.min_edge},
        {"mean_edge", r.quality.mean_edge},
        {"min_edge_ratio", r.quality.mean_edge > 0 ? r.quality.min_edge / r.quality.mean_edge : 0.0},
        {"volume", r.quality.volume},
        {"volume_ratio", r.input_volume > 0 ? r.quality.volume / r.input_volume : 0.0},
        {"components", r.quality.components},
        {"faces_shared_by_more_than_two", r.quality.overshared_faces},
        {"attempts", r.tet_stats.attempts},
        {"edge_length", r.tet_stats.edge_length},
        {"boundary_splits", r.tet_stats.boundary_splits},
        {"steiner_points", r.tet_stats.steiner_points},
        {"conforming", r.tet_stats.conforming},
        {"peeled_slivers", r.tet_stats.peeled}}},
      {"coverage",
       {{"inside_fraction", r.inside_fraction},
        {"within_tolerance_fraction", r.covered_fraction},
        {"max_outside_distance", r.max_outside_distance},
        {"max_outside_distance_fraction", frac(r.max_outside_distance)},
        {"deviation_sample_spacing", r.deviation_sample_spacing}}},
      {"seconds", seconds}};
}

}  // namespace squeeze::meshing
