#include "squeeze/render/gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/osmesa.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include "squeeze/common/error.h"

namespace squeeze::render {

GlBackend parse_gl_backend(const std::string& name) {
  if (name == "osmesa") return GlBackend::osmesa;
  if (name == "egl") return GlBackend::egl;
  throw InputError("--gl: unknown backend '" + name + "' (osmesa or egl)");
}

const char* gl_backend_name(GlBackend backend) { return backend == GlBackend::osmesa ? "osmesa" : "egl"; }

namespace {

using GetStringFn = const unsigned char* (*)(unsigned int);

std::string describe(const GlContext& c, const char* backend) {
  auto get = reinterpret_cast<GetStringFn>(c.proc("glGetString"));
  std::string s = backend;
  if (!get) return s;
  const auto str = [&](unsigned int e) {
    const unsigned char* p = get(e);
    return p ? std::string(reinterpret_cast<const char*>(p)) : std::string("?");
  };
  return s + ", " + str(GL_RENDERER) + ", OpenGL " + str(GL_VERSION);
}

class OsmesaContext final : public GlContext {
 public:
  OsmesaContext() {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 0,
                           OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                           OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!ctx_) throw InputError("--gl osmesa: cannot create an OpenGL 3.3 core context (OSMesaCreateContextAttribs)");
    make_current();
  }
  ~OsmesaContext() override {
    if (ctx_) OSMesaDestroyContext(ctx_);
  }
  void* proc(const char* name) const override { return reinterpret_cast<void*>(OSMesaGetProcAddress(name)); }
  void make_current() override {
    // Drawing goes to framebuffer objects; the default framebuffer is a small dummy.
    if (!OSMesaMakeCurrent(ctx_, dummy_.data(), GL_UNSIGNED_BYTE, kDummy, kDummy))
      throw InputError("--gl osmesa: cannot make the context current (OSMesaMakeCurrent)");
  }
  std::string description() const override { return describe(*this, "OSMesa"); }

 private:
  static constexpr int kDummy = 4;
  OSMesaContext ctx_ = nullptr;
  std::vector<unsigned char> dummy_ = std::vector<unsigned char>(kDummy * kDummy * 4);
};

class EglContext final : public GlContext {
 public:
  EglContext() {
    const char* ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!ext || !std::strstr(ext, "EGL_MESA_platform_surfaceless"))
      throw InputError("--gl egl: EGL_MESA_platform_surfaceless is not available (Mesa's libEGL needed)");
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) throw InputError("--gl egl: eglGetPlatformDisplayEXT is missing");
    dpy_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (dpy_ == EGL_NO_DISPLAY || !eglInitialize(dpy_, &major, &minor))
      throw InputError("--gl egl: cannot initialize the surfaceless display (eglInitialize)");
    if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(EGL_OPENGL_API)");
    const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (!eglChooseConfig(dpy_, config_attribs, &config, 1, &n) || n < 1) config = nullptr;  // EGL_KHR_no_config_context
    const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    ctx_ = eglCreateContext(dpy_, config, EGL_NO_CONTEXT, ctx_attribs);
    if (ctx_ == EGL_NO_CONTEXT) fail("cannot create an OpenGL 3.3 core context (eglCreateContext)");
    make_current();
  }
  ~EglContext() override {
    if (dpy_ != EGL_NO_DISPLAY) {
      eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      if (ctx_ != EGL_NO_CONTEXT) eglDestroyContext(dpy_, ctx_);
      eglTerminate(dpy_);
    }
  }
  void* proc(const char* name) const override { return reinterpret_cast<void*>(eglGetProcAddress(name)); }
  void make_current() override {
    if (!eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx_))
      fail("cannot make the context current without a surface (eglMakeCurrent)");
  }
  std::string description() const override { return describe(*this, "EGL surfaceless"); }

 private:
  [[noreturn]] void fail(const std::string& what) {
    const EGLint e = eglGetError();
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", static_cast<unsigned>(e));
    if (dpy_ != EGL_NO_DISPLAY) {
      if (ctx_ != EGL_NO_CONTEXT) eglDestroyContext(dpy_, ctx_);
      eglTerminate(dpy_);
      dpy_ = EGL_NO_DISPLAY;
    }
    throw InputError("--gl egl: " + what + " failed, EGL error " + code);
  }
  EGLDisplay dpy_ = EGL_NO_DISPLAY;
  EGLContext ctx_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<GlContext> create_gl_context(GlBackend backend) {
  if (backend == GlBackend::osmesa) return std::make_unique<OsmesaContext>();
  return std::make_unique<EglContext>();
}

}  // namespace squeeze::render
