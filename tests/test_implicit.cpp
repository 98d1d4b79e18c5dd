// Tests of the implicit integrator (issue 17): the element Hessians against finite differences,
// then physics — rest, a cantilever against Verlet, momentum, an impact on a rigid wall, two bodies
// meeting head-on — and determinism with 1 and 2 threads.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "fem_test_worlds.h"
#include "meshing_test_util.h"
#include "squeeze/common/error.h"
#include "squeeze/fem/block_ldlt.h"
#include "squeeze/fem/body.h"
#include "squeeze/fem/constraints.h"
#include "squeeze/fem/implicit.h"
#include "squeeze/fem/integrator.h"
#include "squeeze/fem/scene.h"
#include "squeeze/fem/world.h"

using namespace squeeze;
using namespace squeeze::fem;
using Eigen::Vector3d;

namespace {

Vec3 rand_vec(std::mt19937& g, double s = 1.0) {
  std::uniform_real_distribution<double> u(-s, s);
  return Vec3(u(g), u(g), u(g));
}

bool same_bits(const RowMatrixX3d& a, const RowMatrixX3d& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

std::unique_ptr<TimeIntegrator> implicit_with(double tolerance) {
  ImplicitOptions o;
  o.tolerance = tolerance;
  o.cg_tolerance = std::min(1e-2, tolerance);
  return make_implicit_integrator(o);
}

Vector3d momentum(const World& w, const State& s) {
  Vector3d p = Vector3d::Zero();
  for (int i = 0; i < w.state_rows(); ++i) p += w.masses()(i) * s.v.row(i).transpose();
  return p;
}

// Elements for the pair-kernel tests: 300 random edges and 300 random tetrahedra over n points
// (about a third undamped), appended to those given, and a random x_n gradient for each.
struct Edge { int i, j; double D0, k, kd; };
struct Tet { int v[4]; double V0, k, kd; };
void add_random_elements(std::mt19937& g, int n, std::vector<Edge>& edges, std::vector<Tet>& tets,
                         std::vector<Vec3>& eg, std::vector<std::array<Vec3, 4>>& tg) {
  std::uniform_real_distribution<double> u(0.1, 3.0);
  for (int e = 0; e < 300; ++e) {
    const int i = static_cast<int>(g() % n), j = (i + 1 + static_cast<int>(g() % (n - 1))) % n;
    edges.push_back({i, j, u(g), u(g) * 1e3, g() % 3 == 0 ? 0.0 : u(g)});
  }
  for (int t = 0; t < 300; ++t) {
    Tet T{{0, 0, 0, 0}, u(g) * 0.01, u(g) * 1e3, g() % 3 == 0 ? 0.0 : u(g)};
    for (int& c : T.v) c = static_cast<int>(g() % n);
    tets.push_back(T);
  }
  eg.resize(edges.size());
  tg.resize(tets.size());
  for (auto& v : eg) v = rand_vec(g, 5.0);
  for (auto& a : tg)
    for (auto& v : a) v = rand_vec(g, 5.0);
}

}  // namespace

// ∂²E_D/∂p_j² against central differences of the gradient k C ∂C/∂p_j, stretched and compressed;
// the psd variant is positive semi-definite and exact when the edge is stretched.
TEST(FemKernels, DistanceHessianMatchesFiniteDifferences) {
  std::mt19937 g(3);
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3 pi = rand_vec(g), pj = rand_vec(g);
    const double D0 = (pj - pi).norm() * (trial % 2 ? 0.6 : 1.5), k = 2.5, eps = 1e-6;
    auto grad_j = [&](const Vec3& q) {
      Vec3 gj;
      const double C = distance_constraint(pi, q, D0, &gj);
      return Vec3(k * C * gj);
    };
    const Eigen::Matrix3d H = distance_hessian(pi, pj, D0, k, false);
    for (int c = 0; c < 3; ++c) {
      Vec3 a = pj, b = pj;
      a[c] += eps;
      b[c] -= eps;
      const Vec3 fd = (grad_j(a) - grad_j(b)) / (2 * eps);
      for (int r = 0; r < 3; ++r) EXPECT_NEAR(H(r, c), fd[r], 1e-6 * (1 + std::abs(fd[r]))) << trial;
    }
    const Eigen::Matrix3d P = distance_hessian(pi, pj, D0, k, true);
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(P).eigenvalues().minCoeff(), -1e-12 * P.norm());
    if ((pj - pi).norm() > D0) {
      EXPECT_LT((P - H).norm(), 1e-12 * H.norm());
    }
  }
}

// The exact 12×12 Hessian of E_V against central differences of its gradient k C ∂C/∂p, for
// random, flattened and inverted tetrahedra; the Gauss–Newton one is positive semi-definite.
TEST(FemKernels, VolumeHessianMatchesFiniteDifferences) {
  std::mt19937 g(5);
  for (int trial = 0; trial < 40; ++trial) {
    Vec3 p[4];
    for (auto& q : p) q = rand_vec(g);
    const double V0 = 0.08 * (trial % 3 + 1), k = 1.7, eps = 1e-6;
    auto grad = [&](const Vec3* q) {
      Vec3 gk[4];
      const double C = volume_constraint(q[0], q[1], q[2], q[3], V0, gk);
      Eigen::Matrix<double, 12, 1> G;
      for (int i = 0; i < 4; ++i) G.segment<3>(3 * i) = k * C * gk[i];
      return G;
    };
    const Eigen::Matrix<double, 12, 12> H = volume_hessian(p[0], p[1], p[2], p[3], V0, k);
    EXPECT_LT((H - H.transpose()).norm(), 1e-12 * (1 + H.norm()));
    for (int v = 0; v < 4; ++v)
      for (int c = 0; c < 3; ++c) {
        Vec3 a[4], b[4];
        std::copy(p, p + 4, a);
        std::copy(p, p + 4, b);
        a[v][c] += eps;
        b[v][c] -= eps;
        const Eigen::Matrix<double, 12, 1> fd = (grad(a) - grad(b)) / (2 * eps);
        for (int r = 0; r < 12; ++r) EXPECT_NEAR(H(r, 3 * v + c), fd[r], 1e-5 * (1 + std::abs(fd[r]))) << trial;
      }
    Vec3 gk[4];
    volume_constraint(p[0], p[1], p[2], p[3], V0, gk);
    const Eigen::Matrix<double, 12, 12> GN = volume_hessian_gn(gk, k);
    using Mat12 = Eigen::Matrix<double, 12, 12>;
    const double lowest = Eigen::SelfAdjointEigenSolver<Mat12>(GN).eigenvalues().minCoeff();
    EXPECT_GE(lowest, -1e-9 * GN.norm());
    // The solver's lower blocks: those of the exact Hessian, and without curvature those of GN.
    for (bool curvature : {true, false}) {
      Eigen::Matrix3d Hd[4], Hl[6];
      Vec3 gl[4];
      volume_hessian_lower(p, V0, k, curvature, Hd, Hl, gl);
      const Mat12& R = curvature ? H : GN;
      int q = 0;
      for (int a = 0; a < 4; ++a) {
        EXPECT_LT((Hd[a] - R.block<3, 3>(3 * a, 3 * a)).norm(), 1e-12 * (1 + R.norm()));
        for (int b = a + 1; b < 4; ++b, ++q) EXPECT_LT((Hl[q] - R.block<3, 3>(3 * b, 3 * a)).norm(), 1e-12 * (1 + R.norm()));
      }
    }
  }
}

#if defined(__SSE2__)
// The implicit integrator's assembly computes its elements' Newton blocks two at a time (SSE2
// lanes): they must be the scalar functions' to the last bit, exact and positive semi-definite,
// damped or not (each lane on its own), compressed and stretched edges, inverted and flat
// tetrahedra; a zero-length edge is refused (the scalar function takes it).
TEST(FemKernels, NewtonBlockPairsEqualScalarBitForBit) {
  std::mt19937 g(17);
  const int n = 40;
  RowMatrixX3d X(n, 3);
  for (int i = 0; i < n; ++i) X.row(i) = rand_vec(g).transpose();
  X.row(5) = 0.5 * (X.row(2) + X.row(3)), X.row(4) = X.row(2);  // tet (2, 3, 4, 5): flat
  std::vector<Edge> edges;
  std::vector<Tet> tets{{{2, 3, 4, 5}, 0.05, 3.0, 0.2}};
  std::vector<Vec3> eg;
  std::vector<std::array<Vec3, 4>> tg;
  add_random_elements(g, n, edges, tets, eg, tg);
  const double h = 1.0 / 30;
  const double* x = X.data();
  auto bits_equal = [](const double* a, const double* b, int m) { return std::memcmp(a, b, sizeof(double) * m) == 0; };
  for (bool exact : {true, false}) {
    for (size_t e = 0; e + 1 < edges.size(); ++e) {
      Eigen::Matrix3d P[2];
      ASSERT_TRUE(edge_newton_block_pair(x, edges[e], edges[e + 1], !exact, h, eg[e].data(), eg[e + 1].data(),
                                         P[0].data(), P[1].data()));
      for (int q = 0; q < 2; ++q) {
        const Edge& E = edges[e + q];
        const Eigen::Matrix3d S = edge_newton_block(Vec3(x + 3 * E.i), Vec3(x + 3 * E.j), E.D0, E.k, !exact, E.kd, h, eg[e + q]);
        EXPECT_TRUE(bits_equal(S.data(), P[q].data(), 9)) << "edge " << e + q << (exact ? " exact" : " psd");
      }
    }
    for (size_t t = 0; t + 1 < tets.size(); ++t) {
      Eigen::Matrix3d P[2][10];
      tet_newton_blocks_pair(x, tets[t], tets[t + 1], exact, h, tg[t][0].data(), tg[t + 1][0].data(), P[0][0].data(),
                             P[1][0].data());
      for (int q = 0; q < 2; ++q) {
        const Tet& T = tets[t + q];
        Vec3 p[4];
        for (int c = 0; c < 4; ++c) p[c] = Vec3(x + 3 * T.v[c]);
        Eigen::Matrix3d S[10];
        tet_newton_blocks(p, T.V0, T.k, exact, T.kd, h, tg[t + q].data(), S, S + 4);
        for (int b = 0; b < 10; ++b)
          EXPECT_TRUE(bits_equal(S[b].data(), P[q][b].data(), 9)) << "tet " << t + q << " block " << b << (exact ? " exact" : " psd");
      }
    }
  }
  Edge zero{0, 1, 0.3, 2.0, 0.1};
  X.row(1) = X.row(0);
  Eigen::Matrix3d P[2];
  EXPECT_FALSE(edge_newton_block_pair(x, zero, edges[0], false, h, eg[0].data(), eg[1].data(), P[0].data(), P[1].data()));
}

// The potential's and the gradient's element terms two at a time: bit for bit the implicit
// integrator's scalar expressions (its potential and energy_gradient), damped or not, with and
// without the damping potential, a zero-length edge and a flat tetrahedron included.
TEST(FemKernels, PotentialPairsEqualScalarBitForBit) {
  std::mt19937 g(23);
  const int n = 40;
  RowMatrixX3d X(n, 3), Xn(n, 3);
  for (int i = 0; i < n; ++i) X.row(i) = rand_vec(g).transpose(), Xn.row(i) = X.row(i) + 0.1 * rand_vec(g).transpose();
  X.row(1) = X.row(0);                                          // edge (0, 1): zero length
  X.row(5) = 0.5 * (X.row(2) + X.row(3)), X.row(4) = X.row(2);  // tet (2, 3, 4, 5): flat
  std::vector<Edge> edges{{0, 1, 0.3, 2.0, 0.1}};
  std::vector<Tet> tets{{{2, 3, 4, 5}, 0.05, 3.0, 0.2}};
  std::vector<Vec3> eg;
  std::vector<std::array<Vec3, 4>> tg;
  add_random_elements(g, n, edges, tets, eg, tg);
  const double h = 1.0 / 30;
  const double *x = X.data(), *xn = Xn.data();
  auto lane = [](__m128d v, int q) { return _mm_cvtsd_f64(q ? _mm_unpackhi_pd(v, v) : v); };
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; };
  auto same3 = [&](const simd::Pair3& f, int q, const Vec3& v) {
    return same(lane(f.x, q), v[0]) && same(lane(f.y, q), v[1]) && same(lane(f.z, q), v[2]);
  };
  for (size_t e = 0; e + 1 < edges.size(); ++e) {
    __m128d energy, damping;
    edge_potential_pair(x, xn, edges[e], edges[e + 1], h, eg[e].data(), eg[e + 1].data(), energy, damping);
    for (bool damped : {true, false}) {
      const simd::Pair3 f = edge_gradient_pair(x, xn, edges[e], edges[e + 1], h, damped, eg[e].data(), eg[e + 1].data());
      for (int q = 0; q < 2; ++q) {
        const Edge& E = edges[e + q];
        const Vec3 xi(x + 3 * E.i), xj(x + 3 * E.j), xni(xn + 3 * E.i), xnj(xn + 3 * E.j);
        const double qd = eg[e + q].dot((xj - xnj) - (xi - xni));
        EXPECT_TRUE(same(lane(energy, q), distance_energy(xi, xj, E.D0, E.k))) << "edge " << e + q;
        EXPECT_TRUE(same(lane(damping, q), 0.5 * E.kd / h * qd * qd)) << "edge " << e + q;
        Vec3 gj;
        const double C = distance_constraint(xi, xj, E.D0, &gj);
        Vec3 ref = E.k * C * gj;
        if (damped && E.kd > 0) ref += (E.kd / h * qd) * eg[e + q];
        EXPECT_TRUE(same3(f, q, ref)) << "edge " << e + q << (damped ? " damped" : "");
      }
    }
  }
  for (size_t t = 0; t + 1 < tets.size(); ++t) {
    __m128d energy, damping;
    tet_potential_pair(x, xn, tets[t], tets[t + 1], h, tg[t][0].data(), tg[t + 1][0].data(), energy, damping);
    for (bool damped : {true, false}) {
      simd::Pair3 f[4];
      tet_gradient_pair(x, xn, tets[t], tets[t + 1], h, damped, tg[t][0].data(), tg[t + 1][0].data(), f);
      for (int q = 0; q < 2; ++q) {
        const Tet& T = tets[t + q];
        Vec3 p[4], gk[4];
        for (int k = 0; k < 4; ++k) p[k] = Vec3(x + 3 * T.v[k]);
        double qd = 0;
        for (int k = 0; k < 4; ++k) qd += tg[t + q][k].dot(p[k] - Vec3(xn + 3 * T.v[k]));
        EXPECT_TRUE(same(lane(energy, q), volume_energy(p[0], p[1], p[2], p[3], T.V0, T.k))) << "tet " << t + q;
        EXPECT_TRUE(same(lane(damping, q), 0.5 * T.kd / h * qd * qd)) << "tet " << t + q;
        const double C = volume_constraint(p[0], p[1], p[2], p[3], T.V0, gk);
        const double r = damped && T.kd > 0 ? qd : 0.0;
        for (int k = 0; k < 4; ++k) {
          const Vec3 ref = damped ? Vec3(T.k * C * gk[k] + (T.kd / h * r) * tg[t + q][k]) : Vec3(T.k * C * gk[k]);
          EXPECT_TRUE(same3(f[k], q, ref)) << "tet " << t + q << " corner " << k << (damped ? " damped" : "");
        }
      }
    }
  }
}
#endif

namespace {
// The vertex pairs of a tetrahedral mesh's elements, (I, J) with I > J, shifted by offset, appended
// to pairs (not sorted, may repeat).
void add_tet_pairs(const meshing::TetMesh& m, int offset, std::vector<std::pair<int, int>>& pairs) {
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        pairs.emplace_back(offset + std::max(m.T(t, a), m.T(t, b)), offset + std::min(m.T(t, a), m.T(t, b)));
}

// A symmetric matrix of the pattern `pairs` (n block rows): off-diagonal blocks uniform in [−1, 1]
// drawn from g, diagonal blocks that dominate their rows (positive definite).
void dominant_blocks(const std::vector<std::pair<int, int>>& pairs, int n, std::mt19937& g,
                     std::vector<Eigen::Matrix3d>& off, std::vector<Eigen::Matrix3d>& diag) {
  std::uniform_real_distribution<double> u(-1, 1);
  off.resize(pairs.size());
  diag.resize(static_cast<size_t>(n));
  std::vector<double> row(static_cast<size_t>(n), 1.0);
  for (size_t q = 0; q < pairs.size(); ++q) {
    for (int e = 0; e < 9; ++e) off[q](e / 3, e % 3) = u(g);
    row[pairs[q].first] += off[q].cwiseAbs().sum();
    row[pairs[q].second] += off[q].cwiseAbs().sum();
  }
  for (int i = 0; i < n; ++i) diag[i] = row[i] * Eigen::Matrix3d::Identity();
}
}  // namespace

// BlockLDLT solves symmetric block systems exactly (residual at rounding level against the dense
// matrix) on the vertex graph of a tetrahedral mesh and on random graphs, positive definite or
// indefinite, refactorises a second matrix of the same pattern, and refuses a singular pivot.
TEST(FemBlockLDLT, SolvesSymmetricBlockSystemsOnMeshAndRandomPatterns) {
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1);
  auto random_block = [&] {
    Eigen::Matrix3d B;
    for (int i = 0; i < 9; ++i) B(i / 3, i % 3) = u(g);
    return B;
  };
  std::vector<std::pair<int, std::vector<std::pair<int, int>>>> patterns;
  {
    const meshing::TetMesh box = box_tet_mesh(Vec3(0, 0, 0), Vec3(1, 0.5, 0.3), Eigen::Vector3i(6, 3, 2));
    std::vector<std::pair<int, int>> pairs;
    add_tet_pairs(box, 0, pairs);
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    patterns.emplace_back(static_cast<int>(box.V.rows()), pairs);
  }
  for (int n : {1, 2, 7, 60}) {
    std::vector<std::pair<int, int>> pairs;
    for (int i = 1; i < n; ++i)
      for (int j = 0; j < i; ++j)
        if (g() % 5 == 0) pairs.emplace_back(i, j);
    patterns.emplace_back(n, pairs);
  }
  for (const auto& [n, pairs] : patterns) {
    SCOPED_TRACE(n);
    BlockLDLT f;
    f.analyze(n, pairs);
    for (int variant = 0; variant < 3; ++variant) {  // SPD, another SPD, indefinite
      std::vector<Eigen::Matrix3d> off(pairs.size()), diag(static_cast<size_t>(n));
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * n, 3 * n);
      for (size_t q = 0; q < pairs.size(); ++q) {
        off[q] = random_block();
        A.block<3, 3>(3 * pairs[q].first, 3 * pairs[q].second) = off[q];
        A.block<3, 3>(3 * pairs[q].second, 3 * pairs[q].first) = off[q].transpose();
      }
      for (int i = 0; i < n; ++i) {  // diagonally dominant: SPD; minus on half of them: indefinite
        const double row = A.block(3 * i, 0, 3, 3 * n).cwiseAbs().sum();
        const Eigen::Matrix3d S = random_block();
        diag[i] = 0.1 * (S + S.transpose()) + (row + 1.0) * Eigen::Matrix3d::Identity();
        if (variant == 2 && i % 2) diag[i] = -diag[i];
        A.block<3, 3>(3 * i, 3 * i) = diag[i];
      }
      ASSERT_TRUE(f.factorize(diag, off));
      Eigen::VectorXd b(3 * n), x;
      for (int i = 0; i < 3 * n; ++i) b[i] = u(g);
      f.solve(b, x);
      EXPECT_LT((A * x - b).norm(), 1e-12 * A.norm() * (1 + x.norm())) << "variant " << variant;
    }
  }
  // A zero diagonal block with no coupling is a singular pivot.
  BlockLDLT f;
  f.analyze(2, {{1, 0}});
  EXPECT_FALSE(f.factorize({Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Zero()}, {Eigen::Matrix3d::Zero()}));
}


// precondition() keeps a small factor's single-precision values as doubles (the same numbers,
// without a conversion per use; BlockLDLT::kRoundedInDouble): its results are those of the
// single-precision copy bit for bit, sequential or cut into parts, and solve() is unchanged.
TEST(FemBlockLDLT, PreconditionerInDoubleEqualsSinglePrecisionBitForBit) {
  std::vector<std::pair<int, int>> pairs;
  int n = 0;
  for (const Eigen::Vector3i& cells : {Eigen::Vector3i(14, 7, 6), Eigen::Vector3i(9, 9, 9)}) {  // two bodies: a cut
    const meshing::TetMesh box = box_tet_mesh(Vec3(0, 0, 0), Vec3(1, 0.5, 0.4), cells);
    add_tet_pairs(box, n, pairs);
    n += static_cast<int>(box.V.rows());
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  std::mt19937 g(3);
  std::vector<Eigen::Matrix3d> off, diag;
  dominant_blocks(pairs, n, g, off, diag);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b[i] = u(g);
  for (int parts : {1, 2}) {
    SCOPED_TRACE(parts);
    BlockLDLT f;
    f.analyze(n, pairs, parts);
    ASSERT_EQ(f.parts(), parts);  // the bins' substitutions run too
    Eigen::VectorXd x[2], p[2];
    for (int in_double : {0, 1}) {
      f.set_rounded_in_double(in_double ? std::numeric_limits<size_t>::max() : 0);
      ASSERT_TRUE(f.factorize(diag, off));
      f.solve(b, x[in_double]);
      f.precondition(b, p[in_double]);
    }
    EXPECT_TRUE(x[0] == x[1]);
    EXPECT_TRUE(p[0] == p[1]);
    EXPECT_LT((p[1] - x[1]).norm(), 1e-5 * x[1].norm());
    EXPECT_GT((p[1] - x[1]).norm(), 0.0);  // single-precision values
  }
}

// The parallel cut of the elimination tree changes only who computes what: on the vertex graphs of
// two tetrahedral boxes (two bodies), apart or joined by contact-like couplings, the factors and
// solutions with 1 to 4 parts, under 1 or 2 threads, are bit for bit those of the sequential
// algorithm; bodies apart are cut and the cut takes work off the critical path; precondition()
// (L in single precision) agrees with solve() to single precision's rounding.
TEST(FemBlockLDLT, PartsGiveBitIdenticalFactorsAndSolutions) {
  int pipelined = 0;  // analyses whose top ran on two threads
  for (int couplings : {0, 20}) {
    SCOPED_TRACE(testing::Message() << couplings << " couplings");
    std::vector<std::pair<int, int>> pairs;
    int n = 0;
    for (const Eigen::Vector3i& cells : {Eigen::Vector3i(14, 7, 6), Eigen::Vector3i(9, 9, 9)}) {
      const meshing::TetMesh box = box_tet_mesh(Vec3(0, 0, 0), Vec3(1, 0.5, 0.4), cells);
      add_tet_pairs(box, n, pairs);
      n += static_cast<int>(box.V.rows());
    }
    std::mt19937 g(5);
    for (int c = 0; c < couplings; ++c) {
      const int i = n / 2 + static_cast<int>(g() % static_cast<unsigned>(n / 2)), j = static_cast<int>(g() % static_cast<unsigned>(n / 2));
      pairs.emplace_back(std::max(i, j), std::min(i, j));
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Eigen::Matrix3d> off, diag;
    dominant_blocks(pairs, n, g, off, diag);
    Eigen::VectorXd b(3 * n);
    for (int i = 0; i < 3 * n; ++i) b[i] = u(g);

    BlockLDLT ref;
    ref.analyze(n, pairs, 1);
    ASSERT_EQ(ref.parts(), 1);
    EXPECT_FALSE(ref.pipelined());
    ASSERT_GE(ref.factor_updates(), BlockLDLT::kParallelUpdates);
    ASSERT_TRUE(ref.factorize(diag, off));
    Eigen::VectorXd x_ref, p_ref;
    ref.solve(b, x_ref);
    ref.precondition(b, p_ref);
    EXPECT_LT((p_ref - x_ref).norm(), 1e-5 * x_ref.norm());
    EXPECT_GT((p_ref - x_ref).norm(), 0.0);  // it is the single-precision factor
    for (int threads : {1, 2}) {
      tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
      for (int parts : {0, 2, 3, 4}) {
        SCOPED_TRACE(testing::Message() << threads << " threads, " << parts << " parts");
        BlockLDLT f;
        f.analyze(n, pairs, parts);
        if (couplings == 0) {
          EXPECT_EQ(f.parts(), std::min(2, parts == 0 ? threads : parts));  // the two bodies
        }
        EXPECT_EQ(f.factor_blocks(), ref.factor_blocks());
        EXPECT_EQ(f.pipelined(), (parts == 0 ? threads : parts) > 1 && f.top_updates() >= BlockLDLT::kParallelUpdates);
        pipelined += f.pipelined();
        if (f.parts() > 1) {
          EXPECT_LE(f.top_updates() + f.largest_bin_updates(), f.factor_updates() - f.factor_updates() / 10);
          EXPECT_GE(f.largest_bin_updates() * f.parts() + f.top_updates(), f.factor_updates());
        }
        for (int again = 0; again < 2; ++again) {  // a refactorisation reuses the cut
          ASSERT_TRUE(f.factorize(diag, off));
          Eigen::VectorXd x, p;
          f.solve(b, x);
          f.precondition(b, p);
          EXPECT_TRUE(x == x_ref);
          EXPECT_TRUE(p == p_ref);
        }
      }
    }
    if (couplings == 0) {  // a singular pivot in one of the bins is found
      BlockLDLT f;
      f.analyze(n, pairs, 2);
      ASSERT_EQ(f.parts(), 2);
      std::vector<Eigen::Matrix3d> bad(diag), bad_off(off);
      bad[0].setZero();
      for (size_t q = 0; q < pairs.size(); ++q)
        if (pairs[q].second == 0) bad_off[q].setZero();
      EXPECT_FALSE(f.factorize(bad, bad_off));
      ASSERT_TRUE(f.factorize(diag, off));  // and the workspace is clean after it
      Eigen::VectorXd x;
      f.solve(b, x);
      EXPECT_TRUE(x == x_ref);
    }
  }
  EXPECT_GT(pipelined, 0);  // the joined bodies' top is large enough to run on two threads
}

// A singular pivot in the top's rows while they run on two threads is refused (the other thread
// does not wait for it forever), and the next factorisation is the sequential one bit for bit.
TEST(FemBlockLDLT, PipelinedTopRefusesASingularPivot) {
  const meshing::TetMesh box = box_tet_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), Eigen::Vector3i(10, 10, 10));
  std::vector<std::pair<int, int>> pairs;
  add_tet_pairs(box, 0, pairs);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  const int n = static_cast<int>(box.V.rows());
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Matrix3d> off, diag;
  dominant_blocks(pairs, n, g, off, diag);
  Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(3 * n, [&] { return u(g); }), x_ref, x;
  BlockLDLT ref;
  ref.analyze(n, pairs, 1);
  ASSERT_TRUE(ref.factorize(diag, off));
  ref.solve(b, x_ref);
  BlockLDLT f;
  f.analyze(n, pairs, 2);
  ASSERT_TRUE(f.pipelined());
  const std::vector<int> top = f.top_vertices();
  ASSERT_GE(top.size(), 3u);
  for (int v : {top.front(), top[top.size() / 2], top.back()}) {  // first, middle and last in the top
    SCOPED_TRACE(v);
    std::vector<Eigen::Matrix3d> bad(diag), bad_off(off);  // vertex v decoupled, zero pivot
    bad[v].setZero();
    for (size_t q = 0; q < pairs.size(); ++q)
      if (pairs[q].first == v || pairs[q].second == v) bad_off[q].setZero();
    EXPECT_FALSE(f.factorize(bad, bad_off));
    ASSERT_TRUE(f.factorize(diag, off));
    f.solve(b, x);
    EXPECT_TRUE(x == x_ref);
  }
}

// At rest, without gravity, the residual is zero: a step takes no Newton iteration and leaves the
// state exactly as it was.
TEST(FemImplicit, RestStateHasZeroResidual) {
  WorldOptions o;
  o.integrator = "implicit";
  o.h = 1.0 / 30;
  o.gravity.setZero();
  World w(o);
  Material m;
  m.k_distance = m.k_volume = 50;
  m.damping_distance = m.damping_volume = 0.1;
  w.add_body(Body(ball_tet_mesh(0.1, 4), m));
  Eigen::Affine3d a = Eigen::Affine3d::Identity();
  a.translation() = Vector3d(0.5, 0, 0);
  w.add_body(Body(box_tet_mesh(Vector3d(-0.1, -0.1, -0.1), Vector3d(0.1, 0.1, 0.1), Eigen::Vector3i(2, 2, 2)), m, true, a));
  State s = w.initial_state();
  const State s0 = s;
  for (int k = 0; k < 5; ++k) w.step(s);
  EXPECT_TRUE(same_bits(s.x, s0.x));
  EXPECT_TRUE(same_bits(s.v, s0.v));
  EXPECT_EQ(w.integrator().stats().iterations, 0);
  EXPECT_EQ(w.integrator().stats().steps, 5);
}

namespace {

// A 40 × 5 × 5 cm rubber beam pinned at x = 0 sagging under gravity: its tip's settled deflection
// (m, downward positive) after `seconds` of simulation with `integrator` at step h.
double cantilever_tip(const std::string& integrator, double h, double seconds, double tolerance = 1e-6) {
  WorldOptions o;
  o.integrator = integrator;
  o.h = h > 0 ? h : 1e-3;
  o.collisions = false;
  World w(o);
  Material m;
  m.density = 1000;
  m.k_distance = 40;
  m.k_volume = 40;
  m.damping_distance = m.damping_volume = 0.05;
  m.deformation_damping = 30;
  m.mass_scaling = 0;
  w.add_body(Body(box_tet_mesh(Vector3d(0, -0.025, -0.025), Vector3d(0.4, 0.025, 0.025), Eigen::Vector3i(12, 2, 2)), m));
  w.pin(Eigen::AlignedBox3d(Vector3d(-0.001, -1, -1), Vector3d(0.001, 1, 1)));
  if (integrator == "implicit") w.set_integrator(implicit_with(tolerance));
  if (h <= 0) w.set_time_step(h = 0.9 * stable_time_step(w));  // Verlet: just below its stable step
  State s = w.initial_state();
  const int steps = static_cast<int>(std::lround(seconds / h));
  for (int k = 0; k < steps; ++k) w.step(s);
  EXPECT_TRUE(s.x.allFinite());
  double tip = 0;
  int n = 0;
  for (int i = 0; i < w.state_rows(); ++i)
    if (w.body(0).rest(i, 0) > 0.399) tip += w.body(0).rest(i, 1) - s.x(i, 1), ++n;
  return tip / n;
}

}  // namespace

// The settled deflection of a cantilever converges as h → 0 and agrees with the paper's Verlet step
// at a small h (just below its stable step) within 2 %: the same energies have the same
// equilibrium, which backward Euler reaches at any h.
TEST(FemImplicit, CantileverDeflectionConvergesAndAgreesWithVerlet) {
  const double verlet = cantilever_tip("verlet", 0, 0.8);
  const double d1 = cantilever_tip("implicit", 1.0 / 30, 0.8), d2 = cantilever_tip("implicit", 1.0 / 120, 0.8),
               d3 = cantilever_tip("implicit", 1.0 / 480, 0.8);
  std::printf("cantilever tip deflection: Verlet %.6f m; implicit h 1/30 %.6f, 1/120 %.6f, 1/480 %.6f m\n", verlet, d1, d2,
              d3);
  EXPECT_GT(verlet, 0.005);  // a real sag, not a rigid beam
  // Converged: the implicit deflections agree to 0.1 % from h = 1/30 down to 1/480.
  EXPECT_NEAR(d1, d3, 1e-3 * d3);
  EXPECT_NEAR(d2, d3, 1e-3 * d3);
  EXPECT_NEAR(d3, verlet, 0.02 * verlet);
}

// Without external forces and without any damping, linear momentum is conserved — through a
// collision of two deformable balls (penalty contacts are internal forces).
TEST(FemImplicit, MomentumIsConservedWithoutExternalForcesOrDamping) {
  WorldOptions o;
  o.integrator = "implicit";
  o.h = 1.0 / 60;
  o.gravity.setZero();
  o.contact_stiffness = 500;
  World w(o);
  Material m;
  m.k_distance = m.k_volume = 5;
  m.deformation_damping = 0;
  Eigen::Affine3d a = Eigen::Affine3d::Identity(), b = a;
  a.translation() = Vector3d(-0.15, 0, 0);
  b.translation() = Vector3d(0.15, 0.03, 0.01);
  w.add_body(Body(ball_tet_mesh(0.1, 4), m, false, a));
  w.add_body(Body(ball_tet_mesh(0.1, 4), m, false, b));
  w.set_integrator(implicit_with(1e-10));
  State s = w.initial_state();
  for (int i = 0; i < w.body(0).vertices(); ++i) s.v.row(i) = Vector3d(1.0, 0.1, 0).transpose();
  for (int i = w.first_state_row(1); i < w.state_rows(); ++i) s.v.row(i) = Vector3d(-0.5, 0, 0.2).transpose();
  const Vector3d p0 = momentum(w, s);
  int touching = 0;
  for (int k = 0; k < 30; ++k) {
    w.step(s);
    touching += w.last_stats().colliding_vertices > 0;
    EXPECT_LT((momentum(w, s) - p0).norm(), 1e-7 * p0.norm()) << "step " << k;
  }
  EXPECT_GT(touching, 2);  // the balls did collide
  EXPECT_EQ(w.integrator().stats().not_converged, 0);
}

// A soft ball thrown at 10 m/s at a rigid wall with frame-sized steps: finite throughout, never
// through the wall, and it comes off it.
TEST(FemImplicit, BodyThrownAtARigidWallStaysFiniteAndComesOff) {
  WorldOptions o;
  o.integrator = "implicit";
  o.h = 1.0 / 30;
  o.gravity.setZero();
  o.contact_stiffness = 2e4;
  o.contact_damping = 5;
  World w(o);
  Material m;
  m.k_distance = m.k_volume = 20;
  m.damping_distance = m.damping_volume = 0.01;
  w.add_body(Body(ball_tet_mesh(0.1, 5), m));
  Eigen::Affine3d wall = Eigen::Affine3d::Identity();
  wall.translation() = Vector3d(0.5, 0, 0);
  w.add_body(Body(box_tet_mesh(Vector3d(0, -0.5, -0.5), Vector3d(0.2, 0.5, 0.5), Eigen::Vector3i(2, 5, 5)), Material{}, true, wall));
  State s = w.initial_state();
  for (int i = 0; i < w.state_rows(); ++i) s.v(i, 0) = 10.0;
  double deepest = 0, closest = 1;
  for (int k = 0; k < 15; ++k) {
    w.step(s);
    ASSERT_TRUE(s.x.allFinite()) << "step " << k;
    deepest = std::max(deepest, s.x.col(0).maxCoeff() - 0.5);  // beyond the wall's face
    closest = std::min(closest, 0.5 - s.x.col(0).mean());
  }
  const double vx = s.v.col(0).mean();
  std::printf("wall impact at 10 m/s: deepest vertex %.4f m beyond the face, centre %.3f m from it at the closest, "
              "leaving at %.2f m/s; %lld substeps for %lld steps\n",
              deepest, closest, vx, w.integrator().stats().substeps, w.integrator().stats().steps);
  EXPECT_LT(vx, -1.0);             // it came off the wall
  EXPECT_LT(deepest, 0.05);        // a quarter of the ball's radius at most, never through (the wall is 0.2 m thick)
  EXPECT_LT(s.x.col(0).maxCoeff(), 0.5);  // and it is out again
}

// The head-on scene: two soft 0.6 m balls of about 800 tets, meshed from the icosphere,
// 2 m/s each, no gravity, at the automatic step: finite, they bounce apart, each keeps its volume
// within 10 % at every frame, and the penetration stays below 25 % of the mean edge length.
TEST(FemImplicit, HeadOnBodiesBounceApart) {
  const sqt::TempDir dir("implicit-headon");
  ::setenv("SQUEEZE_CACHE_DIR", (dir.path() / "cache").c_str(), 1);
  const std::string sphere = sqt::data("sphere.off").string();
  nlohmann::json j = {
      {"integrator", "implicit"},
      {"floor", nullptr},
      {"gravity", {0, 0, 0}},
      {"objects",
       {{{"name", "left"}, {"mesh", sphere}, {"tets", 800}, {"velocity", {2, 0, 0}},
         {"transform", {{"scale", 0.6}, {"translate", {-0.45, 0, 0}}}}},
        {{"name", "right"}, {"mesh", sphere}, {"tets", 800}, {"velocity", {-2, 0, 0}},
         {"transform", {{"scale", 0.6}, {"translate", {0.45, 0.05, 0}}}}}}}};
  const std::filesystem::path file = dir.path() / "headon.json";
  std::ofstream(file) << j.dump(2);
  SceneWorld w = build_scene(load_scene(file));
  ASSERT_GT(w.world.tets(), 2 * 500);
  const double edge = 0.5 * (w.world.body(0).mean_edge_length() + w.world.body(1).mean_edge_length());
  State s = w.initial_state();
  const int frames = static_cast<int>(std::lround(1.0 / w.time_step()));
  double worst_volume = 0, deepest = 0;
  for (int f = 0; f < frames; ++f) {
    w.step(s);
    ASSERT_TRUE(s.x.allFinite() && s.v.allFinite()) << "frame " << f;
    for (int b = 0; b < 2; ++b) worst_volume = std::max(worst_volume, std::abs(w.world.body_volume(s, b) / w.rest_volume[b] - 1));
    deepest = std::max(deepest, w.world.contact_stats(s).max_depth);
  }
  const double vl = s.v.topRows(w.world.body(0).vertices()).col(0).mean();
  const double vr = s.v.bottomRows(w.world.body(1).vertices()).col(0).mean();
  std::printf("head-on: largest volume change %.2f %%, deepest penetration %.4f m (%.1f %% of the mean edge %.4f m), "
              "leaving at %.2f and %.2f m/s\n",
              100 * worst_volume, deepest, 100 * deepest / edge, edge, vl, vr);
  EXPECT_LT(worst_volume, 0.10);
  EXPECT_LE(deepest, 0.25 * edge);
  EXPECT_LT(vl, -0.1);  // bounced: the left ball moves left again
  EXPECT_GT(vr, 0.1);
}

// Same state, same forces: bit-identical with 1 and 2 threads, every pass parallel: the Hessian
// assembled in two parts (one ball each) or, for one ball, its element blocks computed in
// parallel, the factorisation cut into two bins (balls of 8 cells a side are large enough) or not
// (one thread).
TEST(FemImplicit, BitIdenticalWhateverTheThreadCount) {
  auto run = [](int threads, int balls) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
    WorldOptions o;
    o.integrator = "implicit";
    o.h = 1.0 / 30;
    o.floor = true;
    o.floor_height = -0.15;
    o.contact_stiffness = 2e3;
    o.contact_damping = 0.5;
    o.parallel = {0, 0, 0, 0};
    World w(o);
    Material m;
    m.k_distance = m.k_volume = 5;
    m.damping_distance = m.damping_volume = 0.002;
    Eigen::Affine3d a = Eigen::Affine3d::Identity(), b = a;
    a.translation() = Vector3d(-0.12, 0, 0);
    b.translation() = Vector3d(0.12, 0.02, 0.01);
    w.add_body(Body(ball_tet_mesh(0.1, 8), m, false, a));
    if (balls == 2) w.add_body(Body(ball_tet_mesh(0.1, 8), m, false, b));
    State s = w.initial_state();
    for (int i = 0; i < w.state_rows(); ++i) s.v(i, 0) = i < w.body(0).vertices() ? 1.5 : -1.5;
    for (int k = 0; k < 30; ++k) w.step(s);
    return s;
  };
  for (int balls : {1, 2}) {
    SCOPED_TRACE(balls);
    const State a = run(1, balls), b = run(2, balls);
    EXPECT_TRUE(same_bits(a.x, b.x));
    EXPECT_TRUE(same_bits(a.v, b.v));
  }
}

// Options out of range are refused.
TEST(FemImplicit, BadOptionsAreRefused) {
  ImplicitOptions o;
  o.tolerance = 0;
  EXPECT_THROW(make_implicit_integrator(o), InputError);
  o = ImplicitOptions{};
  o.motion_fraction = -1;
  EXPECT_THROW(make_implicit_integrator(o), InputError);
  o = ImplicitOptions{};
  o.cg_tolerance = 1;
  EXPECT_THROW(make_implicit_integrator(o), InputError);
  o = ImplicitOptions{};
  o.inexact_cg_tolerance = -0.1;
  EXPECT_THROW(make_implicit_integrator(o), InputError);
}

namespace {

// Two soft balls overlapping by about 1.5 cm at rest, no gravity (the organs of a body touch so).
World overlapping_balls(const std::string& integrator, bool rest_overlap) {
  WorldOptions o;
  o.integrator = integrator;
  o.h = integrator == "implicit" ? 1.0 / 30 : 2e-4;
  o.gravity.setZero();
  o.contact_stiffness = 2e3;
  o.contact_damping = 1;
  o.rest_overlap = rest_overlap;
  World w(o);
  Material m;
  m.k_distance = m.k_volume = 5;
  m.damping_distance = m.damping_volume = 0.002;
  Eigen::Affine3d a = Eigen::Affine3d::Identity(), b = a;
  a.translation() = Vector3d(-0.0925, 0, 0);
  b.translation() = Vector3d(0.0925, 0.01, 0);
  w.add_body(Body(ball_tet_mesh(0.1, 5), m, false, a));
  w.add_body(Body(ball_tet_mesh(0.1, 5), m, false, b));
  w.prepare();
  return w;
}

}  // namespace

// Issue 18: objects that overlap at rest start at rest (both integrators): the overlap is their
// contacts' rest state. Without it, the same overlap pushes them apart.
TEST(FemWorld, RestOverlapsStartAtRest) {
  for (const char* integrator : {"verlet", "implicit"}) {
    SCOPED_TRACE(integrator);
    World w = overlapping_balls(integrator, true);
    ASSERT_GT(w.rest_overlaps().size(), 4u);  // they do overlap
    double deepest = 0;
    for (const auto& o : w.rest_overlaps()) deepest = std::max(deepest, o.depth);
    EXPECT_GT(deepest, 0.005);
    State s = w.initial_state();
    ASSERT_EQ(s.overlap.size(), static_cast<Eigen::Index>(w.rest_overlaps().size()));
    const State s0 = s;
    const int steps = std::string(integrator) == "implicit" ? 30 : 5000;
    for (int k = 0; k < steps; ++k) w.step(s);
    EXPECT_LT(s.v.cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((s.x - s0.x).cwiseAbs().maxCoeff(), 1e-9);
    World off = overlapping_balls(integrator, false);
    EXPECT_TRUE(off.rest_overlaps().empty());
    State t = off.initial_state();
    for (int k = 0; k < steps; ++k) off.step(t);
    EXPECT_GT(t.v.cwiseAbs().maxCoeff(), 1e-3);  // pushed apart
  }
}

// Issue 18: the tolerance of a rest overlap shrinks as the objects separate and is gone once they
// are apart: from then on, pushed back together, they collide exactly as objects that never
// overlapped (bit for bit), instead of sinking into each other by the old overlap.
TEST(FemWorld, RestOverlapRelaxesAsObjectsSeparate) {
  for (const char* integrator : {"verlet", "implicit"}) {
    SCOPED_TRACE(integrator);
    World w = overlapping_balls(integrator, true);
    State s = w.initial_state();
    const int n0 = w.body(0).vertices();
    RowMatrixX3d pull = RowMatrixX3d::Zero(w.state_rows(), 3);
    for (int i = 0; i < w.state_rows(); ++i) pull(i, 0) = (i < n0 ? -1.0 : 1.0) * w.masses()(i);
    const double h = w.time_step();
    for (double t = 0; t < 0.3; t += h) w.step(s, &pull);  // pulled apart
    EXPECT_EQ(s.overlap.cwiseAbs().maxCoeff(), 0.0);       // out: no tolerance left
    s.v.setZero();
    World never = overlapping_balls(integrator, false);    // the same balls, overlaps never tolerated
    State t = s;
    t.overlap.resize(0);
    const RowMatrixX3d push = -pull;
    w.integrator().reset();  // what the integrator carries from step to step (its last factorisation, its
                             // last contacts) is not the overlap's doing: both start afresh
    double deepest = 0;
    for (double time = 0; time < 1.0; time += h) {
      w.step(s, &push);  // pushed back into each other
      never.step(t, &push);
      deepest = std::max(deepest, w.last_stats().max_depth);
    }
    std::printf("%s: after separating, pushed back: deepest penetration %.4f m\n", integrator, deepest);
    EXPECT_GT(deepest, 0.0);  // they did touch again
    EXPECT_TRUE(same_bits(s.x, t.x));
    EXPECT_TRUE(same_bits(s.v, t.v));
  }
}

// Soft attachments (issue 18) in the incremental potential: a cube whose every vertex is held by a
// zero-length spring k settles with the mean sag M g / (N k) (the attachments carry the weight),
// at the frame interval 1/30 s as with Verlet at its small step.
TEST(FemImplicit, SoftAttachmentsSettleAtWeightOverStiffness) {
  const double k = 200, c = 1.0;
  World w = sqt::attached_cube("implicit", k, c);
  w.set_time_step(1.0 / 30);
  w.set_integrator(implicit_with(1e-6));
  State s = w.initial_state();
  for (int n = 0; n < 90; ++n) w.step(s);  // 3 s
  double sag = 0;
  for (int i = 0; i < w.state_rows(); ++i) sag += w.body(0).rest(i, 1) - s.x(i, 1);
  sag /= w.state_rows();
  const double expected = w.masses().sum() * 9.81 / (w.state_rows() * k);
  EXPECT_NEAR(sag, expected, 1e-3 * expected);
  EXPECT_LT(s.v.cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_EQ(w.integrator().stats().not_converged, 0);
}

namespace {

// A soft 10 cm cube of 10 × 10 × 10 cells (mean edge about 1.3 cm: gravity alone moves a free
// vertex ½ g h² = 12 mm in a step, more than half an edge) under gravity at h = 1/20 s:
// resting on a rigid slab (`support` "slab": penalty contacts), hanging from its pinned top face
// ("pins"), free ("none"), or beside a rigid blade 4 mm thick ("blade": the planes x = blade and
// x = blade + 0.004 m, 40 cm each way, so its corners are far outside the cube; the cube's column
// of vertices at x = 0 is the one nearest to it). Its world options are soft_cube_options() unless
// given; `bottom` is the height of its lowest face (m; the slab's top is at −0.001).
WorldOptions soft_cube_options() {
  WorldOptions o;
  o.integrator = "implicit";
  o.h = 1.0 / 20;
  o.contact_stiffness = 2e4;
  o.contact_damping = 2;
  return o;
}

World soft_cube(const std::string& support, const WorldOptions& o = soft_cube_options(), double bottom = 0,
                double blade = 0.0005) {
  World w(o);
  Material m;
  m.k_distance = m.k_volume = 50;
  m.damping_distance = m.damping_volume = 0.01;
  m.deformation_damping = 20;
  w.add_body(Body(
      box_tet_mesh(Vector3d(-0.05, bottom, -0.05), Vector3d(0.05, bottom + 0.1, 0.05), Eigen::Vector3i(10, 10, 10)), m));
  if (support == "slab")
    w.add_body(Body(box_tet_mesh(Vector3d(-0.2, -0.05, -0.2), Vector3d(0.2, -0.001, 0.2), Eigen::Vector3i(1, 1, 1)),
                    Material{}, true));
  if (support == "blade")
    w.add_body(Body(box_tet_mesh(Vector3d(blade, -0.2, -0.2), Vector3d(blade + 0.004, 0.2, 0.2), Eigen::Vector3i(1, 1, 1)),
                    Material{}, true));
  if (support == "pins") w.pin(Eigen::AlignedBox3d(Vector3d(-1, 0.099, -1), Vector3d(1, 1, 1)));
  w.prepare();
  return w;
}

}  // namespace

// Issue 17 (cost on fine meshes): a body at rest on another or hanging from its pins takes whole
// frame-sized steps (the substep prediction counts every force at x_n, not gravity alone), and a
// body resting on a contact keeps it from step to step (no contact round re-finding it, few
// Newton iterations); a body falling toward another is split into substeps, one falling with
// nothing within reach is not.
TEST(FemImplicit, BodiesAtRestTakeWholeStepsAndKeepTheirContacts) {
  for (const char* support : {"slab", "pins"}) {
    SCOPED_TRACE(support);
    World w = soft_cube(support);
    State s = w.initial_state();
    for (int k = 0; k < 40; ++k) w.step(s);  // 2 s: settled
    const IntegratorStats a = w.integrator().stats();
    for (int k = 0; k < 15; ++k) w.step(s);
    const IntegratorStats b = w.integrator().stats();
    const double per_step = static_cast<double>(b.iterations - a.iterations) / 15;
    std::printf("%s, settled: %lld substeps, %lld contact rounds, %.2f Newton iterations and %.2f factorisations "
                "per step, largest |v_y| %.2g m/s, colliding vertices %d\n",
                support, b.substeps - a.substeps, b.contact_rounds - a.contact_rounds, per_step,
                static_cast<double>(b.factorizations - a.factorizations) / 15, s.v.col(1).cwiseAbs().maxCoeff(),
                w.last_stats().colliding_vertices);
    EXPECT_LT(s.v.col(1).cwiseAbs().maxCoeff(), 1e-3);  // at rest (on the frictionless slab it may turn slowly)
    EXPECT_EQ(b.substeps - a.substeps, 15);            // whole steps
    EXPECT_EQ(b.contact_rounds - a.contact_rounds, 0);
    EXPECT_LE(per_step, 2.0);
    EXPECT_EQ(b.not_converged, 0);
    if (std::string(support) == "slab") {
      EXPECT_GT(w.last_stats().colliding_vertices, 50);  // it does rest on the slab
      EXPECT_GT(s.x.col(1).minCoeff(), -0.01);           // and not in it
    }
  }
  // Free fall 1 cm above the slab: ½ g h² is more than half an edge, and the slab is within reach.
  World near = soft_cube("slab");
  State s = near.initial_state();
  s.x.col(1).array() += 0.01;
  near.step(s);
  EXPECT_GE(near.integrator().stats().substeps, 2);
  // Free fall with nothing within reach (no floor, no other object): whole steps, and the cube
  // falls as backward Euler at h drops it (g h² N (N + 1) / 2 after N steps: ½ g t² (1 + 1/N))
  // without deforming.
  World alone = soft_cube("none");
  State f = alone.initial_state();
  const double y0 = f.x.col(1).mean();
  for (int k = 0; k < 10; ++k) alone.step(f);
  EXPECT_EQ(alone.integrator().stats().substeps, 10);
  const double h = alone.time_step(), fall = y0 - f.x.col(1).mean();
  EXPECT_NEAR(fall, 9.81 * h * h * 10 * 11 / 2, 1e-9);
  double strain = 0;  // no relative motion: every vertex fell by the same amount
  for (int i = 0; i < alone.state_rows(); ++i)
    strain = std::max(strain, std::abs((alone.body(0).rest(i, 1) - f.x(i, 1)) - fall));
  EXPECT_LT(strain, 1e-6);
}

// A motion that a shorter substep does not shorten is a jump, not a missed event: a cube whose
// bottom starts 2 cm (two edge lengths) inside a rigid slab, with no rest-overlap tolerance, is
// pushed out by the same 2 cm at any substep length. The motion check halves such a substep once,
// sees the halves move as far, and keeps them, instead of halving down to its depth limit.
TEST(FemImplicit, AJumpIsNotHalvedAgainAndAgain) {
  WorldOptions o = soft_cube_options();
  o.rest_overlap = false;
  o.gravity.setZero();
  World w = soft_cube("slab", o, -0.02);
  State s = w.initial_state();
  w.step(s);
  const IntegratorStats st = w.integrator().stats();
  std::printf("a 2 cm jump: %lld substeps, %lld Newton iterations, lowest y %.4f m\n", st.substeps, st.iterations,
              s.x.col(1).minCoeff());
  EXPECT_TRUE(s.x.allFinite());
  EXPECT_GT(s.x.col(1).minCoeff(), -0.012);  // mostly out
  EXPECT_LE(st.substeps, 8);                  // not 2^8 halvings of a substep
}

// A carried contact (the last substep's, kept while its vertex stays near the plane it was found
// on) must not outlive the surface: a cube sliding at 1 m/s on a frictionless slab falls off its
// edge as it would without any carried contact.
TEST(FemImplicit, ABodySlidingOffASlabFallsOffIt) {
  World w = soft_cube("slab");
  State s = w.initial_state();
  for (int k = 0; k < 10; ++k) w.step(s);  // settle on the slab
  ASSERT_GT(s.x.col(1).mean(), 0.03);
  for (int i = 0; i < w.state_rows(); ++i) s.v(i, 0) = 1.0;
  for (int k = 0; k < 12; ++k) w.step(s);  // 0.6 s: off the edge (x = 0.2) after about 0.25 s
  const double x = s.x.col(0).mean(), y = s.x.col(1).mean();
  std::printf("after sliding 0.6 s at 1 m/s: centre at x %.3f m, y %.3f m\n", x, y);
  EXPECT_GT(x, 0.3);    // it slid past the edge
  EXPECT_LT(y, -0.2);   // and fell (about ½ g (0.35 s)² = 0.6 m below the slab)
}

// A vertex inside a part of another object thinner than its edges: its depth estimate (the nearest
// crossing of its edges with that object's surface) flips to the far side once it is pressed past
// the part's mid-plane, and the new direction pushes it through the part. A soft cube pressed
// sideways (a steady load of 10 or 20 g, soft contacts, no rest-overlap tolerance) against a rigid
// blade 4 mm thick, whose face is 0.5 or 2 mm from one column of its vertices; the blade's corners
// are far outside the cube, so only that column touches it. The blade holds the column on the side
// it came in by (the last substep's contact plane is kept when detection points the other way).
// Without that, the cube went through the blade in three of the four cases (8-22 m in 0.5 s).
TEST(FemImplicit, AThinBladeHoldsWhatIsPressedAgainstIt) {
  for (double load : {100.0, 200.0})
    for (double gap : {0.0005, 0.002}) {
      SCOPED_TRACE(::testing::Message() << "load " << load << " m/s^2, gap " << gap << " m");
      WorldOptions o = soft_cube_options();
      o.rest_overlap = false;
      o.gravity = Vector3d(load, 0, 0);
      o.contact_stiffness = 500;
      World w = soft_cube("blade", o, 0, gap);
      State s = w.initial_state();
      const int n = w.body(0).vertices();
      const double x0 = s.x.col(0).head(n).mean();
      double column = -1;  // the largest x reached by the column that meets the blade (rest x = 0)
      for (int k = 0; k < 10; ++k) {
        w.step(s);
        for (int i = 0; i < n; ++i)
          if (std::abs(w.body(0).rest(i, 0)) < 1e-9) column = std::max(column, s.x(i, 0));
      }
      const IntegratorStats st = w.integrator().stats();
      std::printf("load %.0f, gap %.4f: centre moved %.4f m, column reached x %.4f m (blade %.4f..%.4f); %lld "
                  "substeps\n", load, gap, s.x.col(0).head(n).mean() - x0, column, gap, gap + 0.004, st.substeps);
      EXPECT_TRUE(s.x.allFinite());
      EXPECT_GT(column, gap);            // it is pressed into the blade
      EXPECT_LT(column, gap + 0.004);    // and not through it
      EXPECT_LT(s.x.col(0).head(n).mean() - x0, 0.01);
      EXPECT_LE(st.substeps, 100);
    }
}
