#include "squeeze/fem/scene.h"

#include "squeeze/common/format.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/integrator.h"
#include "squeeze/meshing/tet_geometry.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include <spdlog/spdlog.h>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/mesh_pipeline.h"
#include "squeeze/meshing/point_triangle_distance.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::fem {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Checker = JsonChecker;

std::string type_name(const json& j) { return json_type_name(j); }
std::string num(double x) { return format_number(x); }


const std::vector<std::pair<std::string, Eigen::Vector3d>>& scene_color_names() {
  static const std::vector<std::pair<std::string, Eigen::Vector3d>> names = [] {
    const std::pair<const char*, int> table[] = {
        {"black", 0x000000},  {"white", 0xffffff},  {"gray", 0x808080},   {"grey", 0x808080},
        {"silver", 0xc0c0c0}, {"red", 0xff0000},    {"maroon", 0x800000}, {"orange", 0xffa500},
        {"yellow", 0xffff00}, {"olive", 0x808000},  {"lime", 0x00ff00},   {"green", 0x008000},
        {"teal", 0x008080},   {"cyan", 0x00ffff},   {"blue", 0x0000ff},   {"navy", 0x000080},
        {"purple", 0x800080}, {"magenta", 0xff00ff}, {"pink", 0xffc0cb},  {"brown", 0xa52a2a},
        {"salmon", 0xfa8072}, {"coral", 0xff7f50},  {"gold", 0xffd700},   {"beige", 0xf5f5dc},
        {"tan", 0xd2b48c},    {"crimson", 0xdc143c}, {"indigo", 0x4b0082}, {"violet", 0xee82ee}};
    std::vector<std::pair<std::string, Eigen::Vector3d>> v;
    for (const auto& [n, hex] : table)
      v.emplace_back(n, Eigen::Vector3d((hex >> 16 & 0xff) / 255.0, (hex >> 8 & 0xff) / 255.0, (hex & 0xff) / 255.0));
    return v;
  }();
  return names;
}

namespace {

// `color`: [r, g, b] with each in [0, 1], or a name of scene_color_names(). Throws InputError.
Eigen::Vector3d parse_color(const JsonChecker& c, const nlohmann::json& j, const std::string& path) {
  if (j.is_string()) {
    std::string name = c.string(j, path);
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char ch) { return std::tolower(ch); });
    std::string list;
    for (const auto& [n, rgb] : scene_color_names()) {
      if (n == name) return rgb;
      list += (list.empty() ? "" : ", ") + n;
    }
    c.fail(path, "unknown colour \"" + name + "\" (a [r, g, b] triple in [0, 1], or one of: " + list + ")");
  }
  if (!j.is_array()) c.fail(path, "must be [r, g, b] in [0, 1] or a colour name");
  const Eigen::Vector3d rgb = c.vec3(j, path);
  for (int k = 0; k < 3; ++k)
    if (!(rgb(k) >= 0 && rgb(k) <= 1))
      c.fail(path + "[" + std::to_string(k) + "]", "must be in [0, 1], got " + format_number(rgb(k)));
  return rgb;
}

// Two independent 64-bit hashes (FNV-1a and a multiply-xorshift mix) = 128 bits of cache key.
struct Hash128 {
  std::uint64_t a = 1469598103934665603ULL, b = 0x9E3779B97F4A7C15ULL;
  void add(const char* p, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      const auto c = static_cast<unsigned char>(p[i]);
      a = (a ^ c) * 1099511628211ULL;
      b = (b ^ c) * 0xff51afd7ed558ccdULL;
      b ^= b >> 29;
    }
  }
  void add(const std::string& s) { add(s.data(), s.size()); }
  std::string hex() const {
    std::ostringstream s;
    s << std::hex << std::setfill('0') << std::setw(16) << a << std::setw(16) << b;
    return s.str();
  }
};

std::string read_file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string() + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::atomic<long long> g_scene_builds{0};

}  // namespace

long long scene_builds() { return g_scene_builds; }

Eigen::Affine3d SceneTransform::affine() const {
  const double d = M_PI / 180.0;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(rotate_deg.z() * d, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(rotate_deg.y() * d, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(rotate_deg.x() * d, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  Eigen::Affine3d A = Eigen::Affine3d::Identity();
  A.linear() = R * scale.asDiagonal();
  A.translation() = translate;
  return A;
}

const char* ScenePin::key() const {
  switch (kind) {
    case Kind::box: return "box";
    case Kind::near: return "near";
    case Kind::surface: return "surface";
  }
  return "?";
}

// Material presets (objects[].material.preset). Young's moduli are small-strain values of the
// linear model; the sources, their methods and ranges are in scenes/README.md ("Material presets").
// Elastography reports a shear modulus μ or E = 3μ (nearly incompressible tissue).
const std::vector<MaterialPreset>& material_presets() {
  static const std::vector<MaterialPreset> table = {
      {"liver", 5.5e3, 1060,
       "healthy human liver in vivo, transient elastography: E = 5.49 ± 1.59 kPa in 429 subjects (Roulot et al. 2008, "
       "J Hepatol 48:606-613, PMID 18222014); density 1060 kg/m³ (Duck 1990, Physical Properties of Tissue)"},
      {"lung", 4.5e3, 260,
       "human lung parenchyma in vivo, MR elastography: shear stiffness 1.14 ± 0.14 kPa at residual volume, 1.83 ± 0.22 kPa "
       "at total lung capacity, E = 3μ = 3.4-5.5 kPa (Mariappan et al. 2011, J Magn Reson Imaging 33:1351-1361); "
       "density of inflated lung 260 kg/m³ (ICRP Publication 23, 1975; deflated 1050)"},
      {"heart", 2.5e4, 1055,
       "passive left-ventricular myocardium ex vivo, AFM indentation of intact mouse hearts: 21.4-27.4 kPa (Kossivas et al. "
       "2013, Int J Nanotechnology, doi:10.1504/IJNT.2013.058565; 10-500 kPa by method: Emig et al. 2021, Biophys Rev "
       "13:587-610, doi:10.1007/s12551-021-00838-1); density 1055 kg/m³ (Gheorghe et al. 2019, BMC Med Imaging, "
       "doi:10.1186/s12880-019-0326-4)"},
      {"fat", 3.0e3, 950,
       "adipose tissue ex vivo, indentation at small strain: about 3 kPa, like fibroglandular tissue (Samani et al. 2007, "
       "Phys Med Biol 52:1565, doi:10.1088/0031-9155/52/6/002); density 925-970 kg/m³ (Martin et al. 1994, Int J Obes "
       "18:79-83)"},
      {"rubber", 1.2e6, 950,
       "vulcanised natural rubber: shear modulus about 0.4 MPa, E = 3μ (Treloar 1944 data, as fitted by Ogden et al. 2004, "
       "Comput Mech 34:484-502, doi:10.1007/s00466-004-0593-y; MatWeb lists 0.5 MPa); density 950 kg/m³ (uncompounded)"},
  };
  return table;
}

const MaterialPreset* find_material_preset(const std::string& name) {
  for (const MaterialPreset& p : material_presets())
    if (name == p.name) return &p;
  return nullptr;
}

int Scene::find(const std::string& name) const {
  for (size_t i = 0; i < objects.size(); ++i)
    if (objects[i].name == name) return static_cast<int>(i);
  return -1;
}

Scene parse_scene(const std::string& text, const fs::path& file) {
  const Checker c{file.string()};
  const json j = parse_json(text, file.string());
  const fs::path base = file.has_parent_path() ? file.parent_path() : fs::path(".");
  c.keys(j, "", {"integrator", "time_step", "gravity", "floor", "bounds", "contact", "self_collision", "objects", "goal",
                 "description", "planner", "render"});
  Scene s;
  s.file = file;
  if (j.contains("integrator")) {
    s.integrator = c.string(j["integrator"], "integrator");
    try {
      make_integrator(s.integrator);
    } catch (const InputError&) {
      std::string list;
      for (const std::string& n : integrator_names()) list += (list.empty() ? "\"" : ", \"") + n + "\"";
      c.fail("integrator", "must be one of " + list + ", got \"" + s.integrator + "\"");
    }
  }
  if (j.contains("time_step") && !(j["time_step"].is_string() && j["time_step"] == "auto")) {
    // A step the stages cannot honour is an error, never replaced: below 1e-6 s (the automatic
    // step's floor too) a frame would take millions of steps; above 1 s nothing stays resolved.
    s.time_step = c.positive(j["time_step"], "time_step");
    if (!(*s.time_step >= kMinTimeStep && *s.time_step <= kMaxTimeStep))
      c.fail("time_step", "must be in [" + format_number(kMinTimeStep) + ", " + format_number(kMaxTimeStep) +
                              "] s or \"auto\", got " + format_number(*s.time_step));
  }
  if (j.contains("gravity")) s.gravity = c.vec3(j["gravity"], "gravity");
  if (j.contains("floor")) {
    if (j["floor"].is_null() || (j["floor"].is_boolean() && !j["floor"].get<bool>())) s.floor.reset();
    else s.floor = c.number(j["floor"], "floor");
  }
  if (j.contains("bounds")) s.bounds = c.box(j["bounds"], "bounds");
  if (j.contains("contact")) {
    const json& k = j["contact"];
    c.keys(k, "contact", {"stiffness", "damping", "rest_overlap"});
    if (k.contains("stiffness")) s.contact_stiffness = c.non_negative(k["stiffness"], "contact.stiffness");
    if (k.contains("damping")) s.contact_damping = c.non_negative(k["damping"], "contact.damping");
    if (k.contains("rest_overlap")) s.rest_overlap = c.boolean(k["rest_overlap"], "contact.rest_overlap");
  }
  if (j.contains("self_collision")) s.self_collision = c.boolean(j["self_collision"], "self_collision");
  // Blocks of later stages, validated there (plan/, render/).
  for (const char* k : {"planner", "render"})
    if (j.contains(k) && !j[k].is_null()) {
      if (!j[k].is_object()) c.fail(k, "must be an object, got " + type_name(j[k]));
      (std::string(k) == "planner" ? s.planner : s.render) = j[k];
    }

  if (!j.contains("objects")) c.fail("objects", "missing (required: at least one object)");
  const json& objs = j["objects"];
  if (!objs.is_array()) c.fail("objects", "must be an array, got " + type_name(objs));
  if (objs.empty()) c.fail("objects", "must hold at least one object");
  for (size_t i = 0; i < objs.size(); ++i) {
    const std::string p = "objects[" + std::to_string(i) + "]";
    const json& o = objs[i];
    c.keys(o, p, {"name", "mesh", "role", "kind", "tets", "mesh_route", "simulation_mesh", "transform", "material", "gravity",
                  "velocity", "pinned", "color"});
    SceneObject ob;
    if (!o.contains("name")) c.fail(p + ".name", "missing (required)");
    ob.name = c.string(o["name"], p + ".name");
    if (ob.name.empty()) c.fail(p + ".name", "must not be empty");
    for (char ch : ob.name)
      if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-'))
        c.fail(p + ".name", "'" + ob.name + "' may only hold letters, digits, '_' and '-' (it names CSV columns and files)");
    if (s.find(ob.name) >= 0) c.fail(p + ".name", "duplicate object name '" + ob.name + "'");
    if (!o.contains("mesh")) c.fail(p + ".mesh", "missing (required)");
    const std::string mesh = c.string(o["mesh"], p + ".mesh");
    if (mesh.empty()) c.fail(p + ".mesh", "must not be empty");
    ob.mesh = fs::path(mesh).is_absolute() ? fs::path(mesh) : base / mesh;
    std::error_code ec;
    if (!fs::exists(ob.mesh, ec)) c.fail(p + ".mesh", "file " + ob.mesh.string() + " does not exist");
    if (fs::is_directory(ob.mesh, ec)) c.fail(p + ".mesh", ob.mesh.string() + " is a directory, not a mesh file");
    if (!fs::is_regular_file(ob.mesh, ec))
      c.fail(p + ".mesh", ob.mesh.string() + " is not a regular file (a device, a pipe or a socket)");
    if (o.contains("role")) {
      const std::string r = c.string(o["role"], p + ".role");
      if (r != "robot" && r != "obstacle") c.fail(p + ".role", "must be \"robot\" or \"obstacle\", got \"" + r + "\"");
      ob.robot = r == "robot";
    }
    if (o.contains("kind")) {
      const std::string k = c.string(o["kind"], p + ".kind");
      if (k != "deformable" && k != "rigid") c.fail(p + ".kind", "must be \"deformable\" or \"rigid\", got \"" + k + "\"");
      ob.rigid = k == "rigid";
    }
    if (o.contains("tets")) {
      const double t = c.number(o["tets"], p + ".tets");
      if (t != std::floor(t) || t < 10 || t > 100000) c.fail(p + ".tets", "must be an integer in [10, 100000], got " + num(t));
      ob.tets = static_cast<int>(t);
    }
    if (o.contains("mesh_route")) {
      ob.mesh_route = c.string(o["mesh_route"], p + ".mesh_route");
      const std::vector<std::string>& routes = meshing::mesh_route_names();
      if (std::find(routes.begin(), routes.end(), ob.mesh_route) == routes.end()) {
        std::string list;  // "a", "b", "c" or "d"
        for (size_t i = 0; i < routes.size(); ++i)
          list += (i == 0 ? "" : i + 1 == routes.size() ? " or " : ", ") + ("\"" + routes[i] + "\"");
        c.fail(p + ".mesh_route", "must be " + list + ", got \"" + ob.mesh_route + "\"");
      }
    }
    if (o.contains("simulation_mesh")) {
      ob.simulation_mesh = c.string(o["simulation_mesh"], p + ".simulation_mesh");
      if (ob.simulation_mesh != "auto" && ob.simulation_mesh != "tight" && ob.simulation_mesh != "convex_shells")
        c.fail(p + ".simulation_mesh", "must be \"auto\", \"tight\" or \"convex_shells\", got \"" + ob.simulation_mesh + "\"");
    }
    if (o.contains("transform")) {
      const json& t = o["transform"];
      const std::string q = p + ".transform";
      c.keys(t, q, {"scale", "rotate_deg", "translate"});
      if (t.contains("scale")) {
        if (t["scale"].is_array()) {
          ob.transform.scale = c.vec3(t["scale"], q + ".scale");
          for (int k = 0; k < 3; ++k)
            if (!(ob.transform.scale(k) > 0)) c.fail(q + ".scale[" + std::to_string(k) + "]", "must be > 0, got " + num(ob.transform.scale(k)));
        } else {
          ob.transform.scale.setConstant(c.positive(t["scale"], q + ".scale"));
        }
        for (int k = 0; k < 3; ++k)  // metres from any unit (1e-6: micrometres to metres), not overflow
          if (ob.transform.scale(k) > 1e6 || ob.transform.scale(k) < 1e-9)
            c.fail(q + ".scale", "must be in [1e-9, 1e6], got " + num(ob.transform.scale(k)));
      }
      if (t.contains("rotate_deg")) ob.transform.rotate_deg = c.vec3(t["rotate_deg"], q + ".rotate_deg");
      if (t.contains("translate")) {
        ob.transform.translate = c.vec3(t["translate"], q + ".translate");
        if (ob.transform.translate.cwiseAbs().maxCoeff() > 1e6)
          c.fail(q + ".translate", "must be within 1e6 m of the origin");
      }
    }
    if (o.contains("material")) {
      const json& m = o["material"];
      const std::string q = p + ".material";
      c.keys(m, q, {"preset", "density", "youngs_modulus", "k_distance", "k_volume", "damping", "volume_weighted",
                    "mass_scaling", "deformation_damping"});
      if (m.contains("preset")) {  // first: the explicit keys below override it
        ob.preset = c.string(m["preset"], q + ".preset");
        const MaterialPreset* preset = find_material_preset(ob.preset);
        if (!preset) {
          std::string list;
          for (const MaterialPreset& x : material_presets()) list += (list.empty() ? "\"" : ", \"") + std::string(x.name) + "\"";
          c.fail(q + ".preset", "unknown preset \"" + ob.preset + "\" (known: " + list + ")");
        }
        ob.density = preset->density;
        ob.youngs_modulus = preset->youngs_modulus;
      }
      if (m.contains("density")) ob.density = c.positive(m["density"], q + ".density");
      if (m.contains("youngs_modulus")) ob.youngs_modulus = c.positive(m["youngs_modulus"], q + ".youngs_modulus");
      if (m.contains("k_distance")) ob.k_distance = c.positive(m["k_distance"], q + ".k_distance");
      if (m.contains("k_volume")) ob.k_volume = c.positive(m["k_volume"], q + ".k_volume");
      if (m.contains("damping")) ob.damping = c.non_negative(m["damping"], q + ".damping");
      if (m.contains("volume_weighted")) ob.volume_weighted = c.boolean(m["volume_weighted"], q + ".volume_weighted");
      if (m.contains("deformation_damping"))
        ob.deformation_damping = c.non_negative(m["deformation_damping"], q + ".deformation_damping");
      if (m.contains("mass_scaling")) {
        ob.mass_scaling = c.non_negative(m["mass_scaling"], q + ".mass_scaling");
        if (ob.mass_scaling != 0 && ob.mass_scaling < 1)
          c.fail(q + ".mass_scaling", "must be 0 (off) or >= 1, got " + num(ob.mass_scaling));
      }
    }
    if (o.contains("gravity")) ob.gravity = c.boolean(o["gravity"], p + ".gravity");
    if (o.contains("color")) ob.color = parse_color(c, o["color"], p + ".color");
    if (o.contains("velocity")) ob.velocity = c.vec3(o["velocity"], p + ".velocity");
    if (o.contains("pinned")) {
      const json& pins = o["pinned"];
      if (!pins.is_array()) c.fail(p + ".pinned", "must be an array, got " + type_name(pins));
      for (size_t k = 0; k < pins.size(); ++k) {
        const std::string q = p + ".pinned[" + std::to_string(k) + "]";
        const json& e = pins[k];
        c.keys(e, q, {"box", "near", "radius", "surface", "distance", "stiffness", "sag", "damping", "damping_ratio",
                      "carries_weight"});
        ScenePin pin;
        const int kinds = int(e.contains("box")) + int(e.contains("near")) + int(e.contains("surface"));
        if (kinds != 1)
          c.fail(q, kinds == 0 ? "missing the vertices to hold: one of \"box\", \"near\" (with \"radius\") or \"surface\" (with \"distance\")"
                               : "holds one of \"box\", \"near\" or \"surface\", not several");
        if (e.contains("radius") && !e.contains("near")) c.fail(q + ".radius", "only with \"near\"");
        if (e.contains("distance") && !e.contains("surface")) c.fail(q + ".distance", "only with \"surface\"");
        if (e.contains("box")) {
          pin.kind = ScenePin::Kind::box;
          pin.box = c.box(e["box"], q + ".box");
        } else if (e.contains("near")) {
          pin.kind = ScenePin::Kind::near;
          pin.point = c.vec3(e["near"], q + ".near");
          if (!e.contains("radius")) c.fail(q + ".radius", "missing (required with \"near\")");
          pin.radius = c.positive(e["radius"], q + ".radius");
        } else {
          pin.kind = ScenePin::Kind::surface;
          const std::string f = c.string(e["surface"], q + ".surface");
          if (f.empty()) c.fail(q + ".surface", "must not be empty");
          pin.surface = fs::path(f).is_absolute() ? fs::path(f) : base / f;
          std::error_code ec;
          if (!fs::is_regular_file(pin.surface, ec)) c.fail(q + ".surface", "file " + pin.surface.string() + " does not exist");
          if (!e.contains("distance")) c.fail(q + ".distance", "missing (required with \"surface\")");
          pin.distance = c.positive(e["distance"], q + ".distance");
        }
        if (e.contains("stiffness") && e.contains("sag"))
          c.fail(q + ".sag", "either \"stiffness\" (N/m per vertex) or \"sag\" (m), not both");
        if (e.contains("stiffness")) pin.stiffness = c.positive(e["stiffness"], q + ".stiffness");
        if (e.contains("sag")) pin.sag = c.positive(e["sag"], q + ".sag");
        if (e.contains("damping") && e.contains("damping_ratio"))
          c.fail(q + ".damping_ratio", "either \"damping\" (N·s/m per vertex) or \"damping_ratio\", not both");
        if (e.contains("damping")) {
          if (!pin.soft())
            c.fail(q + ".damping", "only for soft attachments (with \"stiffness\" or \"sag\"); a hard pin never moves");
          pin.damping = c.non_negative(e["damping"], q + ".damping");
        }
        if (e.contains("damping_ratio")) {
          if (!pin.soft())
            c.fail(q + ".damping_ratio", "only for soft attachments (with \"stiffness\" or \"sag\"); a hard pin never moves");
          pin.damping_ratio = c.non_negative(e["damping_ratio"], q + ".damping_ratio");
        }
        if (e.contains("carries_weight")) {
          pin.carries_weight = c.boolean(e["carries_weight"], q + ".carries_weight");
          if (pin.carries_weight && !pin.soft())
            c.fail(q + ".carries_weight",
                   "only for soft attachments (with \"stiffness\" or \"sag\"); a hard pin holds its vertices anyway");
        }
        ob.pinned.push_back(std::move(pin));
      }
      if (ob.rigid && !ob.pinned.empty()) c.fail(p + ".pinned", "a rigid object never moves: pins apply to deformable objects only");
    }
    s.objects.push_back(std::move(ob));
  }

  if (j.contains("goal") && !j["goal"].is_null()) {
    const json& g = j["goal"];
    c.keys(g, "goal", {"position", "tolerance", "object"});
    SceneGoal goal;
    if (!g.contains("position")) c.fail("goal.position", "missing (required in a goal)");
    goal.position = c.vec3(g["position"], "goal.position");
    if (g.contains("tolerance")) goal.tolerance = c.positive(g["tolerance"], "goal.tolerance");
    if (g.contains("object")) {
      goal.object = c.string(g["object"], "goal.object");
      if (s.find(goal.object) < 0) c.fail("goal.object", "no object named '" + goal.object + "'");
    } else {
      int robots = 0;
      for (const SceneObject& o : s.objects)
        if (o.robot) {
          ++robots;
          goal.object = o.name;
        }
      if (robots != 1)
        c.fail("goal.object", "missing: required when the scene has " + std::to_string(robots) + " robots instead of one");
    }
    s.goal = goal;
  }
  return s;
}

Scene load_scene(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw InputError(file.string() + ": scene file does not exist");
  std::string text;
  try {
    text = read_file_bytes(file);
  } catch (const InputError&) {
    throw InputError(file.string() + ": scene file cannot be read");
  }
  return parse_scene(text, file);
}

fs::path mesh_cache_dir() {
  if (const char* d = std::getenv("SQUEEZE_CACHE_DIR"); d && *d) return fs::path(d);
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return fs::path(d) / "squeeze";
  if (const char* d = std::getenv("HOME"); d && *d) return fs::path(d) / ".cache" / "squeeze";
  return {};
}

meshing::TetMesh object_tet_mesh(const fs::path& mesh, int tets, bool* cache_hit, Progress* progress,
                                 std::string* off_target, const std::string& route) {
  if (cache_hit) *cache_hit = false;
  if (off_target) off_target->clear();
  if (meshing::is_tet_format(mesh)) return meshing::load_tet_mesh(mesh);
  meshing::MeshOptions options;
  options.tetrahedralize.target_tets = tets;
  meshing::set_mesh_route(options, route);
  // The cache key: format version, the input's extension and bytes, every meshing option.
  const std::string bytes = read_file_bytes(mesh);
  std::ostringstream opt;
  opt << std::setprecision(17) << "squeeze-mesh-cache-v2|algorithm " << meshing::kMeshingAlgorithmVersion << "|" << mesh.extension().string() << '|'
      << options.decomposition.concavity << ',' << options.decomposition.max_hulls << ','
      << options.decomposition.max_hull_volume_ratio << ',' << options.decomposition.voxel_resolution << ','
      << options.decomposition.cut_samples << ',' << options.decomposition.flat_thickness << '|'
      << options.tets_per_hull << ',' << options.max_deviation << ',' << options.inner_deviation << ','
      << options.shells.facet_distance << ',' << options.shells.facet_distance_per_size << ','
      << options.shells.offset << ',' << options.shells.max_tets << ',' << options.shells.coverage_tolerance << ','
      << options.shells.min_dihedral << ',' << options.shells.sliver_bound << '|' << options.tetrahedralize.target_tets << ','
      << options.tetrahedralize.refine_dihedral << ',' << options.tetrahedralize.sliver_bound << ','
      << options.tetrahedralize.max_tets << ',' << options.tetrahedralize.seed << '|'
      // The routes for inputs that are not closed parts: a changed default re-meshes.
      << options.winding << ',' << options.winding_facet_distance << ',' << options.winding_dilation << ','
      << options.winding_mesh.max_tets << ',' << options.winding_mesh.min_dihedral << ','
      << options.winding_mesh.sliver_bound << ',' << options.winding_mesh.optimize_seconds << ',' << options.wrap
      << ',' << options.wrap_alpha << ',' << options.wrap_offset << ',' << options.sheet_thickness << ','
      << options.shells_fallback << ',' << options.winding_mesh.facet_size << ',' << options.winding_surface_dilation << ','
      << options.winding_mesh.cover_tolerance << (options.shells_only ? ",shells_only" : "") << (options.split_skinny ? "" : ",no_skinny_split") << (options.thin_parts_as_prisms ? "" : ",no_thin_prisms") << (options.slab_first_for_wide_holes ? "" : ",solid_first") << '|' << bytes.size() << '|';
  Hash128 h;
  h.add(opt.str());
  h.add(bytes);
  const std::string key = h.hex();
  const fs::path dir = mesh_cache_dir();
  const fs::path cached = dir.empty() ? fs::path() : dir / "meshes" / (key + ".mesh");
  const fs::path record = dir.empty() ? fs::path() : dir / "meshes" / (key + ".json");
  std::error_code ec;
  if (!cached.empty() && fs::is_regular_file(cached, ec)) {
    // An entry is used only when its record names the key it was made for and the checksum of the
    // mesh file's bytes matches: a damaged, truncated or swapped entry is meshed again.
    std::string problem;
    try {
      const nlohmann::json j = parse_json(read_file_bytes(record), record.string());
      Hash128 content;
      content.add(read_file_bytes(cached));
      if (!j.is_object() || j.value("format", "") != "squeeze-mesh-cache" || j.value("key", "") != key)
        problem = "its record " + record.filename().string() + " is not that of this key";
      else if (j.value("checksum", "") != content.hex())
        problem = "its checksum does not match its content";
      else {
        meshing::TetMesh m = meshing::load_tet_mesh(cached);
        if (cache_hit) *cache_hit = true;
        if (off_target) *off_target = j.value("off_target", "");
        return m;
      }
    } catch (const std::exception& e) {  // InputError, or a record of the wrong shape
      problem = std::string("it cannot be read: ") + e.what();
    }
    spdlog::warn("{}: the cached mesh of {} is not used, {}: meshing it again", cached.string(), mesh.string(), problem);
  }
  if (progress) progress->stage("meshing " + mesh.filename().string());
  meshing::MeshResult r = meshing::mesh_file(mesh, options, nullptr);
  if (progress) progress->finish();
  if (off_target) *off_target = r.target_exceeded_because;
  if (!cached.empty()) {
    fs::create_directories(cached.parent_path(), ec);
    try {
      if (!ec) {
        meshing::save_tet_mesh(cached, r.tets);  // atomic: through a temporary file renamed at the end
        Hash128 content;
        content.add(read_file_bytes(cached));
        nlohmann::json j = {{"format", "squeeze-mesh-cache"},
                            {"version", 2},
                            {"key", key},
                            {"checksum", content.hex()},
                            {"source", fs::absolute(mesh).lexically_normal().string()},
                            {"target_tets", tets},
                            {"tets", r.tets.T.rows()},
                            {"off_target", r.target_exceeded_because}};
        write_atomically(record, [&](const fs::path& tmp) {  // after the mesh: a record vouches for a complete file
          std::ofstream o(tmp);
          o << j.dump(2) << '\n';
          if (!o) throw InputError(record.string() + ": write failed");
        });
      }
    } catch (const InputError&) {
      // An unwritable cache only costs time.
    }
  }
  return std::move(r.tets);
}

std::vector<int> pinned_vertices(const Body& body, const ScenePin& pin) {
  std::vector<int> held;
  const RowMatrixX3d& X = body.rest;
  const int n = body.vertices();
  if (pin.kind == ScenePin::Kind::box) {
    for (int v = 0; v < n; ++v)
      if (pin.box.contains(X.row(v).transpose())) held.push_back(v);
    return held;
  }
  if (pin.kind == ScenePin::Kind::near) {
    for (int v = 0; v < n; ++v)
      if ((X.row(v).transpose() - pin.point).norm() <= pin.radius) held.push_back(v);
    return held;
  }
  // Surface: the triangles near the object, against a grid of its vertices (cells of at least
  // the distance and the mean edge length: a triangle visits few cells, a cell holds few vertices).
  const meshing::SurfaceMesh S = meshing::load_surface(pin.surface);
  const double d = pin.distance;
  const double cell = std::max(d, body.mean_edge_length() > 0 ? body.mean_edge_length() : d);
  const Eigen::Vector3d lo = X.colwise().minCoeff().transpose(), hi = X.colwise().maxCoeff().transpose();
  const Eigen::Vector3i dims = (((hi - lo) / cell).array().floor().cast<int>() + 1).matrix();
  auto cell_of = [&](const Eigen::Vector3d& p) {
    return ((p - lo) / cell).array().floor().cast<int>().max(0).min(dims.array() - 1).matrix().eval();
  };
  auto code = [&](const Eigen::Vector3i& c) { return (static_cast<long long>(c.z()) * dims.y() + c.y()) * dims.x() + c.x(); };
  std::vector<std::pair<long long, int>> cells(static_cast<size_t>(n));  // (cell, vertex), sorted
  for (int v = 0; v < n; ++v) cells[v] = {code(cell_of(X.row(v).transpose())), v};
  std::sort(cells.begin(), cells.end());
  std::vector<char> in(static_cast<size_t>(n), 0);
  const Eigen::AlignedBox3d object(lo.array() - d, hi.array() + d);
  for (Eigen::Index f = 0; f < S.F.rows(); ++f) {
    const Eigen::Vector3d a = S.V.row(S.F(f, 0)).transpose(), b = S.V.row(S.F(f, 1)).transpose(),
                          c = S.V.row(S.F(f, 2)).transpose();
    Eigen::AlignedBox3d tb(a);
    tb.extend(b).extend(c);
    tb.min().array() -= d;
    tb.max().array() += d;
    if (!tb.intersects(object)) continue;
    const Eigen::Vector3i c0 = cell_of(tb.min()), c1 = cell_of(tb.max());
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x) {
          const long long k = code(Eigen::Vector3i(x, y, z));
          for (auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(k, -1)); it != cells.end() && it->first == k; ++it) {
            const int v = it->second;
            if (in[v]) continue;
            const Eigen::Vector3d p = X.row(v).transpose();
            if (tb.contains(p) && meshing::point_triangle_distance(p, a, b, c) <= d) in[v] = 1;
          }
        }
  }
  for (int v = 0; v < n; ++v)
    if (in[v]) held.push_back(v);
  return held;
}

// γ_max / ω_max allowed to the default stiffness-proportional damping: a damped step of at least
// a third of the undamped one (F − 1/F with F = 3).
constexpr double kDampingStepCost = 8.0 / 3.0;

namespace {

// The Verlet stability bound, vertex by vertex (see stable_time_step): the step and the vertex
// that sets it, with its terms.
struct VerletBound {
  double h = 1e-3;      // s, at most 1 ms
  int body = -1, vertex = -1;
  double w2e = 0, w2c = 0, w2a = 0, w2 = 0, gamma = 0;  // ω² terms (1/s²) and damping rate (1/s) there
};

VerletBound verlet_bound(const World& world) {
  const WorldOptions& o = world.options();
  VerletBound v;
  for (int b = 0; b < world.bodies(); ++b) {
    const Body& B = world.body(b);
    const int r0 = world.first_state_row(b);
    if (B.rigid || r0 < 0) continue;
    Eigen::VectorXd w2e, ge;
    vertex_frequency_bounds(B, world.masses().segment(r0, B.vertices()), w2e, &ge);
    for (int i = 0; i < B.vertices(); ++i) {
      const double m = world.masses()(r0 + i), cs = world.contact_scale(r0 + i);
      if (!(m > 0)) continue;
      const double w2c = cs * o.contact_stiffness / m;
      double w2 = w2e(i) + w2c, gamma = ge(i) + cs * o.contact_damping / m;
      const double ka = world.attachment_stiffness(r0 + i), ca = world.attachment_damping(r0 + i);
      const double w2a = ka / m;
      if (ka > 0 || ca > 0) w2 += w2a, gamma += ca / m;
      const double d = gamma + std::sqrt(gamma * gamma + 4 * w2);
      if (d > 0 && 2.0 / d < v.h) v = {2.0 / d, b, i, w2e(i), w2c, w2a, w2, gamma};
    }
  }
  return v;
}

}  // namespace

double stable_time_step(const World& world) { return verlet_bound(world).h; }

TimeStepChoice auto_time_step(const World& world, const Scene& scene) {
  TimeStepChoice c;
  if (scene.integrator == "implicit") {
    c.h = kImplicitFrameInterval;
    c.term = "frame interval";
    c.detail = "1/30 s";
    for (int b = 0; b < world.bodies(); ++b) {
      const Body& B = world.body(b);
      const double v = static_cast<size_t>(b) < scene.objects.size() ? scene.objects[b].velocity.norm() : 0.0;
      if (B.rigid || !(v > 0) || !(B.mean_edge_length() > 0)) continue;
      const double hb = 0.5 * B.mean_edge_length() / v;
      if (hb < c.h) {
        c.h = hb;
        c.object = b;
        c.term = "initial speed";
        c.detail = format_g3(v) + " m/s over half its mean edge length " + format_g3(0.5 * B.mean_edge_length()) + " m";
      }
    }
    return c;
  }
  // Verlet: the stability bound, vertex by vertex (stable_time_step), and the tightest term.
  const VerletBound v = verlet_bound(world);
  c.h = v.h;
  if (v.body < 0) {
    c.term = "cap";
    c.detail = "1 ms at most";
    return c;
  }
  c.object = v.body;
  // The stiffest of elasticity, contact and a soft attachment at this vertex; "and damping"
  // where the damping rate exceeds the frequency (2 / h = γ + sqrt(γ² + 4ω²) is then well above 2ω).
  const char* stiffest = v.w2e >= v.w2c && v.w2e >= v.w2a ? "elastic" : v.w2c >= v.w2a ? "contact" : "attachment";
  c.term = std::string(stiffest) + (v.gamma > std::sqrt(v.w2) ? " and damping" : "");
  c.detail = "vertex " + std::to_string(v.vertex) + ": ω " + format_g3(std::sqrt(v.w2)) + " rad/s (elastic " +
             format_g3(std::sqrt(v.w2e)) + ", contact " + format_g3(std::sqrt(v.w2c)) +
             (v.w2a > 0 ? ", attachment " + format_g3(std::sqrt(v.w2a)) : std::string()) + "), damping rate γ " +
             format_g3(v.gamma) + " 1/s";
  return c;
}

std::string TimeStepChoice::describe(const Scene& scene) const {
  std::string s = format_g3(h) + " s (" + scene.integrator + ": ";
  if (term == "given") return s + "time_step of the scene)";
  if (object >= 0 && static_cast<size_t>(object) < scene.objects.size())
    s += term + (term == "initial speed" ? " of '" : " stability of '") + scene.objects[object].name + "', ";
  else
    s += term + ", ";
  return s + detail + ")";
}

namespace {

// Whether deformable object o, meshed from a surface, is simulated on its convex shells with
// `tight` (the mesh of its mesh_route) embedded (SceneObject::simulation_mesh): asked for, or
// "auto" and `tight` has more than 35 % more tetrahedra than `tets` (the bound of its deviation
// needs them: `tets` is then the number of degrees of freedom the object moves with).
bool simulate_on_shells(const SceneObject& o, const meshing::TetMesh& tight) {
  if (o.rigid || meshing::is_tet_format(o.mesh)) return false;
  if (o.simulation_mesh == "convex_shells") return true;
  return o.simulation_mesh == "auto" && static_cast<double>(tight.T.rows()) > 1.35 * o.tets;
}

}  // namespace

std::string simulation_mesh_route(const SceneObject& o) {
  if (o.rigid || meshing::is_tet_format(o.mesh) || o.simulation_mesh == "tight") return o.mesh_route;
  if (o.simulation_mesh == "convex_shells") return "all_convex_shells";
  const meshing::TetMesh tight = object_tet_mesh(o.mesh, o.tets, nullptr, nullptr, nullptr, o.mesh_route);  // (cached)
  return simulate_on_shells(o, tight) ? "all_convex_shells" : o.mesh_route;
}

SceneWorld build_scene(const Scene& scene, Progress* progress) {
  const std::string file = scene.file.string();
  // What building the scene finds worth a warning (SceneWorld::warnings): logged at once, as
  // "FILE: objects[i].KEY: …", and kept without the file's name.
  std::vector<std::string> warnings;
  auto warn = [&](const std::string& line) {
    spdlog::warn("{}: {}", file, line);
    warnings.push_back(line);
  };
  WorldOptions wo;
  wo.gravity = scene.gravity;
  wo.floor = scene.floor.has_value();
  wo.floor_height = scene.floor.value_or(0.0);
  wo.contact_stiffness = scene.contact_stiffness;
  wo.contact_damping = scene.contact_damping;
  wo.self_collision = scene.self_collision;
  wo.rest_overlap = scene.rest_overlap;
  wo.cap_contact_stiffness = true;  // contact never sets the stable step
  wo.h = scene.time_step.value_or(1e-3);
  wo.integrator = scene.integrator;
  World world(wo);
  std::vector<meshing::TetMesh> meshes;
  std::vector<double> rest_volume;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    const std::string p = "objects[" + std::to_string(i) + "]";
    meshing::TetMesh m;
    std::string off_target;
    try {
      m = object_tet_mesh(o.mesh, o.tets, nullptr, progress, &off_target, o.mesh_route);
    } catch (const InputError& e) {
      throw InputError(file + ": " + p + ".mesh: " + e.what());
    }
    if (o.simulation_mesh == "convex_shells" && meshing::is_tet_format(o.mesh))
      throw InputError(file + ": " + p + ".simulation_mesh: \"convex_shells\" needs a surface to mesh; " +
                       o.mesh.filename().string() + " is a tetrahedral mesh (used as it is)");
    if (o.simulation_mesh == "convex_shells" && o.rigid)
      warn(p + ".simulation_mesh: '" + o.name + "' is rigid (it never deforms): it collides with its mesh as it is");
    // A deformable object simulated on a cage (simulation_mesh): its convex shells at `tets`, the
    // mesh above (tight to its surface) embedded for contact and volume.
    std::optional<meshing::TetMesh> embedded;  // the mesh above in world coordinates (World::embed)
    double embedded_volume = 0;                // m³
    if (simulate_on_shells(o, m)) {
      meshing::TetMesh shells;
      try {
        shells = object_tet_mesh(o.mesh, o.tets, nullptr, progress, &off_target, "all_convex_shells");
      } catch (const InputError& e) {
        throw InputError(file + ": " + p + ".mesh: " + e.what());
      }
      embedded.emplace();
      embedded->V.resize(m.V.rows(), 3);
      const Eigen::Affine3d A = o.transform.affine();
      for (Eigen::Index i = 0; i < m.V.rows(); ++i) embedded->V.row(i) = (A * Eigen::Vector3d(m.V.row(i).transpose())).transpose();
      embedded->T = m.T;
      embedded_volume = meshing::tet_volumes(*embedded).sum();
      spdlog::debug("{}: {}: simulated on its convex shells ({} tetrahedra), its {} tetrahedra embedded", file, p,
                    shells.T.rows(), m.T.rows());
      m = std::move(shells);
    }
    // The tet count is a target met within about ±35%. Far fewer than asked cannot honour the
    // request: an error; more than asked (the surface needs them): a warning that says so.
    if (!off_target.empty() && !meshing::is_tet_format(o.mesh)) {
      const long long n = m.T.rows();
      const std::string what = p + ".tets: " + std::to_string(o.tets) + " requested, but meshing " +
                               o.mesh.filename().string() + " gives " + std::to_string(n) + " tetrahedra (" + off_target + ")";
      if (n < 0.65 * o.tets) throw InputError(file + ": " + what + ": ask for at most about " + std::to_string(n));
      warn(what);
    }
    Material mat;
    mat.density = o.density;
    mat.k_distance = mat.k_volume = 1.0;  // placeholders until the rest data is known
    mat.volume_weighted = o.volume_weighted;
    std::optional<Body> body;
    try {
      body.emplace(m, mat, o.rigid, o.transform.affine());
    } catch (const InputError& e) {
      throw InputError(file + ": " + p + ".mesh: " + e.what());
    }
    const double V = body->total_volume();
    // On a cage, the object's mass is its own (the embedded mesh's volume), spread over the cage.
    const double V_object = embedded ? embedded_volume : V;
    if (embedded) mat.density = o.density * V_object / V;
    mat.k_distance = o.k_distance.value_or(o.youngs_modulus * V / std::max<Eigen::Index>(1, body->E.rows()));
    mat.k_volume = o.k_volume.value_or(3.0 * o.youngs_modulus * V / std::max(1, body->tets()));
    mat.mass_scaling = o.rigid ? 0.0 : o.mass_scaling;
    mat.deformation_damping = o.deformation_damping;
    const auto set_material = [&](const Material& m2) {
      try {
        body->set_material(m2);
      } catch (const InputError& e) {  // a stiffness or damping that overflows its products
        throw InputError(file + ": " + p + ".material: " + e.what() + " (k_distance " + num(m2.k_distance) +
                         ", k_volume " + num(m2.k_volume) + ", damping " + num(m2.damping_distance) + ")");
      }
    };
    set_material(mat);  // masses (mass scaling) from the final stiffnesses
    if (o.damping) {
      mat.damping_distance = mat.damping_volume = *o.damping;
    } else {
      // Damping time τ = min(5 ms, (8/3) / ω_max) (ω_max: the object's highest frequency bound):
      // stiffness-proportional damping gives the stiffest vertex a damping rate γ = τ ω_max²;
      // with γ <= (8/3) ω_max the step 2 / (γ + sqrt(γ² + 4ω²)) stays >= 1 / (3 ω_max), a third of
      // the undamped one (with 5 ms, fine meshes would get steps ∝ edge length²). The slow modes
      // that τ then damps too little are damped by deformation_damping.
      double w2max = 0;
      if (!o.rigid) {
        Eigen::VectorXd w2;
        vertex_frequency_bounds(*body, body->mass, w2);
        w2max = w2.maxCoeff();
      }
      const double tau = w2max > 0 ? std::min(5e-3, kDampingStepCost / std::sqrt(w2max)) : 5e-3;  // s
      mat.damping_distance = tau * mat.k_distance;
      mat.damping_volume = tau * mat.k_volume;
    }
    set_material(mat);
    meshing::TetMesh rest;
    rest.V = body->rest;
    rest.T = body->T;
    rest.label = m.label;
    meshes.push_back(std::move(rest));
    rest_volume.push_back(V_object);
    body->gravity = o.gravity;
    const int b = world.add_body(std::move(*body));
    if (embedded) {
      try {
        world.embed(b, *embedded);
      } catch (const InputError& e) {
        throw InputError(file + ": " + p + ".simulation_mesh: " + e.what());
      }
    }
  }
  // Pins and soft attachments: per object, on rest positions in world coordinates.
  std::vector<std::vector<int>> pin_counts(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    const int b = static_cast<int>(i), r0 = world.first_state_row(b);
    for (size_t k = 0; k < o.pinned.size(); ++k) {
      const ScenePin& pin = o.pinned[k];
      const std::string at = "objects[" + std::to_string(i) + "].pinned[" + std::to_string(k) + "]";
      const std::string key = at + "." + pin.key();
      std::vector<int> held;
      try {
        held = pinned_vertices(world.body(b), pin);
      } catch (const InputError& e) {
        throw InputError(file + ": " + key + ": " + e.what());
      }
      if (held.empty()) {
        std::string where;
        if (pin.kind == ScenePin::Kind::near)
          where = " (none within " + num(pin.radius) + " m of the point)";
        else if (pin.kind == ScenePin::Kind::surface)
          where = " (none within " + num(pin.distance) + " m of " + pin.surface.filename().string() + ")";
        throw InputError(file + ": " + key + ": holds no vertex of '" + o.name + "' at rest" + where);
      }
      const double g = world.gravity_of(b).norm();
      if (pin.sag && !(g > 0))
        throw InputError(file + ": " + at + ".sag: no gravity acts on '" + o.name +
                         "' (a sag is the stretch its weight causes); give \"stiffness\" instead");
      for (int v : held) {
        if (!pin.soft()) {
          world.pin_vertex(r0 + v);
          continue;
        }
        // sag: the vertex's weight stretches its spring by sag, k = m g / sag (its share of the
        // object's mass, so the attachment as a whole does not depend on the mesh's resolution).
        const double m = world.masses()(r0 + v);
        const double stiffness = pin.stiffness ? *pin.stiffness : m * g / *pin.sag;
        const double damping = pin.damping_ratio ? 2.0 * *pin.damping_ratio * std::sqrt(stiffness * m) : pin.damping;
        world.attach(r0 + v, stiffness, damping, pin.carries_weight);
      }
      pin_counts[i].push_back(static_cast<int>(held.size()));
    }
  }
  TimeStepChoice choice;
  if (scene.time_step) {
    choice.h = *scene.time_step;
    choice.term = "given";
  } else {
    choice = auto_time_step(world, scene);
  }
  const double h = choice.h;
  if (!scene.time_step && h < kMinTimeStep)
    throw InputError(file + ": time_step: the stable step of these meshes is only " + num(h) +
                     " s (tiny or flat tetrahedra, or very stiff materials): set time_step, another tets count, or a "
                     "tet mesh of better quality");
  world.set_time_step(h);
  world.prepare();
  SceneWorld sw(scene, std::move(world));
  sw.warnings = std::move(warnings);
  sw.time_step_choice = choice;
  sw.meshes = std::move(meshes);
  sw.rest_volume = std::move(rest_volume);
  sw.pin_counts = std::move(pin_counts);
  if (scene.bounds) {
    sw.bounds = *scene.bounds;
  } else {
    Eigen::AlignedBox3d box;
    for (const meshing::TetMesh& m : sw.meshes)
      for (Eigen::Index v = 0; v < m.V.rows(); ++v) box.extend(Eigen::Vector3d(m.V.row(v).transpose()));
    if (scene.floor && *scene.floor < box.max().y()) box.extend(Eigen::Vector3d(box.min().x(), *scene.floor, box.min().z()));
    const double margin = 0.5 * box.sizes().maxCoeff();
    box.min().array() -= margin;
    box.max().array() += margin;
    if (scene.floor && *scene.floor < box.max().y()) box.min().y() = std::max(box.min().y(), *scene.floor);
    sw.bounds = box;
  }
  ++g_scene_builds;
  return sw;
}

State SceneWorld::initial_state() const {
  State s = world.initial_state();
  for (int b = 0; b < world.bodies(); ++b) {
    const int r0 = world.first_state_row(b);
    if (r0 < 0) continue;
    for (int v = 0; v < world.body(b).vertices(); ++v)
      if (!world.pinned(r0 + v)) s.v.row(r0 + v) = scene.objects[b].velocity.transpose();
  }
  return s;
}

void SceneWorld::set_time_step(double step) {
  if (!(step > 0) || !std::isfinite(step)) throw InputError(scene.file.string() + ": time_step: must be > 0");
  world.set_time_step(step);
}


RowMatrixX3d SceneWorld::positions(const State& s, int b) const {
  const int r0 = world.first_state_row(b);
  if (r0 < 0) return world.body(b).rest;
  return s.x.middleRows(r0, world.body(b).vertices());
}

ObjectMetrics object_metrics(const SceneWorld& w, const State& s, int b) {
  ObjectMetrics m;
  const Body& B = w.world.body(b);
  const RowMatrixX3d X = w.positions(s, b);
  const int r0 = w.world.first_state_row(b);
  m.volume_ratio = r0 < 0 ? 1.0 : w.world.body_volume(s, b) / w.rest_volume[b];
  const double M = B.mass.sum();
  m.com = M > 0 ? Eigen::Vector3d((B.mass.transpose() * X).transpose() / M)
                : Eigen::Vector3d(X.colwise().mean().transpose());
  m.aabb.setEmpty();
  for (Eigen::Index v = 0; v < X.rows(); ++v) m.aabb.extend(Eigen::Vector3d(X.row(v).transpose()));
  if (r0 >= 0)
    for (int v = 0; v < B.vertices(); ++v) m.kinetic_energy += 0.5 * B.mass(v) * s.v.row(r0 + v).squaredNorm();
  return m;
}

}  // namespace squeeze::fem
