#include "squeeze/fem/collision.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "squeeze/common/error.h"

namespace squeeze::fem {
namespace {

constexpr int kBlock = 64;   // tets per task of the detection pass (fixed: results are concatenated in order)

bool allowed(const CollisionFilter& f, int v, int t) {
  const int gv = f.vertex_group[v], gt = f.tet_group[t];
  if (gv == gt && (!f.self_collision || (!f.vertex_on_surface.empty() && !f.vertex_on_surface[v]))) return false;
  return !(f.group_rigid[gv] && f.group_rigid[gt]);
}

// Cell coordinate floor(x / cell), clamped so that far-flung (or non-finite) positions cannot
// overflow. The floor by truncation (exact below 2^52) avoids a libm call without SSE4.1.
std::int64_t cell_of(double x, double inv) {
  const double y = x * inv;
  if (!(y > -1e15)) return -1000000000000000LL;
  if (!(y < 1e15)) return 1000000000000000LL;
  const std::int64_t c = static_cast<std::int64_t>(y);  // toward zero
  return static_cast<double>(c) > y ? c - 1 : c;
}

}  // namespace

SpatialHash::SpatialHash(double cell, int table_size) : cell_(cell) {
  if (!(cell > 0) || !std::isfinite(cell)) throw InputError("spatial hash: cell size must be > 0");
  if (table_size < 1) throw InputError("spatial hash: table size must be >= 1");
  fastmod_ = ~std::uint64_t{0} / static_cast<std::uint32_t>(table_size) + 1;
  bucket_.assign(static_cast<size_t>(table_size), Bucket{0, -1, 0, 0});
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
  return reduce(h);
}

std::vector<Contact> SpatialHash::find(const Eigen::Ref<const RowMatrixX3d>& X, const Eigen::MatrixX4i& T,
                                       const CollisionFilter& filter, int serial_below) {
  const int nv = static_cast<int>(X.rows()), nt = static_cast<int>(T.rows());
  if (++now_ == 0) {  // wrapped around: clear once every 2^32 queries
    for (Bucket& bk : bucket_) bk.stamp = 0;
    now_ = 1;
  }
  const double inv = 1.0 / cell_;
  entry_.resize(static_cast<size_t>(nv));
  auto key_of = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    constexpr std::int64_t m = (1 << 21) - 1;
    return ((i & m) << 42) | ((j & m) << 21) | (k & m);
  };
  // Pass 1: vertices grouped by hash entry (counting sort over the entries touched this time),
  // and the bounding boxes used to clip the tets' lookups (same loop).
  vhash_.resize(static_cast<size_t>(nv));
  vkey_.resize(static_cast<size_t>(nv));
  touched_.clear();
  const int ngroups = static_cast<int>(filter.group_rigid.size());
  const bool all_surface = filter.vertex_on_surface.empty();
  const double infd = std::numeric_limits<double>::infinity();
  // Per object: bounding box of its interior vertices.
  std::vector<Eigen::Vector3d> ilo(static_cast<size_t>(ngroups), Eigen::Vector3d::Constant(infd));
  std::vector<Eigen::Vector3d> ihi(static_cast<size_t>(ngroups), Eigen::Vector3d::Constant(-infd));
  // Bounding box of the deformable vertices: a rigid tet's AABB is clipped to it (rigid tets only
  // meet deformable vertices), which keeps large rigid tets from scanning cells where no vertex
  // can be.
  Eigen::Vector3d def_lo = Eigen::Vector3d::Constant(infd), def_hi = -def_lo;
  Bucket* const bk = bucket_.data();
  vcell_.resize(static_cast<size_t>(nv));
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 2048), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v != r.end(); ++v) {
      const std::int64_t i = cell_of(X(v, 0), inv), j = cell_of(X(v, 1), inv), k = cell_of(X(v, 2), inv);
      vcell_[v] = {i, j, k};
      vhash_[v] = hash(i, j, k);
      vkey_[v] = key_of(i, j, k);
    }
  });
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d p = X.row(v).transpose();
    const std::uint32_t h = vhash_[v];
    Bucket& b = bk[h];
    if (b.stamp != now_) {
      b.stamp = now_;
      b.count = 0;
      b.scount = 0;
      touched_.push_back(h);
    }
    ++b.count;
    const bool interior = !all_surface && !filter.vertex_on_surface[v];
    if (!interior) ++b.scount;
    if (!p.allFinite()) continue;
    const int g = filter.vertex_group[v];
    if (interior) {
      ilo[g] = ilo[g].cwiseMin(p);
      ihi[g] = ihi[g].cwiseMax(p);
    }
    if (!filter.group_rigid[g]) {
      def_lo = def_lo.cwiseMin(p);
      def_hi = def_hi.cwiseMax(p);
    }
  }
  int offset = 0;
  for (std::uint32_t h : touched_) {
    Bucket& b = bk[h];
    b.head = offset;
    offset += b.count;
    ifill_[h] = b.scount;  // interior vertices go after the surface ones
    b.count = 0;           // refilled below: surface cursor
  }
  for (int v = 0; v < nv; ++v) {
    const std::uint32_t h = vhash_[v];
    const int g = filter.vertex_group[v];
    const bool interior = !all_surface && !filter.vertex_on_surface[v];
    Bucket& b = bk[h];
    const int slot = interior ? ifill_[h]++ : b.count++;
    entry_[b.head + slot] = {X(v, 0), X(v, 1), X(v, 2), vkey_[v], v, interior ? -1 - g : g};
  }
  for (std::uint32_t h : touched_) bk[h].count = ifill_[h];
  const std::array<std::int64_t, 3> def_lo_cell{cell_of(def_lo[0], inv), cell_of(def_lo[1], inv), cell_of(def_lo[2], inv)},
      def_hi_cell{cell_of(def_hi[0], inv), cell_of(def_hi[1], inv), cell_of(def_hi[2], inv)};
  // Pass 2: tets look up the cells of their AABB.
  const int nblocks = (nt + kBlock - 1) / kBlock;
  if (blocks_.size() < static_cast<size_t>(nblocks)) blocks_.resize(static_cast<size_t>(nblocks));
  if (cands_.size() < static_cast<size_t>(nblocks)) cands_.resize(static_cast<size_t>(nblocks));
  const std::uint32_t now = now_;
  const VertexEntry* const entries = entry_.data();
  // Boxes of the objects that have interior vertices (the others never need their entries' tails).
  struct IBox {
    int g;
    double lo[3], hi[3];
  };
  std::vector<IBox> iboxes;
  for (int g = 0; g < ngroups; ++g)
    if (ilo[g][0] <= ihi[g][0]) iboxes.push_back({g, {ilo[g][0], ilo[g][1], ilo[g][2]}, {ihi[g][0], ihi[g][1], ihi[g][2]}});
  const double* const xp = X.data();
  const std::ptrdiff_t xs = X.outerStride();
  const int* const tcol = T.data();  // column-major: T(t, k) = tcol[t + k·nt]
  const bool self = filter.self_collision;
  auto block = [&](int blk) {
    auto& res = blocks_[blk];
    res.clear();
    // Cell-mates found for the last scanned cell range (a per-block buffer, reused between
    // queries): consecutive tets of a mesh often share their range (the 6 tets of a Kuhn cube
    // share their AABB), so the lookups are reused.
    std::vector<const VertexEntry*>& cand = cands_[blk];
    std::array<std::int64_t, 7> cached{};
    bool have_cached = false;
    const int t1 = std::min(nt, (blk + 1) * kBlock);
    for (int t = blk * kBlock; t < t1; ++t) {
      const int c[4] = {tcol[t], tcol[t + nt], tcol[t + 2 * nt], tcol[t + 3 * nt]};
      const double* const p0 = xp + xs * c[0];
      const double* const p1 = xp + xs * c[1];
      const double* const p2 = xp + xs * c[2];
      const double* const p3 = xp + xs * c[3];
      using CMap = Eigen::Map<const Eigen::Vector3d>;
      Eigen::Vector3d lo = CMap(p0), hi = lo;
      lo = lo.cwiseMin(CMap(p1)), hi = hi.cwiseMax(CMap(p1));
      lo = lo.cwiseMin(CMap(p2)), hi = hi.cwiseMax(CMap(p2));
      lo = lo.cwiseMin(CMap(p3)), hi = hi.cwiseMax(CMap(p3));
      // All finite: x − x is 0 for a finite x, NaN otherwise.
      if (!((lo - lo).sum() + (hi - hi).sum() == 0.0)) continue;
      const int tg = filter.tet_group[t];
      const bool tet_rigid = filter.group_rigid[tg] != 0;
      // A deformable tet's corners are among all vertices, so its AABB lies in theirs: only rigid
      // tets (which meet deformable vertices only) are clipped, to the deformable vertices' box.
      if (tet_rigid && ((lo.array() > def_hi.array()).any() || (def_lo.array() > hi.array()).any() ||
                        (def_lo.array() > def_hi.array()).any()))
        continue;
      // Interior vertices only meet tets of other objects: scan them only near such vertices.
      bool need_interior = false;
      for (const IBox& b : iboxes)
        if (b.g != tg && b.lo[0] <= hi[0] && b.lo[1] <= hi[1] && b.lo[2] <= hi[2] && b.hi[0] >= lo[0] &&
            b.hi[1] >= lo[1] && b.hi[2] >= lo[2]) {
          need_interior = true;
          break;
        }
      const size_t first = res.size();
      alignas(TetFrame) unsigned char frame_buf[sizeof(TetFrame)];
      const TetFrame* frame = nullptr;  // built at the first candidate
      const double lx = lo[0], ly = lo[1], lz = lo[2], hx = hi[0], hy = hi[1], hz = hi[2];
#if defined(__SSE2__)
      // One branch per candidate instead of up to six: x, y compared as a pair, z alone. Like the
      // scalar test !(x < lo || x > hi), a NaN coordinate passes (the containment test rejects it).
      const __m128d lxy = _mm_set_pd(ly, lx), hxy = _mm_set_pd(hy, hx), lz1 = _mm_set_sd(lz), hz1 = _mm_set_sd(hz);
      auto in_box = [&](const VertexEntry& en) {
        const __m128d xy = _mm_loadu_pd(&en.x), z = _mm_load_sd(&en.z);
        const __m128d ixy = _mm_and_pd(_mm_cmpnlt_pd(xy, lxy), _mm_cmpngt_pd(xy, hxy));
        const __m128d iz = _mm_and_pd(_mm_cmpnlt_sd(z, lz1), _mm_cmpngt_sd(z, hz1));
        return ((_mm_movemask_pd(ixy) << 1) | (_mm_movemask_pd(iz) & 1)) == 7;
      };
#else
      auto in_box = [&](const VertexEntry& en) {
        return !(en.x < lx || en.x > hx || en.y < ly || en.y > hy || en.z < lz || en.z > hz);
      };
#endif
      auto accept = [&](double x, double y, double z, int v, int group) {
        if ((v == c[0]) | (v == c[1]) | (v == c[2]) | (v == c[3])) return;
        const int vg = group >= 0 ? group : -1 - group;
        if (vg == tg ? (!self || group < 0) : (tet_rigid && filter.group_rigid[vg])) return;
        if (!frame)
          frame = new (frame_buf) TetFrame(Eigen::Vector3d(p0[0], p0[1], p0[2]), Eigen::Vector3d(p1[0], p1[1], p1[2]),
                                           Eigen::Vector3d(p2[0], p2[1], p2[2]), Eigen::Vector3d(p3[0], p3[1], p3[2]));
        Contact ct;
        if (frame->contains(Eigen::Vector3d(x, y, z), &ct.bary)) {
          ct.vertex = v;
          ct.tet = t;
          res.push_back(ct);
        }
      };
      // Cells of the (clipped) AABB: floor is monotone, so the cell of a min / max of coordinates
      // is the min / max of the cells (the corners' cells come from pass 1).
      const std::int64_t *C0 = vcell_[c[0]].data(), *C1 = vcell_[c[1]].data(), *C2 = vcell_[c[2]].data(),
                         *C3 = vcell_[c[3]].data();
      std::int64_t r[6];
      for (int a = 0; a < 3; ++a) {
        const std::int64_t m01 = C1[a] < C0[a] ? C1[a] : C0[a], m23 = C3[a] < C2[a] ? C3[a] : C2[a];
        const std::int64_t M01 = C0[a] < C1[a] ? C1[a] : C0[a], M23 = C2[a] < C3[a] ? C3[a] : C2[a];
        r[2 * a] = m23 < m01 ? m23 : m01;
        r[2 * a + 1] = M01 < M23 ? M23 : M01;
      }
      if (tet_rigid)
        for (int a = 0; a < 3; ++a) {
          r[2 * a] = std::max(r[2 * a], def_lo_cell[a]);
          r[2 * a + 1] = std::min(r[2 * a + 1], def_hi_cell[a]);
        }
      const std::int64_t i0 = r[0], i1 = r[1], j0 = r[2], j1 = r[3], k0 = r[4], k1 = r[5];
      const std::int64_t di = i1 - i0, dj = j1 - j0, dk = k1 - k0;
      if ((di | dj | dk) >= (1 << 20) || (di + 1) * (dj + 1) * (dk + 1) > nv) {
        // a huge tet (far larger than a cell): test every vertex
        for (int e = 0; e < nv; ++e)
          if (in_box(entries[e]))
            accept(entries[e].x, entries[e].y, entries[e].z, entries[e].vertex, entries[e].group);
      } else {
        const std::array<std::int64_t, 7> range{i0, i1, j0, j1, k0, k1, need_interior ? 1 : 0};
        if (!have_cached || range != cached) {
          cached = range;
          have_cached = true;
          cand.clear();
          // hash() and key_of() with their per-axis terms hoisted out of the inner loops.
          constexpr std::uint32_t shift = 1u << 20;
          constexpr std::int64_t m21 = (1 << 21) - 1;
          for (std::int64_t k = k0; k <= k1; ++k) {
            const std::uint32_t hk = (static_cast<std::uint32_t>(k) + shift) * 83492791u;
            for (std::int64_t j = j0; j <= j1; ++j) {
              const std::uint32_t hjk = ((static_cast<std::uint32_t>(j) + shift) * 19349663u) ^ hk;
              const std::int64_t kjk = ((j & m21) << 21) | (k & m21);
              for (std::int64_t i = i0; i <= i1; ++i) {
                const Bucket& b = bk[reduce(((static_cast<std::uint32_t>(i) + shift) * 73856093u) ^ hjk)];
                if (b.stamp != now) continue;
                const std::int64_t key = ((i & m21) << 42) | kjk;
                const VertexEntry* en = entries + b.head;
                for (const VertexEntry* end = en + (need_interior ? b.count : b.scount); en != end; ++en)
                  if (en->key == key) cand.push_back(en);  // else another cell with the same hash
              }
            }
          }
        }
        for (const VertexEntry* en : cand)
          if (in_box(*en)) accept(en->x, en->y, en->z, en->vertex, en->group);
      }
      if (res.size() - first > 1)
        std::sort(res.begin() + static_cast<std::ptrdiff_t>(first), res.end(),
                  [](const Contact& a, const Contact& b) { return a.vertex < b.vertex; });
    }
  };
  // Small scenes: waking TBB workers costs more than the pass (results do not depend on it).
  if (nt < serial_below) {
    for (int blk = 0; blk < nblocks; ++blk) block(blk);
  } else {
    tbb::parallel_for(0, nblocks, block);
  }
  std::vector<Contact> all;
  size_t total = 0;
  for (int blk = 0; blk < nblocks; ++blk) total += blocks_[blk].size();
  all.reserve(total);
  for (int blk = 0; blk < nblocks; ++blk) all.insert(all.end(), blocks_[blk].begin(), blocks_[blk].end());
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
                                            const std::vector<Contact>& contacts, int serial_below) {
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

  // 2. Border vertices: each from its own edges only, so in parallel (same result).
  auto border = [&](size_t r) {
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
    }
  };
  if (res.size() < static_cast<size_t>(std::max(0, serial_below))) {
    for (size_t r = 0; r < res.size(); ++r) border(r);
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, res.size(), 8), [&](const tbb::blocked_range<size_t>& b) {
      for (size_t r = b.begin(); r != b.end(); ++r) border(r);
    });
  }
  std::vector<int> frontier;
  for (size_t r = 0; r < res.size(); ++r)
    if (res[r].layer == 0) frontier.push_back(static_cast<int>(r));

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
