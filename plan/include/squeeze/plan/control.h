// squeeze::plan — manipulation forces (Rodriguez, Lien, Amato, ICRA 2006, Sec. V-A) and their
// registry.
//
// A Control is what one edge of the planning tree applies to the robot for its duration. Its kind
// is an entry of the control registry (control_kinds()); the built-in kinds, in sampling order:
//   body           every robot vertex i gets f_i = F · (m_i / M) · d, d the unit vector from the
//                  robot's centre of mass (in the state the edge starts from) toward `target`:
//                  a translation of the whole robot.
//   control_point  the robot vertex `vertex` and every robot vertex within `radius` of it (in
//                  the start state) get f_i = F · (m_i / M_S) · d, d from that vertex toward
//                  `target`, M_S their mass: turns and bends the robot.
//   interpolation  pulls every robot vertex toward its place in the goal configuration (the rest
//                  shape translated so that its centre of mass is at `target`): a critically
//                  damped spring per vertex, a_i = ω² (g_i − x_i) − 2 ω v_i, clamped to
//                  |a_i| <= F / M, plus the robot's own gravity cancelled; f_i = m_i a_i. Recomputed
//                  every step (it depends on the state). Used toward the goal (paper V-A) and, at
//                  the end of a replayed path, to bring the robot to rest there (paper V-B).
//
// A kind owns everything about itself: its name (the plan file's "kind" and the planner block's
// weights key), default weight, how the planner samples its parameters, the forces it applies and
// its JSON keys. To add one: a ControlKind in its own file plan/src/controls/NAME.cpp defining
// `const ControlKind& NAME_control()`, that file in plan/CMakeLists.txt, and NAME in the one
// registration line of plan/src/control_registry.cpp.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "squeeze/fem/world.h"
#include "squeeze/plan/random.h"

namespace squeeze {
struct JsonChecker;
}

namespace squeeze::plan {

class ControlKind;

struct Control {
  const ControlKind* kind = nullptr;  // an entry of control_kinds()
  Eigen::Vector3d target{0, 0, 0};    // m: the sample x, or the goal for kinds that go toward it
  double force = 0;                   // N: total magnitude, or a cap (interpolation)
  int vertex = -1;                    // robot vertex (index within the robot's mesh), if the kind uses one
  double radius = 0;                  // m, if the kind uses one
  double omega = 0;                   // 1/s, if the kind uses one
  Eigen::Vector4d param = Eigen::Vector4d::Zero();  // free parameters of kinds that need more
};

/// What the forces need to know about the robot (one deformable object of the world).
struct Robot {
  int body = -1;              // object index in the world
  int first_row = 0;          // its first state row
  int vertices = 0;
  Eigen::VectorXd mass;       // #vertices kg (0 for pinned vertices: they get no force)
  double total_mass = 0;      // kg, of the movable vertices
  fem::RowMatrixX3d rest;     // #vertices by 3 rest positions (m)
  Eigen::Vector3d rest_com;   // m, mass-weighted
  Eigen::Vector3d gravity{0, 0, 0};  // m/s², what gravity does to it (World::gravity_of)
  std::vector<int> surface;   // movable vertices on the surface (all movable ones if none is)
  Eigen::VectorXd attach_k;   // #vertices N/m: stiffness of each vertex's soft attachment (World::attach; 0: none)
  fem::RowMatrixX3d anchor;   // #vertices by 3 (m): where each attachment spring has zero length (the rest
                              // position, raised by m g / k where it carries the weight)
  /// Throws InputError if object `b` is rigid or has no movable vertex; std::logic_error if the robot
  /// has soft attachments and `world` is not prepared (World::attachment_anchor).
  Robot(const fem::World& world, int b);
  Robot() = default;
  /// Mass-weighted centre of the robot's movable vertices in state s (m).
  Eigen::Vector3d com(const fem::State& s) const;
};

/// What a kind's sampler may use besides the random stream.
struct SamplingContext {
  const Robot* robot = nullptr;
  double max_force = 0;            // N, PlannerOptions::max_force
  double control_radius = 0;       // m, PlannerOptions::control_radius
  double interpolation_omega = 0;  // 1/s, PlannerOptions::interpolation_omega
};

/// The forces of one control on one edge, ready to apply (constant parts precomputed for the
/// state the edge starts from).
class AppliedControl {
 public:
  virtual ~AppliedControl() = default;
  /// Adds this step's manipulation forces (N) to the robot's rows of F (#N by 3, all state rows).
  virtual void add_forces(const fem::State& s, fem::RowMatrixX3d& F) const = 0;
  /// True if add_forces does not depend on s (the propagator then sums them once per edge).
  virtual bool constant() const = 0;
};

class ControlKind {
 public:
  virtual ~ControlKind() = default;
  /// Its name: "body", "control_point", ... (JSON "kind", planner.weights key).
  virtual const char* name() const = 0;
  /// Weight in the planner's draw when the scene gives none.
  virtual double default_weight() const = 0;
  /// True if its target is always the goal (the planner then draws no sample point for it).
  virtual bool toward_goal() const { return false; }
  /// Draws the kind's parameters of c (kind and target are set) from rng, in a fixed order.
  virtual void sample(Control& c, const SamplingContext& ctx, Random& rng) const = 0;
  /// Its forces for an edge starting in `start`. Throws InputError if c does not fit the robot.
  virtual std::unique_ptr<AppliedControl> apply(const Robot& robot, const Control& c, const fem::State& start) const = 0;
  /// Checks c against the robot before a replay; throws InputError "what: problem" if it cannot apply.
  virtual void validate(const Control& c, const Robot& robot, const std::string& what) const;
  /// Its own JSON keys beside "kind", "target", "force", "steps", "duration".
  virtual std::vector<std::string> json_keys() const { return {}; }
  /// Writes / reads its own keys. read: throws InputError "FILE: PATH.KEY: problem".
  virtual void to_json(const Control& c, nlohmann::json& j) const;
  virtual void from_json(const JsonChecker& check, const nlohmann::json& j, const std::string& path, Control& c) const;
};

/// The registered kinds, in sampling order (the order of the planner's weights).
const std::vector<const ControlKind*>& control_kinds();
/// The kind called `name`; throws InputError "what: must be one of ..." otherwise.
const ControlKind& control_kind(const std::string& name, const std::string& what = "control kind");
/// A kind's position in control_kinds() (for per-kind arrays such as the weights).
int control_kind_index(const ControlKind& kind);

/// The forces of control c on the robot for an edge starting in `start` (c.kind->apply).
std::unique_ptr<AppliedControl> apply_control(const Robot& robot, const Control& c, const fem::State& start);

/// Constant forces on some robot rows: what the body and control-point kinds apply.
class ConstantForces : public AppliedControl {
 public:
  ConstantForces(std::vector<int> rows, std::vector<Eigen::Vector3d> forces)
      : rows_(std::move(rows)), f_(std::move(forces)) {}
  void add_forces(const fem::State& s, fem::RowMatrixX3d& F) const override;
  bool constant() const override { return true; }

 private:
  std::vector<int> rows_;           // state rows that get a force
  std::vector<Eigen::Vector3d> f_;  // their forces (N)
};

}  // namespace squeeze::plan
