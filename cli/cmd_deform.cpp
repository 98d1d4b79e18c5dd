// `squeeze deform SURFACE REST_TETS DEFORMED_TETS -o OUT`: free-form deformation of a
// high-resolution surface by a coarse tetrahedral mesh (bind to the rest state, replay the
// deformed one).
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <spdlog/spdlog.h>

#include "commands.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/ffd/ffd.h"
#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"
#include "squeeze/meshing/tet_geometry.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

struct DeformArgs {
  std::string surface, rest, deformed, output;
  ffd::BindOptions options;
};

}  // namespace

Runner add_deform_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<DeformArgs>();
  CLI::App* cmd = app.add_subcommand(
      "deform",
      "Bind a high-resolution surface to a coarse tetrahedral mesh and replay a deformation of that mesh on it\n"
      "(free-form deformation by barycentric coordinates). Vertices outside the mesh follow their nearest\n"
      "tetrahedron. SURFACE: OFF, OBJ, PLY, STL, glTF, ...; REST_TETS and DEFORMED_TETS: any format `squeeze mesh`\n"
      "writes, with the same vertices and tetrahedra. OUT keeps SURFACE's vertices and faces in order (STL has\n"
      "no shared vertices: every facet corner is a vertex); .off/.obj are written in full precision,\n"
      "assimp formats (.ply, .stl, .glb, ...) in single precision.\n"
      "Example: squeeze deform bunny.off bunny.mesh squashed.mesh -o squashed_bunny.ply");
  cmd->add_option("SURFACE", args->surface, "High-resolution surface to deform")->required();
  cmd->add_option("REST_TETS", args->rest, "Coarse tetrahedral mesh in its rest state (e.g. from `squeeze mesh`)")
      ->required();
  cmd->add_option("DEFORMED_TETS", args->deformed, "The same mesh deformed (same connectivity)")->required();
  cmd->add_option("-o,--output", args->output, "Deformed surface; the format follows the extension")->required();
  cmd->add_option("--max-outside", args->options.max_outside,
                  "Fail if a surface vertex lies farther than this fraction of its bounding-box diagonal outside "
                  "the tetrahedral mesh (default: no limit; such vertices follow their nearest tetrahedron)")
      ->check(CLI::NonNegativeNumber);

  return [args, &global]() -> int {
    DeformArgs& a = *args;
    const auto start = std::chrono::steady_clock::now();
    // Fail fast, before any work, on outputs that cannot be written.
    if (!meshing::is_surface_format(a.output))
      throw InputError(a.output + ": unknown surface format (use " + meshing::surface_format_examples() + ")");
    check_output_directory(a.output);

    meshing::LoadOptions load;
    load.keep_order = true;  // the output matches the input vertex for vertex, face for face
    meshing::SurfaceMesh surface = meshing::load_surface(a.surface, load);
    const meshing::TetMesh rest = meshing::load_tet_mesh(a.rest);
    const meshing::TetMesh deformed = meshing::load_tet_mesh(a.deformed);
    ffd::check_same_connectivity(rest, deformed, a.rest, a.deformed);
    const Eigen::VectorXd rest_volumes = meshing::tet_volumes(rest);
    if (rest_volumes.minCoeff() <= 0)
      spdlog::warn("{}: {} tetrahedra have zero or negative volume; vertices in them cannot be bound reliably", a.rest,
                   (rest_volumes.array() <= 0).count());
    const Eigen::VectorXd volumes = meshing::tet_volumes(deformed);
    if (volumes.minCoeff() <= 0)
      spdlog::warn("{}: {} of {} tetrahedra are inverted or flat; the surface inside them turns inside out",
                   a.deformed, (volumes.array() <= 0).count(), volumes.size());

    Progress progress(!global.quiet);
    const ffd::Binding binding = ffd::bind_surface(surface.V, rest, a.options, &progress, a.surface);
    const double diagonal = meshing::bounding_box_diagonal(surface.V);
    if (binding.outside > 0)
      spdlog::info("{}: {} of {} vertices lie outside {}, at most {:.4g} ({:.3g}% of the diagonal) away; they follow "
                   "their nearest tetrahedron",
                   a.surface, binding.outside, surface.V.rows(), a.rest, binding.max_outside_distance,
                   100.0 * binding.max_outside_distance / diagonal);
    Eigen::MatrixX3d moved;
    replay(binding, deformed.V, moved);
    const double displacement = (moved - surface.V).rowwise().norm().maxCoeff();
    surface.V = moved;
    meshing::save_surface(a.output, surface);

    if (!global.quiet) {
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr,
                   "squeeze: %s: %lld vertices bound to %lld tetrahedra (%d outside, at most %.3g%% of the diagonal "
                   "away), largest displacement %.4g (%.3g%% of the diagonal), %.2f s\n",
                   a.surface.c_str(), static_cast<long long>(surface.V.rows()),
                   static_cast<long long>(rest.T.rows()), binding.outside,
                   100.0 * binding.max_outside_distance / diagonal, displacement, 100.0 * displacement / diagonal,
                   seconds);
    }
    return kExitOk;
  };
}

}  // namespace squeeze::cli
