#include "squeeze/meshing/winding_number.h"

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numeric>

namespace squeeze::meshing {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr double kInv4Pi = 0.25 / M_PI;

// The signed solid angle of triangle (a,b,c) seen from the origin (a,b,c relative to the query
// point) is 2 atan2(det, den) (Van Oosterom and Strackee 1983): its two arguments.
struct HalfSolidAngle {
  double det, den;
};
inline HalfSolidAngle half_solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  return {a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb};
}

// The solid angle with the library's atan2 (the exact reference, winding_number()).
inline double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const HalfSolidAngle h = half_solid_angle(a, b, c);
  return 2.0 * std::atan2(h.det, h.den);
}

inline double atan2_poly(double y, double x) {
  // atan(t) on [0, tan(π/8)]: t + t·z·h(z), z = t², h a degree-8 polynomial fitted to
  // (atan(t)/t − 1)/z by Chebyshev least squares at 4,000 Chebyshev points (numpy, 2026-11-25):
  // largest error 4.2e-15 over 400,001 points. [tan(π/8), 1] maps onto it by
  // atan(t) = π/4 + atan((t − 1)/(t + 1)); [1, ∞) by atan(t) = π/2 − atan(1/t). Written as
  // selects, not branches: the octant of a near triangle's solid angle is unpredictable.
  constexpr double h[9] = {-0.3333333333335414,  0.20000000004948473,  -0.14285714521837525,
                           0.11111111354908106,  -0.09090677935795236, 0.07685695705908752,
                           -0.06580081428765631, 0.05265909942421324,  -0.028562535080168986};
  constexpr double kTanPi8 = 0.41421356237309503;
  if (std::isnan(x) || std::isnan(y)) return x + y;
  const double ax = std::abs(x), ay = std::abs(y);
  const double num = std::min(ax, ay), den = std::max(ax, ay);
  if (!(den > 0)) return std::signbit(x) ? std::copysign(M_PI, y) : std::copysign(0.0, y);  // atan2(±0, ±0)
  const double t0 = num / den;  // in [0, 1]
  const bool upper = t0 > kTanPi8;
  const double t1 = (t0 - 1) / (t0 + 1);
  const double t = upper ? t1 : t0, base = upper ? M_PI_4 : 0.0;
  const double z = t * t;
  double p = h[8];
  for (int k = 7; k >= 0; --k) p = p * z + h[k];
  double r = base + (t + t * z * p);
  r = ay > ax ? M_PI_2 - r : r;
  r = x < 0 ? M_PI - r : r;
  return std::copysign(r, y);
}

}  // namespace

double fast_atan2(double y, double x) { return atan2_poly(y, x); }

double triangle_winding_number(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b, const Eigen::RowVector3d& c,
                               const Eigen::RowVector3d& p) {
  const HalfSolidAngle h = half_solid_angle((a - p).transpose(), (b - p).transpose(), (c - p).transpose());
  return atan2_poly(h.det, h.den) / (2 * M_PI);
}

double winding_number(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Eigen::RowVector3d& p) {
  double w = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    w += solid_angle(V.row(F(f, 0)).transpose() - p.transpose(), V.row(F(f, 1)).transpose() - p.transpose(),
                     V.row(F(f, 2)).transpose() - p.transpose());
  return w * kInv4Pi;
}

struct FastWindingNumber::Impl {
  // The traversal's data in two arrays, in tree order: what every visited node needs (centre,
  // reach, children), then what a far one adds (its expansion), so that the hot part stays in
  // cache (144-byte nodes were the queries' cache misses on the heart's 10,000 nodes).
  struct Hot {
    Vec3 centre;      // area-weighted centroid of its triangles
    double reach2;    // (beta × the largest distance from centre to a triangle vertex)²
    int left, right;  // children, or -1 for a leaf
    int begin, end;   // triangle range in tree order (leaves)
  };
  struct Far {
    Vec3 area_n;                // sum of the triangles' area vectors (0.5 × cross products)
    Eigen::Matrix3d moment;     // Σ (x̄_t − centre) A_tᵀ: the first moments about the centre times normals
    double moment_trace;        // tr moment
    Eigen::Matrix3d second[3];  // second[k] = Σ n_tk ∫_t (x − centre)(x − centre)ᵀ dA
    Vec3 second_trace;          // tr second[k]
  };
  std::vector<Hot> hot;
  std::vector<Far> far_data;
  std::vector<Vec3> a, b, c;  // triangle corners, in tree order
  double beta;

  int build(std::vector<int>& order, std::vector<Vec3>& cen, int begin, int end) {
    const int id = static_cast<int>(hot.size());
    hot.emplace_back();
    far_data.emplace_back();
    Hot h{Vec3::Zero(), 0.0, -1, -1, begin, end};
    Far f;
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    Vec3 weighted = Vec3::Zero();
    double area = 0.0;
    f.area_n = Vec3::Zero();
    for (int i = begin; i < end; ++i) {
      const int t = order[i];
      lo = lo.cwiseMin(cen[t]);
      hi = hi.cwiseMax(cen[t]);
      const double ar = an0[t].norm();
      f.area_n += an0[t];
      weighted += ar * cen[t];
      area += ar;
    }
    h.centre = area > 0 ? Vec3(weighted / area) : Vec3(0.5 * (lo + hi));
    double r2 = 0.0;
    f.moment.setZero();
    for (auto& m : f.second) m.setZero();
    for (int i = begin; i < end; ++i) {
      const int t = order[i];
      const Vec3 va = a0[t] - h.centre, vb = b0[t] - h.centre, vc = c0[t] - h.centre, g = cen[t] - h.centre;
      r2 = std::max({r2, va.squaredNorm(), vb.squaredNorm(), vc.squaredNorm()});
      f.moment += g * an0[t].transpose();
      // ∫_t δ δᵀ dA = area/12 (Σ v vᵀ + 9 g gᵀ), vertices and centroid relative to the centre.
      const Eigen::Matrix3d s = (va * va.transpose() + vb * vb.transpose() + vc * vc.transpose() + 9.0 * g * g.transpose()) / 12.0;
      for (int k = 0; k < 3; ++k) f.second[k] += an0[t](k) * s;
    }
    h.reach2 = beta * beta * r2;
    f.moment_trace = f.moment.trace();
    for (int k = 0; k < 3; ++k) f.second_trace(k) = f.second[k].trace();
    if (end - begin > 8) {
      int axis;
      (hi - lo).maxCoeff(&axis);
      const int mid = (begin + end) / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                       [&](int x, int y) { return cen[x][axis] < cen[y][axis] || (cen[x][axis] == cen[y][axis] && x < y); });
      h.left = build(order, cen, begin, mid);
      h.right = build(order, cen, mid, end);
    }
    hot[static_cast<size_t>(id)] = h;
    far_data[static_cast<size_t>(id)] = f;
    return id;
  }
  std::vector<Vec3> a0, b0, c0, an0;  // input order, during build (an0: area × normal)

  // Far clusters by their expansion to second order, near leaves triangle by triangle; one pass
  // down the tree with an explicit stack.
  double eval(const Vec3& p) const {
    double far = 0.0, near = 0.0;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const int id = stack[--top];
      const Hot& n = hot[static_cast<size_t>(id)];
      const Vec3 d = n.centre - p;
      const double d2 = d.squaredNorm();
      if (d2 > n.reach2 && n.reach2 > 0) {
        // ∫ f(d + δ)·n dA, f(r) = r / |r|³ = −∇(1/|r|), to second order in δ about the centre:
        //   f(d)·A + tr(J M) + ½ Σ_kij C_kij T_ijk, with J = I/r³ − 3 d dᵀ/r⁵ and
        //   T_ijk = 15 d_i d_j d_k / r⁷ − 3 (δ_ij d_k + δ_ik d_j + δ_jk d_i) / r⁵ (−∂³(1/r)),
        //   C_kij = second[k]_ij (symmetric in ij).
        const Far& e = far_data[static_cast<size_t>(id)];
        const double inv2 = 1.0 / d2, inv3 = inv2 * std::sqrt(inv2), inv5 = inv3 * inv2;
        const Vec3 c0 = e.second[0] * d, c1 = e.second[1] * d, c2 = e.second[2] * d;
        const double dcd = d(0) * d.dot(c0) + d(1) * d.dot(c1) + d(2) * d.dot(c2);  // Σ_k d_k dᵀ C_k d
        const double cdk = c0(0) + c1(1) + c2(2);                                  // Σ_k (C_k d)_k
        far += inv3 * (d.dot(e.area_n) + e.moment_trace) - 3.0 * inv5 * d.dot(e.moment * d) +
               0.5 * (15.0 * inv5 * inv2 * dcd - 3.0 * inv5 * (d.dot(e.second_trace) + 2.0 * cdk));
        continue;
      }
      if (n.left < 0) {
        for (int i = n.begin; i < n.end; ++i) {
          const size_t t = static_cast<size_t>(i);
          const HalfSolidAngle h = half_solid_angle(a[t] - p, b[t] - p, c[t] - p);
          near += atan2_poly(h.det, h.den);
        }
        continue;
      }
      stack[top++] = n.right;
      stack[top++] = n.left;
    }
    return kInv4Pi * far + 2.0 * kInv4Pi * near;
  }
};

FastWindingNumber::FastWindingNumber(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double beta)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.beta = beta;
  const int nf = static_cast<int>(F.rows());
  m.a0.resize(nf);
  m.b0.resize(nf);
  m.c0.resize(nf);
  m.an0.resize(nf);
  std::vector<Vec3> cen(nf);
  for (int f = 0; f < nf; ++f) {
    m.a0[f] = V.row(F(f, 0)).transpose();
    m.b0[f] = V.row(F(f, 1)).transpose();
    m.c0[f] = V.row(F(f, 2)).transpose();
    cen[f] = (m.a0[f] + m.b0[f] + m.c0[f]) / 3.0;
    m.an0[f] = 0.5 * (m.b0[f] - m.a0[f]).cross(m.c0[f] - m.a0[f]);
  }
  std::vector<int> order(nf);
  std::iota(order.begin(), order.end(), 0);
  m.hot.reserve(static_cast<size_t>(2 * nf / 4 + 2));
  m.far_data.reserve(m.hot.capacity());
  if (nf > 0) m.build(order, cen, 0, nf);
  m.a.resize(nf);
  m.b.resize(nf);
  m.c.resize(nf);
  for (int i = 0; i < nf; ++i) {
    m.a[i] = m.a0[order[i]];
    m.b[i] = m.b0[order[i]];
    m.c[i] = m.c0[order[i]];
  }
  m.a0.clear(); m.b0.clear(); m.c0.clear(); m.an0.clear();
  m.a0.shrink_to_fit(); m.b0.shrink_to_fit(); m.c0.shrink_to_fit(); m.an0.shrink_to_fit();
}

FastWindingNumber::~FastWindingNumber() = default;
FastWindingNumber::FastWindingNumber(FastWindingNumber&&) noexcept = default;

double FastWindingNumber::operator()(const Eigen::RowVector3d& p) const {
  if (impl_->hot.empty()) return 0.0;
  return impl_->eval(p.transpose());
}

Eigen::VectorXd face_offset_winding_numbers(const FastWindingNumber& w, const Eigen::MatrixX3d& V,
                                            const Eigen::MatrixX3i& F, double offset, Eigen::VectorXd* outside,
                                            Eigen::VectorXd* inside) {
  Eigen::VectorXd area = Eigen::VectorXd::Zero(F.rows());
  if (outside) outside->setConstant(F.rows(), std::numeric_limits<double>::quiet_NaN());
  if (inside) inside->setConstant(F.rows(), std::numeric_limits<double>::quiet_NaN());
  tbb::parallel_for(Eigen::Index(0), F.rows(), [&](Eigen::Index f) {
    const Eigen::RowVector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    if (!(len > 0)) return;
    area(f) = 0.5 * len;
    const Eigen::RowVector3d m = (a + b + c) / 3.0, u = n / len * offset;
    if (outside) (*outside)(f) = w(m + u);
    if (inside) (*inside)(f) = w(m - u);
  });
  return area;
}

double winding_volume(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, Eigen::RowVector3d* jump_area) {
  if (jump_area) jump_area->setZero();
  if (V.rows() == 0 || F.rows() == 0) return 0.0;
  const FastWindingNumber w(V, F);
  const Eigen::RowVector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  const double eps = 1e-4 * (hi - lo).norm();
  const Eigen::RowVector3d apex = 0.5 * (lo + hi);
  std::vector<double> vol(static_cast<size_t>(F.rows()), 0.0);
  std::vector<int> jumps(static_cast<size_t>(F.rows()), 0);
  tbb::parallel_for(Eigen::Index(0), F.rows(), [&](Eigen::Index f) {
    const Eigen::RowVector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a);
    if (!(n.norm() > 0)) return;
    const Eigen::RowVector3d m = (a + b + c) / 3.0, u = n.normalized() * eps;
    auto own = [&](const Eigen::RowVector3d& q) { return triangle_winding_number(a, b, c, q); };
    const double rest = 0.5 * ((w(m - u) - own(m - u)) + (w(m + u) - own(m + u)));
    const int jump = (rest > -0.25 ? 1 : 0) - (rest > 0.75 ? 1 : 0);
    jumps[static_cast<size_t>(f)] = jump;
    vol[static_cast<size_t>(f)] = jump * (a - apex).dot((b - apex).cross(c - apex)) / 6.0;
  });
  double sum = 0;
  for (double x : vol) sum += x;  // (in face order: the same sum whatever the threads)
  if (jump_area)
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      if (jumps[static_cast<size_t>(f)] != 0)
        *jump_area += jumps[static_cast<size_t>(f)] / 6.0 *
                      (V.row(F(f, 1)) - V.row(F(f, 0))).cross(V.row(F(f, 2)) - V.row(F(f, 0)));
  return sum;
}

}  // namespace squeeze::meshing
