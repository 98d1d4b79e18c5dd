#include "squeeze/plan/plan_io.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/fem/scene.h"

namespace squeeze::plan {
using json = nlohmann::json;

namespace {

json control_json(const Control& c, int steps, double h) {
  json j = {{"kind", c.kind->name()},
            {"target", {c.target.x(), c.target.y(), c.target.z()}},
            {"force", c.force},
            {"steps", steps},
            {"duration", steps * h}};
  c.kind->to_json(c, j);
  return j;
}

Control read_control(const JsonChecker& c, const json& j, const std::string& path, int* steps) {
  if (!j.is_object()) c.fail(path, "must be an object, got " + json_type_name(j));
  if (!j.contains("kind")) c.fail(path + ".kind", "missing (required)");
  Control ctl;
  ctl.kind = &control_kind(c.string(j["kind"], path + ".kind"), c.file + ": " + path + ".kind");
  std::vector<std::string> keys = {"kind", "target", "force", "steps", "duration"};
  for (const std::string& k : ctl.kind->json_keys()) keys.push_back(k);
  c.keys(j, path, keys);
  for (const char* k : {"target", "force", "steps"})
    if (!j.contains(k)) c.fail(path + "." + k, "missing (required)");
  ctl.target = c.vec3(j["target"], path + ".target");
  ctl.force = c.non_negative(j["force"], path + ".force");
  *steps = static_cast<int>(c.integer(j["steps"], path + ".steps", 0, 1LL << 30));
  ctl.kind->from_json(c, j, path, ctl);
  return ctl;
}

}  // namespace

PlanFile make_plan_file(const fem::Scene& scene, const PlannerOptions& options, const PlanResult& r) {
  PlanFile f;
  f.scene = std::filesystem::absolute(scene.file).lexically_normal().string();
  f.status = r.status;
  f.options = options;
  f.stats = r.stats;
  f.time_step = r.time_step;
  f.integrator = scene.integrator;
  f.path = r.path;
  f.settle = r.settle;
  f.settle_steps = r.settle_steps;
  f.start_settle_steps = r.start_settle_steps;
  f.final_state_hash = r.final_state_hash;
  return f;
}

void save_plan(const std::filesystem::path& file, const PlanFile& p) {
  json j;
  j["format"] = "squeeze-plan";
  j["version"] = 1;
  j["scene"] = p.scene;
  j["status"] = to_string(p.status);
  j["seed"] = p.options.seed;
  j["time_step"] = p.time_step;
  if (!p.integrator.empty()) j["integrator"] = p.integrator;
  const PlannerOptions& o = p.options;
  j["planner"] = {{"iterations", o.iterations},
                  {"seed", o.seed},
                  {"goal_bias", o.goal_bias},
                  {"t_min", o.t_min},
                  {"t_max", o.t_max},
                  {"max_force", o.max_force},
                  {"control_radius", o.control_radius},
                  {"max_volume_change", o.max_volume_change},
                  {"interpolation_omega", o.interpolation_omega},
                  {"settle", o.settle},
                  {"settle_start", o.settle_start},
                  {"batch", o.batch},
                  {"keep_valid_prefix", o.keep_valid_prefix},
                  {"algorithm", o.algorithm}};
  for (const ControlKind* k : control_kinds()) j["planner"]["weights"][k->name()] = o.weights[k->name()];
  const PlanStatistics& s = p.stats;
  j["statistics"] = {{"iterations", s.iterations},
                     {"nodes", s.nodes},
                     {"truncated", s.truncated},
                     {"discarded", {{"diverged", s.discarded_diverged},
                                    {"volume", s.discarded_volume},
                                    {"bounds", s.discarded_bounds},
                                    {"volume_by_object", s.discarded_volume_by_object},
                                    {"total", s.discarded_diverged + s.discarded_volume + s.discarded_bounds}}},
                     {"seconds", s.seconds},
                     {"iterations_per_second", s.seconds > 0 ? s.iterations / s.seconds : 0.0},
                     {"simulation_steps", s.simulation_steps},
                     {"bytes_per_node", s.bytes_per_node},
                     {"state_bytes", s.state_bytes},
                     {"peak_memory_bytes", s.peak_memory},
                     {"final_distance", s.final_distance}};
  j["path"] = json::array();
  for (const PathSegment& seg : p.path) j["path"].push_back(control_json(seg.control, seg.steps, p.time_step));
  j["settle"] = control_json(p.settle, p.settle_steps, p.time_step);
  j["start_settle_steps"] = p.start_settle_steps;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016" PRIx64, p.final_state_hash);
  j["final_state_hash"] = hex;
  write_atomically(file, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp);
    out << j.dump(2) << '\n';
    if (!out) throw InputError(file.string() + ": write failed");
  });
}

PlanFile load_plan(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot be read (missing or unreadable plan file)");
  std::ostringstream text;
  text << in.rdbuf();
  const json j = parse_json(text.str(), file.string());
  const JsonChecker c{file.string()};
  if (!j.is_object() || !j.contains("format") || j["format"] != "squeeze-plan")
    c.fail("format", "not a squeeze plan (expected \"format\": \"squeeze-plan\")");
  PlanFile p;
  if (c.integer(j.value("version", json(0)), "version", 1, 1) != 1) c.fail("version", "unsupported");
  for (const char* k : {"scene", "status", "time_step", "path", "settle"})
    if (!j.contains(k)) c.fail(k, "missing (required)");
  p.scene = c.string(j["scene"], "scene");
  const std::string st = c.string(j["status"], "status");
  p.status = st == "solved" ? PlanStatus::solved : st == "approximate" ? PlanStatus::approximate : PlanStatus::failed;
  p.time_step = c.positive(j["time_step"], "time_step");
  if (!(p.time_step >= fem::kMinTimeStep && p.time_step <= fem::kMaxTimeStep))  // the scene's range
    c.fail("time_step", "must be in [" + format_number(fem::kMinTimeStep) + ", " + format_number(fem::kMaxTimeStep) +
                            "] s, got " + format_number(p.time_step));
  if (j.contains("integrator")) p.integrator = c.string(j["integrator"], "integrator");
  if (!j["path"].is_array()) c.fail("path", "must be an array");
  for (size_t i = 0; i < j["path"].size(); ++i) {
    PathSegment seg;
    seg.control = read_control(c, j["path"][i], "path[" + std::to_string(i) + "]", &seg.steps);
    p.path.push_back(seg);
  }
  p.settle = read_control(c, j["settle"], "settle", &p.settle_steps);
  if (j.contains("start_settle_steps"))
    p.start_settle_steps = static_cast<int>(c.integer(j["start_settle_steps"], "start_settle_steps", 0, 1LL << 30));
  if (j.contains("seed")) p.options.seed = static_cast<std::uint64_t>(c.integer(j["seed"], "seed", 0, 1LL << 53));
  // The hash is what a replay is checked against: required, exactly 16 hexadecimal digits.
  if (!j.contains("final_state_hash"))
    c.fail("final_state_hash", "missing (required: the replay is checked against it; the plan file is damaged)");
  const std::string h = c.string(j["final_state_hash"], "final_state_hash");
  if (h.size() != 16 || h.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos)
    c.fail("final_state_hash", "must be 16 hexadecimal digits, got \"" + h + "\"");
  p.final_state_hash = std::strtoull(h.c_str(), nullptr, 16);
  if (j.contains("statistics") && j["statistics"].is_object()) {
    const json& s = j["statistics"];
    if (s.contains("iterations")) p.stats.iterations = static_cast<int>(c.integer(s["iterations"], "statistics.iterations", 0, (1LL << 31) - 1));
    if (s.contains("nodes")) p.stats.nodes = static_cast<int>(c.integer(s["nodes"], "statistics.nodes", 0, (1LL << 31) - 1));
    if (s.contains("seconds")) p.stats.seconds = c.non_negative(s["seconds"], "statistics.seconds");
    if (s.contains("final_distance")) p.stats.final_distance = c.non_negative(s["final_distance"], "statistics.final_distance");
  }
  return p;
}

}  // namespace squeeze::plan
