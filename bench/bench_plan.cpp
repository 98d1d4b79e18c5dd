// squeeze::plan — the planner on a bundled scene over several seeds (issue 6): per seed, the
// time to solution, iterations, iterations per second, nodes, bytes per node, peak memory and the
// largest volume change of any object along the replayed path; then the success rate and the
// median time. Defaults: scenes/barriers1.json, seeds 1..10, a 120 s limit per seed (the issue's
// test). Environment: SQUEEZE_BENCH_SCENE (scene file), SQUEEZE_BENCH_SEEDS (count),
// SQUEEZE_BENCH_LIMIT (seconds per seed).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "squeeze/fem/scene.h"
#include "squeeze/plan/evaluate.h"

using namespace squeeze;
using namespace squeeze::meshing;

namespace {

std::string scene_file() {
  const char* s = std::getenv("SQUEEZE_BENCH_SCENE");
  return s ? s : std::string(SQUEEZE_SOURCE_DIR) + "/scenes/barriers1.json";
}
int seeds() {
  const char* s = std::getenv("SQUEEZE_BENCH_SEEDS");
  return s ? std::max(1, std::atoi(s)) : 10;
}
double limit() {
  const char* s = std::getenv("SQUEEZE_BENCH_LIMIT");
  return s ? std::atof(s) : 120.0;
}

struct Row {
  int seed;
  bool solved;
  double seconds, iterations, rate, volume;
};
std::vector<Row> rows;

void BM_Plan(benchmark::State& st) {
  const fem::SceneWorld world = fem::build_scene(fem::load_scene(scene_file()));
  plan::PlannerOptions o = plan::planner_options(world);
  o.seed = static_cast<std::uint64_t>(st.range(0));
  o.time_limit = limit();
  o.iterations = std::max(o.iterations, 100000000 / 2);  // the time limit decides
  for (auto _ : st) {
    const plan::PlanEvaluation e = plan::evaluate_plan(world, o);
    const plan::PlanStatistics& s = e.result.stats;
    const double volume = *std::max_element(e.max_volume_change.begin(), e.max_volume_change.end());
    st.counters["solved"] = e.result.status == plan::PlanStatus::solved;
    st.counters["plan_s"] = s.seconds;
    st.counters["iterations"] = s.iterations;
    st.counters["it_per_s"] = s.iterations / s.seconds;
    st.counters["nodes"] = s.nodes;
    st.counters["bytes_per_node"] = s.bytes_per_node;
    st.counters["peak_MiB"] = s.peak_memory / 1048576.0;
    st.counters["max_volume_change_pct"] = 100 * volume;
    st.counters["replay_matches"] = e.replay_matches;
    rows.push_back({static_cast<int>(o.seed), e.result.status == plan::PlanStatus::solved, s.seconds,
                    static_cast<double>(s.iterations), s.iterations / s.seconds, volume});
  }
}

// Issue 15: what building a scene once saves. BM_SceneBuild: build_scene of a bundled scene (meshes
// from the cache, bodies, materials, pins, stable step, prepared rest data), what `squeeze run`
// did up to 7 times before. BM_SceneCopy: a copy of the built SceneWorld, what planning, replay
// and metrics each take now (rest data shared; the copy's own scratch is made at its first step).
std::string bundled(const std::string& name) { return std::string(SQUEEZE_SOURCE_DIR) + "/scenes/" + name + ".json"; }

void BM_SceneBuild(benchmark::State& st, const std::string& name) {
  const fem::Scene scene = fem::load_scene(bundled(name));
  fem::build_scene(scene);  // fills the mesh cache if needed
  for (auto _ : st) benchmark::DoNotOptimize(fem::build_scene(scene));
}

void BM_SceneCopy(benchmark::State& st, const std::string& name) {
  const fem::SceneWorld w = fem::build_scene(fem::load_scene(bundled(name)));
  for (auto _ : st) {
    fem::SceneWorld copy = w;
    benchmark::DoNotOptimize(copy);
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  for (const char* name : {"body_parts", "barriers2"}) {
    benchmark::RegisterBenchmark((std::string("BM_SceneBuild/") + name).c_str(), BM_SceneBuild, std::string(name))
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark((std::string("BM_SceneCopy/") + name).c_str(), BM_SceneCopy, std::string(name))
        ->Unit(benchmark::kMillisecond);
  }
  auto* b = benchmark::RegisterBenchmark("BM_Plan", BM_Plan)->ArgName("seed")->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
  for (int s = 1; s <= seeds(); ++s) b->Arg(s);
  benchmark::RunSpecifiedBenchmarks();
  if (rows.empty()) return 0;  // e.g. --benchmark_filter=BM_Scene
  std::vector<double> t, rate;
  int solved = 0;
  double worst_volume = 0, iterations = 0, seconds = 0;
  for (const Row& r : rows) {
    if (r.solved) {
      ++solved;
      t.push_back(r.seconds);
    }
    iterations += r.iterations;
    seconds += r.seconds;
    worst_volume = std::max(worst_volume, r.volume);
  }
  std::sort(t.begin(), t.end());
  const double median = t.empty() ? 0 : (t.size() % 2 ? t[t.size() / 2] : 0.5 * (t[t.size() / 2 - 1] + t[t.size() / 2]));
  std::printf("\n%s: solved %d of %zu seeds within %.0f s; median time to solution %.2f s (paper: 634 s for "
              "Barriers1, ratio %.0fx); %.1f iterations/s overall; largest volume change along a replayed path %.2f%%\n",
              scene_file().c_str(), solved, rows.size(), limit(), median, median > 0 ? 634.0 / median : 0.0,
              iterations / seconds, 100 * worst_volume);
  return 0;
}
