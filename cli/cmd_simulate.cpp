// `squeeze simulate SCENE --duration S -o DIR [--fps 30]`: simulates a JSON scene without planning
// and writes DIR/metrics.csv and DIR/trajectory/ (formats in scenes/README.md).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "scene_options.h"
#include "trajectory_writer.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/integrator.h"
#include "squeeze/fem/scene.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

struct SimulateArgs {
  std::string scene, output, integrator;
  double duration = 0, fps = 30;
};


}  // namespace

Runner add_simulate_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Simulate a JSON scene (no planning): deformable and rigid objects, gravity, floor, collisions.\n"
      "Writes DIR/metrics.csv (one row per frame) and DIR/trajectory/ (index.json, rest meshes, one\n"
      "binary frame of float64 positions per output frame). Scene and output formats: scenes/README.md.\n"
      "Example: squeeze simulate scenes/cube_drop.json --duration 2 -o out/cube");
  cmd->add_option("SCENE", args->scene, "Scene file (JSON)")->required();
  cmd->add_option("--duration", args->duration, "Simulated time (s), > 0")->required();
  cmd->add_option("-o,--output", args->output, "Output directory (created if missing; its parent must exist)")
      ->required();
  cmd->add_option("--fps", args->fps, "Output frames per simulated second, > 0")->capture_default_str();
  add_integrator_option(cmd, args->integrator);

  return [args, &global]() -> int {
    SimulateArgs& a = *args;
    if (!(a.duration > 0) || !std::isfinite(a.duration)) throw InputError("--duration must be > 0");
    if (!(a.fps > 0) || !std::isfinite(a.fps)) throw InputError("--fps must be > 0");
    const double frames_d = std::floor(a.duration * a.fps + 1e-9);
    if (frames_d > 1e7) throw InputError("--duration × --fps: too many frames (at most 10 million)");
    const int frames = static_cast<int>(frames_d) + 1;  // t = 0, 1/fps, ..., <= duration
    check_output_folder(a.output);

    // All input checks (scene, meshes, bodies) before anything is written.
    Progress progress(!global.quiet);
    fem::Scene scene = load_scene_with(a.scene, a.integrator);
    fem::SceneWorld w = fem::build_scene(scene, &progress);
    {
      std::optional<double> limit;  // the planner block is not simulate's to validate: no limit if it is bad
      try {
        limit = scene_volume_limit(w);
      } catch (const InputError&) {
      }
      print_scene_warnings(w, limit, 0.0);  // squeeze check's warnings; the simulation is the settle
    }
    const double interval = 1.0 / a.fps;
    const double substeps_d = std::ceil(interval / w.time_step() - 1e-9);
    if (!(substeps_d <= 1e8))  // never a wrapped-around count: a step that cannot be honoured is an error
      throw InputError(a.scene + ": time_step " + format_number(w.time_step()) + " s: " + format_number(substeps_d) +
                       " steps per frame interval of --fps " + format_number(a.fps) + " (at most 100 million)");
    const int substeps = std::max(1, static_cast<int>(substeps_d));
    const double h = interval / substeps;
    w.set_time_step(h);  // divides the frame interval, never larger than the scene's step
    const int nobj = w.world.bodies();
    spdlog::info("time step {}{}", w.time_step_choice.describe(scene),
                 h != w.time_step_choice.h ? ", lowered to " + std::to_string(h) + " s to divide the frame interval" : "");

    FolderReplacement out(a.output);  // the new output beside the old one, swapped in whole by commit()
    TrajectoryWriter writer(w, out.staging(), a.fps, h, frames);
    fem::State s = w.initial_state();
    progress.stage("simulating", frames);
    for (int f = 0; f < frames; ++f) {
      bool diverged = fem::diverged(s);
      if (f > 0)
        for (int k = 0; k < substeps && !diverged; ++k) {
          w.step(s);
          diverged = fem::diverged(s);  // the planner's test (Validity::diverged)
        }
      if (diverged)
        throw InputError(a.scene + ": the simulation diverged before t = " + format_number(f * interval) +
                         " s: lower time_step or the material stiffness");
      writer.add_frame(s, f * interval);
      progress.update(f + 1);
    }
    progress.finish();
    writer.commit();
    out.commit();
    spdlog::info("{}", describe_integrator_stats(w.world));
    if (!global.quiet)
      std::fprintf(stderr, "squeeze: %s: %d objects, %d frames, time step %.3g s, wrote %s\n", a.scene.c_str(), nobj,
                   frames, h, a.output.c_str());
    return kExitOk;
  };
}

}  // namespace squeeze::cli
