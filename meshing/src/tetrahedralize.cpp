// CGAL translation unit: the Delaunay tetrahedralization of a closed surface, made conforming,
// refined and exuded. Keep other code out of it, it is one of the slowest files to compile.
#include "squeeze/meshing/tetrahedralize.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/exude_mesh_3.h>
#include <CGAL/spatial_sort.h>

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <map>
#include <memory>
#include <queue>
#include <unordered_map>
#include <vector>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/split_long_edges.h"
#include "squeeze/meshing/tet_cleanup.h"
#include "squeeze/meshing/tet_geometry.h"
#include "squeeze/meshing/winding_number.h"
#include "sigfpe_trap.h"

namespace squeeze::meshing {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
// Mesh_3's regular triangulation (all weights 0 until the exuder: a Delaunay triangulation), so
// that CGAL's exuder can work on the result.
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Vh = Tr::Vertex_handle;
using Ch = Tr::Cell_handle;
using Facet = Tr::Facet;
using WPoint = Tr::Weighted_point;
using BPoint = Tr::Bare_point;
using Vec3 = Eigen::Vector3d;

// 2-D constrained Delaunay triangulations of the flat patches of the surface.
using Vb2 = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using Fb2 = CGAL::Constrained_triangulation_face_base_2<K, CGAL::Triangulation_face_base_with_info_2<int, K>>;
using Tds2 = CGAL::Triangulation_data_structure_2<Vb2, Fb2>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds2, CGAL::No_constraint_intersection_requiring_constructions_tag>;

uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}

struct Key3 {
  int a, b, c;  // sorted
  bool operator==(const Key3& o) const { return a == o.a && b == o.b && c == o.c; }
};
Key3 key3(int a, int b, int c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return {a, b, c};
}
struct Key3Hash {
  size_t operator()(const Key3& k) const {
    uint64_t h = static_cast<uint64_t>(static_cast<uint32_t>(k.a)) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.b)) + 0x7F4A7C159E3779B9ULL + (h << 6) + (h >> 2);
    h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.c)) + 0x94D049BB133111EBULL + (h << 6) + (h >> 2);
    return static_cast<size_t>(h);
  }
};

// Circumcentre of the tetrahedron (a, b, c, d); false when it is flat.
bool circumcentre(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Vec3& x) {
  Eigen::Matrix3d M;
  M.row(0) = (b - a).transpose();
  M.row(1) = (c - a).transpose();
  M.row(2) = (d - a).transpose();
  const Vec3 rhs(0.5 * (b - a).squaredNorm(), 0.5 * (c - a).squaredNorm(), 0.5 * (d - a).squaredNorm());
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(M);
  if (!lu.isInvertible()) return false;
  x = a + lu.solve(rhs);
  return x.allFinite();
}

// Centre x of the circle through the triangle (a, b, c). Returns |(b − a) × (c − a)|², four times
// the squared area: not above 0 (or NaN) for a degenerate triangle, x then untouched.
double circumcircle_centre(const Vec3& a, const Vec3& b, const Vec3& c, Vec3& x) {
  const Vec3 ab = b - a, ac = c - a, n = ab.cross(ac);
  const double n2 = n.squaredNorm();
  if (n2 > 0) x = a + (ac.squaredNorm() * n.cross(ab) + ab.squaredNorm() * ac.cross(n)) / (2.0 * n2);
  return n2;
}

// The centre of the circle through the largest of the four faces of tetrahedron abcd (flat ones
// included); false if every face is degenerate.
bool circumcircle_centre_of_largest_face(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Vec3& x) {
  const Vec3* p[4] = {&a, &b, &c, &d};
  double best = 0;
  for (int skip = 0; skip < 4; ++skip) {
    const Vec3* f[3];
    for (int k = 0, j = 0; k < 4; ++k)
      if (k != skip) f[j++] = p[k];
    Vec3 centre;
    const double n2 = circumcircle_centre(*f[0], *f[1], *f[2], centre);
    if (!(n2 > best)) continue;
    best = n2;
    x = centre;
  }
  return best > 0 && x.allFinite();
}

double min_dihedral(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const auto ang = dihedral_angles(a.transpose(), b.transpose(), c.transpose(), d.transpose());
  return *std::min_element(ang.begin(), ang.end());
}

// One meshing run at one interior edge length.
struct RunResult {
  TetMesh mesh;
  int boundary_splits = 0;
  int steiner = 0;
  int size_driven = 0;  // insertions and splits asked for by the size bound (not quality)
  bool conforming = true;
  bool recovered = true;  // the first recovery, before any refinement, made the boundary conforming
  bool abandoned = false;  // ... it gave up at the split budget (TetrahedralizeOptions::recovery_splits_per_face)
  bool exuder_stopped = false;  // CGAL's exuder met a NaN weight and stopped (exude())
  int peeled = 0;
  // Whether the interior edge length shaped the run beyond its starting points (crease and lattice
  // points, Mesher::same_start): quality splits bounded by it (it was below the surface's median
  // edge) or a point inserted for size. Where neither, a run at a longer length from the same
  // starting points is the same run: its size bound finds a subset of the same cells too large,
  // and those found now inserted nothing (tetrahedralize skips it).
  bool length_bound = false;
  double work = 0;             // conflict-zone cells refinement searched (Mesher::conflict_cells_)
  bool work_exceeded = false;  // ... beyond the Mesher's budget: refinement stopped there
  bool run_bound = false;      // ... beyond TetrahedralizeOptions::run_refine_work: stopped there
  bool exuder_pump_bound = false;  // the exuder stopped at TetrahedralizeOptions::exude_pumps_per_sliver
  int flat_cells_flipped = 0;  // Mesher::flip_flat_surface_cells's flips
};

class Mesher {
 public:
  // work_budget: conflict-zone cells refinement may search (0: no bound; TetrahedralizeOptions::max_refine_work).
  // input_faces: the faces of the boundary as given, before its long edges were split.
  Mesher(const SurfaceMesh& s, const FastWindingNumber& wn, const TetrahedralizeOptions& opt, double edge_length,
         double work_budget, int input_faces)
      : opt_(opt), L_(edge_length), work_budget_(work_budget), input_faces_(input_faces), wn_(wn),
        tr_(c3t3_.triangulation()) {
    build_surface(s);
    start_points_ = P_.size();
  }

  // Whether this mesher starts from the same points as `other` (the surface's, and the crease and
  // lattice points its edge length puts on it), in the same order.
  bool same_start(const Mesher& other) const {
    return start_points_ == other.start_points_ &&
           std::equal(P_.begin(), P_.begin() + static_cast<long>(start_points_), other.P_.begin());
  }

  RunResult run(Progress* progress) {
    RunResult r;
    using Clock = std::chrono::steady_clock;
    auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    const auto t_start = Clock::now();
    build_delaunay();
    // Recovery by splits may add up to four points per point before it gives up: a thin tube's
    // simplified boundary (a coil spring of 3 mm wire at 150 tetrahedra: long triangles whose
    // diametral balls hold the other side of the wire) needed 1,042 splits for its 725 points and
    // was given up at 1.5 (meshing version 18: not conforming, 1.2 % of the diagonal in).
    conformity_cap_ = static_cast<int>(P_.size()) * 4 + 200;
    // (The split budget for this first recovery only: the recoveries after refinement rounds have
    // the point cap alone.)
    r.conforming =
        make_conforming(std::max(0.0, opt_.recovery_splits_per_face) * static_cast<double>(input_faces_), &r.abandoned);
    r.recovered = r.conforming;
    classify(r.conforming);
    const double t_recover = since(t_start);
    const auto t_refine = Clock::now();
    // Quality splits stop at edges a third as long as the shorter of the interior edge length
    // and the surface's median edge (near a sharp crease refinement would otherwise not end).
    std::vector<double> len;
    for (const auto& [k, ts] : edge_tris_) len.push_back(edge_length(k));
    std::nth_element(len.begin(), len.begin() + static_cast<long>(len.size() / 2), len.end());
    min_split_ = std::min(L_, len.empty() ? L_ : len[len.size() / 2]) / 3.0;
    const bool split_bound = !len.empty() && L_ < len[len.size() / 2];  // RunResult::length_bound
    // The safety net (max_tets) in points, but never below twice the points the recovered
    // boundary has: a small part of a large model gets max_tets by its share of the volume (1,000
    // at least, so 333 points), and a boundary of more points than that had no refinement at all
    // (trimesh's counter.unitsmm.STL: five screws, each 1,262 boundary faces and 1,313 points
    // after recovery, kept cells of 0.23° for the exuder, which left 3.2-4.9°; meshing version 44).
    max_vertices_ = std::max({64, opt_.max_tets / 3, 2 * static_cast<int>(P_.size())});
    // Refinement leans on the surface faces being faces of the triangulation; where they are not
    // (a failed recovery), it runs for a few rounds only, within a work bound
    // (TetrahedralizeOptions::unrecovered_refine_work). Where a refinement round loses them (its
    // splits near a thin part could not be recovered), refinement stops there: further rounds
    // would refine a triangulation classified by the winding number, adding points without end
    // (a 4 mm hemispherical shell at 150: 2,000 → 6,000 points in six rounds, 8 s, 18,000
    // tetrahedra, still not conforming).
    for (int round = 0; round < (r.conforming ? 200 : r.abandoned ? 0 : 8); ++round) {
      if (progress) progress->update(round, "refinement round " + std::to_string(round + 1));
      if (static_cast<int>(P_.size()) > max_vertices_) break;
      const int points_before = static_cast<int>(P_.size());
      if (!refine_round()) break;
      // The cap is on recovery's own splits: the points refinement adds do not count against it
      // (they did until meshing version 45: a plate with 3 mm ribs at 150 lost its conformity in
      // the tenth round, at the cap the recovery of its first 332 points had set, and went on to
      // a remeshed boundary, 12 s in all; 1.2 s since).
      if (opt_.recovery_cap_on_own_splits) conformity_cap_ += static_cast<int>(P_.size()) - points_before;
      if (over_budget()) {
        r.work_exceeded = true;
        spdlog::debug("refinement stopped after round {}: {} conflict-zone cells searched (bound {:.4g})", round,
                      conflict_cells_, work_budget_);
      }
      const bool was_conforming = r.conforming;
      if (r.conforming) r.conforming = make_conforming();
      classify(r.conforming);
      spdlog::debug("round {}: {} points, conforming {}, {} splits, {} steiner, {} conflict cells", round, P_.size(),
                    r.conforming, splits_, steiner_, conflict_cells_);
      if (was_conforming && !r.conforming) break;
      if (r.work_exceeded) break;
      if (over_run_bound()) {
        r.run_bound = true;
        spdlog::warn("tetrahedralize: refinement stopped at its work bound ({} conflict-zone cells searched in round {}; "
                     "TetrahedralizeOptions::run_refine_work): the mesh may keep flat tetrahedra",
                     conflict_cells_, round + 1);
        break;
      }
      if (!r.recovered && opt_.unrecovered_refine_work > 0 &&
          static_cast<double>(conflict_cells_) > opt_.unrecovered_refine_work) {
        spdlog::debug("refinement of a boundary not recovered stopped after round {}: {} conflict-zone cells searched",
                      round, conflict_cells_);
        break;
      }
    }
    if (!r.conforming)
      spdlog::debug("tetrahedralize: some boundary faces are not faces of the triangulation; tetrahedra classified by "
                    "the winding number at their centroids");
    const double refine_s = since(t_refine);
    const auto t_exude = Clock::now();
    setup_complex();
    // (Not after the work bound: the mesh is left for another boundary, and the exuder can take its
    // time limit over such a one. Nor where the boundary is not conforming: its complex is the
    // faces between cells classified by the winding number, and on such ones the exuder ran to its
    // 30 s time limit (trimesh's round.stl, octagonal_pocket.ply and ADIS16480.STL at 150, each a
    // run that lost its boundary in refinement), where on conforming runs it takes under a second.)
    if (opt_.exude && !r.work_exceeded && r.conforming) r.exuder_stopped = !exude(r);
    const double exude_s = since(t_exude);
    r.mesh = extract();
    spdlog::debug("tetrahedralize run: recovery {:.2f} s (conforming {}), refinement {:.2f} s, exudation {:.2f} s",
                  t_recover, r.recovered, refine_s, exude_s);
    // Boundary tetrahedra still below the floor (flat caps over the surface that refinement could
    // not reach without splitting the surface below min_split_) are peeled off where that moves the
    // boundary by at most peel_max_height (a coarse mesh's 4° sliver can be 2 % of the diagonal
    // thick: the lumbar spine at 150).
    r.peeled = peel_boundary_slivers(r.mesh, opt_.min_dihedral, opt_.peel_max_height);
    if (r.peeled > 0) remove_unused_vertices(r.mesh);
    r.boundary_splits = splits_;
    r.steiner = steiner_;
    r.size_driven = size_driven_;
    r.length_bound = split_bound || size_driven_ > 0;
    r.work = static_cast<double>(conflict_cells_);
    r.flat_cells_flipped = flat_flips_;
    return r;
  }

  // Whether refinement has searched more conflict-zone cells than this run's budget
  // (TetrahedralizeOptions::max_refine_work, what earlier attempts left of it).
  bool over_budget() const { return work_budget_ > 0 && static_cast<double>(conflict_cells_) > work_budget_; }

  // Whether refinement has searched more conflict-zone cells than any run may
  // (TetrahedralizeOptions::run_refine_work).
  bool over_run_bound() const {
    return opt_.run_refine_work > 0 && static_cast<double>(conflict_cells_) > opt_.run_refine_work;
  }

  // Inside or outside, per cell: by the parity of surface crossings where every surface face is a
  // face of the triangulation, else by the winding number at the centroid (exact away from the
  // faces that are missing, and right wherever the cell does not straddle the surface).
  void classify(bool conforming) {
    if (!conforming) {
      classify_by_winding_number();
      return;
    }
    classify_by_parity();
    if (opt_.flip_flat_surface_cells && flip_flat_surface_cells() > 0) classify_by_parity();
  }

  // Inside cells of no volume on the surface: four surface points of one flat patch, two of the
  // cell's faces surface triangles (sharing an edge), the other two not. Such a cell lies in the
  // patch's plane; its two surface triangles are the quad's one diagonal and its two other faces
  // the other, also faces of the triangulation. Taking that other diagonal for the surface leaves
  // the surface where it was (the four points are in one plane) and puts the cell outside. The
  // alternative, refining it, asks for splits of the surface round after round that make more
  // such cells: a 6 mm plate turned in space, whose points are coplanar only up to rounding, took
  // 20-38 rounds and up to 16 s at 2,000 tetrahedra, where axis-aligned it takes under a second
  // (meshing version 43). Returns the flips made; the caller classifies again.
  int flip_flat_surface_cells() {
    std::vector<uint64_t> edges;
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c) {
      if (c->subdomain_index() == 0) continue;
      bool all_surface = true;
      for (int k = 0; k < 4 && all_surface; ++k) {
        const int v = id(c->vertex(k));
        all_surface = v >= 0 && on_surface_[static_cast<size_t>(v)];
      }
      if (!all_surface) continue;
      int faces[2], n = 0;
      for (int i = 0; i < 4; ++i) {
        const int t = surface_tri(c, i);
        if (t < 0) continue;
        if (n == 2) {
          n = 3;
          break;
        }
        faces[n++] = t;
      }
      if (n != 2 || tri_patch_[static_cast<size_t>(faces[0])] != tri_patch_[static_cast<size_t>(faces[1])]) continue;
      // The shared edge: the two corners of faces[0] that are also corners of faces[1].
      const auto& u = tri_[static_cast<size_t>(faces[0])];
      const auto& w = tri_[static_cast<size_t>(faces[1])];
      int shared[2], m = 0;
      for (int a : u)
        if (m < 2 && (a == w[0] || a == w[1] || a == w[2])) shared[m++] = a;
      if (m == 2) edges.push_back(edge_key(shared[0], shared[1]));
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    std::vector<uint64_t> flipped;
    int flips = 0;
    for (uint64_t e : edges) flips += flip_to_delaunay(e, &flipped);
    if (flips > 0) spdlog::debug("tetrahedralize: {} flat cells on the surface flipped outside", flips);
    flat_flips_ += flips;
    return flips;
  }

  void classify_by_winding_number() {
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c) {
      Vec3 g = Vec3::Zero();
      for (int k = 0; k < 4; ++k) {
        const auto& p = tr_.point(c->vertex(k));
        g += Vec3(p.x(), p.y(), p.z());
      }
      c->set_subdomain_index(wn_(g.transpose() / 4.0) > 0.5 ? 1 : 0);
    }
  }

 private:
  const TetrahedralizeOptions& opt_;
  const double L_;  // interior edge length (INFINITY: quality refinement only)
  const double work_budget_;  // conflict-zone cells refinement may search (0: no bound)
  const int input_faces_;     // the boundary's faces as given (before its long edges are split)
  const FastWindingNumber& wn_;  // of the surface (the fallback classification)
  int conformity_cap_ = 0;       // make_conforming gives up beyond this many points (raised by the
                                 // points each refinement round adds)
  C3t3 c3t3_;
  Tr& tr_;
  std::vector<Vec3> P_;            // every vertex: the surface's, split points, Steiner points
  std::vector<Vh> vh_;             // its vertex in the triangulation (null before build_delaunay)
  std::vector<char> on_surface_;   // 1: on the surface
  std::unordered_map<const void*, int> id_;
  std::vector<std::array<int, 3>> tri_;  // surface triangles, outward; dead ones have tri_alive_ 0
  std::vector<char> tri_alive_;
  // A cell that had the triangle as a facet when make_conforming last found it (null: none yet).
  // The triangle is still a facet where that cell is still in the triangulation with its three
  // corners; else TDS::is_facet searches the cells around a corner, whose count is large in a
  // Delaunay triangulation of surface points (a thin shell of 22,800 triangles: 190 passes over
  // its triangles in two tetrahedralizations).
  std::vector<Ch> tri_cell_;
  std::vector<int> tri_patch_;     // flat patch of the input each triangle lies in
  std::vector<int> tri_depth_;     // how many splits made it from a triangle of the first surface
  std::unordered_map<uint64_t, std::array<int, 2>> edge_tris_;
  std::unordered_map<Key3, int, Key3Hash> face_;
  int splits_ = 0, steiner_ = 0, size_driven_ = 0;
  int flat_flips_ = 0;  // surface diagonals flipped to put flat cells outside (flip_flat_surface_cells)
  long conflict_cells_ = 0;  // cells of the conflict zones refinement searched (its work)
  size_t start_points_ = 0;        // P_'s points before run() (same_start)
  double min_split_ = 0;           // quality does not split surface edges shorter than this
  int max_vertices_ = 0;           // refinement stops beyond this many points (run())

  int count_inside() const {
    int n = 0;
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c) n += c->subdomain_index() != 0;
    return n;
  }
  double max_radius() const { return 0.85 * L_; }  // circumradius above which a tetrahedron is too large

  // ---- the surface ----
  void add_tri(int a, int b, int c, int patch, int depth = 0) {
    const int t = static_cast<int>(tri_.size());
    tri_.push_back({a, b, c});
    tri_alive_.push_back(1);
    tri_cell_.push_back(Ch());
    tri_patch_.push_back(patch);
    tri_depth_.push_back(depth);
    const int e[3][2] = {{a, b}, {b, c}, {c, a}};
    for (const auto& ed : e) {
      auto [it, fresh] = edge_tris_.try_emplace(edge_key(ed[0], ed[1]), std::array<int, 2>{-1, -1});
      (it->second[0] < 0 ? it->second[0] : it->second[1]) = t;
    }
    face_[key3(a, b, c)] = t;
  }
  void remove_tri(int t) {
    tri_alive_[static_cast<size_t>(t)] = 0;
    const auto& v = tri_[static_cast<size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      auto it = edge_tris_.find(edge_key(v[k], v[(k + 1) % 3]));
      if (it == edge_tris_.end()) continue;
      if (it->second[0] == t) it->second[0] = -1;
      if (it->second[1] == t) it->second[1] = -1;
      if (it->second[0] < 0 && it->second[1] < 0) edge_tris_.erase(it);
    }
    face_.erase(key3(v[0], v[1], v[2]));
  }
  double edge_length(uint64_t key) const {
    return (P_[key >> 32] - P_[key & 0xFFFFFFFFu]).norm();
  }
  uint64_t longest_edge(int t) const {
    const auto& v = tri_[static_cast<size_t>(t)];
    uint64_t best = 0;
    double len = -1;
    for (int k = 0; k < 3; ++k) {
      const double l = (P_[v[k]] - P_[v[(k + 1) % 3]]).squaredNorm();
      if (l > len) len = l, best = edge_key(v[k], v[(k + 1) % 3]);
    }
    return best;
  }
  // Splits surface edge `key` at its midpoint (a point of the surface); inserts the point in the
  // triangulation when it exists. Returns the new vertex, -1 if the edge is gone.
  int split_edge(uint64_t key) {
    auto it = edge_tris_.find(key);
    if (it == edge_tris_.end()) return -1;
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xFFFFFFFFu);
    const std::array<int, 2> ts = it->second;
    // Not quite the midpoint: a fixed hash of the edge moves it by up to a tenth of the edge, so
    // that splits of parallel faces (the two sides of a plate) do not line up into cospherical
    // configurations. On the edge's line either way (exactly so for axis-parallel edges).
    uint64_t h = key * 0x9E3779B97F4A7C15ULL;
    h ^= h >> 31;
    const double s = 0.5 + 0.2 * (static_cast<double>(h & 0xFFFF) / 65535.0 - 0.5);
    const int m = add_point(P_[a] + s * (P_[b] - P_[a]), true, vh_[static_cast<size_t>(a)]);
    for (int t : ts) {
      if (t < 0) continue;
      const auto v = tri_[static_cast<size_t>(t)];
      int k = 0;
      while (!((v[k] == a && v[(k + 1) % 3] == b) || (v[k] == b && v[(k + 1) % 3] == a))) ++k;
      const int x = v[k], y = v[(k + 1) % 3], z = v[(k + 2) % 3];
      const int pa = tri_patch_[static_cast<size_t>(t)], depth = tri_depth_[static_cast<size_t>(t)] + 1;
      remove_tri(t);
      add_tri(x, m, z, pa, depth);
      add_tri(m, y, z, pa, depth);
    }
    ++splits_;
    return m;
  }
  bool is_surface_facet(const Ch& c, int i) const {
    int v[3];
    for (int k = 0; k < 3; ++k) {
      const Vh h = c->vertex((i + 1 + k) & 3);
      if (tr_.is_infinite(h)) return false;
      v[k] = id(h);
    }
    return face_.count(key3(v[0], v[1], v[2])) > 0;
  }
  int surface_tri(const Ch& c, int i) const {
    int v[3];
    for (int k = 0; k < 3; ++k) {
      const Vh h = c->vertex((i + 1 + k) & 3);
      if (tr_.is_infinite(h)) return -1;
      v[k] = id(h);
    }
    const auto it = face_.find(key3(v[0], v[1], v[2]));
    return it == face_.end() ? -1 : it->second;
  }

  // The surface the mesh will have: each flat patch of the input surface (adjacent triangles in
  // one plane) is triangulated anew in 2-D (CGAL's constrained Delaunay triangulation) from its
  // boundary, whose edges (creases between patches) are split into equal pieces no longer than
  // the boundary spacing, plus points of a lattice of that spacing inside it. The lattice is
  // laid in a frame that depends only on the plane's normal direction, so the two faces of a plate
  // get the same points seen along the normal and their triangulations line up: the tetrahedra
  // between them form prisms instead of slivers. Every point lies on the input surface
  // (creases: on their edge; lattice points: in their plane), so the boundary stays exact.
  void build_surface(const SurfaceMesh& s) {
    const Eigen::Index nf = s.F.rows();
    for (Eigen::Index i = 0; i < s.V.rows(); ++i) P_.push_back(s.V.row(i).transpose());
    Eigen::RowVector3d lo, hi;
    bounding_box(s.V, lo, hi);
    const double diag = (hi - lo).norm();
    // Flat within a hundred-thousandth of the diagonal: files keep few digits (an OBJ with six
    // decimals puts the corners of a flat cap up to 8.7e-7 m off its plane), and the corners of a
    // face that is flat in the model must make one patch, or its thin fan triangles, each a plane
    // of its own, meet at nearly 180° and their recovery splits them without end (the legs of a
    // spider model: 300 splits, not conforming, 4.2°). Far below the deviation bounds (1e-2).
    const double tol = 1e-5 * diag;
    const Vec3 origin = lo.transpose();
    // Edge -> faces.
    std::unordered_map<uint64_t, std::array<int, 2>> ef;
    for (Eigen::Index f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        auto [it, fresh] = ef.try_emplace(edge_key(s.F(f, k), s.F(f, (k + 1) % 3)), std::array<int, 2>{-1, -1});
        (it->second[0] < 0 ? it->second[0] : it->second[1]) = static_cast<int>(f);
      }
    auto normal = [&](Eigen::Index f) {
      const Vec3 a = P_[s.F(f, 0)], b = P_[s.F(f, 1)], c = P_[s.F(f, 2)];
      return Vec3((b - a).cross(c - a));
    };
    auto plane_distance = [&](Eigen::Index f, int v) {
      const Vec3 n = normal(f);
      const double len = n.norm();
      return len > 0 ? std::abs(n.dot(P_[v] - P_[s.F(f, 0)])) / len : INFINITY;
    };
    // Patches: flood fill across edges whose two faces lie in one plane (within `tol`, and facing
    // the same way), each face also within `tol` of the plane of the patch's first face, so that a
    // finely triangulated curved surface, nearly flat from one face to the next, does not drift
    // into one "flat" patch.
    std::vector<int> patch(static_cast<size_t>(nf), -1);
    int patches = 0;
    for (Eigen::Index f0 = 0; f0 < nf; ++f0) {
      if (patch[f0] >= 0) continue;
      std::vector<int> stack{static_cast<int>(f0)};
      patch[f0] = patches;
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        for (int k = 0; k < 3; ++k) {
          const auto& two = ef[edge_key(s.F(f, k), s.F(f, (k + 1) % 3))];
          const int g = two[0] == f ? two[1] : two[0];
          if (g < 0 || patch[g] >= 0) continue;
          int opp = -1;
          for (int j = 0; j < 3; ++j)
            if (s.F(g, j) != s.F(f, k) && s.F(g, j) != s.F(f, (k + 1) % 3)) opp = s.F(g, j);
          int mine = s.F(f, (k + 2) % 3);
          if (opp < 0 || !(plane_distance(f, opp) <= tol && plane_distance(g, mine) <= tol) ||
              normal(f).dot(normal(g)) <= 0 || !(plane_distance(f0, opp) <= tol) || normal(f0).dot(normal(g)) <= 0)
            continue;
          patch[g] = patches;
          stack.push_back(g);
        }
      }
      ++patches;
    }
    // Crease edges, split into equal pieces no longer than the spacing.
    const double spacing = std::isfinite(L_) ? L_ : INFINITY;
    std::unordered_map<uint64_t, std::vector<int>> chain;  // from the lower vertex id to the higher
    std::vector<uint64_t> crease;
    for (const auto& [key, two] : ef)
      if (two[1] < 0 || patch[two[0]] != patch[two[1]]) crease.push_back(key);
    std::sort(crease.begin(), crease.end());
    for (uint64_t key : crease) {
      const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xFFFFFFFFu);
      const double len = (P_[b] - P_[a]).norm();
      // (At most 64 pieces: a spacing far below the surface's own edges comes from a part with next
      // to no volume, whose faces need no points between their corners.)
      const int k = std::isfinite(spacing) ? std::clamp(static_cast<int>(std::ceil(len / spacing - 1e-9)), 1, 64) : 1;
      std::vector<int> c{a};
      for (int i = 1; i < k; ++i) {
        c.push_back(static_cast<int>(P_.size()));
        P_.push_back(P_[a] + (static_cast<double>(i) / k) * (P_[b] - P_[a]));
      }
      c.push_back(b);
      chain[key] = std::move(c);
    }
    // Each patch in 2-D.
    std::vector<std::vector<int>> faces_of(static_cast<size_t>(patches));
    for (Eigen::Index f = 0; f < nf; ++f) faces_of[patch[f]].push_back(static_cast<int>(f));
    for (int pi = 0; pi < patches; ++pi) {
      const auto& fs = faces_of[static_cast<size_t>(pi)];
      Vec3 n = Vec3::Zero(), centre = Vec3::Zero();
      double area = 0;
      for (int f : fs) {
        const Vec3 nn = normal(f);
        n += nn;
        area += nn.norm();
        centre += nn.norm() * (P_[s.F(f, 0)] + P_[s.F(f, 1)] + P_[s.F(f, 2)]) / 3.0;
      }
      if (!(n.norm() > 0) || !(area > 0)) {  // degenerate faces: keep them as they are
        for (int f : fs) add_tri(s.F(f, 0), s.F(f, 1), s.F(f, 2), pi);
        continue;
      }
      centre /= area;
      n.normalize();
      // The frame depends on the normal's direction only (n and -n give the same).
      int big;
      n.cwiseAbs().maxCoeff(&big);
      const Vec3 nc = n(big) < 0 ? Vec3(-n) : n;
      int least;
      nc.cwiseAbs().minCoeff(&least);
      const Vec3 u = nc.cross(Vec3::Unit(least)).normalized(), v = nc.cross(u);
      const bool flip = n.dot(nc) < 0;  // outward is -nc: reverse the 2-D orientation
      auto to2 = [&](const Vec3& p) { return K::Point_2((p - origin).dot(u), (p - origin).dot(v)); };
      Cdt cdt;
      std::unordered_map<int, Cdt::Vertex_handle> vmap;
      auto vertex = [&](int id) {
        auto it = vmap.find(id);
        if (it != vmap.end()) return it->second;
        Cdt::Vertex_handle h = cdt.insert(to2(P_[id]));
        h->info() = id;
        vmap.emplace(id, h);
        return h;
      };
      std::vector<std::pair<K::Point_2, K::Point_2>> segments;
      std::vector<uint64_t> boundary;
      for (int f : fs)
        for (int k = 0; k < 3; ++k) {
          const uint64_t key = edge_key(s.F(f, k), s.F(f, (k + 1) % 3));
          if (chain.count(key)) boundary.push_back(key);
        }
      std::sort(boundary.begin(), boundary.end());
      boundary.erase(std::unique(boundary.begin(), boundary.end()), boundary.end());
      for (uint64_t key : boundary) {
        const auto& c = chain[key];
        for (size_t i = 0; i + 1 < c.size(); ++i) {
          const auto h0 = vertex(c[i]), h1 = vertex(c[i + 1]);
          cdt.insert_constraint(h0, h1);
          segments.emplace_back(h0->point(), h1->point());
        }
      }
      mark_domain(cdt);
      // Lattice points inside, at least half a spacing from the patch's boundary.
      if (std::isfinite(spacing)) {
        double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
        for (const auto& [id, h] : vmap) {
          x0 = std::min(x0, h->point().x()), x1 = std::max(x1, h->point().x());
          y0 = std::min(y0, h->point().y()), y1 = std::max(y1, h->point().y());
        }
        const double offset = nc.dot(centre - origin);
        std::vector<std::pair<K::Point_2, int>> inner;
        for (long i = static_cast<long>(std::floor(x0 / spacing)); i <= static_cast<long>(std::ceil(x1 / spacing)); ++i)
          for (long j = static_cast<long>(std::floor(y0 / spacing)); j <= static_cast<long>(std::ceil(y1 / spacing)); ++j) {
            uint64_t h = (static_cast<uint64_t>(i) * 0x9E3779B97F4A7C15ULL) ^ (static_cast<uint64_t>(j) * 0xC2B2AE3D27D4EB4FULL);
            h ^= h >> 29;
            h *= 0xBF58476D1CE4E5B9ULL;
            h ^= h >> 32;
            const double jx = (static_cast<double>(h & 0xFFFF) / 65535.0 - 0.5) * 0.1 * spacing;
            const double jy = (static_cast<double>((h >> 16) & 0xFFFF) / 65535.0 - 0.5) * 0.1 * spacing;
            const K::Point_2 q(static_cast<double>(i) * spacing + jx, static_cast<double>(j) * spacing + jy);
            if (q.x() < x0 || q.x() > x1 || q.y() < y0 || q.y() > y1) continue;
            const Cdt::Face_handle fh = cdt.locate(q);
            if (cdt.is_infinite(fh) || !(fh->info() & 1)) continue;
            double near = INFINITY;
            for (const auto& sg : segments)
              near = std::min(near, std::sqrt(CGAL::squared_distance(q, K::Segment_2(sg.first, sg.second))));
            if (near < 0.5 * spacing) continue;
            inner.emplace_back(q, 0);
          }
        spdlog::trace("patch {}: {} faces, {} boundary edges, {} lattice points, spacing {:.3g}, extent {:.3g} x {:.3g}", pi,
                      fs.size(), boundary.size(), inner.size(), spacing, x1 - x0, y1 - y0);
        for (auto& [q, id] : inner) {
          id = static_cast<int>(P_.size());
          P_.push_back(origin + q.x() * u + q.y() * v + offset * nc);
          Cdt::Vertex_handle h = cdt.insert(q);
          h->info() = id;
        }
        if (!inner.empty()) mark_domain(cdt);
      }
      for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
        if (!(f->info() & 1)) continue;
        const int a = f->vertex(0)->info(), b = f->vertex(1)->info(), c = f->vertex(2)->info();
        if (flip) add_tri(a, c, b, pi);
        else add_tri(a, b, c, pi);
      }
    }
    vh_.assign(P_.size(), Vh());
    on_surface_.assign(P_.size(), 1);
  }
  // Nesting levels of the faces of a 2-D constrained triangulation (0 outside; odd: inside the
  // polygon bounded by the constraints), by a flood fill from the infinite face.
  static void mark_domain(Cdt& cdt) {
    for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
    std::deque<std::pair<Cdt::Face_handle, int>> q;
    q.emplace_back(cdt.infinite_face(), 0);
    while (!q.empty()) {
      auto [f, level] = q.front();
      q.pop_front();
      if (f->info() != -1) continue;
      f->info() = level;
      for (int i = 0; i < 3; ++i) {
        const Cdt::Face_handle g = f->neighbor(i);
        if (g->info() != -1) continue;
        if (cdt.is_constrained(Cdt::Edge(f, i))) q.emplace_back(g, level + 1);
        else q.emplace_front(g, level);
      }
    }
  }

  // ---- the triangulation ----
  int id(const Vh& v) const {
    const auto it = id_.find(&*v);
    return it == id_.end() ? -1 : it->second;
  }
  // Adds point p (a surface point or not) and inserts it in the triangulation once there is one.
  // Returns its index; or, where the triangulation already has a vertex at exactly p, that
  // vertex's index: CGAL then returns the old vertex, and a second index for it would hide the
  // surface faces around it from is_surface_facet (the parity flood then leaks through them and
  // marks every cell outside). It happens where flips in a flat patch bring back a surface edge
  // that was split before, its old midpoint left on it, and the edge is split again at the same
  // point (a cone of 16 sides at 150 tetrahedra: no tetrahedron at all).
  int add_point(const Vec3& p, bool surface, Vh hint) {
    const int i = static_cast<int>(P_.size());
    P_.push_back(p);
    vh_.push_back(Vh());
    on_surface_.push_back(surface ? 1 : 0);
    if (tr_.number_of_vertices() == 0) return i;
    const int j = insert(i, hint);
    if (j != i) {  // already a vertex: its index stands for p
      P_.pop_back();
      vh_.pop_back();
      on_surface_.pop_back();
      if (surface) on_surface_[static_cast<size_t>(j)] = 1;
    }
    return j;
  }
  // Inserts point i; returns the index its vertex has: i, or the earlier point at exactly the same
  // place (see add_point), whose index then stands for both.
  int insert(int i, Vh hint) {
    const Vec3& p = P_[static_cast<size_t>(i)];
    const Vh v = hint == Vh() ? tr_.insert(WPoint(BPoint(p(0), p(1), p(2))))
                              : tr_.insert(WPoint(BPoint(p(0), p(1), p(2))), hint);
    vh_[static_cast<size_t>(i)] = v;
    return id_.try_emplace(&*v, i).first->second;
  }
  void build_delaunay() {
    // The surface's vertices (input vertices inside a flat patch are no longer on it).
    std::vector<char> used(P_.size(), 0);
    for (size_t t = 0; t < tri_.size(); ++t)
      if (tri_alive_[t])
        for (int v : tri_[t]) used[static_cast<size_t>(v)] = 1;
    std::vector<int> order;
    for (size_t i = 0; i < P_.size(); ++i)
      if (used[i]) order.push_back(static_cast<int>(i));
    struct Traits {
      const std::vector<Vec3>* P;
      struct Less {
        const std::vector<Vec3>* P;
        int axis;
        bool operator()(int a, int b) const { return (*P)[a](axis) < (*P)[b](axis); }
      };
      using Point_3 [[maybe_unused]] = int;  // the traits concept names it (CGAL spatial_sort)
      using Less_x_3 = Less;
      using Less_y_3 = Less;
      using Less_z_3 = Less;
      Less_x_3 less_x_3_object() const { return {P, 0}; }
      Less_y_3 less_y_3_object() const { return {P, 1}; }
      Less_z_3 less_z_3_object() const { return {P, 2}; }
    };
    CGAL::spatial_sort(order.begin(), order.end(), Traits{&P_}, CGAL::Hilbert_sort_median_policy());
    Vh hint;
    std::unordered_map<int, int> same;  // point -> the earlier point at exactly its place
    for (int i : order) {
      const int j = insert(i, hint);
      if (j != i) same.emplace(i, j);
      hint = vh_[static_cast<size_t>(i)];
    }
    // Surface triangles name each place by one index (is_surface_facet looks them up by the
    // vertices' indices); a triangle left with a repeated corner encloses nothing and goes.
    if (same.empty()) return;
    spdlog::debug("tetrahedralize: {} surface points at exactly the place of another", same.size());
    const size_t n = tri_.size();
    for (size_t t = 0; t < n; ++t) {
      if (!tri_alive_[t]) continue;
      std::array<int, 3> v = tri_[t];
      bool changed = false;
      for (int& x : v)
        if (const auto it = same.find(x); it != same.end()) x = it->second, changed = true;
      if (!changed) continue;
      const int patch = tri_patch_[t], depth = tri_depth_[t];
      remove_tri(static_cast<int>(t));
      if (v[0] != v[1] && v[1] != v[2] && v[2] != v[0]) add_tri(v[0], v[1], v[2], patch, depth);
    }
  }

  // Flips surface edge (a, b) to (c, d) when its two triangles (a, b, c) and (b, a, d) lie in one
  // plane (exact predicate) and (c, d) is an edge of the triangulation: where points of a flat
  // region are cocircular, the triangulation's choice of diagonal is as good as the surface's, and
  // taking it keeps the surface exactly where it was. Returns whether it flipped.
  bool flip_to_delaunay(uint64_t key, std::vector<uint64_t>* flipped) {
    auto it = edge_tris_.find(key);
    if (it == edge_tris_.end() || it->second[0] < 0 || it->second[1] < 0) return false;
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xFFFFFFFFu);
    const int t0 = it->second[0], t1 = it->second[1];
    auto opposite = [&](int t) {
      const auto& v = tri_[static_cast<size_t>(t)];
      for (int k = 0; k < 3; ++k)
        if (v[k] != a && v[k] != b) return v[k];
      return -1;
    };
    const int c = opposite(t0), d = opposite(t1);
    if (c < 0 || d < 0 || c == d || edge_tris_.count(edge_key(c, d))) return false;
    // In one flat patch any diagonal will do; across patches that are nearly flat (the quad's
    // corners within a thousandth of its longest edge of the other triangle's plane) the flip moves
    // the surface by that much at most.
    if (tri_patch_[static_cast<size_t>(t0)] != tri_patch_[static_cast<size_t>(t1)]) {
      const Vec3 &A = P_[a], &B = P_[b], &C = P_[c], &D = P_[d];
      const double longest = std::max({(A - B).norm(), (A - C).norm(), (A - D).norm(), (B - C).norm(), (B - D).norm()});
      const Vec3 n0 = (B - A).cross(C - A), n1 = (A - B).cross(D - B);
      if (!(n0.norm() > 0 && n1.norm() > 0)) return false;
      if (std::abs(n0.normalized().dot(D - A)) > 1e-3 * longest || std::abs(n1.normalized().dot(C - B)) > 1e-3 * longest ||
          n0.dot(n1) <= 0)
        return false;
    }
    // Keep the orientation: t0 = (c, x, y) in its own order, t1 = (d, y, x); flipped: (c, x, d), (c, d, y).
    const auto v = tri_[static_cast<size_t>(t0)];
    int k = 0;
    while (v[k] != c) ++k;
    const int x = v[(k + 1) % 3], y = v[(k + 2) % 3];
    // Only across a convex quad (c, x, d, y): where a corner lies on the new diagonal (a split point
    // of that edge, put back by earlier flips), a flipped triangle would be a needle of zero area,
    // never a face of the triangulation, its edge split at the same point again and again (the
    // heart with holes, hollowed, at 300: one such edge left its 8,966 faces not conforming).
    {
      const Vec3 &C = P_[c], &X = P_[x], &D = P_[d], &Y = P_[y];
      const Vec3 n = (X - C).cross(Y - C), m0 = (X - C).cross(D - C), m1 = (D - C).cross(Y - C);
      const double l2 = std::max({(X - C).squaredNorm(), (D - C).squaredNorm(), (Y - C).squaredNorm(),
                                  (D - X).squaredNorm(), (Y - D).squaredNorm()});
      if (!(m0.norm() > 1e-10 * l2 && m1.norm() > 1e-10 * l2 && m0.dot(n) > 0 && m1.dot(n) > 0)) return false;
    }
    Ch cell;  // (after the quad's test: the cells around c are many)
    int i, j;
    if (!tr_.is_edge(vh_[c], vh_[d], cell, i, j)) return false;
    const int pa = tri_patch_[static_cast<size_t>(t0)];
    const int depth = std::max(tri_depth_[static_cast<size_t>(t0)], tri_depth_[static_cast<size_t>(t1)]);
    remove_tri(t0);
    remove_tri(t1);
    add_tri(c, x, d, pa, depth);
    add_tri(c, d, y, pa, depth);
    flipped->push_back(edge_key(c, d));
    flipped->push_back(key);
    return true;
  }

  // Splits surface edges until every surface triangle is a face of the triangulation: an edge
  // that is missing (unless a flip in a flat region recovers it), else the longest edge of a
  // missing triangle. Returns false if a cap stopped it: the point cap (conformity_cap_), or
  // recovery going round in circles: six rounds of splits in a row, none with a tenth fewer edges
  // to split than the fewest so far, that have added a quarter more points than there were then
  // (and 200 at least, as the cap allows small surfaces; between the sheets of a 4 mm shell it
  // hovers at 100–240 edges a round, 60 points each, where a coil spring's wire goes 618, 475,
  // 356, ..., 8, 2 and holds, and a 2 mm fin 7, 7, 6, 4, 1). split_budget: where positive, it also
  // gives up (*abandoned set) once its own splits would pass this in a round that does not converge
  // (TetrahedralizeOptions::recovery_splits_per_face).
  bool make_conforming(double split_budget = 0, bool* abandoned = nullptr) {
    std::vector<uint64_t> flipped;  // each new diagonal once: no flipping back and forth
    size_t fewest = SIZE_MAX, points_then = 0;
    int stalled = 0;
    const int splits_before = splits_;
    for (int round = 0; round < 64; ++round) {
      std::vector<uint64_t> split, missing;
      std::vector<int> remove;
      for (size_t t = 0; t < tri_.size(); ++t) {
        if (!tri_alive_[t]) continue;
        const auto& v = tri_[t];
        Ch& was = tri_cell_[t];
        if (opt_.remember_facet_cells && was != Ch() && tr_.tds().cells().is_used(was) && was->has_vertex(vh_[v[0]]) &&
            was->has_vertex(vh_[v[1]]) && was->has_vertex(vh_[v[2]]))
          continue;
        Ch c;
        int i, j, k;
        if (tr_.is_facet(vh_[v[0]], vh_[v[1]], vh_[v[2]], c, i, j, k)) {
          was = c;
          continue;
        }
        // Steiner points (inside, not on the surface) in the triangle's diametral ball keep it out
        // of the triangulation whatever the surface does: they go.
        const size_t before = remove.size();
        steiner_in_diametral_ball(static_cast<int>(t), remove);
        if (remove.size() > before) continue;
        bool edge_missing = false;
        for (int e = 0; e < 3; ++e) {
          int a, b;
          if (!tr_.is_edge(vh_[v[e]], vh_[v[(e + 1) % 3]], c, a, b)) {
            missing.push_back(edge_key(v[e], v[(e + 1) % 3]));
            edge_missing = true;
          }
        }
        if (!edge_missing) split.push_back(longest_edge(static_cast<int>(t)));
      }
      if (split.empty() && missing.empty() && remove.empty()) return true;
      if (!remove.empty()) {
        std::sort(remove.begin(), remove.end());
        remove.erase(std::unique(remove.begin(), remove.end()), remove.end());
        for (int q : remove) remove_steiner(q);
        spdlog::debug("conformity round {}: removed {} Steiner points", round, remove.size());
        continue;  // re-check before splitting anything
      }
      std::sort(missing.begin(), missing.end());
      missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
      int flips = 0;
      for (uint64_t e : missing) {
        if (std::find(flipped.begin(), flipped.end(), e) == flipped.end() && flip_to_delaunay(e, &flipped)) ++flips;
        else split.push_back(e);
      }
      if (flips > 0) {
        spdlog::debug("conformity round {}: {} flips", round, flips);
        continue;  // re-check before splitting anything
      }
      std::sort(split.begin(), split.end());
      split.erase(std::unique(split.begin(), split.end()), split.end());
      // Edges whose triangles were all split 10 times already are not split further: around a
      // sharp crease recovery by splitting can go on without end. (An edge with a triangle split
      // fewer times on one side is: until meshing version 41 one such triangle on either side
      // stopped it, and a triangle split 9 times beside one split 10 times, missing with all its
      // edges in place, left the hollowed heart with holes of seed 391 not conforming. Each split
      // of such an edge deepens its shallower side, so the splits still end.)
      split.erase(std::remove_if(split.begin(), split.end(),
                                 [&](uint64_t k) {
                                   const auto it = edge_tris_.find(k);
                                   if (it == edge_tris_.end()) return true;
                                   for (int t : it->second)
                                     if (t >= 0 && tri_depth_[static_cast<size_t>(t)] < 10) return false;
                                   return true;
                                 }),
                  split.end());
      if (split.empty()) {
        spdlog::debug("conformity round {}: gave up, {} missing edges, only edges of triangles split 10 times left", round,
                      missing.size());
        return false;
      }
      // Over the split budget and not converging (this round asks for no fewer splits than 0.9 of
      // the fewest so far): a boundary of few large faces, whose long edges were split into many,
      // can need more splits than its faces several times over and still converge (the ribbed plate
      // of the tests: 60 faces; its splits fall round after round).
      if (split_budget > 0 && static_cast<double>(split.size()) >= 0.9 * static_cast<double>(fewest) &&
          static_cast<double>(splits_ - splits_before + static_cast<int>(split.size())) > split_budget) {
        spdlog::debug("conformity round {}: gave up at the split budget ({} splits + {} > {:.0f}, {} faces given; "
                      "the fewest a round {}): not refined",
                      round, splits_ - splits_before, split.size(), split_budget, input_faces_, fewest);
        if (abandoned) *abandoned = true;
        return false;
      }
      if (static_cast<int>(P_.size()) + static_cast<int>(split.size()) > conformity_cap_) {
        spdlog::debug("conformity round {}: gave up at the cap ({} points + {} splits > {})", round, P_.size(), split.size(),
                      conformity_cap_);
        return false;
      }
      spdlog::debug("conformity round {}: {} points, {} edges to split", round, P_.size(), split.size());
      if (static_cast<double>(split.size()) < 0.9 * static_cast<double>(fewest)) {
        fewest = split.size();
        points_then = P_.size();
        stalled = 0;
      } else if (++stalled >= 6 && P_.size() > points_then + std::max<size_t>(points_then / 4, 200)) {
        spdlog::debug("conformity round {}: gave up, {} edges to split, none under {} in {} rounds ({} points, {} then)", round,
                      split.size(), fewest, stalled, P_.size(), points_then);
        return false;
      }
      for (uint64_t k : split) split_edge(k);
    }
    return false;
  }

  // The Steiner points (not surface points) strictly inside the diametral ball of surface
  // triangle t, among the vertices of the cells around its corners; appended to `out`.
  void steiner_in_diametral_ball(int t, std::vector<int>& out) const {
    const auto& v = tri_[static_cast<size_t>(t)];
    const Vec3& A = P_[v[0]];
    Vec3 centre;
    if (!(circumcircle_centre(A, P_[v[1]], P_[v[2]], centre) > 0)) return;
    const double r2 = (A - centre).squaredNorm();
    std::vector<Ch> around;
    for (int k = 0; k < 3; ++k) tr_.incident_cells(vh_[v[k]], std::back_inserter(around));
    for (const Ch& c : around)
      for (int k = 0; k < 4; ++k) {
        const Vh h = c->vertex(k);
        if (tr_.is_infinite(h)) continue;
        const int q = id(h);
        if (q < 0 || on_surface_[static_cast<size_t>(q)]) continue;
        if ((P_[q] - centre).squaredNorm() < r2 * (1 - 1e-12)) out.push_back(q);
      }
  }

  void remove_steiner(int q) {
    const Vh h = vh_[static_cast<size_t>(q)];
    if (h == Vh()) return;
    id_.erase(&*h);
    tr_.remove(h);
    vh_[static_cast<size_t>(q)] = Vh();
    --steiner_;
  }

  // Inside = an odd number of surface crossings from the infinite cells (0-1 breadth-first search).
  void classify_by_parity() {
    std::unordered_map<const void*, int> depth;
    depth.reserve(tr_.number_of_cells() * 2);
    std::deque<Ch> dq;
    for (auto c = tr_.all_cells_begin(); c != tr_.all_cells_end(); ++c)
      if (tr_.is_infinite(c)) {
        depth[&*c] = 0;
        dq.push_back(c);
      }
    while (!dq.empty()) {
      const Ch c = dq.front();
      dq.pop_front();
      const int d = depth[&*c];
      for (int i = 0; i < 4; ++i) {
        const Ch n = c->neighbor(i);
        const int w = is_surface_facet(c, i) ? 1 : 0;
        auto [it, fresh] = depth.try_emplace(&*n, d + w);
        if (!fresh && it->second <= d + w) continue;
        it->second = d + w;
        if (w) dq.push_back(n);
        else dq.push_front(n);
      }
    }
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c) {
      const auto it = depth.find(&*c);
      c->set_subdomain_index(it != depth.end() && (it->second & 1) ? 1 : 0);
    }
  }

  // One round of refinement. Returns whether anything changed.
  bool refine_round() {
    struct Bad {
      double key;
      std::array<int, 4> v;
      Vec3 x;
      bool quality;
    };
    std::vector<Bad> bad;
    const double rmax = max_radius();
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c) {
      if (c->subdomain_index() == 0) continue;
      std::array<int, 4> v;
      for (int k = 0; k < 4; ++k) v[static_cast<size_t>(k)] = id(c->vertex(k));
      const Vec3 &a = P_[v[0]], &b = P_[v[1]], &cc = P_[v[2]], &d = P_[v[3]];
      Vec3 x;
      double theta = min_dihedral(a, b, cc, d);
      if (!circumcentre(a, b, cc, d, x) || !(theta > 1e-3)) {
        // A flat cell (four points on one circle, say the Steiner points a thin slab's refinement
        // puts on its mid-plane): the centre of the circle through its largest face, in the plane.
        if (!circumcircle_centre_of_largest_face(a, b, cc, d, x)) continue;
        theta = 0;
      }
      const double R = (x - a).norm();
      const bool quality = theta < opt_.refine_dihedral;
      if (!quality && !(R > rmax)) continue;
      std::sort(v.begin(), v.end());
      bad.push_back({quality ? theta : 1000.0 - R / rmax, v, x, quality});
    }
    if (bad.empty()) return false;
    std::sort(bad.begin(), bad.end(), [](const Bad& p, const Bad& q) { return p.key != q.key ? p.key < q.key : p.v < q.v; });
    std::vector<uint64_t> split;
    int inserted = 0;
    int why_gone = 0, why_short = 0, why_outside = 0, why_near = 0;
    std::vector<Facet> boundary, internal;
    std::vector<Ch> cells;
    // Inserts p (inside bad cell c's circumsphere, so c is in conflict with it) unless that would
    // destroy a surface face (returns the largest such face in *enc) or p is closer than `near_min`
    // to a vertex of the conflict zone.
    enum class Try { inserted, encroaches, near, outside };
    auto try_insert = [&](const Vec3& p, const Ch& c, double near_min, int* enc) {
      const WPoint wp(BPoint(p(0), p(1), p(2)));
      // find_conflicts needs c in conflict with p (a rounded circumcentre of a nearly flat cell, or
      // the circle centre of a flat one, may not be).
      if (tr_.side_of_power_sphere(c, wp, true) != CGAL::ON_BOUNDED_SIDE) return Try::outside;
      boundary.clear(), internal.clear(), cells.clear();
      tr_.find_conflicts(wp, c, std::back_inserter(boundary), std::back_inserter(cells), std::back_inserter(internal));
      conflict_cells_ += static_cast<long>(cells.size());
      *enc = -1;
      double enc_area = -1;
      for (const Facet& f : internal) {
        const int t = surface_tri(f.first, f.second);
        if (t < 0) continue;
        const auto& v = tri_[static_cast<size_t>(t)];
        const double area = (P_[v[1]] - P_[v[0]]).cross(P_[v[2]] - P_[v[0]]).squaredNorm();
        if (area > enc_area) enc_area = area, *enc = t;
      }
      // Nor inside the diametral ball of a surface face on the zone's boundary (Shewchuk's
      // encroachment): a point that close to the surface would make the faces around it
      // non-Delaunay as soon as the surface is split nearby, and recovering them would split the
      // surface down to that distance.
      for (const Facet& f : boundary) {
        const int t = surface_tri(f.first, f.second);
        if (t < 0) continue;
        const auto& v = tri_[static_cast<size_t>(t)];
        const Vec3& A = P_[v[0]];
        Vec3 centre;
        const double n2 = circumcircle_centre(A, P_[v[1]], P_[v[2]], centre);
        if (!(n2 > 0)) continue;
        if ((p - centre).squaredNorm() < (A - centre).squaredNorm()) {
          const double area = n2;
          if (area > enc_area) enc_area = area, *enc = t;
        }
      }
      if (*enc >= 0) return Try::encroaches;
      for (const Ch& k : cells)
        if (tr_.is_infinite(k) || k->subdomain_index() == 0) return Try::outside;
      if (boundary.empty()) return Try::outside;
      double near = INFINITY;
      for (const Ch& k : cells)
        for (int j = 0; j < 4; ++j) near = std::min(near, (P_[id(k->vertex(j))] - p).norm());
      if (near < near_min) return Try::near;
      const int i = static_cast<int>(P_.size());
      P_.push_back(p);
      on_surface_.push_back(0);
      const Vh v = tr_.insert_in_hole(wp, cells.begin(), cells.end(), boundary.front().first, boundary.front().second);
      vh_.push_back(v);
      id_[&*v] = i;
      std::vector<Ch> around;
      tr_.incident_cells(v, std::back_inserter(around));
      for (const Ch& k : around) k->set_subdomain_index(1);
      ++steiner_;
      return Try::inserted;
    };
    for (const Bad& b : bad) {
      // (Within the round too: one round of a long rod's refinement searched 5.6 million cells
      // against a budget of 2 million, 1.8 s.)
      if (static_cast<int>(P_.size()) > max_vertices_ || over_run_bound() || over_budget()) break;
      Ch c;
      if (!tr_.is_cell(vh_[b.v[0]], vh_[b.v[1]], vh_[b.v[2]], vh_[b.v[3]], c)) { ++why_gone; continue; }
      const double R = (P_[b.v[0]] - b.x).norm();
      int enc;
      Try got = try_insert(b.x, c, 0.2 * R, &enc);
      if (got == Try::inserted) {
        ++inserted;
        if (!b.quality) ++size_driven_;
        continue;
      }
      if (got == Try::encroaches) {
        // Quality asks for a finer boundary there; size does not (the boundary spacing is set).
        const uint64_t e = longest_edge(enc);
        if (b.quality && edge_length(e) > min_split_) {
          split.push_back(e);
          continue;
        }
      }
      if (b.quality) ++(got == Try::near ? why_near : got == Try::outside ? why_outside : why_short);
    }
    spdlog::debug("refine: {} bad, {} inserted, {} splits asked, gone {}, short {}, outside {}, near {}", bad.size(), inserted, split.size(), why_gone, why_short, why_outside, why_near);
    std::sort(split.begin(), split.end());
    split.erase(std::unique(split.begin(), split.end()), split.end());
    int done = 0;
    for (uint64_t k : split) done += split_edge(k) >= 0;
    return inserted + done > 0;
  }

  // CGAL's exuder on the tetrahedra below sliver_bound: weights only, never a surface face.
  // The complex CGAL's optimizers work on: the inside cells, the surface faces, vertex dimensions.
  void setup_complex() {
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c) {
      if (c->subdomain_index() == 0) continue;
      for (int i = 0; i < 4; ++i) {
        const Ch n = c->neighbor(i);
        if (tr_.is_infinite(n) || n->subdomain_index() == 0) c3t3_.add_to_complex(c, i, C3t3::Surface_patch_index(0, 1));
      }
    }
    for (size_t i = 0; i < vh_.size(); ++i) {
      if (vh_[i] == Vh()) continue;
      c3t3_.set_dimension(vh_[i], on_surface_[i] ? 2 : 3);
      if (on_surface_[i]) c3t3_.set_index(vh_[i], C3t3::Surface_patch_index(0, 1));
      else c3t3_.set_index(vh_[i], C3t3::Subdomain_index(1));
    }
    c3t3_.rescan_after_load_of_triangulation();
  }

  // CGAL's exuder on the tetrahedra below sliver_bound: weights only, never a surface face.
  // (Under detail::run_unless_sigfpe: beside a numerically flat cell, points split on a surface
  // edge and collinear with it up to rounding, CGAL 5.5's exuder can take a NaN weight and die of
  // SIGFPE; it then stops there, its earlier pumps kept.)
  // Returns false where it stopped at a NaN weight.
  // Its pumps (a vertex's weight changed to lift a sliver) are counted, and bounded by
  // TetrahedralizeOptions::exude_pumps_per_sliver: where the slivers cannot be lifted the exuder
  // can pump round in a circle until its time limit (a comb of 2 mm teeth at 1000: 571,216 pumps
  // in 30 s for 233 slivers, where the corpus's and organs' runs take about one per sliver).
  struct PumpBound {};  // thrown by the visitor between two pumps (the triangulation consistent)
  struct PumpCounter {
    long* pumps;
    long bound;
    void after_cell_pumped(std::size_t) {
      if (++*pumps >= bound) throw PumpBound{};
    }
  };
  bool exude(RunResult& r) {
    long slivers = 0;
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c)
      if (c->subdomain_index() != 0)
        slivers += min_dihedral(P_[id(c->vertex(0))], P_[id(c->vertex(1))], P_[id(c->vertex(2))], P_[id(c->vertex(3))]) <
                   opt_.sliver_bound;
    const long bound = opt_.exude_pumps_per_sliver > 0 ? std::max(1000L, opt_.exude_pumps_per_sliver * slivers) : LONG_MAX;
    CGAL::Mesh_optimization_return_code code = CGAL::BOUND_REACHED;
    long pumps = 0;
    const bool whole = detail::run_unless_sigfpe([&] {
      using Criterion = CGAL::Mesh_3::Min_dihedral_angle_criterion<Tr>;
      Criterion criterion(opt_.sliver_bound, c3t3_.triangulation());
      CGAL::Mesh_3::Slivers_exuder<C3t3, Criterion, PumpCounter> exuder(c3t3_, criterion);
      exuder.set_time_limit(opt_.exude_seconds);
      try {
        code = exuder(PumpCounter{&pumps, bound});
      } catch (const PumpBound&) {
        r.exuder_pump_bound = true;
      }
    });
    spdlog::debug("tetrahedralize: exuder: {} pumps for {} tetrahedra under {} degrees{}", pumps, slivers, opt_.sliver_bound,
                  r.exuder_pump_bound ? " (its bound)" : "");
    if (!whole)
      spdlog::debug("tetrahedralize: CGAL's sliver exuder met a NaN weight (a numerically flat cell) and stopped there");
    if (code == CGAL::TIME_LIMIT_REACHED)
      spdlog::warn("tetrahedralize: CGAL's sliver exuder stopped at its time limit ({} s): the mesh may differ from "
                   "run to run",
                   opt_.exude_seconds);
    return whole;
  }

  TetMesh extract() {
    // Vertices by their point (the exuder re-creates vertices, remeshing adds and moves interior
    // ones; surface vertices keep their points exactly).
    std::map<std::array<double, 3>, int> at;
    for (size_t i = 0; i < P_.size(); ++i) at.emplace(std::array<double, 3>{P_[i](0), P_[i](1), P_[i](2)}, static_cast<int>(i));
    std::unordered_map<const void*, int> vid;
    auto index = [&](const Vh& v) {
      auto it = vid.find(&*v);
      if (it != vid.end()) return it->second;
      const auto& p = tr_.point(v);
      const std::array<double, 3> key{p.x(), p.y(), p.z()};
      auto [jt, fresh] = at.try_emplace(key, static_cast<int>(P_.size()));
      if (fresh) P_.emplace_back(key[0], key[1], key[2]);
      vid.emplace(&*v, jt->second);
      return jt->second;
    };
    TetMesh m;
    std::vector<std::array<int, 4>> T;
    for (auto c = tr_.finite_cells_begin(); c != tr_.finite_cells_end(); ++c) {
      if (c->subdomain_index() == 0) continue;
      std::array<int, 4> t;
      for (int k = 0; k < 4; ++k) t[static_cast<size_t>(k)] = index(c->vertex(k));
      T.push_back(t);
    }
    std::vector<int> map(P_.size(), -1);
    // Vertices in order of first use by the tetrahedra sorted by their vertex ids: deterministic.
    std::sort(T.begin(), T.end(), [](const std::array<int, 4>& a, const std::array<int, 4>& b) {
      std::array<int, 4> x = a, y = b;
      std::sort(x.begin(), x.end());
      std::sort(y.begin(), y.end());
      return x < y;
    });
    int n = 0;
    for (auto& t : T)
      for (int& v : t) {
        if (map[static_cast<size_t>(v)] < 0) map[static_cast<size_t>(v)] = n++;
        v = map[static_cast<size_t>(v)];
      }
    m.V.resize(n, 3);
    for (size_t i = 0; i < P_.size(); ++i)
      if (map[i] >= 0) m.V.row(map[i]) = P_[i].transpose();
    m.T.resize(static_cast<Eigen::Index>(T.size()), 4);
    for (size_t i = 0; i < T.size(); ++i)
      for (int k = 0; k < 4; ++k) m.T(static_cast<Eigen::Index>(i), k) = T[i][static_cast<size_t>(k)];
    // In CGAL's vertex order: a triangulation's cells are positively oriented by its exact
    // predicate. (Not by the sign of a floating-point volume, orient_positively: that turned a
    // nearly flat cell the wrong way round by rounding, and relocate_sliver_vertices, which keeps
    // every volume positive, then moved a vertex to inflate it, inverted over its neighbours: a
    // 4 mm plate turned in space came out 1.00027 of its volume; meshing version 43. It is applied
    // at the very end, after the sliver moves.)
    return m;
  }
};

}  // namespace

TetMesh tetrahedralize(const SurfaceMesh& input_boundary, const TetrahedralizeOptions& opt, TetrahedralizeStats* stats,
                       Progress* progress) {
  if (input_boundary.F.rows() == 0) throw InputError("tetrahedralize: the surface has no face");
  if (opt.target_tets < 1) throw InputError("--target-tets must be at least 1");
  if (opt.max_attempts < 1) throw InputError("tetrahedralize: max_attempts must be at least 1");
  if (!(opt.edge_length_scale > 0) || !std::isfinite(opt.edge_length_scale))
    throw InputError("tetrahedralize: edge_length_scale must be positive and finite");
  // Long edges split first (TetrahedralizeOptions::long_edge), never below a twentieth of the
  // diagonal: a large flat face beside fine detail is cut into a few hundred pieces, not millions.
  const double split_above = std::max(opt.long_edge * median_edge_length(input_boundary),
                                      bounding_box_diagonal(input_boundary.V) / 20.0);
  const SurfaceMesh boundary =
      opt.long_edge > 0 && split_above > 0 ? split_long_edges(input_boundary, split_above) : input_boundary;
  if (boundary.F.rows() != input_boundary.F.rows())
    spdlog::debug("tetrahedralize: {} boundary faces with their edges longer than {:.4g} split: {} faces",
                  input_boundary.F.rows(), split_above, boundary.F.rows());
  double volume = 0;
  const Vec3 o = boundary.V.colwise().mean().transpose();
  for (Eigen::Index f = 0; f < boundary.F.rows(); ++f) {
    const Vec3 a = boundary.V.row(boundary.F(f, 0)).transpose() - o, b = boundary.V.row(boundary.F(f, 1)).transpose() - o,
               c = boundary.V.row(boundary.F(f, 2)).transpose() - o;
    volume += a.dot(b.cross(c)) / 6.0;
  }
  volume = std::abs(volume);
  const double target = opt.target_tets;
  // A regular tetrahedron of edge L has volume L³ / (6√2); Delaunay meshes average about half that.
  double L = opt.edge_length_scale * std::cbrt(6.0 * std::sqrt(2.0) * volume / (0.5 * target));
  CGAL::get_default_random() = CGAL::Random(static_cast<int>(opt.seed));
  const FastWindingNumber wn(boundary.V, boundary.F);
  TetrahedralizeStats st;
  RunResult best;
  double best_score = INFINITY;
  double previous_n = INFINITY, previous_L = 0;
  std::unique_ptr<Mesher> mesher;  // the next attempt's, made before it where it decides whether to run it
  // The refinement work the attempts may still do (Mesher's budget: 0, no bound).
  auto work_left = [&] { return opt.max_refine_work > 0 ? std::max(1.0, opt.max_refine_work - st.refine_work) : 0.0; };
  for (int attempt = 0; attempt < opt.max_attempts; ++attempt) {
    const auto t0 = std::chrono::steady_clock::now();
    if (progress) progress->stage("tetrahedralizing the boundary (attempt " + std::to_string(attempt + 1) + ")");
    if (!mesher) mesher = std::make_unique<Mesher>(boundary, wn, opt, L, work_left(), static_cast<int>(input_boundary.F.rows()));
    RunResult r = mesher->run(progress);
    const double n = static_cast<double>(r.mesh.T.rows());
    const bool recovered = r.recovered, length_bound = r.length_bound;
    spdlog::debug("tetrahedralize attempt {}: edge length {:.4g}: {} tetrahedra, {} boundary splits, {} Steiner points "
                 "({} for size), {:.2f} s",
                 attempt + 1, L, r.mesh.T.rows(), r.boundary_splits, r.steiner, r.size_driven,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    st.attempts = attempt + 1;
    st.exuder_nan_stops += r.exuder_stopped;
    st.exuder_pump_bounds += r.exuder_pump_bound;
    st.refine_work += r.work;
    st.flat_cells_flipped += r.flat_cells_flipped;
    st.runs_at_work_bound += r.run_bound;
    const bool exceeded = r.work_exceeded;
    st.work_exceeded = st.work_exceeded || exceeded;
    // A mesh that is not conforming (its tetrahedra classified by the winding number) is judged by
    // the volume it keeps as well: a thin roof 4 % of its diagonal thick, whose tapering end the
    // recovery did not follow, kept 6 % of its volume in the attempt nearest the target.
    double lost = 0;
    if (!r.conforming && n > 0) {
      const double kept = tet_volumes(r.mesh).sum() / volume;
      lost = kept > 0 ? std::abs(std::log(kept)) : 1e9;
    }
    const double score = (r.conforming ? 0 : 100 + 10 * lost) + (n > 0 ? std::abs(std::log(n / target)) : 1e9);
    if (score < best_score) {
      best_score = score;
      st.edge_length = L;
      st.boundary_splits = r.boundary_splits;
      st.steiner_points = r.steiner;
      st.conforming = r.conforming;
      st.recovered = r.recovered;
      st.recovery_abandoned = r.abandoned;
      st.peeled = r.peeled;
      best = std::move(r);
    }
    if (n > 0.87 * target && n < 1.15 * target) break;
    if (exceeded) break;  // its work bound: no further attempt
    // Coarser made no difference: the boundary (its faces and the quality it needs) sets the count.
    // Nor can it where the boundary was not recovered before refinement began: that recovery
    // depends on L only through the points set along creases, fewer for a longer L.
    if (n > target && !recovered) break;
    if (n > target && L > previous_L && n >= 0.95 * previous_n) {
      st.minimum_tets = static_cast<int>(std::min(n, previous_n));
      break;
    }
    previous_n = n;
    previous_L = L;
    L *= n > 0 ? std::clamp(std::cbrt(n / target), 0.5, 2.0) : 1.0;
    // Nor where the length shaped nothing in this run but its starting points, and the longer one
    // starts from the same points (RunResult::length_bound): it would give the same mesh (the
    // heart's second attempt did, 0.7 s).
    if (attempt + 1 >= opt.max_attempts) break;
    std::unique_ptr<Mesher> next = std::make_unique<Mesher>(boundary, wn, opt, L, work_left(), static_cast<int>(input_boundary.F.rows()));
    if (opt.skip_repeated_attempts && n > target && !length_bound && next->same_start(*mesher)) break;
    mesher = std::move(next);
  }
  // Slivers left in the mesh kept (four corners on the boundary, where neither refinement nor
  // exudation reaches them, or boundary ones too thick to peel): their vertices are moved
  // (boundary ones only within the tangent plane of a smooth boundary), then what is still below
  // the floor is flipped away (boundary and volume unchanged), as in the winding-number route.
  // Not where the boundary is not conforming (its tetrahedra classified by the winding number): that
  // mesh holds no bound whatever its angles and is replaced where anything holds (ADIS16480.STL's
  // first attempt: 49,651 moves, 14 s, for 0.22°; meshing version 55).
  if (st.conforming) {
    st.relocated = relocate_sliver_vertices(best.mesh, opt.min_dihedral);
    st.flips = flip_slivers(best.mesh, opt.min_dihedral);
  }
  // Slivers still left (interior ones with all four vertices on the boundary, across a spike
  // thinner than the tetrahedra: the urchin of 24 spikes, seed 23, at 1000 kept five, 1.5° and
  // up, through the moves and flips, and went on to three retries and its winding-number solid,
  // 15,765 tetrahedra in 16 s): their short edges contracted, the moves and flips again after
  // each round (each reaches what the others opened), while any of them changes something. Before
  // the last peeling: peeled first, the urchin's boundary lay 1.47 % of the diagonal out where
  // the peeling took it inward at the tip, 0.965 % so. Where the first round contracts nothing,
  // the mesh is left as it was (no further moves). Not where the boundary was not recovered (its
  // tetrahedra classified by the winding number): that mesh holds no bound whatever its angles,
  // and its slivers can be thousands (a CAD cylinder's fanned caps: 130 s of contractions).
  if (opt.contract_max_length > 0 && st.conforming) {
    const double max_length = std::min(opt.peel_max_height, opt.contract_max_length * st.edge_length);
    auto worst = [&] {
      const TetMesh& x = best.mesh;
      double w = 180.0;
      for (Eigen::Index t = 0; t < x.T.rows(); ++t)
        w = std::min(w, min_dihedral(x.V.row(x.T(t, 0)), x.V.row(x.T(t, 1)), x.V.row(x.T(t, 2)), x.V.row(x.T(t, 3))));
      return w;
    };
    for (int round = 0; round < 8 && worst() < opt.min_dihedral; ++round) {
      const int c = contract_sliver_edges(best.mesh, opt.min_dihedral, max_length);
      if (c == 0 && round == 0) break;
      const int moves = relocate_sliver_vertices(best.mesh, opt.min_dihedral);
      const int flips = flip_slivers(best.mesh, opt.min_dihedral);
      st.contractions += c;
      st.relocated += moves;
      st.flips += flips;
      if (c + moves + flips == 0) break;
    }
    if (st.contractions > 0) remove_unused_vertices(best.mesh);
  }
  // Boundary slivers neither could mend (a corner or crease holds every vertex) are peeled off
  // after all, whatever their height: a flat tetrahedron is worse than the boundary moving (the
  // elephant at 150 kept a 0° one).
  const int late = peel_boundary_slivers(best.mesh, opt.min_dihedral);
  if (late > 0) remove_unused_vertices(best.mesh);
  st.peeled += late;
  spdlog::debug("tetrahedralize: slivers: {} vertex moves, {} flips, {} peeled at the end, {} edges contracted",
                st.relocated, st.flips, late, st.contractions);
  // A cell still nearly flat has its floating-point volume made positive as well, now that no
  // vertex moves any more (extract: the moves before must see CGAL's orientation). Consumers such
  // as the FEM's rest state test that sign.
  orient_positively(best.mesh);
  if (stats) *stats = st;
  if (progress) progress->finish();
  return std::move(best.mesh);
}

}  // namespace squeeze::meshing
