#include "squeeze/plan/scene_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>

#include "squeeze/common/format.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/forces.h"
#include "squeeze/meshing/point_triangle_distance.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"
#include "squeeze/meshing/tet_locator.h"
#include "squeeze/meshing/winding_number.h"
#include "squeeze/plan/propagator.h"

namespace squeeze::plan {
namespace {

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f %%", 100 * x);
  return buf;
}

std::string who(const fem::Scene& scene, int b) {
  return "objects[" + std::to_string(b) + "] '" + scene.objects[b].name + "'";
}

// Closest distance (m) from the boundary vertices of `a` to the boundary triangles of `b` (rest
// positions); triangles whose bounding box is farther than the best so far are skipped.
double boundary_distance(const fem::Body& a, const fem::Body& b) {
  struct Tri { Eigen::Vector3d p[3]; Eigen::AlignedBox3d box; };
  std::vector<Tri> tris(static_cast<size_t>(b.F.rows()));
  for (Eigen::Index f = 0; f < b.F.rows(); ++f) {
    Tri& t = tris[static_cast<size_t>(f)];
    t.box.setEmpty();
    for (int k = 0; k < 3; ++k) {
      t.p[k] = b.rest.row(b.F(f, k)).transpose();
      t.box.extend(t.p[k]);
    }
  }
  double best = std::numeric_limits<double>::infinity();
  for (int v = 0; v < a.vertices(); ++v) {
    if (!a.on_boundary[static_cast<size_t>(v)]) continue;
    const Eigen::Vector3d p = a.rest.row(v).transpose();
    for (const Tri& t : tris) {
      if (t.box.exteriorDistance(p) >= best) continue;
      best = std::min(best, meshing::point_triangle_distance(p, t.p[0], t.p[1], t.p[2]));
    }
  }
  return best;
}

// An object's surface at rest in world coordinates (m): the file it was meshed from, transformed,
// or the boundary of its coarse mesh when the file is a tet mesh.
struct RestSurface {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;
  Eigen::AlignedBox3d box;
};

RestSurface rest_surface(const fem::SceneWorld& w, int b) {
  const fem::SceneObject& so = w.scene.objects[static_cast<size_t>(b)];
  RestSurface s;
  if (meshing::is_tet_format(so.mesh)) {
    const fem::Body& body = w.world.body(b);
    s.V = body.rest;
    s.F = body.F;
  } else {
    const meshing::SurfaceMesh m = meshing::load_surface(so.mesh);
    const Eigen::Affine3d A = so.transform.affine();
    s.V.resize(m.V.rows(), 3);
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) s.V.row(i) = (A * Eigen::Vector3d(m.V.row(i).transpose())).transpose();
    s.F = m.F;
  }
  s.box.setEmpty();
  for (Eigen::Index i = 0; i < s.V.rows(); ++i) s.box.extend(Eigen::Vector3d(s.V.row(i).transpose()));
  return s;
}

// Fraction of the rows of P inside the winding-number solid of `inside` (0 when their boxes are apart).
double fraction_inside(const Eigen::MatrixX3d& P, const Eigen::AlignedBox3d& box,
                       const meshing::FastWindingNumber& inside) {
  if (P.rows() == 0) return 0;
  long long n = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (box.contains(Eigen::Vector3d(P.row(i).transpose())) && inside(P.row(i)) >= 0.5) ++n;
  return static_cast<double>(n) / static_cast<double>(P.rows());
}

// Fraction of the rows of P inside a tetrahedron of `mesh`.
double fraction_inside(const Eigen::MatrixX3d& P, const meshing::TetLocator& mesh) {
  if (P.rows() == 0) return 0;
  long long n = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i) n += mesh.locate(P.row(i)) >= 0;
  return static_cast<double>(n) / static_cast<double>(P.rows());
}

}  // namespace

SceneCheck check_scene(const fem::SceneWorld& w, const SceneCheckOptions& options) {
  const fem::Scene& scene = w.scene;
  const fem::World& world = w.world;
  SceneCheck out;
  out.time_step = w.time_step_choice;
  out.max_volume_change = options.max_volume_change;
  const int nb = world.bodies();

  // --- per object ---
  for (int b = 0; b < nb; ++b) {
    const fem::Body& B = world.body(b);
    ObjectCheck o;
    o.name = scene.objects[b].name;
    o.robot = scene.objects[b].robot;
    o.rigid = B.rigid;
    o.tets = B.tets();
    o.vertices = B.vertices();
    o.volume = w.rest_volume[b];
    if (static_cast<size_t>(b) < w.pin_counts.size()) o.pin_counts = w.pin_counts[b];
    const int r0 = world.first_state_row(b);
    if (r0 >= 0)
      for (int v = 0; v < B.vertices(); ++v) {
        o.mass += world.masses()(r0 + v);
        if (world.pinned(r0 + v)) ++o.hard_pins;
        else if (world.attachment_stiffness(r0 + v) > 0 || world.attachment_damping(r0 + v) > 0) ++o.soft_pins;
      }
    if (scene.floor)
      for (int v = 0; v < B.vertices(); ++v)
        if (B.rest(v, 1) < *scene.floor - touch_tolerance(B)) {  // touching the floor is resting on it
          ++o.below_floor;
          o.below_floor_depth = std::max(o.below_floor_depth, *scene.floor - B.rest(v, 1));
        }
    if (options.details && r0 >= 0) {
      // A world of this object alone: the same options, its pins and attachments.
      fem::World alone(world.options());
      alone.add_body(B);
      for (int v = 0; v < B.vertices(); ++v) {
        if (world.pinned(r0 + v)) alone.pin_vertex(v);
        const double ka = world.attachment_stiffness(r0 + v), ca = world.attachment_damping(r0 + v);
        if (ka > 0 || ca > 0) alone.attach(v, ka, ca);
      }
      fem::Scene sub = scene;
      sub.objects = {scene.objects[b]};
      o.time_step = fem::auto_time_step(alone, sub);
    }
    out.objects.push_back(std::move(o));
  }

  // --- rest overlaps: fem's collision pass on the rest state (World::rest_overlaps: the raw depths,
  // which with contact.rest_overlap are the contacts' rest state; else a pass on the initial state) ---
  std::map<std::pair<int, int>, OverlapCheck> pairs;
  auto count = [&](int va, int tb, double depth) {
    if (va < 0 || tb < 0) return;
    OverlapCheck& c = pairs[{std::min(va, tb), std::max(va, tb)}];
    c.a = std::min(va, tb);
    c.b = std::max(va, tb);
    (va == c.a ? c.a_in_b : c.b_in_a) += 1;
    c.depth = std::max(c.depth, depth);
  };
  if (world.options().rest_overlap) {
    for (const fem::World::RestOverlap& o : world.rest_overlaps()) count(o.body, o.penetrated, o.depth);
  } else {
    fem::ForceWorkspace ws;
    const fem::State s0 = w.initial_state();
    for (const fem::Penetration& p : fem::find_penetrations(world, s0, ws))
      count(fem::collision_vertex_body(world, p.vertex), fem::collision_tet_body(world, p.tet), p.depth);
  }
  for (int a = 0; a < nb; ++a)
    for (int b = a + 1; b < nb; ++b) {
      if (world.body(a).rigid && world.body(b).rigid) continue;  // never move, never interact
      const bool robot_pair = scene.objects[a].robot || scene.objects[b].robot;
      if (!options.details && !robot_pair) continue;
      OverlapCheck& c = pairs[{a, b}];
      c.a = a;
      c.b = b;
      if (!c.overlapping())
        c.gap = std::min(boundary_distance(world.collision_body(a), world.collision_body(b)),
                         boundary_distance(world.collision_body(b), world.collision_body(a)));
    }
  // --- coarse against surface overlaps: every pair whose surfaces' or coarse meshes' boxes meet ---
  // The coarse mesh of an object is the one it collides with: its simulation mesh, or the tight
  // mesh embedded in it (simulation_mesh, World::embed).
  if (options.details && options.surfaces && nb > 1) {
    std::vector<RestSurface> surf;
    std::vector<meshing::TetMesh> coarse(static_cast<size_t>(nb));
    std::vector<Eigen::AlignedBox3d> coarse_box(static_cast<size_t>(nb));
    for (int b = 0; b < nb; ++b) {
      surf.push_back(rest_surface(w, b));
      coarse[b].V = world.collision_body(b).rest;
      coarse[b].T = world.collision_body(b).T;
      coarse_box[b].setEmpty();
      for (Eigen::Index i = 0; i < coarse[b].V.rows(); ++i) coarse_box[b].extend(Eigen::Vector3d(coarse[b].V.row(i).transpose()));
    }
    std::vector<std::unique_ptr<meshing::FastWindingNumber>> winding(static_cast<size_t>(nb));
    std::vector<std::unique_ptr<meshing::TetLocator>> locator(static_cast<size_t>(nb));
    auto wn = [&](int b) -> const meshing::FastWindingNumber& {
      if (!winding[b]) winding[b] = std::make_unique<meshing::FastWindingNumber>(surf[b].V, surf[b].F);
      return *winding[b];
    };
    auto loc = [&](int b) -> const meshing::TetLocator& {
      if (!locator[b]) locator[b] = std::make_unique<meshing::TetLocator>(coarse[b]);
      return *locator[b];
    };
    for (int a = 0; a < nb; ++a)
      for (int b = a + 1; b < nb; ++b) {
        const bool listed = pairs.count({a, b}) > 0;
        if (!listed && !surf[a].box.intersects(surf[b].box) && !coarse_box[a].intersects(coarse_box[b])) continue;
        OverlapCheck c = listed ? pairs[{a, b}] : OverlapCheck{};
        c.a = a;
        c.b = b;
        c.coarse_a_in_b = fraction_inside(coarse[a].V, loc(b));
        c.coarse_b_in_a = fraction_inside(coarse[b].V, loc(a));
        c.surface_a_in_b = fraction_inside(surf[a].V, surf[b].box, wn(b));
        c.surface_b_in_a = fraction_inside(surf[b].V, surf[a].box, wn(a));
        if (listed || c.coarse_a_in_b + c.coarse_b_in_a + c.surface_a_in_b + c.surface_b_in_a > 0) pairs[{a, b}] = c;
      }
  }
  for (auto& [key, c] : pairs) out.overlaps.push_back(c);

  // --- settle: a copy of the world, no control ---
  if (options.settle > 0) {
    fem::SceneWorld sim = w;
    fem::State s = sim.initial_state();
    const double h = sim.time_step();
    const long long steps = std::min<long long>(20000, std::max<long long>(1, std::llround(std::ceil(options.settle / h - 1e-9))));
    if (options.progress)
      options.progress->stage("checking the scene (a " + format_g3(options.settle) + " s settle)", static_cast<double>(steps));
    for (long long k = 0; k < steps && !out.settle_diverged; ++k) {
      sim.step(s);
      if (options.progress) options.progress->update(static_cast<double>(k + 1));
      out.settle_diverged = fem::diverged(s);
      if (out.settle_diverged) break;
      for (int b = 0; b < nb; ++b) {
        if (world.body(b).rigid) continue;
        const double c = std::abs(world.body_volume(s, b) / w.rest_volume[b] - 1.0);
        if (!(c <= out.objects[b].settle_volume_change)) out.objects[b].settle_volume_change = c;
      }
    }
    out.settle = steps * h;
    if (options.progress) options.progress->finish();
  }

  // --- warnings, in a fixed order: objects, pairs, robot and goal, settle ---
  std::vector<std::string>& warn = out.warnings;
  std::vector<int> robots;
  for (int b = 0; b < nb; ++b)
    if (scene.objects[b].robot) robots.push_back(b);
  for (int b = 0; b < nb; ++b) {
    const ObjectCheck& o = out.objects[b];
    if (!o.rigid && o.below_floor > 0)
      warn.push_back(who(scene, b) + ": " + std::to_string(o.below_floor) + " of its " + std::to_string(o.vertices) +
                     " vertices start below the floor (y = " + format_g3(*scene.floor) + " m), the deepest by " +
                     format_g3(o.below_floor_depth) + " m: the floor penalty pushes them up at once");
    if (!o.rigid && o.hard_pins == o.vertices)
      warn.push_back(who(scene, b) + ": its pins hold every vertex, so it never moves (make it \"kind\": \"rigid\")");
    if (o.robot && (o.hard_pins > 0 || o.soft_pins > 0))
      warn.push_back(who(scene, b) + ": the robot has " + std::to_string(o.hard_pins) + " pinned and " +
                     std::to_string(o.soft_pins) + " softly attached vertices: the planner's forces work against them");
    if (o.robot && o.rigid)
      warn.push_back(who(scene, b) + ": the robot is rigid and never moves: squeeze plan refuses it");
  }
  const bool tolerant = world.options().rest_overlap;
  for (const OverlapCheck& c : out.overlaps) {
    if (c.a == c.b && c.overlapping()) {
      warn.push_back(who(scene, c.a) + ": overlaps itself at rest (" + std::to_string(c.a_in_b) +
                     " vertices inside its own tetrahedra, deepest " + format_g3(c.depth) + " m)" +
                     (tolerant ? ": a contact at rest (contact.rest_overlap)"
                               : ": self-collision pushes them apart at once; set \"self_collision\": false or mend the mesh"));
      continue;
    }
    // As plan::check_robot_start: with rest overlaps, only an object placed inside the other (the
    // centre of one inside the other) is no contact at rest.
    const bool deep = !tolerant || plan::placed_inside(world, c.a, c.b);
    const bool robot_pair = scene.objects[c.a].robot || scene.objects[c.b].robot;
    const std::string counts = std::to_string(c.a_in_b) + " vertices of '" + scene.objects[c.a].name + "' inside '" +
                               scene.objects[c.b].name + "', " + std::to_string(c.b_in_a) + " of '" +
                               scene.objects[c.b].name + "' inside '" + scene.objects[c.a].name + "', deepest " +
                               format_g3(c.depth) + " m";
    if (c.overlapping() && robot_pair) {
      const int r = scene.objects[c.a].robot ? c.a : c.b, other = r == c.a ? c.b : c.a;
      if (deep)
        warn.push_back(who(scene, r) + ": the robot starts inside '" + scene.objects[other].name + "' (" + counts +
                       "): squeeze plan and run refuse to start");
      else
        warn.push_back(who(scene, r) + ": the robot touches '" + scene.objects[other].name + "' at rest (" + counts +
                       "): a contact at rest (contact.rest_overlap); it pushes only deeper than that");
    } else if (c.overlapping()) {
      warn.push_back(who(scene, c.a) + " and " + who(scene, c.b) + " overlap at rest (" + counts + ")" +
                     (tolerant ? ": a contact at rest (contact.rest_overlap)"
                               : ": the contact penalty pushes them apart at once, squeezing them"));
    } else if (robot_pair && c.gap >= 0) {
      const int r = scene.objects[c.a].robot ? c.a : c.b, other = r == c.a ? c.b : c.a;
      const double edge = world.body(r).mean_edge_length();
      if (c.gap < 0.01 * edge)
        warn.push_back(who(scene, r) + ": the robot starts touching '" + scene.objects[other].name + "' (gap " + format_g3(c.gap) +
                       " m, below 1 % of its mean edge length " + format_g3(edge) + " m)");
    }
  }
  for (const OverlapCheck& c : out.overlaps) {
    if (!c.surfaces_measured()) continue;
    const double ab = c.coarse_a_in_b - c.surface_a_in_b, ba = c.coarse_b_in_a - c.surface_b_in_a;
    if (std::max(std::abs(ab), std::abs(ba)) <= 0.02) continue;
    const bool first = std::abs(ab) >= std::abs(ba);
    const int x = first ? c.a : c.b, y = first ? c.b : c.a;
    warn.push_back(who(scene, x) + ": " + percent(first ? c.coarse_a_in_b : c.coarse_b_in_a) +
                   " of its coarse vertices are inside the coarse mesh of '" + scene.objects[y].name + "', " +
                   percent(first ? c.surface_a_in_b : c.surface_b_in_a) +
                   " of its surface vertices inside its surface: the coarse meshes " +
                   ((first ? ab : ba) > 0 ? "overlap more" : "overlap less") +
                   " than the geometry (more than 2 points; docs/meshing.md)");
  }
  if (robots.size() > 1) {
    std::string names;
    for (int r : robots) names += (names.empty() ? "'" : ", '") + scene.objects[r].name + "'";
    warn.push_back("objects: " + std::to_string(robots.size()) + " robots (" + names + "): squeeze plan needs exactly one");
  }
  if (!robots.empty() && !scene.goal)
    warn.push_back(who(scene, robots[0]) + " is the robot but the scene has no goal: squeeze plan and run need one");
  if (robots.empty() && scene.goal)
    warn.push_back("goal: the scene has a goal but no robot: squeeze plan and run need an object with \"role\": \"robot\"");
  if (scene.goal) {
    const Eigen::Vector3d& g = scene.goal->position;
    if (!w.bounds.contains(g))
      warn.push_back("goal.position: [" + format_g3(g.x()) + ", " + format_g3(g.y()) + ", " + format_g3(g.z()) +
                     "] lies outside the bounds of the scene: squeeze plan refuses it");
    if (scene.floor && g.y() < *scene.floor)
      warn.push_back("goal.position: lies below the floor (y = " + format_g3(*scene.floor) + " m): no object can reach it");
  }
  if (scene.time_step && scene.integrator == "verlet") {
    const fem::TimeStepChoice a = fem::auto_time_step(world, scene);
    if (*scene.time_step > a.h * (1 + 1e-9))
      warn.push_back("time_step: " + format_g3(*scene.time_step) + " s is " + format_g3(*scene.time_step / a.h) +
                     " times the stable Verlet step estimated for the meshes (" + format_g3(a.h) + " s, " + a.term + " of '" +
                     (a.object >= 0 ? scene.objects[a.object].name : std::string("?")) +
                     "'): it may diverge; the estimate is conservative" +
                     (out.settle > 0 && !out.settle_diverged ? " and the " + format_g3(out.settle) + " s settle did not diverge"
                                                              : std::string()));
  }
  if (out.settle_diverged)
    warn.push_back("the simulation diverges within " + format_g3(out.settle) + " s at the time step " + format_g3(w.time_step()) +
                   " s: lower time_step or the stiffnesses");
  if (out.max_volume_change && !out.settle_diverged) {
    const double limit = *out.max_volume_change;
    for (int b = 0; b < nb; ++b) {
      const double c = out.objects[b].settle_volume_change;
      if (out.objects[b].rigid) continue;
      if (c >= limit)
        warn.push_back(who(scene, b) + ": its volume changes by " + percent(c) + " within " + format_g3(out.settle) +
                       " s without any control, beyond planner.max_volume_change (" + format_g3(100 * limit) + " %" +
                       "): every expansion will be discarded");
      else if (c >= 0.5 * limit)
        warn.push_back(who(scene, b) + ": its volume changes by " + percent(c) + " within " + format_g3(out.settle) +
                       " s without any control, more than half of planner.max_volume_change (" + format_g3(100 * limit) + " %" +
                       "): many expansions will be discarded");
    }
  }
  return out;
}

}  // namespace squeeze::plan
