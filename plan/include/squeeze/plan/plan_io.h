// squeeze::plan — PLAN.json: what `squeeze plan` writes and `squeeze replay` reads.
//
// { "format": "squeeze-plan", "version": 1, "scene": ABSOLUTE PATH, "status": "solved" | ...,
//   "seed": N, "time_step": h (s), "integrator": NAME, "planner": {every PlannerOptions field},
//   "statistics": {...PlanStatistics...},
//   "path": [ {"kind": "body" | "control_point" | "interpolation", "target": [x,y,z] (m),
//              "force": N, "vertex": i, "radius": m, "omega": 1/s, "steps": n, "duration": s}, ... ],
//   "settle": {"kind": "interpolation", ..., "steps": n, "duration": s},
//   "start_settle_steps": n (steps without control before the path: planner.settle_start),
//   "final_state_hash": "16 hex digits" }
#pragma once
#include <filesystem>

#include "squeeze/plan/planner.h"

namespace squeeze::plan {

struct PlanFile {
  std::string scene;
  PlanStatus status = PlanStatus::failed;
  PlannerOptions options;
  PlanStatistics stats;
  double time_step = 0;
  std::string integrator;  // the scene's integrator when planned ("" in plans made before: the scene's)
  std::vector<PathSegment> path;
  Control settle;
  int settle_steps = 0;
  int start_settle_steps = 0;  // steps without control from the scene's initial state to the plan's start
  std::uint64_t final_state_hash = 0;
};

/// The plan file of a planner result: the scene's absolute path, status, options, statistics,
/// path, the settle phase (PlanResult::settle) and the hash.
PlanFile make_plan_file(const fem::Scene& scene, const PlannerOptions& options, const PlanResult& result);

/// Writes atomically (temporary name, rename). Throws InputError on I/O errors.
void save_plan(const std::filesystem::path& file, const PlanFile& plan);
/// Reads and validates; throws InputError "FILE: KEY: problem".
PlanFile load_plan(const std::filesystem::path& file);

}  // namespace squeeze::plan
