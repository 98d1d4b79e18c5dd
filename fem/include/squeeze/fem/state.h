// squeeze::fem — the simulated state of a world, and what a step found.
#pragma once
#include <Eigen/Core>

#include "squeeze/fem/body.h"

namespace squeeze::fem {

/// Positions and velocities of every vertex of every deformable object, object after object in
/// the order they were added (World::first_state_row). A plain value: copy it to save, assign to
/// restore. Rigid objects are not part of it.
struct State {
  RowMatrixX3d x;     // #N by 3 positions (m)
  RowMatrixX3d v;     // #N by 3 velocities (m/s)
  double time = 0.0;  // s
};

/// What the last collision pass found (World::last_stats, ForceWorkspace::stats).
struct StepStats {
  int contacts = 0;            // (vertex, tet) pairs found by the spatial hash
  int colliding_vertices = 0;  // vertices given a penetration depth
  double max_depth = 0.0;      // m
};

}  // namespace squeeze::fem
