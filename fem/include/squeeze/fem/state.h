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
  // Rest overlaps (WorldOptions::rest_overlap): per vertex that overlaps another object at rest
  // (World::overlap_vertices), the penetration depth its contact tolerates now (m). It starts at
  // the rest depth and only shrinks: to the current depth while the vertex stays inside, to 0 once
  // it is out. Empty when no vertex overlaps at rest.
  Eigen::VectorXd overlap;
};

/// The speed (m/s) above which a state counts as diverged: faster than 1 km/s is a blow-up, not
/// motion (and would make collision detection crawl).
constexpr double kDivergedSpeed = 1e3;

/// Whether `s` has diverged: a position or velocity that is NaN or infinite, or a speed component
/// above kDivergedSpeed. The one test of `plan` (Validity::diverged), `simulate`, `replay` and
/// `squeeze check`'s settle.
inline bool diverged(const State& s) {
  return !s.x.allFinite() || !s.v.allFinite() || (s.v.size() > 0 && !(s.v.cwiseAbs().maxCoeff() <= kDivergedSpeed));
}

/// What the last collision pass found (World::last_stats, ForceWorkspace::stats).
struct StepStats {
  int contacts = 0;            // (vertex, tet) pairs found by the spatial hash
  int colliding_vertices = 0;  // vertices given a penetration depth
  double max_depth = 0.0;      // m, beyond the rest overlap a vertex may keep (State::overlap)
};

}  // namespace squeeze::fem
