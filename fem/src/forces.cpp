#include "squeeze/fem/forces.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "squeeze/common/error.h"
#include "squeeze/fem/collision.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/world.h"
#include "world_data.h"

namespace squeeze::fem {

struct ForceWorkspace::Impl {
  std::uint64_t version = 0;  // of the WorldData the buffers are sized for
  std::vector<double> acc;    // the element groups' accumulator slots, 3 doubles each
  RowMatrixX3d X_all;         // positions in the collision numbering
  std::unique_ptr<SpatialHash> hash;
  // Contact forces of the evaluation, applied in the order found: per row a singly linked list.
  std::vector<int> contact_head, contact_tail;  // per state row, −1: none
  std::vector<int> contact_next;
  std::vector<Vec3> contact_f;
  std::vector<int> contact_rows;  // rows with a list (to reset them)
  StepStats stats;
  Eigen::VectorXd overlap;    // the rest-overlap tolerances after the last evaluation (State::overlap)
  // find_penetrations' last call: its input (the state's positions, the tolerances it used) and
  // output. Detection is a function of them (and of the world, version), and the implicit
  // integrator asks again at the same state: its last contact round of a substep and the first
  // detection of the next one both detect at the substep's result (the ball of bench_integrators,
  // 1 s: 37 of 108 detections, 40.7 M → 21.1 M instructions, callgrind).
  bool last_valid = false;
  RowMatrixX3d last_x;
  Eigen::VectorXd last_allowance, last_overlap;
  std::vector<Penetration> last_pens;
  StepStats last_stats;

  void fit(const WorldData& d) {
    if (version == d.version) return;
    acc.assign(3 * static_cast<size_t>(d.slots), 0.0);
    X_all = d.X_rest_all;
    contact_head.assign(static_cast<size_t>(d.rows), -1);
    contact_tail.assign(static_cast<size_t>(d.rows), -1);
    contact_rows.clear();
    if (!hash || hash->cell() != d.cell || hash->table_size() != d.table) hash = std::make_unique<SpatialHash>(d.cell, d.table);
    last_valid = false;
    version = d.version;
  }
};

ForceWorkspace::ForceWorkspace() : impl_(std::make_unique<Impl>()) {}
ForceWorkspace::~ForceWorkspace() = default;
ForceWorkspace::ForceWorkspace(const ForceWorkspace&) : impl_(std::make_unique<Impl>()) {}
ForceWorkspace& ForceWorkspace::operator=(const ForceWorkspace&) {
  impl_ = std::make_unique<Impl>();
  return *this;
}
ForceWorkspace::ForceWorkspace(ForceWorkspace&&) noexcept = default;
ForceWorkspace& ForceWorkspace::operator=(ForceWorkspace&&) noexcept = default;
const StepStats& ForceWorkspace::stats() const { return impl_->stats; }
const Eigen::VectorXd& ForceWorkspace::overlap() const { return impl_->overlap; }

namespace {

template <class Fn>
void parallel_rows(int n, Fn fn) {
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 512), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) fn(i);
  });
}

void check_rows(const WorldData& d, const State& s, const RowMatrixX3d* external) {
  if (s.x.rows() != d.rows || s.v.rows() != d.rows)
    throw InputError("fem world: the state has " + std::to_string(s.x.rows()) + " rows, the world " +
                     std::to_string(d.rows));
  if (external && external->rows() != d.rows)
    throw InputError("fem world: external forces have " + std::to_string(external->rows()) + " rows, the world " +
                     std::to_string(d.rows));
}

// The element pass: every group adds its elements' forces into its own accumulator slots
// (parallel over groups; fixed orders within a group).
void element_forces(const WorldData& d, const World& w, const State& s, std::vector<double>& acc_v) {
  const double* x = s.x.data();
  const double* v = s.v.data();
  double* acc = acc_v.data();
  auto add3 = [](double* a, const double* f) { a[0] += f[0], a[1] += f[1], a[2] += f[2]; };
  auto group = [&](const WorldData::ElemGroup& G) {
    std::fill(acc + G.a0, acc + G.a1, 0.0);
    int e = G.e0;
#if defined(__SSE2__)
    for (; e + 1 < G.e1; e += 2) {  // edge e, then edge e + 1 (they may share a vertex)
      const WorldData::EdgeElem &E0 = d.edges[e], &E1 = d.edges[e + 1];
      const simd::Pair3 fj = distance_forces_pair(x, v, E0, E1), fi = simd::neg(fj);
      simd::add_lane0(acc + E0.si, fi), simd::add_lane0(acc + E0.sj, fj);
      simd::add_lane1(acc + E1.si, fi), simd::add_lane1(acc + E1.sj, fj);
    }
#endif
    for (; e < G.e1; ++e) {
      const WorldData::EdgeElem& E = d.edges[e];
      Vec3 fi, fj;
      distance_forces(Vec3(x + 3 * E.i), Vec3(x + 3 * E.j), Vec3(v + 3 * E.i), Vec3(v + 3 * E.j), E.D0, E.k, E.kd, fi,
                      fj);
      add3(acc + E.si, fi.data()), add3(acc + E.sj, fj.data());
    }
    int t = G.t0;
#if defined(__SSE2__)
    for (; t + 1 < G.t1; t += 2) {  // tet t, then tet t + 1
      const WorldData::TetElem &T0 = d.tet_elems[t], &T1 = d.tet_elems[t + 1];
      simd::Pair3 f[4];
      volume_forces_pair(x, v, T0, T1, f);
      for (int k = 0; k < 4; ++k) simd::add_lane0(acc + T0.s[k], f[k]);
      for (int k = 0; k < 4; ++k) simd::add_lane1(acc + T1.s[k], f[k]);
    }
#endif
    for (; t < G.t1; ++t) {
      const WorldData::TetElem& T = d.tet_elems[t];
      Vec3 p[4], vel[4], f[4];
      for (int k = 0; k < 4; ++k) {
        p[k] = Vec3(x + 3 * T.v[k]);
        vel[k] = Vec3(v + 3 * T.v[k]);
      }
      volume_forces(p, vel, T.V0, T.k, T.kd, f);
      for (int k = 0; k < 4; ++k) add3(acc + T.s[k], f[k].data());
    }
  };
  const int ng = static_cast<int>(d.groups.size());
  // Small scenes (fewer edges and tets than the threshold) run on the calling thread.
  if (d.edges.size() + d.tet_elems.size() < static_cast<size_t>(w.options().parallel.elements)) {
    for (const WorldData::ElemGroup& G : d.groups) group(G);
  } else {
    tbb::parallel_for(tbb::blocked_range<int>(0, ng, 1), [&](const tbb::blocked_range<int>& r) {
      for (int g = r.begin(); g != r.end(); ++g) group(d.groups[g]);
    });
  }
}

// Σ of a row's slots, fixed order.
inline Vec3 gathered(const WorldData& d, const std::vector<double>& acc, int row) {
  Vec3 f = Vec3::Zero();
  const double* src = acc.data();
  for (int c = d.gather_start[row]; c < d.gather_start[row + 1]; ++c) f += Vec3(src + d.gather[c]);
  return f;
}

// The rest-overlap tolerances of state s: its own, or the rest depths for a state made before the
// world was prepared (World::initial_state then had none to give).
const Eigen::VectorXd& current_overlap(const WorldData& d, const State& s) {
  return s.overlap.size() == d.overlap_depths.size() ? s.overlap : d.overlap_depths;
}

// Depths beyond each overlapping vertex's tolerance; `next` receives the shrunk tolerances
// (min(tolerance, depth) for a vertex still inside, 0 for one that is out).
void apply_overlap(const WorldData& d, const Eigen::VectorXd& allowance, std::vector<Penetration>& pens,
                   Eigen::VectorXd& next) {
  next.setZero(allowance.size());
  if (allowance.size() == 0) return;
  for (Penetration& p : pens) {
    const int slot = d.overlap_slot[p.vertex];
    if (slot < 0 || !(p.depth > 0)) continue;
    const double a = allowance(slot);
    next(slot) = std::min(a, p.depth);
    p.depth = std::max(0.0, p.depth - a);
  }
}

// Collision detection and the contact penalty forces of state s, into the workspace's lists.
void collect_contact_forces(const WorldData& d, const World& w, const State& s, ForceWorkspace::Impl& ws,
                            bool with_forces) {
  for (int r : ws.contact_rows) ws.contact_head[r] = ws.contact_tail[r] = -1;
  ws.contact_rows.clear();
  ws.contact_next.clear();
  ws.contact_f.clear();
  ws.stats = StepStats{};
  const WorldOptions& o = w.options();
  // Rest overlaps: the tolerance of each overlapping vertex, shrunk below to its current depth.
  const Eigen::VectorXd& allowance = current_overlap(d, s);
  ws.overlap.setZero(allowance.size());
  if (!o.collisions || d.bodies.empty()) return;
  d.collision_positions(s.x, ws.X_all);
  const std::vector<Contact> contacts = ws.hash->find(ws.X_all, d.T_all, d.filter, o.parallel.detection_tets);
  ws.stats.contacts = static_cast<int>(contacts.size());
  if (contacts.empty()) return;
  std::vector<Penetration> pens = penetration_depths(d.scene, ws.X_all, contacts, o.parallel.border_vertices);
  apply_overlap(d, allowance, pens, ws.overlap);
  ws.stats.colliding_vertices = static_cast<int>(pens.size());
  // A collision vertex follows the state rows coll_row[a, b) with the weights coll_w (one row of
  // weight 1 for a vertex of the simulation mesh itself, none for a rigid one; embed).
  auto velocity = [&](int g) -> Vec3 { return d.followed(g) ? d.follow(g, s.v) : Vec3::Zero(); };
  auto add = [&](int row, const Vec3& f) {  // appended: applied in the order found
    const int id = static_cast<int>(ws.contact_f.size());
    ws.contact_f.push_back(f);
    ws.contact_next.push_back(-1);
    if (ws.contact_head[row] < 0) {
      ws.contact_head[row] = id;
      ws.contact_rows.push_back(row);
    } else {
      ws.contact_next[ws.contact_tail[row]] = id;
    }
    ws.contact_tail[row] = id;
  };
  // f at collision vertex g, times `scale`, onto its rows by their weights (a single row of
  // weight 1 gets scale · f exactly).
  auto spread = [&](int g, double scale, const Vec3& f) {
    for (int c = d.coll_start[g]; c < d.coll_start[g + 1]; ++c) add(d.coll_row[c], (scale * d.coll_w[c]) * f);
  };
  for (const Penetration& p : pens) {  // fixed order: sequential
    if (!(p.depth > 0)) continue;
    ws.stats.max_depth = std::max(ws.stats.max_depth, p.depth);
    if (!with_forces) continue;
    Vec3 vt = Vec3::Zero();
    for (int k = 0; k < 4; ++k) vt += p.bary[k] * velocity(d.T_all(p.tet, k));
    const Vec3& r = p.direction;
    const double closing = (velocity(p.vertex) - vt).dot(r);
    double kc, cc;  // of the penetrating vertex; a rigid one: interpolated from the tet's corners
    if (!o.cap_contact_stiffness) {
      kc = o.contact_stiffness;
      cc = o.contact_damping;
    } else if (d.followed(p.vertex)) {
      kc = d.contact_coefficient(p.vertex, d.contact_k);
      cc = d.contact_coefficient(p.vertex, d.contact_c);
    } else {
      kc = cc = 0;
      for (int k = 0; k < 4; ++k) {
        const int g = d.T_all(p.tet, k);
        if (d.followed(g))
          kc += p.bary[k] * d.contact_coefficient(g, d.contact_k), cc += p.bary[k] * d.contact_coefficient(g, d.contact_c);
      }
    }
    const Vec3 f = (kc * p.depth - cc * closing) * r;
    if (d.followed(p.vertex)) {
      spread(p.vertex, 1.0, f);
    } else {  // rigid vertex inside a deformable tet: the reaction acts on the tet
      for (int k = 0; k < 4; ++k) spread(d.T_all(p.tet, k), -p.bary[k], f);  // (none for a rigid corner)
    }
  }
}

}  // namespace

void assemble_forces(const World& w, const State& s, const RowMatrixX3d* external, ForceWorkspace& workspace,
                     RowMatrixX3d& F, const ForceTerms& terms) {
  const WorldData& d = w.data();
  check_rows(d, s, external);
  ForceWorkspace::Impl& ws = workspace.impl();
  ws.fit(d);
  // Collision detection and response (partly sequential: the hash's counting sort, the
  // penetration depths) run alongside the element pass; both read the state only and write
  // disjoint data, so the results do not depend on the threads.
  if (terms.contacts && terms.internal)
    tbb::parallel_invoke([&] { collect_contact_forces(d, w, s, ws, true); }, [&] { element_forces(d, w, s, ws.acc); });
  else if (terms.contacts)
    collect_contact_forces(d, w, s, ws, true);
  else if (terms.internal)
    element_forces(d, w, s, ws.acc);
  const WorldOptions& o = w.options();
  const Vec3 g = o.gravity;
  const bool gravity = terms.gravity;
  const bool cancel = terms.gravity && d.any_gravity_off;  // objects whose gravity is off
  const RowMatrixX3d* ext = terms.external ? external : nullptr;
  const bool floor = terms.floor && o.floor;
  const double fy = o.floor_height;
  const bool contacts = terms.contacts;
  const bool attached = terms.attachments && d.any_attached;
  F.resize(d.rows, 3);
  parallel_rows(d.rows, [&](int i) {
    Vec3 f = terms.internal ? gathered(d, ws.acc, i) : Vec3::Zero();
    if (gravity) f += d.mass(i) * g;
    if (cancel || ext) {
      Vec3 e = (cancel && d.gravity_off[i]) ? Vec3(-d.mass(i) * g) : Vec3::Zero();
      if (ext) e += ext->row(i).transpose();
      f += e;
    }
    if (floor && s.x(i, 1) < fy && d.floor_row[i])
      f.y() += d.contact_k(i) * (fy - s.x(i, 1)) - d.contact_c(i) * std::min(0.0, s.v(i, 1));
    if (attached && (d.attach_k(i) > 0 || d.attach_c(i) > 0))  // zero-length spring to the rest position
      f -= d.attach_k(i) * (Vec3(s.x.row(i).transpose()) - Vec3(d.attach_anchor.row(i).transpose())) +
           d.attach_c(i) * Vec3(s.v.row(i).transpose());
    if (contacts)
      for (int id = ws.contact_head[i]; id >= 0; id = ws.contact_next[id]) f += ws.contact_f[id];
    F.row(i) = f.transpose();
  });
  // The floor under embedded meshes: it holds their vertices (the same penalty, with their share
  // of their rows' coefficients), and their rows by the weights they follow them with.
  if (floor && d.any_embedded)
    for (int g : d.embedded_vertices) {
      const double y = d.follow(g, s.x).y();
      if (!(y < fy)) continue;
      const double vy = d.follow(g, s.v).y();
      const double f = d.contact_coefficient(g, d.contact_k) * (fy - y) - d.contact_coefficient(g, d.contact_c) * std::min(0.0, vy);
      for (int q = d.coll_start[g]; q < d.coll_start[g + 1]; ++q) F(d.coll_row[q], 1) += d.coll_w[q] * f;
    }
}

std::vector<Penetration> find_penetrations(const World& w, const State& s, ForceWorkspace& workspace) {
  const WorldData& d = w.data();
  check_rows(d, s, nullptr);
  ForceWorkspace::Impl& ws = workspace.impl();
  ws.fit(d);
  const Eigen::VectorXd& allowance = current_overlap(d, s);
  auto same = [](const auto& a, const auto& b) {
    return a.size() == b.size() && std::equal(a.data(), a.data() + a.size(), b.data(), [](double u, double v) {
             return std::memcmp(&u, &v, sizeof(double)) == 0;  // bit for bit (NaN, −0)
           });
  };
  if (ws.last_valid && same(ws.last_x, s.x) && same(ws.last_allowance, allowance)) {
    ws.stats = ws.last_stats;
    ws.overlap = ws.last_overlap;
    return ws.last_pens;
  }
  ws.stats = StepStats{};
  ws.overlap.setZero(allowance.size());  // out of every other object: no tolerance left
  const WorldOptions& o = w.options();
  std::vector<Penetration> out;
  if (o.collisions && !d.bodies.empty()) {
    d.collision_positions(s.x, ws.X_all);
    const std::vector<Contact> contacts = ws.hash->find(ws.X_all, d.T_all, d.filter, o.parallel.detection_tets);
    ws.stats.contacts = static_cast<int>(contacts.size());
    if (!contacts.empty()) {
      std::vector<Penetration> pens = penetration_depths(d.scene, ws.X_all, contacts, o.parallel.border_vertices);
      apply_overlap(d, allowance, pens, ws.overlap);
      ws.stats.colliding_vertices = static_cast<int>(pens.size());
      for (Penetration& p : pens)
        if (p.depth > 0) {
          ws.stats.max_depth = std::max(ws.stats.max_depth, p.depth);
          out.push_back(std::move(p));
        }
    }
  }
  ws.last_x = s.x;
  ws.last_allowance = allowance;
  ws.last_overlap = ws.overlap;
  ws.last_pens = out;
  ws.last_stats = ws.stats;
  ws.last_valid = true;
  return out;
}

int collision_vertex_body(const World& w, int g) {
  const WorldData& d = w.data();
  if (g < 0 || g >= static_cast<int>(d.filter.vertex_group.size())) return -1;
  return d.group_body[static_cast<size_t>(d.filter.vertex_group[g])];
}

int collision_tet_body(const World& w, int tet) {
  const WorldData& d = w.data();
  if (tet < 0 || tet >= static_cast<int>(d.filter.tet_group.size())) return -1;
  return d.group_body[static_cast<size_t>(d.filter.tet_group[tet])];
}

Eigen::Vector4i collision_tet(const World& w, int tet) { return w.data().T_all.row(tet).transpose(); }

Eigen::Vector3d collision_vertex_position(const World& w, const State& s, int g) {
  const WorldData& d = w.data();
  return d.followed(g) ? d.follow(g, s.x) : Eigen::Vector3d(d.X_rest_all.row(g).transpose());  // rigid: at rest
}

void detect_contacts(const World& w, const State& s, ForceWorkspace& workspace) {
  const WorldData& d = w.data();
  check_rows(d, s, nullptr);
  ForceWorkspace::Impl& ws = workspace.impl();
  ws.fit(d);
  collect_contact_forces(d, w, s, ws, false);
}

}  // namespace squeeze::fem
