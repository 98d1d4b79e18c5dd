// Tests of the ffd stage (issue 4): binding real surfaces to tetrahedral meshes and replaying
// deformations, the order-preserving surface I/O `squeeze deform` relies on, and the CLI's
// handling of bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "squeeze/common/error.h"
#include "squeeze/ffd/ffd.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"
#include "squeeze/meshing/tet_geometry.h"

namespace {

using namespace squeeze;
using namespace squeeze::meshing;
using namespace squeeze::ffd;
namespace fs = std::filesystem;

SurfaceMesh load_ordered(const std::string& name) {
  LoadOptions o;
  o.keep_order = true;
  return load_surface(fs::path(SQUEEZE_TEST_DATA) / name, o);
}

// A conforming tetrahedral mesh of the box [lo, hi] split into n^3 cubes of six (Kuhn) tetrahedra
// each. Shrunk inside a surface's bounding box, it leaves part of the surface outside.
TetMesh grid_mesh(const Eigen::RowVector3d& lo, const Eigen::RowVector3d& hi, int n) {
  TetMesh m;
  const int s = n + 1;
  m.V.resize(s * s * s, 3);
  auto id = [s](int i, int j, int k) { return i + s * (j + s * k); };
  for (int k = 0; k < s; ++k)
    for (int j = 0; j < s; ++j)
      for (int i = 0; i < s; ++i)
        m.V.row(id(i, j, k)) = lo + (hi - lo).cwiseProduct(Eigen::RowVector3d(i, j, k) / n);
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.T.resize(6 * n * n * n, 4);
  int t = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          m.T(t, 0) = id(c[0], c[1], c[2]);
          for (int a = 0; a < 3; ++a) {
            ++c[p[a]];
            m.T(t, a + 1) = id(c[0], c[1], c[2]);
          }
          ++t;
        }
  orient_positively(m);
  return m;
}

// The grid over the central 80% of V's bounding box (so some vertices are outside).
TetMesh inner_grid(const Eigen::MatrixX3d& V, int n) {
  Eigen::RowVector3d lo, hi;
  bounding_box(V, lo, hi);
  const Eigen::RowVector3d pad = 0.1 * (hi - lo);
  return grid_mesh(lo + pad, hi - pad, n);
}

// A smooth, orientation-preserving map: a twist about z, a bend, anisotropic scale.
Eigen::RowVector3d smooth_map(const Eigen::RowVector3d& p, const Eigen::RowVector3d& centre, double size) {
  const Eigen::RowVector3d q = (p - centre) / size;
  const double a = 0.6 * q(2), c = std::cos(a), s = std::sin(a);
  const Eigen::RowVector3d r(c * q(0) - s * q(1), s * q(0) + c * q(1), q(2) + 0.15 * q(0) * q(0));
  return centre + size * Eigen::RowVector3d(1.2 * r(0), 0.9 * r(1), r(2));
}

Eigen::Matrix3d smooth_jacobian(const Eigen::RowVector3d& p, const Eigen::RowVector3d& centre, double size) {
  Eigen::Matrix3d J;
  const double h = 1e-6 * size;
  for (int k = 0; k < 3; ++k) {
    Eigen::RowVector3d e = Eigen::RowVector3d::Zero();
    e(k) = h;
    J.col(k) = ((smooth_map(p + e, centre, size) - smooth_map(p - e, centre, size)) / (2 * h)).transpose();
  }
  return J;
}

const char* kSurfaces[] = {"bunny00.off", "elephant.off", "ChineseDragon-10kv.off", "sphere.off"};

TEST(FfdBind, RestStateIsReproduced) {
  for (const char* name : kSurfaces) {
    SCOPED_TRACE(name);
    const SurfaceMesh s = load_ordered(name);
    const TetMesh tets = inner_grid(s.V, 6);
    const Binding b = bind_surface(s.V, tets);
    ASSERT_EQ(b.tet.size(), s.V.rows());
    EXPECT_GT(b.outside, 0);
    EXPECT_LT(b.outside, s.V.rows());
    const double diag = bounding_box_diagonal(s.V);
    const double err = (replay(b, tets.V) - s.V).rowwise().norm().maxCoeff();
    EXPECT_LE(err, 1e-12 * diag);
    // Rows sum to 1; exactly the vertices outside every tetrahedron have a coordinate below
    // locate()'s tolerance, and the reported distance is that of the farthest of them.
    for (Eigen::Index i = 0; i < b.bary.rows(); ++i) EXPECT_NEAR(b.bary.row(i).sum(), 1.0, 1e-12);
    EXPECT_EQ((b.bary.rowwise().minCoeff().array() < -1e-10).count(), b.outside);
    EXPECT_GT(b.max_outside_distance, 0.0);
    EXPECT_LT(b.max_outside_distance, 0.2 * diag);
  }
}

TEST(FfdBind, AffineMapsAreReproducedIncludingOutsideVertices) {
  for (const char* name : {"bunny00.off", "ChineseDragon-10kv.off"}) {
    SCOPED_TRACE(name);
    const SurfaceMesh s = load_ordered(name);
    const TetMesh tets = inner_grid(s.V, 5);
    const Binding b = bind_surface(s.V, tets);
    ASSERT_GT(b.outside, 100);
    const double diag = bounding_box_diagonal(s.V);
    Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    Eigen::Matrix3d scale = Eigen::Vector3d(2.0, 0.5, 1.3).asDiagonal();
    Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
    shear(0, 1) = 0.4;
    shear(2, 0) = -0.3;
    const Eigen::RowVector3d shift(3.0, -1.0, 250.0);
    for (const Eigen::Matrix3d& A : {Eigen::Matrix3d(rot), Eigen::Matrix3d(scale), Eigen::Matrix3d(shear),
                                     Eigen::Matrix3d(rot * scale * shear)}) {
      const Eigen::MatrixX3d X = (tets.V * A.transpose()).rowwise() + shift;
      const Eigen::MatrixX3d expected = (s.V * A.transpose()).rowwise() + shift;
      const Eigen::MatrixX3d got = replay(b, X);
      double worst_outside = 0;
      for (Eigen::Index i = 0; i < s.V.rows(); ++i) {
        const double e = (got.row(i) - expected.row(i)).norm();
        EXPECT_LE(e, 1e-9 * diag) << "vertex " << i;
        if (b.bary.row(i).minCoeff() < -1e-6) worst_outside = std::max(worst_outside, e);
      }
      EXPECT_LE(worst_outside, 1e-9 * diag);
      // The sparse weight matrix is the same map.
      EXPECT_LE((weight_matrix(b) * X - got).cwiseAbs().maxCoeff(), 1e-12 * diag);
    }
  }
}

TEST(FfdBind, WeightMatrixHasFourEntriesPerRow) {
  const SurfaceMesh s = load_ordered("sphere.off");
  const TetMesh tets = inner_grid(s.V, 3);
  const Binding b = bind_surface(s.V, tets);
  const auto W = weight_matrix(b);
  EXPECT_EQ(W.rows(), s.V.rows());
  EXPECT_EQ(W.cols(), tets.V.rows());
  EXPECT_EQ(W.nonZeros(), 4 * s.V.rows());
  const Eigen::VectorXd sums = W * Eigen::VectorXd::Ones(W.cols());
  EXPECT_LE((sums.array() - 1.0).abs().maxCoeff(), 1e-12);
}

TEST(FfdBind, SmoothDeformationGivesNoCracksAndNoFlippedFaces) {
  for (const char* name : {"bunny00.off", "elephant.off"}) {
    SCOPED_TRACE(name);
    const SurfaceMesh s = load_ordered(name);
    Eigen::RowVector3d lo, hi;
    bounding_box(s.V, lo, hi);
    // A convex coarse mesh that encloses everything: every surface edge lies inside it.
    const Eigen::RowVector3d pad = 0.02 * (hi - lo);
    const TetMesh tets = grid_mesh(lo - pad, hi + pad, 6);
    const Binding b = bind_surface(s.V, tets);
    EXPECT_EQ(b.outside, 0);
    const Eigen::RowVector3d centre = 0.5 * (lo + hi);
    const double size = (hi - lo).norm();
    TetMesh moved = tets;
    for (Eigen::Index i = 0; i < tets.V.rows(); ++i) moved.V.row(i) = smooth_map(tets.V.row(i), centre, size);
    ASSERT_GT(tet_volumes(moved).minCoeff(), 0.0) << "the coarse mesh must not be inverted";
    // Lipschitz constant of the piecewise-linear map: the largest singular value of a tet Jacobian.
    double lipschitz = 0;
    for (Eigen::Index t = 0; t < tets.T.rows(); ++t) {
      Eigen::Matrix3d D0, D1;
      for (int k = 0; k < 3; ++k) {
        D0.col(k) = (tets.V.row(tets.T(t, k + 1)) - tets.V.row(tets.T(t, 0))).transpose();
        D1.col(k) = (moved.V.row(tets.T(t, k + 1)) - moved.V.row(tets.T(t, 0))).transpose();
      }
      const Eigen::Matrix3d J = D1 * D0.inverse();
      lipschitz = std::max(lipschitz, Eigen::JacobiSVD<Eigen::Matrix3d>(J).singularValues()(0));
    }
    const Eigen::MatrixX3d V = replay(b, moved.V);
    int flipped = 0, cracked = 0, checked = 0;
    for (Eigen::Index f = 0; f < s.F.rows(); ++f) {
      const Eigen::RowVector3d a = s.V.row(s.F(f, 0)), c = s.V.row(s.F(f, 1)), d = s.V.row(s.F(f, 2));
      const Eigen::Vector3d n0 = (c - a).cross(d - a).transpose();
      if (n0.norm() < 1e-12 * size * size) continue;  // degenerate in the input already
      ++checked;
      const Eigen::Vector3d n1 =
          (V.row(s.F(f, 1)) - V.row(s.F(f, 0))).cross(V.row(s.F(f, 2)) - V.row(s.F(f, 0))).transpose();
      // Normals transform with the cofactor matrix of the local Jacobian.
      const Eigen::Matrix3d J = smooth_jacobian((a + c + d) / 3.0, centre, size);
      const Eigen::Vector3d expected = J.determinant() * J.inverse().transpose() * n0;
      if (n1.dot(expected) <= 0) ++flipped;
      for (int k = 0; k < 3; ++k) {  // each edge stretches at most by the Lipschitz constant
        const int u = s.F(f, k), w = s.F(f, (k + 1) % 3);
        if ((V.row(u) - V.row(w)).norm() > lipschitz * (s.V.row(u) - s.V.row(w)).norm() * (1 + 1e-9) + 1e-15 * size)
          ++cracked;
      }
    }
    EXPECT_GT(checked, s.F.rows() * 9 / 10);
    EXPECT_EQ(flipped, 0);
    EXPECT_EQ(cracked, 0);
    // Vertex normals for rendering: unit length, and agreeing with the face orientation.
    const Eigen::MatrixX3d N = vertex_normals(V, s.F);
    ASSERT_EQ(N.rows(), V.rows());
    for (Eigen::Index i = 0; i < N.rows(); ++i) EXPECT_NEAR(N.row(i).norm(), 1.0, 1e-12);
  }
}

TEST(FfdBind, SameResultWithOneAndTwoThreads) {
  const SurfaceMesh s = load_ordered("bunny00.off");
  const TetMesh tets = inner_grid(s.V, 7);
  Binding one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = bind_surface(s.V, tets);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = bind_surface(s.V, tets);
  }
  EXPECT_TRUE(one.tet == two.tet);
  EXPECT_TRUE(one.bary == two.bary);  // bitwise
  EXPECT_EQ(one.outside, two.outside);
  EXPECT_EQ(one.max_outside_distance, two.max_outside_distance);
}

TEST(FfdBind, RejectsBadInput) {
  const TetMesh tets = grid_mesh(Eigen::RowVector3d(0, 0, 0), Eigen::RowVector3d(1, 1, 1), 2);
  EXPECT_THROW(bind_surface(Eigen::MatrixX3d(0, 3), tets), InputError);
  Eigen::MatrixX3d V = Eigen::MatrixX3d::Constant(4, 3, 0.5);
  V(2, 1) = std::nan("");
  try {
    bind_surface(V, tets, {}, nullptr, "x.off");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "x.off: vertex 2 has a NaN or infinite coordinate");
  }
  V(2, 1) = 5.0;  // 4 units outside a unit cube; diagonal of V is 4.5
  BindOptions strict;
  strict.max_outside = 0.5;
  EXPECT_THROW(bind_surface(V, tets, strict), InputError);
  EXPECT_NO_THROW(bind_surface(V, tets));
  TetMesh other = tets;
  other.T(3, 0) = other.T(3, 1);
  EXPECT_THROW(check_same_connectivity(tets, other, "a.mesh", "b.mesh"), InputError);
  EXPECT_THROW(check_same_connectivity(tets, grid_mesh(Eigen::RowVector3d(0, 0, 0), Eigen::RowVector3d(1, 1, 1), 3),
                                       "a.mesh", "b.mesh"),
               InputError);
  EXPECT_NO_THROW(check_same_connectivity(tets, tets, "a.mesh", "b.mesh"));
}

// ---- order-preserving surface I/O -------------------------------------------------------------

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("squeeze_test_ffd_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(reinterpret_cast<uintptr_t>(this)));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
  size_t entries() const { return static_cast<size_t>(std::distance(fs::directory_iterator(path), {})); }
};

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(FfdSurfaceIo, KeepOrderKeepsEveryVertexAndFace) {
  TempDir dir;
  // Vertex 0 and 5 are unreferenced, 1 and 6 coincide, the second face is a quad.
  const std::string verts = "9 9 9\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n5 5 5\n0 0 0\n";
  write_text(dir / "a.off", "OFF\n7 3 0\n" + verts + "3 1 2 3\n4 1 3 4 2\n3 6 2 4\n");
  write_text(dir / "a.obj",
             "# comment\nv 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 5 5 5\nv 0 0 0\nvn 0 0 1\n"
             "f 2/1/1 3/1/1 4/1/1\nf 2//1 4//1 5//1 3//1\nf -1 -5 -3\n");
  write_text(dir / "a.ply",
             "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 3\nproperty list uchar int vertex_indices\nend_header\n" +
                 verts + "3 1 2 3\n4 1 3 4 2\n3 6 2 4\n");
  Eigen::MatrixX3i F(4, 3);
  F << 1, 2, 3, 1, 3, 4, 1, 4, 2, 6, 2, 4;
  for (const char* name : {"a.off", "a.obj", "a.ply"}) {
    SCOPED_TRACE(name);
    LoadOptions o;
    o.keep_order = true;
    const SurfaceMesh m = load_surface(dir / name, o);
    ASSERT_EQ(m.V.rows(), 7);
    EXPECT_EQ(m.V.row(0), Eigen::RowVector3d(9, 9, 9));
    EXPECT_EQ(m.V.row(5), Eigen::RowVector3d(5, 5, 5));
    EXPECT_EQ(m.V.row(6), Eigen::RowVector3d(0, 0, 0));
    EXPECT_EQ(m.F, F);
    // The default (welding) load is unchanged: unreferenced vertices dropped, 1 and 6 welded.
    EXPECT_EQ(load_surface(dir / name).V.rows(), 4);
  }
  // Our writers keep everything (assimp's single precision for PLY).
  const SurfaceMesh m = load_ordered("elephant.off");
  for (const char* name : {"out.off", "out.obj", "out.ply"}) {
    SCOPED_TRACE(name);
    save_surface(dir / name, m);
    LoadOptions o;
    o.keep_order = true;
    const SurfaceMesh back = load_surface(dir / name, o);
    ASSERT_EQ(back.V.rows(), m.V.rows());
    EXPECT_EQ(back.F, m.F);
    EXPECT_LE((back.V - m.V).cwiseAbs().maxCoeff(), std::string(name) == "out.ply" ? 1e-5 : 0.0);
  }
}

// ---- the CLI ----------------------------------------------------------------------------------

struct CliRun {
  int code;
  std::string err;
};

CliRun run(const std::string& args, const TempDir& dir) {
  const std::string err_file = dir / "stderr.txt";
  const int status = std::system((std::string(SQUEEZE_BINARY) + " " + args + " 2> " + err_file).c_str());
  std::ifstream in(err_file);
  std::stringstream ss;
  ss << in.rdbuf();
  fs::remove(err_file);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ss.str()};
}

TEST(FfdCli, DeformReplaysTheCoarseDeformationInInputOrder) {
  TempDir dir;
  const std::string surface = std::string(SQUEEZE_TEST_DATA) + "/elephant.off";
  const SurfaceMesh s = load_ordered("elephant.off");
  const TetMesh rest = inner_grid(s.V, 4);
  TetMesh moved = rest;
  Eigen::RowVector3d lo, hi;
  bounding_box(s.V, lo, hi);
  for (Eigen::Index i = 0; i < rest.V.rows(); ++i)
    moved.V.row(i) = smooth_map(rest.V.row(i), 0.5 * (lo + hi), (hi - lo).norm());
  save_tet_mesh(dir / "rest.mesh", rest);
  save_tet_mesh(dir / "moved.vtk", moved);
  for (const char* out : {"out.obj", "out.off", "out.stl"}) {
    SCOPED_TRACE(out);
    const CliRun r = run("-q deform " + surface + " " + (dir / "rest.mesh") + " " + (dir / "moved.vtk") + " -o " +
                          (dir / out),
                      dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    LoadOptions o;
    o.keep_order = true;
    const SurfaceMesh got = load_surface(dir / out, o);
    if (std::string(out) == "out.stl") {  // no shared vertices: three corners per facet
      EXPECT_EQ(got.V.rows(), 3 * s.F.rows());
      continue;
    }
    ASSERT_EQ(got.V.rows(), s.V.rows());
    EXPECT_EQ(got.F, s.F);
    const Eigen::MatrixX3d expected = replay(bind_surface(s.V, load_tet_mesh(dir / "rest.mesh")), moved.V);
    EXPECT_LE((got.V - expected).cwiseAbs().maxCoeff(), 1e-12 * bounding_box_diagonal(s.V));
  }
}

void expect_clean_failure(const std::string& args, const TempDir& dir, size_t entries_before,
                          const std::string& mentions) {
  SCOPED_TRACE(args);
  const CliRun r = run(args, dir);
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind("squeeze: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out.off"));
  EXPECT_EQ(dir.entries(), entries_before) << "a temporary or partial file was left behind";
}

TEST(FfdCli, BadInputFailsWithOneLineAndNoOutput) {
  TempDir dir;
  const std::string surface = std::string(SQUEEZE_TEST_DATA) + "/sphere.off";
  const SurfaceMesh s = load_ordered("sphere.off");
  save_tet_mesh(dir / "rest.mesh", inner_grid(s.V, 2));
  save_tet_mesh(dir / "other.mesh", inner_grid(s.V, 3));
  TetMesh renumbered = inner_grid(s.V, 2);
  std::swap(renumbered.T(0, 0), renumbered.T(0, 1));
  save_tet_mesh(dir / "renumbered.mesh", renumbered);
  write_text(dir / "empty.off", "OFF\n0 0 0\n");
  write_text(dir / "nan.off", "OFF\n4 1 0\n0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 1 2\n");
  write_text(dir / "nan.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 nan 0 0\n"
                               "0 0 1 0\nTetrahedra\n1\n1 2 3 4 1\nEnd\n");
  const size_t before = dir.entries();
  const std::string rest = dir / "rest.mesh", out = " -o " + (dir / "out.off");
  expect_clean_failure("deform " + surface + " " + rest + " " + (dir / "other.mesh") + out, dir, before,
                       "not a deformation of");
  expect_clean_failure("deform " + surface + " " + rest + " " + (dir / "renumbered.mesh") + out, dir, before,
                       "tetrahedron 0");
  expect_clean_failure("deform " + (dir / "empty.off") + " " + rest + " " + rest + out, dir, before, "empty.off");
  expect_clean_failure("deform " + (dir / "nan.off") + " " + rest + " " + rest + out, dir, before, "nan.off");
  expect_clean_failure("deform " + surface + " " + rest + " " + (dir / "nan.mesh") + out, dir, before, "nan.mesh");
  expect_clean_failure("deform " + surface + " " + rest + " " + (dir / "missing.mesh") + out, dir, before,
                       "missing.mesh");
  expect_clean_failure("deform " + surface + " " + rest + " " + rest + " -o " + (dir / "out.xyz123"), dir, before,
                       "out.xyz123");
  expect_clean_failure("deform " + surface + " " + rest + " " + rest + " --max-outside 0" + out, dir, before,
                       "outside");
}

}  // namespace
