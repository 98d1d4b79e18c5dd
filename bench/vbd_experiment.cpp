// An experiment, not an integrator users can pick: Vertex Block Descent (Chen, Macklin et al.,
// "Vertex Block Descent", ACM TOG 43(4), SIGGRAPH 2024) on the same incremental potential as the
// implicit integrator (implicit.h: Teschner's distance and volume energies, their damping, gravity,
// the floor's penalty and damping, deformation damping), against the implicit integrator's
// Newton-PCG, on a scene with one deformable object and the floor (default
// bench/scenes/ball_drop.json; object-object and self contacts are not in this VBD, so scenes with
// them do not compare). Plain VBD: vertices coloured greedily (no two in one element share a
// colour), each colour's vertices in parallel take one 3×3 Newton step on the potential with the
// others fixed (the diagonal blocks of the element Hessians, psd for the edges), a given number of
// sweeps per step from the inertial target y, no Chebyshev acceleration. Both solve every step
// without substeps (motion_fraction huge), against a reference of Newton at tolerance 1e-7.
// It reads the world's elements from fem's private world_data.h (a bench of the solver, not of
// the public API). Results: bench/README.md ("Vertex Block Descent").
//   build/bench/vbd_experiment [SCENE.json [SECONDS]]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>
#include <tbb/parallel_for.h>
#include "squeeze/common/error.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/implicit.h"
#include "squeeze/fem/integrator.h"
#include "squeeze/fem/scene.h"
#include "../fem/src/world_data.h"
using namespace squeeze;
using namespace squeeze::fem;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

struct Vbd : TimeIntegrator {
  int iters;
  explicit Vbd(int n) : iters(n) {}
  const char* name() const override { return "vbd"; }
  std::unique_ptr<TimeIntegrator> clone() const override { return std::make_unique<Vbd>(iters); }
  bool fitted = false;
  std::vector<std::vector<int>> vedges, vtets, colors;
  void fit(const WorldData& d) {
    if (fitted) return;
    fitted = true;
    vedges.assign(d.rows, {});
    vtets.assign(d.rows, {});
    for (size_t e = 0; e < d.edges.size(); ++e) vedges[d.edges[e].i].push_back(e), vedges[d.edges[e].j].push_back(e);
    for (size_t t = 0; t < d.tet_elems.size(); ++t)
      for (int a = 0; a < 4; ++a) vtets[d.tet_elems[t].v[a]].push_back(t);
    // greedy colouring: vertices sharing an element differ
    std::vector<int> col(d.rows, -1);
    for (int i = 0; i < d.rows; ++i) {
      std::vector<char> used(64, 0);
      for (int t : vtets[i])
        for (int a = 0; a < 4; ++a) { int v = d.tet_elems[t].v[a]; if (col[v] >= 0 && col[v] < 64) used[col[v]] = 1; }
      for (int e : vedges[i]) { int v = d.edges[e].i == i ? d.edges[e].j : d.edges[e].i; if (col[v] >= 0 && col[v] < 64) used[col[v]] = 1; }
      int c = 0; while (used[c]) ++c;
      col[i] = c;
      if ((int)colors.size() <= c) colors.resize(c + 1);
      colors[c].push_back(i);
    }
  }
  void step(const World& w, State& s, const RowMatrixX3d*, ForceWorkspace&) override {
    const WorldData& d = w.data();
    const WorldOptions& o = w.options();
    fit(d);
    const double h = w.time_step();
    damp_deformation(w, s, h);
    const RowMatrixX3d xn = s.x;
    RowMatrixX3d y = xn;
    for (int i = 0; i < d.rows; ++i)
      if (!d.pinned[i] && d.mass(i) > 0) y.row(i) += h * s.v.row(i) + h * h * o.gravity.transpose();
    RowMatrixX3d x = y;
    std::vector<Vec3> eg(d.edges.size());
    for (size_t e = 0; e < d.edges.size(); ++e)
      distance_constraint(Vec3(xn.row(d.edges[e].i).transpose()), Vec3(xn.row(d.edges[e].j).transpose()), d.edges[e].D0, &eg[e]);
    std::vector<std::array<Vec3, 4>> tg(d.tet_elems.size());
    for (size_t t = 0; t < d.tet_elems.size(); ++t) {
      const auto& T = d.tet_elems[t];
      volume_constraint(Vec3(xn.row(T.v[0]).transpose()), Vec3(xn.row(T.v[1]).transpose()), Vec3(xn.row(T.v[2]).transpose()),
                        Vec3(xn.row(T.v[3]).transpose()), T.V0, tg[t].data());
    }
    std::vector<char> floor_damped(d.rows, 0);
    if (o.floor) for (int i = 0; i < d.rows; ++i) floor_damped[i] = xn(i, 1) < o.floor_height;
    for (int it = 0; it < iters; ++it) {
      for (const auto& cv : colors) {
        tbb::parallel_for(size_t(0), cv.size(), [&](size_t q) {
          const int i = cv[q];
          if (d.pinned[i] || !(d.mass(i) > 0)) return;
          const double mh = d.mass(i) / (h * h);
          Vec3 f = -mh * Vec3((x.row(i) - y.row(i)).transpose());
          Mat3 H = mh * Mat3::Identity();
          for (int e : vedges[i]) {
            const auto& E = d.edges[e];
            Vec3 gj;
            const double C = distance_constraint(Vec3(x.row(E.i).transpose()), Vec3(x.row(E.j).transpose()), E.D0, &gj);
            const Vec3 gi = E.j == i ? gj : Vec3(-gj);
            f -= E.k * C * gi;
            H += distance_hessian(Vec3(x.row(E.i).transpose()), Vec3(x.row(E.j).transpose()), E.D0, E.k, true);
            if (E.kd > 0) {
              const Vec3 gn = E.j == i ? eg[e] : Vec3(-eg[e]);
              const double rate = eg[e].dot(Vec3((x.row(E.j) - xn.row(E.j) - x.row(E.i) + xn.row(E.i)).transpose()));
              f -= (E.kd / h) * rate * gn;
              H += (E.kd / h) * gn * gn.transpose();
            }
          }
          for (int t : vtets[i]) {
            const auto& T = d.tet_elems[t];
            Vec3 g[4];
            const double C = volume_constraint(Vec3(x.row(T.v[0]).transpose()), Vec3(x.row(T.v[1]).transpose()),
                                               Vec3(x.row(T.v[2]).transpose()), Vec3(x.row(T.v[3]).transpose()), T.V0, g);
            int a = 0; while (T.v[a] != i) ++a;
            f -= T.k * C * g[a];
            H += T.k * g[a] * g[a].transpose();
            if (T.kd > 0) {
              double rate = 0;
              for (int b = 0; b < 4; ++b) rate += tg[t][b].dot(Vec3((x.row(T.v[b]) - xn.row(T.v[b])).transpose()));
              f -= (T.kd / h) * rate * tg[t][a];
              H += (T.kd / h) * tg[t][a] * tg[t][a].transpose();
            }
          }
          if (o.floor && x(i, 1) < o.floor_height) { f.y() += d.contact_k(i) * (o.floor_height - x(i, 1)); H(1, 1) += d.contact_k(i); }
          if (o.floor && floor_damped[i] && x(i, 1) < xn(i, 1)) { f.y() -= d.contact_c(i) / h * (x(i, 1) - xn(i, 1)); H(1, 1) += d.contact_c(i) / h; }
          x.row(i) += H.ldlt().solve(f).transpose();
        });
      }
    }
    for (int i = 0; i < d.rows; ++i) {
      if (d.pinned[i]) { s.v.row(i).setZero(); continue; }
      s.v.row(i) = (x.row(i) - xn.row(i)) / h;
      s.x.row(i) = x.row(i);
    }
    s.time += h;
    ++stats_.steps;
  }
};

int run_experiment(const std::string& file, double duration) {
  Scene scene = load_scene(file);
  scene.integrator = "implicit";
  scene.time_step.reset();
  const SceneWorld built = build_scene(scene);
  const int steps = std::lround(duration / built.world.time_step());
  double edge = 0; int nb = 0;
  for (int b = 0; b < built.world.bodies(); ++b) if (!built.world.body(b).rigid) edge += built.world.body(b).mean_edge_length(), ++nb;
  if (nb == 0) throw InputError(file + ": no deformable object to compare the solvers on");
  edge /= nb;
  auto run = [&](std::unique_ptr<TimeIntegrator> integ, std::vector<RowMatrixX3d>* traj, const std::vector<RowMatrixX3d>* ref, const char* label) {
    SceneWorld w = built;
    w.world.set_integrator(std::move(integ));
    State s = w.world.initial_state();
    double worst = 0, wall = 0;
    for (int k = 0; k < steps; ++k) {
      auto t0 = std::chrono::steady_clock::now();
      w.world.step(s);
      wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (traj) traj->push_back(s.x);
      if (ref) worst = std::max(worst, ((s.x - (*ref)[k]).rowwise().norm()).maxCoeff() / edge);
    }
    double vol = 0;
    for (int b = 0; b < w.world.bodies(); ++b) if (!w.world.body(b).rigid) vol = std::max(vol, std::abs(w.world.body_volume(s, b) / w.rest_volume[b] - 1));
    std::printf("%-40s %7.3f s wall for %.2f s (%.2f sim s per wall s), worst deviation from the reference %.4f edge lengths, volume change %.2f %%\n",
                label, wall, steps * w.world.time_step(), steps * w.world.time_step() / wall, worst, 100 * vol);
  };
  {
    SceneWorld w = built;
    w.world.prepare();
    Vbd probe(1);
    probe.fit(w.world.data());
    std::printf("%s: %d state rows (vertices), %zu colours\n", file.c_str(), w.world.state_rows(), probe.colors.size());
  }
  ImplicitOptions ro; ro.motion_fraction = 1e9; ro.tolerance = 1e-7; ro.max_newton_iterations = 100;
  std::vector<RowMatrixX3d> ref;
  run(make_implicit_integrator(ro), &ref, nullptr, "reference: Newton, tolerance 1e-7");
  ImplicitOptions io; io.motion_fraction = 1e9;
  run(make_implicit_integrator(io), nullptr, &ref, "Newton-PCG, tolerance 1e-3 (default)");
  // One-step error: from each state of the reference, one step of VBD against the reference's next.
  {
    SceneWorld w = built;
    ImplicitOptions ro2 = ro;
    w.world.set_integrator(make_implicit_integrator(ro2));
    State s = w.world.initial_state();
    std::vector<State> states{ s };
    for (int k = 0; k < steps; ++k) { w.world.step(s); states.push_back(s); }
    for (int n : {10, 50, 200, 1000}) {
      SceneWorld v = built;
      v.world.set_integrator(std::make_unique<Vbd>(n));
      double worst = 0, mean = 0;
      for (int k = 0; k < steps; ++k) {
        State t = states[k];
        v.world.step(t);
        const double e = ((t.x - states[k + 1].x).rowwise().norm()).maxCoeff() / edge;
        worst = std::max(worst, e); mean += e / steps;
      }
      std::printf("VBD %4d iterations: one step from the reference state: max vertex error %.4f edge lengths (mean over steps %.4f)\n", n, worst, mean);
    }
  }
  for (int n : {5, 10, 20, 50, 100, 200}) {
    char label[64]; std::snprintf(label, sizeof label, "VBD, %d iterations per step", n);
    run(std::make_unique<Vbd>(n), nullptr, &ref, label);
  }
  return 0;
}

int main(int argc, char** argv) {
  const std::string file = argc > 1 ? argv[1] : SQUEEZE_SOURCE_DIR "/bench/scenes/ball_drop.json";
  char* end = nullptr;
  const double duration = argc > 2 ? std::strtod(argv[2], &end) : 1.0;
  if (argc > 2 && (end == argv[2] || *end != '\0' || !(duration > 0) || !std::isfinite(duration))) {
    std::fprintf(stderr, "vbd_experiment: SECONDS must be a positive number, got '%s'\n", argv[2]);
    return 2;
  }
  try {
    return run_experiment(file, duration);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vbd_experiment: %s\n", e.what());
    return 2;
  }
}
