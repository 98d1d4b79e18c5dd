// squeeze::fem — 3×3 block-vector products of the sparse solver (block_ldlt.cpp) and of the
// implicit integrator's Newton matrix (implicit.cpp), private to fem/src.
//
// The same IEEE operations in the same order as the Eigen expressions they replaced (Eigen 3.4
// with SSE2), so the factors, solutions and products are bit for bit those of the build before
// (the trajectories of bench/scenes/ball_drop, headon and organs are byte-identical), without
// Eigen's per-block index arithmetic and one-at-a-time conversions of single-precision blocks.
// Each entry of a block-vector product is a sum of three products, which Eigen associated two
// ways: its SSE2 product of a double block (rows 0 and 1 as a pair) and its product of a
// transposed double block as (a₀ + a₁) + a₂; row 2 of a double block and every entry of a
// single-precision block (converted to double one number at a time) as a₀ + (a₁ + a₂). kRight:
// the single-precision factor's association (every entry a₀ + (a₁ + a₂)), whether its blocks are
// read as floats or as the doubles they round to. The result is then assigned to, added to or
// subtracted from its target (Op).
#pragma once
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace squeeze::fem::blocks {

enum class Op { kAssign, kAdd, kSubtract };  // t = x, t += x, t −= x

inline double sum_right(double a0, double a1, double a2) { return a0 + (a1 + a2); }
inline double sum_left(double a0, double a1, double a2) { return (a0 + a1) + a2; }
#if defined(__SSE2__)
// Rows 0 and 1 of column c of a column-major 3×3 block, as doubles.
inline __m128d column01(const double* b, int c) { return _mm_loadu_pd(b + 3 * c); }
inline __m128d column01(const float* b, int c) {
  return _mm_cvtps_pd(_mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(b + 3 * c))));
}
template <Op kOp>
inline void combine(double* t, __m128d x) {
  if (kOp == Op::kAssign)
    _mm_storeu_pd(t, x);
  else
    _mm_storeu_pd(t, kOp == Op::kAdd ? _mm_add_pd(_mm_loadu_pd(t), x) : _mm_sub_pd(_mm_loadu_pd(t), x));
}
#endif
template <Op kOp>
inline void combine(double& t, double x) {
  if (kOp == Op::kAssign)
    t = x;
  else if (kOp == Op::kAdd)
    t += x;
  else
    t -= x;
}

// t ← B v, t + B v or t − B v (t, v: 3 doubles; B: a column-major 3×3 block of doubles or floats).
template <Op kOp, bool kRight, class Real>
inline void product(const Real* B, const double* v, double* t) {
#if defined(__SSE2__)
  const __m128d v0 = _mm_set1_pd(v[0]), v1 = _mm_set1_pd(v[1]), v2 = _mm_set1_pd(v[2]);
  const __m128d p0 = _mm_mul_pd(column01(B, 0), v0), p1 = _mm_mul_pd(column01(B, 1), v1), p2 = _mm_mul_pd(column01(B, 2), v2);
  const __m128d xy = kRight ? _mm_add_pd(p0, _mm_add_pd(p1, p2)) : _mm_add_pd(_mm_add_pd(p0, p1), p2);
  combine<kOp>(t, xy);
#else
  for (int r = 0; r < 2; ++r) {
    const double a0 = static_cast<double>(B[r]) * v[0], a1 = static_cast<double>(B[3 + r]) * v[1],
                 a2 = static_cast<double>(B[6 + r]) * v[2];
    combine<kOp>(t[r], kRight ? sum_right(a0, a1, a2) : sum_left(a0, a1, a2));
  }
#endif
  combine<kOp>(t[2], sum_right(static_cast<double>(B[2]) * v[0], static_cast<double>(B[5]) * v[1],
                                     static_cast<double>(B[8]) * v[2]));
}

// The same with Bᵀ.
template <Op kOp, bool kRight, class Real>
inline void transposed_product(const Real* B, const double* v, double* t) {
#if defined(__SSE2__)
  // Entries 0 and 1 as a pair: the rows of B's columns 0 and 1, (B(r,0), B(r,1)).
  const __m128d c0 = column01(B, 0), c1 = column01(B, 1), c2 = column01(B, 2);  // (B(0,c), B(1,c))
  const __m128d r0 = _mm_unpacklo_pd(c0, c1), r1 = _mm_unpackhi_pd(c0, c1);
  const __m128d r2 = _mm_set_pd(static_cast<double>(B[5]), static_cast<double>(B[2]));
  const __m128d v01 = _mm_loadu_pd(v), v2 = _mm_set1_pd(v[2]);
  const __m128d p0 = _mm_mul_pd(r0, _mm_unpacklo_pd(v01, v01)), p1 = _mm_mul_pd(r1, _mm_unpackhi_pd(v01, v01)),
                p2 = _mm_mul_pd(r2, v2);
  const __m128d xy = kRight ? _mm_add_pd(p0, _mm_add_pd(p1, p2)) : _mm_add_pd(_mm_add_pd(p0, p1), p2);
  combine<kOp>(t, xy);
  // Entry 2: column 2 of B with v.
  const __m128d q = _mm_mul_pd(c2, v01);
  const double a0 = _mm_cvtsd_f64(q), a1 = _mm_cvtsd_f64(_mm_unpackhi_pd(q, q)), a2 = static_cast<double>(B[8]) * v[2];
  combine<kOp>(t[2], kRight ? sum_right(a0, a1, a2) : sum_left(a0, a1, a2));
#else
  for (int c = 0; c < 3; ++c) {  // column c of B with v
    const double a0 = static_cast<double>(B[3 * c]) * v[0], a1 = static_cast<double>(B[3 * c + 1]) * v[1],
                 a2 = static_cast<double>(B[3 * c + 2]) * v[2];
    combine<kOp>(t[c], kRight ? sum_right(a0, a1, a2) : sum_left(a0, a1, a2));
  }
#endif
}

// A 3-vector accumulated in registers (entries 0 and 1 as a pair): t.add_product(B, v) is
// product<Op::kAdd, false>(B, v, t) and t.add_transposed_product(B, v) transposed_product<Op::kAdd,
// false>(B, v, t) for double blocks, the same sums; the loops that sum many blocks into one
// vector keep it out of memory (the stores of the others may alias it for all the compiler
// knows, and it went through memory at every block).
struct Sum3 {
#if defined(__SSE2__)
  __m128d xy;
  double z;
  explicit Sum3(const double* v) : xy(_mm_loadu_pd(v)), z(v[2]) {}
  void store(double* t) const {
    _mm_storeu_pd(t, xy);
    t[2] = z;
  }
  void add_product(const double* B, const double* v) {
    const __m128d v0 = _mm_set1_pd(v[0]), v1 = _mm_set1_pd(v[1]), v2 = _mm_set1_pd(v[2]);
    xy = _mm_add_pd(xy, _mm_add_pd(_mm_add_pd(_mm_mul_pd(column01(B, 0), v0), _mm_mul_pd(column01(B, 1), v1)),
                                   _mm_mul_pd(column01(B, 2), v2)));
    z += sum_right(B[2] * v[0], B[5] * v[1], B[8] * v[2]);
  }
  void add_transposed_product(const double* B, const double* v) {
    const __m128d c0 = column01(B, 0), c1 = column01(B, 1), c2 = column01(B, 2);
    const __m128d v01 = _mm_loadu_pd(v);
    const __m128d p0 = _mm_mul_pd(_mm_unpacklo_pd(c0, c1), _mm_unpacklo_pd(v01, v01));
    const __m128d p1 = _mm_mul_pd(_mm_unpackhi_pd(c0, c1), _mm_unpackhi_pd(v01, v01));
    const __m128d p2 = _mm_mul_pd(_mm_set_pd(B[5], B[2]), _mm_set1_pd(v[2]));
    xy = _mm_add_pd(xy, _mm_add_pd(_mm_add_pd(p0, p1), p2));
    const __m128d q = _mm_mul_pd(c2, v01);
    z += sum_left(_mm_cvtsd_f64(q), _mm_cvtsd_f64(_mm_unpackhi_pd(q, q)), B[8] * v[2]);
  }
#else
  double t3[3];
  explicit Sum3(const double* v) : t3{v[0], v[1], v[2]} {}
  void store(double* t) const { t[0] = t3[0], t[1] = t3[1], t[2] = t3[2]; }
  void add_product(const double* B, const double* v) { product<Op::kAdd, false>(B, v, t3); }
  void add_transposed_product(const double* B, const double* v) { transposed_product<Op::kAdd, false>(B, v, t3); }
#endif
};

}  // namespace squeeze::fem::blocks
