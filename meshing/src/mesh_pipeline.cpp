#include "squeeze/meshing/mesh_pipeline.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <algorithm>
#include <cmath>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_locator.h"

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

MeshResult mesh_surface(const SurfaceMesh& surface, const MeshOptions& opt, Progress* progress) {
  if (!(opt.coverage_tolerance >= 0)) throw InputError("coverage tolerance must be >= 0");
  if (!(opt.tets_per_hull >= 0)) throw InputError("tets_per_hull must be >= 0");
  if (opt.tetrahedralize.target_tets < 1) throw InputError("--target-tets must be at least 1");
  MeshResult r;
  StageTimer timer(r, progress);
  timer.start("analysing input");
  r.input.V = surface.V;
  r.input.F = orient_outward(surface.V, surface.F);
  r.info = analyse_surface(r.input);
  if (opt.check_self_intersection) r.info.self_intersecting = does_self_intersect(r.input);
  const double diag = bounding_box_diagonal(r.input.V);
  if (!(diag > 0)) throw InputError("input has zero extent (all vertices coincide)");

  timer.start("decomposing");
  DecompositionOptions dopt = opt.decomposition;
  if (dopt.max_hulls >= 1) dopt.max_hulls = hull_budget(opt);
  r.hull_budget = dopt.max_hulls;
  r.decomposition = decompose(r.input, dopt, progress);
  r.input_volume_from_winding_number = !r.info.closed;
  r.input_volume = r.info.closed ? r.info.volume : r.decomposition.solid_volume;
  if (!r.info.closed) r.info.volume = r.input_volume;

  timer.start("tetrahedralizing");
  r.tets = tetrahedralize(r.decomposition.shells, opt.tetrahedralize, &r.tet_stats, progress, &r.input.V);
  if (r.tets.T.rows() == 0) throw InputError("tetrahedralization produced no tetrahedra");

  timer.start("measuring");
  r.quality = tet_quality(r.tets);
  const TetLocator locator(r.tets);
  const Eigen::Index n = r.input.V.rows();
  std::vector<double> dist(static_cast<size_t>(n), 0.0);
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    if (locator.locate(r.input.V.row(i)) >= 0) return;
    double d = 0;
    locator.nearest(r.input.V.row(i), &d);
    dist[static_cast<size_t>(i)] = d;
  });
  Eigen::Index inside = 0, covered = 0;
  for (double d : dist) {
    inside += d == 0.0;
    covered += d <= opt.coverage_tolerance * diag;
    r.max_outside_distance = std::max(r.max_outside_distance, d);
  }
  r.inside_fraction = static_cast<double>(inside) / static_cast<double>(n);
  r.covered_fraction = static_cast<double>(covered) / static_cast<double>(n);
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
  return json{
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
        {"volume_method", r.input_volume_from_winding_number ? "winding_number" : "divergence"}}},
      {"decomposition",
       {{"hulls", r.decomposition.shells.size()},
        {"max_concavity", r.decomposition.max_concavity},
        {"max_concavity_fraction", diag > 0 ? r.decomposition.max_concavity / diag : 0.0},
        {"concavity_threshold", r.decomposition.threshold},
        {"hit_max_hulls", r.decomposition.hit_max_hulls},
        {"hull_budget", r.hull_budget}}},
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
        {"mesh3_attempts", r.tet_stats.attempts},
        {"cell_size", r.tet_stats.cell_size},
        {"facet_distance", r.tet_stats.facet_distance},
        {"offset", r.tet_stats.offset},
        {"peeled_slivers", r.tet_stats.peeled_slivers}}},
      {"coverage",
       {{"inside_fraction", r.inside_fraction},
        {"within_tolerance_fraction", r.covered_fraction},
        {"max_outside_distance", r.max_outside_distance},
        {"max_outside_distance_fraction", diag > 0 ? r.max_outside_distance / diag : 0.0}}},
      {"seconds", seconds}};
}

}  // namespace squeeze::meshing
