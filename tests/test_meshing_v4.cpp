// Meshing version 4 on shapes generated here, which the corpus does not hold (issue 16): boxes and
// plates come out exact, a slot keeps its gap, many parts stay many, a scan with holes is closed.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "meshing_test_util.h"
#include "shapes.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/chord_volume.h"
#include "squeeze/meshing/envelope.h"
#include "squeeze/meshing/mesh_pipeline.h"
#include "squeeze/meshing/point_triangle_distance.h"
#include "squeeze/meshing/remesh.h"
#include "squeeze/meshing/shell_tetrahedralize.h"
#include "squeeze/meshing/split_long_edges.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_cleanup.h"
#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_locator.h"
#include "squeeze/meshing/tet_quality.h"
#include "squeeze/meshing/tetrahedralize.h"
#include "squeeze/meshing/surface_analysis.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/triangle_intersection.h"
#include "squeeze/meshing/winding_number.h"
#include "squeeze/meshing/winding_tetrahedralize.h"

namespace {

// tetrahedralize() of s at `target` tetrahedra in one attempt (one interior edge length), its
// options changed by `set` first: the tests of one option against its default or none.
template <class Set>
squeeze::meshing::TetMesh one_run(const squeeze::meshing::SurfaceMesh& s, int target, Set&& set, squeeze::meshing::TetrahedralizeStats& st) {
  squeeze::meshing::TetrahedralizeOptions o;
  o.target_tets = target;
  o.max_attempts = 1;
  set(o);
  return squeeze::meshing::tetrahedralize(s, o, &st);
}

using squeeze::meshing::bounding_box_diagonal;
using squeeze::meshing::MeshOptions;
using squeeze::meshing::MeshResult;
using squeeze::meshing::SurfaceMesh;
using sqt::join;
using Vec3 = Eigen::Vector3d;
namespace fs = std::filesystem;

using sqt::surface_of;

/// The surface of the box [lo, hi] with each side divided into n pieces along each axis (n(k) >= 1):
/// (n0+1)(n1+1)(n2+1) - (n0-1)(n1-1)(n2-1) vertices, outward triangles.
SurfaceMesh box(const Vec3& lo, const Vec3& hi, std::array<int, 3> n = {1, 1, 1}) {
  std::map<std::array<int, 3>, int> id;
  std::vector<Vec3> V;
  std::vector<std::array<int, 3>> F;
  auto vertex = [&](std::array<int, 3> g) {
    auto [it, fresh] = id.try_emplace(g, static_cast<int>(V.size()));
    if (fresh) {
      Vec3 p;
      for (int k = 0; k < 3; ++k) p(k) = lo(k) + (hi(k) - lo(k)) * g[static_cast<size_t>(k)] / n[static_cast<size_t>(k)];
      V.push_back(p);
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < n[static_cast<size_t>(u)]; ++i)
        for (int j = 0; j < n[static_cast<size_t>(v)]; ++j) {
          std::array<int, 3> g[4];
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int c = 0; c < 4; ++c) {
            g[c][static_cast<size_t>(axis)] = side * n[static_cast<size_t>(axis)];
            g[c][static_cast<size_t>(u)] = i + di[c];
            g[c][static_cast<size_t>(v)] = j + dj[c];
          }
          int q[4];
          for (int c = 0; c < 4; ++c) q[c] = vertex(g[c]);
          // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
          if (side == 1) F.push_back({q[0], q[1], q[2]}), F.push_back({q[0], q[2], q[3]});
          else F.push_back({q[0], q[2], q[1]}), F.push_back({q[0], q[3], q[2]});
        }
    }
  return surface_of(V, F);
}

/// The part `outer` with the closed surface `inner` (inside it) as its cavity: inner's faces turned
/// to face into the hollow, as CAD exports a hollow part.
SurfaceMesh with_cavity(const SurfaceMesh& outer, const SurfaceMesh& inner) {
  SurfaceMesh m = join({outer, inner});
  for (Eigen::Index f = outer.F.rows(); f < m.F.rows(); ++f) std::swap(m.F(f, 1), m.F(f, 2));
  return m;
}

/// An icosphere (`levels` subdivisions of the icosahedron) of radius r about c.
SurfaceMesh sphere(const Vec3& c, double r, int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> V = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> F = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& v : V) v.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto m = [&](int a, int b) {
      auto [it, fresh] = mid.try_emplace({std::min(a, b), std::max(a, b)}, static_cast<int>(V.size()));
      if (fresh) V.push_back((V[static_cast<size_t>(a)] + V[static_cast<size_t>(b)]).normalized());
      return it->second;
    };
    std::vector<std::array<int, 3>> G;
    for (const auto& f : F) {
      const int a = m(f[0], f[1]), b = m(f[1], f[2]), d = m(f[2], f[0]);
      G.push_back({f[0], a, d}), G.push_back({f[1], b, a}), G.push_back({f[2], d, b}), G.push_back({a, b, d});
    }
    F = G;
  }
  for (auto& v : V) v = c + r * v;
  return surface_of(V, F);
}

double box_volume(const Vec3& lo, const Vec3& hi) { return (hi - lo).prod(); }

MeshResult mesh(const SurfaceMesh& s, int target) {
  MeshOptions o;
  if (target > 0) o.tetrahedralize.target_tets = target;
  return squeeze::meshing::mesh_surface(s, o);
}

double tet_volume(const squeeze::meshing::TetMesh& m) {
  double v = 0;
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) {
    const Vec3 a = m.V.row(m.T(t, 0)), b = m.V.row(m.T(t, 1)), c = m.V.row(m.T(t, 2)), d = m.V.row(m.T(t, 3));
    v += (b - a).cross(c - a).dot(d - a) / 6.0;
  }
  return v;
}

/// `s` with every vertex turned by R and then moved by `shift`.
SurfaceMesh turned(SurfaceMesh s, const Eigen::Matrix3d& R, const Vec3& shift) {
  for (Eigen::Index i = 0; i < s.V.rows(); ++i) s.V.row(i) = (R * s.V.row(i).transpose() + shift).transpose();
  return s;
}

/// x as a file that keeps 9 significant digits has it.
double nine_digits(double x) { return sqs::significant_digits(x, 9); }

/// Random placements of the turned-plate tests: a turn by 0.1-3 rad about an axis of normally
/// distributed coordinates, then a shift of standard normal coordinates; the same sequence for a seed.
struct RandomPlacements {
  explicit RandomPlacements(unsigned seed) : rng(seed) {}
  Eigen::Matrix3d turn() { return Eigen::AngleAxisd(angle(rng), Vec3(g(rng), g(rng), g(rng)).normalized()).toRotationMatrix(); }
  Vec3 shift() { return Vec3(g(rng), g(rng), g(rng)); }
  std::mt19937 rng;
  std::normal_distribution<double> g{0.0, 1.0};
  std::uniform_real_distribution<double> angle{0.1, 3.0};
};

/// Interior faces whose two tetrahedra lie on the same side of them (one of the two inverted over
/// the other): 0 in a mesh that is a proper tetrahedralization.
int folded_faces(const squeeze::meshing::TetMesh& m) {
  using squeeze::meshing::kTetFace;
  const squeeze::meshing::TetFaces faces = squeeze::meshing::tet_faces(m.T);
  int folded = 0;
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      const int n = faces.neighbor(t, k);
      if (n <= t) continue;  // each interior face once
      int j = 0;             // n's vertex opposite the shared face
      while (faces.neighbor(n, j) != t) ++j;
      const Vec3 a = m.V.row(m.T(t, kTetFace[k][0])), b = m.V.row(m.T(t, kTetFace[k][1])),
                 c = m.V.row(m.T(t, kTetFace[k][2]));
      const Vec3 normal = (b - a).cross(c - a);
      folded += normal.dot(Vec3(m.V.row(m.T(t, k))) - a) * normal.dot(Vec3(m.V.row(m.T(n, j))) - a) > 0;
    }
  return folded;
}

/// The issue's bounds on a mesh of one closed input: volume ratio within `volume` of 1, deviations
/// out and in within the given fractions of the diagonal, the dihedral floor of 5°, `components`
/// pieces.
void expect_within(const MeshResult& r, double diag, double volume, double out, double in, int components) {
  if (r.deviation_out <= 0.015 * diag) {
    EXPECT_EQ(r.deviation_exceeded_because, "");  // (1.5 × the default bound)
  }
  ASSERT_TRUE(r.volume_ratio.has_value());
  EXPECT_NEAR(*r.volume_ratio, 1.0, volume);
  EXPECT_LE(r.deviation_out, out * diag);
  EXPECT_LE(r.deviation_in, in * diag);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_EQ(r.quality.components, components);
}

/// A closed part meshed at each target as one thin part (one layer of prisms), conforming, within
/// expect_within's bounds (one piece).
void expect_one_slab(const SurfaceMesh& s, std::initializer_list<int> targets, double volume, double out, double in) {
  const double diag = bounding_box_diagonal(s.V);
  for (int target : targets) {
    SCOPED_TRACE("target " + std::to_string(target));
    const MeshResult r = mesh(s, target);
    EXPECT_EQ(r.thin_parts, 1);
    EXPECT_TRUE(r.tet_stats.conforming);
    expect_within(r, diag, volume, out, in, 1);
  }
}

struct BoxCase {
  const char* name;
  Vec3 lo, hi;
  std::array<int, 3> n;
};

const BoxCase kBoxes[] = {
    {"curtain 1 x 0.6 x 0.02, 8 vertices", {0, 0, 0}, {1, 0.6, 0.02}, {1, 1, 1}},
    {"plate 1 x 0.04 x 0.3, 84 vertices", {0, 0, 0}, {1, 0.04, 0.3}, {6, 1, 5}},
    {"slot jaw 0.1 x 0.5 x 0.3, 8 vertices", {0.09, 0, 0}, {0.19, 0.5, 0.3}, {1, 1, 1}},
    {"cube 0.3, 26 vertices", {-0.15, -0.15, -0.15}, {0.15, 0.15, 0.15}, {2, 2, 2}},
};

// Boxes and plates come out exact: volume within 1 %, every tet vertex within 0.2 % of the
// diagonal of the box (no inflation), the report's deviations within 0.2 %, one component,
// dihedral angles of at least 5 degrees; at the issue's targets and the default.
TEST(MeshingV4, BoxesAndPlatesComeOutExact) {
  for (const BoxCase& c : kBoxes)
    for (int target : {150, 300, 1000, 0}) {
      const std::string what = std::string(c.name) + " at target " + (target ? std::to_string(target) : "default");
      const SurfaceMesh s = box(c.lo, c.hi, c.n);
      const MeshResult r = mesh(s, target);
      const double diag = (c.hi - c.lo).norm();
      ASSERT_GT(r.tets.T.rows(), 0) << what;
      EXPECT_NEAR(tet_volume(r.tets) / box_volume(c.lo, c.hi), 1.0, 0.01) << what;
      for (Eigen::Index i = 0; i < r.tets.V.rows(); ++i)
        for (int k = 0; k < 3; ++k) {
          EXPECT_GE(r.tets.V(i, k), c.lo(k) - 0.002 * diag) << what << ", vertex " << i;
          EXPECT_LE(r.tets.V(i, k), c.hi(k) + 0.002 * diag) << what << ", vertex " << i;
        }
      EXPECT_LE(r.deviation_out, 0.002 * diag) << what;
      EXPECT_LE(r.deviation_in, 0.002 * diag) << what;
      EXPECT_EQ(r.quality.components, 1) << what;
      if (target > 0 && r.target_exceeded_because.empty()) {
        EXPECT_GE(r.quality.tets, 0.65 * target) << what;
        EXPECT_LE(r.quality.tets, 1.35 * target) << what;
      }
    }
}

// The same boxes, and a plate 6 mm thick, turned about an axis along no box edge and moved away
// from the origin: still exact (their corners now carry rounding). The 6 mm plate at 300 had its
// slab 0.26 % of the diagonal inside (meshing version 41): the ray from a rim vertex of its
// mid-surface ran along a side wall, Möller–Trumbore met that wall at a random parameter, and the
// slab lost half its thickness there.
TEST(MeshingV4, BoxesAndPlatesTurnedInSpaceComeOutExact) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 shift(3, -2, 5);
  std::vector<BoxCase> cases(std::begin(kBoxes), std::end(kBoxes));
  cases.push_back({"plate 0.8 x 0.4 x 0.006, 8 vertices", {0, 0, 0}, {0.8, 0.4, 0.006}, {1, 1, 1}});
  for (const BoxCase& c : cases)
    for (int target : {150, 300, 1000}) {
      const std::string what = std::string(c.name) + ", turned, at target " + std::to_string(target);
      const SurfaceMesh s = turned(box(c.lo, c.hi, c.n), R, shift);
      const MeshResult r = mesh(s, target);
      const double diag = (c.hi - c.lo).norm();
      ASSERT_GT(r.tets.T.rows(), 0) << what;
      EXPECT_NEAR(tet_volume(r.tets) / box_volume(c.lo, c.hi), 1.0, 0.01) << what;
      for (Eigen::Index i = 0; i < r.tets.V.rows(); ++i) {
        const Vec3 x = R.transpose() * (r.tets.V.row(i).transpose() - shift);  // back in the box's frame
        for (int k = 0; k < 3; ++k) {
          EXPECT_GE(x(k), c.lo(k) - 0.002 * diag) << what << ", vertex " << i;
          EXPECT_LE(x(k), c.hi(k) + 0.002 * diag) << what << ", vertex " << i;
        }
      }
      // (The report's deviations are fractions of the input's bounding-box diagonal, which a turn
      // lengthens: 1.18 m for the 6 mm plate, whose own diagonal is 0.89 m.)
      const double input_diag = squeeze::meshing::bounding_box_diagonal(s.V);
      EXPECT_LE(r.deviation_out, 0.002 * input_diag) << what;
      EXPECT_LE(r.deviation_in, 0.002 * input_diag) << what;
      EXPECT_EQ(r.quality.components, 1) << what;
      EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
    }
}

// Cells of no volume on a turned plate's faces (meshing version 43). Turned in space, the points
// of a face (its corners, split points and lattice) are coplanar only up to rounding, so Delaunay
// makes cells of four of them on the face, inside by parity. Refined, each asked for splits of the
// surface that made more: the 6 mm plate at 2000 took 16 s in 4 attempts (under 1 s axis-aligned).
// Flipping the surface's diagonal under such a cell puts it outside, the surface where it was. On
// three placements at 1000, one attempt each: the flips happen, the plates come out exact and
// conforming, and refinement searches under half the cells it did without them (4.3 million
// against 10.5 million when this was written) for fewer boundary splits (462 against 846).
// (The 4 mm plate also came out 1.00027 of its volume: a nearly flat cell across it, turned the
// wrong way round by a floating-point orientation test, was inflated inverted by the sliver moves;
// tetrahedralize now keeps CGAL's orientation until they are done, and no face is folded.)
TEST(MeshingV4, FlatCellsOnATurnedPlatesFacesAreFlippedOutsideNotRefined) {
  struct Placement {
    Vec3 size;
    double angle;
    Vec3 axis, shift;
  };
  const Placement placements[] = {{{0.8, 0.4, 0.006}, 0.7, {1, 2, 3}, {3, -2, 5}},
                                  {{0.8, 0.4, 0.006}, 1.1, {-2, 1, 0.5}, {-1, 4, 2}},
                                  {{0.5, 0.5, 0.004}, 2.0, {1, 1, 1}, {0, 0, 0}}};
  double work_with = 0, work_without = 0;
  int splits_with = 0, splits_without = 0;
  for (const Placement& p : placements) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(p.angle, p.axis.normalized()).toRotationMatrix();
    const SurfaceMesh s = turned(box(Vec3::Zero(), p.size), R, p.shift);
    squeeze::meshing::TetrahedralizeOptions o;
    o.target_tets = 1000;
    o.max_attempts = 1;
    squeeze::meshing::TetrahedralizeStats with, without;
    const squeeze::meshing::TetMesh m = squeeze::meshing::tetrahedralize(s, o, &with);
    o.flip_flat_surface_cells = false;
    squeeze::meshing::tetrahedralize(s, o, &without);
    const std::string what = "plate " + std::to_string(p.size(2)) + " thick, turned " + std::to_string(p.angle);
    EXPECT_GT(with.flat_cells_flipped, 0) << what;
    EXPECT_EQ(without.flat_cells_flipped, 0) << what;
    EXPECT_TRUE(with.conforming) << what;
    EXPECT_NEAR(tet_volume(m) / p.size.prod(), 1.0, 1e-9) << what;
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
      const Vec3 x = R.transpose() * (m.V.row(i).transpose() - p.shift);  // in the plate's frame
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(x(k), -1e-9) << what << ", vertex " << i;
        EXPECT_LE(x(k), p.size(k) + 1e-9) << what << ", vertex " << i;
      }
    }
    EXPECT_GE(squeeze::meshing::tet_quality(m).min_dihedral, 5.0) << what;
    EXPECT_EQ(folded_faces(m), 0) << what;
    work_with += with.refine_work, work_without += without.refine_work;
    splits_with += with.boundary_splits, splits_without += without.boundary_splits;
  }
  EXPECT_LT(work_with, 0.5 * work_without);
  EXPECT_LT(splits_with, splits_without);
}

// A small part of a large model gets the safety net max_tets by its share of the volume (1,000 at
// least: 333 points), and its boundary alone can have more points than that. Refinement then never
// ran, and the exuder was left with cells of 0.2°: trimesh's counter.unitsmm.STL (a plate and five
// screws of 1,262 boundary faces each) kept 3.2-4.9° in three screws. Since meshing version 44 the
// net is never below twice the points of the recovered boundary. An ellipsoid of 1,280 faces (642
// points, all on its surface) under that small net is refined to the floor and keeps its volume
// within 0.1 % (boundary slivers peeled); under a net of 10 tetrahedra as well. With version 43's
// net it was not refined at all (4.99°, 0.19 % of its volume lost).
TEST(MeshingV4, SmallPartsBoundaryIsRefinedWhateverItsShareOfTheNet) {
  SurfaceMesh s = sphere(Vec3::Zero(), 1.0, 3);
  s.V = s.V * Eigen::Vector3d(0.01, 0.008, 0.006).asDiagonal();  // (an ellipsoid: not one sphere)
  ASSERT_EQ(s.V.rows(), 642);
  const double volume = sqt::enclosed_volume(s);
  ASSERT_GT(volume, 0);
  for (const int net : {1000, 10}) {
    squeeze::meshing::TetrahedralizeOptions o;
    o.target_tets = 1;  // (the screws' share of 300)
    o.max_tets = net;
    o.max_attempts = 1;
    squeeze::meshing::TetrahedralizeStats st;
    const squeeze::meshing::TetMesh m = squeeze::meshing::tetrahedralize(s, o, &st);
    const std::string what = "net " + std::to_string(net);
    EXPECT_TRUE(st.conforming) << what;
    EXPECT_GT(st.steiner_points + st.boundary_splits, 0) << what << ": refined";
    EXPECT_GE(squeeze::meshing::tet_quality(m).min_dihedral, 5.0) << what;
    EXPECT_NEAR(tet_volume(m) / volume, 1.0, 1e-3) << what;  // (boundary slivers peeled)
  }
}

// Conformity recovery's cap (four points per point of the recovered boundary) is on recovery's
// own splits: the points refinement adds do not count against it (meshing version 45). The plate
// with 3 mm ribs (sqs::ribbed_plate) at 150 recovers its 332 points, then refinement splits its
// boundary round after round; before, the tenth round's recovery found 1,533 points over the cap
// of 1,528 and gave up, every attempt lost its boundary, and squeeze mesh went on to a remeshed
// surface (12 s, 6,228 tetrahedra). Now the first attempt keeps it: exact, at 5 degrees or more.
TEST(MeshingV4, RefinementPointsDoNotCountAgainstTheRecoveryCap) {
  const SurfaceMesh s = sqs::ribbed_plate();
  const double volume = sqt::enclosed_volume(s);
  ASSERT_GT(volume, 0);
  squeeze::meshing::TetrahedralizeOptions o;
  o.target_tets = 150;
  o.max_attempts = 1;
  squeeze::meshing::TetrahedralizeStats st;
  const squeeze::meshing::TetMesh m = squeeze::meshing::tetrahedralize(s, o, &st);
  EXPECT_TRUE(st.conforming);
  EXPECT_GT(st.boundary_splits, 1000);  // (refinement's splits: well over the cap's margin)
  EXPECT_NEAR(tet_volume(m) / volume, 1.0, 1e-9);
  EXPECT_GE(squeeze::meshing::tet_quality(m).min_dihedral, 5.0);
}

// TriangleBvh: a segment in a triangle's plane crosses nothing, turned any way. From each corner
// of a 6 mm box's top face, 3 thicknesses straight down (along its side walls, which hold the
// segment up to rounding): the first crossing, if any, is the bottom face, at a third of the way.
// Through the middle of the top face, from above: crossed half way. Before meshing version 42 a
// rounding-level determinant passed, and a side wall was met at a random parameter.
TEST(MeshingTriangleBvh, SegmentsInATrianglesPlaneCrossNothing) {
  RandomPlacements placements(42);
  int wrong = 0, crossed_middle = 0;
  const int turns = 200;
  for (int k = 0; k < turns; ++k) {
    const Eigen::Matrix3d R = placements.turn();
    const Vec3 shift = placements.shift();
    const Vec3 hi(0.8, 0.4, 0.006);
    const SurfaceMesh s = turned(box(Vec3::Zero(), hi), R, shift);
    const squeeze::meshing::TriangleBvh bvh(s.V, s.F);
    const Vec3 down = -R.col(2);
    for (const Vec3& corner : {Vec3(0, 0, hi(2)), Vec3(hi(0), 0, hi(2)), Vec3(0, hi(1), hi(2)), Vec3(hi(0), hi(1), hi(2))}) {
      const Vec3 a = R * corner + shift;
      double t = -1;
      if (bvh.first_crossing(a, a + 3 * hi(2) * down, 1e-4, &t) && std::abs(t - 1.0 / 3.0) > 1e-6) ++wrong;
    }
    const Vec3 top = R * Vec3(0.3, 0.1, hi(2)) + shift;
    double t = -1;
    crossed_middle += bvh.first_crossing(top - 0.01 * down, top + 0.01 * down, 0.0, &t) && std::abs(t - 0.5) < 1e-9;
  }
  EXPECT_EQ(wrong, 0) << "of " << 4 * turns << " segments along side walls";
  EXPECT_EQ(crossed_middle, turns);
}

// ... and where the file keeps few digits: a wall written with 9 significant digits stands off
// its plane by about 1e-9, over the determinant bound above for a long, thin wall triangle. From
// the middle of each top edge of a 6 mm plate (its vertices rounded to 9 digits), 3 thicknesses
// along the top face's inward normal: no crossing but the bottom face, at a third of the way.
// Before meshing version 46 the wall was met at a random parameter (a star-shaped plate's slab
// put its rim 0.14 mm from one side instead of half way).
TEST(MeshingTriangleBvh, SegmentsAlongAWallOfFewDigitsCrossNothing) {
  RandomPlacements placements(46);
  int wrong = 0, crossed = 0;
  const int turns = 200;
  for (int k = 0; k < turns; ++k) {
    const Eigen::Matrix3d R = placements.turn();
    const Vec3 hi(0.8, 0.4, 0.006);
    const Vec3 shift = placements.shift();
    SurfaceMesh s = turned(box(Vec3::Zero(), hi), R, shift);
    s.V = s.V.unaryExpr(&nine_digits);
    const squeeze::meshing::TriangleBvh bvh(s.V, s.F);
    // The top face's corners, as the file has them.
    auto vertex = [&](const Vec3& local) { return Vec3((R * local + shift).unaryExpr(&nine_digits)); };
    const Vec3 c00 = vertex(Vec3(0, 0, hi(2))), c10 = vertex(Vec3(hi(0), 0, hi(2))), c01 = vertex(Vec3(0, hi(1), hi(2))),
               c11 = vertex(Vec3(hi(0), hi(1), hi(2)));
    const Vec3 down = -(c10 - c00).cross(c01 - c00).normalized();
    for (const auto& [p, q] : {std::pair{c00, c10}, std::pair{c10, c11}, std::pair{c11, c01}, std::pair{c01, c00}}) {
      const Vec3 a = 0.5 * (p + q);
      double t = -1;
      if (bvh.first_crossing(a, a + 3 * hi(2) * down, 1e-4, &t)) {
        ++crossed;
        if (std::abs(t - 1.0 / 3.0) > 1e-6) ++wrong;
      }
    }
  }
  EXPECT_EQ(wrong, 0) << "of " << 4 * turns << " segments along side walls written with 9 digits";
  EXPECT_GT(crossed, 0);
}

// A five-pointed star 0.4 m across and 2 mm thick, turned in space and written with 9 digits (a
// plate, so exact: the issue's 1 % of volume and 0.2 % of the diagonal). At 150 and 300 it is one
// layer of prisms; before meshing version 46 the rays that set its rim's thickness met the side
// walls (TriangleBvh, few digits), and the slab stood 0.86 mm out of one side and 1.36 mm in
// from the other: 0.26 % of the diagonal in, 1.2 % of the volume lost.
TEST(MeshingV4, StarPlateOfFewDigitsTurnedIsExact) {
  std::vector<Eigen::Vector2d> P;
  for (int k = 0; k < 10; ++k) {
    const double r = k % 2 == 0 ? 0.2 : 0.08, a = 2 * M_PI * k / 10;
    P.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  SurfaceMesh s = turned(sqs::extruded(P, 0.002), Eigen::AngleAxisd(0.8, Vec3(0.3, 1, 0.2).normalized()).toRotationMatrix(),
                         Vec3::Zero());
  s.V = s.V.unaryExpr(&nine_digits);
  const double diag = bounding_box_diagonal(s.V);
  for (int target : {150, 300}) {
    SCOPED_TRACE("target " + std::to_string(target));
    const MeshResult r = mesh(s, target);
    EXPECT_EQ(r.thin_parts, 1);
    expect_within(r, diag, 0.01, 0.002, 0.002, 1);
    EXPECT_GE(r.quality.min_dihedral, 5.0);
  }
}

// TriangleBvh against every triangle, on the real meshes of tests/data: nearest() gives the
// smallest distance and, of the triangles at it, the lowest index; under a bound, that or
// nothing; any_within() whether the smallest distance is within r (at most r). At points near the surface on
// both sides (along each vertex's offset to its neighbour, scaled) and spread over the box.
TEST(MeshingTriangleBvh, AgreesWithEveryTriangleOnTheDataMeshes) {
  for (const char* name : {"bunny00.off", "ChineseDragon-10kv.off", "elephant.off", "sphere.off"}) {
    SCOPED_TRACE(name);
    const SurfaceMesh m = squeeze::meshing::load_surface(std::string(SQUEEZE_TEST_DATA) + "/" + name);
    const squeeze::meshing::TriangleBvh bvh(m.V, m.F);
    const Vec3 lo = m.V.colwise().minCoeff().transpose(), hi = m.V.colwise().maxCoeff().transpose();
    const double diag = (hi - lo).norm();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Vec3> points;
    for (int i = 0; i < 150; ++i) {
      const Eigen::Index f = static_cast<Eigen::Index>(rng() % static_cast<unsigned>(m.F.rows()));
      const Vec3 a = m.V.row(m.F(f, 0)).transpose(), b = m.V.row(m.F(f, 1)).transpose(), c = m.V.row(m.F(f, 2)).transpose();
      const Vec3 n = (b - a).cross(c - a).normalized();
      points.push_back((a + b + c) / 3.0 + (unit(rng) - 0.5) * 0.04 * diag * n);
      points.push_back(a);  // on a vertex: ties between the triangles around it
      points.push_back(lo + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(hi - lo));
    }
    for (const Vec3& p : points) {
      double best = INFINITY;
      int best_face = -1;
      for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
        const Vec3 q = squeeze::meshing::closest_point_on_triangle(p, m.V.row(m.F(f, 0)).transpose(),
                                                                   m.V.row(m.F(f, 1)).transpose(), m.V.row(m.F(f, 2)).transpose());
        const double d2 = (q - p).squaredNorm();
        if (d2 < best) best = d2, best_face = static_cast<int>(f);
      }
      best = std::sqrt(best);
      int face = -2;
      Vec3 closest;
      ASSERT_EQ(bvh.nearest(p, &face, &closest), best);
      EXPECT_EQ(face, best_face);
      EXPECT_NEAR((closest - p).norm(), best, 1e-12 * diag);
      for (double r : {0.5 * best, 2.0 * best, 0.01 * diag}) {
        const double bounded = bvh.nearest(p, &face, nullptr, r);
        if (best < r) {
          EXPECT_EQ(bounded, best);
          EXPECT_EQ(face, best_face);
        } else {
          EXPECT_EQ(bounded, INFINITY);
          EXPECT_EQ(face, -1);
        }
        EXPECT_EQ(bvh.any_within(p, r), best <= r) << "r " << r << ", nearest " << best;
      }
    }
  }
}

// A rod 2 m long and 1 cm across, turned, 100 m from the origin, written with 7 digits (meshing
// version 47): its faces are flat only to about 1e-5 m, a thousandth of its width, so refinement on
// its own 12 faces stops at its work bound (MeshOptions::skinny_refine_work). That first attempt
// holds all the same and is kept, the box's own faces. Before, the boundary split into rounder
// triangles took its place: at 1000, this rod kept a simplified split boundary of 1,552 faces; the
// same rod of another triangulation (a file written so) took one that was not conforming, and 11 s
// of retries after it.
TEST(MeshingV4, FewDigitRodFarFromTheOriginKeepsItsOwnFaces) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.2, Vec3(0.2, 0.3, 1).normalized()).toRotationMatrix();
  SurfaceMesh s = turned(box({-1, -0.005, -0.005}, {1, 0.005, 0.005}), R, Vec3(100, -50, 20));
  s.V = s.V.unaryExpr([](double x) { return sqs::significant_digits(x, 7); });
  const double diag = bounding_box_diagonal(s.V);
  const MeshResult r = mesh(s, 1000);
  EXPECT_EQ(r.boundary.F.rows(), 12);
  EXPECT_TRUE(r.tet_stats.conforming);
  expect_within(r, diag, 0.01, 0.002, 0.002, 1);
}

// Round plates, as a CAD tessellation gives them: a disc 0.4 m across and 5 mm thick, of 32 and
// 128 sides, turned in space, comes out within a plate's bounds at 150 and 300 (volume 1 %,
// 0.2 % of the diagonal each way), one piece: where the target's faces are fewer than the
// disc's, the simplification cuts its rim's chords only within them (128 sides: 0.085 % each way
// and 0.997 of the volume when this was written; 32 sides: exact).
TEST(MeshingV4, RoundPlatesTurnedInSpaceComeOutWithinAPlatesBounds) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.9, Vec3(2, -1, 1).normalized()).toRotationMatrix();
  for (int sides : {32, 128}) {
    const SurfaceMesh s = turned(sqs::disc(0.2, 0.005, sides), R, Vec3(1, 2, -3));
    const double diag = bounding_box_diagonal(s.V);
    for (int target : {150, 300}) {
      SCOPED_TRACE(std::to_string(sides) + " sides at " + std::to_string(target));
      expect_within(mesh(s, target), diag, 0.01, 0.002, 0.002, 1);
    }
  }
}

// A coin (48 sides, 0.1 m across, 4 mm thick, turned) at 150: its tetrahedra are set by its
// thickness (over 1,000 whatever its boundary), so its boundary is made again with its faces
// (meshing version 48). Before, it was simplified to the target's 168 faces, of 42 sides: 0.33 % of
// the diagonal out and in (MeshOptions::more_faces_where_over_target false gives that back).
TEST(MeshingV4, ThinRoundPlateKeepsItsOutlineWhereItsThicknessSetsTheCount) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.1, Vec3(0.3, 1, 0.5).normalized()).toRotationMatrix();
  const SurfaceMesh s = turned(sqs::disc(0.05, 0.004, 48), R, Vec3(0.8, 0.6, -0.3));
  const double diag = bounding_box_diagonal(s.V);
  const MeshResult r = mesh(s, 150);
  expect_within(r, diag, 0.01, 0.0005, 0.0005, 1);
  EXPECT_EQ(r.boundary.F.rows(), s.F.rows());
  EXPECT_FALSE(r.target_exceeded_because.empty());
}

// An input of more triangles than MeshOptions::dense_faces is meshed through its decimated proxy
// (version 49), and what the result says of its input is the input's: its faces, and deviations
// measured against it within the bounds asked. Since version 54 the default threshold (30,000)
// takes the corpus bunny (75,408 faces): its own envelope's edge collapses took most of its 9 s.
TEST(MeshingV4, DenseInputIsMeshedThroughItsProxyAndMeasuredAgainstItself) {
  const SurfaceMesh s = squeeze::meshing::load_surface(sqt::data("bunny00.off"));
  const double diag = bounding_box_diagonal(s.V);
  MeshOptions o;
  o.tetrahedralize.target_tets = 300;
  const MeshResult r = squeeze::meshing::mesh_surface(s, o);
  EXPECT_GT(r.proxy_faces, 0);
  EXPECT_LE(r.proxy_faces, s.F.rows() - o.dense_min_saving);
  EXPECT_NEAR(r.proxy_error, 0.1 * 0.45 * 0.01 * diag, 1e-12 * diag);
  EXPECT_EQ(r.input.F.rows(), s.F.rows());
  EXPECT_EQ(r.info.faces, s.F.rows());
  EXPECT_EQ(r.input.V, s.V);
  expect_within(r, diag, 0.02, 0.015, 0.005, 1);  // (the issue's bounds: at 300 the proxy's mesh is
                                                  // 0.452 % in when this was written, against the
                                                  // input; the bunny's own surface gives 0.449 %)
  // The report says so.
  const auto report = squeeze::meshing::mesh_report(r, "bunny00.off");
  EXPECT_EQ(report["proxy"]["faces"].get<int>(), r.proxy_faces);
  EXPECT_EQ(report["input"]["faces"].get<int>(), s.F.rows());
  // A proxy's bound of the whole inner bound or more is refused.
  o.dense_error = 1;
  EXPECT_THROW(squeeze::meshing::mesh_surface(s, o), squeeze::InputError);
  // Without the proxy, no proxy.
  EXPECT_TRUE(squeeze::meshing::mesh_report(mesh(sqs::disc(0.05, 0.004, 12), 150), "disc")["proxy"].is_null());
}

// The proxy is meshed only where it has at least dense_min_saving triangles fewer than the input
// (version 54); else the input itself is, and the result is the one without a proxy (a bumpy
// sphere of 20,480 faces kept 20,380 in its proxy, took four times the seconds through it and
// lay 0.526 % of the diagonal in). Here a Loop-subdivided disc with the threshold lowered to 1.
TEST(MeshingV4, ProxyIsMeshedOnlyWhereItSavesEnoughFaces) {
  const SurfaceMesh s = sqs::loop_subdivided(sqs::disc(0.05, 0.01, 16), 2);
  MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.dense_faces = 0;
  const MeshResult own = squeeze::meshing::mesh_surface(s, o);
  ASSERT_EQ(own.proxy_faces, 0);
  o.dense_faces = 1;
  o.dense_min_saving = 0;
  const MeshResult kept = squeeze::meshing::mesh_surface(s, o);
  ASSERT_GT(kept.proxy_faces, 0);
  ASSERT_LT(kept.proxy_faces, s.F.rows());
  // A saving one face more than the proxy's: the input itself, the same mesh as without a proxy.
  o.dense_min_saving = static_cast<int>(s.F.rows()) - kept.proxy_faces + 1;
  const MeshResult not_kept = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(not_kept.proxy_faces, 0);
  EXPECT_EQ(not_kept.tets.T, own.tets.T);
  EXPECT_EQ(not_kept.tets.V, own.tets.V);
  EXPECT_TRUE(squeeze::meshing::mesh_report(not_kept, "disc")["proxy"].is_null());
  // ... and exactly the saving asked for: the proxy.
  o.dense_min_saving -= 1;
  EXPECT_EQ(squeeze::meshing::mesh_surface(s, o).proxy_faces, kept.proxy_faces);
  o.dense_min_saving = -1;
  EXPECT_THROW(squeeze::meshing::mesh_surface(s, o), squeeze::InputError);
}

// ... by the boundary route (no fallback to the convex shells), with dihedral angles of at least 5
// degrees (the curtain at 300 once got a flat interior tetrahedron from Steiner points on its
// mid-plane).
TEST(MeshingV4, BoxesAndPlatesKeepDihedralsOfFiveDegrees) {
  for (const BoxCase& c : kBoxes)
    for (int target : {150, 300, 1000, 0}) {
      const MeshResult r = mesh(box(c.lo, c.hi, c.n), target);
      EXPECT_EQ(r.method, "boundary") << c.name << " at target " << target << ": " << r.fallback_because;
      EXPECT_GE(r.quality.min_dihedral, 5.0) << c.name << " at target " << target;
    }
}

// Two 0.1 m jaws 18 cm apart, given as one input: the gap stays 18 cm (no tet vertex of either
// jaw's mesh enters it by more than 0.2 % of the diagonal) and the jaws stay two meshes.
TEST(MeshingV4, SlotKeepsItsGap) {
  const SurfaceMesh s = join({box({-0.19, 0, 0}, {-0.09, 0.5, 0.3}), box({0.09, 0, 0}, {0.19, 0.5, 0.3})});
  for (int target : {150, 500}) {
    const MeshResult r = mesh(s, target);
    const double diag = Vec3(0.38, 0.5, 0.3).norm(), tol = 0.002 * diag;
    ASSERT_GT(r.tets.T.rows(), 0);
    EXPECT_EQ(r.parts, 2);
    EXPECT_EQ(r.quality.components, 2);
    double left = -INFINITY, right = INFINITY;
    for (Eigen::Index i = 0; i < r.tets.V.rows(); ++i) {
      const double x = r.tets.V(i, 0);
      EXPECT_FALSE(x > -0.09 + tol && x < 0.09 - tol) << "vertex " << i << " at x = " << x << " is in the gap";
      if (x < 0) left = std::max(left, x);
      else right = std::min(right, x);
    }
    EXPECT_NEAR(right - left, 0.18, 2 * tol) << "target " << target;
    EXPECT_NEAR(tet_volume(r.tets) / (2 * 0.1 * 0.5 * 0.3), 1.0, 0.01);
  }
}

// A model of many closed parts, some overlapping, some far apart: one mesh per part, each part's
// volume kept (the parts' volumes summed, overlaps counted twice as the input has them), the
// deviation bounds held, the tet count within the target or the report saying why.
TEST(MeshingV4, ManyPartsStayMany) {
  std::vector<SurfaceMesh> ps;
  double volume = 0;
  for (int i = 0; i < 6; ++i) {
    const Vec3 lo(0.3 * i, 0, 0), hi(0.3 * i + 0.2, 0.1 + 0.05 * i, 0.15);
    ps.push_back(box(lo, hi));
    volume += box_volume(lo, hi);
  }
  for (int i = 0; i < 6; ++i) {
    ps.push_back(sphere(Vec3(0.3 * i + 0.1, 0.5, 0.1), 0.08, 3));  // tessellated: a bit under 4/3 π r³
    volume += squeeze::meshing::analyse_surface(ps.back()).volume;
  }
  ps.push_back(box({0.15, 0.05, 0.05}, {0.35, 0.12, 0.1}));  // overlaps the first two boxes
  volume += box_volume({0.15, 0.05, 0.05}, {0.35, 0.12, 0.1});
  const SurfaceMesh s = join(ps);
  Eigen::RowVector3d lo = s.V.colwise().minCoeff(), hi = s.V.colwise().maxCoeff();
  const double diag = (hi - lo).norm();
  for (int target : {300, 1000}) {
    const MeshResult r = mesh(s, target);
    const std::string what = "target " + std::to_string(target);
    EXPECT_EQ(r.parts, 13) << what;
    EXPECT_EQ(r.quality.components, 13) << what;
    EXPECT_NEAR(tet_volume(r.tets) / volume, 1.0, 0.05) << what;
    EXPECT_LE(r.deviation_out, 0.015 * diag) << what;
    EXPECT_LE(r.deviation_in, 0.005 * diag) << what;
    EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
    if (r.target_exceeded_because.empty()) {
      EXPECT_GE(r.quality.tets, 0.65 * target) << what;
      EXPECT_LE(r.quality.tets, 1.35 * target) << what;
    }
  }
}

// A scanned ball with holes (faces missing) is not a closed part: it takes the winding-number route
// (by default since meshing version 8: an open scan of a solid, not welded; before, the convex
// shells; also with `winding`)
// (Mesh_3 of the solid its winding number encloses), says why, and comes out one closed mesh within
// issue 16's volume band, with the input's surface inside it (to within 1.2 % of the diagonal: the
// rims are not yet within issue 16's 0.5 %).
TEST(MeshingV4, ScanWithWideHolesIsASheetByDefaultAndASolidByTheWindingNumberRoute) {
  SurfaceMesh ball = sphere(Vec3(0, 0, 0), 0.1, 3);
  const double full = squeeze::meshing::analyse_surface(ball).volume;
  std::vector<int> keep;
  for (Eigen::Index f = 0; f < ball.F.rows(); ++f) {
    const Vec3 c = (ball.V.row(ball.F(f, 0)) + ball.V.row(ball.F(f, 1)) + ball.V.row(ball.F(f, 2))).transpose() / 3.0;
    // Three holes: a cap at +z, one at -x, one at +y.
    if (c.z() > 0.085 || c.x() < -0.09 || c.y() > 0.092) continue;
    keep.push_back(static_cast<int>(f));
  }
  ASSERT_LT(keep.size(), static_cast<size_t>(ball.F.rows()));
  SurfaceMesh scan;
  scan.V = ball.V;
  scan.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (size_t i = 0; i < keep.size(); ++i) scan.F.row(static_cast<Eigen::Index>(i)) = ball.F.row(keep[i]);
  const double diag = 0.2 * std::sqrt(3.0);
  {
    // By default since meshing version 14, holes this wide (the caps of the solid lie 10 % of the
    // diagonal off the scan, over three times the outer bound) make it an open sheet, a slab within the
    // bounds (OpenTubeIsMeshedAsASheetWhereItsCapsBreakTheBound). From version 11 to 13: the
    // winding-number solid's boundary, simplified against the scan and tetrahedralized, as it
    // still is for narrower holes (docs/meshing.md, "Version 14").
    const MeshResult r = mesh(scan, 300);
    EXPECT_EQ(r.method, "boundary") << r.fallback_because;
    EXPECT_NE(r.fallback_because.find("holes are wider than the deviation bound"), std::string::npos) << r.fallback_because;
    EXPECT_EQ(r.quality.components, 1);
    EXPECT_TRUE(r.tet_stats.conforming);
    EXPECT_GE(r.quality.min_dihedral, 5.0);
    EXPECT_LE(r.deviation_out, 0.015 * diag);
    EXPECT_LE(r.deviation_in, 0.005 * diag);
  }
  for (int target : {150, 1000}) {
    MeshOptions o;
    o.tetrahedralize.target_tets = target;
    o.winding = true;
    const MeshResult r = squeeze::meshing::mesh_surface(scan, o);
    const std::string what = "target " + std::to_string(target);
    ASSERT_GT(r.tets.T.rows(), 0) << what;
    EXPECT_FALSE(r.boundary_from_input) << what;
    EXPECT_EQ(r.method, "winding_number") << what;
    EXPECT_NE(r.fallback_because.find("open scans of solids"), std::string::npos) << what << ": " << r.fallback_because;
    EXPECT_EQ(r.quality.components, 1) << what;
    EXPECT_GE(tet_volume(r.tets) / full, 0.9) << what;
    EXPECT_LE(tet_volume(r.tets) / full, 1.2) << what;
    // deviation_out is not bounded: it is measured from the input's surface, and the solid closes
    // the holes with a film (the cap at +z is 10 % of the diagonal wide).
    // Not yet issue 16's 0.5 %: the hole rims are sharp edges of the winding-number solid that
    // Mesh_3 cuts (1.1 % here; docs/meshing.md, "What is left").
    EXPECT_LE(r.deviation_in, 0.012 * diag) << what;
    EXPECT_GE(r.quality.min_dihedral, 5.0) << what << ": " << r.quality.tets << " tetrahedra, conforming "
                                           << r.tet_stats.conforming << ", boundary " << r.boundary.F.rows();
  }
}


// The same ball scan as a scanner leaves it once more: (a) a stray triangle, the face at the top of
// the +z hole kept while its neighbours went (its own component: an open sheet of one face), and
// (b) two faces at one vertex cut away that share no edge, so that their holes touch at that
// vertex (a bow tie). (b): the holes' caps were not estimated, the scan not being an open
// 2-manifold until the bow tie is split; the solid was made first, then the slab. (a), where the
// slab is not made first (its caps estimated within the bound, here by the option): the input
// was judged welded segments, not an open scan, and its winding-number solid kept, caps 10 % of
// the diagonal off, no slab tried (the bunny with six holes 4 % of its diagonal across, stray
// triangles and touching holes: 3.6 % off at every target). Now slabs within the bounds, one per
// component of the scan (meshing version 31).
TEST(MeshingV4, ScanWithAStrayTriangleAndTouchingHolesIsASlab) {
  const SurfaceMesh ball = sphere(Vec3(0, 0, 0), 0.1, 3);
  const double diag = 0.2 * std::sqrt(3.0);
  auto centroid = [&](Eigen::Index f) {
    return Vec3((ball.V.row(ball.F(f, 0)) + ball.V.row(ball.F(f, 1)) + ball.V.row(ball.F(f, 2))).transpose() / 3.0);
  };
  Eigen::Index top = 0;
  for (Eigen::Index f = 0; f < ball.F.rows(); ++f)
    if (centroid(f).z() > centroid(top).z()) top = f;
  // The vertex nearest -y, and two of its faces that share only it.
  Eigen::Index v = 0;
  for (Eigen::Index i = 0; i < ball.V.rows(); ++i)
    if (ball.V(i, 1) < ball.V(v, 1)) v = i;
  std::vector<Eigen::Index> fan;
  for (Eigen::Index f = 0; f < ball.F.rows(); ++f)
    if ((ball.F.row(f).array() == v).any()) fan.push_back(f);
  ASSERT_GE(fan.size(), 5u);
  auto shared = [&](Eigen::Index f, Eigen::Index g) {
    int n = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) n += ball.F(f, a) == ball.F(g, b);
    return n;
  };
  Eigen::Index cut1 = fan[0], cut2 = -1;
  for (Eigen::Index f : fan)
    if (shared(cut1, f) == 1) cut2 = f;
  ASSERT_GE(cut2, 0);
  struct Case {
    bool stray, slab_first;
    const char* what;
  };
  for (const Case& c : {Case{true, false, "a stray triangle, the solid first"}, Case{true, true, "a stray triangle"},
                        Case{false, true, "holes that touch at a vertex"}}) {
    SCOPED_TRACE(c.what);
    std::vector<Eigen::Index> keep;
    for (Eigen::Index f = 0; f < ball.F.rows(); ++f) {
      const Vec3 m = centroid(f);
      const bool hole = m.z() > 0.085 || m.x() < -0.09 || m.y() > 0.092;
      if (c.stray ? (hole && f != top) : (hole || f == cut1 || f == cut2)) continue;
      keep.push_back(f);
    }
    SurfaceMesh scan;
    scan.V = ball.V;
    scan.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
    for (size_t i = 0; i < keep.size(); ++i) scan.F.row(static_cast<Eigen::Index>(i)) = ball.F.row(keep[i]);
    MeshOptions o;
    o.tetrahedralize.target_tets = 300;
    o.slab_first_for_wide_holes = c.slab_first;
    const MeshResult r = squeeze::meshing::mesh_surface(scan, o);
    EXPECT_EQ(r.method, "boundary") << r.fallback_because;
    EXPECT_NE(r.fallback_because.find("holes are wider than the deviation bound"), std::string::npos) << r.fallback_because;
    EXPECT_EQ(r.quality.components, c.stray ? 2 : 1);  // one slab per component of the scan
    EXPECT_TRUE(r.tet_stats.conforming);
    EXPECT_GE(r.quality.min_dihedral, 5.0);
    EXPECT_LE(r.deviation_out, 0.01 * diag);
    EXPECT_LE(r.deviation_in, 0.005 * diag);
    if (c.slab_first) {
      for (const auto& [stage, seconds] : r.seconds) EXPECT_NE(stage, "winding-number surface") << "the solid was made first";
    }
  }
}

// A detailed scan with holes wider than the bound (the corpus dragon, four holes 3 % of its
// diagonal across, cut around faces spread over its index): its solid's caps lie about 2.5 % off,
// so it must be a slab, and the slab's prisms leave slivers at a few spikes and folds that no
// split or smoothing mends. Version 31 kept the solid (sheet_sliver_drop = 0: not a slab within
// the bounds); since version 32 those tetrahedra are dropped and the slab holds every bound.
TEST(MeshingV4, DetailedScanWithWideHolesIsASlabWithItsLastSliversDropped) {
  const SurfaceMesh dragon = sqt::read_off(sqt::data("ChineseDragon-10kv.off"));
  const double diag = (dragon.V.colwise().maxCoeff() - dragon.V.colwise().minCoeff()).norm();
  const Eigen::Index nf = dragon.F.rows();
  auto centroid = [&](Eigen::Index f) {
    return Vec3((dragon.V.row(dragon.F(f, 0)) + dragon.V.row(dragon.F(f, 1)) + dragon.V.row(dragon.F(f, 2))).transpose() / 3.0);
  };
  std::vector<Eigen::Index> keep;
  for (Eigen::Index f = 0; f < nf; ++f) {
    bool hole = false;
    for (Eigen::Index k = 0; k < 4; ++k) hole = hole || (centroid(f) - centroid(k * nf / 4 + nf / 8)).norm() <= 0.03 * diag;
    if (!hole) keep.push_back(f);
  }
  SurfaceMesh scan;
  scan.V = dragon.V;
  scan.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (size_t i = 0; i < keep.size(); ++i) scan.F.row(static_cast<Eigen::Index>(i)) = dragon.F.row(keep[i]);
  ASSERT_LT(scan.F.rows(), nf);
  for (const double drop : {0.0, 0.005}) {
    SCOPED_TRACE("sheet_sliver_drop " + std::to_string(drop));
    MeshOptions o;
    o.tetrahedralize.target_tets = 300;
    o.sheet_sliver_drop = drop;
    const MeshResult r = squeeze::meshing::mesh_surface(scan, o);
    const bool slab = r.sheets == 1 && r.deviation_out <= 0.01 * diag;
    if (drop == 0) {
      EXPECT_FALSE(slab) << "version 31 had no slab within the bounds";
      continue;
    }
    EXPECT_TRUE(slab) << r.fallback_because;
    EXPECT_NE(r.fallback_because.find("holes are wider than the deviation bound"), std::string::npos) << r.fallback_because;
    EXPECT_LE(r.deviation_in, 0.0045 * diag);
    EXPECT_GE(r.quality.min_dihedral, 5.0);
    EXPECT_EQ(r.quality.components, 1);
    EXPECT_TRUE(r.tet_stats.conforming);
    EXPECT_FALSE(r.target_exceeded_because.empty()) << "far over the target: the report says why";
  }
}

// Segments welded at a shared wall (as the lung files' lobes are: each wall's edges have three
// faces) are not closed parts. By default (meshing version 11) their winding-number solid's
// boundary is simplified against them and tetrahedralized; with `winding` that solid is meshed by
// Mesh_3 as it is; with `shells_fallback` they take the convex shells; with `wrap` their alpha
// wrap is meshed by the boundary route: one part, the union's volume (by winding number), the
// deviation bounds held against the input.
TEST(MeshingV4, WeldedSegmentsTakeTheAlphaWrapWhenAsked) {
  const Vec3 a0(0, 0, 0), a1(0.2, 0.12, 0.1), b0(0.2, 0, 0), b1(0.35, 0.12, 0.1), c0(0.05, 0.12, 0), c1(0.2, 0.2, 0.1);
  const fs::path dir = fs::temp_directory_path() / ("squeeze_welded_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  sqt::write_off(dir / "welded.off", join({box(a0, a1, {2, 2, 2}), box(b0, b1, {2, 2, 2}), box(c0, c1, {2, 2, 2})}));
  const SurfaceMesh s = squeeze::meshing::load_surface(dir / "welded.off");  // welds the shared corners
  fs::remove_all(dir);
  const double volume = box_volume(a0, a1) + box_volume(b0, b1) + box_volume(c0, c1);
  const double diag = sqt::diagonal(s.V);
  int winding_tets = 0;
  for (int target : {150, 300, 1000}) {
    const MeshResult r = mesh(s, target);  // the default
    const std::string what = "target " + std::to_string(target);
    EXPECT_EQ(r.method, "winding_number_boundary") << what << ": " << r.fallback_because;
    EXPECT_EQ(r.parts, 1) << what;
    EXPECT_EQ(r.quality.components, 1) << what;
    EXPECT_TRUE(r.tet_stats.conforming) << what;
    ASSERT_TRUE(r.volume_ratio.has_value()) << what;
    EXPECT_GE(*r.volume_ratio, target >= 1000 ? 0.95 : 0.9) << what;
    EXPECT_LE(*r.volume_ratio, target >= 1000 ? 1.1 : 1.2) << what;
    EXPECT_LE(r.deviation_out, 0.015 * diag) << what;
    EXPECT_LE(r.deviation_in, 0.005 * diag) << what;
    EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
    std::printf("[ welded   ] default at %d: %d tets, volume ratio %.3f, dev out %.2f %%, in %.2f %%, %.1f deg\n", target,
                r.quality.tets, *r.volume_ratio, 100 * r.deviation_out / diag, 100 * r.deviation_in / diag,
                r.quality.min_dihedral);
    if (target == 300) winding_tets = r.quality.tets;
  }
  {
    MeshOptions o;
    o.tetrahedralize.target_tets = 300;
    o.shells_fallback = true;
    EXPECT_EQ(squeeze::meshing::mesh_surface(s, o).method, "convex_shells");
  }
  {
    // With `winding`: their winding-number solid (the union), meshed by Mesh_3.
    MeshOptions o;
    o.tetrahedralize.target_tets = 300;
    o.winding = true;
    const MeshResult r = squeeze::meshing::mesh_surface(s, o);
    EXPECT_EQ(r.method, "winding_number");
    EXPECT_EQ(r.parts, 1);
    EXPECT_EQ(r.quality.components, 1);
    ASSERT_TRUE(r.volume_ratio.has_value());
    EXPECT_GE(*r.volume_ratio, 0.9);
    EXPECT_LE(*r.volume_ratio, 1.2);
    EXPECT_LE(r.deviation_out, 0.015 * diag);
    EXPECT_LE(r.deviation_in, 0.012 * diag);
    EXPECT_GE(r.quality.min_dihedral, 5.0);
    std::printf("[ welded   ] winding route at 300: %d tets, volume ratio %.3f, dev out %.2f %%, in %.2f %%, %.1f deg\n",
                r.quality.tets, *r.volume_ratio, 100 * r.deviation_out / diag, 100 * r.deviation_in / diag,
                r.quality.min_dihedral);
    // The simplified boundary needs fewer tetrahedra than Mesh_3's own within the same bounds.
    EXPECT_LT(winding_tets, r.quality.tets);
  }
  for (int target : {300, 1000}) {
    MeshOptions o;
    o.tetrahedralize.target_tets = target;
    o.wrap = true;
    const MeshResult r = squeeze::meshing::mesh_surface(s, o);
    const std::string what = "target " + std::to_string(target);
    EXPECT_EQ(r.method, "alpha_wrap") << what << ": " << r.fallback_because;
    EXPECT_TRUE(r.wrap.used) << what;
    EXPECT_EQ(r.parts, 1) << what;
    EXPECT_EQ(r.quality.components, 1) << what;
    EXPECT_NEAR(r.input_volume / volume, 1.0, 0.02) << what << ": the union's volume by winding number";
    ASSERT_TRUE(r.volume_ratio.has_value()) << what;
    EXPECT_GE(*r.volume_ratio, 0.95) << what;
    EXPECT_LE(*r.volume_ratio, 1.1) << what;
    EXPECT_LE(r.deviation_out, 0.015 * diag) << what;
    EXPECT_LE(r.deviation_in, 0.005 * diag) << what;
    // The wrap's simplified boundary kept a 2.7-degree sliver at 1000 until tetrahedralize() moved
    // and flipped the slivers Mesh_3's exuder leaves.
    EXPECT_GE(r.quality.min_dihedral, 5.0) << what << ": " << r.quality.tets << " tetrahedra, conforming "
                                           << r.tet_stats.conforming << ", boundary " << r.boundary.F.rows();
    std::printf("[ welded   ] alpha wrap at %d: %d tets, volume ratio %.3f, %.1f deg, %d moves, %d flips\n", target,
                r.quality.tets, *r.volume_ratio, r.quality.min_dihedral, r.tet_stats.relocated, r.tet_stats.flips);
  }
}

}  // namespace

// The plain surfaces the bench variants of the bundled scenes mesh instead of their hand-made voxel
// meshes (bench/scenes/barriers{1,2}_box_plates.json, windows_surface_walls.json) come out exact at
// the counts those scenes ask: the boundary route, volume within 1 %, deviations within 0.2 % of
// the diagonal, one component, dihedral angles of at least 5 degrees.
TEST(MeshingV4, SceneSurfacesOfPlatesAndWallsComeOutExact) {
  const struct {
    const char* file;
    int target;
  } cases[] = {{"plate_0.1x1.96x1.4.off", 252}, {"plate_0.1x1.96x1.4.off", 1008}, {"windows_walls.off", 1218}};
  for (const auto& c : cases) {
    const std::string what = std::string(c.file) + " at " + std::to_string(c.target);
    const SurfaceMesh s = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/" + c.file);
    const MeshResult r = mesh(s, c.target);
    const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
    EXPECT_EQ(r.method, "boundary") << what << ": " << r.fallback_because;
    ASSERT_TRUE(r.volume_ratio.has_value()) << what;
    EXPECT_NEAR(*r.volume_ratio, 1.0, 0.01) << what;
    EXPECT_LE(r.deviation_out, 0.002 * diag) << what;
    EXPECT_LE(r.deviation_in, 0.002 * diag) << what;
    EXPECT_EQ(r.quality.components, 1) << what;
    EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
  }
}

namespace {

// The spinal cord (30 closed segments, the boundary route): at 150 tetrahedra Mesh_3's exuder left
// an interior sliver of 2.7 degrees in one flat segment, all four corners on the boundary. The
// relocation and flips at the end of tetrahedralize() lift such slivers above the 5-degree floor
// while the volume and the deviations stay those of the input's own boundary. (Since meshing
// version 43, which flips flat cells on the surface outside instead of refining them, the cord at
// 150 keeps no sliver to mend; at 300 four vertices are moved.)
TEST(MeshingV4, ThinSegmentsKeepDihedralsOfFiveDegreesOnTheBoundaryRoute) {
  const SurfaceMesh s = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/spinal_cord.off");
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  const MeshResult r = mesh(s, 300);
  EXPECT_EQ(r.method, "boundary") << r.fallback_because;
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_GT(r.tet_stats.relocated + r.tet_stats.flips, 0) << "no sliver was left to mend: the test no longer tests it";
  EXPECT_GE(r.quality.min_dihedral, 5.0) << r.tet_stats.relocated << " moves, " << r.tet_stats.flips << " flips";
  expect_within(r, diag, 0.01, 0.015, 0.005, 30);
}

// The lumbar spine at 150 tetrahedra (5 vertebrae, the boundary route): a coarse interior leaves a
// boundary sliver of 4.1° that is 2 % of the diagonal thick. Peeled, it took the deviation out to
// 1.98 %; the peeling now stops at the inner bound and the sliver moves take it instead.
TEST(MeshingV4, ThickBoundarySliversAreMovedNotPeeled) {
  const SurfaceMesh s =
      squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/spine_lumbar_L1-L5.off");
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  const MeshResult r = mesh(s, 150);
  EXPECT_EQ(r.method, "boundary") << r.fallback_because;
  expect_within(r, diag, 0.01, 0.015, 0.005, 5);
}


// The lumbar spine with three holes cut (faces within 3 % of the diagonal of three points; two
// vertebrae opened): its slab, the two opened vertebrae as slabs beside the three closed ones,
// lies 0.4515 % of the diagonal in at 300, the closed ones' own 0.45 %. Kept since meshing
// version 37 (first_try_inner_deviation): before, the whole input's solid was made instead,
// hollowed, within the bounds but one mesh of the five vertebrae (they lie 0.06-0.17 % of the
// diagonal apart, closer than its dilation) and in about 14 s.
TEST(MeshingV4, VertebraeWithHolesStayFiveSlabsAndClosedParts) {
  const SurfaceMesh spine =
      squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/spine_lumbar_L1-L5.off");
  const double diag = (spine.V.colwise().maxCoeff() - spine.V.colwise().minCoeff()).norm();
  const SurfaceMesh holed = sqs::with_holes_at(spine,
                                               {{0.00865932, 0.197801, -0.05858313}, {0.03339757, 0.21325533, -0.02452497},
                                                {-0.014068, 0.19224233, -0.03184763}},
                                               0.03);
  ASSERT_LT(holed.F.rows(), spine.F.rows());
  const MeshResult r = mesh(holed, 300);
  EXPECT_EQ(r.method, "boundary") << r.fallback_because;
  EXPECT_NE(r.fallback_because.find("meshed as an open sheet"), std::string::npos) << r.fallback_because;
  EXPECT_EQ(r.sheets, 2);
  EXPECT_EQ(r.quality.components, 5);
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_LE(r.deviation_out, 0.01 * diag);
  EXPECT_LE(r.deviation_in, 0.005 * diag);
  EXPECT_GT(r.deviation_in, 0.0045 * diag) << "the slab holds the 0.45 % target: the test no longer tests the option";
}

namespace {
// The issue's bounds a holed input's mesh keeps: conforming, the dihedral floor, deviation_out
// within 1.5 % and deviation_in within 0.5 % of the diagonal `diag` of the input.
void expect_within_the_bounds(const MeshResult& r, double diag) {
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_LE(r.deviation_out, 0.015 * diag);
  EXPECT_LE(r.deviation_in, 0.005 * diag);
}
// How many winding-number surfaces a result made (its report's seconds have a row each).
int winding_surfaces(const MeshResult& r) {
  int surfaces = 0;
  for (const auto& [stage, seconds] : r.seconds) surfaces += stage == "winding-number surface";
  return surfaces;
}
}  // namespace

// The sacrum with three holes cut (the thirty-third session's scratch input): an open scan whose
// slab, tried first, folds at a spike and does not hold. Since meshing version 38 (hollow_first)
// its solid is made hollowed straight away, by its holes' outlines (caps about 2 % of the diagonal
// off), and kept: one winding-number surface, within the bounds. Before version 36 it was the
// capped solid, 2.48 % of the diagonal out; in versions 36 and 37 the same hollowed mesh after the
// capped one.
TEST(MeshingV4, SacrumWithHolesIsHollowedFirstAfterItsSlab) {
  const SurfaceMesh sacrum = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/sacrum_coccyx.off");
  const double diag = (sacrum.V.colwise().maxCoeff() - sacrum.V.colwise().minCoeff()).norm();
  const SurfaceMesh holed = sqs::with_holes_at(sacrum,
                                               {{0.0103615767, 0.1036276667, -0.0833586667},
                                                {-0.0042128167, 0.0867579333, -0.1036236667},
                                                {0.0175554333, 0.1139286667, -0.0640076}},
                                               0.03);
  ASSERT_EQ(holed.F.rows(), 11139);  // the scratch input's faces
  const MeshResult r = mesh(holed, 300);
  EXPECT_EQ(r.method, "winding_number_boundary") << r.fallback_because;
  EXPECT_GT(r.winding_stats.hollow_depth, 0.0);
  EXPECT_NE(r.fallback_because.find("would lie about"), std::string::npos) << r.fallback_because;
  EXPECT_EQ(winding_surfaces(r), 1) << "the capped solid was made too";
  EXPECT_EQ(r.quality.components, r.parts);
  expect_within_the_bounds(r, diag);
}

// The heart (welded segments) with four holes cut (the thirty-eighth session's scratch input,
// seed 381): its solid is hollowed first. A flap between two holes is part of that solid only by
// its dilation (outside it 0.5 % of the diagonal off on both sides). Until meshing version 39 the
// winding-number surface's cover pass took that flap's surface point on one side only, and Mesh_3
// never found the flap: an input vertex 0.76 % of the diagonal outside, so the hollowed solid was
// refused and the capped one (2.9 % out) kept. Now both sides are seeded, and the hollowed solid
// holds the bounds.
TEST(MeshingV4, FlapsBetweenHolesAreSeededOnBothSides) {
  const SurfaceMesh heart = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/tests/data/organs/heart.off");
  const double diag = (heart.V.colwise().maxCoeff() - heart.V.colwise().minCoeff()).norm();
  const SurfaceMesh holed = sqs::with_holes_at(heart,
                                               {{-0.0288107, 0.44545, 0.0519153},
                                                {0.00136949, 0.484691, -0.00491019},
                                                {0.0193634, 0.512833, 0.00228259},
                                                {0.00543473, 0.474684, 0.00916497}},
                                               0.04);
  ASSERT_EQ(heart.F.rows() - holed.F.rows(), 1070);  // the scratch input's faces cut
  const MeshResult r = mesh(holed, 300);
  EXPECT_EQ(r.method, "winding_number_boundary") << r.fallback_because;
  EXPECT_GT(r.winding_stats.hollow_depth, 0.0) << "the capped solid was kept";
  EXPECT_EQ(winding_surfaces(r), 1) << "the hollowed solid made first was refused";
  EXPECT_EQ(r.quality.components, r.parts);
  expect_within_the_bounds(r, diag);
}

// The heart with four holes 3 % of its diagonal in radius (seed 391), written to an OFF file and
// read back, as `squeeze mesh` reads it: its hollowed solid's first boundary holds (meshing
// version 40). Before, one surface edge stayed missing beside a triangle split 10 times (the cap
// against splitting without end), the boundary was simplified again within half the bounds: 46,278
// tetrahedra, not 31,758. (Without the round trip, bench_mesh's BM_HeartWithHoles, the digits
// differ and the first boundary held before too.)
TEST(MeshingV4, HollowedHeartKeepsItsFirstBoundary) {
  const SurfaceMesh heart = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/tests/data/organs/heart.off");
  const double diag = (heart.V.colwise().maxCoeff() - heart.V.colwise().minCoeff()).norm();
  const SurfaceMesh holed = sqs::with_holes_at(heart,
                                               {{0.075214, 0.467939, 0.0640765},
                                                {0.00254863, 0.47815, 0.0756827},
                                                {0.0392196, 0.429359, 0.0836583},
                                                {0.0058577, 0.430776, 0.0496153}},
                                               0.03);
  const std::string file = (fs::temp_directory_path() / ("squeeze_heart_holes_" + std::to_string(::getpid()) + ".off")).string();
  squeeze::meshing::save_surface(file, holed);
  const MeshResult r = mesh(squeeze::meshing::load_surface(file), 300);
  std::remove(file.c_str());
  EXPECT_EQ(r.method, "winding_number_boundary") << r.fallback_because;
  EXPECT_GT(r.winding_stats.hollow_depth, 0.0);
  EXPECT_EQ(r.boundary_retries, 0);
  EXPECT_LT(r.quality.tets, 40000);
  EXPECT_EQ(r.quality.components, r.parts);
  expect_within_the_bounds(r, diag);
}

// The spinal cord with four holes cut (seed 391 of the thirty-eighth session): 26 components
// left, three of them open, 0.49 m long. Its winding-number surface's seeds, 8 facet distances
// apart at the input's vertices, gave Mesh_3 no facet: until meshing version 39 it then ran Mesh_3's
// tetrahedra of the solid three times (0 tetrahedra, 30 s each) and fell back to convex shells,
// 4.9 % of the diagonal off, in 95 s. Since then the seeds are taken again a facet distance apart.
TEST(MeshingV4, LongThinScanWithoutFacetsIsSeededFiner) {
  const SurfaceMesh cord = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/spinal_cord.off");
  const double diag = (cord.V.colwise().maxCoeff() - cord.V.colwise().minCoeff()).norm();
  const SurfaceMesh holed = sqs::with_holes_at(cord,
                                               {{-0.00537817, 0.746601, -0.0120983},
                                                {0.000512638, 0.69454, -0.0140828},
                                                {-0.00550805, 0.708026, -0.0118433},
                                                {-0.00579887, 0.676319, -0.0114351}},
                                               0.03);
  ASSERT_EQ(cord.F.rows() - holed.F.rows(), 1406);  // the scratch input's faces cut
  const MeshResult r = mesh(holed, 300);
  EXPECT_EQ(r.method, "winding_number_boundary") << r.fallback_because;
  expect_within_the_bounds(r, diag);
}

// The sacrum (2 parts; the large one's simplified boundary is not recovered at a crumple of the
// input): that part is meshed as its own winding-number solid, within the issue's bounds at 150
// ([0.9, 1.2]) and, with a smaller dilation, at 1000 ([0.95, 1.1]; its volume was 1.19 there).
TEST(MeshingV4, SacrumPartFallsBackToItsWindingNumberSolidWithinTheBounds) {
  const SurfaceMesh s =
      squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/sacrum_coccyx.off");
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  for (int target : {150, 1000}) {
    SCOPED_TRACE(target);
    const MeshResult r = mesh(s, target);
    EXPECT_EQ(r.method, "boundary") << r.fallback_because;
    EXPECT_EQ(r.parts_by_winding_number, 1);
    EXPECT_TRUE(r.tet_stats.conforming);
    ASSERT_TRUE(r.volume_ratio.has_value());
    if (target >= 1000) {
      EXPECT_GE(*r.volume_ratio, 0.95);
      EXPECT_LE(*r.volume_ratio, 1.1);
    }
    expect_within(r, diag, 0.2, 0.015, 0.005, 2);
    EXPECT_NE(r.target_exceeded_because.find("winding-number solid"), std::string::npos) << r.target_exceeded_because;
  }
}

// A thin CAD plate (trimesh's fixed_top.ply, tests/data/cad) at 150: its boundary is never
// recovered conforming, and its winding-number solid, at the dilation the bound allows, grew to
// 1.412 times its volume, over the volume bound; the part then kept its boundary that was not
// conforming, 1.36 % of the diagonal in. Since meshing version 54 the solid is made again with the
// dilation and facet distance scaled down (0.4 here): within every bound, by its solid.
namespace {
// A CAD part of tests/data/cad at 150 with the defaults: the boundary route, the part its own
// winding-number solid, within the issue's bounds at 150 (volume in [0.9, 1.2]).
MeshResult expect_cad_part_held_by_its_solid(const std::string& file) {
  const SurfaceMesh s = squeeze::meshing::load_surface(sqt::data(file));
  const double diag = bounding_box_diagonal(s.V);
  MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  MeshResult r = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(r.method, "boundary") << file;
  EXPECT_EQ(r.parts_by_winding_number, 1) << file;
  expect_within(r, diag, 0.2, 0.015, 0.005, 1);
  EXPECT_GE(*r.volume_ratio, 0.9) << file;
  EXPECT_LE(*r.volume_ratio, 1.2) << file;
  return r;
}
}  // namespace

TEST(MeshingV4, ThinPartWhoseSolidGrewOverTheBoundIsMadeAgainThinner) {
  expect_cad_part_held_by_its_solid("cad/fixed_top.ply");
}

// trimesh's ADIS16480.STL (a sensor housing: pockets, bosses, small fillets) at 150: its simplified
// boundary's first recovery gives up at recovery_splits_per_face (4 per face; it went on to 21,456
// splits for 1,614 faces before version 55), that run is not refined, and the part takes no retry
// but its remeshed surface before its winding-number solid, which holds the bounds.
TEST(MeshingV4, CadPartWhoseRecoveryIsHopelessGoesToItsSolidWithinTheBounds) {
  const MeshResult r = expect_cad_part_held_by_its_solid("cad/ADIS16480.STL");
  EXPECT_LE(r.boundary_retries, 1);  // (retry 0 only)
}

// A part whose first boundary lost conformity and whose mean thickness (twice its volume over its
// area) is at least solid_first_thickness (0.5) of its first attempt's edge length takes its
// winding-number solid before retries 1 and 3 (meshing version 53): the sacrum at 1000 (10,818
// faces, under solid_first_faces; 0.64 of its edge length thick) went through retries 1, 3 and 4,
// none conforming, before the same solid. The comb's thin teeth keep the retries first
// (BranchingThinWallsAreExact).
TEST(MeshingV4, ThickPartWhoseBoundaryLostConformityTakesItsSolidBeforeTheRetries) {
  const SurfaceMesh s =
      squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/sacrum_coccyx.off");
  MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.solid_first_thickness = 0;  // (version 52)
  const MeshResult before = squeeze::meshing::mesh_surface(s, o);
  ASSERT_EQ(before.parts_by_winding_number, 1) << "the case this is about";
  o.solid_first_thickness = 0.5;
  const MeshResult r = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(r.parts_by_winding_number, 1);
  EXPECT_LT(r.boundary_retries, before.boundary_retries);
  EXPECT_TRUE(r.tets.T == before.tets.T && r.tets.V == before.tets.V) << "the same solid";
  o.solid_first_thickness = -1;
  EXPECT_THROW(squeeze::meshing::mesh_surface(s, o), squeeze::InputError);
}

/// A closed hemispherical shell: outer radius R, wall `thickness`, nu segments around, nv rings
/// from the pole to the rim (both sheets), the rim closed by a band of quads; outward triangles.
SurfaceMesh hemispherical_shell(double R, double thickness, int nu, int nv) {
  std::vector<Vec3> V;
  std::vector<std::array<int, 3>> F;
  const int per_sheet = 1 + nv * nu;
  auto id = [&](int sheet, int ring, int j) { return sheet * per_sheet + (ring == 0 ? 0 : 1 + (ring - 1) * nu + (j % nu)); };
  for (int sheet = 0; sheet < 2; ++sheet) {
    const double r = sheet == 0 ? R : R - thickness;
    V.emplace_back(0, 0, r);
    for (int ring = 1; ring <= nv; ++ring) {
      const double polar = 0.5 * M_PI * ring / nv;
      for (int j = 0; j < nu; ++j) {
        const double a = 2 * M_PI * j / nu;
        V.emplace_back(r * std::sin(polar) * std::cos(a), r * std::sin(polar) * std::sin(a), r * std::cos(polar));
      }
    }
  }
  auto add = [&](int sheet, int a, int b, int c) {
    if (sheet == 0) F.push_back({a, b, c});
    else F.push_back({a, c, b});  // the inner sheet faces the hollow
  };
  for (int sheet = 0; sheet < 2; ++sheet) {
    for (int j = 0; j < nu; ++j) add(sheet, id(sheet, 0, 0), id(sheet, 1, j), id(sheet, 1, j + 1));
    for (int ring = 1; ring < nv; ++ring)
      for (int j = 0; j < nu; ++j) {
        const int a = id(sheet, ring, j), b = id(sheet, ring + 1, j), c = id(sheet, ring + 1, j + 1), d = id(sheet, ring, j + 1);
        add(sheet, a, b, c), add(sheet, a, c, d);
      }
  }
  for (int j = 0; j < nu; ++j) {  // the rim
    const int a = id(0, nv, j), b = id(1, nv, j), c = id(1, nv, j + 1), d = id(0, nv, j + 1);
    F.push_back({a, b, c}), F.push_back({a, c, d});
  }
  return surface_of(V, F);
}

// A 4 mm hemispherical shell of radius 0.2 m whose triangles are 6.5 times its thickness: the
// Delaunay tetrahedralization of its own surface is made conforming, then a refinement round's
// splits between the two sheets cannot be recovered within the cap. Refinement used to go on for
// six more rounds on a triangulation classified by the winding number: 2,000 → 6,000 points,
// 18,077 tetrahedra, 8 s per attempt (the whole `squeeze mesh` at 150: 18 s, over the 15 s
// bound). It now stops where conformity is lost. The pipeline's mesh (simplified boundary, not
// conforming either) keeps the volume, the outer bound and the dihedral floor; its inner
// deviation is 0.24 % of the diagonal for one triangulation of this shell and 0.59 % for this one
// (docs/meshing.md, "What is left"), so only twice the issue's bound is asserted here.
TEST(MeshingV4, ThinShellRefinementStopsWhereConformityIsLost) {
  const SurfaceMesh s = hemispherical_shell(0.2, 0.004, 48, 12);
  squeeze::meshing::TetrahedralizeOptions t;
  t.target_tets = 150;
  squeeze::meshing::TetrahedralizeStats st;
  const squeeze::meshing::TetMesh m = squeeze::meshing::tetrahedralize(s, t, &st);
  EXPECT_GT(m.T.rows(), 0);
  // (Since meshing version 43 the shell's flat quads' cells are flipped outside, not split, so its
  // conformity is lost in the third round, not the first: 11,648 tetrahedra and 2,793 splits when
  // this was written, where the loss in the first round kept them under 9,000 and 2,000, and
  // refinement on without the stop made 18,077 tetrahedra.)
  EXPECT_LT(m.T.rows(), 13000) << st.boundary_splits << " boundary splits, " << st.steiner_points << " Steiner points, conforming " << st.conforming << ", attempts " << st.attempts;
  EXPECT_LT(st.boundary_splits, 3500);

  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  expect_within(mesh(s, 150), diag, 0.1, 0.015, 0.01, 1);
}


// The attempt tetrahedralize skips (TetrahedralizeOptions::skip_repeated_attempts) would have
// repeated the last one: run anyway, the mesh kept is the same, bit for bit. Over the corpus sphere
// and finely divided boxes at targets their boundaries exceed; at least one of them must skip.
TEST(MeshingV4, SkippedAttemptWouldHaveGivenTheSameMesh) {
  std::vector<std::pair<std::string, SurfaceMesh>> inputs;
  inputs.emplace_back("sphere", squeeze::meshing::load_surface(sqt::data("sphere.off")));
  inputs.emplace_back("box 8", box(Vec3(0, 0, 0), Vec3(1, 0.7, 0.4), {8, 8, 8}));
  inputs.emplace_back("plate 12", box(Vec3(0, 0, 0), Vec3(1, 0.05, 0.6), {12, 2, 12}));
  int skipped = 0;
  for (const auto& [name, s] : inputs)
    for (int target : {10, 40, 150}) {
      squeeze::meshing::TetrahedralizeOptions t;
      t.target_tets = target;
      squeeze::meshing::TetrahedralizeStats with, without;
      const squeeze::meshing::TetMesh a = squeeze::meshing::tetrahedralize(s, t, &with);
      t.skip_repeated_attempts = false;
      const squeeze::meshing::TetMesh b = squeeze::meshing::tetrahedralize(s, t, &without);
      SCOPED_TRACE(name + " at " + std::to_string(target));
      EXPECT_LE(with.attempts, without.attempts);
      skipped += with.attempts < without.attempts;
      ASSERT_EQ(a.V.rows(), b.V.rows());
      ASSERT_EQ(a.T.rows(), b.T.rows());
      EXPECT_TRUE(a.V == b.V);
      EXPECT_TRUE(a.T == b.T);
      EXPECT_EQ(with.edge_length, without.edge_length);
    }
  EXPECT_GT(skipped, 0) << "no input skipped an attempt: the test no longer tests the skip";
}

// One table of mesh routes: each name sets exactly its own flag, an unknown one is an error that
// lists them all.
TEST(MeshingV4, MeshRoutesByName) {
  const std::vector<std::string>& names = squeeze::meshing::mesh_route_names();
  ASSERT_EQ(names.size(), 5u);
  for (const std::string& n : names) {
    MeshOptions o;
    o.winding = o.wrap = o.shells_fallback = o.shells_only = true;  // cleared by every route but its own
    squeeze::meshing::set_mesh_route(o, n);
    EXPECT_EQ(o.shells_fallback, n == "convex_shells") << n;
    EXPECT_EQ(o.shells_only, n == "all_convex_shells") << n;
    EXPECT_EQ(o.winding, n == "winding_number") << n;
    EXPECT_EQ(o.wrap, n == "alpha_wrap") << n;
  }
  MeshOptions o;
  try {
    squeeze::meshing::set_mesh_route(o, "shells");
    FAIL() << "an unknown route was taken";
  } catch (const squeeze::InputError& e) {
    EXPECT_EQ(std::string(e.what()), "unknown mesh route \"shells\" (auto, convex_shells, winding_number, alpha_wrap, all_convex_shells)");
  }
}

/// A closed cylinder from p0 to p1 of radius r with n segments: each cap a fan around its centre,
/// each side quad two triangles as long as the cylinder (2n + 2 vertices, 4n faces, outward).
SurfaceMesh cylinder(const Vec3& p0, const Vec3& p1, double r, int n) {
  const Vec3 d = (p1 - p0).normalized();
  const Vec3 a = std::abs(d.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX();
  const Vec3 u = d.cross(a).normalized(), w = d.cross(u);
  SurfaceMesh s;
  s.V.resize(2 * n + 2, 3);
  s.V.row(0) = p0.transpose();
  s.V.row(1) = p1.transpose();
  for (int end = 0; end < 2; ++end)
    for (int j = 0; j < n; ++j) {
      const double t = 2 * M_PI * j / n;
      s.V.row(2 + end * n + j) = ((end ? p1 : p0) + r * (std::cos(t) * u + std::sin(t) * w)).transpose();
    }
  s.F.resize(4 * n, 3);
  for (int j = 0; j < n; ++j) {
    const int a0 = 2 + j, a1 = 2 + (j + 1) % n, b0 = 2 + n + j, b1 = 2 + n + (j + 1) % n;
    s.F.row(4 * j) << 0, a1, a0;
    s.F.row(4 * j + 1) << 1, b0, b1;
    s.F.row(4 * j + 2) << a0, a1, b1;
    s.F.row(4 * j + 3) << a0, b1, b0;
  }
  return s;
}

double signed_volume(const SurfaceMesh& s) {
  double v = 0;
  for (Eigen::Index f = 0; f < s.F.rows(); ++f)
    v += s.V.row(s.F(f, 0)).dot(s.V.row(s.F(f, 1)).cross(s.V.row(s.F(f, 2)))) / 6.0;
  return v;
}

// split_long_edges keeps the surface: the same vertices first, the same signed volume (so the same
// orientation) and area, every edge shared by exactly two faces (closed and conforming), and no
// edge longer than asked (and it says so); on a sphere, the cylinder and a curtain box.
TEST(MeshingV4, SplitLongEdgesKeepsTheSurfaceAndBoundsItsEdges) {
  const SurfaceMesh inputs[] = {cylinder(Vec3(0, 0, 0.05), Vec3(0.08, -0.12, 0.25), 0.012, 10),
                                box(Vec3(0, 0, 0), Vec3(1, 0.6, 0.02)), sphere(Vec3(0.1, 0.2, 0.3), 0.2, 2)};
  for (const SurfaceMesh& s : inputs) {
    const double bound = 3 * squeeze::meshing::median_edge_length(s);
    bool complete = false;
    const SurfaceMesh t = squeeze::meshing::split_long_edges(s, bound, &complete);
    EXPECT_TRUE(complete);
    ASSERT_GE(t.V.rows(), s.V.rows());
    EXPECT_TRUE(t.V.topRows(s.V.rows()).isApprox(s.V));
    EXPECT_NEAR(signed_volume(t), signed_volume(s), 1e-12 * std::abs(signed_volume(s)));
    std::map<std::pair<int, int>, int> directed;
    double longest = 0;
    for (Eigen::Index f = 0; f < t.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = t.F(f, k), b = t.F(f, (k + 1) % 3);
        ++directed[{a, b}];
        longest = std::max(longest, (t.V.row(a) - t.V.row(b)).norm());
      }
    for (const auto& [e, n] : directed) {
      EXPECT_EQ(n, 1) << "edge " << e.first << "-" << e.second << " used twice in one direction";
      EXPECT_EQ(directed.count({e.second, e.first}), 1u) << "edge " << e.first << "-" << e.second << " has no twin";
    }
    EXPECT_LE(longest, bound);
  }
  EXPECT_THROW(squeeze::meshing::split_long_edges(inputs[0], 0.0), squeeze::InputError);
  // A bound far below the input's edges stops at the face budget (8 #F + 10,000 before a round;
  // a round at most quadruples), not at a million faces.
  const SurfaceMesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  bool complete = true;
  const SurfaceMesh fine = squeeze::meshing::split_long_edges(cube, 1e-4, &complete);
  EXPECT_FALSE(complete);  // it says that edges longer than asked remain
  EXPECT_GT(fine.F.rows(), 8 * cube.F.rows());
  EXPECT_LE(fine.F.rows(), 4 * (8 * cube.F.rows() + 10000));
  EXPECT_NEAR(signed_volume(fine), 1.0, 1e-12);
}

// A cylinder of 10 segments (22 vertices; its sides are triangles 30 times longer than wide, as
// CAD exports and many-part models have them) comes out exact at the issue's targets: the
// Delaunay tetrahedralization of its own vertices could not be made conforming (the sides' split
// edges reached the ten-splits limit): more than one piece at every target (9 at 1000, with 880
// slivers peeled), volume 0.992 at 150. Its long edges are now split first.
TEST(MeshingV4, LongThinTrianglesOfACylinderComeOutExact) {
  const SurfaceMesh s = cylinder(Vec3(0, 0, 0.05), Vec3(0.08, -0.12, 0.25), 0.012, 10);
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  for (int target : {150, 300, 1000}) {
    const MeshResult r = mesh(s, target);
    SCOPED_TRACE("target " + std::to_string(target));
    EXPECT_EQ(r.method, "boundary") << r.fallback_because;
    EXPECT_TRUE(r.tet_stats.conforming);
    expect_within(r, diag, 0.01, 0.002, 0.002, 1);
  }
}


// A 1 m rod of 3 mm radius, 12 sides and 40 rings (side triangles 25 mm by 1.6 mm): its own
// boundary left the simplification no collapse, and its Delaunay refinement searched conflict
// zones the size of the rod (21 s and 2.2 degrees, not conforming, at 150; 169 s at 1000). Mostly
// skinny triangles: it is split to rounder ones and simplified, and comes out within the bounds
// with far less refinement work (a deterministic proxy for its time).
TEST(MeshingV4, RodOfLongThinTrianglesIsSplitAndMeshedWithinTheBounds) {
  const SurfaceMesh s = sqs::ringed_rod(0.003, 1.0, 12, 40);
  EXPECT_GT(squeeze::meshing::skinny_split_length(s), 0.0);
  EXPECT_EQ(squeeze::meshing::skinny_split_length(sphere(Vec3(0.1, 0.2, 0.3), 0.2, 3)), 0.0);
  EXPECT_EQ(squeeze::meshing::skinny_split_length(box(Vec3(0, 0, 0), Vec3(1, 0.6, 0.02))), 0.0);
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  for (int target : {150, 1000}) {
    SCOPED_TRACE("target " + std::to_string(target));
    const MeshResult r = mesh(s, target);
    EXPECT_EQ(r.method, "boundary") << r.fallback_because;
    EXPECT_TRUE(r.tet_stats.conforming);
    expect_within(r, diag, 0.05, 0.015, 0.005, 1);
    EXPECT_FALSE(r.tet_stats.work_exceeded);
    EXPECT_LT(r.tet_stats.refine_work, 1e6);
    EXPECT_LT(r.quality.tets, 4 * target);
  }
  // The same rod with rounder triangles is not split, and meshes alike.
  const SurfaceMesh fine = sqs::ringed_rod(0.003, 1.0, 12, 160);
  EXPECT_EQ(squeeze::meshing::skinny_split_length(fine), 0.0);
}

// A rod 2 m long and 2 cm across of one ring of 16 sides (side triangles 2 m by 3.9 mm: a CAD
// export's dowel) at 150, along an axis and turned off the axes. Along z, its first attempt split
// its boundary many times per face and went to retry 0 alone, whose remesh lost 11.9 % of the
// rod's volume at 10 mm and 3.0 % at 5.1 mm (chords of its round sides); halving the length
// again went over the retry's triangle cap, and the rod kept its first attempt, 7,509
// tetrahedra down to 2.8 degrees. Turned, its first attempt split less and its boundary of
// skinny triangles was split, simplified only to 17,762 faces and tetrahedralized three times
// over (134 s beside a test run, 2.7 degrees). Now such a boundary is not tetrahedralized, and
// the remesh length shrinks toward 2 % lost (meshing version 26): both hold.
TEST(MeshingV4, RodOfOneRingIsRemeshedShortEnoughToKeepItsVolume) {
  const SurfaceMesh s = sqs::ringed_rod(0.01, 2.0, 16, 1);
  SurfaceMesh turned = s;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  for (Eigen::Index v = 0; v < s.V.rows(); ++v)
    turned.V.row(v) = (R * s.V.row(v).transpose() + Vec3(3, -2, 5)).transpose();
  for (const SurfaceMesh* rod : std::array<const SurfaceMesh*, 2>{&s, &turned}) {
    SCOPED_TRACE(rod == &s ? "along z" : "turned");
    const MeshResult r = mesh(*rod, 150);
    EXPECT_EQ(r.method, "boundary") << r.fallback_because;
    EXPECT_EQ(r.parts_remeshed, 1);
    EXPECT_TRUE(r.tet_stats.conforming);
    expect_within(r, bounding_box_diagonal(rod->V), 0.05, 0.015, 0.005, 1);
    EXPECT_LT(r.quality.tets, 1000);
  }
}

// integrated_mean_curvature: π L on a rod (its long edges turn 2π/n each; the rims' 90° are
// creases, kept by the remesh, and count nothing), about 4π R on the sphere of tests/data, 0 on a
// box (creases only), negative on a surface turned inside out. And chord_length_for_volume_loss
// predicts the remesh: remeshed at the length it gives for 2.5 %, rods of 16 and 32 sides and a
// finely faceted sphere lose between 1.5 and 3 % of their volume (retry 0 accepts up to 3 %).
// Before meshing version 27 retry 0 started at a quarter of the interior edge length and the
// 32-sided rod at 1000 lost 3.6 % there.
TEST(MeshingV4, ChordLengthForAVolumeLossPredictsTheRemesh) {
  using squeeze::meshing::chord_length_for_volume_loss;
  using squeeze::meshing::integrated_mean_curvature;
  const SurfaceMesh sphere = sqt::read_off(sqt::data("sphere.off"));
  const double R = sphere.V.rowwise().norm().maxCoeff();
  EXPECT_NEAR(integrated_mean_curvature(sphere, 40.0), 4 * M_PI * R, 0.05 * 4 * M_PI * R);
  EXPECT_NEAR(integrated_mean_curvature(box(Vec3(0, 0, 0), Vec3(2, 1, 0.1), {4, 2, 1}), 40.0), 0.0, 1e-12);
  SurfaceMesh inside_out = sphere;
  inside_out.F.col(1).swap(inside_out.F.col(2));
  EXPECT_LT(integrated_mean_curvature(inside_out, 40.0), -0.9 * 4 * M_PI * R);
  EXPECT_TRUE(std::isinf(chord_length_for_volume_loss(inside_out, sqt::enclosed_volume(sphere), 0.025, 40.0)));
  const SurfaceMesh rod16 = sqs::ringed_rod(0.01, 0.4, 16, 1), rod32 = sqs::ringed_rod(0.01, 0.4, 32, 1);
  EXPECT_NEAR(integrated_mean_curvature(rod16, 40.0), M_PI * 0.4, 1e-9);
  // A sphere of triangles far smaller than the length (tests/data's: about as long, and its own
  // chords have lost what the prediction counts; remeshed, it lost 0.7 %).
  std::vector<Eigen::Vector2d> arc;
  for (int k = 0; k <= 48; ++k) arc.emplace_back(k % 48 == 0 ? 0.0 : std::sin(M_PI * k / 48), -std::cos(M_PI * k / 48));
  const SurfaceMesh fine = sqs::revolved(arc, 96);
  for (const SurfaceMesh* s : {&rod16, &rod32, &fine}) {
    SCOPED_TRACE(s == &fine ? "sphere" : s == &rod16 ? "rod of 16 sides" : "rod of 32 sides");
    const double v = sqt::enclosed_volume(*s);
    squeeze::meshing::RemeshOptions o;
    o.edge_length = chord_length_for_volume_loss(*s, v, 0.025, o.sharp_angle);
    ASSERT_TRUE(std::isfinite(o.edge_length));
    const SurfaceMesh r = squeeze::meshing::remesh_isotropic(*s, o);
    ASSERT_GT(r.F.rows(), 0);
    const double lost = 1.0 - sqt::enclosed_volume(r) / v;
    EXPECT_GT(lost, 0.015) << "at " << o.edge_length;
    EXPECT_LT(lost, 0.03) << "at " << o.edge_length;
  }
  // MeshOptions::remesh_volume_loss outside [0, 1) is an input error, as the other options.
  for (double bad : {-0.01, 1.0, std::nan("")}) {
    MeshOptions o;
    o.remesh_volume_loss = bad;
    EXPECT_THROW(squeeze::meshing::mesh_surface(box(Vec3(0, 0, 0), Vec3(1, 1, 1)), o), squeeze::InputError) << bad;
  }
}

// A refinement work budget (TetrahedralizeOptions::max_refine_work) stops refinement within a
// round, not at its end: the same rod's boundary, split at a tenth of a metre, searched 5.6
// million conflict-zone cells in its second round against a budget of 2 million.
TEST(MeshingV4, RefinementStopsAtItsWorkBudgetWithinARound) {
  const SurfaceMesh s = sqs::ringed_rod(0.01, 2.0, 16, 1);
  for (double budget : {2e5, 2e6}) {
    SCOPED_TRACE("budget " + std::to_string(budget));
    squeeze::meshing::TetrahedralizeOptions t;
    t.target_tets = 150;
    t.max_attempts = 1;
    t.max_refine_work = budget;
    squeeze::meshing::TetrahedralizeStats st;
    const squeeze::meshing::TetMesh m = squeeze::meshing::tetrahedralize(s, t, &st);
    EXPECT_GT(m.T.rows(), 0);
    EXPECT_TRUE(st.work_exceeded);
    EXPECT_GT(st.refine_work, budget);
    // Past the budget by at most one insertion's conflict zone (a few thousand cells here).
    EXPECT_LT(st.refine_work, budget + 1e5);
  }
}

// Asked for its convex shells, the rod (one shell, thinner than Mesh_3's cells) got 24 tetrahedra
// around its middle, 3.6 times its volume and a diagonal off it. Such a shells mesh is refused and
// the input is meshed by the default route, the report saying why.
TEST(MeshingV4, ShellsOnlyFallsBackWhereMesh3CannotMeshTheShells) {
  const SurfaceMesh s = sqs::ringed_rod(0.003, 1.0, 12, 40);
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.shells_only = true;
  const MeshResult r = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(r.method, "boundary");
  EXPECT_NE(r.fallback_because.find("convex shells were asked for, but"), std::string::npos) << r.fallback_because;
  expect_within(r, diag, 0.05, 0.015, 0.005, 1);
  // Where Mesh_3 can, the shells stay (the sphere: one shell around it).
  const MeshResult b = squeeze::meshing::mesh_surface(sphere(Vec3(0, 0, 0), 0.2, 3), o);
  EXPECT_EQ(b.method, "convex_shells");
}

// The heart's convex shells meshed by Mesh_3 (the paper's coarse mesh, --shells-fallback) took 38 s
// at 300, 26.5 s of it in Mesh_3's sliver perturber (evaluating the union's inside test), and 41 s
// at 500 (eight attempts, the last three 11 s each). Since meshing version 17 the exuder's slivers
// are relocated and flipped instead (tet_cleanup.h): the mesh must hold the same bounds.
TEST(MeshingV4, HeartShellsHoldTheirBoundsWithoutThePerturber) {
  const SurfaceMesh s = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/heart.off");
  for (int target : {300, 500}) {
    SCOPED_TRACE(target);
    MeshOptions o;
    o.tetrahedralize.target_tets = target;
    o.shells_fallback = true;
    const MeshResult r = squeeze::meshing::mesh_surface(s, o);
    ASSERT_EQ(r.method, "convex_shells") << r.fallback_because;
    EXPECT_FALSE(o.shells.perturb);
    EXPECT_GE(r.shell_stats.covered, 0.999);
    EXPECT_GE(r.quality.min_dihedral, o.tetrahedralize.min_dihedral);
    EXPECT_GE(r.covered_fraction, 0.999);
    EXPECT_EQ(r.quality.components, 1);
    EXPECT_GE(r.quality.tets, 0.65 * target);
    EXPECT_LE(r.quality.tets, 1.35 * target);
    // The shells are looser than the bound (7.6 % of the diagonal out), and the report says so.
    EXPECT_NE(r.deviation_exceeded_because.find("the convex shells' mesh lies up to"), std::string::npos)
        << r.deviation_exceeded_because;
  }
}

// --shells-fallback (the paper's convex shells for inputs that are not closed parts) kept the shells'
// Mesh_3 mesh whatever it held. A rod 1 m long and 4 mm across, two boxes welded at a shared wall,
// was one thin shell: Mesh_3's cells, sized by the target, are far wider than it, and its mesh held
// a third of the rod's vertices (its corners only), or, dilated until it held them, grew 5,342
// times the shell's volume. Since meshing version 17 the default route meshes it instead, as
// --shells-only already did, and the report says why. (Since version 18 that rod is one closed
// part, its wall dropped. Two segments of the rod that overlap by 20 cm, the second's end 0.1 µm
// off the first's vertices there, are not: only their faces from 0.5 to 0.6 weld, and their shells
// fail in the same way.)
// Convex shells that leave the input's points far outside (a Moebius strip's four shells at 150
// held 36 % of its vertices) are dilated by at most 5 % of their diagonal. The dilation grew as a
// multiple of a facet distance that grows with the cell size: 26 m around the 1 m strip after
// eight attempts, 576 % of the diagonal out (the mesh was then refused or, as the fallback, kept).
TEST(MeshingV4, ShellsDilationIsBounded) {
  const SurfaceMesh strip = sqs::mobius_strip(0.5, 0.2, 120, 8);
  squeeze::meshing::DecompositionOptions d;
  d.max_hulls = 4;
  const auto shells = squeeze::meshing::decompose(strip, d).shells;
  ASSERT_FALSE(shells.empty());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& sh : shells) {
    lo = lo.cwiseMin(sh.hull.V.colwise().minCoeff().transpose());
    hi = hi.cwiseMax(sh.hull.V.colwise().maxCoeff().transpose());
  }
  const double diag = (hi - lo).norm();
  squeeze::meshing::ShellTetrahedralizeOptions o;
  o.target_tets = 150;
  squeeze::meshing::ShellTetrahedralizeStats st;
  const squeeze::meshing::TetMesh m = squeeze::meshing::tetrahedralize_shells(shells, o, &st, nullptr, &strip.V);
  ASSERT_GT(m.T.rows(), 0);
  EXPECT_LE(st.offset, 0.05 * diag + 1e-12);
  for (int k = 0; k < 3; ++k) {
    EXPECT_GE(m.V.col(k).minCoeff(), lo(k) - 0.1 * diag);
    EXPECT_LE(m.V.col(k).maxCoeff(), hi(k) + 0.1 * diag);
  }
}

TEST(MeshingV4, ShellsFallbackIsRefusedWhereItsMeshDoesNotHoldTheInput) {
  const fs::path dir = fs::temp_directory_path() / ("squeeze_welded_rod_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  SurfaceMesh second = box(Vec3(0.4, 0, 0), Vec3(1.0, 0.004, 0.004), {6, 1, 1});
  for (Eigen::Index v = 0; v < second.V.rows(); ++v)
    if (second.V(v, 0) == 0.4) second.V(v, 0) += 1e-7;  // 0.1 µm: not welded
  sqt::write_off(dir / "rod.off", join({box(Vec3(0, 0, 0), Vec3(0.6, 0.004, 0.004), {6, 1, 1}), second}));
  const SurfaceMesh s = squeeze::meshing::load_surface(dir / "rod.off");  // welds the shared faces
  fs::remove_all(dir);
  MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.shells_fallback = true;
  const auto t0 = std::chrono::steady_clock::now();
  const MeshResult r = squeeze::meshing::mesh_surface(s, o);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(r.method, "convex_shells");
  EXPECT_NE(r.fallback_because.find("convex shells were asked for, but their Mesh_3 mesh"), std::string::npos)
      << r.fallback_because;
  EXPECT_NE(r.fallback_because.find("--shells-fallback"), std::string::npos) << r.fallback_because;
  EXPECT_GE(r.covered_fraction, 0.999);
  int measured = 0;  // the report's seconds hold both tries: each was measured
  for (const auto& [stage, seconds] : r.seconds) measured += stage == "measuring";
  EXPECT_EQ(measured, 2);
  // Their stages sum to the call's wall time (since meshing version 50 a try dropped with its stages
  // is in `tries not kept`).
  double staged = 0;
  for (const auto& stage : r.seconds) staged += stage.second;
  EXPECT_NEAR(staged, wall, 0.06);
}

// Segments welded face to face, each closed with its own copy of the shared wall (two boxes end to
// end: the wall's two faces are twins, the same vertices in opposite orders), are their union: the
// twins, enclosed by the rest of the input, are dropped both, and what is left is one closed part,
// meshed exact by the boundary route. Until meshing version 18 one twin was kept, the input was not
// a closed part, and a rod 4 mm across came out 5.6 to 6.9 times its volume (a 2 cm one 1.8 times,
// three welded 0.5 m cubes 1.03 times). A sheet modelled as two faces back to back encloses nothing
// and is still one sheet.
TEST(MeshingV4, SegmentsWeldedFaceToFaceAreTheirUnion) {
  const struct {
    const char* name;
    std::vector<std::pair<Vec3, Vec3>> boxes;  // each closed, their shared walls in both
    Vec3 lo, hi;                               // the union's bounding box
    double volume;
    int squares = 2;                           // squares along each box face's side
    bool one_copy = true;                      // also meshed with one copy of each wall
  } cases[] = {
      {"rod 1 m x 4 mm, two segments", {{{0, 0, 0}, {0.5, 0.004, 0.004}}, {{0.5, 0, 0}, {1, 0.004, 0.004}}}, {0, 0, 0},
       {1, 0.004, 0.004}, 1 * 0.004 * 0.004},
      {"L of three blocks",
       {{{0, 0, 0}, {0.2, 0.12, 0.1}}, {{0.2, 0, 0}, {0.35, 0.12, 0.1}}, {{0, 0.12, 0}, {0.2, 0.2, 0.1}}},
       {0, 0, 0},
       {0.35, 0.2, 0.1},
       0.2 * 0.12 * 0.1 + 0.15 * 0.12 * 0.1 + 0.2 * 0.08 * 0.1},
      // A voxel model: nine 0.1 m cubes, 3 by 3, touching face to face, two triangles a face. The
      // walls cut the middle cube's top and bottom into patches of their own, which an orientation
      // test cannot turn outward. Until meshing version 28 they were oriented apart from the rest,
      // no wall was found, and the plate came out 1.6 times its volume, 10 % of the diagonal out.
      // (With four squares a face, as the other cases, such a flat patch kept the file's
      // orientation by the rounding of its signed volume, and it passed before.)
      {"plate of nine cubes",
       {{{0, 0, 0}, {0.1, 0.1, 0.1}}, {{0.1, 0, 0}, {0.2, 0.1, 0.1}}, {{0.2, 0, 0}, {0.3, 0.1, 0.1}},
        {{0, 0.1, 0}, {0.1, 0.2, 0.1}}, {{0.1, 0.1, 0}, {0.2, 0.2, 0.1}}, {{0.2, 0.1, 0}, {0.3, 0.2, 0.1}},
        {{0, 0.2, 0}, {0.1, 0.3, 0.1}}, {{0.1, 0.2, 0}, {0.2, 0.3, 0.1}}, {{0.2, 0.2, 0}, {0.3, 0.3, 0.1}}},
       {0, 0, 0},
       {0.3, 0.3, 0.1},
       0.3 * 0.3 * 0.1,
       1,
       // (Not found as walls with one copy of each: each wall's winding-number mean holds the
       // other eleven's open shares. docs/meshing.md, version 28.)
       false},
  };
  const fs::path dir = fs::temp_directory_path() / ("squeeze_welded_faces_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (const auto& c : cases) {
    std::vector<SurfaceMesh> parts;
    for (const auto& [lo, hi] : c.boxes) parts.push_back(box(lo, hi, {c.squares, c.squares, c.squares}));
    sqt::write_off(dir / "welded.off", join(parts));
    const SurfaceMesh twins = squeeze::meshing::load_surface(dir / "welded.off");  // welds the shared walls
    // ... and with one copy of each wall: the later face of each twin pair left out.
    SurfaceMesh one = twins;
    {
      std::set<std::array<int, 3>> seen;
      std::vector<Eigen::Index> keep;
      for (Eigen::Index f = 0; f < twins.F.rows(); ++f) {
        std::array<int, 3> k{twins.F(f, 0), twins.F(f, 1), twins.F(f, 2)};
        std::sort(k.begin(), k.end());
        if (seen.insert(k).second) keep.push_back(f);
      }
      ASSERT_LT(keep.size(), static_cast<size_t>(twins.F.rows())) << c.name;
      one.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
      for (size_t i = 0; i < keep.size(); ++i) one.F.row(static_cast<Eigen::Index>(i)) = twins.F.row(keep[i]);
    }
    const double diag = (c.hi - c.lo).norm();
    for (int target : {150, 1000, 0}) {
      for (const SurfaceMesh* s : {&twins, static_cast<const SurfaceMesh*>(&one)}) {
        if (s == &one && !c.one_copy) continue;
        const std::string what = std::string(c.name) + (s == &one ? ", one copy of each wall," : ", walls in both,") +
                                 " at target " + (target ? std::to_string(target) : "default");
        const MeshResult r = mesh(*s, target);
        EXPECT_EQ(r.method, "boundary") << what << ": " << r.fallback_because;
        EXPECT_NEAR(tet_volume(r.tets) / c.volume, 1.0, 0.01) << what;
        EXPECT_LE(r.deviation_out, 0.002 * diag) << what;
        EXPECT_LE(r.deviation_in, 0.002 * diag) << what;
        EXPECT_EQ(r.quality.components, 1) << what;
        EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
        for (Eigen::Index i = 0; i < r.tets.V.rows(); ++i)
          for (int k = 0; k < 3; ++k) {
            ASSERT_GE(r.tets.V(i, k), c.lo(k) - 0.002 * diag) << what << ", vertex " << i;
            ASSERT_LE(r.tets.V(i, k), c.hi(k) + 0.002 * diag) << what << ", vertex " << i;
          }
      }
    }
  }
  // A square sheet, 0.4 m, modelled as two faces back to back (each face and its twin): no wall
  // between solids, so one copy is kept and the sheet is meshed as a slab about its mid-surface.
  {
    SurfaceMesh sheet;
    sheet.V.resize(4, 3);
    sheet.V << 0, 0, 0, 0.4, 0, 0, 0.4, 0.4, 0, 0, 0.4, 0;
    sheet.F.resize(4, 3);
    sheet.F << 0, 1, 2, 0, 2, 3, 0, 2, 1, 0, 3, 2;
    const MeshResult r = mesh(sheet, 150);
    EXPECT_EQ(r.quality.components, 1);
    EXPECT_GT(r.tets.T.rows(), 0);
    EXPECT_LE(r.deviation_out, 0.015 * 0.4 * std::sqrt(2.0));
    EXPECT_LE(r.deviation_in, 0.005 * 0.4 * std::sqrt(2.0));
  }
  fs::remove_all(dir);
}

// A point computed two ways lands a few ulps apart (0.6 × 4/6 = 0.39999999999999997, and 0.4):
// two rods 4 mm across, 0.6 m long, overlapping by 0.2 m, each in six sections, share their
// vertices at x = 0.4 only to 6e-17. The loader welds vertices within 1e-12 of the diagonal
// (LoadOptions::weld_tolerance, since meshing version 18): the rods' shared faces are then one, the
// union one closed part, meshed exact. Identical coordinates only (tolerance 0) leave some faces
// apart: not a closed part, and the winding-number route's tetrahedra were 5.1 times its volume.
TEST(MeshingV4, NearlyCoincidentVerticesAreWelded) {
  const fs::path dir = fs::temp_directory_path() / ("squeeze_near_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const SurfaceMesh first = box(Vec3(0, 0, 0), Vec3(0.6, 0.004, 0.004), {6, 1, 1}),
                    second = box(Vec3(0.4, 0, 0), Vec3(1.0, 0.004, 0.004), {6, 1, 1});
  ASSERT_NE(0.6 * 4 / 6, 0.4);
  sqt::write_off(dir / "rods.off", join({first, second}));
  const SurfaceMesh s = squeeze::meshing::load_surface(dir / "rods.off");
  squeeze::meshing::LoadOptions exact;
  exact.weld_tolerance = 0;
  const SurfaceMesh apart = squeeze::meshing::load_surface(dir / "rods.off", exact);
  fs::remove_all(dir);
  EXPECT_EQ(s.V.rows(), 4 * 11);  // the rings at x = 0, 0.1, ..., 1.0
  EXPECT_EQ(apart.V.rows(), 4 * 12);
  const double diag = Vec3(1, 0.004, 0.004).norm();
  for (int target : {150, 1000}) {
    const MeshResult r = mesh(s, target);
    EXPECT_EQ(r.method, "boundary") << target << ": " << r.fallback_because;
    EXPECT_NEAR(tet_volume(r.tets) / (1 * 0.004 * 0.004), 1.0, 0.01) << target;
    EXPECT_LE(r.deviation_out, 0.002 * diag) << target;
    EXPECT_LE(r.deviation_in, 0.002 * diag) << target;
    EXPECT_EQ(r.quality.components, 1) << target;
  }
}

/// A tube open at both ends, no thickness: radius r about the z axis from z = 0 to `length`,
/// `sides` around and `rings` along, (sides)(rings + 1) vertices.
SurfaceMesh open_tube(double r, double length, int sides, int rings) {
  SurfaceMesh s;
  s.V.resize(sides * (rings + 1), 3);
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i < sides; ++i) {
      const double t = 2 * M_PI * i / sides;
      s.V.row(j * sides + i) << r * std::cos(t), r * std::sin(t), length * j / rings;
    }
  s.F.resize(2 * sides * rings, 3);
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < sides; ++i) {
      const int a = j * sides + i, b = j * sides + (i + 1) % sides;
      s.F.row(2 * (j * sides + i)) << a, b, b + sides;
      s.F.row(2 * (j * sides + i) + 1) << a, b + sides, a + sides;
    }
  return s;
}

// Open scans of thin solids whose holes are narrow: the winding-number solid's boundary is not
// found by Mesh_3 about a solid thinner than its seeds' spacing, and Mesh_3's own tetrahedra of it
// were 8.3 times the volume of a rod 4 mm across with one end open. Since meshing version 18 the
// scan with its holes capped is meshed as a closed part where each cap lies within the bound
// (method "capped_boundary").
TEST(MeshingV4, ThinOpenScansAreMeshedWithTheirNarrowHolesCapped) {
  // Rods 1 m long, 4 mm and 2 cm across, without their end at x = 1 (the 2 cm rod's cap lies 1 %
  // of the diagonal off it, the bound itself: Mesh_3's tetrahedra of its solid were 1.8 times its
  // volume).
  for (double t : {0.004, 0.02}) {
    const SurfaceMesh closed = box(Vec3(0, 0, 0), Vec3(1, t, t), {2, 1, 1});
    SurfaceMesh rod;
    rod.V = closed.V;
    std::vector<Eigen::Index> keep;
    for (Eigen::Index f = 0; f < closed.F.rows(); ++f)
      if (!(closed.V(closed.F(f, 0), 0) == 1 && closed.V(closed.F(f, 1), 0) == 1 && closed.V(closed.F(f, 2), 0) == 1))
        keep.push_back(f);
    rod.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
    for (size_t i = 0; i < keep.size(); ++i) rod.F.row(static_cast<Eigen::Index>(i)) = closed.F.row(keep[i]);
    ASSERT_EQ(rod.F.rows(), closed.F.rows() - 2);
    const double diag = Vec3(1, t, t).norm(), volume = 1 * t * t;
    for (int target : {150, 1000, 0}) {
      const std::string what = std::to_string(t) + " m rod at target " + (target ? std::to_string(target) : std::string("default"));
      const MeshResult r = mesh(rod, target);
      EXPECT_EQ(r.method, "capped_boundary") << what << ": " << r.fallback_because;
      EXPECT_NE(r.fallback_because.find("holes are narrower than the bound"), std::string::npos) << what;
      EXPECT_NEAR(tet_volume(r.tets) / volume, 1.0, 0.01) << what;
      EXPECT_NEAR(r.input_volume / volume, 1.0, 0.01) << what << ": the capped scan's volume";
      EXPECT_LE(r.deviation_out, (t < 0.01 ? 0.005 : 0.015) * diag) << what;
      EXPECT_LE(r.deviation_in, 0.002 * diag) << what;
      EXPECT_EQ(r.quality.components, 1) << what;
      EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
    }
  }
  // A pipe 4 mm across and 1 m long, 16 sides, open at both ends, of triangles 50 times as long as
  // they are wide.
  const SurfaceMesh pipe = open_tube(0.002, 1.0, 16, 20);
  const double pipe_diag = sqt::diagonal(pipe.V);
  for (int target : {150, 1000}) {
    const std::string what = "pipe at target " + std::to_string(target);
    const MeshResult r = mesh(pipe, target);
    EXPECT_EQ(r.method, "capped_boundary") << what << ": " << r.fallback_because;
    EXPECT_NEAR(r.quality.volume / r.input_volume, 1.0, 0.05) << what;
    EXPECT_LE(r.deviation_out, 0.015 * pipe_diag) << what;
    EXPECT_LE(r.deviation_in, 0.005 * pipe_diag) << what;
    EXPECT_EQ(r.quality.components, 1) << what;
    EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
  }
}

// A tube open at both ends (10 cm across, 40 cm long, no thickness: a vessel's wall, say) encloses
// a solid by its winding number, so it was meshed as one: the caps over its ends lay 11.7 % of the
// diagonal off the input. Meshed as an open sheet (a slab) it holds the bounds, and the report says
// why.
// Thin closed tubes that pass close to themselves: a coil spring of 3 mm wire (8 turns 15 mm apart,
// 50 mm radius) at 150 tetrahedra. Its simplified boundary's long triangles have the other side of
// the wire in their diametral balls; recovering them took 1,042 edge splits for 725 points, and
// recovery gave up at 1.5 splits a point (meshing version 18: not conforming, 1.2 % of the
// diagonal in). And a cube with a fin 2 mm thick welded on (one closed part, 16 faces), whose fin
// took as many splits at 150 and 300 (version 18: not conforming, 11 % out, 44 % in, 3.9°).
TEST(MeshingV4, ThinTubesAndFinsAreRecoveredConforming) {
  const SurfaceMesh spring = sqs::coil_spring(0.05, 0.015, 8, 0.003, 10, 799);
  const double spring_diag = (spring.V.colwise().maxCoeff() - spring.V.colwise().minCoeff()).norm();
  const MeshResult r = mesh(spring, 150);
  EXPECT_EQ(r.method, "boundary");
  EXPECT_TRUE(r.tet_stats.conforming);
  expect_within(r, spring_diag, 0.05, 0.015, 0.005, 1);
  // The cube 0.1 m, the fin 0.3 m out of one side, 2 mm thick and as tall as the cube.
  const double x[8] = {0, 0.1, 0.1, 0.4, 0.4, 0.1, 0.1, 0}, y[8] = {0, 0, 0.049, 0.049, 0.051, 0.051, 0.1, 0.1};
  SurfaceMesh fin;
  fin.V.resize(16, 3);
  for (int z = 0; z < 2; ++z)
    for (int i = 0; i < 8; ++i) fin.V.row(8 * z + i) << x[i], y[i], 0.1 * z;
  std::vector<std::array<int, 3>> F;
  for (int i = 0; i < 8; ++i) {
    const int j = (i + 1) % 8;
    F.push_back({i, j, 8 + j});
    F.push_back({i, 8 + j, 8 + i});
  }
  for (const auto& t : std::vector<std::array<int, 3>>{{0, 1, 2}, {0, 2, 5}, {0, 5, 6}, {0, 6, 7}, {2, 3, 4}, {2, 4, 5}}) {
    F.push_back({t[2], t[1], t[0]});
    F.push_back({8 + t[0], 8 + t[1], 8 + t[2]});
  }
  fin.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t f = 0; f < F.size(); ++f) fin.F.row(static_cast<Eigen::Index>(f)) << F[f][0], F[f][1], F[f][2];
  const double fin_diag = (fin.V.colwise().maxCoeff() - fin.V.colwise().minCoeff()).norm();
  for (int target : {150, 300}) {
    SCOPED_TRACE("cube with a fin at " + std::to_string(target));
    const MeshResult f = mesh(fin, target);
    EXPECT_TRUE(f.tet_stats.conforming);
    expect_within(f, fin_diag, 0.01, 0.002, 0.002, 1);
  }
}

// A hipped roof 4.2 mm thick (vertically) and 0.65 m long, one of the closed parts of a building
// model (assimp's test/models/OBJ/regr01.obj), its coordinates rounded to 0.1 mm. At its far end
// the top runs on while the underside rises to meet it at 38°: faces of the top there face that
// bevel, not the underside, so they were left out of its side (version 19: the slab missed them
// by 0.8 % of the diagonal), and the taper gave prisms of no height. The boundary route then left
// it not conforming at every target: 6 % of its volume at 150, 1.5° at 1,000. Version 20: its side
// takes them in, the slab is no thinner than a quarter of the mean thickness, and the slab is tried
// where the first attempt does not hold (L over 3 times the thickness: 5.8 at 1,000).
// A CAD cylinder as trimesh's cylinder.stl has it (radius 1, height 8, 104 sides, caps fanned from
// their centres: cylinder() above): at 150 its boundary's first tetrahedralization splits its
// edges about eight times per face (3,315 for 416) and is not conforming. It takes none of the
// retries that start from its own triangles (each had split as much and not held: 3 retries, 94 s
// on a busy machine; meshing version 21: its winding-number solid at once). Since version 22 its
// surface remeshed into round triangles is tried first, and holds: one retry, no solid.
TEST(MeshingV4, BoundaryThatSplitsFarOverItsFacesIsRemeshedWithoutOtherRetries) {
  const SurfaceMesh s = cylinder(Vec3(0, 0, 0), Vec3(0, 0, 8), 1.0, 104);
  const MeshResult r = mesh(s, 150);
  EXPECT_EQ(r.boundary_retries, 1);
  EXPECT_EQ(r.parts_by_winding_number, 0);
  EXPECT_EQ(r.parts_remeshed, 1);
  expect_within(r, bounding_box_diagonal(s.V), 0.05, 0.015, 0.005, 1);
  EXPECT_TRUE(r.tet_stats.conforming);
  MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.remesh_retry = false;  // as version 21
  const MeshResult old = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(old.boundary_retries, 0);
  EXPECT_EQ(old.parts_by_winding_number, 1);
  EXPECT_EQ(old.parts_remeshed, 0);
}

// remesh_isotropic: a box whose long faces are strips 20 times longer than wide (a CAD
// tessellation: those triangles under 3°) comes out as round triangles about the edge length
// long, and the same box: its creases and corners kept, every vertex on its faces, the volume
// exact, closed.
TEST(MeshingV4, RemeshIsotropicMakesRoundTrianglesOfTheSameBox) {
  const SurfaceMesh s = box(Vec3(0, 0, 0), Vec3(2, 1, 0.1), {40, 1, 1});
  auto min_angles = [](const SurfaceMesh& m) {
    std::vector<double> a;
    for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
      double least = 180;
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = m.V.row(m.F(f, k)), q = m.V.row(m.F(f, (k + 1) % 3)), r = m.V.row(m.F(f, (k + 2) % 3));
        const Vec3 u = q - p, w = r - p;
        least = std::min(least, std::atan2(u.cross(w).norm(), u.dot(w)) * 180 / M_PI);
      }
      a.push_back(least);
    }
    return a;
  };
  auto share_under = [](const std::vector<double>& a, double deg) {
    return static_cast<double>(std::count_if(a.begin(), a.end(), [&](double x) { return x < deg; })) / a.size();
  };
  EXPECT_GT(share_under(min_angles(s), 5.0), 0.45);  // the strips of its two largest sides: 2.9°
  squeeze::meshing::RemeshOptions o;
  o.edge_length = 0.1;
  const SurfaceMesh r = squeeze::meshing::remesh_isotropic(s, o);
  ASSERT_GT(r.F.rows(), 100);
  EXPECT_LT(share_under(min_angles(r), 20.0), 0.05);
  double volume = 0;
  for (Eigen::Index f = 0; f < r.F.rows(); ++f)
    volume += Vec3(r.V.row(r.F(f, 0))).dot(Vec3(r.V.row(r.F(f, 1))).cross(Vec3(r.V.row(r.F(f, 2))))) / 6.0;
  EXPECT_NEAR(volume, 0.2, 1e-9);
  const Vec3 hi(2, 1, 0.1);
  for (Eigen::Index v = 0; v < r.V.rows(); ++v) {
    double off = INFINITY;
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(r.V(v, k), -1e-12);
      EXPECT_LE(r.V(v, k), hi(k) + 1e-12);
      off = std::min({off, std::abs(r.V(v, k)), std::abs(r.V(v, k) - hi(k))});
    }
    EXPECT_LT(off, 1e-12) << "vertex " << v << " off the box's faces";
  }
  std::map<std::pair<int, int>, int> uses;
  for (Eigen::Index f = 0; f < r.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++uses[{r.F(f, k), r.F(f, (k + 1) % 3)}];
  for (const auto& [e, n] : uses) EXPECT_EQ(n + uses.count({e.second, e.first}) - 1, 1) << "edge not closed and oriented";
  for (const Eigen::Index c : {0, 1, 2, 3})  // corners kept
    EXPECT_TRUE((r.V.rowwise() - s.V.row(c)).rowwise().norm().minCoeff() < 1e-12);
  EXPECT_THROW(squeeze::meshing::remesh_isotropic(s, squeeze::meshing::RemeshOptions{}), squeeze::InputError);
}

TEST(MeshingV4, ThinRoofTaperingAtOneEndIsOneLayerOfPrisms) {
  const double v[16][3] = {{0.1754, 0.6084, 0.3298}, {0.1755, 0.6084, 0.3340}, {-0.0446, -0.0419, 0.2009}, {-0.0420, -0.0419, 0.1967}, {0.1754, 0.1436, 0.3298}, {0.3925, -0.0419, 0.1967}, {0.3951, -0.0419, 0.2009}, {0.1755, 0.1436, 0.3340}, {-0.0446, 0.2895, 0.2009}, {-0.0420, 0.2790, 0.1967}, {0.1761, 0.6084, 0.3294}, {0.3925, 0.2790, 0.1967}, {0.3951, 0.2895, 0.2009}, {0.1830, 0.6084, 0.3294}, {0.1679, 0.6084, 0.3294}, {0.1748, 0.6084, 0.3294}};
  const int f[28][3] = {{9, 3, 2}, {2, 8, 9}, {4, 3, 9}, {4, 9, 15}, {4, 15, 0}, {11, 5, 4}, {10, 11, 4}, {0, 10, 4}, {11, 12, 6}, {6, 5, 11}, {7, 6, 12}, {1, 7, 12}, {13, 1, 12}, {1, 14, 8}, {1, 8, 2}, {1, 2, 7}, {10, 0, 1}, {1, 13, 10}, {3, 4, 7}, {7, 2, 3}, {14, 1, 0}, {0, 15, 14}, {4, 5, 6}, {6, 7, 4}, {10, 13, 12}, {12, 11, 10}, {8, 14, 15}, {15, 9, 8}};
  SurfaceMesh roof;
  roof.V.resize(16, 3);
  roof.F.resize(28, 3);
  for (int i = 0; i < 16; ++i) roof.V.row(i) << v[i][0], v[i][1], v[i][2];
  for (int i = 0; i < 28; ++i) roof.F.row(i) << f[i][0], f[i][1], f[i][2];
  const double diag = (roof.V.colwise().maxCoeff() - roof.V.colwise().minCoeff()).norm();
  for (int target : {150, 1000}) {
    SCOPED_TRACE("roof at " + std::to_string(target));
    const MeshResult r = mesh(roof, target);
    EXPECT_EQ(r.method, "boundary");
    EXPECT_EQ(r.thin_parts, 1);
    EXPECT_TRUE(r.tet_stats.conforming);
    expect_within(r, diag, target >= 1000 ? 0.05 : 0.1, 0.015, 0.005, 1);
  }
}

TEST(MeshingV4, OpenTubeIsMeshedAsASheetWhereItsCapsBreakTheBound) {
  const SurfaceMesh s = open_tube(0.05, 0.4, 32, 20);
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  const MeshResult r = mesh(s, 300);
  EXPECT_NE(r.fallback_because.find("holes are wider than the deviation bound"), std::string::npos) << r.fallback_because;
  EXPECT_LE(r.deviation_out, 0.015 * diag);
  EXPECT_LE(r.deviation_in, 0.005 * diag);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_EQ(r.quality.components, 1);
}

// A closed spherical cap shell (a bowl): outer radius r, `thick` thick, opening below the equator
// at polar angle `open`, n around, m from the pole to the rim; the rim a band of n quads.
SurfaceMesh bowl(double r, double thick, double open, int n, int m) {
  std::vector<Vec3> V;
  std::vector<std::array<int, 3>> F;
  for (int side = 0; side < 2; ++side) {  // outer, then inner
    const double R = side == 0 ? r : r - thick;
    V.push_back(Vec3(0, 0, R));
    for (int j = 1; j <= m; ++j)
      for (int i = 0; i < n; ++i) {
        const double th = open * j / m, ph = 2 * M_PI * i / n;
        V.push_back(Vec3(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph), R * std::cos(th)));
      }
  }
  const int o = 1 + m * n;  // the inner side's first vertex
  auto at = [&](int side, int j, int i) { return side * o + (j == 0 ? 0 : 1 + (j - 1) * n + (i % n)); };
  for (int side = 0; side < 2; ++side)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < n; ++i) {
        std::array<int, 3> a{at(side, j, i), at(side, j + 1, i), at(side, j + 1, i + 1)};
        std::array<int, 3> b{at(side, j, i), at(side, j + 1, i + 1), at(side, j, i + 1)};
        if (side == 1) std::swap(a[1], a[2]), std::swap(b[1], b[2]);  // the inner side faces inward
        F.push_back(a);
        if (j > 0) F.push_back(b);
      }
  for (int i = 0; i < n; ++i)  // the rim: outer to inner
    F.push_back({at(0, m, i), at(1, m, i), at(1, m, i + 1)}), F.push_back({at(0, m, i), at(1, m, i + 1), at(0, m, i + 1)});
  return surface_of(V, F);
}

// Parts much thinner than their tetrahedra would be long: a 1 m square plate 2 mm thick (12
// triangles) and a bowl of 10 cm radius 1 mm thick. Delaunay refinement between sides so close met
// slivers at every scale: the plate took 146 s and came out at 8 % of its volume, 18 % of the
// diagonal inside; the bowl was not conforming. Since meshing version 15 each is one layer of
// prisms across its thickness: the plate exact (the issue's boxes and plates: volume within 1 %,
// deviation 0.2 %), the bowl within the bounds, both at least 5 degrees and conforming.
TEST(MeshingV4, ThinPlateAndBowlAreOneLayerOfPrismsAcrossTheirThickness) {
  {
    const SurfaceMesh plate = box(Vec3(0, 0, 0), Vec3(1, 1, 0.002));
    const double diag = bounding_box_diagonal(plate.V);
    for (int target : {150, 1000}) {
      const std::string what = "plate at " + std::to_string(target);
      const MeshResult r = mesh(plate, target);
      EXPECT_EQ(r.thin_parts, 1) << what;
      EXPECT_NEAR(tet_volume(r.tets), 0.002, 0.01 * 0.002) << what;
      EXPECT_LE(r.deviation_out, 0.002 * diag) << what;
      EXPECT_LE(r.deviation_in, 0.002 * diag) << what;
      EXPECT_GE(r.quality.min_dihedral, 5.0) << what;
      EXPECT_TRUE(r.tet_stats.conforming) << what;
      EXPECT_EQ(r.quality.components, 1) << what;
      EXPECT_NE(r.target_exceeded_because.find("thinner than the tetrahedra"), std::string::npos) << r.target_exceeded_because;
    }
  }
  {
    const SurfaceMesh b = bowl(0.1, 0.001, 0.5 * M_PI, 64, 16);
    const double diag = bounding_box_diagonal(b.V), volume = sqt::enclosed_volume(b);
    ASSERT_GT(volume, 0);
    const MeshResult r = mesh(b, 300);
    EXPECT_EQ(r.thin_parts, 1);
    EXPECT_NEAR(tet_volume(r.tets) / volume, 1.0, 0.05);
    EXPECT_LE(r.deviation_out, 0.01 * diag);
    EXPECT_LE(r.deviation_in, 0.0045 * diag);
    EXPECT_GE(r.quality.min_dihedral, 5.0);
    EXPECT_TRUE(r.tet_stats.conforming);
    EXPECT_EQ(r.quality.components, 1);
  }
}

// An input far from the origin next to its size (world or survey coordinates) is meshed moved to
// the origin and moved back: the bunny at (1e5, -2e5, 3e5) gives the mesh it gives at the origin,
// moved (before: 3,107 tetrahedra, 1.07 times its volume, 59 s, against 1,864 in 5 s), and its
// convex shells' planes still bound their vertices.
// A 3 mm plate 0.6 × 0.4 m with 24 square holes 2 cm wide. The walls of the holes nearest the rim
// face the rim 4 cm away, within the tetrahedra's length at 150: they counted as paired faces, the
// flood of one side went through them from the top to the bottom, and the plate took the boundary
// route, whose exuder stopped at its 30 s limit (41 s in all; meshing version 18). One layer of
// prisms since version 19: exact, in well under a second.
TEST(MeshingV4, PerforatedPlateIsOneLayerOfPrisms) {
  std::vector<std::pair<int, int>> holes;
  for (int i = 2; i < 30; i += 4)
    for (int j = 2; j < 20; j += 6) holes.emplace_back(i, j);
  expect_one_slab(sqs::perforated_plate(30, 20, 0.6, 0.4, 0.003, holes), {150, 1000}, 0.01, 0.002, 0.002);
}

// A crumpled open sheet, 1 m square, 40 × 40 quads whose heights are white noise of 2 cm: no coarser
// sheet holds the bound, and remeshing it finer than its own triangles was pointless (78,000
// triangles at 7.7 mm: 233,773 tetrahedra, 38 s; meshing version 18). Its own triangles are the
// finest try since version 19. (Its folds leave slivers in the prisms: see docs/meshing.md.)
TEST(MeshingV4, RoughSheetIsNotRemeshedFinerThanItsOwnTriangles) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  const int n = 40;
  SurfaceMesh s;
  s.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) s.V.row(j * (n + 1) + i) << double(i) / n, double(j) / n, noise(rng);
  s.F.resize(2 * n * n, 3);
  for (int j = 0, f = 0; j < n; ++j)
    for (int i = 0; i < n; ++i, f += 2) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      s.F.row(f) << a, b, d;
      s.F.row(f + 1) << a, d, c;
    }
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  const MeshResult r = mesh(s, 300);
  EXPECT_EQ(r.sheets, 1);
  EXPECT_LE(r.quality.tets, 4 * s.F.rows());  // one layer of prisms over (about) its own triangles
  EXPECT_LE(r.deviation_out, 0.015 * diag);
  EXPECT_LE(r.deviation_in, 0.005 * diag);
}

// A sheet of a few large polygons creased between them (trimesh's polygonfaces.obj: a square 1 km
// wide with a triangle bent up 90° from one side, three triangles in all): the first remesh
// rounds the crease off (18.4 m from the input, bound 6 m), so its own triangles are the next try,
// and prisms 15 m thick over triangles 1 km wide left 0.29° (version 31). Since version 32 its own
// triangles are split to the width a prism may have: the crease stays, no sliver.
// Version 35: closed parts beside a stray component that is none. Four boards 1 m × 0.02 m ×
// 0.4 m crossing at their middles (closed parts that overlap, each meshed on its own) and a fin of
// three triangles on one edge above them (non-manifold: no closed part, no sheet) took the whole
// input to its winding-number solid, whose dilation and chords swell the thin boards (1.3-1.6
// times their volume). Now the boards stay exact and only the fin is a solid of its own.
TEST(MeshingV4, StrayFinBesideClosedBoardsLeavesTheBoardsExact) {
  std::vector<SurfaceMesh> pieces;
  double boards = 0;
  for (int k = 0; k < 4; ++k) {
    SurfaceMesh b = box(Vec3(-0.5, -0.01, -0.2), Vec3(0.5, 0.01, 0.2));
    const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI * k / 4, Vec3::UnitZ()).toRotationMatrix();
    b.V = (b.V * R.transpose()).eval();
    boards += 1.0 * 0.02 * 0.4;
    pieces.push_back(b);
  }
  SurfaceMesh fin;
  fin.V.resize(5, 3);
  fin.V << 0, 0, 0.2, 0, 0, 0.6, 0.3, 0, 0.4, -0.3, 0, 0.4, 0, 0.3, 0.4;
  fin.F.resize(3, 3);
  fin.F << 0, 1, 2, 0, 1, 3, 0, 1, 4;
  pieces.push_back(fin);
  const SurfaceMesh s = join(pieces);
  const double diag = bounding_box_diagonal(s.V);
  MeshOptions o;
  o.tetrahedralize.target_tets = 300;
  const MeshResult r = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(r.method, "winding_number_boundary");
  EXPECT_EQ(r.quality.components, 5) << "four boards and the fin's solid";
  EXPECT_LE(r.deviation_out, 0.015 * diag);
  EXPECT_LE(r.deviation_in, 0.005 * diag);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_GT(r.quality.volume, 0.999 * boards);
  EXPECT_LT(r.quality.volume, 1.1 * boards) << "the boards exact, the fin's solid thin";
  o.closed_parts_beside_solid = false;  // the whole input's solid, as before
  const MeshResult whole = squeeze::meshing::mesh_surface(s, o);
  EXPECT_GT(whole.quality.volume, 1.2 * boards);
}

TEST(MeshingV4, SheetOfAFewCreasedPolygonsIsSplitNotRemeshed) {
  const fs::path dir = fs::temp_directory_path() / ("squeeze_polygons_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    std::ofstream obj(dir / "polygonfaces.obj");
    obj << "v -500 0 500\nv 500 0 500\nv 500 0 -500\nv -500 0 -500\nv 0 500 -500\nf 1// 2// 3// 4// 5//\n";
  }
  const SurfaceMesh loaded = squeeze::meshing::load_surface(dir / "polygonfaces.obj");
  fs::remove_all(dir);
  ASSERT_EQ(loaded.F.rows(), 3);

  // The same polygon fanned from its first corner: a bend sharp enough that its winding numbers
  // call it a scan (sheet-like over 74 % of its area), whose slab on equal triangles left 22 of
  // its 644 faces over slivers: more than the hundredth version 31 mended (its solid then, 15 %
  // out). Since version 32, smoothed and split: one face's sliver left, dropped.
  SurfaceMesh fan;
  fan.V.resize(5, 3);
  fan.V << -500, 0, 500, 500, 0, 500, 500, 0, -500, -500, 0, -500, 0, 500, -500;
  fan.F.resize(3, 3);
  fan.F << 0, 1, 2, 0, 2, 3, 0, 3, 4;
  for (const int target : {150, 1000})
    for (const SurfaceMesh* s : {&loaded, static_cast<const SurfaceMesh*>(&fan)}) {
      SCOPED_TRACE(std::to_string(target) + (s == &fan ? ", fanned" : ", as loaded"));
      const double diag = (s->V.colwise().maxCoeff() - s->V.colwise().minCoeff()).norm();
      const MeshResult r = mesh(*s, target);
      EXPECT_EQ(r.sheets, 1);
      EXPECT_GE(r.quality.min_dihedral, 5.0);
      EXPECT_LE(r.deviation_out, 0.01 * diag);
      EXPECT_LE(r.deviation_in, 0.0045 * diag);
      EXPECT_EQ(r.quality.components, 1);
      EXPECT_TRUE(r.tet_stats.conforming);
    }
}

TEST(MeshingV4, InputFarFromTheOriginIsMeshedAsAtTheOrigin) {
  const SurfaceMesh bunny = sqt::read_off(sqt::data("bunny00.off"));
  SurfaceMesh far = bunny;
  const Eigen::RowVector3d shift(1e5, -2e5, 3e5);
  far.V.rowwise() += shift;
  const MeshResult a = mesh(bunny, 300), b = mesh(far, 300);
  ASSERT_GT(a.tets.T.rows(), 0);
  EXPECT_EQ(b.tets.T.rows(), a.tets.T.rows());
  EXPECT_EQ(b.tets.V.rows(), a.tets.V.rows());
  const double diag = bounding_box_diagonal(bunny.V);
  // (The same mesh up to rounding: moved to the bounding box's centre, not by `shift`, the
  // refinement's points can fall elsewhere, so the figures are compared, not the vertices.)
  EXPECT_NEAR(b.quality.volume, a.quality.volume, 1e-3 * a.quality.volume);
  EXPECT_NEAR(b.deviation_out, a.deviation_out, 1e-3 * diag);
  EXPECT_NEAR(b.deviation_in, a.deviation_in, 1e-3 * diag);
  EXPECT_GE(b.quality.min_dihedral, 5.0);
  const Eigen::RowVector3d lo = far.V.colwise().minCoeff(), hi = far.V.colwise().maxCoeff();
  EXPECT_LT((b.tets.V.colwise().minCoeff() - lo).cwiseAbs().maxCoeff(), 0.02 * diag);
  EXPECT_LT((b.tets.V.colwise().maxCoeff() - hi).cwiseAbs().maxCoeff(), 0.02 * diag);
  EXPECT_NEAR(b.input.V(0, 0), far.V(0, 0), 1e-9);
  ASSERT_FALSE(b.decomposition.shells.empty());
  for (const auto& shell : b.decomposition.shells)
    for (Eigen::Index v = 0; v < shell.hull.V.rows(); ++v) EXPECT_LE(shell.hull.signed_value(shell.hull.V.row(v)), 1e-6 * diag);
}

// A scan meshed as one slab within every bound, conforming, graded (under 30,000 tetrahedra).
void expect_graded_slab_within_bounds(const MeshResult& r, double diag) {
  EXPECT_EQ(r.sheets, 1) << r.fallback_because;
  EXPECT_LE(r.deviation_out, 0.01 * diag);
  EXPECT_LE(r.deviation_in, 0.0045 * diag);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_EQ(r.quality.components, 1);
  EXPECT_FALSE(r.target_exceeded_because.empty());  // a slab 1 % thick: thousands of prisms, and says so
  EXPECT_LT(r.quality.tets, 30000);                  // graded (the bunny's equal-triangle slab: 127,653)
}

// A scan of a solid with holes wider than the outer bound: the bunny of tests/data with four holes
// of 2 % of the diagonal in radius. As a solid (its winding-number solid's boundary) the caps over
// them lie 1.8 % of the diagonal off the scan, and no solid can do better: a surface spanning a
// hole's rim within the bound of the scan has to run along the whole scan. Since meshing version
// 15 it is a slab (its sheet remeshed where it curves, graded by simplify_sheet where it does not,
// one layer of prisms) within every bound. Before, its caps stayed (under three times the bound),
// and its slab alone, remeshed to equal triangles, took 127,653 tetrahedra of 2.6 degrees. Since
// version 16 the holes' caps are estimated from their outlines (hole_caps.h) and the slab is made
// first: no winding-number solid is made at all (bench_mesh BM_ScanWithHoles: 1.37 times faster).
TEST(MeshingV4, ScanWithHolesWiderThanTheBoundIsAGradedSlabWithinTheBounds) {
  const SurfaceMesh bunny = sqt::read_off(sqt::data("bunny00.off"));
  const double diag = bounding_box_diagonal(bunny.V);
  const SurfaceMesh scan = sqs::with_holes(bunny, 0.02);
  ASSERT_LT(scan.F.rows(), bunny.F.rows() - 100);
  const MeshResult r = mesh(scan, 300);
  EXPECT_NE(r.fallback_because.find("holes are wider than the deviation bound"), std::string::npos) << r.fallback_because;
  expect_graded_slab_within_bounds(r, diag);
  for (const auto& [stage, seconds] : r.seconds) EXPECT_NE(stage, "winding-number surface") << "the solid was made first";
}

// A scan with a hole wider than the bound and no slab (a fin on one edge: not a 2-manifold, as a
// zipper scan's flaps or an organ's welded segments are): its winding-number solid's cap lies far
// off (14 % of the diagonal), and the report says why and names --wrap, whose shell goes into the
// hole (twenty-fifth session; the wrap itself, 55 s on this sphere, is not run here). Since
// meshing version 36 the solid is made again hollowed where the outside reaches in through the
// hole: a shell around the hole's rim, within the bounds (0.76 % of the diagonal out).
TEST(MeshingV4, SolidsOfScansWithWideHolesAndNoSlabAreHollowedNotCapped) {
  const SurfaceMesh sphere = sqt::read_off(sqt::data("sphere.off"));
  const Eigen::RowVector3d centre = sphere.V.colwise().mean();
  const double R = (sphere.V.rowwise() - centre).rowwise().norm().mean();
  const Eigen::RowVector3d top = centre + Eigen::RowVector3d(0, 0, R);
  SurfaceMesh scan;
  scan.V.resize(sphere.V.rows() + 1, 3);
  scan.V.topRows(sphere.V.rows()) = sphere.V;
  std::vector<Eigen::RowVector3i> kept;
  for (Eigen::Index f = 0; f < sphere.F.rows(); ++f) {
    const Eigen::RowVector3d c = (sphere.V.row(sphere.F(f, 0)) + sphere.V.row(sphere.F(f, 1)) + sphere.V.row(sphere.F(f, 2))) / 3.0;
    if ((c - top).norm() > 0.6 * R) kept.push_back(sphere.F.row(f));  // a hole 0.6 R wide about the top
  }
  // The fin: a triangle on the kept edge nearest the equator, standing out a tenth of R.
  int a = -1, b = -1;
  double nearest = INFINITY;
  for (const Eigen::RowVector3i& f : kept)
    for (int k = 0; k < 3; ++k) {
      const double z = std::abs(0.5 * (sphere.V(f(k), 2) + sphere.V(f((k + 1) % 3), 2)) - centre(2));
      if (z < nearest) nearest = z, a = f(k), b = f((k + 1) % 3);
    }
  const Eigen::RowVector3d mid = 0.5 * (sphere.V.row(a) + sphere.V.row(b));
  scan.V.row(sphere.V.rows()) = mid + 0.1 * R * (mid - centre).normalized();
  kept.emplace_back(a, b, static_cast<int>(sphere.V.rows()));
  scan.F.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t f = 0; f < kept.size(); ++f) scan.F.row(static_cast<Eigen::Index>(f)) = kept[f];
  const double diag = bounding_box_diagonal(scan.V);
  MeshOptions capped;
  capped.tetrahedralize.target_tets = 300;
  capped.hollow_where_caps_lie_far = false;  // (version 35)
  const MeshResult c = squeeze::meshing::mesh_surface(scan, capped);
  EXPECT_EQ(c.method, "winding_number_boundary");
  EXPECT_EQ(c.winding_stats.hollow_depth, 0.0);
  EXPECT_GT(c.deviation_out, 0.05 * diag) << "the cap over the hole";
  EXPECT_NE(c.deviation_exceeded_because.find("closes its holes"), std::string::npos) << c.deviation_exceeded_because;
  EXPECT_NE(c.deviation_exceeded_because.find("--wrap"), std::string::npos) << c.deviation_exceeded_because;

  const MeshResult r = mesh(scan, 300);
  EXPECT_EQ(r.method, "winding_number_boundary");
  EXPECT_GT(r.winding_stats.hollow_depth, 0.0);
  EXPECT_NE(r.fallback_because.find("hollowed where the outside reaches in"), std::string::npos) << r.fallback_because;
  EXPECT_LE(r.deviation_out, 0.01 * diag) << "a shell around the hole's rim, no cap";
  EXPECT_LE(r.deviation_in, 0.0045 * diag);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_EQ(r.quality.components, 1);
  EXPECT_EQ(r.deviation_exceeded_because, "");
  // Hollow: well under the sphere's volume (the shell is about 1 % of the diagonal thick).
  EXPECT_LT(tet_volume(r.tets), 0.5 * tet_volume(c.tets));
  // Since version 38 (hollow_first) the hollowed solid is made first, by the hole's outline, and
  // kept: one winding-number surface in the report's seconds. With hollow_first off, the capped
  // solid first and then the same hollowed mesh: both stages.
  auto surfaces = [](const MeshResult& m) {
    int n = 0;
    for (const auto& [stage, seconds] : m.seconds) n += stage == "winding-number surface";
    return n;
  };
  EXPECT_EQ(surfaces(r), 1);
  EXPECT_NE(r.fallback_because.find("would lie about"), std::string::npos) << r.fallback_because;
  MeshOptions capped_first;
  capped_first.tetrahedralize.target_tets = 300;
  capped_first.hollow_first = false;
  const MeshResult f = squeeze::meshing::mesh_surface(scan, capped_first);
  EXPECT_EQ(surfaces(f), 2);
  EXPECT_NE(f.fallback_because.find("the caps over them lay"), std::string::npos) << f.fallback_because;
  EXPECT_EQ(f.tets.T, r.tets.T);
  EXPECT_EQ(f.tets.V, r.tets.V);
}

// The elephant of tests/data with four holes of 3 % of the diagonal: as a solid, its caps lie 2.3 %
// of the diagonal off (1,609 tetrahedra). Its slab (version 15) left slivers where the scan folds
// sharply: prisms there invert, their offsets were halved to a thirty-second, and splitting the
// faces around them did not converge (on the elephant with holes of 2 %: 2 faces left after three
// rounds; its equal-triangle slab, 53,266 tetrahedra of 0.00007°), so the solid stayed. Since
// version 16 the sheet is smoothed around such faces first (smooth_sheet_faces, no vertex moved
// over a fifth of the slab's half thickness) and the graded slab holds every bound.
TEST(MeshingV4, ElephantWithHolesIsASlabWithoutSlivers) {
  const SurfaceMesh elephant = sqt::read_off(sqt::data("elephant.off"));
  const double diag = bounding_box_diagonal(elephant.V);
  const SurfaceMesh scan = sqs::with_holes(elephant, 0.03);
  ASSERT_LT(scan.F.rows(), elephant.F.rows() - 20);
  expect_graded_slab_within_bounds(mesh(scan, 300), diag);
}

// A curtain with folds: a 1 m by 0.6 m slab 2 cm thick, waved 5 cm (three waves), 4,096 faces. At
// 150 its boundary simplified to 280 faces pinched it (not conforming, 1.2 % of the diagonal in):
// recovery gave up at 1.5 splits a point. Version 14 took a third retry, simplified toward four
// times the faces (1,124: 0.40 % in, 5.8 degrees). Since version 19 recovery goes on while it
// makes progress (up to four splits a point) and the 280 faces are recovered: conforming, within
// the bounds, no retry.
TEST(MeshingV4, WavySlabComesWithinTheBoundsAtASmallTarget) {
  const int nu = 40, nv = 24;
  auto z = [](double u) { return 0.05 * std::sin(6 * M_PI * u); };
  SurfaceMesh s;
  const int n = (nu + 1) * (nv + 1);
  s.V.resize(2 * n, 3);
  for (int side = 0; side < 2; ++side)
    for (int j = 0; j <= nv; ++j)
      for (int i = 0; i <= nu; ++i) {
        const double u = double(i) / nu, v = 0.6 * j / nv;
        s.V.row(side * n + j * (nu + 1) + i) << u, v, z(u) + (side == 0 ? 0.01 : -0.01);
      }
  std::vector<Eigen::Vector3i> F;
  auto idx = [&](int i, int j) { return j * (nu + 1) + i; };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int a = idx(i, j), b = a + 1, c = idx(i, j + 1), d = c + 1;
      F.emplace_back(a, b, d), F.emplace_back(a, d, c);                  // top, up
      F.emplace_back(a + n, d + n, b + n), F.emplace_back(a + n, c + n, d + n);  // bottom, down
    }
  std::vector<int> ring;
  for (int i = 0; i < nu; ++i) ring.push_back(idx(i, 0));
  for (int j = 0; j < nv; ++j) ring.push_back(idx(nu, j));
  for (int i = nu; i > 0; --i) ring.push_back(idx(i, nv));
  for (int j = nv; j > 0; --j) ring.push_back(idx(0, j));
  for (size_t k = 0; k < ring.size(); ++k) {
    const int a = ring[k], b = ring[(k + 1) % ring.size()];
    F.emplace_back(b, a, a + n), F.emplace_back(b, a + n, b + n);
  }
  s.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t f = 0; f < F.size(); ++f) s.F.row(static_cast<Eigen::Index>(f)) = F[f].transpose();
  ASSERT_GT(signed_volume(s), 0.0);
  const double diag = (s.V.colwise().maxCoeff() - s.V.colwise().minCoeff()).norm();
  const MeshResult r = mesh(s, 150);
  EXPECT_EQ(r.method, "boundary") << r.fallback_because;
  EXPECT_EQ(r.boundary_retries, 0);
  EXPECT_TRUE(r.tet_stats.conforming);
  expect_within(r, diag, 0.05, 0.015, 0.005, 1);
}

// drop_debris_components: a tetrahedron hanging on a mesh by one vertex is its own face-connected
// component and goes when its volume share is below the bound; two solids of similar size stay.
TEST(MeshingV4, DebrisComponentsAreDroppedAndSolidsKept) {
  squeeze::meshing::TetMesh m;
  m.V.resize(8, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,  // a unit corner tetrahedron (volume 1/6)
      1, 1, 1, 1.1, 1, 1, 1, 1.1, 1, 1, 1, 1.1;  // a small one (volume 1/6000) sharing no vertex
  m.T.resize(3, 4);
  m.T << 0, 1, 2, 3,  //
      4, 5, 6, 7,     //
      1, 5, 6, 7;     // joined to the first by vertex 1 and to the second by a face
  // Components: {0}, {1, 2}; the second's volume is 1/6000 + that of tet 2.
  Eigen::VectorXi C;
  ASSERT_EQ(squeeze::meshing::tet_components(m, C), 2);
  squeeze::meshing::TetMesh a = m;
  EXPECT_EQ(squeeze::meshing::drop_debris_components(a, 1e-6), 0) << "both above a tiny bound";
  EXPECT_EQ(a.T.rows(), 3);
  // Without tet 2 the small tetrahedron hangs by nothing: 0.1 % of the volume.
  squeeze::meshing::TetMesh b;
  b.V = m.V;
  b.T = m.T.topRows(2);
  b.label = Eigen::VectorXi::LinSpaced(2, 7, 8);
  EXPECT_EQ(squeeze::meshing::drop_debris_components(b, 0.005), 1);
  ASSERT_EQ(b.T.rows(), 1);
  EXPECT_EQ(b.T.row(0), Eigen::RowVector4i(0, 1, 2, 3));
  EXPECT_EQ(b.label.size(), 1);
  EXPECT_EQ(b.label(0), 7);
  // A bound above every component removes nothing (never the whole mesh).
  squeeze::meshing::TetMesh c = m;
  EXPECT_EQ(squeeze::meshing::drop_debris_components(c, 0.99), 0);
}

// A many-part model as an OBJ export has them: an ellipsoid body, a head and eight legs, each leg
// a cylinder of 10 segments pushed into the body (the parts intersect each other, each is
// closed), written with six decimals as a script wrote it. One mesh per part: the legs whose
// boundary was not recovered had left single tetrahedra hanging on by a vertex (45 components
// for 10 parts at 300).
TEST(MeshingV4, ManyPartModelWithLegsThroughItsBodyGivesOnePiecePerPart) {
  std::vector<std::pair<std::vector<Vec3>, std::vector<std::array<int, 3>>>> parts;
  auto uv_sphere = [&](const Vec3& c, const Vec3& scale) {  // 16 around, 10 rings, poles on z
    const int nu = 16, nv = 10;
    std::vector<Vec3> V{Vec3(0, 0, 1)};
    for (int k = 1; k < nv; ++k)
      for (int j = 0; j < nu; ++j) {
        const double th = M_PI * k / nv, a = 2 * M_PI * j / nu;
        V.emplace_back(std::sin(th) * std::cos(a), std::sin(th) * std::sin(a), std::cos(th));
      }
    V.emplace_back(0, 0, -1);
    const int n = static_cast<int>(V.size());
    auto idx = [&](int k, int j) { return 1 + (k - 1) * nu + j % nu; };
    std::vector<std::array<int, 3>> F;
    for (int j = 0; j < nu; ++j) F.push_back({0, idx(1, j), idx(1, j + 1)});
    for (int k = 1; k < nv - 1; ++k)
      for (int j = 0; j < nu; ++j) {
        const int a = idx(k, j), b = idx(k + 1, j), cc = idx(k + 1, j + 1), d = idx(k, j + 1);
        F.push_back({a, b, cc}), F.push_back({a, cc, d});
      }
    for (int j = 0; j < nu; ++j) F.push_back({n - 1, idx(nv - 1, j + 1), idx(nv - 1, j)});
    for (Vec3& v : V) v = c + v.cwiseProduct(scale);
    parts.emplace_back(V, F);
  };
  uv_sphere(Vec3::Zero(), Vec3(0.12, 0.08, 0.1));
  uv_sphere(Vec3(0.15, 0, 0), Vec3(0.06, 0.05, 0.05));
  for (int i = 0; i < 8; ++i) {
    const double side = i < 4 ? 1 : -1, k = i % 4, x = -0.06 + 0.045 * k;
    const SurfaceMesh leg =
        cylinder(Vec3(x, 0, side * 0.05), Vec3(x + 0.08 * (k - 1.5) / 1.5, -0.12, side * 0.25), 0.012, 10);
    std::vector<Vec3> V;
    std::vector<std::array<int, 3>> F;
    for (Eigen::Index v = 0; v < leg.V.rows(); ++v) V.push_back(leg.V.row(v).transpose());
    for (Eigen::Index f = 0; f < leg.F.rows(); ++f) F.push_back({leg.F(f, 0), leg.F(f, 1), leg.F(f, 2)});
    parts.emplace_back(V, F);
  }
  const sqt::TempDir dir("spider");
  const fs::path obj = dir.path() / "spider.obj";
  {
    std::ofstream out(obj);
    int offset = 1;
    char line[128];
    for (size_t p = 0; p < parts.size(); ++p) {
      out << "o part" << p << "\n";
      for (const Vec3& v : parts[p].first) {
        std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", v.x(), v.y(), v.z());
        out << line;
      }
      for (const auto& f : parts[p].second) out << "f " << f[0] + offset << " " << f[1] + offset << " " << f[2] + offset << "\n";
      offset += static_cast<int>(parts[p].first.size());
    }
  }
  const MeshResult r = mesh(squeeze::meshing::load_surface(obj), 300);
  EXPECT_EQ(r.quality.components, 10);
  ASSERT_TRUE(r.volume_ratio.has_value());
  EXPECT_NEAR(*r.volume_ratio, 1.0, 0.01);
  // Every leg conforming, and no tetrahedron below the floor: the file's six decimals put each
  // flat cap a little off its plane, and the legs' caps must still be meshed as flat patches (four
  // legs were not conforming, 4.1°, before; tetrahedralize.cpp, build_surface).
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_LE(r.deviation_out, 0.015 * bounding_box_diagonal(r.input.V));
  EXPECT_LE(r.deviation_in, 0.005 * bounding_box_diagonal(r.input.V));
}

// Cones: a sharp tip between thin triangles (a fan from the apex). The recovery of their boundary
// splits the thin triangles ten times over; of 90 generated cones (24 to 96 sides, 10 to 40 cm
// tall, corners in 9 digits or full precision, at 150, 300 and 1000) 52 failed a criterion, some
// not conforming with 8 % of the diagonal out, some with no tetrahedron at all (the flips of a flat
// patch brought a split edge back with its old midpoint on it, and splitting it again put a second
// vertex at exactly that point). Now a part whose boundary does not hold after its retries is meshed
// as its winding-number solid (mesh_pipeline.cpp), a point already in the triangulation is not
// added twice (tetrahedralize.cpp, add_point), and a few cones here come out one conforming piece of
// their own shape within the issue's bounds.
SurfaceMesh cone(int n, bool few_digits, double height = 0.2) {
  std::vector<Vec3> V;
  std::vector<std::array<int, 3>> F;
  auto digits = [&](double x) { return few_digits ? nine_digits(x) : x; };
  for (int j = 0; j < n; ++j)
    V.emplace_back(digits(0.05 * std::cos(2 * M_PI * j / n)), digits(0.05 * std::sin(2 * M_PI * j / n)), 0);
  V.emplace_back(0, 0, height);  // apex n
  V.emplace_back(0, 0, 0);       // centre of the base n + 1
  for (int j = 0; j < n; ++j) {
    F.push_back({j, (j + 1) % n, n});
    F.push_back({n + 1, (j + 1) % n, j});
  }
  return surface_of(V, F);
}

TEST(MeshingV4, SharpConesComeOutWholeAndConforming) {
  struct Case {
    int n;
    bool nine_digits;
    double height;
    int target;
  };
  // Each of these failed before (not conforming, or below 5°, or 2-15 % of the diagonal out).
  // (The cone of 64 sides in nine digits, 0.4 m tall, at 300, is SharpConeDoesNotCrashTheExuder's.)
  for (const Case& k : {Case{64, true, 0.2, 150}, Case{32, true, 0.2, 300}, Case{96, false, 0.4, 150}}) {
    SCOPED_TRACE(std::to_string(k.n) + " sides, " + (k.nine_digits ? "9 digits, " : "full precision, ") +
                 std::to_string(k.height) + " m tall, at " + std::to_string(k.target));
    const SurfaceMesh c = cone(k.n, k.nine_digits, k.height);
    const MeshResult r = mesh(c, k.target);
    EXPECT_EQ(r.method, "boundary");
    EXPECT_TRUE(r.tet_stats.conforming);
    expect_within(r, bounding_box_diagonal(c.V), 0.2, 0.015, 0.005, 1);
    std::printf("cone of %d sides at %d: %d tetrahedra, %.2f degrees, volume ratio %.3f, %d by winding number\n", k.n,
                k.target, r.quality.tets, r.quality.min_dihedral, *r.volume_ratio, r.parts_by_winding_number);
  }
}

// The cone of 64 sides at full precision, at 300: CGAL's sliver exuder met a numerically flat
// cell beside a sliver, took a NaN weight, and the process died of SIGFPE (exit 136). It now stops
// there (its earlier pumps kept) and the meshing goes on. (Since meshing version 23 runs that are
// not conforming are not exuded, and that cone's NaN was in one: the cone of 64 sides in nine
// digits, 0.4 m tall, the only one of 72 cones tried that reaches it, met it in a conforming run.
// Since version 40 conformity recovery flips only across convex quads, and that cone's mesh no
// longer reaches it either, nor do 144 cones tried (32-128 sides, 0.2-0.5 m tall, 150-1,000
// tetrahedra); MeshingSigfpeTrap.GmpsSigfpeOnANanIsSurvived raises GMP's SIGFPE itself.)
TEST(MeshingV4, SharpConeDoesNotCrashTheExuder) {
  const MeshResult r = mesh(cone(64, true, 0.4), 300);
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_GT(r.quality.tets, 0);
  ASSERT_TRUE(r.volume_ratio.has_value());
  EXPECT_NEAR(*r.volume_ratio, 1.0, 0.2);
}

// A hollow ball given as its outer shell and its inner shell facing into the hollow (as CAD
// exports a hollow part): one solid, the space between, with the hollow left empty. Before, the
// inner shell became a full ball of its own inside the outer one. Two nested balls both facing
// out stay two overlapping solids, as before (the file says so).
TEST(MeshingV4, InwardInnerShellIsACavity) {
  const SurfaceMesh outer = sphere(Vec3::Zero(), 0.1, 2);
  SurfaceMesh inner = sphere(Vec3::Zero(), 0.08, 2);
  const double shell = std::abs(signed_volume(outer)) - std::abs(signed_volume(inner));
  const SurfaceMesh hollow = with_cavity(outer, inner);
  for (int target : {300, 1000}) {
    SCOPED_TRACE(target);
    const MeshResult r = mesh(hollow, target);
    EXPECT_EQ(r.method, "boundary");
    EXPECT_EQ(r.cavities, 1);
    EXPECT_EQ(r.parts, 1);
    EXPECT_EQ(r.quality.components, 1);
    EXPECT_NEAR(r.quality.volume, shell, 0.02 * shell);
    EXPECT_GE(r.quality.min_dihedral, 5.0);
    for (Eigen::Index t = 0; t < r.tets.T.rows(); ++t) {  // nothing in the hollow
      Vec3 c = Vec3::Zero();
      for (int k = 0; k < 4; ++k) c += r.tets.V.row(r.tets.T(t, k)).transpose() / 4.0;
      ASSERT_GT(c.norm(), 0.075) << "tetrahedron " << t << " lies in the hollow";
    }
  }
  const MeshResult two = mesh(join({outer, inner}), 300);
  EXPECT_EQ(two.cavities, 0);
  EXPECT_EQ(two.parts, 2);
}

}  // namespace

// Version 35: a fin (three triangles on one edge) encloses no volume, so its winding-number solid
// is its dilation alone, and the seeds at its five vertices give Mesh_3 no facet to start from;
// seeded along its faces as well (seed_faces_if_no_facet), that solid is found: closed, outward.
TEST(Envelope, FinSolidIsFoundWhenSeededAlongItsFaces) {
  SurfaceMesh fin;
  fin.V.resize(5, 3);
  fin.V << 0, 0, 0, 0, 0, 0.4, 0.3, 0, 0.2, -0.3, 0, 0.2, 0, 0.3, 0.2;
  fin.F.resize(3, 3);
  fin.F << 0, 1, 2, 0, 1, 3, 0, 1, 4;
  squeeze::meshing::WindingTetrahedralizeOptions wo;
  wo.facet_distance = 0.004;
  wo.dilation = 0.003;
  EXPECT_EQ(squeeze::meshing::winding_number_surface(fin.V, fin.F, wo).F.rows(), 0);
  wo.seed_faces_if_no_facet = true;
  const SurfaceMesh solid = squeeze::meshing::winding_number_surface(fin.V, fin.F, wo);
  ASSERT_GT(solid.F.rows(), 0);
  EXPECT_TRUE(squeeze::meshing::is_closed(solid.F));
  EXPECT_TRUE(squeeze::meshing::is_oriented_two_manifold(solid.F, static_cast<int>(solid.V.rows())));
  EXPECT_GT(squeeze::meshing::analyse_surface(solid).volume, 0.0);
}

// Version 40: tetrahedralize_winding_number sizes its cells by the volume's magnitude. A negative
// winding volume (an open scan whose holes' cones were taken from far away: the spinal cord with
// holes, -1.08e-6 m³) was floored at 1e-12 diag³: cells of 17 µm, 30 s an attempt, no tetrahedron.
TEST(Envelope, NegativeWindingVolumeSizesCellsByItsMagnitude) {
  const SurfaceMesh b = box(Vec3(0, 0, 0), Vec3(1, 0.7, 0.4), {2, 2, 2});
  squeeze::meshing::WindingTetrahedralizeOptions wo;
  wo.target_tets = 300;
  wo.facet_distance = 0.004;
  wo.dilation = 0.003;
  squeeze::meshing::WindingTetrahedralizeStats plus, minus;
  const squeeze::meshing::TetMesh a = squeeze::meshing::tetrahedralize_winding_number(b.V, b.F, 0.28, wo, &plus);
  const squeeze::meshing::TetMesh c = squeeze::meshing::tetrahedralize_winding_number(b.V, b.F, -0.28, wo, &minus);
  ASSERT_GT(a.T.rows(), 0);
  EXPECT_GT(plus.cell_size, 0.01);
  EXPECT_EQ(minus.cell_size, plus.cell_size);
  EXPECT_EQ(c.T.rows(), a.T.rows());
}

// Version 36's hollowing options out of range are refused with InputError, before any meshing.
TEST(Envelope, HollowOptionsOutOfRangeAreRefused) {
  const SurfaceMesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  squeeze::meshing::WindingTetrahedralizeOptions wo;
  wo.hollow_cell = 1.5;
  EXPECT_THROW(squeeze::meshing::winding_number_surface(cube.V, cube.F, wo), squeeze::InputError);
  wo.hollow_cell = 0.01;
  wo.hollow_depth = -0.1;
  EXPECT_THROW(squeeze::meshing::winding_number_surface(cube.V, cube.F, wo), squeeze::InputError);
  wo.hollow_depth = std::nan("");
  EXPECT_THROW(squeeze::meshing::winding_number_surface(cube.V, cube.F, wo), squeeze::InputError);
}

// The inside test's memo (version 40's option) outside 2^12..2^30 slots is refused; at its
// smallest the surface is the same as at the default (the memo only answers repeats).
TEST(Envelope, LabelMemoSizeOutOfRangeIsRefusedAndChangesNothing) {
  const SurfaceMesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  squeeze::meshing::WindingTetrahedralizeOptions wo;
  wo.facet_distance = 0.004;
  wo.dilation = 0.003;
  for (const int bad : {11, 31, -1}) {
    wo.label_memo_log2_slots = bad;
    EXPECT_THROW(squeeze::meshing::winding_number_surface(cube.V, cube.F, wo), squeeze::InputError) << bad;
  }
  wo.label_memo_log2_slots = 23;
  const SurfaceMesh a = squeeze::meshing::winding_number_surface(cube.V, cube.F, wo);
  wo.label_memo_log2_slots = 12;
  const SurfaceMesh b = squeeze::meshing::winding_number_surface(cube.V, cube.F, wo);
  ASSERT_GT(a.F.rows(), 0);
  EXPECT_EQ(b.F, a.F);
  EXPECT_EQ(b.V, a.V);
}

// Options that are fractions in (0, 1] are refused with InputError out of it, before any meshing:
// MeshOptions::first_try_inner_deviation (meshing versions 37-38) and solid_min_scale (version
// 57). At 1 each is allowed.
TEST(Envelope, UnitIntervalOptionsOutOfRangeAreRefused) {
  const SurfaceMesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const std::pair<const char*, double MeshOptions::*> options[] = {
      {"first_try_inner_deviation", &MeshOptions::first_try_inner_deviation},
      {"solid_min_scale", &MeshOptions::solid_min_scale}};
  for (const auto& [name, field] : options) {
    for (const double value : {0.0, -0.5, 1.5, std::nan("")}) {
      MeshOptions o;
      o.*field = value;
      EXPECT_THROW(squeeze::meshing::mesh_surface(cube, o), squeeze::InputError) << name << " = " << value;
    }
    MeshOptions o;
    o.*field = 1.0;
    EXPECT_GT(squeeze::meshing::mesh_surface(cube, o).tets.T.rows(), 0) << name;
  }
}

// deviation_exceeded_because names each bound a result misses by over 1.5 times (deviation_in
// since meshing version 37: the heart with holes was 1.23 % of the diagonal in, unexplained), and
// is empty within them.
TEST(Envelope, DeviationsOverTheBoundsAreExplainedEach) {
  const MeshOptions o;  // max_deviation 0.01, inner_deviation 0.45
  MeshResult r;
  r.input = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const double diag = std::sqrt(3.0);
  r.method = "winding_number_boundary";
  r.deviation_out = 0.0149 * diag;
  r.deviation_in = 0.0067 * diag;
  EXPECT_EQ(squeeze::meshing::deviation_exceeded_because(r, o), "");
  r.deviation_in = 0.0068 * diag;  // over 1.5 × 0.45 %
  const std::string in = squeeze::meshing::deviation_exceeded_because(r, o);
  EXPECT_NE(in.find("outside the mesh"), std::string::npos) << in;
  EXPECT_NE(in.find("winding number stays under 1/2"), std::string::npos) << in;
  EXPECT_EQ(in.find("off the input"), std::string::npos) << in;
  r.deviation_out = 0.0151 * diag;
  const std::string both = squeeze::meshing::deviation_exceeded_because(r, o);
  EXPECT_NE(both.find("off the input"), std::string::npos) << both;
  EXPECT_NE(both.find("; input surface points lie up to"), std::string::npos) << both;
  r.deviation_in = 0;
  r.method = "convex_shells";
  const std::string out = squeeze::meshing::deviation_exceeded_because(r, o);
  EXPECT_NE(out.find("convex shells"), std::string::npos) << out;
  EXPECT_EQ(out.find("outside the mesh"), std::string::npos) << out;
}

// Meshing version 56: tetrahedralize_winding_number seeds the input's points its mesh leaves
// outside by more than the cover tolerance and refines again, as winding_number_surface does: a
// CAD part's solid at 150 tetrahedra (trimesh's featuretype.STL) lay 0.84 % of the diagonal in
// where its facets cut off corners and crests, 0.28 % with the seeds. Here three welded boxes,
// their facets as coarse as 150 tetrahedra make them: without the pass the boxes' corners lie
// farther out than the tolerance, with it within it.
TEST(Envelope, WindingSolidSeedsTheCornersItsFacetsCutOff) {
  const Vec3 a0(0, 0, 0), a1(0.2, 0.12, 0.1), b0(0.2, 0, 0), b1(0.35, 0.12, 0.1), c0(0.05, 0.12, 0), c1(0.2, 0.2, 0.1);
  const SurfaceMesh soup = join({box(a0, a1, {3, 3, 3}), box(b0, b1, {3, 3, 3}), box(c0, c1, {3, 3, 3})});
  const double diag = sqt::diagonal(soup.V);
  const double volume = box_volume(a0, a1) + box_volume(b0, b1) + box_volume(c0, c1);
  squeeze::meshing::WindingTetrahedralizeOptions wo;
  wo.target_tets = 150;
  wo.facet_distance = 0.004;
  wo.dilation = 0.0045;
  // The largest distance of the soup's points outside the mesh from its boundary (points 0.1 % of
  // the diagonal apart), as a fraction of the diagonal.
  auto in = [&](const squeeze::meshing::TetMesh& m) {
    const squeeze::meshing::TetLocator locator(m);
    const squeeze::meshing::TriangleBvh boundary(m.V, squeeze::meshing::boundary_faces(m.T));
    double worst = 0;
    for (const Vec3& x : squeeze::meshing::surface_samples(soup.V, soup.F, 0.001 * diag))
      if (locator.locate(x.transpose()) < 0) worst = std::max(worst, boundary.nearest(x));
    return worst / diag;
  };
  squeeze::meshing::WindingTetrahedralizeStats with, without;
  const squeeze::meshing::TetMesh covered = squeeze::meshing::tetrahedralize_winding_number(soup.V, soup.F, volume, wo, &with);
  wo.cover_solid = false;
  const squeeze::meshing::TetMesh plain = squeeze::meshing::tetrahedralize_winding_number(soup.V, soup.F, volume, wo, &without);
  ASSERT_GT(covered.T.rows(), 0);
  ASSERT_GT(plain.T.rows(), 0);
  const double in_covered = in(covered), in_plain = in(plain);
  std::printf("[ solid    ] in %.3f %% of the diagonal with the cover seeds (%d seeds), %.3f %% without (%d)\n",
              100 * in_covered, with.seeds, 100 * in_plain, without.seeds);
  EXPECT_GT(with.seeds, without.seeds);
  EXPECT_GT(in_plain, wo.cover_tolerance);
  EXPECT_LE(in_covered, wo.cover_tolerance + 0.0005);
  EXPECT_GT(squeeze::meshing::tet_quality(covered).volume, volume);  // dilated, never cut
}

// Meshing version 11: the boundary of a soup's winding-number solid (winding_number_surface) is a
// closed, outward, 2-manifold surface without self-intersections around the soup (three welded
// boxes: the corners and edges its facets cut off seeded and refined again), and
// simplify_envelope with the soup as its target keeps the bounds against the soup itself: every
// point of the simplified surface within max_outside of the soup's triangles, every point of the
// soup inside it or within max_inside.
TEST(Envelope, TargetSoupBoundsHoldAgainstTheSoup) {
  const Vec3 a0(0, 0, 0), a1(0.2, 0.12, 0.1), b0(0.2, 0, 0), b1(0.35, 0.12, 0.1), c0(0.05, 0.12, 0), c1(0.2, 0.2, 0.1);
  const fs::path dir = fs::temp_directory_path() / ("squeeze_soup_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  sqt::write_off(dir / "welded.off", join({box(a0, a1, {3, 3, 3}), box(b0, b1, {3, 3, 3}), box(c0, c1, {3, 3, 3})}));
  const SurfaceMesh soup = squeeze::meshing::load_surface(dir / "welded.off");
  fs::remove_all(dir);
  const double diag = sqt::diagonal(soup.V);
  squeeze::meshing::WindingTetrahedralizeOptions wo;
  wo.facet_distance = 0.004;
  wo.dilation = 0.0045;
  squeeze::meshing::WindingTetrahedralizeStats stats;
  const SurfaceMesh solid = squeeze::meshing::winding_number_surface(soup.V, soup.F, wo, &stats);
  ASSERT_GT(solid.F.rows(), 0);
  {  // Version 35's skip in the cover pass takes the same seeds, so the same surface.
    squeeze::meshing::WindingTetrahedralizeOptions each = wo;
    each.cover_skip = false;
    squeeze::meshing::WindingTetrahedralizeStats each_stats;
    const SurfaceMesh same = squeeze::meshing::winding_number_surface(soup.V, soup.F, each, &each_stats);
    EXPECT_GT(stats.attempts, 1) << "a cover pass seeded more";
    EXPECT_EQ(each_stats.seeds, stats.seeds);
    ASSERT_EQ(same.F.rows(), solid.F.rows());
    EXPECT_TRUE(same.F == solid.F && same.V == solid.V);
  }
  EXPECT_TRUE(squeeze::meshing::is_closed(solid.F));
  EXPECT_TRUE(squeeze::meshing::is_oriented_two_manifold(solid.F, static_cast<int>(solid.V.rows())));
  EXPECT_FALSE(squeeze::meshing::does_self_intersect(solid));
  const double union_volume = box_volume(a0, a1) + box_volume(b0, b1) + box_volume(c0, c1);
  EXPECT_GT(squeeze::meshing::analyse_surface(solid).volume, union_volume);  // outward, dilated
  EXPECT_LT(squeeze::meshing::analyse_surface(solid).volume, 1.2 * union_volume);

  // The largest distance of `b` from `target` (at points 0.1 % of the diagonal apart), and of
  // `target`'s points outside `b` from it, as fractions of the diagonal.
  auto worst = [&](const SurfaceMesh& b, const SurfaceMesh& target) {
    const squeeze::meshing::TriangleBvh to_target(target.V, target.F), to_b(b.V, b.F);
    const squeeze::meshing::FastWindingNumber inside_b(b.V, b.F);
    double out = 0, in = 0;
    for (const Vec3& x : squeeze::meshing::surface_samples(b.V, b.F, 0.001 * diag)) out = std::max(out, to_target.nearest(x));
    for (const Vec3& x : squeeze::meshing::surface_samples(target.V, target.F, 0.001 * diag))
      if (inside_b(x.transpose()) < 0.5) in = std::max(in, to_b.nearest(x));
    return std::pair<double, double>(out / diag, in / diag);
  };
  const auto [solid_out, solid_in] = worst(solid, soup);
  // The soup's sharp corners and edges are within the cover tolerance (0.3 %) of its solid's
  // surface (0.55 % outside before the cover seeds).
  EXPECT_LE(solid_in, wo.cover_tolerance + 0.0005);
  squeeze::meshing::EnvelopeOptions e;
  e.max_outside = 0.01 * diag;
  e.max_inside = 0.0045 * diag;
  e.min_triangle_angle = 25;
  e.min_fold_angle = 45;
  const SurfaceMesh b = squeeze::meshing::simplify_envelope(solid, soup, e);
  const auto [out, in] = worst(b, soup);
  std::printf("[ soup     ] solid %ld faces (out %.3f %%, in %.3f %%) -> %ld faces: out %.3f %%, in %.3f %% of the diagonal\n",
              static_cast<long>(solid.F.rows()), 100 * solid_out, 100 * solid_in, static_cast<long>(b.F.rows()), 100 * out,
              100 * in);
  EXPECT_LT(b.F.rows(), solid.F.rows() / 2);
  EXPECT_TRUE(squeeze::meshing::is_oriented_two_manifold(b.F, static_cast<int>(b.V.rows())));
  EXPECT_FALSE(squeeze::meshing::does_self_intersect(b));
  EXPECT_LE(out, 0.0125);  // max_outside, checked at a lattice of each new face: within a quarter more
  EXPECT_LE(in, 0.0050);
  EXPECT_THROW(squeeze::meshing::simplify_envelope(solid, SurfaceMesh{}, e), squeeze::InputError);
}

// The target, not the surface, is what the bounds hold against: a sphere simplified against a
// sphere 0.45 % of the diagonal inside it stays within max_outside of the inner one (against
// itself it goes farther out, as far as the bounds from itself allow).
TEST(Envelope, TargetIsWhatTheBoundsHoldAgainst) {
  const SurfaceMesh outer = sphere(Vec3(0, 0, 0), 0.1, 4);
  const double diag = sqt::diagonal(outer.V);
  SurfaceMesh inner = outer;
  inner.V *= 1.0 - 0.0045 * diag / 0.1;
  squeeze::meshing::EnvelopeOptions e;
  e.max_outside = 0.006 * diag;
  e.max_inside = 0.002 * diag;
  auto farthest = [&](const SurfaceMesh& b) {
    const squeeze::meshing::TriangleBvh to_inner(inner.V, inner.F);
    double d = 0;
    for (const Vec3& x : squeeze::meshing::surface_samples(b.V, b.F, 0.001 * diag)) d = std::max(d, to_inner.nearest(x));
    return d / diag;
  };
  const SurfaceMesh against_inner = squeeze::meshing::simplify_envelope(outer, inner, e);
  const SurfaceMesh against_itself = squeeze::meshing::simplify_envelope(outer, e);
  std::printf("[ sphere   ] %ld faces -> %ld against the inner sphere (%.3f %% from it), %ld against itself (%.3f %%)\n",
              static_cast<long>(outer.F.rows()), static_cast<long>(against_inner.F.rows()), 100 * farthest(against_inner),
              static_cast<long>(against_itself.F.rows()), 100 * farthest(against_itself));
  EXPECT_LT(against_inner.F.rows(), outer.F.rows() / 4);
  // (samples 0.1 % of the diagonal apart: the largest distance found to within a few hundredths of
  // a percent; 0.600 % and 0.662 % when written)
  EXPECT_LE(farthest(against_inner), 0.006 * 1.03);
  EXPECT_GT(farthest(against_itself), 0.006 * 1.03);
}

// Three triangles welded along one edge (a fan: no volume, and not open sheets either, as each is
// welded to the others) are an error naming what is wrong, at once: before meshing version 11
// the convex shells of the flat input grew a blob for minutes (Mesh_3's perturber at its limit).
TEST(MeshingV4, WeldedFanEnclosingNoVolumeIsAnErrorAtOnce) {
  SurfaceMesh fan;
  fan.V.resize(5, 3);
  fan.V << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0.2, 0.5, 0, 1;
  fan.F.resize(3, 3);
  fan.F << 0, 1, 2, 0, 1, 3, 0, 1, 4;
  try {
    mesh(fan, 300);
    FAIL() << "no error";
  } catch (const squeeze::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("encloses no volume"), std::string::npos) << e.what();
  }
}

// The sacrum's own surface at 150 tetrahedra: its boundary is not recovered before refinement
// (the mesh is classified by the winding number, one the pipeline's retries replace). Such a
// run's refinement stops past TetrahedralizeOptions::unrecovered_refine_work (trimesh's
// plate_holes.STL searched 27 million cells in such rounds, 18 s of a 35 s row), and it is not
// exuded (the exuder ran to its 30 s time limit on such runs: trimesh's round.stl at 150).
TEST(MeshingV4, ABoundaryNotRecoveredIsRefinedWithinItsBoundAndNotExuded) {
  const SurfaceMesh s = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/sacrum_coccyx.off");
  auto run = [&](double bound, bool exude, squeeze::meshing::TetrahedralizeStats& st) {
    return one_run(s, 150, [&](squeeze::meshing::TetrahedralizeOptions& o) { o.unrecovered_refine_work = bound, o.exude = exude; }, st);
  };
  squeeze::meshing::TetrahedralizeStats unbounded, bounded, bounded_not_exuded;
  const squeeze::meshing::TetMesh m0 = run(0, true, unbounded);
  ASSERT_FALSE(unbounded.recovered);
  EXPECT_FALSE(unbounded.conforming);
  const squeeze::meshing::TetMesh m1 = run(1e4, true, bounded);
  EXPECT_FALSE(bounded.recovered);
  EXPECT_LT(bounded.refine_work, 0.5 * unbounded.refine_work);  // (387,000 against 2.1 million when written)
  EXPECT_LT(m1.T.rows(), m0.T.rows());
  const squeeze::meshing::TetMesh m2 = run(1e4, false, bounded_not_exuded);
  EXPECT_TRUE(m1.V == m2.V && m1.T == m2.T) << "exuded";
}


// The sacrum's own surface at 150 again: its first recovery gives up once it would split more
// boundary edges than TetrahedralizeOptions::recovery_splits_per_face × its faces in a round that
// does not converge (no fewer splits than 0.9 of the fewest a round so far), and that run is not
// refined (squeeze mesh retries no such boundary but its remeshed surface; trimesh's
// ADIS16480.STL at 150 spent 29 s in one). Its default (4) is above what the sacrum needs: the
// same mesh as no bound.
TEST(MeshingV4, ARecoveryOverItsSplitBudgetIsAbandonedUnrefined) {
  const SurfaceMesh s = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/scenes/assets/sacrum_coccyx.off");
  auto run = [&](double per_face, squeeze::meshing::TetrahedralizeStats& st) {
    return one_run(s, 150, [&](squeeze::meshing::TetrahedralizeOptions& o) { o.recovery_splits_per_face = per_face; }, st);
  };
  squeeze::meshing::TetrahedralizeStats none, tight, by_default;
  const squeeze::meshing::TetMesh m0 = run(0, none);
  ASSERT_FALSE(none.recovered);
  EXPECT_FALSE(none.recovery_abandoned);
  EXPECT_GT(none.refine_work, 0.0);
  const squeeze::meshing::TetMesh m1 = run(0.1, tight);
  EXPECT_TRUE(tight.recovery_abandoned);
  EXPECT_FALSE(tight.conforming);
  EXPECT_EQ(tight.refine_work, 0.0);
  EXPECT_EQ(tight.steiner_points, 0);
  // (Past the budget only in rounds that still converge: 3,125 splits when written, against 5,418
  // with refinement's.)
  EXPECT_GT(tight.boundary_splits, static_cast<int>(0.1 * static_cast<double>(s.F.rows())));
  EXPECT_LT(tight.boundary_splits, none.boundary_splits);
  EXPECT_GT(m1.T.rows(), 0);
  EXPECT_LT(m1.T.rows(), m0.T.rows());
  const squeeze::meshing::TetMesh m2 = run(squeeze::meshing::TetrahedralizeOptions{}.recovery_splits_per_face, by_default);
  EXPECT_FALSE(by_default.recovery_abandoned);
  EXPECT_TRUE(m2.V == m0.V && m2.T == m0.T);
}

// A knife 1 m long and deep whose edge is 1.1° sharp (back 2 cm): a thin part whose mid-surface's
// prisms at the edge, as thin as the slab is allowed there, needed four rounds of splits before
// none held a tetrahedron under 5° (2 of 685 faces still did after three). With three rounds it
// went to the boundary route: 8 % of the diagonal in and 24 s at 150; a
// knife of 0.29° ran for minutes there. The thin-part route now takes up to six rounds.
TEST(MeshingV4, KnifeEdgeIsASlabWithinTheBounds) {
  const SurfaceMesh s = sqs::knife(1.0, 0.02, 1.0, 10);
  ASSERT_GT(signed_volume(s), 0.0);
  expect_one_slab(s, {150, 1000}, 0.1, 0.01, 0.005);
}

// A hollow box 0.3 m across whose wall is 3 mm thick: a thin part whose two sides are closed
// surfaces (the outer box and its cavity), so its mid-surface is closed too. Before meshing
// version 24 the thin-part route took open mid-surfaces only; on the boundary route every
// tetrahedralization lost its boundary in refinement (walls 3 mm apart, tetrahedra 5 cm long),
// and at 150 the part kept 46 tetrahedra and 2.8 % of its volume, 23 % of the diagonal in. Now a
// closed slab of prisms, exact as boxes are.
TEST(MeshingV4, HollowThinBoxIsAClosedSlab) {
  const SurfaceMesh s = with_cavity(box(Vec3::Zero(), Vec3::Constant(0.3)), box(Vec3::Constant(0.003), Vec3::Constant(0.297)));
  ASSERT_GT(signed_volume(s), 0.0);
  expect_one_slab(s, {150, 1000}, 0.01, 0.002, 0.002);
}

// A bottle with a 1.5 mm wall, open at its rim (sqs::thin_bottle): its prisms 12 mm wide at 300
// cut the rim's circle (an octagon, 1.9 mm inside it) and the neck 3 cm across (1.7 mm), over the
// inner bound of 1.2 mm, so the slab was refused and the bottle took the boundary route: 9,508
// tetrahedra in 28 s. Now the mid-surface keeps its outline and its creases within a quarter of
// the inner bound, and a slab off the bounds is made again at shorter edges (meshing version 24).
TEST(MeshingV4, ThinBottleIsASlabWithinTheBounds) {
  const SurfaceMesh s = sqs::thin_bottle();
  ASSERT_GT(signed_volume(s), 0.0);
  expect_one_slab(s, {300}, 0.02, 0.01, 0.005);
}

// TetrahedralizeOptions::run_refine_work, the safety net every run's refinement has: on the
// elephant (recovered, conforming) the default bound, far above its work, changes nothing; a
// bound at a third of its work stops the run there, which is counted, and leaves a conforming
// mesh with fewer tetrahedra.
TEST(MeshingV4, EveryRunsRefinementStopsAtItsWorkBound) {
  const SurfaceMesh s = squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/tests/data/elephant.off");
  auto run = [&](double bound, squeeze::meshing::TetrahedralizeStats& st) {
    return one_run(s, 1000, [&](squeeze::meshing::TetrahedralizeOptions& o) { o.run_refine_work = bound; }, st);
  };
  squeeze::meshing::TetrahedralizeStats unbounded, by_default, bounded;
  const squeeze::meshing::TetMesh m0 = run(0, unbounded);
  ASSERT_TRUE(unbounded.conforming);
  ASSERT_GT(unbounded.refine_work, 0);
  EXPECT_EQ(unbounded.runs_at_work_bound, 0);
  const squeeze::meshing::TetMesh m1 = run(squeeze::meshing::TetrahedralizeOptions{}.run_refine_work, by_default);
  EXPECT_EQ(by_default.runs_at_work_bound, 0);
  EXPECT_TRUE(m0.V == m1.V && m0.T == m1.T);
  const squeeze::meshing::TetMesh m2 = run(unbounded.refine_work / 3, bounded);
  EXPECT_EQ(bounded.runs_at_work_bound, 1);
  EXPECT_LT(bounded.refine_work, 0.6 * unbounded.refine_work);
  EXPECT_TRUE(bounded.conforming);
  EXPECT_GT(m2.T.rows(), 0);
  EXPECT_LT(m2.T.rows(), m0.T.rows());
}

// Thin walls that branch (meshing version 25): a comb (sqs::comb: 2 mm teeth 4 mm apart) and a
// plate with ribs (sqs::ribbed_plate: 3 mm). Neither is a thin part (its sides are not two), and
// on the boundary route every attempt lost its boundary: its points, spaced by the edge length
// (19 mm on the comb at 150), put each wall's points in the diametral balls of the next one's
// triangles, and recovery by splits gave up at its cap. The comb failed at every target (at 150:
// 12,176 tetrahedra, not conforming, 1.8 % of the diagonal in; at 1000 Mesh_3's winding-number
// solid, 1.14 of its volume), the ribbed plate at 150 (not conforming, 0.67 % in, 1.5°). Runs
// from a finer start (TetrahedralizeOptions::finer_start_runs) now recover them: exact, as boxes are.
TEST(MeshingV4, BranchingThinWallsAreExact) {
  for (const auto& [name, s, targets] : {std::tuple{"comb", sqs::comb(), std::vector<int>{150, 1000}},
                                         std::tuple{"ribbed plate", sqs::ribbed_plate(), std::vector<int>{150}}}) {
    SCOPED_TRACE(name);
    ASSERT_GT(signed_volume(s), 0.0);
    const double diag = bounding_box_diagonal(s.V);
    for (int target : targets) {
      SCOPED_TRACE("target " + std::to_string(target));
      const MeshResult r = mesh(s, target);
      EXPECT_TRUE(r.tet_stats.conforming);
      expect_within(r, diag, 0.01, 0.002, 0.002, 1);
    }
  }
}

// The finer start itself: the comb's boundary tetrahedralized at 150 is not conforming in any
// attempt from the first edge length, and is, exactly, from a quarter of it
// (TetrahedralizeOptions::edge_length_scale, as squeeze mesh's retry 4 runs it).
TEST(MeshingV4, FinerStartRecoversTheBoundaryTheAttemptsLost) {
  const SurfaceMesh s = sqs::comb();
  auto run = [&](double scale, int attempts, squeeze::meshing::TetrahedralizeStats& st) {
    squeeze::meshing::TetrahedralizeOptions o;
    o.target_tets = 150;
    o.edge_length_scale = scale;
    o.max_attempts = attempts;
    o.exude = false;
    return squeeze::meshing::tetrahedralize(s, o, &st);
  };
  squeeze::meshing::TetrahedralizeStats first, finer;
  run(1.0, squeeze::meshing::TetrahedralizeOptions{}.max_attempts, first);
  EXPECT_FALSE(first.conforming);
  const squeeze::meshing::TetMesh m = run(0.25, 1, finer);
  EXPECT_TRUE(finer.conforming);
  EXPECT_LT(finer.edge_length, 0.3 * first.edge_length);
  EXPECT_NEAR(tet_volume(m) / signed_volume(s), 1.0, 1e-9);
  EXPECT_GE(squeeze::meshing::tet_quality(m).min_dihedral, 5.0);
  squeeze::meshing::TetrahedralizeOptions bad;
  bad.edge_length_scale = 0;
  EXPECT_THROW(squeeze::meshing::tetrahedralize(s, bad), squeeze::InputError);
}

// The exuder's pump bound (TetrahedralizeOptions::exude_pumps_per_sliver): on the comb at 1000 its
// first attempt's exuder pumped 571,216 times for 233 slivers until its 30 s time limit, so the
// mesh depended on the machine's speed. It now stops at 20 pumps per sliver, counted, and the
// same input gives the same mesh.
// edge_incidences groups each undirected edge's faces (surface_analysis.h), shared by the
// components, the welded-segment walls and the mean curvature: over the corpus's real meshes,
// every face's three edges once each, in (a, b, face) order, a < b, `forward` as the face goes;
// on the closed sphere every run is two faces going opposite ways.
TEST(MeshingV4, EdgeIncidencesGroupEachEdgesFacesOverTheCorpus) {
  for (const std::string name : {"sphere.off", "bunny00.off", "ChineseDragon-10kv.off", "elephant.off"}) {
    const SurfaceMesh s = sqt::read_off(sqt::data(name));
    const std::vector<squeeze::meshing::EdgeIncidence> e = squeeze::meshing::edge_incidences(s.F);
    ASSERT_EQ(e.size(), static_cast<size_t>(3 * s.F.rows())) << name;
    std::map<std::array<int, 3>, int> uses;  // (a, b, face) → directed uses: +1 a → b, -1 b → a
    for (Eigen::Index f = 0; f < s.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int u = s.F(f, k), v = s.F(f, (k + 1) % 3);
        uses[{std::min(u, v), std::max(u, v), static_cast<int>(f)}] += u < v ? 1 : -1;
      }
    for (size_t i = 0; i < e.size(); ++i) {
      EXPECT_LT(e[i].a, e[i].b) << name;
      const auto it = uses.find({e[i].a, e[i].b, e[i].face});
      ASSERT_NE(it, uses.end()) << name;
      EXPECT_EQ(it->second, e[i].forward ? 1 : -1) << name;
      if (i > 0) {
        EXPECT_TRUE(std::tie(e[i - 1].a, e[i - 1].b, e[i - 1].face) < std::tie(e[i].a, e[i].b, e[i].face)) << name;
      }
    }
    size_t runs = 0, two_opposite = 0;
    squeeze::meshing::for_each_edge(e, [&](size_t i, size_t j) {
      ++runs;
      for (size_t k = i; k < j; ++k) EXPECT_TRUE(e[k].a == e[i].a && e[k].b == e[i].b) << name;
      if (j < e.size()) {
        EXPECT_FALSE(e[j].a == e[i].a && e[j].b == e[i].b) << name;
      }
      two_opposite += j - i == 2 && e[i].forward != e[i + 1].forward;
    });
    std::set<std::pair<int, int>> edges;
    for (const auto& x : e) edges.insert({x.a, x.b});
    EXPECT_EQ(runs, edges.size()) << name;
    if (name == "sphere.off") {
      EXPECT_EQ(two_opposite, runs) << name;
    }
  }
}

// A figure-eight tube 6 mm across on a curve 12 cm wide passes through itself, so it is meshed by
// the boundary of its winding-number solid, which Mesh_3 finds dilated: 17.3 % over the tube's
// volume at 1,000 tetrahedra, and 11.4 % after version 29's one round at 0.46 of the dilation (a
// tet mesh over the bound of 1.1). Since meshing version 30 the solid is made finer again while
// over 9 % (17.5 % below 1,000), up to three rounds: 1.066. Since version 31 the growth is
// estimated before the first solid (the dilation times the tube's area), and that one solid is
// made at 0.3 of the dilation: 1.055, one Mesh_3 run instead of three.
TEST(MeshingV4, SelfIntersectingThinTubeKeepsItsVolumeOnTheWindingNumberRoute) {
  const SurfaceMesh m = sqs::figure_eight_tube(0.06, 0.003, 10, 64);
  const double diag = bounding_box_diagonal(m.V);
  const MeshResult r = mesh(m, 1000);
  EXPECT_EQ(r.method, "winding_number_boundary") << r.fallback_because;
  expect_within(r, diag, 0.1, 0.015, 0.005, 1);  // volume ratio in [0.9, 1.1], and:
  EXPECT_GE(*r.volume_ratio, 0.95);              // (the issue's bound at 1,000: [0.95, 1.1])
  EXPECT_EQ(r.winding_solids, 1);  // (the dilation's growth estimated first: version 31)
}

TEST(MeshingV4, ExuderStopsAtItsPumpBoundTheSameWayEachRun) {
  // (As squeeze mesh reads it from a file: mesh_file's loading orders the vertices otherwise, and
  // the comb in memory does not pump in a circle.)
  const std::string path = ::testing::TempDir() + "/squeeze_comb.off";
  squeeze::meshing::save_surface(path, sqs::comb());
  MeshOptions mo;
  mo.tetrahedralize.target_tets = 1000;
  const MeshResult a = squeeze::meshing::mesh_file(path, mo), b = squeeze::meshing::mesh_file(path, mo);
  EXPECT_GE(a.tet_stats.exuder_pump_bounds, 1);
  EXPECT_TRUE(a.tet_stats.conforming);
  EXPECT_TRUE(a.tets.V == b.tets.V && a.tets.T == b.tets.T);
  // The elephant's exuder ends on its own (about one pump per sliver).
  squeeze::meshing::TetrahedralizeStats e;
  squeeze::meshing::TetrahedralizeOptions o;
  o.target_tets = 1000;
  o.max_attempts = 1;
  squeeze::meshing::tetrahedralize(
      squeeze::meshing::load_surface(std::string(SQUEEZE_SOURCE_DIR) + "/tests/data/elephant.off"), o, &e);
  EXPECT_EQ(e.exuder_pump_bounds, 0);
}

// triangles_cross: two faces of one surface meet only at the corners and edge they share, or they
// cross; a degenerate one crosses nothing. Each case also with the triangles swapped and their corners turned (the same answer).
TEST(TriangleIntersection, CrossingTouchingAndSharedCornersAreToldApart) {
  using squeeze::meshing::triangles_cross;
  using T = std::array<Vec3, 3>;
  using I = std::array<std::int64_t, 3>;
  auto check = [](const T& a, const I& ia, const T& b, const I& ib, bool expected, const char* what) {
    for (int turn = 0; turn < 3; ++turn) {
      const T a2{a[static_cast<size_t>(turn)], a[static_cast<size_t>((turn + 1) % 3)], a[static_cast<size_t>((turn + 2) % 3)]};
      const I ia2{ia[static_cast<size_t>(turn)], ia[static_cast<size_t>((turn + 1) % 3)], ia[static_cast<size_t>((turn + 2) % 3)]};
      EXPECT_EQ(triangles_cross(a2, ia2, b, ib), expected) << what << ", turned " << turn;
      EXPECT_EQ(triangles_cross(b, ib, a2, ia2), expected) << what << ", swapped, turned " << turn;
    }
  };
  const T flat{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)};
  const I flat_ids{0, 1, 2};
  // No corner shared.
  check(flat, flat_ids, {Vec3(0.2, 0.2, -1), Vec3(0.3, 0.3, 1), Vec3(3, 3, 0.5)}, {3, 4, 5}, true, "pierced");
  check(flat, flat_ids, {Vec3(0, 0, 1), Vec3(2, 0, 1), Vec3(0, 2, 1)}, {3, 4, 5}, false, "parallel, apart");
  check(flat, flat_ids, {Vec3(0.5, 0.5, 0), Vec3(3, 0.5, 0), Vec3(0.5, 3, 0)}, {3, 4, 5}, true, "one plane, overlapping");
  // The same point under two ids is two corners: they touch, and that is a crossing.
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(-1, 0, 1), Vec3(0, -1, 1)}, {3, 4, 5}, true, "a corner on a corner, not shared");
  // One corner shared.
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(-1, 0, 1), Vec3(0, -1, 1)}, {0, 4, 5}, false, "a fan's neighbour, bent");
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(1, 1, -1)}, {0, 4, 5}, true, "its opposite edge through the other");
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(0.5, 0.5, 1), Vec3(1, 0.2, 1)}, {0, 4, 5}, false, "above it, from the corner");
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(-1, 0, 0), Vec3(0, -1, 0)}, {0, 4, 5}, false, "one plane, side by side");
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(0.5, 0.1, 0), Vec3(-1, -3, 0)}, {0, 4, 5}, true, "one plane, an edge into its angle");
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(0.2, 0.4, 0), Vec3(0.4, 0.2, 0)}, {0, 4, 5}, true, "one plane, inside it");
  // An edge shared: not tested (the fold test's), whatever the angle.
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, -1, 0)}, {0, 1, 5}, false, "an edge, flat");
  check(flat, flat_ids, {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0.5, 0.5, 0)}, {0, 1, 5}, false, "an edge, folded onto it");
  // A degenerate triangle (three corners on a line) crosses nothing.
  check(flat, flat_ids, {Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 1)}, {3, 4, 5}, false, "degenerate");
}

// simplify_envelope (no_local_crossings) leaves no two faces that cross: over every pair of faces
// that share a corner (triangles_cross) and every pair that do not (does_self_intersect), on the
// urchin of the tests and the sphere of tests/data, simplified toward a few targets.
TEST(Envelope, SimplifiedFacesCrossNoOtherFace) {
  for (const auto& [name, s] : {std::pair<std::string, SurfaceMesh>{"urchin", sqs::urchin()},
                                {"sphere", squeeze::meshing::load_surface(std::string(SQUEEZE_TEST_DATA) + "/sphere.off")}}) {
    const double diag = bounding_box_diagonal(s.V);
    for (int target : {40, 150, 600}) {
      squeeze::meshing::EnvelopeOptions e;
      e.max_outside = 0.01 * diag;
      e.max_inside = 0.0045 * diag;
      e.target_faces = target;
      const SurfaceMesh b = squeeze::meshing::simplify_envelope(s, e);
      ASSERT_GT(b.F.rows(), 0) << name;
      EXPECT_FALSE(squeeze::meshing::does_self_intersect(b)) << name << " at " << target;
      std::vector<std::vector<int>> around(static_cast<size_t>(b.V.rows()));
      for (int f = 0; f < b.F.rows(); ++f)
        for (int k = 0; k < 3; ++k) around[static_cast<size_t>(b.F(f, k))].push_back(f);
      int crossing = 0, pairs = 0;
      for (const auto& faces : around)
        for (size_t i = 0; i < faces.size(); ++i)
          for (size_t j = i + 1; j < faces.size(); ++j) {
            std::array<Vec3, 3> x, y;
            std::array<std::int64_t, 3> ix, iy;
            for (int k = 0; k < 3; ++k) {
              ix[static_cast<size_t>(k)] = b.F(faces[i], k), iy[static_cast<size_t>(k)] = b.F(faces[j], k);
              x[static_cast<size_t>(k)] = b.V.row(b.F(faces[i], k)).transpose();
              y[static_cast<size_t>(k)] = b.V.row(b.F(faces[j], k)).transpose();
            }
            ++pairs;
            crossing += squeeze::meshing::triangles_cross(x, ix, y, iy);
          }
      EXPECT_GT(pairs, b.F.rows()) << name;
      EXPECT_EQ(crossing, 0) << name << " at " << target;
    }
  }
}

// Where a part's first boundary loses conformity (recovery gave up) and it has over
// solid_first_faces faces, its winding-number solid is tried before retries 1 and 3 (meshing version
// 51): the urchin at 150 (4,992 faces) holds no retry, and its solid is the same mesh either way.
TEST(MeshingV4, SolidFirstWhereTheFirstBoundaryLostConformityIsTheSameMeshWithFewerRetries) {
  const SurfaceMesh s = sqs::urchin();
  ASSERT_EQ(s.F.rows(), 4992);
  MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.solid_first_faces = 0;  // (version 50: after every retry)
  const MeshResult last = squeeze::meshing::mesh_surface(s, o);
  o.solid_first_faces = 4000;
  const MeshResult first = squeeze::meshing::mesh_surface(s, o);
  ASSERT_EQ(last.parts_by_winding_number, 1) << "no boundary attempt held: the case this is about";
  EXPECT_EQ(first.parts_by_winding_number, 1);
  EXPECT_LT(first.boundary_retries, last.boundary_retries);
  EXPECT_TRUE(first.tets.T == last.tets.T && first.tets.V == last.tets.V) << "the same solid";
  const double diag = bounding_box_diagonal(s.V);
  EXPECT_LE(first.deviation_out, 0.015 * diag);
  EXPECT_LE(first.deviation_in, 0.005 * diag);
  EXPECT_GE(first.quality.min_dihedral, 5.0);
  o.solid_first_faces = 5000;  // over its faces: as version 50
  const MeshResult over = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(over.boundary_retries, last.boundary_retries);
}

// Interior slivers left after the moves, flips and peeling have their short edges contracted
// (TetrahedralizeOptions::contract_max_length, meshing version 52): the urchin of 24 spikes (seed
// 23) at 1000 had five across a spike's tip in its remeshed boundary's mesh (retry 0, conforming),
// went on to every retry and was meshed as its winding-number solid (15,765 tetrahedra, 16 s).
// Now retry 0 holds, at a third of the tetrahedra, within every bound.
TEST(MeshingV4, SliversAcrossASpikeTipAreContractedAndTheBoundaryHolds) {
  const SurfaceMesh s = sqs::urchin23();
  ASSERT_EQ(s.F.rows(), 4992);
  const double diag = bounding_box_diagonal(s.V);
  MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.tetrahedralize.contract_max_length = 0;  // (version 51)
  o.solid_first_thickness = 0;               // (version 52: its solid after every retry, not before them)
  const MeshResult before = squeeze::meshing::mesh_surface(s, o);
  o.solid_first_thickness = MeshOptions{}.solid_first_thickness;
  ASSERT_EQ(before.parts_by_winding_number, 1) << "no boundary attempt held: the case this is about";
  EXPECT_EQ(before.tet_stats.contractions, 0);
  o.tetrahedralize.contract_max_length = 0.25;
  const MeshResult r = squeeze::meshing::mesh_surface(s, o);
  EXPECT_EQ(r.method, "boundary");
  EXPECT_EQ(r.parts_by_winding_number, 0);
  EXPECT_GT(r.tet_stats.contractions, 0);
  EXPECT_TRUE(r.tet_stats.conforming);
  EXPECT_LT(r.tets.T.rows(), before.tets.T.rows() / 2);
  EXPECT_LT(r.boundary_retries, before.boundary_retries);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_GT(r.quality.min_volume, 0);
  EXPECT_EQ(r.quality.components, 1);
  EXPECT_LE(r.deviation_out, 0.01 * diag);
  EXPECT_LE(r.deviation_in, 0.005 * diag);
  ASSERT_TRUE(r.volume_ratio.has_value());
  EXPECT_NEAR(*r.volume_ratio, 1.0, 0.05);
}

// A result whose input lies over inner_retry_deviation (0.5) of max_deviation outside it is meshed
// again with the inner bound 0.85 times as large (meshing version 51): the urchin at 1000 lay
// 0.502 % of the diagonal in (the envelope's samples, spaced by the inner bound, missed a spike's
// side); meshed again, within 0.5 %, at its other bounds.
TEST(MeshingV4, InputOverTheInnerBoundOutsideIsMeshedAgainTighter) {
  const SurfaceMesh s = sqs::urchin();
  const double diag = bounding_box_diagonal(s.V);
  MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.inner_retry_deviation = 0;  // (not meshed again: version 50)
  const MeshResult once = squeeze::meshing::mesh_surface(s, o);
  ASSERT_GT(once.deviation_in, 0.005 * diag) << "the case this is about";
  o.inner_retry_deviation = 0.5;
  const MeshResult r = squeeze::meshing::mesh_surface(s, o);
  EXPECT_LE(r.deviation_in, 0.005 * diag);
  EXPECT_LT(r.deviation_in, once.deviation_in);
  EXPECT_LE(r.deviation_out, 0.015 * diag);
  EXPECT_GE(r.quality.min_dihedral, 5.0);
  EXPECT_EQ(r.quality.components, 1);
  ASSERT_TRUE(r.volume_ratio.has_value());
  EXPECT_NEAR(*r.volume_ratio, 1.0, 0.05);
  double staged = 0;
  for (const auto& stage : r.seconds) staged += stage.second;
  bool not_kept = false;
  for (const auto& stage : r.seconds) not_kept = not_kept || stage.first == "tries not kept";
  EXPECT_TRUE(not_kept) << "the first meshing's seconds are counted";
  o.inner_retry_deviation = -1;
  EXPECT_THROW(squeeze::meshing::mesh_surface(s, o), squeeze::InputError);
}
