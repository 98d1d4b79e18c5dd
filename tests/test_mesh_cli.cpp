// `squeeze mesh` as a user runs it (issue 3): inputs in formats the project has never seen (made
// here from the corpus), determinism across runs and thread counts, output formats, and every bad
// input's error (one line on stderr, non-zero exit, no output or temporary file left, no crash).
#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <functional>

#include "meshing_test_util.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"

namespace {
using namespace sqt;

// ---------------------------------------------------------------------------------------------
// Surface writers of our own (assimp's exporter covers binary STL, binary PLY and glTF).

Eigen::MatrixX3d vertex_normals(const SurfaceMesh& m) {
  Eigen::MatrixX3d N = Eigen::MatrixX3d::Zero(m.V.rows(), 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::RowVector3d n =
        (m.V.row(m.F(f, 1)) - m.V.row(m.F(f, 0))).cross(m.V.row(m.F(f, 2)) - m.V.row(m.F(f, 0)));
    for (int k = 0; k < 3; ++k) N.row(m.F(f, k)) += n;
  }
  for (Eigen::Index i = 0; i < N.rows(); ++i)
    if (N.row(i).norm() > 0) N.row(i).normalize();
  return N;
}

Eigen::RowVector2d uv_of(const Eigen::RowVector3d& p, const Eigen::RowVector3d& c) {
  const Eigen::RowVector3d d = p - c;
  return {0.5 + std::atan2(d(1), d(0)) / (2 * M_PI), 0.5 + std::atan2(d(2), std::hypot(d(0), d(1))) / M_PI};
}

void write_ascii_stl(const fs::path& p, const SurfaceMesh& m) {
  std::ofstream out(p);
  out.precision(9);
  out << "solid squeeze_test\n";
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::RowVector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    Eigen::RowVector3d n = (b - a).cross(c - a);
    if (n.norm() > 0) n.normalize();
    out << "  facet normal " << n(0) << ' ' << n(1) << ' ' << n(2) << "\n    outer loop\n";
    for (const auto& v : {a, b, c}) out << "      vertex " << v(0) << ' ' << v(1) << ' ' << v(2) << '\n';
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid squeeze_test\n";
}

void write_ply(const fs::path& p, const SurfaceMesh& m, bool binary, bool normals_and_uv) {
  const Eigen::MatrixX3d N = vertex_normals(m);
  const Eigen::RowVector3d c = m.V.colwise().mean();
  std::ofstream out(p, std::ios::binary);
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment made by test_mesh_cli\n";
  out << "element vertex " << m.V.rows() << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals_and_uv) out << "property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n";
  out << "element face " << m.F.rows() << "\nproperty list uchar int vertex_indices\nend_header\n";
  out.precision(9);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    std::vector<float> v{float(m.V(i, 0)), float(m.V(i, 1)), float(m.V(i, 2))};
    if (normals_and_uv) {
      const Eigen::RowVector2d uv = uv_of(m.V.row(i), c);
      for (double x : {N(i, 0), N(i, 1), N(i, 2), uv(0), uv(1)}) v.push_back(float(x));
    }
    if (binary) {
      out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
    } else {
      for (size_t k = 0; k < v.size(); ++k) out << (k ? " " : "") << v[k];
      out << '\n';
    }
  }
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    if (binary) {
      const unsigned char three = 3;
      const int32_t idx[3] = {m.F(f, 0), m.F(f, 1), m.F(f, 2)};
      out.write(reinterpret_cast<const char*>(&three), 1);
      out.write(reinterpret_cast<const char*>(idx), sizeof idx);
    } else {
      out << "3 " << m.F(f, 0) << ' ' << m.F(f, 1) << ' ' << m.F(f, 2) << '\n';
    }
  }
}

/// OBJ with an MTL file: positions, texture coordinates and normals, faces v/vt/vn, the faces
/// split between two materials (assimp makes two meshes of it; squeeze welds them back).
/// `objects` > 1 writes that many named objects (parts) from `parts`.
void write_obj_mtl(const fs::path& p, const std::vector<SurfaceMesh>& parts) {
  const fs::path mtl = fs::path(p).replace_extension(".mtl");
  {
    std::ofstream m(mtl);
    m << "# made by test_mesh_cli\nnewmtl skin\nKa 0.1 0.1 0.1\nKd 0.6 0.5 0.4\nKs 0 0 0\nd 1\nillum 1\n\n"
         "newmtl tusk\nKd 0.9 0.9 0.8\nillum 1\n";
  }
  std::ofstream out(p);
  out.precision(17);
  out << "# made by test_mesh_cli\nmtllib " << mtl.filename().string() << "\n";
  long base = 1;
  for (size_t k = 0; k < parts.size(); ++k) {
    const SurfaceMesh& m = parts[k];
    const Eigen::MatrixX3d N = vertex_normals(m);
    const Eigen::RowVector3d c = m.V.colwise().mean();
    out << "o part" << k << "\n";
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) out << "v " << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << '\n';
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
      const Eigen::RowVector2d uv = uv_of(m.V.row(i), c);
      out << "vt " << uv(0) << ' ' << uv(1) << '\n';
    }
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) out << "vn " << N(i, 0) << ' ' << N(i, 1) << ' ' << N(i, 2) << '\n';
    for (int half = 0; half < 2; ++half) {
      out << "usemtl " << (half ? "tusk" : "skin") << "\n";
      for (Eigen::Index f = half * (m.F.rows() / 2); f < (half ? m.F.rows() : m.F.rows() / 2); ++f) {
        out << 'f';
        for (int j = 0; j < 3; ++j) {
          const long i = base + m.F(f, j);
          out << ' ' << i << '/' << i << '/' << i;
        }
        out << '\n';
      }
    }
    base += m.V.rows();
  }
}

SurfaceMesh translated(SurfaceMesh m, const Eigen::RowVector3d& t) {
  m.V.rowwise() += t;
  return m;
}

/// Drops vertices no face uses.
SurfaceMesh compact(const SurfaceMesh& m) {
  std::vector<int> map(static_cast<size_t>(m.V.rows()), -1);
  int n = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (map[m.F(f, k)] < 0) map[m.F(f, k)] = n++;
  SurfaceMesh c;
  c.V.resize(n, 3);
  for (size_t i = 0; i < map.size(); ++i)
    if (map[i] >= 0) c.V.row(map[i]) = m.V.row(static_cast<Eigen::Index>(i));
  c.F = m.F;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) c.F(f, k) = map[m.F(f, k)];
  return c;
}

// ---------------------------------------------------------------------------------------------
// Inputs in other formats.

struct Variant {
  std::string name;
  // Writes the input into `dir`; returns its file name and sets what we know about it.
  std::function<std::string(const fs::path& dir, InputTruth& truth)> make;
};

const SurfaceMesh& elephant() {
  static const SurfaceMesh m = read_off(data("elephant.off"));
  return m;
}
const SurfaceMesh& sphere() {
  static const SurfaceMesh m = read_off(data("sphere.off"));
  return m;
}

std::vector<Variant> variants() {
  return {
      {"stl_binary_elephant",
       [](const fs::path& d, InputTruth& t) {
         squeeze::meshing::save_surface(d / "elephant.stl", elephant());
         // Binary STL: 80-byte header, count, 50 bytes per triangle.
         EXPECT_EQ(fs::file_size(d / "elephant.stl"), 84u + 50u * static_cast<unsigned>(elephant().F.rows()));
         t = truth_of(elephant(), true);
         return "elephant.stl";
       }},
      {"stl_ascii_sphere",
       [](const fs::path& d, InputTruth& t) {
         write_ascii_stl(d / "sphere.stl", sphere());
         t = truth_of(sphere(), true);
         return "sphere.stl";
       }},
      {"stl_ascii_elephant",
       [](const fs::path& d, InputTruth& t) {
         write_ascii_stl(d / "elephant_ascii.stl", elephant());
         t = truth_of(elephant(), true);
         return "elephant_ascii.stl";
       }},
      {"ply_binary_normals_uv_elephant",
       [](const fs::path& d, InputTruth& t) {
         write_ply(d / "elephant.ply", elephant(), true, true);
         t = truth_of(elephant(), true);
         return "elephant.ply";
       }},
      {"ply_ascii_sphere",
       [](const fs::path& d, InputTruth& t) {
         write_ply(d / "sphere.ply", sphere(), false, false);
         t = truth_of(sphere(), true);
         return "sphere.ply";
       }},
      {"obj_mtl_elephant",
       [](const fs::path& d, InputTruth& t) {
         write_obj_mtl(d / "elephant.obj", {elephant()});
         t = truth_of(elephant(), true);
         return "elephant.obj";
       }},
      {"gltf_sphere",
       [](const fs::path& d, InputTruth& t) {
         squeeze::meshing::save_surface(d / "sphere.gltf", sphere());
         t = truth_of(sphere(), true);
         return "sphere.gltf";
       }},
      {"glb_elephant",
       [](const fs::path& d, InputTruth& t) {
         squeeze::meshing::save_surface(d / "elephant.glb", elephant());
         t = truth_of(elephant(), true);
         return "elephant.glb";
       }},
      {"many_parts_obj",
       [](const fs::path& d, InputTruth& t) {
         // Three disjoint elephants (1.5 bounding boxes apart) and a sphere, as four objects.
         const double w = (elephant().V.colwise().maxCoeff() - elephant().V.colwise().minCoeff()).maxCoeff();
         std::vector<SurfaceMesh> parts{elephant(), translated(elephant(), {1.5 * w, 0, 0}),
                                        translated(elephant(), {0, 0, 1.5 * w}),
                                        translated(sphere(), {1.5 * w, 0, 1.5 * w})};
         write_obj_mtl(d / "herd.obj", parts);
         t = truth_of(join(parts), true);
         EXPECT_EQ(t.components, 4);
         return "herd.obj";
       }},
      {"far_from_origin_obj",
       [](const fs::path& d, InputTruth& t) {
         const SurfaceMesh far = translated(elephant(), {1000.0, -2000.0, 500.0});
         write_obj_mtl(d / "far.obj", {far});
         t = truth_of(far, true);
         return "far.obj";
       }},
      {"dirty_ply",
       [](const fs::path& d, InputTruth& t) {
         // Elephant with half its faces flipped, every 10th face duplicated, every 50th face
         // followed by a degenerate face with a repeated index and by a zero-area face through
         // the midpoint of one of its edges.
         const SurfaceMesh& e = elephant();
         std::vector<Eigen::RowVector3d> pts;
         for (Eigen::Index i = 0; i < e.V.rows(); ++i) pts.push_back(e.V.row(i));
         std::vector<std::array<int, 3>> tris;
         for (Eigen::Index f = 0; f < e.F.rows(); ++f) {
           std::array<int, 3> tri{e.F(f, 0), e.F(f, 1), e.F(f, 2)};
           if (f % 2) std::swap(tri[1], tri[2]);
           tris.push_back(tri);
           if (f % 10 == 0) tris.push_back(tri);
           if (f % 50 == 0) {
             tris.push_back({tri[0], tri[0], tri[1]});
             pts.push_back(0.5 * (pts[tri[0]] + pts[tri[1]]));
             tris.push_back({tri[0], static_cast<int>(pts.size()) - 1, tri[1]});
           }
         }
         SurfaceMesh m;
         m.V.resize(static_cast<Eigen::Index>(pts.size()), 3);
         for (size_t i = 0; i < pts.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = pts[i];
         m.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
         for (size_t i = 0; i < tris.size(); ++i)
           m.F.row(static_cast<Eigen::Index>(i)) << tris[i][0], tris[i][1], tris[i][2];
         write_ply(d / "dirty.ply", m, false, false);
         t = truth_of(elephant(), true);  // the solid is the elephant's
         t.points = m.V;                  // midpoints lie on its surface
         return "dirty.ply";
       }},
      {"open_elephant_ply",
       [](const fs::path& d, InputTruth& t) {
         // Delete the faces near the elephant's first vertex (a patch of a few percent).
         const SurfaceMesh& e = elephant();
         const double r = 0.06 * diagonal(e.V);
         std::vector<int> keep;
         for (Eigen::Index f = 0; f < e.F.rows(); ++f) {
           const Eigen::RowVector3d c = (e.V.row(e.F(f, 0)) + e.V.row(e.F(f, 1)) + e.V.row(e.F(f, 2))) / 3.0;
           if ((c - e.V.row(0)).norm() > r) keep.push_back(static_cast<int>(f));
         }
         EXPECT_GT(e.F.rows() - static_cast<Eigen::Index>(keep.size()), e.F.rows() / 100);
         EXPECT_LT(e.F.rows() - static_cast<Eigen::Index>(keep.size()), e.F.rows() / 10);
         SurfaceMesh open;
         open.V = e.V;
         open.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
         for (size_t i = 0; i < keep.size(); ++i) open.F.row(static_cast<Eigen::Index>(i)) = e.F.row(keep[i]);
         open = compact(open);
         squeeze::meshing::save_surface(d / "open.ply", open);
         t = truth_of(open, false);
         return "open.ply";
       }},
  };
}

void PrintTo(const Variant& v, std::ostream* os) { *os << v.name; }

class FormatTest : public ::testing::TestWithParam<Variant> {};

TEST_P(FormatTest, MeshMeetsTheContract) {
  const Variant& v = GetParam();
  TempDir dir(v.name);
  InputTruth truth;
  const std::string input = v.make(dir.path(), truth);
  ASSERT_TRUE(fs::exists(dir / input));
  const auto tmp_before = temporaries_in(dir.path());  // (a .gltf written by save_surface may leave one; see test_meshing)
  const RunResult run = run_squeeze({"mesh", input, "-o", "out.mesh", "--report", "r.json"}, dir.path(), 300);
  ASSERT_FALSE(run.crashed()) << "squeeze crashed or timed out, code " << run.code << "\n" << run.err;
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_EQ(temporaries_in(dir.path()).size(), tmp_before.size()) << "squeeze left a temporary file";
  const TetMesh tets = squeeze::meshing::load_tet_mesh(dir / "out.mesh");
  // The open elephant's hole (6 % of the diagonal in radius) is wider than the deviation bound: as
  // a solid its cap lay 4.4 % off; since meshing version 16 it is a slab of prisms 1 % thick, about
  // 16,000 tetrahedra, within every bound, and the report says why the count is over.
  const bool slab = v.name == "open_elephant_ply";
  const TetFacts facts = expect_mesh_contract(tets, truth, v.name, slab ? 60000 : 5000);
  const nlohmann::json report = nlohmann::json::parse(read_text(dir / "r.json"));
  if (slab) {
    EXPECT_TRUE(report["target_exceeded_because"].is_string()) << report.dump();
    EXPECT_LE(report["deviation_out"].get<double>(), 0.01);
  }
  expect_report(report, facts, truth, v.name);
  if (v.name != "dirty_ply") { EXPECT_EQ(report["input"]["closed"].get<bool>(), truth.closed) << v.name; }
}

INSTANTIATE_TEST_SUITE_P(MeshCliFormats, FormatTest, ::testing::ValuesIn(variants()),
                         [](const ::testing::TestParamInfo<Variant>& i) { return i.param.name; });

// ---------------------------------------------------------------------------------------------
// Determinism.

TEST(MeshCliDeterminism, SameInputGivesByteIdenticalOutputTwiceAndForAnyThreadCount) {
  TempDir dir("determinism");
  const std::string in = data("elephant.off").string();
  const RunResult a = run_squeeze({"-q", "mesh", in, "-o", "a.mesh"}, dir.path(), 300);
  const RunResult b = run_squeeze({"-q", "mesh", in, "-o", "b.mesh"}, dir.path(), 300);
  const RunResult one = run_squeeze({"-q", "-j", "1", "mesh", in, "-o", "j1.mesh"}, dir.path(), 300);
  const RunResult two = run_squeeze({"-q", "-j", "2", "mesh", in, "-o", "j2.mesh"}, dir.path(), 300);
  for (const RunResult* r : {&a, &b, &one, &two}) ASSERT_EQ(r->code, 0) << r->err;
  const std::string ta = read_text(dir / "a.mesh"), tb = read_text(dir / "b.mesh");
  const std::string t1 = read_text(dir / "j1.mesh"), t2 = read_text(dir / "j2.mesh");
  ASSERT_FALSE(ta.empty());
  EXPECT_TRUE(ta == tb) << "two runs differ (" << ta.size() << " vs " << tb.size() << " bytes)";
  EXPECT_TRUE(t1 == t2) << "-j 1 and -j 2 differ (" << t1.size() << " vs " << t2.size() << " bytes)";
  EXPECT_TRUE(ta == t1) << "default threads and -j 1 differ (" << ta.size() << " vs " << t1.size() << " bytes)";
  // -q prints nothing on success.
  EXPECT_TRUE(a.err.empty()) << a.err;
}

TEST(MeshCliDeterminism, SmallTargetIsByteIdenticalForAnyThreadCount) {
  TempDir dir("determinism-target");
  const std::string in = data("elephant.off").string();
  const RunResult one = run_squeeze({"-q", "-j", "1", "mesh", in, "-o", "j1.mesh", "--target-tets", "300"}, dir.path(), 300);
  const RunResult two = run_squeeze({"-q", "-j", "2", "mesh", in, "-o", "j2.mesh", "--target-tets", "300"}, dir.path(), 300);
  ASSERT_EQ(one.code, 0) << one.err;
  ASSERT_EQ(two.code, 0) << two.err;
  const std::string t1 = read_text(dir / "j1.mesh"), t2 = read_text(dir / "j2.mesh");
  ASSERT_FALSE(t1.empty());
  EXPECT_TRUE(t1 == t2) << "-j 1 and -j 2 differ (" << t1.size() << " vs " << t2.size() << " bytes)";
}

// ---------------------------------------------------------------------------------------------
// Output formats and side outputs through the command line.

TEST(MeshCliOutputs, EveryTetFormatAndShellsAndReport) {
  TempDir dir("outputs");
  const SurfaceMesh s = sphere();
  const InputTruth truth = truth_of(s, true);
  for (const std::string out : {"s.mesh", "s.msh", "s.vtk", "s.vtu", "s.node"}) {
    SCOPED_TRACE(out);
    const RunResult r = run_squeeze({"mesh", data("sphere.off").string(), "-o", out, "--shells", "shells.obj",
                                     "--report", "r.json"},
                                    dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
    TetMesh m;
    try {
      m = squeeze::meshing::load_tet_mesh(dir / out);
    } catch (const std::exception& e) {
      ADD_FAILURE() << out << ": load_tet_mesh threw " << e.what();
      continue;
    }
    expect_mesh_contract(m, truth, out);
    const SurfaceMesh shells = squeeze::meshing::load_surface(dir / "shells.obj");
    EXPECT_GE(shells.F.rows(), 4);
    if (out == "s.node") { EXPECT_TRUE(fs::exists(dir / "s.ele")); }
  }
  EXPECT_TRUE(temporaries_in(dir.path()).empty());
}

// The summary line's volume ratio is the report's volume_ratio where the input is closed (the
// sphere: 1.000). Where it is not, the report's is null and the line names the ratio it prints,
// to the input's winding-number volume, or prints none: trimesh's open bunny, whose hollowed
// mesh is a shell, read "volume ratio 0.170" as if it had lost most of its volume.
TEST(MeshCliOutputs, SummaryVolumeRatioIsTheReportsOrNamedAsTheWindingNumbers) {
  TempDir dir("summary");
  auto ratio_in = [](const std::string& err) {
    const std::string key = "volume ratio ";
    const auto at = err.find(key);
    return at == std::string::npos ? std::string() : err.substr(at + key.size(), err.find(',', at) - at - key.size());
  };
  const RunResult closed = run_squeeze({"mesh", data("sphere.off").string(), "-o", "s.mesh", "--report", "s.json"}, dir.path());
  ASSERT_EQ(closed.code, 0) << closed.err;
  const nlohmann::json rs = nlohmann::json::parse(read_text(dir / "s.json"));
  ASSERT_TRUE(rs["volume_ratio"].is_number()) << rs.dump();
  char want[32];
  std::snprintf(want, sizeof want, "%.3f", rs["volume_ratio"].get<double>());
  EXPECT_EQ(ratio_in(closed.err), want) << closed.err;
  EXPECT_EQ(closed.err.find("winding-number volume ratio"), std::string::npos) << closed.err;

  const RunResult open = run_squeeze({"mesh", data("ChineseDragon-10kv.off").string(), "-o", "d.mesh", "--target-tets",
                                      "150", "--report", "d.json"},
                                     dir.path(), 300);
  ASSERT_EQ(open.code, 0) << open.err;
  const nlohmann::json rd = nlohmann::json::parse(read_text(dir / "d.json"));
  EXPECT_TRUE(rd["volume_ratio"].is_null()) << rd.dump();
  const bool named = open.err.find("winding-number volume ratio ") != std::string::npos;
  EXPECT_TRUE(named || ratio_in(open.err) == "n/a") << open.err;
}

TEST(MeshCliOutputs, TargetTetsRaisesTheCount) {
  TempDir dir("target");
  const RunResult a = run_squeeze({"-q", "mesh", data("sphere.off").string(), "-o", "a.mesh", "--target-tets", "300"},
                                  dir.path());
  const RunResult b = run_squeeze({"-q", "mesh", data("sphere.off").string(), "-o", "b.mesh", "--target-tets", "3000"},
                                  dir.path());
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  const auto na = squeeze::meshing::load_tet_mesh(dir / "a.mesh").T.rows(), nb = squeeze::meshing::load_tet_mesh(dir / "b.mesh").T.rows();
  EXPECT_GT(nb, 3 * na) << na << " vs " << nb;
}

// --shells-only: a closed input (the sphere, which takes its own boundary by default) is meshed as
// its convex shells, and the report says so; without the flag, not.
TEST(MeshCliOutputs, ShellsOnlyMeshesAClosedPartAsItsConvexShells) {
  TempDir dir("shells-only");
  const RunResult a = run_squeeze({"-q", "mesh", data("sphere.off").string(), "-o", "a.mesh", "--target-tets", "300",
                                   "--shells-only", "--report", "a.json"},
                                  dir.path());
  const RunResult b = run_squeeze({"-q", "mesh", data("sphere.off").string(), "-o", "b.mesh", "--target-tets", "300",
                                   "--report", "b.json"},
                                  dir.path());
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  const nlohmann::json ra = nlohmann::json::parse(read_text(dir / "a.json")), rb = nlohmann::json::parse(read_text(dir / "b.json"));
  EXPECT_EQ(ra["method"], "convex_shells");
  EXPECT_NE(ra["fallback_because"].get<std::string>().find("shells_only"), std::string::npos) << ra["fallback_because"];
  EXPECT_EQ(rb["method"], "boundary");
  EXPECT_GT(ra["volume_ratio"].get<double>(), 1.0);  // the hulls hold the whole sphere
  EXPECT_LE(ra["deviation_in"].get<double>(), rb["deviation_in"].get<double>() + 0.005);
}

// ---------------------------------------------------------------------------------------------
// Bad inputs.

struct BadCase {
  std::string name;
  std::function<std::vector<std::string>(const fs::path& dir)> setup;  // returns the arguments after `mesh`
  std::string names;        // what stderr must name (file or option)
  std::vector<std::string> problem;  // stderr must contain one of these (case-insensitive)
  std::vector<std::string> no_outputs = {"out.mesh", "r.json", "s.off", "out.ele", "out.node"};
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string write_file(const fs::path& dir, const std::string& name, const std::string& bytes) {
  std::ofstream(dir / name, std::ios::binary) << bytes;
  return name;
}

const std::string kTetOff = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";

std::vector<BadCase> bad_cases() {
  const std::vector<std::string> outs = {"-o", "out.mesh", "--report", "r.json", "--shells", "s.off"};
  auto with = [outs](std::vector<std::string> a) {
    a.insert(a.end(), outs.begin(), outs.end());
    return a;
  };
  const std::string sphere_off = data("sphere.off").string();
  return {
      {"missing_file", [=](const fs::path&) { return with({"missing.off"}); }, "missing.off",
       {"no such file", "not found", "does not exist", "missing"}},
      {"text_xyz", [=](const fs::path& d) { return with({write_file(d, "points.xyz", "1 2 3\n4 5 6\n7 8 9\n")}); },
       "points.xyz", {"format", "cannot read", "unreadable", "no suitable"}},
      {"random_bytes_ply",
       [=](const fs::path& d) {
         std::string bytes(5000, '\0');
         unsigned x = 12345;
         for (char& c : bytes) c = static_cast<char>((x = x * 1103515245u + 12345u) >> 16);
         return with({write_file(d, "noise.ply", bytes)});
       },
       "noise.ply", {"ply", "cannot read", "format", "invalid"}},
      {"empty_file", [=](const fs::path& d) { return with({write_file(d, "empty.off", "")}); }, "empty.off",
       {"empty"}},
      {"zero_faces",
       [=](const fs::path& d) { return with({write_file(d, "nofaces.off", "OFF\n4 0 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n")}); },
       "nofaces.off", {"face", "triangle"}},
      {"nan_coordinate",
       [=](const fs::path& d) {
         std::string t = kTetOff;
         t.replace(t.find("0 1 0"), 5, "0 nan 0");
         return with({write_file(d, "nan.off", t)});
       },
       "nan.off", {"nan"}},
      {"inf_coordinate",
       [=](const fs::path& d) {
         std::string t = kTetOff;
         t.replace(t.find("1 0 0"), 5, "inf 0 0");
         return with({write_file(d, "inf.off", t)});
       },
       "inf.off", {"inf"}},
      {"all_degenerate",
       [=](const fs::path& d) {
         return with({write_file(d, "degenerate.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 0 1\n3 1 2 2\n3 3 3 3\n")});
       },
       "degenerate.off", {"degenerate"}},
      {"all_coincident",
       [=](const fs::path& d) {
         return with({write_file(d, "point.off", "OFF\n3 1 0\n0.5 0.5 0.5\n0.5 0.5 0.5\n0.5 0.5 0.5\n3 0 1 2\n")});
       },
       "point.off", {"degenerate", "zero extent", "coincide"}},
      {"flat_input",
       [=](const fs::path& d) {
         // A single triangle: a surface that bounds no volume.
         return with({write_file(d, "flat.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")});
       },
       "", {}},  // either meshes a thin slab (exit 0) or fails cleanly; checked below
      {"concavity_negative", [=](const fs::path&) { return with({sphere_off, "--concavity", "-1"}); }, "--concavity",
       {"> 0", "positive", "must be"}},
      {"concavity_zero", [=](const fs::path&) { return with({sphere_off, "--concavity", "0"}); }, "--concavity",
       {"> 0", "positive", "must be"}},
      {"target_tets_zero", [=](const fs::path&) { return with({sphere_off, "--target-tets", "0"}); }, "--target-tets",
       {"at least", "> 0", "positive", "must be"}},
      {"dense_faces_negative", [=](const fs::path&) { return with({sphere_off, "--dense-faces", "-1"}); }, "--dense-faces",
       {"at least", "must be"}},
      {"dense_min_saving_negative", [=](const fs::path&) { return with({sphere_off, "--dense-min-saving", "-1"}); },
       "--dense-min-saving", {"at least", "must be"}},
      {"max_hulls_zero", [=](const fs::path&) { return with({sphere_off, "--max-hulls", "0"}); }, "--max-hulls",
       {"at least", "> 0", "positive", "must be"}},
      {"wrap_alpha_zero", [=](const fs::path&) { return with({sphere_off, "--wrap", "--wrap-alpha", "0"}); },
       "--wrap-alpha", {"positive", "less or equal to 0", "must be"}},
      {"wrap_alpha_too_large", [=](const fs::path&) { return with({sphere_off, "--wrap", "--wrap-alpha", "200"}); },
       "--wrap-alpha", {"below 1"}},
      {"wrap_offset_negative", [=](const fs::path&) { return with({sphere_off, "--wrap", "--wrap-offset", "-0.1"}); },
       "--wrap-offset", {"positive", "less or equal to 0", "must be"}},
      {"winding_facet_distance_zero",
       [=](const fs::path&) { return with({sphere_off, "--winding", "--winding-facet-distance", "0"}); },
       "--winding-facet-distance", {"positive", "must be"}},
      {"winding_dilation_too_large",
       [=](const fs::path&) { return with({sphere_off, "--winding", "--winding-dilation", "200"}); },
       "--winding-dilation", {"below 1"}},
      {"winding_surface_dilation_too_large",
       [=](const fs::path&) { return with({sphere_off, "--winding-surface-dilation", "200"}); },
       "--winding-surface-dilation", {"below 1"}},
      {"winding_surface_dilation_negative",
       [=](const fs::path&) { return with({sphere_off, "--winding-surface-dilation", "-1"}); },
       "--winding-surface-dilation", {"at least 0"}},
      {"target_tets_not_a_number", [=](const fs::path&) { return with({sphere_off, "--target-tets", "many"}); },
       "--target-tets", {"many", "number", "convert", "integer"}},
      {"unknown_output_extension",
       [=](const fs::path&) { return std::vector<std::string>{sphere_off, "-o", "out.xyz", "--report", "r.json"}; },
       "out.xyz", {"format", "extension"}, {"out.xyz", "r.json"}},
      {"unknown_shells_extension",
       [=](const fs::path&) {
         return std::vector<std::string>{sphere_off, "-o", "out.mesh", "--report", "r.json", "--shells", "s.xyz"};
       },
       "s.xyz", {"format", "extension"}, {"out.mesh", "r.json", "s.xyz"}},
      {"output_directory_missing",
       [=](const fs::path&) { return std::vector<std::string>{sphere_off, "-o", "nodir/out.mesh", "--report", "r.json"}; },
       "nodir", {"does not exist", "no such", "directory"}, {"nodir", "r.json"}},
      {"report_directory_missing",
       [=](const fs::path&) { return std::vector<std::string>{sphere_off, "-o", "out.mesh", "--report", "nodir/r.json"}; },
       "nodir", {"does not exist", "no such", "directory"}, {"nodir", "out.mesh"}},
      {"input_is_a_directory",
       [=](const fs::path& d) {
         fs::create_directories(d / "adir.off");
         return with({"adir.off"});
       },
       "adir.off", {"directory"}},
  };
}

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadInputTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInputTest, FailsWithOneLineAndLeavesNothing) {
  const BadCase& c = GetParam();
  TempDir dir(c.name);
  const std::vector<std::string> args = c.setup(dir.path());
  std::vector<std::string> cmd{"mesh"};
  cmd.insert(cmd.end(), args.begin(), args.end());
  std::set<fs::path> before;
  for (const auto& e : fs::recursive_directory_iterator(dir.path())) before.insert(e.path());
  const RunResult r = run_squeeze(cmd, dir.path(), 60);
  ASSERT_FALSE(r.timed_out()) << c.name << ": hung (timeout 60 s)";
  ASSERT_FALSE(r.crashed()) << c.name << ": crashed, exit code " << r.code << "\n" << r.err;
  if (c.name == "flat_input" && r.code == 0) {
    // Meshing a lone triangle as a thin slab is acceptable; then the contract must hold.
    const TetMesh m = squeeze::meshing::load_tet_mesh(dir / "out.mesh");
    const TetFacts f = tet_facts(m);
    EXPECT_EQ(f.nonpositive, 0);
    EXPECT_EQ(f.overshared_faces, 0);
    EXPECT_LE(f.tets, 5000) << "more tetrahedra than the default cap";
    return;
  }
  EXPECT_NE(r.code, 0) << c.name << ": exit code 0 for a bad input";
  const auto ls = lines(r.err);
  EXPECT_EQ(ls.size(), 1u) << c.name << ": stderr is not one line:\n" << r.err;
  const std::string err = lower(r.err);
  if (!c.names.empty()) {
    EXPECT_NE(err.find(lower(c.names)), std::string::npos) << c.name << ": stderr does not name " << c.names << ":\n"
                                                           << r.err;
  }
  if (!c.problem.empty()) {
    bool any = false;
    for (const auto& p : c.problem) any |= err.find(lower(p)) != std::string::npos;
    EXPECT_TRUE(any) << c.name << ": stderr does not say what is wrong:\n" << r.err;
  }
  for (const auto& o : c.no_outputs)
    if (!before.count(dir / o)) { EXPECT_FALSE(fs::exists(dir / o)) << c.name << ": left " << o << " behind"; }
  std::vector<std::string> created;
  for (const auto& e : fs::recursive_directory_iterator(dir.path()))
    if (!before.count(e.path())) created.push_back(e.path().filename().string());
  EXPECT_TRUE(created.empty()) << c.name << ": created " << created.size() << " file(s), first "
                               << (created.empty() ? "" : created.front());
  EXPECT_TRUE(temporaries_in(dir.path()).empty());
}

INSTANTIATE_TEST_SUITE_P(MeshCliErrors, BadInputTest, ::testing::ValuesIn(bad_cases()),
                         [](const ::testing::TestParamInfo<BadCase>& i) { return i.param.name; });

TEST(MeshCliCommandLine, HelpAndVersion) {
  TempDir dir("help");
  const RunResult h = run_squeeze({"mesh", "--help"}, dir.path());
  EXPECT_EQ(h.code, 0);
  EXPECT_NE(h.out.find("--target-tets"), std::string::npos);
  const RunResult v = run_squeeze({"--version"}, dir.path());
  EXPECT_EQ(v.code, 0);
  EXPECT_NE(v.out.find("squeeze"), std::string::npos);
  const RunResult none = run_squeeze({}, dir.path());
  EXPECT_NE(none.code, 0);
  EXPECT_FALSE(none.crashed());
}

}  // namespace
