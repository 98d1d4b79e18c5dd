#include "squeeze/render/renderer.h"

#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "squeeze/common/error.h"
#include "squeeze/render/gl_context.h"

namespace squeeze::render {

namespace {

// The GL 3.3 core functions used here, loaded through GlContext::proc.
#define SQUEEZE_GL_FUNCTIONS(X)                                                                          \
  X(PFNGLGETSTRINGPROC, GetString) X(PFNGLGETINTEGERVPROC, GetIntegerv) X(PFNGLGETERRORPROC, GetError)    \
  X(PFNGLGENBUFFERSPROC, GenBuffers) X(PFNGLBINDBUFFERPROC, BindBuffer) X(PFNGLBUFFERDATAPROC, BufferData) \
  X(PFNGLBUFFERSUBDATAPROC, BufferSubData) X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                       \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays) X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)               \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                                                      \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                                                     \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)                                             \
  X(PFNGLVERTEXATTRIB3FPROC, VertexAttrib3f)                                                               \
  X(PFNGLCREATESHADERPROC, CreateShader) X(PFNGLSHADERSOURCEPROC, ShaderSource)                           \
  X(PFNGLCOMPILESHADERPROC, CompileShader) X(PFNGLGETSHADERIVPROC, GetShaderiv)                           \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog) X(PFNGLDELETESHADERPROC, DeleteShader)                   \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram) X(PFNGLATTACHSHADERPROC, AttachShader)                         \
  X(PFNGLLINKPROGRAMPROC, LinkProgram) X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                             \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog) X(PFNGLUSEPROGRAMPROC, UseProgram)                     \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram) X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)             \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv) X(PFNGLUNIFORM3FVPROC, Uniform3fv)                       \
  X(PFNGLUNIFORM1IPROC, Uniform1i) X(PFNGLUNIFORM1FPROC, Uniform1f)                                       \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)               \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                                                      \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)                                                  \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)                                            \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)                                              \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)           \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)                                                    \
  X(PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC, RenderbufferStorageMultisample)                              \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer) X(PFNGLGENTEXTURESPROC, GenTextures)                       \
  X(PFNGLBINDTEXTUREPROC, BindTexture) X(PFNGLDELETETEXTURESPROC, DeleteTextures)                         \
  X(PFNGLTEXIMAGE2DPROC, TexImage2D) X(PFNGLTEXPARAMETERIPROC, TexParameteri)                             \
  X(PFNGLTEXPARAMETERFVPROC, TexParameterfv) X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                     \
  X(PFNGLVIEWPORTPROC, Viewport) X(PFNGLCLEARPROC, Clear) X(PFNGLCLEARCOLORPROC, ClearColor)              \
  X(PFNGLENABLEPROC, Enable) X(PFNGLDISABLEPROC, Disable) X(PFNGLDRAWELEMENTSPROC, DrawElements)          \
  X(PFNGLDRAWARRAYSPROC, DrawArrays) X(PFNGLREADPIXELSPROC, ReadPixels)                                   \
  X(PFNGLPOLYGONOFFSETPROC, PolygonOffset) X(PFNGLCULLFACEPROC, CullFace) X(PFNGLDEPTHFUNCPROC, DepthFunc)                               \
  X(PFNGLDEPTHMASKPROC, DepthMask) X(PFNGLBLENDFUNCPROC, BlendFunc) X(PFNGLPIXELSTOREIPROC, PixelStorei)  \
  X(PFNGLDRAWBUFFERPROC, DrawBuffer) X(PFNGLREADBUFFERPROC, ReadBuffer) X(PFNGLFINISHPROC, Finish)

struct Gl {
#define SQUEEZE_GL_MEMBER(type, name) type name = nullptr;
  SQUEEZE_GL_FUNCTIONS(SQUEEZE_GL_MEMBER)
#undef SQUEEZE_GL_MEMBER
  void load(const GlContext& c) {
#define SQUEEZE_GL_LOAD(type, name)                                                 \
  name = reinterpret_cast<type>(c.proc("gl" #name));                                 \
  if (!name) throw InputError("OpenGL: function gl" #name " is missing (OpenGL 3.3 core needed)");
    SQUEEZE_GL_FUNCTIONS(SQUEEZE_GL_LOAD)
#undef SQUEEZE_GL_LOAD
  }
};

const char* kMeshVS = R"(#version 330 core
layout(location = 0) in vec3 pos;
layout(location = 1) in vec3 nrm;
uniform mat4 view_proj;
uniform mat4 light_vp;
uniform float depth_shift;
out vec3 v_pos;
out vec3 v_nrm;
out vec4 v_light;
void main() {
  v_pos = pos;
  v_nrm = nrm;
  v_light = light_vp * vec4(pos, 1.0);
  gl_Position = view_proj * vec4(pos, 1.0);
  gl_Position.z -= depth_shift * gl_Position.w;
}
)";

// One source, four programs (no run-time branches: llvmpipe would evaluate every path for every
// fragment): MESH (two-sided, shadows, specular), FLOOR (checkered ground fading into the
// background, shadows unless NO_SHADOW), LINES (flat colour).
const char* kMeshFS = R"(
in vec3 v_pos;
in vec3 v_nrm;
in vec4 v_light;
uniform vec3 colour;
uniform vec3 light_dir;
uniform vec3 eye;
uniform vec3 background;
uniform vec3 floor_centre;
uniform float floor_cell;
uniform float floor_radius;
uniform float shininess;
uniform float alpha;
uniform float texel;
uniform sampler2DShadow shadow_map;
out vec4 frag;
float lit_fraction(vec3 n) {
#ifdef NO_SHADOW
  return 1.0;
#else
  vec3 p = v_light.xyz / v_light.w * 0.5 + 0.5;
  float z = min(p.z, 1.0) - texel * (1.0 + 2.0 * (1.0 - abs(dot(n, light_dir))));
  // One bilinear (2x2 percentage-closer) tap; outside the map (clamped to its edge, cleared to
  // the far plane) counts as lit. Four taps looked barely softer and cost llvmpipe ~25 % more.
  return texture(shadow_map, vec3(p.xy, z));
#endif
}
void main() {
#if defined(LINES)
  frag = vec4(colour, alpha);
#elif defined(FLOOR)
  vec2 q = floor((v_pos.xz - floor_centre.xz) / floor_cell);
  vec3 base = colour * colour * (mod(q.x + q.y, 2.0) < 0.5 ? 1.0 : 0.86);  // sRGB -> linear (gamma 2)
  float ndl = max(light_dir.y, 0.0);
  vec3 c = sqrt(base * (vec3(0.30, 0.32, 0.36) + lit_fraction(vec3(0.0, 1.0, 0.0)) * 0.85 * ndl));
  float d = length(v_pos.xz - floor_centre.xz);
  frag = vec4(mix(c, background, smoothstep(0.25 * floor_radius, floor_radius, d)), alpha);
#else
  vec3 n = normalize(v_nrm);
  if (!gl_FrontFacing) n = -n;
  vec3 base = colour * colour;  // sRGB -> linear (gamma 2)
  float ndl = max(dot(n, light_dir), 0.0);
  float sh = lit_fraction(n);
  vec3 ambient = base * mix(vec3(0.16, 0.15, 0.14), vec3(0.30, 0.32, 0.36), 0.5 + 0.5 * n.y);
  vec3 h = normalize(light_dir + normalize(eye - v_pos));
  vec3 c = ambient + sh * (base * (0.85 * ndl) + shininess * pow(max(dot(n, h), 0.0), 40.0));
  frag = vec4(sqrt(c), alpha);  // linear -> sRGB (gamma 2)
#endif
}
)";

const char* kDepthVS = R"(#version 330 core
layout(location = 0) in vec3 pos;
uniform mat4 light_vp;
void main() { gl_Position = light_vp * vec4(pos, 1.0); }
)";
const char* kDepthFS = R"(#version 330 core
void main() {}
)";

using Mat4 = Eigen::Matrix4f;

Mat4 look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  const Eigen::Vector3d f = (target - eye).normalized();
  const Eigen::Vector3d s = f.cross(up).normalized();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m.cast<float>();
}

Mat4 perspective(double fov_deg, double aspect, double n, double f) {
  const double t = 1.0 / std::tan(fov_deg * M_PI / 360.0);
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (f + n) / (n - f);
  m(2, 3) = 2 * f * n / (n - f);
  m(3, 2) = -1;
  return m.cast<float>();
}

Mat4 ortho(double r, double n, double f) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = 1 / r;
  m(1, 1) = 1 / r;
  m(2, 2) = -2 / (f - n);
  m(2, 3) = -(f + n) / (f - n);
  return m.cast<float>();
}

// A mesh (or wireframe) on the GPU.
struct GpuMesh {
  GLuint vao = 0, pos = 0, nrm = 0, ebo = 0;
  int vertices = 0;
  GLsizei indices = 0;
  Eigen::Vector3f rgb;
  float shininess = 0.3f;
  bool lines = false;
  bool has_data = false;
  bool cull = false;  // closed, outward: back faces culled
};

}  // namespace

struct Renderer::Impl {
  GlContext* ctx = nullptr;
  Gl gl;
  RendererOptions opt;
  int samples = 1;
  GLuint ms_fbo = 0, ms_colour = 0, ms_depth = 0, out_fbo = 0, out_colour = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;
  GLuint prog = 0, floor_prog = 0, plain_prog = 0, lines_prog = 0, depth_prog = 0;  // meshes, ground with
                                                   // and without shadows, wireframes, shadow map
  using Mesh = GpuMesh;
  std::vector<Mesh> meshes;
  std::vector<float> scratch;
  GLuint floor_vao = 0, floor_vbo = 0;
  std::optional<double> floor;
  Eigen::AlignedBox3d bounds{Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1)};
  Camera camera;
  bool camera_set = false;
  Eigen::Vector3f background{0.90f, 0.92f, 0.95f};
  Eigen::Vector3d light_dir = Eigen::Vector3d(-0.45, 1.0, 0.55).normalized();  // towards the light

  GLuint compile(const char* vs, const char* fs, const char* fs_prefix = "") {
    auto shader = [&](GLenum type, const char* src) {
      const GLuint s = gl.CreateShader(type);
      gl.ShaderSource(s, 1, &src, nullptr);
      gl.CompileShader(s);
      GLint ok = 0;
      gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
      if (!ok) {
        char log[2048] = {0};
        gl.GetShaderInfoLog(s, sizeof log, nullptr, log);
        std::string l = log;
        std::replace(l.begin(), l.end(), '\n', ' ');
        throw std::runtime_error("OpenGL: shader compilation failed: " + l);
      }
      return s;
    };
    const std::string fs_text = std::string(fs_prefix) + fs;
    const GLuint v = shader(GL_VERTEX_SHADER, vs), f = shader(GL_FRAGMENT_SHADER, fs_text.c_str());
    const GLuint p = gl.CreateProgram();
    gl.AttachShader(p, v);
    gl.AttachShader(p, f);
    gl.LinkProgram(p);
    gl.DeleteShader(v);
    gl.DeleteShader(f);
    GLint ok = 0;
    gl.GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
      char log[2048] = {0};
      gl.GetProgramInfoLog(p, sizeof log, nullptr, log);
      throw std::runtime_error(std::string("OpenGL: shader link failed: ") + log);
    }
    return p;
  }

  GLint loc(GLuint p, const char* name) { return gl.GetUniformLocation(p, name); }

};

Renderer::Renderer(GlContext& ctx, const RendererOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& r = *impl_;
  r.ctx = &ctx;
  r.opt = options;
  r.gl.load(ctx);
  Gl& gl = r.gl;
  if (options.width < kMinImageSide || options.height < kMinImageSide || options.width > kMaxImageSide ||
      options.height > kMaxImageSide)
    throw InputError("image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     ": each side must be in [" + std::to_string(kMinImageSide) + ", " +
                     std::to_string(kMaxImageSide) + "]");
  GLint max_rb = 0, max_samples = 1, max_vp[2] = {0, 0};
  gl.GetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  gl.GetIntegerv(GL_MAX_SAMPLES, &max_samples);
  gl.GetIntegerv(GL_MAX_VIEWPORT_DIMS, max_vp);
  const int limit = std::min<int>(max_rb, std::min(max_vp[0], max_vp[1]));
  if (options.width > limit || options.height > limit)
    throw InputError("image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     ": larger than the OpenGL limit " + std::to_string(limit));
  r.samples = std::max(1, std::min(options.samples, static_cast<int>(max_samples)));

  // Multisampled target, resolved into a single-sampled one for reading.
  gl.GenFramebuffers(1, &r.ms_fbo);
  gl.GenRenderbuffers(1, &r.ms_colour);
  gl.GenRenderbuffers(1, &r.ms_depth);
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.ms_fbo);
  gl.BindRenderbuffer(GL_RENDERBUFFER, r.ms_colour);
  gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, r.samples > 1 ? r.samples : 0, GL_RGBA8, options.width,
                                    options.height);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, r.ms_colour);
  gl.BindRenderbuffer(GL_RENDERBUFFER, r.ms_depth);
  gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, r.samples > 1 ? r.samples : 0, GL_DEPTH_COMPONENT24,
                                    options.width, options.height);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, r.ms_depth);
  if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw InputError("image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     ": cannot create a multisampled framebuffer of that size (out of memory?)");
  gl.GenFramebuffers(1, &r.out_fbo);
  gl.GenRenderbuffers(1, &r.out_colour);
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.out_fbo);
  gl.BindRenderbuffer(GL_RENDERBUFFER, r.out_colour);
  gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, 0, GL_RGBA8, options.width, options.height);
  gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, r.out_colour);
  if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw InputError("image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     ": cannot create a framebuffer of that size");

  // Shadow map.
  gl.GenTextures(1, &r.shadow_tex);
  gl.BindTexture(GL_TEXTURE_2D, r.shadow_tex);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, options.shadow_size, options.shadow_size, 0,
                GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  gl.GenFramebuffers(1, &r.shadow_fbo);
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.shadow_fbo);
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, r.shadow_tex, 0);
  gl.DrawBuffer(GL_NONE);
  gl.ReadBuffer(GL_NONE);
  if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("OpenGL: incomplete shadow-map framebuffer");
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);

  r.prog = r.compile(kMeshVS, kMeshFS, "#version 330 core\n");
  r.floor_prog = r.compile(kMeshVS, kMeshFS, "#version 330 core\n#define FLOOR 1\n");
  r.plain_prog = r.compile(kMeshVS, kMeshFS, "#version 330 core\n#define FLOOR 1\n#define NO_SHADOW 1\n");
  r.lines_prog = r.compile(kMeshVS, kMeshFS, "#version 330 core\n#define LINES 1\n");
  r.depth_prog = r.compile(kDepthVS, kDepthFS);

  // The ground quad (positions set in set_floor()).
  gl.GenVertexArrays(1, &r.floor_vao);
  gl.GenBuffers(1, &r.floor_vbo);
  gl.BindVertexArray(r.floor_vao);
  gl.BindBuffer(GL_ARRAY_BUFFER, r.floor_vbo);
  gl.BufferData(GL_ARRAY_BUFFER, 8 * 3 * sizeof(float), nullptr, GL_DYNAMIC_DRAW);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  gl.EnableVertexAttribArray(0);
  gl.VertexAttrib3f(1, 0, 1, 0);
  gl.BindVertexArray(0);
}

Renderer::~Renderer() {
  Impl& r = *impl_;
  Gl& gl = r.gl;
  if (!gl.DeleteBuffers) return;
  for (auto& m : r.meshes) {
    GLuint b[3] = {m.pos, m.nrm, m.ebo};
    gl.DeleteBuffers(3, b);
    gl.DeleteVertexArrays(1, &m.vao);
  }
  gl.DeleteBuffers(1, &r.floor_vbo);
  gl.DeleteVertexArrays(1, &r.floor_vao);
  GLuint fb[3] = {r.ms_fbo, r.out_fbo, r.shadow_fbo};
  gl.DeleteFramebuffers(3, fb);
  GLuint rb[3] = {r.ms_colour, r.ms_depth, r.out_colour};
  gl.DeleteRenderbuffers(3, rb);
  gl.DeleteTextures(1, &r.shadow_tex);
  gl.DeleteProgram(r.prog);
  gl.DeleteProgram(r.plain_prog);
  gl.DeleteProgram(r.floor_prog);
  gl.DeleteProgram(r.lines_prog);
  gl.DeleteProgram(r.depth_prog);
}

int Renderer::width() const { return impl_->opt.width; }
int Renderer::height() const { return impl_->opt.height; }
int Renderer::samples() const { return impl_->samples; }

namespace {
template <class Idx>
GpuMesh make_mesh(Gl& gl, const Idx& I, int vertices, bool normals) {
  GpuMesh m;
  m.vertices = vertices;
  std::vector<GLuint> idx(static_cast<size_t>(I.size()));
  for (Eigen::Index f = 0; f < I.rows(); ++f)
    for (Eigen::Index c = 0; c < I.cols(); ++c) {
      const int v = I(f, c);
      if (v < 0 || v >= vertices) throw std::invalid_argument("Renderer: index out of range");
      idx[static_cast<size_t>(f * I.cols() + c)] = static_cast<GLuint>(v);
    }
  m.indices = static_cast<GLsizei>(idx.size());
  gl.GenVertexArrays(1, &m.vao);
  gl.BindVertexArray(m.vao);
  gl.GenBuffers(1, &m.pos);
  gl.BindBuffer(GL_ARRAY_BUFFER, m.pos);
  gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices) * 3 * sizeof(float), nullptr, GL_STREAM_DRAW);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  gl.EnableVertexAttribArray(0);
  if (normals) {
    gl.GenBuffers(1, &m.nrm);
    gl.BindBuffer(GL_ARRAY_BUFFER, m.nrm);
    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices) * 3 * sizeof(float), nullptr, GL_STREAM_DRAW);
    gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    gl.EnableVertexAttribArray(1);
  } else {
    gl.VertexAttrib3f(1, 0, 1, 0);
  }
  gl.GenBuffers(1, &m.ebo);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
  gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * sizeof(GLuint)), idx.data(),
                GL_STATIC_DRAW);
  gl.BindVertexArray(0);
  return m;
}

void upload(Gl& gl, GLuint buffer, const Eigen::MatrixX3d& M, std::vector<float>& scratch) {
  scratch.resize(static_cast<size_t>(M.rows()) * 3);
  for (Eigen::Index i = 0; i < M.rows(); ++i)
    for (int c = 0; c < 3; ++c) scratch[static_cast<size_t>(i * 3 + c)] = static_cast<float>(M(i, c));
  gl.BindBuffer(GL_ARRAY_BUFFER, buffer);
  gl.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(scratch.size() * sizeof(float)), scratch.data());
}
}  // namespace

bool is_closed_oriented(const Eigen::MatrixX3i& F) {
  if (F.rows() == 0) return false;
  std::vector<std::pair<int, int>> e;  // directed edges
  e.reserve(static_cast<size_t>(F.rows()) * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) e.emplace_back(F(f, c), F(f, (c + 1) % 3));
  std::sort(e.begin(), e.end());
  for (size_t i = 0; i < e.size(); ++i) {
    if (e[i].first == e[i].second) return false;
    if (i + 1 < e.size() && e[i] == e[i + 1]) return false;  // the same direction twice
    if (!std::binary_search(e.begin(), e.end(), std::make_pair(e[i].second, e[i].first))) return false;
  }
  return true;
}

int Renderer::add_mesh(const Eigen::MatrixX3i& F, int vertices, const Eigen::Vector3f& rgb, float shininess,
                       bool closed) {
  Impl::Mesh m = make_mesh(impl_->gl, F, vertices, true);
  m.rgb = rgb;
  m.shininess = shininess;
  m.cull = closed;
  impl_->meshes.push_back(m);
  return static_cast<int>(impl_->meshes.size()) - 1;
}

int Renderer::add_lines(const Eigen::MatrixX2i& E, int vertices, const Eigen::Vector3f& rgb) {
  Impl::Mesh m = make_mesh(impl_->gl, E, vertices, false);
  m.rgb = rgb;
  m.lines = true;
  impl_->meshes.push_back(m);
  return static_cast<int>(impl_->meshes.size()) - 1;
}

void Renderer::update_mesh(int id, const Eigen::MatrixX3d& V, const Eigen::MatrixX3d& N) {
  Impl::Mesh& m = impl_->meshes.at(static_cast<size_t>(id));
  if (V.rows() != m.vertices || N.rows() != m.vertices || m.lines)
    throw std::invalid_argument("Renderer::update_mesh: wrong vertex count");
  upload(impl_->gl, m.pos, V, impl_->scratch);
  upload(impl_->gl, m.nrm, N, impl_->scratch);
  m.has_data = true;
}

void Renderer::update_lines(int id, const Eigen::MatrixX3d& V) {
  Impl::Mesh& m = impl_->meshes.at(static_cast<size_t>(id));
  if (V.rows() != m.vertices || !m.lines) throw std::invalid_argument("Renderer::update_lines: wrong vertex count");
  upload(impl_->gl, m.pos, V, impl_->scratch);
  m.has_data = true;
}

void Renderer::set_floor(std::optional<double> height) { impl_->floor = height; }
void Renderer::set_bounds(const Eigen::AlignedBox3d& bounds) { impl_->bounds = bounds; }
void Renderer::set_camera(const Camera& camera) {
  impl_->camera = camera;
  impl_->camera_set = true;
}

Camera frame_bounds(const Eigen::AlignedBox3d& bounds, double aspect, double fov_deg, const Eigen::Vector3d& direction) {
  Camera c;
  c.fov_deg = fov_deg;
  const Eigen::Vector3d centre = bounds.center();
  const double radius = std::max(1e-6, 0.5 * bounds.diagonal().norm());
  const double half_v = fov_deg * M_PI / 360.0;
  const double half_h = std::atan(std::tan(half_v) * aspect);
  const double dist = 1.08 * radius / std::sin(std::min(half_v, half_h));
  c.target = centre;
  const Eigen::Vector3d dir = direction.norm() > 0 ? direction.normalized() : Eigen::Vector3d(0.55, 0.45, 1.0).normalized();
  c.eye = centre + dist * dir;
  c.up = std::abs(dir.y()) > 0.99 ? Eigen::Vector3d(0, 0, -1) : Eigen::Vector3d(0, 1, 0);
  return c;
}

Camera frame_points(const Eigen::MatrixX3d& P, double aspect, double fov_deg, const Eigen::Vector3d& direction,
                    double margin) {
  if (P.rows() == 0) throw InputError("camera: nothing to frame");
  const Eigen::Vector3d d = direction.normalized();  // target -> eye
  const Eigen::Vector3d up0 = std::abs(d.y()) > 0.99 ? Eigen::Vector3d(0, 0, -1) : Eigen::Vector3d(0, 1, 0);
  const Eigen::Vector3d right = up0.cross(d).normalized(), up = d.cross(right);
  const double tv = std::tan(fov_deg * M_PI / 360.0) / margin, th = tv * aspect;
  // Camera coordinates relative to the points' mean: a = along right, b = along up, z = towards the eye.
  Eigen::Vector3d c = P.colwise().mean().transpose();
  Camera cam;
  cam.fov_deg = fov_deg;
  cam.up = up0;
  // The eye at distance s from c along d; the silhouette is centred by moving c across the view,
  // then the distance is fitted again (a few rounds: the perspective couples the two).
  double s = 0;
  for (int round = 0; round < 4; ++round) {
    s = 0;
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      const Eigen::Vector3d q = P.row(i).transpose() - c;
      const double z = q.dot(d);
      s = std::max({s, z + std::abs(q.dot(right)) / th, z + std::abs(q.dot(up)) / tv});
    }
    s = std::max(s, 1e-6);
    double lo_a = 1e300, hi_a = -1e300, lo_b = 1e300, hi_b = -1e300;  // view-plane tangents
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      const Eigen::Vector3d q = P.row(i).transpose() - c;
      const double depth = std::max(1e-9, s - q.dot(d));
      lo_a = std::min(lo_a, q.dot(right) / depth), hi_a = std::max(hi_a, q.dot(right) / depth);
      lo_b = std::min(lo_b, q.dot(up) / depth), hi_b = std::max(hi_b, q.dot(up) / depth);
    }
    c += s * (0.5 * (lo_a + hi_a) * right + 0.5 * (lo_b + hi_b) * up);
  }
  s = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const Eigen::Vector3d q = P.row(i).transpose() - c;
    const double z = q.dot(d);
    s = std::max({s, z + std::abs(q.dot(right)) / th, z + std::abs(q.dot(up)) / tv});
  }
  cam.target = c;
  cam.eye = c + std::max(s, 1e-6) * d;
  return cam;
}

void Renderer::draw(Image& out) {
  Impl& r = *impl_;
  Gl& gl = r.gl;
  const int W = r.opt.width, H = r.opt.height;
  const Eigen::Vector3d centre = r.bounds.center();
  const double radius = std::max(1e-6, 0.5 * r.bounds.diagonal().norm());
  const Camera cam = r.camera_set ? r.camera : frame_bounds(r.bounds, double(W) / H);

  // Light: orthographic over the bounding sphere, from light_dir.
  const Eigen::Vector3d L = r.light_dir;
  const Eigen::Vector3d lup = std::abs(L.y()) > 0.9 ? Eigen::Vector3d(0, 0, 1) : Eigen::Vector3d(0, 1, 0);
  const Mat4 light_vp = ortho(radius * 1.05, radius * 0.5, radius * 6.0) * look_at(centre + 2.5 * radius * L, centre, lup);

  // Shadow pass (meshes only; the floor only receives).
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.shadow_fbo);
  gl.Viewport(0, 0, r.opt.shadow_size, r.opt.shadow_size);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.DepthMask(GL_TRUE);
  gl.Disable(GL_BLEND);
  gl.Disable(GL_CULL_FACE);
  gl.Clear(GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_POLYGON_OFFSET_FILL);
  gl.PolygonOffset(1.5f, 2.0f);
  gl.UseProgram(r.depth_prog);
  gl.UniformMatrix4fv(r.loc(r.depth_prog, "light_vp"), 1, GL_FALSE, light_vp.data());
  for (const Impl::Mesh& m : r.meshes) {
    if (!m.has_data || m.lines) continue;
    if (m.cull) {
      gl.Enable(GL_CULL_FACE);
      gl.CullFace(GL_FRONT);
    } else {
      gl.Disable(GL_CULL_FACE);
    }
    gl.BindVertexArray(m.vao);
    gl.DrawElements(GL_TRIANGLES, m.indices, GL_UNSIGNED_INT, nullptr);
  }
  gl.Disable(GL_CULL_FACE);
  gl.Disable(GL_POLYGON_OFFSET_FILL);

  // Main pass.
  const double dist = (cam.eye - centre).norm();
  const double floor_radius = 10 * radius;  // the ground fades into the background from 2.5 r to 10 r
  const double near = std::max(1e-4 * radius, dist - 2.0 * radius) * 0.5;
  const double far = dist + floor_radius * 1.5;
  const Mat4 view_proj = perspective(cam.fov_deg, double(W) / H, near, far) * look_at(cam.eye, cam.target, cam.up);
  gl.BindFramebuffer(GL_FRAMEBUFFER, r.ms_fbo);
  gl.Viewport(0, 0, W, H);
  gl.ClearColor(r.background.x(), r.background.y(), r.background.z(), 1);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_MULTISAMPLE);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, r.shadow_tex);
  const Eigen::Vector3f Lf = L.cast<float>(), eyef = cam.eye.cast<float>(), centref = centre.cast<float>();
  // A cell of about a tenth of the scene's size, rounded to 1, 2 or 5 × a power of ten (m).
  const double raw = 2 * radius / 10;
  const double p10 = std::pow(10.0, std::floor(std::log10(raw)));
  const double cell = raw / p10 < 2 ? p10 : raw / p10 < 5 ? 2 * p10 : 5 * p10;
  for (GLuint p : {r.plain_prog, r.floor_prog, r.prog, r.lines_prog}) {
    gl.UseProgram(p);
    gl.UniformMatrix4fv(r.loc(p, "view_proj"), 1, GL_FALSE, view_proj.data());
    gl.UniformMatrix4fv(r.loc(p, "light_vp"), 1, GL_FALSE, light_vp.data());
    gl.Uniform3fv(r.loc(p, "light_dir"), 1, Lf.data());
    gl.Uniform3fv(r.loc(p, "eye"), 1, eyef.data());
    gl.Uniform3fv(r.loc(p, "background"), 1, r.background.data());
    gl.Uniform3fv(r.loc(p, "floor_centre"), 1, centref.data());
    gl.Uniform1f(r.loc(p, "floor_radius"), static_cast<float>(floor_radius));
    gl.Uniform1f(r.loc(p, "floor_cell"), static_cast<float>(cell));
    gl.Uniform1f(r.loc(p, "texel"), 1.0f / r.opt.shadow_size);
    gl.Uniform1f(r.loc(p, "alpha"), 1.0f);
    gl.Uniform1f(r.loc(p, "depth_shift"), 0.0f);
    gl.Uniform1i(r.loc(p, "shadow_map"), 0);
  }

  if (r.floor) {
    // The ground in two parts: all of it without shadows, then the patch that the shadow map
    // covers (the light's frustum cut by the plane) with them, drawn over it: shading the shadow
    // taps only where a shadow can fall halves the cost of the ground on llvmpipe.
    const float y = static_cast<float>(*r.floor), R = static_cast<float>(floor_radius);
    const float cx = centref.x(), cz = centref.z();
    float quad[24] = {cx - R, y, cz - R, cx + R, y, cz - R, cx - R, y, cz + R, cx + R, y, cz + R};
    const Eigen::Matrix4d LV = look_at(centre + 2.5 * radius * L, centre, lup).cast<double>();
    const Eigen::Vector3d ls = LV.block<1, 3>(0, 0).transpose(), lu = LV.block<1, 3>(1, 0).transpose();
    const bool patch = L.y() > 1e-3;
    if (patch) {
      int at = 12;
      for (double b : {-1.0, 1.0})
        for (double a : {-1.0, 1.0}) {
          const Eigen::Vector3d c = centre + 1.06 * radius * (a * ls + b * lu);
          const Eigen::Vector3d q = c + (*r.floor - c.y()) / L.y() * L;
          quad[at++] = static_cast<float>(q.x());
          quad[at++] = y;
          quad[at++] = static_cast<float>(q.z());
        }
    }
    gl.BindBuffer(GL_ARRAY_BUFFER, r.floor_vbo);
    gl.BufferSubData(GL_ARRAY_BUFFER, 0, sizeof quad, quad);
    gl.BindVertexArray(r.floor_vao);
    const Eigen::Vector3f grey(0.80f, 0.80f, 0.78f);
    for (GLuint p : {r.plain_prog, r.floor_prog}) {
      if (p == r.floor_prog && !patch) break;
      gl.UseProgram(p);
      gl.Uniform3fv(r.loc(p, "colour"), 1, grey.data());
      gl.Uniform1f(r.loc(p, "shininess"), 0.0f);
      gl.DepthFunc(p == r.floor_prog ? GL_ALWAYS : GL_LESS);  // the patch lies on the ground just drawn
      gl.DrawArrays(GL_TRIANGLE_STRIP, p == r.floor_prog ? 4 : 0, 4);
    }
    gl.DepthFunc(GL_LESS);
  }
  gl.UseProgram(r.prog);
  const GLint colour = r.loc(r.prog, "colour"), shin = r.loc(r.prog, "shininess");
  for (const Impl::Mesh& m : r.meshes) {
    if (!m.has_data || m.lines) continue;
    gl.Uniform3fv(colour, 1, m.rgb.data());
    gl.Uniform1f(shin, m.shininess);
    if (m.cull) {
      gl.Enable(GL_CULL_FACE);
      gl.CullFace(GL_BACK);
    } else {
      gl.Disable(GL_CULL_FACE);
    }
    gl.BindVertexArray(m.vao);
    gl.DrawElements(GL_TRIANGLES, m.indices, GL_UNSIGNED_INT, nullptr);
  }
  gl.Disable(GL_CULL_FACE);
  // Wireframes: hidden parts faint, visible parts solid.
  bool any_lines = false;
  for (const Impl::Mesh& m : r.meshes) any_lines = any_lines || (m.lines && m.has_data);
  if (any_lines) {
    gl.UseProgram(r.lines_prog);
    gl.Enable(GL_BLEND);
    gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gl.Uniform1f(r.loc(r.lines_prog, "depth_shift"), 2e-4f);
    for (int pass = 0; pass < 2; ++pass) {
      gl.DepthFunc(pass == 0 ? GL_GREATER : GL_LEQUAL);
      gl.DepthMask(GL_FALSE);
      gl.Uniform1f(r.loc(r.lines_prog, "alpha"), pass == 0 ? 0.3f : 1.0f);
      for (const Impl::Mesh& m : r.meshes) {
        if (!m.has_data || !m.lines) continue;
        gl.Uniform3fv(r.loc(r.lines_prog, "colour"), 1, m.rgb.data());
        gl.BindVertexArray(m.vao);
        gl.DrawElements(GL_LINES, m.indices, GL_UNSIGNED_INT, nullptr);
      }
    }
    gl.DepthFunc(GL_LESS);
    gl.DepthMask(GL_TRUE);
    gl.Disable(GL_BLEND);
  }
  gl.BindVertexArray(0);

  // Resolve and read back.
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, r.ms_fbo);
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, r.out_fbo);
  gl.BlitFramebuffer(0, 0, W, H, 0, 0, W, H, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, r.out_fbo);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  out.width = W;
  out.height = H;
  out.pixels.resize(static_cast<size_t>(W) * H * 4);
  gl.ReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, out.pixels.data());
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  const GLenum err = gl.GetError();
  if (err != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", err);
    throw std::runtime_error(std::string("OpenGL error ") + code + " while drawing a frame");
  }
}

}  // namespace squeeze::render
