// The paper's planner: a kinodynamic RRT over the whole deformable state (Rodriguez, Lien, Amato,
// ICRA 2006, Algorithm 1; LaValle and Kuffner, "Randomized kinodynamic planning", IJRR 2001).
//
// One iteration: sample x in the scene's bounds (the goal with probability goal_bias, and always
// for a kind that goes toward the goal); take the node whose robot centre of mass is nearest to x
// (kd-tree, nanoflann); draw a manipulation force by the weights and a duration dT in
// [t_min, t_max]; restore the node's state, propagate dT / h steps with the force (collisions and
// penalties every step) and add the result as a child unless it is invalid (NaN or blow-up,
// volume change beyond max_volume_change, robot outside bounds). Solved when the goal object's
// centre of mass is within the goal's tolerance.
//
// Parallelism and determinism: iterations run in batches of `batch` expansions. All random draws
// of a batch come from one seeded stream, in order, against the tree as it was when the batch
// began; the expansions then run in parallel (one propagator per slot) and are added in batch
// order. The batch size does not depend on the number of threads, so the same seed gives the
// same tree and the same plan with any number of threads.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nanoflann.hpp>

#include "squeeze/common/progress.h"
#include "squeeze/plan/planner.h"
#include "squeeze/plan/state_store.h"

namespace squeeze::plan {
namespace {

std::size_t peak_rss_bytes() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return static_cast<std::size_t>(std::atoll(line.c_str() + 6)) * 1024;
  return 0;
}

struct Node {
  int parent = -1;
  PathSegment edge;              // from the parent
  Eigen::Vector3d com{0, 0, 0};  // robot centre of mass
  double distance = 0;           // goal object's centre of mass to the goal
  double time = 0;
  StateStore::Blocks blocks;
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

class Rrt : public Planner {
 public:
  const char* name() const override { return "rrt"; }
  PlanResult solve(const PlanningProblem& problem, const PlannerOptions& options, Progress* progress) override;
};

PlanResult Rrt::solve(const PlanningProblem& pb, const PlannerOptions& options, Progress* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const fem::SceneWorld& w = *pb.world;
  // One propagator per expansion of a batch; they run in parallel.
  std::vector<std::unique_ptr<Propagator>> workers;
  for (int k = 0; k < options.batch; ++k) workers.push_back(pb.make_propagator());
  if (options.time_limit > 0)  // expansions stop within a step of the limit
    for (auto& wk : workers)
      wk->set_deadline(t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(options.time_limit)));

  const double h = w.time_step();
  const int min_steps = std::max(1, static_cast<int>(std::lround(options.t_min / h)));
  const int max_steps = std::max(min_steps, static_cast<int>(std::lround(options.t_max / h)));
  const Robot& robot = pb.robot;
  const Eigen::Vector3d goal = pb.goal;
  SamplingContext ctx;
  ctx.robot = &robot;
  ctx.max_force = options.max_force;
  ctx.control_radius = options.control_radius;
  ctx.interpolation_omega = options.interpolation_omega;

  PlanResult result;
  result.time_step = h;
  std::vector<Node> nodes;
  nodes.reserve(1024);
  StateStore store(w.world);
  const fem::State& s0 = pb.start;
  {
    Node root;
    root.com = robot.com(s0);
    root.distance = (pb.goal_object.com(s0) - goal).norm();
    root.blocks = store.store(s0, nullptr);
    nodes.push_back(std::move(root));
  }
  ComCloud cloud{&nodes};
  ComTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));

  Random rng(options.seed);
  const Eigen::AlignedBox3d& bounds = w.bounds;
  int best = 0, solved_node = -1;
  if (nodes[0].distance <= pb.tolerance) solved_node = 0;

  struct Job {
    int from = 0;
    PathSegment edge;
    fem::State result;
    Validity validity = Validity::valid;
    int object = -1;  // the object that made it invalid
    bool truncated = false;  // valid up to fewer steps than drawn (keep_valid_prefix)
  };
  result.stats.discarded_volume_by_object.assign(static_cast<size_t>(w.world.bodies()), 0);
  std::vector<Job> jobs(options.batch);
  // With a time limit far below what the iterations would take, a percentage of iterations means
  // nothing: show the elapsed time only.
  if (progress) progress->stage("planning", options.time_limit > 0 && options.iterations >= 1000000 ? 0 : options.iterations);
  while (solved_node < 0 && result.stats.iterations < options.iterations) {
    if (options.time_limit > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >= options.time_limit) {
      result.timed_out = true;
      break;
    }
    const int n = std::min(options.batch, options.iterations - result.stats.iterations);
    // 1. All random draws of the batch, in order, against the tree as it is.
    for (int k = 0; k < n; ++k) {
      Job& job = jobs[k];
      Control c;
      c.kind = options.weights.pick(rng.uniform());
      Eigen::Vector3d x;
      if (c.kind->toward_goal() || rng.uniform() < options.goal_bias) {
        x = goal;
      } else {
        for (int d = 0; d < 3; ++d) x(d) = rng.uniform(bounds.min()(d), bounds.max()(d));
      }
      job.from = nearest(tree, x);
      c.target = x;
      c.kind->sample(c, ctx, rng);
      job.edge.control = c;
      job.edge.steps = min_steps + rng.index(max_steps - min_steps + 1);
    }
    // 2. The expansions, in parallel (each on its own propagator; results independent of threads).
    tbb::parallel_for(0, n, [&](int k) {
      Job& job = jobs[k];
      fem::State start = s0;
      store.restore(nodes[job.from].blocks, nodes[job.from].time, start);
      if (options.keep_valid_prefix) {
        int kept = 0;
        job.validity = workers[k]->propagate_while_valid(start, job.edge.control, job.edge.steps, job.result, &kept);
        job.truncated = job.validity == Validity::valid && kept < job.edge.steps;
        if (job.validity == Validity::valid) job.edge.steps = kept;
      } else {
        job.validity = workers[k]->propagate(start, job.edge.control, job.edge.steps, job.result);
      }
      job.object = workers[k]->invalid_object();
    });
    // 3. Added in batch order. When the time limit fell inside this batch, the expansions it cut
    // short are dropped and the ones that finished before it are kept (as OMPL's planners keep the
    // motion in flight when their termination condition fires); the planner then stops.
    bool timed_out = false;
    for (int k = 0; k < n; ++k) {
      Job& job = jobs[k];
      if (job.validity == Validity::timeout) {
        timed_out = true;
        continue;
      }
      ++result.stats.iterations;
      switch (job.validity) {
        case Validity::diverged: ++result.stats.discarded_diverged; continue;
        case Validity::volume:
          ++result.stats.discarded_volume;
          if (job.object >= 0) ++result.stats.discarded_volume_by_object[static_cast<size_t>(job.object)];
          continue;
        case Validity::bounds: ++result.stats.discarded_bounds; continue;
        case Validity::timeout: continue;  // not reached (skipped above)
        case Validity::valid: break;
      }
      if (job.truncated) ++result.stats.truncated;
      Node node;
      node.parent = job.from;
      node.edge = job.edge;
      node.com = robot.com(job.result);
      node.distance = (pb.goal_object.com(job.result) - goal).norm();
      node.time = job.result.time;
      node.blocks = store.store(job.result, &nodes[job.from].blocks);
      nodes.push_back(std::move(node));
      const int id = static_cast<int>(nodes.size()) - 1;
      tree.addPoints(id, id);
      if (nodes[id].distance < nodes[best].distance) best = id;
      if (solved_node < 0 && nodes[id].distance <= pb.tolerance) solved_node = id;
    }
    if (progress) {
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      char buf[160];
      std::snprintf(buf, sizeof buf, "nodes %zu, best distance %.3g m, %.1f it/s", nodes.size(), nodes[best].distance,
                    secs > 0 ? result.stats.iterations / secs : 0.0);
      progress->update(result.stats.iterations, buf);
    }
    if (timed_out) {
      result.timed_out = true;
      break;
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
    store.restore(nodes[id].blocks, nodes[id].time, s);
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

}  // namespace

std::unique_ptr<Planner> make_rrt_planner() { return std::make_unique<Rrt>(); }

}  // namespace squeeze::plan
