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

#include "commands.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/scene.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

struct SimulateArgs {
  std::string scene, output;
  double duration = 0, fps = 30;
};

// Removes a directory tree on scope exit unless released.
struct TreeGuard {
  fs::path path;
  ~TreeGuard() {
    if (!path.empty()) {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  }
};

std::string fmt(double x) {
  if (x == 0) return "0";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

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

  return [args, &global]() -> int {
    SimulateArgs& a = *args;
    if (!(a.duration > 0) || !std::isfinite(a.duration)) throw InputError("--duration must be > 0");
    if (!(a.fps > 0) || !std::isfinite(a.fps)) throw InputError("--fps must be > 0");
    const double frames_d = std::floor(a.duration * a.fps + 1e-9);
    if (frames_d > 1e7) throw InputError("--duration × --fps: too many frames (at most 10 million)");
    const int frames = static_cast<int>(frames_d) + 1;  // t = 0, 1/fps, ..., <= duration
    const fs::path out = a.output;
    std::error_code ec;
    if (fs::exists(out, ec) && !fs::is_directory(out, ec))
      throw InputError(a.output + ": exists and is not a directory");
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (!fs::is_directory(parent, ec))
      throw InputError(a.output + ": parent directory " + parent.string() + " does not exist");

    // All input checks (scene, meshes, bodies) before anything is written.
    Progress progress(!global.quiet);
    fem::Scene scene = fem::load_scene(a.scene);
    fem::SceneWorld w = fem::build_scene(scene, &progress);
    const double interval = 1.0 / a.fps;
    const int substeps = std::max(1, static_cast<int>(std::ceil(interval / w.h - 1e-9)));
    const double h = interval / substeps;
    w.set_time_step(h);  // divides the frame interval, never larger than the scene's step
    const int nobj = w.world.bodies();

    const bool created = !fs::exists(out, ec);
    fs::create_directories(out, ec);
    if (ec) throw InputError(a.output + ": cannot create the directory: " + ec.message());
    TreeGuard out_guard;
    if (created) out_guard.path = out;  // removed again if anything fails
    const fs::path traj = out / "trajectory";
    const fs::path tmp = out / (".trajectory.tmp-" + std::to_string(::getpid()));
    fs::remove_all(tmp, ec);
    TreeGuard tmp_guard{tmp};
    fs::create_directories(tmp / "rest", ec);
    fs::create_directories(tmp / "frames", ec);
    if (ec) throw InputError((tmp / "frames").string() + ": cannot create the directory: " + ec.message());

    nlohmann::json index;
    index["format"] = "squeeze-trajectory";
    index["version"] = 1;
    index["scene"] = fs::absolute(scene.file).lexically_normal().string();
    index["fps"] = a.fps;
    index["time_step"] = h;
    index["frames"] = frames;
    index["frame_file"] = "frames/%06d.bin";
    index["floor"] = scene.floor ? nlohmann::json(*scene.floor) : nlohmann::json(nullptr);
    index["bounds"] = {{"min", {w.bounds.min().x(), w.bounds.min().y(), w.bounds.min().z()}},
                       {"max", {w.bounds.max().x(), w.bounds.max().y(), w.bounds.max().z()}}};
    if (scene.goal)
      index["goal"] = {{"position", {scene.goal->position.x(), scene.goal->position.y(), scene.goal->position.z()}},
                       {"tolerance", scene.goal->tolerance},
                       {"object", scene.goal->object}};
    int offset = 0;
    for (int b = 0; b < nobj; ++b) {
      const fem::SceneObject& o = scene.objects[b];
      const std::string rest = "rest/" + o.name + ".mesh";
      save_tet_mesh(tmp / rest, w.meshes[b]);
      index["objects"].push_back({{"name", o.name},
                                  {"role", o.robot ? "robot" : "obstacle"},
                                  {"kind", o.rigid ? "rigid" : "deformable"},
                                  {"rest_mesh", rest},
                                  {"vertices", w.world.body(b).vertices()},
                                  {"tets", w.world.body(b).tets()},
                                  {"offset", offset}});
      offset += w.world.body(b).vertices();
    }
    index["frame_vertices"] = offset;

    std::ostringstream csv;
    csv << "time,max_penetration,colliding_vertices";
    for (const auto& o : scene.objects)
      for (const char* c : {"volume_ratio", "com_x", "com_y", "com_z", "aabb_min_x", "aabb_min_y", "aabb_min_z",
                            "aabb_max_x", "aabb_max_y", "aabb_max_z", "kinetic_energy"})
        csv << ',' << o.name << '.' << c;
    csv << '\n';

    fem::State s = w.initial_state();
    fem::RowMatrixX3d F;
    std::vector<double> buffer(static_cast<size_t>(offset) * 3);
    progress.stage("simulating", frames);
    for (int f = 0; f < frames; ++f) {
      bool diverged = false;
      if (f > 0)
        for (int k = 0; k < substeps && !diverged; ++k) {
          w.step(s);
          // Faster than 1 km/s is a blow-up, not motion (and would make collision detection crawl).
          diverged = !(s.v.size() == 0 || s.v.cwiseAbs().maxCoeff() < 1e3);
        }
      if (diverged || !s.x.allFinite() || !s.v.allFinite())
        throw InputError(a.scene + ": the simulation diverged before t = " + fmt(f * interval) +
                         " s: lower time_step or the material stiffness");
      // Contacts of this very state (the step's statistics belong to the state before it).
      w.world.total_forces(s, w.external.rows() ? &w.external : nullptr, F);
      const fem::StepStats& st = w.world.last_stats();
      double depth = st.max_depth;
      int colliding = st.colliding_vertices;
      if (scene.floor)
        for (Eigen::Index i = 0; i < s.x.rows(); ++i)
          if (s.x(i, 1) < *scene.floor) {
            depth = std::max(depth, *scene.floor - s.x(i, 1));
            ++colliding;
          }
      csv << fmt(f * interval) << ',' << fmt(depth) << ',' << colliding;
      size_t at = 0;
      for (int b = 0; b < nobj; ++b) {
        const fem::ObjectMetrics m = fem::object_metrics(w, s, b);
        for (double x : {m.volume_ratio, m.com.x(), m.com.y(), m.com.z(), m.aabb.min().x(), m.aabb.min().y(),
                         m.aabb.min().z(), m.aabb.max().x(), m.aabb.max().y(), m.aabb.max().z(), m.kinetic_energy})
          csv << ',' << fmt(x);
        const fem::RowMatrixX3d X = w.positions(s, b);
        std::copy(X.data(), X.data() + X.size(), buffer.data() + at);
        at += static_cast<size_t>(X.size());
      }
      csv << '\n';
      char name[32];
      std::snprintf(name, sizeof name, "%06d.bin", f);
      std::ofstream bin(tmp / "frames" / name, std::ios::binary);
      bin.write(reinterpret_cast<const char*>(buffer.data()), static_cast<std::streamsize>(buffer.size() * sizeof(double)));
      if (!bin) throw InputError((tmp / "frames" / name).string() + ": write failed");
      progress.update(f + 1);
    }
    progress.finish();
    {
      std::ofstream idx(tmp / "index.json");
      idx << index.dump(2) << '\n';
      if (!idx) throw InputError((tmp / "index.json").string() + ": write failed");
    }
    write_atomically(out / "metrics.csv", [&](const fs::path& p) {
      std::ofstream o(p);
      o << csv.str();
      if (!o) throw InputError((out / "metrics.csv").string() + ": write failed");
    });
    fs::remove_all(traj, ec);
    fs::rename(tmp, traj, ec);
    if (ec) throw InputError(traj.string() + ": cannot move the trajectory into place: " + ec.message());
    tmp_guard.path.clear();
    out_guard.path.clear();
    if (!global.quiet)
      std::fprintf(stderr, "squeeze: %s: %d objects, %d frames, time step %.3g s, wrote %s\n", a.scene.c_str(), nobj,
                   frames, h, out.string().c_str());
    return kExitOk;
  };
}

}  // namespace squeeze::cli
