#include "squeeze/fem/integrator.h"

#include <Eigen/LU>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "squeeze/common/error.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/world.h"

// The registry: one line names every integrator. Each NAME is defined in fem/src/NAME.cpp as
// `std::unique_ptr<TimeIntegrator> make_NAME_integrator()`.
#define SQUEEZE_INTEGRATORS(X) X(verlet) X(implicit)

namespace squeeze::fem {

#define SQUEEZE_DECLARE_INTEGRATOR(NAME) std::unique_ptr<TimeIntegrator> make_##NAME##_integrator();
SQUEEZE_INTEGRATORS(SQUEEZE_DECLARE_INTEGRATOR)
#undef SQUEEZE_DECLARE_INTEGRATOR

namespace {
struct Entry {
  const char* name;
  std::unique_ptr<TimeIntegrator> (*make)();
};
const std::vector<Entry>& registry() {
#define SQUEEZE_INTEGRATOR_ENTRY(NAME) Entry{#NAME, &make_##NAME##_integrator},
  static const std::vector<Entry> table = {SQUEEZE_INTEGRATORS(SQUEEZE_INTEGRATOR_ENTRY)};
#undef SQUEEZE_INTEGRATOR_ENTRY
  return table;
}
}  // namespace

std::vector<std::string> integrator_names() {
  std::vector<std::string> names;
  for (const Entry& e : registry()) names.emplace_back(e.name);
  return names;
}

std::unique_ptr<TimeIntegrator> make_integrator(const std::string& name) {
  for (const Entry& e : registry())
    if (name == e.name) return e.make();
  std::string list;
  for (const Entry& e : registry()) list += (list.empty() ? "\"" : ", \"") + std::string(e.name) + "\"";
  throw InputError("integrator: unknown integrator \"" + name + "\" (known: " + list + ")");
}

std::string describe_integrator_stats(const World& w) {
  const TimeIntegrator& i = w.integrator();
  const IntegratorStats& s = i.stats();
  std::ostringstream o;
  o << i.name() << ": " << s.steps << " steps";
  if (s.substeps != s.steps) o << ", " << s.substeps << " substeps";
  if (s.iterations > 0 || std::string(i.name()) != "verlet") {
    o << std::setprecision(3) << ", " << (s.substeps ? double(s.iterations) / s.substeps : 0.0)
      << " Newton iterations per substep, " << s.factorizations << " factorisations, " << s.cg_iterations
      << " CG iterations, " << s.contact_rounds << " contact rounds; " << s.not_converged
      << " substeps stopped at the iteration limit";
  }
  return o.str();
}

void damp_deformation(const World& w, State& s, double h) {
  const Eigen::VectorXd& mass = w.masses();
  for (int b = 0; b < w.bodies(); ++b) {
    const Body& B = w.body(b);
    const int r0 = w.first_state_row(b);
    const double alpha = B.material.deformation_damping;
    if (r0 < 0 || !(alpha > 0)) continue;
    const int n = B.vertices();
    // Rigid motion with the momentum of the object (sequential: fixed summation order). A pinned
    // object is anchored: its reference motion is rest (v_rigid = 0).
    bool anchored = false;
    for (int i = r0; i < r0 + n && !anchored; ++i) anchored = w.pinned(i);
    Vec3 c = Vec3::Zero(), vcm = Vec3::Zero(), om = Vec3::Zero();
    if (!anchored) {
      double M = 0;
      Vec3 mx = Vec3::Zero(), mv = Vec3::Zero();
      for (int i = r0; i < r0 + n; ++i) {
        M += mass(i);
        mx += mass(i) * Vec3(s.x.row(i).transpose());
        mv += mass(i) * Vec3(s.v.row(i).transpose());
      }
      if (!(M > 0)) continue;
      c = mx / M;
      vcm = mv / M;
      Vec3 L = Vec3::Zero();
      Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
      for (int i = r0; i < r0 + n; ++i) {
        const Vec3 r = Vec3(s.x.row(i).transpose()) - c;
        L += mass(i) * r.cross(Vec3(s.v.row(i).transpose()) - vcm);
        I += mass(i) * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      }
      const Eigen::FullPivLU<Eigen::Matrix3d> lu(I);
      if (lu.isInvertible()) om = lu.solve(L);
    }
    const double keep = std::exp(-alpha * h);
    for (int i = r0; i < r0 + n; ++i) {
      if (w.pinned(i)) continue;
      const Vec3 vr = vcm + om.cross(Vec3(s.x.row(i).transpose()) - c);
      s.v.row(i) = (vr + keep * (Vec3(s.v.row(i).transpose()) - vr)).transpose();
    }
  }
}

}  // namespace squeeze::fem
