// squeeze::plan — how a planner advances a state: the propagator of OMPL's kinodynamic planners
// (ompl::control::StatePropagator): propagate(state, control, duration, result). The simulation
// propagator runs the steps of paper Algorithm 1, lines 7–11: every step the world computes
// collisions and penalty forces, and the control adds the manipulation forces.
#pragma once
#include <Eigen/Geometry>
#include <chrono>
#include <functional>
#include <vector>
#include <memory>

#include "squeeze/fem/scene.h"
#include "squeeze/plan/control.h"

namespace squeeze::plan {

/// Why an expansion was kept or discarded (paper: invalid expansions are not added to the tree).
enum class Validity { valid, diverged, volume, bounds, timeout };
const char* to_string(Validity v);

struct PropagatorOptions {
  double max_volume_change = 0.1;  // fraction: |V/V_ref − 1| above it in any deformable object is invalid
  int check_every = 1;             // steps between validity checks (and at the last step), >= 1
  bool stop_when_invalid = true;   // false: run every step anyway (replay)
  std::vector<double> reference_volume;  // per object, m³: V_ref (the planner's settled start state);
                                         // empty: the rest volumes
};

class Propagator {
 public:
  virtual ~Propagator() = default;
  /// Simulates `steps` time steps from `start` with `control` applied to the robot; `result`
  /// receives the final state (or the state where the expansion became invalid).
  virtual Validity propagate(const fem::State& start, const Control& control, int steps, fem::State& result) = 0;
  /// Like propagate, but an expansion that leaves the bounds or changes a volume beyond the limit
  /// keeps its valid beginning: `result` is the last state that passed a check, *kept the steps to
  /// it, and the return value valid (OMPL's SpaceInformation::propagateWhileValid). Returns the
  /// invalid Validity, with *kept = 0, when no checked state before it was valid, and diverged or
  /// timeout as propagate does. This default runs propagate and keeps all steps or none.
  virtual Validity propagate_while_valid(const fem::State& start, const Control& control, int steps,
                                         fem::State& result, int* kept) {
    const Validity v = propagate(start, control, steps, result);
    *kept = v == Validity::valid ? steps : 0;
    return v;
  }
  /// Time steps simulated by this propagator so far (statistics).
  virtual long long steps_done() const = 0;
  /// The object that made the last propagation invalid (volume: the one beyond the limit), or −1.
  virtual int invalid_object() const { return -1; }
  /// Propagations stop with Validity::timeout at this wall-clock time (the planner's --time-limit
  /// is then kept within one step of simulation).
  void set_deadline(std::chrono::steady_clock::time_point t) { deadline_ = t; }

 protected:
  bool past_deadline() const { return deadline_ != std::chrono::steady_clock::time_point::max() &&
                                      std::chrono::steady_clock::now() >= deadline_; }
  std::chrono::steady_clock::time_point deadline_ = std::chrono::steady_clock::time_point::max();
};

/// Makes one propagator; a planner asks for one per parallel expansion (each used by one thread).
using PropagatorFactory = std::function<std::unique_ptr<Propagator>()>;

/// |V/V0 − 1| of object b of `world` in s (0 for a rigid object; NaN if s is not finite).
double volume_change(const fem::SceneWorld& world, const fem::State& s, int b);

/// The propagator of a scene: a copy of a built SceneWorld (cheap: the rest data is shared).
class SimulationPropagator : public Propagator {
 public:
  /// Throws InputError if the scene's robot is missing or rigid, or options.check_every < 1.
  SimulationPropagator(const fem::SceneWorld& world, const PropagatorOptions& options);

  Validity propagate(const fem::State& start, const Control& control, int steps, fem::State& result) override;
  Validity propagate_while_valid(const fem::State& start, const Control& control, int steps, fem::State& result,
                                 int* kept) override;
  long long steps_done() const override { return steps_done_; }
  int invalid_object() const override { return invalid_object_; }

  /// Called after every step with the state and the number of steps done in this propagation.
  std::function<void(const fem::State&, int)> on_step;

  const fem::SceneWorld& world() const { return world_; }
  fem::SceneWorld& world() { return world_; }
  const Robot& robot() const { return robot_; }
  int goal_object() const { return goal_object_; }
  /// Centre of mass of the goal object in state s (m).
  Eigen::Vector3d goal_com(const fem::State& s) const;
  /// |V/V_ref − 1| of object b in s (PropagatorOptions::reference_volume; 0 for a rigid object; NaN
  /// if s is not finite).
  double volume_change(const fem::State& s, int b) const;
  /// Largest |V/V0 − 1| over the deformable objects in s, and the object (or −1).
  double max_volume_change(const fem::State& s, int* object = nullptr) const;

 private:
  Validity check(const fem::State& s);  // sets invalid_object_
  // propagate() and propagate_while_valid(): with `last_valid`, the last state that passed a
  // check is kept there and its step in *kept.
  Validity run(const fem::State& start, const Control& control, int steps, fem::State& result,
               fem::State* last_valid, int* kept);
  fem::SceneWorld world_;
  PropagatorOptions options_;
  Robot robot_;
  Robot goal_;  // the goal object (usually the robot)
  int goal_object_ = -1;
  fem::RowMatrixX3d F_;
  long long steps_done_ = 0;
  int invalid_object_ = -1;
};

/// Index of the scene's robot; throws InputError "FILE: objects: …" if there is none or several.
int robot_index(const fem::Scene& scene);
/// Index of the scene's goal object (goal.object, else the robot); throws InputError if it is rigid.
int goal_object_index(const fem::Scene& scene);

/// How far (m) a robot vertex may lie past a surface at rest and still count as touching it, not
/// penetrating it: 0.1 % of the robot's mean coarse edge length (0.05 mm for a 20 cm cube of 5 cm
/// edges). A robot resting on the floor or on a face of an obstacle is a valid start.
double touch_tolerance(const fem::Body& robot);

/// Throws InputError "FILE: objects[i].transform: the robot starts inside NAME (…)" if, at rest, a
/// vertex of the robot's coarse mesh lies inside a tetrahedron of another object or a vertex of
/// another object inside a robot tetrahedron, deeper than touch_tolerance from each of its faces —
/// with rest overlaps on (contact.rest_overlap, the default) only if one was placed inside the
/// other (placed_inside: a touching overlap, however deep its coarse meshes make it, is a contact
/// at rest) — or the robot starts below the floor or outside the bounds by more than
/// touch_tolerance.
void check_robot_start(const fem::SceneWorld& world);

/// Whether, at rest, the centre of mass of object a lies inside a tetrahedron of object b or the
/// centre of b inside a tetrahedron of a: one object placed inside the other, not touching it.
bool placed_inside(const fem::World& world, int a, int b);

}  // namespace squeeze::plan
