// squeeze::plan — manipulation forces (Rodriguez, Lien, Amato, ICRA 2006, Sec. V-A).
//
// A Control is what one edge of the planning tree applies to the robot for its duration:
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
// Body and control-point forces are constant over the edge.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "squeeze/fem/body.h"
#include "squeeze/fem/world.h"

namespace squeeze::plan {

enum class ForceKind { body, control_point, interpolation };
/// "body", "control_point", "interpolation".
const char* to_string(ForceKind kind);
/// Inverse of to_string; throws InputError naming `what` on anything else.
ForceKind force_kind_from_string(const std::string& name, const std::string& what);

struct Control {
  ForceKind kind = ForceKind::body;
  Eigen::Vector3d target{0, 0, 0};  // m: the sample x (body, control point) or the goal (interpolation)
  double force = 0;                 // N: total magnitude (body, control point); cap F (interpolation)
  int vertex = -1;                  // control point: robot vertex (index within the robot's mesh)
  double radius = 0;                // m: control point radius
  double omega = 0;                 // 1/s: interpolation spring frequency ω
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
  Eigen::Vector3d gravity{0, 0, 0};  // m/s², what gravity does to it (zero if its gravity is off)
  /// Throws InputError if object `b` is rigid or has no movable vertex.
  Robot(const fem::World& world, int b, const Eigen::Vector3d& gravity);
  Robot() = default;
  /// Mass-weighted centre of the robot's movable vertices in state s (m).
  Eigen::Vector3d com(const fem::State& s) const;
};

/// A control made ready for one edge: constant forces precomputed for the start state.
class AppliedControl {
 public:
  /// start: the state the edge starts from (directions and the control point set are taken there).
  AppliedControl(const Robot& robot, const Control& control, const fem::State& start);
  /// Adds this step's manipulation forces (N) to the robot's rows of F (#N by 3, all state rows).
  void add_forces(const fem::State& s, fem::RowMatrixX3d& F) const;
  bool constant() const { return control_.kind != ForceKind::interpolation; }

 private:
  const Robot* robot_;
  Control control_;
  std::vector<int> rows_;           // robot vertices that get a constant force
  std::vector<Eigen::Vector3d> f_;  // their forces
};

}  // namespace squeeze::plan
