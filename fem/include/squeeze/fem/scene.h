// squeeze::fem — JSON scenes (issue 5): parsing and validation, meshing with a cache, building
// a World, per-frame metrics. The format is documented key by key in scenes/README.md.
//
//   Scene s = load_scene("scenes/cube_drop.json");        // parse + validate (no meshing)
//   SceneWorld w = build_scene(s, &progress);            // mesh (cached), bodies, pins
//   State st = w.initial_state();
//   w.step(st);                                          // per-object gravity flags applied
//   SceneWorld copy = w;                                 // cheap: shares the rest data
//
// Errors: every problem with the scene is an InputError with one line
// "SCENE_FILE: KEY.PATH: problem", e.g. "cube.json: objects[2].material.k_volume: must be > 0".
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string>
#include <vector>

#include "squeeze/fem/body.h"
#include "squeeze/fem/world.h"
#include "squeeze/meshing/tet_mesh.h"

namespace squeeze {
class Progress;
}

namespace squeeze::fem {

/// Placement of an object's mesh: world = translate + R · (scale ∘ v), with R = Rz·Ry·Rx of
/// rotate_deg (degrees about the fixed x, then y, then z axis).
struct SceneTransform {
  Eigen::Vector3d scale{1, 1, 1};      // per axis, > 0
  Eigen::Vector3d rotate_deg{0, 0, 0};  // degrees
  Eigen::Vector3d translate{0, 0, 0};   // m
  Eigen::Affine3d affine() const;
};

/// One entry of objects[].pinned: which rest vertices it holds, and how. The vertices are those
/// whose rest position (after the object's transform, m) lies
///  * box:      in the world box `box`;
///  * near:     within `radius` of the point `point`;
///  * surface:  within `distance` of the triangle mesh in the file `surface` (any format
///              meshing::load_surface reads, in the scene's world coordinates, m).
/// Without stiffness they are pinned (never move); with one, each is held by a zero-length spring
/// of that stiffness (N/m) and damping (N·s/m) to its rest position (World::attach).
struct ScenePin {
  enum class Kind { box, near, surface };
  Kind kind = Kind::box;
  Eigen::AlignedBox3d box;             // box: m
  Eigen::Vector3d point{0, 0, 0};      // near: m
  double radius = 0;                   // near: m, > 0
  std::filesystem::path surface;       // surface: the mesh file (absolute: resolved against the scene's folder)
  double distance = 0;                 // surface: m, > 0
  std::optional<double> stiffness;     // N/m per vertex, > 0; empty (and no sag): a hard pin
  std::optional<double> sag;           // m, > 0, instead of stiffness: each vertex's spring is m_i |g| / sag
                                       // (its weight would stretch it by sag), so the whole attachment
                                       // holds the same whatever the mesh's resolution
  double damping = 0;                  // N·s/m per vertex, >= 0 (soft attachments only)
  std::optional<double> damping_ratio; // >= 0, instead of damping: c_i = 2 ζ sqrt(k_i m_i) (1: critical)
  bool carries_weight = false;         // soft attachments only: the spring carries its vertices' weight
                                       // at rest (World::attach carry_weight), so they start in equilibrium
  /// The key naming the selection in messages: "box", "near" or "surface".
  const char* key() const;
  /// A soft attachment (stiffness or sag), not a hard pin.
  bool soft() const { return stiffness.has_value() || sag.has_value(); }
};

/// A named material of objects[].material.preset: measured values of a tissue or material, with
/// where they come from (scenes/README.md has the table and the sources).
struct MaterialPreset {
  const char* name;
  double youngs_modulus;  // Pa
  double density;         // kg/m³
  const char* source;     // one line: measurement, range, citation
};
/// Every preset, in the order of the documentation ("liver", "lung", "heart", "fat", "rubber").
const std::vector<MaterialPreset>& material_presets();
/// The preset called `name`, or null.
const MaterialPreset* find_material_preset(const std::string& name);

/// One object of a scene, defaults filled in. Optional values left empty are derived from the
/// mesh when the world is built (see scenes/README.md for the formulas).
struct SceneObject {
  std::string name;                       // required, unique
  std::filesystem::path mesh;             // required; absolute (resolved against the scene's folder)
  bool robot = false;                     // role: "robot" | "obstacle" (default)
  bool rigid = false;                     // kind: "rigid" | "deformable" (default)
  int tets = 500;                         // meshing target (ignored when `mesh` is a tet mesh)
  std::string mesh_route = "auto";        // inputs that are not closed parts (welded, non-manifold or
                                          // open segments): "auto" (meshing version 11: their
                                          // winding-number solid's boundary), "convex_shells",
                                          // "winding_number" (Mesh_3 as it is) or "alpha_wrap"
                                          // (meshing::mesh_route_names, set_mesh_route)
  std::string simulation_mesh = "auto";   // deformable objects meshed from a surface: "tight" (simulate
                                          // on the mesh of mesh_route), "convex_shells" (simulate on
                                          // the convex shells at `tets`, few degrees of freedom, with the
                                          // mesh of mesh_route embedded for contact and volume:
                                          // World::embed) or "auto" (convex_shells where the mesh of
                                          // mesh_route has over 1.35 × tets tetrahedra, else tight)
  SceneTransform transform;
  std::string preset;                     // material.preset ("" if none): it set density and youngs_modulus
  double density = 1000.0;                // kg/m³ (material.density, else the preset's)
  double youngs_modulus = 1e5;            // Pa, only used to derive the default stiffnesses (else the preset's)
  std::optional<double> k_distance;       // J, of an edge of average volume share; default youngs_modulus · V / #edges
  std::optional<double> k_volume;         // J, of a tet of average volume; default 3 · youngs_modulus · V / #tets
  std::optional<double> damping;          // J·s, both damping terms; default τ · k, τ = min(5 ms, (8/3) / ω_max)
  bool volume_weighted = true;            // Material::volume_weighted
  double mass_scaling = 1.5;              // Material::mass_scaling (κ >= 1, or 0: off)
  double deformation_damping = 20.0;      // 1/s, Material::deformation_damping
  bool gravity = true;                    // false: gravity does not act on this object
  Eigen::Vector3d velocity{0, 0, 0};      // m/s, initial
  std::vector<ScenePin> pinned;           // pins and soft attachments of rest vertices
  std::optional<Eigen::Vector3d> color;   // render colour, linear [r, g, b] in [0, 1] (`color`: a triple
                                          // or a name of scene_color_names()); default: the OBJ's MTL
                                          // Kd, else a palette colour chosen by the object's name
};

/// The colour names `color` accepts (CSS colour names, lower case) with their [r, g, b] in [0, 1].
const std::vector<std::pair<std::string, Eigen::Vector3d>>& scene_color_names();

struct SceneGoal {
  Eigen::Vector3d position{0, 0, 0};  // m
  double tolerance = 0.05;            // m
  std::string object;                 // name of the object that must reach it (default: the robot)
};

/// A parsed, validated scene.
struct Scene {
  std::filesystem::path file;              // the scene file as given
  std::string integrator = "implicit";     // "implicit" (backward Euler, the default: stable at frame-sized
                                           // steps) or "verlet" (the paper's explicit step), integrator.h
  std::optional<double> time_step;         // s; default ("auto"): per integrator, see auto_time_step
  Eigen::Vector3d gravity{0, -9.81, 0};    // m/s²
  std::optional<double> floor = 0.0;       // m, height of the floor y >= floor; null: no floor
  std::optional<Eigen::AlignedBox3d> bounds;  // m; default: derived (see build_scene)
  double contact_stiffness = 1e5;          // N/m per penetrating vertex (objects and floor)
  double contact_damping = 10.0;           // N·s/m along the contact normal while penetrating
  bool rest_overlap = true;                // overlaps at rest are the contacts' rest state (WorldOptions::rest_overlap)
  bool self_collision = true;
  std::vector<SceneObject> objects;
  std::optional<SceneGoal> goal;
  // The `planner` and `render` blocks as written (null if absent); plan/ and render/ validate
  // them (NaN/Infinity literals appear as marked strings, see squeeze/common/json_check.h).
  nlohmann::json planner, render;

  /// Index of the object called `name`, or -1.
  int find(const std::string& name) const;
};

/// Reads and validates a scene file (JSON). Mesh paths are resolved relative to the scene's folder
/// and must exist. Throws InputError "FILE: KEY.PATH: problem" on any problem: unreadable file,
/// invalid JSON, unknown key, missing key, wrong type, NaN or infinite number, out-of-range value
/// (time_step <= 0, negative stiffness, ...), duplicate or unknown object name, missing mesh file.
Scene load_scene(const std::filesystem::path& file);
/// The same from JSON text; `file` names the scene in messages and anchors relative mesh paths.
Scene parse_scene(const std::string& json_text, const std::filesystem::path& file);

/// Directory of the coarse-mesh cache: $SQUEEZE_CACHE_DIR, else $XDG_CACHE_HOME/squeeze, else
/// $HOME/.cache/squeeze (empty if none of them is set).
std::filesystem::path mesh_cache_dir();

/// The coarse tetrahedral mesh of an object in its model units (before the transform): loaded
/// directly if `mesh` is a tet mesh (meshing::is_tet_format: .mesh, .msh, ...), otherwise made by the
/// meshing pipeline with target_tets = tets and cached as CACHE/meshes/HASH.mesh, HASH being a
/// 128-bit hash of the file's bytes and every meshing option, with CACHE/meshes/HASH.json beside it
/// (the key it was made for, a checksum of the .mesh file's bytes, the count and why it is off the
/// target); an entry whose record is missing or does not match (a damaged or swapped file) is meshed
/// again with a warning and overwritten. `cache_hit` (optional) tells whether the cache served it;
/// `off_target` (optional) gets why the count is more than 35% off `tets`
/// (MeshResult::target_exceeded_because), or "". Throws InputError "PATH: problem".
///   route  SceneObject::mesh_route (meshing::mesh_route_names: "auto", "convex_shells",
///          "winding_number", "alpha_wrap"); InputError for another
meshing::TetMesh object_tet_mesh(const std::filesystem::path& mesh, int tets, bool* cache_hit = nullptr,
                                 Progress* progress = nullptr, std::string* off_target = nullptr,
                                 const std::string& route = "auto");

/// The route of the mesh object `o` moves on (its simulation mesh, SceneWorld::meshes): "all_convex_shells"
/// for a deformable object meshed from a surface that simulates on its convex shells
/// (simulation_mesh "convex_shells", or "auto" over its target: meshes it through the cache to
/// tell), else o.mesh_route. object_tet_mesh(o.mesh, o.tets, ..., simulation_mesh_route(o)) is that mesh.
/// Throws InputError as object_tet_mesh where "auto" meshes the object (an unreadable file, say).
std::string simulation_mesh_route(const SceneObject& o);

/// The automatic time step of a world and what sets it (scene key `time_step`: "auto").
struct TimeStepChoice {
  double h = 0;          // s
  int object = -1;       // the object that sets it, or -1 (the frame interval, or no deformable object)
  std::string term;      // Verlet: "elastic", "contact" or "attachment" (+ " and damping") (the stability bound of that term at the
                         // object's stiffest vertex); implicit: "frame interval" or "initial speed"
  std::string detail;    // numbers behind it, one phrase
  /// One line: "0.0333 s (implicit: the frame interval 1/30 s)", "8.2e-05 s (verlet: elastic stability of 'ball', ...)".
  std::string describe(const Scene& scene) const;
};

/// The range of a scene's `time_step` (s): a given step outside it is an error (load_scene), and so
/// is an automatic step below kMinTimeStep (build_scene).
constexpr double kMinTimeStep = 1e-6;
constexpr double kMaxTimeStep = 1.0;

/// The frame interval the implicit integrator's automatic step keeps to (s).
constexpr double kImplicitFrameInterval = 1.0 / 30;

/// A World built from a scene, with what the later stages need beside it. Build it once
/// (build_scene: meshing, bodies, pins, time step) and copy it: copies are cheap (the world's rest
/// data is shared) and independent, so planning, replay and metrics each work on their own copy.
class SceneWorld {
 public:
  Scene scene;
  World world;                        // per-object gravity, pins and the time step included
  std::vector<meshing::TetMesh> meshes;  // per object: rest mesh in world coordinates (m)
  Eigen::AlignedBox3d bounds;         // scene bounds (given, or derived)
  std::vector<double> rest_volume;    // per object, m³
  TimeStepChoice time_step_choice;    // what chose the time step (h = the scene's time_step if it gives one)
  std::vector<std::vector<int>> pin_counts;  // per object, per objects[].pinned entry: the vertices it holds
  std::vector<std::string> warnings;  // what building it warned about, one line each ("objects[i].tets: …":
                                      // more tetrahedra than asked, and why), already logged; `squeeze
                                      // check` lists them with its own

  SceneWorld(Scene s, World w) : scene(std::move(s)), world(std::move(w)) {}
  /// The time step (s): the world's.
  double time_step() const { return world.time_step(); }
  /// Changes the time step (s, > 0); nothing is rebuilt. Throws InputError naming the scene.
  void set_time_step(double step);
  /// Rest positions, initial velocities (zero on pinned vertices), time 0.
  State initial_state() const;
  /// One step of the world (per-object gravity and pins are the world's).
  void step(State& s) { world.step(s); }
  /// Positions of object b in state s (#V by 3, m); rigid objects: their rest positions.
  RowMatrixX3d positions(const State& s, int b) const;
};

/// The vertices of `body` (rest positions, m) that the pin selects (ScenePin: box, near or surface),
/// ascending. Throws InputError "PATH: problem" if the surface file cannot be loaded.
std::vector<int> pinned_vertices(const Body& body, const ScenePin& pin);

/// The largest stable explicit step (s) of a world's deformable objects (estimate): for every
/// vertex i, ω² = ω_i² + k_c,i / m_i + k_a,i / m_i and γ = γ_i + c_c,i / m_i + c_a,i / m_i, with ω_i², γ_i
/// the element-by-element bounds of vertex_frequency_bounds (body.h: Σ over the vertex's edges and
/// tets of k Σ_k |∂C/∂p_k|² / m_k, and the same with the damping coefficients), k_c,i, c_c,i the
/// vertex's contact stiffness and damping (World::contact_scale), k_a,i, c_a,i its soft attachment's
/// (World::attach) and m the masses (mass scaling included);
/// h = min over vertices of 2 / (γ + sqrt(γ² + 4ω²)), at most 1e-3 s. That is half the exact limit
/// of a damped oscillator under the symplectic Euler step, (hω)² + 2hγ <= 4 (1/ω without damping,
/// 1/γ when overdamped). Returns 1e-3 with no deformable object.
double stable_time_step(const World& world);

/// The automatic time step of `world` for its integrator:
///  * verlet: stable_time_step, and which vertex term is the tightest (elastic ω², contact k_c/m,
///    attachment k_a/m, damping γ);
///  * implicit: chosen for accuracy, not stability: one frame interval (kImplicitFrameInterval), or
///    less where an object's initial speed would carry it more than half its mean edge length in
///    one step (h ≤ ½ L / |v0|). Within a step, the integrator's motion substeps (implicit.h) keep
///    every vertex's motion per substep below half an edge length whatever the speed it reaches.
TimeStepChoice auto_time_step(const World& world, const Scene& scene);

/// Meshes every object (through the cache), builds bodies, pins, soft attachments and the time
/// step; the world is prepared (World::prepare), so copies share its rest data.
/// Throws InputError "FILE: objects[i].KEY: problem" (e.g. "objects[1].pinned[0].near: holds no
/// vertex of 'liver' at rest", or a pin surface that cannot be loaded).
SceneWorld build_scene(const Scene& scene, Progress* progress = nullptr);

/// How many times build_scene has run in this process (a scene should be built once per command;
/// `squeeze run -v` reports it).
long long scene_builds();

/// Measures of one object in one state.
struct ObjectMetrics {
  double volume_ratio = 1;   // V / V0
  Eigen::Vector3d com;       // m, mass-weighted centre
  Eigen::AlignedBox3d aabb;  // m
  double kinetic_energy = 0; // J
};
ObjectMetrics object_metrics(const SceneWorld& w, const State& s, int b);

}  // namespace squeeze::fem
