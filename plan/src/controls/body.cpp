// The body force (Rodriguez 2006, Sec. V-A): every robot vertex pushed toward the sample point,
// in proportion to its mass (a translation of the whole robot).
#include "directed.h"

namespace squeeze::plan {

namespace {

class BodyControl : public ControlKind {
 public:
  const char* name() const override { return "body"; }
  double default_weight() const override { return 0.5; }
  void sample(Control& c, const SamplingContext& ctx, Random& rng) const override {
    c.force = rng.uniform(0.0, ctx.max_force);
  }
  std::unique_ptr<AppliedControl> apply(const Robot& robot, const Control& c, const fem::State& start) const override {
    std::vector<int> set;
    for (int i = 0; i < robot.vertices; ++i)
      if (robot.mass(i) > 0) set.push_back(i);
    return directed_forces(robot, c, robot.com(start), set, robot.total_mass);
  }
};

}  // namespace

const ControlKind& body_control() {
  static const BodyControl kind;
  return kind;
}

}  // namespace squeeze::plan
