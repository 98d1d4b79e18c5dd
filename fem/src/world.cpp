#include "squeeze/fem/world.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <Eigen/LU>
#include <algorithm>
#include <cstdint>
#include <cmath>
#include <string>

#include "squeeze/common/error.h"
#include "squeeze/fem/constraints.h"

namespace squeeze::fem {
namespace {

int next_prime(int n) {
  auto prime = [](int x) {
    if (x < 2) return false;
    for (int d = 2; static_cast<long long>(d) * d <= x; ++d)
      if (x % d == 0) return false;
    return true;
  };
  while (!prime(n)) ++n;
  return n;
}

constexpr int kClusterRows = 128;       // vertices per cluster of an element group
constexpr size_t kSerialElements = 2048;  // fewer elements (edges + tets): force pass on the calling thread

template <class Fn>
void parallel_rows(int n, Fn fn) {
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 512), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) fn(i);
  });
}

}  // namespace

World::World(const WorldOptions& options) : options_(options) {
  if (!(options.h > 0) || !std::isfinite(options.h)) throw InputError("fem world: time step h must be > 0");
  if (options.contact_stiffness < 0 || options.contact_damping < 0)
    throw InputError("fem world: contact stiffness and damping must be >= 0");
  if (!options.gravity.allFinite()) throw InputError("fem world: gravity must be finite");
  if (options.cell_size < 0 || options.table_size < 0)
    throw InputError("fem world: cell_size and table_size must be >= 0 (0: automatic)");
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

int World::add_body(Body body) {
  const int b = static_cast<int>(bodies_.size());
  body.set_material(body.material);  // coefficients and masses follow the material as assigned
  if (body.rigid) {
    state_row_.push_back(-1);
  } else {
    state_row_.push_back(rows_);
    const int n = body.vertices();
    mass_.conservativeResize(rows_ + n);
    mass_.segment(rows_, n) = body.mass;
    pinned_.resize(static_cast<size_t>(rows_ + n), 0);
    contact_scale_.conservativeResize(rows_ + n);
    contact_scale_.segment(rows_, n).setOnes();
    if (options_.cap_contact_stiffness && options_.contact_stiffness > 0) {
      Eigen::VectorXd w2v;
      vertex_frequency_bounds(body, body.mass, w2v);
      const double w2 = w2v.maxCoeff();  // bound of the object's highest elastic ω² (1/s²)
      for (int i = 0; i < n; ++i)
        contact_scale_(rows_ + i) = std::min(1.0, body.mass(i) * w2 / options_.contact_stiffness);
    }
    rows_ += n;
  }
  bodies_.push_back(std::move(body));
  prepared_ = false;
  return b;
}

int World::pin(const Eigen::AlignedBox3d& box) {
  for (int b = 0; b < bodies(); ++b) {
    if (state_row_[b] < 0) continue;
    for (int i = 0; i < bodies_[b].vertices(); ++i)
      if (box.contains(bodies_[b].rest.row(i).transpose())) pinned_[state_row_[b] + i] = 1;
  }
  prepared_ = false;
  int n = 0;
  for (char p : pinned_) n += p;
  return n;
}

void World::pin_vertex(int row) {
  if (row < 0 || row >= rows_) throw InputError("fem world: pinned row " + std::to_string(row) + " out of range");
  pinned_[row] = 1;
  prepared_ = false;
}

int World::tets() const {
  int n = 0;
  for (const Body& b : bodies_) n += b.tets();
  return n;
}

State World::initial_state() const {
  State s;
  s.x.resize(rows_, 3);
  s.v = RowMatrixX3d::Zero(rows_, 3);
  for (int b = 0; b < bodies(); ++b)
    if (state_row_[b] >= 0) s.x.middleRows(state_row_[b], bodies_[b].vertices()) = bodies_[b].rest;
  return s;
}

void World::prepare() {
  inv_mass_.resize(rows_);
  for (int i = 0; i < rows_; ++i) inv_mass_(i) = (pinned_[i] || !(mass_(i) > 0)) ? 0.0 : 1.0 / mass_(i);
  contact_k_.resize(rows_);
  contact_c_.resize(rows_);
  for (int i = 0; i < rows_; ++i) {
    contact_k_(i) = options_.contact_stiffness * contact_scale(i);
    contact_c_(i) = options_.contact_damping * contact_scale(i);
  }
  build_element_groups();
  contact_head_.assign(static_cast<size_t>(rows_), -1);
  contact_tail_.assign(static_cast<size_t>(rows_), -1);
  contact_rows_.clear();
  // Collision numbering: deformables in state order, then rigid objects.
  scene_ = CollisionScene{};
  filter_ = CollisionFilter{};
  filter_.self_collision = options_.self_collision;
  std::vector<int> order;
  for (int b = 0; b < bodies(); ++b)
    if (state_row_[b] >= 0) order.push_back(b);
  for (int b = 0; b < bodies(); ++b)
    if (state_row_[b] < 0) order.push_back(b);
  int nv_all = 0, nt_all = 0;
  double edge_sum = 0;
  long long edge_count = 0;
  for (int b : order) {
    scene_.bodies.push_back(&bodies_[b]);
    scene_.first_vertex.push_back(nv_all);
    scene_.first_tet.push_back(nt_all);
    nv_all += bodies_[b].vertices();
    nt_all += bodies_[b].tets();
    if (!bodies_[b].rigid || rows_ == 0) {  // rigid obstacles' (often long) edges do not set the cell
      edge_sum += bodies_[b].D0.sum();
      edge_count += bodies_[b].D0.size();
    }
  }
  // Groups are bodies in the collision order; map penetrated-body indices back when used.
  T_all_.resize(nt_all, 4);
  X_all_.resize(nv_all, 3);
  filter_.vertex_group.resize(static_cast<size_t>(nv_all));
  filter_.tet_group.resize(static_cast<size_t>(nt_all));
  filter_.vertex_on_surface.resize(static_cast<size_t>(nv_all));
  for (size_t g = 0; g < order.size(); ++g) {
    const Body& B = bodies_[order[g]];
    const int fv = scene_.first_vertex[g], ft = scene_.first_tet[g];
    T_all_.middleRows(ft, B.tets()) = B.T.array() + fv;
    X_all_.middleRows(fv, B.vertices()) = B.rest;
    std::fill(filter_.vertex_group.begin() + fv, filter_.vertex_group.begin() + fv + B.vertices(), static_cast<int>(g));
    std::copy(B.on_boundary.begin(), B.on_boundary.end(), filter_.vertex_on_surface.begin() + fv);
    std::fill(filter_.tet_group.begin() + ft, filter_.tet_group.begin() + ft + B.tets(), static_cast<int>(g));
    filter_.group_rigid.push_back(B.rigid ? 1 : 0);
  }
  const double cell = options_.cell_size > 0 ? options_.cell_size : (edge_count ? edge_sum / edge_count : 1.0);
  const int table = options_.table_size > 0 ? options_.table_size : next_prime(std::max(4 * nv_all, 97));
  if (!hash_ || hash_->cell() != cell || hash_->table_size() != table) hash_ = std::make_unique<SpatialHash>(cell, table);
  prepared_ = true;
}

void World::build_element_groups() {
  // Clusters: per deformable object, its vertices in the Morton order of their rest positions
  // (10 bits per axis in the object's bounding box), kClusterRows at a time.
  edges_.clear();
  tet_elems_.clear();
  groups_.clear();
  std::vector<int> rank(static_cast<size_t>(rows_), 0);  // position of a row in its object's Morton order
  struct Owned { int cluster, elem; };
  std::vector<Owned> edge_owner, tet_owner;
  std::vector<EdgeElem> all_edges;
  std::vector<TetElem> all_tets;
  int clusters = 0;
  for (int b = 0; b < bodies(); ++b) {
    const int r0 = state_row_[b];
    if (r0 < 0) continue;
    const Body& B = bodies_[b];
    const int n = B.vertices();
    const Eigen::Vector3d lo = B.rest.colwise().minCoeff().transpose(), hi = B.rest.colwise().maxCoeff().transpose();
    const Eigen::Vector3d scale = (1023.0 / (hi - lo).cwiseMax(1e-300).array()).matrix();
    std::vector<std::pair<std::uint32_t, int>> key(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      std::uint32_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const double q = (B.rest(i, a) - lo[a]) * scale[a];
        const std::uint32_t c = q > 0 ? static_cast<std::uint32_t>(std::min(1023.0, q)) : 0u;
        for (int bit = 0; bit < 10; ++bit) code |= ((c >> bit) & 1u) << (3 * bit + a);
      }
      key[i] = {code, i};
    }
    std::sort(key.begin(), key.end());
    for (int p = 0; p < n; ++p) rank[r0 + key[p].second] = p;
    auto cluster_of = [&](int row) { return clusters + rank[row] / kClusterRows; };
    auto owner = [&](const int* v, int m) {
      int best = v[0];
      for (int c = 1; c < m; ++c)
        if (rank[v[c]] < rank[best]) best = v[c];
      return cluster_of(best);
    };
    for (int e = 0; e < B.E.rows(); ++e) {
      const int v[2] = {r0 + B.E(e, 0), r0 + B.E(e, 1)};
      edge_owner.push_back({owner(v, 2), static_cast<int>(all_edges.size())});
      all_edges.push_back({v[0], v[1], B.D0(e), B.k_edge(e), B.kd_edge(e), 0, 0});
    }
    for (int t = 0; t < B.tets(); ++t) {
      const int v[4] = {r0 + B.T(t, 0), r0 + B.T(t, 1), r0 + B.T(t, 2), r0 + B.T(t, 3)};
      tet_owner.push_back({owner(v, 4), static_cast<int>(all_tets.size())});
      all_tets.push_back({{v[0], v[1], v[2], v[3]}, B.V0(t), B.k_tet(t), B.kd_tet(t), {0, 0, 0, 0}});
    }
    clusters += (n + kClusterRows - 1) / kClusterRows;
  }
  auto by_cluster = [](const Owned& a, const Owned& b) { return a.cluster != b.cluster ? a.cluster < b.cluster : a.elem < b.elem; };
  std::sort(edge_owner.begin(), edge_owner.end(), by_cluster);
  std::sort(tet_owner.begin(), tet_owner.end(), by_cluster);
  // Groups in cluster order; each group's slots: the rows its elements touch, ascending.
  std::vector<int> slot(static_cast<size_t>(rows_), -1);  // row → slot of the current group
  std::vector<int> rows_of;                               // the current group's rows
  std::vector<std::pair<int, int>> row_slot;              // (row, slot offset), group order
  size_t ie = 0, it = 0;
  int nslots = 0;
  for (int c = 0; c < clusters; ++c) {
    ElemGroup g{};
    g.e0 = static_cast<int>(edges_.size());
    g.t0 = static_cast<int>(tet_elems_.size());
    rows_of.clear();
    auto touch = [&](int row) {
      if (slot[row] < 0) slot[row] = 0, rows_of.push_back(row);
    };
    const size_t ie0 = ie, it0 = it;
    for (; ie < edge_owner.size() && edge_owner[ie].cluster == c; ++ie) {
      const EdgeElem& E = all_edges[edge_owner[ie].elem];
      touch(E.i), touch(E.j);
    }
    for (; it < tet_owner.size() && tet_owner[it].cluster == c; ++it)
      for (int k = 0; k < 4; ++k) touch(all_tets[tet_owner[it].elem].v[k]);
    std::sort(rows_of.begin(), rows_of.end());
    g.a0 = 3 * nslots;
    for (int row : rows_of) {
      slot[row] = 3 * nslots++;
      row_slot.push_back({row, slot[row]});
    }
    g.a1 = 3 * nslots;
    for (size_t q = ie0; q < ie; ++q) {
      EdgeElem E = all_edges[edge_owner[q].elem];
      E.si = slot[E.i], E.sj = slot[E.j];
      edges_.push_back(E);
    }
    for (size_t q = it0; q < it; ++q) {
      TetElem T = all_tets[tet_owner[q].elem];
      for (int k = 0; k < 4; ++k) T.s[k] = slot[T.v[k]];
      tet_elems_.push_back(T);
    }
    for (int row : rows_of) slot[row] = -1;
    g.e1 = static_cast<int>(edges_.size());
    g.t1 = static_cast<int>(tet_elems_.size());
    if (g.e1 > g.e0 || g.t1 > g.t0) groups_.push_back(g);
  }
  acc_.assign(3 * static_cast<size_t>(nslots), 0.0);
  // Per row, its slots in group order (counting sort of row_slot by row, stable).
  gather_start_.assign(static_cast<size_t>(rows_) + 1, 0);
  for (const auto& rs : row_slot) ++gather_start_[rs.first + 1];
  for (int r = 0; r < rows_; ++r) gather_start_[r + 1] += gather_start_[r];
  gather_.assign(row_slot.size(), 0);
  std::vector<int> fill(gather_start_.begin(), gather_start_.end() - 1);
  for (const auto& rs : row_slot) gather_[fill[rs.first]++] = rs.second;
}

void World::element_forces(const State& s) const {
  const double* x = s.x.data();
  const double* v = s.v.data();
  double* acc = acc_.data();
  auto add3 = [](double* a, const double* f) { a[0] += f[0], a[1] += f[1], a[2] += f[2]; };
  auto group = [&](const ElemGroup& G) {
    std::fill(acc + G.a0, acc + G.a1, 0.0);
    int e = G.e0;
#if defined(__SSE2__)
    for (; e + 1 < G.e1; e += 2) {  // edge e, then edge e + 1 (they may share a vertex)
      const EdgeElem &E0 = edges_[e], &E1 = edges_[e + 1];
      const simd::Pair3 fj = distance_forces_pair(x, v, E0, E1), fi = simd::neg(fj);
      simd::add_lane0(acc + E0.si, fi), simd::add_lane0(acc + E0.sj, fj);
      simd::add_lane1(acc + E1.si, fi), simd::add_lane1(acc + E1.sj, fj);
    }
#endif
    for (; e < G.e1; ++e) {
      const EdgeElem& E = edges_[e];
      Vec3 fi, fj;
      distance_forces(Vec3(x + 3 * E.i), Vec3(x + 3 * E.j), Vec3(v + 3 * E.i), Vec3(v + 3 * E.j), E.D0, E.k, E.kd, fi,
                      fj);
      add3(acc + E.si, fi.data()), add3(acc + E.sj, fj.data());
    }
    int t = G.t0;
#if defined(__SSE2__)
    for (; t + 1 < G.t1; t += 2) {  // tet t, then tet t + 1
      const TetElem &T0 = tet_elems_[t], &T1 = tet_elems_[t + 1];
      simd::Pair3 f[4];
      volume_forces_pair(x, v, T0, T1, f);
      for (int k = 0; k < 4; ++k) simd::add_lane0(acc + T0.s[k], f[k]);
      for (int k = 0; k < 4; ++k) simd::add_lane1(acc + T1.s[k], f[k]);
    }
#endif
    for (; t < G.t1; ++t) {
      const TetElem& T = tet_elems_[t];
      Vec3 p[4], vel[4], f[4];
      for (int k = 0; k < 4; ++k) {
        p[k] = Vec3(x + 3 * T.v[k]);
        vel[k] = Vec3(v + 3 * T.v[k]);
      }
      volume_forces(p, vel, T.V0, T.k, T.kd, f);
      for (int k = 0; k < 4; ++k) add3(acc + T.s[k], f[k].data());
    }
  };
  const int ng = static_cast<int>(groups_.size());
  // Small scenes (fewer than kSerialElements edges and tets) run on the calling thread.
  if (edges_.size() + tet_elems_.size() < kSerialElements) {
    for (const ElemGroup& G : groups_) group(G);
  } else {
    tbb::parallel_for(tbb::blocked_range<int>(0, ng, 1), [&](const tbb::blocked_range<int>& r) {
      for (int g = r.begin(); g != r.end(); ++g) group(groups_[g]);
    });
  }
}

Eigen::Vector3d World::gathered(int row) const {
  Vec3 f = Vec3::Zero();
  const double* src = acc_.data();
  for (int c = gather_start_[row]; c < gather_start_[row + 1]; ++c) f += Vec3(src + gather_[c]);
  return f;
}

void World::internal_forces(const State& s, RowMatrixX3d& F) const {
  if (s.x.rows() != rows_ || s.v.rows() != rows_)
    throw InputError("fem world: the state has " + std::to_string(s.x.rows()) + " rows, the world " +
                     std::to_string(rows_));
  if (!prepared_) const_cast<World*>(this)->prepare();
  F.resize(rows_, 3);
  element_forces(s);
  parallel_rows(rows_, [&](int i) { F.row(i) = gathered(i).transpose(); });
}

void World::collect_contact_forces(const State& s) {
  for (int r : contact_rows_) contact_head_[r] = contact_tail_[r] = -1;
  contact_rows_.clear();
  contact_next_.clear();
  contact_f_.clear();
  stats_ = StepStats{};
  if (!options_.collisions || bodies_.empty()) return;
  X_all_.topRows(rows_) = s.x;
  const std::vector<Contact> contacts = hash_->find(X_all_, T_all_, filter_);
  stats_.contacts = static_cast<int>(contacts.size());
  if (contacts.empty()) return;
  const std::vector<Penetration> pens = penetration_depths(scene_, X_all_, contacts);
  stats_.colliding_vertices = static_cast<int>(pens.size());
  auto velocity = [&](int g) -> Vec3 { return g < rows_ ? Vec3(s.v.row(g).transpose()) : Vec3::Zero(); };
  auto add = [&](int row, const Vec3& f) {  // appended: applied in the order found
    const int id = static_cast<int>(contact_f_.size());
    contact_f_.push_back(f);
    contact_next_.push_back(-1);
    if (contact_head_[row] < 0) {
      contact_head_[row] = id;
      contact_rows_.push_back(row);
    } else {
      contact_next_[contact_tail_[row]] = id;
    }
    contact_tail_[row] = id;
  };
  for (const Penetration& p : pens) {  // fixed order: sequential
    if (!(p.depth > 0)) continue;
    stats_.max_depth = std::max(stats_.max_depth, p.depth);
    Vec3 vt = Vec3::Zero();
    for (int k = 0; k < 4; ++k) vt += p.bary[k] * velocity(T_all_(p.tet, k));
    const Vec3& r = p.direction;
    const double closing = (velocity(p.vertex) - vt).dot(r);
    double kc, cc;  // of the penetrating vertex; a rigid one: interpolated from the tet's corners
    if (!options_.cap_contact_stiffness) {
      kc = options_.contact_stiffness;
      cc = options_.contact_damping;
    } else if (p.vertex < rows_) {
      kc = contact_k_(p.vertex);
      cc = contact_c_(p.vertex);
    } else {
      kc = cc = 0;
      for (int k = 0; k < 4; ++k) {
        const int g = T_all_(p.tet, k);
        if (g < rows_) kc += p.bary[k] * contact_k_(g), cc += p.bary[k] * contact_c_(g);
      }
    }
    const Vec3 f = (kc * p.depth - cc * closing) * r;
    if (p.vertex < rows_) {
      add(p.vertex, f);
    } else {  // rigid vertex inside a deformable tet: the reaction acts on the tet
      for (int k = 0; k < 4; ++k) {
        const int g = T_all_(p.tet, k);
        if (g < rows_) add(g, -(p.bary[k] * f));
      }
    }
  }
}

void World::add_contact_forces(const State& s, RowMatrixX3d& F) {
  collect_contact_forces(s);
  for (int r : contact_rows_)
    for (int id = contact_head_[r]; id >= 0; id = contact_next_[id]) F.row(r) += contact_f_[id].transpose();
}

void World::total_forces(const State& s, const RowMatrixX3d* external, RowMatrixX3d& F) {
  if (external && external->rows() != rows_)
    throw InputError("fem world: external forces have " + std::to_string(external->rows()) + " rows, the world " +
                     std::to_string(rows_));
  internal_forces(s, F);
  const Vec3 g = options_.gravity;
  const bool floor = options_.floor;
  const double fy = options_.floor_height;
  parallel_rows(rows_, [&](int i) {
    Vec3 f = F.row(i).transpose() + mass_(i) * g;
    if (external) f += external->row(i).transpose();
    if (floor && s.x(i, 1) < fy) f.y() += contact_k_(i) * (fy - s.x(i, 1)) - contact_c_(i) * std::min(0.0, s.v(i, 1));
    F.row(i) = f.transpose();
  });
  add_contact_forces(s, F);
}

void World::step(State& s, const RowMatrixX3d* external) {
  // Same forces, same summation order as total_forces() followed by the Verlet update, fused:
  // contacts first (they read the state only), then the element pass, then one pass per row
  // that gathers, adds gravity, external, floor and contact forces, and integrates.
  if (external && external->rows() != rows_)
    throw InputError("fem world: external forces have " + std::to_string(external->rows()) + " rows, the world " +
                     std::to_string(rows_));
  if (s.x.rows() != rows_ || s.v.rows() != rows_)
    throw InputError("fem world: the state has " + std::to_string(s.x.rows()) + " rows, the world " +
                     std::to_string(rows_));
  if (!prepared_) prepare();
  damp_deformation(s);
  // Collision detection and response (partly sequential: the hash's counting sort, the
  // penetration depths) run alongside the element pass; both read the state only and write
  // disjoint data, so the results do not depend on the threads.
  tbb::parallel_invoke([&] { collect_contact_forces(s); }, [&] { element_forces(s); });
  const Vec3 g = options_.gravity;
  const bool floor = options_.floor;
  const double fy = options_.floor_height;
  const double h = options_.h;
  parallel_rows(rows_, [&](int i) {
    if (pinned_[i]) {
      s.v.row(i).setZero();
      return;
    }
    Vec3 f = gathered(i) + mass_(i) * g;
    if (external) f += external->row(i).transpose();
    if (floor && s.x(i, 1) < fy) f.y() += contact_k_(i) * (fy - s.x(i, 1)) - contact_c_(i) * std::min(0.0, s.v(i, 1));
    for (int id = contact_head_[i]; id >= 0; id = contact_next_[id]) f += contact_f_[id];
    s.v.row(i) += (h * inv_mass_(i)) * f.transpose();
    s.x.row(i) += h * s.v.row(i);
  });
  s.time += h;
}

void World::damp_deformation(State& s) const {
  for (int b = 0; b < bodies(); ++b) {
    const Body& B = bodies_[b];
    const int r0 = state_row_[b];
    const double alpha = B.material.deformation_damping;
    if (r0 < 0 || !(alpha > 0)) continue;
    const int n = B.vertices();
    // Rigid motion with the momentum of the object (sequential: fixed summation order). A pinned
    // object is anchored: its reference motion is rest (v_rigid = 0).
    bool anchored = false;
    for (int i = r0; i < r0 + n && !anchored; ++i) anchored = pinned_[i] != 0;
    Vec3 c = Vec3::Zero(), vcm = Vec3::Zero(), w = Vec3::Zero();
    if (!anchored) {
      double M = 0;
      Vec3 mx = Vec3::Zero(), mv = Vec3::Zero();
      for (int i = r0; i < r0 + n; ++i) {
        M += mass_(i);
        mx += mass_(i) * Vec3(s.x.row(i).transpose());
        mv += mass_(i) * Vec3(s.v.row(i).transpose());
      }
      if (!(M > 0)) continue;
      c = mx / M;
      vcm = mv / M;
      Vec3 L = Vec3::Zero();
      Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
      for (int i = r0; i < r0 + n; ++i) {
        const Vec3 r = Vec3(s.x.row(i).transpose()) - c;
        L += mass_(i) * r.cross(Vec3(s.v.row(i).transpose()) - vcm);
        I += mass_(i) * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      }
      const Eigen::FullPivLU<Eigen::Matrix3d> lu(I);
      if (lu.isInvertible()) w = lu.solve(L);
    }
    const double keep = std::exp(-alpha * options_.h);
    for (int i = r0; i < r0 + n; ++i) {
      if (pinned_[i]) continue;
      const Vec3 vr = vcm + w.cross(Vec3(s.x.row(i).transpose()) - c);
      s.v.row(i) = (vr + keep * (Vec3(s.v.row(i).transpose()) - vr)).transpose();
    }
  }
}

double World::elastic_energy(const State& s) const {
  double e = 0;
  for (int b = 0; b < bodies(); ++b) {
    const int r0 = state_row_[b];
    if (r0 < 0) continue;
    const Body& B = bodies_[b];
    for (int k = 0; k < B.E.rows(); ++k)
      e += distance_energy(s.x.row(r0 + B.E(k, 0)).transpose(), s.x.row(r0 + B.E(k, 1)).transpose(), B.D0(k),
                           B.k_edge(k));
    for (int t = 0; t < B.tets(); ++t)
      e += volume_energy(s.x.row(r0 + B.T(t, 0)).transpose(), s.x.row(r0 + B.T(t, 1)).transpose(),
                         s.x.row(r0 + B.T(t, 2)).transpose(), s.x.row(r0 + B.T(t, 3)).transpose(), B.V0(t),
                         B.k_tet(t));
  }
  return e;
}

double World::kinetic_energy(const State& s) const {
  double e = 0;
  for (int i = 0; i < rows_; ++i) e += 0.5 * mass_(i) * s.v.row(i).squaredNorm();
  return e;
}

double World::gravity_energy(const State& s) const {
  double e = 0;
  for (int i = 0; i < rows_; ++i) e -= mass_(i) * s.x.row(i).dot(options_.gravity.transpose());
  return e;
}

double World::body_volume(const State& s, int b) const {
  if (state_row_[b] < 0) return bodies_[b].total_volume();
  return volume(bodies_[b], s.x.middleRows(state_row_[b], bodies_[b].vertices()));
}

}  // namespace squeeze::fem
