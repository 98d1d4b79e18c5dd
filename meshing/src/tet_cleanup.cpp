#include "squeeze/meshing/tet_cleanup.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <iterator>
#include <cmath>
#include <set>
#include <vector>

#include <tbb/parallel_for.h>

#include "squeeze/meshing/point_triangle_distance.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_geometry.h"
#include "squeeze/meshing/tet_locator.h"

namespace squeeze::meshing {
namespace {

using Vec3 = Eigen::Vector3d;

double min_dihedral_of(const TetMesh& m, int t) {
  const auto a = dihedral_angles(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3)));
  return *std::min_element(a.begin(), a.end());
}

// The smallest dihedral angle of the tetrahedron of m's vertices t, −1 if it is not positively
// oriented (the quality flip_slivers and contract_sliver_edges compare, before and after).
double oriented_quality(const TetMesh& m, const Eigen::Vector4i& t) {
  if (!(tet_volume(m.V.row(t(0)), m.V.row(t(1)), m.V.row(t(2)), m.V.row(t(3))) > 0)) return -1.0;
  const auto a = dihedral_angles(m.V.row(t(0)), m.V.row(t(1)), m.V.row(t(2)), m.V.row(t(3)));
  return *std::min_element(a.begin(), a.end());
}

}  // namespace

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

namespace {

// Keeps the tetrahedra `keep` (ascending rows of T) and their labels, in that order.
void keep_tets(TetMesh& m, const std::vector<int>& keep) {
  Eigen::MatrixX4i T(static_cast<Eigen::Index>(keep.size()), 4);
  Eigen::VectorXi L(m.label.size() ? static_cast<Eigen::Index>(keep.size()) : 0);
  for (size_t i = 0; i < keep.size(); ++i) {
    T.row(static_cast<Eigen::Index>(i)) = m.T.row(keep[i]);
    if (L.size()) L(static_cast<Eigen::Index>(i)) = m.label(keep[i]);
  }
  m.T = std::move(T);
  m.label = std::move(L);
}

}  // namespace

int drop_debris_components(TetMesh& m, double max_fraction) {
  Eigen::VectorXi C;
  const int n = tet_components(m, C);
  if (n <= 1) return 0;
  const Eigen::VectorXd v = tet_volumes(m).cwiseAbs();
  std::vector<double> volume(static_cast<size_t>(n), 0.0);
  double total = 0;
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) {
    volume[static_cast<size_t>(C(t))] += v(t);
    total += v(t);
  }
  const double bound = max_fraction * total;
  std::vector<int> keep;
  for (int t = 0; t < m.T.rows(); ++t)
    if (!(volume[static_cast<size_t>(C(t))] < bound)) keep.push_back(t);
  if (keep.empty()) return 0;  // every component below the bound: keep them all
  const int removed = static_cast<int>(m.T.rows() - static_cast<Eigen::Index>(keep.size()));
  if (removed > 0) keep_tets(m, keep);
  return removed;
}

int drop_slivers(TetMesh& m, double min_degrees) {
  std::vector<int> keep;
  keep.reserve(static_cast<size_t>(m.T.rows()));
  for (int t = 0; t < m.T.rows(); ++t)
    if (!(min_dihedral_of(m, t) < min_degrees)) keep.push_back(t);
  const int removed = static_cast<int>(m.T.rows() - static_cast<Eigen::Index>(keep.size()));
  if (removed > 0) keep_tets(m, keep);
  return removed;
}

int peel_boundary_slivers(TetMesh& m, double min_degrees, double max_height) {
  // How far peeling t moves the boundary: the largest height of t over one of its boundary faces
  // (the distance of the opposite vertex from that face's plane, 3·volume / area).
  auto height = [&](int t, const Eigen::MatrixX4i& boundary_face) {
    Eigen::RowVector3d p[4];
    for (int k = 0; k < 4; ++k) p[k] = m.V.row(m.T(t, k));
    const double six_v = 6.0 * std::abs(tet_volume(p[0], p[1], p[2], p[3]));
    double h = 0;
    for (int k = 0; k < 4; ++k) {
      if (boundary_face(t, k) < 0) continue;
      const Eigen::RowVector3d &a = p[(k + 1) % 4], &b = p[(k + 2) % 4], &c = p[(k + 3) % 4];
      const double twice_area = (b - a).cross(c - a).norm();
      h = std::max(h, twice_area > 0 ? six_v / twice_area : INFINITY);
    }
    return h;
  };
  int removed = 0;
  for (int pass = 0; pass < 16; ++pass) {
    const Eigen::MatrixX4i boundary_face = tet_faces(m.T).boundary_face;
    std::vector<int> keep;
    keep.reserve(static_cast<size_t>(m.T.rows()));
    for (int t = 0; t < m.T.rows(); ++t)
      if (!(boundary_face.row(t).maxCoeff() >= 0 && min_dihedral_of(m, t) < min_degrees &&
            !(height(t, boundary_face) > max_height)))
        keep.push_back(t);
    if (keep.size() == static_cast<size_t>(m.T.rows()) || keep.empty()) break;
    removed += static_cast<int>(m.T.rows()) - static_cast<int>(keep.size());
    keep_tets(m, keep);
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
    const TetFaces faces = tet_faces(m.T);
    const Eigen::Index nb = faces.boundary.rows();
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
    Eigen::MatrixX3d FN, N;
    area_weighted_normals(m.V, faces.boundary, FN, N);
    std::vector<Vec3> fn(static_cast<size_t>(nb));
    std::vector<Vec3> vn(static_cast<size_t>(nv));
    for (Eigen::Index f = 0; f < nb; ++f) {
      const Vec3 n = FN.row(f).transpose();
      const double len = n.norm();
      fn[static_cast<size_t>(f)] = len > 0 ? Vec3(n / len) : Vec3::Zero();
    }
    for (Eigen::Index v = 0; v < nv; ++v) {
      Vec3& n = vn[static_cast<size_t>(v)];
      n = N.row(v).transpose();
      if (n.norm() > 0) n.normalize();
    }
    // Nearest boundary face of every point outside (ties to the lowest index).
    std::vector<int> face(out.size(), 0);
    tbb::parallel_for(size_t(0), out.size(), [&](size_t i) {
      const Vec3 p = P.row(out[i]).transpose();
      double best = INFINITY;
      for (Eigen::Index f = 0; f < nb; ++f) {
        const double d = point_triangle_distance(p, m.V.row(faces.boundary(f, 0)).transpose(),
                                                 m.V.row(faces.boundary(f, 1)).transpose(),
                                                 m.V.row(faces.boundary(f, 2)).transpose());
        if (d < best) best = d, face[i] = static_cast<int>(f);
      }
    });
    std::vector<double> push(static_cast<size_t>(nv), 0.0);
    const double push_share = 0.6;  // of the distance, per round (measured: 1.0 inflates more)
    for (size_t i = 0; i < out.size(); ++i) {
      const int f = face[i];
      for (int k = 0; k < 3; ++k) {
        const int v = faces.boundary(f, k);
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

int relocate_sliver_vertices(TetMesh& m, double min_degrees, int passes) {
  const Eigen::Index nv = m.V.rows(), nt = m.T.rows();
  if (nt == 0) return 0;
  // Vertex → tetrahedra.
  std::vector<std::vector<int>> around(static_cast<size_t>(nv));
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) around[static_cast<size_t>(m.T(t, k))].push_back(t);
  // Boundary vertices and their area-weighted normals (moves stay in the tangent plane).
  const Eigen::MatrixX3i B = boundary_faces(m.T);
  Eigen::MatrixX3d FN, N;  // per boundary face: its area-weighted normal (2 × area); per vertex their sum
  area_weighted_normals(m.V, B, FN, N);
  std::vector<char> on_boundary(static_cast<size_t>(nv), 0);
  for (Eigen::Index f = 0; f < B.rows(); ++f)
    for (int k = 0; k < 3; ++k) on_boundary[static_cast<size_t>(B(f, k))] = 1;
  // A boundary vertex moves only where its boundary faces are nearly coplanar (all within 20
  // degrees of their mean normal): a corner or a crease stays where it is.
  std::vector<char> smooth(static_cast<size_t>(nv), 1);
  for (Eigen::Index f = 0; f < B.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (!(FN.row(f).normalized().dot(N.row(B(f, k)).normalized()) > std::cos(20.0 * M_PI / 180.0)))
        smooth[static_cast<size_t>(B(f, k))] = 0;
  auto volume = [&](int t) { return tet_volume(m.V.row(m.T(t, 0)), m.V.row(m.T(t, 1)), m.V.row(m.T(t, 2)), m.V.row(m.T(t, 3))); };
  // The worst dihedral angle around v (−1 if a tetrahedron is inverted or flat).
  auto local_min = [&](int v) {
    double w = 180.0;
    for (int t : around[static_cast<size_t>(v)]) {
      if (!(volume(t) > 0)) return -1.0;
      w = std::min(w, min_dihedral_of(m, t));
    }
    return w;
  };
  int moves = 0;
  for (int pass = 0; pass < passes; ++pass) {
    int moved = 0;
    for (int t = 0; t < nt; ++t) {
      if (!(min_dihedral_of(m, t) < min_degrees)) continue;
      for (int k = 0; k < 4 && min_dihedral_of(m, t) < min_degrees; ++k) {
        const int v = m.T(t, k);
        const bool surface = on_boundary[static_cast<size_t>(v)];
        if (surface && !smooth[static_cast<size_t>(v)]) continue;
        const Vec3 p0 = m.V.row(v);
        double shortest = INFINITY;
        for (int s : around[static_cast<size_t>(v)])
          for (int j = 0; j < 4; ++j)
            if (m.T(s, j) != v) shortest = std::min(shortest, (m.V.row(m.T(s, j)).transpose() - p0).norm());
        // Directions: the axes and the sliver's height at v (away from its opposite face), in the
        // tangent plane for a boundary vertex.
        const Vec3 a = m.V.row(m.T(t, (k + 1) % 4)), b = m.V.row(m.T(t, (k + 2) % 4)), c = m.V.row(m.T(t, (k + 3) % 4));
        Vec3 dirs[8] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(), (b - a).cross(c - a), Vec3::Zero(), Vec3::Zero(),
                        Vec3::Zero(), Vec3::Zero()};
        const Vec3 n = surface ? Vec3(N.row(v).transpose().normalized()) : Vec3::Zero();
        for (int i = 0; i < 4; ++i) {
          if (surface) dirs[i] -= dirs[i].dot(n) * n;
          const double len = dirs[i].norm();
          dirs[i] = len > 1e-12 ? Vec3(dirs[i] / len) : Vec3::Zero();
          dirs[i + 4] = -dirs[i];
        }
        const double before = local_min(v);
        double best = before;
        Vec3 best_p = p0;
        for (double step : {0.05, 0.1, 0.2})
          for (const Vec3& d : dirs) {
            if (d.isZero()) continue;
            m.V.row(v) = (p0 + step * shortest * d).transpose();
            const double w = local_min(v);
            if (w > best + 1e-9) best = w, best_p = m.V.row(v).transpose();
          }
        m.V.row(v) = best_p.transpose();
        if (best > before) ++moved;
      }
    }
    moves += moved;
    if (moved == 0) break;
  }
  return moves;
}

int flip_slivers(TetMesh& m, double min_degrees, int max_flips) {
  const bool labelled = m.label.size() == m.T.rows();
  // Signed volume of four vertices, and the smallest dihedral angle of a positively oriented
  // tetrahedron (−1 if it is not).
  auto orient = [&](int a, int b, int c, int d) { return tet_volume(m.V.row(a), m.V.row(b), m.V.row(c), m.V.row(d)); };
  auto quality = [&](const Eigen::Vector4i& t) { return oriented_quality(m, t); };
  // A tetrahedron of these vertices, positively oriented (two swapped if needed).
  auto oriented = [&](int a, int b, int c, int d) {
    return orient(a, b, c, d) > 0 ? Eigen::Vector4i(a, b, c, d) : Eigen::Vector4i(b, a, c, d);
  };
  auto has = [&](int t, int v) { return (m.T.row(t).array() == v).any(); };
  // Kept up to date flip by flip (twenty-fifth session, the same meshes; before, each flip
  // measured every tetrahedron and rebuilt the vertex lists again: 31 s for 1,000 flips in a
  // 65,000-tetrahedron mesh, trimesh's ADIS16480.STL): each tetrahedron's quality, the
  // tetrahedra at each vertex, the slivers ordered worst first (ties by row, as a stable sort of
  // the rows gives), and which slivers were found to take no flip since anything within one
  // vertex of them last changed. The flips made are the same: each round takes the worst sliver
  // that takes a flip, as when all were tried again.
  int nt = static_cast<int>(m.T.rows());
  std::vector<double> q(static_cast<size_t>(nt));
  std::vector<std::vector<int>> around(static_cast<size_t>(m.V.rows()));
  std::set<std::pair<double, int>> bad;
  for (int t = 0; t < nt; ++t) {
    q[static_cast<size_t>(t)] = quality(m.T.row(t).transpose());
    if (q[static_cast<size_t>(t)] < min_degrees) bad.emplace(q[static_cast<size_t>(t)], t);
    for (int k = 0; k < 4; ++k) around[static_cast<size_t>(m.T(t, k))].push_back(t);
  }
  std::vector<char> stuck(static_cast<size_t>(nt), 0);  // a sliver that takes no flip as the mesh is
  // The tetrahedra other than `t` that hold every vertex of `vs`.
  auto sharing = [&](std::initializer_list<int> vs, int t) {
    std::vector<int> out;
    for (int s : around[static_cast<size_t>(*vs.begin())]) {
      if (s == t) continue;
      bool all = true;
      for (int v : vs) all = all && has(s, v);
      if (all) out.push_back(s);
    }
    return out;
  };
  auto unlist = [&](int t) {  // t out of its vertices' lists and the slivers
    for (int k = 0; k < 4; ++k) {
      std::vector<int>& a = around[static_cast<size_t>(m.T(t, k))];
      a.erase(std::find(a.begin(), a.end(), t));
    }
    bad.erase({q[static_cast<size_t>(t)], t});
  };
  auto list = [&](int t) {  // t (its row as it is now) into its vertices' lists and the slivers
    q[static_cast<size_t>(t)] = quality(m.T.row(t).transpose());
    for (int k = 0; k < 4; ++k) around[static_cast<size_t>(m.T(t, k))].push_back(t);
    if (q[static_cast<size_t>(t)] < min_degrees) bad.emplace(q[static_cast<size_t>(t)], t);
  };
  std::vector<int> touched;  // vertices of the rows a flip changes (its new rows use only these)
  auto touch = [&](int t) {
    for (int k = 0; k < 4; ++k) touched.push_back(m.T(t, k));
  };
  // The flip of sliver t (2-3 first, over its faces in order, then 3-2 over its edges), where one
  // is valid and raises the smallest dihedral angle of what it replaces.
  auto flip = [&](int t) {
    const double qt = q[static_cast<size_t>(t)];
    // 2-3 flips: t and its neighbour u across face (a, b, c) become three tetrahedra around the
    // edge between their apexes d and e, valid where that edge crosses the face.
    for (int k = 0; k < 4; ++k) {
      const int d = m.T(t, k), a = m.T(t, (k + 1) % 4), b = m.T(t, (k + 2) % 4), c = m.T(t, (k + 3) % 4);
      const std::vector<int> nb = sharing({a, b, c}, t);
      if (nb.size() != 1) continue;  // a boundary face
      const int u = nb[0];
      if (labelled && m.label(u) != m.label(t)) continue;
      int e = -1;
      for (int j = 0; j < 4; ++j)
        if (m.T(u, j) != a && m.T(u, j) != b && m.T(u, j) != c) e = m.T(u, j);
      const double s1 = orient(d, e, a, b), s2 = orient(d, e, b, c), s3 = orient(d, e, c, a);
      if (!((s1 > 0 && s2 > 0 && s3 > 0) || (s1 < 0 && s2 < 0 && s3 < 0))) continue;
      const Eigen::Vector4i n1 = oriented(d, e, a, b), n2 = oriented(d, e, b, c), n3 = oriented(d, e, c, a);
      const double before = std::min(qt, q[static_cast<size_t>(u)]);
      if (!(std::min({quality(n1), quality(n2), quality(n3)}) > before + 1e-9)) continue;
      touch(t), touch(u);
      unlist(t), unlist(u);
      m.T.row(t) = n1.transpose();
      m.T.row(u) = n2.transpose();
      m.T.conservativeResize(nt + 1, 4);
      m.T.row(nt) = n3.transpose();
      if (labelled) {
        m.label.conservativeResize(nt + 1);
        m.label(nt) = m.label(t);
      }
      q.push_back(0.0);
      stuck.push_back(0);
      ++nt;
      for (int s : {t, u, nt - 1}) list(s);
      return true;
    }
    // 3-2 flips: an interior edge (i, j) with exactly three tetrahedra around it, whose other
    // vertices p, q, r make a triangle the edge crosses, becomes two tetrahedra on that triangle.
    for (int k = 0; k < 4; ++k)
      for (int l = k + 1; l < 4; ++l) {
        const int i = m.T(t, k), j = m.T(t, l);
        std::vector<int> ring = sharing({i, j}, t);
        if (ring.size() != 2) continue;
        ring.push_back(t);
        std::vector<int> others;
        for (int s : ring)
          for (int x = 0; x < 4; ++x)
            if (m.T(s, x) != i && m.T(s, x) != j) others.push_back(m.T(s, x));
        std::sort(others.begin(), others.end());
        // Closed ring: three vertices, each in two of the three tetrahedra.
        if (!(others.size() == 6 && others[0] == others[1] && others[2] == others[3] && others[4] == others[5] &&
              others[1] != others[2] && others[3] != others[4]))
          continue;
        if (labelled && !(m.label(ring[0]) == m.label(t) && m.label(ring[1]) == m.label(t))) continue;
        const int p = others[0], pq = others[2], r = others[4];
        const double si = orient(p, pq, r, i), sj = orient(p, pq, r, j);
        if (!((si > 0 && sj < 0) || (si < 0 && sj > 0))) continue;
        const Eigen::Vector4i n1 = oriented(p, pq, r, i), n2 = oriented(p, pq, r, j);
        double before = qt;
        for (int s : ring) before = std::min(before, q[static_cast<size_t>(s)]);
        if (!(std::min(quality(n1), quality(n2)) > before + 1e-9)) continue;
        // Two of the three rows take the new tetrahedra; the third is removed (the last row moves
        // into its place).
        std::sort(ring.begin(), ring.end());
        const int last = nt - 1;
        for (int s : ring) touch(s), unlist(s);
        if (ring[2] != last) touch(last), unlist(last);
        m.T.row(ring[0]) = n1.transpose();
        m.T.row(ring[1]) = n2.transpose();
        if (ring[2] != last) {
          m.T.row(ring[2]) = m.T.row(last);
          if (labelled) m.label(ring[2]) = m.label(last);
        }
        m.T.conservativeResize(last, 4);
        if (labelled) m.label.conservativeResize(last);
        q.pop_back();
        stuck.pop_back();
        nt = last;
        list(ring[0]), list(ring[1]);
        if (ring[2] != last) list(ring[2]);  // (the last row, moved: its vertices touched above)
        return true;
      }
    return false;
  };
  int flips = 0;
  while (flips < max_flips) {
    bool flipped = false;
    for (auto it = bad.begin(); it != bad.end(); ++it) {
      const int t = it->second;
      if (stuck[static_cast<size_t>(t)]) continue;
      touched.clear();
      if (!flip(t)) {
        stuck[static_cast<size_t>(t)] = 1;
        continue;
      }
      // Every sliver within one vertex of a changed row is tried again.
      for (int v : touched)
        for (int s : around[static_cast<size_t>(v)]) stuck[static_cast<size_t>(s)] = 0;
      flipped = true;
      break;
    }
    if (!flipped) break;
    ++flips;
  }
  return flips;
}

int contract_sliver_edges(TetMesh& m, double min_degrees, double max_length, int max_contractions) {
  const int nv = static_cast<int>(m.V.rows());
  std::vector<char> dead(static_cast<size_t>(m.T.rows()), 0);  // tetrahedra a contraction removed
  std::vector<std::set<int>> around(static_cast<size_t>(nv));   // vertex → live tetrahedra
  for (int t = 0; t < m.T.rows(); ++t)
    for (int k = 0; k < 4; ++k) around[static_cast<size_t>(m.T(t, k))].insert(t);
  // The boundary faces, kept up to date (a contraction of a boundary edge changes those at its
  // ends): sorted vertex triples.
  auto sorted3 = [](int a, int b, int c) {
    std::array<int, 3> f{a, b, c};
    std::sort(f.begin(), f.end());
    return f;
  };
  std::vector<std::set<std::array<int, 3>>> boundary(static_cast<size_t>(nv));  // at each vertex
  {
    const Eigen::MatrixX3i B = boundary_faces(m.T);
    for (Eigen::Index f = 0; f < B.rows(); ++f)
      for (int k = 0; k < 3; ++k) boundary[static_cast<size_t>(B(f, k))].insert(sorted3(B(f, 0), B(f, 1), B(f, 2)));
  }
  auto quality = [&](const Eigen::Vector4i& t) { return oriented_quality(m, t); };
  auto has = [&](int t, int v) { return (m.T.row(t).array() == v).any(); };
  // Each tetrahedron's quality, measured once and again where a contraction changes its row.
  std::vector<double> q(static_cast<size_t>(m.T.rows()));
  for (int t = 0; t < m.T.rows(); ++t) q[static_cast<size_t>(t)] = quality(m.T.row(t).transpose());
  constexpr int kOmega = -1;  // the vertex joined to every boundary face (closing the complex)
  // The link of vertex v in the closed complex: its vertices and edges (pairs, smaller first).
  auto link = [&](int v, std::set<int>& LV, std::set<std::pair<int, int>>& LE) {
    auto edge = [&](int a, int b) { LE.insert({std::min(a, b), std::max(a, b)}); };
    for (int t : around[static_cast<size_t>(v)]) {
      int o[3], n = 0;
      for (int k = 0; k < 4; ++k)
        if (m.T(t, k) != v) o[n++] = m.T(t, k);
      for (int x : o) LV.insert(x);
      edge(o[0], o[1]), edge(o[1], o[2]), edge(o[0], o[2]);
    }
    if (!boundary[static_cast<size_t>(v)].empty()) {
      LV.insert(kOmega);
      for (const auto& f : boundary[static_cast<size_t>(v)]) {
        for (int x : f)
          if (x != v) edge(x, kOmega);
      }
    }
  };
  // Contracts r into k (r's tetrahedra take k; those holding both go) where the link condition
  // holds (Dey, Edelsbrunner, Guha, Nekhayev, "Topology preserving edge contraction", 1999), no
  // tetrahedron inverts, and the worst of the changed tetrahedra is better than the worst before.
  auto contract = [&](int k, int r) {
    const bool kb = !boundary[static_cast<size_t>(k)].empty(), rb = !boundary[static_cast<size_t>(r)].empty();
    std::vector<int> both, moved;
    for (int t : around[static_cast<size_t>(r)]) (has(t, k) ? both : moved).push_back(t);
    bool edge_on_boundary = false;
    std::vector<int> wings;  // third vertices of the boundary faces on edge (k, r)
    for (const auto& f : boundary[static_cast<size_t>(r)])
      if (f[0] == k || f[1] == k || f[2] == k) {
        edge_on_boundary = true;
        for (int x : f)
          if (x != k && x != r) wings.push_back(x);
      }
    // The boundary stays where it is, but for a boundary edge contracted to one of its ends.
    if (rb && !(kb && edge_on_boundary)) return false;
    if (kb && rb && !edge_on_boundary) return false;
    // Link condition: Lk(k) ∩ Lk(r) = Lk(kr).
    std::set<int> VK, VR, VKR;
    std::set<std::pair<int, int>> EK, ER, EKR;
    link(k, VK, EK);
    link(r, VR, ER);
    for (int t : both) {
      int o[2], n = 0;
      for (int j = 0; j < 4; ++j)
        if (m.T(t, j) != k && m.T(t, j) != r) o[n++] = m.T(t, j);
      VKR.insert(o[0]), VKR.insert(o[1]);
      EKR.insert({std::min(o[0], o[1]), std::max(o[0], o[1])});
    }
    if (edge_on_boundary) {
      VKR.insert(kOmega);
      for (int w : wings) VKR.insert(w), EKR.insert({kOmega, w});
    }
    std::set<int> VI;
    std::set_intersection(VK.begin(), VK.end(), VR.begin(), VR.end(), std::inserter(VI, VI.begin()));
    std::set<std::pair<int, int>> EI;
    std::set_intersection(EK.begin(), EK.end(), ER.begin(), ER.end(), std::inserter(EI, EI.begin()));
    if (VI != VKR || EI != EKR) return false;
    // Quality: the worst changed tetrahedron better than the worst of those before (the removed
    // ones included), and fewer below the floor.
    double before = INFINITY, after = INFINITY;
    int below_before = 0, below_after = 0;
    for (int t : both) {
      const double qt = q[static_cast<size_t>(t)];
      before = std::min(before, qt), below_before += qt < min_degrees;
    }
    std::vector<Eigen::Vector4i> rows;
    std::vector<double> after_q;
    for (int t : moved) {
      const double qt = q[static_cast<size_t>(t)];
      before = std::min(before, qt), below_before += qt < min_degrees;
      Eigen::Vector4i row = m.T.row(t).transpose();
      for (int j = 0; j < 4; ++j)
        if (row(j) == r) row(j) = k;
      const double qn = quality(row);
      if (!(qn > 0)) return false;
      after = std::min(after, qn), below_after += qn < min_degrees;
      rows.push_back(row);
      after_q.push_back(qn);
    }
    if (!(after > before + 1e-9 && below_after < below_before)) return false;
    // Made: the boundary faces at r move to k (those on the edge go), then the rows.
    if (rb) {
      const std::vector<std::array<int, 3>> at_r(boundary[static_cast<size_t>(r)].begin(),
                                                 boundary[static_cast<size_t>(r)].end());
      for (const auto& f : at_r) {
        for (int x : f) boundary[static_cast<size_t>(x)].erase(f);
        if (f[0] == k || f[1] == k || f[2] == k) continue;
        std::array<int, 3> g = f;
        for (int& x : g)
          if (x == r) x = k;
        g = sorted3(g[0], g[1], g[2]);
        for (int x : g) boundary[static_cast<size_t>(x)].insert(g);
      }
    }
    for (int t : both) {
      dead[static_cast<size_t>(t)] = 1;
      for (int j = 0; j < 4; ++j) around[static_cast<size_t>(m.T(t, j))].erase(t);
    }
    for (size_t i = 0; i < moved.size(); ++i) {
      m.T.row(moved[i]) = rows[i].transpose();
      q[static_cast<size_t>(moved[i])] = after_q[i];
      around[static_cast<size_t>(r)].erase(moved[i]);
      around[static_cast<size_t>(k)].insert(moved[i]);
    }
    return true;
  };
  int made = 0;
  // A sliver none of whose edges contracted is tried again only once a contraction changed a
  // tetrahedron within one vertex of it (as flip_slivers does).
  std::vector<char> stuck(static_cast<size_t>(m.T.rows()), 0);
  for (bool progress = true; progress && made < max_contractions;) {
    progress = false;
    // The slivers, worst first (ties by row).
    std::vector<std::pair<double, int>> bad;
    for (int t = 0; t < m.T.rows(); ++t)
      if (!dead[static_cast<size_t>(t)] && !stuck[static_cast<size_t>(t)] && q[static_cast<size_t>(t)] < min_degrees)
        bad.emplace_back(q[static_cast<size_t>(t)], t);
    std::sort(bad.begin(), bad.end());
    for (const auto& [qt, t] : bad) {
      if (dead[static_cast<size_t>(t)] || stuck[static_cast<size_t>(t)]) continue;
      // Its edges, shortest first; each contracted toward either end.
      std::array<std::pair<double, std::pair<int, int>>, 6> edges;
      int n = 0;
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b)
          edges[static_cast<size_t>(n++)] = {(m.V.row(m.T(t, a)) - m.V.row(m.T(t, b))).norm(), {m.T(t, a), m.T(t, b)}};
      std::sort(edges.begin(), edges.end());
      bool contracted = false;
      for (const auto& [len, e] : edges) {
        if (!(len <= max_length)) break;
        int kept = -1;
        if (contract(e.first, e.second))
          kept = e.first;
        else if (contract(e.second, e.first))
          kept = e.second;
        if (kept < 0) continue;
        ++made;
        progress = contracted = true;
        // The slivers within one vertex of the kept end's tetrahedra are tried again.
        for (int s : around[static_cast<size_t>(kept)])
          for (int j = 0; j < 4; ++j)
            for (int u : around[static_cast<size_t>(m.T(s, j))]) stuck[static_cast<size_t>(u)] = 0;
        break;
      }
      if (!contracted) stuck[static_cast<size_t>(t)] = 1;
      if (made >= max_contractions) break;
    }
  }
  if (made > 0) {
    std::vector<int> keep;
    for (int t = 0; t < m.T.rows(); ++t)
      if (!dead[static_cast<size_t>(t)]) keep.push_back(t);
    keep_tets(m, keep);
  }
  return made;
}

}  // namespace squeeze::meshing
