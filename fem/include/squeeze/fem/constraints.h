// squeeze::fem — stateless per-element kernels of the constraint-based deformable model:
// energies, constraint gradients, elastic and damping forces of one edge or one tetrahedron.
//
// Source: M. Teschner, B. Heidelberger, M. Müller, M. Gross, "A versatile and robust model for
// geometrically complex deformable solids", CGI 2004, doi:10.1109/CGI.2004.1309199, as used by
// S. Rodriguez, J.-M. Lien, N. M. Amato, "Planning motion in completely deformable environments",
// ICRA 2006, Section IV-A:
//   E = ½ k C²                                                         (eq. 1)
//   F_i = −k C ∂C/∂p_i                                                 (eq. 2)
//   C_D = (|p_j − p_i| − D0) / D0                                      (eq. 3, distance)
//   C_V = (⅙ (p_j − p_i)·((p_k − p_i)×(p_l − p_i)) − V0) / V0          (eq. 4, volume)
// and the damping force of Teschner et al. 2004 (Section 3):
//   F_damp,i = −k_d (Σ_j ∂C/∂p_j · v_j) ∂C/∂p_i.
//
// Units: positions in m, velocities in m/s. C is a dimensionless ratio, so the stiffness k is an
// energy (J = N·m); ∂C/∂p is in 1/m, the elastic force k C ∂C/∂p in N. The damping coefficient
// k_d multiplies (1/s)·(1/m), so it is in J·s = N·m·s.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace squeeze::fem {

using Vec3 = Eigen::Vector3d;

/// Distance constraint C_D of edge (pi,pj) with rest length D0 > 0 (m); grad_j receives ∂C/∂p_j
/// (1/m); ∂C/∂p_i = −grad_j. A zero-length edge has a zero gradient.
inline double distance_constraint(const Vec3& pi, const Vec3& pj, double D0, Vec3* grad_j) {
  const Vec3 d = pj - pi;
  const double len = d.norm();
  if (grad_j) *grad_j = len > 0 ? Vec3(d / (len * D0)) : Vec3::Zero();
  return (len - D0) / D0;
}

/// E_D = ½ k C_D² (J), k in J.
inline double distance_energy(const Vec3& pi, const Vec3& pj, double D0, double k) {
  const double C = distance_constraint(pi, pj, D0, nullptr);
  return 0.5 * k * C * C;
}

/// Elastic plus damping forces (N) of one edge: fi on p_i, fj = −fi on p_j.
///   k   stiffness (J), kd  damping (J·s), vi, vj  velocities (m/s)
inline void distance_forces(const Vec3& pi, const Vec3& pj, const Vec3& vi, const Vec3& vj, double D0, double k,
                            double kd, Vec3& fi, Vec3& fj) {
  Vec3 g;
  const double C = distance_constraint(pi, pj, D0, &g);
  const double rate = g.dot(vj - vi);  // dC/dt (1/s)
  fj = -(k * C + kd * rate) * g;
  fi = -fj;
}

/// Volume constraint C_V of tetrahedron (p0,p1,p2,p3) with rest volume V0 > 0 (m³); grad[0..3]
/// receive ∂C/∂p_k (1/m). Negative for inverted tetrahedra, whose forces restore the volume.
inline double volume_constraint(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double V0,
                                Vec3 grad[4]) {
  const Vec3 a = p1 - p0, b = p2 - p0, c = p3 - p0;
  const Vec3 bc = b.cross(c);
  // The expression of meshing::tet_volume (tet_geometry.h), kept here rather than called: bc is
  // shared with the gradient below, and this is the hot kernel whose order volume_forces_pair
  // repeats bit for bit.
  const double V = a.dot(bc) / 6.0;
  if (grad) {
    const double s = 1.0 / (6.0 * V0);
    grad[1] = s * bc;
    grad[2] = s * c.cross(a);
    grad[3] = s * a.cross(b);
    grad[0] = -(grad[1] + grad[2] + grad[3]);
  }
  return (V - V0) / V0;
}

/// E_V = ½ k C_V² (J), k in J.
inline double volume_energy(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double V0, double k) {
  const double C = volume_constraint(p0, p1, p2, p3, V0, nullptr);
  return 0.5 * k * C * C;
}

/// Elastic plus damping forces (N) of one tetrahedron on its four vertices.
///   p, v  positions (m) and velocities (m/s) of the four vertices; k (J), kd (J·s)
inline void volume_forces(const Vec3 p[4], const Vec3 v[4], double V0, double k, double kd, Vec3 f[4]) {
  Vec3 g[4];
  const double C = volume_constraint(p[0], p[1], p[2], p[3], V0, g);
  const double rate = g[0].dot(v[0]) + g[1].dot(v[1]) + g[2].dot(v[2]) + g[3].dot(v[3]);
  const double s = -(k * C + kd * rate);
  for (int i = 0; i < 4; ++i) f[i] = s * g[i];
}

#if defined(__SSE2__)
// Two elements at once, one per SSE2 lane, with the scalar kernels' operations in the scalar
// kernels' order (IEEE add, sub, mul, div and sqrt are exact per lane, and there is no fused
// multiply-add here), so the forces are bit for bit those of distance_forces / volume_forces
// (test FemKernels.PairKernelsEqualScalarKernelsBitForBit). World::step computes its elements
// with them.
// The pair kernels are forced inline: called through the stack, GCC stopped inlining the tet
// kernel and its 24 doubles of results went through memory.
#if defined(__GNUC__)
#define SQUEEZE_FEM_INLINE inline __attribute__((always_inline))
#else
#define SQUEEZE_FEM_INLINE inline
#endif
#if defined(__clang__)
#define SQUEEZE_FEM_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define SQUEEZE_FEM_UNROLL _Pragma("GCC unroll 16")
#else
#define SQUEEZE_FEM_UNROLL
#endif
namespace simd {
struct Pair3 {
  __m128d x, y, z;  // lane 0: first element, lane 1: second
};
inline Pair3 load_pair(const double* a, const double* b) {
  const __m128d a01 = _mm_loadu_pd(a), b01 = _mm_loadu_pd(b);
  return {_mm_unpacklo_pd(a01, b01), _mm_unpackhi_pd(a01, b01), _mm_set_pd(b[2], a[2])};
}
inline void store_pair(double* a, double* b, const Pair3& v) {
  _mm_storeu_pd(a, _mm_unpacklo_pd(v.x, v.y));
  _mm_storeu_pd(b, _mm_unpackhi_pd(v.x, v.y));
  _mm_store_sd(a + 2, v.z);
  _mm_storeh_pd(b + 2, v.z);
}
/// a += lane 0 of v (a: 3 doubles); add_lane1: lane 1. The same IEEE additions as a scalar a += f.
inline void add_lane0(double* a, const Pair3& v) {
  _mm_storeu_pd(a, _mm_add_pd(_mm_loadu_pd(a), _mm_unpacklo_pd(v.x, v.y)));
  _mm_store_sd(a + 2, _mm_add_sd(_mm_load_sd(a + 2), v.z));
}
inline void add_lane1(double* a, const Pair3& v) {
  _mm_storeu_pd(a, _mm_add_pd(_mm_loadu_pd(a), _mm_unpackhi_pd(v.x, v.y)));
  _mm_store_sd(a + 2, _mm_add_sd(_mm_load_sd(a + 2), _mm_unpackhi_pd(v.z, v.z)));
}
inline Pair3 sub(const Pair3& a, const Pair3& b) {
  return {_mm_sub_pd(a.x, b.x), _mm_sub_pd(a.y, b.y), _mm_sub_pd(a.z, b.z)};
}
inline Pair3 add(const Pair3& a, const Pair3& b) {
  return {_mm_add_pd(a.x, b.x), _mm_add_pd(a.y, b.y), _mm_add_pd(a.z, b.z)};
}
inline Pair3 scale(__m128d s, const Pair3& a) { return {_mm_mul_pd(s, a.x), _mm_mul_pd(s, a.y), _mm_mul_pd(s, a.z)}; }
inline Pair3 neg(const Pair3& a) {
  const __m128d sign = _mm_set1_pd(-0.0);
  return {_mm_xor_pd(a.x, sign), _mm_xor_pd(a.y, sign), _mm_xor_pd(a.z, sign)};
}
inline __m128d dot(const Pair3& a, const Pair3& b) {  // (a.x b.x + a.y b.y) + a.z b.z, as Eigen's dot
  return _mm_add_pd(_mm_add_pd(_mm_mul_pd(a.x, b.x), _mm_mul_pd(a.y, b.y)), _mm_mul_pd(a.z, b.z));
}
inline Pair3 cross(const Pair3& a, const Pair3& b) {  // as Eigen's cross
  return {_mm_sub_pd(_mm_mul_pd(a.y, b.z), _mm_mul_pd(a.z, b.y)),
          _mm_sub_pd(_mm_mul_pd(a.z, b.x), _mm_mul_pd(a.x, b.z)),
          _mm_sub_pd(_mm_mul_pd(a.x, b.y), _mm_mul_pd(a.y, b.x))};
}
}  // namespace simd

/// distance_forces of two edges at once, bit for bit: fj of both (lane 0: e0, lane 1: e1);
/// f_i = −f_j.
///   x, v    row-major #rows by 3 positions (m) and velocities (m/s)
///   e0, e1  edges: any type with rows `int i, j`, rest length `double D0` (m), stiffness `k` (J)
///           and damping `kd` (J·s)
template <class Edge>
SQUEEZE_FEM_INLINE simd::Pair3 distance_forces_pair(const double* x, const double* v, const Edge& e0, const Edge& e1) {
  using namespace simd;
  const Pair3 pi = load_pair(x + 3 * e0.i, x + 3 * e1.i), pj = load_pair(x + 3 * e0.j, x + 3 * e1.j);
  const Pair3 vi = load_pair(v + 3 * e0.i, v + 3 * e1.i), vj = load_pair(v + 3 * e0.j, v + 3 * e1.j);
  const __m128d D0 = _mm_set_pd(e1.D0, e0.D0), k = _mm_set_pd(e1.k, e0.k), kd = _mm_set_pd(e1.kd, e0.kd);
  const Pair3 d = sub(pj, pi);
  const __m128d len = _mm_sqrt_pd(dot(d, d));
  const __m128d den = _mm_mul_pd(len, D0);
  const __m128d positive = _mm_cmpgt_pd(len, _mm_setzero_pd());  // len > 0 (false for NaN): else g = 0
  const Pair3 g{_mm_and_pd(positive, _mm_div_pd(d.x, den)), _mm_and_pd(positive, _mm_div_pd(d.y, den)),
                _mm_and_pd(positive, _mm_div_pd(d.z, den))};
  const __m128d C = _mm_div_pd(_mm_sub_pd(len, D0), D0);
  const __m128d rate = dot(g, sub(vj, vi));
  const __m128d s = _mm_xor_pd(_mm_add_pd(_mm_mul_pd(k, C), _mm_mul_pd(kd, rate)), _mm_set1_pd(-0.0));
  return scale(s, g);
}

/// volume_constraint of two tetrahedra at once, bit for bit: returns C = (V − V0) / V0 of both and
/// writes g[q] = ∂C/∂p_q.
///   p   the 4 corners of both (lane 0: t0, lane 1: t1), positions (m); V0  rest volumes (m³)
SQUEEZE_FEM_INLINE __m128d volume_constraint_pair(const simd::Pair3 p[4], __m128d V0, simd::Pair3 g[4]) {
  using namespace simd;
  const Pair3 a = sub(p[1], p[0]), b = sub(p[2], p[0]), c = sub(p[3], p[0]);
  const Pair3 bc = cross(b, c);
  const __m128d V = _mm_div_pd(dot(a, bc), _mm_set1_pd(6.0));
  const __m128d s = _mm_div_pd(_mm_set1_pd(1.0), _mm_mul_pd(_mm_set1_pd(6.0), V0));
  g[1] = scale(s, bc);
  g[2] = scale(s, cross(c, a));
  g[3] = scale(s, cross(a, b));
  g[0] = neg(add(add(g[1], g[2]), g[3]));
  return _mm_div_pd(_mm_sub_pd(V, V0), V0);
}

/// volume_forces of two tetrahedra at once, bit for bit: f[q] the forces (N) on corner q of
/// both (lane 0: t0, lane 1: t1).
///   x, v    row-major #rows by 3 positions (m) and velocities (m/s)
///   t0, t1  tetrahedra: any type with rows `int v[4]`, rest volume `double V0` (m³), stiffness
///           `k` (J) and damping `kd` (J·s)
template <class Tet>
SQUEEZE_FEM_INLINE void volume_forces_pair(const double* x, const double* v, const Tet& t0, const Tet& t1,
                                           simd::Pair3 out[4]) {
  using namespace simd;
  Pair3 p[4], vel[4];
  for (int c = 0; c < 4; ++c) {
    p[c] = load_pair(x + 3 * t0.v[c], x + 3 * t1.v[c]);
    vel[c] = load_pair(v + 3 * t0.v[c], v + 3 * t1.v[c]);
  }
  const __m128d V0 = _mm_set_pd(t1.V0, t0.V0), k = _mm_set_pd(t1.k, t0.k), kd = _mm_set_pd(t1.kd, t0.kd);
  Pair3 g[4];
  const __m128d C = volume_constraint_pair(p, V0, g);
  const __m128d rate =
      _mm_add_pd(_mm_add_pd(_mm_add_pd(dot(g[0], vel[0]), dot(g[1], vel[1])), dot(g[2], vel[2])), dot(g[3], vel[3]));
  const __m128d f = _mm_xor_pd(_mm_add_pd(_mm_mul_pd(k, C), _mm_mul_pd(kd, rate)), _mm_set1_pd(-0.0));
  for (int q = 0; q < 4; ++q) out[q] = scale(f, g[q]);
}
#endif

// ---------------------------------------------------------------------------------------------
// Hessians (IPC Toolkit style: value, gradient and Hessian of one element), for the implicit
// integrator (integrator.h, "implicit"). Each exact Hessian is tested against finite differences
// of the gradient (tests/test_fem.cpp, FemKernels.*HessianMatchesFiniteDifferences); the solver
// uses the positive semi-definite variants, which keep Newton's directions descent directions.

/// ∂²E_D/∂p_j² (3×3, J/m²) of E_D = ½ k C_D² (eq. 3): k/D0² (d̂d̂ᵀ + (1 − D0/|d|)(I − d̂d̂ᵀ)), d = p_j − p_i.
/// The edge's 6×6 Hessian over (p_i, p_j) is [[H, −H], [−H, H]]. psd: the transverse factor
/// (1 − D0/|d|), negative for a compressed edge, is clamped at 0 (the nearest positive
/// semi-definite matrix of this form). A zero-length edge gets k/D0² · I.
inline Eigen::Matrix3d distance_hessian(const Vec3& pi, const Vec3& pj, double D0, double k, bool psd) {
  const Vec3 d = pj - pi;
  const double len = d.norm();
  const double s = k / (D0 * D0);
  if (!(len > 0)) return s * Eigen::Matrix3d::Identity();
  const Vec3 n = d / len;
  double t = 1.0 - D0 / len;
  if (psd && t < 0) t = 0;
  const Eigen::Matrix3d nn = n * n.transpose();
  return s * (nn + t * (Eigen::Matrix3d::Identity() - nn));
}

/// Cross-product matrix: skew(u) w = u × w.
inline Eigen::Matrix3d skew(const Vec3& u) {
  Eigen::Matrix3d S;
  S << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  return S;
}

/// The 3×3 blocks of the exact Hessian of E_V = ½ k C_V² (eq. 4) over (p0, p1, p2, p3), J/m²:
/// H_ab = k ∇_a C ∇_b Cᵀ + (k C / V0) ∂²V/∂p_a∂p_b. V = ⅙ det[p1 − p0, p2 − p0, p3 − p0] is linear in
/// each corner, so ∂²V/∂p_a² = 0, and each cross block is a cross-product matrix of an edge / 6:
/// with e1 = p1 − p0, e2 = p2 − p0, e3 = p3 − p0, ∂²V/∂p1∂p2 = −skew(e3)/6, ∂²V/∂p1∂p3 = skew(e2)/6,
/// ∂²V/∂p2∂p3 = −skew(e1)/6, ∂²V/∂p0∂p1 = skew(e2 − e3)/6, ∂²V/∂p0∂p2 = skew(e3 − e1)/6,
/// ∂²V/∂p0∂p3 = skew(e1 − e2)/6, and ∂²V/∂p_b∂p_a = (∂²V/∂p_a∂p_b)ᵀ = −∂²V/∂p_a∂p_b.
/// Indefinite where C ≠ 0. grad: receives the four ∂C/∂p_k (1/m). Returns C.
/// The same blocks as the solver stores them (the others are their transposes): the diagonal ones
/// Hd[a] = H_aa and the lower ones Hl[q] = H_ba, a < b, q over the pairs (0,1), (0,2), (0,3), (1,2),
/// (1,3), (2,3). With curvature false, the Gauss–Newton blocks k ∇_a C ∇_b Cᵀ only (positive
/// semi-definite, volume_hessian_gn). grad: receives the four ∂C/∂p_k (1/m). Returns C.
inline double volume_hessian_lower(const Vec3 p[4], double V0, double k, bool curvature, Eigen::Matrix3d Hd[4],
                                   Eigen::Matrix3d Hl[6], Vec3 grad[4]) {
  const double C = volume_constraint(p[0], p[1], p[2], p[3], V0, grad);
  for (int a = 0; a < 4; ++a) Hd[a] = k * grad[a] * grad[a].transpose();
  int q = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) Hl[q++] = k * grad[b] * grad[a].transpose();
  if (curvature) {  // H_ba += w (∂²V/∂p_a∂p_b)ᵀ = −w ∂²V/∂p_a∂p_b, w = k C / V0, the skew blocks above
    const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0], e3 = p[3] - p[0];
    const double w = k * C / (6.0 * V0);
    Hl[0] -= w * skew(e2 - e3);
    Hl[1] -= w * skew(e3 - e1);
    Hl[2] -= w * skew(e1 - e2);
    Hl[3] += w * skew(e3);
    Hl[4] -= w * skew(e2);
    Hl[5] += w * skew(e1);
  }
  return C;
}

inline double volume_hessian_blocks(const Vec3 p[4], double V0, double k, Eigen::Matrix3d H[4][4], Vec3 grad[4]) {
  Eigen::Matrix3d Hd[4], Hl[6];
  const double C = volume_hessian_lower(p, V0, k, true, Hd, Hl, grad);
  int q = 0;
  for (int a = 0; a < 4; ++a) {
    H[a][a] = Hd[a];
    for (int b = a + 1; b < 4; ++b, ++q) {
      H[b][a] = Hl[q];
      H[a][b] = Hl[q].transpose();
    }
  }
  return C;
}

/// Exact Hessian (12×12 over (p0, p1, p2, p3), J/m²) of E_V = ½ k C_V²: the blocks of
/// volume_hessian_blocks. Indefinite where C ≠ 0; the solver uses it where the whole Hessian is
/// positive definite, else volume_hessian_gn.
inline Eigen::Matrix<double, 12, 12> volume_hessian(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                                                    double V0, double k) {
  const Vec3 p[4] = {p0, p1, p2, p3};
  Eigen::Matrix3d B[4][4];
  Vec3 g[4];
  volume_hessian_blocks(p, V0, k, B, g);
  Eigen::Matrix<double, 12, 12> H;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) H.block<3, 3>(3 * a, 3 * b) = B[a][b];
  return H;
}

/// Gauss–Newton Hessian of E_V: k ∇C ∇Cᵀ (12×12, positive semi-definite, rank 1), the exact one
/// without the C ∇²C term. grad: the four ∂C/∂p_k (1/m).
inline Eigen::Matrix<double, 12, 12> volume_hessian_gn(const Vec3 grad[4], double k) {
  Eigen::Matrix<double, 12, 1> G;
  for (int i = 0; i < 4; ++i) G.segment<3>(3 * i) = grad[i];
  return k * G * G.transpose();
}

// ---------------------------------------------------------------------------------------------
// The implicit integrator's Newton blocks of one element: its Hessian plus the Hessian of its
// damping potential ½ (k_d / h) (∇C(x_n)·Δx)², (k_d / h) ∇C ∇Cᵀ with ∇C frozen at the substep's
// start (implicit.cpp, "assemble"), the latter where k_d / h > 0.

/// An edge's block (its 6×6 matrix is [[H, −H], [−H, H]]): distance_hessian(pi, pj, D0, k, psd)
/// plus (kd / h) g gᵀ, g = ∂C/∂p_j at x_n.
inline Eigen::Matrix3d edge_newton_block(const Vec3& pi, const Vec3& pj, double D0, double k, bool psd, double kd,
                                         double h, const Vec3& g) {
  Eigen::Matrix3d H = distance_hessian(pi, pj, D0, k, psd);
  if (kd > 0) H += (kd / h) * g * g.transpose();
  return H;
}

/// A tetrahedron's blocks in volume_hessian_lower's layout (Hd[4] diagonal, Hl[6] the blocks
/// (b, a), a < b): volume_hessian_lower(p, V0, k, curvature) plus (kd / h) ∇_a C ∇_b Cᵀ from tg[4],
/// the ∂C/∂p_a at x_n.
inline void tet_newton_blocks(const Vec3 p[4], double V0, double k, bool curvature, double kd, double h,
                              const Vec3 tg[4], Eigen::Matrix3d Hd[4], Eigen::Matrix3d Hl[6]) {
  Vec3 grad[4];
  volume_hessian_lower(p, V0, k, curvature, Hd, Hl, grad);
  const double damp = kd / h;
  if (damp > 0) {
    int q = 0;
    for (int a = 0; a < 4; ++a) {
      Hd[a] += damp * tg[a] * tg[a].transpose();
      for (int b = a + 1; b < 4; ++b) Hl[q++] += damp * tg[b] * tg[a].transpose();
    }
  }
}

#if defined(__SSE2__)
// The Newton blocks of two elements at once, one per SSE2 lane, with the scalar functions'
// operations in their order (Eigen's: an outer product's entry (i, j) is (s u_i) v_j, a sum of
// matrices is taken entry by entry), so bit for bit edge_newton_block / tet_newton_blocks
// (FemKernels.NewtonBlockPairsEqualScalarBitForBit). The implicit integrator's assembly computes
// its elements with them: 1,380 instructions per tetrahedron through Eigen (callgrind), about
// half of that here.
namespace simd {
// Lane 0 of the 3×3 blocks m (9 pairs, column-major) to o0, lane 1 to o1.
inline void store_block_pair(const __m128d m[9], double* o0, double* o1) {
  for (int e = 0; e < 9; ++e) {
    _mm_storel_pd(o0 + e, m[e]);
    _mm_storeh_pd(o1 + e, m[e]);
  }
}
// m += (s u) vᵀ where mask (all bits of a lane) is set; a lane outside it keeps m exactly.
inline void add_outer_masked(__m128d m[9], __m128d s, const Pair3& u, const Pair3& v, __m128d mask, bool all) {
  const __m128d su[3] = {_mm_mul_pd(s, u.x), _mm_mul_pd(s, u.y), _mm_mul_pd(s, u.z)};
  const __m128d vv[3] = {v.x, v.y, v.z};
  if (all) {
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) m[i + 3 * j] = _mm_add_pd(m[i + 3 * j], _mm_mul_pd(su[i], vv[j]));
    return;
  }
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const __m128d sum = _mm_add_pd(m[i + 3 * j], _mm_mul_pd(su[i], vv[j]));
      m[i + 3 * j] = _mm_or_pd(_mm_and_pd(mask, sum), _mm_andnot_pd(mask, m[i + 3 * j]));
    }
}
}  // namespace simd

/// edge_newton_block of two edges at once: H0, H1 receive the blocks (9 doubles each, column-major).
/// Returns false and writes nothing if an edge has zero length (then use edge_newton_block).
///   x       row-major positions (m); g0, g1  the edges' ∂C/∂p_j at x_n (3 doubles each)
template <class Edge>
SQUEEZE_FEM_INLINE bool edge_newton_block_pair(const double* x, const Edge& e0, const Edge& e1, bool psd, double h,
                                               const double* g0, const double* g1, double* H0, double* H1) {
  using namespace simd;
  const Pair3 d = sub(load_pair(x + 3 * e0.j, x + 3 * e1.j), load_pair(x + 3 * e0.i, x + 3 * e1.i));
  const __m128d len = _mm_sqrt_pd(dot(d, d));
  if (_mm_movemask_pd(_mm_cmpgt_pd(len, _mm_setzero_pd())) != 3) return false;
  const __m128d D0 = _mm_set_pd(e1.D0, e0.D0), k = _mm_set_pd(e1.k, e0.k);
  const __m128d s = _mm_div_pd(k, _mm_mul_pd(D0, D0));
  const __m128d n[3] = {_mm_div_pd(d.x, len), _mm_div_pd(d.y, len), _mm_div_pd(d.z, len)};
  __m128d t = _mm_sub_pd(_mm_set1_pd(1.0), _mm_div_pd(D0, len));
  if (psd) t = _mm_and_pd(t, _mm_cmpnlt_pd(t, _mm_setzero_pd()));  // t < 0: +0
  __m128d m[9];
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const __m128d nn = _mm_mul_pd(n[j], n[i]);
      const __m128d I = _mm_set1_pd(i == j ? 1.0 : 0.0);
      m[i + 3 * j] = _mm_mul_pd(s, _mm_add_pd(nn, _mm_mul_pd(t, _mm_sub_pd(I, nn))));
    }
  const __m128d kd = _mm_set_pd(e1.kd, e0.kd);
  const __m128d damped = _mm_cmpgt_pd(kd, _mm_setzero_pd());
  if (const int lanes = _mm_movemask_pd(damped)) {
    const Pair3 g = load_pair(g0, g1);
    add_outer_masked(m, _mm_div_pd(kd, _mm_set1_pd(h)), g, g, damped, lanes == 3);
  }
  store_block_pair(m, H0, H1);
  return true;
}

/// tet_newton_blocks of two tetrahedra at once: out0, out1 receive Hd[4] then Hl[6] (90 doubles
/// each, the blocks column-major).
///   x         row-major positions (m); tg0, tg1  each tetrahedron's ∂C/∂p_a at x_n (4 × 3 doubles)
template <class Tet>
SQUEEZE_FEM_INLINE void tet_newton_blocks_pair(const double* x, const Tet& t0, const Tet& t1, bool curvature, double h,
                                               const double* tg0, const double* tg1, double* out0, double* out1) {
  using namespace simd;
  Pair3 p[4];
  for (int c = 0; c < 4; ++c) p[c] = load_pair(x + 3 * t0.v[c], x + 3 * t1.v[c]);
  const __m128d V0 = _mm_set_pd(t1.V0, t0.V0), k = _mm_set_pd(t1.k, t0.k);
  Pair3 g[4];
  const __m128d C = volume_constraint_pair(p, V0, g);
  const Pair3 a = sub(p[1], p[0]), b = sub(p[2], p[0]), c = sub(p[3], p[0]);
  // Block by block: volume_hessian_lower's k ∇_b C ∇_a Cᵀ, then its curvature's
  // cross-product term (w skew(u), skew(u) = [[0, −u_z, u_y], [u_z, 0, −u_x], [−u_y, u_x, 0]]),
  // then the damping's (kd / h) ∇_b C(x_n) ∇_a C(x_n)ᵀ.
  const __m128d w = _mm_div_pd(_mm_mul_pd(k, C), _mm_mul_pd(_mm_set1_pd(6.0), V0));
  const Pair3 skew_u[6] = {sub(b, c), sub(c, a), sub(a, b), c, b, a};  // e2 − e3, e3 − e1, e1 − e2, e3, e2, e1
  const bool skew_subtract[6] = {true, true, true, false, true, false};
  const __m128d damp = _mm_div_pd(_mm_set_pd(t1.kd, t0.kd), _mm_set1_pd(h));
  const __m128d damped = _mm_cmpgt_pd(damp, _mm_setzero_pd());
  const int lanes = _mm_movemask_pd(damped);
  Pair3 tg[4] = {};
  if (lanes)
    for (int q = 0; q < 4; ++q) tg[q] = load_pair(tg0 + 3 * q, tg1 + 3 * q);
  Pair3 kg[4];
  for (int q = 0; q < 4; ++q) kg[q] = scale(k, g[q]);
  Pair3 dtg[4] = {};
  if (lanes)
    for (int r = 0; r < 4; ++r) dtg[r] = scale(damp, tg[r]);
  const __m128d zero = _mm_setzero_pd(), sign = _mm_set1_pd(-0.0);
  int q = 0;  // the pair (a, b) in Hl's order
  // Unrolled (the pragmas), entry by entry from registers to the outputs: as loops over blocks
  // accumulated in arrays, GCC kept their operands in memory (about 980 instructions per
  // tetrahedron, callgrind).
  SQUEEZE_FEM_UNROLL
  for (int A = 0; A < 4; ++A)
    SQUEEZE_FEM_UNROLL
    for (int B = A; B < 4; ++B) {
      const int slot = B == A ? A : 4 + q;
      double* o0 = out0 + 9 * slot;
      double* o1 = out1 + 9 * slot;
      const __m128d ku[3] = {kg[B].x, kg[B].y, kg[B].z}, v[3] = {g[A].x, g[A].y, g[A].z};
      const Pair3& u = skew_u[B > A ? q : 0];
      const __m128d S[9] = {zero, u.z, _mm_xor_pd(u.y, sign), _mm_xor_pd(u.z, sign), zero, u.x, u.y, _mm_xor_pd(u.x, sign), zero};
      const __m128d du[3] = {dtg[B].x, dtg[B].y, dtg[B].z}, dv[3] = {tg[A].x, tg[A].y, tg[A].z};
      SQUEEZE_FEM_UNROLL
      for (int j = 0; j < 3; ++j)
        SQUEEZE_FEM_UNROLL
        for (int i = 0; i < 3; ++i) {
          const int e = i + 3 * j;
          __m128d m = _mm_mul_pd(ku[i], v[j]);
          if (curvature && B > A) {
            const __m128d ws = _mm_mul_pd(w, S[e]);
            m = skew_subtract[q] ? _mm_sub_pd(m, ws) : _mm_add_pd(m, ws);
          }
          if (lanes) {
            const __m128d sum = _mm_add_pd(m, _mm_mul_pd(du[i], dv[j]));
            m = lanes == 3 ? sum : _mm_or_pd(_mm_and_pd(damped, sum), _mm_andnot_pd(damped, m));
          }
          _mm_storel_pd(o0 + e, m);
          _mm_storeh_pd(o1 + e, m);
        }
      if (B > A) ++q;
    }
}

// The implicit integrator's potential terms and gradients of two elements at once (implicit.cpp,
// "potential", "energy_gradient"), bit for bit its scalar expressions
// (FemKernels.PotentialPairsEqualScalarBitForBit): an element's energy ½ k C², and its damping
// potential ½ (k_d / h) q², q = ∇C(x_n)·(x − x_n) summed over its vertices. x, xn: row-major
// positions and the substep's start (m); g: the gradients at x_n (3 doubles per vertex, j's for
// an edge, the four corners' for a tetrahedron).
template <class Edge>
SQUEEZE_FEM_INLINE void edge_potential_pair(const double* x, const double* xn, const Edge& e0, const Edge& e1, double h,
                                            const double* g0, const double* g1, __m128d& energy, __m128d& damping) {
  using namespace simd;
  const Pair3 xi = load_pair(x + 3 * e0.i, x + 3 * e1.i), xj = load_pair(x + 3 * e0.j, x + 3 * e1.j);
  const Pair3 d = sub(xj, xi);
  const __m128d D0 = _mm_set_pd(e1.D0, e0.D0);
  const __m128d C = _mm_div_pd(_mm_sub_pd(_mm_sqrt_pd(dot(d, d)), D0), D0);
  energy = _mm_mul_pd(_mm_mul_pd(_mm_mul_pd(_mm_set1_pd(0.5), _mm_set_pd(e1.k, e0.k)), C), C);
  const Pair3 dx = sub(sub(xj, load_pair(xn + 3 * e0.j, xn + 3 * e1.j)), sub(xi, load_pair(xn + 3 * e0.i, xn + 3 * e1.i)));
  const __m128d q = dot(load_pair(g0, g1), dx);
  const __m128d c = _mm_div_pd(_mm_mul_pd(_mm_set1_pd(0.5), _mm_set_pd(e1.kd, e0.kd)), _mm_set1_pd(h));
  damping = _mm_mul_pd(_mm_mul_pd(c, q), q);
}

template <class Tet>
SQUEEZE_FEM_INLINE void tet_potential_pair(const double* x, const double* xn, const Tet& t0, const Tet& t1, double h,
                                           const double* g0, const double* g1, __m128d& energy, __m128d& damping) {
  using namespace simd;
  Pair3 p[4];
  for (int c = 0; c < 4; ++c) p[c] = load_pair(x + 3 * t0.v[c], x + 3 * t1.v[c]);
  const Pair3 a = sub(p[1], p[0]), b = sub(p[2], p[0]), c = sub(p[3], p[0]);
  const __m128d V0 = _mm_set_pd(t1.V0, t0.V0);
  const __m128d V = _mm_div_pd(dot(a, cross(b, c)), _mm_set1_pd(6.0));
  const __m128d C = _mm_div_pd(_mm_sub_pd(V, V0), V0);
  energy = _mm_mul_pd(_mm_mul_pd(_mm_mul_pd(_mm_set1_pd(0.5), _mm_set_pd(t1.k, t0.k)), C), C);
  __m128d q = _mm_setzero_pd();
  for (int k = 0; k < 4; ++k)
    q = _mm_add_pd(q, dot(load_pair(g0 + 3 * k, g1 + 3 * k), sub(p[k], load_pair(xn + 3 * t0.v[k], xn + 3 * t1.v[k]))));
  const __m128d cd = _mm_div_pd(_mm_mul_pd(_mm_set1_pd(0.5), _mm_set_pd(t1.kd, t0.kd)), _mm_set1_pd(h));
  damping = _mm_mul_pd(_mm_mul_pd(cd, q), q);
}

/// The gradient of an edge's energy, plus its damping potential's where `damping` and k_d > 0:
/// f = k C ∂C/∂p_j + (k_d / h) q g (∂/∂p_i = −f), of two edges at once.
template <class Edge>
SQUEEZE_FEM_INLINE simd::Pair3 edge_gradient_pair(const double* x, const double* xn, const Edge& e0, const Edge& e1,
                                                  double h, bool damping, const double* g0, const double* g1) {
  using namespace simd;
  const Pair3 xi = load_pair(x + 3 * e0.i, x + 3 * e1.i), xj = load_pair(x + 3 * e0.j, x + 3 * e1.j);
  const Pair3 d = sub(xj, xi);
  const __m128d D0 = _mm_set_pd(e1.D0, e0.D0);
  const __m128d len = _mm_sqrt_pd(dot(d, d));
  const __m128d den = _mm_mul_pd(len, D0);
  const __m128d positive = _mm_cmpgt_pd(len, _mm_setzero_pd());  // len > 0 (false for NaN): else ∂C/∂p_j = 0
  const Pair3 gj{_mm_and_pd(positive, _mm_div_pd(d.x, den)), _mm_and_pd(positive, _mm_div_pd(d.y, den)),
                 _mm_and_pd(positive, _mm_div_pd(d.z, den))};
  const __m128d C = _mm_div_pd(_mm_sub_pd(len, D0), D0);
  Pair3 f = scale(_mm_mul_pd(_mm_set_pd(e1.k, e0.k), C), gj);
  const __m128d kd = _mm_set_pd(e1.kd, e0.kd);
  const __m128d damped = _mm_cmpgt_pd(kd, _mm_setzero_pd());
  if (damping && _mm_movemask_pd(damped)) {
    const Pair3 g = load_pair(g0, g1);
    const Pair3 dx = sub(sub(xj, load_pair(xn + 3 * e0.j, xn + 3 * e1.j)), sub(xi, load_pair(xn + 3 * e0.i, xn + 3 * e1.i)));
    const Pair3 sum = add(f, scale(_mm_mul_pd(_mm_div_pd(kd, _mm_set1_pd(h)), dot(g, dx)), g));
    auto pick = [&](__m128d with, __m128d without) { return _mm_or_pd(_mm_and_pd(damped, with), _mm_andnot_pd(damped, without)); };
    f = {pick(sum.x, f.x), pick(sum.y, f.y), pick(sum.z, f.z)};
  }
  return f;
}

/// The gradient of a tetrahedron's energy, plus its damping potential's where `damping`:
/// f[k] = k C ∂C/∂p_k (+ (k_d / h) q ∂C/∂p_k(x_n), q = 0 where k_d = 0), of two tetrahedra at once.
template <class Tet>
SQUEEZE_FEM_INLINE void tet_gradient_pair(const double* x, const double* xn, const Tet& t0, const Tet& t1, double h,
                                          bool damping, const double* g0, const double* g1, simd::Pair3 f[4]) {
  using namespace simd;
  Pair3 p[4];
  for (int c = 0; c < 4; ++c) p[c] = load_pair(x + 3 * t0.v[c], x + 3 * t1.v[c]);
  const __m128d V0 = _mm_set_pd(t1.V0, t0.V0);
  const Pair3 a = sub(p[1], p[0]), b = sub(p[2], p[0]), c = sub(p[3], p[0]);
  const Pair3 bc = cross(b, c);
  const __m128d V = _mm_div_pd(dot(a, bc), _mm_set1_pd(6.0));
  const __m128d s = _mm_div_pd(_mm_set1_pd(1.0), _mm_mul_pd(_mm_set1_pd(6.0), V0));
  Pair3 g[4];
  g[1] = scale(s, bc);
  g[2] = scale(s, cross(c, a));
  g[3] = scale(s, cross(a, b));
  g[0] = neg(add(add(g[1], g[2]), g[3]));
  const __m128d kC = _mm_mul_pd(_mm_set_pd(t1.k, t0.k), _mm_div_pd(_mm_sub_pd(V, V0), V0));
  if (!damping) {
    for (int k = 0; k < 4; ++k) f[k] = scale(kC, g[k]);
    return;
  }
  const __m128d kd = _mm_set_pd(t1.kd, t0.kd);
  const __m128d damped = _mm_cmpgt_pd(kd, _mm_setzero_pd());
  Pair3 tg[4];
  for (int k = 0; k < 4; ++k) tg[k] = load_pair(g0 + 3 * k, g1 + 3 * k);
  __m128d q = _mm_setzero_pd();
  for (int k = 0; k < 4; ++k) q = _mm_add_pd(q, dot(tg[k], sub(p[k], load_pair(xn + 3 * t0.v[k], xn + 3 * t1.v[k]))));
  q = _mm_and_pd(damped, q);  // 0 where k_d = 0
  const __m128d r = _mm_mul_pd(_mm_div_pd(kd, _mm_set1_pd(h)), q);
  for (int k = 0; k < 4; ++k) f[k] = add(scale(kC, g[k]), scale(r, tg[k]));
}
#endif

}  // namespace squeeze::fem
