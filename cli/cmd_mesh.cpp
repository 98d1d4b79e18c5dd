// `squeeze mesh INPUT -o OUT`: convex shells and one coarse tetrahedral mesh of any surface.
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <spdlog/spdlog.h>

#include "commands.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/log.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/mesh_pipeline.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

// --facet-distance when --target-tets is not given (fraction of the diagonal).
constexpr double kBoundaryFirstFacetDistance = 0.007;
// --sliver-bound when --target-tets is not given (degrees).
constexpr double kBoundaryFirstSliverBound = 6.0;

struct MeshArgs {
  std::string input, output, shells, report;
  meshing::MeshOptions options;
};


}  // namespace

Runner add_mesh_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand(
      "mesh",
      "Decompose a surface into convex shells and tetrahedralize them into one coarse tetrahedral mesh.\n"
      "INPUT: any surface assimp reads (OFF, OBJ, PLY, STL, glTF, ...); open, self-intersecting and\n"
      "non-manifold scans are fine. OUT: " + meshing::tet_format_list(true) + ".\n"
      "Example: squeeze mesh bunny.off -o bunny.mesh --shells shells.off --report report.json");
  cmd->add_option("INPUT", args->input, "Input surface")->required();
  cmd->add_option("-o,--output", args->output, "Output tetrahedral mesh; the format follows the extension")->required();
  cmd->add_option("--concavity", args->options.decomposition.concavity,
                  "Split pieces until their concavity (depth of the deepest surface point below the piece's "
                  "convex hull) is at most this fraction of the bounding-box diagonal")
      ->capture_default_str();
  cmd->add_option("--max-hulls", args->options.decomposition.max_hulls,
                  "At most this many convex shells (and at most target-tets / tets-per-hull)")
      ->capture_default_str();
  CLI::Option* target = cmd->add_option("--target-tets", args->options.tetrahedralize.target_tets,
                  "Desired number of tetrahedra (met within about 35%); the planner's cost grows with it. "
                  "Without it: up to --max-hulls shells and a boundary within 0.7% of the diagonal, "
                  "whatever count that needs (at most 5000)")
      ->capture_default_str();
  cmd->add_option("--tets-per-hull", args->options.tets_per_hull,
                  "The hull budget is at most target-tets / this (0: --max-hulls alone)")
      ->capture_default_str();
  cmd->add_option("--voxel-resolution", args->options.decomposition.voxel_resolution,
                  "Voxels along the longest side for inside/outside and cut evaluation")
      ->capture_default_str();
  CLI::Option* facet = cmd->add_option("--facet-distance", args->options.tetrahedralize.facet_distance,
                  "Largest distance of boundary facets from the shells, as a fraction of the diagonal "
                  "(0: a fifth of the cell size, which follows --target-tets)")
      ->capture_default_str();
  cmd->add_option("--offset", args->options.tetrahedralize.offset,
                  "Dilation of the shells before meshing, as a fraction of the diagonal (keeps their corners inside)")
      ->capture_default_str();
  CLI::Option* sliver = cmd->add_option("--sliver-bound", args->options.tetrahedralize.sliver_bound,
                  "Degrees: Mesh_3's sliver perturber and exuder work on tetrahedra with a smaller dihedral angle "
                  "(without --target-tets: 6)")
      ->capture_default_str();
  cmd->add_option("--shells", args->shells,
                  "Also write the convex shells as one surface file (" + meshing::surface_format_examples() + ")");
  cmd->add_option("--report", args->report, "Also write a JSON report (input, hulls, tets, quality, coverage, seconds)");

  return [args, &global, target, facet, sliver]() -> int {
    MeshArgs& a = *args;
    if (target->count() == 0) {
      // No target: the boundary-first defaults (as before targets were honoured on curved input),
      // which keep the tet volume within 1.35 of the input's on the corpus.
      a.options.tets_per_hull = 0;
      if (facet->count() == 0) a.options.tetrahedralize.facet_distance = kBoundaryFirstFacetDistance;
      // Perturbing to 10 degrees costs seconds on these fine boundaries (the bunny: 5 s instead of
      // 0.3 s); boundary slivers are still peeled at min_dihedral.
      if (sliver->count() == 0) a.options.tetrahedralize.sliver_bound = kBoundaryFirstSliverBound;
    }
    // Fail fast, before any work, on outputs that cannot be written.
    if (!meshing::is_tet_format(a.output))
      throw InputError(a.output + ": unknown tetrahedral mesh format (use " + meshing::tet_format_list() + ")");
    check_output_directory(a.output);
    if (!a.shells.empty()) {
      if (!meshing::is_surface_format(a.shells))
        throw InputError(a.shells + ": unknown surface format (use " + meshing::surface_format_examples() + ")");
      check_output_directory(a.shells);
    }
    if (!a.report.empty()) check_output_directory(a.report);
    if (!(a.options.decomposition.concavity > 0)) throw InputError("--concavity must be > 0");
    if (a.options.decomposition.max_hulls < 1) throw InputError("--max-hulls must be at least 1");
    if (a.options.tetrahedralize.target_tets < 1) throw InputError("--target-tets must be at least 1");
    if (!(a.options.tets_per_hull >= 0)) throw InputError("--tets-per-hull must be >= 0");
    if (!(a.options.tetrahedralize.facet_distance >= 0)) throw InputError("--facet-distance must be >= 0");

    Progress progress(!global.quiet);
    meshing::MeshResult r = meshing::mesh_file(a.input, a.options, &progress);
    progress.finish();
    if (r.quality.min_dihedral < 5.0)
      spdlog::warn("{}: smallest dihedral angle {:.2f} deg is below 5 deg", a.input, r.quality.min_dihedral);
    if (r.decomposition.hit_max_hulls)
      spdlog::info("{}: stopped at the hull budget {} with concavity {:.4g} above the threshold {:.4g}", a.input,
                   r.hull_budget, r.decomposition.max_concavity, r.decomposition.threshold);

    meshing::save_tet_mesh(a.output, r.tets);
    if (!a.shells.empty()) meshing::save_surface(a.shells, meshing::shells_surface(r.decomposition));
    if (!a.report.empty()) {
      const auto json = meshing::mesh_report(r, a.input);
      write_atomically(a.report, [&](const fs::path& tmp) {
        std::ofstream out(tmp);
        out << json.dump(2) << '\n';
        if (!out) throw InputError(a.report + ": write failed");
      });
    }
    if (!global.quiet) {
      double total = 0;
      for (const auto& s : r.seconds) total += s.second;
      std::fprintf(stderr,
                   "squeeze: %s: %zu convex shells (max concavity %.3g%% of diagonal), %d tetrahedra, %d vertices, "
                   "dihedral %.1f..%.1f deg, min/mean edge %.2f, volume ratio %.3f, %.2f%% of input vertices covered, "
                   "%.2f s\n",
                   a.input.c_str(), r.decomposition.shells.size(),
                   100.0 * r.decomposition.max_concavity / meshing::bounding_box_diagonal(r.input.V), r.quality.tets,
                   r.quality.vertices, r.quality.min_dihedral, r.quality.max_dihedral,
                   r.quality.mean_edge > 0 ? r.quality.min_edge / r.quality.mean_edge : 0.0, r.input_volume > 0 ? r.quality.volume / r.input_volume : 0.0, 100.0 * r.covered_fraction, total);
    }
    return kExitOk;
  };
}

}  // namespace squeeze::cli
