// The implicit integrator: backward Euler by minimising the incremental potential (implicit.h).
#include "squeeze/fem/implicit.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <spdlog/spdlog.h>

#include "block_kernels.h"
#include "squeeze/common/error.h"
#include "squeeze/fem/block_ldlt.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/world.h"
#include "world_data.h"

namespace squeeze::fem {
namespace {

using Mat3 = Eigen::Matrix3d;

// A contact of the last substep is carried into the next while its depth at the start is above
// −kCarryMargin × the mean edge length (substep, carry_contacts).
constexpr double kCarryMargin = 0.1;
// ... and while its vertex has slid less than kCarryDrift × the mean edge length along the contact
// plane, relative to the point of the penetrated tetrahedron it was found in: a plane found at
// the edge of a table must not hold a body that slides off the table (it holds it at most this far
// beyond the edge; FemImplicit.ABodySlidingOffASlabFallsOffIt). 0.5 dropped most of the organs'
// resting contacts as they sagged (221 factorisations in 2 s instead of 106); 2 keeps them.
constexpr double kCarryDrift = 2.0;
// A substep that halves one and moves at least this fraction of its motion is kept (substep).
constexpr double kJumpRatio = 0.8;
// A contact's penalty curvature is kept in the Newton matrix while its depth is above −kCurvatureBand
// × the mean edge length, not only while it is positive (assemble).
constexpr double kCurvatureBand = 0.01;
// An inexact Newton direction (ImplicitOptions::inexact_cg_tolerance) is taken instead of a new
// factorisation only where a factorisation costs at least this many CG iterations' multiply-adds:
// the block triangular solves run at about a quarter of the factorisation's speed per multiply-add
// (memory-bound; bench/README.md; measured with the double-precision factor, before CG's
// substitutions read it in single precision, BlockLDLT::precondition, which made them 1.3–1.9×
// faster), so this is a factorisation of about 10 CG iterations' time (now somewhat more), and
// an inexact direction can cost a Newton iteration more (assembly, gradient, line search). On small
// meshes (Barriers2: 10; the organs' shells: 18) factorising stays cheaper; the organs' fine
// meshes (63) are where it pays.
constexpr double kInexactFactorCost = 40;

// A symmetric matrix of 3×3 blocks over the free vertices: its diagonal blocks and the blocks
// (I, J), I > J, of its lower triangle. The pattern is built once from the block pairs; blocks are
// then added in place. BlockLDLT factorises it; multiply is the conjugate gradients' product.
class BlockMatrix {
 public:
  // n blocks per side; pairs (I, J) with I > J (duplicates allowed). Returns true if the pattern
  // differs from the previous one (the factorisation must be analysed again).
  bool build(int n, std::vector<std::pair<int, int>> pairs) {
    // The same pairs in the same order as last time (a substep without contacts after another):
    // the same pattern, without sorting them again (1.2 % of the ball's samples, perf).
    if (n == n_ && pairs == input_) return false;
    input_ = pairs;
    std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second < b.second : a.first < b.first;  // by column, then row
    });
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    if (n == n_ && pairs == pairs_) return false;
    n_ = n;
    pairs_ = std::move(pairs);
    col_start_.assign(static_cast<size_t>(n) + 1, 0);
    for (const auto& p : pairs_) ++col_start_[p.second + 1];
    for (int J = 0; J < n; ++J) col_start_[J + 1] += col_start_[J];
    row_start_.assign(static_cast<size_t>(n) + 1, 0);
    for (const auto& p : pairs_) ++row_start_[p.first + 1];
    for (int I = 0; I < n; ++I) row_start_[I + 1] += row_start_[I];
    row_pairs_.resize(pairs_.size());
    std::vector<int> next(row_start_.begin(), row_start_.end() - 1);
    for (size_t q = 0; q < pairs_.size(); ++q) row_pairs_[static_cast<size_t>(next[pairs_[q].first]++)] = static_cast<int>(q);
    diag_.assign(static_cast<size_t>(n), Mat3::Zero());
    off_.assign(pairs_.size(), Mat3::Zero());
    return true;
  }
  // Index of the off-diagonal block (I, J), I > J, or -1.
  int find(int I, int J) const {
    const auto first = pairs_.begin() + col_start_[J], last = pairs_.begin() + col_start_[J + 1];
    const auto it = std::lower_bound(first, last, std::make_pair(I, J),
                                     [](const auto& a, const auto& b) { return a.first < b.first; });
    return it != last && it->first == I ? static_cast<int>(it - pairs_.begin()) : -1;
  }
  void zero() {
    std::fill(diag_.begin(), diag_.end(), Mat3::Zero());
    std::fill(off_.begin(), off_.end(), Mat3::Zero());
  }
  // Adds the symmetric block H (every element's diagonal block is symmetric by construction) to
  // the diagonal block of vertex I.
  void add_diag(int I, const Mat3& H) { combine<false>(diag_[static_cast<size_t>(I)].data(), H.data(), false); }
  void add_off(int id, const Mat3& H) { off_[static_cast<size_t>(id)] += H; }
  // Adds H (transposed: Hᵀ) to, or subtracts it from, the off-diagonal block id: the same entry
  // additions as add_off(id, H.transpose()) and add_off(id, −H), in plain loops (Eigen's sum with
  // a transpose was a call per block, 3 % of the ball's samples, perf).
  void add_off(int id, const Mat3& H, bool transposed) { combine<false>(off_[static_cast<size_t>(id)].data(), H.data(), transposed); }
  void subtract_off(int id, const Mat3& H, bool transposed) {
    combine<true>(off_[static_cast<size_t>(id)].data(), H.data(), transposed);
  }
  // out = A p (3 per block). Row by row, each row's terms in the order of a pass over the pairs
  // (by column, then row: first the blocks (K, J), J < K, by column, then the transposes of the
  // blocks (I, K) of column K, by row), so the same sums as that pass, which read and wrote two
  // rows of out per block: 51.6 → 45.1 M instructions over the ball's second (callgrind).
  void multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const {
    out.resize(p.size());
    const double* const pv = p.data();
    const Mat3* const off = off_.data();
    const std::pair<int, int>* const pairs = pairs_.data();
    const int* const row_pairs = row_pairs_.data();
    double* const o = out.data();
    for (int K = 0; K < n_; ++K) {
      blocks::product<blocks::Op::kAssign, false>(diag_[static_cast<size_t>(K)].data(), pv + 3 * K, o + 3 * K);
      blocks::Sum3 t(o + 3 * K);
      for (int a = row_start_[K]; a < row_start_[K + 1]; ++a) {
        const int q = row_pairs[a];
        t.add_product(off[q].data(), pv + 3 * pairs[q].second);
      }
      for (int q = col_start_[K]; q < col_start_[K + 1]; ++q) t.add_transposed_product(off[q].data(), pv + 3 * pairs[q].first);
      t.store(o + 3 * K);
    }
  }
  int blocks() const { return n_; }
  const std::vector<std::pair<int, int>>& pairs() const { return pairs_; }
  const std::vector<Mat3>& diag() const { return diag_; }
  const std::vector<Mat3>& off() const { return off_; }

 private:
  // b ← b ± h or b ± hᵀ (3×3, column-major), entry by entry.
  template <bool kSubtract>
  static void combine(double* b, const double* h, bool transposed) {
    if (transposed) {
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) b[i + 3 * j] = kSubtract ? b[i + 3 * j] - h[j + 3 * i] : b[i + 3 * j] + h[j + 3 * i];
    } else {
      for (int e = 0; e < 9; ++e) b[e] = kSubtract ? b[e] - h[e] : b[e] + h[e];
    }
  }
  int n_ = -1;
  std::vector<std::pair<int, int>> input_;  // the pairs given to the last build, as given
  std::vector<std::pair<int, int>> pairs_;  // (I, J), I > J, sorted by column then row
  std::vector<int> col_start_;             // per block column J: its pairs [col_start_[J], col_start_[J+1])
  std::vector<int> row_start_, row_pairs_;  // per block row I: its pairs row_pairs_[row_start_[I] .. row_start_[I+1]), by column
  std::vector<Mat3> diag_;                 // per block row: its diagonal block
  std::vector<Mat3> off_;                  // per pair (I, J): block (I, J)
};

// A contact of the step, linearised where it was detected: over its stencil (the penetrating
// vertex p and the 4 corners of the penetrated tet) with weights w = (1, −b_0, …, −b_3), the depth
// is d(x) = c0 − Σ_s w_s r·x_s over the free rows of the stencil (fixed ones, rigid or pinned, are
// folded into c0). Its energy is ½ k max(0, d)², its dissipation ½ (c / h) (Σ_s w_s r·(x_s − x_s^n))².
// Where p or the corners are vertices of embedded collision meshes (World::embed), each stands
// for the 4 state rows it follows, weighted by its barycentric coordinates: up to 20 rows, a row
// met twice counted once with the sum of its weights.
constexpr int kMaxStencil = 20;
struct LinearContact {
  int n = 5;                 // rows in the stencil
  int row[kMaxStencil];      // state rows of the stencil, −1 where fixed
  double w[kMaxStencil];     // 1, −b_0, …, −b_3 (times the embedding's weights)
  Vec3 r;               // unit direction out of the penetrated object
  double c0 = 0;        // m
  double k = 0, c = 0;  // N/m, N·s/m
  int vertex = -1;      // collision index of p (a vertex is in the set once)
  int body = -1;        // the penetrated object
  double scale = 0;     // m: mean edge length of the object of its first free row (the curvature band
                        // of assemble, the carry limits of carry_contacts)
  Vec3 at[kMaxStencil];  // positions of the stencil's free rows where the contact was linearised
};

// Σ_s w_s r·X_s over the free rows of a contact's stencil.
inline double stencil_dot(const LinearContact& c, const RowMatrixX3d& X) {
  double q = 0;
  for (int s = 0; s < c.n; ++s)
    if (c.row[s] >= 0) q += c.w[s] * c.r.dot(Vec3(X.row(c.row[s]).transpose()));
  return q;
}

class ImplicitIntegrator : public TimeIntegrator {
 public:
  explicit ImplicitIntegrator(const ImplicitOptions& o) : o_(o) {}
  const char* name() const override { return "implicit"; }
  std::unique_ptr<TimeIntegrator> clone() const override { return std::make_unique<ImplicitIntegrator>(o_); }
  void step(const World& world, State& s, const RowMatrixX3d* external, ForceWorkspace& ws) override;
  void reset() override {
    factor_h_ = 0;
    contacts_.clear();
    carried_.clear();
  }

 private:
  void fit(const World& w);
  int substeps_for(const World& w, const State& s, const RowMatrixX3d* external, double h);
  // parent_worst: the largest motion (edge lengths) of the substep this one halves (motion check).
  void substep(const World& w, State& s, const RowMatrixX3d* external, ForceWorkspace& ws, double h, int depth,
               double parent_worst = std::numeric_limits<double>::infinity());
  void carry_contacts();
  void add_contacts(const World& w, const std::vector<Penetration>& pens, const RowMatrixX3d& x);
  // The floor under embedded meshes (World::embed): a contact of each of their vertices below it at
  // x (vertex id −2 − its collision index), over the rows the vertex follows.
  void add_floor_contacts(const World& w, const RowMatrixX3d& x);
  // G_x: G(x) if known (the initial guess's, computed to choose it), else NaN.
  void solve(const World& w, double h, RowMatrixX3d& x, double G_x = std::numeric_limits<double>::quiet_NaN());
  double potential(const World& w, const RowMatrixX3d& x, double h) const;
  void energy_gradient(const World& w, const RowMatrixX3d& x, double h, bool damping, RowMatrixX3d& Gr) const;
  void gradient(const World& w, const RowMatrixX3d& x, double h, Eigen::VectorXd& g);
  void assemble(const World& w, const RowMatrixX3d& x, double h, bool exact);
  // The Newton blocks at x of the edges edges[0, ne) and the tetrahedra tets[0, nt) (element
  // indices; null: 0, 1, …) into eH[0, ne) and tH[0, nt); in parallel if `parallel`.
  void element_blocks(const World& w, const RowMatrixX3d& x, double h, bool exact, const int* edges, size_t ne,
                      Mat3* eH, const int* tets, size_t nt, std::array<Mat3, 10>* tH, bool parallel);
  void build_pattern(const World& w);
  bool factorize(double h);
  bool newton_direction(const World& w, const RowMatrixX3d& x, double h, const Eigen::VectorXd& g, Eigen::VectorXd& dx);

  ImplicitOptions o_;
  std::uint64_t version_ = 0;
  std::vector<int> free_;        // per state row: its free index, or −1 (pinned)
  std::vector<int> free_rows_;   // per free index: its state row
  Eigen::VectorXd edge_scale_;   // per state row: mean edge length of its object (m)
  Eigen::VectorXd vertex_stiffness_;  // per state row: Σ k_e / L_e² over its edges (N/m; substeps_for)
  RowMatrixX3d row_gravity_;     // per state row: the gravity acting on it (m/s²)
  // The substep's data.
  RowMatrixX3d xn_, y_;                     // start of the substep, inertial target
  std::vector<Vec3> edge_g_;                // per edge: ∂C/∂p_j at x_n (its damping)
  std::vector<std::array<Vec3, 4>> tet_g_;  // per tet: ∂C/∂p_k at x_n (its damping)
  // The elements' Hessian blocks of one assembly in one part (assemble): per edge its block, per
  // tet its 4 diagonal blocks and 6 blocks (b, a), a < b, computed in parallel, summed in order.
  std::vector<Mat3> edge_H_;
  std::vector<std::array<Mat3, 10>> tet_H_;
  // An assembly in two parts: per part, its elements (those with a free row in it, ascending) and
  // their blocks.
  std::vector<int> part_edges_[2], part_tets_[2];
  std::vector<Mat3> part_edge_H_[2];
  std::vector<std::array<Mat3, 10>> part_tet_H_[2];
  std::vector<LinearContact> contacts_;
  std::vector<LinearContact> carried_;      // the last substep's contacts by vertex, offered to the next (see substep)
  bool still_holds(LinearContact& c, const RowMatrixX3d& X) const;
  const LinearContact* carried_for(int vertex) const;
  std::vector<char> floor_damped_;          // per state row: below the floor at x_n
  BlockMatrix H_;
  // Off-diagonal blocks of each element's vertex pairs (a < b, in the order of pair_code), as
  // 2·block + (1 if the block is stored transposed), or −1 where a vertex is fixed.
  std::vector<int> edge_block_;
  std::vector<std::array<int, 6>> tet_block_;
  std::vector<int> contact_block_, contact_block_start_;  // per contact its pairs' codes (n (n − 1) / 2)
  BlockLDLT ldlt_;
  // Parallel assembly (assemble): rows of free index below it are one part, the others the other;
  // a boundary between bodies, 0 if no such boundary halves the elements well enough.
  int assembly_split_ = 0;
  bool analysed_ = false;     // ldlt_ analysed the current pattern
  double factor_cost_ = 0;    // a factorisation's multiply-adds over one CG iteration's (analysis)
  double factor_h_ = 0;       // the substep length of ldlt_'s factorisation (0: none): a preconditioner while h is the same
  Eigen::VectorXd r_, z_, p_, Hp_;  // PCG scratch
  RowMatrixX3d Gr_;                 // gradient scratch (per state row)
  std::vector<char> far_;           // per body: in free flight this step (substeps_for)
  std::vector<Eigen::AlignedBox3d> rigid_box_;  // per body: a rigid object's bounding box (empty for deformables)
};

void ImplicitIntegrator::fit(const World& w) {
  const WorldData& d = w.data();
  if (version_ == d.version) return;
  version_ = d.version;
  free_.assign(static_cast<size_t>(d.rows), -1);
  free_rows_.clear();
  for (int i = 0; i < d.rows; ++i)
    if (d.inv_mass(i) > 0) {
      free_[i] = static_cast<int>(free_rows_.size());
      free_rows_.push_back(i);
    }
  edge_scale_.setConstant(d.rows, 1.0);
  row_gravity_.setZero(d.rows, 3);
  for (size_t b = 0; b < d.bodies.size(); ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0) continue;
    const Body& B = d.bodies[b];
    const double L = B.mean_edge_length() > 0 ? B.mean_edge_length() : 1.0;
    const Vec3 g = w.gravity_of(static_cast<int>(b));
    for (int i = r0; i < r0 + B.vertices(); ++i) {
      edge_scale_(i) = L;
      row_gravity_.row(i) = g.transpose();
    }
  }
  rigid_box_.assign(d.bodies.size(), Eigen::AlignedBox3d());
  for (size_t b = 0; b < d.bodies.size(); ++b)
    if (d.state_row[b] < 0)
      for (int k = 0; k < d.bodies[b].vertices(); ++k)
        rigid_box_[b].extend(Vec3(d.bodies[b].rest.row(k).transpose()));  // (rigid: rest is where it is)
  vertex_stiffness_.setZero(d.rows);
  for (const auto& E : d.edges) {
    const double K = E.k / (E.D0 * E.D0);
    vertex_stiffness_(E.i) += K;
    vertex_stiffness_(E.j) += K;
  }
  // The assembly's two parts: the boundary between bodies (in free-row order) that best halves the
  // elements' work (an edge 1, a tetrahedron 3), kept if the larger part is at most 60 %.
  {
    std::vector<double> work(free_rows_.size() + 1, 0.0);  // by the free index of an element's first free vertex
    auto first_free = [&](std::initializer_list<int> rows) {
      for (int r : rows)
        if (free_[r] >= 0) return free_[r];
      return -1;
    };
    for (const auto& E : d.edges) {
      const int f = first_free({E.i, E.j});
      if (f >= 0) work[f] += 1;
    }
    for (const auto& T : d.tet_elems) {
      const int f = first_free({T.v[0], T.v[1], T.v[2], T.v[3]});
      if (f >= 0) work[f] += 3;
    }
    double total = 0;
    for (double x : work) total += x;
    assembly_split_ = 0;
    double best = 0.6 * total, below = 0;
    int f = 0;
    for (size_t b = 0; b < d.bodies.size(); ++b) {
      const int r0 = d.state_row[b];
      if (r0 < 0) continue;
      const int f0 = f;
      for (int i = r0; i < r0 + d.bodies[b].vertices(); ++i)
        if (free_[i] >= 0) {
          below += work[free_[i]];
          ++f;
        }
      if (f > f0 && f < static_cast<int>(free_rows_.size()) && std::max(below, total - below) <= best) {
        best = std::max(below, total - below);
        assembly_split_ = f;
      }
    }
    for (int part = 0; part < 2; ++part) {
      auto mine = [&](int row) { return free_[row] >= 0 && (free_[row] >= assembly_split_) == (part == 1); };
      part_edges_[part].clear();
      part_tets_[part].clear();
      if (assembly_split_ == 0) continue;
      for (size_t e = 0; e < d.edges.size(); ++e)
        if (mine(d.edges[e].i) || mine(d.edges[e].j)) part_edges_[part].push_back(static_cast<int>(e));
      for (size_t t = 0; t < d.tet_elems.size(); ++t) {
        const auto& T = d.tet_elems[t];
        if (mine(T.v[0]) || mine(T.v[1]) || mine(T.v[2]) || mine(T.v[3])) part_tets_[part].push_back(static_cast<int>(t));
      }
    }
  }
  analysed_ = false;
  contacts_.clear();
  carried_.clear();
}

// The substeps of a step of length h: enough that no free vertex is predicted to move more than
// motion_fraction of its object's mean edge length in one. The prediction is |v| h + ½ |a| h² with a
// the acceleration of every force at x_n: gravity, external forces, the elastic forces and the
// penalties of the last substep's contacts, the floor and the attachments. A body resting on
// others or hanging from its pins thus takes whole steps where gravity alone would have split
// them. Where that acceleration is large, it is mostly an imbalance that the vertex's own edges
// resist, and backward Euler moves the vertex about |f| / K (K = Σ k_e / L_e² over its edges), not
// ½ |a| h²: the vertex's share is capped by that plus ½ |A| h², A the acceleration of its
// object's centre of mass (what moves the body as a whole, such as gravity in free fall).
int ImplicitIntegrator::substeps_for(const World& w, const State& s, const RowMatrixX3d* ext, double h) {
  const WorldData& d = w.data();
  const WorldOptions& o = w.options();
  energy_gradient(w, s.x, h, false, Gr_);
  // Per state row: its force (N); per object: the velocity and acceleration of its free vertices'
  // centre of mass.
  RowMatrixX3d& F = Gr_;
  for (int i : free_rows_) {
    Vec3 f = d.mass(i) * Vec3(row_gravity_.row(i).transpose()) - Vec3(F.row(i).transpose());
    if (ext) f += Vec3(ext->row(i).transpose());
    F.row(i) = f.transpose();
  }
  const size_t nb = d.bodies.size();
  std::vector<Vec3> body_accel(nb, Vec3::Zero()), body_velocity(nb, Vec3::Zero());
  for (size_t b = 0; b < nb; ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0) continue;
    Vec3 force = Vec3::Zero(), momentum = Vec3::Zero();
    double mass = 0;
    for (int i = r0; i < r0 + d.bodies[b].vertices(); ++i)
      if (free_[i] >= 0) force += F.row(i).transpose(), momentum += d.mass(i) * s.v.row(i).transpose(), mass += d.mass(i);
    if (mass > 0) body_accel[b] = force / mass, body_velocity[b] = momentum / mass;
  }
  // Per vertex: its predicted motion, and the part of it relative to its object's centre of mass.
  auto forced = [&](int i, const Vec3& f, double whole) {
    const double K = vertex_stiffness_(i);
    const double a = 0.5 * d.inv_mass(i) * f.norm() * h * h;
    return K > 0 ? std::min(a, f.norm() / K + whole) : a;
  };
  // Per state row: its predicted motion and its motion about its object's centre of mass (m); per
  // object: the largest of each, and its bounding box at x_n.
  Eigen::VectorXd motion = Eigen::VectorXd::Zero(d.rows), about = Eigen::VectorXd::Zero(d.rows);
  std::vector<double> reach(nb, 0.0), own(nb, 0.0);
  std::vector<Eigen::AlignedBox3d> box(nb);
  for (size_t b = 0; b < nb; ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0) {
      box[b] = rigid_box_[b];
      continue;
    }
    const double whole = 0.5 * body_accel[b].norm() * h * h;
    for (int i = r0; i < r0 + d.bodies[b].vertices(); ++i) {
      box[b].extend(Vec3(s.x.row(i).transpose()));
      if (free_[i] < 0) continue;
      const Vec3 f = F.row(i).transpose();
      motion(i) = s.v.row(i).norm() * h + forced(i, f, whole);
      about(i) = (s.v.row(i) - body_velocity[b].transpose()).norm() * h + forced(i, f - d.mass(i) * body_accel[b], 0.0);
      reach[b] = std::max(reach[b], motion(i));
      own[b] = std::max(own[b], about(i));
    }
  }
  // An object is in free flight when nothing can reach it within the step: its box stays apart from
  // every other object's box by more than twice their relative motion (of their centres of mass,
  // plus each one's motion about its own) and half its mean edge length, and from the floor by
  // twice its reach and that. Its motion as a whole then needs no substeps (no contact to resolve;
  // backward Euler integrates the flight); only its vertices' motion relative to its centre of
  // mass counts (its deformation, self-contact). Two objects falling side by side stay in flight.
  double need = 1;
  far_.assign(nb, 0);
  for (size_t b = 0; b < nb; ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0 || box[b].isEmpty()) continue;
    const double margin = 0.5 * d.bodies[b].mean_edge_length();
    bool far = !o.floor || box[b].min().y() - 2 * reach[b] - margin > o.floor_height;
    for (size_t c = 0; c < nb && far; ++c) {
      if (c == b || box[c].isEmpty()) continue;
      const double relative = (body_velocity[b] - body_velocity[c]).norm() * h +
                              0.5 * (body_accel[b] - body_accel[c]).norm() * h * h + own[b] + own[c];
      far = box[b].exteriorDistance(box[c]) > 2 * relative + margin;
    }
    far_[b] = far;
    const Eigen::VectorXd& m = far ? about : motion;
    for (int i = r0; i < r0 + d.bodies[b].vertices(); ++i)
      if (free_[i] >= 0) need = std::max(need, m(i) / (o_.motion_fraction * edge_scale_(i)));
  }
  if (!std::isfinite(need)) return o_.max_substeps;
  return static_cast<int>(std::min<double>(o_.max_substeps, std::ceil(need - 1e-9)));
}

void ImplicitIntegrator::step(const World& w, State& s, const RowMatrixX3d* ext, ForceWorkspace& ws) {
  fit(w);
  const double H = w.time_step(), t0 = s.time;
  const int k = std::max(1, substeps_for(w, s, ext, H));
  for (int i = 0; i < k; ++i) substep(w, s, ext, ws, H / k, 0);
  s.time = t0 + H;
  ++stats_.steps;
}

void ImplicitIntegrator::substep(const World& w, State& s, const RowMatrixX3d* ext, ForceWorkspace& ws, double h,
                                 int depth, double parent_worst) {
  const WorldData& d = w.data();
  const WorldOptions& o = w.options();
  const State before = s;
  const IntegratorStats at_start = stats_;
  damp_deformation(w, s, h);
  xn_ = s.x;
  // The inertial target y = x_n + h v_n + h² (g + f_ext / m) of the free rows; fixed rows stay.
  y_ = xn_;
  for (int i : free_rows_) {
    Vec3 a = row_gravity_.row(i).transpose();
    if (ext) a += d.inv_mass(i) * Vec3(ext->row(i).transpose());
    y_.row(i) += (h * Vec3(s.v.row(i).transpose()) + (h * h) * a).transpose();
  }
  // Damping gradients at x_n.
  edge_g_.resize(d.edges.size());
  for (size_t e = 0; e < d.edges.size(); ++e) {
    const auto& E = d.edges[e];
    distance_constraint(Vec3(xn_.row(E.i).transpose()), Vec3(xn_.row(E.j).transpose()), E.D0, &edge_g_[e]);
  }
  tet_g_.resize(d.tet_elems.size());
  for (size_t t = 0; t < d.tet_elems.size(); ++t) {
    const auto& T = d.tet_elems[t];
    volume_constraint(Vec3(xn_.row(T.v[0]).transpose()), Vec3(xn_.row(T.v[1]).transpose()),
                      Vec3(xn_.row(T.v[2]).transpose()), Vec3(xn_.row(T.v[3]).transpose()), T.V0, tet_g_[t].data());
  }
  floor_damped_.assign(static_cast<size_t>(d.rows), 0);
  if (o.floor)
    for (int i = 0; i < d.rows; ++i) floor_damped_[i] = xn_(i, 1) < o.floor_height;
  // Contacts at x_n, the solve; contacts found at the result join and the solve goes on.
  contacts_.clear();
  State probe = s;
  if (o.collisions) {
    add_contacts(w, find_penetrations(w, probe, ws), xn_);  // depths beyond the rest overlaps
    s.overlap = ws.overlap();                               // shrunk where vertices came out
    probe.overlap = s.overlap;
    carry_contacts();
  }
  add_floor_contacts(w, xn_);
  // The initial guess: the inertial target y (exact in free flight) or x_n + h v_n (exact at rest
  // and in equilibrium), whichever has the lower potential. Both come from the state alone.
  RowMatrixX3d x = y_;
  double G_x = potential(w, x, h);
  {
    RowMatrixX3d coast = xn_;
    for (int i : free_rows_) coast.row(i) += h * s.v.row(i);
    const double G_coast = potential(w, coast, h);
    if (G_coast < G_x) x = std::move(coast), G_x = G_coast;
  }
  solve(w, h, x, G_x);  // its first line search starts from G_x (one potential less per substep)
  for (int round = 0; round < o_.contact_rounds && (o.collisions || (o.floor && d.any_embedded)); ++round) {
    probe.x = x;
    const size_t count = contacts_.size();
    if (o.collisions) add_contacts(w, find_penetrations(w, probe, ws), x);
    add_floor_contacts(w, x);
    if (contacts_.size() == count) break;
    ++stats_.contact_rounds;
    solve(w, h, x);
  }
  // Motion check: a substep that moved a vertex more than twice the allowed fraction is redone as
  // two halves (a contact or an elastic snap that the prediction did not see), unless it halves a
  // substep that moved as far (more than kJumpRatio of its motion): a motion that a shorter step
  // does not shorten is a jump (a vertex pushed out of a deep penetration moves as far at any h),
  // and halving again only wastes work and leaves a larger velocity (the jump over a shorter h).
  // (An object in free flight, far_, is judged by its vertices' motion relative to its centre of mass.)
  double worst = 0;
  int worst_i = -1;
  for (size_t b = 0; b < d.bodies.size(); ++b) {
    const int r0 = d.state_row[b];
    if (r0 < 0) continue;
    Vec3 shift = Vec3::Zero();
    if (b < far_.size() && far_[b]) {
      double mass = 0;
      for (int i = r0; i < r0 + d.bodies[b].vertices(); ++i)
        if (free_[i] >= 0) shift += d.mass(i) * (x.row(i) - xn_.row(i)).transpose(), mass += d.mass(i);
      if (mass > 0) shift /= mass;
    }
    for (int i = r0; i < r0 + d.bodies[b].vertices(); ++i)
      if (free_[i] >= 0) {
        const double m = (Vec3((x.row(i) - xn_.row(i)).transpose()) - shift).norm() / edge_scale_(i);
        if (m > worst) worst = m, worst_i = i;
      }
  }
  const bool halve = !(worst <= 2 * o_.motion_fraction) && depth < 8 && !(worst >= kJumpRatio * parent_worst);
  spdlog::debug("implicit substep t={:.5f} h={:.3g} depth {}: worst motion {:.3f} edge lengths{}, {} Newton, {} factorisations, "
                "{} CG, {} contact rounds, {} contacts; worst vertex {}",
                before.time, h, depth, worst, halve ? " (halved)" : "", stats_.iterations - at_start.iterations,
                stats_.factorizations - at_start.factorizations, stats_.cg_iterations - at_start.cg_iterations,
                stats_.contact_rounds - at_start.contact_rounds, contacts_.size(), worst_i);
  if (halve) {
    s = before;
    substep(w, s, ext, ws, h / 2, depth + 1, worst);
    substep(w, s, ext, ws, h / 2, depth + 1, worst);
    return;
  }
  for (int i = 0; i < d.rows; ++i) {
    if (free_[i] < 0) {
      s.v.row(i).setZero();
      continue;
    }
    s.v.row(i) = (x.row(i) - xn_.row(i)) / h;
    s.x.row(i) = x.row(i);
  }
  s.time += h;
  ++stats_.substeps;
  carried_ = contacts_;
  std::sort(carried_.begin(), carried_.end(), [](const LinearContact& a, const LinearContact& b) { return a.vertex < b.vertex; });
}

// Resting contact: a vertex that a contact held at the end of the last substep is usually found
// just outside (or at the rest-overlap tolerance of) the other object at x_n, so detection at x_n
// misses it, the solve lets it sink, a contact round finds it again and the Newton solve starts
// over. The last substep's contacts that detection at x_n did not renew are therefore kept, with
// their linearisation (the plane they were found on), while their depth at x_n is within
// kCarryMargin edge lengths of contact and their vertex has slid less than kCarryDrift edge lengths
// along the plane: the penalty ½ k max(0, d)² costs nothing while the vertex stays out, and holds
// it where it rests. Their damping acts only while they are active at x_n.
void ImplicitIntegrator::carry_contacts() {
  if (carried_.empty()) return;
  std::vector<int> fresh;  // the vertices detection at x_n found (their contacts are new)
  fresh.reserve(contacts_.size());
  for (const LinearContact& c : contacts_) fresh.push_back(c.vertex);
  std::sort(fresh.begin(), fresh.end());
  for (LinearContact c : carried_) {
    if (std::binary_search(fresh.begin(), fresh.end(), c.vertex)) continue;
    if (still_holds(c, xn_)) contacts_.push_back(c);
  }
}

// A carried contact still holds at X while its depth there is above −kCarryMargin edge lengths and
// its vertex has slid less than kCarryDrift edge lengths along its plane; its damping is switched
// off where it is not active at X.
bool ImplicitIntegrator::still_holds(LinearContact& c, const RowMatrixX3d& X) const {
  const double depth = c.c0 - stencil_dot(c, X);
  if (!(depth > -kCarryMargin * c.scale)) return false;
  Vec3 drift = Vec3::Zero();  // Σ_s w_s (x_s − at_s): the vertex's motion relative to the tet's point
  for (int k = 0; k < c.n; ++k)
    if (c.row[k] >= 0) drift += c.w[k] * (Vec3(X.row(c.row[k]).transpose()) - c.at[k]);
  if (!((drift - c.r * c.r.dot(drift)).norm() < kCarryDrift * c.scale)) return false;
  if (depth <= 0) c.c = 0;
  return true;
}

const LinearContact* ImplicitIntegrator::carried_for(int vertex) const {
  auto it = std::lower_bound(carried_.begin(), carried_.end(), vertex,
                             [](const LinearContact& c, int v) { return c.vertex < v; });
  return it != carried_.end() && it->vertex == vertex ? &*it : nullptr;
}

void ImplicitIntegrator::add_contacts(const World& w, const std::vector<Penetration>& pens, const RowMatrixX3d& x) {
  const WorldData& d = w.data();
  const WorldOptions& o = w.options();
  const int rows = d.rows;
  std::vector<char> have(static_cast<size_t>(d.X_rest_all.rows()), 0);
  for (const LinearContact& c : contacts_)
    if (c.vertex >= 0) have[c.vertex] = 1;
  for (const Penetration& p : pens) {
    if (!(p.depth > 0) || have[p.vertex]) continue;
    have[p.vertex] = 1;
    LinearContact c;
    const int g[5] = {p.vertex, d.T_all(p.tet, 0), d.T_all(p.tet, 1), d.T_all(p.tet, 2), d.T_all(p.tet, 3)};
    const double wg[5] = {1.0, -p.bary[0], -p.bary[1], -p.bary[2], -p.bary[3]};
    c.r = p.direction;
    // Coefficients as the explicit contact force takes them (World::contact_scale).
    if (!o.cap_contact_stiffness) {
      c.k = o.contact_stiffness;
      c.c = o.contact_damping;
    } else if (d.followed(p.vertex)) {
      c.k = d.contact_coefficient(p.vertex, d.contact_k);
      c.c = d.contact_coefficient(p.vertex, d.contact_c);
    } else {
      for (int k = 0; k < 4; ++k)
        if (d.followed(g[k + 1]))
          c.k += p.bary[k] * d.contact_coefficient(g[k + 1], d.contact_k),
              c.c += p.bary[k] * d.contact_coefficient(g[k + 1], d.contact_c);
    }
    // The stencil: as (p, the tet's corners), one slot each, without embedded meshes; else the
    // free rows they follow (coll_row, by coll_w), merged.
    if (!d.any_embedded) {
      c.n = 5;
      for (int s = 0; s < 5; ++s) {
        c.w[s] = wg[s];
        c.row[s] = g[s] < rows && free_[g[s]] >= 0 ? g[s] : -1;
      }
    } else {
      c.n = 0;
      for (int s = 0; s < 5; ++s)
        for (int k = d.coll_start[g[s]]; k < d.coll_start[g[s] + 1]; ++k) {
          const int row = d.coll_row[k];
          if (free_[row] < 0) continue;
          const double wk = wg[s] * d.coll_w[k];
          int t = 0;
          while (t < c.n && c.row[t] != row) ++t;
          if (t < c.n) {
            c.w[t] += wk;
          } else {
            c.row[c.n] = row;
            c.w[c.n++] = wk;
          }
        }
    }
    bool any_free = false;
    double q = 0;  // Σ w r·x over the free rows of the stencil, at the detection point
    for (int s = 0; s < c.n; ++s) {
      if (c.row[s] >= 0) {
        any_free = true;
        c.at[s] = x.row(c.row[s]).transpose();
        q += c.w[s] * c.r.dot(c.at[s]);
      }
    }
    if (!any_free) continue;
    for (int s = 0; s < c.n; ++s)
      if (c.row[s] >= 0) {
        c.scale = edge_scale_(c.row[s]);
        break;
      }
    c.c0 = p.depth + q;
    c.vertex = p.vertex;
    c.body = p.body;
    // Coherence: the last substep held this vertex out of the same object along a plane that still
    // holds (carry_contacts' limits), and detection now pushes it out the other way: the vertex is
    // inside a part of that object thinner than its depth estimates can tell apart, and the new
    // direction would push it through (a jump of the part's thickness at any h). The plane it came
    // in by is kept.
    if (const LinearContact* old = carried_for(p.vertex); old && old->body == p.body && old->r.dot(c.r) < 0) {
      LinearContact k = *old;
      if (still_holds(k, x)) c = k;
    }

    contacts_.push_back(c);
  }
}


void ImplicitIntegrator::add_floor_contacts(const World& w, const RowMatrixX3d& x) {
  const WorldData& d = w.data();
  const WorldOptions& o = w.options();
  if (!o.floor || !d.any_embedded) return;
  std::vector<int> have;
  for (const LinearContact& c : contacts_)
    if (c.vertex <= -2) have.push_back(-2 - c.vertex);
  std::sort(have.begin(), have.end());
  for (int g : d.embedded_vertices) {
    const double y = d.follow(g, x).y();
    if (!(y < o.floor_height) || std::binary_search(have.begin(), have.end(), g)) continue;
    LinearContact c;
    c.r = Vec3(0, 1, 0);
    c.n = 0;
    double q = 0;
    for (int k = d.coll_start[g]; k < d.coll_start[g + 1]; ++k) {
      const int row = d.coll_row[k];
      if (free_[row] < 0) continue;
      c.row[c.n] = row;
      c.w[c.n] = d.coll_w[k];
      c.at[c.n] = x.row(row).transpose();
      q += c.w[c.n] * c.at[c.n].y();
      ++c.n;
    }
    if (c.n == 0) continue;
    c.k = d.contact_coefficient(g, d.contact_k);
    c.c = d.contact_coefficient(g, d.contact_c);
    c.scale = edge_scale_(c.row[0]);
    c.c0 = (o.floor_height - y) + q;  // depth(x) = c0 − Σ w y over the free rows
    c.vertex = -2 - g;
    c.body = -1;
    contacts_.push_back(c);
  }
}

double ImplicitIntegrator::potential(const World& w, const RowMatrixX3d& x, double h) const {
  const WorldData& d = w.data();
  const WorldOptions& o = w.options();
  double G = 0;
  for (int i : free_rows_) G += 0.5 * d.mass(i) * (x.row(i) - y_.row(i)).squaredNorm() / (h * h);
  size_t e = 0, t = 0;
#if defined(__SSE2__)
  // Two elements at a time (constraints.h, bit for bit the scalar terms below), summed in order.
  auto add_pair = [&G](__m128d energy, __m128d damping, double kd0, double kd1) {
    G += _mm_cvtsd_f64(energy);
    if (kd0 > 0) G += _mm_cvtsd_f64(damping);
    G += _mm_cvtsd_f64(_mm_unpackhi_pd(energy, energy));
    if (kd1 > 0) G += _mm_cvtsd_f64(_mm_unpackhi_pd(damping, damping));
  };
  for (; e + 1 < d.edges.size(); e += 2) {
    __m128d energy, damping;
    edge_potential_pair(x.data(), xn_.data(), d.edges[e], d.edges[e + 1], h, edge_g_[e].data(), edge_g_[e + 1].data(),
                        energy, damping);
    add_pair(energy, damping, d.edges[e].kd, d.edges[e + 1].kd);
  }
#endif
  for (; e < d.edges.size(); ++e) {
    const auto& E = d.edges[e];
    const Vec3 xi = x.row(E.i).transpose(), xj = x.row(E.j).transpose();
    G += distance_energy(xi, xj, E.D0, E.k);
    if (E.kd > 0) {
      const double q = edge_g_[e].dot((xj - Vec3(xn_.row(E.j).transpose())) - (xi - Vec3(xn_.row(E.i).transpose())));
      G += 0.5 * E.kd / h * q * q;
    }
  }
#if defined(__SSE2__)
  for (; t + 1 < d.tet_elems.size(); t += 2) {
    __m128d energy, damping;
    tet_potential_pair(x.data(), xn_.data(), d.tet_elems[t], d.tet_elems[t + 1], h, tet_g_[t][0].data(),
                       tet_g_[t + 1][0].data(), energy, damping);
    add_pair(energy, damping, d.tet_elems[t].kd, d.tet_elems[t + 1].kd);
  }
#endif
  for (; t < d.tet_elems.size(); ++t) {
    const auto& T = d.tet_elems[t];
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = x.row(T.v[k]).transpose();
    G += volume_energy(p[0], p[1], p[2], p[3], T.V0, T.k);
    if (T.kd > 0) {
      double q = 0;
      for (int k = 0; k < 4; ++k) q += tet_g_[t][k].dot(p[k] - Vec3(xn_.row(T.v[k]).transpose()));
      G += 0.5 * T.kd / h * q * q;
    }
  }
  for (const LinearContact& c : contacts_) {
    const double depth = c.c0 - stencil_dot(c, x);
    if (depth > 0) G += 0.5 * c.k * depth * depth;
    const double q = stencil_dot(c, x) - stencil_dot(c, xn_);
    G += 0.5 * c.c / h * q * q;
  }
  if (o.floor)
    for (int i : free_rows_) {
      if (!d.floor_row[i]) continue;  // held through its embedded mesh (add_floor_contacts)
      const double pen = o.floor_height - x(i, 1);
      if (pen > 0) G += 0.5 * d.contact_k(i) * pen * pen;
      if (floor_damped_[i]) {
        const double dy = std::min(0.0, x(i, 1) - xn_(i, 1));
        G += 0.5 * d.contact_c(i) / h * dy * dy;
      }
    }
  if (d.any_attached)  // soft attachments: ½ k |x − x_rest|² + ½ (c / h) |x − x_n|²
    for (int i : free_rows_) {
      const double k = d.attach_k(i), c = d.attach_c(i);
      if (k > 0) G += 0.5 * k * (x.row(i) - d.attach_anchor.row(i)).squaredNorm();
      if (c > 0) G += 0.5 * c / h * (x.row(i) - xn_.row(i)).squaredNorm();
    }
  return G;
}

void ImplicitIntegrator::energy_gradient(const World& w, const RowMatrixX3d& x, double h, bool damping,
                                         RowMatrixX3d& Gr) const {
  const WorldData& d = w.data();
  const WorldOptions& o = w.options();
  Gr.setZero(d.rows, 3);
  auto add = [&](int row, const Vec3& v) { Gr.row(row) += v.transpose(); };
  size_t e = 0, t = 0;
#if defined(__SSE2__)
  // Two elements at a time (constraints.h, bit for bit the scalar terms below), added in order.
  double* const gr = Gr.data();
  auto add_lane = [gr](int row, const simd::Pair3& f, int lane, bool negate) {
    for (int c = 0; c < 3; ++c) {
      const __m128d v = c == 0 ? f.x : c == 1 ? f.y : f.z;
      const double value = _mm_cvtsd_f64(lane ? _mm_unpackhi_pd(v, v) : v);
      gr[3 * row + c] += negate ? -value : value;
    }
  };
  // (The damping gradients exist once a substep has begun: substeps_for asks without damping
  // before the first, when edge_g_ and tet_g_ are still empty; the kernels read them only with it.)
  for (; e + 1 < d.edges.size(); e += 2) {
    const simd::Pair3 f = edge_gradient_pair(x.data(), xn_.data(), d.edges[e], d.edges[e + 1], h, damping,
                                             damping ? edge_g_[e].data() : nullptr, damping ? edge_g_[e + 1].data() : nullptr);
    for (int lane = 0; lane < 2; ++lane) {
      add_lane(d.edges[e + lane].j, f, lane, false);
      add_lane(d.edges[e + lane].i, f, lane, true);
    }
  }
  for (; t + 1 < d.tet_elems.size(); t += 2) {
    simd::Pair3 f[4];
    tet_gradient_pair(x.data(), xn_.data(), d.tet_elems[t], d.tet_elems[t + 1], h, damping,
                      damping ? tet_g_[t][0].data() : nullptr, damping ? tet_g_[t + 1][0].data() : nullptr, f);
    for (int lane = 0; lane < 2; ++lane)
      for (int k = 0; k < 4; ++k) add_lane(d.tet_elems[t + lane].v[k], f[k], lane, false);
  }
#endif
  for (; e < d.edges.size(); ++e) {
    const auto& E = d.edges[e];
    const Vec3 xi = x.row(E.i).transpose(), xj = x.row(E.j).transpose();
    Vec3 gj;
    const double C = distance_constraint(xi, xj, E.D0, &gj);
    Vec3 f = E.k * C * gj;  // ∂E/∂x_j; ∂E/∂x_i = −f
    if (damping && E.kd > 0) {
      const double q = edge_g_[e].dot((xj - Vec3(xn_.row(E.j).transpose())) - (xi - Vec3(xn_.row(E.i).transpose())));
      f += (E.kd / h * q) * edge_g_[e];
    }
    add(E.j, f);
    add(E.i, -f);
  }
  for (; t < d.tet_elems.size(); ++t) {
    const auto& T = d.tet_elems[t];
    Vec3 p[4], gk[4];
    for (int k = 0; k < 4; ++k) p[k] = x.row(T.v[k]).transpose();
    const double C = volume_constraint(p[0], p[1], p[2], p[3], T.V0, gk);
    double q = 0;
    if (damping && T.kd > 0)
      for (int k = 0; k < 4; ++k) q += tet_g_[t][k].dot(p[k] - Vec3(xn_.row(T.v[k]).transpose()));
    if (damping)
      for (int k = 0; k < 4; ++k) add(T.v[k], T.k * C * gk[k] + (T.kd / h * q) * tet_g_[t][k]);
    else
      for (int k = 0; k < 4; ++k) add(T.v[k], T.k * C * gk[k]);
  }
  for (const LinearContact& c : contacts_) {
    const double depth = c.c0 - stencil_dot(c, x);
    // ∂/∂x_s of ½k d² = −k d w_s r; of ½(c/h) q² = (c/h) q w_s r.
    double a = depth > 0 ? -c.k * depth : 0.0;
    if (damping) a += c.c / h * (stencil_dot(c, x) - stencil_dot(c, xn_));
    if (a != 0)
      for (int s = 0; s < c.n; ++s)
        if (c.row[s] >= 0) add(c.row[s], (a * c.w[s]) * c.r);
  }
  for (int i : free_rows_) {
    if (o.floor && d.floor_row[i]) {
      const double pen = o.floor_height - x(i, 1);
      if (pen > 0) Gr(i, 1) -= d.contact_k(i) * pen;
      if (damping && floor_damped_[i]) Gr(i, 1) += d.contact_c(i) / h * std::min(0.0, x(i, 1) - xn_(i, 1));
    }
    if (d.any_attached) {
      if (d.attach_k(i) > 0) Gr.row(i) += d.attach_k(i) * (x.row(i) - d.attach_anchor.row(i));
      if (damping && d.attach_c(i) > 0) Gr.row(i) += d.attach_c(i) / h * (x.row(i) - xn_.row(i));
    }
  }
}

void ImplicitIntegrator::gradient(const World& w, const RowMatrixX3d& x, double h, Eigen::VectorXd& g) {
  const WorldData& d = w.data();
  energy_gradient(w, x, h, true, Gr_);
  g.resize(3 * static_cast<Eigen::Index>(free_rows_.size()));
  for (size_t f = 0; f < free_rows_.size(); ++f) {
    const int i = free_rows_[f];
    g.segment<3>(3 * static_cast<Eigen::Index>(f)) =
        Gr_.row(i).transpose() + d.mass(i) / (h * h) * Vec3((x.row(i) - y_.row(i)).transpose());
  }
}

void ImplicitIntegrator::build_pattern(const World& w) {
  const WorldData& d = w.data();
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(d.edges.size() + 10 * contacts_.size());  // (more where meshes are embedded)
  auto pair = [&](int ri, int rj) {
    const int a = ri >= 0 ? free_[ri] : -1, b = rj >= 0 ? free_[rj] : -1;
    if (a < 0 || b < 0 || a == b) return;
    pairs.emplace_back(std::max(a, b), std::min(a, b));
  };
  for (const auto& E : d.edges) pair(E.i, E.j);  // every pair of a tet's corners is an edge
  for (const LinearContact& c : contacts_)
    for (int s = 0; s < c.n; ++s)
      for (int t = s + 1; t < c.n; ++t) pair(c.row[s], c.row[t]);
  const bool changed = H_.build(static_cast<int>(free_rows_.size()), std::move(pairs));
  if (changed) analysed_ = false;
  // Each element pair's block: (row vertex b, column vertex a) for a < b.
  auto code = [&](int ra, int rb) {
    const int A = ra >= 0 ? free_[ra] : -1, B = rb >= 0 ? free_[rb] : -1;
    if (A < 0 || B < 0 || A == B) return -1;
    return B > A ? 2 * H_.find(B, A) : 2 * H_.find(A, B) + 1;
  };
  if (changed || edge_block_.size() != d.edges.size()) {
    edge_block_.resize(d.edges.size());
    for (size_t e = 0; e < d.edges.size(); ++e) edge_block_[e] = code(d.edges[e].i, d.edges[e].j);
    tet_block_.resize(d.tet_elems.size());
    for (size_t t = 0; t < d.tet_elems.size(); ++t) {
      int q = 0;
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) tet_block_[t][q++] = code(d.tet_elems[t].v[a], d.tet_elems[t].v[b]);
    }
  }
  contact_block_.clear();
  contact_block_start_.assign(1, 0);
  for (const LinearContact& c : contacts_) {
    for (int a = 0; a < c.n; ++a)
      for (int b = a + 1; b < c.n; ++b) contact_block_.push_back(code(c.row[a], c.row[b]));
    contact_block_start_.push_back(static_cast<int>(contact_block_.size()));
  }
}

// Elements' Newton blocks at x, two at a time (constraints.h, the SSE2 pair kernels: bit for bit
// the scalar edge_newton_block and tet_newton_blocks). The assembly in one part computes all of
// them on the calling thread below WorldOptions::parallel.assembly_tets tetrahedra, else in
// parallel; each of two parts computes its own on its own thread. With the pair
// kernels a block costs half what it did, and two TBB tasks per Newton iteration cost more than
// they save on small meshes, the more so while another process keeps the second core busy
// (bench_integrators, implicit, load 2.3–2.7, simulated s per wall s on the calling thread /
// parallel: the ball, 473 tetrahedra, 16.0–16.9 / 12.4–15.4; the bunny, 1,914, 3.17–3.21 /
// 3.13–3.17; balls of 1,135, 6,216 and 24,066 tetrahedra 6.46 / 5.87, 0.251 / 0.207, 5.43 / 6.22;
// the threshold was 256 before).
void ImplicitIntegrator::element_blocks(const World& w, const RowMatrixX3d& x, double h, bool exact, const int* edge_ids,
                                        size_t ne, Mat3* eH, const int* tet_ids, size_t nt, std::array<Mat3, 10>* tH,
                                        bool parallel) {
  const WorldData& d = w.data();
  const double* const X = x.data();
  // Element a of the list: ids[a], or a itself (two instantiations of each loop: the indirection
  // cost the one-body assembly 1.5 M instructions over the ball's second).
  auto listed = [](const int* ids) { return [ids](size_t a) { return static_cast<size_t>(ids[a]); }; };
  auto all = [](size_t a) { return a; };
  auto edges_of = [&](auto edge, size_t a, size_t end) {
#if defined(__SSE2__)
    for (; a + 1 < end; a += 2) {
      const size_t e0 = edge(a), e1 = edge(a + 1);
      if (!edge_newton_block_pair(X, d.edges[e0], d.edges[e1], !exact, h, edge_g_[e0].data(), edge_g_[e1].data(),
                                  eH[a].data(), eH[a + 1].data()))
        break;  // a zero-length edge: the scalar function from here on
    }
#endif
    for (; a < end; ++a) {
      const size_t e = edge(a);
      const auto& E = d.edges[e];
      eH[a] = edge_newton_block(Vec3(x.row(E.i).transpose()), Vec3(x.row(E.j).transpose()), E.D0, E.k, !exact, E.kd, h,
                                edge_g_[e]);
    }
  };
  auto tets_of = [&](auto tet, size_t a, size_t end) {
#if defined(__SSE2__)
    for (; a + 1 < end; a += 2) {
      const size_t t0 = tet(a), t1 = tet(a + 1);
      tet_newton_blocks_pair(X, d.tet_elems[t0], d.tet_elems[t1], exact, h, tet_g_[t0][0].data(), tet_g_[t1][0].data(),
                             tH[a][0].data(), tH[a + 1][0].data());
    }
#endif
    for (; a < end; ++a) {
      const size_t t = tet(a);
      const auto& T = d.tet_elems[t];
      Vec3 p[4];
      for (int k = 0; k < 4; ++k) p[k] = x.row(T.v[k]).transpose();
      tet_newton_blocks(p, T.V0, T.k, exact, T.kd, h, tet_g_[t].data(), tH[a].data(), tH[a].data() + 4);
    }
  };
  auto edges = [&](size_t a, size_t end) {
    if (edge_ids)
      edges_of(listed(edge_ids), a, end);
    else
      edges_of(all, a, end);
  };
  auto tets = [&](size_t a, size_t end) {
    if (tet_ids)
      tets_of(listed(tet_ids), a, end);
    else
      tets_of(all, a, end);
  };
  if (!parallel) {
    edges(0, ne);
    tets(0, nt);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ne, 1024), [&](const tbb::blocked_range<size_t>& r) { edges(r.begin(), r.end()); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nt, 256), [&](const tbb::blocked_range<size_t>& r) { tets(r.begin(), r.end()); });
}

void ImplicitIntegrator::assemble(const World& w, const RowMatrixX3d& x, double h, bool exact) {
  const WorldData& d = w.data();
  const WorldOptions& o = w.options();
  H_.zero();
  // The inertia, floor, attachment and element blocks are assembled in parts (part −1: all rows).
  // A block belongs to the part of its row (the larger free index of an off-diagonal block); an
  // element with rows in both parts is evaluated by both, each adding its own blocks. Every block
  // receives its terms in the same order whatever the parts: bit for bit the sequential sum, on
  // one thread or two. mine: a free row (−1: fixed) of the part; mine_off: an off-diagonal block
  // (its code, −1: none) of the part.
  const int split = assembly_split_;
  const auto& pairs = H_.pairs();
  auto mine = [&](int part, int f) { return f >= 0 && (part < 0 || (f >= split) == (part == 1)); };
  auto mine_off = [&](int part, int c) {
    return c >= 0 && (part < 0 || (pairs[static_cast<size_t>(c >> 1)].first >= split) == (part == 1));
  };
  // An element's symmetric block matrix over its n vertices, the blocks of one part: diagonal
  // blocks to the free vertices, the block (b, a), a < b, of each pair through its precomputed code.
  auto scatter = [&](int part, int n, const int* rows, const int* codes, auto&& block) {
    int q = 0;
    for (int a = 0; a < n; ++a) {
      const int A = rows[a] >= 0 ? free_[rows[a]] : -1;  // −1: a fixed vertex (rigid or pinned)
      if (mine(part, A)) H_.add_diag(A, block(a, a));
      for (int b = a + 1; b < n; ++b, ++q) {
        const int c = codes[q];
        if (!mine_off(part, c)) continue;
        if (c & 1)
          H_.add_off(c >> 1, block(b, a).transpose());
        else
          H_.add_off(c >> 1, block(b, a));
      }
    }
  };
  auto assemble_part = [&](int part) {
    for (size_t f = 0; f < free_rows_.size(); ++f) {
      if (!mine(part, static_cast<int>(f))) continue;
      const int i = free_rows_[f];
      Mat3 M = (d.mass(i) / (h * h)) * Mat3::Identity();
      if (o.floor && d.floor_row[i]) {
        if (x(i, 1) < o.floor_height) M(1, 1) += d.contact_k(i);
        if (floor_damped_[i] && x(i, 1) < xn_(i, 1)) M(1, 1) += d.contact_c(i) / h;
      }
      if (d.any_attached) M.diagonal().array() += d.attach_k(i) + d.attach_c(i) / h;  // soft attachment
      H_.add_diag(static_cast<int>(f), M);
    }
    if (part < 0) {  // all the blocks computed first (element_blocks), then summed in order
      for (size_t e = 0; e < d.edges.size(); ++e) {
        const auto& E = d.edges[e];
        const int A = free_[E.i], B = free_[E.j], c = edge_block_[e];
        const Mat3& He = edge_H_[e];  // the edge's blocks: He on the diagonal, −He (its transpose) off it
        if (A >= 0) H_.add_diag(A, He);
        if (B >= 0) H_.add_diag(B, He);
        if (c >= 0) H_.subtract_off(c >> 1, He, c & 1);
      }
      for (size_t t = 0; t < d.tet_elems.size(); ++t) {
        const auto& T = d.tet_elems[t];
        const Mat3* Hd = tet_H_[t].data();
        const Mat3* Hl = Hd + 4;  // in pair order, as the codes
        for (int k = 0; k < 4; ++k)
          if (free_[T.v[k]] >= 0) H_.add_diag(free_[T.v[k]], Hd[k]);
        for (int q = 0; q < 6; ++q)
          if (const int c = tet_block_[t][q]; c >= 0) H_.add_off(c >> 1, Hl[q], c & 1);
      }
      return;
    }
    // One of two parts: its elements' blocks first (into its own buffers), then summed in order.
    const std::vector<int>& pe = part_edges_[part];
    const std::vector<int>& pt = part_tets_[part];
    part_edge_H_[part].resize(pe.size());
    part_tet_H_[part].resize(pt.size());
    element_blocks(w, x, h, exact, pe.data(), pe.size(), part_edge_H_[part].data(), pt.data(), pt.size(),
                   part_tet_H_[part].data(), false);
    for (size_t a = 0; a < pe.size(); ++a) {
      const auto& E = d.edges[static_cast<size_t>(pe[a])];
      const Mat3& He = part_edge_H_[part][a];
      const int rows[2] = {E.i, E.j};
      scatter(part, 2, rows, &edge_block_[static_cast<size_t>(pe[a])], [&](int i, int j) -> Mat3 { return i == j ? He : Mat3(-He); });
    }
    for (size_t a = 0; a < pt.size(); ++a) {
      const size_t t = static_cast<size_t>(pt[a]);
      const Mat3* Hd = part_tet_H_[part][a].data();
      const Mat3* Hl = Hd + 4;  // block (b, a), a < b, at the pair's index a (7 − a) / 2 + b − a − 1
      scatter(part, 4, d.tet_elems[t].v, tet_block_[t].data(),
              [&](int j, int i) -> const Mat3& { return i == j ? Hd[i] : Hl[i * (7 - i) / 2 + j - i - 1]; });
    }
  };
  if (split > 0) {
    tbb::parallel_invoke([&] { assemble_part(0); }, [&] { assemble_part(1); });
  } else {
    edge_H_.resize(d.edges.size());
    tet_H_.resize(d.tet_elems.size());
    element_blocks(w, x, h, exact, nullptr, d.edges.size(), edge_H_.data(), nullptr, d.tet_elems.size(), tet_H_.data(),
                   d.tet_elems.size() >= static_cast<size_t>(o.parallel.assembly_tets));
    assemble_part(-1);
  }
  for (size_t k = 0; k < contacts_.size(); ++k) {
    const LinearContact& c = contacts_[k];
    const double depth = c.c0 - stencil_dot(c, x);
    const double kc = (depth > -kCurvatureBand * c.scale ? c.k : 0.0) + c.c / h;
    if (!(kc > 0)) continue;
    const Mat3 rr = c.r * c.r.transpose();
    scatter(-1, c.n, c.row, contact_block_.data() + contact_block_start_[k], [&](int a, int b) -> Mat3 { return (kc * c.w[a] * c.w[b]) * rr; });
  }
}

bool ImplicitIntegrator::factorize(double h) {
  if (!analysed_) {
    ldlt_.analyze(H_.blocks(), H_.pairs());
    analysed_ = true;
    // A factorisation's 3×3 block products (27 multiply-adds each) against one CG iteration's
    // block-vector products (9 each: a solve with L and Lᵀ, the product with H).
    const double iteration = 2.0 * static_cast<double>(ldlt_.factor_blocks()) + 2.0 * static_cast<double>(H_.pairs().size()) + H_.blocks();
    factor_cost_ = 3.0 * static_cast<double>(ldlt_.factor_updates()) / std::max(1.0, iteration);
  }
  const bool ok = ldlt_.factorize(H_.diag(), H_.off());
  ++stats_.factorizations;
  factor_h_ = ok ? h : 0.0;
  return factor_h_ > 0;
}

// Newton's direction dx = −H⁻¹ g with the exact Hessian H at x: by conjugate gradients
// preconditioned by the last factorisation (of an earlier Hessian with the same h) while they
// converge within a few iterations; else by factorising H (which becomes the preconditioner).
// Where H is not positive definite (negative curvature, or no descent), with the positive
// semi-definite Hessian instead. Returns false if no descent direction was found.
bool ImplicitIntegrator::newton_direction(const World& w, const RowMatrixX3d& x, double h, const Eigen::VectorXd& g,
                                          Eigen::VectorXd& dx) {
  const int kMaxCg = o_.max_cg_iterations;
  const double kCgTolerance = o_.cg_tolerance;
  for (int exact = 1; exact >= 0; --exact) {
    assemble(w, x, h, exact == 1);
    if (factor_h_ == h) {
      // PCG from dx = 0.
      const int n = static_cast<int>(g.size());
      dx.setZero(n);
      r_ = -g;
      ldlt_.precondition(r_, z_);
      p_ = z_;
      double rz = r_.dot(z_);
      const double stop = kCgTolerance * g.norm();
      bool negative = false, done = false;
      for (int it = 0; it < kMaxCg && !done; ++it) {
        ++stats_.cg_iterations;
        H_.multiply(p_, Hp_);
        const double pHp = p_.dot(Hp_);
        if (!(pHp > 0)) {
          negative = true;
          break;
        }
        const double a = rz / pHp;
        dx += a * p_;
        r_ -= a * Hp_;
        if (r_.norm() <= stop) {
          done = true;
          break;
        }
        ldlt_.precondition(r_, z_);
        const double rz1 = r_.dot(z_);
        p_ = z_ + (rz1 / rz) * p_;
        rz = rz1;
      }
      if (negative) continue;  // indefinite: the positive semi-definite Hessian
      // Inexact Newton: a direction that reduced the residual to inexact_cg_tolerance will do
      // rather than a new factorisation.
      if (!done && !negative && factor_cost_ >= kInexactFactorCost && r_.norm() <= o_.inexact_cg_tolerance * g.norm())
        done = true;
      if (done && dx.allFinite() && g.dot(dx) < 0) return true;
    }
    if (!factorize(h)) continue;
    r_ = -g;
    ldlt_.solve(r_, dx);
    if (dx.allFinite() && g.dot(dx) < 0) return true;
    factor_h_ = 0;  // an indefinite factorisation is no preconditioner
  }
  return false;
}

void ImplicitIntegrator::solve(const World& w, double h, RowMatrixX3d& x, double G_x) {
  if (free_rows_.empty()) return;
  build_pattern(w);
  const WorldData& d = w.data();
  Eigen::VectorXd g, dx;
  RowMatrixX3d trial;
  const double tol = o_.tolerance;
  // The largest |v_f| / edge scale over the free vertices of a per-vertex vector v (3 per vertex).
  auto largest = [&](const Eigen::VectorXd& v, bool force) {
    double m = 0;
    for (size_t f = 0; f < free_rows_.size(); ++f) {
      const int i = free_rows_[f];
      double n = v.segment<3>(3 * static_cast<Eigen::Index>(f)).norm() / edge_scale_(i);
      if (force) n *= h * h / d.mass(i);  // a force → the displacement it causes within a step
      m = std::max(m, n);
    }
    return m;
  };
  bool converged = false;
  double previous_full_step = 0;  // the last Newton step (edge lengths) if the line search took it whole, else 0
  double Gx = G_x;                   // G(x)
  bool have_Gx = !std::isnan(G_x);  // Gx is known
  for (int it = 0; it < o_.max_newton_iterations; ++it) {
    gradient(w, x, h, g);
    // Converged when the residual force would move no vertex by tolerance × its edge scale.
    if (largest(g, true) < tol) {
      converged = true;
      break;
    }
    ++stats_.iterations;
    // Newton's direction with the exact Hessian, where it is a descent direction; else with the
    // positive semi-definite Hessian (distance_hessian psd, volume_hessian_gn).
    const bool ok = newton_direction(w, x, h, g, dx);
    if (!ok) break;
    const double step = largest(dx, false);
    // Backtracking line search on G (Armijo). G at x is the last accepted trial's.
    if (!have_Gx) Gx = potential(w, x, h);
    const double G0 = Gx, slope = g.dot(dx);
    double alpha = 1;
    for (int ls = 0; ls < 30; ++ls) {
      trial = x;
      for (size_t f = 0; f < free_rows_.size(); ++f)
        trial.row(free_rows_[f]) += alpha * dx.segment<3>(3 * static_cast<Eigen::Index>(f)).transpose();
      Gx = potential(w, trial, h);
      if (Gx <= G0 + 1e-4 * alpha * slope) break;
      alpha *= 0.5;
    }
    have_Gx = true;
    x.swap(trial);
    if (alpha * step < tol) {
      converged = true;
      break;
    }
    // Quadratic convergence: two full Newton steps in a row, the second at most a quarter of the
    // first, predict the next one as step³ / previous² (e_{k+1} ≈ C e_k², C ≈ e_k / e_{k−1}²); below
    // the tolerance, the next iteration (gradient, Hessian, linear solve) would only confirm it.
    if (alpha == 1 && previous_full_step > 0 && step <= 0.25 * previous_full_step &&
        step * step * step < tol * previous_full_step * previous_full_step) {
      converged = true;
      break;
    }
    previous_full_step = alpha == 1 ? step : 0.0;
  }
  if (!converged) ++stats_.not_converged;
}

}  // namespace

std::unique_ptr<TimeIntegrator> make_implicit_integrator(const ImplicitOptions& o) {
  if (o.max_newton_iterations < 1) throw InputError("implicit integrator: max_newton_iterations must be >= 1");
  if (!(o.tolerance > 0)) throw InputError("implicit integrator: tolerance must be > 0");
  if (!(o.motion_fraction > 0)) throw InputError("implicit integrator: motion_fraction must be > 0");
  if (o.max_substeps < 1) throw InputError("implicit integrator: max_substeps must be >= 1");
  if (o.contact_rounds < 0) throw InputError("implicit integrator: contact_rounds must be >= 0");
  if (o.max_cg_iterations < 0) throw InputError("implicit integrator: max_cg_iterations must be >= 0");
  if (!(o.cg_tolerance > 0 && o.cg_tolerance < 1)) throw InputError("implicit integrator: cg_tolerance must be in (0, 1)");
  if (!(o.inexact_cg_tolerance >= 0 && o.inexact_cg_tolerance < 1))
    throw InputError("implicit integrator: inexact_cg_tolerance must be in [0, 1)");
  return std::make_unique<ImplicitIntegrator>(o);
}

std::unique_ptr<TimeIntegrator> make_implicit_integrator() { return make_implicit_integrator(ImplicitOptions{}); }

}  // namespace squeeze::fem
