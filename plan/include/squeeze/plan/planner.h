// squeeze::plan — planning the robot's motion in a built scene (Rodriguez, Lien, Amato, "Planning
// motion in completely deformable environments", ICRA 2006, Algorithm 1 and Sec. V).
//
// A Planner (OMPL's ompl::base::Planner) is handed a PlanningProblem: the built scene, its robot,
// the goal, the start state and a factory of propagators (propagator.h) through which it advances
// states; it samples controls through the control registry (control.h). plan() picks the planner
// of PlannerOptions::algorithm from the registry. Registered planners:
//   "rrt"  the paper's kinodynamic RRT (Algorithm 1), rrt.cpp: every tree node is a full
//          simulation state of the robot and every deformable obstacle; see docs/plan.md.
//   "ompl:RRT", "ompl:KPIECE1", "ompl:SST", "ompl:EST", "ompl:PDST"
//          OMPL's control-based planners (libompl 1.5) over the same states, controls and
//          propagator, ompl_planners.cpp (OMPL's headers stay there); see docs/plan.md.
// To add a planner: a class deriving from Planner in its own file plan/src/NAME.cpp defining
// `std::unique_ptr<Planner> make_ID_planner()`, that file in plan/CMakeLists.txt, and
// X("name", ID) in the one registration line of plan/src/planner_registry.cpp.
//
// Determinism: planners draw from a seeded Random (random.h) and must give the same plan for a
// seed whatever the number of threads (the RRT draws a whole batch before running it in parallel).
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

/// Relative weights of the manipulation forces, one per registered kind (control_kinds() order;
/// any scale, >= 0, not all zero). Default: each kind's default_weight.
struct ForceWeights {
  std::vector<double> w;
  ForceWeights();
  /// The weight of the kind called `kind`; throws InputError for an unknown kind.
  double& operator[](const std::string& kind);
  double operator[](const std::string& kind) const;
  double sum() const;  // Σ in registry order
  /// The kind a uniform draw `u` in [0, 1) picks: by the cumulative weights, in registry order (the
  /// last kind takes the rest). The RRT and the OMPL adapters draw their controls through it.
  const ControlKind* pick(double u) const;
};

/// The scene's "planner" block (scenes/README.md), defaults filled in.
struct PlannerOptions {
  std::string algorithm = "rrt";   // planner by name (planner_names())
  int iterations = 1000;           // expansions attempted (valid or not)
  std::uint64_t seed = 1;          // of the random stream
  double goal_bias = 0.05;         // probability that x is the goal position
  double t_min = 0.05;             // s, shortest expansion
  double t_max = 0.5;              // s, longest expansion
  double max_force = 0;            // N; scene default: MaxForceTerms::max_force (the robot's weight, size,
                                   // attachments and stiffness)
  double control_radius = 0;       // m; scene default: ¼ of the robot's bounding-box diagonal
  double max_volume_change = 0.1;  // fraction of rest volume, any deformable object
  double interpolation_omega = 0;  // 1/s, ω of the interpolation force; default 2π / t_max
  double settle = 1.0;             // s, interpolation phase at the end of a replayed path
  double settle_start = -1;        // s simulated without control from the scene's initial state before planning:
                                   // the tree's root and the volume reference of max_volume_change; −1 ("auto"):
                                   // until the scene is at rest (settle_start_state), at most kSettleStartMax
  ForceWeights weights;
  int batch = 4;                   // expansions drawn and run together (not a thread count)
  bool keep_valid_prefix = true;   // an expansion that leaves the bounds or breaks the volume limit keeps
                                   // its valid beginning as the new node (OMPL's propagateWhileValid);
                                   // false: it is discarded whole (the paper's Algorithm 1)
  double time_limit = 0;           // s of wall time, 0: none (CLI --time-limit)
};

/// What the default planner.max_force is made of: the robot's mechanics (docs/plan.md, "max_force").
struct MaxForceTerms {
  double mass = 0;              // kg, of the robot
  double gravity = 0;           // m/s², |g| on the share of its mass its attachments do not carry
  double size = 0;              // m, d: its bounding-box diagonal at rest
  double attach_stiffness = 0;  // N/m, K: the sum of its soft attachments' stiffnesses
  double volume = 0;            // m³, V: its rest volume
  double youngs_modulus = 0;    // Pa, E: Σ k_edge / V, the modulus its distance constraints give (for the
                                // default stiffnesses, the object's youngs_modulus)
  double cross_section = 0;     // m², A = V^(2/3)
  static constexpr double kSqueezeStrain = 0.2;  // ε: the fraction it must be able to compress itself by
  /// N, E · A · ε: the force that compresses it by ε against its own elasticity.
  double squeeze() const { return youngs_modulus * cross_section * kSqueezeStrain; }
  /// N, the default: max(2 m |g| (lift it twice over), m d / t_max² (move it half its size from rest
  /// within t_max: ½ a t² = d / 2), K d / 2 (hold it half its size from its attachments), E A ε).
  double max_force(double t_max) const;
};
/// The terms of the default max_force for the robot of a built scene.
MaxForceTerms max_force_terms(const fem::SceneWorld& world);

/// Reads and validates `scene.planner` (errors "FILE: planner.KEY: problem"), deriving the
/// defaults from the built world: max_force from the robot's mass, control_radius from its size.
PlannerOptions planner_options(const fem::SceneWorld& world);
/// Throws InputError "FILE: planner.KEY: problem" if an option is out of range.
void check_options(const PlannerOptions& options, const std::string& file);

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
  int truncated = 0;           // expansions kept up to their last valid state (keep_valid_prefix)
  std::vector<int> discarded_volume_by_object;  // per object: the expansions it broke the volume limit in
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
  std::vector<fem::State> path_states;  // state at the end of every segment (path.size()); empty for planners
                                        // that keep only the final state (the OMPL ones: final_state_hash)
  Control settle;                       // the replay's final interpolation phase (settle_control)
  int settle_steps = 0;                 // its time steps: options.settle / h
  int start_settle_steps = 0;           // steps without control from the scene's initial state to the start (settle_start)
  std::uint64_t final_state_hash = 0;   // state_hash of the final node's state
  bool timed_out = false;               // stopped by options.time_limit
};

/// What a planner is handed (OMPL: SpaceInformation and ProblemDefinition).
struct PlanningProblem {
  const fem::SceneWorld* world = nullptr;  // the built scene: bounds, time step, objects
  Robot robot;                             // the object the controls move
  Robot goal_object;                       // the object whose centre of mass must reach the goal
  Eigen::Vector3d goal{0, 0, 0};           // m
  double tolerance = 0.05;                 // m
  fem::State start;                        // the settled start (settle_start_state): the tree's root
  int start_settle_steps = 0;              // steps it took from the scene's initial state
  std::vector<double> start_volume;        // per object (m³) in `start`: the reference of max_volume_change
  PropagatorFactory make_propagator;       // one propagator per parallel expansion
};

class Planner {
 public:
  virtual ~Planner() = default;
  virtual const char* name() const = 0;
  /// Plans from problem.start. Honours options.iterations and options.time_limit (stops within one
  /// batch of expansions).
  virtual PlanResult solve(const PlanningProblem& problem, const PlannerOptions& options, Progress* progress) = 0;
};

/// The registered planner names.
std::vector<std::string> planner_names();
/// A planner by name; throws InputError naming the registered ones if `name` is unknown.
std::unique_ptr<Planner> make_planner(const std::string& name);

/// Throws InputError "FILE: KEY: problem" unless the world can be planned in: a goal inside the
/// bounds, and the robot starting clear of every other object, above the floor and inside the
/// bounds (check_robot_start). plan() calls it; commands call it early, before other work.
void check_planning_inputs(const fem::SceneWorld& world);

/// The longest automatic settle before planning (s).
constexpr double kSettleStartMax = 2.0;

/// The start state of planning and replay: the scene's initial state simulated without control for
/// `seconds` (≥ 0), or, with seconds < 0 ("auto"), until every deformable object's kinetic energy
/// per kilogram stays below ½ (1 mm/s)² — the scene is at rest — at most kSettleStartMax. `steps`
/// receives the number of steps taken. Deterministic: replay calls it with the plan's step count
/// (settle_steps ≥ 0 overrides seconds) and gets the same state bit for bit. `progress` (optional)
/// shows the steps as a stage "settling the start".
fem::State settle_start_state(const fem::SceneWorld& world, double seconds, int* steps, int settle_steps = -1,
                              Progress* progress = nullptr);

/// The problem of a built scene: its settled start (options.settle_start). make_propagator: null
/// for copies of the world (SimulationPropagator with max_volume_change from options and the
/// settled start's volumes as reference). `progress` (optional) shows the settle.
PlanningProblem planning_problem(const fem::SceneWorld& world, const PlannerOptions& options,
                                 PropagatorFactory make_propagator = {}, Progress* progress = nullptr);

/// FNV-1a 64 of the bytes of s.x, s.v and s.overlap (to check a replay against the tree).
std::uint64_t state_hash(const fem::State& s);

/// Plans in a built scene from its initial state with the planner of options.algorithm.
/// make_propagator: how expansions advance states (default: copies of `world`). Throws
/// InputError if the scene has no goal or no robot, the goal lies outside the bounds, the robot
/// starts inside another object (check_robot_start), or an option is out of range.
PlanResult plan(const fem::SceneWorld& world, const PlannerOptions& options, Progress* progress = nullptr,
                PropagatorFactory make_propagator = {});

/// The states a plan passes through: re-simulates `path` from `start` (the plan's settled start:
/// settle_start_state with its start_settle_steps) with `propagator` (its on_step sees every step
/// of the path), then `settle_steps` of the settle control. Returns the state at the end of every
/// path segment (bit-identical to the tree's).
std::vector<fem::State> replay(SimulationPropagator& propagator, const fem::State& start,
                               const std::vector<PathSegment>& path, const Control& settle, int settle_steps);

/// The settle control of a plan's replay (interpolation to the goal with the planner's cap and ω).
Control settle_control(const fem::SceneWorld& world, const PlannerOptions& options);

}  // namespace squeeze::plan
