#include "squeeze/render/settings.h"

#include <nlohmann/json.hpp>

#include "squeeze/common/json_check.h"

namespace squeeze::render {

const std::vector<std::pair<std::string, Eigen::Vector3d>>& camera_views() {
  static const std::vector<std::pair<std::string, Eigen::Vector3d>> views = {
      {"oblique", Eigen::Vector3d(0.55, 0.45, 1.0)},       {"front", Eigen::Vector3d(0, 0, 1)},
      {"back", Eigen::Vector3d(0, 0, -1)},                  {"left", Eigen::Vector3d(-1, 0, 0)},
      {"right", Eigen::Vector3d(1, 0, 0)},                  {"top", Eigen::Vector3d(0, 1, 0)},
      {"three_quarter", Eigen::Vector3d(0.55, 0.45, 1.0)}};  // the former name of "oblique"
  return views;
}

std::string camera_view_names() {
  std::string names;
  for (const auto& [n, d] : camera_views())
    if (n != "three_quarter") names += (names.empty() ? "" : ", ") + n;
  return names;
}

const Eigen::Vector3d* find_camera_view(const std::string& name) {
  for (const auto& [n, d] : camera_views())
    if (n == name) return &d;
  return nullptr;
}

RenderSettings parse_render_settings(const nlohmann::json& r, const std::string& file) {
  RenderSettings s;
  if (r.is_null()) return s;
  const JsonChecker c{file};
  c.keys(r, "render", {"width", "height", "fps", "camera"});
  if (r.contains("width")) s.width = static_cast<int>(c.integer(r["width"], "render.width", kMinImageSide, kMaxImageSide));
  if (r.contains("height"))
    s.height = static_cast<int>(c.integer(r["height"], "render.height", kMinImageSide, kMaxImageSide));
  if (r.contains("fps")) {
    s.fps = c.positive(r["fps"], "render.fps");
    if (*s.fps > 10000) c.fail("render.fps", "must be <= 10000, got " + format_number(*s.fps));
  }
  if (r.contains("camera") && r["camera"].is_object() && r["camera"].contains("preset")) {
    const nlohmann::json& j = r["camera"];
    c.keys(j, "render.camera", {"preset", "fit", "frame", "fov_deg"});
    CameraPreset p;
    p.view = c.string(j["preset"], "render.camera.preset");
    if (!find_camera_view(p.view))
      c.fail("render.camera.preset", "must be one of " + camera_view_names() + ", got \"" + p.view + "\"");
    if (j.contains("fit") && j.contains("frame")) c.fail("render.camera.frame", "give \"fit\" only (\"frame\" is its former name)");
    for (const char* key : {"fit", "frame"}) {
      if (!j.contains(key)) continue;
      const std::string q = std::string("render.camera.") + key;
      if (!j[key].is_array() || j[key].empty()) c.fail(q, "must be a non-empty array of object names");
      for (size_t i = 0; i < j[key].size(); ++i) p.fit.push_back(c.string(j[key][i], q + "[" + std::to_string(i) + "]"));
    }
    if (j.contains("fov_deg")) {
      p.fov_deg = c.positive(j["fov_deg"], "render.camera.fov_deg");
      if (!(p.fov_deg < 180)) c.fail("render.camera.fov_deg", "must be < 180, got " + format_number(p.fov_deg));
    }
    s.camera_preset = p;
  } else if (r.contains("camera")) {
    const nlohmann::json& j = r["camera"];
    c.keys(j, "render.camera", {"eye", "target", "up", "fov_deg"});
    Camera cam;
    if (!j.contains("eye")) c.fail("render.camera.eye", "missing (a camera needs eye and target)");
    if (!j.contains("target")) c.fail("render.camera.target", "missing (a camera needs eye and target)");
    cam.eye = c.vec3(j["eye"], "render.camera.eye");
    cam.target = c.vec3(j["target"], "render.camera.target");
    if (j.contains("up")) cam.up = c.vec3(j["up"], "render.camera.up");
    if (j.contains("fov_deg")) {
      cam.fov_deg = c.positive(j["fov_deg"], "render.camera.fov_deg");
      if (!(cam.fov_deg < 180)) c.fail("render.camera.fov_deg", "must be < 180, got " + format_number(cam.fov_deg));
    }
    const Eigen::Vector3d d = cam.target - cam.eye;
    if (!(d.norm() > 0)) c.fail("render.camera.target", "must differ from render.camera.eye");
    if (!(cam.up.norm() > 0) || d.normalized().cross(cam.up.normalized()).norm() < 1e-6)
      c.fail("render.camera.up", "must be non-zero and not parallel to target - eye");
    s.camera = cam;
  }
  return s;
}

}  // namespace squeeze::render
