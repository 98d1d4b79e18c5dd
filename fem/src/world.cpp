#include "squeeze/fem/world.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

template <class Fn>
void parallel_rows(int n, Fn fn) {
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 64), [&](const tbb::blocked_range<int>& r) {
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
  if (body.rigid) {
    state_row_.push_back(-1);
  } else {
    state_row_.push_back(rows_);
    const int n = body.vertices();
    mass_.conservativeResize(rows_ + n);
    mass_.segment(rows_, n) = body.mass;
    pinned_.resize(static_cast<size_t>(rows_ + n), 0);
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
  // Per-element force scratch.
  edge_row0_.assign(bodies_.size(), 0);
  tet_row0_.assign(bodies_.size(), 0);
  int ne = 0, nt = 0;
  for (int b = 0; b < bodies(); ++b) {
    if (state_row_[b] < 0) continue;
    edge_row0_[b] = ne;
    tet_row0_[b] = nt;
    ne += 2 * static_cast<int>(bodies_[b].E.rows());
    nt += 4 * bodies_[b].tets();
  }
  edge_f_.resize(ne, 3);
  tet_f_.resize(nt, 3);
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

void World::internal_forces(const State& s, RowMatrixX3d& F) const {
  if (s.x.rows() != rows_ || s.v.rows() != rows_)
    throw InputError("fem world: the state has " + std::to_string(s.x.rows()) + " rows, the world " +
                     std::to_string(rows_));
  if (!prepared_) const_cast<World*>(this)->prepare();
  F.resize(rows_, 3);
  for (int b = 0; b < bodies(); ++b) {
    const int r0 = state_row_[b];
    if (r0 < 0) continue;
    const Body& B = bodies_[b];
    const Material& m = B.material;
    const int e0 = edge_row0_[b], t0 = tet_row0_[b];
    parallel_rows(static_cast<int>(B.E.rows()), [&](int e) {
      const int i = r0 + B.E(e, 0), j = r0 + B.E(e, 1);
      Vec3 fi, fj;
      distance_forces(s.x.row(i).transpose(), s.x.row(j).transpose(), s.v.row(i).transpose(), s.v.row(j).transpose(),
                      B.D0(e), m.k_distance, m.damping_distance, fi, fj);
      edge_f_.row(e0 + 2 * e) = fi.transpose();
      edge_f_.row(e0 + 2 * e + 1) = fj.transpose();
    });
    parallel_rows(B.tets(), [&](int t) {
      Vec3 p[4], v[4], f[4];
      for (int k = 0; k < 4; ++k) {
        p[k] = s.x.row(r0 + B.T(t, k)).transpose();
        v[k] = s.v.row(r0 + B.T(t, k)).transpose();
      }
      volume_forces(p, v, B.V0(t), m.k_volume, m.damping_volume, f);
      for (int k = 0; k < 4; ++k) tet_f_.row(t0 + 4 * t + k) = f[k].transpose();
    });
    parallel_rows(B.vertices(), [&](int i) {
      Vec3 f = Vec3::Zero();
      for (int c = B.edge_start[i]; c < B.edge_start[i + 1]; ++c) f += edge_f_.row(e0 + B.edge_code[c]).transpose();
      for (int c = B.tet_start[i]; c < B.tet_start[i + 1]; ++c) f += tet_f_.row(t0 + B.tet_code[c]).transpose();
      F.row(r0 + i) = f.transpose();
    });
  }
}

void World::add_contact_forces(const State& s, RowMatrixX3d& F) {
  stats_ = StepStats{};
  if (!options_.collisions || bodies_.empty()) return;
  X_all_.topRows(rows_) = s.x;
  const std::vector<Contact> contacts = hash_->find(X_all_, T_all_, filter_);
  stats_.contacts = static_cast<int>(contacts.size());
  if (contacts.empty()) return;
  const std::vector<Penetration> pens = penetration_depths(scene_, X_all_, contacts);
  stats_.colliding_vertices = static_cast<int>(pens.size());
  const double kc = options_.contact_stiffness, cc = options_.contact_damping;
  auto velocity = [&](int g) -> Vec3 { return g < rows_ ? Vec3(s.v.row(g).transpose()) : Vec3::Zero(); };
  for (const Penetration& p : pens) {  // fixed order: sequential
    if (!(p.depth > 0)) continue;
    stats_.max_depth = std::max(stats_.max_depth, p.depth);
    Vec3 vt = Vec3::Zero();
    for (int k = 0; k < 4; ++k) vt += p.bary[k] * velocity(T_all_(p.tet, k));
    const Vec3& r = p.direction;
    const double closing = (velocity(p.vertex) - vt).dot(r);
    const Vec3 f = (kc * p.depth - cc * closing) * r;
    if (p.vertex < rows_) {
      F.row(p.vertex) += f.transpose();
    } else {  // rigid vertex inside a deformable tet: the reaction acts on the tet
      for (int k = 0; k < 4; ++k) {
        const int g = T_all_(p.tet, k);
        if (g < rows_) F.row(g) -= (p.bary[k] * f).transpose();
      }
    }
  }
}

void World::total_forces(const State& s, const RowMatrixX3d* external, RowMatrixX3d& F) {
  if (external && external->rows() != rows_)
    throw InputError("fem world: external forces have " + std::to_string(external->rows()) + " rows, the world " +
                     std::to_string(rows_));
  internal_forces(s, F);
  const Vec3 g = options_.gravity;
  const bool floor = options_.floor;
  const double fy = options_.floor_height, kc = options_.contact_stiffness, cc = options_.contact_damping;
  parallel_rows(rows_, [&](int i) {
    Vec3 f = F.row(i).transpose() + mass_(i) * g;
    if (external) f += external->row(i).transpose();
    if (floor && s.x(i, 1) < fy) f.y() += kc * (fy - s.x(i, 1)) - cc * std::min(0.0, s.v(i, 1));
    F.row(i) = f.transpose();
  });
  add_contact_forces(s, F);
}

void World::step(State& s, const RowMatrixX3d* external) {
  total_forces(s, external, force_);
  const double h = options_.h;
  parallel_rows(rows_, [&](int i) {
    if (pinned_[i]) {
      s.v.row(i).setZero();
      return;
    }
    s.v.row(i) += (h * inv_mass_(i)) * force_.row(i);
    s.x.row(i) += h * s.v.row(i);
  });
  s.time += h;
}

double World::elastic_energy(const State& s) const {
  double e = 0;
  for (int b = 0; b < bodies(); ++b) {
    const int r0 = state_row_[b];
    if (r0 < 0) continue;
    const Body& B = bodies_[b];
    for (int k = 0; k < B.E.rows(); ++k)
      e += distance_energy(s.x.row(r0 + B.E(k, 0)).transpose(), s.x.row(r0 + B.E(k, 1)).transpose(), B.D0(k),
                           B.material.k_distance);
    for (int t = 0; t < B.tets(); ++t)
      e += volume_energy(s.x.row(r0 + B.T(t, 0)).transpose(), s.x.row(r0 + B.T(t, 1)).transpose(),
                         s.x.row(r0 + B.T(t, 2)).transpose(), s.x.row(r0 + B.T(t, 3)).transpose(), B.V0(t),
                         B.material.k_volume);
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
