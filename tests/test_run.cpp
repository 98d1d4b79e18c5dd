// Tests of `squeeze run` and the bundled scenes (issue 8): the whole pipeline end to end on a small
// scene, every bundled scene loads and passes the start checks, and bad scenes get one clear line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing_test_util.h"
#include "squeeze/fem/scene.h"
#include "squeeze/plan/planner.h"
#include "squeeze/plan/propagator.h"

namespace fs = std::filesystem;
using namespace squeeze;
using namespace squeeze::meshing;

namespace {

const std::string kScenes = std::string(SQUEEZE_SOURCE_DIR) + "/scenes/";


// squeeze ARGS run in the test's folder d, under a time limit: the exit code, stderr into *err.
int run(const fs::path& d, const std::vector<std::string>& args, std::string* err = nullptr) {
  return sqt::run_squeeze(args, d, err);
}

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// Barriers1 with absolute mesh paths, written elsewhere (so that tests can break it).
nlohmann::json barriers1() {
  nlohmann::json j = read_json(kScenes + "barriers1.json");
  for (auto& o : j["objects"]) o["mesh"] = kScenes + o["mesh"].get<std::string>();
  return j;
}

}  // namespace

TEST(BundledScenes, LoadBuildAndPassTheStartChecks) {
  for (const char* name : {"barriers1", "barriers2", "windows", "falling_objects", "body_parts"}) {
    SCOPED_TRACE(name);
    const fem::Scene scene = fem::load_scene(kScenes + name + ".json");
    const fem::SceneWorld w = fem::build_scene(scene);
    EXPECT_NO_THROW(plan::check_robot_start(w));
    EXPECT_NO_THROW(plan::planner_options(w));
    ASSERT_TRUE(scene.goal);
    EXPECT_TRUE(w.bounds.contains(scene.goal->position));
    // Roughly the paper's Table I tet counts.
    const int tets = w.world.tets();
    const int paper = std::string(name) == "barriers1"         ? 673
                      : std::string(name) == "barriers2"       ? 2343
                      : std::string(name) == "windows"         ? 1710
                      : std::string(name) == "falling_objects" ? 396
                                                               : 300;
    EXPECT_GT(tets, paper * 0.6) << tets;
    EXPECT_LT(tets, paper * 1.4) << tets;
  }
}

TEST(RunCli, WholePipelineOnBarriers1) {
  const sqt::TempDir tmp("run-b1");
  const fs::path& d = tmp.path();
  const fs::path out = d / "out";
  std::string err;
  const int rc = run(d,
                     {"-q", "run", kScenes + "barriers1.json", "-o", out.string(), "--seed", "2", "--width", "320",
                      "--height", "180", "--fps", "10", "--export", "pc2"},
                     &err);
  ASSERT_TRUE(rc == 0 || rc == 3) << rc << err;
  for (const char* f : {"plan.json", "metrics.csv", "trajectory/index.json", "volume.png", "volume.svg", "summary.json",
                        "frames/frame_00000.png", "export/robot.pc2"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const nlohmann::json s = read_json(out / "summary.json");
  const nlohmann::json idx = read_json(out / "trajectory" / "index.json");
  int pngs = 0;
  for (const auto& e : fs::directory_iterator(out / "frames")) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, idx["frames"].get<int>());
  EXPECT_EQ(s["frames"], idx["frames"]);
  for (const char* k : {"status", "iterations", "seconds", "max_volume_change", "outputs", "final_distance"})
    EXPECT_TRUE(s.contains(k)) << k;
  if (rc == 0) {
    EXPECT_EQ(s["status"], "solved");
    EXPECT_LT(s["final_distance"].get<double>(), 0.1);
    for (const auto& [name, v] : s["max_volume_change"].items()) EXPECT_LT(v.get<double>(), 0.03) << name;
  }
  // Nothing temporary left behind.
  for (const auto& e : fs::recursive_directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(RunCli, BadScenesGetOneLineNamingFileAndKey) {
  const sqt::TempDir tmp("run-bad");
  const fs::path& d = tmp.path();
  struct Case {
    std::string what, expect;
    std::function<void(nlohmann::json&)> edit;
  };
  const std::vector<Case> cases = {
      {"missing asset", "objects[1].mesh: file", [](nlohmann::json& j) { j["objects"][1]["mesh"] = "/nonexistent/plate.mesh"; }},
      {"no robot", "no object has \"role\": \"robot\"",
       [](nlohmann::json& j) {
         j["objects"][0]["role"] = "obstacle";
         j["goal"]["object"] = "robot";
       }},
      {"two robots", "a second robot",
       [](nlohmann::json& j) {
         j["objects"][1]["role"] = "robot";
         j["goal"]["object"] = "robot";
       }},
      {"goal outside bounds", "goal.position: outside the bounds", [](nlohmann::json& j) { j["goal"]["position"] = {9, 0, 0}; }},
      {"robot inside an obstacle", "objects[0].transform: the robot starts inside \"plate_a\"",
       [](nlohmann::json& j) { j["objects"][0]["transform"]["translate"] = {-0.6, 0.5, 0.0}; }},
      {"bad planner key", "planner.t_min: must be <= planner.t_max",
       [](nlohmann::json& j) { j["planner"] = {{"t_min", 1.0}, {"t_max", 0.5}}; }},
      {"bad render key", "render.camera.fov_deg", [](nlohmann::json& j) { j["render"]["camera"]["fov_deg"] = -3; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    nlohmann::json j = barriers1();
    c.edit(j);
    const fs::path scene = d / "scene.json";
    std::ofstream(scene) << j.dump(2);
    std::string err;
    EXPECT_EQ(run(d, {"run", scene.string(), "-o", (d / "out").string()}, &err), 1);
    EXPECT_NE(err.find(c.expect), std::string::npos) << err;
    EXPECT_NE(err.find("scene.json"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_FALSE(fs::exists(d / "out" / "plan.json"));
  }
}

TEST(BenchTable1Cli, BadArgumentsGetOneLineAndWriteNothing) {
  const sqt::TempDir tmp("run-table1");
  const fs::path& d = tmp.path();
  std::string err;
  EXPECT_EQ(run(d, {"bench", "table1", "-o", (d / "missing" / "out").string()}, &err), 1);
  EXPECT_NE(err.find("parent directory"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  std::ofstream(d / "file") << "x";
  EXPECT_EQ(run(d, {"bench", "table1", "-o", (d / "file").string()}, &err), 1);
  EXPECT_NE(err.find("exists and is not a directory"), std::string::npos) << err;
  EXPECT_EQ(run(d, {"bench", "table1", "--only", "nosuchscene", "-o", (d / "out").string()}, &err), 1);
  EXPECT_NE(err.find("--only nosuchscene: no bundled scene matches"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(d / "out"));
}

// Issue 15: `squeeze run` builds the scene's World once; planning, replay and metrics use copies.
TEST(RunCli, BuildsTheSceneWorldOnce) {
  const sqt::TempDir tmp("run-once");
  const fs::path& d = tmp.path();
  std::string err;
  const int rc = run(d, {"-v", "run", kScenes + "barriers1.json", "-o", (d / "out").string(), "--iterations", "8",
                         "--no-render"},
                     &err);
  ASSERT_TRUE(rc == 0 || rc == 3) << rc << err;
  EXPECT_NE(err.find("built the scene's world 1 time (planning, replay and metrics use copies)"), std::string::npos)
      << err;
}
