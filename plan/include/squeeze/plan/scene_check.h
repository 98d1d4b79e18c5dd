// squeeze::plan — what a built scene will do before it is simulated or planned (`squeeze check`):
// per object its size, mass, pins and the time step it alone would need; the rest overlaps of
// every pair of objects; a short settle without control; and warnings for what will go wrong.
// `squeeze simulate`, `plan` and `run` print the warnings (check_scene with details off) on the
// world they already built.
//
//   const fem::SceneWorld w = fem::build_scene(fem::load_scene("scenes/body_parts.json"));
//   const SceneCheck c = check_scene(w);          // never throws for what it finds
//   for (const std::string& s : c.warnings) spdlog::warn("{}", s);
//
// It lives in plan/ because several of its questions are the planner's (the robot, the goal, the
// expansion volume limit planner.max_volume_change); the rest is fem's (collision.h, forces.h).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "squeeze/fem/scene.h"

namespace squeeze::plan {

struct SceneCheckOptions {
  bool details = true;     // per-object time steps and the gaps between every pair (squeeze check);
                           // false: only what the warnings need (gaps of the robot's pairs)
  double settle = 0.1;     // s simulated from the start without control to measure the volume changes
                           // (0: none); the world's own integrator and time step
  bool surfaces = true;    // with details: per pair, how much of each object lies inside the other in
                           // its coarse mesh and in its surface (OverlapCheck::coarse_a_in_b, ...);
                           // loads every object's surface file
  // The expansion volume limit (planner.max_volume_change, a fraction) the settle is held against;
  // empty: none (a scene without a robot is not planned).
  std::optional<double> max_volume_change;
  Progress* progress = nullptr;  // the settle's steps as a stage "checking the scene (a … s settle)"; null: silent
};

/// One object at rest.
struct ObjectCheck {
  std::string name;
  bool robot = false, rigid = false;
  int tets = 0, vertices = 0;
  double mass = 0;               // kg (deformable objects; mass scaling included; 0 for rigid ones)
  double volume = 0;             // m³ at rest
  int hard_pins = 0;             // vertices pinned (never move)
  int soft_pins = 0;             // vertices held by a soft attachment (and not pinned)
  std::vector<int> pin_counts;   // per objects[].pinned entry: vertices it holds
  int below_floor = 0;           // vertices below the floor at rest
  double below_floor_depth = 0;  // m, the deepest of them
  fem::TimeStepChoice time_step; // the automatic step of a world of this object alone (its pins and
                                 // attachments kept; h = 0: rigid, or details off)
  double settle_volume_change = 0;  // largest |V/V0 − 1| during the settle (0 for rigid objects)
};

/// Two objects at rest (a < b; a == b: an object with itself, when self-collision is on).
struct OverlapCheck {
  int a = -1, b = -1;
  int a_in_b = 0;     // vertices of a inside tetrahedra of b (fem's collision pass at rest)
  int b_in_a = 0;     // vertices of b inside tetrahedra of a
  double depth = 0;   // m, the deepest penetration between them (Heidelberger 2004 depth)
  double gap = -1;    // m, closest distance of their boundaries when they do not overlap; −1: not
                      // measured (details off and no robot in the pair) or overlapping
  // With details and surfaces (−1: not measured), the fidelity of the overlap: the fraction of a's
  // coarse vertices (all of them, rest positions) inside a tetrahedron of b's coarse mesh, and the
  // fraction of the vertices of a's surface (the file the object was meshed from, transformed; a
  // tet-mesh file's boundary) inside b's surface (generalized winding number >= 0.5,
  // meshing/winding_number.h); the same for b in a. Touching surfaces overlap a little; coarse
  // meshes that are not the geometry overlap more (issue 16 allows 2 points of difference).
  double coarse_a_in_b = -1, surface_a_in_b = -1, coarse_b_in_a = -1, surface_b_in_a = -1;
  bool overlapping() const { return a_in_b + b_in_a > 0; }
  bool surfaces_measured() const { return coarse_a_in_b >= 0; }
};

struct SceneCheck {
  std::vector<ObjectCheck> objects;    // scene order
  std::vector<OverlapCheck> overlaps;  // every pair that overlaps, and with details (or a robot in it) every pair
  fem::TimeStepChoice time_step;       // the scene's (SceneWorld::time_step_choice)
  double settle = 0;                   // s simulated (0: none)
  bool settle_diverged = false;        // the settle produced NaN or a speed above 1 km/s
  std::optional<double> max_volume_change;  // the limit compared against
  std::vector<std::string> warnings;   // one line each, "objects[i] 'name': …" or "goal: …"
};

/// Analyses the built scene `w` (a copy of its world is stepped for the settle; nothing is rebuilt).
/// Warnings (each one line): deformable objects below the floor at rest; objects overlapping at rest
/// (the contact penalty will push them apart, squeezing them); the robot overlapping or touching an
/// obstacle (gap below 1 % of its mean edge length); no robot but a goal, a robot but no goal, more
/// than one robot, a rigid robot; the goal outside the bounds or below the floor; a settle whose
/// volume change of a deformable object reaches the expansion limit (or half of it), or that
/// diverges; a given Verlet time_step above the stable step estimated for the meshes
/// (fem::auto_time_step); an object whose pins hold every vertex; a robot with pins or attachments;
/// with details and surfaces, a pair whose coarse meshes overlap more than 2 points beyond their
/// surfaces (in either direction). Throws InputError "PATH: problem" if a surface file cannot be
/// loaded for the surface measures.
SceneCheck check_scene(const fem::SceneWorld& w, const SceneCheckOptions& options = {});

}  // namespace squeeze::plan
