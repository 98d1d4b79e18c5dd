// squeeze::render — the scene's `render` block (scenes/README.md, "render"):
//   "render": {"width": 1280, "height": 720, "fps": 30,
//              "camera": {"eye": [x,y,z], "target": [x,y,z], "up": [0,1,0], "fov_deg": 35}}
#pragma once
#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

namespace squeeze::render {

/// A pinhole camera (world coordinates, m).
struct Camera {
  Eigen::Vector3d eye{0, 0, 1};     // m, position
  Eigen::Vector3d target{0, 0, 0};  // m, looked-at point (!= eye)
  Eigen::Vector3d up{0, 1, 0};      // up direction (not parallel to target - eye)
  double fov_deg = 35;              // vertical field of view, degrees, in (0, 180)
};

/// The render block, each value empty when the scene does not give it.
struct RenderSettings {
  std::optional<int> width, height;  // pixels, [16, 16384]
  std::optional<double> fps;         // output frames per second (default: the trajectory's)
  std::optional<Camera> camera;      // default: framed automatically on the objects' bounds
};

/// Validates `render` (null: no block, all defaults). Throws InputError
/// "FILE: render.camera.fov_deg: must be > 0, got -3" (unknown keys, wrong types, ranges, an eye
/// on the target, an up along the view direction).
RenderSettings parse_render_settings(const nlohmann::json& render, const std::string& file);

/// Largest image side accepted (pixels); the GL implementation may lower it.
constexpr int kMaxImageSide = 16384;
constexpr int kMinImageSide = 16;

}  // namespace squeeze::render
