#include "squeeze/meshing/tet_quality.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numeric>
#include <vector>

#include <tbb/parallel_for.h>

namespace squeeze::meshing {
namespace {

using Vec3 = Eigen::Vector3d;

// Faces of tet (v0,v1,v2,v3) oriented outward for a positively oriented tet.
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceRef {
  std::array<int, 3> key;  // sorted vertex ids
  int tet, local;
};

std::vector<FaceRef> sorted_faces(const Eigen::MatrixX4i& T) {
  std::vector<FaceRef> f;
  f.reserve(static_cast<size_t>(T.rows()) * 4);
  for (int t = 0; t < T.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> key{T(t, kFace[k][0]), T(t, kFace[k][1]), T(t, kFace[k][2])};
      std::sort(key.begin(), key.end());
      f.push_back({key, t, k});
    }
  std::sort(f.begin(), f.end(), [](const FaceRef& a, const FaceRef& b) {
    return a.key != b.key ? a.key < b.key : a.tet < b.tet;
  });
  return f;
}

template <class Fn>
void for_each_face(const std::vector<FaceRef>& f, Fn fn) {
  for (size_t i = 0; i < f.size();) {
    size_t j = i + 1;
    while (j < f.size() && f[j].key == f[i].key) ++j;
    fn(i, j);
    i = j;
  }
}

double min_dihedral_of(const TetMesh& m, int t) {
  const auto a = dihedral_angles(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3)));
  return *std::min_element(a.begin(), a.end());
}

}  // namespace

double tet_volume(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b, const Eigen::RowVector3d& c,
                  const Eigen::RowVector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

Eigen::VectorXd tet_volumes(const TetMesh& m) {
  Eigen::VectorXd v(m.T.rows());
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    v(t) = tet_volume(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3)));
  return v;
}

std::array<double, 6> dihedral_angles(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b,
                                      const Eigen::RowVector3d& c, const Eigen::RowVector3d& d) {
  const Vec3 p[4] = {a.transpose(), b.transpose(), c.transpose(), d.transpose()};
  // Outward face normals; the dihedral angle at edge (i,j) is pi minus the angle between the
  // normals of the two faces that contain it.
  Vec3 n[4];
  for (int k = 0; k < 4; ++k) {
    const Vec3 u = p[kFace[k][1]] - p[kFace[k][0]], v = p[kFace[k][2]] - p[kFace[k][0]];
    n[k] = u.cross(v);
    const double len = n[k].norm();
    if (len > 0) n[k] /= len;
  }
  // Face k is opposite vertex k; edge (i,j) is shared by the faces opposite the other two vertices.
  static constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  std::array<double, 6> out{};
  for (int e = 0; e < 6; ++e) {
    int f[2], q = 0;
    for (int k = 0; k < 4; ++k)
      if (k != kEdge[e][0] && k != kEdge[e][1]) f[q++] = k;
    const double cosang = std::clamp(-n[f[0]].dot(n[f[1]]), -1.0, 1.0);
    out[e] = std::acos(cosang) * 180.0 / M_PI;
  }
  return out;
}

void orient_positively(TetMesh& m) {
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    if (tet_volume(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3))) < 0)
      std::swap(m.T(t, 2), m.T(t, 3));
}

void remove_unused_vertices(TetMesh& m) {
  std::vector<int> map(static_cast<size_t>(m.V.rows()), -1);
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    for (int k = 0; k < 4; ++k) map[m.T(t, k)] = 0;
  int n = 0;
  for (auto& x : map)
    if (x == 0) x = n++;
  Eigen::MatrixX3d V(n, 3);
  for (size_t i = 0; i < map.size(); ++i)
    if (map[i] >= 0) V.row(map[i]) = m.V.row(static_cast<Eigen::Index>(i));
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    for (int k = 0; k < 4; ++k) m.T(t, k) = map[m.T(t, k)];
  m.V = std::move(V);
}

int peel_boundary_slivers(TetMesh& m, double min_degrees) {
  int removed = 0;
  for (int pass = 0; pass < 16; ++pass) {
    const auto faces = sorted_faces(m.T);
    std::vector<int> boundary_faces(static_cast<size_t>(m.T.rows()), 0);
    for_each_face(faces, [&](size_t i, size_t j) {
      if (j - i == 1) ++boundary_faces[faces[i].tet];
    });
    std::vector<int> keep;
    keep.reserve(static_cast<size_t>(m.T.rows()));
    for (int t = 0; t < m.T.rows(); ++t)
      if (!(boundary_faces[t] > 0 && min_dihedral_of(m, t) < min_degrees)) keep.push_back(t);
    if (keep.size() == static_cast<size_t>(m.T.rows()) || keep.empty()) break;
    removed += static_cast<int>(m.T.rows()) - static_cast<int>(keep.size());
    Eigen::MatrixX4i T(static_cast<Eigen::Index>(keep.size()), 4);
    Eigen::VectorXi L(m.label.size() ? static_cast<Eigen::Index>(keep.size()) : 0);
    for (size_t i = 0; i < keep.size(); ++i) {
      T.row(static_cast<Eigen::Index>(i)) = m.T.row(keep[i]);
      if (L.size()) L(static_cast<Eigen::Index>(i)) = m.label(keep[i]);
    }
    m.T = std::move(T);
    m.label = std::move(L);
  }
  return removed;
}

int inflate_to_cover(TetMesh& m, const Eigen::MatrixX3d& P, double tolerance, double min_degrees, int iterations) {
  int moves = 0;
  const Eigen::Index nv = m.V.rows();
  // Tets around each vertex (CSR).
  std::vector<int> start(static_cast<size_t>(nv) + 1, 0), items;
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    for (int k = 0; k < 4; ++k) ++start[static_cast<size_t>(m.T(t, k)) + 1];
  for (size_t i = 0; i < static_cast<size_t>(nv); ++i) start[i + 1] += start[i];
  items.resize(static_cast<size_t>(start.back()));
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (Eigen::Index t = 0; t < m.T.rows(); ++t)
      for (int k = 0; k < 4; ++k) items[static_cast<size_t>(fill[static_cast<size_t>(m.T(t, k))]++)] = static_cast<int>(t);
  }
  for (int round = 0; round < iterations; ++round) {
    const FaceCensus census = face_census(m);
    const Eigen::Index nb = census.boundary.rows();
    if (nb == 0) break;
    // Points outside by more than the tolerance, and their distance.
    const TetLocator locator(m);
    std::vector<double> dist(static_cast<size_t>(P.rows()), 0.0);
    tbb::parallel_for(Eigen::Index(0), P.rows(), [&](Eigen::Index i) {
      if (locator.locate(P.row(i)) < 0) locator.nearest(P.row(i), &dist[static_cast<size_t>(i)]);
    });
    std::vector<Eigen::Index> out;
    for (Eigen::Index i = 0; i < P.rows(); ++i)
      if (dist[static_cast<size_t>(i)] > tolerance) out.push_back(i);
    if (out.empty()) break;
    // Boundary face normals and vertex normals (area weighted).
    std::vector<Vec3> fn(static_cast<size_t>(nb));
    std::vector<Vec3> vn(static_cast<size_t>(nv), Vec3::Zero());
    for (Eigen::Index f = 0; f < nb; ++f) {
      const Vec3 a = m.V.row(census.boundary(f, 0)).transpose(), b = m.V.row(census.boundary(f, 1)).transpose(),
                 c = m.V.row(census.boundary(f, 2)).transpose();
      const Vec3 n = (b - a).cross(c - a);
      for (int k = 0; k < 3; ++k) vn[static_cast<size_t>(census.boundary(f, k))] += n;
      const double len = n.norm();
      fn[static_cast<size_t>(f)] = len > 0 ? Vec3(n / len) : Vec3::Zero();
    }
    for (auto& n : vn)
      if (n.norm() > 0) n.normalize();
    // Nearest boundary face of every point outside (ties to the lowest index).
    std::vector<int> face(out.size(), 0);
    tbb::parallel_for(size_t(0), out.size(), [&](size_t i) {
      const Vec3 p = P.row(out[i]).transpose();
      double best = INFINITY;
      for (Eigen::Index f = 0; f < nb; ++f) {
        const double d = point_triangle_distance(p, m.V.row(census.boundary(f, 0)).transpose(),
                                                 m.V.row(census.boundary(f, 1)).transpose(),
                                                 m.V.row(census.boundary(f, 2)).transpose());
        if (d < best) best = d, face[i] = static_cast<int>(f);
      }
    });
    std::vector<double> push(static_cast<size_t>(nv), 0.0);
    const double push_share = 0.6;  // of the distance, per round (measured: 1.0 inflates more)
    for (size_t i = 0; i < out.size(); ++i) {
      const int f = face[i];
      for (int k = 0; k < 3; ++k) {
        const int v = census.boundary(f, k);
        // Barycentric share: the face vertex nearest the point moves the most; later rounds
        // finish what a short push leaves (pushing all three by the full distance inflates).
        const double along = std::max(0.5, vn[static_cast<size_t>(v)].dot(fn[static_cast<size_t>(f)]));
        push[static_cast<size_t>(v)] = std::max(push[static_cast<size_t>(v)], push_share * dist[static_cast<size_t>(out[i])] / along);
      }
    }
    // Apply, halving (then dropping) moves that would spoil a tetrahedron.
    std::vector<int> moved;
    for (Eigen::Index v = 0; v < nv; ++v)
      if (push[static_cast<size_t>(v)] > 0) moved.push_back(static_cast<int>(v));
    if (moved.empty()) break;
    const Eigen::MatrixX3d before = m.V;
    std::vector<double> scale(static_cast<size_t>(nv), 1.0);
    auto tet_ok = [&](int t) {
      const Eigen::RowVector3d a = m.V.row(m.T(t, 0)), b = m.V.row(m.T(t, 1)), c = m.V.row(m.T(t, 2)), d = m.V.row(m.T(t, 3));
      if (!(tet_volume(a, b, c, d) > 0)) return false;
      const auto now = dihedral_angles(a, b, c, d);
      const auto old = dihedral_angles(before.row(m.T(t, 0)), before.row(m.T(t, 1)), before.row(m.T(t, 2)),
                                       before.row(m.T(t, 3)));
      const double lo = std::min(min_degrees, *std::min_element(old.begin(), old.end()));
      return *std::min_element(now.begin(), now.end()) >= lo;
    };
    bool ok = false;
    for (int attempt = 0; attempt < 8 && !ok; ++attempt) {
      for (int v : moved)
        m.V.row(v) = before.row(v) + scale[static_cast<size_t>(v)] * push[static_cast<size_t>(v)] * vn[static_cast<size_t>(v)].transpose();
      ok = true;
      for (int v : moved) {
        if (scale[static_cast<size_t>(v)] == 0.0) continue;
        for (int j = start[static_cast<size_t>(v)]; j < start[static_cast<size_t>(v) + 1]; ++j) {
          const int t = items[static_cast<size_t>(j)];
          if (tet_ok(t)) continue;
          ok = false;
          for (int k = 0; k < 4; ++k) {
            double& sc = scale[static_cast<size_t>(m.T(t, k))];
            sc = attempt >= 3 ? 0.0 : 0.5 * sc;
          }
        }
      }
    }
    if (!ok) {
      m.V = before;
      break;
    }
    int made = 0;
    for (int v : moved) made += scale[static_cast<size_t>(v)] > 0;
    moves += made;
    if (made == 0) break;
  }
  return moves;
}

FaceCensus face_census(const TetMesh& m) {
  FaceCensus c;
  const auto faces = sorted_faces(m.T);
  std::vector<std::array<int, 3>> b;
  for_each_face(faces, [&](size_t i, size_t j) {
    if (j - i == 1) {
      const FaceRef& f = faces[i];
      b.push_back({m.T(f.tet, kFace[f.local][0]), m.T(f.tet, kFace[f.local][1]), m.T(f.tet, kFace[f.local][2])});
    } else if (j - i == 2) {
      ++c.interior;
    } else {
      ++c.overshared;
    }
  });
  c.boundary.resize(static_cast<Eigen::Index>(b.size()), 3);
  for (size_t i = 0; i < b.size(); ++i) c.boundary.row(static_cast<Eigen::Index>(i)) << b[i][0], b[i][1], b[i][2];
  return c;
}

int tet_components(const TetMesh& m, Eigen::VectorXi& C) {
  const auto faces = sorted_faces(m.T);
  std::vector<int> parent(static_cast<size_t>(m.T.rows()));
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> find = [&](int x) { return parent[x] == x ? x : parent[x] = find(parent[x]); };
  for_each_face(faces, [&](size_t i, size_t j) {
    for (size_t k = i + 1; k < j; ++k) {
      const int a = find(faces[i].tet), b = find(faces[k].tet);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  });
  C.resize(m.T.rows());
  std::vector<int> id(static_cast<size_t>(m.T.rows()), -1);
  int n = 0;
  for (int t = 0; t < m.T.rows(); ++t) {
    const int r = find(t);
    if (id[r] < 0) id[r] = n++;
    C(t) = id[r];
  }
  return n;
}

TetQuality tet_quality(const TetMesh& m) {
  TetQuality q;
  q.tets = static_cast<int>(m.T.rows());
  q.vertices = static_cast<int>(m.V.rows());
  if (q.tets == 0) return q;
  const Eigen::VectorXd vol = tet_volumes(m);
  q.min_volume = vol.minCoeff();
  q.volume = vol.sum();
  q.min_dihedral = 180.0;
  q.max_dihedral = 0.0;
  for (int t = 0; t < q.tets; ++t) {
    const auto a = dihedral_angles(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3)));
    q.min_dihedral = std::min(q.min_dihedral, *std::min_element(a.begin(), a.end()));
    q.max_dihedral = std::max(q.max_dihedral, *std::max_element(a.begin(), a.end()));
  }
  // Unique edges: (min, max) vertex pairs of the six edges of every tet.
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<size_t>(q.tets) * 6);
  for (int t = 0; t < q.tets; ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edges.emplace_back(std::min(m.T(t, a), m.T(t, b)), std::max(m.T(t, a), m.T(t, b)));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  q.min_edge = INFINITY;
  double sum = 0;
  for (const auto& [a, b] : edges) {
    const double l = (m.V.row(a) - m.V.row(b)).norm();
    q.min_edge = std::min(q.min_edge, l);
    sum += l;
  }
  q.mean_edge = sum / static_cast<double>(edges.size());
  Eigen::VectorXi C;
  q.components = tet_components(m, C);
  q.overshared_faces = face_census(m).overshared;
  return q;
}

double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Ericson, Real-Time Collision Detection, 5.1.5 (closest point on triangle).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + (d1 / (d1 - d3)) * ab)).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + (d2 / (d2 - d6)) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

TetLocator::TetLocator(const TetMesh& mesh) : mesh_(mesh) {
  const auto& V = mesh.V;
  const auto& T = mesh.T;
  if (T.rows() == 0) return;
  Vec3 lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  double edge = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t) edge += (V.row(T(t, 0)) - V.row(T(t, 1))).norm();
  edge /= static_cast<double>(T.rows());
  const double extent = (hi - lo).maxCoeff();
  cell_ = std::max({edge, extent / 256.0, 1e-300});
  origin_ = lo;
  for (int k = 0; k < 3; ++k) n_[k] = std::max(1, static_cast<int>(std::ceil((hi(k) - lo(k)) / cell_)) + 1);
  const size_t cells = static_cast<size_t>(n_[0]) * n_[1] * n_[2];
  std::vector<int> count(cells + 1, 0);
  box_.resize(static_cast<size_t>(T.rows()) * 6);
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    Vec3 tlo = V.row(T(t, 0)).transpose(), thi = tlo;
    for (int k = 1; k < 4; ++k) {
      tlo = tlo.cwiseMin(V.row(T(t, k)).transpose());
      thi = thi.cwiseMax(V.row(T(t, k)).transpose());
    }
    // Padding covers locate()'s tolerance: barycentric >= -1e-10 is within 1e-10 diameters.
    const double pad = 1e-9 * (thi - tlo).maxCoeff();
    for (int k = 0; k < 3; ++k) {
      box_[6 * t + k] = tlo(k) - pad;
      box_[6 * t + 3 + k] = thi(k) + pad;
    }
  }
  auto range = [&](Eigen::Index t, int a[3], int b[3]) {
    Vec3 tlo = V.row(T(t, 0)).transpose(), thi = tlo;
    for (int k = 1; k < 4; ++k) {
      tlo = tlo.cwiseMin(V.row(T(t, k)).transpose());
      thi = thi.cwiseMax(V.row(T(t, k)).transpose());
    }
    for (int k = 0; k < 3; ++k) {
      a[k] = std::clamp(static_cast<int>(std::floor((tlo(k) - origin_(k)) / cell_)), 0, n_[k] - 1);
      b[k] = std::clamp(static_cast<int>(std::floor((thi(k) - origin_(k)) / cell_)), 0, n_[k] - 1);
    }
  };
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      for (size_t c = 0; c < cells; ++c) count[c + 1] += count[c];
      start_ = count;
      items_.resize(static_cast<size_t>(count[cells]));
    }
    for (Eigen::Index t = 0; t < T.rows(); ++t) {
      int a[3], b[3];
      range(t, a, b);
      for (int k = a[2]; k <= b[2]; ++k)
        for (int j = a[1]; j <= b[1]; ++j)
          for (int i = a[0]; i <= b[0]; ++i) {
            const size_t c = static_cast<size_t>(i) + n_[0] * (static_cast<size_t>(j) + n_[1] * static_cast<size_t>(k));
            if (pass == 0) ++count[c + 1];
            else items_[count[c]++] = static_cast<int>(t);
          }
    }
  }
}

bool TetLocator::in_box(int t, const Vec3& p) const {
  const double* b = &box_[6 * static_cast<size_t>(t)];
  return p(0) >= b[0] && p(1) >= b[1] && p(2) >= b[2] && p(0) <= b[3] && p(1) <= b[4] && p(2) <= b[5];
}

double TetLocator::box_distance(int t, const Vec3& p) const {
  const double* b = &box_[6 * static_cast<size_t>(t)];
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max({b[k] - p(k), 0.0, p(k) - b[3 + k]});
    s += d * d;
  }
  return std::sqrt(s);
}

Eigen::Vector4d TetLocator::barycentric(int t, const Eigen::RowVector3d& p) const {
  const auto& V = mesh_.V;
  const auto& T = mesh_.T;
  const Vec3 a = V.row(T(t, 0)).transpose();
  Eigen::Matrix3d M;
  M.col(0) = V.row(T(t, 1)).transpose() - a;
  M.col(1) = V.row(T(t, 2)).transpose() - a;
  M.col(2) = V.row(T(t, 3)).transpose() - a;
  const Vec3 x = M.partialPivLu().solve(p.transpose() - a);
  return Eigen::Vector4d(1.0 - x.sum(), x(0), x(1), x(2));
}

int TetLocator::locate(const Eigen::RowVector3d& p, Eigen::Vector4d* bary) const {
  if (items_.empty()) return -1;
  int c[3];
  for (int k = 0; k < 3; ++k) {
    c[k] = static_cast<int>(std::floor((p(k) - origin_(k)) / cell_));
    if (c[k] < 0 || c[k] >= n_[k]) return -1;
  }
  const size_t cell = static_cast<size_t>(c[0]) + n_[0] * (static_cast<size_t>(c[1]) + n_[1] * static_cast<size_t>(c[2]));
  int best = -1;
  for (int i = start_[cell]; i < start_[cell + 1]; ++i) {
    const int t = items_[i];
    if (best >= 0 && t > best) continue;
    if (!in_box(t, p.transpose())) continue;
    const Eigen::Vector4d b = barycentric(t, p);
    if (b.minCoeff() >= -1e-10) {
      best = t;
      if (bary) *bary = b;
    }
  }
  return best;
}

double TetLocator::distance_to(int t, const Vec3& p) const {
  const Eigen::Vector4d b = barycentric(t, p.transpose());
  if (b.minCoeff() >= 0) return 0.0;
  const auto& V = mesh_.V;
  const auto& T = mesh_.T;
  double d = INFINITY;
  for (int k = 0; k < 4; ++k)
    d = std::min(d, point_triangle_distance(p, V.row(T(t, kFace[k][0])).transpose(), V.row(T(t, kFace[k][1])).transpose(),
                                            V.row(T(t, kFace[k][2])).transpose()));
  return d;
}

int TetLocator::nearest(const Eigen::RowVector3d& p, double* distance) const {
  if (mesh_.T.rows() == 0) return -1;
  const Vec3 q = p.transpose();
  int c[3];
  double outside = 0.0;  // distance from p to the grid box
  for (int k = 0; k < 3; ++k) {
    const double x = (q(k) - origin_(k)) / cell_;
    c[k] = std::clamp(static_cast<int>(std::floor(x)), 0, n_[k] - 1);
    const double below = std::max(0.0, -x), above = std::max(0.0, x - n_[k]);
    outside = std::max({outside, below * cell_, above * cell_});
  }
  int best = -1;
  double best_d = INFINITY;
  const int max_ring = std::max({n_[0], n_[1], n_[2]});
  for (int r = 0; r <= max_ring; ++r) {
    // Cells in ring r are at least (r - 1) cells away from p (plus its distance to the grid).
    if (best >= 0 && std::max((r - 1) * cell_, outside) > best_d) break;
    for (int k = c[2] - r; k <= c[2] + r; ++k)
      for (int j = c[1] - r; j <= c[1] + r; ++j)
        for (int i = c[0] - r; i <= c[0] + r; ++i) {
          if (std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])}) != r) continue;
          if (i < 0 || j < 0 || k < 0 || i >= n_[0] || j >= n_[1] || k >= n_[2]) continue;
          if (best >= 0) {  // skip cells entirely farther than the best so far
            double s = 0;
            const int cc[3] = {i, j, k};
            for (int a = 0; a < 3; ++a) {
              const double lo = origin_(a) + cc[a] * cell_, hi = lo + cell_;
              const double d = std::max({lo - q(a), 0.0, q(a) - hi});
              s += d * d;
            }
            if (std::sqrt(s) > best_d) continue;
          }
          const size_t cell = static_cast<size_t>(i) + n_[0] * (static_cast<size_t>(j) + n_[1] * static_cast<size_t>(k));
          for (int s = start_[cell]; s < start_[cell + 1]; ++s) {
            const int t = items_[s];
            if (best >= 0 && box_distance(t, q) > best_d) continue;
            const double d = distance_to(t, q);
            if (d < best_d || (d == best_d && t < best)) best_d = d, best = t;
          }
        }
  }
  if (distance) *distance = best_d;
  return best;
}

}  // namespace squeeze::meshing
