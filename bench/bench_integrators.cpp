// squeeze::fem — the implicit integrator against the paper's Verlet step on the same scene (issue
// 17): simulated seconds per wall-clock second, each with its automatic time step (Verlet: the
// stable step, stable_time_step; implicit: one frame interval, 1/30 s, with its motion substeps).
// BM_Integrator/<scene>/<integrator>: runs of `duration` simulated seconds from the scene's
// initial state, repeated until 2 s of wall clock (meshes from the cache; the first run meshes). Counters: sim_per_wall (simulated
// s per wall s), h (s), steps, substeps and Newton iterations per step, and the largest volume change.
// Scenes: bench/scenes/ball_drop.json, bunny_drop.json, headon.json, organs.json (box pins: the
// organs sag and touch), organs_embedded.json (the same organs moving on their convex shells, their
// tight meshes embedded: World::embed) and the bundled scenes/body_parts.json (supported: at rest) and barriers2.json; SQUEEZE_BENCH_SCENES=a.json,b.json replaces the list.
#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "squeeze/fem/integrator.h"
#include "squeeze/fem/scene.h"

using namespace squeeze;

namespace {

struct Case {
  std::string file;
  double duration;  // simulated s
};

std::vector<Case> cases() {
  const std::string src = SQUEEZE_SOURCE_DIR;
  if (const char* env = std::getenv("SQUEEZE_BENCH_SCENES")) {
    std::vector<Case> v;
    std::stringstream ss(env);
    const double duration = std::getenv("SQUEEZE_BENCH_DURATION") ? std::atof(std::getenv("SQUEEZE_BENCH_DURATION")) : 1.0;
    for (std::string f; std::getline(ss, f, ',');) v.push_back({f, duration});
    return v;
  }
  return {{src + "/bench/scenes/ball_drop.json", 1.0},
          {src + "/bench/scenes/bunny_drop.json", 1.5},
          {src + "/bench/scenes/headon.json", 0.5},
          {src + "/bench/scenes/organs.json", 0.5},
          {src + "/bench/scenes/organs_embedded.json", 0.5},
          {src + "/scenes/body_parts.json", 0.5},
          {src + "/scenes/barriers2.json", 0.5}};
}

std::map<std::string, double> g_rate;  // scene/integrator → simulated s per wall s

void BM_Integrator(benchmark::State& st, Case c, std::string integrator) {
  fem::Scene scene = fem::load_scene(c.file);
  scene.integrator = integrator;
  scene.time_step.reset();  // the integrator's automatic step
  const fem::SceneWorld built = fem::build_scene(scene);
  for (auto _ : st) {
    // The same run from the same initial state, repeated until kMinWall of wall clock has passed:
    // a run of a tenth of a second (the implicit ball) is timed as noise otherwise. The rate is
    // the simulated time of all repetitions over their wall clock; the counters are the last one's.
    constexpr double kMinWall = 2.0;  // s
    fem::SceneWorld w = built;
    fem::State s;
    int steps = 0, reps = 0;
    double wall = 0;
    while (reps == 0 || wall < kMinWall) {
      w = built;
      s = w.initial_state();
      steps = std::max(1, static_cast<int>(std::lround(c.duration / w.time_step())));
      const auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < steps; ++k) {
        w.step(s);
        if (!s.x.allFinite()) break;
      }
      wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ++reps;
    }
    double worst = 0;
    st.SetIterationTime(wall / reps);
    for (int b = 0; b < w.world.bodies(); ++b)
      if (!w.world.body(b).rigid) worst = std::max(worst, std::abs(w.world.body_volume(s, b) / w.rest_volume[b] - 1));
    const fem::IntegratorStats& is = w.world.integrator().stats();
    const double sim = steps * w.time_step();
    st.counters["sim_per_wall"] = reps * sim / wall;
    st.counters["repetitions"] = reps;
    st.counters["h"] = w.time_step();
    st.counters["steps"] = steps;
    st.counters["substeps_per_step"] = double(is.substeps) / steps;
    st.counters["newton_per_step"] = double(is.iterations) / steps;
    st.counters["factor_per_step"] = double(is.factorizations) / steps;
    st.counters["cg_per_step"] = double(is.cg_iterations) / steps;
    st.counters["contact_rounds_per_step"] = double(is.contact_rounds) / steps;
    st.counters["not_converged_per_step"] = double(is.not_converged) / steps;
    st.counters["volume_change_end_pct"] = 100 * worst;
    st.counters["finite"] = s.x.allFinite();
    const std::string stem = std::filesystem::path(c.file).stem().string();
    g_rate[stem + "/" + integrator] = reps * sim / wall;
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  for (const Case& c : cases()) {
    const std::string stem = std::filesystem::path(c.file).stem().string();
    for (const char* i : {"verlet", "implicit"})
      benchmark::RegisterBenchmark(("BM_Integrator/" + stem + "/" + i).c_str(), BM_Integrator, c, std::string(i))
          ->Iterations(1)
          ->UseManualTime()
          ->Unit(benchmark::kSecond);
  }
  benchmark::RunSpecifiedBenchmarks();
  for (const Case& c : cases()) {
    const std::string stem = std::filesystem::path(c.file).stem().string();
    const auto v = g_rate.find(stem + "/verlet"), i = g_rate.find(stem + "/implicit");
    if (v != g_rate.end() && i != g_rate.end())
      std::printf("%s: implicit %.3g, Verlet %.3g simulated s per wall s: %.1fx\n", stem.c_str(), i->second, v->second,
                  i->second / v->second);
  }
  return 0;
}
