// One build of the fem stage as a shared library for ab.cpp: the bench_fem scene (two balls
// pushed together on a rigid slab, fem_bench_scene.h), with C entry points.
// Built by mklib.sh; see README.md.
#include <cstring>
#include <memory>
#include "../fem_bench_scene.h"
using namespace squeeze;
using namespace squeeze::fem;
using bench::Scene;

static std::unique_ptr<Scene> g;
static State g_in;
extern "C" void setup(int n) {
  g = std::make_unique<Scene>(bench::make_scene(n));
  for (int k = 0; k < bench::kInContactStep; ++k) g->world.step(g->state, &g->ext);
  g_in = g->state;
}
// ns per tet-step over `steps` steps from the in-contact state (steps <= kReplaySteps stays in
// contact).
extern "C" double run(int steps) {
  return bench::run_window(*g, g_in, steps) * 1e9 / steps / g->world.tets();
}
extern "C" unsigned long long state_hash() {
  unsigned long long h = 1469598103934665603ull;
  const double* p = g->state.x.data();
  for (long i = 0; i < g->state.x.size(); ++i) { unsigned long long b; std::memcpy(&b, p + i, 8); h = (h ^ b) * 1099511628211ull; }
  return h;
}
