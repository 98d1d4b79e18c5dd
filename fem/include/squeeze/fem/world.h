// squeeze::fem — a world of deformable and rigid objects: the model, and its time step.
//
// Model: Rodriguez, Lien, Amato, ICRA 2006, Section IV (constraint forces of Teschner et al.
// 2004, spatial-hash collision detection, consistent penetration depth response); see
// constraints.h and collision.h for the sources. The forces are assembled by forces.h
// (assemble_forces); a TimeIntegrator (integrator.h) advances a State with them. World::step is
// the one-line way to do both with the world's own integrator and scratch data.
//
//   World w(options);                        // h, gravity, floor, contact coefficients
//   w.add_body(Body(mesh, material));        // deformable or rigid objects
//   w.pin(box);                              // pinned vertices never move
//   w.attach(row, 100.0, 1.0);               // or are held by a spring to their rest position
//   State s = w.initial_state();
//   for (...) w.step(s);                     // the integrator of options.integrator ("verlet")
//
// A World is a value: copies are cheap (they share the immutable rest data: bodies, element
// groups, collision numbering) and independent (each has its own scratch data and integrator), so
// one built world can be handed to several threads as copies. It is not safe to use one World
// from two threads at once; the const functions that take a ForceWorkspace are.
//
// Determinism: every force is summed per vertex from per-group results in a fixed order, the
// collision lists are concatenated in tetrahedron order, and the contact forces are summed in a
// fixed order: the same state and forces give bit-identical results whatever the number of TBB
// threads.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "squeeze/fem/body.h"
#include "squeeze/fem/forces.h"
#include "squeeze/fem/state.h"

namespace squeeze::fem {

class TimeIntegrator;
struct WorldData;  // the prepared rest data (fem/src/world_data.h)

/// Below these sizes a pass runs on the calling thread (waking TBB workers would cost more than
/// the pass). Results never depend on them; tests lower them to 0 to run the parallel paths.
struct ParallelThresholds {
  int elements = 2048;         // edges + tets of the element force pass
  int detection_tets = 1024;   // tetrahedra of the spatial hash's detection pass
  int border_vertices = 32;    // colliding vertices of the penetration depth's border pass
  int assembly_tets = 8192;    // tetrahedra of the implicit integrator's element blocks (one body)
};

struct WorldOptions {
  double h = 1e-3;                                 // s, time step
  std::string integrator = "verlet";               // time integrator by name (integrator.h: integrator_names())
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};        // m/s², on every object whose Body::gravity is true
  bool floor = false;                              // enables the half-space y >= floor_height
  double floor_height = 0.0;                       // m
  bool collisions = true;                          // detect and answer collisions between objects
  bool self_collision = true;                      // ... and within a deformable object
  double contact_stiffness = 1e5;                  // N/m, k_c of the penalty force k_c·d·r (also the floor)
  double contact_damping = 0.0;                    // N·s/m, along r, only while penetrating (also the floor)
  // true: an overlap of two objects (or of two parts of one) present at rest is the contact's rest
  // state: the penalty acts on the penetration beyond each vertex's rest depth, a tolerance that
  // shrinks as the vertex comes out (State::overlap) and is gone once it is out, so touching
  // objects neither explode at t = 0 nor stay interpenetrated once they move apart. false: every
  // penetration is penalised from the start.
  bool rest_overlap = true;
  // true: vertex i of object b gets the contact coefficients times min(1, m_i ω_b² / k_c), ω_b² =
  // the largest of b's vertex_frequency_bounds (body.h; the object's highest elastic frequency):
  // a light vertex (small tets) is never made stiffer by contact than the stiffest
  // vertex of its object is by elasticity, so contact does not set the stable step (the contact
  // damping ratio is kept). Vertices of coarse meshes keep k_c. A rigid vertex inside a
  // deformable tet uses Σ bary_k · factor_k of the tet's corners. false: k_c and c_c everywhere.
  bool cap_contact_stiffness = false;
  double cell_size = 0.0;                          // m, spatial hash cell; 0: mean edge length of the deformable objects
  int table_size = 0;                              // spatial hash entries; 0: a prime >= 4 × vertex count
  ParallelThresholds parallel;                     // when passes go parallel (never changes results)
};

class World {
 public:
  /// Throws InputError if h <= 0, a contact coefficient is negative, gravity is not finite, or
  /// the integrator is unknown.
  explicit World(const WorldOptions& options = {});
  ~World();
  /// Copies share the rest data and get their own scratch data and integrator.
  World(const World& other);
  World& operator=(const World& other);
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  /// Adds an object; returns its index. States made before no longer fit (step() throws on them).
  int add_body(Body body);
  /// Gives deformable object b a collision mesh of its own: `mesh` (world positions at rest, m;
  /// positively oriented tetrahedra) then stands for b in collision detection, penetration depth,
  /// rest overlaps and body_volume, while b's own tetrahedra carry its mass and elasticity. Each
  /// vertex of `mesh` follows b's tetrahedron that contains it (or the nearest one) by its
  /// barycentric coordinates, extrapolated outside (ffd::bind_surface; the paper's FFD, Section
  /// VI-A), so contact forces reach b's vertices by the same weights. The use: a coarse simulation
  /// mesh (few degrees of freedom) around the tight mesh of the object's surface (the geometry
  /// that touches), as a cage around an embedded mesh (Sacht et al., "Nested Cages", 2015).
  /// Calling it again replaces the mesh. Throws InputError if b is out of range or rigid, or the
  /// mesh is empty, not finite or has a tetrahedron of non-positive volume.
  void embed(int b, const meshing::TetMesh& mesh);
  /// Whether object b has an embedded collision mesh (embed).
  bool embedded(int b) const;
  /// The mesh object b collides with: its embedded mesh, else its own rest data.
  const Body& collision_body(int b) const;
  /// Positions (m) of the vertices of collision_body(b) in state s: W·x for an embedded mesh, the
  /// object's own rows else (rigid objects: their rest positions).
  RowMatrixX3d collision_positions(const State& s, int b) const;
  /// Pins every vertex of every deformable object whose rest position lies in box (m). Returns
  /// how many vertices are pinned now in total.
  int pin(const Eigen::AlignedBox3d& box);
  /// Pins one vertex (row of the state). Throws InputError if out of range.
  void pin_vertex(int row);
  /// Soft attachment of one vertex (row of the state) to its rest position x0: a zero-length
  /// spring with the force −stiffness (x − x0) − damping v (assemble_forces; the implicit
  /// integrator takes the same term as the energy ½ k |x − x0|² and the dissipation ½ (c / h) |Δx|²).
  /// Calling it again for a row adds to its coefficients (springs in parallel); a pinned row stays
  /// pinned. stable_time_step counts k / m and c / m in the row's frequency bound.
  ///   stiffness  N/m, >= 0;  damping  N·s/m, >= 0
  /// With carry_weight the spring also carries the row's weight at rest: its anchor is raised to
  /// x0 − m g / k (g the row's object's gravity, m its mass), so at x = x0 it pulls with −m g and
  /// the vertex starts in equilibrium (the tissue that holds an organ in a body and that the scene
  /// does not model; scene key pinned[].carries_weight). The anchor is fixed by prepare(); the
  /// rows of one call sum their weights over the stiffnesses of all their springs.
  /// Throws InputError if the row is out of range, a coefficient is negative or not finite, or
  /// carry_weight is asked of a spring without stiffness.
  void attach(int row, double stiffness, double damping = 0.0, bool carry_weight = false);
  /// The soft attachment of a state row: stiffness (N/m) and damping (N·s/m), 0 if none.
  double attachment_stiffness(int row) const;
  double attachment_damping(int row) const;
  /// Whether the soft attachment of a state row carries the row's weight (attach carry_weight).
  bool attachment_carries_weight(int row) const;
  /// Where the attachment spring of a state row has zero length (m): its rest position, raised by
  /// m g / k where it carries the weight. prepare() first (std::logic_error otherwise).
  Eigen::Vector3d attachment_anchor(int row) const;
  /// Builds the derived rest data now (element groups, collision numbering) instead of at the
  /// first step: copies made afterwards share it. Idempotent.
  void prepare();

  const WorldOptions& options() const { return options_; }
  /// The time step h (s). set_time_step changes it (no rebuild). Throws InputError if <= 0.
  double time_step() const { return options_.h; }
  void set_time_step(double h);
  /// The integrator step() uses, and its replacement (e.g. make_integrator("verlet")).
  TimeIntegrator& integrator() { return *integrator_; }
  const TimeIntegrator& integrator() const { return *integrator_; }
  void set_integrator(std::unique_ptr<TimeIntegrator> integrator);

  int bodies() const;
  const Body& body(int b) const;
  /// First state row of object b, or -1 for a rigid object.
  int first_state_row(int b) const;
  int state_rows() const;
  int tets() const;  // all objects
  bool pinned(int row) const;
  const Eigen::VectorXd& masses() const;  // #N kg per state row
  /// Factor (<= 1) of the contact coefficients of a state row: see WorldOptions::cap_contact_stiffness.
  double contact_scale(int row) const;
  /// The gravity acceleration acting on object b (m/s²): options().gravity, or zero if Body::gravity is false.
  Eigen::Vector3d gravity_of(int b) const;

  /// Rest positions, zero velocities, time 0, the rest overlaps (State::overlap).
  State initial_state() const;
  /// A vertex that overlaps another object (or another part of its own) at rest.
  struct RestOverlap {
    int vertex = -1;     // collision numbering: state rows, then the rigid objects' vertices
    int body = -1;       // the object it belongs to
    int penetrated = -1; // the object it is inside
    double depth = 0;    // m, its penetration depth at rest (its contact's tolerance, State::overlap)
  };
  /// Every vertex inside another object at rest, in State::overlap's order (empty with
  /// WorldOptions::rest_overlap false). prepare() first.
  const std::vector<RestOverlap>& rest_overlaps() const;

  /// Advances s by one step h with the world's integrator. external: #N by 3 forces (N) per state
  /// row, or null. Throws InputError if s or external has the wrong number of rows.
  void step(State& s, const RowMatrixX3d* external = nullptr);

  /// Internal constraint forces only (elastic + damping), #N by 3 (N); no gravity, contact, floor.
  void internal_forces(const State& s, RowMatrixX3d& F);
  /// Every force of the next step (internal, gravity, external, floor, contacts), #N by 3 (N).
  void total_forces(const State& s, const RowMatrixX3d* external, RowMatrixX3d& F);
  /// The contacts of state s (its StepStats), without forces.
  StepStats contact_stats(const State& s);
  /// What the last step() (or force evaluation) found.
  const StepStats& last_stats() const;

  double elastic_energy(const State& s) const;   // J, Σ ½ k C² over all constraints
  double kinetic_energy(const State& s) const;   // J, ½ Σ m v²
  double gravity_energy(const State& s) const;   // J, −Σ m g·x over the objects gravity acts on
  /// Volume (m³) of deformable object b in state s.
  double body_volume(const State& s, int b) const;

  /// The prepared rest data (prepare() first). For the force assembly and integrators.
  const WorldData& data() const;

 private:
  WorldData& mutable_data();  // copy-on-write: unshares the rest data before a change
  WorldOptions options_;
  std::shared_ptr<WorldData> data_;             // rest data, shared between copies
  std::unique_ptr<TimeIntegrator> integrator_;  // per copy
  ForceWorkspace workspace_;                    // per copy
};

}  // namespace squeeze::fem
