// squeeze::plan — kinodynamic RRT over the whole deformable state (Rodriguez, Lien, Amato,
// "Planning motion in completely deformable environments", ICRA 2006, Algorithm 1 and Sec. V).
//
// Every node of the tree is a full simulation state: positions and velocities of every movable
// vertex of the robot and of every deformable obstacle. One iteration: sample x in the scene's
// bounds (the goal with probability goal_bias, and always for an interpolation force); take the
// node whose robot centre of mass is nearest to x (kd-tree, nanoflann); draw a manipulation force
// by the weights and a duration dT in [t_min, t_max]; restore the node's state, simulate dT / h
// steps with the force (collisions and penalties every step) and add the result as a child unless
// it is invalid (NaN or blow-up, volume change beyond max_volume_change, robot outside bounds).
// Solved when the goal object's centre of mass is within goal.tolerance of goal.position.
//
// Parallelism and determinism: iterations run in batches of `batch` expansions. All random draws
// of a batch come from one seeded stream, in order, against the tree as it was when the batch
// began; the expansions then run in parallel (one world per worker) and are added in batch order.
// The batch size does not depend on the number of threads, so the same seed gives the same tree
// and the same plan with any number of threads.
//
// Storage: a node keeps one block (x and v) per deformable object; a block bit-identical to the
// parent's (an object at rest, or not touched along the branch) is shared, not copied.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "squeeze/fem/scene.h"
#include "squeeze/plan/control.h"
#include "squeeze/plan/propagator.h"

namespace squeeze {
class Progress;
}

namespace squeeze::plan {

/// Relative weights of the manipulation forces (any scale, >= 0, not all zero).
struct ForceWeights {
  double body = 0.5;
  double control_point = 0.3;
  double interpolation = 0.2;
};

/// The scene's "planner" block (scenes/README.md), defaults filled in.
struct PlannerOptions {
  int iterations = 1000;           // expansions attempted (valid or not)
  std::uint64_t seed = 1;          // of the random stream
  double goal_bias = 0.05;         // probability that x is the goal position
  double t_min = 0.05;             // s, shortest expansion
  double t_max = 0.5;              // s, longest expansion
  double max_force = 0;            // N; scene default: robot mass × max(2 |g|, d / t_max²), d its bbox diagonal
  double control_radius = 0;       // m; scene default: ¼ of the robot's bounding-box diagonal
  double max_volume_change = 0.1;  // fraction of rest volume, any deformable object
  double interpolation_omega = 0;  // 1/s, ω of the interpolation force; default 2π / t_max
  double settle = 1.0;             // s, interpolation phase at the end of a replayed path
  ForceWeights weights;
  int batch = 4;                   // expansions drawn and run together (not a thread count)
  double time_limit = 0;           // s of wall time, 0: none (CLI --time-limit)
};

/// Reads and validates `scene.planner` (errors "FILE: planner.KEY: problem"), deriving the
/// defaults from the built world: max_force from the robot's mass, control_radius from its size.
PlannerOptions planner_options(const fem::SceneWorld& world);

enum class PlanStatus { solved, approximate, failed };
const char* to_string(PlanStatus s);

/// One edge of the path: a control applied for `steps` time steps of h.
struct PathSegment {
  Control control;
  int steps = 0;
};

struct PlanStatistics {
  int iterations = 0;          // expansions attempted
  int nodes = 0;               // tree nodes (root included)
  int discarded_diverged = 0;  // NaN or blow-up
  int discarded_volume = 0;    // volume change beyond max_volume_change
  int discarded_bounds = 0;    // robot left the bounds
  double seconds = 0;          // wall time of planning
  long long simulation_steps = 0;
  double bytes_per_node = 0;   // state storage per node (shared blocks counted once)
  std::size_t state_bytes = 0; // all node states
  std::size_t peak_memory = 0; // bytes, peak resident set of the process (VmHWM), 0 if unknown
  double final_distance = 0;   // m, goal object's centre of mass to the goal, at the path's end
};

struct PlanResult {
  PlanStatus status = PlanStatus::failed;
  PlanStatistics stats;
  double time_step = 0;              // s, h used
  std::vector<PathSegment> path;     // from the start state to the final node
  std::vector<fem::State> path_states;  // state at the end of every segment (path.size())
  Control settle;                       // the replay's final interpolation phase (settle_control)
  int settle_steps = 0;                 // its time steps: options.settle / h
  std::uint64_t final_state_hash = 0;   // state_hash of the final node's state
};

/// Throws InputError "FILE: KEY: problem" unless the world can be planned in: a goal inside the
/// bounds, and the robot starting clear of every other object, above the floor and inside the
/// bounds (check_robot_start). plan() calls it; commands call it early, before other work.
void check_planning_inputs(const fem::SceneWorld& world);

/// FNV-1a 64 of the bytes of s.x and s.v (to check a replay against the tree).
std::uint64_t state_hash(const fem::State& s);

/// Plans from the scene's initial state. Throws InputError if the scene has no goal or no robot,
/// the goal lies outside the bounds, or the robot starts inside another object (check_robot_start).
PlanResult plan(const fem::Scene& scene, const PlannerOptions& options, Progress* progress = nullptr);

/// The states a plan passes through: re-simulates `path` from the scene's initial state with
/// `propagator` (its on_step sees every step), then `settle_steps` of interpolation toward the
/// goal. Returns the state at the end of every path segment (bit-identical to the tree's).
std::vector<fem::State> replay(SimulationPropagator& propagator, const std::vector<PathSegment>& path,
                               const Control& settle, int settle_steps);

/// The settle control of a plan's replay (interpolation to the goal with the planner's cap and ω).
Control settle_control(const SimulationPropagator& propagator, const PlannerOptions& options);

}  // namespace squeeze::plan
