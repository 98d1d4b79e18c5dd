#include "squeeze/meshing/tet_faces.h"

#include <algorithm>
#include <array>
#include <functional>
#include <numeric>
#include <vector>

namespace squeeze::meshing {
namespace {

// One face of one tetrahedron, keyed by its sorted vertex ids.
struct FaceRef {
  std::array<int, 3> key;  // sorted vertex ids
  int tet, local;          // the face opposite local vertex `local` of `tet`
};

// All 4 #T faces, grouped by key: sorted by (key, tet, local), a total order, so the result does
// not depend on the sort algorithm.
std::vector<FaceRef> sorted_faces(const Eigen::MatrixX4i& T) {
  std::vector<FaceRef> f;
  f.reserve(static_cast<size_t>(T.rows()) * 4);
  for (int t = 0; t < T.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> key{T(t, kTetFace[k][0]), T(t, kTetFace[k][1]), T(t, kTetFace[k][2])};
      std::sort(key.begin(), key.end());
      f.push_back({key, t, k});
    }
  std::sort(f.begin(), f.end(), [](const FaceRef& a, const FaceRef& b) {
    if (a.key != b.key) return a.key < b.key;
    return a.tet != b.tet ? a.tet < b.tet : a.local < b.local;
  });
  return f;
}

// Calls fn(i, j) for every run f[i..j) of faces with the same key, in key order.
template <class Fn>
void for_each_face(const std::vector<FaceRef>& f, Fn fn) {
  for (size_t i = 0; i < f.size();) {
    size_t j = i + 1;
    while (j < f.size() && f[j].key == f[i].key) ++j;
    fn(i, j);
    i = j;
  }
}

}  // namespace

TetFaces tet_faces(const Eigen::MatrixX4i& T) {
  TetFaces r;
  r.boundary_face = Eigen::MatrixX4i::Constant(T.rows(), 4, -1);
  r.neighbor = Eigen::MatrixX4i::Constant(T.rows(), 4, -1);
  const auto faces = sorted_faces(T);
  std::vector<std::array<int, 3>> b;
  for_each_face(faces, [&](size_t i, size_t j) {
    if (j - i == 1) {
      const FaceRef& f = faces[i];
      r.boundary_face(f.tet, f.local) = static_cast<int>(b.size());
      b.push_back({T(f.tet, kTetFace[f.local][0]), T(f.tet, kTetFace[f.local][1]), T(f.tet, kTetFace[f.local][2])});
    } else if (j - i == 2) {
      r.neighbor(faces[i].tet, faces[i].local) = faces[i + 1].tet;
      r.neighbor(faces[i + 1].tet, faces[i + 1].local) = faces[i].tet;
      ++r.interior;
    } else {
      ++r.overshared;
    }
  });
  r.boundary.resize(static_cast<Eigen::Index>(b.size()), 3);
  for (size_t i = 0; i < b.size(); ++i) r.boundary.row(static_cast<Eigen::Index>(i)) << b[i][0], b[i][1], b[i][2];
  return r;
}

Eigen::MatrixX3i boundary_faces(const Eigen::MatrixX4i& T) { return tet_faces(T).boundary; }

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

}  // namespace squeeze::meshing
