// squeeze::fem — cost of World::step in nanoseconds per tetrahedron per time step, collision
// detection and response included: two deformable balls pushed into each other (always in
// contact: steps 300 to 600 of the scene, replayed) on a rigid slab with gravity. Args: voxel balls' cells per axis n (about 2π n³ tets, plus 150 rigid),
// threads. Knobs for tuning: SQUEEZE_FEM_CELL (hash cell in grid spacings) and SQUEEZE_FEM_TABLE
// (hash table size) override the World's automatic choices.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdlib>

#include "squeeze/fem/world.h"

using namespace squeeze;
using namespace squeeze::fem;

namespace {

struct Scene {
  World world;
  State state;
  RowMatrixX3d ext;
};

// Stiffnesses scale with the resolution so that h·ω stays about 0.1 (ω² ∝ k / (D0² m) ∝ k n⁵).
Scene make_scene(int n) {
  const double s3 = std::pow(4.0 / n, 3), s5 = std::pow(4.0 / n, 5);
  WorldOptions o;
  o.h = 1e-4;
  o.contact_stiffness = 2e4 * s3;
  o.contact_damping = 2 * s3;
  if (const char* c = std::getenv("SQUEEZE_FEM_CELL")) o.cell_size = std::atof(c) * 0.2 / n;  // × grid spacing
  if (const char* t = std::getenv("SQUEEZE_FEM_TABLE")) o.table_size = std::atoi(t);
  World w(o);
  Material m;
  m.k_distance = 5 * s5;
  m.k_volume = 5 * s5;
  m.damping_distance = 0.002 * s5;
  m.damping_volume = 0.002 * s5;
  Eigen::Affine3d a = Eigen::Affine3d::Identity(), b = a;
  a.translation() = Eigen::Vector3d(-0.1, 0, 0);
  b.translation() = Eigen::Vector3d(0.1, 0.01, 0);
  w.add_body(Body(ball_tet_mesh(0.1, n), m, false, a));
  w.add_body(Body(ball_tet_mesh(0.1, n), m, false, b));
  w.add_body(Body(box_tet_mesh(Eigen::Vector3d(-0.5, -0.2, -0.5), Eigen::Vector3d(0.5, -0.1, 0.5),
                               Eigen::Vector3i(5, 1, 5)),
                  Material{}, true));
  State s = w.initial_state();
  RowMatrixX3d ext = RowMatrixX3d::Zero(s.x.rows(), 3);
  for (int i = 0; i < s.x.rows(); ++i) ext(i, 0) = (i < w.body(0).vertices() ? 10.0 : -10.0) * w.masses()(i);
  return {std::move(w), std::move(s), std::move(ext)};
}

void BM_FemStep(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0)), threads = static_cast<int>(st.range(1));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  Scene sc = make_scene(n);
  for (int k = 0; k < 300; ++k) sc.world.step(sc.state, &sc.ext);  // warm up, get in contact
  // Measured window: steps 300..600, replayed (the balls bounce apart after ~1 s simulated, so a
  // free run would time a contact-free scene); restoring the State is a copy, negligible.
  const State in_contact = sc.state;
  int k = 0;
  for (auto _ : st) {
    sc.world.step(sc.state, &sc.ext);
    if (++k == 300) {
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
