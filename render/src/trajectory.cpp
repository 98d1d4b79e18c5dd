#include "squeeze/render/trajectory.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "squeeze/common/error.h"
#include "squeeze/common/json_check.h"
#include "squeeze/fem/scene.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::render {
namespace fs = std::filesystem;

fs::path Trajectory::frame_path(int k) const {
  char name[512];
  std::snprintf(name, sizeof name, frame_file.c_str(), k);
  return dir / name;
}

void Trajectory::read_frame(int k, Eigen::MatrixX3d& X) const {
  const fs::path p = frame_path(k);
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string() + ": cannot open the trajectory frame");
  const size_t n = static_cast<size_t>(frame_vertices) * 3;
  std::vector<double> buf(n);
  in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n * sizeof(double)));
  if (!in || in.peek() != std::char_traits<char>::eof())
    throw InputError(p.string() + ": expected " + std::to_string(n * sizeof(double)) + " bytes (" +
                     std::to_string(frame_vertices) + " vertices × 3 float64)");
  X.resize(frame_vertices, 3);
  for (int i = 0; i < frame_vertices; ++i)
    for (int c = 0; c < 3; ++c) {
      const double x = buf[static_cast<size_t>(i) * 3 + c];
      if (!std::isfinite(x)) throw InputError(p.string() + ": vertex " + std::to_string(i) + " is NaN or infinite");
      X(i, c) = x;
    }
}

meshing::TetMesh Trajectory::rest_mesh(int i) const { return meshing::load_tet_mesh(objects.at(static_cast<size_t>(i)).rest_mesh); }

Trajectory load_trajectory(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path.string() + ": no such trajectory folder");
  Trajectory t;
  if (fs::is_regular_file(path / "index.json", ec))
    t.dir = path;
  else if (fs::is_regular_file(path / "trajectory" / "index.json", ec))
    t.dir = path / "trajectory";
  else
    throw InputError(path.string() + ": not a trajectory (no index.json in it or in trajectory/)");
  const fs::path index = t.dir / "index.json";
  std::ifstream in(index);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw InputError(index.string() + ": cannot read");
  const nlohmann::json j = parse_json(text.str(), index.string());
  const JsonChecker c{index.string()};
  if (!j.is_object()) c.fail("(top level)", "must be an object");
  if (!j.contains("format") || j["format"] != "squeeze-trajectory") c.fail("format", "must be \"squeeze-trajectory\"");
  if (!j.contains("version") || c.integer(j["version"], "version", 0, 1 << 30) != 1)
    c.fail("version", "unsupported (this squeeze reads version 1)");
  for (const char* k : {"fps", "frames", "frame_file", "frame_vertices", "objects"})
    if (!j.contains(k)) c.fail(k, "missing");
  t.scene = j.contains("scene") ? fs::path(c.string(j["scene"], "scene")) : fs::path();
  t.fps = c.positive(j["fps"], "fps");
  t.frames = static_cast<int>(c.integer(j["frames"], "frames", 1, 10'000'000));
  t.frame_vertices = static_cast<int>(c.integer(j["frame_vertices"], "frame_vertices", 0, 1 << 30));
  t.frame_file = c.string(j["frame_file"], "frame_file");
  {
    // Exactly one integer conversion and nothing else that printf would interpret.
    int conversions = 0;
    for (size_t i = 0; i < t.frame_file.size(); ++i)
      if (t.frame_file[i] == '%') {
        if (i + 1 < t.frame_file.size() && t.frame_file[i + 1] == '%') {
          ++i;
          continue;
        }
        size_t e = i + 1;
        while (e < t.frame_file.size() && std::isdigit(static_cast<unsigned char>(t.frame_file[e]))) ++e;
        if (e >= t.frame_file.size() || t.frame_file[e] != 'd') c.fail("frame_file", "must hold one %d or %0Nd pattern");
        ++conversions;
      }
    if (conversions != 1) c.fail("frame_file", "must hold exactly one %d or %0Nd pattern");
  }
  if (j.contains("floor") && !j["floor"].is_null()) t.floor = c.number(j["floor"], "floor");
  const nlohmann::json& objs = j["objects"];
  if (!objs.is_array() || objs.empty()) c.fail("objects", "must be a non-empty array");
  int offset = 0;
  for (size_t i = 0; i < objs.size(); ++i) {
    const std::string p = "objects[" + std::to_string(i) + "]";
    const nlohmann::json& o = objs[i];
    if (!o.is_object()) c.fail(p, "must be an object");
    for (const char* k : {"name", "rest_mesh", "vertices", "tets", "offset"})
      if (!o.contains(k)) c.fail(p + "." + k, "missing");
    TrajectoryObject to;
    to.name = c.string(o["name"], p + ".name");
    to.robot = o.contains("role") && o["role"] == "robot";
    to.rigid = o.contains("kind") && o["kind"] == "rigid";
    to.rest_mesh = t.dir / c.string(o["rest_mesh"], p + ".rest_mesh");
    to.vertices = static_cast<int>(c.integer(o["vertices"], p + ".vertices", 1, 1 << 30));
    to.tets = static_cast<int>(c.integer(o["tets"], p + ".tets", 1, 1 << 30));
    to.offset = static_cast<int>(c.integer(o["offset"], p + ".offset", 0, 1 << 30));
    if (to.offset != offset) c.fail(p + ".offset", "must be " + std::to_string(offset) + " (objects follow each other)");
    offset += to.vertices;
    t.objects.push_back(std::move(to));
  }
  if (offset != t.frame_vertices)
    c.fail("frame_vertices", "must be the sum of the objects' vertices, " + std::to_string(offset));
  return t;
}

void check_trajectory_matches_scene(const Trajectory& traj, const fem::Scene& scene) {
  const std::string head = traj.dir.string() + ": not a trajectory of " + scene.file.string() + ": ";
  if (traj.objects.size() != scene.objects.size())
    throw InputError(head + "it has " + std::to_string(traj.objects.size()) + " objects, the scene " +
                     std::to_string(scene.objects.size()));
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const fem::SceneObject& so = scene.objects[i];
    const TrajectoryObject& to = traj.objects[i];
    if (so.name != to.name)
      throw InputError(head + "object " + std::to_string(i) + " is '" + to.name + "', the scene's is '" + so.name + "'");
    if (so.rigid != to.rigid)
      throw InputError(head + "object '" + so.name + "' is " + (to.rigid ? "rigid" : "deformable") +
                       " in the trajectory, " + (so.rigid ? "rigid" : "deformable") + " in the scene");
    const meshing::TetMesh coarse =
        fem::object_tet_mesh(so.mesh, so.tets, nullptr, nullptr, nullptr, fem::simulation_mesh_route(so));
    if (coarse.V.rows() != to.vertices || coarse.T.rows() != to.tets)
      throw InputError(head + "object '" + so.name + "' has " + std::to_string(to.vertices) + " vertices and " +
                       std::to_string(to.tets) + " tets, the scene's coarse mesh " +
                       std::to_string(coarse.V.rows()) + " and " + std::to_string(coarse.T.rows()));
    const meshing::TetMesh rest = traj.rest_mesh(static_cast<int>(i));
    if (rest.V.rows() != to.vertices || rest.T.rows() != to.tets)
      throw InputError(to.rest_mesh.string() + ": does not have the " + std::to_string(to.vertices) +
                       " vertices and " + std::to_string(to.tets) + " tets of index.json");
    const Eigen::Affine3d A = so.transform.affine();
    Eigen::MatrixX3d W(coarse.V.rows(), 3);
    for (Eigen::Index v = 0; v < coarse.V.rows(); ++v) W.row(v) = (A * Eigen::Vector3d(coarse.V.row(v).transpose())).transpose();
    const double size = (W.colwise().maxCoeff() - W.colwise().minCoeff()).norm();
    const double err = (W - rest.V).cwiseAbs().maxCoeff();
    if (!(err <= 1e-6 * size + 1e-12))
      throw InputError(head + "the rest mesh of object '" + so.name + "' is not the scene's (moved by up to " +
                       format_number(err) + " m)");
    if (rest.T != coarse.T) throw InputError(head + "the tets of object '" + so.name + "' differ from the scene's");
  }
}

}  // namespace squeeze::render
