// decimate_quadric (decimate.h): the proxy that dense inputs are meshed through (meshing version
// 49). Properties on generated shapes and on the corpus: flat sides collapse exactly, every vertex
// stays within the bound of the input surface and the input within it of the result, topology and
// borders are the input's, the same input gives the same result, bad input is an InputError.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "meshing_test_util.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/decimate.h"
#include "squeeze/meshing/surface_analysis.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/triangle_bvh.h"

namespace {

using squeeze::meshing::bounding_box_diagonal;
using squeeze::meshing::decimate_quadric;
using squeeze::meshing::DecimateOptions;
using squeeze::meshing::DecimateStats;
using squeeze::meshing::SurfaceMesh;
using squeeze::meshing::TriangleBvh;
using Vec3 = Eigen::Vector3d;

/// Each triangle split into four at its edges' midpoints (shared between the two faces of an
/// edge), `levels` times: the same surface with 4^levels times the faces.
SurfaceMesh subdivided(SurfaceMesh m, int levels) {
  for (int l = 0; l < levels; ++l) {
    std::vector<Vec3> V;
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) V.push_back(m.V.row(i).transpose());
    std::map<std::pair<int, int>, int> mid;
    auto at = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto [it, fresh] = mid.try_emplace(key, static_cast<int>(V.size()));
      if (fresh) V.push_back(0.5 * (V[static_cast<size_t>(a)] + V[static_cast<size_t>(b)]));
      return it->second;
    };
    std::vector<std::array<int, 3>> F;
    for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
      const int a = m.F(f, 0), b = m.F(f, 1), c = m.F(f, 2);
      const int ab = at(a, b), bc = at(b, c), ca = at(c, a);
      F.push_back({a, ab, ca});
      F.push_back({ab, b, bc});
      F.push_back({ca, bc, c});
      F.push_back({ab, bc, ca});
    }
    m = sqt::surface_of(V, F);
  }
  return m;
}

/// The box [0, a] x [0, b] x [0, c]: 8 vertices, 12 outward triangles.
SurfaceMesh box(double a, double b, double c) {
  std::vector<Vec3> V;
  for (int i = 0; i < 8; ++i) V.emplace_back((i & 1) * a, ((i >> 1) & 1) * b, ((i >> 2) & 1) * c);
  const std::vector<std::array<int, 3>> F = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return sqt::surface_of(V, F);
}

double signed_volume(const SurfaceMesh& m) {
  double v = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    v += m.V.row(m.F(f, 0)).dot(m.V.row(m.F(f, 1)).cross(m.V.row(m.F(f, 2)))) / 6.0;
  return v;
}

/// The largest distance from the vertices of `from` to the triangles of `to`.
double farthest_vertex(const SurfaceMesh& from, const SurfaceMesh& to) {
  const TriangleBvh bvh(to.V, to.F);
  double d = 0;
  for (Eigen::Index i = 0; i < from.V.rows(); ++i) d = std::max(d, bvh.nearest(from.V.row(i).transpose()));
  return d;
}

/// The positions of the vertices on border edges (edges of one face), sorted.
std::vector<std::tuple<double, double, double>> border_points(const SurfaceMesh& m) {
  std::map<std::pair<int, int>, int> count;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++count[std::minmax(m.F(f, k), m.F(f, (k + 1) % 3))];
  std::vector<int> ids;
  for (const auto& [e, n] : count)
    if (n == 1) ids.push_back(e.first), ids.push_back(e.second);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<std::tuple<double, double, double>> p;
  for (int i : ids) p.emplace_back(m.V(i, 0), m.V(i, 1), m.V(i, 2));
  std::sort(p.begin(), p.end());
  return p;
}

TEST(Decimate, FlatSidesCollapseAndTheBoxStaysExact) {
  const SurfaceMesh input = subdivided(box(1.0, 0.6, 0.02), 4);  // 3,072 faces
  DecimateOptions o;
  o.max_error = 1e-9;
  DecimateStats stats;
  const SurfaceMesh out = decimate_quadric(input, o, &stats);
  EXPECT_LE(out.F.rows(), 48) << "of " << input.F.rows();
  EXPECT_EQ(stats.faces, out.F.rows());
  EXPECT_GT(stats.collapses, 1000);
  EXPECT_LE(stats.max_error, 1e-9);
  EXPECT_TRUE(squeeze::meshing::is_oriented_two_manifold(out.F, static_cast<int>(out.V.rows())));
  EXPECT_NEAR(signed_volume(out), 1.0 * 0.6 * 0.02, 1e-12);
  // Every vertex on the box's surface; its eight corners kept.
  const Vec3 hi(1.0, 0.6, 0.02);
  int corners = 0;
  for (Eigen::Index i = 0; i < out.V.rows(); ++i) {
    const Vec3 p = out.V.row(i).transpose();
    double to_side = INFINITY;
    int at_side = 0;
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p(k), -1e-12);
      EXPECT_LE(p(k), hi(k) + 1e-12);
      const double d = std::min(std::abs(p(k)), std::abs(p(k) - hi(k)));
      to_side = std::min(to_side, d);
      at_side += d <= 1e-12;
    }
    EXPECT_LE(to_side, 1e-12) << "vertex " << i;
    corners += at_side == 3;
  }
  EXPECT_EQ(corners, 8);
}

TEST(Decimate, KeepsItsBoundTopologyAndBordersOnTheCorpus) {
  // (The dragon has holes and intersects itself; the heart is welded segments with non-manifold
  // edges.)
  for (const char* name : {"bunny00.off", "elephant.off", "ChineseDragon-10kv.off", "organs/heart.off", "organs/lung_left.off"}) {
    SCOPED_TRACE(name);
    const SurfaceMesh input = squeeze::meshing::load_surface(sqt::data(name));
    const double diag = bounding_box_diagonal(input.V);
    DecimateOptions o;
    o.max_error = 2e-3 * diag;
    DecimateStats stats;
    const SurfaceMesh out = decimate_quadric(input, o, &stats);
    EXPECT_LT(out.F.rows(), 0.8 * static_cast<double>(input.F.rows()));  // (these are coarse meshes already)
    EXPECT_LE(stats.max_error, o.max_error);
    // The result's vertices within the bound of the input (each lies within it of the planes of the
    // faces it took in; the surfaces themselves are measured here, at the vertices). The input's
    // vertices may lie farther from the result, under chords across curved or sharp regions: up to
    // 2.76 times the bound (the left lung's, since meshing version 50; 1.3 times at most elsewhere).
    EXPECT_LE(farthest_vertex(out, input), o.max_error);
    EXPECT_LE(farthest_vertex(input, out), 3.0 * o.max_error);
    const auto a = squeeze::meshing::analyse_surface(input), b = squeeze::meshing::analyse_surface(out);
    EXPECT_EQ(b.components, a.components);
    EXPECT_EQ(b.boundary_edges, a.boundary_edges);
    EXPECT_EQ(b.nonmanifold_edges, a.nonmanifold_edges);
    EXPECT_EQ(b.closed, a.closed);
    EXPECT_EQ(border_points(out), border_points(input));
    if (a.closed && a.nonmanifold_edges == 0) {
      EXPECT_TRUE(squeeze::meshing::is_oriented_two_manifold(out.F, static_cast<int>(out.V.rows())));
      EXPECT_NEAR(signed_volume(out) / signed_volume(input), 1.0, 0.01);
    }
  }
}

// A scan's noise fills the quadric's sum of squares long before any one plane is near the bound: a
// unit cube split into 12,288 triangles, every vertex moved by Gaussian noise of 1e-4, decimated
// within 1e-3. Checked plane by plane (the default) it keeps under a third of the faces the
// quadric's root alone keeps (version 49), and its vertices are as near the input.
TEST(Decimate, NoisyScanPlaneByPlaneKeepsFewerFacesWithinTheBound) {
  SurfaceMesh input = subdivided(box(1.0, 1.0, 1.0), 5);
  ASSERT_EQ(input.F.rows(), 12288);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-4);
  for (Eigen::Index i = 0; i < input.V.size(); ++i) input.V.data()[i] += noise(rng);
  DecimateOptions o;
  o.max_error = 1e-3;
  DecimateStats by_plane, by_root;
  const SurfaceMesh a = decimate_quadric(input, o, &by_plane);
  o.plane_by_plane = false;
  const SurfaceMesh b = decimate_quadric(input, o, &by_root);
  EXPECT_LT(3 * a.F.rows(), b.F.rows()) << a.F.rows() << " against " << b.F.rows();
  for (const auto* r : {&a, &b}) {
    EXPECT_LE(farthest_vertex(*r, input), o.max_error);
    EXPECT_LE(farthest_vertex(input, *r), 3.0 * o.max_error);
    EXPECT_NEAR(signed_volume(*r), signed_volume(input), 1e-2 * signed_volume(input));
    EXPECT_TRUE(squeeze::meshing::is_oriented_two_manifold(r->F, static_cast<int>(r->V.rows())));
  }
  EXPECT_LE(by_plane.max_error, o.max_error);
  EXPECT_LE(by_root.max_error, o.max_error);
}

TEST(Decimate, SameInputSameResult) {
  const SurfaceMesh input = squeeze::meshing::load_surface(sqt::data("elephant.off"));
  DecimateOptions o;
  o.max_error = 1e-3 * bounding_box_diagonal(input.V);
  const SurfaceMesh a = decimate_quadric(input, o), b = decimate_quadric(input, o);
  ASSERT_EQ(a.F.rows(), b.F.rows());
  EXPECT_EQ(a.F, b.F);
  EXPECT_EQ(a.V, b.V);
}

TEST(Decimate, StopsAtItsTargetFaces) {
  const SurfaceMesh input = squeeze::meshing::load_surface(sqt::data("bunny00.off"));
  DecimateOptions o;
  o.max_error = 1e-2 * bounding_box_diagonal(input.V);
  o.target_faces = 20000;
  const SurfaceMesh out = decimate_quadric(input, o);
  EXPECT_LE(out.F.rows(), 20000);
  EXPECT_GE(out.F.rows(), 19998);  // (a collapse removes two faces)
}

TEST(Decimate, BadInputIsAnInputError) {
  const SurfaceMesh ok = box(1, 1, 1);
  DecimateOptions o;
  o.max_error = -1;
  EXPECT_THROW(decimate_quadric(ok, o), squeeze::InputError);
  o.max_error = NAN;
  EXPECT_THROW(decimate_quadric(ok, o), squeeze::InputError);
  o.max_error = 0.1;
  SurfaceMesh nan = ok;
  nan.V(3, 1) = NAN;
  EXPECT_THROW(decimate_quadric(nan, o), squeeze::InputError);
  SurfaceMesh out_of_range = ok;
  out_of_range.F(5, 2) = 8;
  EXPECT_THROW(decimate_quadric(out_of_range, o), squeeze::InputError);
  EXPECT_EQ(decimate_quadric(SurfaceMesh{}, o).F.rows(), 0);
}

}  // namespace
