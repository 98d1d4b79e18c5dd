// squeeze — plans and renders the motion of deformable objects among deformable and rigid
// obstacles (Rodriguez, Lien, Amato, ICRA 2006, and beyond).
#include <tbb/global_control.h>

#include <cstdio>
#include <iostream>
#include <memory>

#include "commands.h"
#include "squeeze/common/error.h"
#include "squeeze/common/log.h"

int main(int argc, char** argv) {
  using namespace squeeze::cli;
  CLI::App app{
      "squeeze: motion planning for deformable objects among deformable and rigid obstacles.\n"
      "Pipeline: mesh (convex shells -> coarse tetrahedral mesh) -> ffd -> fem -> plan -> render.\n"
      "Run `squeeze COMMAND --help` for a command's options."};
  app.require_subcommand(1);
  Global global;
  app.add_flag("-q,--quiet", global.quiet, "Print errors only (no progress, no warnings)");
  app.add_flag("-v,--verbose", global.verbose, "More detail on stderr (-vv for debug output)");
  app.add_option("-j,--threads", global.threads, "Worker threads (default: all cores); results do not depend on it")
      ->check(CLI::NonNegativeNumber);
  app.set_version_flag("--version", "squeeze 0.1.0");
  app.fallthrough();

  const Runner mesh = add_mesh_command(app, global);
  const Runner deform = add_deform_command(app, global);
  const Runner simulate = add_simulate_command(app, global);
  const Runner plan = add_plan_command(app, global);
  const Runner replay = add_replay_command(app, global);
  const Runner render = add_render_command(app, global);
  const Runner bench = add_bench_command(app, global);
  const Runner run = add_run_command(app, global);
  const Runner check = add_check_command(app, global);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::fprintf(stderr, "squeeze: error: %s (see squeeze --help)\n", e.what());
    return kExitUsage;
  }
  squeeze::set_verbosity(global.quiet          ? squeeze::Verbosity::quiet
                         : global.verbose >= 2 ? squeeze::Verbosity::debug
                         : global.verbose == 1 ? squeeze::Verbosity::verbose
                                               : squeeze::Verbosity::normal);
  std::unique_ptr<tbb::global_control> threads;
  if (global.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    static_cast<size_t>(global.threads));
  try {
    for (CLI::App* sub : app.get_subcommands()) {
      if (sub->get_name() == "mesh") return mesh();
      if (sub->get_name() == "deform") return deform();
      if (sub->get_name() == "simulate") return simulate();
      if (sub->get_name() == "plan") return plan();
      if (sub->get_name() == "replay") return replay();
      if (sub->get_name() == "render") return render();
      if (sub->get_name() == "bench") return bench();
      if (sub->get_name() == "run") return run();
      if (sub->get_name() == "check") return check();
    }
  } catch (const squeeze::InputError& e) {
    std::fprintf(stderr, "squeeze: error: %s\n", e.what());
    return kExitInputError;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "squeeze: error: out of memory\n");
    return kExitInputError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "squeeze: internal error: %s\n", e.what());
    return 70;
  }
  return kExitUsage;
}
