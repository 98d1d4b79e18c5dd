// The forces the body and control-point kinds share: a total force F toward a target, shared by
// a set of robot vertices in proportion to their masses (private to plan/src/controls).
#pragma once
#include <vector>

#include "squeeze/plan/control.h"

namespace squeeze::plan {

/// f_i = F · (m_i / M_S) · d for every i in `set` (robot vertex indices, all with m_i > 0), d the
/// unit vector from `from` toward c.target, M_S = set_mass. No direction (target at `from`) or an
/// empty set: no force (a valid, idle edge).
std::unique_ptr<AppliedControl> directed_forces(const Robot& robot, const Control& c, const Eigen::Vector3d& from,
                                                const std::vector<int>& set, double set_mass);

}  // namespace squeeze::plan
