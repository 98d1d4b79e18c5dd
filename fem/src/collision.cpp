#include "squeeze/fem/collision.h"

#include <tbb/parallel_for.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "squeeze/common/error.h"

namespace squeeze::fem {
namespace {

constexpr int kBlock = 64;   // tets per task of the detection pass (fixed: results are concatenated in order)

bool allowed(const CollisionFilter& f, int v, int t) {
  const int gv = f.vertex_group[v], gt = f.tet_group[t];
  if (gv == gt && (!f.self_collision || (!f.vertex_on_surface.empty() && !f.vertex_on_surface[v]))) return false;
  return !(f.group_rigid[gv] && f.group_rigid[gt]);
}

// Cell coordinate, clamped so that far-flung (or non-finite) positions cannot overflow.
std::int64_t cell_of(double x, double inv) {
  const double c = std::floor(x * inv);
  if (!(c > -1e15)) return -1000000000000000LL;
  if (!(c < 1e15)) return 1000000000000000LL;
  return static_cast<std::int64_t>(c);
}

}  // namespace

TetFrame::TetFrame(const Eigen::Vector3d& a_, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& d)
    : a(a_) {
  Eigen::Matrix3d M;
  M.col(0) = b - a;
  M.col(1) = c - a;
  M.col(2) = d - a;
  const double det = M.determinant();
  valid = std::isfinite(det) && det != 0.0;
  if (valid) inverse = M.inverse();
}

Eigen::Vector4d TetFrame::barycentric(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d l = inverse * (p - a);
  return {1.0 - l[0] - l[1] - l[2], l[0], l[1], l[2]};
}

bool TetFrame::contains(const Eigen::Vector3d& p, Eigen::Vector4d* bary) const {
  if (!valid) return false;
  const Eigen::Vector4d b = barycentric(p);
  if (bary) *bary = b;
  return b.minCoeff() >= 0.0;
}

SpatialHash::SpatialHash(double cell, int table_size) : cell_(cell) {
  if (!(cell > 0) || !std::isfinite(cell)) throw InputError("spatial hash: cell size must be > 0");
  if (table_size < 1) throw InputError("spatial hash: table size must be >= 1");
  stamp_.assign(static_cast<size_t>(table_size), 0);
  fastmod_ = ~std::uint64_t{0} / static_cast<std::uint32_t>(table_size) + 1;
  head_.assign(static_cast<size_t>(table_size), -1);
  count_.assign(static_cast<size_t>(table_size), 0);
  scount_.assign(static_cast<size_t>(table_size), 0);
  ifill_.assign(static_cast<size_t>(table_size), 0);
}

std::uint32_t SpatialHash::hash(std::int64_t i, std::int64_t j, std::int64_t k) const {
  // 32-bit products (the coordinates' low bits), then a modulo by multiplication (Lemire, Kaser,
  // Kurz, "Faster remainder by direct computation", 2019): equal to h % table_size.
  // The coordinates are shifted by 2^20 (the grid's origin moved): with signed coordinates near
  // 0 the xor of the products is nearly symmetric and collides for ~40 % of the cells.
  constexpr std::uint32_t shift = 1u << 20;
  const std::uint32_t h = ((static_cast<std::uint32_t>(i) + shift) * 73856093u) ^
                          ((static_cast<std::uint32_t>(j) + shift) * 19349663u) ^
                          ((static_cast<std::uint32_t>(k) + shift) * 83492791u);
  const std::uint64_t low = fastmod_ * h;
  return static_cast<std::uint32_t>((static_cast<unsigned __int128>(low) * head_.size()) >> 64);
}

std::vector<Contact> SpatialHash::find(const Eigen::Ref<const RowMatrixX3d>& X, const Eigen::MatrixX4i& T,
                                       const CollisionFilter& filter) {
  const int nv = static_cast<int>(X.rows()), nt = static_cast<int>(T.rows());
  if (++now_ == 0) {  // wrapped around: clear once every 2^32 queries
    std::fill(stamp_.begin(), stamp_.end(), 0u);
    now_ = 1;
  }
  const double inv = 1.0 / cell_;
  entry_.resize(static_cast<size_t>(nv));
  auto key_of = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    constexpr std::int64_t m = (1 << 21) - 1;
    return ((i & m) << 42) | ((j & m) << 21) | (k & m);
  };
  // Pass 1: vertices grouped by hash entry (counting sort over the entries touched this time).
  vhash_.resize(static_cast<size_t>(nv));
  touched_.clear();
  std::vector<std::int64_t> vkey(static_cast<size_t>(nv));
  const int ngroups = static_cast<int>(filter.group_rigid.size());
  auto interior_vertex = [&](int v) { return !filter.vertex_on_surface.empty() && !filter.vertex_on_surface[v]; };
  for (int v = 0; v < nv; ++v) {
    const std::int64_t i = cell_of(X(v, 0), inv), j = cell_of(X(v, 1), inv), k = cell_of(X(v, 2), inv);
    const std::uint32_t h = hash(i, j, k);
    vhash_[v] = h;
    vkey[v] = key_of(i, j, k);
    if (stamp_[h] != now_) {
      stamp_[h] = now_;
      count_[h] = 0;
      scount_[h] = 0;
      touched_.push_back(h);
    }
    ++count_[h];
    if (!interior_vertex(v)) ++scount_[h];
  }
  int offset = 0;
  for (std::uint32_t h : touched_) {
    head_[h] = offset;
    offset += count_[h];
    ifill_[h] = scount_[h];  // interior vertices go after the surface ones
    count_[h] = 0;           // refilled below: surface cursor
  }
  // Per object: bounding box of its interior vertices.
  std::vector<Eigen::Vector3d> ilo(static_cast<size_t>(ngroups), Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()));
  std::vector<Eigen::Vector3d> ihi(static_cast<size_t>(ngroups), Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity()));
  for (int v = 0; v < nv; ++v) {
    const std::uint32_t h = vhash_[v];
    const int g = filter.vertex_group[v];
    const bool interior = interior_vertex(v);
    const int slot = interior ? ifill_[h]++ : count_[h]++;
    entry_[head_[h] + slot] = {X(v, 0), X(v, 1), X(v, 2), vkey[v], v, interior ? -1 - g : g};
    if (interior && X.row(v).allFinite()) {
      ilo[g] = ilo[g].cwiseMin(X.row(v).transpose());
      ihi[g] = ihi[g].cwiseMax(X.row(v).transpose());
    }
  }
  for (std::uint32_t h : touched_) count_[h] = ifill_[h];
  // Bounding boxes of all vertices and of the deformable ones: a tet's AABB is clipped to the
  // box of the vertices it may contain (rigid tets only meet deformable vertices), which keeps
  // large rigid tets from scanning cells where no vertex can be.
  Eigen::Vector3d all_lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), all_hi = -all_lo;
  Eigen::Vector3d def_lo = all_lo, def_hi = all_hi;
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d p = X.row(v).transpose();
    if (!p.allFinite()) continue;
    all_lo = all_lo.cwiseMin(p);
    all_hi = all_hi.cwiseMax(p);
    if (!filter.group_rigid[filter.vertex_group[v]]) {
      def_lo = def_lo.cwiseMin(p);
      def_hi = def_hi.cwiseMax(p);
    }
  }
  // Pass 2: tets look up the cells of their AABB.
  const int nblocks = (nt + kBlock - 1) / kBlock;
  std::vector<std::vector<Contact>> out(static_cast<size_t>(nblocks));
  tbb::parallel_for(0, nblocks, [&](int blk) {
    auto& res = out[blk];
    const int t1 = std::min(nt, (blk + 1) * kBlock);
    for (int t = blk * kBlock; t < t1; ++t) {
      const int c[4] = {T(t, 0), T(t, 1), T(t, 2), T(t, 3)};
      Eigen::Vector3d lo = X.row(c[0]).transpose(), hi = lo;
      for (int q = 1; q < 4; ++q) {
        lo = lo.cwiseMin(X.row(c[q]).transpose());
        hi = hi.cwiseMax(X.row(c[q]).transpose());
      }
      if (!lo.allFinite() || !hi.allFinite()) continue;
      const bool rigid_tet = filter.group_rigid[filter.tet_group[t]] != 0;
      const Eigen::Vector3d clo = lo.cwiseMax(rigid_tet ? def_lo : all_lo), chi = hi.cwiseMin(rigid_tet ? def_hi : all_hi);
      if ((clo.array() > chi.array()).any()) continue;
      // Interior vertices only meet tets of other objects: scan them only near such vertices.
      bool need_interior = false;
      for (int g = 0; g < ngroups && !need_interior; ++g)
        need_interior = g != filter.tet_group[t] && (ilo[g].array() <= hi.array()).all() &&
                        (ihi[g].array() >= lo.array()).all();
      const size_t first = res.size();
      bool have_frame = false;
      TetFrame frame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                     Eigen::Vector3d::UnitZ());
      const int tg = filter.tet_group[t];
      const bool tet_rigid = filter.group_rigid[tg] != 0;
      auto test = [&](const VertexEntry& en) {
        const int v = en.vertex;
        if (en.x < lo[0] || en.x > hi[0] || en.y < lo[1] || en.y > hi[1] || en.z < lo[2] || en.z > hi[2]) return;
        if (v == c[0] || v == c[1] || v == c[2] || v == c[3]) return;
        const int vg = en.group >= 0 ? en.group : -1 - en.group;
        if (vg == tg ? (!filter.self_collision || en.group < 0) : (tet_rigid && filter.group_rigid[vg])) return;
        const Eigen::Vector3d p(en.x, en.y, en.z);
        if (!have_frame) {
          frame = TetFrame(X.row(c[0]).transpose(), X.row(c[1]).transpose(), X.row(c[2]).transpose(),
                           X.row(c[3]).transpose());
          have_frame = true;
        }
        Contact ct;
        if (frame.contains(p, &ct.bary)) {
          ct.vertex = v;
          ct.tet = t;
          res.push_back(ct);
        }
      };
      const std::int64_t i0 = cell_of(clo[0], inv), i1 = cell_of(chi[0], inv), j0 = cell_of(clo[1], inv),
                         j1 = cell_of(chi[1], inv), k0 = cell_of(clo[2], inv), k1 = cell_of(chi[2], inv);
      const double cells = double(i1 - i0 + 1) * double(j1 - j0 + 1) * double(k1 - k0 + 1);
      const std::int64_t span = std::max({i1 - i0, j1 - j0, k1 - k0});
      if (cells > nv || span >= (1 << 20)) {  // a huge tet (far larger than a cell): test every vertex
        for (int e = 0; e < nv; ++e) test(entry_[e]);
      } else {
        for (std::int64_t k = k0; k <= k1; ++k)
          for (std::int64_t j = j0; j <= j1; ++j)
            for (std::int64_t i = i0; i <= i1; ++i) {
              const std::uint32_t h = hash(i, j, k);
              if (stamp_[h] != now_) continue;
              const std::int64_t key = key_of(i, j, k);
              const VertexEntry* en = entry_.data() + head_[h];
              for (const VertexEntry* end = en + (need_interior ? count_[h] : scount_[h]); en != end; ++en)
                if (en->key == key) test(*en);  // else another cell with the same hash
            }
      }
      std::sort(res.begin() + static_cast<std::ptrdiff_t>(first), res.end(),
                [](const Contact& a, const Contact& b) { return a.vertex < b.vertex; });
    }
  });
  std::vector<Contact> all;
  size_t total = 0;
  for (const auto& r : out) total += r.size();
  all.reserve(total);
  for (const auto& r : out) all.insert(all.end(), r.begin(), r.end());
  return all;
}

std::vector<Contact> find_contacts_brute_force(const Eigen::Ref<const RowMatrixX3d>& X, const Eigen::MatrixX4i& T,
                                               const CollisionFilter& filter) {
  std::vector<Contact> all;
  for (int t = 0; t < T.rows(); ++t) {
    const TetFrame frame(X.row(T(t, 0)).transpose(), X.row(T(t, 1)).transpose(), X.row(T(t, 2)).transpose(),
                         X.row(T(t, 3)).transpose());
    for (int v = 0; v < X.rows(); ++v) {
      if (v == T(t, 0) || v == T(t, 1) || v == T(t, 2) || v == T(t, 3) || !allowed(filter, v, t)) continue;
      Contact ct;
      if (frame.contains(X.row(v).transpose(), &ct.bary)) {
        ct.vertex = v;
        ct.tet = t;
        all.push_back(ct);
      }
    }
  }
  return all;
}

namespace {

// Walks body B's tets from tet t (local, containing p) along the segment p→q until the segment
// leaves B through a boundary triangle. x: intersection point, n: outward unit normal there.
bool surface_hit(const Body& B, int fv, const Eigen::Ref<const RowMatrixX3d>& X, int t, const Eigen::Vector3d& p,
                 const Eigen::Vector3d& q, Eigen::Vector3d& x, Eigen::Vector3d& n) {
  int prev = -1;
  const int max_steps = B.tets() + 4;
  for (int step = 0; step < max_steps; ++step) {
    const TetFrame fr(X.row(fv + B.T(t, 0)).transpose(), X.row(fv + B.T(t, 1)).transpose(),
                      X.row(fv + B.T(t, 2)).transpose(), X.row(fv + B.T(t, 3)).transpose());
    if (!fr.valid) return false;
    const Eigen::Vector4d bp = fr.barycentric(p), bq = fr.barycentric(q);
    double best = std::numeric_limits<double>::infinity();
    int face = -1;
    for (int k = 0; k < 4; ++k) {
      if (!(bq[k] < bp[k])) continue;
      if (prev >= 0 && B.neighbor(t, k) == prev) continue;  // the face we came through
      const double lam = bp[k] / (bp[k] - bq[k]);
      if (lam < best) {
        best = lam;
        face = k;
      }
    }
    if (face < 0 || best > 1.0) return false;  // q lies in this tet: the segment does not leave B here
    const int nb = B.neighbor(t, face);
    if (nb < 0) {
      const int bf = B.boundary_face(t, face);
      if (bf < 0) return false;
      const Eigen::Vector3d a = X.row(fv + B.F(bf, 0)).transpose(), b = X.row(fv + B.F(bf, 1)).transpose(),
                            c = X.row(fv + B.F(bf, 2)).transpose();
      const Eigen::Vector3d nn = (b - a).cross(c - a);
      const double len = nn.norm();
      if (!(len > 0)) return false;
      n = nn / len;
      x = p + std::max(0.0, best) * (q - p);
      return true;
    }
    prev = t;
    t = nb;
  }
  return false;
}

}  // namespace

std::vector<Penetration> penetration_depths(const CollisionScene& scene, const Eigen::Ref<const RowMatrixX3d>& X,
                                            const std::vector<Contact>& contacts) {
  const int nv = static_cast<int>(X.rows());
  const int nb = static_cast<int>(scene.bodies.size());
  auto body_of_vertex = [&](int v) {
    return static_cast<int>(std::upper_bound(scene.first_vertex.begin(), scene.first_vertex.end(), v) -
                            scene.first_vertex.begin()) - 1;
  };
  auto body_of_tet = [&](int t) {
    return static_cast<int>(std::upper_bound(scene.first_tet.begin(), scene.first_tet.end(), t) -
                            scene.first_tet.begin()) - 1;
  };
  (void)nb;
  // 1. Colliding vertices: first contact of each vertex.
  std::vector<int> slot(static_cast<size_t>(nv), -1);  // index into result
  std::vector<Penetration> res;
  for (const Contact& c : contacts) {
    if (slot[c.vertex] >= 0) continue;
    slot[c.vertex] = static_cast<int>(res.size());
    Penetration p;
    p.vertex = c.vertex;
    p.tet = c.tet;
    p.body = body_of_tet(c.tet);
    p.bary = c.bary;
    p.depth = 0;
    p.direction.setZero();
    p.layer = -1;  // unassigned
    res.push_back(p);
  }
  std::vector<int> vbody(res.size());
  for (size_t r = 0; r < res.size(); ++r) vbody[r] = body_of_vertex(res[r].vertex);

  // 2. Border vertices.
  std::vector<int> frontier;
  for (size_t r = 0; r < res.size(); ++r) {
    Penetration& pen = res[r];
    const int a = vbody[r];
    const Body& A = *scene.bodies[a];
    const Body& B = *scene.bodies[pen.body];
    const int fa = scene.first_vertex[a], fb = scene.first_vertex[pen.body];
    const int lp = pen.vertex - fa;
    const Eigen::Vector3d p = X.row(pen.vertex).transpose();
    double sw = 0, sd = 0;
    Eigen::Vector3d sn = Eigen::Vector3d::Zero();
    for (int e = A.edge_start[lp]; e < A.edge_start[lp + 1]; ++e) {
      const int code = A.edge_code[e];
      const int lq = A.E(code / 2, 1 - code % 2);
      const int q = fa + lq;
      if (slot[q] >= 0) continue;  // both ends colliding
      Eigen::Vector3d x, n;
      if (!surface_hit(B, fb, X, pen.tet - scene.first_tet[pen.body], p, X.row(q).transpose(), x, n)) continue;
      const double d2 = (x - p).squaredNorm();
      const double w = 1.0 / std::max(d2, 1e-24);
      sw += w;
      sd += w * (x - p).dot(n);
      sn += w * n;
    }
    if (sw > 0 && sn.norm() > 0) {
      pen.depth = sd / sw;
      pen.direction = sn.normalized();
      pen.layer = 0;
      frontier.push_back(static_cast<int>(r));
    }
  }

  // 3. Breadth-first propagation into the colliding region (same penetrated object).
  std::vector<char> queued(res.size(), 0);
  for (int layer = 1; !frontier.empty(); ++layer) {
    std::vector<int> next;
    for (int r : frontier) {
      const Body& A = *scene.bodies[vbody[r]];
      const int fa = scene.first_vertex[vbody[r]];
      const int lp = res[r].vertex - fa;
      for (int e = A.edge_start[lp]; e < A.edge_start[lp + 1]; ++e) {
        const int code = A.edge_code[e];
        const int q = fa + A.E(code / 2, 1 - code % 2);
        const int s = slot[q];
        if (s < 0 || res[s].layer >= 0 || queued[s] || res[s].body != res[r].body) continue;
        queued[s] = 1;
        next.push_back(s);
      }
    }
    std::sort(next.begin(), next.end());
    // Compute the whole layer from earlier layers, then assign.
    std::vector<std::pair<double, Eigen::Vector3d>> val(next.size());
    for (size_t i = 0; i < next.size(); ++i) {
      const int r = next[i];
      const Body& A = *scene.bodies[vbody[r]];
      const int fa = scene.first_vertex[vbody[r]];
      const int lp = res[r].vertex - fa;
      const Eigen::Vector3d p = X.row(res[r].vertex).transpose();
      double sw = 0, sd = 0;
      Eigen::Vector3d sn = Eigen::Vector3d::Zero();
      for (int e = A.edge_start[lp]; e < A.edge_start[lp + 1]; ++e) {
        const int code = A.edge_code[e];
        const int q = fa + A.E(code / 2, 1 - code % 2);
        const int s = slot[q];
        if (s < 0 || res[s].layer < 0 || res[s].body != res[r].body) continue;
        const Eigen::Vector3d pj = X.row(q).transpose();
        const double w = 1.0 / std::max((pj - p).squaredNorm(), 1e-24);
        sw += w;
        sd += w * ((pj - p).dot(res[s].direction) + res[s].depth);
        sn += w * res[s].direction;
      }
      val[i] = {sw > 0 ? sd / sw : 0.0, sn.norm() > 0 ? Eigen::Vector3d(sn.normalized()) : Eigen::Vector3d::Zero()};
    }
    frontier.clear();
    for (size_t i = 0; i < next.size(); ++i) {
      if (val[i].second.squaredNorm() == 0) continue;
      res[next[i]].depth = val[i].first;
      res[next[i]].direction = val[i].second;
      res[next[i]].layer = layer;
      frontier.push_back(next[i]);
    }
  }
  res.erase(std::remove_if(res.begin(), res.end(), [](const Penetration& p) { return p.layer < 0; }), res.end());
  return res;
}

}  // namespace squeeze::fem
