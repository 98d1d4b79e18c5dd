#include "squeeze/plan/planner.h"

#include "squeeze/plan/control.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/integrator.h"

namespace squeeze::plan {
using json = nlohmann::json;

ForceWeights::ForceWeights() {
  for (const ControlKind* k : control_kinds()) w.push_back(k->default_weight());
}

double& ForceWeights::operator[](const std::string& kind) {
  const int i = control_kind_index(control_kind(kind, "planner.weights"));
  if (w.size() < control_kinds().size()) w.resize(control_kinds().size(), 0.0);
  return w[static_cast<size_t>(i)];
}

double ForceWeights::operator[](const std::string& kind) const {
  const int i = control_kind_index(control_kind(kind, "planner.weights"));
  return static_cast<size_t>(i) < w.size() ? w[static_cast<size_t>(i)] : 0.0;
}

double ForceWeights::sum() const {
  double s = 0;
  for (double x : w) s += x;
  return s;
}

const ControlKind* ForceWeights::pick(double u) const {
  const std::vector<const ControlKind*>& kinds = control_kinds();
  const double target = u * sum();
  double acc = 0;
  for (size_t i = 0; i + 1 < kinds.size(); ++i) {
    acc += w[i];
    if (target < acc) return kinds[i];
  }
  return kinds.back();
}

const char* to_string(PlanStatus s) {
  switch (s) {
    case PlanStatus::solved: return "solved";
    case PlanStatus::approximate: return "approximate";
    case PlanStatus::failed: return "failed";
  }
  return "?";
}

std::uint64_t state_hash(const fem::State& s) {
  std::uint64_t h = 1469598103934665603ULL;
  auto add = [&](const double* p, size_t n) {
    const auto* c = reinterpret_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n * sizeof(double); ++i) h = (h ^ c[i]) * 1099511628211ULL;
  };
  add(s.x.data(), static_cast<size_t>(s.x.size()));
  add(s.v.data(), static_cast<size_t>(s.v.size()));
  add(s.overlap.data(), static_cast<size_t>(s.overlap.size()));  // nothing for scenes without rest overlaps
  return h;
}

MaxForceTerms max_force_terms(const fem::SceneWorld& w) {
  const int r = robot_index(w.scene);
  const fem::Body& robot = w.world.body(r);
  MaxForceTerms t;
  const Eigen::Vector3d lo = robot.rest.colwise().minCoeff(), hi = robot.rest.colwise().maxCoeff();
  t.size = (hi - lo).norm();
  // Weight its attachments carry (pinned[].carries_weight) need not be lifted: g counts only the
  // share of mass they do not.
  double carried = 0;
  for (int i = w.world.first_state_row(r), e = i + robot.vertices(); i < e; ++i) {
    t.mass += w.world.masses()(i);
    if (w.world.attachment_carries_weight(i)) carried += w.world.masses()(i);
    if (!w.world.pinned(i)) t.attach_stiffness += w.world.attachment_stiffness(i);
  }
  t.gravity = w.world.gravity_of(r).norm() * (t.mass > 0 ? 1.0 - carried / t.mass : 1.0);
  t.volume = robot.total_volume();
  t.youngs_modulus = robot.k_edge.size() && t.volume > 0 ? robot.k_edge.sum() / t.volume : 0.0;
  t.cross_section = std::cbrt(t.volume) * std::cbrt(t.volume);
  return t;
}

double MaxForceTerms::max_force(double t_max) const {
  return std::max({mass * 2.0 * gravity, mass * size / (t_max * t_max), 0.5 * attach_stiffness * size, squeeze()});
}

PlannerOptions planner_options(const fem::SceneWorld& w) {
  const fem::Scene& scene = w.scene;
  const JsonChecker c{scene.file.string()};
  PlannerOptions o;
  const int r = robot_index(scene);
  const fem::Body& robot = w.world.body(r);
  const Eigen::Vector3d lo = robot.rest.colwise().minCoeff(), hi = robot.rest.colwise().maxCoeff();
  const double size = (hi - lo).norm();
  o.control_radius = 0.25 * size;
  std::optional<double> max_force;
  const json& j = scene.planner;
  if (!j.is_null()) {
    c.keys(j, "planner", {"algorithm", "iterations", "seed", "goal_bias", "t_min", "t_max", "max_force",
                          "control_radius", "max_volume_change", "weights", "interpolation_omega", "settle", "batch",
                          "settle_start", "keep_valid_prefix"});
    if (j.contains("settle_start") && !(j["settle_start"].is_string() && j["settle_start"] == "auto"))
      o.settle_start = c.non_negative(j["settle_start"], "planner.settle_start");
    if (j.contains("algorithm")) {
      o.algorithm = c.string(j["algorithm"], "planner.algorithm");
      try {
        make_planner(o.algorithm);
      } catch (const InputError& e) {
        throw InputError(scene.file.string() + ": " + e.what());
      }
    }
    if (j.contains("iterations")) o.iterations = static_cast<int>(c.integer(j["iterations"], "planner.iterations", 1, 100000000));
    if (j.contains("seed")) o.seed = static_cast<std::uint64_t>(c.integer(j["seed"], "planner.seed", 0, (1LL << 53)));
    if (j.contains("goal_bias")) {
      o.goal_bias = c.number(j["goal_bias"], "planner.goal_bias");
      if (o.goal_bias < 0 || o.goal_bias > 1) c.fail("planner.goal_bias", "must be in [0, 1], got " + format_number(o.goal_bias));
    }
    if (j.contains("t_min")) o.t_min = c.positive(j["t_min"], "planner.t_min");
    if (j.contains("t_max")) o.t_max = c.positive(j["t_max"], "planner.t_max");
    if (j.contains("max_force")) max_force = c.positive(j["max_force"], "planner.max_force");
    if (j.contains("control_radius")) o.control_radius = c.positive(j["control_radius"], "planner.control_radius");
    if (j.contains("max_volume_change")) o.max_volume_change = c.positive(j["max_volume_change"], "planner.max_volume_change");
    if (j.contains("interpolation_omega")) o.interpolation_omega = c.positive(j["interpolation_omega"], "planner.interpolation_omega");
    if (j.contains("settle")) o.settle = c.non_negative(j["settle"], "planner.settle");
    if (j.contains("keep_valid_prefix")) o.keep_valid_prefix = c.boolean(j["keep_valid_prefix"], "planner.keep_valid_prefix");
    if (j.contains("batch")) o.batch = static_cast<int>(c.integer(j["batch"], "planner.batch", 1, 1024));
    if (j.contains("weights")) {
      const json& k = j["weights"];
      std::vector<std::string> names;
      for (const ControlKind* kind : control_kinds()) names.emplace_back(kind->name());
      c.keys(k, "planner.weights", names);
      for (const std::string& name : names)
        if (k.contains(name)) o.weights[name] = c.non_negative(k[name], "planner.weights." + name);
      if (!(o.weights.sum() > 0)) c.fail("planner.weights", "at least one weight must be > 0");
    }
    if (o.t_min > o.t_max)
      c.fail("planner.t_min", "must be <= planner.t_max (" + format_number(o.t_max) + "), got " + format_number(o.t_min));
  }
  if (!(o.interpolation_omega > 0)) o.interpolation_omega = 2 * M_PI / o.t_max;
  const MaxForceTerms t = max_force_terms(w);
  o.max_force = max_force ? *max_force : t.max_force(o.t_max);
  return o;
}

void check_options(const PlannerOptions& o, const std::string& file) {
  auto bad = [&](const std::string& what) { throw InputError(file + ": " + what); };
  if (o.iterations < 1) bad("planner.iterations: must be >= 1");
  if (!(o.t_min > 0) || !(o.t_max > 0) || o.t_min > o.t_max) bad("planner.t_min, t_max: need 0 < t_min <= t_max");
  if (!(o.max_force > 0) || !std::isfinite(o.max_force)) bad("planner.max_force: must be > 0");
  if (!(o.control_radius > 0)) bad("planner.control_radius: must be > 0");
  if (!(o.max_volume_change > 0)) bad("planner.max_volume_change: must be > 0");
  if (!(o.goal_bias >= 0 && o.goal_bias <= 1)) bad("planner.goal_bias: must be in [0, 1]");
  bool weights_ok = o.weights.w.size() == control_kinds().size();
  for (double x : o.weights.w) weights_ok = weights_ok && x >= 0 && std::isfinite(x);
  if (!weights_ok || !(o.weights.sum() > 0)) bad("planner.weights: must be >= 0 and not all zero");
  if (o.batch < 1) bad("planner.batch: must be >= 1");
  if (o.time_limit < 0) bad("time limit: must be >= 0");
}

Control settle_control(const fem::SceneWorld& w, const PlannerOptions& o) {
  Control c;
  c.kind = &control_kind("interpolation");
  // The goal is for the goal object's centre; the robot's rest shape is placed there.
  c.target = w.scene.goal ? w.scene.goal->position : Robot(w.world, robot_index(w.scene)).rest_com;
  c.force = o.max_force;
  c.omega = o.interpolation_omega;
  return c;
}

void check_planning_inputs(const fem::SceneWorld& w) {
  const std::string file = w.scene.file.string();
  if (!w.scene.goal) throw InputError(file + ": goal: missing (the planner needs \"goal\": {\"position\": [x, y, z]})");
  if (!w.bounds.contains(w.scene.goal->position))
    throw InputError(file + ": goal.position: outside the bounds of the scene");
  check_robot_start(w);
}

fem::State settle_start_state(const fem::SceneWorld& w, double seconds, int* steps, int settle_steps,
                              Progress* progress) {
  fem::SceneWorld copy = w;  // its own scratch and integrator
  copy.world.integrator().reset();
  fem::State s = copy.initial_state();
  const double h = copy.time_step();
  const bool automatic = settle_steps < 0 && seconds < 0;
  const long long limit = settle_steps >= 0 ? settle_steps
                          : std::llround(std::ceil((automatic ? kSettleStartMax : seconds) / h - 1e-9));
  double movable = 0;  // kg of the free vertices
  for (int i = 0; i < copy.world.state_rows(); ++i)
    if (!copy.world.pinned(i)) movable += copy.world.masses()(i);
  constexpr double kRestSpeed = 1e-3;  // m/s: the scene is at rest when its RMS speed is below it
  long long n = 0;
  if (progress) progress->stage(automatic ? "settling the start (until at rest)" : "settling the start", static_cast<double>(limit));
  for (; n < limit; ++n) {
    if (automatic && n > 0 && !(copy.world.kinetic_energy(s) > 0.5 * movable * kRestSpeed * kRestSpeed)) break;
    copy.step(s);
    if (progress) progress->update(static_cast<double>(n + 1));
    if (!s.x.allFinite()) break;
  }
  if (progress) progress->finish();
  if (steps) *steps = static_cast<int>(n);
  return s;
}

PlanningProblem planning_problem(const fem::SceneWorld& w, const PlannerOptions& options,
                                 PropagatorFactory make_propagator, Progress* progress) {
  check_planning_inputs(w);
  PlanningProblem p;
  p.world = &w;
  p.robot = Robot(w.world, robot_index(w.scene));
  p.goal_object = Robot(w.world, goal_object_index(w.scene));
  p.goal = w.scene.goal->position;
  p.tolerance = w.scene.goal->tolerance;
  p.start = settle_start_state(w, options.settle_start, &p.start_settle_steps, -1, progress);
  if (!p.start.x.allFinite())
    throw InputError(w.scene.file.string() + ": planner.settle_start: the scene diverged while settling before planning "
                     "(see squeeze check)");
  // A robot whose centre leaves the bounds while the start settles (nothing holds it: no floor
  // under it, no pins) starts every expansion invalid, and the search cannot move: one clear error,
  // not a tree of one node and a final settle that drags the robot to the goal through everything.
  // (Its centre, not any vertex: a robot resting on a floor at the bounds' edge may dip a vertex
  // below it, as it may during the search.)
  if (const Eigen::Vector3d com = p.robot.com(p.start); !w.bounds.contains(com)) {
    const Eigen::Vector3d moved = com - p.robot.rest_com;
    throw InputError(w.scene.file.string() + ": planner.settle_start: the robot leaves the bounds while the start settles " +
                     "without control (its centre moves " + format_number(moved.norm()) + " m in " +
                     std::to_string(p.start_settle_steps) + " steps: nothing holds it, e.g. no floor under it and no pins); " +
                     "add a floor or pins, or set planner.settle_start to 0");
  }
  p.start_volume.resize(static_cast<size_t>(w.world.bodies()));
  for (int b = 0; b < w.world.bodies(); ++b) p.start_volume[b] = w.world.body_volume(p.start, b);
  if (make_propagator) {
    p.make_propagator = std::move(make_propagator);
  } else {
    PropagatorOptions popt;
    popt.max_volume_change = options.max_volume_change;
    popt.reference_volume = p.start_volume;
    p.make_propagator = [&w, popt] { return std::make_unique<SimulationPropagator>(w, popt); };
  }
  return p;
}

PlanResult plan(const fem::SceneWorld& world, const PlannerOptions& options, Progress* progress,
                PropagatorFactory make_propagator) {
  check_options(options, world.scene.file.string());
  const std::unique_ptr<Planner> planner = make_planner(options.algorithm);
  const PlanningProblem problem = planning_problem(world, options, std::move(make_propagator), progress);
  PlanResult r = planner->solve(problem, options, progress);
  r.start_settle_steps = problem.start_settle_steps;
  r.settle = settle_control(world, options);
  r.settle_steps = static_cast<int>(std::lround(options.settle / world.time_step()));
  return r;
}

std::vector<fem::State> replay(SimulationPropagator& p, const fem::State& start, const std::vector<PathSegment>& path,
                               const Control& settle, int settle_steps) {
  std::vector<fem::State> ends;
  fem::State s = start, next;
  for (const PathSegment& seg : path) {
    p.propagate(s, seg.control, seg.steps, next);
    s = next;
    ends.push_back(s);
  }
  if (settle_steps > 0) p.propagate(s, settle, settle_steps, next);
  return ends;
}

}  // namespace squeeze::plan
