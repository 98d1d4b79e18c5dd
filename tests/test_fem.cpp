// Tests of squeeze::fem: constraint kernels, the world's step, spatial hashing, penetration depth.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "fem_test_worlds.h"
#include "squeeze/common/error.h"
#include "squeeze/fem/collision.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/scene.h"
#include "squeeze/fem/world.h"
#include "squeeze/fem/forces.h"
#include "squeeze/fem/integrator.h"

using namespace squeeze;
using namespace squeeze::meshing;
using namespace squeeze::fem;
using Eigen::Vector3d;

namespace {

Vector3d rand_vec(std::mt19937& g, double s = 1.0) {
  std::uniform_real_distribution<double> u(-s, s);
  return {u(g), u(g), u(g)};
}

TetMesh cube(double side, int n, const Vector3d& lo = Vector3d::Zero()) {
  return box_tet_mesh(lo, lo + Vector3d::Constant(side), Eigen::Vector3i::Constant(n));
}

WorldOptions no_gravity() {
  WorldOptions o;
  o.gravity.setZero();
  o.collisions = false;
  return o;
}

// Total energy with the central velocity (x_{n+1} − x_{n−1}) / 2h = (v_n + v_{n+1}) / 2 at x_n.
double central_energy(const World& w, const State& s, const State& next) {
  State c = s;
  c.v = 0.5 * (s.v + next.v);
  return w.kinetic_energy(c) + w.elastic_energy(s) + w.gravity_energy(s);
}

// Internal forces F (#rows by 3, N) at state s: they sum to zero and exert no net torque about
// the origin, to 1e-12 of their summed magnitude (which must be above 1 N: a real test).
void expect_no_net_force_or_torque(const State& s, const RowMatrixX3d& F) {
  Vector3d net = Vector3d::Zero(), torque = Vector3d::Zero();
  double scale = 0;
  for (int i = 0; i < F.rows(); ++i) {
    net += F.row(i).transpose();
    torque += Vector3d(s.x.row(i)).cross(Vector3d(F.row(i)));
    scale += F.row(i).norm();
  }
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(net.norm(), 1e-12 * scale);
  EXPECT_LT(torque.norm(), 1e-12 * scale);
}

}  // namespace

TEST(FemKernels, ForcesAreMinusEnergyGradient) {
  std::mt19937 g(1);
  for (int trial = 0; trial < 20; ++trial) {
    Vec3 p[4];
    for (auto& q : p) q = rand_vec(g);
    const double D0 = 0.7, V0 = 0.05, k = 3.0, eps = 1e-6;
    Vec3 fi, fj;
    distance_forces(p[0], p[1], Vec3::Zero(), Vec3::Zero(), D0, k, 0.0, fi, fj);
    Vec3 fv[4], zero[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    volume_forces(p, zero, V0, k, 0.0, fv);
    for (int v = 0; v < 4; ++v)
      for (int c = 0; c < 3; ++c) {
        Vec3 a[4], b[4];
        std::copy(p, p + 4, a);
        std::copy(p, p + 4, b);
        a[v][c] += eps;
        b[v][c] -= eps;
        const double dV = (volume_energy(a[0], a[1], a[2], a[3], V0, k) - volume_energy(b[0], b[1], b[2], b[3], V0, k)) /
                          (2 * eps);
        EXPECT_NEAR(fv[v][c], -dV, 1e-5 * (1 + std::abs(dV)));
        if (v < 2) {
          const double dD = (distance_energy(a[0], a[1], D0, k) - distance_energy(b[0], b[1], D0, k)) / (2 * eps);
          EXPECT_NEAR((v == 0 ? fi : fj)[c], -dD, 1e-6 * (1 + std::abs(dD)));
        }
      }
  }
}

TEST(FemKernels, DampingOpposesRelativeMotionOnly) {
  const Vec3 pi(0, 0, 0), pj(1, 0, 0);
  Vec3 fi, fj;
  distance_forces(pi, pj, Vec3(1, 2, 3), Vec3(1, 2, 3), 1.0, 1.0, 5.0, fi, fj);  // rigid translation
  EXPECT_NEAR(fi.norm(), 0.0, 1e-12);
  distance_forces(pi, pj, Vec3::Zero(), Vec3(1, 0, 0), 1.0, 0.0, 5.0, fi, fj);  // separating
  EXPECT_LT(fj.x(), 0.0);
  EXPECT_DOUBLE_EQ(fi.x(), -fj.x());
}

#if defined(__SSE2__)
TEST(FemKernels, PairKernelsEqualScalarKernelsBitForBit) {
  // World::step computes its elements two at a time (SSE2 lanes); the forces must be the scalar
  // kernels' to the last bit, including a zero-length edge (zero gradient) and a flat tet.
  struct Edge { int i, j; double D0, k, kd; };
  struct Tet { int v[4]; double V0, k, kd; };
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(0.1, 3.0);
  const int n = 40;
  RowMatrixX3d X(n, 3), V(n, 3);
  for (int i = 0; i < n; ++i) X.row(i) = rand_vec(g).transpose(), V.row(i) = rand_vec(g, 5.0).transpose();
  X.row(1) = X.row(0);                                  // edge (0, 1): zero length
  X.row(5) = 0.5 * (X.row(2) + X.row(3)), X.row(4) = X.row(2);  // tet (2, 3, 4, 5): flat
  std::vector<Edge> edges{{0, 1, 0.3, 2.0, 0.1}};
  std::vector<Tet> tets{{{2, 3, 4, 5}, 0.05, 3.0, 0.2}};
  for (int e = 0; e < 200; ++e) {
    const int i = static_cast<int>(g() % n), j = (i + 1 + static_cast<int>(g() % (n - 1))) % n;
    edges.push_back({i, j, u(g), u(g) * 1e3, u(g)});
  }
  for (int t = 0; t < 200; ++t) {
    Tet T{{0, 0, 0, 0}, u(g) * 0.01, u(g) * 1e3, u(g)};
    for (int& c : T.v) c = static_cast<int>(g() % n);
    tets.push_back(T);
  }
  const double *x = X.data(), *v = V.data();
  auto bits_equal = [](const double* a, const double* b, int m) { return std::memcmp(a, b, sizeof(double) * m) == 0; };
  for (size_t e = 0; e + 1 < edges.size(); ++e) {
    double pair0[6], pair1[6];
    const simd::Pair3 fj = distance_forces_pair(x, v, edges[e], edges[e + 1]);
    simd::store_pair(pair0, pair1, simd::neg(fj));
    simd::store_pair(pair0 + 3, pair1 + 3, fj);
    for (int q = 0; q < 2; ++q) {
      const Edge& E = edges[e + q];
      Vec3 fi, fj;
      distance_forces(Vec3(x + 3 * E.i), Vec3(x + 3 * E.j), Vec3(v + 3 * E.i), Vec3(v + 3 * E.j), E.D0, E.k, E.kd, fi, fj);
      const double scalar[6] = {fi[0], fi[1], fi[2], fj[0], fj[1], fj[2]};
      EXPECT_TRUE(bits_equal(scalar, q == 0 ? pair0 : pair1, 6)) << "edge " << e + q;
    }
  }
  for (size_t t = 0; t + 1 < tets.size(); ++t) {
    double pair0[12], pair1[12];
    simd::Pair3 f4[4];
    volume_forces_pair(x, v, tets[t], tets[t + 1], f4);
    for (int c = 0; c < 4; ++c) simd::store_pair(pair0 + 3 * c, pair1 + 3 * c, f4[c]);
    for (int q = 0; q < 2; ++q) {
      const Tet& T = tets[t + q];
      Vec3 p[4], vel[4], f[4];
      for (int c = 0; c < 4; ++c) p[c] = Vec3(x + 3 * T.v[c]), vel[c] = Vec3(v + 3 * T.v[c]);
      volume_forces(p, vel, T.V0, T.k, T.kd, f);
      double scalar[12];
      for (int c = 0; c < 4; ++c) scalar[3 * c] = f[c][0], scalar[3 * c + 1] = f[c][1], scalar[3 * c + 2] = f[c][2];
      EXPECT_TRUE(bits_equal(scalar, q == 0 ? pair0 : pair1, 12)) << "tet " << t + q;
    }
  }
}
#endif

TEST(FemBody, MassesAndRestData) {
  Material m;
  m.density = 500;
  const Body b(cube(2.0, 2), m);
  EXPECT_NEAR(b.mass.sum(), 500 * 8.0, 1e-9);
  EXPECT_NEAR(b.total_volume(), 8.0, 1e-12);
  EXPECT_EQ(b.tets(), 48);
  EXPECT_GT(b.F.rows(), 0);
  EXPECT_THROW(Body(TetMesh{}, m), InputError);
  TetMesh bad = cube(1.0, 1);
  std::swap(bad.T(0, 0), bad.T(0, 1));
  EXPECT_THROW(Body(bad, m), InputError);
  const TetMesh ball = ball_tet_mesh(1.0, 4);
  EXPECT_NO_THROW(Body(ball, m));
}

TEST(FemBody, SurfaceIsTheBoxSurfaceOutward) {
  // A Kuhn box of 2×1×3 cells: 4 (n0 n1 + n1 n2 + n0 n2) = 44 outward surface triangles, every other
  // tet face shared with exactly one neighbor. Its tets' corners are reordered by even permutations
  // (same orientation), so that every local face is on the boundary somewhere.
  const Vector3d lo(-0.5, 0.0, 0.25), hi(0.5, 0.3, 1.0);
  TetMesh mesh = box_tet_mesh(lo, hi, Eigen::Vector3i(2, 1, 3));
  const int even[3][4] = {{0, 1, 2, 3}, {1, 2, 0, 3}, {2, 3, 0, 1}};
  for (Eigen::Index t = 0; t < mesh.T.rows(); ++t) {
    const Eigen::RowVector4i r = mesh.T.row(t);
    const int* e = even[t % 3];
    mesh.T.row(t) << r(e[0]), r(e[1]), r(e[2]), r(e[3]);
  }
  const Body b(mesh, Material{});  // throws if a tet were inverted
  ASSERT_EQ(b.F.rows(), 44);
  const Vector3d centre = 0.5 * (lo + hi);
  double area = 0;
  for (Eigen::Index f = 0; f < b.F.rows(); ++f) {
    const Vector3d p0 = b.rest.row(b.F(f, 0)), p1 = b.rest.row(b.F(f, 1)), p2 = b.rest.row(b.F(f, 2));
    const Vector3d n = (p1 - p0).cross(p2 - p0);
    area += 0.5 * n.norm();
    EXPECT_GT(n.dot((p0 + p1 + p2) / 3.0 - centre), 0.0) << "triangle " << f << " points inward";
  }
  const Vector3d d = hi - lo;
  EXPECT_NEAR(area, 2 * (d.x() * d.y() + d.y() * d.z() + d.x() * d.z()), 1e-12);
  int boundary = 0, locals = 0;
  for (int t = 0; t < b.tets(); ++t)
    for (int k = 0; k < 4; ++k) {
      EXPECT_NE(b.boundary_face(t, k) >= 0, b.neighbor(t, k) >= 0) << t << ' ' << k;
      boundary += b.boundary_face(t, k) >= 0;
      if (b.boundary_face(t, k) >= 0) locals |= 1 << k;
    }
  EXPECT_EQ(boundary, 44);
  EXPECT_EQ(locals, 15) << "every local face must be on the boundary somewhere";
  for (int v = 0; v < b.vertices(); ++v) {
    const Vector3d p = b.rest.row(v);
    const bool on_box = ((p - lo).cwiseAbs().minCoeff() < 1e-12) || ((p - hi).cwiseAbs().minCoeff() < 1e-12);
    EXPECT_EQ(b.on_boundary[static_cast<size_t>(v)] != 0, on_box) << "vertex " << v;
  }
}

TEST(FemWorld, RestIsEquilibrium) {
  World w(no_gravity());
  w.add_body(Body(cube(1.0, 2), Material{}));
  State s = w.initial_state();
  RowMatrixX3d F;
  w.total_forces(s, nullptr, F);
  EXPECT_EQ(F.cwiseAbs().maxCoeff(), 0.0);
  const State s0 = s;
  w.step(s);
  EXPECT_EQ((s.x - s0.x).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(s.v.cwiseAbs().maxCoeff(), 0.0);
}

TEST(FemWorld, InternalForcesHaveNoNetForceOrTorque) {
  Material m;
  m.damping_distance = 0.3;
  m.damping_volume = 0.2;
  World w(no_gravity());
  w.add_body(Body(cube(1.0, 3), m));
  State s = w.initial_state();
  std::mt19937 g(7);
  for (int i = 0; i < s.x.rows(); ++i) {
    s.x.row(i) += rand_vec(g, 0.15).transpose();
    s.v.row(i) = rand_vec(g, 2.0).transpose();
  }
  RowMatrixX3d F;
  w.internal_forces(s, F);
  expect_no_net_force_or_torque(s, F);
}

// The world sums its element forces in groups (clusters of about 128 vertices, in Morton order,
// each with its own accumulator slots). On objects of several clusters, one of them with its
// vertices in random order (as a mesher may leave them), every row's force is the plain sum of its
// edges' and tets' kernel forces, to rounding.
TEST(FemWorld, GroupedForcesEqualThePerElementSum) {
  TetMesh ball = ball_tet_mesh(0.1, 7);  // ~300 vertices: three clusters
  {
    std::vector<int> perm(static_cast<size_t>(ball.V.rows()));
    for (size_t i = 0; i < perm.size(); ++i) perm[i] = static_cast<int>(i);
    std::shuffle(perm.begin(), perm.end(), std::mt19937(11));
    Eigen::MatrixX3d V(ball.V.rows(), 3);
    for (int i = 0; i < ball.V.rows(); ++i) V.row(perm[i]) = ball.V.row(i);
    for (int t = 0; t < ball.T.rows(); ++t)
      for (int k = 0; k < 4; ++k) ball.T(t, k) = perm[ball.T(t, k)];
    ball.V = V;
  }
  Material m;
  m.damping_distance = 0.3;
  m.damping_volume = 0.2;
  World w(no_gravity());
  w.add_body(Body(ball, m));
  w.add_body(Body(cube(0.2, 6, Vector3d(0.3, 0, 0)), m));  // 343 vertices, mesh order
  ASSERT_GT(w.body(0).vertices(), 256);
  State s = w.initial_state();
  std::mt19937 g(5);
  for (int i = 0; i < s.x.rows(); ++i) {
    s.x.row(i) += rand_vec(g, 0.004).transpose();
    s.v.row(i) = rand_vec(g, 1.0).transpose();
  }
  RowMatrixX3d F, ref = RowMatrixX3d::Zero(s.x.rows(), 3);
  w.internal_forces(s, F);
  for (int b = 0; b < w.bodies(); ++b) {
    const Body& B = w.body(b);
    const int r0 = w.first_state_row(b);
    auto X = [&](int i) { return Vector3d(s.x.row(r0 + i)); };
    auto V = [&](int i) { return Vector3d(s.v.row(r0 + i)); };
    for (int e = 0; e < B.E.rows(); ++e) {
      Vector3d fi, fj;
      distance_forces(X(B.E(e, 0)), X(B.E(e, 1)), V(B.E(e, 0)), V(B.E(e, 1)), B.D0(e), B.k_edge(e), B.kd_edge(e), fi,
                      fj);
      ref.row(r0 + B.E(e, 0)) += fi.transpose();
      ref.row(r0 + B.E(e, 1)) += fj.transpose();
    }
    for (int t = 0; t < B.tets(); ++t) {
      Vector3d p[4], v[4], f[4];
      for (int k = 0; k < 4; ++k) p[k] = X(B.T(t, k)), v[k] = V(B.T(t, k));
      volume_forces(p, v, B.V0(t), B.k_tet(t), B.kd_tet(t), f);
      for (int k = 0; k < 4; ++k) ref.row(r0 + B.T(t, k)) += f[k].transpose();
    }
  }
  const double scale = ref.cwiseAbs().maxCoeff();
  EXPECT_GT(scale, 1.0);
  EXPECT_LT((F - ref).cwiseAbs().maxCoeff(), 1e-12 * scale);
  expect_no_net_force_or_torque(s, F);
}

TEST(FemWorld, ForcesAreMinusFiniteDifferenceGradient) {
  Material m;
  m.k_distance = 20;
  m.k_volume = 50;
  World w(no_gravity());
  w.add_body(Body(cube(1.0, 2), m));
  State s = w.initial_state();
  std::mt19937 g(3);
  for (int i = 0; i < s.x.rows(); ++i) s.x.row(i) += rand_vec(g, 0.2).transpose();
  RowMatrixX3d F;
  w.internal_forces(s, F);
  const double eps = 1e-6;
  for (int i = 0; i < s.x.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      State a = s, b = s;
      a.x(i, c) += eps;
      b.x(i, c) -= eps;
      const double d = (w.elastic_energy(a) - w.elastic_energy(b)) / (2 * eps);
      EXPECT_NEAR(F(i, c), -d, 1e-5 * (1 + std::abs(d)));
    }
}

TEST(FemWorld, InvertedTetrahedronRecoversItsVolume) {
  TetMesh t;
  t.V.resize(4, 3);
  t.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  t.T.resize(1, 4);
  t.T << 0, 1, 2, 3;
  Material m;
  m.k_distance = 10;
  m.k_volume = 10;
  m.damping_distance = 5;
  m.damping_volume = 5;
  m.density = 100;
  WorldOptions o = no_gravity();
  o.h = 1e-3;
  World w(o);
  w.add_body(Body(t, m));
  State s = w.initial_state();
  s.x(3, 2) = -0.5;  // through the opposite face: inverted
  ASSERT_LT(w.body_volume(s, 0), 0.0);
  for (int n = 0; n < 20000; ++n) w.step(s);
  EXPECT_NEAR(w.body_volume(s, 0), 1.0 / 6.0, 0.02 / 6.0);
}

TEST(FemWorld, DampedMotionNeverGainsEnergy) {
  Material m;
  m.k_distance = 100;
  m.k_volume = 100;
  m.damping_distance = 0.02;
  m.damping_volume = 0.02;
  WorldOptions o = no_gravity();
  o.h = 1e-4;
  World w(o);
  w.add_body(Body(cube(0.1, 2), m));
  State s = w.initial_state();
  std::mt19937 g(5);
  for (int i = 0; i < s.x.rows(); ++i) s.x.row(i) += rand_vec(g, 0.01).transpose();
  State next = s;
  w.step(next);
  const double e0 = central_energy(w, s, next);
  double e = e0;
  for (int n = 0; n < 20000; ++n) {
    s = next;
    w.step(next);
    const double en = central_energy(w, s, next);
    ASSERT_LE(en, e * (1 + 1e-9) + 1e-15) << "step " << n;
    e = en;
  }
  EXPECT_LT(e, 0.5 * e0);
}

TEST(FemWorld, UndampedMotionConservesEnergy) {
  Material m;
  m.k_distance = 100;
  m.k_volume = 100;
  WorldOptions o = no_gravity();
  o.h = 1e-4;
  World w(o);
  w.add_body(Body(cube(0.1, 1), m));
  State s = w.initial_state();
  std::mt19937 g(11);
  for (int i = 0; i < s.x.rows(); ++i) s.x.row(i) += rand_vec(g, 0.01).transpose();
  State next = s;
  w.step(next);
  const double e0 = central_energy(w, s, next);
  ASSERT_GT(e0, 0);
  double worst = 0;
  for (int n = 0; n < 100000; ++n) {
    s = next;
    w.step(next);
    worst = std::max(worst, std::abs(central_energy(w, s, next) - e0));
  }
  EXPECT_LT(worst, 0.01 * e0);
}

namespace {

struct HashScene {
  RowMatrixX3d X;
  Eigen::MatrixX4i T;
  CollisionFilter filter;
};

// Two overlapping balls, a rigid box, random jitter (self-intersections included).
HashScene hash_scene(unsigned seed) {
  std::mt19937 g(seed);
  const TetMesh a = ball_tet_mesh(0.5, 3), b = ball_tet_mesh(0.4, 3), c = cube(1.0, 2, Vector3d(-0.2, -1.0, -0.5));
  HashScene s;
  const TetMesh* ms[3] = {&a, &b, &c};
  const Vector3d shift[3] = {Vector3d::Zero(), Vector3d(0.6, 0.1, 0), Vector3d::Zero()};
  int nv = 0, nt = 0;
  for (auto* m : ms) nv += m->V.rows(), nt += m->T.rows();
  s.X.resize(nv, 3);
  s.T.resize(nt, 4);
  int fv = 0, ft = 0;
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < ms[k]->V.rows(); ++i) {
      s.X.row(fv + i) = ms[k]->V.row(i) + shift[k].transpose() + rand_vec(g, 0.08).transpose();
      s.filter.vertex_group.push_back(k);
    }
    for (int t = 0; t < ms[k]->T.rows(); ++t) {
      s.T.row(ft + t) = ms[k]->T.row(t).array() + fv;
      s.filter.tet_group.push_back(k);
    }
    fv += ms[k]->V.rows();
    ft += ms[k]->T.rows();
  }
  s.filter.group_rigid = {0, 0, 1};
  std::mt19937 g2(seed + 100);  // some vertices interior (tested only against other objects)
  for (int v = 0; v < nv; ++v) s.filter.vertex_on_surface.push_back(g2() % 3 != 0);
  return s;
}

std::vector<std::pair<int, int>> pairs(const std::vector<Contact>& c) {
  std::vector<std::pair<int, int>> p;
  for (const auto& x : c) p.emplace_back(x.tet, x.vertex);
  std::sort(p.begin(), p.end());
  return p;
}

}  // namespace

TEST(FemCollision, SpatialHashMatchesBruteForce) {
  for (unsigned seed : {1u, 2u}) {
    HashScene s = hash_scene(seed);
    for (int variant = 0; variant < 3; ++variant) {
      s.filter.self_collision = variant != 1;
      if (variant == 2) s.filter.vertex_on_surface.clear();
      const auto ref = pairs(find_contacts_brute_force(s.X, s.T, s.filter));
      ASSERT_FALSE(ref.empty());
      for (double cell : {0.05, 0.2, 2.0})
        for (int table : {1, 7, 1009, 100003}) {
          SpatialHash h(cell, table);
          EXPECT_EQ(pairs(h.find(s.X, s.T, s.filter)), ref) << "cell " << cell << " table " << table;
          EXPECT_EQ(pairs(h.find(s.X, s.T, s.filter)), ref) << "second query, cell " << cell;  // time stamps
        }
    }
  }
  EXPECT_THROW(SpatialHash(0.0, 10), InputError);
  EXPECT_THROW(SpatialHash(1.0, 0), InputError);
}

TEST(FemCollision, DeepPenetrationPointsOutOfTheEnteredSide) {
  // A ball (r = 0.05) sunk into a rigid plate y in [-0.1, 0] down to y = -0.08: its lowest
  // vertices are nearer the plate's bottom face, but the ball entered from the top.
  Body plate(box_tet_mesh(Vector3d(-0.3, -0.1, -0.3), Vector3d(0.3, 0.0, 0.3), Eigen::Vector3i(6, 2, 6)), Material{},
             true);
  Eigen::Affine3d at = Eigen::Affine3d::Identity();
  at.translation() = Vector3d(0.013, -0.03, 0.007);
  Body ball(ball_tet_mesh(0.05, 4), Material{}, false, at);
  CollisionScene scene;
  scene.bodies = {&ball, &plate};
  scene.first_vertex = {0, ball.vertices()};
  scene.first_tet = {0, ball.tets()};
  RowMatrixX3d X(ball.vertices() + plate.vertices(), 3);
  X << ball.rest, plate.rest;
  Eigen::MatrixX4i T(ball.tets() + plate.tets(), 4);
  T << ball.T, (plate.T.array() + ball.vertices()).matrix();
  CollisionFilter f;
  f.vertex_group.assign(ball.vertices(), 0);
  f.vertex_group.resize(X.rows(), 1);
  f.tet_group.assign(ball.tets(), 0);
  f.tet_group.resize(T.rows(), 1);
  f.group_rigid = {0, 1};
  SpatialHash h(ball.mean_edge_length(), 1009);
  const auto contacts = h.find(X, T, f);
  const auto pens = penetration_depths(scene, X, contacts);
  int inside = 0;
  for (int i = 0; i < ball.vertices(); ++i) inside += ball.rest(i, 1) < -1e-9;
  ASSERT_GT(inside, 20);
  int found = 0;
  double deepest = 0;
  for (const auto& p : pens) {
    if (p.vertex >= ball.vertices()) continue;  // plate vertices inside the ball: the ball's side
    ++found;
    EXPECT_GT(p.direction.y(), 0.95) << "vertex " << p.vertex << " layer " << p.layer;
    EXPECT_NEAR(p.depth, -X(p.vertex, 1), 0.006) << "vertex " << p.vertex << " layer " << p.layer;
    deepest = std::max(deepest, p.depth);
  }
  EXPECT_GE(found, inside - 2);
  EXPECT_GT(deepest, 0.07);
}

namespace {

Vector3d centroid(const World& w, const State& s, int b) {
  return s.x.middleRows(w.first_state_row(b), w.body(b).vertices()).colwise().mean().transpose();
}

double centroid_gap(const World& w, const State& s) { return (centroid(w, s, 1) - centroid(w, s, 0)).norm(); }

// Two balls driven into each other over a rigid slab with gravity and a floor: a busy scene.
// n: cells per axis of the balls (4: one element group per ball; 7: three, forces in parallel).
World busy_world(int n = 4) {
  WorldOptions o;
  o.h = 1e-4;
  o.parallel = {0, 0, 0, 0};  // every pass in parallel, however small (with 2 threads)
  o.floor = true;
  o.floor_height = -0.3;
  o.contact_stiffness = 2e3;
  o.contact_damping = 0.5;
  World w(o);
  Material m;
  m.k_distance = 5;
  m.k_volume = 5;
  m.damping_distance = 0.002;
  m.damping_volume = 0.002;
  Eigen::Affine3d a = Eigen::Affine3d::Identity(), b = a;
  a.translation() = Vector3d(-0.12, 0, 0);
  b.translation() = Vector3d(0.12, 0.02, 0.01);
  w.add_body(Body(ball_tet_mesh(0.1, n), m, false, a));
  w.add_body(Body(ball_tet_mesh(0.1, n), m, false, b));
  w.add_body(Body(box_tet_mesh(Vector3d(-0.5, -0.2, -0.5), Vector3d(0.5, -0.1, 0.5), Eigen::Vector3i(5, 1, 5)),
                  Material{}, true));
  return w;
}

State run_busy(int threads, int steps, int* ball_contact_steps, int n = 4) {
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  World w = busy_world(n);
  State s = w.initial_state();
  RowMatrixX3d ext = RowMatrixX3d::Zero(s.x.rows(), 3);
  for (int i = 0; i < w.body(0).vertices(); ++i) ext(i, 0) = 5.0 * w.masses()(i);
  for (int i = 0; i < w.body(1).vertices(); ++i) {
    const int r = w.first_state_row(1) + i;
    ext(r, 0) = -5.0 * w.masses()(r);
  }
  *ball_contact_steps = 0;
  for (int n = 0; n < steps; ++n) {
    w.step(s, &ext);
    *ball_contact_steps += w.last_stats().colliding_vertices > 0 &&
                           centroid_gap(w, s) < 0.2;  // balls (radius 0.1) overlap
  }
  return s;
}

// The busy scene stepped `steps` steps with 1 and with 2 threads: the balls (n cells per axis)
// collide at least `min_touch` steps, and the states are equal bit for bit.
void expect_bit_identical_with_1_and_2_threads(int n, int steps, int min_touch) {
  int touch1 = 0, touch2 = 0;
  const State a = run_busy(1, steps, &touch1, n), b = run_busy(2, steps, &touch2, n);
  EXPECT_GT(touch1, min_touch);  // the balls did collide
  EXPECT_EQ(touch1, touch2);
  ASSERT_EQ(a.x.size(), b.x.size());
  EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), sizeof(double) * a.x.size()), 0);
  EXPECT_EQ(std::memcmp(a.v.data(), b.v.data(), sizeof(double) * a.v.size()), 0);
  EXPECT_TRUE(a.x.allFinite());
}

}  // namespace

// The parallel thresholds are 0 here: with 2 threads every pass (element forces, detection,
// penetration depths) runs in parallel even on these small balls.
TEST(FemWorld, BitIdenticalWhateverTheThreadCount) { expect_bit_identical_with_1_and_2_threads(4, 1500, 50); }

// Finer balls: several element groups per object, the force pass in parallel.
TEST(FemWorld, BitIdenticalWhateverTheThreadCountWithManyElementGroups) {
  expect_bit_identical_with_1_and_2_threads(7, 1200, 20);
}

TEST(FemPhysics, CubeDroppedOnRigidFloorComesToRest) {
  WorldOptions o;
  o.h = 1e-4;
  o.contact_stiffness = 1e5;
  o.contact_damping = 20;
  World w(o);
  Material m;
  m.k_distance = 50;
  m.k_volume = 50;
  m.damping_distance = 0.05;
  m.damping_volume = 0.05;
  const double L = 0.2;
  w.add_body(Body(cube(L, 3, Vector3d(-0.1, 0.1, -0.1)), m));
  w.add_body(Body(box_tet_mesh(Vector3d(-1, -0.2, -1), Vector3d(1, 0, 1), Eigen::Vector3i(4, 1, 4)), Material{}, true));
  State s = w.initial_state();
  const double v0 = w.body_volume(s, 0);
  double peak = 0, lowest = 1;
  for (int n = 0; n < 20000; ++n) {
    w.step(s);
    peak = std::max(peak, w.kinetic_energy(s));
    if (n > 10000) lowest = std::min(lowest, s.x.col(1).minCoeff());
  }
  EXPECT_GT(peak, 0.5 * 8.0 * 9.81 * 0.09);  // it did fall
  EXPECT_LT(w.kinetic_energy(s), 0.01 * peak);
  EXPECT_GT(lowest, -0.01 * L);              // penetration below 1% of its size
  EXPECT_LT(s.x.col(1).minCoeff(), 0.01 * L);  // resting on the floor, not floating
  EXPECT_NEAR(w.body_volume(s, 0), v0, 0.03 * v0);
}

TEST(FemPhysics, SpheresDrivenHeadOnDoNotPassThrough) {
  WorldOptions o;
  o.h = 1e-4;
  o.gravity.setZero();
  o.contact_stiffness = 2e4;
  o.contact_damping = 2;
  World w(o);
  Material m;
  m.k_distance = 5;
  m.k_volume = 5;
  m.damping_distance = 0.002;
  m.damping_volume = 0.002;
  Eigen::Affine3d a = Eigen::Affine3d::Identity(), b = a;
  a.translation() = Vector3d(-0.15, 0, 0);
  b.translation() = Vector3d(0.15, 0.01, 0);
  w.add_body(Body(ball_tet_mesh(0.1, 4), m, false, a));
  w.add_body(Body(ball_tet_mesh(0.1, 4), m, false, b));
  State s = w.initial_state();
  RowMatrixX3d ext = RowMatrixX3d::Zero(s.x.rows(), 3);
  int touching = 0;
  double closest = 1;
  for (int n = 0; n < 10000; ++n) {
    // 10 m/s² driving each ball towards the other's centroid.
    const Vector3d c0 = centroid(w, s, 0), c1 = centroid(w, s, 1);
    const Vector3d dir = (c1 - c0).normalized();
    closest = std::min(closest, (c1 - c0).norm());
    for (int i = 0; i < s.x.rows(); ++i)
      ext.row(i) = ((i < w.body(0).vertices() ? 10.0 : -10.0) * w.masses()(i) * dir).transpose();
    w.step(s, &ext);
    touching += w.last_stats().colliding_vertices > 0;
  }
  EXPECT_GT(touching, 100);
  // Centroids stay about 3/4 of a diameter apart: no pass-through. (0.148 since volume weighting:
  // the balls' surface edges, shared by fewer tets, are softer than the interior ones.)
  EXPECT_GT(closest, 0.14);
  EXPECT_TRUE(s.x.allFinite());
}

TEST(FemPhysics, PinnedPlateSagsAndStaysAttached) {
  WorldOptions o;
  o.h = 5e-5;
  o.collisions = false;
  World w(o);
  Material m;
  m.k_distance = 50;
  m.k_volume = 50;
  m.damping_distance = 0.05;
  m.damping_volume = 0.05;
  w.add_body(Body(box_tet_mesh(Vector3d(0, 0, 0), Vector3d(0.5, 0.04, 0.2), Eigen::Vector3i(10, 1, 4)), m));
  const int pinned = w.pin(Eigen::AlignedBox3d(Vector3d(-1, -1, -1), Vector3d(1e-9, 1, 1)));
  EXPECT_EQ(pinned, 2 * 5);
  State s = w.initial_state();
  const State s0 = s;
  const Body& B = w.body(0);
  double mean_tip = 0;  // mean tip displacement over the last 10000 steps (it still oscillates)
  for (int n = 0; n < 20000; ++n) {
    w.step(s);
    if (n >= 10000)
      for (int i = 0; i < B.vertices(); ++i)
        if (B.rest(i, 0) > 0.499) mean_tip += (s.x(i, 1) - s0.x(i, 1)) / 10000 / 10;  // 10 tip vertices
  }
  double max_strain = 0;
  for (int i = 0; i < B.vertices(); ++i)
    if (w.pinned(i)) {
      EXPECT_EQ((s.x.row(i) - s0.x.row(i)).norm(), 0.0);
    }
  for (int e = 0; e < B.E.rows(); ++e)
    max_strain = std::max(max_strain, std::abs((s.x.row(B.E(e, 1)) - s.x.row(B.E(e, 0))).norm() / B.D0(e) - 1));
  EXPECT_LT(mean_tip, -0.005);  // sags
  EXPECT_LT(max_strain, 0.3);   // attached: no edge torn
  EXPECT_TRUE(s.x.allFinite());
}

// ---- Volume weighting, mass scaling, deformation damping (issue 5: meshed surfaces' time step) ----

namespace {

// A cube [-1, 1]³ (n cells per axis) whose vertices are pulled towards the centre, p ← p |p|∞²: the
// tets at the centre are (n/2)² times smaller (in edge length) than those at the surface.
TetMesh graded_box(int n) {
  TetMesh m = box_tet_mesh(Vector3d::Constant(-1), Vector3d::Constant(1), Eigen::Vector3i::Constant(n));
  for (int v = 0; v < m.V.rows(); ++v) {
    const double r = m.V.row(v).cwiseAbs().maxCoeff();
    m.V.row(v) *= r * r;
  }
  return m;
}

}  // namespace

TEST(FemBody, VolumeWeightedCoefficients) {
  Material m;
  m.k_distance = 7;
  m.k_volume = 11;
  m.damping_distance = 0.5;
  m.damping_volume = 0.25;
  const Body b(graded_box(6), m);
  ASSERT_TRUE(m.volume_weighted);  // the default
  // Each tet shares its volume among its 6 edges; stiffness ∝ represented volume, mean = k.
  EXPECT_NEAR(b.edge_volume.sum(), b.total_volume(), 1e-12);
  EXPECT_NEAR(b.k_edge.mean(), 7.0, 1e-12);
  EXPECT_NEAR(b.k_tet.mean(), 11.0, 1e-12);
  for (int e = 0; e < b.E.rows(); ++e) {
    EXPECT_NEAR(b.k_edge(e), 7.0 * b.edge_volume(e) / b.edge_volume.mean(), 1e-9);
    EXPECT_NEAR(b.kd_edge(e) / b.k_edge(e), 0.5 / 7.0, 1e-12);
  }
  for (int t = 0; t < b.tets(); ++t) EXPECT_NEAR(b.k_tet(t), 11.0 * b.V0(t) / b.V0.mean(), 1e-9);
  EXPECT_GT(b.k_tet.maxCoeff() / b.k_tet.minCoeff(), 20.0);  // graded: coefficients really vary
  // Unweighted: uniform coefficients (the paper as written).
  m.volume_weighted = false;
  const Body u(graded_box(6), m);
  EXPECT_EQ(u.k_edge.minCoeff(), 7.0);
  EXPECT_EQ(u.k_edge.maxCoeff(), 7.0);
  EXPECT_EQ(u.k_tet.maxCoeff(), 11.0);
  EXPECT_EQ(u.added_mass, 0.0);
  m.mass_scaling = 0.5;
  EXPECT_THROW(Body(graded_box(3), m), InputError);
  m.mass_scaling = 0;
  m.deformation_damping = -1;
  EXPECT_THROW(Body(graded_box(3), m), InputError);
}

TEST(FemWorld, VolumeWeightedRestZeroForceBalanceAndGradient) {
  Material m;
  m.k_distance = 20;
  m.k_volume = 50;
  m.damping_distance = 0.3;
  m.damping_volume = 0.2;
  World w(no_gravity());
  w.add_body(Body(graded_box(4), m));
  State s = w.initial_state();
  RowMatrixX3d F;
  w.internal_forces(s, F);
  EXPECT_EQ(F.cwiseAbs().maxCoeff(), 0.0);  // rest is an equilibrium
  std::mt19937 g(17);
  for (int i = 0; i < s.x.rows(); ++i) {
    s.x.row(i) += rand_vec(g, 0.01).transpose();
    s.v.row(i) = rand_vec(g, 1.0).transpose();
  }
  w.internal_forces(s, F);
  expect_no_net_force_or_torque(s, F);
  // Elastic forces are minus the gradient of elastic_energy (same weighted coefficients).
  s.v.setZero();
  w.internal_forces(s, F);
  const double eps = 1e-7;
  for (int i = 0; i < s.x.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      State a = s, b = s;
      a.x(i, c) += eps;
      b.x(i, c) -= eps;
      const double d = (w.elastic_energy(a) - w.elastic_energy(b)) / (2 * eps);
      EXPECT_NEAR(F(i, c), -d, 1e-5 * (1 + F.row(i).norm())) << i << "," << c;
    }
}

TEST(FemWorld, VolumeWeightingAndMassScalingKeepTheStableStep) {
  // The graded box's central tets are 16 times smaller (edge length) than its surface ones: with uniform
  // stiffnesses the stable step collapses; weighted, it follows the edge lengths, and mass
  // scaling removes the outliers for a tiny fraction of the mass.
  auto step_of = [](bool weighted, double kappa, double* added) {
    Material m;
    m.k_distance = m.k_volume = 100;
    m.volume_weighted = weighted;
    m.mass_scaling = kappa;
    World w(no_gravity());
    w.add_body(Body(graded_box(8), m));
    if (added) *added = w.body(0).added_mass / w.body(0).mass.sum();
    return stable_time_step(w);
  };
  double added = 0;
  const double uniform = step_of(false, 0, nullptr), weighted = step_of(true, 0, nullptr),
               scaled = step_of(true, 1.5, &added);
  std::printf("graded box: stable step uniform %.3g s, weighted %.3g s, + mass scaling %.3g s (%.3g %% mass added)\n",
              uniform, weighted, scaled, 100 * added);
  EXPECT_GT(weighted, 8 * uniform);
  EXPECT_GT(scaled, 1.5 * weighted);
  EXPECT_GT(added, 0.0);
  EXPECT_LT(added, 0.05);
}

TEST(FemPhysics, SagDoesNotDependOnTheResolution) {
  // A column 0.1 × 0.5 × 0.1 m hanging from its top face under its own weight, E = 1e6 Pa with the
  // scene loader's defaults (k_distance = E V / #edges, k_volume = 3 E V / #tets), settled by
  // deformation damping: the sag of its bottom (~1 mm) must not depend on the mesh resolution.
  // (A bending test would not do: linear tets with a stiff volume constraint lock in bending, so a
  // coarse cantilever is too stiff whatever the weighting.)
  auto sag = [](int n) {
    const TetMesh mesh = box_tet_mesh(Vector3d::Zero(), Vector3d(0.1, 0.5, 0.1), Eigen::Vector3i(n, 5 * n, n));
    Material m;
    const Body probe(mesh, m);
    const double E = 1e6, V = probe.total_volume();
    m.k_distance = E * V / probe.E.rows();
    m.k_volume = 3 * E * V / probe.tets();
    m.deformation_damping = 100;
    m.mass_scaling = 1.5;
    const Eigen::AlignedBox3d top(Vector3d(-1, 0.5 - 1e-9, -1), Vector3d(1, 1, 1));
    WorldOptions o;
    o.collisions = false;
    World probe_world(o);
    probe_world.add_body(Body(mesh, m));
    o.h = 0.9 * stable_time_step(probe_world);
    World w(o);
    w.add_body(Body(mesh, m));
    w.pin(top);
    State s = w.initial_state();
    const int steps = static_cast<int>(1.0 / o.h);
    for (int k = 0; k < steps; ++k) w.step(s);
    EXPECT_LT(w.kinetic_energy(s), 1e-6) << "n " << n;  // settled (5 kg)
    double d = 0;
    int bottom = 0;
    for (int i = 0; i < w.body(0).vertices(); ++i)
      if (w.body(0).rest(i, 1) < 1e-9) d += s.x(i, 1) - w.body(0).rest(i, 1), ++bottom;
    return d / bottom;
  };
  const double coarse = sag(1), fine = sag(2);
  std::printf("hanging column: sag %.4g m (1 cell across), %.4g m (2 cells across)\n", coarse, fine);
  // It stretches by ρ g L² / 2E' = 4.3 mm: the effective modulus E' of these defaults is about E / 3.5.
  EXPECT_LT(coarse, -2e-3);
  EXPECT_GT(coarse, -8e-3);
  EXPECT_NEAR(fine / coarse, 1.0, 0.15) << "coarse " << coarse << " fine " << fine;
}

TEST(FemWorld, DeformationDampingKeepsMomentumAndRigidMotion) {
  Material m;
  m.k_distance = m.k_volume = 100;
  m.deformation_damping = 50;
  WorldOptions o = no_gravity();
  o.h = 1e-4;
  World w(o);
  w.add_body(Body(cube(0.1, 2), m));
  State s = w.initial_state();
  // Rigid motion: translation + rotation about the centre is kept exactly (up to rounding).
  const Vector3d vc(0.3, -0.2, 0.1), om(1, 2, -3), c(0.05, 0.05, 0.05);
  for (int i = 0; i < s.x.rows(); ++i) s.v.row(i) = (vc + om.cross(Vector3d(s.x.row(i)) - c)).transpose();
  const State s0 = s;
  w.step(s);
  for (int i = 0; i < s.x.rows(); ++i) EXPECT_LT((s.v.row(i) - s0.v.row(i)).norm(), 1e-3) << i;  // only elastic (centrifugal) change
  // A deformation dies out while the momentum stays.
  std::mt19937 g(23);
  for (int i = 0; i < s.x.rows(); ++i) s.v.row(i) = rand_vec(g, 1.0).transpose();
  auto momentum = [&](const State& st) {
    Vector3d p = Vector3d::Zero();
    for (int i = 0; i < st.v.rows(); ++i) p += w.masses()(i) * Vector3d(st.v.row(i));
    return p;
  };
  const Vector3d p0 = momentum(s);
  const double e0 = w.kinetic_energy(s);
  const Body& B = w.body(0);
  auto max_rate = [&](const State& st) {  // fastest change of an edge length (m/s)
    double r = 0;
    for (int e = 0; e < B.E.rows(); ++e) {
      const Vector3d d = st.x.row(B.E(e, 1)) - st.x.row(B.E(e, 0)), dv = st.v.row(B.E(e, 1)) - st.v.row(B.E(e, 0));
      r = std::max(r, std::abs(d.normalized().dot(dv)));
    }
    return r;
  };
  const double rate0 = max_rate(s);
  for (int k = 0; k < 2000; ++k) w.step(s);  // 0.2 s: e^(−αt) = e^(−10)
  EXPECT_LT((momentum(s) - p0).norm(), 1e-9 * (1 + p0.norm()));
  // What is left is a rigid motion: edges hardly change their lengths (amplitude e^(−αt/2) = e^(−5)).
  double speed = 0;
  for (int i = 0; i < s.v.rows(); ++i) speed = std::max(speed, s.v.row(i).norm());
  EXPECT_GT(speed, 0.1);  // it still moves (momentum, angular momentum)
  EXPECT_LT(max_rate(s), 0.03 * rate0);
  EXPECT_LT(w.kinetic_energy(s), e0);
}

// Issue 15: a World is a value. A copy shares the rest data, steps bit for bit like the original,
// and changing one (a body, a pin, the time step) leaves the other as it was.
TEST(FemWorld, CopiesStepLikeTheOriginalAndChangeIndependently) {
  World a = busy_world(4);
  a.prepare();
  World b = a;
  State sa = a.initial_state(), sb = b.initial_state();
  for (int k = 0; k < 200; ++k) {
    a.step(sa);
    b.step(sb);
  }
  EXPECT_EQ(std::memcmp(sa.x.data(), sb.x.data(), sizeof(double) * sa.x.size()), 0);
  EXPECT_EQ(std::memcmp(sa.v.data(), sb.v.data(), sizeof(double) * sa.v.size()), 0);
  // A new time step for the copy only; nothing rebuilt, the original keeps its own.
  b.set_time_step(5e-5);
  EXPECT_EQ(b.time_step(), 5e-5);
  EXPECT_EQ(a.time_step(), 1e-4);
  State s1 = a.initial_state(), s2 = s1;
  a.step(s1);
  b.step(s2);
  EXPECT_NEAR(s1.time, 1e-4, 1e-18);
  EXPECT_NEAR(s2.time, 5e-5, 1e-18);
  // Pinning a vertex of the copy does not pin the original's.
  World c = a;
  c.pin_vertex(0);
  EXPECT_TRUE(c.pinned(0));
  EXPECT_FALSE(a.pinned(0));
  // A body added to the copy only.
  World d = a;
  d.add_body(Body(ball_tet_mesh(0.05, 3), Material{}, false));
  EXPECT_EQ(d.bodies(), a.bodies() + 1);
  EXPECT_GT(d.state_rows(), a.state_rows());
  State sd = d.initial_state();
  d.step(sd);
  EXPECT_TRUE(sd.x.allFinite());
}

// Issue 15: the force assembly is thread-safe on one const World with one workspace per thread,
// and World::total_forces is the same assembly.
TEST(FemWorld, AssemblyWithSeparateWorkspacesIsThreadSafe) {
  World w = busy_world(7);
  w.prepare();
  State s = w.initial_state();
  RowMatrixX3d ext = RowMatrixX3d::Zero(s.x.rows(), 3);
  for (int k = 0; k < 400; ++k) w.step(s);  // a deformed state with contacts
  RowMatrixX3d F;
  w.total_forces(s, nullptr, F);
  ASSERT_GT(w.last_stats().contacts, 0);
  const World& cw = w;
  std::vector<RowMatrixX3d> got(8);
  tbb::parallel_for(0, 8, [&](int i) {
    ForceWorkspace ws;
    assemble_forces(cw, s, &ext, ws, got[i]);
  });
  for (const RowMatrixX3d& G : got) EXPECT_EQ(std::memcmp(G.data(), F.data(), sizeof(double) * F.size()), 0);
  // internal_only: no gravity, floor or contacts.
  ForceWorkspace ws;
  RowMatrixX3d I, J;
  assemble_forces(cw, s, nullptr, ws, I, ForceTerms::internal_only());
  w.internal_forces(s, J);
  EXPECT_EQ(std::memcmp(I.data(), J.data(), sizeof(double) * I.size()), 0);
  EXPECT_GT((F - I).norm(), 0.0);
}

// Issue 15: integrators come from one registry; an unknown one is named.
TEST(FemIntegrator, RegistryMakesTheRegisteredOnesAndNamesThemOtherwise) {
  const std::vector<std::string> names = integrator_names();
  ASSERT_FALSE(names.empty());
  EXPECT_EQ(names[0], "verlet");
  for (const std::string& n : names) {
    const std::unique_ptr<TimeIntegrator> i = make_integrator(n);
    EXPECT_EQ(i->name(), n);
    EXPECT_EQ(i->clone()->name(), n);
  }
  try {
    make_integrator("euler");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown integrator \"euler\" (known: \"verlet\""), std::string::npos) << e.what();
  }
  WorldOptions o;
  o.integrator = "euler";
  EXPECT_THROW(World{o}, InputError);
}

// Issue 15: gravity is per body in the world: an object without it feels no net force at rest,
// and the interpolation of the planner reads it from the world.
TEST(FemWorld, GravityIsPerBody) {
  WorldOptions o;
  o.h = 1e-4;
  o.collisions = false;
  World w(o);
  Material m;
  m.k_distance = m.k_volume = 10;
  Body floating(ball_tet_mesh(0.1, 3), m, false);
  floating.gravity = false;
  w.add_body(floating);
  Eigen::Affine3d far = Eigen::Affine3d::Identity();
  far.translation() = Vector3d(1, 0, 0);
  w.add_body(Body(ball_tet_mesh(0.1, 3), m, false, far));
  EXPECT_EQ(w.gravity_of(0), Vector3d::Zero());
  EXPECT_EQ(w.gravity_of(1), o.gravity);
  State s = w.initial_state();
  RowMatrixX3d F;
  w.total_forces(s, nullptr, F);
  const int n0 = w.body(0).vertices();
  EXPECT_LT(F.topRows(n0).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(F.bottomRows(F.rows() - n0).cwiseAbs().maxCoeff(), 1e-6);
  for (int k = 0; k < 100; ++k) w.step(s);
  EXPECT_LT((s.x.topRows(n0) - w.body(0).rest).cwiseAbs().maxCoeff(), 1e-12);
}

// ---- Soft attachments (issue 18): zero-length springs to the rest position ----

namespace {

using sqt::attached_cube;

double mean_sag(const World& w, const State& s) {
  double sag = 0;
  for (int i = 0; i < w.state_rows(); ++i) sag += w.body(0).rest(i, 1) - s.x(i, 1);
  return sag / w.state_rows();
}

}  // namespace

// Issue 18: an attachment that carries its vertices' weight holds them in equilibrium at rest:
// zero net force at the rest state, and neither integrator moves them (where the same springs
// without carries_weight sag by M g / (N k)).
TEST(FemAttachment, CarriedWeightStartsInEquilibrium) {
  for (const char* integrator : {"verlet", "implicit"}) {
    const bool verlet = std::string(integrator) == "verlet";
    World w = attached_cube(integrator, 50, 0.5, true);
    w.set_time_step(verlet ? stable_time_step(w) : 1.0 / 30);
    State s = w.initial_state();
    RowMatrixX3d F;
    ForceWorkspace ws;
    w.prepare();
    assemble_forces(w, s, nullptr, ws, F);
    EXPECT_LT(F.cwiseAbs().maxCoeff(), 1e-9 * w.masses().maxCoeff() * 9.81) << integrator;
    const int steps = static_cast<int>(0.5 / w.options().h);  // half a second
    for (int n = 0; n < steps; ++n) w.step(s);
    EXPECT_LT(std::abs(mean_sag(w, s)), 1e-9) << integrator;
    World plain = attached_cube(integrator, 50, 0.5, false);
    plain.set_time_step(w.options().h);
    State p = plain.initial_state();
    for (int n = 0; n < steps; ++n) plain.step(p);
    EXPECT_GT(mean_sag(plain, p), 5e-4) << integrator;  // the same springs without the weight: they sag
  }
  World w = attached_cube("verlet", 0, 0.5);
  EXPECT_THROW(w.attach(0, 0, 1, true), squeeze::InputError);
}

TEST(FemAttachment, SettledSagIsWeightOverStiffnessWithVerlet) {
  const double k = 200, c = 1.0;
  World w = attached_cube("verlet", k, c);
  EXPECT_EQ(w.attachment_stiffness(5), k);
  EXPECT_EQ(w.attachment_damping(5), c);
  w.set_time_step(stable_time_step(w));
  State s = w.initial_state();
  for (int n = 0; n < static_cast<int>(3.0 / w.time_step()); ++n) w.step(s);
  const double M = w.masses().sum(), expected = M * 9.81 / (w.state_rows() * k);
  EXPECT_GT(expected, 1e-3);  // a visible sag (1.8 mm)
  EXPECT_NEAR(mean_sag(w, s), expected, 1e-3 * expected);
  EXPECT_LT(s.v.cwiseAbs().maxCoeff(), 1e-5);  // settled
  // The force of the one assembly at the settled state: the attachments cancel gravity.
  RowMatrixX3d F;
  w.total_forces(s, nullptr, F);
  EXPECT_LT(F.colwise().sum().norm(), 1e-6 * M * 9.81);
}

// The attachment's k / m and c / m enter the per-vertex frequency bound: a stiff attachment on
// light vertices lowers the automatic step, the Verlet step at that bound stays stable, and a step
// well above it (2.5×, beyond the exact limit 2 / ω of the attachment's oscillation) diverges.
TEST(FemAttachment, StableStepCountsTheAttachmentAndKeepsVerletStable) {
  World free_cube = attached_cube("verlet", 0, 0);
  const double h_elastic = stable_time_step(free_cube);
  const double k = 3e8;  // ω = sqrt(k / m) about 6 times the cube's highest elastic frequency
  World w = attached_cube("verlet", k, 0);
  const double h = stable_time_step(w);
  const double m_max = w.masses().maxCoeff();
  EXPECT_LT(h, h_elastic / 5);                     // the attachment sets it
  EXPECT_LE(h, std::sqrt(m_max / k) * (1 + 1e-12));  // ... below 1/ω of the heaviest vertex's spring
  World c = attached_cube("verlet", k, 0);
  Scene sc;
  sc.integrator = "verlet";
  sc.objects.resize(1);
  sc.objects[0].name = "cube";
  EXPECT_EQ(auto_time_step(c, sc).term, "attachment");
  auto run = [&](double step) {
    World x = attached_cube("verlet", k, 0);
    x.set_time_step(step);
    State s = x.initial_state();
    const State s0 = s;
    s.x.col(1).array() += 1e-3;  // displaced: the springs oscillate
    double worst = 0;
    for (int n = 0; n < 3000; ++n) {
      x.step(s);
      if (!s.x.allFinite()) return 1e300;
      worst = std::max(worst, (s.x - s0.x).cwiseAbs().maxCoeff());
    }
    return worst;
  };
  EXPECT_LT(run(h), 2e-3);   // bounded by the initial displacement (plus a little sag)
  EXPECT_GT(run(2.5 * h), 1.0);  // diverges
}

TEST(FemAttachment, BadCoefficientsAndRowsAreRefused) {
  World w = attached_cube("verlet", 1, 0);
  EXPECT_THROW(w.attach(-1, 1), InputError);
  EXPECT_THROW(w.attach(w.state_rows(), 1), InputError);
  EXPECT_THROW(w.attach(0, -1), InputError);
  EXPECT_THROW(w.attach(0, 1, std::nan("")), InputError);
  w.attach(0, 2, 3);  // adds
  EXPECT_EQ(w.attachment_stiffness(0), 3);
  EXPECT_EQ(w.attachment_damping(0), 3);
}
