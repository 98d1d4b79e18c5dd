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
  // Collision numbering: all vertices (deformables in state order, then rigid), all tets.
  CollisionScene scene;     // bodies point into `bodies` (valid while this WorldData lives)
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

  WorldData() = default;
  WorldData(const WorldData& o);  // copies the build data; the copy must be prepared again
  WorldData& operator=(const WorldData&) = delete;
};

}  // namespace squeeze::fem
