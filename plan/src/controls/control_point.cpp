// The control-point force (Rodriguez 2006, Sec. V-A): a random surface vertex of the robot and
// its neighbours within a radius pushed toward the sample point (turns and bends the robot).
#include "directed.h"
#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"

namespace squeeze::plan {
namespace {

class ControlPointControl : public ControlKind {
 public:
  const char* name() const override { return "control_point"; }
  double default_weight() const override { return 0.3; }
  void sample(Control& c, const SamplingContext& ctx, Random& rng) const override {
    c.force = rng.uniform(0.0, ctx.max_force);
    const std::vector<int>& surface = ctx.robot->surface;
    c.vertex = surface[rng.index(static_cast<int>(surface.size()))];
    c.radius = ctx.control_radius;
  }
  void validate(const Control& c, const Robot& robot, const std::string& what) const override {
    if (c.vertex < 0 || c.vertex >= robot.vertices)
      throw InputError(what + ": a control point names robot vertex " + std::to_string(c.vertex) + " but the robot has " +
                       std::to_string(robot.vertices));
  }
  std::unique_ptr<AppliedControl> apply(const Robot& robot, const Control& c, const fem::State& start) const override {
    validate(c, robot, "control point");
    const Eigen::Vector3d from = start.x.row(robot.first_row + c.vertex).transpose();
    const double r2 = c.radius * c.radius;
    std::vector<int> set;
    double set_mass = 0;
    for (int i = 0; i < robot.vertices; ++i)
      if (robot.mass(i) > 0 && (start.x.row(robot.first_row + i).transpose() - from).squaredNorm() <= r2) {
        set.push_back(i);
        set_mass += robot.mass(i);
      }
    return directed_forces(robot, c, from, set, set_mass);
  }
  std::vector<std::string> json_keys() const override { return {"vertex", "radius"}; }
  void to_json(const Control& c, nlohmann::json& j) const override {
    j["vertex"] = c.vertex;
    j["radius"] = c.radius;
  }
  void from_json(const JsonChecker& check, const nlohmann::json& j, const std::string& path, Control& c) const override {
    if (!j.contains("vertex")) check.fail(path + ".vertex", "missing (required for a control_point force)");
    if (!j.contains("radius")) check.fail(path + ".radius", "missing (required for a control_point force)");
    c.vertex = static_cast<int>(check.integer(j["vertex"], path + ".vertex", 0, 1LL << 30));
    c.radius = check.non_negative(j["radius"], path + ".radius");
  }
};

}  // namespace

const ControlKind& control_point_control() {
  static const ControlPointControl kind;
  return kind;
}

}  // namespace squeeze::plan
