// squeeze::fem — collision detection and penetration depth between tetrahedral meshes.
//
// Detection: M. Teschner, B. Heidelberger, M. Müller, D. Pomeranets, M. Gross, "Optimized spatial
// hashing for collision detection of deformable objects", VMV 2003. Vertices are hashed into a
// table by their grid cell (hash of the integer cell coordinates with the primes 73856093,
// 19349663, 83492791, modulo the table size); each tetrahedron looks up the cells its AABB
// overlaps and tests the vertices found there by barycentric coordinates. A time stamp per table
// entry avoids clearing the table between queries.
//
// Response: B. Heidelberger, M. Teschner, R. Keiser, M. Müller, M. Gross, "Consistent penetration
// depth estimation for deformable collision response", VMV 2004. Colliding vertices → intersecting
// edges (one colliding, one free end point) → intersection points x_i with the penetrated object's
// surface and its normals n_i → depth and direction of border vertices (weights 1/|x_i − p|²) →
// breadth-first propagation into the colliding region (weights 1/|p_j − p|²).
#pragma once
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "squeeze/fem/body.h"

namespace squeeze::fem {

/// A tetrahedron prepared for point-in-tetrahedron tests: bary(p) = (1 − Σλ, λ) with
/// λ = M⁻¹ (p − a), M = [b−a, c−a, d−a]. The same arithmetic serves the spatial hash and any
/// brute-force check, so both agree bit for bit.
struct TetFrame {
  Eigen::Vector3d a;
  Eigen::Matrix3d inverse;
  bool valid = false;  // false for a degenerate (zero-volume) tetrahedron: contains nothing
  TetFrame(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d);
  Eigen::Vector4d barycentric(const Eigen::Vector3d& p) const;
  /// All four barycentric coordinates >= 0 (boundary included).
  bool contains(const Eigen::Vector3d& p, Eigen::Vector4d* bary = nullptr) const;
};

// Inline: the spatial hash calls these for every candidate vertex.
inline TetFrame::TetFrame(const Eigen::Vector3d& a_, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& d)
    : a(a_) {
  // M = [b−a, c−a, d−a]; inverse = adj(M) / det(M) with the determinant expanded along the
  // first column of the same cofactors (Eigen's 3×3 formula, computed once).
  const Eigen::Vector3d u = b - a, v = c - a, w = d - a;  // columns of M
  // cof(r, k): cofactor of M(r, k).
  const double c00 = v[1] * w[2] - w[1] * v[2], c10 = v[2] * w[0] - w[2] * v[0], c20 = v[0] * w[1] - w[0] * v[1];
  const double det = c00 * u[0] + c10 * u[1] + c20 * u[2];
  valid = std::isfinite(det) && det != 0.0;
  if (!valid) return;
  const double id = 1.0 / det;
  const double c01 = w[1] * u[2] - u[1] * w[2], c11 = w[2] * u[0] - u[2] * w[0], c21 = w[0] * u[1] - u[0] * w[1];
  const double c02 = u[1] * v[2] - v[1] * u[2], c12 = u[2] * v[0] - v[2] * u[0], c22 = u[0] * v[1] - v[0] * u[1];
  inverse << c00 * id, c10 * id, c20 * id,  //
      c01 * id, c11 * id, c21 * id,         //
      c02 * id, c12 * id, c22 * id;
}

inline Eigen::Vector4d TetFrame::barycentric(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d l = inverse * (p - a);
  return {1.0 - l[0] - l[1] - l[2], l[0], l[1], l[2]};
}

inline bool TetFrame::contains(const Eigen::Vector3d& p, Eigen::Vector4d* bary) const {
  if (!valid) return false;
  const Eigen::Vector4d b = barycentric(p);
  if (bary) *bary = b;
  return b.minCoeff() >= 0.0;
}

/// A vertex found inside a tetrahedron (indices into the query's X and T).
struct Contact {
  int vertex = -1, tet = -1;
  Eigen::Vector4d bary;  // barycentric coordinates of the vertex in the tet
};

/// Which (vertex, tet) pairs are tested: pairs where the vertex is a corner of the tet are always
/// skipped; vertex and tet of one group (object) only if self_collision and the vertex is on the
/// object's surface (an interior vertex inside a tet of its own object means an inverted element,
/// which the volume constraint restores, not a self-collision; skipping them keeps the test
/// cheap); vertex and tet of two rigid groups never.
struct CollisionFilter {
  std::vector<int> vertex_group;          // #X group (object) of every vertex
  std::vector<int> tet_group;             // #T group of every tet
  std::vector<char> group_rigid;          // per group: 1 if rigid
  std::vector<char> vertex_on_surface;    // #X, or empty: every vertex counts as on the surface
  bool self_collision = true;
};

/// Optimized spatial hashing. Not thread-safe itself (owns the table); find() runs its
/// tetrahedron pass in parallel with TBB and its result does not depend on the number of threads.
class SpatialHash {
 public:
  /// cell  grid cell edge (m) > 0, about the mean edge length (Teschner 2003, Sec. 5)
  /// table_size  number of hash entries >= 1 (larger = fewer hash collisions)
  /// Throws InputError otherwise.
  SpatialHash(double cell, int table_size);

  /// Every allowed (vertex, tet) pair with the vertex inside the tet (TetFrame::contains),
  /// sorted by tet then vertex.
  ///   X  #X by 3 positions (m), T  #T by 4 indices into X
  /// serial_below: fewer tets run the pass on the calling thread (waking TBB workers would cost
  /// more; the result is the same either way).
  std::vector<Contact> find(const Eigen::Ref<const RowMatrixX3d>& X, const Eigen::MatrixX4i& T,
                            const CollisionFilter& filter, int serial_below = 1024);

  /// hash(i,j,k) = ((i'·73856093) xor (j'·19349663) xor (k'·83492791)) mod table_size, in 32-bit
  /// arithmetic, with i' = i + 2^20 (likewise j', k'): the shift keeps the xor of the products of
  /// small signed coordinates from colliding.
  std::uint32_t hash(std::int64_t i, std::int64_t j, std::int64_t k) const;
  double cell() const { return cell_; }
  int table_size() const { return static_cast<int>(bucket_.size()); }

 private:
  struct VertexEntry {     // one hashed vertex, packed for the lookup loop
    double x, y, z;
    std::int64_t key;      // its cell (i, j, k), 21 bits each
    int vertex;
    int group;             // object; −1 − object for interior vertices (never tested against their own object)
  };
  struct Bucket {           // one hash entry, packed: a lookup touches one cache line
    std::uint32_t stamp;   // valid when == now_
    int head, count, scount;
  };
  double cell_;
  std::uint64_t fastmod_ = 0;  // Lemire's constant for the modulo by the table size
  std::uint32_t now_ = 0;
  // Per hash entry (valid when stamp == now_): its vertices are entry_[head .. head + count),
  // surface vertices first (scount of them): a tet far from every other object's interior
  // vertices scans only those.
  std::vector<Bucket> bucket_;
  std::vector<int> ifill_;
  std::vector<std::uint32_t> vhash_, touched_;
  std::vector<std::int64_t> vkey_;
  std::vector<std::array<std::int64_t, 3>> vcell_;  // per vertex: its cell (i, j, k)
  /// h mod table_size (Lemire's fast remainder).
  std::uint32_t reduce(std::uint32_t h) const {
    return static_cast<std::uint32_t>((static_cast<unsigned __int128>(fastmod_ * h) * bucket_.size()) >> 64);
  }
  std::vector<VertexEntry> entry_;  // vertices grouped by hash entry (counting sort)
  std::vector<std::vector<Contact>> blocks_;  // per block of tets (reused between queries)
  std::vector<std::vector<const VertexEntry*>> cands_;  // per block of tets: cell-mates of the last cell range (reused)
};

/// The same pairs as SpatialHash::find by testing every vertex against every tet, O(#X·#T):
/// the reference for tests.
std::vector<Contact> find_contacts_brute_force(const Eigen::Ref<const RowMatrixX3d>& X, const Eigen::MatrixX4i& T,
                                               const CollisionFilter& filter);

/// The objects of a collision query laid out in one global numbering: object b owns vertices
/// [first_vertex[b], first_vertex[b] + bodies[b]->vertices()) and tets [first_tet[b], ...).
struct CollisionScene {
  std::vector<const Body*> bodies;
  std::vector<int> first_vertex, first_tet;
};

/// Penetration of one colliding vertex (Heidelberger 2004).
struct Penetration {
  int vertex = -1;             // global vertex index
  int tet = -1;                // global index of the penetrated tetrahedron (the first one found)
  int body = -1;               // penetrated object
  double depth = 0;            // m, >= 0 when consistent
  Eigen::Vector3d direction;   // unit direction out of the penetrated object
  Eigen::Vector4d bary;        // barycentric coordinates of the vertex in `tet`
  int layer = 0;               // 0: border vertex (has an intersecting edge); k: propagation step
};

/// Depth and direction of every colliding vertex that the propagation reaches (vertices of a
/// colliding region with no intersecting edge that reaches the penetrated surface get none).
/// A vertex in several tets keeps its first contact (contacts sorted by tet). The intersection of
/// edge (p,q) with the penetrated surface is found by walking the penetrated mesh's face adjacency
/// from p's tet towards q; the surface normal is that of the boundary triangle crossed.
///   X  all positions (m) in the scene's numbering; contacts from SpatialHash::find
///   serial_below  fewer colliding vertices: the border pass runs on the calling thread (same result)
std::vector<Penetration> penetration_depths(const CollisionScene& scene, const Eigen::Ref<const RowMatrixX3d>& X,
                                            const std::vector<Contact>& contacts, int serial_below = 32);

}  // namespace squeeze::fem
