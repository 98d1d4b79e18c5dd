// One build of the fem stage as a shared library for ab.cpp: the bench_fem scene (two balls
// pushed together on a rigid slab, steps 300.. replayed), with C entry points.
// Built by mklib.sh; see README.md.
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
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

}  // namespace
static std::unique_ptr<Scene> g;
static State g_in;
extern "C" void setup(int n) {
  g = std::make_unique<Scene>(make_scene(n));
  for (int k = 0; k < 300; ++k) g->world.step(g->state, &g->ext);
  g_in = g->state;
}
extern "C" double run(int steps) {  // ns per tet-step over `steps` steps from the in-contact state
  g->state = g_in;
  auto t0 = std::chrono::steady_clock::now();
  for (int s = 0; s < steps; ++s) g->world.step(g->state, &g->ext);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1e9 / steps / g->world.tets();
}
extern "C" unsigned long long state_hash() {
  unsigned long long h = 1469598103934665603ull;
  const double* p = g->state.x.data();
  for (long i = 0; i < g->state.x.size(); ++i) { unsigned long long b; std::memcpy(&b, p + i, 8); h = (h ^ b) * 1099511628211ull; }
  return h;
}
