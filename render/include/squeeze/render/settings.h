// squeeze::render — the scene's `render` block (scenes/README.md, "render"):
//   "render": {"width": 1280, "height": 720, "fps": 30,
//              "camera": {"eye": [x,y,z], "target": [x,y,z], "up": [0,1,0], "fov_deg": 35}}
//   or a camera preset that frames objects automatically from a named side:
//              "camera": {"preset": "front", "fit": ["heart", "liver"], "fov_deg": 30}
//   ("frame" is accepted as the former name of "fit").
#pragma once
#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace squeeze::render {

/// A pinhole camera (world coordinates, m).
struct Camera {
  Eigen::Vector3d eye{0, 0, 1};     // m, position
  Eigen::Vector3d target{0, 0, 0};  // m, looked-at point (!= eye)
  Eigen::Vector3d up{0, 1, 0};      // up direction (not parallel to target - eye)
  double fov_deg = 35;              // vertical field of view, degrees, in (0, 180)
};

/// A camera placed automatically (frame_bounds): looking from the side `view` at the bounds of the
/// objects named in `fit` (all objects if empty) over the whole motion, +y up.
struct CameraPreset {
  std::string view = "oblique";        // a name of camera_views()
  std::vector<std::string> fit;        // object names; empty: every object
  double fov_deg = 35;                 // vertical field of view, degrees, in (0, 180)
};

/// The preset views: name and the direction from the framed bounds' centre to the eye.
/// "oblique" (0.55, 0.45, 1) (the default framing), "front" +z, "back" −z, "left" −x, "right" +x,
/// "top" +y (up −z); "three_quarter" is the former name of "oblique".
const std::vector<std::pair<std::string, Eigen::Vector3d>>& camera_views();

/// The preset names for help texts and messages: "oblique, front, back, left, right, top".
std::string camera_view_names();

/// The eye direction of the preset `name` (a name of camera_views()), or nullptr.
const Eigen::Vector3d* find_camera_view(const std::string& name);

/// The render block, each value empty when the scene does not give it.
struct RenderSettings {
  std::optional<int> width, height;  // pixels, [16, 16384]
  std::optional<double> fps;         // output frames per second (default: the trajectory's)
  std::optional<Camera> camera;      // default: framed automatically on the objects' bounds
  std::optional<CameraPreset> camera_preset;  // render.camera with "preset" (camera then empty)
};

/// Validates `render` (null: no block, all defaults). Throws InputError
/// "FILE: render.camera.fov_deg: must be > 0, got -3" (unknown keys, wrong types, ranges, an eye
/// on the target, an up along the view direction).
RenderSettings parse_render_settings(const nlohmann::json& render, const std::string& file);

/// Largest image side accepted (pixels); the GL implementation may lower it.
constexpr int kMaxImageSide = 16384;
constexpr int kMinImageSide = 16;

}  // namespace squeeze::render
