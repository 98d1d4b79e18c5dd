#include "squeeze/render/render.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/scene.h"
#include "squeeze/ffd/ffd.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_geometry.h"
#include "squeeze/meshing/tet_io.h"
#include "squeeze/render/export_formats.h"
#include "squeeze/render/exporter.h"
#include "squeeze/render/plot.h"
#include "squeeze/render/png_io.h"
#include "squeeze/render/renderer.h"
#include "squeeze/render/settings.h"
#include "squeeze/render/trajectory.h"
#include "squeeze/render/video.h"

namespace squeeze::render {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

void parse_exports(const std::string& list, RenderOptions& o) {
  if (list.empty() || list == "none") return;
  std::stringstream s(list);
  for (std::string item; std::getline(s, item, ',');) {
    if (!find_export_format(item))
      throw InputError("--export " + list + ": unknown export '" + item + "' (" + export_format_names() + ", or none)");
    if (std::find(o.exports.begin(), o.exports.end(), item) == o.exports.end()) o.exports.push_back(item);
  }
}

std::pair<int, int> parse_frame_range(const std::string& text) {
  const auto bad = [&](const std::string& why) { return InputError("--frames " + text + ": " + why); };
  const auto parse_int = [&](const std::string& s) {
    if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos)
      throw bad("expected A-B with whole numbers 0 <= A <= B (e.g. 0-99)");
    return std::stoi(s);
  };
  const auto dash = text.find('-');
  if (dash == std::string::npos) {
    const int a = parse_int(text);
    return {a, a};
  }
  const int a = parse_int(text.substr(0, dash)), b = parse_int(text.substr(dash + 1));
  if (a > b) throw bad("the first frame is after the last");
  return {a, b};
}

namespace {

Eigen::MatrixX2i unique_edges(const Eigen::MatrixX3i& F) {
  std::vector<std::pair<int, int>> e;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      int a = F(f, c), b = F(f, (c + 1) % 3);
      if (a > b) std::swap(a, b);
      e.emplace_back(a, b);
    }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  Eigen::MatrixX2i E(static_cast<Eigen::Index>(e.size()), 2);
  for (size_t i = 0; i < e.size(); ++i) E.row(static_cast<Eigen::Index>(i)) << e[i].first, e[i].second;
  return E;
}

// The vertices of [0, n) that a face of F uses, ascending.
Eigen::VectorXi referenced_vertices(const Eigen::MatrixX3i& F, Eigen::Index n) {
  std::vector<char> used(static_cast<size_t>(n), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) used[static_cast<size_t>(F(f, c))] = 1;
  std::vector<int> keep;
  for (Eigen::Index v = 0; v < n; ++v)
    if (used[static_cast<size_t>(v)]) keep.push_back(static_cast<int>(v));
  return Eigen::Map<Eigen::VectorXi>(keep.data(), static_cast<Eigen::Index>(keep.size()));
}

// Removes the vertices of `s` that no face uses, keeping the order of the others (the order of the
// file: Blender's OBJ importer drops unused vertices, so exports keep only the used ones).
void drop_unreferenced(meshing::SurfaceMesh& s) {
  const Eigen::VectorXi keep = referenced_vertices(s.F, s.V.rows());
  if (keep.size() == s.V.rows()) return;
  Eigen::VectorXi to_new = Eigen::VectorXi::Constant(s.V.rows(), -1);
  Eigen::MatrixX3d V(keep.size(), 3);
  for (Eigen::Index i = 0; i < keep.size(); ++i) {
    to_new(keep(i)) = static_cast<int>(i);
    V.row(i) = s.V.row(keep(i));
  }
  spdlog::debug("render: {} vertices that no face uses dropped", s.V.rows() - keep.size());
  s.F = s.F.unaryExpr([&](int v) { return to_new(v); }).eval();
  s.V = std::move(V);
}

// Volume of the tetrahedra T at positions X (units³).
double mesh_volume(const Eigen::MatrixX4i& T, const Eigen::MatrixX3d& X) {
  double v = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    v += meshing::tet_volume(X.row(T(t, 0)), X.row(T(t, 1)), X.row(T(t, 2)), X.row(T(t, 3)));
  return v;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

// The diffuse colour (Kd) of the first material an OBJ uses, from its MTL library, if any.
std::optional<Eigen::Vector3f> obj_material_colour(const fs::path& obj) {
  std::string ext = obj.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".obj") return std::nullopt;
  std::ifstream in(obj);
  std::string line, mtllib, usemtl;
  while (std::getline(in, line) && (mtllib.empty() || usemtl.empty())) {
    if (line.rfind("mtllib", 0) == 0 && mtllib.empty()) mtllib = trim(line.substr(6));
    if (line.rfind("usemtl", 0) == 0 && usemtl.empty()) usemtl = trim(line.substr(6));
  }
  if (mtllib.empty()) return std::nullopt;
  std::ifstream mtl(obj.parent_path() / mtllib);
  bool in_material = false;
  std::optional<Eigen::Vector3f> first;
  while (std::getline(mtl, line)) {
    const std::string l = trim(line);
    if (l.rfind("newmtl", 0) == 0) in_material = usemtl.empty() || trim(l.substr(6)) == usemtl;
    if (l.rfind("Kd", 0) == 0 && (in_material || (!first && usemtl.empty()))) {
      std::istringstream s(l.substr(2));
      Eigen::Vector3f c;
      if (s >> c.x() >> c.y() >> c.z()) {
        if (in_material) return c.cwiseMax(0).cwiseMin(1);
        first = c.cwiseMax(0).cwiseMin(1);
      }
    }
  }
  return first;
}

// A stable index for an object name (FNV-1a): an object keeps its default colour whatever other
// objects the scene holds, and in whatever order.
std::uint32_t name_hash(const std::string& name) {
  std::uint32_t h = 2166136261u;
  for (unsigned char ch : name) h = (h ^ ch) * 16777619u;
  return h;
}

// Default colours: deformable objects warm and saturated (twelve), rigid ones neutral greys
// (three shades): visibly different kinds.
constexpr int kPaletteSize = 12;
Eigen::Vector3f palette_colour(int i) {
  static const float kColours[kPaletteSize][3] = {
      {0.88f, 0.50f, 0.28f}, {0.27f, 0.56f, 0.82f}, {0.42f, 0.72f, 0.36f}, {0.78f, 0.38f, 0.66f},
      {0.92f, 0.76f, 0.26f}, {0.33f, 0.74f, 0.74f}, {0.86f, 0.33f, 0.35f}, {0.55f, 0.45f, 0.80f},
      {0.62f, 0.44f, 0.26f}, {0.95f, 0.60f, 0.68f}, {0.20f, 0.45f, 0.45f}, {0.70f, 0.78f, 0.30f}};
  return {kColours[i][0], kColours[i][1], kColours[i][2]};
}
Eigen::Vector3f rigid_colour(const std::string& name) {
  const float g = 0.58f - 0.08f * static_cast<float>(name_hash(name) % 3);
  return {g, g + 0.02f, g + 0.05f};
}

// The default colours of the deformable objects named `names`: each takes the palette slot its
// name hashes to, or the next free one when an object earlier in name order took it (while any
// is free). So an object's colour depends on its name only, unless another object's name hashes
// to the same slot and sorts before it; distinct objects get distinct colours up to twelve.
std::map<std::string, Eigen::Vector3f> deformable_colours(std::vector<std::string> names) {
  std::sort(names.begin(), names.end());
  std::map<std::string, Eigen::Vector3f> colours;
  std::vector<char> taken(kPaletteSize, 0);
  int used = 0;
  for (const std::string& name : names) {
    int slot = static_cast<int>(name_hash(name) % kPaletteSize);
    if (used < kPaletteSize)
      while (taken[static_cast<size_t>(slot)]) slot = (slot + 1) % kPaletteSize;
    if (!taken[static_cast<size_t>(slot)]) ++used;
    taken[static_cast<size_t>(slot)] = 1;
    colours[name] = palette_colour(slot);
  }
  return colours;
}

struct Object {
  std::string name;
  bool rigid = false;
  bool direct = false;      // the scene mesh is a tet mesh: its boundary is drawn, no FFD
  bool closed = false;      // closed and oriented outwards: back faces culled
  ffd::Binding binding;          // surface -> coarse mesh (when !direct)
  Eigen::MatrixX3d rest;    // high-res surface vertices at rest (world, m)
  Eigen::MatrixX3i F;       // its triangles
  Eigen::MatrixX4i T;       // coarse tets
  Eigen::MatrixX2i coarse_edges;  // boundary edges of the coarse mesh
  int offset = 0, vertices = 0;   // coarse vertices in a frame
  Eigen::Vector3f colour;
  int mesh_id = -1, lines_id = -1;
  Eigen::VectorXi boundary;        // tet-mesh object: surface vertex -> coarse vertex (boundary nodes only)
  Eigen::MatrixX3i draw_F;         // faces drawn (split along creases for tet-mesh objects)
  Eigen::VectorXi draw_source;     // drawn vertex -> surface vertex (empty: the same vertices)
  Eigen::MatrixX3d surface, normals, coarse, drawn;  // per frame
};

// Splits the vertices of F along creases for drawing: the faces around a vertex are grouped by
// their rest normals (within `crease_deg` of a group's first face), and each group gets its own
// copy of the vertex, so that vertex normals stay smooth inside a group and sharp between groups
// (a box keeps its edges). Returns the faces over the copies; source(i) is the original of copy i.
Eigen::MatrixX3i split_creases(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double crease_deg,
                               Eigen::VectorXi& source) {
  const double cos_max = std::cos(crease_deg * M_PI / 180.0);
  Eigen::MatrixX3d N(F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    N.row(f) = n.norm() > 0 ? Eigen::RowVector3d(n.normalized().transpose()) : Eigen::RowVector3d::Zero();
  }
  std::vector<std::vector<std::pair<int, int>>> corners(static_cast<size_t>(V.rows()));  // (face, corner)
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) corners[static_cast<size_t>(F(f, c))].emplace_back(static_cast<int>(f), c);
  Eigen::MatrixX3i out = F;
  std::vector<int> src;
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    std::vector<int> leaders;  // first face of each group
    std::vector<int> ids;
    for (const auto& [f, c] : corners[static_cast<size_t>(v)]) {
      size_t g = 0;
      while (g < leaders.size() && N.row(leaders[g]).dot(N.row(f)) < cos_max) ++g;
      if (g == leaders.size()) {
        leaders.push_back(f);
        ids.push_back(static_cast<int>(src.size()));
        src.push_back(static_cast<int>(v));
      }
      out(f, c) = ids[g];
    }
  }
  source = Eigen::Map<Eigen::VectorXi>(src.data(), static_cast<Eigen::Index>(src.size()));
  return out;
}

// --- The steps of render_trajectory ---

// Every input of a render, checked; nothing is written yet.
struct Inputs {
  fem::Scene scene;
  RenderSettings settings;   // the scene's render block
  Trajectory traj;
  int width = 0, height = 0;  // pixels
  double fps = 0;             // output frames per simulated second: frame k at t = k / fps
  int total = 0;              // output frames of the whole path
  int first = 0, last = 0;    // inclusive range of output frames rendered
  std::optional<std::string> camera;  // --camera
};

// Loads and checks the scene, the image size, the trajectory, the frame range, the output folder
// and the plot drivers, in that order. Throws InputError.
Inputs check_inputs(const RenderOptions& o) {
  Inputs in;
  in.scene = fem::load_scene(o.scene);
  in.settings = parse_render_settings(in.scene.render, in.scene.file.string());
  in.width = o.width ? *o.width : in.settings.width.value_or(1280);
  in.height = o.height ? *o.height : in.settings.height.value_or(720);
  const auto check_side = [](const char* opt, int v) {
    if (v < kMinImageSide || v > kMaxImageSide)
      throw InputError(std::string(opt) + " " + std::to_string(v) + ": must be in [" + std::to_string(kMinImageSide) +
                       ", " + std::to_string(kMaxImageSide) + "] pixels");
  };
  check_side("--width", in.width);
  check_side("--height", in.height);
  if (static_cast<long long>(in.width) * in.height > 100'000'000LL)
    throw InputError("--width × --height: " + std::to_string(in.width) + "x" + std::to_string(in.height) +
                     " is more than 100 megapixels");
  if (o.samples < 1 || o.samples > 64) throw InputError("samples: must be in [1, 64]");

  if (o.camera && !find_camera_view(*o.camera))
    throw InputError("--camera " + *o.camera + ": must be one of " + camera_view_names());
  in.camera = o.camera;
  in.traj = load_trajectory(o.trajectory);
  check_trajectory_matches_scene(in.traj, in.scene);

  in.fps = o.fps ? *o.fps : in.settings.fps.value_or(in.traj.fps);
  in.total = static_cast<int>(std::floor(in.traj.duration() * in.fps + 1e-6)) + 1;
  in.first = 0;
  in.last = in.total - 1;
  if (o.frames) {
    in.first = o.frames->first;
    in.last = o.frames->second;
    if (in.last >= in.total)
      throw InputError("--frames " + std::to_string(in.first) + "-" + std::to_string(in.last) + ": the path has " +
                       std::to_string(in.total) + " frames (0-" + std::to_string(in.total - 1) + ")");
  }

  // Output folder: created later if missing (its parent must exist), then checked for writing.
  check_output_folder(o.output);
  if (o.plots && !plot_drivers_available())
    throw InputError("volume.png: PLplot's cairo drivers are missing (Debian: install plplot-driver-cairo)");
  return in;
}

// Object i of the scene: its high-resolution surface placed by its transform and bound to the
// trajectory's coarse rest mesh (a tet-mesh object: the boundary of that mesh, drawn directly),
// turned outwards when closed, and its faces for drawing. Its colour is set by load_objects.
Object load_object(const fem::SceneObject& so, const Trajectory& traj, int i, Progress* progress) {
  Object ob;
  ob.name = so.name;
  ob.rigid = so.rigid;
  ob.offset = traj.objects[static_cast<size_t>(i)].offset;
  ob.vertices = traj.objects[static_cast<size_t>(i)].vertices;
  const meshing::TetMesh rest = traj.rest_mesh(i);
  ob.T = rest.T;
  const Eigen::MatrixX3i coarse_faces = meshing::boundary_faces(rest.T);
  ob.coarse_edges = unique_edges(coarse_faces);
  ob.direct = meshing::is_tet_format(so.mesh);
  if (ob.direct) {
    // The surface is the boundary of the tet mesh: its nodes in ascending order (interior nodes
    // are not part of it, so a per-vertex export holds exactly the vertices its faces use).
    ob.boundary = referenced_vertices(coarse_faces, rest.V.rows());
    Eigen::VectorXi to_surface = Eigen::VectorXi::Constant(rest.V.rows(), -1);
    ob.rest.resize(ob.boundary.size(), 3);
    for (Eigen::Index i = 0; i < ob.boundary.size(); ++i) {
      to_surface(ob.boundary(i)) = static_cast<int>(i);
      ob.rest.row(i) = rest.V.row(ob.boundary(i));
    }
    ob.F = coarse_faces.unaryExpr([&](int v) { return to_surface(v); });
  } else {
    if (progress) progress->stage("loading " + so.name);
    meshing::LoadOptions lo;
    lo.keep_order = true;
    meshing::SurfaceMesh s = meshing::load_surface(so.mesh, lo);
    const Eigen::Affine3d A = so.transform.affine();
    for (Eigen::Index v = 0; v < s.V.rows(); ++v) s.V.row(v) = (A * Eigen::Vector3d(s.V.row(v).transpose())).transpose();
    if (A.linear().determinant() < 0) s.F.col(1).swap(s.F.col(2));  // a mirroring transform keeps outward faces
    drop_unreferenced(s);  // vertices no face uses are not part of the surface (nor of its exports)
    ob.rest = std::move(s.V);
    ob.F = std::move(s.F);
    ob.binding = ffd::bind_surface(ob.rest, rest, ffd::BindOptions{}, progress, so.mesh.filename().string());
  }
  // A closed, consistently oriented surface is drawn with back faces culled; turned outwards first.
  ob.closed = is_closed_oriented(ob.F);
  if (ob.closed) {
    double vol = 0;
    for (Eigen::Index f = 0; f < ob.F.rows(); ++f)
      vol += Eigen::Vector3d(ob.rest.row(ob.F(f, 0))).dot(
          Eigen::Vector3d(ob.rest.row(ob.F(f, 1))).cross(Eigen::Vector3d(ob.rest.row(ob.F(f, 2)))));
    if (vol < 0) ob.F.col(1).swap(ob.F.col(2));
  }
  // Tet-mesh objects (boxes, plates) are drawn with sharp edges; surfaces smooth everywhere.
  if (ob.direct)
    ob.draw_F = split_creases(ob.rest, ob.F, 40.0, ob.draw_source);
  else
    ob.draw_F = ob.F;
  return ob;
}

// Every object of the scene (load_object), coloured: its `color` key, else the MTL colour of an
// OBJ surface, else the default colour of its name and kind.
std::vector<Object> load_objects(const fem::Scene& scene, const Trajectory& traj, Progress* progress) {
  std::vector<std::string> deformable;
  for (const fem::SceneObject& so : scene.objects)
    if (!so.rigid) deformable.push_back(so.name);
  const std::map<std::string, Eigen::Vector3f> palette = deformable_colours(deformable);
  std::vector<Object> objects;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const fem::SceneObject& so = scene.objects[i];
    Object ob = load_object(so, traj, static_cast<int>(i), progress);
    const std::optional<Eigen::Vector3f> mtl = ob.direct ? std::nullopt : obj_material_colour(so.mesh);
    ob.colour = so.color ? Eigen::Vector3f(so.color->cast<float>()) : mtl ? *mtl : so.rigid ? rigid_colour(so.name) : palette.at(so.name);
    objects.push_back(std::move(ob));
  }
  return objects;
}

// What one pass over every trajectory frame gives.
struct Motion {
  std::vector<std::vector<double>> volume;  // per object and trajectory frame: change from frame 0 (%)
  Eigen::AlignedBox3d view_bounds;          // rest surfaces and coarse motion, grown by 5 %, down to the floor
  std::vector<Eigen::AlignedBox3d> object_bounds;  // per object: its rest surface and coarse motion
  std::vector<std::vector<Eigen::Vector3d>> object_points;  // per object: rest surface (≤ 4000 points) and
                                                            // coarse vertices at ≤ 17 frames (camera presets)
};

// Reads every trajectory frame once: the objects' volumes (plot) and the bounds of the motion
// (camera, shadows). Throws InputError on a bad frame file.
Motion scan_trajectory(const Trajectory& traj, const std::vector<Object>& objects, Progress* progress) {
  Motion m;
  m.volume.resize(objects.size());
  std::vector<double> rest_volume(objects.size());
  Eigen::AlignedBox3d bounds;
  m.object_bounds.resize(objects.size());
  m.object_points.resize(objects.size());
  for (size_t b = 0; b < objects.size(); ++b) {
    const Eigen::Index n = objects[b].rest.rows(), stride = std::max<Eigen::Index>(1, n / 4000);
    for (Eigen::Index v = 0; v < n; ++v) {
      m.object_bounds[b].extend(Eigen::Vector3d(objects[b].rest.row(v).transpose()));
      if (v % stride == 0) m.object_points[b].push_back(objects[b].rest.row(v).transpose());
    }
  }
  const int frame_stride = std::max(1, traj.frames / 16);
  Eigen::MatrixX3d X;
  if (progress) progress->stage("reading the trajectory", traj.frames);
  for (int f = 0; f < traj.frames; ++f) {
    traj.read_frame(f, X);
    for (size_t b = 0; b < objects.size(); ++b) {
      const Object& ob = objects[b];
      const Eigen::MatrixX3d Xb = X.middleRows(ob.offset, ob.vertices);
      const double vol = mesh_volume(ob.T, Xb);
      if (f == 0) rest_volume[b] = vol;
      m.volume[b].push_back(rest_volume[b] > 0 ? 100.0 * (vol / rest_volume[b] - 1.0) : 0.0);
      for (Eigen::Index v = 0; v < Xb.rows(); ++v) m.object_bounds[b].extend(Eigen::Vector3d(Xb.row(v).transpose()));
      if (f % frame_stride == 0 || f == traj.frames - 1)
        for (Eigen::Index v = 0; v < Xb.rows(); ++v) m.object_points[b].push_back(Xb.row(v).transpose());
    }
    if (progress) progress->update(f + 1);
  }
  if (progress) progress->finish();
  for (const Eigen::AlignedBox3d& b : m.object_bounds) bounds.extend(b);
  // The surfaces may stick out of the coarse meshes a little: grow by 5 %.
  const Eigen::Vector3d grow = 0.05 * bounds.diagonal();
  bounds.min() -= grow;
  bounds.max() += grow;
  m.view_bounds = bounds;
  if (traj.floor) {
    // Keep the floor contact in view.
    m.view_bounds.min().y() = std::min(m.view_bounds.min().y(), *traj.floor);
  }
  return m;
}

// Floor, bounds and camera (the scene's, else framing the motion), and every object's mesh (and
// with `coarse` its wireframe) added to `renderer`.
void set_up_scene(Renderer& renderer, std::vector<Object>& objects, const Inputs& in, const Motion& motion,
                  bool coarse) {
  const Eigen::AlignedBox3d& view_bounds = motion.view_bounds;
  renderer.set_floor(in.scene.floor);
  renderer.set_bounds(view_bounds);
  const double aspect = double(in.width) / in.height;
  std::optional<CameraPreset> preset = in.settings.camera_preset;
  if (in.camera) {  // --camera (checked by check_inputs): a preset replaces the scene's camera
    if (!preset) preset = CameraPreset{};
    preset->view = *in.camera;
  }
  if (in.settings.camera && !in.camera) {
    renderer.set_camera(*in.settings.camera);
  } else if (preset) {
    // The named objects (every object if none is named) over the whole motion, seen from the
    // preset's side and fitted tightly into the view.
    std::vector<Eigen::Vector3d> points;
    for (size_t b = 0; b < objects.size(); ++b)
      if (preset->fit.empty()) points.insert(points.end(), motion.object_points[b].begin(), motion.object_points[b].end());
    for (const std::string& name : preset->fit) {
      size_t b = 0;
      while (b < objects.size() && objects[b].name != name) ++b;
      if (b == objects.size())
        throw InputError(in.scene.file.string() + ": render.camera.fit: no object named '" + name + "'");
      points.insert(points.end(), motion.object_points[b].begin(), motion.object_points[b].end());
    }
    Eigen::MatrixX3d P(static_cast<Eigen::Index>(points.size()), 3);
    for (size_t i = 0; i < points.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
    renderer.set_camera(frame_points(P, aspect, preset->fov_deg, *find_camera_view(preset->view)));
  } else {
    renderer.set_camera(frame_bounds(view_bounds, aspect));
  }
  for (Object& ob : objects) {
    const int drawn = static_cast<int>(ob.draw_source.size() ? ob.draw_source.size() : ob.rest.rows());
    ob.mesh_id = renderer.add_mesh(ob.draw_F, drawn, ob.colour, ob.rigid ? 0.6f : 0.25f, ob.closed);
    if (coarse) ob.lines_id = renderer.add_lines(ob.coarse_edges, ob.vertices, Eigen::Vector3f(0.08f, 0.1f, 0.2f));
  }
}

// Creates the output folder (after every check) and checks that it is writable; a folder created
// here is removed again when it is not. Throws InputError.
void create_output_folder(const fs::path& out) {
  std::error_code ec;
  const bool created = !fs::exists(out, ec);
  fs::create_directories(out, ec);
  if (ec) throw InputError(out.string() + ": cannot create the directory: " + ec.message());
  try {
    check_output_directory(out / "frame_00000.png");
  } catch (...) {
    if (created) fs::remove(out, ec);
    throw;
  }
}

// Creates `folder` (OUT/export) if there is any exporter, and begins every exporter on the objects
// and the frame range. Throws InputError.
void begin_exports(const std::vector<std::unique_ptr<Exporter>>& exporters, const fs::path& folder,
                   const std::vector<Object>& objects, const Inputs& in) {
  if (exporters.empty()) return;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder.string() + ": cannot create the directory: " + ec.message());
  ExportContext c;
  c.folder = folder;
  for (const Object& ob : objects) c.objects.push_back(ExportObject{ob.name, ob.rest, ob.F, ob.T, ob.colour, ob.rigid});
  c.first_frame = in.first;
  c.last_frame = in.last;
  c.frame_count = in.last - in.first + 1;
  c.fps = in.fps;
  for (const auto& e : exporters) e->begin(c);
}

// The coarse state of every object (all of a frame's vertices) at output frame k, t = k / fps:
// interpolated linearly between the two trajectory frames around t, reusing the frames already read
// when k grows one by one.
class StateSampler {
 public:
  StateSampler(const Trajectory& traj, double fps) : traj_(traj), fps_(fps) {}
  // Throws InputError on a bad frame file.
  const Eigen::MatrixX3d& at(int k) {
    const double s = std::min<double>(traj_.frames - 1, k / fps_ * traj_.fps);
    int i0 = static_cast<int>(std::floor(s + 1e-9));
    i0 = std::clamp(i0, 0, traj_.frames - 1);
    const double a = std::clamp(s - i0, 0.0, 1.0);
    const int i1 = std::min(i0 + 1, traj_.frames - 1);
    if (loaded0_ != i0) {
      if (loaded1_ == i0) {
        std::swap(X0_, X1_);
      } else {
        traj_.read_frame(i0, X0_);
      }
      loaded0_ = i0;
      loaded1_ = -1;
    }
    if (a > 1e-9 && loaded1_ != i1) {
      traj_.read_frame(i1, X1_);
      loaded1_ = i1;
    }
    state_ = a > 1e-9 ? Eigen::MatrixX3d((1 - a) * X0_ + a * X1_) : X0_;
    return state_;
  }

 private:
  const Trajectory& traj_;
  double fps_;
  Eigen::MatrixX3d X0_, X1_, state_;  // trajectory frames loaded0_ and loaded1_ (-1: none), the state
  int loaded0_ = -1, loaded1_ = -1;
};

// Moves every object to `state`: its coarse vertices, its surface (FFD replay; a tet-mesh object's
// surface is its coarse mesh) and the normals, and hands them to the renderer.
void pose_objects(std::vector<Object>& objects, const Eigen::MatrixX3d& state, Renderer& renderer) {
  for (Object& ob : objects) {
    ob.coarse = state.middleRows(ob.offset, ob.vertices);
    if (ob.direct) {
      ob.surface.resize(ob.boundary.size(), 3);
      for (Eigen::Index i = 0; i < ob.boundary.size(); ++i) ob.surface.row(i) = ob.coarse.row(ob.boundary(i));
    } else
      replay(ob.binding, ob.coarse, ob.surface);
    if (ob.draw_source.size()) {
      ob.drawn.resize(ob.draw_source.size(), 3);
      for (Eigen::Index i = 0; i < ob.draw_source.size(); ++i) ob.drawn.row(i) = ob.surface.row(ob.draw_source(i));
      ob.normals = ffd::vertex_normals(ob.drawn, ob.draw_F);
      renderer.update_mesh(ob.mesh_id, ob.drawn, ob.normals);
    } else {
      ob.normals = ffd::vertex_normals(ob.surface, ob.draw_F);
      renderer.update_mesh(ob.mesh_id, ob.surface, ob.normals);
    }
    if (ob.lines_id >= 0) renderer.update_lines(ob.lines_id, ob.coarse);
  }
}

// The frame loop: every output frame of the range posed, drawn and queued for PNG encoding (unless
// --no-png) and handed to the exporters; then the last PNG waited for and the exporters finished.
// Sets stats.rendered and the loop's times. Throws InputError.
void render_frames(const RenderOptions& o, const Inputs& in, std::vector<Object>& objects, Renderer& renderer,
                   const std::vector<std::unique_ptr<Exporter>>& exporters, VideoWriter* video, RenderStats& stats) {
  const auto t1 = Clock::now();
  const std::clock_t c1 = std::clock();
  PngWriter writer(2, 1);
  Image image;
  StateSampler sampler(in.traj, in.fps);
  std::vector<ExportState> states;
  const int count = in.last - in.first + 1;
  double draw_s = 0, wait_s = 0;  // drawing + read-back, waiting for the encoder
  for (int k = in.first; k <= in.last; ++k) {
    pose_objects(objects, sampler.at(k), renderer);
    if (o.png || video) {
      const auto d0 = Clock::now();
      writer.recycle(image);
      renderer.draw(image);
      const auto d1 = Clock::now();
      if (video) video->add(image);
      if (o.png) writer.push(o.output / frame_file_name("frame_", k, ".png"), std::move(image));
      draw_s += std::chrono::duration<double>(d1 - d0).count();
      wait_s += std::chrono::duration<double>(Clock::now() - d1).count();
    }
    if (!exporters.empty()) {
      states.clear();
      for (const Object& ob : objects) states.push_back(ExportState{ob.surface, ob.coarse});
      for (const auto& e : exporters) e->frame(k, k / in.fps, states);
    }
    ++stats.rendered;
    if (o.on_frame)
      o.on_frame(FrameProgress{k - in.first + 1, count, std::chrono::duration<double>(Clock::now() - t1).count()});
  }
  writer.finish();
  for (const auto& e : exporters) e->finish();
  if (video) video->finish();
  stats.frame_seconds = std::chrono::duration<double>(Clock::now() - t1).count();
  stats.frame_cpu_seconds = double(std::clock() - c1) / CLOCKS_PER_SEC;
  spdlog::debug("render: {} frames in {:.3f} s: drawing and read-back {:.3f} s, waiting for the PNG encoder {:.3f} s",
                stats.rendered, stats.frame_seconds, draw_s, wait_s);
}

// volume.png and volume.svg in `out`: the volume change of every deformable object (every object
// if none is deformable) along the whole path. Throws InputError.
void write_volume_plots(const fs::path& out, const Inputs& in, const std::vector<Object>& objects, const Motion& m) {
  const bool any_deformable = std::any_of(objects.begin(), objects.end(), [](const Object& ob) { return !ob.rigid; });
  LinePlot plot;
  plot.title = "Volume change along the path (" + in.scene.file.stem().string() + ")";
  plot.x_label = "time (s)";
  plot.y_label = "volume change (%)";
  for (int f = 0; f < in.traj.frames; ++f) plot.x.push_back(f / in.traj.fps);
  for (size_t b = 0; b < objects.size(); ++b)
    if (!objects[b].rigid || !any_deformable)
      plot.series.push_back(PlotSeries{objects[b].name, m.volume[b], objects[b].colour});
  save_plot(out / "volume.png", plot);
  save_plot(out / "volume.svg", plot);
}

// OUT/render-manifest.json, written last (atomically): the frames of the range, the plots and every
// file under OUT/export/, each complete (PNGs and exports are renamed into place when complete).
void write_manifest(const RenderOptions& o, const Inputs& in, const RenderStats& stats) {
  nlohmann::json m;
  m["format"] = "squeeze-render-manifest";
  m["version"] = 1;
  m["scene"] = fs::absolute(o.scene).lexically_normal().string();
  m["trajectory"] = fs::absolute(o.trajectory).lexically_normal().string();
  m["fps"] = in.fps;
  m["total_frames"] = in.total;
  m["width"] = stats.width;
  m["height"] = stats.height;
  m["frames"] = {{"first", in.first}, {"last", in.last}, {"files", nlohmann::json::array()}};
  if (o.png)
    for (int k = in.first; k <= in.last; ++k) m["frames"]["files"].push_back(frame_file_name("frame_", k, ".png"));
  m["plots"] = nlohmann::json::array();
  if (o.plots) m["plots"] = {"volume.png", "volume.svg"};
  std::vector<std::string> exports;
  std::error_code ec;
  const fs::path folder = o.output / "export";
  if (!o.exports.empty() && fs::is_directory(folder, ec))
    for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file(ec)) exports.push_back(fs::relative(it->path(), o.output, ec).generic_string());
  if (ec) throw InputError(folder.string() + ": cannot list the exports: " + ec.message());
  std::sort(exports.begin(), exports.end());
  m["exports"] = exports;
  const fs::path path = o.output / kRenderManifest;
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << m.dump(2) << '\n';
    if (!f) throw InputError(path.string() + ": write failed");
  });
}

}  // namespace

RenderStats render_trajectory(const RenderOptions& o, Progress* progress) {
  return render_trajectory(o, {}, progress);
}

RenderStats render_trajectory(const RenderOptions& o, std::vector<std::unique_ptr<Exporter>> more, Progress* progress) {
  const auto t0 = Clock::now();
  std::vector<std::unique_ptr<Exporter>> exporters = make_exporters(o.exports);
  for (auto& e : more) exporters.push_back(std::move(e));
  const Inputs in = check_inputs(o);
  std::vector<Object> objects = load_objects(in.scene, in.traj, progress);
  const Motion motion = scan_trajectory(in.traj, objects, progress);

  std::unique_ptr<GlContext> ctx = create_gl_context(o.gl);
  RendererOptions ro;
  ro.width = in.width;
  ro.height = in.height;
  ro.samples = o.samples;
  Renderer renderer(*ctx, ro);
  set_up_scene(renderer, objects, in, motion, o.coarse);

  create_output_folder(o.output);
  begin_exports(exporters, o.output / "export", objects, in);

  RenderStats stats;
  stats.width = in.width;
  stats.height = in.height;
  stats.samples = renderer.samples();
  stats.gl = ctx->description();
  stats.total_frames = in.total;
  stats.fps = in.fps;
  for (const Object& ob : objects) stats.surface_triangles += ob.F.rows();
  stats.setup_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  std::unique_ptr<VideoWriter> video;
  if (!o.video.empty()) {
    std::string why;
    if (video_available(&why) || !o.video_optional) {
      video = std::make_unique<VideoWriter>(o.video, in.width, in.height, in.fps);
      stats.video = o.video.string();
    } else {
      spdlog::warn("{}: not written: {}", o.video.string(), why);
    }
  }
  render_frames(o, in, objects, renderer, exporters, video.get(), stats);
  if (o.plots) write_volume_plots(o.output, in, objects, motion);
  write_manifest(o, in, stats);  // last: what it lists is complete
  return stats;
}

}  // namespace squeeze::render
