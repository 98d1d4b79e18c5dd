// The scene of bench_fem (and of bench/ab): two deformable voxel balls of radius 0.1 m, n cells
// per axis (about π n³ tets each), pushed into each other by external forces of ±10 m/s² × mass
// along x, on a rigid slab of 150 tets, gravity on. In contact from about step 300
// (kInContactStep) for kReplaySteps steps; the benchmarks replay that window (the balls bounce
// apart after ~1 s simulated, so a free run would time a contact-free scene). Knobs for tuning:
// SQUEEZE_FEM_CELL (hash cell in grid spacings) and SQUEEZE_FEM_TABLE (hash table size) override
// the World's automatic choices.
#pragma once
#include <chrono>
#include <cmath>
#include <cstdlib>

#include "squeeze/fem/world.h"

namespace squeeze::fem::bench {

constexpr int kInContactStep = 300;  // steps from rest until the balls are in contact
constexpr int kReplaySteps = 300;    // length of the in-contact window the benchmarks replay

struct Scene {
  World world;
  State state;
  RowMatrixX3d ext;
};

// Stiffnesses scale with the resolution so that h·ω stays about 0.1 (ω² ∝ k / (D0² m) ∝ k n⁵).
inline Scene make_scene(int n) {
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

// Seconds for `steps` steps of `sc` from `start`, after an untimed warm-up of `warm` steps from
// there (warm caches, threads awake when the previous window ran in another configuration).
inline double run_window(Scene& sc, const State& start, int steps, int warm = 0) {
  sc.state = start;
  for (int k = 0; k < warm; ++k) sc.world.step(sc.state, &sc.ext);
  sc.state = start;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < steps; ++k) sc.world.step(sc.state, &sc.ext);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace squeeze::fem::bench
