// Open sheets and their slabs (sheet.h).
#include "squeeze/meshing/sheet.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "squeeze/common/error.h"
#include "squeeze/meshing/split_long_edges.h"
#include "squeeze/meshing/surface_analysis.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/winding_number.h"

namespace squeeze::meshing {

SheetEvidence sheet_evidence(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  SheetEvidence e;
  if (F.rows() == 0) return e;
  const std::vector<EdgeIncidence> h = edge_incidences(F);
  bool manifold = true;
  int boundary = 0;
  std::vector<int> rim_edges(static_cast<size_t>(V.rows()), 0);  // boundary edges at each vertex
  for_each_edge(h, [&](size_t i, size_t j) {
    if (j - i == 1) {
      ++boundary;
      ++rim_edges[static_cast<size_t>(h[i].a)];
      ++rim_edges[static_cast<size_t>(h[i].b)];
    } else if (j - i > 2 || h[i].forward == h[i + 1].forward) {
      manifold = false;
    }
  });
  // A vertex on the boundary has two boundary edges; four or more: two fans meeting at a point (a
  // bow tie), which no offset or remeshing takes.
  for (int n : rim_edges) manifold = manifold && (n == 0 || n == 2);
  e.open_manifold = manifold && boundary > 0;
  e.closed_manifold = manifold && boundary == 0;
  if (!e.open_manifold) return e;
  const FastWindingNumber w(V, F);
  const double diag = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  const double eps = 1e-4 * diag;
  Eigen::VectorXd outside, inside;
  const Eigen::VectorXd face_area = face_offset_winding_numbers(w, V, F, eps, &outside, &inside);
  double total = 0, sheet = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    total += face_area(f);
    const double p = std::abs(outside(f)), q = std::abs(inside(f));
    if (p > 0.25 && p < 0.75 && q > 0.25 && q < 0.75) sheet += face_area(f);
  }
  e.sheet_area_fraction = total > 0 ? sheet / total : 0.0;
  return e;
}

int split_bow_ties(SurfaceMesh& m, std::vector<int>* index) {
  const Eigen::Index nv = m.V.rows();
  if (m.F.rows() == 0) return 0;
  const std::vector<std::vector<int>> faces_at = vertex_faces(m.F, nv);
  std::vector<Eigen::RowVector3d> added;
  int copies = 0;
  for (Eigen::Index v = 0; v < nv; ++v) {
    const std::vector<int>& at = faces_at[static_cast<size_t>(v)];
    // The faces of each edge (v, w) are among v's: edges in one face are boundary edges, fans are
    // v's faces joined across edges in exactly two (union-find over `at`).
    std::map<int, std::vector<size_t>> across;  // w -> faces in `at` with the edge (v, w)
    for (size_t i = 0; i < at.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        const int w = m.F(at[i], k);
        if (w != v) across[w].push_back(i);
      }
    int rim = 0;
    for (const auto& [w, fs] : across) rim += fs.size() == 1 ? 1 : 0;
    if (rim < 4) continue;
    std::vector<int> parent(at.size());
    for (size_t i = 0; i < at.size(); ++i) parent[i] = static_cast<int>(i);
    std::function<int(int)> root = [&](int i) {
      int& up = parent[static_cast<size_t>(i)];
      return up == i ? i : up = root(up);
    };
    for (const auto& [w, fs] : across)
      if (fs.size() == 2) parent[static_cast<size_t>(root(static_cast<int>(fs[0])))] = root(static_cast<int>(fs[1]));
    std::map<int, std::vector<int>> fans;  // root -> faces
    for (size_t i = 0; i < at.size(); ++i) fans[root(static_cast<int>(i))].push_back(at[i]);
    if (fans.size() < 2) continue;
    bool first = true;
    for (const auto& [r, fs] : fans) {
      if (first) {  // (the first fan keeps the vertex)
        first = false;
        continue;
      }
      Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
      double shortest = INFINITY;
      for (int f : fs) {
        for (int k = 0; k < 3; ++k) {
          centroid += m.V.row(m.F(f, k)) / (3.0 * static_cast<double>(fs.size()));
          if (m.F(f, k) != v) shortest = std::min(shortest, (m.V.row(m.F(f, k)) - m.V.row(v)).norm());
        }
      }
      const Eigen::RowVector3d toward = centroid - m.V.row(v);
      const double len = toward.norm();
      const Eigen::RowVector3d at_v = m.V.row(v);
      added.push_back(len > 0 && std::isfinite(shortest) ? Eigen::RowVector3d(at_v + 0.01 * shortest * toward / len) : at_v);
      const int copy = static_cast<int>(nv) + static_cast<int>(added.size()) - 1;
      for (int f : fs)
        for (int k = 0; k < 3; ++k)
          if (m.F(f, k) == v) m.F(f, k) = copy;
      if (index) index->push_back((*index)[static_cast<size_t>(v)]);
      ++copies;
    }
  }
  if (copies == 0) return 0;
  m.V.conservativeResize(nv + static_cast<Eigen::Index>(added.size()), Eigen::NoChange);
  for (size_t i = 0; i < added.size(); ++i) m.V.row(nv + static_cast<Eigen::Index>(i)) = added[i];
  return copies;
}

namespace {

// Each vertex's offset direction and half thickness (thicken_sheet): base[v], or half_thickness
// when base is empty, limited where the sheet bends and where another part of it is near.
struct Offsets {
  Eigen::MatrixX3d N;       // #V by 3 unit directions
  std::vector<double> hv;   // #V half thicknesses (units)
};

Offsets offsets(const SurfaceMesh& sheet, double half_thickness, const std::vector<double>& base) {
  if (!(half_thickness > 0)) throw InputError("thicken_sheet: the half thickness must be positive");
  for (double b : base)
    if (!(b > 0)) throw InputError("sheet_tets: every half thickness must be positive");
  const Eigen::Index nv = sheet.V.rows(), nf = sheet.F.rows();
  Eigen::MatrixX3d FN, unused;
  area_weighted_normals(sheet.V, sheet.F, FN, unused);  // (the faces' normals)
  Eigen::MatrixX3d N;
  angle_weighted_normals(sheet.V, sheet.F, N);  // (the bisector on a crease: a bent plate's mid-surface)
  const std::vector<std::vector<int>> faces_at = vertex_faces(sheet.F, nv);
  for (Eigen::Index v = 0; v < nv; ++v) {
    const double len = N.row(v).norm();
    if (len > 0) N.row(v) /= len;
    else if (!faces_at[static_cast<size_t>(v)].empty())
      throw InputError("thicken_sheet: vertex " + std::to_string(v) + " has no normal (its faces have no area)");
  }
  // Where the normal leans more than 60° from one of the vertex's faces (a graded sheet: a large
  // face beside small ones across a crease), it is turned toward that face, a few times, while
  // that raises the smallest cosine: the prisms' sides then lean less.
  {
    for (Eigen::Index v = 0; v < nv; ++v) {
      const auto& around = faces_at[static_cast<size_t>(v)];
      auto worst = [&](const Eigen::RowVector3d& n, int* arg) {
        double m = 2;
        for (int f : around) {
          const Eigen::RowVector3d fn = FN.row(f).normalized();
          if (n.dot(fn) < m) m = n.dot(fn), *arg = f;
        }
        return m;
      };
      int f = -1;
      double m = worst(N.row(v), &f);
      for (int it = 0; it < 8 && m < 0.5 && f >= 0; ++it) {
        const Eigen::RowVector3d n = (N.row(v) + 0.5 * FN.row(f).normalized()).normalized();
        int g = -1;
        const double mn = worst(n, &g);
        if (!(mn > m)) break;
        N.row(v) = n, m = mn, f = g;
      }
    }
  }
  // Where the sheet bends sharply (radius R, estimated per edge as its length over the angle
  // between its vertex normals), the slab's inner side is squeezed by h / R: at most a quarter.
  std::vector<double> hv(static_cast<size_t>(nv), half_thickness);
  if (static_cast<Eigen::Index>(base.size()) == nv) hv = base;
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = sheet.F(f, k), b = sheet.F(f, (k + 1) % 3);
      const double turn = (N.row(a) - N.row(b)).norm(), len = (sheet.V.row(a) - sheet.V.row(b)).norm();
      if (!(turn > 0)) continue;
      const double limit = 0.25 * len / turn;
      hv[static_cast<size_t>(a)] = std::min(hv[static_cast<size_t>(a)], limit);
      hv[static_cast<size_t>(b)] = std::min(hv[static_cast<size_t>(b)], limit);
    }
  // Where another part of the sheet lies closer along the normal (the two sides of an elephant's
  // ear, scanned as one sheet; a curtain folded onto itself), at most 0.45 of the way to it: the
  // two slabs do not overlap.
  // (Looked for along the vertex's normal and its faces': where the sheet bends sharply next to
  // the vertex, its normal leans past the other part.)
  {
    const TriangleBvh bvh(sheet.V, sheet.F);
    tbb::parallel_for(Eigen::Index(0), nv, [&](Eigen::Index v) {
      if (faces_at[static_cast<size_t>(v)].empty()) return;
      const Eigen::Vector3d x = sheet.V.row(v).transpose();
      std::vector<Eigen::Vector3d> directions{N.row(v).transpose()};
      for (int f : faces_at[static_cast<size_t>(v)])
        if (FN.row(f).norm() > 0) directions.push_back(FN.row(f).normalized().transpose());
      double& o = hv[static_cast<size_t>(v)];
      const double reach = o / 0.45;
      for (const Eigen::Vector3d& n : directions)
        for (double dir : {-1.0, 1.0}) {
          double t;
          if (bvh.first_crossing(x, x + dir * reach * n, 1e-4, &t)) o = std::min(o, 0.45 * t * reach);
        }
      // A ray through another part's outline can miss it (two arms ending side by side): an offset
      // point nearer than 0.9 of its offset to a face that is not around the vertex's neighbours
      // (a graded sheet's chords lie that near on its concave side) is halved.
      const Eigen::Vector3d n = N.row(v).transpose();
      std::vector<int> ring;  // the vertex and its neighbours
      for (int f : faces_at[static_cast<size_t>(v)])
        for (int k = 0; k < 3; ++k) ring.push_back(sheet.F(f, k));
      auto own = [&](int g) {
        for (int k = 0; k < 3; ++k)
          if (std::find(ring.begin(), ring.end(), sheet.F(g, k)) != ring.end()) return true;
        return false;
      };
      for (double dir : {-1.0, 1.0})
        for (int k = 0; k < 6; ++k) {
          int g = -1;
          if (!(bvh.nearest(x + dir * o * n, &g) < 0.9 * o) || g < 0 || own(g)) break;
          o *= 0.5;
        }
    });
  }
  return Offsets{std::move(N), std::move(hv)};
}

// The slab of `sheet` with those offsets, each scaled by scale[v] (sheet_tets shrinks it where a
// prism inverts; empty: 1).
SurfaceMesh slab_of(const SurfaceMesh& sheet, const Offsets& off, const std::vector<double>& scale) {
  const Eigen::Index nv = sheet.V.rows(), nf = sheet.F.rows();
  SurfaceMesh s;
  s.V.resize(2 * nv, 3);
  for (Eigen::Index v = 0; v < nv; ++v) {
    const double h = off.hv[static_cast<size_t>(v)] * (static_cast<Eigen::Index>(scale.size()) == nv ? scale[static_cast<size_t>(v)] : 1.0);
    s.V.row(v) = sheet.V.row(v) + h * off.N.row(v);
    s.V.row(nv + v) = sheet.V.row(v) - h * off.N.row(v);
  }
  // The boundary edges, in their face's direction.
  std::vector<std::pair<int, int>> rim;
  const std::vector<EdgeIncidence> h = edge_incidences(sheet.F);
  for_each_edge(h, [&](size_t i, size_t j) {
    if (j - i == 1) rim.push_back(h[i].forward ? std::make_pair(h[i].a, h[i].b) : std::make_pair(h[i].b, h[i].a));
  });
  s.F.resize(2 * nf + 2 * static_cast<Eigen::Index>(rim.size()), 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    s.F.row(f) = sheet.F.row(f);
    s.F.row(nf + f) << static_cast<int>(nv) + sheet.F(f, 0), static_cast<int>(nv) + sheet.F(f, 2),
        static_cast<int>(nv) + sheet.F(f, 1);
  }
  // The +side's face runs a → b; the strip runs b → a on the +side and a → b on the −side, split
  // along the diagonal sheet_tets uses: from the lower-numbered vertex's −side copy to the other's
  // +side copy.
  Eigen::Index r = 2 * nf;
  const int o = static_cast<int>(nv);
  for (const auto& [a, b] : rim) {
    if (a < b) {
      s.F.row(r++) << b, a, o + a;
      s.F.row(r++) << b, o + a, o + b;
    } else {
      s.F.row(r++) << b, a, o + b;
      s.F.row(r++) << a, o + a, o + b;
    }
  }
  return s;
}

}  // namespace

SurfaceMesh thicken_sheet(const SurfaceMesh& sheet, double half_thickness) {
  return slab_of(sheet, offsets(sheet, half_thickness, {}), {});
}

int smooth_sheet_faces(SurfaceMesh& sheet, const std::vector<int>& faces, double max_move) {
  const Eigen::Index nv = sheet.V.rows(), nf = sheet.F.rows();
  const std::vector<std::vector<int>> around = vertex_faces(sheet.F, nv);
  std::vector<char> moves(static_cast<size_t>(nv), 0);
  for (int f : faces) {
    if (f < 0 || f >= nf) throw InputError("smooth_sheet_faces: face " + std::to_string(f) + " out of range");
    for (int k = 0; k < 3; ++k)
      for (int g : around[static_cast<size_t>(sheet.F(f, k))])
        for (int j = 0; j < 3; ++j) moves[static_cast<size_t>(sheet.F(g, j))] = 1;
  }
  // The outline stays (the remeshing kept it on the input's).
  const std::vector<EdgeIncidence> h = edge_incidences(sheet.F);
  for_each_edge(h, [&](size_t i, size_t j) {
    if (j - i == 1) moves[static_cast<size_t>(h[i].a)] = moves[static_cast<size_t>(h[i].b)] = 0;
  });
  Eigen::MatrixX3d W = sheet.V;
  int moved = 0;
  for (Eigen::Index v = 0; v < nv; ++v) {
    if (!moves[static_cast<size_t>(v)]) continue;
    std::vector<int> ring;  // the neighbours, each once
    for (int g : around[static_cast<size_t>(v)])
      for (int j = 0; j < 3; ++j)
        if (sheet.F(g, j) != v) ring.push_back(sheet.F(g, j));
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    if (ring.empty()) continue;
    Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
    for (int u : ring) mean += sheet.V.row(u);
    Eigen::RowVector3d step = 0.5 * (mean / static_cast<double>(ring.size()) - sheet.V.row(v));
    if (step.norm() > max_move) step *= max_move / step.norm();
    W.row(v) = sheet.V.row(v) + step;
    ++moved;
  }
  sheet.V = std::move(W);
  return moved;
}

int split_sheet_faces(SurfaceMesh& sheet, const std::vector<int>& faces, const TriangleBvh* onto) {
  const Eigen::Index nf = sheet.F.rows();
  auto key = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  std::map<std::pair<int, int>, int> mid;  // split edge -> its new vertex
  std::vector<Eigen::RowVector3d> added;
  for (int f : faces) {
    if (f < 0 || f >= nf) throw InputError("split_sheet_faces: face " + std::to_string(f) + " out of range");
    int best = 0;
    double len = -1;
    for (int k = 0; k < 3; ++k) {
      const double l = (sheet.V.row(sheet.F(f, k)) - sheet.V.row(sheet.F(f, (k + 1) % 3))).norm();
      if (l > len) len = l, best = k;
    }
    const auto e = key(sheet.F(f, best), sheet.F(f, (best + 1) % 3));
    if (mid.count(e)) continue;
    Eigen::Vector3d m = 0.5 * (sheet.V.row(e.first) + sheet.V.row(e.second)).transpose();
    if (onto) {
      Eigen::Vector3d q;
      if (std::isfinite(onto->nearest(m, nullptr, &q))) m = q;
    }
    mid[e] = static_cast<int>(sheet.V.rows() + static_cast<Eigen::Index>(added.size()));
    added.push_back(m.transpose());
  }
  if (mid.empty()) return 0;
  std::vector<std::array<int, 3>> F(static_cast<size_t>(nf));
  for (Eigen::Index f = 0; f < nf; ++f) F[static_cast<size_t>(f)] = {sheet.F(f, 0), sheet.F(f, 1), sheet.F(f, 2)};
  const Eigen::Index old = sheet.V.rows();
  auto point = [&](int v) -> Eigen::RowVector3d {
    return v < old ? Eigen::RowVector3d(sheet.V.row(v)) : added[static_cast<size_t>(v - old)];
  };
  const std::vector<std::array<int, 3>> out = red_green_split(
      F,
      [&](int a, int b) {
        const auto it = mid.find(key(a, b));
        return it == mid.end() ? -1 : it->second;
      },
      [&](int a, int b) { return (point(a) - point(b)).squaredNorm(); });
  const Eigen::Index nv = sheet.V.rows();
  sheet.V.conservativeResize(nv + static_cast<Eigen::Index>(added.size()), 3);
  for (size_t i = 0; i < added.size(); ++i) sheet.V.row(nv + static_cast<Eigen::Index>(i)) = added[i];
  sheet.F.resize(static_cast<Eigen::Index>(out.size()), 3);
  for (size_t i = 0; i < out.size(); ++i) sheet.F.row(static_cast<Eigen::Index>(i)) << out[i][0], out[i][1], out[i][2];
  return static_cast<int>(mid.size());
}

namespace {
bool prisms(const SurfaceMesh& sheet, double half_thickness, const std::vector<double>& base, TetMesh& out,
            SurfaceMesh* slab_out, std::vector<int>* inverted);
}

bool sheet_tets(const SurfaceMesh& sheet, double half_thickness, TetMesh& out, SurfaceMesh* slab_out,
                std::vector<int>* inverted) {
  return prisms(sheet, half_thickness, {}, out, slab_out, inverted);
}

bool sheet_tets(const SurfaceMesh& sheet, const std::vector<double>& half_thickness, TetMesh& out, SurfaceMesh* slab_out,
                std::vector<int>* inverted) {
  if (static_cast<Eigen::Index>(half_thickness.size()) != sheet.V.rows())
    throw InputError("sheet_tets: one half thickness per vertex of the sheet");
  const double top = half_thickness.empty() ? 1.0 : *std::max_element(half_thickness.begin(), half_thickness.end());
  return prisms(sheet, top, half_thickness, out, slab_out, inverted);
}

namespace {
bool prisms(const SurfaceMesh& sheet, double half_thickness, const std::vector<double>& base, TetMesh& out,
            SurfaceMesh* slab_out, std::vector<int>* inverted) {
  const int nv = static_cast<int>(sheet.V.rows());
  // Where a prism inverts (its vertices' normals lean across a crease of a graded sheet), its
  // vertices' offsets are halved and the slab made again: up to five times (a thirty-second of
  // the thickness there); beyond, the sheet folds too sharply for a slab (false).
  std::vector<double> scale(static_cast<size_t>(nv), 1.0);
  if (inverted) inverted->clear();
  const Offsets o = offsets(sheet, half_thickness, base);
  for (int round = 0; round < 6; ++round) {
    SurfaceMesh slab = slab_of(sheet, o, scale);
    Eigen::MatrixX4i T(3 * sheet.F.rows(), 4);
    auto volume = [&](const Eigen::Vector4i& t) {
      const Eigen::RowVector3d a = slab.V.row(t(0));
      return (slab.V.row(t(1)) - a).dot((slab.V.row(t(2)) - a).cross(slab.V.row(t(3)) - a));
    };
    std::vector<int> shrink;  // vertices of inverted prisms
    for (Eigen::Index f = 0; f < sheet.F.rows(); ++f) {
      std::array<int, 3> v{sheet.F(f, 0), sheet.F(f, 1), sheet.F(f, 2)};
      // Sorted: the parity of the sort decides the orientation the prism's tetrahedra should have.
      int parity = 1;
      for (int pass = 0; pass < 2; ++pass)
        for (int k = 0; k < 2; ++k)
          if (v[static_cast<size_t>(k)] > v[static_cast<size_t>(k) + 1]) {
            std::swap(v[static_cast<size_t>(k)], v[static_cast<size_t>(k) + 1]);
            parity = -parity;
          }
      const int i = v[0], j = v[1], k = v[2];  // the +side: i, j, k; the −side: nv + i, ...
      const std::array<std::pair<Eigen::Vector4i, int>, 3> prism{{{Eigen::Vector4i(nv + i, nv + j, nv + k, k), parity},
                                                                   {Eigen::Vector4i(nv + i, nv + j, j, k), -parity},
                                                                   {Eigen::Vector4i(nv + i, i, j, k), parity}}};
      for (int q = 0; q < 3; ++q) {
        Eigen::Vector4i t = prism[static_cast<size_t>(q)].first;
        const int sign = prism[static_cast<size_t>(q)].second;
        if (!(sign * volume(t) > 0)) {  // inverted or flat
          shrink.insert(shrink.end(), {i, j, k});
          if (inverted && round == 5) inverted->push_back(static_cast<int>(f));
          break;
        }
        if (sign < 0) std::swap(t(2), t(3));
        T.row(3 * f + q) = t.transpose();
      }
    }
    if (shrink.empty()) {
      out.V = slab.V;
      out.T = std::move(T);
      out.label.resize(0);
      if (slab_out) *slab_out = std::move(slab);
      return true;
    }
    spdlog::debug("sheet_tets: {} vertices of inverted prisms (round {})", shrink.size(), round);
    for (int x : shrink) scale[static_cast<size_t>(x)] = 0.5 * std::min(scale[static_cast<size_t>(x)], 1.0);
    // (a vertex in several inverted prisms is halved once per round)
    for (int x : shrink) scale[static_cast<size_t>(x)] = std::min(scale[static_cast<size_t>(x)], std::pow(0.5, round + 1));
  }
  return false;
}
}  // namespace

}  // namespace squeeze::meshing
