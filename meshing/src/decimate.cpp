#include "squeeze/meshing/decimate.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <queue>
#include <string>
#include <unordered_set>
#include <vector>

#include "squeeze/common/error.h"
#include "squeeze/meshing/surface_analysis.h"

namespace squeeze::meshing {
namespace {

using Vec3 = Eigen::Vector3d;

// Σ (n·p + d)² over planes (n unit): pᵀAp + 2bᵀp + c.
struct Quadric {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Vec3 b = Vec3::Zero();
  double c = 0;
  void add_plane(const Vec3& n, double d) {
    A += n * n.transpose();
    b += d * n;
    c += d * d;
  }
  Quadric& operator+=(const Quadric& o) {
    A += o.A;
    b += o.b;
    c += o.c;
    return *this;
  }
  double at(const Vec3& p) const { return std::max(0.0, p.dot(A * p) + 2.0 * b.dot(p) + c); }
};

// The quadric's minimiser nearest m (eigenvalues under 1e-3 of the largest cut: along those
// directions the point stays at m's), or m where that lies over `reach` from m.
Vec3 minimiser_near(const Quadric& q, const Vec3& m, double reach) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(q.A);
  const Vec3 lambda = es.eigenvalues();
  const double cut = 1e-3 * lambda.maxCoeff();
  const Vec3 r = -(q.A * m + q.b);  // A x = r for the offset x from m
  Vec3 x = Vec3::Zero();
  for (int k = 0; k < 3; ++k)
    if (lambda[k] > cut && lambda[k] > 0) x += es.eigenvectors().col(k) * (es.eigenvectors().col(k).dot(r) / lambda[k]);
  return x.norm() <= reach ? Vec3(m + x) : m;
}

// 4√3 area / (sum of squared edges): 1 for an equilateral triangle, 0 for one of no area.
double shape(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double s = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return s > 0 ? 2.0 * std::sqrt(3.0) * (b - a).cross(c - a).norm() / s : 0.0;
}

struct Candidate {
  double cost;
  int u, w;          // u kept, w removed
  unsigned su, sw;   // their stamps when the candidate was made (its placement is made again
                     // when it is taken: the queue's entries stay small)
};

struct Later {  // the priority queue's order: cheapest first, then by vertex indices
  bool operator()(const Candidate& x, const Candidate& y) const {
    if (x.cost != y.cost) return x.cost > y.cost;
    if (x.u != y.u) return x.u > y.u;
    return x.w > y.w;
  }
};

class Decimator {
 public:
  Decimator(const SurfaceMesh& s, const DecimateOptions& opt) : input_(s), opt_(opt) {
    const Eigen::Index nv = s.V.rows(), nf = s.F.rows();
    if (nv > 0) {
      const Eigen::RowVector3d lo = s.V.colwise().minCoeff(), hi = s.V.colwise().maxCoeff();
      centre_ = 0.5 * (lo + hi).transpose();
      diag_ = (hi - lo).norm();
    }
    pos_.resize(static_cast<size_t>(nv));
    for (Eigen::Index i = 0; i < nv; ++i) pos_[static_cast<size_t>(i)] = s.V.row(i).transpose() - centre_;
    F_.resize(static_cast<size_t>(nf));
    for (Eigen::Index f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) F_[static_cast<size_t>(f)][static_cast<size_t>(k)] = s.F(f, k);
    face_alive_.assign(F_.size(), 1);
    faces_ = static_cast<int>(F_.size());
    vf_.resize(pos_.size());
    frozen_.assign(pos_.size(), 0);
    q_.resize(pos_.size());
    plane_.assign(F_.size(), Eigen::Vector4d::Zero());
    planes_of_.resize(pos_.size());
    bound_ = opt.max_error * opt.max_error;
    stamp_.assign(pos_.size(), 0);
    parked_.resize(pos_.size());
    source_.resize(pos_.size());
    for (size_t v = 0; v < source_.size(); ++v) source_[v] = static_cast<Eigen::Index>(v);
    cos_turn_ = std::cos(opt.max_normal_turn * M_PI / 180.0);
    tiny_area_ = 1e-14 * diag_ * diag_;
    for (size_t f = 0; f < F_.size(); ++f) {
      const auto& t = F_[f];
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
        for (int v : t) frozen_[static_cast<size_t>(v)] = 1;
        continue;
      }
      for (int v : t) vf_[static_cast<size_t>(v)].push_back(static_cast<int>(f));
      const Vec3 n = normal(t[0], t[1], t[2]);
      const double len = n.norm();
      if (!(len > 2.0 * tiny_area_)) {
        for (int v : t) frozen_[static_cast<size_t>(v)] = 1;
        continue;
      }
      const Vec3 u = n / len;
      const double d = -u.dot(pos_[static_cast<size_t>(t[0])]);
      plane_[f] << u, d;
      for (int v : t) {
        q_[static_cast<size_t>(v)].add_plane(u, d);
        planes_of_[static_cast<size_t>(v)].push_back(static_cast<int>(f));  // (in increasing order)
      }
    }
    freeze_non_manifold(s.F);
  }

  void run(DecimateStats* stats) {
    std::vector<Candidate> initial;
    initial.reserve(edges_.size());
    for (const auto& [a, b] : edges_) {
      Candidate c;
      if (candidate(a, b, &c)) initial.push_back(c);
    }
    std::priority_queue<Candidate, std::vector<Candidate>, Later> heap(Later{}, std::move(initial));
    int collapses = 0;
    double worst = 0;
    std::vector<int> ring;
    while (!heap.empty() && (opt_.target_faces <= 0 || faces_ > opt_.target_faces)) {
      const Candidate c = heap.top();
      heap.pop();
      const size_t u = static_cast<size_t>(c.u), w = static_cast<size_t>(c.w);
      if (vf_[u].empty() || vf_[w].empty() || stamp_[u] != c.su || stamp_[w] != c.sw) continue;  // stale
      Vec3 p;
      double error = 0;
      if (!candidate(c.u, c.w, nullptr, &p, &error)) continue;
      bool made = collapse(c.u, c.w, p);
      // Where the quadric's placement fails the checks, the edge's ends within the bound: a flat
      // region's midpoints often make slivers where an end does not.
      if (!made && !frozen_[u]) {
        Quadric q = q_[u];
        q += q_[w];
        for (const size_t end : {u, w}) {
          const Vec3 e = pos_[end];
          if (within(u, w, e, q.at(e), &error) && collapse(c.u, c.w, e)) {
            made = true;
            break;
          }
        }
      }
      if (!made) {
        // Parked at both ends: tried again when the faces around either change.
        if (parked_edges_.insert(key(c.u, c.w)).second) {
          parked_[u].push_back(c.w);
          parked_[w].push_back(c.u);
        }
        continue;
      }
      ++collapses;
      worst = std::max(worst, error);
      neighbours(c.u, ring);
      for (int x : ring) {
        Candidate n;
        if (candidate(c.u, x, &n)) heap.push(n);
      }
      ring.push_back(c.u);
      for (int x : ring) {
        for (int y : parked_[static_cast<size_t>(x)]) {
          Candidate n;
          if (parked_edges_.erase(key(x, y)) && !vf_[static_cast<size_t>(y)].empty() &&
              candidate(x, y, &n))
            heap.push(n);
        }
        parked_[static_cast<size_t>(x)].clear();
      }
    }
    if (stats) {
      stats->collapses = collapses;
      stats->max_error = worst;
      stats->frozen_vertices = static_cast<int>(std::count(frozen_.begin(), frozen_.end(), 1));
    }
  }

  SurfaceMesh result(DecimateStats* stats) const {
    SurfaceMesh out;
    std::vector<int> index(pos_.size(), -1);
    int nv = 0, nf = 0;
    for (size_t f = 0; f < F_.size(); ++f)
      if (face_alive_[f]) {
        ++nf;
        for (int v : F_[f])
          if (index[static_cast<size_t>(v)] < 0) index[static_cast<size_t>(v)] = nv++;
      }
    out.V.resize(nv, 3);
    out.F.resize(nf, 3);
    // (A vertex at an input vertex's place keeps the input's coordinates: (x - c) + c need not round to x.)
    for (size_t v = 0; v < pos_.size(); ++v)
      if (index[v] >= 0)
        out.V.row(index[v]) = source_[v] >= 0 ? Eigen::RowVector3d(input_.V.row(source_[v]))
                                              : Eigen::RowVector3d((pos_[v] + centre_).transpose());
    Eigen::Index r = 0;
    for (size_t f = 0; f < F_.size(); ++f)
      if (face_alive_[f]) {
        for (int k = 0; k < 3; ++k) out.F(r, k) = index[static_cast<size_t>(F_[f][static_cast<size_t>(k)])];
        ++r;
      }
    if (stats) stats->faces = nf;
    return out;
  }

 private:
  // The edge (a, b) as one number, either way round.
  static std::uint64_t key(int a, int b) {
    if (a > b) std::swap(a, b);
    return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
  }

  Vec3 normal(int a, int b, int c) const {
    const Vec3& x = pos_[static_cast<size_t>(a)];
    return (pos_[static_cast<size_t>(b)] - x).cross(pos_[static_cast<size_t>(c)] - x);
  }

  // Vertices on edges of other than two faces, or of two that run along them the same way, and
  // vertices whose faces do not make one fan around them; the edges, each once, in edges_.
  void freeze_non_manifold(const Eigen::MatrixX3i& F) {
    const std::vector<EdgeIncidence> e = edge_incidences(F);
    for_each_edge(e, [&](size_t i, size_t j) {
      if (e[i].a == e[i].b) return;  // (of a face with a repeated vertex: frozen already)
      edges_.emplace_back(e[i].a, e[i].b);
      if (j - i != 2 || e[i].forward == e[i + 1].forward)
        frozen_[static_cast<size_t>(e[i].a)] = frozen_[static_cast<size_t>(e[i].b)] = 1;
    });
    // Fans: around v, each face (v, x, y) in its own order takes x to y; one cycle through all.
    std::vector<std::pair<int, int>> step;
    for (size_t v = 0; v < pos_.size(); ++v) {
      if (frozen_[v] || vf_[v].empty()) continue;
      step.clear();
      for (int f : vf_[v]) {
        const auto& t = F_[static_cast<size_t>(f)];
        const int k = t[0] == static_cast<int>(v) ? 0 : t[1] == static_cast<int>(v) ? 1 : 2;
        step.emplace_back(t[static_cast<size_t>((k + 1) % 3)], t[static_cast<size_t>((k + 2) % 3)]);
      }
      size_t length = 0;
      int x = step[0].first;
      do {
        auto it = std::find_if(step.begin(), step.end(), [&](const std::pair<int, int>& s) { return s.first == x; });
        if (it == step.end()) break;
        x = it->second;
        ++length;
      } while (x != step[0].first && length <= step.size());
      if (length != step.size() || x != step[0].first || step.size() < 3) frozen_[v] = 1;
    }
  }

  void neighbours(int v, std::vector<int>& out) const {
    out.clear();
    for (int f : vf_[static_cast<size_t>(v)])
      for (int x : F_[static_cast<size_t>(f)])
        if (x != v) out.push_back(x);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  // Whether p lies within max_error of the plane of every input face that u and w took in, given
  // their summed quadric's value there (cost): where that is within max_error² its root bounds
  // every distance; else (plane_by_plane) the planes are checked one by one. The largest distance
  // (or that root) in *error.
  bool within(size_t u, size_t w, const Vec3& p, double cost, double* error) const {
    if (cost <= bound_) {
      *error = std::sqrt(cost);
      return true;
    }
    if (!opt_.plane_by_plane) return false;
    double worst = 0;
    for (const size_t v : {u, w})
      for (const int f : planes_of_[v]) {
        const Eigen::Vector4d& h = plane_[static_cast<size_t>(f)];
        const double d = std::abs(h.head<3>().dot(p) + h[3]);
        if (d > opt_.max_error) return false;
        worst = std::max(worst, d);
      }
    *error = worst;
    return true;
  }

  // The collapse of edge (a, b), where its placement lies within the bound (within()); its
  // placement in *at where asked. Its cost, the queue's order, is the summed quadric there.
  bool candidate(int a, int b, Candidate* c, Vec3* at = nullptr, double* error = nullptr) const {
    const size_t ia = static_cast<size_t>(a), ib = static_cast<size_t>(b);
    if (frozen_[ia] && frozen_[ib]) return false;
    int u = std::min(a, b), w = std::max(a, b);
    if (frozen_[static_cast<size_t>(w)]) std::swap(u, w);
    const size_t iu = static_cast<size_t>(u), iw = static_cast<size_t>(w);
    Quadric q = q_[iu];
    q += q_[iw];
    Vec3 p = pos_[iu];
    if (!frozen_[iu]) {
      const Vec3 m = 0.5 * (pos_[iu] + pos_[iw]);
      p = minimiser_near(q, m, (pos_[iu] - pos_[iw]).norm());
    }
    const double cost = q.at(p);
    double e = 0;
    if (!within(iu, iw, p, cost, &e)) return false;
    if (c) *c = {cost, u, w, stamp_[iu], stamp_[iw]};
    if (at) *at = p;
    if (error) *error = e;
    return true;
  }

  // Collapses w into u at p where the checks (decimate_quadric) pass.
  bool collapse(int u, int w, const Vec3& p) {
    const size_t iu = static_cast<size_t>(u), iw = static_cast<size_t>(w);
    int shared[2], opposite[2], n_shared = 0;
    for (int f : vf_[iw]) {
      const auto& t = F_[static_cast<size_t>(f)];
      if (t[0] != u && t[1] != u && t[2] != u) continue;
      if (n_shared == 2) return false;
      shared[n_shared] = f;
      opposite[n_shared] = t[0] != u && t[0] != w ? t[0] : t[1] != u && t[1] != w ? t[1] : t[2];
      ++n_shared;
    }
    if (n_shared != 2 || opposite[0] == opposite[1]) return false;
    for (int o : opposite)
      if (vf_[static_cast<size_t>(o)].size() < 4) return false;
    // Link condition.
    neighbours(u, ring_u_);
    neighbours(w, ring_w_);
    int common = 0;
    for (size_t i = 0, j = 0; i < ring_u_.size() && j < ring_w_.size();) {
      if (ring_u_[i] < ring_w_[j]) ++i;
      else if (ring_w_[j] < ring_u_[i]) ++j;
      else ++common, ++i, ++j;
    }
    if (common != 2) return false;
    // Normals and shapes of the faces that stay.
    for (size_t side = 0; side < 2; ++side)
      for (int f : vf_[side == 0 ? iu : iw]) {
        if (f == shared[0] || f == shared[1]) continue;
        const auto& t = F_[static_cast<size_t>(f)];
        Vec3 old[3], now[3];
        for (size_t k = 0; k < 3; ++k) {
          old[k] = pos_[static_cast<size_t>(t[k])];
          now[k] = t[k] == u || t[k] == w ? p : old[k];
        }
        const Vec3 n_old = (old[1] - old[0]).cross(old[2] - old[0]);
        const Vec3 n_now = (now[1] - now[0]).cross(now[2] - now[0]);
        const double l_now = n_now.norm();
        if (!(l_now > 2.0 * tiny_area_)) return false;
        if (n_now.dot(n_old) < cos_turn_ * l_now * n_old.norm()) return false;
        const double s_now = shape(now[0], now[1], now[2]);
        if (s_now < 0.05 && s_now < shape(old[0], old[1], old[2])) return false;
      }
    // Made.
    source_[iu] = p == pos_[iu] ? source_[iu] : p == pos_[iw] ? source_[iw] : -1;
    pos_[iu] = p;
    q_[iu] += q_[iw];
    merged_.clear();
    std::set_union(planes_of_[iu].begin(), planes_of_[iu].end(), planes_of_[iw].begin(), planes_of_[iw].end(),
                   std::back_inserter(merged_));
    planes_of_[iu].swap(merged_);
    planes_of_[iw].clear();
    planes_of_[iw].shrink_to_fit();
    for (int f : shared) {
      face_alive_[static_cast<size_t>(f)] = 0;
      --faces_;
    }
    auto drop_shared = [&](std::vector<int>& list) {
      list.erase(std::remove_if(list.begin(), list.end(), [&](int f) { return f == shared[0] || f == shared[1]; }), list.end());
    };
    drop_shared(vf_[iu]);
    for (int o : opposite) drop_shared(vf_[static_cast<size_t>(o)]);
    for (int f : vf_[iw]) {
      if (f == shared[0] || f == shared[1]) continue;
      for (int& x : F_[static_cast<size_t>(f)])
        if (x == w) x = u;
      vf_[iu].push_back(f);
    }
    vf_[iw].clear();
    vf_[iw].shrink_to_fit();
    ++stamp_[iu];
    ++stamp_[iw];
    return true;
  }

  const SurfaceMesh& input_;
  DecimateOptions opt_;
  Vec3 centre_ = Vec3::Zero();
  double diag_ = 0, cos_turn_ = 0, tiny_area_ = 0;
  std::vector<Vec3> pos_;                 // about centre_
  std::vector<std::array<int, 3>> F_;
  std::vector<char> face_alive_;
  int faces_ = 0;
  std::vector<std::vector<int>> vf_;      // faces around each vertex (alive ones)
  std::vector<char> frozen_;
  std::vector<std::pair<int, int>> edges_;  // every edge once (a < b), sorted
  std::vector<Quadric> q_;
  double bound_ = 0;                      // max_error² (squared units)
  std::vector<Eigen::Vector4d> plane_;    // per input face: unit normal and offset about centre_ (0: no area)
  std::vector<std::vector<int>> planes_of_;  // per vertex: the input faces it took in, in increasing order
  std::vector<unsigned> stamp_;
  std::vector<Eigen::Index> source_;      // per vertex: the input vertex at whose place it is (-1: none)
  std::vector<std::vector<int>> parked_;  // per vertex: the other ends of its edges whose collapse
                                          // failed the checks, until the faces around it change
  std::unordered_set<std::uint64_t> parked_edges_;  // those edges, each once
  std::vector<int> ring_u_, ring_w_, merged_;  // scratch
};

}  // namespace

SurfaceMesh decimate_quadric(const SurfaceMesh& surface, const DecimateOptions& options, DecimateStats* stats) {
  if (!(options.max_error >= 0) || !std::isfinite(options.max_error))
    throw InputError("decimate_quadric: max_error must be finite and at least 0");
  if (!surface.V.allFinite()) throw InputError("decimate_quadric: a vertex coordinate is not finite");
  const Eigen::Index nv = surface.V.rows();
  if (surface.F.size() > 0 && (surface.F.minCoeff() < 0 || surface.F.maxCoeff() >= nv))
    throw InputError("decimate_quadric: a face's vertex index is out of range");
  Decimator d(surface, options);
  d.run(stats);
  return d.result(stats);
}

}  // namespace squeeze::meshing
