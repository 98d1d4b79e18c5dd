// squeeze::plan — plan a scene and measure the replayed path: what the planner benchmark
// (bench/bench_plan.cpp) and `squeeze bench table1` report per seed.
#pragma once
#include <string>
#include <vector>

#include "squeeze/plan/planner.h"

namespace squeeze::plan {

struct PlanEvaluation {
  PlanResult result;
  bool replay_matches = false;            // replay reproduced every tree state on the path bit for bit
  std::vector<std::string> objects;       // deformable objects, scene order
  std::vector<double> max_volume_change;  // per deformable object: max |V/V_start − 1| over every step of the
                                          // replayed path (settling phase included), V_start its volume in the
                                          // planner's settled start state
};

/// Plans in the built scene `world` with `options`, then replays the path (and the settling phase) and measures it.
PlanEvaluation evaluate_plan(const fem::SceneWorld& world, const PlannerOptions& options, Progress* progress = nullptr);

}  // namespace squeeze::plan
