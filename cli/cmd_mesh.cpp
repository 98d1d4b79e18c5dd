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

struct MeshArgs {
  std::string input, output, shells, report;
  meshing::MeshOptions options;
  double facet_distance = 0;  // --facet-distance (before version 4; now --max-deviation)
  double offset = 0;          // --offset (before version 4; no longer used)
};


}  // namespace

Runner add_mesh_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand(
      "mesh",
      "Tetrahedralize a surface into a coarse mesh of its own shape: each closed part's boundary,\n"
      "simplified within --max-deviation, is tetrahedralized (a part much thinner than its tetrahedra,\n"
      "a plate or a bowl: one layer of prisms across its thickness, the report's thin_parts; a CAD\n"
      "part whose long, thin triangles do not tetrahedralize: its surface remeshed into round ones\n"
      "first, the report's parts_remeshed); open\n"
      "sheets (one layer of triangles: a curtain, a cloth) become thin slabs around them\n"
      "(--sheet-thickness), one layer of prisms; open scans of solids (holes) and inputs with welded,\n"
      "non-manifold or self-intersecting segments become the solid their winding number encloses (a\n"
      "scan whose holes are wider than the bound, judged by their outlines: its slab, as a sheet, tried\n"
      "first; where no slab holds, and for welded segments, the solid hollowed where the outside\n"
      "reaches in through the holes, a shell around their rims instead of caps over them): its\n"
      "boundary, found by CGAL Mesh_3, simplified within --max-deviation of the input and\n"
      "tetrahedralized (--winding: Mesh_3's own tetrahedra; --shells-fallback: their convex shells,\n"
      "the paper's method; --wrap: their alpha wrap, a closed surface just outside them, meshed like a\n"
      "boundary); the report's method and fallback_because say which and why, target_exceeded_because\n"
      "why the count is off the target, and deviation_exceeded_because (also warned) why the boundary\n"
      "lies over 1.5 times --max-deviation off the input (the convex shells; caps over wide holes), or\n"
      "the input over 1.5 times the inner bound (0.45 of it) outside the mesh.\n"
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
  cmd->add_option("--target-tets", args->options.tetrahedralize.target_tets,
                  "Desired number of tetrahedra (met within about 35% when the boundary allows; a boundary that "
                  "needs more gets more, and the report says why); the planner's cost grows with it")
      ->capture_default_str();
  cmd->add_option("--max-deviation", args->options.max_deviation,
                  "Largest distance of the tetrahedral mesh's boundary from the input surface, as a fraction of the "
                  "bounding-box diagonal; input surface points may lie outside the mesh by at most 0.45 of it")
      ->capture_default_str();
  cmd->add_flag("--winding", args->options.winding,
                "Inputs that are not closed parts: keep CGAL Mesh_3's tetrahedra of their winding-number solid "
                "as they are (before meshing version 11; the default simplifies that solid's boundary against the "
                "input and tetrahedralizes it: fewer tetrahedra within the same bounds)");
  cmd->add_flag("--shells-fallback", args->options.shells_fallback,
                "Inputs with welded, non-manifold or self-intersecting segments: mesh their convex shells with "
                "Mesh_3 (the paper's method, before meshing version 11): a few hundred tetrahedra, but 1.1-1.6 "
                "times their volume and several % of the diagonal out. Where Mesh_3 cannot mesh the shells around "
                "the input (a part thinner than its cells), the default route instead (the report's fallback_because)");
  cmd->add_flag("--shells-only", args->options.shells_only,
                "Mesh every input, closed parts too, as its convex shells with Mesh_3 (the paper's coarse meshes, "
                "looser than the deviation bounds): a simulation cage for a tight mesh embedded in it (scene key "
                "objects[].simulation_mesh). Where Mesh_3 cannot mesh the shells around the input (a part thinner "
                "than its cells), the default route instead (the report's fallback_because)");
  cmd->add_option("--winding-facet-distance", args->options.winding_facet_distance,
                  "Inputs that are not closed parts: Mesh_3's facet distance on their winding-number solid, as a "
                  "multiple of --max-deviation (smaller: closer to the input inside, more tetrahedra and seconds)")
      ->capture_default_str();
  cmd->add_option("--winding-dilation", args->options.winding_dilation,
                  "Open scans of solids, --winding, and a closed part meshed as its own winding-number solid: how far "
                  "the solid is grown around the input surface, as a multiple of --max-deviation (larger: boundary "
                  "chords stay outside the input, deviation_out and the volume grow by as much)")
      ->capture_default_str();
  cmd->add_option("--winding-surface-dilation", args->options.winding_surface_dilation,
                  "Welded, non-manifold or self-intersecting segments (the default route): how far their winding-number "
                  "solid, whose boundary is simplified and tetrahedralized, is grown around the input surface, as a "
                  "multiple of --max-deviation (larger: fewer tetrahedra and seconds, more volume and overlap with "
                  "touching parts)")
      ->capture_default_str();
  cmd->add_flag("--wrap", args->options.wrap,
                "Inputs that are not closed parts: mesh their alpha wrap (closed, just outside them) instead of "
                "their convex shells; tighter (volume, deviation) but more tetrahedra and seconds");
  cmd->add_option("--wrap-alpha", args->options.wrap_alpha,
                  "With --wrap: the alpha wrap's alpha (gaps, holes and cavities narrower than this are filled), "
                  "as a multiple of --max-deviation")
      ->capture_default_str();
  cmd->add_option("--wrap-offset", args->options.wrap_offset,
                  "With --wrap: how far outside the input the alpha wrap lies, as a multiple of --max-deviation")
      ->capture_default_str();
  cmd->add_option("--sheet-thickness", args->options.sheet_thickness,
                  "Open sheets (one layer of triangles enclosing no volume: a curtain, a cloth) are meshed as slabs "
                  "this thick, the sheet in the middle, as a multiple of --max-deviation times the bounding-box "
                  "diagonal (the report's sheets.thickness)")
      ->capture_default_str();
  cmd->add_option("--dense-faces", args->options.dense_faces,
                  "Inputs of more triangles (a fine scan) are meshed through a proxy decimated by quadric error "
                  "within a tenth of the inner bound of them, and measured against the input itself (the report's "
                  "proxy; 0: never)")
      ->capture_default_str();
  cmd->add_option("--dense-min-saving", args->options.dense_min_saving,
                  "With --dense-faces: the proxy is meshed only where it has at least this many triangles fewer "
                  "than the input; else the input itself is")
      ->capture_default_str();
  cmd->add_option("--tets-per-hull", args->options.tets_per_hull,
                  "The hull budget is at most target-tets / this (0: --max-hulls alone)")
      ->capture_default_str();
  cmd->add_option("--voxel-resolution", args->options.decomposition.voxel_resolution,
                  "Voxels along the longest side for inside/outside and cut evaluation")
      ->capture_default_str();
  CLI::Option* facet = cmd->add_option("--facet-distance", args->facet_distance,
                  "Before meshing version 4: the largest distance of boundary facets from the shells; now the same "
                  "as --max-deviation (0: not given)")
      ->capture_default_str();
  CLI::Option* offset = cmd->add_option("--offset", args->offset,
                  "Before meshing version 4: a dilation of the shells; version 4 meshes the input's own boundary "
                  "and does not dilate (accepted and ignored)")
      ->capture_default_str();
  cmd->add_option("--sliver-bound", args->options.tetrahedralize.sliver_bound,
                  "Degrees: the sliver exuder works on tetrahedra with a smaller dihedral angle")
      ->capture_default_str();
  cmd->add_option("--shells", args->shells,
                  "Also write the convex shells as one surface file (" + meshing::surface_format_examples() + ")");
  cmd->add_option("--report", args->report, "Also write a JSON report (input, hulls, tets, quality, coverage, seconds)");

  return [args, &global, facet, offset]() -> int {
    MeshArgs& a = *args;
    if (facet->count() > 0) {
      if (!(a.facet_distance >= 0)) throw InputError("--facet-distance must be >= 0");
      if (a.facet_distance > 0) {
        spdlog::warn("--facet-distance is --max-deviation since meshing version 4: using --max-deviation {}",
                     a.facet_distance);
        a.options.max_deviation = a.facet_distance;
      }
    }
    if (offset->count() > 0) spdlog::warn("--offset is ignored since meshing version 4 (the mesh is not dilated)");
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
    if (!(a.options.max_deviation > 0 && a.options.max_deviation < 1))
      throw InputError("--max-deviation must be between 0 and 1 (a fraction of the bounding-box diagonal)");
    if (!(a.options.tetrahedralize.sliver_bound >= 0 && a.options.tetrahedralize.sliver_bound < 90))
      throw InputError("--sliver-bound must be between 0 and 90 degrees");

    Progress progress(!global.quiet);
    meshing::MeshResult r = meshing::mesh_file(a.input, a.options, &progress);
    progress.finish();
    if (r.quality.min_dihedral < a.options.tetrahedralize.min_dihedral)
      spdlog::warn("{}: smallest dihedral angle {:.2f} deg is below {} deg", a.input, r.quality.min_dihedral,
                   a.options.tetrahedralize.min_dihedral);
    if (!r.deviation_exceeded_because.empty()) spdlog::warn("{}: {}", a.input, r.deviation_exceeded_because);
    if (!r.target_exceeded_because.empty())
      spdlog::info("{}: {} tetrahedra for a target of {}: {}", a.input, r.quality.tets, r.target_tets,
                   r.target_exceeded_because);
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
      const double diag = meshing::bounding_box_diagonal(r.input.V);
      // The report's volume_ratio (closed inputs); where the input is not closed, the ratio to its
      // winding-number volume, named so (a hollowed open scan's mesh is a shell: trimesh's bunny,
      // 0.170, is not a mesh that lost most of its volume); none where the input encloses no volume
      // that can be measured (a sheet, an open scan whose winding-number volume is not positive).
      char ratio[64] = "volume ratio n/a";
      if (r.volume_ratio)
        std::snprintf(ratio, sizeof ratio, "volume ratio %.3f", *r.volume_ratio);
      else if (r.input_volume > 0)
        std::snprintf(ratio, sizeof ratio, "winding-number volume ratio %.3f", r.quality.volume / r.input_volume);
      std::fprintf(stderr,
                   "squeeze: %s: %zu convex shells (max concavity %.3g%% of diagonal), %d tetrahedra, %d vertices, "
                   "dihedral %.1f..%.1f deg, %s, deviation out %.3g%% / in %.3g%% of diagonal, %.2f s\n",
                   a.input.c_str(), r.decomposition.shells.size(), 100.0 * r.decomposition.max_concavity / diag,
                   r.quality.tets, r.quality.vertices, r.quality.min_dihedral, r.quality.max_dihedral, ratio,
                   100.0 * r.deviation_out / diag, 100.0 * r.deviation_in / diag, total);
    }
    return kExitOk;
  };
}

}  // namespace squeeze::cli
