// Replaying a plan into an output folder (metrics.csv + trajectory/): shared by `squeeze replay`
// and `squeeze run`. Defined in cmd_plan.cpp.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "squeeze/fem/scene.h"
#include "squeeze/plan/plan_io.h"

namespace squeeze {
class Progress;
}

namespace squeeze::cli {

struct ReplayOutput {
  int frames = 0;
  double duration = 0;                    // s, path + settling
  double final_distance = 0;              // m, goal object's centre of mass to the goal after settling
  std::vector<std::string> names;         // objects, scene order
  std::vector<double> max_volume_change;  // per object: max |V/V0 − 1| over every step (0 for rigid)
  std::uint64_t hash = 0;                 // state_hash at the end of the last path segment
  bool matches = false;                   // hash equals the plan's final_state_hash
};

/// Re-simulates plan `f` of `scene` (path, then `settle_steps` of settling) and writes
/// OUTPUT/metrics.csv and OUTPUT/trajectory/ at `fps`. Throws InputError on bad input.
ReplayOutput write_replay(const fem::Scene& scene, const plan::PlanFile& f, const std::string& plan_name,
                          const std::string& output, double fps, int settle_steps, Progress& progress);

std::string hex64(std::uint64_t h);

}  // namespace squeeze::cli
