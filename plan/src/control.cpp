#include "squeeze/plan/control.h"

#include <cmath>

#include "squeeze/common/error.h"

namespace squeeze::plan {

const char* to_string(ForceKind kind) {
  switch (kind) {
    case ForceKind::body: return "body";
    case ForceKind::control_point: return "control_point";
    case ForceKind::interpolation: return "interpolation";
  }
  return "?";
}

ForceKind force_kind_from_string(const std::string& name, const std::string& what) {
  if (name == "body") return ForceKind::body;
  if (name == "control_point") return ForceKind::control_point;
  if (name == "interpolation") return ForceKind::interpolation;
  throw InputError(what + ": must be \"body\", \"control_point\" or \"interpolation\", got \"" + name + "\"");
}

Robot::Robot(const fem::World& world, int b, const Eigen::Vector3d& g) : body(b), gravity(g) {
  const fem::Body& B = world.body(b);
  if (B.rigid) throw InputError("the robot (object " + std::to_string(b) + ") is rigid: it cannot be moved");
  first_row = world.first_state_row(b);
  vertices = B.vertices();
  mass.resize(vertices);
  rest = B.rest;
  rest_com.setZero();
  total_mass = 0;
  for (int i = 0; i < vertices; ++i) {
    mass(i) = world.pinned(first_row + i) ? 0.0 : world.masses()(first_row + i);
    total_mass += mass(i);
    rest_com += mass(i) * rest.row(i).transpose();
  }
  if (!(total_mass > 0)) throw InputError("the robot (object " + std::to_string(b) + ") has no movable vertex");
  rest_com /= total_mass;
}

Eigen::Vector3d Robot::com(const fem::State& s) const {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i = 0; i < vertices; ++i) c += mass(i) * s.x.row(first_row + i).transpose();
  return c / total_mass;
}

AppliedControl::AppliedControl(const Robot& robot, const Control& control, const fem::State& start)
    : robot_(&robot), control_(control) {
  if (control.kind == ForceKind::interpolation) return;
  Eigen::Vector3d from;
  std::vector<int> set;
  double set_mass = 0;
  if (control.kind == ForceKind::body) {
    from = robot.com(start);
    for (int i = 0; i < robot.vertices; ++i)
      if (robot.mass(i) > 0) set.push_back(i);
    set_mass = robot.total_mass;
  } else {
    if (control.vertex < 0 || control.vertex >= robot.vertices)
      throw InputError("control point vertex " + std::to_string(control.vertex) + " is not a robot vertex (0.." +
                       std::to_string(robot.vertices - 1) + ")");
    from = start.x.row(robot.first_row + control.vertex).transpose();
    const double r2 = control.radius * control.radius;
    for (int i = 0; i < robot.vertices; ++i)
      if (robot.mass(i) > 0 && (start.x.row(robot.first_row + i).transpose() - from).squaredNorm() <= r2) {
        set.push_back(i);
        set_mass += robot.mass(i);
      }
  }
  Eigen::Vector3d d = control.target - from;
  const double len = d.norm();
  if (!(len > 0) || set.empty() || !(set_mass > 0)) return;  // no direction: no force (a valid, idle edge)
  d /= len;
  for (int i : set) {
    rows_.push_back(robot.first_row + i);
    f_.push_back(control.force * (robot.mass(i) / set_mass) * d);
  }
}

void AppliedControl::add_forces(const fem::State& s, fem::RowMatrixX3d& F) const {
  if (control_.kind != ForceKind::interpolation) {
    for (size_t k = 0; k < rows_.size(); ++k) F.row(rows_[k]) += f_[k].transpose();
    return;
  }
  const Robot& r = *robot_;
  const double w = control_.omega, a_max = control_.force / r.total_mass;
  const Eigen::Vector3d shift = control_.target - r.rest_com;
  for (int i = 0; i < r.vertices; ++i) {
    if (r.mass(i) <= 0) continue;
    const int row = r.first_row + i;
    const Eigen::Vector3d goal = r.rest.row(i).transpose() + shift;
    Eigen::Vector3d a = w * w * (goal - s.x.row(row).transpose()) - 2 * w * s.v.row(row).transpose();
    const double n = a.norm();
    if (n > a_max) a *= a_max / n;
    F.row(row) += (r.mass(i) * (a - r.gravity)).transpose();
  }
}

}  // namespace squeeze::plan
