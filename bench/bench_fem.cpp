// squeeze::fem — cost of World::step in nanoseconds per tetrahedron per time step, collision
// detection and response included, on the scene of fem_bench_scene.h (always in contact: steps
// 300 to 600, replayed). BM_FemStep: args voxel balls' cells per axis n (about 2π n³ tets, plus
// 150 rigid), threads. BM_FemSpeedup: the 2-thread speed-up measured in interleaved rounds.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <thread>
#include <vector>

#include "fem_bench_scene.h"

using namespace squeeze;
using namespace squeeze::meshing;
using namespace squeeze::fem;

namespace {

using bench::Scene;
using bench::make_scene;
using bench::kInContactStep;
using bench::kReplaySteps;
using bench::run_window;
constexpr int kWarmSteps = 100;  // untimed steps before each BM_FemSpeedup window

void BM_FemStep(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0)), threads = static_cast<int>(st.range(1));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  Scene sc = make_scene(n);
  for (int k = 0; k < kInContactStep; ++k) sc.world.step(sc.state, &sc.ext);  // warm up, get in contact
  // Measured window: the in-contact steps, replayed; restoring the State is a copy, negligible.
  const State in_contact = sc.state;
  int k = 0;
  for (auto _ : st) {
    sc.world.step(sc.state, &sc.ext);
    if (++k == kReplaySteps) {
      k = 0;
      sc.state = in_contact;
    }
  }
  const double tets = sc.world.tets();
  st.counters["tets"] = tets;
  st.counters["contacts"] = sc.world.last_stats().colliding_vertices;
  st.counters["s_per_tet_step"] =
      benchmark::Counter(tets, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// The 2-thread speed-up, measured so that the host's drift cancels: rounds alternate a window of
// the scene on 1 thread, the same window on 2 threads, and two independent copies of the scene
// stepping side by side on 1 thread each (no data shared: the most two threads of this host can
// give a step at that moment; on a virtual machine whose two vCPUs share one physical core, or
// whose core is shared with other guests, well below 2). Per round ratios, medians over rounds.
void BM_FemSpeedup(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0)), rounds = static_cast<int>(st.range(1));
  Scene a = make_scene(n), b = make_scene(n);
  for (int k = 0; k < kInContactStep; ++k) a.world.step(a.state, &a.ext);  // b only replays a's window
  const State start = a.state;
  tbb::task_arena one(1), two(2);
  std::vector<double> t1, t2, speedup, ceiling;
  for (auto _ : st) {
    for (int r = 0; r < rounds; ++r) {
      double s1 = 0, s2 = 0, sa = 0, sb = 0;
      one.execute([&] { s1 = run_window(a, start, kReplaySteps, kWarmSteps); });
      two.execute([&] { s2 = run_window(a, start, kReplaySteps, kWarmSteps); });
      {  // side by side: each thread steps its own scene in its own 1-thread arena
        std::thread other([&] { tbb::task_arena own(1); own.execute([&] { sb = run_window(b, start, kReplaySteps, kWarmSteps); }); });
        tbb::task_arena own(1);
        own.execute([&] { sa = run_window(a, start, kReplaySteps, kWarmSteps); });
        other.join();
      }
      t1.push_back(s1);
      t2.push_back(s2);
      speedup.push_back(s1 / s2);
      ceiling.push_back(2 * s1 / std::max(sa, sb));  // two windows done in max(sa, sb)
    }
  }
  const double per = 1e9 / (double(kReplaySteps) * a.world.tets());
  st.counters["tets"] = a.world.tets();
  st.counters["ns_1thread"] = median(t1) * per;
  st.counters["ns_2threads"] = median(t2) * per;
  st.counters["speedup"] = median(speedup);
  st.counters["ceiling"] = median(ceiling);
}

}  // namespace

BENCHMARK(BM_FemSpeedup)
    ->ArgNames({"n", "rounds"})
    ->Args({3, 20})
    ->Args({7, 20})
    ->Args({18, 5})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

BENCHMARK(BM_FemStep)
    ->ArgNames({"n", "threads"})
    ->Args({3, 1})
    ->Args({3, 2})
    ->Args({7, 1})
    ->Args({7, 2})
    ->Args({18, 1})
    ->Args({18, 2})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

BENCHMARK_MAIN();
