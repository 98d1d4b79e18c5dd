// squeeze::render — an OpenGL 3.3 core renderer of triangle meshes for offscreen frames:
// smooth shading from per-vertex normals, per-mesh colours, a checkered ground plane, shadows from
// one directional light (a 2048² shadow map, bilinear percentage-closer filtering), multisample
// anti-aliasing (a multisampled framebuffer resolved by a blit), optional wireframe overlays.
// All GL calls stay in renderer.cpp (functions loaded through GlContext::proc).
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "squeeze/render/settings.h"

namespace squeeze::render {

class GlContext;

struct RendererOptions {
  int width = 1280;        // pixels, [kMinImageSide, kMaxImageSide] and at most GL_MAX_RENDERBUFFER_SIZE
  int height = 720;        // pixels
  int samples = 4;         // MSAA samples per pixel (lowered to GL_MAX_SAMPLES; 1: none)
  int shadow_size = 2048;  // shadow map side, texels
};

/// An RGBA8 image, rows bottom to top (OpenGL order): pixels.size() == width*height*4.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;
};

class Renderer {
 public:
  /// Compiles the shaders and creates the framebuffers on the current context of `gl` (which must
  /// outlive the renderer). Throws InputError if the size exceeds what the GL implementation
  /// supports ("--width 40000: larger than the OpenGL limit 16384") or the framebuffer is incomplete.
  Renderer(GlContext& gl, const RendererOptions& options);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Adds a triangle mesh of fixed connectivity F (#F by 3 indices into #V vertices) in colour
  /// `rgb` (sRGB, components in [0, 1]); `shininess` in [0, 1] scales the specular highlight.
  /// `closed`: F is a closed surface oriented outwards, so back faces are culled (in the shadow
  /// pass front faces: only the far side casts), which halves the rasterization work; otherwise
  /// both sides are drawn and lit. Returns its id for update_mesh(). Set its vertices before draw().
  int add_mesh(const Eigen::MatrixX3i& F, int vertices, const Eigen::Vector3f& rgb, float shininess = 0.3f,
               bool closed = false);
  /// New positions V and unit normals N (#V by 3 each, m) of mesh `id`.
  void update_mesh(int id, const Eigen::MatrixX3d& V, const Eigen::MatrixX3d& N);
  /// Adds a wireframe: segments E (#E by 2 indices into #V vertices) drawn in `rgb` on top of the
  /// shaded meshes (hidden parts faint). Returns its id for update_lines().
  int add_lines(const Eigen::MatrixX2i& E, int vertices, const Eigen::Vector3f& rgb);
  void update_lines(int id, const Eigen::MatrixX3d& V);

  /// The ground plane y = height (m), drawn out to a distance of about 40 × the scene's radius.
  void set_floor(std::optional<double> height);
  /// The region that casts shadows and is framed (m): sets the light's shadow volume.
  void set_bounds(const Eigen::AlignedBox3d& bounds);
  void set_camera(const Camera& camera);

  /// Draws every mesh and returns the resolved frame.
  void draw(Image& out);

  int width() const;
  int height() const;
  int samples() const;  // MSAA samples in use

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Whether the triangles F form a closed surface, each edge shared by exactly two faces that use
/// it in opposite directions (consistently oriented, no boundary, no non-manifold edge).
bool is_closed_oriented(const Eigen::MatrixX3i& F);

/// A camera looking at `bounds` from `direction` (from the centre towards the eye; default the front,
/// right and above, (0.55, 0.45, 1)) with +y up (−z up when looking along y) at the distance that
/// fits its bounding sphere into the field of view.
Camera frame_bounds(const Eigen::AlignedBox3d& bounds, double aspect, double fov_deg = 35,
                    const Eigen::Vector3d& direction = Eigen::Vector3d(0.55, 0.45, 1.0));

/// A camera looking from `direction` (from the target towards the eye) with +y up (−z up when
/// looking along y), aimed and placed so that every point of P (#P by 3, m) is inside the
/// perspective view (vertical field of view `fov_deg`, width/height `aspect`) with `margin` around
/// (1.04: 4 % of the half-extents) and the points' silhouette centred: the tight fit of what is
/// seen, not of a bounding sphere. Used by the camera presets. Throws InputError if P is empty.
Camera frame_points(const Eigen::MatrixX3d& P, double aspect, double fov_deg, const Eigen::Vector3d& direction,
                    double margin = 1.04);

}  // namespace squeeze::render
