// squeeze::fem — cost of World::step in nanoseconds per tetrahedron per time step, collision
// detection and response included, on the scene of fem_bench_scene.h (always in contact: steps
// 300 to 600, replayed). Args: voxel balls' cells per axis n (about 2π n³ tets, plus 150 rigid),
// threads.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "fem_bench_scene.h"

using namespace squeeze;
using namespace squeeze::fem;

namespace {

using bench::Scene;
using bench::make_scene;
using bench::kInContactStep;
using bench::kReplaySteps;

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

}  // namespace

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
