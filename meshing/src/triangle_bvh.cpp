#include "squeeze/meshing/triangle_bvh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "squeeze/meshing/point_triangle_distance.h"

namespace squeeze::meshing {

using Vec3 = Eigen::Vector3d;

namespace {

double box_distance2(const Vec3& lo, const Vec3& hi, const Vec3& p) {
  const double x = std::max(std::max(lo(0) - p(0), 0.0), p(0) - hi(0));
  const double y = std::max(std::max(lo(1) - p(1), 0.0), p(1) - hi(1));
  const double z = std::max(std::max(lo(2) - p(2), 0.0), p(2) - hi(2));
  return x * x + y * y + z * z;
}

// Whether the segment a + t (b - a), t in [0, 1], meets the box (slab test).
bool segment_meets_box(const Vec3& a, const Vec3& b, const Vec3& lo, const Vec3& hi) {
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    const double d = b(k) - a(k);
    if (std::abs(d) < 1e-300) {
      if (a(k) < lo(k) || a(k) > hi(k)) return false;
      continue;
    }
    double u = (lo(k) - a(k)) / d, v = (hi(k) - a(k)) / d;
    if (u > v) std::swap(u, v);
    t0 = std::max(t0, u);
    t1 = std::min(t1, v);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

TriangleBvh::TriangleBvh(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) : V_(V), F_(F) {
  const int n = static_cast<int>(F_.rows());
  order_.resize(static_cast<size_t>(n));
  std::iota(order_.begin(), order_.end(), 0);
  std::vector<Vec3> centroid(static_cast<size_t>(n));
  for (int f = 0; f < n; ++f)
    centroid[static_cast<size_t>(f)] = (V_.row(F_(f, 0)) + V_.row(F_(f, 1)) + V_.row(F_(f, 2))).transpose() / 3.0;
  nodes_.reserve(static_cast<size_t>(2 * n / 4 + 2));
  if (n > 0) build(0, n, centroid);
  corner_.resize(static_cast<size_t>(n));
  for (size_t i = 0; i < corner_.size(); ++i)
    for (int k = 0; k < 3; ++k) corner_[i][static_cast<size_t>(k)] = V_.row(F_(order_[i], k)).transpose();
}

int TriangleBvh::build(int begin, int end, std::vector<Vec3>& centroid) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Vec3 lo = Vec3::Constant(INFINITY), hi = -lo, clo = lo, chi = hi;
  for (int i = begin; i < end; ++i) {
    const int f = order_[static_cast<size_t>(i)];
    for (int k = 0; k < 3; ++k) {
      lo = lo.cwiseMin(V_.row(F_(f, k)).transpose());
      hi = hi.cwiseMax(V_.row(F_(f, k)).transpose());
    }
    clo = clo.cwiseMin(centroid[static_cast<size_t>(f)]);
    chi = chi.cwiseMax(centroid[static_cast<size_t>(f)]);
  }
  nodes_[static_cast<size_t>(id)].lo = lo;
  nodes_[static_cast<size_t>(id)].hi = hi;
  if (end - begin <= 4) {
    nodes_[static_cast<size_t>(id)].begin = begin;
    nodes_[static_cast<size_t>(id)].end = end;
    return id;
  }
  int axis;
  (chi - clo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](int a, int b) {
    const double x = centroid[static_cast<size_t>(a)](axis), y = centroid[static_cast<size_t>(b)](axis);
    return x != y ? x < y : a < b;
  });
  const int left = build(begin, mid, centroid);
  const int right = build(mid, end, centroid);
  nodes_[static_cast<size_t>(id)].left = left;
  nodes_[static_cast<size_t>(id)].right = right;
  return id;
}

Vec3 TriangleBvh::normal(int f) const {
  const Vec3 a = V_.row(F_(f, 0)).transpose(), b = V_.row(F_(f, 1)).transpose(), c = V_.row(F_(f, 2)).transpose();
  const Vec3 n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Vec3(n / len) : Vec3::Zero();
}

double TriangleBvh::nearest(const Vec3& p, int* face, Vec3* closest, double bound) const {
  double best2 = bound * bound;
  int best_face = -1;
  Vec3 best_point = p;
  if (nodes_.empty()) {
    if (face) *face = -1;
    return INFINITY;
  }
  // Each node with its box's squared distance from p, computed once (when pushed).
  struct Entry {
    int node;
    double d2;
  };
  Entry stack[128];
  int top = 0;
  stack[top++] = {0, box_distance2(nodes_[0].lo, nodes_[0].hi, p)};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 > best2) continue;
    const Node& node = nodes_[static_cast<size_t>(e.node)];
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        const auto& c = corner_[static_cast<size_t>(i)];
        const Vec3 q = closest_point_on_triangle(p, c[0], c[1], c[2]);
        const double d2 = (q - p).squaredNorm();
        const int f = order_[static_cast<size_t>(i)];
        if (d2 < best2 || (d2 == best2 && best_face >= 0 && f < best_face)) {
          best2 = d2;
          best_face = f;
          best_point = q;
        }
      }
      continue;
    }
    const Node& l = nodes_[static_cast<size_t>(node.left)];
    const Node& r = nodes_[static_cast<size_t>(node.right)];
    const double dl = box_distance2(l.lo, l.hi, p), dr = box_distance2(r.lo, r.hi, p);
    // Nearer child on top of the stack (a child already farther than the best is not pushed: it
    // would be passed over when popped, best2 only shrinking).
    if (dl <= dr) {
      if (dr <= best2) stack[top++] = {node.right, dr};
      if (dl <= best2) stack[top++] = {node.left, dl};
    } else {
      if (dl <= best2) stack[top++] = {node.left, dl};
      if (dr <= best2) stack[top++] = {node.right, dr};
    }
  }
  if (face) *face = best_face;
  if (closest) *closest = best_point;
  return best_face >= 0 ? std::sqrt(best2) : INFINITY;
}

bool TriangleBvh::any_within(const Vec3& p, double r) const {
  if (nodes_.empty() || !(r >= 0)) return false;
  const double r2 = r * r;
  int stack[128];
  int top = 0;
  if (box_distance2(nodes_[0].lo, nodes_[0].hi, p) > r2) return false;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[static_cast<size_t>(stack[--top])];
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        const auto& c = corner_[static_cast<size_t>(i)];
        if ((closest_point_on_triangle(p, c[0], c[1], c[2]) - p).squaredNorm() <= r2) return true;
      }
      continue;
    }
    const Node& l = nodes_[static_cast<size_t>(node.left)];
    const Node& rt = nodes_[static_cast<size_t>(node.right)];
    // Only children within r, the nearer on top of the stack.
    const double dl = box_distance2(l.lo, l.hi, p), dr = box_distance2(rt.lo, rt.hi, p);
    if (dl <= dr) {
      if (dr <= r2) stack[top++] = node.right;
      if (dl <= r2) stack[top++] = node.left;
    } else {
      if (dl <= r2) stack[top++] = node.left;
      if (dr <= r2) stack[top++] = node.right;
    }
  }
  return false;
}

bool TriangleBvh::first_crossing(const Vec3& a, const Vec3& b, double t_min, double* t_out) const {
  return crossing(a, b, t_min, true, t_out);
}

bool TriangleBvh::crossing_nearest(const Vec3& a, const Vec3& b, double hint, double* t_out) const {
  return crossing(a, b, hint, false, t_out);
}

bool TriangleBvh::crossing(const Vec3& a, const Vec3& b, double hint, bool after, double* t_out) const {
  if (nodes_.empty()) return false;
  const Vec3 d = b - a;
  const double d2 = d.squaredNorm();  // (the in-plane test's, once per segment)
  bool found = false;
  double best = INFINITY, best_t = 0;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[static_cast<size_t>(stack[--top])];
    if (!segment_meets_box(a, b, node.lo, node.hi)) continue;
    if (node.left >= 0) {
      stack[top++] = node.left;
      stack[top++] = node.right;
      continue;
    }
    for (int i = node.begin; i < node.end; ++i) {
      const auto& c = corner_[static_cast<size_t>(i)];
      const Vec3 &p0 = c[0], &p1 = c[1], &p2 = c[2];
      // Möller–Trumbore.
      const Vec3 e1 = p1 - p0, e2 = p2 - p0, h = d.cross(e2);
      const double det = e1.dot(h);
      // (A segment in the triangle's plane crosses nothing: det = -d · (e1 × e2) is then rounding
      // alone, and u, v and t are noise. Skipped where |det| is under 1e-12 of its bound
      // |d| |e1| |e2|: a ray along a rotated box's side wall met it there at a random t, and a thin
      // plate's slab lost half its thickness at the rim; meshing version 42.)
      const double e12 = e1.squaredNorm() * e2.squaredNorm();
      if (det * det <= 1e-24 * d2 * e12 || std::abs(det) < 1e-300) continue;
      // (Nor one within 1e-5 of its length of the plane at both ends: files keep few digits, and a
      // side wall written with 9 stands off perpendicular by about 1e-9, over the bound above for
      // a long, thin wall triangle; a star-shaped plate 2 mm thick turned in space put rim points
      // of its slab 0.14 mm from one side instead of 1 mm. Meshing version 46.)
      // (det = -d · (e1 × e2), and |e1 × e2| <= |e1| |e2|: the cross product only where it may pass.)
      if (det * det <= 1e-8 * d2 * e12) {
        const Vec3 n = e1.cross(e2);
        const double n2 = n.squaredNorm();
        const double sa = n.dot(a - p0), sb = sa + n.dot(d), tol2 = 1e-10 * d2 * n2;
        if (det * det <= 1e-8 * d2 * n2 && sa * sa <= tol2 && sb * sb <= tol2) continue;
      }
      const double inv = 1.0 / det;
      const Vec3 s = a - p0;
      const double u = inv * s.dot(h);
      if (u < 0 || u > 1) continue;
      const Vec3 q = s.cross(e1);
      const double v = inv * d.dot(q);
      if (v < 0 || u + v > 1) continue;
      const double t = inv * e2.dot(q);
      if (t < 0 || t > 1 || (after && t < hint)) continue;
      if (std::abs(t - hint) < best) best = std::abs(t - hint), best_t = t, found = true;
    }
  }
  if (found && t_out) *t_out = best_t;
  return found;
}

}  // namespace squeeze::meshing
