// Tests of issue 19: starts at rest on a surface, the default max_force from the robot's
// mechanics, the squeeze force, --time-limit within one expansion, OMPL's planners over squeeze's
// simulation (determinism, replay).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing_test_util.h"
#include "squeeze/common/error.h"
#include "squeeze/plan/planner.h"

namespace fs = std::filesystem;
using namespace squeeze;
using namespace squeeze::plan;

namespace {

const std::string kAssets = std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/";

fs::path write_scene(const fs::path& dir, const nlohmann::json& j, const std::string& name = "scene.json") {
  const fs::path p = dir / name;
  std::ofstream(p) << j.dump(2);
  return p;
}

// A 20 cm cube (cube.off, meshed by squeeze mesh defaults) whose lowest face is at height `bottom`.
nlohmann::json cube_scene(double bottom, const nlohmann::json& extra_objects = nlohmann::json::array()) {
  nlohmann::json objects = {{{"name", "cube"}, {"mesh", kAssets + "cube.off"}, {"role", "robot"},
                             {"transform", {{"scale", 0.2}, {"translate", {-0.3, bottom + 0.1, 0.0}}}}}};
  for (const auto& o : extra_objects) objects.push_back(o);
  return {{"floor", 0.0},
          {"bounds", {{"min", {-0.6, 0.0, -0.4}}, {"max", {0.6, 0.8, 0.4}}}},
          {"objects", objects},
          {"goal", {{"position", {0.3, 0.1, 0.0}}, {"tolerance", 0.05}}}};
}

}  // namespace

// --- starts at rest on a surface ---

TEST(PlanStart, CubeRestingOnTheFloorIsAValidStart) {
  const sqt::TempDir tmp("plan-floor");
  const fem::SceneWorld w = fem::build_scene(fem::load_scene(write_scene(tmp.path(), cube_scene(0.0))));
  ASSERT_NEAR(w.world.body(0).rest.col(1).minCoeff(), 0.0, 1e-6);
  EXPECT_NO_THROW(check_planning_inputs(w));
  // Touching up to rounding of a transform or a mesh (0.1 µm below) is resting on it.
  const fem::SceneWorld touching =
      fem::build_scene(fem::load_scene(write_scene(tmp.path(), cube_scene(-1e-7), "touching.json")));
  ASSERT_LT(touching.world.body(0).rest.col(1).minCoeff(), 0.0);
  EXPECT_NO_THROW(check_planning_inputs(touching));
  // 1 cm into the floor is still refused, naming the floor.
  const fem::SceneWorld below = fem::build_scene(fem::load_scene(write_scene(tmp.path(), cube_scene(-0.01), "below.json")));
  try {
    check_planning_inputs(below);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("below the floor"), std::string::npos) << e.what();
  }
  EXPECT_GT(touch_tolerance(w.world.body(0)), 0.0);
  EXPECT_LT(touch_tolerance(w.world.body(0)), 1e-3);  // m: touching, not a centimetre
}

TEST(PlanStart, CubeRestingOnAnObstacleIsAValidStart) {
  const sqt::TempDir tmp("plan-on-box");
  // A rigid 0.6 × 0.2 × 0.6 m box on the floor; the cube rests on its top face (y = 0.2).
  const nlohmann::json box = {{"name", "box"}, {"mesh", kAssets + "cube.off"}, {"kind", "rigid"},
                              {"transform", {{"scale", {0.6, 0.2, 0.6}}, {"translate", {-0.3, 0.1, 0.0}}}}};
  nlohmann::json on = cube_scene(0.2 - 1e-7, nlohmann::json::array({box}));  // 0.1 µm: touching, up to rounding
  on["contact"] = {{"rest_overlap", false}};  // every overlap at rest counts
  EXPECT_NO_THROW(check_planning_inputs(fem::build_scene(fem::load_scene(write_scene(tmp.path(), on)))));
  nlohmann::json in = cube_scene(0.15, nlohmann::json::array({box}));  // 5 cm into the box
  in["contact"] = {{"rest_overlap", false}};
  try {
    check_planning_inputs(fem::build_scene(fem::load_scene(write_scene(tmp.path(), in, "in.json"))));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("starts inside \"box\""), std::string::npos) << e.what();
  }
}

// --- the default max_force ---

TEST(PlanDefaults, MaxForceCompressesTheRobotAgainstItsOwnElasticity) {
  const sqt::TempDir tmp("plan-max-force");
  auto ball = [&](double E, const std::string& name) {
    const nlohmann::json j = {
        {"gravity", {0, 0, 0}},
        {"floor", nullptr},
        {"objects",
         {{{"name", "ball"}, {"mesh", kAssets + "sphere.off"}, {"role", "robot"}, {"material", {{"youngs_modulus", E}}},
           {"transform", {{"scale", 0.2}}}}}},
        {"goal", {{"position", {0.2, 0.0, 0.0}}, {"tolerance", 0.05}}}};
    return fem::build_scene(fem::load_scene(write_scene(tmp.path(), j, name)));
  };
  const fem::SceneWorld soft = ball(1e5, "soft.json"), stiff = ball(4e5, "stiff.json");
  const MaxForceTerms t = max_force_terms(soft);
  const double V = soft.world.body(0).total_volume();
  EXPECT_NEAR(t.volume, V, 1e-12);
  EXPECT_NEAR(t.youngs_modulus, 1e5, 1e-6 * 1e5);  // the default stiffnesses: Σ k_edge = E V
  EXPECT_NEAR(t.cross_section, std::pow(V, 2.0 / 3.0), 1e-12);
  EXPECT_EQ(t.gravity, 0.0);
  // A 20 cm ball of 100 kPa: E A ε = 1e5 · V^(2/3) · 0.2, about 500 N: far above what moving its
  // 4 kg across its size takes (m d / t_max², about 6 N), so that is the default.
  const double expected = 1e5 * std::pow(V, 2.0 / 3.0) * MaxForceTerms::kSqueezeStrain;
  EXPECT_GT(expected, 300.0);
  EXPECT_NEAR(planner_options(soft).max_force, expected, 1e-9 * expected);
  EXPECT_NEAR(t.max_force(0.5), std::max(t.mass * t.size / 0.25, expected), 1e-9 * expected);
  EXPECT_NEAR(planner_options(stiff).max_force, 4 * expected, 4e-9 * expected);
  // A scene's own max_force wins.
  const nlohmann::json j = {{"gravity", {0, 0, 0}},
                            {"floor", nullptr},
                            {"objects",
                             {{{"name", "ball"}, {"mesh", kAssets + "sphere.off"}, {"role", "robot"},
                               {"transform", {{"scale", 0.2}}}}}},
                            {"goal", {{"position", {0.2, 0.0, 0.0}}, {"tolerance", 0.05}}},
                            {"planner", {{"max_force", 7.5}}}};
  EXPECT_EQ(planner_options(fem::build_scene(fem::load_scene(write_scene(tmp.path(), j, "given.json")))).max_force, 7.5);
}

// --- the squeeze force ---

TEST(PlanForces, SqueezeForcePushesLikeTheBodyForceAndCompressesAcrossIt) {
  const sqt::TempDir tmp("plan-squeeze-force");
  const fem::SceneWorld w = fem::build_scene(fem::load_scene(write_scene(tmp.path(), cube_scene(0.0))));
  const Robot robot(w.world, 0);
  const fem::State s = w.initial_state();
  Control c;
  c.kind = &control_kind("squeeze");
  c.force = 40.0;
  c.target = robot.com(s) + Eigen::Vector3d(1.0, 0.0, 0.0);
  fem::RowMatrixX3d F = fem::RowMatrixX3d::Zero(w.world.state_rows(), 3);
  apply_control(robot, c, s)->add_forces(s, F);
  const Eigen::Vector3d total = F.colwise().sum().transpose();
  EXPECT_NEAR(total.x(), 40.0, 1e-9);
  EXPECT_NEAR(total.y(), 0.0, 1e-9);
  EXPECT_NEAR(total.z(), 0.0, 1e-9);
  // Across x, every force points toward the axis through the centre of mass: Σ f⊥ · r⊥ < 0.
  const Eigen::Vector3d com = robot.com(s);
  double work = 0;
  for (int i = 0; i < robot.vertices; ++i) {
    Eigen::Vector3d r = s.x.row(robot.first_row + i).transpose() - com, f = F.row(robot.first_row + i).transpose();
    r.x() = 0;
    f.x() = 0;
    EXPECT_LE(f.dot(r), 1e-12) << "vertex " << i;
    work += f.dot(r);
  }
  EXPECT_LT(work, 0.0);
}

// --- --time-limit within one expansion ---

TEST(PlanTimeLimit, ReturnsWithinTheLimitPlusOneExpansion) {
  // Barriers1 with a goal no plan reaches: 5 cm below the floor (the 0.5 m cube's centre cannot get
  // within 1 cm of it), so the planner runs into the limit.
  fem::Scene scene = fem::load_scene(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/barriers1.json");
  ASSERT_TRUE(scene.goal);
  scene.goal->position.y() = -0.05;
  scene.goal->tolerance = 0.01;
  const fem::SceneWorld w = fem::build_scene(scene);
  PlannerOptions o = planner_options(w);
  o.iterations = 100000000;
  o.time_limit = 2.0;
  o.settle_start = 0;
  const PlanningProblem pb = planning_problem(w, o);
  // One expansion: the longest, t_max, with the largest body force.
  double expansion = 0;
  {
    std::unique_ptr<Propagator> p = pb.make_propagator();
    Control c;
    c.kind = &control_kind("body");
    c.force = o.max_force;
    c.target = pb.goal;
    fem::State out;
    const auto t0 = std::chrono::steady_clock::now();
    p->propagate(pb.start, c, static_cast<int>(std::lround(o.t_max / w.time_step())), out);
    expansion = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  for (const char* name : {"rrt", "ompl:KPIECE1"}) {
    const auto t0 = std::chrono::steady_clock::now();
    const PlanResult r = make_planner(name)->solve(pb, o, nullptr);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_TRUE(r.timed_out) << name << ": " << r.stats.iterations << " iterations, " << r.stats.nodes << " nodes, "
                             << r.stats.final_distance << " m from the goal (tolerance " << pb.tolerance << " m)";
    EXPECT_NE(r.status, PlanStatus::solved) << name;
    EXPECT_GE(elapsed, 2.0) << name;
    EXPECT_LE(elapsed, 2.0 + expansion) << name << ": one expansion takes " << expansion << " s";
  }
}

// --- OMPL's planners over squeeze's simulation ---

TEST(OmplPlanners, AreRegisteredBesideSqueezesRrt) {
  const std::vector<std::string> names = planner_names();
  for (const char* n : {"rrt", "ompl:RRT", "ompl:KPIECE1", "ompl:SST", "ompl:EST", "ompl:PDST"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  EXPECT_EQ(names.front(), "rrt");
  EXPECT_EQ(PlannerOptions().algorithm, "rrt");
}

TEST(OmplPlanners, SameSeedSamePlanAndTheReplayReproducesIt) {
  const sqt::TempDir tmp("plan-ompl");
  nlohmann::json j = cube_scene(0.0);
  j["planner"] = {{"iterations", 30}, {"t_max", 0.2}};
  const fem::SceneWorld w = fem::build_scene(fem::load_scene(write_scene(tmp.path(), j)));
  for (const char* name : {"ompl:KPIECE1", "ompl:RRT"}) {
    PlannerOptions o = planner_options(w);
    o.algorithm = name;
    o.seed = 3;
    const PlanResult a = squeeze::plan::plan(w, o), b = squeeze::plan::plan(w, o);
    ASSERT_GT(a.path.size(), 0u) << name;
    EXPECT_EQ(a.stats.iterations, b.stats.iterations) << name;
    EXPECT_EQ(a.stats.nodes, b.stats.nodes) << name;
    ASSERT_EQ(a.path.size(), b.path.size()) << name;
    for (size_t i = 0; i < a.path.size(); ++i) {
      EXPECT_EQ(a.path[i].steps, b.path[i].steps);
      EXPECT_EQ(a.path[i].control.kind, b.path[i].control.kind);
      EXPECT_EQ(a.path[i].control.target, b.path[i].control.target);
      EXPECT_EQ(a.path[i].control.force, b.path[i].control.force);
    }
    EXPECT_EQ(a.final_state_hash, b.final_state_hash) << name;
    // The replay of the path ends where the planner's tree did.
    PropagatorOptions popt;
    popt.max_volume_change = o.max_volume_change;
    popt.stop_when_invalid = false;
    SimulationPropagator p(w, popt);
    const PlanningProblem pb = planning_problem(w, o);
    const std::vector<fem::State> ends = replay(p, pb.start, a.path, a.settle, 0);
    ASSERT_EQ(ends.size(), a.path.size());
    EXPECT_EQ(state_hash(ends.back()), a.final_state_hash) << name;
    // Another seed, another plan.
    o.seed = 4;
    EXPECT_NE(squeeze::plan::plan(w, o).final_state_hash, a.final_state_hash) << name;
  }
}
