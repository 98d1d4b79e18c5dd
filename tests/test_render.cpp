// squeeze render (issue 7): offscreen frames (OSMesa and EGL), PNG output, the volume plot, exports,
// the render block, and the CLI end to end with its bad-input cases. Fixtures: synthetic
// trajectories (the scene's coarse meshes moved by known affine maps per frame) and a real
// `squeeze simulate` run of scenes/cube_drop.json.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <sstream>

#include "meshing_test_util.h"
#include "squeeze/common/error.h"
#include "squeeze/fem/scene.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"
#include "squeeze/render/export_formats.h"
#include "squeeze/render/exporter.h"
#include "squeeze/render/pc2_exporter.h"
#include "squeeze/render/png_io.h"
#include "squeeze/render/render.h"
#include "squeeze/render/renderer.h"
#include "squeeze/render/settings.h"
#include "squeeze/render/trajectory.h"
#include "squeeze/render/video.h"

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#if defined(__SANITIZE_ADDRESS__)
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <link.h>
#endif

namespace {
using namespace sqt;
using namespace squeeze::render;
namespace fem = squeeze::fem;
using squeeze::InputError;

const fs::path kSource = SQUEEZE_SOURCE_DIR;

#if defined(__SANITIZE_ADDRESS__)
// Under AddressSanitizer: Mesa's EGL driver (swrast_dri.so, loaded by libEGL_mesa.so at
// eglInitialize) is unloaded again at eglTerminate, and LeakSanitizer then reports the few bytes
// it never frees from "<unknown module>", which no suppression can name. This environment
// initialises the surfaceless display once, as render's GlContext does, and marks every module
// loaded by then from a dri/ folder or named libEGL_mesa as never to be unloaded (dlopen with
// RTLD_NOLOAD | RTLD_NODELETE). The driver's globals then stay mapped and its allocations stay
// reachable from them: nothing is reported (without this: 112 bytes in two indirect leaks).
class KeepEglDriverLoaded : public ::testing::Environment {
 public:
  void SetUp() override {
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) return;  // no EGL here: the EGL tests skip or fail on their own
    EGLDisplay dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor)) return;
    std::vector<std::string> names;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* out) {
          const std::string name = info->dlpi_name ? info->dlpi_name : "";
          if (name.find("/dri/") != std::string::npos || name.find("libEGL_mesa") != std::string::npos)
            static_cast<std::vector<std::string>*>(out)->push_back(name);
          return 0;
        },
        &names);
    for (const std::string& n : names) dlopen(n.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
    eglTerminate(dpy);
  }
};
const auto* const keep_egl_driver_loaded = ::testing::AddGlobalTestEnvironment(new KeepEglDriverLoaded);
#endif

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Mean and standard deviation of the luminance of a PNG's pixels.
struct PixelStats {
  double mean = 0, stddev = 0;
};
PixelStats stats_of(const PngImage& im) {
  double s = 0, s2 = 0;
  const size_t n = static_cast<size_t>(im.width) * im.height;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = &im.pixels[i * static_cast<size_t>(im.channels)];
    const double l = 0.3 * p[0] + 0.59 * p[1] + 0.11 * p[2];
    s += l;
    s2 += l * l;
  }
  PixelStats r;
  r.mean = s / n;
  r.stddev = std::sqrt(std::max(0.0, s2 / n - r.mean * r.mean));
  return r;
}
// Fraction of pixels that differ by more than 8 levels in some channel.
double changed_fraction(const PngImage& a, const PngImage& b) {
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  size_t changed = 0;
  const size_t n = static_cast<size_t>(a.width) * a.height;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      if (std::abs(int(a.pixels[i * a.channels + c]) - int(b.pixels[i * b.channels + c])) > 8) {
        ++changed;
        break;
      }
  return double(changed) / n;
}

std::vector<fs::path> pngs_in(const fs::path& dir) {
  std::vector<fs::path> v;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".png" && e.path().filename().string().rfind("frame_", 0) == 0) v.push_back(e.path());
  std::sort(v.begin(), v.end());
  return v;
}
// Colours of the curves in a PLplot SVG: every stroke colour but black (axes, text) and white
// (legend box), with how often it is used (a curve and its legend line: 2).
std::map<std::string, int> curve_colours(const fs::path& svg) {
  const std::string text = read_text(svg);
  std::map<std::string, int> colours;
  const std::string key = "stroke:rgb(";
  for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1)) {
    const std::string c = text.substr(at + key.size(), text.find(')', at) - at - key.size());
    if (c != "0%,0%,0%" && c != "100%,100%,100%") ++colours[c];
  }
  return colours;
}

bool any_temporary_in(const fs::path& dir) {
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp") != std::string::npos) return true;
  return false;
}

// Writes a trajectory of `scene` (built with fem::build_scene) in the simulate format: frame k
// holds every deformable object's rest mesh moved by motion(k, rest) (rigid objects stay).
fs::path write_trajectory(const fs::path& scene_file, const fs::path& dir, int frames, double fps,
                          const std::function<Eigen::MatrixX3d(int, const Eigen::MatrixX3d&)>& motion) {
  const fem::Scene scene = fem::load_scene(scene_file);
  const fem::SceneWorld w = fem::build_scene(scene);
  const fs::path traj = dir / "trajectory";
  fs::create_directories(traj / "rest");
  fs::create_directories(traj / "frames");
  nlohmann::json index;
  index["format"] = "squeeze-trajectory";
  index["version"] = 1;
  index["scene"] = fs::absolute(scene_file).string();
  index["fps"] = fps;
  index["time_step"] = 1e-3;
  index["frames"] = frames;
  index["frame_file"] = "frames/%06d.bin";
  index["floor"] = scene.floor ? nlohmann::json(*scene.floor) : nlohmann::json(nullptr);
  int offset = 0;
  for (size_t b = 0; b < scene.objects.size(); ++b) {
    const std::string rest = "rest/" + scene.objects[b].name + ".mesh";
    squeeze::meshing::save_tet_mesh(traj / rest, w.meshes[b]);
    index["objects"].push_back({{"name", scene.objects[b].name},
                                {"role", scene.objects[b].robot ? "robot" : "obstacle"},
                                {"kind", scene.objects[b].rigid ? "rigid" : "deformable"},
                                {"rest_mesh", rest},
                                {"vertices", w.meshes[b].V.rows()},
                                {"tets", w.meshes[b].T.rows()},
                                {"offset", offset}});
    offset += static_cast<int>(w.meshes[b].V.rows());
  }
  index["frame_vertices"] = offset;
  std::ofstream(traj / "index.json") << index.dump(2);
  for (int k = 0; k < frames; ++k) {
    std::vector<double> buf;
    for (size_t b = 0; b < scene.objects.size(); ++b) {
      const Eigen::MatrixX3d X = scene.objects[b].rigid || k == 0 ? Eigen::MatrixX3d(w.meshes[b].V) : motion(k, w.meshes[b].V);
      for (Eigen::Index i = 0; i < X.rows(); ++i)
        for (int c = 0; c < 3; ++c) buf.push_back(X(i, c));
    }
    char name[32];
    std::snprintf(name, sizeof name, "%06d.bin", k);
    std::ofstream(traj / "frames" / name, std::ios::binary)
        .write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size() * sizeof(double)));
  }
  return dir;
}

// Sphere (surface, FFD-bound) above a rigid box (tet mesh) on the floor; the sphere slides along +x
// and is squashed in y by frame k: y' = c + (y - c)·(1 - 0.03k), x' = x + 0.02k.
class RenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::make_unique<TempDir>("render");
    ::setenv("SQUEEZE_CACHE_DIR", (dir_->path() / "cache").c_str(), 1);
    fs::copy_file(kSource / "scenes" / "assets" / "cube.mesh", dir_->path() / "cube.mesh");
    fs::copy_file(data("sphere.off"), dir_->path() / "sphere.off");
  }
  fs::path scene(const std::string& render_block = "") {
    const std::string text = R"({"floor": 0.0, )" + render_block + R"( "objects": [
      {"name": "ball", "mesh": "sphere.off", "tets": 60, "role": "robot",
       "transform": {"scale": 0.1, "translate": [0, 0.35, 0]}},
      {"name": "box", "mesh": "cube.mesh", "kind": "rigid",
       "transform": {"scale": [0.3, 0.1, 0.3], "translate": [0.1, 0.05, 0]}}]})";
    const fs::path p = dir_->path() / "scene.json";
    std::ofstream(p) << text;
    return p;
  }
  static Eigen::MatrixX3d squash(int k, const Eigen::MatrixX3d& V) {
    Eigen::MatrixX3d X = V;
    const double c = V.col(1).mean();
    X.col(1) = (V.col(1).array() - c) * (1 - 0.03 * k) + c;
    X.col(0).array() += 0.02 * k;
    return X;
  }
  // Renders only the exports (no PNG, no plot) of output frames [first, last] into OUT/export.
  fs::path render_exports(const fs::path& scene_file, const fs::path& traj, const std::vector<std::string>& exports,
                          int first, int last) {
    RenderOptions o = options(scene_file, traj, "out");
    o.exports = exports;
    o.png = false;
    o.plots = false;
    o.frames = std::make_pair(first, last);
    render_trajectory(o);
    return o.output / "export";
  }
  RenderOptions options(const fs::path& scene_file, const fs::path& traj, const std::string& out) {
    RenderOptions o;
    o.scene = scene_file;
    o.trajectory = traj;
    o.output = dir_->path() / out;
    o.width = 320;
    o.height = 180;
    return o;
  }
  std::unique_ptr<TempDir> dir_;
};

TEST(RenderParse, FrameRanges) {
  EXPECT_EQ(parse_frame_range("3-7"), std::make_pair(3, 7));
  EXPECT_EQ(parse_frame_range("0-0"), std::make_pair(0, 0));
  EXPECT_EQ(parse_frame_range("12"), std::make_pair(12, 12));
  for (const char* bad : {"", "7-3", "a-b", "-3", "3-", "1-2-3", " 1-2", "99999999999-1"})
    EXPECT_NE(error_of([&] { parse_frame_range(bad); }).find("--frames"), std::string::npos) << bad;
  EXPECT_EQ(parse_gl_backend("egl"), GlBackend::egl);
  EXPECT_NE(error_of([] { parse_gl_backend("glx"); }).find("--gl: unknown backend 'glx'"), std::string::npos);
}

TEST(RenderParse, RenderBlockValidation) {
  const auto parse = [](const std::string& text) { return parse_render_settings(nlohmann::json::parse(text), "scene.json"); };
  const RenderSettings none = parse_render_settings(nlohmann::json(), "scene.json");
  EXPECT_FALSE(none.width || none.height || none.fps || none.camera);
  const RenderSettings s = parse(R"({"width": 640, "height": 480, "fps": 24,
      "camera": {"eye": [1, 2, 3], "target": [0, 0.5, 0], "fov_deg": 40}})");
  EXPECT_EQ(*s.width, 640);
  EXPECT_EQ(*s.height, 480);
  EXPECT_EQ(*s.fps, 24);
  ASSERT_TRUE(s.camera);
  EXPECT_EQ(s.camera->eye, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(s.camera->up, Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(s.camera->fov_deg, 40);
  EXPECT_EQ(error_of([&] { parse(R"({"camera": {"eye": [1,1,1], "target": [0,0,0], "fov_deg": -3}})"); }),
            "scene.json: render.camera.fov_deg: must be > 0, got -3");
  EXPECT_EQ(error_of([&] { parse(R"({"camera": {"eye": [1,1,1], "target": [0,0,0], "fov_deg": 180}})"); }),
            "scene.json: render.camera.fov_deg: must be < 180, got 180");
  EXPECT_NE(error_of([&] { parse(R"({"widht": 3})"); }).find("scene.json: render.widht: unknown key"), std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"width": 0})"); }).find("scene.json: render.width:"), std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"height": 1e9})"); }).find("scene.json: render.height:"), std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"fps": 0})"); }).find("scene.json: render.fps: must be > 0"), std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"eye": [1,1,1], "target": [1,1,1]}})"); }).find("render.camera.target"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"eye": [0,1,0], "target": [0,0,0], "up": [0,2,0]}})"); })
                .find("render.camera.up"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"target": [0,0,0]}})"); }).find("render.camera.eye: missing"),
            std::string::npos);
  // Camera presets (issue 18): a named side and the objects to frame.
  const RenderSettings p = parse(R"({"camera": {"preset": "front", "fit": ["heart", "liver"], "fov_deg": 30}})");
  EXPECT_FALSE(p.camera);
  ASSERT_TRUE(p.camera_preset);
  EXPECT_EQ(p.camera_preset->view, "front");
  EXPECT_EQ(p.camera_preset->fit, (std::vector<std::string>{"heart", "liver"}));
  // "frame" is the former name of "fit", "three_quarter" of "oblique"; both still read.
  const RenderSettings old = parse(R"({"camera": {"preset": "three_quarter", "frame": ["heart"]}})");
  EXPECT_EQ(old.camera_preset->fit, (std::vector<std::string>{"heart"}));
  EXPECT_EQ(*find_camera_view("three_quarter"), *find_camera_view("oblique"));
  EXPECT_EQ(camera_view_names(), "oblique, front, back, left, right, top");
  for (const char* v : {"oblique", "front", "back", "left", "right", "top"})
    EXPECT_EQ(parse(std::string(R"({"camera": {"preset": ")") + v + "\"}}").camera_preset->view, v);
  EXPECT_EQ(error_of([&] { parse(R"({"camera": {"preset": "side"}})"); }),
            "scene.json: render.camera.preset: must be one of oblique, front, back, left, right, top, got \"side\"");
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"preset": "top", "fit": ["a"], "frame": ["b"]}})"); })
                .find("render.camera.frame: give \"fit\" only"),
            std::string::npos);
  EXPECT_EQ(p.camera_preset->fov_deg, 30);
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"preset": "side"}})"); }).find("render.camera.preset: must be one of"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"preset": "front", "eye": [1,1,1]}})"); }).find("render.camera.eye: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"preset": "front", "frame": []}})"); }).find("render.camera.frame"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parse(R"({"camera": {"preset": "front", "fit": [3]}})"); }).find("render.camera.fit[0]"),
            std::string::npos);
  // The front view looks along -z at the bounds' centre.
  const Camera c = frame_bounds(Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1)), 1.0, 35,
                                Eigen::Vector3d(0, 0, 1));
  EXPECT_NEAR((c.eye - c.target).normalized().z(), 1.0, 1e-12);
  EXPECT_NEAR(c.target.norm(), 0.0, 1e-12);
}

TEST(RenderPng, RoundTripAndAtomicity) {
  TempDir dir("png");
  Image im;
  im.width = 37;
  im.height = 19;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      for (uint8_t v : {uint8_t(x * 5), uint8_t(y * 11), uint8_t(x ^ y), uint8_t(255)}) im.pixels.push_back(v);
  write_png(dir / "a.png", im);
  const PngImage back = read_png(dir / "a.png");
  ASSERT_EQ(back.width, 37);
  ASSERT_EQ(back.height, 19);
  ASSERT_EQ(back.channels, 3);
  // Rows come back top first: PNG row 0 is the image's last (OpenGL) row.
  for (int y = 0; y < 19; ++y)
    for (int x = 0; x < 37; ++x) {
      const uint8_t* p = &back.pixels[(static_cast<size_t>(y) * 37 + x) * 3];
      const int gy = 18 - y;
      ASSERT_EQ(p[0], uint8_t(x * 5));
      ASSERT_EQ(p[1], uint8_t(gy * 11));
      ASSERT_EQ(p[2], uint8_t(x ^ gy));
    }
  EXPECT_NE(error_of([&] { read_png(data("sphere.off")); }).find("not a valid PNG"), std::string::npos);
  // The background writer reports a failure (missing folder) and leaves nothing behind.
  PngWriter writer;
  Image copy = im;
  writer.push(dir / "missing" / "b.png", std::move(copy));
  EXPECT_THROW(writer.finish(), InputError);
  EXPECT_FALSE(any_temporary_in(dir.path()));
}

TEST(RenderExport, Pc2HeaderAndPayload) {
  TempDir dir("pc2");
  Eigen::MatrixX3d V(2, 3);
  V << 1, 2, 3, 4, 5, 6;
  {
    Pc2Writer w(dir / "a.pc2", 2, 2, 5.0f, 1.0f);
    w.append(V);
    w.append(V * 2);
    w.close();
  }
  const std::string s = read_text(dir / "a.pc2");
  ASSERT_EQ(s.size(), 32u + 2 * 2 * 3 * 4);
  EXPECT_EQ(std::memcmp(s.data(), "POINTCACHE2\0", 12), 0);
  int32_t version, points, samples;
  float start, rate, x;
  std::memcpy(&version, s.data() + 12, 4);
  std::memcpy(&points, s.data() + 16, 4);
  std::memcpy(&start, s.data() + 20, 4);
  std::memcpy(&rate, s.data() + 24, 4);
  std::memcpy(&samples, s.data() + 28, 4);
  EXPECT_EQ(version, 1);
  EXPECT_EQ(points, 2);
  EXPECT_EQ(start, 5.0f);
  EXPECT_EQ(rate, 1.0f);
  EXPECT_EQ(samples, 2);
  std::memcpy(&x, s.data() + 32 + 4 * 4, 4);  // sample 0, point 1, y
  EXPECT_EQ(x, 5.0f);
  std::memcpy(&x, s.data() + 32 + 6 * 4 + 5 * 4, 4);  // sample 1, point 1, z
  EXPECT_EQ(x, 12.0f);
  {
    Pc2Writer w(dir / "b.pc2", 2, 3);
    w.append(V);
    EXPECT_THROW(w.close(), InputError);  // 1 of 3 samples
  }
  EXPECT_FALSE(fs::exists(dir / "b.pc2"));
  EXPECT_FALSE(any_temporary_in(dir.path()));
}

// The registry is the one list of export formats: parse_exports accepts exactly its names, and
// the "unknown export" message and the --export help list every one of them.
TEST(RenderExport, RegistryDrivesParseExports) {
  const std::vector<ExportFormat>& formats = export_formats();
  ASSERT_GE(formats.size(), 4u);
  std::vector<std::string> names;
  for (const ExportFormat& f : formats) {
    EXPECT_FALSE(f.name.empty());
    EXPECT_EQ(f.name.find(','), std::string::npos) << f.name;
    EXPECT_NE(f.name, "none");
    EXPECT_FALSE(f.description.empty()) << f.name;
    EXPECT_NE(f.make(), nullptr) << f.name;
    EXPECT_EQ(find_export_format(f.name), &f);
    RenderOptions o;
    parse_exports(f.name, o);
    EXPECT_EQ(o.exports, std::vector<std::string>{f.name});
    names.push_back(f.name);
  }
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size()) << "a name registered twice";
  // The contract names (scripts use them) come first, in the order of the help; more may follow.
  const std::vector<std::string> contract{"pc2", "obj", "ply", "vtu"};
  EXPECT_TRUE(std::equal(contract.begin(), contract.end(), names.begin()));
  std::string all, listed;
  for (const std::string& n : names) {
    all += (all.empty() ? "" : ",") + n;
    listed += (listed.empty() ? "" : ", ") + n;
  }
  RenderOptions o;
  parse_exports(all + "," + names.front(), o);  // a repeated name counts once
  EXPECT_EQ(o.exports, names);
  EXPECT_EQ(make_exporters(o.exports).size(), names.size());
  for (const char* nothing : {"", "none"}) {
    RenderOptions n;
    parse_exports(nothing, n);
    EXPECT_TRUE(n.exports.empty()) << nothing;
  }
  // An unknown name: one line listing every registered name.
  const std::string e = error_of([&] {
    RenderOptions u;
    parse_exports(names.front() + ",fbx", u);
  });
  EXPECT_EQ(e, "--export " + names.front() + ",fbx: unknown export 'fbx' (" + listed + ", or none)");
  const std::string help = export_option_help();
  for (const ExportFormat& f : formats) {
    EXPECT_NE(e.find(f.name), std::string::npos) << f.name;
    EXPECT_NE(help.find(f.name + " (" + f.description + ")"), std::string::npos) << f.name;
  }
  for (const char* bad : {"none,pc2", "pc2,,obj", "PC2"})
    EXPECT_NE(error_of([&] {
                RenderOptions b;
                parse_exports(bad, b);
              }).find("unknown export"),
              std::string::npos)
        << bad;
  EXPECT_EQ(error_of([] { make_exporters({"pc2", "fbx"}); }), "exports: unknown export 'fbx' (" + listed + ")");
}

TEST_F(RenderTest, SyntheticTrajectoryFramesPlotAndExports) {
  const fs::path sc = scene();
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 11, 10.0, squash);
  RenderOptions o = options(sc, traj, "out");
  o.exports = {"pc2", "obj", "ply", "vtu"};
  o.coarse = true;
  const RenderStats st = render_trajectory(o);
  EXPECT_EQ(st.total_frames, 11);  // 1 s × 10 fps + 1
  EXPECT_EQ(st.rendered, 11);
  EXPECT_GE(st.samples, 1);
  const auto frames = pngs_in(o.output);
  ASSERT_EQ(frames.size(), 11u);
  EXPECT_EQ(frames.front().filename(), "frame_00000.png");
  EXPECT_EQ(frames.back().filename(), "frame_00010.png");
  PngImage prev;
  for (size_t k = 0; k < frames.size(); ++k) {
    const PngImage im = read_png(frames[k]);
    ASSERT_EQ(im.width, 320);
    ASSERT_EQ(im.height, 180);
    EXPECT_GT(stats_of(im).stddev, 10.0) << frames[k];  // not blank
    if (k > 0) {
      EXPECT_GT(changed_fraction(prev, im), 0.002) << frames[k];  // the ball moves
    }
    prev = im;
  }
  EXPECT_GT(fs::file_size(o.output / "volume.png"), 1000u);
  const std::string svg = read_text(o.output / "volume.svg");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  const auto curves = curve_colours(o.output / "volume.svg");
  EXPECT_EQ(curves.size(), 1u);  // the ball; the rigid box has no curve
  for (const auto& [colour, uses] : curves) EXPECT_EQ(uses, 2) << colour;
  // Exports: the ball's pc2 replays the known affine map exactly (FFD reproduces affine maps).
  const std::string pc2 = read_text(o.output / "export" / "ball.pc2");
  int32_t points = 0, samples = 0;
  std::memcpy(&points, pc2.data() + 16, 4);
  std::memcpy(&samples, pc2.data() + 28, 4);
  EXPECT_EQ(samples, 11);
  const squeeze::meshing::SurfaceMesh rest = read_off(data("sphere.off"));
  ASSERT_EQ(points, rest.V.rows());
  ASSERT_EQ(pc2.size(), 32u + size_t(points) * 3 * 4 * 11);
  // World rest positions: transform of sphere.off (scale 0.1, +0.35 y).
  const Eigen::MatrixX3d W0 = (rest.V * 0.1).rowwise() + Eigen::RowVector3d(0, 0.35, 0);
  // The coarse mesh's mean y is not the surface's: compare displacements along x, exact for every vertex.
  for (int k : {0, 4, 10}) {
    double max_err = 0;
    for (Eigen::Index i = 0; i < W0.rows(); ++i) {
      float x;
      std::memcpy(&x, pc2.data() + 32 + (size_t(k) * points + i) * 12, 4);
      max_err = std::max(max_err, std::abs(x - (W0(i, 0) + 0.02 * k)));
    }
    EXPECT_LT(max_err, 1e-5) << "frame " << k;
  }
  for (const char* f : {"export/ball.obj", "export/box.obj", "export/box.pc2", "export/obj/ball_00000.obj",
                        "export/obj/box_00010.obj", "export/ply/ball_00005.ply", "export/vtu/ball_00010.vtu",
                        "export/ball.pvd", "export/box.pvd"})
    EXPECT_TRUE(fs::exists(o.output / f)) << f;
  const squeeze::meshing::TetMesh v10 = squeeze::meshing::load_tet_mesh(o.output / "export" / "vtu" / "ball_00010.vtu");
  const squeeze::meshing::TetMesh r0 = squeeze::meshing::load_tet_mesh(traj / "trajectory" / "rest" / "ball.mesh");
  EXPECT_LT((v10.V - squash(10, r0.V)).cwiseAbs().maxCoeff(), 1e-9);
  const std::string pvd = read_text(o.output / "export" / "ball.pvd");
  EXPECT_NE(pvd.find("timestep=\"1\" group=\"\" part=\"0\" file=\"vtu/ball_00010.vtu\""), std::string::npos);
  EXPECT_FALSE(any_temporary_in(o.output));
}

// An exporter of a format that is not registered: a point cache of the surfaces that throws in
// frame `fail_at` after appending to its stream.
class ThrowingExporter final : public Exporter {
 public:
  explicit ThrowingExporter(int fail_at) : fail_at_(fail_at) {}
  void begin(const ExportContext& c) override {
    writer_ = std::make_unique<Pc2Writer>(c.folder / "throwing.pc2", static_cast<int>(c.objects[0].rest.rows()),
                                          c.frame_count);
  }
  void frame(int k, double, const std::vector<ExportState>& states) override {
    writer_->append(states[0].surface);
    if (k == fail_at_) throw InputError("throwing.pc2: disk full at frame " + std::to_string(k));
  }
  void finish() override { writer_->close(); }

 private:
  int fail_at_;
  std::unique_ptr<Pc2Writer> writer_;
};

// An exception in the middle of the frames (here an exporter's frame()) leaves no temporary and no
// partial file: no point cache or .pvd index covering only some frames, every file present complete.
TEST_F(RenderTest, ExporterThrowingMidwayLeavesNoPartialFile) {
  const fs::path sc = scene();
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 11, 10.0, squash);
  RenderOptions o = options(sc, traj, "out");
  o.exports = {"pc2", "obj", "vtu"};
  o.plots = false;
  std::vector<std::unique_ptr<Exporter>> more;
  more.push_back(std::make_unique<ThrowingExporter>(3));
  int frames_done = 0;
  o.on_frame = [&](const FrameProgress& p) { frames_done = p.done; };
  EXPECT_EQ(error_of([&] { render_trajectory(o, std::move(more)); }), "throwing.pc2: disk full at frame 3");
  EXPECT_EQ(frames_done, 3);  // frames 0-2 went through, frame 3 threw
  ASSERT_TRUE(fs::is_directory(o.output / "export"));
  EXPECT_FALSE(any_temporary_in(o.output));
  int objs = 0, vtus = 0;
  for (const auto& e : fs::recursive_directory_iterator(o.output)) {
    const std::string ext = e.path().extension().string();
    EXPECT_NE(ext, ".pc2") << e.path();  // unfinished streams are removed
    EXPECT_NE(ext, ".pvd") << e.path();  // indexes are written by finish() only
    if (ext == ".obj") {
      EXPECT_GT(squeeze::meshing::load_surface(e.path()).F.rows(), 0) << e.path();
      ++objs;
    }
    if (ext == ".vtu") {
      EXPECT_GT(squeeze::meshing::load_tet_mesh(e.path()).T.rows(), 0) << e.path();
      ++vtus;
    }
  }
  EXPECT_EQ(objs, 2 + 2 * 4);  // the rest OBJs of pc2 (written by begin()), frames 0-3 of obj
  EXPECT_EQ(vtus, 2 * 4);      // frames 0-3
}

TEST_F(RenderTest, FrameRangeRenderFpsAndSceneCamera) {
  const fs::path sc = scene(R"("render": {"fps": 20, "camera": {"eye": [0.3, 0.6, 1.4], "target": [0, 0.2, 0]}},)");
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 11, 10.0, squash);
  RenderOptions o = options(sc, traj / "trajectory", "out");  // the trajectory/ folder itself
  o.frames = std::make_pair(5, 8);
  o.plots = false;
  const RenderStats st = render_trajectory(o);
  EXPECT_EQ(st.total_frames, 21);  // 1 s × 20 fps + 1
  EXPECT_EQ(st.rendered, 4);
  const auto frames = pngs_in(o.output);
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_EQ(frames.front().filename(), "frame_00005.png");
  EXPECT_EQ(frames.back().filename(), "frame_00008.png");
  EXPECT_FALSE(fs::exists(o.output / "volume.png"));
  o.frames = std::make_pair(5, 21);
  EXPECT_EQ(error_of([&] { render_trajectory(o); }), "--frames 5-21: the path has 21 frames (0-20)");
}

TEST_F(RenderTest, OsmesaAndEglDrawTheSameFrame) {
  const fs::path sc = scene();
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 2, 10.0, squash);
  PngImage images[2];
  for (GlBackend b : {GlBackend::osmesa, GlBackend::egl}) {
    RenderOptions o = options(sc, traj, std::string("out-") + gl_backend_name(b));
    o.gl = b;
    o.plots = false;
    const RenderStats st = render_trajectory(o);
    EXPECT_NE(st.gl.find(b == GlBackend::osmesa ? "OSMesa" : "EGL"), std::string::npos) << st.gl;
    images[b == GlBackend::egl] = read_png(o.output / "frame_00001.png");
  }
  EXPECT_GT(stats_of(images[0]).stddev, 10.0);
  EXPECT_LT(changed_fraction(images[0], images[1]), 0.01);  // both llvmpipe: (nearly) identical
}

TEST_F(RenderTest, RejectsATrajectoryOfAnotherScene) {
  const fs::path sc = scene();
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 2, 10.0, squash);
  // Same objects, the box moved: rest meshes differ.
  std::string text = read_text(sc);
  text.replace(text.find("[0.1, 0.05, 0]"), 14, "[0.5, 0.05, 0]");
  std::ofstream(dir_->path() / "moved.json") << text;
  EXPECT_NE(error_of([&] { render_trajectory(options(dir_->path() / "moved.json", traj, "o1")); })
                .find("not a trajectory of"),
            std::string::npos);
  // Another object name.
  text = read_text(sc);
  text.replace(text.find("\"box\""), 5, "\"crate\"");
  std::ofstream(dir_->path() / "renamed.json") << text;
  EXPECT_NE(error_of([&] { render_trajectory(options(dir_->path() / "renamed.json", traj, "o2")); })
                .find("object 1 is 'box', the scene's is 'crate'"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(dir_->path() / "o1"));
  EXPECT_FALSE(fs::exists(dir_->path() / "o2"));
  // A truncated frame: one-line error naming the frame file.
  fs::resize_file(traj / "trajectory" / "frames" / "000001.bin", 24);
  EXPECT_NE(error_of([&] { render_trajectory(options(sc, traj, "o3")); }).find("000001.bin: expected"),
            std::string::npos);
}

// The CLI on a real simulation of the bundled cube scene at 1280x720.
TEST(RenderCli, CubeDropEndToEndAndBadInput) {
  TempDir dir("render-cli");
  ::setenv("SQUEEZE_CACHE_DIR", (dir.path() / "cache").c_str(), 1);
  const std::string scene = (kSource / "scenes" / "cube_drop.json").string();
  RunResult r = run_squeeze({"-q", "simulate", scene, "--duration", "0.3", "--fps", "10", "-o", "sim"}, dir.path(), 300);
  ASSERT_EQ(r.code, 0) << r.err;
  r = run_squeeze({"render", scene, "sim", "-o", "frames", "--width", "1280", "--height", "720"}, dir.path(), 300);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto frames = pngs_in(dir / "frames");
  ASSERT_EQ(frames.size(), 4u);  // 0.3 s × 10 fps + 1
  PngImage prev;
  for (size_t k = 0; k < frames.size(); ++k) {
    const PngImage im = read_png(frames[k]);
    ASSERT_EQ(im.width, 1280);
    ASSERT_EQ(im.height, 720);
    EXPECT_GT(stats_of(im).stddev, 10.0);
    if (k > 0) {
      EXPECT_GT(changed_fraction(prev, im), 0.001) << frames[k];  // falling
    }
    prev = im;
  }
  EXPECT_TRUE(fs::exists(dir / "frames" / "volume.png"));
  EXPECT_TRUE(fs::exists(dir / "frames" / "volume.svg"));
  // Issue 20: the manifest, written last, lists what the render completed.
  {
    const nlohmann::json m = nlohmann::json::parse(read_text(dir / "frames" / "render-manifest.json"));
    EXPECT_EQ(m["format"], "squeeze-render-manifest");
    EXPECT_EQ(m["frames"]["first"], 0);
    EXPECT_EQ(m["frames"]["last"], 3);
    ASSERT_EQ(m["frames"]["files"].size(), 4u);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(dir / "frames" / m["frames"]["files"][k].get<std::string>(), frames[k]);
    EXPECT_EQ(m["plots"], nlohmann::json({"volume.png", "volume.svg"}));
    EXPECT_TRUE(m["exports"].empty());
  }
  // Rendering a sub-range into the same folder replaces it as a whole (common/atomic_file.h): the
  // other frames are carried over, the manifest lists this run's frames and exports, no staging folder is left.
  r = run_squeeze({"-q", "render", scene, "sim", "-o", "frames", "--width", "64", "--height", "48", "--frames", "2-3",
                   "--export", "obj", "--no-plots"},
                  dir.path(), 300);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(pngs_in(dir / "frames").size(), 4u);
  EXPECT_EQ(read_png(dir / "frames" / "frame_00000.png").width, 1280);  // carried over
  EXPECT_EQ(read_png(dir / "frames" / "frame_00002.png").width, 64);    // this run's
  {
    const nlohmann::json m = nlohmann::json::parse(read_text(dir / "frames" / "render-manifest.json"));
    EXPECT_EQ(m["frames"]["files"], nlohmann::json({"frame_00002.png", "frame_00003.png"}));
    EXPECT_TRUE(m["plots"].empty());
    ASSERT_FALSE(m["exports"].empty());
    for (const auto& e : m["exports"]) EXPECT_TRUE(fs::is_regular_file(dir / "frames" / e.get<std::string>())) << e;
  }
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".squeeze-"), std::string::npos) << e.path();

  // Bad input: one line "squeeze: error: ...", exit 1, no PNG written.
  const auto bad = [&](std::vector<std::string> args, const std::string& expect) {
    const RunResult b = run_squeeze(args, dir.path(), 120);
    EXPECT_EQ(b.code, 1) << b.err;
    EXPECT_EQ(lines(b.err).size(), 1u) << b.err;
    EXPECT_EQ(b.err.rfind("squeeze: error: ", 0), 0u) << b.err;
    EXPECT_NE(b.err.find(expect), std::string::npos) << b.err;
    EXPECT_FALSE(fs::exists(dir / "bad" / "frame_00000.png")) << b.err;
  };
  bad({"render", scene, "nowhere", "-o", "bad"}, "nowhere: no such trajectory folder");
  bad({"render", scene, "sim", "-o", "missing/bad"}, "does not exist");
  bad({"render", scene, "sim", "-o", "bad", "--width", "0"}, "--width 0: must be in [16, 16384]");
  bad({"render", scene, "sim", "-o", "bad", "--height", "100000"}, "--height 100000");
  bad({"render", scene, "sim", "-o", "bad", "--frames", "2-9"}, "--frames 2-9: the path has 4 frames");
  bad({"render", scene, "sim", "-o", "bad", "--gl", "vulkan"}, "--gl: unknown backend");
  bad({"render", scene, "sim", "-o", "bad", "--export", "fbx"}, "unknown export 'fbx'");
  std::ofstream(dir / "file") << "x";
  bad({"render", scene, "sim", "-o", "file"}, "exists and is not a directory");
  // A trajectory of another scene (the cube scaled differently).
  std::string text = read_text(scene);
  text.replace(text.find("\"scale\": 0.2"), 12, "\"scale\": 0.3");
  text.replace(text.find("assets/cube.mesh"), 16, (kSource / "scenes" / "assets" / "cube.mesh").string());
  std::ofstream(dir / "other.json") << text;
  bad({"render", "other.json", "sim", "-o", "bad"}, "not a trajectory of other.json");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// The bundled bunny scene end to end: simulate 1 s, render at 1280x720 (issue 7's acceptance test).
TEST(RenderCli, BunnySceneFramesAndVolumePlot) {
  TempDir dir("render-bunny");
  ::setenv("SQUEEZE_CACHE_DIR", (dir.path() / "cache").c_str(), 1);
  const std::string scene = (kSource / "scenes" / "bunny.json").string();
  RunResult r = run_squeeze({"-q", "simulate", scene, "--duration", "1", "-o", "sim"}, dir.path(), 600);
  ASSERT_EQ(r.code, 0) << r.err;
  r = run_squeeze({"-q", "render", scene, "sim", "-o", "frames"}, dir.path(), 600);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // -q
  const auto frames = pngs_in(dir / "frames");
  ASSERT_EQ(frames.size(), 31u);  // 1 s × 30 fps (render.fps) + 1
  PngImage prev;
  int moving = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    const PngImage im = read_png(frames[k]);
    ASSERT_EQ(im.width, 1280);
    ASSERT_EQ(im.height, 720);
    EXPECT_GT(stats_of(im).stddev, 10.0) << frames[k];
    // The bunny falls for ~0.15 s, bounces and settles: the first frames must all differ.
    if (k > 0 && changed_fraction(prev, im) > 0.001) ++moving;
    if (k > 0 && k <= 8) {
      EXPECT_GT(changed_fraction(prev, im), 0.001) << frames[k];
    }
    prev = im;
  }
  EXPECT_GE(moving, 8);
  ASSERT_TRUE(fs::exists(dir / "frames" / "volume.png"));
  const PngImage plot = read_png(dir / "frames" / "volume.png");
  EXPECT_GT(stats_of(plot).stddev, 10.0);
  EXPECT_EQ(curve_colours(dir / "frames" / "volume.svg").size(), 1u);  // one deformable object
}
}  // namespace

// --- Exports for offline rendering (issue 21) ---

namespace {

std::uint32_t be32(const std::string& s, size_t at) {
  return (std::uint32_t(std::uint8_t(s[at])) << 24) | (std::uint32_t(std::uint8_t(s[at + 1])) << 16) |
         (std::uint32_t(std::uint8_t(s[at + 2])) << 8) | std::uint32_t(std::uint8_t(s[at + 3]));
}
float be_float(const std::string& s, size_t at) {
  const std::uint32_t u = be32(s, at);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
float le_float(const std::string& s, size_t at) {
  float f;
  std::memcpy(&f, s.data() + at, 4);
  return f;
}

// The `v` lines of an OBJ, and whether every vertex is used by an `f` line.
Eigen::MatrixX3d obj_vertices(const fs::path& obj, bool* all_used = nullptr) {
  std::ifstream in(obj);
  std::vector<Eigen::RowVector3d> v;
  std::set<long> used;
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      Eigen::RowVector3d p;
      s >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (tag == "f") {
      for (std::string c; s >> c;) used.insert(std::stol(c.substr(0, c.find('/'))));
    }
  }
  Eigen::MatrixX3d V(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) V.row(static_cast<Eigen::Index>(i)) = v[i];
  if (all_used) *all_used = used.size() == v.size() && (v.empty() || (*used.begin() == 1 && *used.rbegin() == long(v.size())));
  return V;
}

}  // namespace

// A box whose scene mesh is a tet mesh with 27 interior nodes (cube.mesh, 5×5×5 nodes) and a
// sphere bound by FFD, both deformable: every per-vertex export (rest OBJ, .pc2, .mdd) holds exactly
// the rendered surface's vertices — the box's 98 boundary nodes, each used by a face, so Blender's
// OBJ importer keeps all of them — in the rest OBJ's order, and every frame of the caches equals
// the frame's OBJ export (squeeze's own surface) within float precision.
TEST_F(RenderTest, PointCachesHoldExactlyTheSurfaceVerticesInTheRestObjOrder) {
  const fs::path sc = dir_->path() / "deformable_box.json";
  std::ofstream(sc) << R"({"floor": 0.0, "objects": [
      {"name": "ball", "mesh": "sphere.off", "tets": 60, "role": "robot",
       "transform": {"scale": 0.1, "translate": [0, 0.35, 0]}},
      {"name": "box", "mesh": "cube.mesh", "transform": {"scale": [0.3, 0.1, 0.3], "translate": [0.1, 0.05, 0]}}]})";
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 11, 10.0, squash);
  const fs::path ex = render_exports(sc, traj, {"pc2", "mdd", "obj"}, 3, 9);
  for (const std::string name : {"ball", "box"}) {
    bool all_used = false;
    const Eigen::MatrixX3d rest = obj_vertices(ex / (name + ".obj"), &all_used);
    EXPECT_TRUE(all_used) << name << ": a vertex of the rest OBJ is used by no face";
    if (name == "box") {
      EXPECT_EQ(rest.rows(), 98) << "the 5×5×5 box has 98 boundary nodes";
    }
    const std::string pc2 = read_text(ex / (name + ".pc2")), mdd = read_text(ex / (name + ".mdd"));
    int32_t points = 0, samples = 0;
    float start = 0;
    std::memcpy(&points, pc2.data() + 16, 4);
    std::memcpy(&start, pc2.data() + 20, 4);
    std::memcpy(&samples, pc2.data() + 28, 4);
    ASSERT_EQ(points, rest.rows()) << name;
    EXPECT_EQ(samples, 7);
    EXPECT_EQ(start, 3.0f);
    // MDD: big-endian counts, then each sample's time (s), then the same points.
    ASSERT_EQ(be32(mdd, 0), 7u);
    ASSERT_EQ(be32(mdd, 4), std::uint32_t(points));
    ASSERT_EQ(mdd.size(), 8u + 7 * 4 + size_t(points) * 12 * 7);
    for (int i = 0; i < 7; ++i) EXPECT_FLOAT_EQ(be_float(mdd, 8 + 4 * i), (3 + i) / 10.0f);
    for (int k = 3; k <= 9; ++k) {
      const Eigen::MatrixX3d want = obj_vertices(ex / "obj" / frame_file_name(name + "_", k, ".obj"));
      ASSERT_EQ(want.rows(), points);
      double err_pc2 = 0, err_mdd = 0;
      for (Eigen::Index v = 0; v < points; ++v)
        for (int c = 0; c < 3; ++c) {
          const size_t at = (size_t(k - 3) * points + v) * 12 + c * 4;
          err_pc2 = std::max(err_pc2, std::abs(le_float(pc2, 32 + at) - want(v, c)));
          err_mdd = std::max(err_mdd, std::abs(be_float(mdd, 8 + 28 + at) - want(v, c)));
        }
      EXPECT_LT(err_pc2, 1e-6) << name << " frame " << k;
      EXPECT_LT(err_mdd, 1e-6) << name << " frame " << k;
    }
  }
  // The box moves (it is deformable): its last frame is not its first.
  EXPECT_GT((obj_vertices(ex / "obj" / "box_00009.obj") - obj_vertices(ex / "obj" / "box_00003.obj")).cwiseAbs().maxCoeff(),
            0.05);
}

namespace {

// The glTF file loaded with tinygltf's own reader (a second implementation of the format).
tinygltf::Model load_glb(const fs::path& path) {
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, path.string())) << err;
  return m;
}

// Accessor `a` of `m` as floats (tightly packed float accessors only, as squeeze writes them).
std::vector<float> floats(const tinygltf::Model& m, int a) {
  const tinygltf::Accessor& acc = m.accessors[static_cast<size_t>(a)];
  const tinygltf::BufferView& view = m.bufferViews[static_cast<size_t>(acc.bufferView)];
  EXPECT_EQ(acc.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  const size_t n = acc.count * static_cast<size_t>(tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type)));
  std::vector<float> out(n);
  std::memcpy(out.data(), m.buffers[static_cast<size_t>(view.buffer)].data.data() + view.byteOffset + acc.byteOffset, n * 4);
  return out;
}

std::map<std::string, Eigen::Vector3d> material_colours(const tinygltf::Model& m) {
  std::map<std::string, Eigen::Vector3d> c;
  for (const tinygltf::Mesh& mesh : m.meshes) {
    const auto& f = m.materials[static_cast<size_t>(mesh.primitives[0].material)].pbrMetallicRoughness.baseColorFactor;
    c[mesh.name] = Eigen::Vector3d(f[0], f[1], f[2]);
  }
  return c;
}

}  // namespace

// export/animation.glb: a node and mesh per object whose POSITION is the rest OBJ's vertices and
// whose morph target k moves them to frame k (base + target = the frame's OBJ export), one
// animation of the morph weights, one-hot at t_k = k / fps, LINEAR; materials in the render colours.
TEST_F(RenderTest, GlbAnimationReproducesEveryFrame) {
  const fs::path sc = scene();
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 11, 10.0, squash);
  const fs::path ex = render_exports(sc, traj, {"glb", "obj", "pc2"}, 2, 10);
  const tinygltf::Model m = load_glb(ex / "animation.glb");
  ASSERT_EQ(m.meshes.size(), 2u);
  ASSERT_EQ(m.nodes.size(), 2u);
  ASSERT_EQ(m.animations.size(), 1u);
  const tinygltf::Animation& anim = m.animations[0];
  ASSERT_EQ(anim.channels.size(), 2u);
  for (const tinygltf::AnimationChannel& ch : anim.channels) {
    EXPECT_EQ(ch.target_path, "weights");
    const tinygltf::AnimationSampler& s = anim.samplers[static_cast<size_t>(ch.sampler)];
    EXPECT_EQ(s.interpolation, "LINEAR");
    const std::vector<float> t = floats(m, s.input), w = floats(m, s.output);
    ASSERT_EQ(t.size(), 9u);
    ASSERT_EQ(w.size(), 81u);
    for (int i = 0; i < 9; ++i) {
      EXPECT_FLOAT_EQ(t[size_t(i)], (2 + i) / 10.0f);
      for (int j = 0; j < 9; ++j) EXPECT_EQ(w[size_t(i * 9 + j)], i == j ? 1.0f : 0.0f);
    }
  }
  for (size_t n = 0; n < m.nodes.size(); ++n) {
    const tinygltf::Mesh& mesh = m.meshes[static_cast<size_t>(m.nodes[n].mesh)];
    EXPECT_EQ(m.nodes[n].name, mesh.name);
    const tinygltf::Primitive& prim = mesh.primitives.at(0);
    const std::vector<float> base = floats(m, prim.attributes.at("POSITION"));
    const Eigen::MatrixX3d rest = obj_vertices(ex / (mesh.name + ".obj"));
    ASSERT_EQ(base.size(), size_t(rest.rows()) * 3) << mesh.name;
    ASSERT_EQ(prim.targets.size(), 9u);
    for (int k = 2; k <= 10; ++k) {
      const std::vector<float> d = floats(m, prim.targets[size_t(k - 2)].at("POSITION"));
      const Eigen::MatrixX3d want = obj_vertices(ex / "obj" / frame_file_name(mesh.name + "_", k, ".obj"));
      double err = 0;
      for (Eigen::Index v = 0; v < want.rows(); ++v)
        for (int c = 0; c < 3; ++c) err = std::max(err, std::abs(base[size_t(v * 3 + c)] + d[size_t(v * 3 + c)] - want(v, c)));
      EXPECT_LT(err, 1e-6) << mesh.name << " frame " << k;
    }
  }
}

// Colours: an object's `color` (a name or [r, g, b]) wins; without one, an object keeps its default
// colour whatever the other objects are and in whatever order they come (stable per name).
TEST_F(RenderTest, ColoursAreTheSceneKeyElseStablePerObjectName) {
  const auto colours_of = [&](const std::string& objects, const std::string& tag) {
    const fs::path sc = dir_->path() / (tag + ".json");
    std::ofstream(sc) << R"({"floor": 0.0, "objects": [)" + objects + "]}";
    const fs::path traj = write_trajectory(sc, dir_->path() / ("sim_" + tag), 2, 10.0, squash);
    RenderOptions o = options(sc, traj, "out_" + tag);
    o.exports = {"glb"};
    o.png = false;
    o.plots = false;
    render_trajectory(o);
    return material_colours(load_glb(o.output / "export" / "animation.glb"));
  };
  const std::string ball = R"({"name": "ball", "mesh": "sphere.off", "tets": 60, "transform": {"scale": 0.1, "translate": [0, 0.35, 0]}})";
  const std::string box = R"({"name": "box", "mesh": "cube.mesh", "kind": "rigid", "transform": {"scale": 0.2, "translate": [0.5, 0.1, 0]}})";
  const std::string ball2 = R"({"name": "other", "mesh": "sphere.off", "tets": 60, "transform": {"scale": 0.1, "translate": [-0.5, 0.35, 0]}})";
  const auto a = colours_of(ball + "," + box, "a");
  const auto b = colours_of(ball2 + "," + box + "," + ball, "b");  // another object first, the order changed
  EXPECT_EQ(a.at("ball"), b.at("ball"));
  EXPECT_EQ(a.at("box"), b.at("box"));
  EXPECT_NE(a.at("ball"), a.at("box"));     // deformable and rigid look different
  EXPECT_NE(b.at("ball"), b.at("other"));   // two deformable objects never share a colour
  const std::string red_ball = R"({"name": "ball", "color": "red", "mesh": "sphere.off", "tets": 60,
      "transform": {"scale": 0.1, "translate": [0, 0.35, 0]}})";
  const std::string teal_box = R"({"name": "box", "color": [0.1, 0.5, 0.5], "mesh": "cube.mesh", "kind": "rigid",
      "transform": {"scale": 0.2, "translate": [0.5, 0.1, 0]}})";
  const auto c = colours_of(red_ball + "," + teal_box, "c");
  EXPECT_LT((c.at("ball") - Eigen::Vector3d(1, 0, 0)).norm(), 1e-6);
  EXPECT_LT((c.at("box") - Eigen::Vector3d(0.1, 0.5, 0.5)).norm(), 1e-6);
}

TEST(SceneColor, NamesTriplesAndErrors) {
  TempDir dir("color");
  fs::copy_file(data("sphere.off"), dir.path() / "s.off");
  const auto load = [&](const std::string& color) {
    const fs::path p = dir.path() / "c.json";
    std::ofstream(p) << R"({"objects": [{"name": "a", "mesh": "s.off", "color": )" + color + "}]}";
    return fem::load_scene(p);
  };
  EXPECT_EQ(*load(R"("Blue")").objects[0].color, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(*load("[0.25, 0.5, 1]").objects[0].color, Eigen::Vector3d(0.25, 0.5, 1));
  EXPECT_FALSE(fem::load_scene([&] {
                 const fs::path p = dir.path() / "n.json";
                 std::ofstream(p) << R"({"objects": [{"name": "a", "mesh": "s.off"}]})";
                 return p;
               }())
                   .objects[0]
                   .color);
  EXPECT_NE(error_of([&] { load(R"("blurple")"); }).find("objects[0].color: unknown colour \"blurple\""), std::string::npos);
  EXPECT_NE(error_of([&] { load("[1, 2, 0]"); }).find("objects[0].color[1]: must be in [0, 1], got 2"), std::string::npos);
  EXPECT_NE(error_of([&] { load("[1, 0]"); }).find("objects[0].color"), std::string::npos);
  EXPECT_NE(error_of([&] { load("7"); }).find("objects[0].color: must be [r, g, b]"), std::string::npos);
}

namespace {

// Frame count (the video track's sample count, box `stsz`) and size (its `avc1` sample entry) of an
// MP4, read from the file's boxes (ISO/IEC 14496-12 §8.7.3, 14496-15 §5.4.2).
struct Mp4Info {
  long frames = -1;
  int width = 0, height = 0;
};
Mp4Info mp4_info(const fs::path& path) {
  const std::string s = read_text(path);
  Mp4Info info;
  const size_t stsz = s.find("stsz"), avc1 = s.find("avc1", s.find("stsd"));  // the sample entry, not a brand
  if (stsz != std::string::npos) info.frames = long(be32(s, stsz + 12));
  if (avc1 != std::string::npos) {
    info.width = (std::uint8_t(s[avc1 + 28]) << 8) | std::uint8_t(s[avc1 + 29]);
    info.height = (std::uint8_t(s[avc1 + 30]) << 8) | std::uint8_t(s[avc1 + 31]);
  }
  return info;
}

}  // namespace

TEST(RenderVideo, WritesEveryFrameAtTheFramesSize) {
  if (!video_available()) GTEST_SKIP() << "no H.264 encoder in this FFmpeg";
  TempDir dir("video");
  Image im;
  im.width = 96;
  im.height = 64;
  {
    VideoWriter v(dir.path() / "a.mp4", 96, 64, 30.0);
    for (int k = 0; k < 17; ++k) {
      im.pixels.assign(size_t(96) * 64 * 4, 255);
      for (int y = 0; y < 64; ++y) im.pixels[(size_t(y) * 96 + (k * 5) % 96) * 4] = 0;  // a moving line
      v.add(im);
    }
    EXPECT_FALSE(fs::exists(dir.path() / "a.mp4"));  // only under a temporary name until finish()
    v.finish();
    EXPECT_EQ(v.frames(), 17);
  }
  const Mp4Info a = mp4_info(dir.path() / "a.mp4");
  EXPECT_EQ(a.frames, 17);
  EXPECT_EQ(a.width, 96);
  EXPECT_EQ(a.height, 64);
  // An unfinished video leaves nothing; a wrong-size frame is an error naming the file.
  {
    VideoWriter v(dir.path() / "b.mp4", 96, 64, 24.0);
    v.add(im);
    Image small;
    small.width = 32;
    small.height = 32;
    small.pixels.assign(size_t(32) * 32 * 4, 0);
    EXPECT_NE(error_of([&] { v.add(small); }).find("b.mp4: a frame of 32x32 in a 96x64 video"), std::string::npos);
  }
  for (const auto& e : fs::directory_iterator(dir.path())) EXPECT_EQ(e.path().filename(), "a.mp4");
}

// render_trajectory with a video: as many video frames as PNG frames, at their size; --camera
// presets change the view, and an unknown one is an error naming the option.
TEST_F(RenderTest, VideoMatchesThePngFramesAndCameraPresetsApply) {
  if (!video_available()) GTEST_SKIP() << "no H.264 encoder in this FFmpeg";
  const fs::path sc = scene();
  const fs::path traj = write_trajectory(sc, dir_->path() / "sim", 11, 10.0, squash);
  RenderOptions o = options(sc, traj, "out");
  o.plots = false;
  o.video = dir_->path() / "out.mp4";
  const RenderStats st = render_trajectory(o);
  EXPECT_EQ(st.video, o.video.string());
  const Mp4Info info = mp4_info(o.video);
  EXPECT_EQ(info.frames, long(pngs_in(o.output).size()));
  EXPECT_EQ(info.width, 320);
  EXPECT_EQ(info.height, 180);

  RenderOptions top = options(sc, traj, "top");
  top.plots = false;
  top.frames = std::make_pair(0, 0);
  top.camera = "top";
  render_trajectory(top);
  EXPECT_GT(changed_fraction(read_png(o.output / "frame_00000.png"), read_png(top.output / "frame_00000.png")), 0.05);
  top.camera = "sideways";
  EXPECT_EQ(error_of([&] { render_trajectory(top); }),
            "--camera sideways: must be one of oblique, front, back, left, right, top");
}

// Medit files carry 17-digit doubles, so they say MeshVersionFormatted 2 (double precision):
// meshio and Gmsh then read them as float64 (version 1 means single precision). Checked with
// meshio 5.0 (Debian python3-meshio): points float64.
TEST(MeditExport, SaysDoublePrecisionAndRoundTripsExactly) {
  TempDir dir("medit");
  squeeze::meshing::TetMesh m;
  m.V.resize(4, 3);
  m.V << 0.1, 0.2, 0.30000000000000004, 1.0 / 3.0, 0, 0, 0, 1, 0, 0, 0, 1;
  m.T.resize(1, 4);
  m.T << 0, 1, 2, 3;
  squeeze::meshing::save_tet_mesh(dir.path() / "a.mesh", m);
  const std::string text = read_text(dir.path() / "a.mesh");
  EXPECT_EQ(text.rfind("MeshVersionFormatted 2\n", 0), 0u) << text.substr(0, 40);
  EXPECT_EQ(squeeze::meshing::load_tet_mesh(dir.path() / "a.mesh").V, m.V);  // bit for bit
}
