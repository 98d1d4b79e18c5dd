#include "squeeze/fem/scene.h"

#include "squeeze/fem/constraints.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/mesh_pipeline.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::fem {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Checker = JsonChecker;

std::string type_name(const json& j) { return json_type_name(j); }
std::string num(double x) { return format_number(x); }

namespace {

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

int Scene::find(const std::string& name) const {
  for (size_t i = 0; i < objects.size(); ++i)
    if (objects[i].name == name) return static_cast<int>(i);
  return -1;
}

Scene parse_scene(const std::string& text, const fs::path& file) {
  const Checker c{file.string()};
  const json j = parse_json(text, file.string());
  const fs::path base = file.has_parent_path() ? file.parent_path() : fs::path(".");
  c.keys(j, "", {"time_step", "gravity", "floor", "bounds", "contact", "self_collision", "objects", "goal",
                 "description", "planner", "render"});
  Scene s;
  s.file = file;
  if (j.contains("time_step") && !(j["time_step"].is_string() && j["time_step"] == "auto"))
    s.time_step = c.positive(j["time_step"], "time_step");
  if (j.contains("gravity")) s.gravity = c.vec3(j["gravity"], "gravity");
  if (j.contains("floor")) {
    if (j["floor"].is_null() || (j["floor"].is_boolean() && !j["floor"].get<bool>())) s.floor.reset();
    else s.floor = c.number(j["floor"], "floor");
  }
  if (j.contains("bounds")) s.bounds = c.box(j["bounds"], "bounds");
  if (j.contains("contact")) {
    const json& k = j["contact"];
    c.keys(k, "contact", {"stiffness", "damping"});
    if (k.contains("stiffness")) s.contact_stiffness = c.non_negative(k["stiffness"], "contact.stiffness");
    if (k.contains("damping")) s.contact_damping = c.non_negative(k["damping"], "contact.damping");
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
    c.keys(o, p, {"name", "mesh", "role", "kind", "tets", "transform", "material", "gravity", "velocity", "pinned"});
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
    if (!fs::is_regular_file(ob.mesh, ec)) c.fail(p + ".mesh", "file " + ob.mesh.string() + " does not exist");
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
      }
      if (t.contains("rotate_deg")) ob.transform.rotate_deg = c.vec3(t["rotate_deg"], q + ".rotate_deg");
      if (t.contains("translate")) ob.transform.translate = c.vec3(t["translate"], q + ".translate");
    }
    if (o.contains("material")) {
      const json& m = o["material"];
      const std::string q = p + ".material";
      c.keys(m, q, {"density", "youngs_modulus", "k_distance", "k_volume", "damping", "volume_weighted", "mass_scaling",
                    "deformation_damping"});
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
    if (o.contains("velocity")) ob.velocity = c.vec3(o["velocity"], p + ".velocity");
    if (o.contains("pinned")) {
      const json& pins = o["pinned"];
      if (!pins.is_array()) c.fail(p + ".pinned", "must be an array, got " + type_name(pins));
      for (size_t k = 0; k < pins.size(); ++k) {
        const std::string q = p + ".pinned[" + std::to_string(k) + "]";
        c.keys(pins[k], q, {"box"});
        if (!pins[k].contains("box")) c.fail(q + ".box", "missing (required)");
        ob.pinned.push_back(c.box(pins[k]["box"], q + ".box"));
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

meshing::TetMesh object_tet_mesh(const fs::path& mesh, int tets, bool* cache_hit, Progress* progress) {
  if (cache_hit) *cache_hit = false;
  if (meshing::is_tet_format(mesh)) return meshing::load_tet_mesh(mesh);
  meshing::MeshOptions options;
  options.tetrahedralize.target_tets = tets;
  // The cache key: format version, the input's extension and bytes, every meshing option.
  const std::string bytes = read_file_bytes(mesh);
  std::ostringstream opt;
  opt << std::setprecision(17) << "squeeze-mesh-cache-v1|algorithm " << meshing::kMeshingAlgorithmVersion << "|" << mesh.extension().string() << '|'
      << options.decomposition.concavity << ',' << options.decomposition.max_hulls << ','
      << options.decomposition.max_hull_volume_ratio << ',' << options.decomposition.voxel_resolution << ','
      << options.decomposition.cut_samples << ',' << options.decomposition.flat_thickness << '|'
      << options.tets_per_hull << ',' << options.max_deviation << ',' << options.inner_deviation << ','
      << options.solid_grid << '|' << options.tetrahedralize.target_tets << ','
      << options.tetrahedralize.refine_dihedral << ',' << options.tetrahedralize.sliver_bound << ','
      << options.tetrahedralize.max_tets << ',' << options.tetrahedralize.seed << '|' << bytes.size() << '|';
  Hash128 h;
  h.add(opt.str());
  h.add(bytes);
  const fs::path dir = mesh_cache_dir();
  const fs::path cached = dir.empty() ? fs::path() : dir / "meshes" / (h.hex() + ".mesh");
  std::error_code ec;
  if (!cached.empty() && fs::is_regular_file(cached, ec)) {
    try {
      meshing::TetMesh m = meshing::load_tet_mesh(cached);
      if (cache_hit) *cache_hit = true;
      return m;
    } catch (const InputError&) {
      // A damaged cache entry: mesh again and overwrite it.
    }
  }
  if (progress) progress->stage("meshing " + mesh.filename().string());
  meshing::MeshResult r = meshing::mesh_file(mesh, options, nullptr);
  if (progress) progress->finish();
  if (!cached.empty()) {
    fs::create_directories(cached.parent_path(), ec);
    try {
      if (!ec) meshing::save_tet_mesh(cached, r.tets);  // atomic: through a temporary file renamed at the end
    } catch (const InputError&) {
      // An unwritable cache only costs time.
    }
  }
  return std::move(r.tets);
}

// γ_max / ω_max allowed to the default stiffness-proportional damping: a damped step of at least
// a third of the undamped one (F − 1/F with F = 3).
constexpr double kDampingStepCost = 8.0 / 3.0;

double stable_time_step(const World& world) {
  const WorldOptions& o = world.options();
  double h = 1e-3;
  for (int b = 0; b < world.bodies(); ++b) {
    const Body& B = world.body(b);
    const int r0 = world.first_state_row(b);
    if (B.rigid || r0 < 0) continue;
    Eigen::VectorXd w2e, ge;
    vertex_frequency_bounds(B, world.masses().segment(r0, B.vertices()), w2e, &ge);
    for (int i = 0; i < B.vertices(); ++i) {
      const double m = world.masses()(r0 + i), cs = world.contact_scale(r0 + i);
      if (!(m > 0)) continue;
      const double w2 = w2e(i) + cs * o.contact_stiffness / m, gamma = ge(i) + cs * o.contact_damping / m;
      const double d = gamma + std::sqrt(gamma * gamma + 4 * w2);
      if (d > 0) h = std::min(h, 2.0 / d);
    }
  }
  return h;
}

SceneWorld build_scene(const Scene& scene, Progress* progress) {
  const std::string file = scene.file.string();
  WorldOptions wo;
  wo.gravity = scene.gravity;
  wo.floor = scene.floor.has_value();
  wo.floor_height = scene.floor.value_or(0.0);
  wo.contact_stiffness = scene.contact_stiffness;
  wo.contact_damping = scene.contact_damping;
  wo.self_collision = scene.self_collision;
  wo.cap_contact_stiffness = true;  // contact never sets the stable step
  wo.h = scene.time_step.value_or(1e-3);
  World world(wo);
  std::vector<meshing::TetMesh> meshes;
  std::vector<double> rest_volume;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    const std::string p = "objects[" + std::to_string(i) + "]";
    meshing::TetMesh m;
    try {
      m = object_tet_mesh(o.mesh, o.tets, nullptr, progress);
    } catch (const InputError& e) {
      throw InputError(file + ": " + p + ".mesh: " + e.what());
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
    mat.k_distance = o.k_distance.value_or(o.youngs_modulus * V / std::max<Eigen::Index>(1, body->E.rows()));
    mat.k_volume = o.k_volume.value_or(3.0 * o.youngs_modulus * V / std::max(1, body->tets()));
    mat.mass_scaling = o.rigid ? 0.0 : o.mass_scaling;
    mat.deformation_damping = o.deformation_damping;
    body->set_material(mat);  // masses (mass scaling) from the final stiffnesses
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
    body->set_material(mat);
    meshing::TetMesh rest;
    rest.V = body->rest;
    rest.T = body->T;
    rest.label = m.label;
    meshes.push_back(std::move(rest));
    rest_volume.push_back(V);
    body->gravity = o.gravity;
    world.add_body(std::move(*body));
  }
  // Pins: per object, on rest positions in world coordinates.
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    const int b = static_cast<int>(i), r0 = world.first_state_row(b);
    for (size_t k = 0; k < o.pinned.size(); ++k) {
      int n = 0;
      for (int v = 0; v < world.body(b).vertices(); ++v)
        if (o.pinned[k].contains(world.body(b).rest.row(v).transpose())) {
          world.pin_vertex(r0 + v);
          ++n;
        }
      if (n == 0)
        throw InputError(file + ": objects[" + std::to_string(i) + "].pinned[" + std::to_string(k) +
                         "].box: holds no vertex of '" + o.name + "' at rest");
    }
  }
  const double h = scene.time_step ? *scene.time_step : stable_time_step(world);
  if (!scene.time_step && h < 1e-6)
    throw InputError(file + ": time_step: the stable step of these meshes is only " + num(h) +
                     " s (tiny or flat tetrahedra, or very stiff materials): set time_step, another tets count, or a "
                     "tet mesh of better quality");
  world.set_time_step(h);
  world.prepare();
  SceneWorld sw(scene, std::move(world));
  sw.meshes = std::move(meshes);
  sw.rest_volume = std::move(rest_volume);
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
