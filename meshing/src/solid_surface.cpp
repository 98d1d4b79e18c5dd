#include "squeeze/meshing/solid_surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/winding_number.h"

namespace squeeze::meshing {
namespace {

using Vec3 = Eigen::Vector3d;

// The six tetrahedra of a unit cube around its diagonal 0-7 (corner c = x + 2y + 4z), each a
// monotone path from corner 0 to corner 7.
constexpr int kCubeTets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

}  // namespace

SurfaceMesh solid_surface(const SurfaceMesh& input, const FastWindingNumber& wn, const TriangleBvh& bvh, double h,
                          Progress* progress) {
  if (!(h > 0)) throw InputError("solid_surface: the grid spacing must be > 0");
  Eigen::RowVector3d lo, hi;
  bounding_box(input.V, lo, hi);
  const Vec3 origin = lo.transpose() - Vec3::Constant(1.5 * h);
  const long nx = static_cast<long>(std::ceil((hi(0) - lo(0)) / h)) + 4;
  const long ny = static_cast<long>(std::ceil((hi(1) - lo(1)) / h)) + 4;
  const long nz = static_cast<long>(std::ceil((hi(2) - lo(2)) / h)) + 4;  // nodes per axis
  const size_t nodes = static_cast<size_t>(nx) * static_cast<size_t>(ny) * static_cast<size_t>(nz);
  auto node = [&](long i, long j, long k) { return static_cast<size_t>(i + nx * (j + ny * k)); };
  auto position = [&](size_t n) {
    const long i = static_cast<long>(n % static_cast<size_t>(nx)), j = static_cast<long>((n / nx) % ny),
               k = static_cast<long>(n / (static_cast<size_t>(nx) * ny));
    return Vec3(origin + h * Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
  };
  // Nodes of cubes a triangle passes through (sampled at a quarter of the spacing).
  std::vector<unsigned char> near(nodes, 0);
  for (Eigen::Index f = 0; f < input.F.rows(); ++f) {
    const Vec3 a = input.V.row(input.F(f, 0)).transpose(), b = input.V.row(input.F(f, 1)).transpose(),
               c = input.V.row(input.F(f, 2)).transpose();
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int n = std::clamp(static_cast<int>(std::ceil(longest / (0.25 * h))), 1, 4096);
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n - i; ++j) {
        const Vec3 p = a + (static_cast<double>(i) / n) * (b - a) + (static_cast<double>(j) / n) * (c - a);
        const long ci = std::clamp(static_cast<long>(std::floor((p(0) - origin(0)) / h)), 0L, nx - 2);
        const long cj = std::clamp(static_cast<long>(std::floor((p(1) - origin(1)) / h)), 0L, ny - 2);
        const long ck = std::clamp(static_cast<long>(std::floor((p(2) - origin(2)) / h)), 0L, nz - 2);
        for (int c8 = 0; c8 < 8; ++c8) near[node(ci + (c8 & 1), cj + ((c8 >> 1) & 1), ck + ((c8 >> 2) & 1))] = 1;
      }
  }
  if (progress) progress->stage("inside/outside of the surface (winding number)");
  std::vector<unsigned char> inside(nodes, 0);
  {
    std::vector<size_t> list;
    for (size_t n = 0; n < nodes; ++n)
      if (near[n]) list.push_back(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, list.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t m = r.begin(); m != r.end(); ++m) inside[list[m]] = wn(position(list[m]).transpose()) > 0.5;
    });
  }
  // Regions of the other nodes (6-connected).
  std::vector<char> seen(nodes, 0);
  std::vector<size_t> members, stack;
  for (size_t seed = 0; seed < nodes; ++seed) {
    if (near[seed] || seen[seed]) continue;
    members.clear();
    seen[seed] = 1;
    stack.push_back(seed);
    while (!stack.empty()) {
      const size_t n = stack.back();
      stack.pop_back();
      members.push_back(n);
      const long i = static_cast<long>(n % static_cast<size_t>(nx)), j = static_cast<long>((n / nx) % ny),
                 k = static_cast<long>(n / (static_cast<size_t>(nx) * ny));
      const long nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
      for (const auto& q : nb) {
        if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= nx || q[1] >= ny || q[2] >= nz) continue;
        const size_t m = node(q[0], q[1], q[2]);
        if (near[m] || seen[m]) continue;
        seen[m] = 1;
        stack.push_back(m);
      }
    }
    std::sort(members.begin(), members.end());
    const size_t samples = std::min<size_t>(16, members.size());
    int in = 0, out = 0;
    for (size_t s = 0; s < samples; ++s) {
      const double w = wn(position(members[members.size() * s / samples]).transpose());
      in += w > 0.7;
      out += w < 0.3;
    }
    if (out == static_cast<int>(samples)) continue;
    if (in == static_cast<int>(samples)) {
      for (size_t n : members) inside[n] = 1;
      continue;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, members.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t m = r.begin(); m != r.end(); ++m) inside[members[m]] = wn(position(members[m]).transpose()) > 0.5;
    });
  }
  // Marching tetrahedra. A vertex per crossing grid edge, keyed by its two nodes.
  if (progress) progress->stage("surface of the solid");
  std::unordered_map<uint64_t, int> vertex_of;
  std::vector<std::pair<size_t, size_t>> edge_nodes;  // (inside node, outside node) per vertex
  std::vector<std::array<int, 3>> tris;
  auto vertex = [&](size_t a, size_t b) {  // a inside, b outside
    const uint64_t key = a < b ? (static_cast<uint64_t>(a) << 32 | b) : (static_cast<uint64_t>(b) << 32 | a);
    auto [it, fresh] = vertex_of.try_emplace(key, static_cast<int>(edge_nodes.size()));
    if (fresh) edge_nodes.emplace_back(a, b);
    return it->second;
  };
  for (long k = 0; k + 1 < nz; ++k)
    for (long j = 0; j + 1 < ny; ++j)
      for (long i = 0; i + 1 < nx; ++i) {
        size_t c[8];
        int count = 0;
        for (int c8 = 0; c8 < 8; ++c8) {
          c[c8] = node(i + (c8 & 1), j + ((c8 >> 1) & 1), k + ((c8 >> 2) & 1));
          count += inside[c[c8]];
        }
        if (count == 0 || count == 8) continue;
        for (const auto& t : kCubeTets) {
          std::vector<int> in, out;
          for (int q = 0; q < 4; ++q) (inside[c[t[q]]] ? in : out).push_back(t[q]);
          if (in.empty() || out.empty()) continue;
          std::vector<int> poly;
          if (in.size() == 1) {
            for (int o : out) poly.push_back(vertex(c[in[0]], c[o]));
          } else if (out.size() == 1) {
            for (int o : in) poly.push_back(vertex(c[o], c[out[0]]));
          } else {  // a quad: in0-out0, in0-out1, in1-out1, in1-out0 (in cyclic order)
            poly = {vertex(c[in[0]], c[out[0]]), vertex(c[in[0]], c[out[1]]), vertex(c[in[1]], c[out[1]]),
                    vertex(c[in[1]], c[out[0]])};
          }
          // Outward: decided on the grid edges' midpoints (never degenerate), against the
          // direction from an inside corner of the tetrahedron to an outside one.
          auto mid = [&](int v) {
            return Vec3(0.5 * (position(edge_nodes[static_cast<size_t>(v)].first) + position(edge_nodes[static_cast<size_t>(v)].second)));
          };
          const Vec3 dir = position(c[out[0]]) - position(c[in[0]]);
          auto emit = [&](int a, int b, int d) {
            const Vec3 p0 = mid(a), p1 = mid(b), p2 = mid(d);
            if ((p1 - p0).cross(p2 - p0).dot(dir) < 0) std::swap(b, d);
            tris.push_back({a, b, d});
          };
          emit(poly[0], poly[1], poly[2]);
          if (poly.size() == 4) emit(poly[0], poly[2], poly[3]);
        }
      }
  // Positions: where the grid edge crosses the input (nearest its middle), else its middle.
  SurfaceMesh out;
  out.V.resize(static_cast<Eigen::Index>(edge_nodes.size()), 3);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, edge_nodes.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v != r.end(); ++v) {
      const Vec3 a = position(edge_nodes[v].first), b = position(edge_nodes[v].second);
      double t = 0.5;
      if (bvh.crossing_nearest(a, b, 0.5, &t)) t = std::clamp(t, 0.15, 0.85);
      else t = 0.5;
      out.V.row(static_cast<Eigen::Index>(v)) = (a + t * (b - a)).transpose();
    }
  });
  out.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t t = 0; t < tris.size(); ++t) out.F.row(static_cast<Eigen::Index>(t)) << tris[t][0], tris[t][1], tris[t][2];
  return out;
}

}  // namespace squeeze::meshing
