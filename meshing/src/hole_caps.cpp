#include "squeeze/meshing/hole_caps.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include <Eigen/Dense>

namespace squeeze::meshing {

namespace {

std::uint64_t edge_key(int a, int b) {
  return static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::min(a, b))) << 32 |
         static_cast<std::uint32_t>(std::max(a, b));
}

// Per undirected edge: how many faces hold it, and the direction (from, to) of its last face's.
struct EdgeUse {
  int faces = 0;
  int from = -1, to = -1;
};

std::unordered_map<std::uint64_t, EdgeUse> edge_uses(const Eigen::MatrixX3i& F) {
  std::unordered_map<std::uint64_t, EdgeUse> uses;
  uses.reserve(static_cast<size_t>(3 * F.rows()));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      EdgeUse& u = uses[edge_key(a, b)];
      ++u.faces;
      u.from = a, u.to = b;
    }
  return uses;
}

}  // namespace

std::vector<std::vector<int>> boundary_loops(const Eigen::MatrixX3i& F) {
  // Each boundary edge, walked against its face's direction: from `to` to `from`.
  std::unordered_map<int, std::vector<int>> next;
  for (const auto& [key, u] : edge_uses(F))
    if (u.faces == 1) next[u.to].push_back(u.from);
  std::vector<std::vector<int>> loops;
  std::unordered_map<int, bool> done;
  // (In a fixed order: the map's is not.)
  std::vector<int> starts;
  for (const auto& [v, n] : next) starts.push_back(v);
  std::sort(starts.begin(), starts.end());
  for (int s : starts) {
    if (done[s]) continue;
    std::vector<int> loop;
    int v = s;
    while (!done[v]) {
      done[v] = true;
      loop.push_back(v);
      const auto it = next.find(v);
      if (it == next.end() || it->second.size() != 1) break;  // an open chain, or a bow tie
      v = it->second.front();
    }
    if (!loop.empty()) loops.push_back(std::move(loop));
  }
  return loops;
}

double hole_cap_distance(const Eigen::MatrixX3d& V, const std::vector<int>& loop) {
  const int n = static_cast<int>(loop.size());
  if (n < 3) return 0.0;
  Eigen::MatrixX3d P(n, 3);
  for (int i = 0; i < n; ++i) P.row(i) = V.row(loop[static_cast<size_t>(i)]);
  const Eigen::RowVector3d c = P.colwise().mean();
  const Eigen::MatrixX3d D = P.rowwise() - c;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(D, Eigen::ComputeThinV);
  const Eigen::MatrixXd Q = D * svd.matrixV().leftCols(2);  // n by 2: the loop in its plane
  const Eigen::Vector2d lo = Q.colwise().minCoeff(), hi = Q.colwise().maxCoeff();
  if (!((hi - lo).minCoeff() > 0)) return 0.0;
  auto distance = [&](const Eigen::Vector2d& x) {
    double best = INFINITY;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d a = Q.row(i).transpose(), b = Q.row((i + 1) % n).transpose(), d = b - a;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0 ? std::clamp((x - a).dot(d) / len2, 0.0, 1.0) : 0.0;
      best = std::min(best, (a + t * d - x).norm());
    }
    return best;
  };
  auto inside = [&](const Eigen::Vector2d& x) {  // crossing number
    bool in = false;
    for (int i = 0, j = n - 1; i < n; j = i++) {
      const double yi = Q(i, 1) - x.y(), yj = Q(j, 1) - x.y();
      if ((yi > 0) != (yj > 0)) {
        const double xc = Q(i, 0) + (Q(j, 0) - Q(i, 0)) * (x.y() - Q(i, 1)) / (Q(j, 1) - Q(i, 1));
        if (xc > x.x()) in = !in;
      }
    }
    return in;
  };
  constexpr int kGrid = 25;
  double best = 0;
  Eigen::Vector2d at = 0.5 * (lo + hi), step = (hi - lo) / (kGrid - 1);
  for (int round = 0; round < 2; ++round) {
    const Eigen::Vector2d from = round == 0 ? lo : Eigen::Vector2d(at - step), span = round == 0 ? Eigen::Vector2d(hi - lo) : Eigen::Vector2d(2 * step);
    Eigen::Vector2d found = at;
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j) {
        const Eigen::Vector2d x = from + Eigen::Vector2d(span.x() * i / (kGrid - 1), span.y() * j / (kGrid - 1));
        if (!inside(x)) continue;
        const double d = distance(x);
        if (d > best) best = d, found = x;
      }
    at = found;
  }
  return best;
}

bool is_open_two_manifold(const Eigen::MatrixX3i& F) {
  std::unordered_map<int, int> rim;  // boundary edges at each vertex
  bool open = false;
  for (const auto& [key, u] : edge_uses(F)) {
    if (u.faces > 2) return false;
    if (u.faces == 1) {
      open = true;
      ++rim[u.from], ++rim[u.to];
    }
  }
  for (const auto& [v, k] : rim)
    if (k != 2) return false;
  return open;
}

}  // namespace squeeze::meshing
