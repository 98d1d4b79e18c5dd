// The squeeze command line: each subcommand registers itself on the CLI11 app and returns the
// callback that runs it (after parsing), which returns the process exit code.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>

namespace squeeze::cli {

/// Options shared by every subcommand.
struct Global {
  bool quiet = false;
  int verbose = 0;
  int threads = 0;  // 0: all cores
};

using Runner = std::function<int()>;

Runner add_mesh_command(CLI::App& app, const Global& global);
Runner add_deform_command(CLI::App& app, const Global& global);
Runner add_simulate_command(CLI::App& app, const Global& global);
Runner add_plan_command(CLI::App& app, const Global& global);    // cmd_plan.cpp
Runner add_replay_command(CLI::App& app, const Global& global);  // cmd_plan.cpp
Runner add_render_command(CLI::App& app, const Global& global);  // cmd_render.cpp
Runner add_run_command(CLI::App& app, const Global& global);     // cmd_run.cpp (squeeze run)
Runner add_bench_command(CLI::App& app, const Global& global);   // cmd_bench.cpp (squeeze bench table1)
Runner add_check_command(CLI::App& app, const Global& global);   // cmd_check.cpp (squeeze check)

/// Exit codes.
constexpr int kExitOk = 0;
constexpr int kExitInputError = 1;   // bad input, configuration or output path
constexpr int kExitUsage = 2;        // bad command line
constexpr int kExitNotSolved = 3;    // planner: no solution (an approximate plan was written)

}  // namespace squeeze::cli
