// squeeze::fem — the rest data of a World, prepared for the force passes (private to fem/src).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "squeeze/fem/body.h"
#include "squeeze/fem/collision.h"
#include "squeeze/fem/world.h"

namespace squeeze::fem {

struct WorldData {
  // --- what the world was built from ---
  std::vector<Body> bodies;
  std::vector<int> state_row;    // per body, -1 if rigid
  int rows = 0;
  Eigen::VectorXd mass;          // per state row (kg)
  Eigen::VectorXd contact_scale; // per state row, see World::contact_scale()
  std::vector<char> pinned;      // per state row
  // Soft attachments (World::attach): per state row, the stiffness (N/m) and damping (N·s/m) of a
  // zero-length spring to the row's rest position (X_rest_all.row(row)); 0 and 0: none.
  Eigen::VectorXd attach_k, attach_c;
  std::vector<char> attach_weight;  // per state row: its attachment carries the row's weight
  // Embedded collision meshes (World::embed): per body, its index in `embedded` or −1. An embedded
  // mesh stands for its body in the collision numbering (detection, penetration depth, rest
  // overlaps) and in body_volume; its vertices follow the body's tetrahedra by barycentric
  // coordinates (extrapolated outside them), so its positions are a linear map W of the state.
  struct Embedded {
    Body mesh;                 // rest data of the collision mesh (world positions at rest)
    Eigen::VectorXi tet;       // #Vc: the body's tetrahedron each vertex follows
    Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> bary;  // #Vc by 4, rows sum to 1
  };
  std::vector<int> embedding;
  std::vector<Embedded> embedded;

  // --- derived by prepare() ---
  bool prepared = false;
  std::uint64_t version = 0;     // unique per prepare(): workspaces resize when it changes
  Eigen::VectorXd inv_mass;      // per state row, 0 for pinned or massless vertices
  Eigen::VectorXd contact_k, contact_c;  // per state row: contact stiffness and damping (contact_scale applied)
  std::vector<char> gravity_off; // per state row: its object has Body::gravity false
  bool any_gravity_off = false;
  bool any_attached = false;     // some free row has a soft attachment (assemble_forces skips the term otherwise)
  RowMatrixX3d attach_anchor;    // per state row: where its attachment spring has zero length: the
                                 // rest position, raised by m g / k where it carries the weight
  // Elements of all deformable objects in groups, for the force pass. A group is the edges and
  // tets owned by a cluster of kClusterRows vertices (world.cpp) of one object, neighbours in
  // space (consecutive in the Morton order of the rest positions; an element belongs to the
  // cluster of its corner first in that order). A group adds its elements' forces, element after
  // element, into its own accumulator slots, one per vertex it touches; a row's force is then
  // the sum of its slots, group after group. Fixed groups, fixed orders: the sums do not depend on
  // the threads, and a row is summed from 1–2 slots instead of ~24 element results, so little
  // data crosses between the cores (docs/fem.md, Determinism).
  struct EdgeElem { int i, j; double D0, k, kd; int si, sj; };  // rows; slots (offsets in doubles into the accumulator)
  struct TetElem { int v[4]; double V0, k, kd; int s[4]; };
  struct ElemGroup { int e0, e1, t0, t1, a0, a1; };  // edges [e0, e1), tets [t0, t1), slots [a0, a1)
  std::vector<EdgeElem> edges;
  std::vector<TetElem> tet_elems;
  std::vector<ElemGroup> groups;
  int slots = 0;  // accumulator slots (3 doubles each)
  // Per state row: its slots, group order: gather[gather_start[r] .. gather_start[r + 1]),
  // offsets in doubles into the accumulator.
  std::vector<int> gather_start, gather;
  // Collision numbering: all vertices (deformables in state order, then rigid), all tets; an
  // embedded body's collision mesh in its place.
  CollisionScene scene;     // bodies point into `bodies` or `embedded` (valid while this WorldData lives)
  std::vector<int> group_body;  // per group of the collision numbering: its body
  // Per collision vertex g, the state rows its position is a combination of:
  // coll_row/coll_w[coll_start[g] .. coll_start[g + 1]) (weights sum to 1); none for rigid
  // vertices. Without embedded meshes the first `rows` collision vertices are the state rows.
  std::vector<int> coll_start, coll_row;
  std::vector<double> coll_w;
  // Per collision vertex: the share of its rows' contact coefficients it takes: 1, or on an
  // embedded mesh the cage's surface vertices over the embedded mesh's (many embedded surface
  // vertices press on one cage vertex: together they are as stiff as the cage's own surface).
  std::vector<double> coll_share;
  bool any_embedded = false;
  // Per state row: the floor holds it (1), or it is a row of an object with an embedded mesh,
  // whose embedded vertices the floor holds instead (0).
  std::vector<char> floor_row;
  std::vector<int> embedded_vertices;  // collision vertices of embedded meshes, ascending
  CollisionFilter filter;
  Eigen::MatrixX4i T_all;
  RowMatrixX3d X_rest_all;  // rest positions in the collision numbering (rigid rows stay so)
  // Rest overlaps: collision vertices inside another object at rest, their rest depths, and per
  // collision vertex its index in them (−1: none).
  std::vector<World::RestOverlap> overlaps;
  Eigen::VectorXd overlap_depths;
  std::vector<int> overlap_slot;
  double cell = 1.0;        // spatial hash cell (m)
  int table = 97;           // spatial hash entries

  /// Positions of the collision vertices that follow the state (x: #rows by 3) into X_all (rigid
  /// vertices keep what X_all holds: their rest positions).
  void collision_positions(const Eigen::Ref<const RowMatrixX3d>& x, RowMatrixX3d& X_all) const {
    if (!any_embedded) {
      X_all.topRows(rows) = x;
      return;
    }
    const int n = static_cast<int>(coll_start.size()) - 1;
    for (int g = 0; g < n; ++g)
      if (followed(g)) X_all.row(g) = follow(g, x).transpose();
  }

  /// Σ w per_row over the rows collision vertex g follows (its position for per_row = x, its
  /// velocity for v); a single row of weight 1 exactly. per_row: #rows by 3.
  Eigen::Vector3d follow(int g, const Eigen::Ref<const RowMatrixX3d>& per_row) const {
    const int a = coll_start[static_cast<size_t>(g)], b = coll_start[static_cast<size_t>(g) + 1];
    if (single_row(g)) return per_row.row(coll_row[static_cast<size_t>(a)]).transpose();
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int c = a; c < b; ++c) p += coll_w[static_cast<size_t>(c)] * per_row.row(coll_row[static_cast<size_t>(c)]).transpose();
    return p;
  }

  /// Collision vertex g follows state rows (it is not rigid).
  bool followed(int g) const { return coll_start[static_cast<size_t>(g) + 1] > coll_start[static_cast<size_t>(g)]; }
  /// Collision vertex g is a state row itself (one row, weight 1): the simulation mesh's own vertex.
  bool single_row(int g) const {
    const int a = coll_start[static_cast<size_t>(g)];
    return coll_start[static_cast<size_t>(g) + 1] - a == 1 && coll_w[static_cast<size_t>(a)] == 1.0;
  }
  /// A contact coefficient of collision vertex g from its rows' (per_row: per state row): the row's
  /// own for a single row, else Σ w per_row times coll_share[g].
  double contact_coefficient(int g, const Eigen::VectorXd& per_row) const {
    if (single_row(g)) return per_row(coll_row[static_cast<size_t>(coll_start[static_cast<size_t>(g)])]);
    double q = 0;
    for (int c = coll_start[static_cast<size_t>(g)]; c < coll_start[static_cast<size_t>(g) + 1]; ++c)
      q += coll_w[static_cast<size_t>(c)] * per_row(coll_row[static_cast<size_t>(c)]);
    return q * coll_share[static_cast<size_t>(g)];
  }

  WorldData() = default;
  WorldData(const WorldData& o);  // copies the build data; the copy must be prepared again
  WorldData& operator=(const WorldData&) = delete;
};

}  // namespace squeeze::fem
