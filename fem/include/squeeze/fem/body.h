// squeeze::fem — one simulated object: a tetrahedral mesh with its material and rest data
// (rest lengths and volumes, lumped masses, edges, incidence lists, face adjacency, surface).
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::fem {

/// Row-major #N by 3 matrix: one vertex per contiguous row (positions, velocities, forces).
using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// Deformation damping (α > 0; Müller et al., "Position based dynamics", VRIPHYS 2006, Sec. 3.5):
/// World::step first replaces the velocities v of the object's free vertices by
/// v_rigid + e^(−αh)(v − v_rigid), v_rigid = v_cm + ω × (x − x_cm) being the rigid motion with the same
/// linear and angular momentum (v_rigid = 0 for an object with a pinned vertex: anchored, it is
/// damped towards rest). It damps every deformation mode at the energy rate α (slow
/// modes as much as fast ones), never rigid motion, conserves momentum, and is exact
/// (unconditionally stable): the stiffness-proportional damping_* coefficients damp a mode of
/// frequency ω at the rate ∝ ω² and, explicit, cost time step when large; this one costs none.
///
/// Material of a deformable object (ignored for rigid ones but for nothing: rigid objects have no
/// mass and never move). Energies are ½ k C² with dimensionless C (see constraints.h), so
/// stiffnesses are in joules. A rule of thumb: an edge of rest length D0 behaves like a spring of
/// k_e / D0² N/m.
///
/// Volume weighting (default): each constraint's stiffness is an energy density times the rest
/// volume it represents, as in FEM, so that small tetrahedra get proportionally small stiffnesses
/// (and small masses): the stable explicit step then scales with the edge length, not with the
/// smallest tet volume. With w_e = Σ V0_t / 6 over the tets t sharing edge e (each tet shares its
/// volume equally among its 6 edges, so Σ_e w_e = total volume):
///   k_e = k_distance · w_e / mean(w),     kd_e = damping_distance · w_e / mean(w)
///   k_t = k_volume · V0_t / mean(V0),     kd_t = damping_volume · V0_t / mean(V0)
/// so k_distance and k_volume keep meaning "the stiffness of an element of average size" and the
/// total stiffness Σ k_e = #E · k_distance is unchanged. Without weighting every edge gets
/// k_distance and every tet k_volume (Rodriguez 2006 / Teschner 2004 as written).
///
/// Selective mass scaling (mass_scaling = κ ≥ 1; 0: off): a vertex whose frequency estimate
/// ω_i = sqrt(s_i / m_i) (s_i from vertex_stiffness) exceeds κ × the object's median gets mass
/// added until it does not: m_i ← max(m_i, s_i / (κ ω_med)²). It removes the few outliers
/// (slivers: a flat tet's volume gradient |∂C/∂p| = area / (3 V0) is huge; vertices of tiny tets)
/// that would otherwise set the stable step of the whole world, at the cost of a little inertia
/// (LS-DYNA's "mass scaling"; on meshes from the meshing stage κ = 1.5 adds < 1 % of the mass).
/// The added mass takes part in everything (inertia, gravity, contact): Body::mass includes it,
/// Body::added_mass reports it.
struct Material {
  double density = 1000.0;        // kg/m³; lumped masses: each tet gives ¼ of its mass to each vertex
  double k_distance = 1000.0;     // J, distance constraint (paper eq. 3) of an edge of average volume share (or of every edge)
  double k_volume = 1000.0;       // J, volume constraint (paper eq. 4) of a tet of average volume (or of every tet)
  double damping_distance = 0.0;  // J·s, Teschner 2004 damping of the distance constraints (weighted like k_distance)
  double damping_volume = 0.0;    // J·s, Teschner 2004 damping of the volume constraints (weighted like k_volume)
  bool volume_weighted = true;    // stiffness and damping ∝ the rest volume an element represents (see above)
  double mass_scaling = 0.0;      // κ ≥ 1: cap of ω_i / median ω by added mass; 0: off (the scene loader uses 1.5)
  double deformation_damping = 0.0;  // 1/s, α: each step, v ← v_rigid + e^(−αh) (v − v_rigid) (see World::step)
};

/// Rest data of one object. Build it from a TetMesh, a material and a rigid transform (the scene
/// loader's input); vertex and tet order are those of the mesh.
class Body {
 public:
  /// mesh       V (m) and positively oriented T of the object in its own frame
  /// transform  placement in the world: world = transform · V
  /// rigid      rigid objects never move but collide
  /// Throws InputError if the mesh has no tetrahedron, an index out of range, a non-finite
  /// coordinate, a tetrahedron of non-positive volume (after the transform), or the material is
  /// invalid (see set_material).
  Body(const meshing::TetMesh& mesh, const Material& material, bool rigid = false,
       const Eigen::Affine3d& transform = Eigen::Affine3d::Identity());

  /// Sets `material` and recomputes what derives from it: masses (with mass scaling), added_mass
  /// and the per-element coefficients k_edge, kd_edge, k_tet, kd_tet. World::add_body calls it
  /// with the body's `material`, so assigning `material` before adding the body is enough.
  /// Throws InputError if density <= 0 (deformable bodies), a stiffness or damping is negative,
  /// or mass_scaling is neither 0 nor >= 1.
  void set_material(const Material& material);

  bool rigid = false;
  bool gravity = true;      // false: gravity does not act on this object (World::gravity_of)
  Material material;
  RowMatrixX3d rest;        // #V by 3 world positions at rest (m)
  Eigen::MatrixX4i T;       // #T by 4 tetrahedra
  Eigen::MatrixX2i E;       // #E by 2 unique edges of the tetrahedra, (i < j), sorted
  Eigen::VectorXd D0;       // #E rest lengths (m)
  Eigen::VectorXd V0;       // #T rest volumes (m³)
  Eigen::VectorXd edge_volume;  // #E rest volume represented by each edge: Σ V0 / 6 of the tets sharing it (m³)
  Eigen::VectorXd mass;     // #V lumped masses (kg), mass scaling included (deformable bodies)
  double added_mass = 0;    // kg added by mass scaling (Material::mass_scaling), included in `mass`
  // Per-element coefficients derived from `material` (set_material): stiffness (J) and damping
  // (J·s) of every edge's distance constraint and every tet's volume constraint.
  Eigen::VectorXd k_edge, kd_edge;  // #E
  Eigen::VectorXd k_tet, kd_tet;    // #T
  Eigen::MatrixX4i neighbor;  // #T by 4: tet across the face opposite local vertex k, or -1
  Eigen::MatrixX4i boundary_face;  // #T by 4: row of F for the face opposite vertex k, or -1
  Eigen::MatrixX3i F;       // #F by 3 boundary triangles, oriented outward
  std::vector<char> on_boundary;  // #V: vertex lies on a boundary triangle
  // CSR incidence list (vertex → edges), in increasing edge order:
  //   edges of vertex i: edge_code[edge_start[i] .. edge_start[i+1]), code = 2·edge + local (0/1)
  std::vector<int> edge_start, edge_code;

  int vertices() const { return static_cast<int>(rest.rows()); }
  int tets() const { return static_cast<int>(T.rows()); }
  double mean_edge_length() const;  // m
  double total_volume() const;      // m³ at rest
};

/// Per-vertex stiffness of `body` at rest (N/m): s_i = Σ k_e / D0_e² over the edges of vertex i +
/// Σ k_t |∂C_V/∂p_i|² over its tets (the trace of the vertex's 3×3 diagonal block of the
/// stiffness matrix at rest), from k_edge and k_tet. damping (optional) receives the same sums
/// with kd_edge and kd_tet (N·s/m). ω_i = sqrt(s_i / m_i) estimates the highest frequency of the
/// vertex (rad/s), γ_i = damping_i / m_i its damping rate (1/s); see stable_time_step (scene.h).
Eigen::VectorXd vertex_stiffness(const Body& body, Eigen::VectorXd* damping = nullptr);

/// Upper bounds of the squared frequency (1/s²) and of the damping rate (1/s) seen by each vertex
/// of `body` at rest, with its masses `mass` (kg): for every element e, ω_e² = k_e Σ_k |∂C/∂p_k|² / m_k
/// over its vertices (the only non-zero eigenvalue of M_e^-1 K_e, K_e = k_e ∇C ∇Cᵀ) and γ_e the same
/// with kd_e; vertex i gets Σ ω_e² and Σ γ_e over its elements. Since xᵀKx = Σ_e xᵀK_e x <=
/// Σ_e ω_e² Σ_{k∈e} m_k |x_k|², the largest eigenvalue of M⁻¹K is at most max_i ω_i² (an
/// element-by-element bound; the diagonal s_i / m_i can be up to 4× too low for slivers).
///   w2  #V (1/s²),  gamma  #V (1/s), or null
void vertex_frequency_bounds(const Body& body, const Eigen::VectorXd& mass, Eigen::VectorXd& w2,
                             Eigen::VectorXd* gamma = nullptr);

/// The volume of `body` at positions X (#V by 3): the sum of its tetrahedra's signed volumes, m³.
double volume(const Body& body, const Eigen::Ref<const RowMatrixX3d>& X);

/// A box [lo, hi] split into n[0]×n[1]×n[2] cells of 6 tetrahedra each (Kuhn / Freudenthal
/// subdivision, conforming), positively oriented. Throws InputError if a count is < 1 or lo >= hi.
meshing::TetMesh box_tet_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n);

/// A voxelized ball of `radius` (m) centered at the origin: the cells of box_tet_mesh of
/// [−radius, radius]³ with n cells per axis whose center lies in the ball (about π n³ tets, all of
/// the same good shape). Throws InputError if radius <= 0 or no cell is kept.
meshing::TetMesh ball_tet_mesh(double radius, int n);

}  // namespace squeeze::fem
