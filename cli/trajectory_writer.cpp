#include "trajectory_writer.h"

#include <unistd.h>

#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {
std::string fmt(double x) {
  if (x == 0) return "0";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}
}  // namespace

TrajectoryWriter::TrajectoryWriter(fem::SceneWorld& w, const fs::path& folder, double fps, double h, int frames)
    : w_(w), out_(folder), frames_(frames), fps_(fps), h_(h) {
  std::error_code ec;
  tmp_ = out_ / "trajectory";
  fs::create_directories(tmp_ / "rest", ec);
  fs::create_directories(tmp_ / "frames", ec);
  if (ec) throw InputError((tmp_ / "frames").string() + ": cannot create the directory: " + ec.message());

  const fem::Scene& scene = w.scene;
  nlohmann::json index;
  index["format"] = "squeeze-trajectory";
  index["version"] = 1;
  index["scene"] = fs::absolute(scene.file).lexically_normal().string();
  index["fps"] = fps;
  index["time_step"] = h;
  index["frames"] = frames;
  index["frame_file"] = "frames/%06d.bin";
  index["floor"] = scene.floor ? nlohmann::json(*scene.floor) : nlohmann::json(nullptr);
  index["bounds"] = {{"min", {w.bounds.min().x(), w.bounds.min().y(), w.bounds.min().z()}},
                     {"max", {w.bounds.max().x(), w.bounds.max().y(), w.bounds.max().z()}}};
  if (scene.goal)
    index["goal"] = {{"position", {scene.goal->position.x(), scene.goal->position.y(), scene.goal->position.z()}},
                     {"tolerance", scene.goal->tolerance},
                     {"object", scene.goal->object}};
  int offset = 0;
  for (int b = 0; b < w.world.bodies(); ++b) {
    const fem::SceneObject& o = scene.objects[b];
    const std::string rest = "rest/" + o.name + ".mesh";
    meshing::save_tet_mesh(tmp_ / rest, w.meshes[b]);
    index["objects"].push_back({{"name", o.name},
                                {"role", o.robot ? "robot" : "obstacle"},
                                {"kind", o.rigid ? "rigid" : "deformable"},
                                {"rest_mesh", rest},
                                {"vertices", w.world.body(b).vertices()},
                                {"tets", w.world.body(b).tets()},
                                {"offset", offset}});
    offset += w.world.body(b).vertices();
  }
  index["frame_vertices"] = offset;
  index_ = index.dump(2);
  buffer_.resize(static_cast<size_t>(offset) * 3);

  csv_ << "time,max_penetration,colliding_vertices";
  for (const auto& o : scene.objects)
    for (const char* c : {"volume_ratio", "com_x", "com_y", "com_z", "aabb_min_x", "aabb_min_y", "aabb_min_z",
                          "aabb_max_x", "aabb_max_y", "aabb_max_z", "kinetic_energy"})
      csv_ << ',' << o.name << '.' << c;
  csv_ << '\n';
}

void TrajectoryWriter::add_frame(const fem::State& s, double t) {
  // Contacts of this very state (the step's statistics belong to the state before it).
  const fem::StepStats st = w_.world.contact_stats(s);
  double depth = st.max_depth;
  int colliding = st.colliding_vertices;
  const auto& floor = w_.scene.floor;
  if (floor)
    for (Eigen::Index i = 0; i < s.x.rows(); ++i)
      if (s.x(i, 1) < *floor) {
        depth = std::max(depth, *floor - s.x(i, 1));
        ++colliding;
      }
  csv_ << fmt(t) << ',' << fmt(depth) << ',' << colliding;
  size_t at = 0;
  for (int b = 0; b < w_.world.bodies(); ++b) {
    const fem::ObjectMetrics m = fem::object_metrics(w_, s, b);
    for (double x : {m.volume_ratio, m.com.x(), m.com.y(), m.com.z(), m.aabb.min().x(), m.aabb.min().y(),
                     m.aabb.min().z(), m.aabb.max().x(), m.aabb.max().y(), m.aabb.max().z(), m.kinetic_energy})
      csv_ << ',' << fmt(x);
    const fem::RowMatrixX3d X = w_.positions(s, b);
    std::copy(X.data(), X.data() + X.size(), buffer_.data() + at);
    at += static_cast<size_t>(X.size());
  }
  csv_ << '\n';
  char name[32];
  std::snprintf(name, sizeof name, "%06d.bin", written_);
  std::ofstream bin(tmp_ / "frames" / name, std::ios::binary);
  bin.write(reinterpret_cast<const char*>(buffer_.data()), static_cast<std::streamsize>(buffer_.size() * sizeof(double)));
  if (!bin) throw InputError((tmp_ / "frames" / name).string() + ": write failed");
  ++written_;
}

void TrajectoryWriter::commit() {
  if (written_ != frames_)
    throw std::logic_error("TrajectoryWriter: " + std::to_string(written_) + " frames written, " +
                           std::to_string(frames_) + " announced");
  {
    std::ofstream idx(tmp_ / "index.json");
    idx << index_ << '\n';
    if (!idx) throw InputError((tmp_ / "index.json").string() + ": write failed");
  }
  {
    std::ofstream o(out_ / "metrics.csv");
    o << csv_.str();
    if (!o) throw InputError((out_ / "metrics.csv").string() + ": write failed");
  }
}

}  // namespace squeeze::cli
