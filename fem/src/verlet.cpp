// The paper's time integrator: explicit Verlet with a fixed step h (Rodriguez, Lien, Amato, ICRA
// 2006, Sec. IV-B; Teschner et al. 2004, Sec. 4):
//   x_{n+1} = 2 x_n − x_{n−1} + h² a_n,  carried as  v_{n+1} = v_n + h a_n,  x_{n+1} = x_n + h v_{n+1}
// so the state holds x_n and v_n = (x_n − x_{n−1}) / h; a_n = F(x_n, v_n) / m with F from
// assemble_forces (forces.h). Objects with deformation damping are damped first (damp_deformation).
// Stable below the highest frequency of the stiffest element and contact (stable_time_step,
// scene.h). Pinned vertices and massless ones never move.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "squeeze/fem/integrator.h"
#include "squeeze/fem/world.h"
#include "world_data.h"

namespace squeeze::fem {
namespace {

class VerletIntegrator : public TimeIntegrator {
 public:
  const char* name() const override { return "verlet"; }
  std::unique_ptr<TimeIntegrator> clone() const override { return std::make_unique<VerletIntegrator>(); }
  void step(const World& world, State& s, const RowMatrixX3d* external, ForceWorkspace& ws) override;

 private:
  RowMatrixX3d F_;  // scratch: the step's forces
};

void VerletIntegrator::step(const World& w, State& s, const RowMatrixX3d* external, ForceWorkspace& ws) {
  const WorldData& d = w.data();
  const double h = w.time_step();
  damp_deformation(w, s, h);
  assemble_forces(w, s, external, ws, F_);
  s.overlap = ws.overlap();  // rest overlaps shrunk where vertices came out (State::overlap)
  tbb::parallel_for(tbb::blocked_range<int>(0, d.rows, 512), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) {
      if (d.pinned[i]) {
        s.v.row(i).setZero();
        continue;
      }
      s.v.row(i) += (h * d.inv_mass(i)) * F_.row(i);
      s.x.row(i) += h * s.v.row(i);
    }
  });
  s.time += h;
  ++stats_.steps;
  ++stats_.substeps;
}

}  // namespace

std::unique_ptr<TimeIntegrator> make_verlet_integrator() { return std::make_unique<VerletIntegrator>(); }

}  // namespace squeeze::fem
