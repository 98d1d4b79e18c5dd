// squeeze::render — an offscreen OpenGL context without a display or a GPU (Mesa llvmpipe).
//
// Two backends behind one small interface: OSMesa (the default on Debian 12) and EGL with the
// surfaceless platform (EGL_MESA_platform_surfaceless), because Mesa removed OSMesa in 25.1.
// Either way the context is OpenGL 3.3 core and draws into framebuffer objects only.
#pragma once
#include <memory>
#include <string>

namespace squeeze::render {

enum class GlBackend { osmesa, egl };

/// "osmesa" / "egl" -> backend. Throws InputError ("--gl: unknown backend 'x' (osmesa or egl)").
GlBackend parse_gl_backend(const std::string& name);
const char* gl_backend_name(GlBackend backend);

/// A current OpenGL context on the calling thread (one per thread; made current on creation).
class GlContext {
 public:
  virtual ~GlContext() = default;
  /// Address of a GL function (core ones included), nullptr if unknown.
  virtual void* proc(const char* name) const = 0;
  /// Makes the context current on the calling thread again.
  virtual void make_current() = 0;
  /// "OSMesa, llvmpipe (LLVM 15.0.6, 256 bits), OpenGL 4.5 ..." for logs.
  virtual std::string description() const = 0;
};

/// Creates an OpenGL 3.3 core context with the backend and makes it current.
/// Throws InputError ("--gl egl: cannot ...: reason") if the backend is unavailable.
std::unique_ptr<GlContext> create_gl_context(GlBackend backend);

}  // namespace squeeze::render
