#include "squeeze/meshing/winding_number.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace squeeze::meshing {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr double kInv4Pi = 0.25 / M_PI;

// Signed solid angle of triangle (a,b,c) seen from the origin (a,b,c relative to the query point).
inline double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double det = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
  return 2.0 * std::atan2(det, den);
}

}  // namespace

double winding_number(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Eigen::RowVector3d& p) {
  double w = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    w += solid_angle(V.row(F(f, 0)).transpose() - p.transpose(), V.row(F(f, 1)).transpose() - p.transpose(),
                     V.row(F(f, 2)).transpose() - p.transpose());
  return w * kInv4Pi;
}

struct FastWindingNumber::Impl {
  struct Node {
    Vec3 centre;     // area-weighted centroid of its triangles
    Vec3 area_n;     // sum of area-weighted normals (0.5 × cross products)
    double radius;   // max distance from centre to any triangle vertex
    int left = -1, right = -1;  // children, or -1 for a leaf
    int begin = 0, end = 0;     // triangle range in order (leaves)
  };
  std::vector<Vec3> a, b, c;  // triangle corners, in tree order
  std::vector<Node> nodes;
  double beta;

  int build(std::vector<int>& order, std::vector<Vec3>& cen, int begin, int end) {
    const int id = static_cast<int>(nodes.size());
    nodes.emplace_back();
    Node n;
    n.begin = begin;
    n.end = end;
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    Vec3 weighted = Vec3::Zero();
    double area = 0.0;
    n.area_n = Vec3::Zero();
    for (int i = begin; i < end; ++i) {
      const int t = order[i];
      lo = lo.cwiseMin(cen[t]);
      hi = hi.cwiseMax(cen[t]);
      const Vec3 an = 0.5 * (b0[t] - a0[t]).cross(c0[t] - a0[t]);
      const double ar = an.norm();
      n.area_n += an;
      weighted += ar * cen[t];
      area += ar;
    }
    n.centre = area > 0 ? Vec3(weighted / area) : Vec3(0.5 * (lo + hi));
    double r2 = 0.0;
    for (int i = begin; i < end; ++i) {
      const int t = order[i];
      r2 = std::max({r2, (a0[t] - n.centre).squaredNorm(), (b0[t] - n.centre).squaredNorm(),
                     (c0[t] - n.centre).squaredNorm()});
    }
    n.radius = std::sqrt(r2);
    if (end - begin > 8) {
      int axis;
      (hi - lo).maxCoeff(&axis);
      const int mid = (begin + end) / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                       [&](int x, int y) { return cen[x][axis] < cen[y][axis] || (cen[x][axis] == cen[y][axis] && x < y); });
      n.left = build(order, cen, begin, mid);
      n.right = build(order, cen, mid, end);
    }
    nodes[id] = n;
    return id;
  }
  std::vector<Vec3> a0, b0, c0;  // input order, during build

  double eval(const Vec3& p, int id) const {
    const Node& n = nodes[id];
    const Vec3 d = n.centre - p;
    const double dist = d.norm();
    if (dist > beta * n.radius && n.radius > 0) return kInv4Pi * d.dot(n.area_n) / (dist * dist * dist);
    if (n.left < 0) {
      double w = 0.0;
      for (int i = n.begin; i < n.end; ++i) w += solid_angle(a[i] - p, b[i] - p, c[i] - p);
      return w * kInv4Pi;
    }
    return eval(p, n.left) + eval(p, n.right);
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
  std::vector<Vec3> cen(nf);
  for (int f = 0; f < nf; ++f) {
    m.a0[f] = V.row(F(f, 0)).transpose();
    m.b0[f] = V.row(F(f, 1)).transpose();
    m.c0[f] = V.row(F(f, 2)).transpose();
    cen[f] = (m.a0[f] + m.b0[f] + m.c0[f]) / 3.0;
  }
  std::vector<int> order(nf);
  std::iota(order.begin(), order.end(), 0);
  m.nodes.reserve(static_cast<size_t>(2 * nf / 4 + 2));
  if (nf > 0) m.build(order, cen, 0, nf);
  m.a.resize(nf);
  m.b.resize(nf);
  m.c.resize(nf);
  for (int i = 0; i < nf; ++i) {
    m.a[i] = m.a0[order[i]];
    m.b[i] = m.b0[order[i]];
    m.c[i] = m.c0[order[i]];
  }
  m.a0.clear(); m.b0.clear(); m.c0.clear();
  m.a0.shrink_to_fit(); m.b0.shrink_to_fit(); m.c0.shrink_to_fit();
}

FastWindingNumber::~FastWindingNumber() = default;
FastWindingNumber::FastWindingNumber(FastWindingNumber&&) noexcept = default;

double FastWindingNumber::operator()(const Eigen::RowVector3d& p) const {
  if (impl_->nodes.empty()) return 0.0;
  return impl_->eval(p.transpose(), 0);
}

}  // namespace squeeze::meshing
