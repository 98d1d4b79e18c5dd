#include "squeeze/plan/propagator.h"

#include <cmath>

#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/fem/collision.h"
#include "squeeze/fem/integrator.h"

namespace squeeze::plan {

const char* to_string(Validity v) {
  switch (v) {
    case Validity::valid: return "valid";
    case Validity::diverged: return "diverged";
    case Validity::volume: return "volume";
    case Validity::bounds: return "bounds";
    case Validity::timeout: return "timeout";
  }
  return "?";
}

int robot_index(const fem::Scene& scene) {
  int robot = -1;
  for (size_t i = 0; i < scene.objects.size(); ++i)
    if (scene.objects[i].robot) {
      if (robot >= 0)
        throw InputError(scene.file.string() + ": objects[" + std::to_string(i) + "].role: a second robot (\"" +
                         scene.objects[i].name + "\"; \"" + scene.objects[robot].name + "\" is the robot): only one is allowed");
      robot = static_cast<int>(i);
    }
  if (robot < 0) throw InputError(scene.file.string() + ": objects: no object has \"role\": \"robot\"");
  if (scene.objects[robot].rigid)
    throw InputError(scene.file.string() + ": objects[" + std::to_string(robot) +
                     "].kind: the robot must be deformable (rigid objects never move)");
  return robot;
}

bool placed_inside(const fem::World& world, int a, int b) {
  auto centre_in = [](const fem::Body& p, const fem::Body& q) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    double m = 0;
    for (int i = 0; i < p.vertices(); ++i) {
      const double mi = p.mass.size() ? p.mass(i) : 1.0;
      c += mi * p.rest.row(i).transpose();
      m += mi;
    }
    if (!(m > 0)) return false;
    c /= m;
    for (int t = 0; t < q.tets(); ++t) {
      const fem::TetFrame f(q.rest.row(q.T(t, 0)).transpose(), q.rest.row(q.T(t, 1)).transpose(),
                            q.rest.row(q.T(t, 2)).transpose(), q.rest.row(q.T(t, 3)).transpose());
      Eigen::Vector4d l;
      if (f.contains(c, &l) && l.minCoeff() > -1e-12) return true;
    }
    return false;
  };
  return centre_in(world.body(a), world.body(b)) || centre_in(world.body(b), world.body(a));
}

double touch_tolerance(const fem::Body& robot) { return 1e-3 * robot.mean_edge_length(); }

void check_robot_start(const fem::SceneWorld& w) {
  const fem::Scene& scene = w.scene;
  const int r = robot_index(scene);
  const fem::Body& robot = w.world.body(r);
  const std::string where = scene.file.string() + ": objects[" + std::to_string(r) + "].transform: ";
  // Touching is not penetrating: a robot resting on the floor, on a wall of the bounds or on an
  // obstacle's face (up to rounding of its transform and of its coarse mesh) is a valid start.
  const double tol = touch_tolerance(robot);
  if (scene.floor && robot.rest.col(1).minCoeff() < *scene.floor - tol)
    throw InputError(where + "the robot starts below the floor (y = " + format_number(*scene.floor) +
                     " m; its lowest vertex at " + format_number(robot.rest.col(1).minCoeff()) + " m, tolerance " +
                     format_number(tol) + " m)");
  for (int k = 0; k < 3; ++k)
    if (robot.rest.col(k).minCoeff() < w.bounds.min()(k) - tol || robot.rest.col(k).maxCoeff() > w.bounds.max()(k) + tol)
      throw InputError(where + "the robot starts outside the bounds (its coarse mesh spans " +
                       std::to_string(robot.rest.col(k).minCoeff()) + " .. " + std::to_string(robot.rest.col(k).maxCoeff()) +
                       " on axis " + "xyz"[k] + ", bounds " + std::to_string(w.bounds.min()(k)) + " .. " +
                       std::to_string(w.bounds.max()(k)) + ")");
  // Vertices of `a` inside tetrahedra of `b` (rest positions) deeper than tol from every face of
  // the tetrahedron (a vertex on a face, within tol, touches).
  auto inside = [tol](const fem::Body& a, const fem::Body& b) {
    const Eigen::AlignedBox3d abox(a.rest.colwise().minCoeff().transpose(), a.rest.colwise().maxCoeff().transpose());
    int count = 0;
    for (int t = 0; t < b.tets(); ++t) {
      Eigen::AlignedBox3d tb;
      Eigen::Vector3d p[4];
      for (int k = 0; k < 4; ++k) {
        p[k] = b.rest.row(b.T(t, k)).transpose();
        tb.extend(p[k]);
      }
      if (!tb.intersects(abox)) continue;
      const fem::TetFrame f(p[0], p[1], p[2], p[3]);
      // Height of vertex k over its opposite face: barycentric l_k times it is the distance to that face.
      const double six_v = std::abs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]));
      Eigen::Vector4d height;
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d& q0 = p[(k + 1) % 4];
        const double area2 = (p[(k + 2) % 4] - q0).cross(p[(k + 3) % 4] - q0).norm();  // twice the face's area
        height(k) = area2 > 0 ? six_v / area2 : 0.0;
      }
      for (int i = 0; i < a.vertices(); ++i) {
        if (!tb.contains(a.rest.row(i).transpose())) continue;
        Eigen::Vector4d l;
        if (f.contains(a.rest.row(i).transpose(), &l) && l.minCoeff() > 1e-9 && l.cwiseProduct(height).minCoeff() > tol)
          ++count;
      }
    }
    return count;
  };
  // With rest overlaps (contact.rest_overlap), a robot touching its neighbours at rest is at rest
  // there (the heart at its atlas place); only an object placed inside the other is an error.
  const bool tolerant = w.world.options().rest_overlap;
  for (int b = 0; b < w.world.bodies(); ++b) {
    if (b == r) continue;
    const int n = inside(robot, w.world.body(b)) + inside(w.world.body(b), robot);
    if (n == 0) continue;
    if (tolerant && !placed_inside(w.world, r, b)) continue;
    throw InputError(where + "the robot starts inside \"" + scene.objects[b].name + "\" (" + std::to_string(n) +
                     " vertices of one coarse mesh are inside the other's tetrahedra" +
                     (tolerant ? ", and the centre of one inside the other: placed inside it, not touching it" : std::string()) +
                     ")");
  }
}

int goal_object_index(const fem::Scene& scene) {
  const int r = robot_index(scene);
  if (!scene.goal || scene.goal->object.empty()) return r;
  const int g = scene.find(scene.goal->object);
  if (g < 0) throw InputError(scene.file.string() + ": goal.object: no object is called \"" + scene.goal->object + "\"");
  if (scene.objects[g].rigid)
    throw InputError(scene.file.string() + ": goal.object: \"" + scene.goal->object + "\" is rigid and never moves");
  return g;
}

double volume_change(const fem::SceneWorld& w, const fem::State& s, int b) {
  if (w.world.body(b).rigid) return 0.0;
  return std::abs(w.world.body_volume(s, b) / w.rest_volume[b] - 1.0);
}

SimulationPropagator::SimulationPropagator(const fem::SceneWorld& world, const PropagatorOptions& options)
    : world_(world), options_(options) {
  if (options.check_every < 1)
    throw InputError("propagator: check_every must be >= 1, got " + std::to_string(options.check_every));
  if (!options.reference_volume.empty() && options.reference_volume.size() != static_cast<size_t>(world.world.bodies()))
    throw std::invalid_argument("propagator: reference_volume needs one volume per object");
  const fem::Scene& scene = world_.scene;
  const int r = robot_index(scene);
  robot_ = Robot(world_.world, r);
  goal_object_ = goal_object_index(scene);
  goal_ = goal_object_ == r ? robot_ : Robot(world_.world, goal_object_);
  F_.setZero(world_.world.state_rows(), 3);
}

Eigen::Vector3d SimulationPropagator::goal_com(const fem::State& s) const { return goal_.com(s); }

double SimulationPropagator::volume_change(const fem::State& s, int b) const {
  if (options_.reference_volume.empty()) return plan::volume_change(world_, s, b);
  if (world_.world.body(b).rigid) return 0.0;
  return std::abs(world_.world.body_volume(s, b) / options_.reference_volume[b] - 1.0);
}

double SimulationPropagator::max_volume_change(const fem::State& s, int* object) const {
  double worst = 0;
  if (object) *object = -1;
  for (int b = 0; b < world_.world.bodies(); ++b) {
    if (world_.world.body(b).rigid) continue;
    const double change = volume_change(s, b);
    if (!(change <= worst)) {  // NaN counts as the worst
      worst = change;
      if (object) *object = b;
    }
  }
  return worst;
}

Validity SimulationPropagator::check(const fem::State& s) {
  if (fem::diverged(s)) return Validity::diverged;  // the same test as `squeeze simulate` and `replay`
  int object = -1;
  const double change = max_volume_change(s, &object);
  if (!std::isfinite(change)) return Validity::diverged;
  if (change > options_.max_volume_change) {
    invalid_object_ = object;
    return Validity::volume;
  }
  const auto X = s.x.middleRows(robot_.first_row, robot_.vertices);
  const Eigen::AlignedBox3d& b = world_.bounds;
  for (int k = 0; k < 3; ++k)
    if (X.col(k).minCoeff() < b.min()(k) || X.col(k).maxCoeff() > b.max()(k)) return Validity::bounds;
  return Validity::valid;
}

Validity SimulationPropagator::propagate(const fem::State& start, const Control& control, int steps,
                                         fem::State& result) {
  return run(start, control, steps, result, nullptr, nullptr);
}

Validity SimulationPropagator::propagate_while_valid(const fem::State& start, const Control& control, int steps,
                                                     fem::State& result, int* kept) {
  fem::State last;
  *kept = 0;
  const Validity v = run(start, control, steps, result, &last, kept);
  if ((v == Validity::bounds || v == Validity::volume) && *kept > 0) {
    result = std::move(last);
    return Validity::valid;
  }
  if (v != Validity::valid) *kept = 0;
  return v;
}

Validity SimulationPropagator::run(const fem::State& start, const Control& control, int steps, fem::State& result,
                                   fem::State* last_valid, int* kept) {
  if (steps < 0) throw InputError("propagate: negative number of steps");
  // An expansion depends on its start state alone, whatever this propagator ran before: the tree
  // and its replay must agree bit for bit.
  world_.world.integrator().reset();
  invalid_object_ = -1;
  result = start;
  const std::unique_ptr<AppliedControl> applied = apply_control(robot_, control, start);
  // Constant forces: the sum is the same every step.
  F_.setZero();
  if (applied->constant()) applied->add_forces(start, F_);
  Validity v = Validity::valid;
  for (int k = 1; k <= steps; ++k) {
    if (!applied->constant()) {
      F_.setZero();
      applied->add_forces(result, F_);
    }
    if (past_deadline()) return Validity::timeout;
    world_.world.step(result, &F_);
    ++steps_done_;
    if (on_step) on_step(result, k);
    if (k % options_.check_every == 0 || k == steps) {
      v = check(result);
      if (v != Validity::valid && options_.stop_when_invalid) return v;
      if (v == Validity::valid && last_valid && k < steps) {
        *last_valid = result;
        *kept = k;
      }
    }
  }
  if (v == Validity::valid && kept) *kept = steps;
  return v;
}

}  // namespace squeeze::plan
