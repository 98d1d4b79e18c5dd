// squeeze::fem — the one force assembly of the model: every force acting on every free vertex of
// a world in a state, as Rodriguez, Lien, Amato (ICRA 2006, Sec. IV-B) sum them for one step:
//   F = Σ distance and volume constraint forces (elastic + damping; constraints.h, Teschner 2004)
//       + m g (objects with Body::gravity) + external forces
//       + floor penalty k_c (y_f − y) − c_c min(0, v_y) below the floor
//       + soft attachments −k_a (x − x_rest) − c_a v of the attached vertices (World::attach)
//       + contact penalty forces (k_c d − c_c (v_rel·r)) r of every colliding vertex (collision.h,
//         Heidelberger 2004); a rigid vertex inside a deformable tet pushes back on that tet's
//         corners with −(k_c d − c_c (v_rel·r)) r spread by its barycentric weights. d is the depth
//         beyond the vertex's rest overlap (State::overlap; WorldOptions::rest_overlap): a vertex
//         inside another object at rest is at rest there, and no force acts while it stays within
//         that depth.
// Every caller that needs forces uses it: the integrators (integrator.h), World::total_forces and
// World::internal_forces, the metrics. Kernels of one element are in constraints.h.
//
// Summation order (fixed, so the results do not depend on the threads): per row, its element
// groups' slots in group order; then gravity; then the external forces (with, for an object whose
// gravity is off, the cancelling −m g added first: gravity is applied and cancelled, which keeps
// the rounding of the plans made before); then the floor; then its soft attachment (only in worlds
// that have one: the sums of worlds without attachments are unchanged); then its contacts in
// detection order.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "squeeze/fem/body.h"
#include "squeeze/fem/collision.h"
#include "squeeze/fem/state.h"

namespace squeeze::fem {

class World;

/// Scratch data of force evaluations: the element groups' accumulators, the spatial hash and the
/// contact lists. One per thread: the const functions below are thread-safe for distinct
/// workspaces. Copying a workspace gives an empty one (it is scratch).
class ForceWorkspace {
 public:
  ForceWorkspace();
  ~ForceWorkspace();
  ForceWorkspace(const ForceWorkspace&);
  ForceWorkspace& operator=(const ForceWorkspace&);
  ForceWorkspace(ForceWorkspace&&) noexcept;
  ForceWorkspace& operator=(ForceWorkspace&&) noexcept;
  /// What the last evaluation's collision pass found.
  const StepStats& stats() const;
  /// The rest-overlap tolerances after the last evaluation (State::overlap, shrunk where a vertex
  /// came out): an integrator stores them in the state it advances.
  const Eigen::VectorXd& overlap() const;

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// Which terms assemble_forces sums.
struct ForceTerms {
  bool internal = true;  // distance and volume constraints, elastic and damping
  bool gravity = true;   // m g of objects with gravity (and the cancellation of the others)
  bool external = true;  // the `external` matrix
  bool floor = true;     // the floor penalty (if the world has a floor)
  bool contacts = true;  // collision detection and the contact penalty (if the world has collisions)
  bool attachments = true;  // the soft attachments' springs (World::attach), summed after the floor
  static ForceTerms internal_only() { return {true, false, false, false, false, false}; }
};

/// F = the forces (N) on every state row of `world` in state s, #N by 3 (pinned rows included:
/// integrators ignore them). external: #N by 3 (N) or null. world must be prepared
/// (World::prepare; World's own functions do it). Throws InputError if s or external has the
/// wrong number of rows; std::logic_error if the world is not prepared.
void assemble_forces(const World& world, const State& s, const RowMatrixX3d* external, ForceWorkspace& ws,
                     RowMatrixX3d& F, const ForceTerms& terms = {});

/// The object (index of World::body) of collision vertex g, and of collision tet `tet` (the
/// numbering of find_penetrations).
int collision_vertex_body(const World& world, int g);
int collision_tet_body(const World& world, int tet);

/// The collision pass alone: the contacts of state s in ws.stats(), no forces.
void detect_contacts(const World& world, const State& s, ForceWorkspace& ws);

/// The collision pass of state s: every colliding vertex with a penetration depth > 0
/// (collision.h, Penetration), in detection order; ws.stats() as detect_contacts. Depths are
/// beyond the vertex's rest-overlap tolerance (State::overlap; ws.overlap() gets the shrunk
/// tolerances). Indices are in
/// the world's collision numbering: the deformable objects' collision meshes (their own, or the
/// mesh embedded in them, World::embed), then the rigid objects'. Without embedded meshes, vertex
/// and tet-corner indices below world.state_rows() are state rows, the others rigid vertices;
/// collision_vertex_position gives every position.
std::vector<Penetration> find_penetrations(const World& world, const State& s, ForceWorkspace& ws);

/// Corners of tet `tet` (collision numbering) and the position of collision vertex `g` in state s.
Eigen::Vector4i collision_tet(const World& world, int tet);
Eigen::Vector3d collision_vertex_position(const World& world, const State& s, int g);

}  // namespace squeeze::fem
