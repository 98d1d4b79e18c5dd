#include "squeeze/meshing/surface_analysis.h"

#include <cassert>

#include <Eigen/Geometry>
#include <algorithm>
#include <climits>
#include <queue>
#include <vector>

namespace squeeze::meshing {

std::vector<EdgeIncidence> edge_incidences(const Eigen::MatrixX3i& F) {
  std::vector<EdgeIncidence> e;
  e.reserve(static_cast<size_t>(F.rows()) * 3);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int u = F(f, k), v = F(f, (k + 1) % 3);
      e.push_back({std::min(u, v), std::max(u, v), f, u < v});
    }
  std::sort(e.begin(), e.end(), [](const EdgeIncidence& x, const EdgeIncidence& y) {
    return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.face < y.face;
  });
  return e;
}

int face_components(const Eigen::MatrixX3i& F, Eigen::VectorXi& C) {
  const auto e = edge_incidences(F);
  std::vector<std::vector<int>> adj(static_cast<size_t>(F.rows()));
  for_each_edge(e, [&](size_t i, size_t j) {
    if (j - i == 2) {
      adj[e[i].face].push_back(e[i + 1].face);
      adj[e[i + 1].face].push_back(e[i].face);
    }
  });
  C = Eigen::VectorXi::Constant(F.rows(), -1);
  int n = 0;
  std::vector<int> stack;
  for (int f = 0; f < F.rows(); ++f) {
    if (C(f) >= 0) continue;
    C(f) = n;
    stack.push_back(f);
    while (!stack.empty()) {
      const int g = stack.back();
      stack.pop_back();
      for (int h : adj[g])
        if (C(h) < 0) {
          C(h) = n;
          stack.push_back(h);
        }
    }
    ++n;
  }
  return n;
}

Eigen::MatrixX3i orient_outward(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const OrientOptions& opt) {
  Eigen::MatrixX3i out = F;
  const auto e = edge_incidences(F);
  // adjacency with "same direction" flag: two faces on a manifold edge are consistent when they
  // traverse it in opposite directions. A face with an edge of more than two faces is on a seam
  // where segments are welded.
  struct Link { int face; bool same; };
  std::vector<std::vector<Link>> adj(static_cast<size_t>(F.rows()));
  std::vector<char> on_seam(static_cast<size_t>(F.rows()), 0);
  for_each_edge(e, [&](size_t i, size_t j) {
    if (j - i != 2) {
      if (j - i > 2)
        for (size_t k = i; k < j; ++k) on_seam[static_cast<size_t>(e[k].face)] = 1;
      return;
    }
    const bool same = e[i].forward == e[i + 1].forward;
    adj[e[i].face].push_back({e[i + 1].face, same});
    adj[e[i + 1].face].push_back({e[i].face, same});
  });
  std::vector<signed char> flip(static_cast<size_t>(F.rows()), -1);
  std::vector<char> in_part(static_cast<size_t>(F.rows()), 0);  // a face already in a file-consistent part
  std::vector<int> comp_faces, stack;
  std::queue<int> q;
  for (int seed = 0; seed < F.rows(); ++seed) {
    if (flip[seed] >= 0) continue;
    comp_faces.clear();
    flip[seed] = 0;
    q.push(seed);
    bool welded = false, file_consistent = true;
    while (!q.empty()) {
      const int f = q.front();
      q.pop();
      comp_faces.push_back(f);
      welded = welded || on_seam[static_cast<size_t>(f)];
      for (const Link& l : adj[f]) {
        file_consistent = file_consistent && !l.same;
        if (flip[l.face] < 0) {
          flip[l.face] = static_cast<signed char>(l.same ? !flip[f] : flip[f]);
          q.push(l.face);
        }
      }
    }
    // A component welded to others (it has non-manifold edges) in which the file turns some edges
    // between large parts that it orients consistently is segments joined where a seam lost its
    // third face (a hole cut at a junction): the file's orientation is kept there, face by face,
    // since turning a part to agree across such an edge turns a segment inside out. Any other
    // component (closed; open but welded to nothing, a scan whose halves the file turns against
    // each other; one with a small part against the rest, a stray flipped face) is made
    // consistent.
    bool keep_file = welded && !file_consistent;
    if (keep_file) {
      for (int f : comp_faces) {
        if (in_part[static_cast<size_t>(f)]) continue;
        long size = 0;
        in_part[static_cast<size_t>(f)] = 1;
        stack.assign(1, f);
        while (!stack.empty()) {
          const int g = stack.back();
          stack.pop_back();
          ++size;
          for (const Link& l : adj[g])
            if (!l.same && !in_part[static_cast<size_t>(l.face)]) {
              in_part[static_cast<size_t>(l.face)] = 1;
              stack.push_back(l.face);
            }
        }
        keep_file = keep_file && size >= opt.min_seamed_part;
      }
      if (keep_file)
        for (int f : comp_faces) flip[static_cast<size_t>(f)] = 0;
    }
    // Signed volume of the component about its centroid, with the propagated (or the file's)
    // orientation.
    Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
    for (int f : comp_faces) c += (V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2))) / 3.0;
    c /= static_cast<double>(comp_faces.size());
    double vol = 0.0;
    for (int f : comp_faces) {
      const Eigen::Vector3d a = (V.row(F(f, 0)) - c).transpose(), b = (V.row(F(f, 1)) - c).transpose(),
                            d = (V.row(F(f, 2)) - c).transpose();
      const double s = a.dot(b.cross(d));
      vol += flip[f] ? -s : s;
    }
    const bool flip_all = vol < 0.0;
    for (int f : comp_faces)
      if (static_cast<bool>(flip[f]) != flip_all) std::swap(out(f, 1), out(f, 2));
  }
  return out;
}

std::vector<std::vector<int>> vertex_faces(const Eigen::MatrixX3i& F, Eigen::Index vertices) {
  assert(F.rows() == 0 || (F.minCoeff() >= 0 && F.maxCoeff() < vertices));
  std::vector<std::vector<int>> at(static_cast<size_t>(vertices));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) at[static_cast<size_t>(F(f, k))].push_back(static_cast<int>(f));
  return at;
}

bool is_closed(const Eigen::MatrixX3i& F) {
  const auto e = edge_incidences(F);
  bool closed = true;
  for_each_edge(e, [&](size_t i, size_t j) { closed = closed && j - i == 2; });
  return closed;
}

bool is_oriented_two_manifold(const Eigen::MatrixX3i& F, int vertices) {
  const auto e = edge_incidences(F);
  bool ok = true;
  // Every edge in exactly two faces, traversed once each way.
  for_each_edge(e, [&](size_t i, size_t j) { ok = ok && j - i == 2 && e[i].forward != e[i + 1].forward; });
  if (!ok) return false;
  // Every vertex's faces form one fan: walk around it through the edges from each face's
  // outgoing edge at the vertex to the face that has that edge incoming.
  std::vector<std::vector<std::pair<int, int>>> out(static_cast<size_t>(vertices));  // (next vertex, the one after it)
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) out[static_cast<size_t>(F(f, k))].emplace_back(F(f, (k + 1) % 3), F(f, (k + 2) % 3));
  for (int v = 0; v < vertices; ++v) {
    auto& fan = out[static_cast<size_t>(v)];
    if (fan.empty()) continue;
    // Map: next vertex -> the vertex after it around v.
    std::sort(fan.begin(), fan.end());
    size_t steps = 0;
    int at = fan.front().first;
    do {
      const auto it = std::lower_bound(fan.begin(), fan.end(), std::make_pair(at, INT_MIN));
      if (it == fan.end() || it->first != at) return false;
      at = it->second;
      ++steps;
    } while (at != fan.front().first && steps <= fan.size());
    if (steps != fan.size()) return false;
  }
  return true;
}

SurfaceInfo analyse_surface(const SurfaceMesh& mesh) {
  SurfaceInfo info;
  info.vertices = static_cast<int>(mesh.V.rows());
  info.faces = static_cast<int>(mesh.F.rows());
  const auto e = edge_incidences(mesh.F);
  for_each_edge(e, [&](size_t i, size_t j) {
    if (j - i == 1) ++info.boundary_edges;
    if (j - i >= 3) ++info.nonmanifold_edges;
  });
  Eigen::VectorXi C;
  info.components = face_components(mesh.F, C);
  info.closed = info.boundary_edges == 0;
  if (info.closed) {
    const Eigen::MatrixX3i F = orient_outward(mesh.V, mesh.F);
    double vol = 0.0;
    for (int f = 0; f < F.rows(); ++f)
      vol += mesh.V.row(F(f, 0)).dot(mesh.V.row(F(f, 1)).cross(mesh.V.row(F(f, 2)))) / 6.0;
    info.volume = std::abs(vol);
  }
  return info;
}

}  // namespace squeeze::meshing
