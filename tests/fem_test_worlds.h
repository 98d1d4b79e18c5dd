// Small fem worlds shared by the fem test executables (test_fem, test_implicit).
#pragma once
#include <string>

#include "squeeze/fem/body.h"
#include "squeeze/fem/world.h"

namespace sqt {

/// A 10 cm cube (2 cells per axis, 27 vertices) under gravity, no floor, no collisions, every
/// vertex attached to its rest position with stiffness k (N/m) and damping c (N·s/m), carrying its
/// weight if carry_weight: at equilibrium the attachments carry the weight, Σ_i k (y0_i − y_i) =
/// M g (internal forces sum to zero), so the mean sag is M g / (N k) exactly. Time step: the
/// WorldOptions default (World::set_time_step to change it).
inline squeeze::fem::World attached_cube(const std::string& integrator, double k, double c, bool carry_weight = false) {
  using namespace squeeze::fem;
  WorldOptions o;
  o.integrator = integrator;
  o.collisions = false;
  World w(o);
  Material m;
  m.k_distance = m.k_volume = 20;
  m.damping_distance = m.damping_volume = 0.01;
  m.deformation_damping = 20;
  w.add_body(Body(box_tet_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.1), Eigen::Vector3i::Constant(2)), m));
  for (int i = 0; i < w.state_rows(); ++i) w.attach(i, k, c, carry_weight);
  return w;
}

}  // namespace sqt
