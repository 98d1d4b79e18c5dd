// Open sheets and their slabs (sheet.h).
#include "squeeze/meshing/sheet.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "squeeze/common/error.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/winding_number.h"

namespace squeeze::meshing {
namespace {

// One directed edge of a face: (from, to), with the face.
struct Half {
  int lo, hi;   // the undirected edge (lo < hi)
  bool forward; // from == lo
  int face, k;  // face and the corner the edge leaves from
  bool operator<(const Half& o) const { return lo != o.lo ? lo < o.lo : hi != o.hi ? hi < o.hi : face < o.face; }
};

std::vector<Half> halves(const Eigen::MatrixX3i& F) {
  std::vector<Half> h;
  h.reserve(static_cast<size_t>(3 * F.rows()));
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      h.push_back({std::min(a, b), std::max(a, b), a < b, f, k});
    }
  std::sort(h.begin(), h.end());
  return h;
}

}  // namespace

SheetEvidence sheet_evidence(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  SheetEvidence e;
  if (F.rows() == 0) return e;
  const std::vector<Half> h = halves(F);
  bool manifold = true;
  int boundary = 0;
  std::vector<int> rim_edges(static_cast<size_t>(V.rows()), 0);  // boundary edges at each vertex
  for (size_t i = 0; i < h.size();) {
    size_t j = i;
    while (j < h.size() && h[j].lo == h[i].lo && h[j].hi == h[i].hi) ++j;
    if (j - i == 1) {
      ++boundary;
      ++rim_edges[static_cast<size_t>(h[i].lo)];
      ++rim_edges[static_cast<size_t>(h[i].hi)];
    } else if (j - i > 2 || h[i].forward == h[i + 1].forward) {
      manifold = false;
    }
    i = j;
  }
  // A vertex on the boundary has two boundary edges; four or more: two fans meeting at a point (a
  // bow tie), which no offset or remeshing takes.
  for (int n : rim_edges) manifold = manifold && (n == 0 || n == 2);
  e.open_manifold = manifold && boundary > 0;
  if (!e.open_manifold) return e;
  const FastWindingNumber w(V, F);
  const double diag = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  const double eps = 1e-4 * diag;
  std::vector<double> sheet_area(static_cast<size_t>(F.rows()), 0.0), face_area(static_cast<size_t>(F.rows()), 0.0);
  tbb::parallel_for(Eigen::Index(0), F.rows(), [&](Eigen::Index f) {
    const Eigen::RowVector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    if (!(len > 0)) return;
    face_area[static_cast<size_t>(f)] = 0.5 * len;
    const Eigen::RowVector3d m = (a + b + c) / 3.0, u = n / len * eps;
    const double p = std::abs(w(m + u)), q = std::abs(w(m - u));
    if (p > 0.25 && p < 0.75 && q > 0.25 && q < 0.75) sheet_area[static_cast<size_t>(f)] = 0.5 * len;
  });
  double total = 0, sheet = 0;
  for (size_t f = 0; f < face_area.size(); ++f) total += face_area[f], sheet += sheet_area[f];
  e.sheet_area_fraction = total > 0 ? sheet / total : 0.0;
  return e;
}

SurfaceMesh thicken_sheet(const SurfaceMesh& sheet, double half_thickness) {
  if (!(half_thickness > 0)) throw InputError("thicken_sheet: the half thickness must be positive");
  const Eigen::Index nv = sheet.V.rows(), nf = sheet.F.rows();
  Eigen::MatrixX3d FN, N;
  area_weighted_normals(sheet.V, sheet.F, FN, N);
  std::vector<char> used(static_cast<size_t>(nv), 0);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) used[static_cast<size_t>(sheet.F(f, k))] = 1;
  for (Eigen::Index v = 0; v < nv; ++v) {
    const double len = N.row(v).norm();
    if (len > 0) N.row(v) /= len;
    else if (used[static_cast<size_t>(v)])
      throw InputError("thicken_sheet: vertex " + std::to_string(v) + " has no normal (its faces have no area)");
  }
  // Where the sheet bends sharply (radius R, estimated per edge as its length over the angle
  // between its vertex normals), the slab's inner side is squeezed by h / R: at most a quarter.
  std::vector<double> hv(static_cast<size_t>(nv), half_thickness);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = sheet.F(f, k), b = sheet.F(f, (k + 1) % 3);
      const double turn = (N.row(a) - N.row(b)).norm(), len = (sheet.V.row(a) - sheet.V.row(b)).norm();
      if (!(turn > 0)) continue;
      const double limit = 0.25 * len / turn;
      hv[static_cast<size_t>(a)] = std::min(hv[static_cast<size_t>(a)], limit);
      hv[static_cast<size_t>(b)] = std::min(hv[static_cast<size_t>(b)], limit);
    }
  SurfaceMesh s;
  s.V.resize(2 * nv, 3);
  for (Eigen::Index v = 0; v < nv; ++v) {
    const Eigen::RowVector3d n = N.row(v);
    s.V.row(v) = sheet.V.row(v) + hv[static_cast<size_t>(v)] * n;
    s.V.row(nv + v) = sheet.V.row(v) - hv[static_cast<size_t>(v)] * n;
  }
  // The boundary edges, in their face's direction.
  std::vector<std::pair<int, int>> rim;
  const std::vector<Half> h = halves(sheet.F);
  for (size_t i = 0; i < h.size();) {
    size_t j = i;
    while (j < h.size() && h[j].lo == h[i].lo && h[j].hi == h[i].hi) ++j;
    if (j - i == 1) rim.emplace_back(sheet.F(h[i].face, h[i].k), sheet.F(h[i].face, (h[i].k + 1) % 3));
    i = j;
  }
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

bool sheet_tets(const SurfaceMesh& sheet, double half_thickness, TetMesh& out, SurfaceMesh* slab_out) {
  SurfaceMesh slab = thicken_sheet(sheet, half_thickness);
  const int nv = static_cast<int>(sheet.V.rows());
  Eigen::MatrixX4i T(3 * sheet.F.rows(), 4);
  auto volume = [&](const Eigen::Vector4i& t) {
    const Eigen::RowVector3d a = slab.V.row(t(0));
    return (slab.V.row(t(1)) - a).dot((slab.V.row(t(2)) - a).cross(slab.V.row(t(3)) - a));
  };
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
      if (!(sign * volume(t) > 0)) return false;  // inverted or flat: the slab folds over itself
      if (sign < 0) std::swap(t(2), t(3));
      T.row(3 * f + q) = t.transpose();
    }
  }
  out.V = slab.V;
  out.T = std::move(T);
  out.label.resize(0);
  if (slab_out) *slab_out = std::move(slab);
  return true;
}

}  // namespace squeeze::meshing
