#include "squeeze/plan/evaluate.h"

#include <cmath>
#include <cstring>

namespace squeeze::plan {

PlanEvaluation evaluate_plan(const fem::SceneWorld& world, const PlannerOptions& options, Progress* progress) {
  PlanEvaluation e;
  e.result = plan(world, options, progress);
  const fem::State start = settle_start_state(world, 0, nullptr, e.result.start_settle_steps);
  PropagatorOptions po;
  po.stop_when_invalid = false;
  for (int b = 0; b < world.world.bodies(); ++b) po.reference_volume.push_back(world.world.body_volume(start, b));
  SimulationPropagator p(world, po);
  const fem::Scene& scene = world.scene;
  const fem::World& w = p.world().world;
  std::vector<int> bodies;
  for (int b = 0; b < w.bodies(); ++b)
    if (!w.body(b).rigid) {
      bodies.push_back(b);
      e.objects.push_back(scene.objects[b].name);
    }
  e.max_volume_change.assign(bodies.size(), 0.0);
  p.on_step = [&](const fem::State& s, int) {
    for (size_t k = 0; k < bodies.size(); ++k) {
      const double c = p.volume_change(s, bodies[k]);
      if (!(c <= e.max_volume_change[k])) e.max_volume_change[k] = c;
    }
  };
  const std::vector<fem::State> ends = replay(p, start, e.result.path, e.result.settle, e.result.settle_steps);
  // Planners that keep only the final state (the OMPL ones: path_states empty) are checked by its hash.
  if (e.result.path_states.empty() && !ends.empty()) {
    e.replay_matches = state_hash(ends.back()) == e.result.final_state_hash;
    return e;
  }
  e.replay_matches = ends.size() == e.result.path_states.size();
  for (size_t i = 0; e.replay_matches && i < ends.size(); ++i) {
    const fem::State& a = ends[i];
    const fem::State& b = e.result.path_states[i];
    e.replay_matches = a.x.size() == b.x.size() &&
                       std::memcmp(a.x.data(), b.x.data(), sizeof(double) * a.x.size()) == 0 &&
                       std::memcmp(a.v.data(), b.v.data(), sizeof(double) * a.v.size()) == 0;
  }
  return e;
}

}  // namespace squeeze::plan
