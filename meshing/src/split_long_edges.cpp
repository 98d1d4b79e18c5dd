#include "squeeze/meshing/split_long_edges.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <functional>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "squeeze/common/error.h"

namespace squeeze::meshing {

double median_edge_length(const SurfaceMesh& s) {
  std::vector<double> len;
  len.reserve(static_cast<size_t>(s.F.rows()) * 3);
  for (Eigen::Index f = 0; f < s.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) len.push_back((s.V.row(s.F(f, k)) - s.V.row(s.F(f, (k + 1) % 3))).norm());
  if (len.empty()) return 0.0;
  std::nth_element(len.begin(), len.begin() + static_cast<long>(len.size() / 2), len.end());
  return len[len.size() / 2];
}

double skinny_split_length(const SurfaceMesh& s, const SkinnySplitOptions& opt) {
  double total = 0, skinny = 0;
  std::vector<double> shortest;
  for (Eigen::Index f = 0; f < s.F.rows(); ++f) {
    const Eigen::RowVector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const double l[3] = {(b - a).norm(), (c - b).norm(), (a - c).norm()};
    const double lo = std::min({l[0], l[1], l[2]}), hi = std::max({l[0], l[1], l[2]});
    total += area;
    if (hi > opt.max_aspect * lo && lo > 0) {
      skinny += area;
      shortest.push_back(lo);
    }
  }
  if (!(total > 0) || !(skinny > opt.area_fraction * total) || shortest.empty()) return 0.0;
  std::nth_element(shortest.begin(), shortest.begin() + static_cast<long>(shortest.size() / 2), shortest.end());
  return opt.shortest_edges * shortest[shortest.size() / 2];
}

std::vector<std::array<int, 3>> red_green_split(const std::vector<std::array<int, 3>>& F,
                                                const std::function<int(int, int)>& midpoint,
                                                const std::function<double(int, int)>& squared_length) {
  std::vector<std::array<int, 3>> G;
  G.reserve(F.size() * 2);
  for (const auto& t : F) {
    int m[3];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      m[k] = midpoint(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)]);  // on edge (t[k], t[k+1])
      n += m[k] >= 0;
    }
    if (n == 0) {
      G.push_back(t);
    } else if (n == 3) {
      G.push_back({t[0], m[0], m[2]});
      G.push_back({m[0], t[1], m[1]});
      G.push_back({m[2], m[1], t[2]});
      G.push_back({m[0], m[1], m[2]});
    } else {
      // Rotate so that edge (a, b) = (t[r], t[r+1]) is split; with two, also (b, c).
      int r = 0;
      if (n == 1) {
        while (m[r] < 0) ++r;
      } else {
        while (!(m[r] >= 0 && m[(r + 1) % 3] >= 0)) ++r;
      }
      const int a = t[static_cast<size_t>(r)], b = t[static_cast<size_t>((r + 1) % 3)], c = t[static_cast<size_t>((r + 2) % 3)];
      const int mab = m[r];
      if (n == 1) {
        G.push_back({a, mab, c});
        G.push_back({mab, b, c});
      } else {
        const int mbc = m[(r + 1) % 3];
        G.push_back({mab, b, mbc});
        // The quadrilateral a, mab, mbc, c along its shorter diagonal.
        if (squared_length(a, mbc) <= squared_length(mab, c)) {
          G.push_back({a, mab, mbc});
          G.push_back({a, mbc, c});
        } else {
          G.push_back({a, mab, c});
          G.push_back({mab, mbc, c});
        }
      }
    }
  }
  return G;
}

SurfaceMesh split_long_edges(const SurfaceMesh& surface, double max_length, bool* complete) {
  if (!(max_length > 0)) throw InputError("split_long_edges: max_length must be positive");
  std::vector<Eigen::RowVector3d> V;
  V.reserve(static_cast<size_t>(surface.V.rows()));
  for (Eigen::Index i = 0; i < surface.V.rows(); ++i) V.push_back(surface.V.row(i));
  std::vector<std::array<int, 3>> F;
  F.reserve(static_cast<size_t>(surface.F.rows()));
  for (Eigen::Index f = 0; f < surface.F.rows(); ++f) F.push_back({surface.F(f, 0), surface.F(f, 1), surface.F(f, 2)});
  const double max2 = max_length * max_length;
  auto key = [](int a, int b) {
    return (static_cast<uint64_t>(std::min(a, b)) << 32) | static_cast<uint32_t>(std::max(a, b));
  };
  // Each round halves every long edge; 64 rounds bound any finite ratio of lengths, and the face
  // budget bounds the output (a round starts only while the faces are within it). The long edges
  // are found before the budget is tested, so that `complete` is known without a further scan.
  const size_t budget = 8 * F.size() + 10000;
  bool done = false;
  for (int round = 0;; ++round) {
    std::unordered_map<uint64_t, int> mid;  // a long edge → its midpoint (created on first use)
    for (const auto& t : F)
      for (int k = 0; k < 3; ++k) {
        const int a = t[static_cast<size_t>(k)], b = t[static_cast<size_t>((k + 1) % 3)];
        if ((V[static_cast<size_t>(a)] - V[static_cast<size_t>(b)]).squaredNorm() > max2) mid.emplace(key(a, b), -1);
      }
    done = mid.empty();
    if (done || round == 64 || F.size() > budget) break;
    // Midpoints numbered in key order: the result does not depend on the hash map's order.
    std::vector<uint64_t> keys;
    keys.reserve(mid.size());
    for (const auto& [k, m] : mid) keys.push_back(k);
    std::sort(keys.begin(), keys.end());
    for (uint64_t k : keys) {
      const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xFFFFFFFFu);
      mid[k] = static_cast<int>(V.size());
      V.push_back(0.5 * (V[static_cast<size_t>(a)] + V[static_cast<size_t>(b)]));
    }
    std::vector<std::array<int, 3>> G = red_green_split(
        F,
        [&](int a, int b) {
          const auto it = mid.find(key(a, b));
          return it == mid.end() ? -1 : it->second;
        },
        [&](int a, int b) { return (V[static_cast<size_t>(a)] - V[static_cast<size_t>(b)]).squaredNorm(); });
    F.swap(G);
  }
  if (complete) *complete = done;
  SurfaceMesh out;
  out.V.resize(static_cast<Eigen::Index>(V.size()), 3);
  for (size_t i = 0; i < V.size(); ++i) out.V.row(static_cast<Eigen::Index>(i)) = V[i];
  out.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t i = 0; i < F.size(); ++i) out.F.row(static_cast<Eigen::Index>(i)) << F[i][0], F[i][1], F[i][2];
  return out;
}

}  // namespace squeeze::meshing
