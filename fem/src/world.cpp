#include "squeeze/fem/world.h"

#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "squeeze/common/error.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/integrator.h"
#include "squeeze/ffd/ffd.h"
#include "world_data.h"

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

constexpr int kClusterRows = 128;  // vertices per cluster of an element group

std::atomic<std::uint64_t> g_version{0};

void check_options(const WorldOptions& options) {
  if (!(options.h > 0) || !std::isfinite(options.h)) throw InputError("fem world: time step h must be > 0");
  if (options.contact_stiffness < 0 || options.contact_damping < 0)
    throw InputError("fem world: contact stiffness and damping must be >= 0");
  if (!options.gravity.allFinite()) throw InputError("fem world: gravity must be finite");
  if (options.cell_size < 0 || options.table_size < 0)
    throw InputError("fem world: cell_size and table_size must be >= 0 (0: automatic)");
  const ParallelThresholds& p = options.parallel;
  if (p.elements < 0 || p.detection_tets < 0 || p.border_vertices < 0 || p.assembly_tets < 0)
    throw InputError("fem world: parallel thresholds must be >= 0");
}

// Elements of all deformable objects in groups (WorldData::groups): per deformable object, its
// vertices in the Morton order of their rest positions (10 bits per axis in the object's bounding
// box), kClusterRows at a time.
void build_element_groups(WorldData& d) {
  const int rows = d.rows;
  d.edges.clear();
  d.tet_elems.clear();
  d.groups.clear();
  std::vector<int> rank(static_cast<size_t>(rows), 0);  // position of a row in its object's Morton order
  struct Owned { int cluster, elem; };
  std::vector<Owned> edge_owner, tet_owner;
  std::vector<WorldData::EdgeElem> all_edges;
  std::vector<WorldData::TetElem> all_tets;
  int clusters = 0;
  for (size_t b = 0; b < d.bodies.size(); ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0) continue;
    const Body& B = d.bodies[b];
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
  std::vector<int> slot(static_cast<size_t>(rows), -1);  // row → slot of the current group
  std::vector<int> rows_of;                              // the current group's rows
  std::vector<std::pair<int, int>> row_slot;             // (row, slot offset), group order
  size_t ie = 0, it = 0;
  int nslots = 0;
  for (int c = 0; c < clusters; ++c) {
    WorldData::ElemGroup g{};
    g.e0 = static_cast<int>(d.edges.size());
    g.t0 = static_cast<int>(d.tet_elems.size());
    rows_of.clear();
    auto touch = [&](int row) {
      if (slot[row] < 0) slot[row] = 0, rows_of.push_back(row);
    };
    const size_t ie0 = ie, it0 = it;
    for (; ie < edge_owner.size() && edge_owner[ie].cluster == c; ++ie) {
      const WorldData::EdgeElem& E = all_edges[edge_owner[ie].elem];
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
      WorldData::EdgeElem E = all_edges[edge_owner[q].elem];
      E.si = slot[E.i], E.sj = slot[E.j];
      d.edges.push_back(E);
    }
    for (size_t q = it0; q < it; ++q) {
      WorldData::TetElem T = all_tets[tet_owner[q].elem];
      for (int k = 0; k < 4; ++k) T.s[k] = slot[T.v[k]];
      d.tet_elems.push_back(T);
    }
    for (int row : rows_of) slot[row] = -1;
    g.e1 = static_cast<int>(d.edges.size());
    g.t1 = static_cast<int>(d.tet_elems.size());
    if (g.e1 > g.e0 || g.t1 > g.t0) d.groups.push_back(g);
  }
  d.slots = nslots;
  // Per row, its slots in group order (counting sort of row_slot by row, stable).
  d.gather_start.assign(static_cast<size_t>(rows) + 1, 0);
  for (const auto& rs : row_slot) ++d.gather_start[rs.first + 1];
  for (int r = 0; r < rows; ++r) d.gather_start[r + 1] += d.gather_start[r];
  d.gather.assign(row_slot.size(), 0);
  std::vector<int> fill(d.gather_start.begin(), d.gather_start.end() - 1);
  for (const auto& rs : row_slot) d.gather[fill[rs.first]++] = rs.second;
}

}  // namespace

WorldData::WorldData(const WorldData& o)
    : bodies(o.bodies),
      state_row(o.state_row),
      rows(o.rows),
      mass(o.mass),
      contact_scale(o.contact_scale),
      pinned(o.pinned),
      attach_k(o.attach_k),
      attach_c(o.attach_c),
      attach_weight(o.attach_weight),
      embedding(o.embedding),
      embedded(o.embedded) {}

World::World(const WorldOptions& options)
    : options_(options), data_(std::make_shared<WorldData>()), integrator_(make_integrator(options.integrator)) {
  check_options(options);
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

World::World(const World& o) : options_(o.options_), data_(o.data_), integrator_(o.integrator_->clone()) {}

World& World::operator=(const World& o) {
  if (this != &o) {
    options_ = o.options_;
    data_ = o.data_;
    integrator_ = o.integrator_->clone();
    workspace_ = ForceWorkspace();
  }
  return *this;
}

WorldData& World::mutable_data() {
  if (data_.use_count() > 1) data_ = std::make_shared<WorldData>(*data_);  // unshare: copies are unaffected
  data_->prepared = false;
  return *data_;
}

const WorldData& World::data() const {
  if (!data_->prepared) throw std::logic_error("fem world: prepare() the world before evaluating forces");
  return *data_;
}

void World::set_time_step(double h) {
  if (!(h > 0) || !std::isfinite(h)) throw InputError("fem world: time step h must be > 0");
  options_.h = h;
}

void World::set_integrator(std::unique_ptr<TimeIntegrator> integrator) {
  if (!integrator) throw std::invalid_argument("World::set_integrator: null integrator");
  options_.integrator = integrator->name();
  integrator_ = std::move(integrator);
}

int World::add_body(Body body) {
  WorldData& d = mutable_data();
  const int b = static_cast<int>(d.bodies.size());
  body.set_material(body.material);  // coefficients and masses follow the material as assigned
  if (body.rigid) {
    d.state_row.push_back(-1);
  } else {
    const int rows = d.rows;
    d.state_row.push_back(rows);
    const int n = body.vertices();
    d.mass.conservativeResize(rows + n);
    d.mass.segment(rows, n) = body.mass;
    d.pinned.resize(static_cast<size_t>(rows + n), 0);
    d.attach_k.conservativeResize(rows + n);
    d.attach_k.segment(rows, n).setZero();
    d.attach_c.conservativeResize(rows + n);
    d.attach_c.segment(rows, n).setZero();
    d.attach_weight.resize(static_cast<size_t>(rows + n), 0);
    d.contact_scale.conservativeResize(rows + n);
    d.contact_scale.segment(rows, n).setOnes();
    if (options_.cap_contact_stiffness && options_.contact_stiffness > 0) {
      Eigen::VectorXd w2v;
      vertex_frequency_bounds(body, body.mass, w2v);
      const double w2 = w2v.maxCoeff();  // bound of the object's highest elastic ω² (1/s²)
      for (int i = 0; i < n; ++i)
        d.contact_scale(rows + i) = std::min(1.0, body.mass(i) * w2 / options_.contact_stiffness);
    }
    d.rows += n;
  }
  d.bodies.push_back(std::move(body));
  d.embedding.push_back(-1);
  return b;
}

void World::embed(int b, const meshing::TetMesh& mesh) {
  if (b < 0 || b >= bodies()) throw InputError("fem world: embed: object " + std::to_string(b) + " out of range");
  const Body& host = data_->bodies[static_cast<size_t>(b)];
  const std::string name = "fem world: the collision mesh of object " + std::to_string(b);
  if (host.rigid) throw InputError(name + ": a rigid object collides with its own mesh (it never deforms)");
  WorldData::Embedded e{Body(mesh, host.material, false), {}, {}};  // throws on an empty or inverted mesh
  meshing::TetMesh rest;
  rest.V = host.rest;
  rest.T = host.T;
  const ffd::Binding bind = ffd::bind_surface(e.mesh.rest, rest, {}, nullptr, name);
  e.tet = bind.tet;
  e.bary = bind.bary;
  WorldData& d = mutable_data();
  if (d.embedding[static_cast<size_t>(b)] >= 0) {
    d.embedded[static_cast<size_t>(d.embedding[static_cast<size_t>(b)])] = std::move(e);
  } else {
    d.embedding[static_cast<size_t>(b)] = static_cast<int>(d.embedded.size());
    d.embedded.push_back(std::move(e));
  }
}

bool World::embedded(int b) const { return data_->embedding[static_cast<size_t>(b)] >= 0; }

const Body& World::collision_body(int b) const {
  const int e = data_->embedding[static_cast<size_t>(b)];
  return e >= 0 ? data_->embedded[static_cast<size_t>(e)].mesh : data_->bodies[static_cast<size_t>(b)];
}

int World::pin(const Eigen::AlignedBox3d& box) {
  WorldData& d = mutable_data();
  for (size_t b = 0; b < d.bodies.size(); ++b) {
    if (d.state_row[b] < 0) continue;
    for (int i = 0; i < d.bodies[b].vertices(); ++i)
      if (box.contains(d.bodies[b].rest.row(i).transpose())) d.pinned[d.state_row[b] + i] = 1;
  }
  int n = 0;
  for (char p : d.pinned) n += p;
  return n;
}

void World::pin_vertex(int row) {
  if (row < 0 || row >= data_->rows) throw InputError("fem world: pinned row " + std::to_string(row) + " out of range");
  mutable_data().pinned[row] = 1;
}

void World::attach(int row, double stiffness, double damping, bool carry_weight) {
  if (row < 0 || row >= data_->rows) throw InputError("fem world: attached row " + std::to_string(row) + " out of range");
  if (!(stiffness >= 0) || !std::isfinite(stiffness) || !(damping >= 0) || !std::isfinite(damping))
    throw InputError("fem world: attachment stiffness and damping must be finite and >= 0");
  if (carry_weight && !(stiffness > 0))
    throw InputError("fem world: an attachment that carries the weight needs a stiffness > 0");
  WorldData& d = mutable_data();
  d.attach_k(row) += stiffness;
  d.attach_c(row) += damping;
  if (carry_weight) d.attach_weight[static_cast<size_t>(row)] = 1;
}

double World::attachment_stiffness(int row) const { return data_->attach_k(row); }
double World::attachment_damping(int row) const { return data_->attach_c(row); }
bool World::attachment_carries_weight(int row) const { return data_->attach_weight[static_cast<size_t>(row)] != 0; }
Eigen::Vector3d World::attachment_anchor(int row) const { return data().attach_anchor.row(row).transpose(); }

int World::bodies() const { return static_cast<int>(data_->bodies.size()); }
const Body& World::body(int b) const { return data_->bodies[b]; }
int World::first_state_row(int b) const { return data_->state_row[b]; }
int World::state_rows() const { return data_->rows; }
bool World::pinned(int row) const { return data_->pinned[row] != 0; }
const Eigen::VectorXd& World::masses() const { return data_->mass; }
double World::contact_scale(int row) const { return data_->contact_scale(row); }

Eigen::Vector3d World::gravity_of(int b) const {
  return data_->bodies[b].gravity ? options_.gravity : Eigen::Vector3d::Zero();
}

int World::tets() const {
  int n = 0;
  for (const Body& b : data_->bodies) n += b.tets();
  return n;
}

State World::initial_state() const {
  const WorldData& d = *data_;
  State s;
  s.x.resize(d.rows, 3);
  s.v = RowMatrixX3d::Zero(d.rows, 3);
  for (int b = 0; b < bodies(); ++b)
    if (d.state_row[b] >= 0) s.x.middleRows(d.state_row[b], d.bodies[b].vertices()) = d.bodies[b].rest;
  if (d.prepared) s.overlap = d.overlap_depths;
  return s;
}

void World::prepare() {
  if (data_->prepared) return;
  WorldData& d = mutable_data();
  const int rows = d.rows;
  d.inv_mass.resize(rows);
  for (int i = 0; i < rows; ++i) d.inv_mass(i) = (d.pinned[i] || !(d.mass(i) > 0)) ? 0.0 : 1.0 / d.mass(i);
  d.contact_k.resize(rows);
  d.contact_c.resize(rows);
  for (int i = 0; i < rows; ++i) {
    d.contact_k(i) = options_.contact_stiffness * d.contact_scale(i);
    d.contact_c(i) = options_.contact_damping * d.contact_scale(i);
  }
  d.any_attached = false;
  for (int i = 0; i < rows; ++i)
    if (!d.pinned[i] && (d.attach_k(i) > 0 || d.attach_c(i) > 0)) d.any_attached = true;
  d.attach_anchor.resize(0, 3);  // filled below, once X_rest_all is
  d.gravity_off.assign(static_cast<size_t>(rows), 0);
  d.any_gravity_off = false;
  for (size_t b = 0; b < d.bodies.size(); ++b)
    if (d.state_row[b] >= 0 && !d.bodies[b].gravity) {
      std::fill(d.gravity_off.begin() + d.state_row[b], d.gravity_off.begin() + d.state_row[b] + d.bodies[b].vertices(), 1);
      d.any_gravity_off = true;
    }
  build_element_groups(d);
  // Collision numbering: deformables in state order, then rigid objects; an object with an
  // embedded collision mesh (embed) is that mesh there.
  d.scene = CollisionScene{};
  d.filter = CollisionFilter{};
  d.group_body.clear();
  d.filter.self_collision = options_.self_collision;
  std::vector<int> order;
  for (int b = 0; b < bodies(); ++b)
    if (d.state_row[b] >= 0) order.push_back(b);
  for (int b = 0; b < bodies(); ++b)
    if (d.state_row[b] < 0) order.push_back(b);
  int nv_all = 0, nt_all = 0;
  double edge_sum = 0;
  long long edge_count = 0;
  d.any_embedded = false;
  for (int b : order) {
    const Body& C = collision_body(b);
    d.any_embedded = d.any_embedded || d.embedding[static_cast<size_t>(b)] >= 0;
    d.scene.bodies.push_back(&C);
    d.group_body.push_back(b);
    d.scene.first_vertex.push_back(nv_all);
    d.scene.first_tet.push_back(nt_all);
    nv_all += C.vertices();
    nt_all += C.tets();
    if (!C.rigid || rows == 0) {  // rigid obstacles' (often long) edges do not set the cell
      edge_sum += C.D0.sum();
      edge_count += C.D0.size();
    }
  }
  d.T_all.resize(nt_all, 4);
  d.X_rest_all.resize(nv_all, 3);
  d.filter.vertex_group.resize(static_cast<size_t>(nv_all));
  d.filter.tet_group.resize(static_cast<size_t>(nt_all));
  d.filter.vertex_on_surface.resize(static_cast<size_t>(nv_all));
  d.coll_start.assign(static_cast<size_t>(nv_all) + 1, 0);
  d.coll_row.clear();
  d.coll_w.clear();
  d.coll_share.clear();
  d.floor_row.assign(static_cast<size_t>(rows), 1);
  d.embedded_vertices.clear();
  for (size_t g = 0; g < order.size(); ++g) {
    const int b = order[g];
    const Body& B = collision_body(b);
    const int fv = d.scene.first_vertex[g], ft = d.scene.first_tet[g];
    d.T_all.middleRows(ft, B.tets()) = B.T.array() + fv;
    d.X_rest_all.middleRows(fv, B.vertices()) = B.rest;
    std::fill(d.filter.vertex_group.begin() + fv, d.filter.vertex_group.begin() + fv + B.vertices(), static_cast<int>(g));
    std::copy(B.on_boundary.begin(), B.on_boundary.end(), d.filter.vertex_on_surface.begin() + fv);
    std::fill(d.filter.tet_group.begin() + ft, d.filter.tet_group.begin() + ft + B.tets(), static_cast<int>(g));
    d.filter.group_rigid.push_back(B.rigid ? 1 : 0);
    // The state rows of each collision vertex.
    const int r0 = d.state_row[static_cast<size_t>(b)], e = d.embedding[static_cast<size_t>(b)];
    double share = 1.0;
    if (r0 >= 0 && e >= 0) {
      const Body& host = d.bodies[static_cast<size_t>(b)];
      const double cage = static_cast<double>(std::count(host.on_boundary.begin(), host.on_boundary.end(), 1));
      const double embedded = static_cast<double>(std::count(B.on_boundary.begin(), B.on_boundary.end(), 1));
      share = std::min(1.0, cage / std::max(1.0, embedded));
      // The floor holds the embedded vertices instead of the host's rows.
      std::fill(d.floor_row.begin() + r0, d.floor_row.begin() + r0 + host.vertices(), 0);
      for (int k = 0; k < B.vertices(); ++k) d.embedded_vertices.push_back(fv + k);
    }
    d.coll_share.resize(static_cast<size_t>(fv + B.vertices()), share);
    for (int k = 0; k < B.vertices(); ++k) {
      if (r0 >= 0 && e >= 0) {
        const WorldData::Embedded& E = d.embedded[static_cast<size_t>(e)];
        const Body& host = d.bodies[static_cast<size_t>(b)];
        for (int j = 0; j < 4; ++j) {
          d.coll_row.push_back(r0 + host.T(E.tet(k), j));
          d.coll_w.push_back(E.bary(k, j));
        }
      } else if (r0 >= 0) {
        d.coll_row.push_back(r0 + k);
        d.coll_w.push_back(1.0);
      }
      d.coll_start[static_cast<size_t>(fv + k) + 1] = static_cast<int>(d.coll_row.size());
    }
  }
  // Attachment anchors: the rest positions, raised by m g / k where the attachment carries the weight.
  d.attach_anchor.resize(rows, 3);
  for (size_t b = 0; b < d.bodies.size(); ++b)
    if (d.state_row[b] >= 0) d.attach_anchor.middleRows(d.state_row[b], d.bodies[b].vertices()) = d.bodies[b].rest;
  for (size_t b = 0; b < d.bodies.size(); ++b) {
    if (d.state_row[b] < 0) continue;
    const Eigen::Vector3d g = gravity_of(static_cast<int>(b));
    for (int i = d.state_row[b]; i < d.state_row[b] + d.bodies[b].vertices(); ++i)
      if (d.attach_weight[static_cast<size_t>(i)] && d.attach_k(i) > 0)
        d.attach_anchor.row(i) -= (d.mass(i) / d.attach_k(i)) * g.transpose();
  }
  d.cell = options_.cell_size > 0 ? options_.cell_size : (edge_count ? edge_sum / edge_count : 1.0);
  d.table = options_.table_size > 0 ? options_.table_size : next_prime(std::max(4 * nv_all, 97));
  d.version = ++g_version;
  d.prepared = true;
  // Rest overlaps: the penetrations of the rest state, found with the contacts' own detection.
  d.overlaps.clear();
  d.overlap_depths.resize(0);
  d.overlap_slot.assign(static_cast<size_t>(nv_all), -1);
  if (options_.rest_overlap && options_.collisions && rows > 0) {
    State rest;
    rest.x.resize(rows, 3);
    rest.v.setZero(rows, 3);
    for (size_t b = 0; b < d.bodies.size(); ++b)
      if (d.state_row[b] >= 0) rest.x.middleRows(d.state_row[b], d.bodies[b].vertices()) = d.bodies[b].rest;
    ForceWorkspace ws;
    const std::vector<Penetration> pens = find_penetrations(*this, rest, ws);
    auto body_of = [&](int group) { return d.group_body[static_cast<size_t>(group)]; };
    for (const Penetration& p : pens)
      d.overlaps.push_back({p.vertex, body_of(d.filter.vertex_group[p.vertex]), body_of(p.body), p.depth});
    std::sort(d.overlaps.begin(), d.overlaps.end(),
              [](const World::RestOverlap& a, const World::RestOverlap& b) { return a.vertex < b.vertex; });
    d.overlap_depths.resize(static_cast<Eigen::Index>(d.overlaps.size()));
    for (size_t k = 0; k < d.overlaps.size(); ++k) {
      d.overlap_slot[d.overlaps[k].vertex] = static_cast<int>(k);
      d.overlap_depths(static_cast<Eigen::Index>(k)) = d.overlaps[k].depth;
    }
  }
}

const std::vector<World::RestOverlap>& World::rest_overlaps() const { return data().overlaps; }

void World::step(State& s, const RowMatrixX3d* external) {
  prepare();
  integrator_->step(*this, s, external, workspace_);
}

void World::internal_forces(const State& s, RowMatrixX3d& F) {
  prepare();
  assemble_forces(*this, s, nullptr, workspace_, F, ForceTerms::internal_only());
}

void World::total_forces(const State& s, const RowMatrixX3d* external, RowMatrixX3d& F) {
  prepare();
  assemble_forces(*this, s, external, workspace_, F);
}

StepStats World::contact_stats(const State& s) {
  prepare();
  detect_contacts(*this, s, workspace_);
  return workspace_.stats();
}

const StepStats& World::last_stats() const { return workspace_.stats(); }

double World::elastic_energy(const State& s) const {
  const WorldData& d = *data_;
  double e = 0;
  for (int b = 0; b < bodies(); ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0) continue;
    const Body& B = d.bodies[b];
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
  for (int i = 0; i < data_->rows; ++i) e += 0.5 * data_->mass(i) * s.v.row(i).squaredNorm();
  return e;
}

double World::gravity_energy(const State& s) const {
  const WorldData& d = *data_;
  double e = 0;
  for (int b = 0; b < bodies(); ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0 || !d.bodies[b].gravity) continue;
    for (int i = r0; i < r0 + d.bodies[b].vertices(); ++i) e -= d.mass(i) * s.x.row(i).dot(options_.gravity.transpose());
  }
  return e;
}

RowMatrixX3d World::collision_positions(const State& s, int b) const {
  const WorldData& d = *data_;
  const int r0 = d.state_row[static_cast<size_t>(b)], e = d.embedding[static_cast<size_t>(b)];
  if (r0 < 0) return d.bodies[static_cast<size_t>(b)].rest;
  if (e < 0) return s.x.middleRows(r0, d.bodies[static_cast<size_t>(b)].vertices());
  const WorldData::Embedded& E = d.embedded[static_cast<size_t>(e)];
  const Body& host = d.bodies[static_cast<size_t>(b)];
  RowMatrixX3d X(E.mesh.vertices(), 3);
  for (int k = 0; k < E.mesh.vertices(); ++k) {
    Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
    for (int j = 0; j < 4; ++j) p += E.bary(k, j) * s.x.row(r0 + host.T(E.tet(k), j));
    X.row(k) = p;
  }
  return X;
}

double World::body_volume(const State& s, int b) const {
  const WorldData& d = *data_;
  if (d.state_row[b] < 0) return d.bodies[b].total_volume();
  const int e = d.embedding[static_cast<size_t>(b)];
  if (e < 0) return volume(d.bodies[b], s.x.middleRows(d.state_row[b], d.bodies[b].vertices()));
  // The embedded mesh's volume at its vertices' positions W·x.
  return volume(d.embedded[static_cast<size_t>(e)].mesh, collision_positions(s, b));
}

}  // namespace squeeze::fem
