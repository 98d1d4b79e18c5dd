// What `squeeze plan`, `squeeze replay` and `squeeze run` share: preparing a scene for planning,
// and replaying a plan into an output folder (metrics.csv + trajectory/). Defined in cmd_plan.cpp.
#pragma once
#include <filesystem>
#include <cstdint>
#include <string>
#include <vector>

#include "squeeze/fem/scene.h"
#include "squeeze/plan/plan_io.h"

namespace squeeze {
class Progress;
}

namespace squeeze::cli {

/// Command-line overrides of the scene's planner block (negative / zero: keep the scene's).
struct PlanOverrides {
  long long seed = -1, iterations = -1;
  double time_limit = 0;  // s, 0: none
};

/// A scene built once for planning and everything after it (replay, metrics): copies of `world`.
struct PreparedPlanning {
  fem::SceneWorld world;
  plan::PlannerOptions options;
};

/// Checks the scene for planning (robot first, before meshing; then, on the built world, the goal,
/// the bounds and the robot's start: plan::check_planning_inputs), builds it (meshes from the
/// cache) and returns it with the planner options, overrides applied. Throws InputError
/// "FILE: KEY: problem".
PreparedPlanning prepare_planning(const fem::Scene& scene, const PlanOverrides& overrides, Progress& progress);

struct ReplayOutput {
  int frames = 0;
  double duration = 0;                    // s, path + settling
  double final_distance = 0;              // m, goal object's centre of mass to the goal after settling
  std::vector<std::string> names;         // objects, scene order
  std::vector<double> max_volume_change;  // per object: max |V/V0 − 1| over every step (0 for rigid)
  std::uint64_t hash = 0;                 // state_hash at the end of the last path segment
  bool matches = false;                   // hash equals the plan's final_state_hash
  std::string integrator_stats;           // fem::describe_integrator_stats of the replay (path and settling)
};

/// Re-simulates plan `f` in the built scene `world` (path, then `settle_steps` of settling) and
/// writes FOLDER/metrics.csv and FOLDER/trajectory/ at `fps` (FOLDER: a FolderReplacement's staging
/// folder). Throws InputError on bad input (a plan that does not fit the scene names `plan_name`)
/// and when the replay diverges (fem::diverged: NaN or faster than 1 km/s), naming `plan_name`.
ReplayOutput write_replay(const fem::SceneWorld& world, const plan::PlanFile& f, const std::string& plan_name,
                          const std::filesystem::path& folder, double fps, int settle_steps, Progress& progress);

std::string hex64(std::uint64_t h);

}  // namespace squeeze::cli
