// `squeeze plan SCENE -o PLAN.json`: kinodynamic RRT over the whole deformable state (plan/).
// `squeeze replay SCENE PLAN.json -o DIR`: re-simulates a plan and writes what `simulate` writes.
#include <tbb/global_control.h>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <spdlog/spdlog.h>

#include "commands.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/integrator.h"
#include "squeeze/fem/scene.h"
#include "squeeze/plan/plan_io.h"
#include "squeeze/plan/planner.h"
#include "plan_shared.h"
#include "scene_options.h"
#include "trajectory_writer.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

struct PlanArgs {
  std::string scene, output, integrator;
  long long seed = -1, iterations = -1;
  double time_limit = 0;
  int threads = 0;
};

struct ReplayArgs {
  std::string scene, plan, output;
  double fps = 30;
  double settle = -1;
};

}  // namespace

std::string hex64(std::uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, h);
  return buf;
}

PreparedPlanning prepare_planning(const fem::Scene& scene, const PlanOverrides& o, Progress& progress) {
  plan::robot_index(scene);  // errors about the robot before meshing
  fem::SceneWorld w = fem::build_scene(scene, &progress);  // meshes (cached)
  plan::check_planning_inputs(w);
  plan::PlannerOptions options = plan::planner_options(w);
  if (o.seed >= 0) options.seed = static_cast<std::uint64_t>(o.seed);
  if (o.iterations > 0) options.iterations = static_cast<int>(std::min<long long>(o.iterations, 100000000));
  options.time_limit = o.time_limit;
  return {std::move(w), options};
}

ReplayOutput write_replay(const fem::SceneWorld& world, const plan::PlanFile& f, const std::string& plan_name,
                          const fs::path& folder, double fps, int settle_steps, Progress& progress) {
  const fem::Scene& scene = world.scene;
  const double h = f.time_step;
  long long total = settle_steps;
  for (const auto& seg : f.path) total += seg.steps;
  const double duration = total * h;
  const double frames_d = std::floor(duration * fps + 1e-9);
  if (!(frames_d <= 1e7))  // the plan's length, not only --fps: say both
    throw InputError(plan_name + ": the path and settling last " + format_number(duration) + " s (" +
                     std::to_string(total) + " steps of time_step " + format_number(h) + " s): at --fps " +
                     format_number(fps) + " that is more than 10 million frames");
  fem::SceneWorld at_h = world;  // the plan's time step (a copy: nothing rebuilt)
  if (at_h.time_step() != f.time_step) at_h.set_time_step(f.time_step);
  // The plan's start: the scene settled without control for its start_settle_steps; volume changes
  // are measured against it, as the planner measured them.
  const fem::State start = plan::settle_start_state(at_h, 0, nullptr, f.start_settle_steps, &progress);
  if (fem::diverged(start))
    throw InputError(plan_name + ": start_settle_steps: the scene diverges while settling before the path at time_step " +
                     format_number(h) + " s");
  plan::PropagatorOptions po;
  po.stop_when_invalid = false;
  for (int b = 0; b < at_h.world.bodies(); ++b) po.reference_volume.push_back(at_h.world.body_volume(start, b));
  plan::SimulationPropagator p(at_h, po);  // a copy of the built world
  for (size_t i = 0; i < f.path.size(); ++i)
    f.path[i].control.kind->validate(f.path[i].control, p.robot(),
                                     plan_name + ": path[" + std::to_string(i) + "] does not fit the robot of " +
                                         scene.file.string() + " (the plan was made for another scene)");
  ReplayOutput out;
  out.frames = static_cast<int>(frames_d) + 1;

  fem::SceneWorld metrics_world = p.world();  // contacts for the metrics, apart from the replay
  TrajectoryWriter writer(metrics_world, folder, fps, h, out.frames);
  const fem::World& w = p.world().world;
  for (int b = 0; b < w.bodies(); ++b) out.names.push_back(scene.objects[b].name);
  out.max_volume_change.assign(w.bodies(), 0.0);
  // Frame k shows the state after step round(k / (fps h)) (within h/2 of t = k / fps).
  auto frame_step = [&](int k) { return std::llround(k / (fps * h)); };
  long long step = 0;
  int next = 1;
  const fem::State& s0 = start;
  fem::State settled = s0;
  // The summary's volume changes are those of the frames, against the start (frame 0): the numbers
  // the volume plot shows (render::render_trajectory plots every frame against frame 0).
  auto frame = [&](const fem::State& s, double t) {
    for (int b = 0; b < w.bodies(); ++b) {
      const double c = p.volume_change(s, b);
      if (!(c <= out.max_volume_change[b])) out.max_volume_change[b] = c;
    }
    writer.add_frame(s, t);
  };
  frame(s0, 0.0);
  progress.stage("replaying", static_cast<double>(total));
  const long long path_steps = total - settle_steps;
  p.on_step = [&](const fem::State& s, int) {
    ++step;
    if (fem::diverged(s))  // as the planner discards a diverged expansion (Validity::diverged)
      throw InputError(plan_name + ": the replay diverged at t = " + format_number(step * h) + " s (" +
                       (step <= path_steps ? "during the path: its controls" : "during the final settling: its settle values") +
                       " are too large for this scene at its time_step " + format_number(h) + " s)");
    if (step == total) settled = s;
    while (next < out.frames && frame_step(next) <= step) frame(s, next++ / fps);
    progress.update(static_cast<double>(step));
  };
  const std::vector<fem::State> ends = plan::replay(p, s0, f.path, f.settle, settle_steps);
  while (next < out.frames) frame(settled, next++ / fps);  // rounding at the very end
  progress.finish();
  writer.commit();
  out.hash = plan::state_hash(ends.empty() ? s0 : ends.back());
  out.integrator_stats = fem::describe_integrator_stats(p.world().world);
  out.matches = out.hash == f.final_state_hash;
  out.final_distance = scene.goal ? (p.goal_com(settled) - scene.goal->position).norm() : 0.0;
  out.duration = duration;
  return out;
}

Runner add_plan_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<PlanArgs>();
  CLI::App* cmd = app.add_subcommand(
      "plan",
      "Plan a motion of the scene's robot to its goal: a kinodynamic RRT whose nodes are full\n"
      "simulation states of the robot and every deformable obstacle (Rodriguez, Lien, Amato 2006).\n"
      "Writes PLAN.json (status, statistics, the path as controls from the start). Exit 0 when\n"
      "solved, 3 when not (an approximate plan is still written). Planner keys: scenes/README.md.\n"
      "Example: squeeze plan scenes/barriers1.json -o out/barriers1.plan.json --seed 3");
  cmd->add_option("SCENE", args->scene, "Scene file (JSON) with a robot and a goal")->required();
  cmd->add_option("-o,--output", args->output, "Plan file to write (JSON)")->required();
  cmd->add_option("--seed", args->seed, "Random seed (default: planner.seed of the scene, else 1)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--iterations", args->iterations, "Expansions to attempt at most (default: planner.iterations)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--time-limit", args->time_limit, "Stop after this many seconds of planning (0: no limit)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--threads", args->threads, "Worker threads (default: -j, else all cores); the plan does not depend on it")
      ->check(CLI::NonNegativeNumber);
  add_integrator_option(cmd, args->integrator);

  return [args, &global]() -> int {
    const PlanArgs& a = *args;
    std::unique_ptr<tbb::global_control> threads;
    if (a.threads > 0)
      threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      static_cast<size_t>(a.threads));
    check_output_directory(a.output);
    Progress progress(!global.quiet);
    const fem::Scene scene = load_scene_with(a.scene, a.integrator);
    const PreparedPlanning prep = prepare_planning(scene, {a.seed, a.iterations, a.time_limit}, progress);
    const plan::PlannerOptions& options = prep.options;
    print_scene_warnings(prep.world, options.max_volume_change, 0.1, &progress);  // squeeze check's warnings
    {
      const plan::MaxForceTerms t = plan::max_force_terms(prep.world);
      spdlog::info("{}: max_force {:.4g} N (default {:.4g} N = max of 2 m g {:.4g}, m d / t_max^2 {:.4g}, K d / 2 {:.4g}, "
                   "E A eps {:.4g}; m {:.4g} kg, d {:.4g} m, E {:.4g} Pa, A {:.4g} m^2)",
                   a.scene, options.max_force, t.max_force(options.t_max), 2 * t.mass * t.gravity,
                   t.mass * t.size / (options.t_max * options.t_max), 0.5 * t.attach_stiffness * t.size, t.squeeze(),
                   t.mass, t.size, t.youngs_modulus, t.cross_section);
    }
    const plan::PlanResult r = plan::plan(prep.world, options, &progress);

    const plan::PlanFile f = plan::make_plan_file(scene, options, r);
    plan::save_plan(a.output, f);
    if (!global.quiet) {
      const plan::PlanStatistics& s = r.stats;
      if (s.discarded_volume > 0) {
        std::string by;
        for (size_t b = 0; b < s.discarded_volume_by_object.size(); ++b)
          if (s.discarded_volume_by_object[b] > 0)
            by += (by.empty() ? "" : ", ") + scene.objects[b].name + " " + std::to_string(s.discarded_volume_by_object[b]);
        spdlog::warn("{}: {} expansions discarded for a volume change beyond planner.max_volume_change {:.3g} % "
                     "(measured against the settled start; by object: {})",
                     a.scene, s.discarded_volume, 100 * options.max_volume_change, by);
      }
      if (r.timed_out) spdlog::info("{}: planning stopped at --time-limit {:.3g} s", a.scene, a.time_limit);
      std::fprintf(stderr,
                   "squeeze: %s: %s after %d iterations (%d nodes, %d cut short; %d discarded: %d diverged, %d volume, %d bounds) "
                   "in %.1f s, %.1f it/s; distance to goal %.3g m (tolerance %.3g m); path of %zu segments, %.2f s; "
                   "%.0f bytes per node, peak memory %.0f MiB; wrote %s\n",
                   a.scene.c_str(), plan::to_string(r.status), s.iterations, s.nodes, s.truncated,
                   s.discarded_diverged + s.discarded_volume + s.discarded_bounds, s.discarded_diverged,
                   s.discarded_volume, s.discarded_bounds, s.seconds, s.seconds > 0 ? s.iterations / s.seconds : 0.0,
                   s.final_distance, scene.goal->tolerance, r.path.size(),
                   [&] {
                     long long n = 0;
                     for (const auto& seg : r.path) n += seg.steps;
                     return n * r.time_step;
                   }(),
                   s.bytes_per_node, s.peak_memory / 1048576.0, a.output.c_str());
    }
    return r.status == plan::PlanStatus::solved ? kExitOk : kExitNotSolved;
  };
}

Runner add_replay_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Re-simulate a plan from the start (the path's controls, then an interpolation phase that\n"
      "brings the robot to rest near the goal) and write DIR/metrics.csv and DIR/trajectory/ like\n"
      "`squeeze simulate`. Checks that the state at the end of the path equals the planner's bit for bit.\n"
      "Example: squeeze replay scenes/barriers1.json out/barriers1.plan.json -o out/barriers1");
  cmd->add_option("SCENE", args->scene, "Scene file (JSON) the plan was made for")->required();
  cmd->add_option("PLAN", args->plan, "Plan file written by `squeeze plan`")->required();
  cmd->add_option("-o,--output", args->output, "Output directory (created if missing; its parent must exist)")
      ->required();
  cmd->add_option("--fps", args->fps, "Output frames per simulated second, > 0")->capture_default_str();
  cmd->add_option("--settle", args->settle, "Seconds of the final interpolation phase (default: the plan's)")
      ->check(CLI::NonNegativeNumber);

  return [args, &global]() -> int {
    const ReplayArgs& a = *args;
    if (!(a.fps > 0) || !std::isfinite(a.fps)) throw InputError("--fps must be > 0");
    Progress progress(!global.quiet);
    check_output_folder(a.output);
    const plan::PlanFile f = plan::load_plan(a.plan);
    const fem::Scene scene = load_scene_with(a.scene, f.integrator);  // the plan's integrator
    constexpr double kMaxSettleSteps = 1e8;
    if (a.settle >= 0 && !(a.settle / f.time_step <= kMaxSettleSteps))
      throw InputError("--settle " + format_number(a.settle) + ": at most " + format_number(kMaxSettleSteps * f.time_step) +
                       " s (100 million steps of the plan's time_step " + format_number(f.time_step) + " s of " + a.plan + ")");
    const int settle_steps = a.settle >= 0 ? static_cast<int>(std::lround(a.settle / f.time_step)) : f.settle_steps;
    const fem::SceneWorld world = fem::build_scene(scene, &progress);
    FolderReplacement out(a.output);  // the new output beside the old one, swapped in whole
    const ReplayOutput r = write_replay(world, f, a.plan, out.staging(), a.fps, settle_steps, progress);
    out.commit();
    spdlog::info("{}", r.integrator_stats);
    if (!global.quiet) {
      double worst = 0;
      for (double v : r.max_volume_change) worst = std::max(worst, v);
      std::fprintf(stderr,
                   "squeeze: replayed %zu segments and %.2f s of settling, %d frames; at the end: distance to "
                   "goal %.3g m; largest volume change along the path %.2f%%; wrote %s\n",
                   f.path.size(), settle_steps * f.time_step, r.frames, r.final_distance, 100 * worst, a.output.c_str());
    }
    if (!r.matches)
      throw InputError(a.plan + ": the replay does not reproduce the planner's final state (hash " + hex64(r.hash) +
                       ", plan " + hex64(f.final_state_hash) + "): the scene or its meshes changed since planning");
    return kExitOk;
  };
}

}  // namespace squeeze::cli
