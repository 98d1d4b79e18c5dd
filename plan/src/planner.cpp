#include "squeeze/plan/planner.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <nanoflann.hpp>
#include <sstream>

#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/common/progress.h"

namespace squeeze::plan {
using json = nlohmann::json;

namespace {

// A small, fully specified random stream (the standard distributions are not portable across
// library implementations; a plan must replay the same everywhere).
class Random {
 public:
  // The seed is mixed first: splitmix64 walks one Weyl sequence, and seeds k and k + 1 used directly
  // would start one draw apart on it (correlated streams).
  explicit Random(std::uint64_t seed) : s_(mix(seed + 0xD1B54A32D192ED03ULL)) {}
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  std::uint64_t next() { return mix(s_ += 0x9E3779B97F4A7C15ULL); }  // splitmix64
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int index(int n) { return static_cast<int>(uniform() * n); }  // [0, n)

 private:
  std::uint64_t s_;
};

std::size_t peak_rss_bytes() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return static_cast<std::size_t>(std::atoll(line.c_str() + 6)) * 1024;
  return 0;
}

// Node states: one block per deformable object (x rows then v rows), shared with the parent
// when bit-identical.
using Block = std::shared_ptr<const std::vector<double>>;

struct ObjectRows {
  int first = 0, count = 0;
};

struct Node {
  int parent = -1;
  PathSegment edge;  // from the parent
  Eigen::Vector3d com{0, 0, 0};  // robot centre of mass
  double distance = 0;           // goal object's centre of mass to the goal
  double time = 0;
  std::vector<Block> blocks;
};

class StateStore {
 public:
  explicit StateStore(const fem::World& w) {
    for (int b = 0; b < w.bodies(); ++b)
      if (w.first_state_row(b) >= 0) objects_.push_back({w.first_state_row(b), w.body(b).vertices()});
  }
  std::vector<Block> store(const fem::State& s, const Node* parent) {
    std::vector<Block> blocks;
    for (size_t o = 0; o < objects_.size(); ++o) {
      const ObjectRows r = objects_[o];
      const size_t n = static_cast<size_t>(r.count) * 3;
      const double* x = s.x.data() + static_cast<size_t>(r.first) * 3;
      const double* v = s.v.data() + static_cast<size_t>(r.first) * 3;
      if (parent) {
        const std::vector<double>& p = *parent->blocks[o];
        if (std::memcmp(p.data(), x, n * sizeof(double)) == 0 && std::memcmp(p.data() + n, v, n * sizeof(double)) == 0) {
          blocks.push_back(parent->blocks[o]);
          continue;
        }
      }
      auto blk = std::make_shared<std::vector<double>>(2 * n);
      std::memcpy(blk->data(), x, n * sizeof(double));
      std::memcpy(blk->data() + n, v, n * sizeof(double));
      bytes_ += 2 * n * sizeof(double);
      blocks.push_back(std::move(blk));
    }
    return blocks;
  }
  void restore(const Node& node, fem::State& s) const {
    for (size_t o = 0; o < objects_.size(); ++o) {
      const ObjectRows r = objects_[o];
      const size_t n = static_cast<size_t>(r.count) * 3;
      const std::vector<double>& b = *node.blocks[o];
      std::memcpy(s.x.data() + static_cast<size_t>(r.first) * 3, b.data(), n * sizeof(double));
      std::memcpy(s.v.data() + static_cast<size_t>(r.first) * 3, b.data() + n, n * sizeof(double));
    }
    s.time = node.time;
  }
  std::size_t bytes() const { return bytes_; }

 private:
  std::vector<ObjectRows> objects_;
  std::size_t bytes_ = 0;
};

// nanoflann adaptor over the nodes' robot centres of mass.
struct ComCloud {
  const std::vector<Node>* nodes;
  size_t kdtree_get_point_count() const { return nodes->size(); }
  double kdtree_get_pt(size_t i, size_t d) const { return (*nodes)[i].com(static_cast<int>(d)); }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};
using ComTree = nanoflann::KDTreeSingleIndexDynamicAdaptor<nanoflann::L2_Simple_Adaptor<double, ComCloud>, ComCloud, 3>;

int nearest(const ComTree& tree, const Eigen::Vector3d& x) {
  size_t index = 0;
  double d2 = 0;
  nanoflann::KNNResultSet<double, size_t> result(1);
  result.init(&index, &d2);
  tree.findNeighbors(result, x.data(), nanoflann::SearchParams());
  return static_cast<int>(index);
}

}  // namespace

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
  return h;
}

PlannerOptions planner_options(const fem::SceneWorld& w) {
  const fem::Scene& scene = w.scene;
  const JsonChecker c{scene.file.string()};
  PlannerOptions o;
  const int r = robot_index(scene);
  const fem::Body& robot = w.world.body(r);
  double mass = 0;
  for (int i = 0; i < robot.vertices(); ++i) mass += w.world.masses()(w.world.first_state_row(r) + i);
  const Eigen::Vector3d lo = robot.rest.colwise().minCoeff(), hi = robot.rest.colwise().maxCoeff();
  const double size = (hi - lo).norm();
  o.control_radius = 0.25 * size;
  std::optional<double> max_force;
  const json& j = scene.planner;
  if (!j.is_null()) {
    c.keys(j, "planner", {"iterations", "seed", "goal_bias", "t_min", "t_max", "max_force", "control_radius",
                          "max_volume_change", "weights", "interpolation_omega", "settle", "batch"});
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
    if (j.contains("batch")) o.batch = static_cast<int>(c.integer(j["batch"], "planner.batch", 1, 1024));
    if (j.contains("weights")) {
      const json& k = j["weights"];
      c.keys(k, "planner.weights", {"body", "control_point", "interpolation"});
      if (k.contains("body")) o.weights.body = c.non_negative(k["body"], "planner.weights.body");
      if (k.contains("control_point")) o.weights.control_point = c.non_negative(k["control_point"], "planner.weights.control_point");
      if (k.contains("interpolation")) o.weights.interpolation = c.non_negative(k["interpolation"], "planner.weights.interpolation");
      if (!(o.weights.body + o.weights.control_point + o.weights.interpolation > 0))
        c.fail("planner.weights", "at least one weight must be > 0");
    }
    if (o.t_min > o.t_max)
      c.fail("planner.t_min", "must be <= planner.t_max (" + format_number(o.t_max) + "), got " + format_number(o.t_min));
  }
  if (!(o.interpolation_omega > 0)) o.interpolation_omega = 2 * M_PI / o.t_max;
  // Default: enough to lift the robot against its own gravity twice over, and to move it about
  // half its own size within t_max from rest (½ a t² = d / 2).
  const double g = scene.objects[r].gravity ? scene.gravity.norm() : 0.0;
  o.max_force = max_force ? *max_force : mass * std::max(2.0 * g, size / (o.t_max * o.t_max));
  return o;
}

namespace {

void check_options(const PlannerOptions& o, const std::string& file) {
  auto bad = [&](const std::string& what) { throw InputError(file + ": " + what); };
  if (o.iterations < 1) bad("planner.iterations: must be >= 1");
  if (!(o.t_min > 0) || !(o.t_max > 0) || o.t_min > o.t_max) bad("planner.t_min, t_max: need 0 < t_min <= t_max");
  if (!(o.max_force > 0) || !std::isfinite(o.max_force)) bad("planner.max_force: must be > 0");
  if (!(o.control_radius > 0)) bad("planner.control_radius: must be > 0");
  if (!(o.max_volume_change > 0)) bad("planner.max_volume_change: must be > 0");
  if (!(o.goal_bias >= 0 && o.goal_bias <= 1)) bad("planner.goal_bias: must be in [0, 1]");
  if (o.weights.body < 0 || o.weights.control_point < 0 || o.weights.interpolation < 0 ||
      !(o.weights.body + o.weights.control_point + o.weights.interpolation > 0))
    bad("planner.weights: must be >= 0 and not all zero");
  if (o.batch < 1) bad("planner.batch: must be >= 1");
  if (o.time_limit < 0) bad("time limit: must be >= 0");
}

}  // namespace

Control settle_control(const SimulationPropagator& p, const PlannerOptions& o) {
  Control c;
  c.kind = ForceKind::interpolation;
  c.target = p.world().scene.goal ? p.world().scene.goal->position : p.robot().rest_com;
  // The goal is for the goal object's centre; the robot's rest shape is placed there.
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

PlanResult plan(const fem::Scene& scene, const PlannerOptions& options, Progress* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  check_options(options, scene.file.string());
  PropagatorOptions popt;
  popt.max_volume_change = options.max_volume_change;
  // One propagator (world) per expansion of a batch; they run in parallel.
  std::vector<std::unique_ptr<SimulationPropagator>> workers;
  workers.push_back(std::make_unique<SimulationPropagator>(scene, popt));
  const SimulationPropagator& main = *workers[0];
  const fem::SceneWorld& w = main.world();
  check_planning_inputs(w);
  const Eigen::Vector3d goal = scene.goal->position;
  for (int k = 1; k < options.batch; ++k) workers.push_back(std::make_unique<SimulationPropagator>(scene, popt));

  const double h = w.h;
  const int min_steps = std::max(1, static_cast<int>(std::lround(options.t_min / h)));
  const int max_steps = std::max(min_steps, static_cast<int>(std::lround(options.t_max / h)));
  const Robot& robot = main.robot();
  // Surface vertices of the robot: the candidates for control points.
  std::vector<int> surface;
  {
    const fem::Body& b = w.world.body(robot.body);
    for (int i = 0; i < b.vertices(); ++i)
      if (b.on_boundary[i] && robot.mass(i) > 0) surface.push_back(i);
    if (surface.empty())
      for (int i = 0; i < b.vertices(); ++i)
        if (robot.mass(i) > 0) surface.push_back(i);
  }

  PlanResult result;
  result.time_step = h;
  result.settle = settle_control(main, options);
  result.settle_steps = static_cast<int>(std::lround(options.settle / h));
  std::vector<Node> nodes;
  nodes.reserve(1024);
  StateStore store(w.world);
  const fem::State s0 = w.initial_state();
  {
    Node root;
    root.com = robot.com(s0);
    root.distance = (main.goal_com(s0) - goal).norm();
    root.blocks = store.store(s0, nullptr);
    nodes.push_back(std::move(root));
  }
  ComCloud cloud{&nodes};
  ComTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));

  Random rng(options.seed);
  const double wsum = options.weights.body + options.weights.control_point + options.weights.interpolation;
  const Eigen::AlignedBox3d& bounds = w.bounds;
  int best = 0, solved_node = -1;
  const double tolerance = scene.goal->tolerance;
  if (nodes[0].distance <= tolerance) solved_node = 0;

  struct Job {
    int from = 0;
    PathSegment edge;
    fem::State result;
    Validity validity = Validity::valid;
  };
  std::vector<Job> jobs(options.batch);
  fem::State scratch = s0;
  // With a time limit far below what the iterations would take, a percentage of iterations means
  // nothing: show the elapsed time only.
  if (progress) progress->stage("planning", options.time_limit > 0 && options.iterations >= 1000000 ? 0 : options.iterations);
  while (solved_node < 0 && result.stats.iterations < options.iterations) {
    if (options.time_limit > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >= options.time_limit)
      break;
    const int n = std::min(options.batch, options.iterations - result.stats.iterations);
    // 1. All random draws of the batch, in order, against the tree as it is.
    for (int k = 0; k < n; ++k) {
      Job& job = jobs[k];
      Control c;
      const double pick = rng.uniform() * wsum;
      c.kind = pick < options.weights.body                                  ? ForceKind::body
               : pick < options.weights.body + options.weights.control_point ? ForceKind::control_point
                                                                             : ForceKind::interpolation;
      Eigen::Vector3d x;
      if (c.kind == ForceKind::interpolation || rng.uniform() < options.goal_bias) {
        x = goal;
      } else {
        for (int d = 0; d < 3; ++d) x(d) = rng.uniform(bounds.min()(d), bounds.max()(d));
      }
      job.from = nearest(tree, x);
      c.target = x;
      if (c.kind == ForceKind::interpolation) {
        // The goal configuration puts the goal object's centre at the goal; for the robot as
        // goal object, its rest shape's centre goes there.
        c.force = options.max_force;
        c.omega = options.interpolation_omega;
      } else {
        c.force = rng.uniform(0.0, options.max_force);
        if (c.kind == ForceKind::control_point) {
          c.vertex = surface[rng.index(static_cast<int>(surface.size()))];
          c.radius = options.control_radius;
        }
      }
      job.edge.control = c;
      job.edge.steps = min_steps + rng.index(max_steps - min_steps + 1);
    }
    // 2. The expansions, in parallel (each on its own world; results independent of threads).
    tbb::parallel_for(0, n, [&](int k) {
      Job& job = jobs[k];
      fem::State start = s0;
      store.restore(nodes[job.from], start);
      job.validity = workers[k]->propagate(start, job.edge.control, job.edge.steps, job.result);
    });
    // 3. Added in batch order.
    for (int k = 0; k < n; ++k) {
      Job& job = jobs[k];
      ++result.stats.iterations;
      switch (job.validity) {
        case Validity::diverged: ++result.stats.discarded_diverged; continue;
        case Validity::volume: ++result.stats.discarded_volume; continue;
        case Validity::bounds: ++result.stats.discarded_bounds; continue;
        case Validity::valid: break;
      }
      Node node;
      node.parent = job.from;
      node.edge = job.edge;
      node.com = robot.com(job.result);
      node.distance = (main.goal_com(job.result) - goal).norm();
      node.time = job.result.time;
      node.blocks = store.store(job.result, &nodes[job.from]);
      nodes.push_back(std::move(node));
      const int id = static_cast<int>(nodes.size()) - 1;
      tree.addPoints(id, id);
      if (nodes[id].distance < nodes[best].distance) best = id;
      if (solved_node < 0 && nodes[id].distance <= tolerance) solved_node = id;
    }
    if (progress) {
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      char buf[160];
      std::snprintf(buf, sizeof buf, "nodes %zu, best distance %.3g m, %.1f it/s", nodes.size(), nodes[best].distance,
                    secs > 0 ? result.stats.iterations / secs : 0.0);
      progress->update(result.stats.iterations, buf);
    }
  }
  if (progress) progress->finish();

  const int last = solved_node >= 0 ? solved_node : best;
  result.status = solved_node >= 0 ? PlanStatus::solved : (best != 0 ? PlanStatus::approximate : PlanStatus::failed);
  std::vector<int> chain;
  for (int id = last; id > 0; id = nodes[id].parent) chain.push_back(id);
  std::reverse(chain.begin(), chain.end());
  for (int id : chain) {
    result.path.push_back(nodes[id].edge);
    fem::State s = s0;
    store.restore(nodes[id], s);
    result.path_states.push_back(std::move(s));
  }
  result.final_state_hash = state_hash(result.path_states.empty() ? s0 : result.path_states.back());
  PlanStatistics& st = result.stats;
  st.nodes = static_cast<int>(nodes.size());
  for (const auto& wk : workers) st.simulation_steps += wk->steps_done();
  st.state_bytes = store.bytes();
  st.bytes_per_node = static_cast<double>(store.bytes()) / nodes.size();
  st.final_distance = nodes[last].distance;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  st.peak_memory = peak_rss_bytes();
  return result;
}

std::vector<fem::State> replay(SimulationPropagator& p, const std::vector<PathSegment>& path, const Control& settle,
                               int settle_steps) {
  std::vector<fem::State> ends;
  fem::State s = p.world().initial_state(), next;
  for (const PathSegment& seg : path) {
    p.propagate(s, seg.control, seg.steps, next);
    s = next;
    ends.push_back(s);
  }
  if (settle_steps > 0) p.propagate(s, settle, settle_steps, next);
  return ends;
}

}  // namespace squeeze::plan
