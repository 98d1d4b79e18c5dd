// Benchmarks of the render stage (issue 7): `squeeze render` throughput at 1280×720 on the
// 75,000-triangle bunny and the 20,000-triangle dragon (tests/data/ChineseDragon-10kv.off), FFD
// replay, normals, shadow pass, 4× MSAA, read-back and PNG encoding (on the second thread) included.
//
//   build/bench/bench_render                      (osmesa; SQUEEZE_BENCH_GL=egl for EGL,
//                                                  SQUEEZE_BENCH_SAMPLES=1 without MSAA,
//                                                  SQUEEZE_BENCH_KEEP=1 keeps /tmp/squeeze-bench-render-*)
//   LP_NUM_THREADS=1 taskset -c 0 build/bench/bench_render    (one core)
//
// Each model sits on the floor next to a rigid box; its trajectory (1 s at 30 fps, 31 frames) is
// its coarse mesh squashed and turned a little more each frame. Counters: frames_per_s (the frame
// loop: rendered frames / its wall time, PNG encoding waited for), cpu_ms_per_frame (CPU time of
// all threads in the frame loop per frame: on a loaded machine, 2000 / cpu_ms_per_frame bounds the
// frames/s two idle cores could reach), setup_s (scene, meshing from the cache, binding, context),
// triangles drawn per frame.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "squeeze/fem/scene.h"
#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"
#include "squeeze/render/render.h"

namespace {
namespace fs = std::filesystem;
using namespace squeeze;
using namespace squeeze::meshing;

constexpr int kFrames = 31;

// Scene + trajectory for one model in a temporary folder (the coarse mesh comes from the mesh cache).
fs::path prepare(const std::string& name, const fs::path& mesh) {
  const fs::path dir = fs::temp_directory_path() / ("squeeze-bench-render-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir / "trajectory" / "rest");
  fs::create_directories(dir / "trajectory" / "frames");
  const SurfaceMesh s = load_surface(mesh);
  Eigen::RowVector3d lo, hi;
  bounding_box(s.V, lo, hi);
  const double scale = 0.2 / (hi - lo).maxCoeff();
  const Eigen::RowVector3d c = 0.5 * (lo + hi);
  nlohmann::json scene = {
      {"floor", 0.0},
      {"objects",
       {{{"name", name}, {"mesh", mesh.string()}, {"tets", 300}, {"role", "robot"},
         {"transform", {{"scale", scale},
                        {"translate", {-scale * c.x(), -scale * lo.y() + 0.002, -scale * c.z()}}}}},
        {{"name", "box"}, {"mesh", (fs::path(SQUEEZE_SOURCE_DIR) / "scenes/assets/cube.mesh").string()},
         {"kind", "rigid"}, {"transform", {{"scale", {0.12, 0.08, 0.12}}, {"translate", {0.2, 0.04, -0.05}}}}}}}};
  std::ofstream(dir / "scene.json") << scene.dump(2);
  const fem::Scene sc = fem::load_scene(dir / "scene.json");
  const fem::SceneWorld w = fem::build_scene(sc);
  nlohmann::json index = {{"format", "squeeze-trajectory"}, {"version", 1}, {"scene", (dir / "scene.json").string()},
                          {"fps", 30.0}, {"time_step", 1e-3}, {"frames", kFrames}, {"frame_file", "frames/%06d.bin"},
                          {"floor", 0.0}};
  int offset = 0;
  for (size_t b = 0; b < sc.objects.size(); ++b) {
    save_tet_mesh(dir / "trajectory" / "rest" / (sc.objects[b].name + ".mesh"), w.meshes[b]);
    index["objects"].push_back({{"name", sc.objects[b].name}, {"kind", sc.objects[b].rigid ? "rigid" : "deformable"},
                                {"rest_mesh", "rest/" + sc.objects[b].name + ".mesh"},
                                {"vertices", w.meshes[b].V.rows()}, {"tets", w.meshes[b].T.rows()}, {"offset", offset}});
    offset += static_cast<int>(w.meshes[b].V.rows());
  }
  index["frame_vertices"] = offset;
  std::ofstream(dir / "trajectory" / "index.json") << index.dump(2);
  for (int k = 0; k < kFrames; ++k) {
    std::vector<double> buf;
    for (size_t b = 0; b < sc.objects.size(); ++b) {
      Eigen::MatrixX3d X = w.meshes[b].V;
      if (!sc.objects[b].rigid) {
        const double squash = 1 - 0.25 * k / (kFrames - 1), a = 0.6 * k / (kFrames - 1);
        const Eigen::RowVector3d centre = X.colwise().mean();
        for (Eigen::Index i = 0; i < X.rows(); ++i) {
          const Eigen::RowVector3d p = X.row(i) - centre;
          const double x = std::cos(a) * p.x() + std::sin(a) * p.z(), z = -std::sin(a) * p.x() + std::cos(a) * p.z();
          const double y = (X(i, 1) - 0.002) * squash + 0.002;
          X.row(i) << centre.x() + x * (1 + 0.5 * (1 - squash)), y, centre.z() + z * (1 + 0.5 * (1 - squash));
        }
      }
      for (Eigen::Index i = 0; i < X.rows(); ++i)
        for (int c2 = 0; c2 < 3; ++c2) buf.push_back(X(i, c2));
    }
    char file[32];
    std::snprintf(file, sizeof file, "%06d.bin", k);
    std::ofstream(dir / "trajectory" / "frames" / file, std::ios::binary)
        .write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size() * sizeof(double)));
  }
  return dir;
}

void BM_Render(benchmark::State& state, const std::string& name, const fs::path& mesh) {
  const fs::path dir = prepare(name, mesh);
  render::RenderOptions o;
  o.scene = dir / "scene.json";
  o.trajectory = dir;
  o.output = dir / "frames";
  o.width = 1280;
  o.height = 720;
  o.plots = false;
  const char* gl = std::getenv("SQUEEZE_BENCH_GL");
  o.gl = render::parse_gl_backend(gl ? gl : "osmesa");
  if (const char* samples = std::getenv("SQUEEZE_BENCH_SAMPLES")) o.samples = std::atoi(samples);
  render::RenderStats s;
  double frames = 0, seconds = 0, setup = 0, cpu = 0;
  for (auto _ : state) {
    s = render::render_trajectory(o);
    frames += s.rendered;
    seconds += s.frame_seconds;
    setup += s.setup_seconds;
    cpu += s.frame_cpu_seconds;
  }
  state.counters["cpu_ms_per_frame"] = 1e3 * cpu / frames;
  state.counters["frames_per_s"] = frames / seconds;
  state.counters["setup_s"] = setup / static_cast<double>(state.iterations());
  state.counters["triangles"] = static_cast<double>(s.surface_triangles);
  state.counters["samples"] = s.samples;
  state.SetLabel(s.gl);
  if (!std::getenv("SQUEEZE_BENCH_KEEP")) fs::remove_all(dir);  // kept: look at the frames
}

BENCHMARK_CAPTURE(BM_Render, bunny, std::string("bunny"),
                  fs::path(SQUEEZE_SOURCE_DIR) / "scenes" / "assets" / "bunny.off")
    ->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK_CAPTURE(BM_Render, dragon, std::string("dragon"), fs::path(SQUEEZE_TEST_DATA) / "ChineseDragon-10kv.off")
    ->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
