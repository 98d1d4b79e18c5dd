// The squeeze force (issue 19): the robot pushed toward the sample point as by the body force, and
// at the same time narrowed across that direction: every movable robot vertex i gets
//   f_i = F · (m_i / M) · (d − r⊥_i / ρ),
// d the unit vector from the robot's centre of mass c (in the state the edge starts from) toward
// the target, r⊥_i = (x_i − c) − ((x_i − c)·d) d the vertex's offset from the axis of motion, and
// ρ the largest |r⊥_i|: the extremes of the robot are pressed toward the axis with the push's own
// acceleration F / M. Σ m_i r⊥_i = 0, so the net force is F d, as for the body force; the rest is
// a pure compression across d (what passing a gap narrower than the robot takes).
#include "directed.h"

namespace squeeze::plan {
namespace {

class SqueezeControl : public ControlKind {
 public:
  const char* name() const override { return "squeeze"; }
  // Off by default: measured in docs/plan.md ("Manipulation that squeezes").
  double default_weight() const override { return 0.0; }
  void sample(Control& c, const SamplingContext& ctx, Random& rng) const override {
    c.force = rng.uniform(0.0, ctx.max_force);
  }
  std::unique_ptr<AppliedControl> apply(const Robot& robot, const Control& c, const fem::State& start) const override {
    const Eigen::Vector3d com = robot.com(start);
    Eigen::Vector3d d = c.target - com;
    std::vector<int> rows;
    std::vector<Eigen::Vector3d> f;
    const double len = d.norm();
    if (!(len > 0) || !(robot.total_mass > 0)) return std::make_unique<ConstantForces>(std::move(rows), std::move(f));
    d /= len;
    std::vector<Eigen::Vector3d> perp(static_cast<size_t>(robot.vertices), Eigen::Vector3d::Zero());
    double rho = 0;
    for (int i = 0; i < robot.vertices; ++i) {
      if (robot.mass(i) <= 0) continue;
      const Eigen::Vector3d r = start.x.row(robot.first_row + i).transpose() - com;
      perp[i] = r - r.dot(d) * d;
      rho = std::max(rho, perp[i].norm());
    }
    for (int i = 0; i < robot.vertices; ++i) {
      if (robot.mass(i) <= 0) continue;
      rows.push_back(robot.first_row + i);
      const Eigen::Vector3d in = rho > 0 ? Eigen::Vector3d(perp[i] / rho) : Eigen::Vector3d::Zero();
      f.push_back(c.force * (robot.mass(i) / robot.total_mass) * (d - in));
    }
    return std::make_unique<ConstantForces>(std::move(rows), std::move(f));
  }
};

}  // namespace

const ControlKind& squeeze_control() {
  static const SqueezeControl kind;
  return kind;
}

}  // namespace squeeze::plan
