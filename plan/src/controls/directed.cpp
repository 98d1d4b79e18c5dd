#include "directed.h"

namespace squeeze::plan {

std::unique_ptr<AppliedControl> directed_forces(const Robot& robot, const Control& c, const Eigen::Vector3d& from,
                                                const std::vector<int>& set, double set_mass) {
  std::vector<int> rows;
  std::vector<Eigen::Vector3d> f;
  Eigen::Vector3d d = c.target - from;
  const double len = d.norm();
  if (len > 0 && !set.empty() && set_mass > 0) {
    d /= len;
    for (int i : set) {
      rows.push_back(robot.first_row + i);
      f.push_back(c.force * (robot.mass(i) / set_mass) * d);
    }
  }
  return std::make_unique<ConstantForces>(std::move(rows), std::move(f));
}

}  // namespace squeeze::plan
