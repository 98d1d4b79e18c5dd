// Helpers shared by the meshing tests (issue 3): running the `squeeze` binary, reading OFF files
// without the library, and checking the contracts of `squeeze mesh` on a written tetrahedral mesh
// with code that is independent of the library's own measures (tet_geometry.h, tet_faces.h, tet_quality.h, TetLocator).
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/tet_mesh.h"

namespace sqt {
namespace fs = std::filesystem;
using namespace squeeze::meshing;
using squeeze::meshing::SurfaceMesh;
using squeeze::meshing::TetMesh;

inline fs::path data(const std::string& name) { return fs::path(SQUEEZE_TEST_DATA) / name; }

/// V (#V points), F (#F index triples) as a SurfaceMesh.
inline SurfaceMesh surface_of(const std::vector<Eigen::Vector3d>& V, const std::vector<std::array<int, 3>>& F) {
  SurfaceMesh m;
  m.V.resize(static_cast<Eigen::Index>(V.size()), 3);
  for (size_t i = 0; i < V.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = V[i].transpose();
  m.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t i = 0; i < F.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) << F[i][0], F[i][1], F[i][2];
  return m;
}

/// A fresh, empty directory for one test, removed when it goes out of scope.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = tag;
    if (info) name += std::string("-") + info->test_suite_name() + "-" + info->name();
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') c = '_';
    path_ = fs::temp_directory_path() / ("squeeze-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    if (!std::getenv("SQUEEZE_KEEP_TEST_FILES")) fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& s) const { return path_ / s; }

 private:
  fs::path path_;
};

inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

inline std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct RunResult {
  int code = -1;          // exit code of squeeze (>= 128: killed by a signal, 124: timed out)
  std::string err, out;   // stderr, stdout
  bool crashed() const { return code >= 128 || code < 0; }
  bool timed_out() const { return code == 124; }
};

/// The factor on every run_squeeze time limit: $SQUEEZE_TEST_TIMEOUT_SCALE (scripts/test.sh
/// --sanitize sets 4: AddressSanitizer runs the meshing 3–5× slower), else 1.
inline double timeout_scale() {
  const char* s = std::getenv("SQUEEZE_TEST_TIMEOUT_SCALE");
  const double f = s ? std::atof(s) : 1.0;
  return f >= 1.0 ? f : 1.0;
}

/// Runs `squeeze ARGS` under `timeout SECONDS` (× timeout_scale()) in directory `cwd`; captures
/// stdout and stderr.
inline RunResult run_squeeze(const std::vector<std::string>& args, const fs::path& cwd, int seconds = 60) {
  const fs::path err = cwd / ".stderr.txt", out = cwd / ".stdout.txt";
  seconds = static_cast<int>(seconds * timeout_scale());
  std::string cmd = "cd " + quote(cwd.string()) + " && timeout -k 10 " + std::to_string(seconds) + " " +
                    quote(SQUEEZE_BINARY);
  for (const auto& a : args) cmd += " " + quote(a);
  cmd += " > " + quote(out.string()) + " 2> " + quote(err.string());
  const int status = std::system(cmd.c_str());
  RunResult r;
  if (status == -1) return r;
  if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
  else if (WIFSIGNALED(status)) r.code = 128 + WTERMSIG(status);
  r.err = read_text(err);
  r.out = read_text(out);
  fs::remove(err);
  fs::remove(out);
  return r;
}

/// The same for checks of the exit code and stderr only: returns the exit code, stderr into *err.
inline int run_squeeze(const std::vector<std::string>& args, const fs::path& cwd, std::string* err, int seconds = 600) {
  RunResult r = run_squeeze(args, cwd, seconds);
  if (err) *err = std::move(r.err);
  return r.code;
}

/// Lines of `s` (a trailing newline does not start a new line).
inline std::vector<std::string> lines(const std::string& s) {
  std::vector<std::string> v;
  std::stringstream ss(s);
  std::string line;
  while (std::getline(ss, line)) v.push_back(line);
  return v;
}

/// Reads an OFF file (no library code): vertices and polygons (fan-triangulated).
/// The surfaces ms as one (vertices stacked, faces shifted): a multi-part input.
inline SurfaceMesh join(const std::vector<SurfaceMesh>& ms) {
  SurfaceMesh out;
  Eigen::Index nv = 0, nf = 0;
  for (const auto& m : ms) nv += m.V.rows(), nf += m.F.rows();
  out.V.resize(nv, 3);
  out.F.resize(nf, 3);
  nv = nf = 0;
  for (const auto& m : ms) {
    out.V.middleRows(nv, m.V.rows()) = m.V;
    out.F.middleRows(nf, m.F.rows()) = m.F.array() + static_cast<int>(nv);
    nv += m.V.rows(), nf += m.F.rows();
  }
  return out;
}

inline SurfaceMesh read_off(const fs::path& p) {
  std::ifstream in(p);
  std::string head;
  in >> head;
  long nv = 0, nf = 0, ne = 0;
  in >> nv >> nf >> ne;
  SurfaceMesh m;
  m.V.resize(nv, 3);
  for (long i = 0; i < nv; ++i) in >> m.V(i, 0) >> m.V(i, 1) >> m.V(i, 2);
  std::vector<std::array<int, 3>> tris;
  for (long f = 0; f < nf; ++f) {
    int n = 0;
    in >> n;
    std::vector<int> idx(static_cast<size_t>(n));
    for (int& i : idx) in >> i;
    for (int k = 2; k < n; ++k) tris.push_back({idx[0], idx[k - 1], idx[k]});
  }
  m.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) << tris[i][0], tris[i][1], tris[i][2];
  return m;
}

inline void write_off(const fs::path& p, const SurfaceMesh& m) {
  std::ofstream out(p);
  out.precision(17);
  out << "OFF\n" << m.V.rows() << ' ' << m.F.rows() << " 0\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) out << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << '\n';
  for (Eigen::Index i = 0; i < m.F.rows(); ++i) out << "3 " << m.F(i, 0) << ' ' << m.F(i, 1) << ' ' << m.F(i, 2) << '\n';
}

inline double diagonal(const Eigen::MatrixX3d& V) {
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

/// Union-find.
struct DisjointSets {
  std::vector<int> p;
  explicit DisjointSets(size_t n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) p[std::max(a, b)] = std::min(a, b);
  }
  int count() {
    int n = 0;
    for (size_t i = 0; i < p.size(); ++i) n += find(static_cast<int>(i)) == static_cast<int>(i);
    return n;
  }
};

/// Connected components of a surface: faces connected through shared vertices, after welding
/// vertices with identical coordinates. Unused vertices do not count.
inline int surface_components(const SurfaceMesh& m) {
  std::map<std::array<double, 3>, int> weld;
  std::vector<int> id(static_cast<size_t>(m.V.rows()));
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    id[i] = weld.emplace(std::array<double, 3>{m.V(i, 0), m.V(i, 1), m.V(i, 2)}, static_cast<int>(weld.size()))
                .first->second;
  DisjointSets ds(weld.size());
  std::vector<char> used(weld.size(), 0);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) used[id[m.F(f, k)]] = 1;
    ds.unite(id[m.F(f, 0)], id[m.F(f, 1)]);
    ds.unite(id[m.F(f, 0)], id[m.F(f, 2)]);
  }
  int n = 0;
  for (size_t i = 0; i < weld.size(); ++i) n += used[i] && ds.find(static_cast<int>(i)) == static_cast<int>(i);
  return n;
}

/// Enclosed volume of a closed, consistently oriented surface (absolute value of the signed sum,
/// taken about the centroid of the vertices for accuracy far from the origin).
inline double enclosed_volume(const SurfaceMesh& m) {
  const Eigen::RowVector3d c = m.V.colwise().mean();
  double v = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::Vector3d a = (m.V.row(m.F(f, 0)) - c).transpose(), b = (m.V.row(m.F(f, 1)) - c).transpose(),
                          d = (m.V.row(m.F(f, 2)) - c).transpose();
    v += a.dot(b.cross(d)) / 6.0;
  }
  return std::abs(v);
}

/// Distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
inline double point_triangle_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

/// Everything the contracts ask about a tetrahedral mesh, measured here from scratch.
struct TetFacts {
  int tets = 0, vertices = 0;
  int nonpositive = 0;           // tets with volume <= 0
  double min_volume = INFINITY, volume = 0;
  double min_dihedral = 180, max_dihedral = 0;  // degrees
  int overshared_faces = 0;      // faces of three or more tets
  int components = 0;            // face-connected
  int bad_indices = 0;           // indices out of range
  double min_edge = 0, mean_edge = 0;  // over unique edges (units)
  Eigen::MatrixX3i boundary;     // faces of one tet
};

inline double tet_signed_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

/// Interior dihedral angle (degrees) at edge pi-pj of the tet whose other vertices are pk, pl:
/// the angle between pk and pl seen along the edge.
inline double dihedral_at(const Eigen::Vector3d& pi, const Eigen::Vector3d& pj, const Eigen::Vector3d& pk,
                          const Eigen::Vector3d& pl) {
  const Eigen::Vector3d e = (pj - pi).normalized();
  Eigen::Vector3d u = pk - pi, v = pl - pi;
  u -= u.dot(e) * e;
  v -= v.dot(e) * e;
  const double nu = u.norm(), nv = v.norm();
  if (nu == 0 || nv == 0) return 0;
  return std::acos(std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0)) * 180.0 / M_PI;
}

inline TetFacts tet_facts(const TetMesh& m) {
  TetFacts f;
  f.tets = static_cast<int>(m.T.rows());
  f.vertices = static_cast<int>(m.V.rows());
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    for (int k = 0; k < 4; ++k) f.bad_indices += m.T(t, k) < 0 || m.T(t, k) >= m.V.rows();
  if (f.bad_indices) return f;
  static constexpr int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  std::map<std::array<int, 3>, std::vector<std::pair<int, int>>> faces;  // sorted face -> (tet, opposite)
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) {
    Eigen::Vector3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = m.V.row(m.T(t, k)).transpose();
    const double v = tet_signed_volume(p[0], p[1], p[2], p[3]);
    f.nonpositive += !(v > 0);
    f.min_volume = std::min(f.min_volume, v);
    f.volume += v;
    for (const auto& e : kEdges) {
      const double a = dihedral_at(p[e[0]], p[e[1]], p[e[2]], p[e[3]]);
      f.min_dihedral = std::min(f.min_dihedral, a);
      f.max_dihedral = std::max(f.max_dihedral, a);
    }
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> key;
      int q = 0;
      for (int j = 0; j < 4; ++j)
        if (j != k) key[q++] = m.T(t, j);
      std::sort(key.begin(), key.end());
      faces[key].emplace_back(static_cast<int>(t), k);
    }
  }
  std::map<std::pair<int, int>, double> edges;
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int c = a + 1; c < 4; ++c)
        edges[{std::min(m.T(t, a), m.T(t, c)), std::max(m.T(t, a), m.T(t, c))}] =
            (m.V.row(m.T(t, a)) - m.V.row(m.T(t, c))).norm();
  f.min_edge = INFINITY;
  for (const auto& [e, l] : edges) f.min_edge = std::min(f.min_edge, l), f.mean_edge += l;
  if (!edges.empty()) f.mean_edge /= static_cast<double>(edges.size());
  DisjointSets ds(static_cast<size_t>(m.T.rows()));
  std::vector<std::array<int, 3>> b;
  for (const auto& [key, users] : faces) {
    if (users.size() > 2) ++f.overshared_faces;
    for (size_t i = 1; i < users.size(); ++i) ds.unite(users[0].first, users[i].first);
    if (users.size() == 1) {
      // Orient outward: the opposite vertex must be on the negative side.
      const int t = users[0].first, opp = m.T(t, users[0].second);
      std::array<int, 3> tri = key;
      const double s = tet_signed_volume(m.V.row(tri[0]).transpose(), m.V.row(tri[1]).transpose(),
                                         m.V.row(tri[2]).transpose(), m.V.row(opp).transpose());
      if (s > 0) std::swap(tri[1], tri[2]);
      b.push_back(tri);
    }
  }
  f.components = m.T.rows() ? ds.count() : 0;
  f.boundary.resize(static_cast<Eigen::Index>(b.size()), 3);
  for (size_t i = 0; i < b.size(); ++i) f.boundary.row(static_cast<Eigen::Index>(i)) << b[i][0], b[i][1], b[i][2];
  return f;
}

/// Fractions of the points P inside the tet mesh, and inside or within `tolerance` of it
/// (brute force over tets with a bounding-box filter; distance to the boundary faces outside).
struct Coverage {
  double inside = 0, covered = 0;
  double max_distance = 0;  // of the points farther than tolerance (lower bound when above tolerance)
};

inline Coverage coverage(const TetMesh& m, const Eigen::MatrixX3i& boundary, const Eigen::MatrixX3d& P,
                         double tolerance) {
  const Eigen::Index nt = m.T.rows();
  std::vector<Eigen::Vector3d> lo(nt), hi(nt);
  std::vector<Eigen::Matrix3d> inv(nt);
  std::vector<Eigen::Vector3d> origin(nt);
  for (Eigen::Index t = 0; t < nt; ++t) {
    Eigen::Vector3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = m.V.row(m.T(t, k)).transpose();
    lo[t] = p[0].cwiseMin(p[1]).cwiseMin(p[2]).cwiseMin(p[3]);
    hi[t] = p[0].cwiseMax(p[1]).cwiseMax(p[2]).cwiseMax(p[3]);
    Eigen::Matrix3d A;
    A << p[1] - p[0], p[2] - p[0], p[3] - p[0];
    inv[t] = A.inverse();
    origin[t] = p[0];
  }
  const double eps = 1e-9;
  Eigen::Index inside = 0, covered = 0;
  Coverage c;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const Eigen::Vector3d p = P.row(i).transpose();
    bool in = false;
    for (Eigen::Index t = 0; t < nt && !in; ++t) {
      if ((p.array() < lo[t].array() - eps * (hi[t] - lo[t]).norm()).any() ||
          (p.array() > hi[t].array() + eps * (hi[t] - lo[t]).norm()).any())
        continue;
      const Eigen::Vector3d b = inv[t] * (p - origin[t]);
      in = b.minCoeff() >= -eps && b.sum() <= 1 + eps;
    }
    if (in) {
      ++inside, ++covered;
      continue;
    }
    double d = INFINITY;
    for (Eigen::Index f = 0; f < boundary.rows() && d > tolerance; ++f)
      d = std::min(d, point_triangle_distance(p, m.V.row(boundary(f, 0)).transpose(), m.V.row(boundary(f, 1)).transpose(),
                                              m.V.row(boundary(f, 2)).transpose()));
    if (d <= tolerance) ++covered;
    else c.max_distance = std::max(c.max_distance, d);
  }
  c.inside = P.rows() ? double(inside) / double(P.rows()) : 0;
  c.covered = P.rows() ? double(covered) / double(P.rows()) : 0;
  return c;
}

/// What we know about an input independently of squeeze.
struct InputTruth {
  Eigen::MatrixX3d points;  // vertices the mesh must cover
  int components = 1;       // connected components
  bool closed = false;      // closed: check the volume ratio
  double volume = 0;        // enclosed volume (closed inputs)
};

inline InputTruth truth_of(const SurfaceMesh& m, bool closed) {
  InputTruth t;
  t.points = m.V;
  t.components = surface_components(m);
  t.closed = closed;
  t.volume = closed ? enclosed_volume(m) : 0.0;
  return t;
}

/// Checks the contracts of `squeeze mesh` (issue 3) on the tetrahedral mesh `m` written for `in`.
/// Returns the measured facts (for cross-checks against the report).
/// max_volume_ratio: bound of tet volume / input volume for closed inputs (coarse targets may
/// enclose the input more loosely; coverage is what must hold).
inline TetFacts expect_mesh_contract(const TetMesh& m, const InputTruth& in, const std::string& what,
                                     int max_tets = 5000, double max_volume_ratio = 1.35) {
  SCOPED_TRACE(what);
  TetFacts f = tet_facts(m);
  EXPECT_EQ(f.bad_indices, 0) << what << ": tet indices out of range";
  if (f.bad_indices) return f;
  EXPECT_GT(f.tets, 0) << what;
  EXPECT_LE(f.tets, max_tets) << what << ": too many tetrahedra";
  EXPECT_EQ(f.nonpositive, 0) << what << ": tetrahedra with non-positive volume (min " << f.min_volume << ")";
  EXPECT_EQ(f.overshared_faces, 0) << what << ": faces shared by more than two tetrahedra";
  EXPECT_GE(f.min_dihedral, 5.0) << what << ": smallest dihedral angle (degrees)";
  EXPECT_GE(f.components, 1) << what;
  EXPECT_LE(f.components, in.components) << what << ": more tet-mesh components than input components";
  const double diag = diagonal(in.points);
  const Coverage c = coverage(m, f.boundary, in.points, 0.005 * diag);
  EXPECT_GE(c.covered, 0.995) << what << ": fraction of input vertices inside or within 0.5% of the diagonal (inside "
                              << c.inside << ", worst distance " << c.max_distance / diag << " of the diagonal)";
  if (in.closed) {
    const double ratio = f.volume / in.volume;
    EXPECT_GE(ratio, 0.95) << what << ": tet volume " << f.volume << " / input volume " << in.volume;
    EXPECT_LE(ratio, max_volume_ratio) << what << ": tet volume " << f.volume << " / input volume " << in.volume;
  }
  std::printf("[ facts    ] %s: %d tets, %d vertices, dihedral %.2f..%.2f, min/mean edge %.3f, %d component(s) "
              "(input %d), inside %.4f, covered %.4f, volume ratio %s\n",
              what.c_str(), f.tets, f.vertices, f.min_dihedral, f.max_dihedral,
              f.mean_edge > 0 ? f.min_edge / f.mean_edge : 0.0, f.components, in.components, c.inside,
              c.covered, in.closed ? std::to_string(f.volume / in.volume).c_str() : "n/a (open)");
  return f;
}

/// The report of `squeeze mesh --report` holds every key the issue asks for, and its figures agree
/// with what we measured on the written mesh (`f`) and know of the input (`in`).
inline void expect_report(const nlohmann::json& r, const TetFacts& f, const InputTruth& in, const std::string& what) {
  SCOPED_TRACE(what + " (report)");
  auto has = [&](const char* group, const char* key) {
    const bool ok = r.contains(group) && r.at(group).is_object() && r.at(group).contains(key);
    EXPECT_TRUE(ok) << what << ": report lacks " << group << "." << key;
    return ok;
  };
  auto number = [&](const char* group, const char* key) {
    if (!has(group, key)) return std::nan("");
    const auto& v = r.at(group).at(key);
    EXPECT_TRUE(v.is_number()) << what << ": " << group << "." << key << " is not a number";
    return v.is_number() ? v.get<double>() : std::nan("");
  };
  // Why the boundary lies beyond 1.5 times the outer bound (default --max-deviation 0.01): a
  // sentence exactly where it does (meshing version 17).
  EXPECT_TRUE(r.contains("deviation_exceeded_because")) << what << ": report lacks deviation_exceeded_because";
  if (r.contains("deviation_exceeded_because") && r.contains("deviation_out") && r["deviation_out"].is_number()) {
    EXPECT_EQ(r["deviation_exceeded_because"].is_string(), r["deviation_out"].get<double>() > 0.015)
        << what << ": deviation_out " << r["deviation_out"] << ", deviation_exceeded_because " << r["deviation_exceeded_because"];
  }
  // Input.
  EXPECT_GE(number("input", "vertices"), 3);
  EXPECT_GE(number("input", "faces"), 1);
  EXPECT_GE(number("input", "components"), 1);
  if (has("input", "closed")) { EXPECT_TRUE(r["input"]["closed"].is_boolean()); }
  if (has("input", "self_intersecting")) { EXPECT_TRUE(r["input"]["self_intersecting"].is_boolean()); }
  const double in_volume = number("input", "volume");
  EXPECT_GT(in_volume, 0);
  if (in.closed) {
    // Divergence volume of a closed surface is exact (up to float32 files); the winding-number
    // estimate on the voxel grid (used when the surface is not watertight) is within a few percent.
    const bool estimated = r["input"].value("volume_method", "") == "winding_number";
    EXPECT_NEAR(in_volume / in.volume, 1.0, estimated ? 0.05 : 2e-3) << what << ": input volume";
  }
  // Decomposition.
  const double hulls = number("decomposition", "hulls");
  EXPECT_GE(hulls, 1);
  EXPECT_GE(number("decomposition", "max_concavity"), 0);
  // Tetrahedra: the report must describe the file that was written.
  EXPECT_EQ(number("tets", "tets"), f.tets);
  EXPECT_EQ(number("tets", "vertices"), f.vertices);
  EXPECT_NEAR(number("tets", "min_dihedral_deg"), f.min_dihedral, 1e-3);
  EXPECT_NEAR(number("tets", "max_dihedral_deg"), f.max_dihedral, 1e-3);
  EXPECT_NEAR(number("tets", "volume") / f.volume, 1.0, 1e-6);
  // Coverage.
  const double inside = number("coverage", "inside_fraction");
  EXPECT_GE(inside, 0);
  EXPECT_LE(inside, 1);
  // Seconds per stage.
  ASSERT_TRUE(r.contains("seconds") && r["seconds"].is_object()) << what << ": report lacks seconds";
  for (const char* stage : {"loading", "decomposing", "tetrahedralizing"}) {
    EXPECT_TRUE(r["seconds"].contains(stage)) << what << ": no seconds for stage " << stage;
    if (r["seconds"].contains(stage)) { EXPECT_GE(r["seconds"][stage].get<double>(), 0.0); }
  }
}

/// No file in `dir` whose name contains ".tmp-" (temporary outputs left behind).
inline std::vector<std::string> temporaries_in(const fs::path& dir) {
  std::vector<std::string> v;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) v.push_back(e.path().filename().string());
  return v;
}

}  // namespace sqt
