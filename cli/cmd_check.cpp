// `squeeze check SCENE [--json FILE]`: builds a scene (meshes through the cache) and tells what it
// will do before it is simulated or planned: per object its tets, vertices, mass, pins, the time
// step it alone would need; the rest overlaps and gaps of the objects; a short settle; warnings.
// Exit 0 with or without warnings, 1 for a bad scene (plan/scene_check.h has the analysis).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "scene_options.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/format.h"
#include "squeeze/common/error.h"
#include "squeeze/common/log.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/scene.h"
#include "squeeze/plan/planner.h"
#include "squeeze/plan/propagator.h"
#include "squeeze/plan/scene_check.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

struct CheckArgs {
  std::string scene, json, integrator;
  double settle = 0.1;
};

std::string fixed2(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", x);
  return buf;
}

std::string vec(const Eigen::Vector3d& v) { return "[" + format_g3(v.x()) + ", " + format_g3(v.y()) + ", " + format_g3(v.z()) + "]"; }

// Columns padded to their widest cell; `right` marks right-aligned columns.
std::string table(const std::vector<std::vector<std::string>>& rows, const std::vector<bool>& right) {
  std::vector<size_t> width(rows.empty() ? 0 : rows[0].size(), 0);
  // Display width: count UTF-8 code points, not bytes (m³, Δ).
  auto cols = [](const std::string& s) {
    size_t n = 0;
    for (unsigned char c : s) n += (c & 0xC0) != 0x80;
    return n;
  };
  for (const auto& r : rows)
    for (size_t c = 0; c < r.size(); ++c) width[c] = std::max(width[c], cols(r[c]));
  std::string out;
  for (const auto& r : rows) {
    std::string line;
    for (size_t c = 0; c < r.size(); ++c) {
      const std::string pad(width[c] - cols(r[c]), ' ');
      line += (c ? "  " : "") + (right[c] ? pad + r[c] : r[c] + (c + 1 < r.size() ? pad : ""));
    }
    out += "  " + line + "\n";
  }
  return out;
}

}  // namespace

std::optional<double> scene_volume_limit(const fem::SceneWorld& w) {
  int robots = 0, robot = -1;
  for (size_t i = 0; i < w.scene.objects.size(); ++i)
    if (w.scene.objects[i].robot) ++robots, robot = static_cast<int>(i);
  if (robots != 1 || w.scene.objects[robot].rigid) return std::nullopt;
  return plan::planner_options(w).max_volume_change;
}

void print_scene_warnings(const fem::SceneWorld& w, std::optional<double> max_volume_change, double settle,
                          Progress* progress) {
  if (verbosity() == Verbosity::quiet) return;  // nothing would be shown: skip the settle too
  plan::SceneCheckOptions o;
  o.details = false;
  o.max_volume_change = max_volume_change;
  o.settle = settle;
  o.progress = progress;
  const plan::SceneCheck c = plan::check_scene(w, o);
  for (const std::string& line : c.warnings) spdlog::warn("{}: {}", w.scene.file.string(), line);
}

Runner add_check_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* cmd = app.add_subcommand(
      "check",
      "Build a scene (meshing through the cache) and tell what it will do before simulating or planning:\n"
      "per object its tets, vertices, mass, pins (hard / soft), the time step it alone would need and\n"
      "which term sets it; the scene's time step; the rest overlaps of every pair of objects (vertices\n"
      "inside the other's coarse mesh, deepest penetration) or the gap between them, and how much of\n"
      "each lies inside the other in the coarse meshes against in the surfaces; the volume change\n"
      "of a short settle without control; and warnings (objects below the floor, a robot inside or\n"
      "touching an obstacle, a goal outside the bounds, a settle that breaks planner.max_volume_change, ...).\n"
      "simulate, plan and run print the same warnings before they start. Exit 0 with or without\n"
      "warnings, 1 for a bad scene. Output: scenes/README.md (\"squeeze check\").\n"
      "Example: squeeze check scenes/body_parts.json --json out/body_parts.check.json");
  cmd->add_option("SCENE", args->scene, "Scene file (JSON)")->required();
  cmd->add_option("--json", args->json, "Also write the report as JSON to this file");
  cmd->add_option("--settle", args->settle, "Seconds simulated without control to measure volume changes (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  add_integrator_option(cmd, args->integrator);

  return [args, &global]() -> int {
    const CheckArgs& a = *args;
    if (!std::isfinite(a.settle)) throw InputError("--settle must be a finite number of seconds");
    if (!a.json.empty()) check_output_directory(a.json);
    Progress progress(!global.quiet);
    const fem::Scene scene = load_scene_with(a.scene, a.integrator);
    const fem::SceneWorld w = fem::build_scene(scene, &progress);
    plan::SceneCheckOptions o;
    o.settle = a.settle;
    o.max_volume_change = scene_volume_limit(w);  // validates the planner block when there is a robot
    if (a.settle > 0) progress.stage("settling");
    const plan::SceneCheck c = plan::check_scene(w, o);
    progress.finish();

    // --- the table (stdout) ---
    int tets = 0, vertices = 0;
    for (const plan::ObjectCheck& ob : c.objects) tets += ob.tets, vertices += ob.vertices;
    std::string s;
    s += a.scene + ": " + std::to_string(c.objects.size()) + " objects, " + std::to_string(tets) + " tets, " +
         std::to_string(vertices) + " vertices\n";
    s += "  time step " + c.time_step.describe(scene) + "\n";
    s += "  gravity " + vec(scene.gravity) + " m/s², floor " + (scene.floor ? "y = " + format_g3(*scene.floor) + " m" : "none") +
         ", bounds " + vec(w.bounds.min()) + " .. " + vec(w.bounds.max()) + " m\n";
    if (scene.goal)
      s += "  goal " + vec(scene.goal->position) + " ± " + format_g3(scene.goal->tolerance) + " m for '" + scene.goal->object + "'\n";
    s += "\n";
    std::vector<std::vector<std::string>> rows = {
        {"object", "kind", "role", "material", "tets", "vertices", "mass kg", "volume m³", "pins hard/soft",
         "below floor", "time step alone (term)", "settle ΔV"}};
    for (size_t b = 0; b < c.objects.size(); ++b) {
      const plan::ObjectCheck& ob = c.objects[b];
      const fem::SceneObject& so = scene.objects[b];
      rows.push_back({ob.name, ob.rigid ? "rigid" : "deformable", ob.robot ? "robot" : "obstacle",
                      ob.rigid ? "-" : so.preset.empty() ? "E " + format_g3(so.youngs_modulus) + " Pa" : so.preset, std::to_string(ob.tets),
                      std::to_string(ob.vertices), ob.rigid ? "-" : format_g3(ob.mass), format_g3(ob.volume),
                      ob.rigid ? "-" : std::to_string(ob.hard_pins) + "/" + std::to_string(ob.soft_pins),
                      ob.below_floor ? std::to_string(ob.below_floor) + " (" + format_g3(ob.below_floor_depth) + " m)" : "-",
                      ob.time_step.h > 0 ? format_g3(ob.time_step.h) + " s (" + ob.time_step.term + ")" : "-",
                      ob.rigid || c.settle <= 0 ? "-" : fixed2(100 * ob.settle_volume_change) + " %"});
    }
    s += table(rows, {false, false, false, false, true, true, true, true, true, true, false, true});
    s += "\n  rest overlaps (vertices of A inside B's tetrahedra and of B inside A's, deepest penetration) and gaps:\n";
    s += "  and, in percent of each object's vertices, how much of A lies inside B (and B inside A) in the\n"
         "  coarse meshes against in the surfaces (winding number); the difference is the meshes' doing:\n";
    std::vector<std::vector<std::string>> pairs = {
        {"A", "B", "A in B", "B in A", "deepest m", "gap m", "A in B coarse/surface %", "B in A coarse/surface %"}};
    auto pct = [](double coarse, double surface) {
      return coarse < 0 ? std::string("-") : fixed2(100 * coarse) + " / " + fixed2(100 * surface);
    };
    for (const plan::OverlapCheck& p : c.overlaps)
      pairs.push_back({scene.objects[p.a].name, p.a == p.b ? "(itself)" : scene.objects[p.b].name, std::to_string(p.a_in_b),
                       std::to_string(p.b_in_a), p.overlapping() ? format_g3(p.depth) : "-", p.gap >= 0 ? format_g3(p.gap) : "-",
                       pct(p.coarse_a_in_b, p.surface_a_in_b), pct(p.coarse_b_in_a, p.surface_b_in_a)});
    if (pairs.size() == 1) s += "  (one object)\n";
    else s += table(pairs, {false, false, true, true, true, true, true, true});
    if (c.settle > 0) {
      s += "\n  settle: " + format_g3(c.settle) + " s from the start without control" + (c.settle_diverged ? " (diverged)" : "");
      s += c.max_volume_change ? "; planner.max_volume_change " + format_g3(100 * *c.max_volume_change) + " %\n" : "\n";
    }
    s += "\n";
    // Building the scene's warnings (logged as it was built: more tetrahedra than asked) first, then
    // the check's: the count says all of them.
    std::vector<std::string> warnings = w.warnings;
    warnings.insert(warnings.end(), c.warnings.begin(), c.warnings.end());
    if (warnings.empty()) s += "no warnings\n";
    else s += std::to_string(warnings.size()) + (warnings.size() == 1 ? " warning:\n" : " warnings:\n");
    for (const std::string& wline : warnings) s += "  warning: " + wline + "\n";
    std::fputs(s.c_str(), stdout);
    std::fflush(stdout);

    // --- the same as JSON ---
    if (!a.json.empty()) {
      using json = nlohmann::json;
      auto step = [&](const fem::TimeStepChoice& t, const fem::Scene& sc) -> json {
        if (!(t.h > 0)) return nullptr;
        return {{"h", t.h}, {"term", t.term}, {"detail", t.detail}, {"text", t.describe(sc)}};
      };
      json j;
      j["scene"] = a.scene;
      j["integrator"] = scene.integrator;
      j["time_step"] = step(c.time_step, scene);
      j["bounds"] = {{"min", {w.bounds.min().x(), w.bounds.min().y(), w.bounds.min().z()}},
                     {"max", {w.bounds.max().x(), w.bounds.max().y(), w.bounds.max().z()}}};
      j["objects"] = json::array();
      for (size_t b = 0; b < c.objects.size(); ++b) {
        const plan::ObjectCheck& ob = c.objects[b];
        fem::Scene alone = scene;
        alone.objects = {scene.objects[b]};
        j["objects"].push_back({{"name", ob.name},
                                {"kind", ob.rigid ? "rigid" : "deformable"},
                                {"role", ob.robot ? "robot" : "obstacle"},
                                {"preset", scene.objects[b].preset.empty() ? json(nullptr) : json(scene.objects[b].preset)},
                                {"youngs_modulus", scene.objects[b].youngs_modulus},
                                {"density", scene.objects[b].density},
                                {"tets", ob.tets},
                                {"vertices", ob.vertices},
                                {"mass", ob.mass},
                                {"volume", ob.volume},
                                {"pins", {{"hard", ob.hard_pins}, {"soft", ob.soft_pins}, {"per_entry", ob.pin_counts}}},
                                {"below_floor", {{"vertices", ob.below_floor}, {"depth", ob.below_floor_depth}}},
                                {"time_step_alone", step(ob.time_step, alone)},
                                {"settle_volume_change", ob.settle_volume_change}});
      }
      j["overlaps"] = json::array();
      for (const plan::OverlapCheck& p : c.overlaps)
        j["overlaps"].push_back({{"a", scene.objects[p.a].name},
                                 {"b", scene.objects[p.b].name},
                                 {"a_in_b", p.a_in_b},
                                 {"b_in_a", p.b_in_a},
                                 {"depth", p.depth},
                                 {"gap", p.gap >= 0 ? json(p.gap) : json(nullptr)},
                                 {"coarse_a_in_b", p.surfaces_measured() ? json(p.coarse_a_in_b) : json(nullptr)},
                                 {"surface_a_in_b", p.surfaces_measured() ? json(p.surface_a_in_b) : json(nullptr)},
                                 {"coarse_b_in_a", p.surfaces_measured() ? json(p.coarse_b_in_a) : json(nullptr)},
                                 {"surface_b_in_a", p.surfaces_measured() ? json(p.surface_b_in_a) : json(nullptr)}});
      j["settle"] = {{"seconds", c.settle},
                     {"diverged", c.settle_diverged},
                     {"max_volume_change", c.max_volume_change ? json(*c.max_volume_change) : json(nullptr)}};
      j["warnings"] = warnings;
      write_atomically(a.json, [&](const fs::path& p) {
        std::ofstream f(p);
        f << j.dump(2) << '\n';
        if (!f) throw InputError(a.json + ": write failed");
      });
    }
    return kExitOk;
  };
}

}  // namespace squeeze::cli
