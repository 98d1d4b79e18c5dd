// squeeze::fem — a world of deformable and rigid objects and its time step.
//
// Model: Rodriguez, Lien, Amato, ICRA 2006, Section IV (constraint forces of Teschner et al.
// 2004, Verlet integration, spatial-hash collision detection, consistent penetration depth
// response); see constraints.h and collision.h for the sources.
//
// Integration (Verlet with a fixed step h; Teschner 2004, Sec. 4):
//   x_{n+1} = 2 x_n − x_{n−1} + h² a_n,  carried as  v_{n+1} = v_n + h a_n,  x_{n+1} = x_n + h v_{n+1}
// so the state holds x_n and v_n = (x_n − x_{n−1}) / h. a_n = F(x_n, v_n) / m with
//   F = Σ distance and volume constraint forces (elastic + damping) + m g + external forces
//       + contact penalty forces k_c d r − c_c (v·r) r of every colliding vertex (Heidelberger 2004)
//       + floor penalty forces when the floor is enabled.
// Pinned vertices never move. Rigid objects never move; a rigid vertex inside a deformable
// tetrahedron pushes back on that tetrahedron's vertices (−k_c d r spread by barycentric weights).
//
// Determinism: every force is summed per vertex from per-group results in a fixed order, the
// collision lists are concatenated in tetrahedron order, and the contact forces are summed in a
// fixed order: the same state and forces give bit-identical results whatever the number of TBB
// threads.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "squeeze/fem/body.h"
#include "squeeze/fem/collision.h"

namespace squeeze::fem {

struct WorldOptions {
  double h = 1e-3;                                 // s, fixed time step
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};        // m/s²
  bool floor = false;                              // enables the half-space y >= floor_height
  double floor_height = 0.0;                       // m
  bool collisions = true;                          // detect and answer collisions between objects
  bool self_collision = true;                      // ... and within a deformable object
  double contact_stiffness = 1e5;                  // N/m, k_c of the penalty force k_c·d·r (also the floor)
  double contact_damping = 0.0;                    // N·s/m, along r, only while penetrating (also the floor)
  // true: vertex i of object b gets the contact coefficients times min(1, m_i ω_b² / k_c), ω_b² =
  // the largest of b's vertex_frequency_bounds (body.h; the object's highest elastic frequency):
  // a light vertex (small tets) is never made stiffer by contact than the stiffest
  // vertex of its object is by elasticity, so contact does not set the stable step (the contact
  // damping ratio is kept). Vertices of coarse meshes keep k_c. A rigid vertex inside a
  // deformable tet uses Σ bary_k · factor_k of the tet's corners. false: k_c and c_c everywhere.
  bool cap_contact_stiffness = false;
  double cell_size = 0.0;                          // m, spatial hash cell; 0: mean edge length of the deformable objects
  int table_size = 0;                              // spatial hash entries; 0: a prime >= 4 × vertex count
};

/// Positions and velocities of every vertex of every deformable object, object after object in
/// the order they were added (World::first_state_row). A plain value: copy it to save, assign to
/// restore. Rigid objects are not part of it.
struct State {
  RowMatrixX3d x;     // #N by 3 positions (m)
  RowMatrixX3d v;     // #N by 3 velocities (m/s), (x_n − x_{n−1}) / h
  double time = 0.0;  // s
};

/// What the last step() found.
struct StepStats {
  int contacts = 0;            // (vertex, tet) pairs found by the spatial hash
  int colliding_vertices = 0;  // vertices given a penetration depth
  double max_depth = 0.0;      // m
};

class World {
 public:
  /// Throws InputError if h <= 0, or a contact coefficient is negative.
  explicit World(const WorldOptions& options = {});
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  /// Adds an object; returns its index. States made before no longer fit (step() throws on them).
  int add_body(Body body);
  /// Pins every vertex of every deformable object whose rest position lies in box (m). Returns
  /// how many vertices are pinned now in total.
  int pin(const Eigen::AlignedBox3d& box);
  /// Pins one vertex (row of the state). Throws InputError if out of range.
  void pin_vertex(int row);

  const WorldOptions& options() const { return options_; }
  int bodies() const { return static_cast<int>(bodies_.size()); }
  const Body& body(int b) const { return bodies_[b]; }
  /// First state row of object b, or -1 for a rigid object.
  int first_state_row(int b) const { return state_row_[b]; }
  int state_rows() const { return rows_; }
  int tets() const;  // all objects
  bool pinned(int row) const { return pinned_[row] != 0; }
  const Eigen::VectorXd& masses() const { return mass_; }  // #N kg per state row
  /// Factor (<= 1) of the contact coefficients of a state row: see WorldOptions::cap_contact_stiffness.
  double contact_scale(int row) const { return contact_scale_(row); }

  /// Rest positions, zero velocities, time 0.
  State initial_state() const;

  /// Advances s by one step h. external: #N by 3 forces (N) per state row, or null. Objects with
  /// Material::deformation_damping > 0 first get their deformation velocities damped (exactly,
  /// see body.h); then the forces of total_forces() and the Verlet update.
  /// Throws InputError if s or external has the wrong number of rows.
  void step(State& s, const RowMatrixX3d* external = nullptr);

  /// Internal constraint forces only (elastic + damping), #N by 3 (N); no gravity, contact, floor.
  void internal_forces(const State& s, RowMatrixX3d& F) const;
  /// Every force of the next step (internal, gravity, external, floor, contacts), #N by 3 (N).
  void total_forces(const State& s, const RowMatrixX3d* external, RowMatrixX3d& F);

  double elastic_energy(const State& s) const;   // J, Σ ½ k C² over all constraints
  double kinetic_energy(const State& s) const;   // J, ½ Σ m v²
  double gravity_energy(const State& s) const;   // J, −Σ m g·x
  /// Volume (m³) of deformable object b in state s.
  double body_volume(const State& s, int b) const;
  const StepStats& last_stats() const { return stats_; }

 private:
  void prepare();  // global numbering, hash
  void build_element_groups();  // edges_, tet_elems_, groups_, acc_, gather_ (prepare)
  void add_contact_forces(const State& s, RowMatrixX3d& F);
  void damp_deformation(State& s) const;  // Material::deformation_damping, per object, fixed order

  WorldOptions options_;
  std::vector<Body> bodies_;
  std::vector<int> state_row_;   // per body, -1 if rigid
  int rows_ = 0;
  Eigen::VectorXd mass_;         // per state row
  Eigen::VectorXd inv_mass_;     // per state row, 0 for pinned or massless vertices
  Eigen::VectorXd contact_scale_;  // per state row, see contact_scale()
  Eigen::VectorXd contact_k_, contact_c_;  // per state row: contact stiffness and damping (contact_scale applied)
  RowMatrixX3d force_;           // step scratch
  std::vector<char> pinned_;     // per state row
  // Collision numbering: all vertices (deformables in state order, then rigid), all tets.
  bool prepared_ = false;
  CollisionScene scene_;
  CollisionFilter filter_;
  Eigen::MatrixX4i T_all_;
  RowMatrixX3d X_all_;
  std::unique_ptr<SpatialHash> hash_;
  // Elements of all deformable objects in groups, for the force pass. A group is the edges and
  // tets owned by a cluster of 128 vertices (kClusterRows, world.cpp) of one object, neighbours in
  // space (consecutive in the Morton order of the rest positions; an element belongs to the
  // cluster of its corner first in that order). A group adds its elements' forces, element after
  // element, into its own accumulator slots, one per vertex it touches; a row's force is then
  // the sum of its slots, group after group. Fixed groups, fixed orders: the sums do not depend on
  // the threads, and a row is summed from 1–2 slots instead of ~24 element results, so little
  // data crosses between the cores (docs/fem.md, Determinism).
  struct EdgeElem { int i, j; double D0, k, kd; int si, sj; };  // rows; slots (offsets in doubles into acc_)
  struct TetElem { int v[4]; double V0, k, kd; int s[4]; };
  struct ElemGroup { int e0, e1, t0, t1, a0, a1; };  // edges [e0, e1), tets [t0, t1), slots acc_[a0, a1)
  std::vector<EdgeElem> edges_;
  std::vector<TetElem> tet_elems_;
  std::vector<ElemGroup> groups_;
  mutable std::vector<double> acc_;  // the groups' accumulator slots, 3 doubles each
  // Per state row: its slots, group order: gather_[gather_start_[r] .. gather_start_[r + 1]),
  // offsets in doubles into acc_.
  std::vector<int> gather_start_, gather_;
  void element_forces(const State& s) const;        // fills acc_ (parallel over groups)
  Eigen::Vector3d gathered(int row) const;          // Σ of the row's slots, fixed order
  // Contact forces of the step, applied in the order found: per row a singly linked list.
  std::vector<int> contact_head_, contact_tail_;    // per state row, −1: none
  std::vector<int> contact_next_;
  std::vector<Eigen::Vector3d> contact_f_;
  std::vector<int> contact_rows_;                   // rows with a list (to reset them)
  void collect_contact_forces(const State& s);      // fills the lists above (and stats_)
  StepStats stats_;
};

}  // namespace squeeze::fem
