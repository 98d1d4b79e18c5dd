// `squeeze render SCENE TRAJECTORY_DIR -o OUT [--width W --height H --frames A-B --coarse
//  --export pc2,obj,ply,vtu,mdd,glb --camera PRESET --video F.mp4 --gl osmesa|egl]`: offscreen frames of the deformed high-resolution
// meshes, the volume plot and exports (docs/render.md).

#include <cstdio>

#include "commands.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/render/export_formats.h"
#include "squeeze/render/render.h"
#include "squeeze/render/settings.h"

namespace squeeze::cli {

namespace {

struct RenderArgs {
  std::string scene, trajectory, output, frames, exports, gl = "osmesa", camera, video;
  int width = 0, height = 0, samples = 4;
  bool coarse = false, no_plots = false, no_png = false;
  CLI::Option *width_opt = nullptr, *height_opt = nullptr;
};

}  // namespace

Runner add_render_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render a trajectory offscreen (OSMesa or EGL, no display or GPU needed): every frame FFD-replayed onto\n"
      "the objects' high-resolution surfaces, as OUT/frame_00000.png ...; the volume change of every\n"
      "deformable object along the path as OUT/volume.png and OUT/volume.svg; optional exports for\n"
      "Blender (.pc2/.mdd point caches, a glTF animation), other renderers (per-frame OBJ/PLY) and ParaView\n"
      "(.vtu + .pvd); an MP4 video with --video.\n"
      "Example: squeeze render scenes/bunny.json out/bunny -o out/bunny/frames");
  cmd->add_option("SCENE", args->scene, "Scene file (JSON) the trajectory was made from")->required();
  cmd->add_option("TRAJECTORY_DIR", args->trajectory,
                  "Output folder of `squeeze simulate` / `squeeze replay`, or its trajectory/ folder")
      ->required();
  cmd->add_option("-o,--output", args->output, "Output folder (created if missing; its parent must exist)")->required();
  args->width_opt = cmd->add_option("--width", args->width, "Image width in pixels (default: the scene's render.width, else 1280)");
  args->height_opt = cmd->add_option("--height", args->height, "Image height in pixels (default: the scene's render.height, else 720)");
  cmd->add_option("--frames", args->frames,
                  "Render only output frames A-B (inclusive, 0-based; frame k is at t = k / fps), e.g. to split a "
                  "long path across machines");
  cmd->add_flag("--coarse", args->coarse, "Overlay the coarse tetrahedral meshes as wireframes");
  cmd->add_option("--export", args->exports, render::export_option_help());
  cmd->add_option("--gl", args->gl, "OpenGL context: osmesa (default) or egl (EGL surfaceless, Mesa)")
      ->capture_default_str();
  cmd->add_option("--samples", args->samples, "Multisample anti-aliasing samples per pixel (1: off)")
      ->capture_default_str();
  cmd->add_flag("--no-plots", args->no_plots, "Do not write volume.png / volume.svg");
  cmd->add_flag("--no-png", args->no_png, "Do not write frame PNGs (exports and plots only)");
  cmd->add_option("--camera", args->camera,
                  "Camera preset, replacing the scene's camera: " + render::camera_view_names() +
                      " (fitted to the scene preset's `fit` objects, else every object, over the whole path)");
  cmd->add_option("--video", args->video, "Also write the frames as an H.264 MP4 video at the frames' size and fps, e.g. "
                                          "--video out.mp4");

  return [args, &global]() -> int {
    const RenderArgs& a = *args;
    render::RenderOptions o;
    o.scene = a.scene;
    o.trajectory = a.trajectory;
    o.output = a.output;
    if (a.width_opt->count() > 0) o.width = a.width;
    if (a.height_opt->count() > 0) o.height = a.height;
    if (!a.frames.empty()) o.frames = render::parse_frame_range(a.frames);
    o.coarse = a.coarse;
    o.plots = !a.no_plots;
    o.png = !a.no_png;
    o.gl = render::parse_gl_backend(a.gl);
    if (a.samples < 1 || a.samples > 64) throw InputError("--samples " + std::to_string(a.samples) + ": must be in [1, 64]");
    o.samples = a.samples;
    render::parse_exports(a.exports, o);
    if (!a.camera.empty()) o.camera = a.camera;
    o.video = a.video;
    Progress progress(!global.quiet);
    o.on_frame = [&progress](const render::FrameProgress& p) {
      if (p.done == 1) progress.stage("rendering frames", p.total);
      progress.update(p.done);
    };
    // Into a staging folder beside OUT, swapped in whole (common/atomic_file.h): a kill or a full
    // disk leaves the old OUT complete; frames of other --frames ranges already in OUT are kept.
    FolderReplacement out(a.output);
    o.output = out.staging();
    const render::RenderStats s = render::render_trajectory(o, &progress);
    out.commit();
    progress.finish();
    if (!global.quiet)
      std::fprintf(stderr, "squeeze: %s: %d of %d frames at %dx%d (%d samples, %.1f frames/s), wrote %s\n",
                   a.scene.c_str(), s.rendered, s.total_frames, s.width, s.height, s.samples,
                   s.frame_seconds > 0 ? s.rendered / s.frame_seconds : 0.0,
                   (a.output + (s.video.empty() ? "" : " and " + s.video)).c_str());
    return kExitOk;
  };
}

}  // namespace squeeze::cli
