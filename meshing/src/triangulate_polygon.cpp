// The triangles of one polygon: a fan where it covers the polygon once, else ear clipping.
#include "squeeze/meshing/triangulate_polygon.h"

#include <cmath>
#include <cstddef>

namespace squeeze::meshing {

void triangulate_polygon(const std::vector<std::array<double, 3>>& pts, const std::vector<long>& poly,
                         std::vector<std::array<int, 3>>& tris) {
  const size_t n = poly.size();
  auto fan = [&](const std::vector<long>& c) {
    for (size_t j = 2; j < c.size(); ++j)
      tris.push_back({static_cast<int>(c[0]), static_cast<int>(c[j - 1]), static_cast<int>(c[j])});
  };
  bool known = n > 3 && n <= 512;
  for (long v : poly) known = known && v >= 0 && v < static_cast<long>(pts.size());
  if (!known) return fan(poly);
  double nx = 0, ny = 0, nz = 0;  // Newell's normal
  for (size_t i = 0; i < n; ++i) {
    const auto& a = pts[static_cast<size_t>(poly[i])];
    const auto& b = pts[static_cast<size_t>(poly[(i + 1) % n])];
    nx += (a[1] - b[1]) * (a[2] + b[2]), ny += (a[2] - b[2]) * (a[0] + b[0]), nz += (a[0] - b[0]) * (a[1] + b[1]);
  }
  // The plane's axes: the normal's largest coordinate dropped, the other two in the order that
  // keeps the polygon counter-clockwise.
  const double ax = std::abs(nx), ay = std::abs(ny), az = std::abs(nz);
  const int drop = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
  const double sign = (drop == 0 ? nx : drop == 1 ? ny : nz) >= 0 ? 1.0 : -1.0;
  const int u = (drop + 1) % 3, w = (drop + 2) % 3;
  auto x = [&](long v) { return pts[static_cast<size_t>(v)][u]; };
  auto y = [&](long v) { return pts[static_cast<size_t>(v)][w]; };
  auto turn = [&](long a, long b, long c) { return sign * ((x(b) - x(a)) * (y(c) - y(a)) - (y(b) - y(a)) * (x(c) - x(a))); };
  bool fan_ok = true;
  for (size_t j = 2; j < n && fan_ok; ++j) fan_ok = turn(poly[0], poly[j - 1], poly[j]) > 0;
  if (fan_ok) return fan(poly);
  auto same = [&](long a, long b) { return x(a) == x(b) && y(a) == y(b); };
  std::vector<long> c = poly;
  while (c.size() > 3) {
    bool clipped = false;
    for (size_t i = 0; i < c.size() && !clipped; ++i) {
      const long a = c[(i + c.size() - 1) % c.size()], b = c[i], d = c[(i + 1) % c.size()];
      if (!(turn(a, b, d) > 0)) continue;
      bool empty = true;
      for (long q : c) {
        if (q == a || q == b || q == d || same(q, a) || same(q, b) || same(q, d)) continue;
        if (turn(a, b, q) >= 0 && turn(b, d, q) >= 0 && turn(d, a, q) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      tris.push_back({static_cast<int>(a), static_cast<int>(b), static_cast<int>(d)});
      c.erase(c.begin() + static_cast<std::ptrdiff_t>(i));
      clipped = true;
    }
    if (!clipped) return fan(c);
  }
  fan(c);
}

}  // namespace squeeze::meshing
