// `squeeze run SCENE -o OUT [--seed N]`: the whole pipeline in one command — mesh (cached), plan,
// replay, FFD + render, plots, exports — with a summary at the end (issue 8).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "plan_shared.h"
#include "scene_options.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/scene.h"
#include "squeeze/plan/plan_io.h"
#include "squeeze/plan/planner.h"
#include "squeeze/render/export_formats.h"
#include "squeeze/render/render.h"
#include "squeeze/render/settings.h"
#include "trajectory_writer.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

struct RunArgs {
  std::string scene, output, exports = "pc2,vtu", gl = "osmesa", integrator, camera, video;
  long long seed = -1, iterations = -1;
  double time_limit = 0, fps = 0;
  int width = 0, height = 0;
  bool no_render = false, no_video = false;
};

using clock_type = std::chrono::steady_clock;
double since(clock_type::time_point t) { return std::chrono::duration<double>(clock_type::now() - t).count(); }

}  // namespace

Runner add_run_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "The whole pipeline on a scene: mesh every object (cached), plan the robot's motion to the goal,\n"
      "replay the plan, FFD the full-resolution surfaces onto the deformed coarse meshes and render\n"
      "them, plot the volume change, export for other tools. Writes OUT/plan.json, OUT/metrics.csv,\n"
      "OUT/trajectory/, OUT/frames/frame_*.png, OUT/video.mp4, OUT/volume.png (+.svg), OUT/export/,\n"
      "OUT/summary.json.\n"
      "Exit 0 when solved, 3 when not (the closest approximate path is still replayed and rendered).\n"
      "Example: squeeze run scenes/barriers1.json -o out/barriers1 --seed 2");
  cmd->add_option("SCENE", args->scene, "Scene file (JSON) with a robot and a goal")->required();
  cmd->add_option("-o,--output", args->output, "Output directory (created if missing; its parent must exist)")->required();
  cmd->add_option("--seed", args->seed, "Planner seed (default: planner.seed of the scene, else 1)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--iterations", args->iterations, "Planner iterations at most (default: planner.iterations)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--time-limit", args->time_limit, "Seconds of planning at most (0: no limit)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--fps", args->fps, "Frames per simulated second (default: render.fps of the scene, else 30)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--width", args->width, "Image width in pixels (default: render.width, else 1280)")->check(CLI::PositiveNumber);
  cmd->add_option("--height", args->height, "Image height in pixels (default: render.height, else 720)")->check(CLI::PositiveNumber);
  cmd->add_option("--export", args->exports, render::export_option_help())->capture_default_str();
  cmd->add_option("--gl", args->gl, "OpenGL context: osmesa or egl")->capture_default_str();
  cmd->add_flag("--no-render", args->no_render, "Stop after the replay (no frames, plots or exports)");
  cmd->add_option("--camera", args->camera,
                  "Camera preset, replacing the scene's camera: " + render::camera_view_names() +
                      " (fitted to the scene preset's `fit` objects, else every object, over the whole path)");
  cmd->add_option("--video", args->video,
                  "H.264 MP4 of the frames (default: OUT/video.mp4 when this FFmpeg has an H.264 encoder)");
  cmd->add_flag("--no-video", args->no_video, "Do not write a video");
  add_integrator_option(cmd, args->integrator);

  return [args, &global]() -> int {
    const RunArgs& a = *args;
    const auto t_all = clock_type::now();
    // Every input check before the long work.
    check_output_folder(a.output);
    render::RenderOptions ro;
    ro.gl = render::parse_gl_backend(a.gl);
    render::parse_exports(a.exports, ro);
    if (!a.camera.empty()) {
      if (!render::find_camera_view(a.camera))
        throw InputError("--camera " + a.camera + ": must be one of " + render::camera_view_names());
      ro.camera = a.camera;
    }
    if (!a.video.empty() && a.no_video) throw InputError("--video and --no-video: give one");
    if (!a.video.empty() && fs::absolute(fs::path(a.video)).parent_path() != fs::absolute(fs::path(a.output)))
      check_output_directory(a.video);  // (a video inside OUT: OUT is created later)
    Progress progress(!global.quiet);
    std::vector<std::pair<std::string, double>> seconds;
    auto t = clock_type::now();
    const fem::Scene scene = load_scene_with(a.scene, a.integrator);
    const render::RenderSettings rs = render::parse_render_settings(scene.render, scene.file.string());
    const long long builds_before = fem::scene_builds();
    const PreparedPlanning prep = prepare_planning(scene, {a.seed, a.iterations, a.time_limit}, progress);
    const plan::PlannerOptions& options = prep.options;
    print_scene_warnings(prep.world, options.max_volume_change, 0.1, &progress);  // squeeze check's warnings
    seconds.emplace_back("meshing", since(t));
    // Everything is written into a staging folder beside OUT and swapped in whole at the end, so a
    // kill at any moment leaves the complete old OUT or the complete new one.
    FolderReplacement staged(a.output);
    const fs::path out = staged.staging();
    const fs::path final_out = a.output;

    // Plan.
    t = clock_type::now();
    const plan::PlanResult r = plan::plan(prep.world, options, &progress);
    const plan::PlanFile f = plan::make_plan_file(scene, options, r);
    plan::save_plan(out / "plan.json", f);
    seconds.emplace_back("planning", since(t));

    // Replay.
    t = clock_type::now();
    const double fps = a.fps > 0 ? a.fps : rs.fps.value_or(30.0);
    const ReplayOutput rep =
        write_replay(prep.world, f, (final_out / "plan.json").string(), out, fps, f.settle_steps, progress);
    // The scene's world is built once (prepare_planning); planning, replay and metrics use copies.
    const long long builds = fem::scene_builds() - builds_before;
    spdlog::info("squeeze run: built the scene's world {} time{} (planning, replay and metrics use copies)", builds,
                builds == 1 ? "" : "s");
    if (!rep.matches)
      throw std::logic_error("the replay does not reproduce the planner's final state (hash " + hex64(rep.hash) +
                             ", planner " + hex64(f.final_state_hash) + ")");
    seconds.emplace_back("replaying", since(t));

    // Render: frames into OUT/frames, then plots and exports into OUT.
    render::RenderStats st;
    if (!a.no_render) {
      t = clock_type::now();
      ro.scene = a.scene;
      ro.trajectory = out;
      ro.fps = fps;  // the trajectory's: one PNG per trajectory frame
      if (a.width > 0) ro.width = a.width;
      if (a.height > 0) ro.height = a.height;
      render::RenderOptions frames = ro;
      frames.output = out / "frames";
      if (!a.no_video) {
        frames.video = a.video.empty() ? out / "video.mp4" : fs::path(a.video);
        frames.video_optional = a.video.empty();  // the default video: a missing encoder only warns
      }
      frames.plots = false;
      frames.exports.clear();
      frames.on_frame = [&](const render::FrameProgress& p) {
        if (p.done == 1) progress.stage("rendering frames", p.total);
        progress.update(p.done);
      };
      st = render::render_trajectory(frames, &progress);
      progress.finish();
      seconds.emplace_back("rendering", since(t));
      t = clock_type::now();
      render::RenderOptions rest = ro;
      rest.output = out;
      rest.png = false;
      render::render_trajectory(rest, &progress);  // exports land in OUT/export/
      seconds.emplace_back("plots and exports", since(t));
    }

    // Summary. (The video's path as the user finds it: OUT/video.mp4 once OUT is in place.)
    const std::string video_path = a.video.empty() ? (final_out / "video.mp4").string() : a.video;
    const plan::PlanStatistics& s = r.stats;
    nlohmann::json sum;
    sum["scene"] = f.scene;
    sum["status"] = plan::to_string(r.status);
    sum["seed"] = options.seed;
    sum["iterations"] = s.iterations;
    sum["nodes"] = s.nodes;
    sum["iterations_per_second"] = s.seconds > 0 ? s.iterations / s.seconds : 0.0;
    sum["final_distance"] = rep.final_distance;
    // The planner's status is its tree's; the settling after the path (the plan's `settle`) can
    // still take the robot into the goal's tolerance from an approximate path's end.
    sum["goal_reached"] = rep.final_distance <= scene.goal->tolerance;
    sum["frames"] = rep.frames;
    sum["path_seconds"] = rep.duration;
    for (const auto& [k, v] : seconds) sum["seconds"][k] = v;
    sum["seconds"]["total"] = since(t_all);
    for (size_t b = 0; b < rep.names.size(); ++b) sum["max_volume_change"][rep.names[b]] = rep.max_volume_change[b];
    sum["outputs"] = {{"plan", (final_out / "plan.json").string()},
                      {"metrics", (final_out / "metrics.csv").string()},
                      {"trajectory", (final_out / "trajectory").string()}};
    if (!a.no_render) {
      sum["outputs"]["frames"] = (final_out / "frames").string();
      sum["outputs"]["volume_plot"] = (final_out / "volume.png").string();
      sum["outputs"]["export"] = (final_out / "export").string();
      if (!st.video.empty()) sum["outputs"]["video"] = video_path;
    }
    write_atomically(out / "summary.json", [&](const fs::path& p) {
      std::ofstream o(p);
      o << sum.dump(2) << '\n';
      if (!o) throw InputError((out / "summary.json").string() + ": write failed");
    });
    staged.commit();
    if (!global.quiet) {
      std::fprintf(stderr, "\nsqueeze run %s: %s after %d iterations (%d nodes, %.1f it/s); robot %.3g m from the goal "
                   "(tolerance %.3g m: %s) after the path and %.1f s of settling\n",
                   a.scene.c_str(), plan::to_string(r.status), s.iterations, s.nodes,
                   s.seconds > 0 ? s.iterations / s.seconds : 0.0, rep.final_distance, scene.goal->tolerance,
                   rep.final_distance <= scene.goal->tolerance ? "reached" : "not reached", options.settle);
      std::fprintf(stderr, "  seconds:");
      for (const auto& [k, v] : seconds) std::fprintf(stderr, " %s %.1f,", k.c_str(), v);
      std::fprintf(stderr, " total %.1f\n  max volume change:", since(t_all));
      for (size_t b = 0; b < rep.names.size(); ++b)
        if (!scene.objects[b].rigid) std::fprintf(stderr, " %s %.2f%%", rep.names[b].c_str(), 100 * rep.max_volume_change[b]);
      std::fprintf(stderr, "\n  wrote: %s/plan.json, metrics.csv, trajectory/ (%d frames at %.3g fps)", a.output.c_str(),
                   rep.frames, fps);
      if (!a.no_render)
        std::fprintf(stderr, ", frames/frame_*.png (%dx%d), volume.png, volume.svg%s%s", st.width, st.height,
                     !ro.exports.empty() ? ", export/" : "", st.video.empty() ? "" : (", " + video_path).c_str());
      std::fprintf(stderr, ", summary.json\n");
    }
    return r.status == plan::PlanStatus::solved ? kExitOk : kExitNotSolved;
  };
}

}  // namespace squeeze::cli
