// The interpolation force (Rodriguez 2006, Sec. V-A and V-B): every robot vertex pulled toward its
// place in the goal configuration by a critically damped spring with a capped acceleration, the
// robot's gravity and the springs of its soft attachments cancelled.
#include "squeeze/common/json_check.h"
#include "squeeze/plan/control.h"

namespace squeeze::plan {
namespace {

class InterpolationForces : public AppliedControl {
 public:
  InterpolationForces(const Robot& robot, const Control& c) : robot_(&robot), c_(c) {}
  bool constant() const override { return false; }
  void add_forces(const fem::State& s, fem::RowMatrixX3d& F) const override {
    const Robot& r = *robot_;
    const double w = c_.omega, a_max = c_.force / r.total_mass;
    const Eigen::Vector3d shift = c_.target - r.rest_com;
    for (int i = 0; i < r.vertices; ++i) {
      if (r.mass(i) <= 0) continue;
      const int row = r.first_row + i;
      const Eigen::Vector3d goal = r.rest.row(i).transpose() + shift;
      Eigen::Vector3d a = w * w * (goal - s.x.row(row).transpose()) - 2 * w * s.v.row(row).transpose();
      const double n = a.norm();
      if (n > a_max) a *= a_max / n;
      F.row(row) += (r.mass(i) * (a - r.gravity)).transpose();
      // The passive forces on the robot are cancelled: its gravity above, and the pull of its soft
      // attachments (which, carrying the weight, would otherwise hold it back from the goal).
      if (r.attach_k(i) > 0) F.row(row) += r.attach_k(i) * (s.x.row(row) - r.anchor.row(i));
    }
  }

 private:
  const Robot* robot_;
  Control c_;
};

class InterpolationControl : public ControlKind {
 public:
  const char* name() const override { return "interpolation"; }
  double default_weight() const override { return 0.2; }
  bool toward_goal() const override { return true; }
  void sample(Control& c, const SamplingContext& ctx, Random&) const override {
    // The goal configuration puts the goal object's centre at the goal; for the robot as goal
    // object, its rest shape's centre goes there.
    c.force = ctx.max_force;
    c.omega = ctx.interpolation_omega;
  }
  std::unique_ptr<AppliedControl> apply(const Robot& robot, const Control& c, const fem::State&) const override {
    return std::make_unique<InterpolationForces>(robot, c);
  }
  std::vector<std::string> json_keys() const override { return {"omega"}; }
  void to_json(const Control& c, nlohmann::json& j) const override { j["omega"] = c.omega; }
  void from_json(const JsonChecker& check, const nlohmann::json& j, const std::string& path, Control& c) const override {
    if (!j.contains("omega")) check.fail(path + ".omega", "missing (required for an interpolation force)");
    c.omega = check.positive(j["omega"], path + ".omega");
  }
};

}  // namespace

const ControlKind& interpolation_control() {
  static const InterpolationControl kind;
  return kind;
}

}  // namespace squeeze::plan
