// squeeze::render — `squeeze render`: every frame of a trajectory, FFD-replayed onto each object's
// high-resolution surface and drawn offscreen into PNGs, plus the volume plot and the exports.
//
//   RenderOptions o;
//   o.scene = "scenes/bunny.json"; o.trajectory = "out/bunny"; o.output = "out/bunny/frames";
//   o.exports = {"pc2", "vtu"};
//   RenderStats s = render_trajectory(o, &progress);
//
// Output folder (docs/render.md): frame_00000.png … (k = output frame, t = k / fps), volume.png,
// volume.svg, and export/ with what each chosen export format writes (export_formats.h: pc2, obj,
// ply, vtu; each an Exporter, exporter.h).
#pragma once
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "squeeze/render/gl_context.h"

namespace squeeze {
class Progress;
}

namespace squeeze::render {

class Exporter;

/// Per-frame progress of render_trajectory.
struct FrameProgress {
  int done = 0, total = 0;  // frames written (rendered and queued for encoding) of the range
  double seconds = 0;       // since the first frame started
};

struct RenderOptions {
  std::filesystem::path scene;                 // scene file (JSON)
  std::filesystem::path trajectory;            // `squeeze simulate` output folder, or its trajectory/
  std::filesystem::path output;                // folder, created if missing (its parent must exist)
  std::optional<int> width, height;            // pixels; default: the scene's render block, else 1280x720
  std::optional<std::pair<int, int>> frames;   // inclusive output-frame range; default: all
  std::optional<double> fps;                   // output frames per second; default: the scene's render.fps, else the trajectory's
  bool coarse = false;                         // overlay the coarse tet meshes as wireframes
  bool png = true;                             // write frame PNGs (false: exports and plots only)
  bool plots = true;                           // write volume.png and volume.svg
  std::vector<std::string> exports;            // export formats by registered name (export_formats.h); default: none
  GlBackend gl = GlBackend::osmesa;            // context backend
  int samples = 4;                             // MSAA samples
  std::optional<std::string> camera;           // a camera preset (camera_views(): oblique, front, …) that
                                               // replaces the scene's camera; fits the scene preset's `fit`
                                               // objects if it has them, else every object
  std::filesystem::path video;                 // H.264 MP4 of the frames (video.h); empty: none
  bool video_optional = false;                 // true: no H.264 encoder only warns (squeeze run's default video)
  std::function<void(const FrameProgress&)> on_frame;  // called after each frame (may be empty)
};

struct RenderStats {
  int width = 0, height = 0, samples = 0;
  int total_frames = 0;           // output frames of the whole path: floor(duration × fps) + 1
  int rendered = 0;               // frames of the range
  double fps = 0;                 // output frames per simulated second
  double setup_seconds = 0;       // loading, binding, context creation
  double frame_seconds = 0;       // the frame loop, PNG encoding included (waited for)
  double frame_cpu_seconds = 0;   // CPU time of the process (all threads) during the frame loop
  std::string gl;                 // GL backend and renderer description
  long long surface_triangles = 0;  // triangles drawn per frame
  std::string video;              // the video written ("" if none): path
};

/// Parses "A-B" (inclusive, 0 <= A <= B) or "A" into a range. Throws InputError ("--frames x: ...").
std::pair<int, int> parse_frame_range(const std::string& text);

/// Adds to options.exports the formats of `list`, comma-separated names of the registered export
/// formats (export_formats(): pc2, obj, ply, vtu; a repeated name counts once); "" or "none": no
/// export. Throws InputError ("--export LIST: unknown export 'x' (pc2, obj, ply, vtu, or none)").
void parse_exports(const std::string& list, RenderOptions& options);

/// Renders a trajectory of a scene. Every input is checked before anything is written: scene and
/// render block, trajectory (index, same objects and coarse meshes as the scene), image size
/// (kMinImageSide..kMaxImageSide and the GL limit), frame range (within 0..total-1), output folder
/// (created if missing; must be writable). Throws InputError with one line naming the file or
/// option and the problem. Files are written atomically (no half-written PNG is ever left).
/// `progress` (may be null) gets the loading and binding stages. The exports named in
/// options.exports go into OUT/export/ (an unknown name throws InputError, before anything is
/// written); an exception mid-way leaves no export file half-written (exporter.h).
/// Last of all, OUT/render-manifest.json lists what this render completed (kRenderManifest;
/// docs/render.md "Manifest"): a reader trusts the files it lists, and a folder without it holds no
/// completed render.
RenderStats render_trajectory(const RenderOptions& options, Progress* progress = nullptr);

/// The name of the manifest render_trajectory writes last into its output folder.
constexpr const char* kRenderManifest = "render-manifest.json";

/// The same, driving `more` exporters (begun, fed every frame and finished like the registered
/// ones, after them) besides those named in options.exports: formats that are not registered.
RenderStats render_trajectory(const RenderOptions& options, std::vector<std::unique_ptr<Exporter>> more,
                              Progress* progress = nullptr);

}  // namespace squeeze::render
