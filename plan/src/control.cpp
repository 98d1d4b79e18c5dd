#include "squeeze/plan/control.h"

#include <cmath>

#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"

namespace squeeze::plan {

Robot::Robot(const fem::World& world, int b) : body(b), gravity(world.gravity_of(b)) {
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
  attach_k.setZero(vertices);
  anchor = rest;
  for (int i = 0; i < vertices; ++i) {
    if (!(mass(i) > 0)) continue;
    attach_k(i) = world.attachment_stiffness(first_row + i);
    if (attach_k(i) > 0) anchor.row(i) = world.attachment_anchor(first_row + i).transpose();
  }
  for (int i = 0; i < vertices; ++i)
    if (B.on_boundary[i] && mass(i) > 0) surface.push_back(i);
  if (surface.empty())
    for (int i = 0; i < vertices; ++i)
      if (mass(i) > 0) surface.push_back(i);
}

Eigen::Vector3d Robot::com(const fem::State& s) const {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i = 0; i < vertices; ++i) c += mass(i) * s.x.row(first_row + i).transpose();
  return c / total_mass;
}

void ConstantForces::add_forces(const fem::State&, fem::RowMatrixX3d& F) const {
  for (size_t k = 0; k < rows_.size(); ++k) F.row(rows_[k]) += f_[k].transpose();
}

void ControlKind::validate(const Control&, const Robot&, const std::string&) const {}
void ControlKind::to_json(const Control&, nlohmann::json&) const {}
void ControlKind::from_json(const JsonChecker&, const nlohmann::json&, const std::string&, Control&) const {}

const ControlKind& control_kind(const std::string& name, const std::string& what) {
  for (const ControlKind* k : control_kinds())
    if (name == k->name()) return *k;
  std::string list;
  for (const ControlKind* k : control_kinds()) list += (list.empty() ? "\"" : ", \"") + std::string(k->name()) + "\"";
  throw InputError(what + ": must be one of " + list + ", got \"" + name + "\"");
}

int control_kind_index(const ControlKind& kind) {
  const auto& kinds = control_kinds();
  for (size_t i = 0; i < kinds.size(); ++i)
    if (kinds[i] == &kind) return static_cast<int>(i);
  return -1;
}

std::unique_ptr<AppliedControl> apply_control(const Robot& robot, const Control& c, const fem::State& start) {
  if (!c.kind) throw std::invalid_argument("apply_control: a control without a kind");
  return c.kind->apply(robot, c, start);
}

}  // namespace squeeze::plan
