// squeeze::fem — the time-integrator seam: how a world's state advances by one step h.
//
// An integrator advances a State with the forces of the model (forces.h: assemble_forces, or the
// per-element kernels of constraints.h) and the world's rest data; it holds no state of the
// simulation itself, only scratch and statistics, so one World can swap integrators between
// steps. World::step calls the world's integrator (WorldOptions::integrator, World::set_integrator).
//
// Registered integrators (make_integrator):
//   "verlet"    the paper's explicit Verlet step (Rodriguez 2006 Sec. IV-B; Teschner 2004 Sec. 4),
//               fem/src/verlet.cpp
//   "implicit"  backward Euler, the same model's incremental potential minimised by Newton's
//               method (implicit.h), fem/src/implicit.cpp
//
// To add one: a class deriving from TimeIntegrator in its own file fem/src/NAME.cpp defining
// `std::unique_ptr<TimeIntegrator> make_NAME_integrator()`, that file in fem/CMakeLists.txt, and NAME
// in the one registration line of fem/src/integrator.cpp.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "squeeze/fem/forces.h"
#include "squeeze/fem/state.h"

namespace squeeze::fem {

class World;

/// What an integrator did so far (World::integrator().stats(); `-v` reports it).
struct IntegratorStats {
  long long steps = 0;          // step() calls
  long long substeps = 0;       // solves: substeps of the implicit integrator, steps of Verlet
  long long iterations = 0;     // Newton iterations (implicit)
  long long not_converged = 0;  // substeps that stopped at the iteration limit
  long long contact_rounds = 0; // extra solves after new contacts were found at a result
  long long factorizations = 0; // sparse factorisations of a Hessian (implicit)
  long long cg_iterations = 0;  // preconditioned conjugate-gradient iterations (implicit)
};

class TimeIntegrator {
 public:
  virtual ~TimeIntegrator() = default;
  /// The registered name ("verlet", ...).
  virtual const char* name() const = 0;
  /// A fresh integrator of the same kind and settings (World copies get their own).
  virtual std::unique_ptr<TimeIntegrator> clone() const = 0;
  /// Advances s by world.time_step(). external: #N by 3 forces (N) per state row, or null.
  /// world is prepared (World::step does it); ws is the scratch of this thread. Pinned vertices
  /// keep their positions with zero velocity.
  virtual void step(const World& world, State& s, const RowMatrixX3d* external, ForceWorkspace& ws) = 0;
  /// Forgets what earlier steps left to speed up later ones (the implicit integrator's lagged
  /// preconditioner and the contacts it carries from one substep to the next). A step's result depends on the state and on the steps since the last
  /// reset(), so whoever must reproduce a run bit for bit from a stored state (the planner's
  /// propagators, the replay) resets before it. Counters are kept.
  virtual void reset() {}
  /// Counters since construction (or reset_stats).
  const IntegratorStats& stats() const { return stats_; }
  void reset_stats() { stats_ = IntegratorStats{}; }

 protected:
  IntegratorStats stats_;
};

/// One line: the world's integrator and its counters ("implicit: 60 steps, 61 substeps, 3.1 Newton
/// iterations per substep, …; 0 substeps stopped at the iteration limit").
std::string describe_integrator_stats(const World& world);

/// The registered integrator names, in registration order.
std::vector<std::string> integrator_names();
/// A new integrator by name. Throws InputError naming the registered ones if `name` is unknown.
std::unique_ptr<TimeIntegrator> make_integrator(const std::string& name);

/// Deformation damping of every object with Material::deformation_damping α > 0 (Müller et al.,
/// "Position based dynamics", VRIPHYS 2006, Sec. 3.5; see body.h): the velocities of its free
/// vertices become v_rigid + e^(−α h)(v − v_rigid), v_rigid the rigid motion with the object's
/// linear and angular momentum (zero for an object with a pinned vertex). Sequential, fixed order.
///   h  time step (s)
void damp_deformation(const World& world, State& s, double h);

}  // namespace squeeze::fem
