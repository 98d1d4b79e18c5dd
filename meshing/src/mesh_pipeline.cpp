#include "squeeze/meshing/mesh_pipeline.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <atomic>
#include <array>
#include <set>
#include <cmath>
#include <functional>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>

#include <spdlog/spdlog.h>

#include "squeeze/common/error.h"
#include "squeeze/common/format.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/alpha_wrap.h"
#include "squeeze/meshing/chord_volume.h"
#include "squeeze/meshing/decimate.h"
#include "squeeze/meshing/hole_caps.h"
#include "squeeze/meshing/remesh.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/sheet.h"
#include "squeeze/meshing/tet_geometry.h"
#include "squeeze/meshing/shell_tetrahedralize.h"
#include "squeeze/meshing/split_long_edges.h"
#include "squeeze/meshing/surface_analysis.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/tet_cleanup.h"
#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_locator.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/winding_number.h"

namespace squeeze::meshing {
namespace {

// Waits in `arena` for `group` (rethrows what one of its tasks threw).
void arena_wait(tbb::task_arena& arena, tbb::task_group& group) {
  arena.execute([&] { group.wait(); });
}

class StageTimer {
 public:
  StageTimer(MeshResult& r, Progress* p) : r_(r), p_(p) {}
  void start(const std::string& name) {
    stop();
    name_ = name;
    t0_ = std::chrono::steady_clock::now();
    if (p_) p_->stage(name);
  }
  void stop() {
    if (name_.empty()) return;
    r_.seconds.emplace_back(name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count());
    if (p_) p_->finish();
    name_.clear();
  }

 private:
  MeshResult& r_;
  Progress* p_;
  std::string name_;
  std::chrono::steady_clock::time_point t0_;
};

// The spacing of the points at which a deviation between surfaces is sampled (farthest_sample,
// surface_samples): 0.2 % of `diag`, coarser where that would be more than about 200,000 points
// on a surface of one of `areas` (units²). The largest distance is then found to within
// spacing / √3.
double deviation_spacing(double diag, std::initializer_list<double> areas) {
  double spacing = 2e-3 * diag;
  for (double a : areas) spacing = std::max(spacing, std::sqrt(a / 2e5));
  return spacing;
}

}  // namespace

int hull_budget(const MeshOptions& opt) {
  const double per_hull = opt.tets_per_hull;
  if (per_hull <= 0) return opt.decomposition.max_hulls;
  const double n = std::round(static_cast<double>(opt.tetrahedralize.target_tets) / per_hull);
  return static_cast<int>(std::clamp(n, 1.0, static_cast<double>(std::max(1, opt.decomposition.max_hulls))));
}

const std::vector<std::string>& mesh_route_names() {
  static const std::vector<std::string> names = {"auto", "convex_shells", "winding_number", "alpha_wrap", "all_convex_shells"};
  return names;
}

void set_mesh_route(MeshOptions& options, const std::string& name) {
  const std::vector<std::string>& names = mesh_route_names();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    throw InputError("unknown mesh route \"" + name + "\" (" + list + ")");
  }
  options.shells_fallback = name == "convex_shells";
  options.shells_only = name == "all_convex_shells";
  options.winding = name == "winding_number";
  options.wrap = name == "alpha_wrap";
}

namespace {

double signed_volume(const SurfaceMesh& m) {
  if (m.V.rows() == 0) return 0;
  const Eigen::RowVector3d o = m.V.colwise().mean();
  double v = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    v += (m.V.row(m.F(f, 0)) - o).dot((m.V.row(m.F(f, 1)) - o).cross(m.V.row(m.F(f, 2)) - o)) / 6.0;
  return v;
}

double area(const SurfaceMesh& m) {
  double a = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    a += 0.5 * (m.V.row(m.F(f, 1)) - m.V.row(m.F(f, 0))).cross(m.V.row(m.F(f, 2)) - m.V.row(m.F(f, 0))).norm();
  return a;
}

// The faces `faces` of m (sorted) with the vertices they use, renumbered in order of first use;
// `index` (optional): per vertex of the result, its index in m.
SurfaceMesh sub_mesh(const SurfaceMesh& m, const std::vector<int>& faces, std::vector<int>* index = nullptr) {
  std::vector<int> map(static_cast<size_t>(m.V.rows()), -1);
  SurfaceMesh out;
  out.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  int n = 0;
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      int& v = map[static_cast<size_t>(m.F(faces[i], k))];
      if (v < 0) v = n++;
      out.F(static_cast<Eigen::Index>(i), k) = v;
    }
  out.V.resize(n, 3);
  if (index) index->assign(static_cast<size_t>(n), -1);
  for (Eigen::Index v = 0; v < m.V.rows(); ++v)
    if (map[static_cast<size_t>(v)] >= 0) {
      out.V.row(map[static_cast<size_t>(v)]) = m.V.row(v);
      if (index) (*index)[static_cast<size_t>(map[static_cast<size_t>(v)])] = static_cast<int>(v);
    }
  return out;
}

// The meshes ms as one: vertices stacked in order, the elements (member `elements`: F or T) of
// each shifted by the vertices before it.
template <class Mesh, class Elements>
Mesh concatenate(const std::vector<Mesh>& ms, Elements Mesh::*elements) {
  Eigen::Index nv = 0, ne = 0;
  for (const Mesh& m : ms) nv += m.V.rows(), ne += (m.*elements).rows();
  Mesh out;
  out.V.resize(nv, 3);
  (out.*elements).resize(ne, Elements::ColsAtCompileTime);
  Eigen::Index v = 0, e = 0;
  for (const Mesh& m : ms) {
    out.V.middleRows(v, m.V.rows()) = m.V;
    (out.*elements).middleRows(e, (m.*elements).rows()) = (m.*elements).array() + static_cast<int>(v);
    v += m.V.rows(), e += (m.*elements).rows();
  }
  return out;
}

// Disjoint sets over 0..n-1 (union by index, path halving).
struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(Eigen::Index n) : parent(static_cast<size_t>(n)) {
    for (size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  }
  int find(int i) {
    while (parent[static_cast<size_t>(i)] != i)
      i = parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    return i;
  }
  void join(int i, int j) { parent[static_cast<size_t>(find(i))] = find(j); }
};

// Per face of G (#G by 3, no repeated face in one orientation): true where it lies in a wall
// between segments welded to each other, which bounds nothing of their union (meshing version 18):
// two boxes end to end, each with its own copy of the shared wall (a face and its twin, the same
// vertices in the opposite order) or with one copy of it. A wall is a patch (faces joined across
// edges of exactly two faces) with an edge of three or more faces (where it meets the segments'
// outsides) that the rest of G encloses: at each of its faces, the mean of the winding numbers just
// off either side is about 1 (0.75 to 1.25; the face's own share is opposite on its two sides, so
// the mean is the rest's; the winding numbers of G's patches oriented, less twin pairs and the
// walls found in earlier rounds). The segments' outsides have a mean of 1/2 (inside on one side,
// outside on the other); a sheet modelled as two faces back to back, 0; a segment inside another,
// 3/2.
// Walls are dropped from a component (faces joined across any edge) only where that leaves each
// of its edges in no face or in two with opposite directions along it: the union's closed
// surface. (Overlapping segments, as the liver's and the lungs', mix means of 1/2, 1 and 3/2 in
// a patch, or leave edges of one face: kept.)
std::vector<char> walls_between_welded_segments(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& G) {
  const Eigen::Index n = G.rows();
  std::vector<char> wall(static_cast<size_t>(n), 0);
  const std::vector<EdgeIncidence> edges = edge_incidences(G);  // each edge's faces together
  std::vector<std::pair<size_t, size_t>> runs;  // [begin, end) of each edge's entries
  bool branching = false;
  for_each_edge(edges, [&](size_t i, size_t j) {
    runs.emplace_back(i, j);
    branching |= j - i > 2;
  });
  if (!branching) return wall;
  // twin: faces of a twin pair (the same three vertices, in either order).
  std::vector<char> twin(static_cast<size_t>(n), 0);
  {
    std::vector<std::pair<std::array<int, 3>, int>> keys(static_cast<size_t>(n));
    for (Eigen::Index f = 0; f < n; ++f) {
      std::array<int, 3> k{G(f, 0), G(f, 1), G(f, 2)};
      std::sort(k.begin(), k.end());
      keys[static_cast<size_t>(f)] = {k, static_cast<int>(f)};
    }
    std::sort(keys.begin(), keys.end());
    for (size_t i = 1; i < keys.size(); ++i)
      if (keys[i].first == keys[i - 1].first) twin[static_cast<size_t>(keys[i].second)] = twin[static_cast<size_t>(keys[i - 1].second)] = 1;
  }
  // Each patch oriented (a segment given inside out, say), so that winding numbers add up. The
  // patches are those of G less its twin pairs (meshing version 28): walls of twin pairs cut the
  // segments' outsides into patches at every edge they meet, down to single squares of a voxel
  // model (887 cubes touching face to face), whose signed volume about their centroid,
  // orient_outward's test, is zero. Turned at random, they left no wall found, and the model was
  // meshed 9 times its volume. The twins, which cancel, take no part in the winding numbers below.
  Eigen::MatrixX3i O = G;
  {
    std::vector<Eigen::Index> single;
    for (Eigen::Index f = 0; f < n; ++f)
      if (!twin[static_cast<size_t>(f)]) single.push_back(f);
    Eigen::MatrixX3i S(static_cast<Eigen::Index>(single.size()), 3);
    for (size_t i = 0; i < single.size(); ++i) S.row(static_cast<Eigen::Index>(i)) = G.row(single[i]);
    const Eigen::MatrixX3i OS = orient_outward(V, S);
    for (size_t i = 0; i < single.size(); ++i) O.row(single[i]) = OS.row(static_cast<Eigen::Index>(i));
  }
  DisjointSets patch(n), component(n);
  for (const auto& [i, j] : runs)
    for (size_t k = i + 1; k < j; ++k) {
      if (j - i == 2) patch.join(edges[k].face, edges[i].face);
      component.join(edges[k].face, edges[i].face);
    }
  std::vector<char> candidate(static_cast<size_t>(n), 0);  // per patch root
  for (const auto& [i, j] : runs)
    if (j - i > 2)
      for (size_t k = i; k < j; ++k) candidate[static_cast<size_t>(patch.find(edges[k].face))] = 1;
  // The winding numbers are those of the faces not yet found in walls, less both faces of each
  // twin pair (which cancel: their orientations, as single faces, orient_outward cannot tell), so
  // that one wall's share does not move another's mean where they meet (an L of three blocks).
  // Found in rounds: a wall's faces all in the band; again without them, while more are found.
  std::vector<char> found(static_cast<size_t>(n), 0);  // per patch root: a wall
  for (int round = 0; round < 4; ++round) {
    std::vector<Eigen::Index> field;
    for (Eigen::Index f = 0; f < n; ++f)
      if (!twin[static_cast<size_t>(f)] && !found[static_cast<size_t>(patch.find(static_cast<int>(f)))]) field.push_back(f);
    Eigen::MatrixX3i W(static_cast<Eigen::Index>(field.size()), 3);
    for (size_t i = 0; i < field.size(); ++i) W.row(static_cast<Eigen::Index>(i)) = O.row(field[i]);
    if (W.rows() == 0) break;
    const FastWindingNumber w(V, W);
    std::vector<char> in_band(candidate);  // per patch root, among those not found yet
    for (Eigen::Index p = 0; p < n; ++p) in_band[static_cast<size_t>(p)] &= !found[static_cast<size_t>(p)];
    for (Eigen::Index f = 0; f < n; ++f) {
      const int p = patch.find(static_cast<int>(f));
      if (!in_band[static_cast<size_t>(p)]) continue;
      const Eigen::RowVector3d a = V.row(O(f, 0)), b = V.row(O(f, 1)), c = V.row(O(f, 2));
      const Eigen::RowVector3d normal = (b - a).cross(c - a);  // twice the area in length
      const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
      // 1 % of the inradius off the centroid, either side: close to the face, far from the others.
      const Eigen::RowVector3d centroid = (a + b + c) / 3.0, off = 0.01 * normal / perimeter;
      const double mean = std::abs(0.5 * (w(centroid + off) + w(centroid - off)));
      if (!(mean > 0.75 && mean < 1.25)) in_band[static_cast<size_t>(p)] = 0;
    }
    int more = 0;
    for (Eigen::Index p = 0; p < n; ++p)
      if (in_band[static_cast<size_t>(p)]) found[static_cast<size_t>(p)] = 1, ++more;
    if (more == 0) break;
  }
  candidate = found;
  std::vector<char> refused(static_cast<size_t>(n), 0);  // per component root
  for (const auto& [i, j] : runs) {
    int left = 0, direction = 0;
    bool walled = false;
    for (size_t k = i; k < j; ++k) {
      const int f = edges[k].face;
      if (candidate[static_cast<size_t>(patch.find(f))]) {
        walled = true;
        continue;
      }
      ++left;
      for (int e = 0; e < 3; ++e) direction += (O(f, e) == edges[k].a && O(f, (e + 1) % 3) == edges[k].b) -
                                               (O(f, e) == edges[k].b && O(f, (e + 1) % 3) == edges[k].a);
    }
    if (walled && !(left == 0 || (left == 2 && direction == 0))) refused[static_cast<size_t>(component.find(edges[i].face))] = 1;
  }
  for (Eigen::Index f = 0; f < n; ++f)
    wall[static_cast<size_t>(f)] = candidate[static_cast<size_t>(patch.find(static_cast<int>(f)))] &&
                                   !refused[static_cast<size_t>(component.find(static_cast<int>(f)))];
  return wall;
}

// F without faces of zero area (three collinear vertices, to 1e-5 of the longest edge; the loader
// has already dropped those with a repeated vertex), without repeats of a face (the same three
// vertices in any order: a duplicated face, or a face and its twin, which enclose nothing; the
// first of each kept), and without the walls between segments welded to each other
// (walls_between_welded_segments: both twins of such a wall dropped).
Eigen::MatrixX3i without_duplicate_and_flat_faces(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  // G: the first face of each vertex set in each orientation, in input order.
  std::map<std::array<int, 3>, std::array<int, 2>> first;  // sorted vertices: G's face per orientation
  std::vector<Eigen::Index> kept;                          // G's faces in F
  int flat = 0, repeated = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::RowVector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    // Zero area: height over the longest edge below 1e-5 of it (a needle: collinear corners,
    // up to the rounding of a float32 file).
    const double longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    if ((b - a).cross(c - a).squaredNorm() <= 1e-10 * longest2 * longest2) {
      ++flat;
      continue;
    }
    std::array<int, 3> k{F(f, 0), F(f, 1), F(f, 2)};
    std::sort(k.begin(), k.end());
    // Its orientation: the cyclic order from the smallest vertex ascending or not.
    const int x = F(f, 0), y = F(f, 1), z = F(f, 2);
    const int next = k[0] == x ? y : k[0] == y ? z : x, last = k[0] == x ? z : k[0] == y ? x : y;
    int& slot = first.try_emplace(k, std::array<int, 2>{-1, -1}).first->second[next < last ? 0 : 1];
    if (slot >= 0) {
      ++repeated;
      continue;
    }
    slot = static_cast<int>(kept.size());
    kept.push_back(f);
  }
  Eigen::MatrixX3i G(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i) G.row(static_cast<Eigen::Index>(i)) = F.row(kept[i]);
  const std::vector<char> wall = walls_between_welded_segments(V, G);
  // Out: G without its walls, each vertex set's first face kept (a sheet's twins once).
  std::vector<Eigen::Index> out;
  int twins = 0, walls = 0;
  for (size_t i = 0; i < kept.size(); ++i) {
    if (wall[i]) {
      ++walls;
      continue;
    }
    std::array<int, 3> k{G(static_cast<Eigen::Index>(i), 0), G(static_cast<Eigen::Index>(i), 1),
                         G(static_cast<Eigen::Index>(i), 2)};
    std::sort(k.begin(), k.end());
    const std::array<int, 2>& both = first.at(k);
    const int other = both[0] == static_cast<int>(i) ? both[1] : both[0];
    if (other >= 0 && other < static_cast<int>(i) && !wall[static_cast<size_t>(other)]) {
      ++twins;
      continue;
    }
    out.push_back(kept[i]);
  }
  if (flat + repeated + twins + walls == 0) return F;
  spdlog::debug("input: {} faces of zero area, {} repeated faces and {} twins dropped, and {} faces of walls between "
                "welded segments", flat, repeated, twins, walls);
  Eigen::MatrixX3i result(static_cast<Eigen::Index>(out.size()), 3);
  for (size_t i = 0; i < out.size(); ++i) result.row(static_cast<Eigen::Index>(i)) = F.row(out[i]);
  return result;
}

// One part of the input and what becomes of it.
struct Part {
  SurfaceMesh surface;        // a component of the input: closed, outward, 2-manifold (or a sheet's slab)
  int component = -1;         // which face-connected component of the input
  bool check = false;         // it intersects itself: check its simplified boundary
  bool failed = false;        // ... which still did
  double volume = 0;
  int target_faces = 0;
  SurfaceMesh boundary;
  EnvelopeStats envelope;
  TetMesh tets;
  TetrahedralizeStats tet_stats;
  int retries = 0;            // boundaries tried after the first (see mesh_parts)
  int tets_count = 0;              // its tetrahedra, counted before they are concatenated
  bool by_winding_number = false;  // meshed as its winding-number solid after its boundary failed
  bool remeshed = false;           // meshed from its own surface remeshed (retry 0, version 22)
  int exuder_nan_stops = 0;   // its attempts' exuders that met a NaN weight (TetrahedralizeStats)
  int exuder_pump_bounds = 0;  // ... that stopped at their pump bound (TetrahedralizeStats)
  SurfaceMesh sheet;          // an open sheet (sheet.h), when `surface` is its slab: meshed as one
                              // layer of prisms (sheet_tets) where it can be
  bool sheet_capped = false;  // ... with more tetrahedra than its share of the target (thinness)
  double thin = 0;            // a closed part meshed as the slab of its mid-surface: its mean thickness
  const SurfaceMesh* target = nullptr;  // the input, when `surface` is not its own boundary but
                              // its winding-number solid's (the bounds are the input's; version 11)
  bool scan = false;          // the sheet is an open scan of a solid (holes wider than the bound)
  bool beside_solid = false;  // a closed part meshed beside the winding-number solid of the input's
                              // other components (MeshOptions::closed_parts_beside_solid)
  double offset = 0;          // how far `surface` lies outside the input (units): a sheet's slab, half
                              // its thickness (sheet.h); taken off the outer bound, and the inner
                              // bound kept below half of it so that the sheet stays inside
};

// The faces of `sheet` whose prisms (sheet_tets: its vertex v is v and #V + v of the slab) hold a
// tetrahedron of `tets` with a dihedral angle under `floor` degrees: those holding all that
// tetrahedron's sheet vertices (after the sliver moves and flips, which keep the vertices).
std::vector<int> sliver_faces(const SurfaceMesh& sheet, const TetMesh& tets, double floor) {
  const int nv = static_cast<int>(sheet.V.rows());
  const std::vector<std::vector<int>> faces_at = vertex_faces(sheet.F, nv);
  std::vector<int> bad;
  for (Eigen::Index t = 0; t < tets.T.rows(); ++t) {
    const auto a = dihedral_angles(tets.V.row(tets.T(t, 0)), tets.V.row(tets.T(t, 1)), tets.V.row(tets.T(t, 2)),
                                   tets.V.row(tets.T(t, 3)));
    if (*std::min_element(a.begin(), a.end()) >= floor) continue;
    std::array<int, 4> base;
    for (int k = 0; k < 4; ++k) base[static_cast<size_t>(k)] = tets.T(t, k) % nv;
    for (int f : faces_at[static_cast<size_t>(base[0])]) {
      bool all = true;
      for (int k = 1; k < 4; ++k)
        all = all && (sheet.F(f, 0) == base[static_cast<size_t>(k)] || sheet.F(f, 1) == base[static_cast<size_t>(k)] ||
                      sheet.F(f, 2) == base[static_cast<size_t>(k)]);
      if (all) bad.push_back(f);
    }
  }
  std::sort(bad.begin(), bad.end());
  bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
  return bad;
}

// The words fallback_because gives open scans of solids (mesh_surface looks for them).
const std::string kOpenScans = "open scans of solids";
// The method of a try, on the winding-number solid of some components only, that the caller
// replaces with the whole input's solid (MeshOptions::closed_parts_beside_solid).
const std::string kWholeSolid = "(whole input's solid)";

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g%%", 100.0 * x);
  return buf;
}

// A result made after an earlier try (a refused shells mesh, a slab or solid not kept): the earlier
// try's stage seconds and its decomposition's put first, so that the report sums both tries'.
void after_earlier_try(MeshResult& later, const MeshResult& earlier) {
  later.seconds.insert(later.seconds.begin(), earlier.seconds.begin(), earlier.seconds.end());
  later.beside.insert(later.beside.begin(), earlier.beside.begin(), earlier.beside.end());
}

// The share of an input's area under which its components that are not closed parts are strays
// beside the closed ones (meshing version 35: meshed as their own solid beside the parts), and at
// or over which the input is mostly welded segments (version 38: its solid hollowed first).
constexpr double kStrayAreaShare = 0.1;

// Whether `s` is mostly segments welded to each other: some edge has more than two faces, and the
// face-connected components (through edges of two faces) that are not closed by themselves cover
// at least kStrayAreaShare of its area (an organ given as patches that meet at seams, valves among
// them; not closed parts beside a stray fin, which the route meshes as parts).
bool mostly_welded_segments(const SurfaceMesh& s) {
  const auto e = edge_incidences(s.F);
  std::vector<char> on_edge(static_cast<size_t>(s.F.rows()), 0);  // a face on an edge of other than two faces
  bool welded = false;
  for_each_edge(e, [&](size_t i, size_t j) {
    if (j - i == 2) return;
    welded = welded || j - i > 2;
    for (size_t k = i; k < j; ++k) on_edge[static_cast<size_t>(e[k].face)] = 1;
  });
  if (!welded) return false;
  Eigen::VectorXi C;
  const int n = face_components(s.F, C);
  std::vector<char> open(static_cast<size_t>(n), 0);
  for (Eigen::Index f = 0; f < s.F.rows(); ++f)
    if (on_edge[static_cast<size_t>(f)]) open[static_cast<size_t>(C(f))] = 1;
  std::vector<int> segments;  // (in increasing order, as sub_mesh takes them)
  for (Eigen::Index f = 0; f < s.F.rows(); ++f)
    if (open[static_cast<size_t>(C(f))]) segments.push_back(static_cast<int>(f));
  return area(sub_mesh(s, segments)) >= kStrayAreaShare * area(s);
}

// Whether r is the winding-number solid of an input that is not closed (its holes capped).
bool winding_solid_of_open_input(const MeshResult& r) {
  return (r.method == "winding_number_boundary" || r.method == "winding_number") && !r.info.closed;
}

// The largest distance from samples of (V, F) `spacing` apart to the triangles of `to` (a one-sided
// Hausdorff distance). A sample with a triangle within the largest distance found so far cannot
// raise it and is skipped (TriangleBvh::any_within); the others are measured: the same maximum as
// measuring every sample, in whatever order the threads take them.
double farthest_sample(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const TriangleBvh& to, double spacing) {
  const auto pts = surface_samples(V, F, spacing);
  std::atomic<double> farthest{0.0};
  tbb::parallel_for(size_t(0), pts.size(), [&](size_t i) {
    double now = farthest.load(std::memory_order_relaxed);
    if (to.any_within(pts[i], now)) return;
    const double d = to.nearest(pts[i]);
    while (d > now && !farthest.compare_exchange_weak(now, d, std::memory_order_relaxed)) {
    }
  });
  return farthest.load();
}

// How far a candidate boundary (V, F) lies from a part's surface S both ways, as its deviation
// bounds judge it: `out` the farthest of its samples from S (S_bvh, S's triangles), `in` the
// farthest of S's samples from it, each `spacing` apart (farthest_sample).
struct TwoWayDistance {
  double out = 0, in = 0;
};
TwoWayDistance farthest_both_ways(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const SurfaceMesh& S,
                                  const TriangleBvh& S_bvh, double spacing) {
  return {farthest_sample(V, F, S_bvh, spacing), farthest_sample(S.V, S.F, TriangleBvh(V, F), spacing)};
}

// The farthest of S's samples (`spacing` apart) that lie outside every tetrahedron (locator) from
// the tetrahedra's boundary (its triangles in `boundary`); 0 where none lies outside.
double farthest_outside(const TetLocator& locator, const TriangleBvh& boundary, const SurfaceMesh& S, double spacing) {
  const auto pts = surface_samples(S.V, S.F, spacing);
  std::vector<double> d(pts.size(), 0.0);
  tbb::parallel_for(size_t(0), pts.size(), [&](size_t i) {
    if (locator.locate(pts[i].transpose()) < 0) d[i] = boundary.nearest(pts[i]);
  });
  return d.empty() ? 0.0 : *std::max_element(d.begin(), d.end());
}

// The faces of each component: C  #F component id per face (face_components), n components.
std::vector<std::vector<int>> faces_by_component(const Eigen::VectorXi& C, int n) {
  std::vector<std::vector<int>> faces(static_cast<size_t>(n));
  for (Eigen::Index f = 0; f < C.size(); ++f) faces[static_cast<size_t>(C(f))].push_back(static_cast<int>(f));
  return faces;
}

// The face-connected components of `s` as parts (surface, signed volume, component); the index
// of the first that is not a closed oriented 2-manifold, or that `encloses` says does not enclose
// volume (its signed volume), or -1.
std::vector<Part> closed_components(const SurfaceMesh& s, const std::function<bool(double)>& encloses, int* bad) {
  Eigen::VectorXi comp;
  const int n = face_components(s.F, comp);
  const std::vector<std::vector<int>> faces = faces_by_component(comp, n);
  std::vector<Part> parts(static_cast<size_t>(n));
  *bad = -1;
  for (int c = 0; c < n; ++c) {
    Part& p = parts[static_cast<size_t>(c)];
    p.surface = sub_mesh(s, faces[static_cast<size_t>(c)]);
    p.volume = signed_volume(p.surface);
    p.component = c;
    if (*bad < 0 && (!is_closed(p.surface.F) || !is_oriented_two_manifold(p.surface.F, static_cast<int>(p.surface.V.rows())) ||
                     !encloses(p.volume)))
      *bad = c;
  }
  return parts;
}

// The report's measures of r.tets against r.input: quality, volume ratio (closed inputs),
// deviation_out / deviation_in, coverage of the input's vertices.
void measure(MeshResult& r, const MeshOptions& opt) {
  const double diag = bounding_box_diagonal(r.input.V);
  r.deviation_in = r.max_outside_distance = 0;  // maxima below (a route may be measured twice)
  r.volume_ratio.reset();
  r.quality = tet_quality(r.tets);
  if (r.info.closed && r.input_volume > 0) r.volume_ratio = r.quality.volume / r.input_volume;
  const TetLocator locator(r.tets);
  const Eigen::MatrixX3i tet_boundary = boundary_faces(r.tets.T);
  const TriangleBvh tet_surface(r.tets.V, tet_boundary);
  const TriangleBvh input_surface(r.input.V, r.input.F);
  // Deviations, at points at most 0.2% of the diagonal apart (coarser if that would be more than
  // about 200,000 points on either surface): the largest distance is then found to within
  // spacing / √3 (0.12% of the diagonal).
  const double spacing = deviation_spacing(diag, {area(r.input), area(SurfaceMesh{r.tets.V, tet_boundary})});
  r.deviation_sample_spacing = spacing;
  r.deviation_out = farthest_sample(r.tets.V, tet_boundary, input_surface, spacing);
  r.deviation_in = farthest_outside(locator, tet_surface, r.input, spacing);
  const Eigen::Index n = r.input.V.rows();
  std::vector<double> dist(static_cast<size_t>(n), 0.0);
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    if (locator.locate(r.input.V.row(i)) >= 0) return;
    dist[static_cast<size_t>(i)] = tet_surface.nearest(r.input.V.row(i).transpose());
  });
  Eigen::Index inside = 0, covered = 0;
  for (double d : dist) {
    inside += d == 0.0;
    covered += d <= opt.coverage_tolerance * diag;
    r.max_outside_distance = std::max(r.max_outside_distance, d);
  }
  r.inside_fraction = static_cast<double>(inside) / static_cast<double>(n);
  r.covered_fraction = static_cast<double>(covered) / static_cast<double>(n);

}

}  // namespace

namespace {
// How much a winding-number solid may grow the input's volume before it is made thinner: 8 % from
// 1,000 tetrahedra, where the issue's volume bound is [0.95, 1.1], 15 % below ([0.9, 1.2]). The
// whole input's solid (the winding-number route, version 30) and a part's own solid alike.
double allowed_solid_growth(double target_tets) { return target_tets >= 1000 ? 0.08 : 0.15; }

// decomposition: the input's, when a first try already made it (mesh_surface), else null.
MeshResult mesh_surface_once(const SurfaceMesh& surface, const MeshOptions& opt, Progress* progress,
                             const Decomposition* decomposition_made = nullptr) {
  if (!(opt.coverage_tolerance >= 0)) throw InputError("coverage tolerance must be >= 0");
  if (!(opt.tets_per_hull >= 0)) throw InputError("tets_per_hull must be >= 0");
  if (opt.tetrahedralize.target_tets < 1) throw InputError("--target-tets must be at least 1");
  if (!(opt.max_deviation > 0 && opt.max_deviation < 1)) throw InputError("--max-deviation must be between 0 and 1");
  if (!(opt.inner_deviation > 0 && opt.inner_deviation <= 1)) throw InputError("inner_deviation must be in (0, 1]");
  if (!(opt.first_try_inner_deviation > 0 && opt.first_try_inner_deviation <= 1))
    throw InputError("MeshOptions::first_try_inner_deviation must be in (0, 1]");
  if (!(opt.solid_min_scale > 0 && opt.solid_min_scale <= 1))
    throw InputError("MeshOptions::solid_min_scale must be in (0, 1]");
  if (!(opt.remesh_volume_loss >= 0 && opt.remesh_volume_loss < 1)) throw InputError("remesh_volume_loss must be in [0, 1)");
  if (!(opt.wrap_alpha > 0 && opt.wrap_alpha * opt.max_deviation < 1))
    throw InputError("--wrap-alpha must be positive and, times --max-deviation, below 1");
  if (!(opt.sheet_sliver_drop >= 0 && opt.sheet_sliver_drop < 1))
    throw InputError("MeshOptions::sheet_sliver_drop must be in [0, 1)");
  if (!(opt.sheet_thickness > 0 && opt.sheet_thickness * opt.max_deviation < 1))
    throw InputError("--sheet-thickness must be positive and, times --max-deviation, below 1");
  if (!(opt.wrap_offset > 0 && opt.wrap_offset * opt.max_deviation < 1))
    throw InputError("--wrap-offset must be positive and, times --max-deviation, below 1");
  if (!(opt.winding_facet_distance > 0 && opt.winding_facet_distance * opt.max_deviation < 1))
    throw InputError("--winding-facet-distance must be positive and, times --max-deviation, below 1");
  if (!(opt.winding_dilation >= 0 && opt.winding_dilation * opt.max_deviation < 1))
    throw InputError("--winding-dilation must be at least 0 and, times --max-deviation, below 1");
  if (!(opt.winding_surface_dilation >= 0 && opt.winding_surface_dilation * opt.max_deviation < 1))
    throw InputError("--winding-surface-dilation must be at least 0 and, times --max-deviation, below 1");
  MeshResult r;
  r.target_tets = opt.tetrahedralize.target_tets;
  StageTimer timer(r, progress);
  timer.start("analysing input");
  r.input.V = surface.V;
  const Eigen::MatrixX3i given = without_duplicate_and_flat_faces(surface.V, surface.F);
  r.input.F = orient_outward(surface.V, given);
  r.info = analyse_surface(r.input);
  r.info.self_intersecting = does_self_intersect(r.input);
  const double diag = bounding_box_diagonal(r.input.V);
  if (!(diag > 0)) throw InputError("input has zero extent (all vertices coincide)");
  // The input's winding-number volume (winding_volume: 1.7 s on the heart), computed once for
  // whichever routes ask (the winding-number boundary's route, then Mesh_3's where it falls back).
  std::optional<double> input_winding_volume_once;
  Eigen::RowVector3d input_jump_area = Eigen::RowVector3d::Zero();  // (winding_volume's, with it)
  auto input_winding_volume = [&]() {
    if (!input_winding_volume_once) input_winding_volume_once = winding_volume(r.input.V, r.input.F, &input_jump_area);
    return *input_winding_volume_once;
  };

  // The convex decomposition (the fallback's shells, every route's tetrahedron labels, the report)
  // runs beside the route's own meshing, in an arena of its own (a thread waiting in the route's
  // parallel loops takes none of its tasks, so the route's CGAL random state stays its own);
  // decomposition() waits for it. Its seconds (r.beside) are its own run's, not the wait's; the
  // task writes only r.decomposition and r.beside, which nothing else touches before the wait.
  timer.stop();
  DecompositionOptions dopt = opt.decomposition;
  if (dopt.max_hulls >= 1) dopt.max_hulls = hull_budget(opt);
  r.hull_budget = dopt.max_hulls;
  tbb::task_arena decomposing_arena;
  tbb::task_group decomposing;
  decomposing_arena.execute([&] {
    decomposing.run([&] {
      const auto t0 = std::chrono::steady_clock::now();
      r.decomposition = decomposition_made ? *decomposition_made : decompose(r.input, dopt, nullptr);
      r.beside.emplace_back("decomposing", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    });
  });
  struct Join {  // every way out of this function waits for the decomposition first
    tbb::task_arena& arena;
    tbb::task_group& group;
    ~Join() {
      try {
        arena_wait(arena, group);
      } catch (...) {  // already leaving by an exception (or a result taken without it): dropped
      }
    }
  } join{decomposing_arena, decomposing};
  auto decomposition = [&]() -> const Decomposition& {
    arena_wait(decomposing_arena, decomposing);  // at once once done; rethrows the decomposition's exception
    return r.decomposition;
  };

  // The input's face-connected components: the candidate parts, and the fallback's part count.
  Eigen::VectorXi component_of;
  const int components = face_components(r.input.F, component_of);

  // The fallback (meshing version 3): the union of the convex shells tetrahedralized with Mesh_3,
  // for the whole input, with the reason in the report.
  // A route other than the input's boundary: its method and reason, and nothing left of the
  // boundary route's figures (it may have run first).
  auto leave_boundary_route = [&](const char* method, const std::string& why, int parts) {
    r.method = method;
    r.fallback_because = why;
    r.parts = parts;
    r.boundary_from_input = false;
    r.boundary = SurfaceMesh{};
    r.envelope = EnvelopeStats{};
    r.boundary_target_faces = 0;
    r.tet_stats = TetrahedralizeStats{};
  };
  auto shells_route = [&](const std::string& why) {
    spdlog::info("meshing the convex shells instead of the input's boundary: {}", why);
    leave_boundary_route("convex_shells", why, components);
    r.input_volume_from_winding_number = !r.info.closed;
    r.input_volume = r.info.closed ? r.info.volume : decomposition().solid_volume;
    r.info.volume = r.input_volume;
    timer.start("tetrahedralizing");
    ShellTetrahedralizeOptions so = opt.shells;
    // The fallback never makes more than shells.max_tets: a larger target cannot be honoured, so it
    // aims at the cap at once (instead of attempts that overshoot it) and the report says why.
    so.target_tets = std::min(opt.tetrahedralize.target_tets, so.max_tets);
    so.seed = opt.tetrahedralize.seed;
    r.tets = tetrahedralize_shells(decomposition().shells, so, &r.shell_stats, progress, &r.input.V);
    if (r.tets.T.rows() == 0) throw InputError("tetrahedralization produced no tetrahedra");
    timer.start("measuring");
    measure(r, opt);
    const double n = r.quality.tets, target = opt.tetrahedralize.target_tets;
    if (target > so.max_tets && n < 0.65 * target)
      r.target_exceeded_because = "the convex shells' fallback (" + why + ") makes at most " +
                                  std::to_string(so.max_tets) + " tetrahedra; it landed at " + std::to_string(r.quality.tets);
    else if (n > 1.35 * target || n < 0.65 * target)
      r.target_exceeded_because = "the convex shells' Mesh_3 refinement (the fallback: " + why + ") landed at " +
                                  std::to_string(r.quality.tets) + " tetrahedra after " +
                                  std::to_string(r.shell_stats.attempts) + " attempts";
    timer.stop();
    return std::move(r);
  };

  // Label: the convex shell that holds the tetrahedron's centroid (the most interior one).
  auto label_by_shells = [&](TetMesh& m) {
    const std::vector<ConvexShell>& shells = decomposition().shells;
    m.label.resize(m.T.rows());
    for (Eigen::Index t = 0; t < m.T.rows(); ++t) {
      const Eigen::RowVector3d c =
          (m.V.row(m.T(t, 0)) + m.V.row(m.T(t, 1)) + m.V.row(m.T(t, 2)) + m.V.row(m.T(t, 3))) / 4.0;
      int arg = 0;
      double v = INFINITY;
      for (size_t s = 0; s < shells.size(); ++s) {
        const double sv = shells[s].hull.signed_value(c);
        if (sv < v) v = sv, arg = static_cast<int>(s);
      }
      m.label(t) = arg + 1;
    }
  };

  // Inputs that are not closed parts (meshing version 6): the solid their generalized winding
  // number encloses (welded or overlapping segments as their union, small holes closed), dilated a
  // little and meshed by Mesh_3 within a facet distance, both from the deviation bounds. Its parts
  // are the solid's connected parts (the decomposition's voxel components). Where Mesh_3 gives
  // nothing: the convex shells.
  auto winding_route = [&](const std::string& why) -> MeshResult {
    spdlog::info("meshing the input's winding-number solid instead of its own boundary: {}", why);
    leave_boundary_route("winding_number", why, 0);
    timer.start("tetrahedralizing");
    r.input_volume_from_winding_number = true;
    r.input_volume = input_winding_volume();
    r.info.volume = r.input_volume;
    WindingTetrahedralizeOptions wo = opt.winding_mesh;
    wo.target_tets = opt.tetrahedralize.target_tets;
    wo.seed = opt.tetrahedralize.seed;
    wo.facet_distance = opt.winding_facet_distance * opt.max_deviation;
    wo.dilation = opt.winding_dilation * opt.max_deviation;
    r.tets = tetrahedralize_winding_number(r.input.V, r.input.F, r.input_volume, wo, &r.winding_stats, progress);
    if (r.tets.T.rows() == 0) return shells_route(why + "; Mesh_3 of its winding-number solid produced no tetrahedra");
    r.parts = decomposition().parts;
    r.tet_stats.attempts = r.winding_stats.attempts;
    r.tet_stats.edge_length = r.winding_stats.cell_size;
    r.tet_stats.peeled = r.winding_stats.peeled_slivers;
    r.tet_stats.conforming = true;  // a subcomplex of one Delaunay triangulation
    label_by_shells(r.tets);
    timer.start("measuring");
    measure(r, opt);
    const double n = r.quality.tets, target = opt.tetrahedralize.target_tets;
    if (n > 1.35 * target)
      r.target_exceeded_because = "keeping the boundary's facets within " + percent(wo.facet_distance) +
                                  " of the bounding-box diagonal of the input's winding-number solid (dilated by " +
                                  percent(wo.dilation) + ", so that they stay within " +
                                  percent(opt.inner_deviation * opt.max_deviation) + " of the input) takes " +
                                  std::to_string(r.quality.tets) + " tetrahedra";
    else if (n < 0.65 * target)
      r.target_exceeded_because = "Mesh_3's refinement of the winding-number solid landed at " +
                                  std::to_string(r.quality.tets) + " tetrahedra after " +
                                  std::to_string(r.winding_stats.attempts) + " attempts";
    timer.stop();
    return std::move(r);
  };

  // The envelope's bounds (fractions of the whole input's diagonal).
  EnvelopeOptions eopt;
  eopt.max_outside = opt.max_deviation * diag;
  eopt.max_inside = opt.inner_deviation * opt.max_deviation * diag;

  // A part's boundary simplified within `bounds`: against the input where the part is its
  // winding-number solid's boundary, else against its own surface.
  auto simplify = [](const Part& p, const EnvelopeOptions& bounds, EnvelopeStats* stats, Progress* pr) {
    return p.target ? simplify_envelope(p.surface, *p.target, bounds, stats, pr)
                    : simplify_envelope(p.surface, bounds, stats, pr);
  };

  // The boundary route: each part's boundary simplified within `bounds`, then
  // tetrahedralized; the parts concatenated, labelled and measured against the input. `fail` is
  // taken, with the reason, where a part cannot be meshed. `wrapped`: the parts are components of
  // the input's alpha wrap (then r.input_volume is the caller's).
  auto boundary_route = [&](std::vector<Part>& parts, const EnvelopeOptions& bounds, bool wrapped,
                            const std::function<MeshResult(const std::string&)>& fail) -> MeshResult {
    // Each part gets the share of target_tets its volume has; its boundary as many faces as a mesh
    // of that many tetrahedra has (edge length from the volume: a regular tetrahedron of edge L has
    // volume L³/(6√2), Delaunay meshes average about half), fewer where the deviation bounds allow
    // nothing coarser. The bounds are fractions of the whole input's diagonal.
    double total_volume = 0;
    for (const Part& p : parts) total_volume += p.volume;
    const double target = opt.tetrahedralize.target_tets;
    const double L = std::cbrt(6.0 * std::sqrt(2.0) * total_volume / (0.5 * target));
    timer.start("tetrahedralizing");  // (simplifying each part's boundary, then tetrahedralizing it)
    // An open sheet: remeshed to near-equilateral triangles, then one layer of prisms, three
    // tetrahedra each, between the two sides of its slab (sheet_tets). The edge length gives the
    // part its share of the target (3 tetrahedra per triangle of area 0.433 L²), at most 5 times
    // the slab's thickness (an equilateral prism that wide splits into tetrahedra of 12.9° and more;
    // the floor is 5°), shortened while the remeshed sheet strays from the input by more than 0.4
    // of the thickness (so that the input stays inside the slab, and the slab within
    // max_deviation of the input). False where the slab folds over itself at every length tried: the
    // slab then takes the boundary route like any part.
    // One layer of prisms over the sheet s (made by make(s, m, slab): sheet_tets) with no tetrahedron
    // under the floor: each round's prisms checked by `accept` (when given; false gives up), their
    // sliver vertices moved and slivers flipped as the boundary route's are, then, where some are
    // left, the sheet mended there and the prisms made again. Mended by `relax` (when given: an open
    // sheet smoothed around those faces; false where it then strays from the input) for
    // kSmoothRounds rounds, then by that and splitting the faces (split_sheet_faces; `split` told
    // the vertex count before, for per-vertex data), up to `rounds` rounds in all, none where over
    // max_bad of the faces hold slivers (no few mends will do). Graded sheets, equal triangles and
    // thin parts' mid-surfaces alike (meshing version 16; before, graded sheets and thin parts had a
    // loop each, of three splits, and equal triangles none).
    enum class Layer { kClean, kSlivers, kFolded, kRefused };
    struct PrismLayer {
      TetMesh m;
      SurfaceMesh slab;
      int relocated = 0, flips = 0;  // sliver vertices moved, slivers flipped
      int dropped = 0;               // slivers and the specks they held dropped (drop_fraction)
    };
    // A layer kept as the part's mesh: edge length len, `triangles` the triangles its share of the
    // target would have had.
    auto keep_prisms = [](Part& p, PrismLayer& layer, int attempts, double len, double triangles) {
      layer.slab.V = layer.m.V;
      p.boundary = std::move(layer.slab);
      p.tets = std::move(layer.m);
      p.tet_stats = TetrahedralizeStats{};
      p.tet_stats.relocated = layer.relocated;
      p.tet_stats.flips = layer.flips;
      p.tet_stats.peeled = layer.dropped;  // (the report's tets.peeled_slivers)
      p.tet_stats.attempts = attempts;
      p.tet_stats.edge_length = len;
      p.tet_stats.conforming = true;
      p.target_faces = 2 * static_cast<int>(std::lround(triangles));
    };
    // (Splitting converges where a long edge lies over a thinned slab, in one to three rounds. On
    // an elephant scanned with holes it does not: where its sheet folds sharply, prisms invert and
    // their offsets are halved to a thirty-second (sheet_tets), and six rounds of splits left 21,
    // 12, 1, 2, 10, 4, then 14 faces over slivers. Smoothing the fold first (21, 5, 1, 2, then
    // none with splits from the fourth round) kept the slab of all four elephants with holes.)
    constexpr int kSmoothRounds = 3;
    using MakePrisms = std::function<bool(const SurfaceMesh&, TetMesh&, SurfaceMesh&, std::vector<int>*)>;
    auto prisms_without_slivers = [&](SurfaceMesh& s, const MakePrisms& make,
                                      const std::function<bool(const SurfaceMesh&)>& accept,
                                      const std::function<bool(SurfaceMesh&, const std::vector<int>&)>& relax,
                                      const std::function<void(Eigen::Index)>& split, int rounds, double max_bad,
                                      double drop_fraction, const std::string& what, PrismLayer& layer) {
      const double floor = opt.tetrahedralize.min_dihedral;
      for (int round = 0;; ++round) {
        layer = PrismLayer{};
        std::vector<int> inverted;
        if (!make(s, layer.m, layer.slab, &inverted)) {
          // (Folded: prisms that stay inverted however thin; the sheet smoothed there, when it may be.)
          spdlog::debug("{}: prisms over {} faces invert{}", what, inverted.size(), relax && round < rounds ? ": smoothed" : "");
          if (!relax || inverted.empty() || round == rounds || !relax(s, inverted)) return Layer::kFolded;
          continue;
        }
        if (accept && !accept(layer.slab)) return Layer::kRefused;
        layer.relocated = relocate_sliver_vertices(layer.m, floor);
        layer.flips = flip_slivers(layer.m, floor);
        const std::vector<int> bad = sliver_faces(s, layer.m, floor);
        if (bad.empty()) return Layer::kClean;
        // Slivers over a few faces only (at most drop_fraction of them: a spike's tip, a fold that
        // splitting and smoothing do not mend): those tetrahedra dropped, and the specks that only
        // they held to the rest; kept where every vertex of the sheet left on no tetrahedron lies
        // within the inner bound of the rest, so that the holes are no wider (meshing version 32;
        // the caller measures the deviations). A dragon scanned with holes: 1,111 of 19,021 faces
        // over slivers, 168 and 73 after two rounds of mends; the splits of further rounds left more.
        // Up to four faces on any sheet (a fragment of a scan with holes cut, 59 faces: slivers over
        // 4, then 9 after a smoothing; meshing version 34).
        auto dropped_clean = [&] {
          const double allowed = std::max(drop_fraction * static_cast<double>(s.F.rows()), 4.0);
          if (!(drop_fraction > 0 && static_cast<double>(bad.size()) <= allowed)) return false;
          TetMesh m = layer.m;
          const int dropped = drop_slivers(m, floor) + drop_debris_components(m, 1e-3);
          const Eigen::Index nv = s.V.rows();
          std::vector<char> used(static_cast<size_t>(m.V.rows()), 0);
          for (Eigen::Index t = 0; t < m.T.rows(); ++t)
            for (int k = 0; k < 4; ++k) used[static_cast<size_t>(m.T(t, k))] = 1;
          bool held = m.V.rows() == 2 * nv && m.T.rows() > 0;
          if (held) {
            const Eigen::MatrixX3i rest = boundary_faces(m.T);
            const TriangleBvh near(m.V, rest);
            for (Eigen::Index v = 0; held && v < nv; ++v)
              held = used[static_cast<size_t>(v)] || used[static_cast<size_t>(nv + v)] ||
                     near.nearest(s.V.row(v).transpose()) <= eopt.max_inside;
          }
          const double worst = held ? tet_quality(m).min_dihedral : 0.0;
          spdlog::debug("{}: prisms over {} of {} faces leave tetrahedra under {}°: {} tetrahedra dropped, {}", what, bad.size(),
                        s.F.rows(), floor, dropped,
                        !held ? "a vertex of the sheet left beyond the inner bound: not kept"
                              : worst >= floor ? "kept" : fmt::format("{:.3g}° left: not kept", worst));
          if (!(held && worst >= floor)) return false;
          remove_unused_vertices(m);
          layer.slab.V = m.V;
          layer.slab.F = boundary_faces(m.T);
          layer.m = std::move(m);
          layer.dropped = dropped;
          return true;
        };
        const bool last = round == rounds || static_cast<double>(bad.size()) > max_bad * static_cast<double>(s.F.rows());
        if (dropped_clean()) return Layer::kClean;
        const bool splits = !relax || round >= kSmoothRounds;
        spdlog::debug("{}: prisms over {} of {} faces leave tetrahedra under {}°{}", what, bad.size(), s.F.rows(), floor,
                      last ? "" : relax ? (splits ? ": smoothed and split" : ": smoothed") : ": split");
        if (last) return Layer::kSlivers;
        if (relax && !relax(s, bad)) return Layer::kSlivers;
        if (splits) {
          const Eigen::Index old = s.V.rows();
          split_sheet_faces(s, bad);  // (midpoints on the faces: projecting them onto the input can cross a thin part)
          if (split) split(old);
        }
      }
    };
    auto mesh_sheet = [&](Part& p) {
      const double h = p.offset;
      const int share = std::max(1, static_cast<int>(std::lround(target * p.volume / total_volume)));
      const double wanted = std::sqrt(3.0 * area(p.sheet) / (0.433 * share));
      const double longest = std::min(wanted, 10.0 * h);
      double Ls = longest;
      const TriangleBvh input(p.sheet.V, p.sheet.F);
      const double fine = 1e-3 * bounding_box_diagonal(p.sheet.V);
      // How far a sheet s strays from the input, either way (sampled 0.25 len apart).
      auto apart_from_input = [&](const SurfaceMesh& s, double len) {
        const TriangleBvh other(s.V, s.F);
        const double spacing = std::max(0.25 * len, fine);
        return std::max(farthest_sample(s.V, s.F, input, spacing), farthest_sample(p.sheet.V, p.sheet.F, other, spacing));
      };
      // The sheet s coarsened where it is flat, within the bound, no edge longer than `longest`
      // (simplify_sheet, meshing version 15), in c: whether it holds the bound.
      auto graded = [&](const SurfaceMesh& s, SurfaceMesh& c) {
        EnvelopeOptions g;
        g.max_outside = g.max_inside = 0.55 * h;  // its samples are sparser than apart_from_input's
        g.max_edge = longest;
        g.min_triangle_angle = 25.0;  // prisms over rounder triangles, and normals that turn little
        g.min_fold_angle = 140.0;     // from face to face (each vertex's normal within its prisms)
        g.max_normal_turn = 30.0;
        g.target_faces = std::max(4, share / 3);
        g.short_edge = 0;
        c = simplify_sheet(s, p.sheet, g);
        const double apart = apart_from_input(c, longest);
        spdlog::debug("sheet (component {}): graded from {} to {} triangles, {:.3g} from the input{}", p.component, s.F.rows(),
                      c.F.rows(), apart, apart <= 0.8 * h ? "" : ": too far");
        return apart <= 0.8 * h;
      };
      auto make = [&](const SurfaceMesh& s, TetMesh& m, SurfaceMesh& slab, std::vector<int>* inverted) {
        return sheet_tets(s, h, m, &slab, inverted);
      };
      // Smoothed around faces over slivers, kept where it stays within the bound of the input.
      auto relax = [&](SurfaceMesh& s, const std::vector<int>& bad) {
        smooth_sheet_faces(s, bad, 0.2 * h);  // (0.1: 32,136 tetrahedra on the elephant, equal triangles; 0.2-0.35: 16,200, graded)
        const double far = apart_from_input(s, longest);
        if (!(far <= 0.9 * h)) spdlog::debug("sheet (component {}): smoothed, {:.3g} from the input: not kept", p.component, far);
        return far <= 0.9 * h;
      };
      const std::string what = "sheet (component " + std::to_string(p.component) + ")";
      // Kept in p: edge length len.
      auto adopt = [&](PrismLayer& layer, double len, int attempt) {
        p.sheet_capped = len < wanted;
        keep_prisms(p, layer, attempt, len, area(p.sheet) / (0.433 * wanted * wanted));
      };
      double apart = 0;
      // Remeshing far finer than the input's own triangles adds nothing it holds: where a retry's
      // shorter length (the sheet was too far from the input) falls below their median edge and
      // the remeshed sheet would have over four times their count, the input's triangles
      // themselves are the last try (a crumpled sheet of 3,200 triangles, 2 cm of noise on a
      // 2.5 cm grid, was remeshed to 78,000 triangles at 7.7 mm: 233,773 tetrahedra, 0.35°, 38 s;
      // meshing version 19). (Somewhat finer, an isotropic remesh makes better prisms than a
      // scan's own triangles: the elephant with holes of 2 %, 17,693 triangles against its 5,452,
      // is a slab within the bounds, its own triangles not. A flat curtain of two triangles is
      // remeshed at the target's length on the first try, never by its own two.)
      const double own_edge = median_edge_length(p.sheet);
      for (int attempt = 1; attempt <= 6; ++attempt) {
        // After an attempt too far from the input: the chords' sag goes as the square of their
        // length, so the length that should just meet the bound, and a tenth less.
        if (attempt > 1) Ls *= std::clamp(0.9 * std::sqrt(0.8 * h / apart), 0.3, 0.9);
        const bool own = attempt > 1 && Ls < own_edge && area(p.sheet) / (0.433 * Ls * Ls) > 4.0 * static_cast<double>(p.sheet.F.rows());
        if (own) Ls = own_edge;
        // (An open scan's slab is not worth more than 200,000 remeshed triangles: its solid is kept.)
        if (p.scan && area(p.sheet) / (0.433 * Ls * Ls) > 2e5) break;
        // (Its own triangles wider than a prism may be, a few large polygons creased between them,
        // are split to that width: the sheet stays the input, creases and all; meshing version 33.)
        SurfaceMesh s = own ? split_long_edges(p.sheet, longest) : remesh_sheet(p.sheet, Ls);
        if (s.F.rows() == 0) {
          apart = 0.8 * h / 0.49;
          continue;
        }
        apart = own ? 0.0 : apart_from_input(s, Ls);
        spdlog::debug("sheet (component {}): edge length {:.4g}{}, {} triangles, {:.3g} from the input (bound {:.3g})", p.component,
                      Ls, own ? " (its own triangles)" : "", s.F.rows(), apart, 0.8 * h);
        if (!(apart <= 0.8 * h)) continue;
        // Shorter than wanted where the sheet curves: then coarsened where it does not (a scan's
        // flat back next to its ears), kept where its prisms leave no sliver (a long edge over the
        // slab thinned where the sheet curves leaves some: split while under 1 % of the faces).
        PrismLayer layer;
        SurfaceMesh c;
        // (Sixteen rounds while under a tenth of the faces hold slivers, where the last few may be
        // dropped: the dragon with holes went from 1,111 of 19,021 faces to 168, then 73, dropped.
        // Eight rounds and a hundredth without, as version 31.)
        const int mends = opt.sheet_sliver_drop > 0 ? 16 : 8;
        const double mend_bad = opt.sheet_sliver_drop > 0 ? 0.1 : 0.01;
        if (Ls < 0.99 * longest && graded(s, c) &&
            prisms_without_slivers(c, make, nullptr, relax, nullptr, mends, mend_bad, opt.sheet_sliver_drop, what + ", graded", layer) == Layer::kClean) {
          adopt(layer, Ls, attempt);
          return true;
        }
        // An open scan's slab of over 20,000 equal triangles (60,000 tetrahedra for a model of a
        // few hundred) is no model of it: its solid is kept.
        if (p.scan && s.F.rows() > 20000)
          throw InputError("the open scan's slab holds the bounds only with " + std::to_string(s.F.rows()) +
                           " equal triangles, and graded it leaves slivers");
        // Equal triangles: kept with what slivers are left (the report's dihedral says so).
        const Layer got = prisms_without_slivers(s, make, nullptr, relax, nullptr, mends, mend_bad, opt.sheet_sliver_drop, what, layer);
        if (got == Layer::kFolded) {
          if (own) break;  // (no finer try)
          apart = 0.8 * h / 0.49;  // folded: the next attempt 0.63 times as long
          continue;
        }
        adopt(layer, Ls, attempt);
        return true;
      }
      if (p.scan) throw InputError("the open scan's slab folds over itself at every edge length tried");
      spdlog::debug("sheet (component {}): its slab folds over itself; meshing it by the boundary route", p.component);
      return false;
    };
    // A closed part much thinner than its tetrahedra would be long (a 2 mm plate a metre wide, a
    // bowl 1 mm thick): Delaunay refinement between two sides so close meets slivers at every
    // scale (the plate: 9,199 boundary splits in 116 s, then 8 % of its volume). Where over 80 % of
    // its area faces an opposite side (the inward ray from a face's centre meets a face turned the
    // other way within L) and L is over 6 times its mean thickness there, it is meshed as the slab
    // of its mid-surface: one side (the faces reached from the largest such face across edges
    // turning under 100°) remeshed, each vertex moved half the local thickness inward, one layer of
    // prisms as thick as the part there (sheet_tets with a half thickness per vertex; meshing
    // version 15). Kept where its slab and the part's surface lie within the bounds of each other.
    // (A side turns by up to 100° across an edge: a bent sheet-metal bracket; the other side, turned
    // the other way, and the rim, which faces no other side, stay apart.)
    // `ratio`: how many times its mean thickness L must be (6; 3 where the boundary route has failed).
    // `*below_ratio` (when given): set where that alone stopped it (only then can a smaller ratio
    // give another answer: the rest is the same work on the same part).
    auto mesh_thin_part = [&](Part& p, const EnvelopeOptions& e, double ratio, bool* below_ratio) {
      if (!opt.thin_parts_as_prisms || p.target || p.offset > 0 || p.sheet.F.rows() > 0 || p.surface.F.rows() < 4)
        return false;
      const SurfaceMesh& S = p.surface;
      const Eigen::Index nf = S.F.rows();
      Eigen::MatrixX3d FN, VN;
      area_weighted_normals(S.V, S.F, FN, VN);
      const TriangleBvh bvh(S.V, S.F);
      std::vector<double> thick(static_cast<size_t>(nf), -1.0), face_area(static_cast<size_t>(nf), 0.0);
      std::vector<double> reach(static_cast<size_t>(nf), -1.0);  // to the first face inward, whichever way it faces
      tbb::parallel_for(Eigen::Index(0), nf, [&](Eigen::Index f) {
        const double len = FN.row(f).norm();
        face_area[static_cast<size_t>(f)] = 0.5 * len;
        if (!(len > 0)) return;
        const Eigen::Vector3d n = FN.row(f).transpose() / len;
        const Eigen::Vector3d c = (S.V.row(S.F(f, 0)) + S.V.row(S.F(f, 1)) + S.V.row(S.F(f, 2))).transpose() / 3.0;
        double t;
        if (!bvh.first_crossing(c, c - L * n, 1e-6, &t)) return;
        reach[static_cast<size_t>(f)] = t * L;
        int g = -1;
        bvh.nearest(c - t * L * n, &g);
        if (g >= 0 && FN.row(g).norm() > 0 && FN.row(g).normalized().dot(n.transpose()) < -0.8)
          thick[static_cast<size_t>(f)] = t * L;
      });
      double total = 0, paired = 0, thickness = 0;
      for (Eigen::Index f = 0; f < nf; ++f) {
        total += face_area[static_cast<size_t>(f)];
        if (thick[static_cast<size_t>(f)] > 0)
          paired += face_area[static_cast<size_t>(f)], thickness += face_area[static_cast<size_t>(f)] * thick[static_cast<size_t>(f)];
      }
      if (!(paired >= 0.8 * total) || !(paired > 0)) return false;
      thickness /= paired;
      if (!(L > ratio * thickness)) {
        if (below_ratio) *below_ratio = true;
        return false;
      }
      // One side: flood from the largest paired face across edges to paired faces turning < 60°,
      // faces paired across more than three times the mean thickness left out (the walls of a
      // perforated plate's holes face the plate's rim or the next hole a few centimetres away:
      // through them the flood went from the top of a 3 mm plate to its bottom, and the plate took
      // the boundary route, its exuder 30 s on slivers between the sides; meshing version 19).
      auto side_face = [&](Eigen::Index g) {
        const double t = thick[static_cast<size_t>(g)];
        return t > 0 && t <= 3.0 * thickness;
      };
      // A face beside the side, turned less than 25° from it (`turn`: the cosine; a rim is turned
      // further), over a bevel (the other side meets it at an angle: facing it by less than the
      // pairing's 143°) within three times the thickness is the side's too (meshing version 20): a
      // roof 4 % of its diagonal thick, whose far end tapers at 38°, kept those faces out of its
      // side, and the slab left them 0.8 % of the diagonal out.
      auto beside_side = [&](Eigen::Index g, double turn) {
        const double t = reach[static_cast<size_t>(g)];
        return t > 0 && t <= 3.0 * thickness && turn > 0.9;
      };
      std::map<std::pair<int, int>, std::vector<int>> edge_faces;
      for (Eigen::Index f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) {
          const int a = S.F(f, k), b = S.F(f, (k + 1) % 3);
          edge_faces[{std::min(a, b), std::max(a, b)}].push_back(static_cast<int>(f));
        }
      int seed = -1;
      for (Eigen::Index f = 0; f < nf; ++f)
        if (side_face(f) && (seed < 0 || face_area[static_cast<size_t>(f)] > face_area[static_cast<size_t>(seed)]))
          seed = static_cast<int>(f);
      std::vector<char> side(static_cast<size_t>(nf), 0);
      std::vector<int> stack{seed}, faces;
      side[static_cast<size_t>(seed)] = 1;
      double side_area = 0;
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        faces.push_back(f);
        side_area += face_area[static_cast<size_t>(f)];
        for (int k = 0; k < 3; ++k) {
          const int a = S.F(f, k), b = S.F(f, (k + 1) % 3);
          for (int g : edge_faces[{std::min(a, b), std::max(a, b)}]) {
            if (side[static_cast<size_t>(g)]) continue;
            const double turn = FN.row(g).normalized().dot(FN.row(f).normalized());
            if ((side_face(g) && turn > -0.2) || beside_side(g, turn)) {
              side[static_cast<size_t>(g)] = 1;
              stack.push_back(g);
            }
          }
        }
      }
      if (!(side_area >= 0.35 * total && side_area <= 0.65 * total)) {
        spdlog::debug("part: thin ({:.3g} thick against tetrahedra {:.3g} long) but its sides are not two ({:.0f} % of its "
                      "area on one)", thickness, L, 100 * side_area / total);
        return false;
      }
      std::sort(faces.begin(), faces.end());
      const SurfaceMesh one = sub_mesh(S, faces);
      // The side is open (a plate, a bowl) or closed: a hollow part's outer surface, its cavity the
      // other side (a box 0.3 m across with a 3 mm wall; meshing version 24: before, such parts took
      // the boundary route, whose refinement lost the walls 3 mm apart: 46 tetrahedra, 2.8 % of
      // the volume at 150). A closed mid-surface's slab is two closed surfaces, no rim.
      if (const SheetEvidence ev = sheet_evidence(one.V, one.F); !ev.open_manifold && !ev.closed_manifold) return false;
      const int share = std::max(1, static_cast<int>(std::lround(target * p.volume / total_volume)));
      const double wanted = std::sqrt(3.0 * area(one) / (0.433 * share));
      const double longest = std::min(wanted, 8.0 * thickness);  // (5: 9-10°, and 2.4 times the tetrahedra; 10: 5.0°)
      // The slab at edge length Ls: Layer::kClean where it holds (kept), kRefused where it lies off
      // the bounds.
      auto slab_at = [&](const double Ls) {
        // Its outline and creases kept within a quarter of the inner bound (remesh_sheet's
        // max_border_sag): a bottle's rim 3 cm across, remeshed at 12 mm, was an octagon whose
        // chords lay 1.9 mm inside it, and its 32° shoulder was cut by 1.7 mm (the bound: 1.2 mm).
        // Meshing version 24.
        SurfaceMesh mid = remesh_sheet(one, Ls, 3, 0.25 * e.max_inside);
        if (mid.F.rows() == 0) return Layer::kFolded;
        // Each vertex: half way to the other side along its normal (the remeshed side's, outward).
        Eigen::MatrixX3d MN;
        angle_weighted_normals(mid.V, mid.F, MN);  // (on a crease, the bisector: toward the inner corner)
        // (A ray along the outline can graze the rim and meet nothing: such a vertex takes the mean
        // of its neighbours' that met the other side.)
        std::vector<double> half(static_cast<size_t>(mid.V.rows()), 0.0);
        std::atomic<int> lost{0};
        for (Eigen::Index v = 0; v < mid.V.rows(); ++v)
          if (!(MN.row(v).norm() > 0)) return Layer::kFolded;
        tbb::parallel_for(Eigen::Index(0), mid.V.rows(), [&](Eigen::Index v) {
          double t;
          const Eigen::Vector3d x = mid.V.row(v).transpose(), n = MN.row(v).normalized().transpose();
          if (bvh.first_crossing(x, x - 3.0 * thickness * n, 1e-4, &t)) half[static_cast<size_t>(v)] = 0.5 * t * 3.0 * thickness;
          else ++lost;
        });
        if (lost > 0) {
          std::vector<double> sum(half.size(), 0.0);
          std::vector<int> count(half.size(), 0);
          for (Eigen::Index f = 0; f < mid.F.rows(); ++f)
            for (int k = 0; k < 3; ++k)
              for (int j = 1; j < 3; ++j) {
                const size_t a = static_cast<size_t>(mid.F(f, k)), b = static_cast<size_t>(mid.F(f, (k + j) % 3));
                if (half[b] > 0) sum[a] += half[b], ++count[a];
              }
          for (size_t v = 0; v < half.size(); ++v)
            if (!(half[v] > 0)) half[v] = count[v] > 0 ? sum[v] / count[v] : 0.5 * thickness;
        }
        for (Eigen::Index v = 0; v < mid.V.rows(); ++v) mid.V.row(v) -= half[static_cast<size_t>(v)] * MN.row(v).normalized();
        // The slab no thinner than a prism Ls wide can be without a tetrahedron under the floor (an
        // eighth of its width: Ls / 16 each way), where the part tapers to an edge (the roof's 38°
        // bevel: prisms of no height there, slivers that no split mended; meshing version 20). It
        // then stands out of the part there by up to that, which accept() checks against the bound.
        const double thinnest = std::min(Ls / 16.0, 0.25 * thickness);
        for (double& h : half) h = std::max(h, thinnest);
        // Vertices added by splits: half way between the sides along their normal (rays both ways).
        auto between_sides = [&](Eigen::Index from) {
          Eigen::MatrixX3d N2;
          angle_weighted_normals(mid.V, mid.F, N2);
          half.resize(static_cast<size_t>(mid.V.rows()), 0.0);
          for (Eigen::Index v = from; v < mid.V.rows(); ++v) {
            const Eigen::Vector3d x = mid.V.row(v).transpose(), n = N2.row(v).normalized().transpose();
            double t1, t2;
            const double reach = 3.0 * thickness;
            if (N2.row(v).norm() > 0 && bvh.first_crossing(x, x + reach * n, 1e-6, &t1) &&
                bvh.first_crossing(x, x - reach * n, 1e-6, &t2)) {
              half[static_cast<size_t>(v)] = std::max(thinnest, 0.5 * reach * (t1 + t2));
              mid.V.row(v) = (x + 0.5 * reach * (t1 - t2) * n).transpose();
            } else {
              half[static_cast<size_t>(v)] = 0.5 * thickness;
            }
          }
        };
        // Prisms as thick as the part, kept where the slab and the part's surface lie within the bounds
        // of each other; faces over slivers (at the outline, where the thickness is its neighbours')
        // split, their new vertices put between the sides.
        auto accept = [&](const SurfaceMesh& slab) {
          const double spacing = std::max(0.25 * Ls, 1e-3 * bounding_box_diagonal(S.V));
          const auto [out, in] = farthest_both_ways(slab.V, slab.F, S, bvh, spacing);
          spdlog::debug("part: thin ({:.3g} thick, tetrahedra {:.3g} long): mid-surface of {} triangles, slab {:.3g} / {:.3g} "
                        "from its surface (bounds {:.3g} / {:.3g})",
                        thickness, L, mid.F.rows(), out, in, e.max_outside, e.max_inside);
          return out <= e.max_outside && in <= e.max_inside;
        };
        // Up to six rounds of splits (three before version 23: a knife whose edge is 1.1° sharp
        // still had 2 of its 685 faces over slivers after three, none after four).
        PrismLayer layer;
        const Layer result = prisms_without_slivers(
            mid, [&](const SurfaceMesh& s, TetMesh& m, SurfaceMesh& slab, std::vector<int>*) { return sheet_tets(s, half, m, &slab); },
            accept, nullptr, between_sides, 6, 1.0, 0.0, "part: thin", layer);
        if (result != Layer::kClean) return result;
        p.thin = thickness;
        keep_prisms(p, layer, 1, Ls, area(one) / (0.433 * wanted * wanted));
        return Layer::kClean;
      };
      // A slab off the bounds (its triangles' chords cut curves: a bottle's neck 30 mm across at
      // 12 mm edges, 1.7 mm inside its wall) is made again at 0.6 and 0.36 of the length, while
      // the mid-surface stays under 20,000 triangles (meshing version 24).
      double Ls = longest;
      for (int attempt = 0; attempt < 3; ++attempt, Ls *= 0.6) {
        if (attempt > 0 && area(one) / (0.433 * Ls * Ls) > 20000) break;
        const Layer result = slab_at(Ls);
        if (result == Layer::kClean) return true;
        if (result != Layer::kRefused) break;
      }
      return false;
    };
    // Once a part has failed, the whole input takes `fail`: the other parts' work is skipped.
    std::atomic<bool> abandoned{false};
    auto mesh_parts = [&](std::vector<Part>& ps, size_t first) {
      const bool progress_here = ps.size() == 1;
      tbb::parallel_for(first, ps.size(), size_t(1), [&](size_t i) {
        // Isolated: a thread waiting inside one part's work (CGAL, TBB loops) takes no other part's
        // work, so each part runs start to end on one thread with its own CGAL random state.
        tbb::this_task_arena::isolate([&] {
          Part& p = ps[i];
          if (abandoned) return;
          if (p.sheet.F.rows() > 0) {
            if (mesh_sheet(p)) return;
            p.check = does_self_intersect(p.surface);  // its slab, on the boundary route after all
          }
          bool stopped_at_ratio = false;  // (mesh_thin_part's ratio alone stopped it)
          if (mesh_thin_part(p, bounds, 6.0, &stopped_at_ratio)) return;
          EnvelopeOptions e = bounds;
          // A winding-number solid's boundary (Mesh_3's facets: angles of 25° and more, creases
          // where the dilation meets the solid) keeps its triangles that round and its folds no
          // sharper than 45°: with the defaults (5°, 20°) the simplified left lung (500 faces, 15
          // triangles under 10°) and heart were not tetrahedralized conforming, and the retries
          // gave 5,000 and 17,500 tetrahedra (docs/meshing.md, version 11).
          if (p.target) {
            e.min_triangle_angle = std::max(e.min_triangle_angle, 25.0);
            e.min_fold_angle = std::max(e.min_fold_angle, 45.0);
          }
          if (p.offset > 0) {
            e.max_outside = std::max(0.25 * e.max_outside, e.max_outside - p.offset);
            e.max_inside = std::min(e.max_inside, 0.5 * p.offset);
          }
          // A surface made mostly of long, thin triangles (a faceted rod) has a rounder version
          // (skinny_split_length): used where its own is too much work to refine or does not hold.
          const double skinny = opt.split_skinny && !p.target && p.offset == 0 ? skinny_split_length(p.surface) : 0.0;
          if (skinny > 0) spdlog::debug("part {}: mostly skinny triangles: their split length {:.4g}", i, skinny);
          // The part's area, and the spacing of the samples its retries' boundaries are measured
          // against its surface by (p.surface stays as it is below).
          const double part_area = area(p.surface);
          const double part_spacing = deviation_spacing(bounding_box_diagonal(p.surface.V), {part_area});
          e.target_faces = std::max(8, static_cast<int>(std::lround(part_area / (0.433 * L * L))));
          p.target_faces = e.target_faces;
          // The most faces a retry tetrahedralizes that are not the simplification's own choice
          // (retry 2's own surface, the skinny retry's split boundary).
          const int max_retry_faces = std::max(4000, 8 * e.target_faces);
          // A boundary still of mostly skinny triangles and over max_retry_faces (its simplification
          // could not coarsen it: a tube of 12 rings and 300 sides, triangles 0.04 mm by 0.11 m,
          // each collapse along a ring leaving one of them thinner, kept all 7,200 faces) is not
          // tetrahedralized, by any attempt (meshing version 29): conformity recovery split that
          // tube for 496 s, to 407,308 tetrahedra that did not hold. The skinny split and retry 0
          // (a remesh into round triangles) below are its routes.
          auto too_skinny = [&](const SurfaceMesh& b) {
            return skinny > 0 && b.F.rows() > max_retry_faces && skinny_split_length(b) > 0;
          };
          p.boundary = simplify(p, e, &p.envelope, progress_here ? progress : nullptr);
          if (spdlog::should_log(spdlog::level::debug))
            spdlog::debug("part {}: simplified boundary of {} faces intersects itself: {}", i, p.boundary.F.rows(),
                          does_self_intersect(p.boundary));
          if (p.check && does_self_intersect(p.boundary)) {
            p.failed = true;
            abandoned = true;
            return;
          }
          if (abandoned) return;
          TetrahedralizeOptions t = opt.tetrahedralize;
          t.target_tets = std::max(1, static_cast<int>(std::lround(target * p.volume / total_volume)));
          t.max_tets = std::max(1000, static_cast<int>(std::lround(opt.tetrahedralize.max_tets * p.volume / total_volume)));
          // Peeling a boundary sliver moves the boundary inward by its height: on the input's own
          // boundary by at most the inner bound (the lumbar spine at 150 had a 4.1° sliver 2 % of
          // the diagonal thick); the alpha wrap lies outside the input by its offset, and peeling
          // its slivers (up to 5 % thick on the welded boxes) moved it toward the input, so no limit.
          if (!wrapped || p.target || p.beside_solid) t.peel_max_height = std::min(t.peel_max_height, e.max_inside);
          if (p.offset > 0) t.exude = false;  // a sheet's slab (TetrahedralizeOptions::exude)
          if (skinny > 0) t.max_refine_work = opt.skinny_refine_work;
          Progress* pr = progress_here ? progress : nullptr;
          // A part is one connected surface, so its mesh is one piece: tetrahedra hanging on by an
          // edge or a vertex (a boundary not recovered, its cells classified by the winding number;
          // or left beside the slivers peeled at a sharp tip) are dropped, each piece under 0.5 %
          // of the part's volume. Before an attempt is judged, so that such debris alone does not
          // send the part to the retries (a 64-sided cone at 300: 11 tetrahedra at its tip cost
          // two retries, 10 s, for the same mesh).
          auto tetrahedralize_part = [&](const SurfaceMesh& b, TetrahedralizeStats* st, int max_tets, int attempts) {
            if (too_skinny(b)) {
              spdlog::debug("part {}: a boundary of {} faces, mostly skinny triangles: not tetrahedralized", i, b.F.rows());
              *st = TetrahedralizeStats{};
              st->conforming = false;
              return TetMesh{};
            }
            TetrahedralizeOptions tb = t;
            tb.max_tets = std::min(tb.max_tets, max_tets);
            tb.max_attempts = std::min(tb.max_attempts, attempts);
            TetMesh m = tetrahedralize(b, tb, st, pr);
            p.exuder_nan_stops += st->exuder_nan_stops;
            p.exuder_pump_bounds += st->exuder_pump_bounds;
            if (const int debris = drop_debris_components(m, 0.005); debris > 0) {
              remove_unused_vertices(m);
              spdlog::debug("part {}: {} tetrahedra in pieces under 0.5 % of its volume dropped", i, debris);
            }
            return m;
          };
          p.tets = tetrahedralize_part(p.boundary, &p.tet_stats, t.max_tets, t.max_attempts);
          const SurfaceMesh first_boundary = p.boundary;  // (retry 4's)
          const EnvelopeStats first_envelope = p.envelope;
          t.max_refine_work = 0;  // the bound is the first boundary's only (the retries below have their own)
          // A boundary whose tetrahedralization is not conforming or keeps a dihedral angle below the
          // floor (the simplification brought two sheets of a thin part close) is tried again,
          // simplified within half the bounds, then as the part's own surface (the input's
          // triangles, when not too many); the first that holds is kept, else the best of them.
          // A part is one connected surface, so its mesh is one piece: tetrahedra joined by faces
          // (a simplified boundary that pinches two sheets together can split it).
          auto holds = [&](const TetMesh& m, const TetrahedralizeStats& st) {
            if (!(m.T.rows() > 0 && st.conforming)) return false;
            const TetQuality q = tet_quality(m);
            return q.min_dihedral >= opt.tetrahedralize.min_dihedral && q.components == 1;
          };
          auto better = [&](const TetMesh& m, const TetrahedralizeStats& st, const TetMesh& than,
                            const TetrahedralizeStats& than_st) {
            if ((m.T.rows() > 0) != (than.T.rows() > 0)) return m.T.rows() > 0;
            if (st.conforming != than_st.conforming) return st.conforming;
            const TetQuality q = tet_quality(m), q_than = tet_quality(than);
            // Neither conforming: the one that keeps the part's volume, by more than 5 % (tetrahedra
            // classified by the winding number where faces were not recovered can drop most of it).
            if (!st.conforming) {
              const double lost = std::abs(std::log(q.volume / p.volume)), lost_than = std::abs(std::log(q_than.volume / p.volume));
              if (std::abs(lost - lost_than) > 0.05) return lost < lost_than;
            }
            if ((q.components == 1) != (q_than.components == 1)) return q.components == 1;
            return q.min_dihedral > q_than.min_dihedral;
          };
          // A retry's mesh, its stats, its boundary and that boundary's simplification replace the part's.
          auto adopt = [&](TetMesh& m, const TetrahedralizeStats& st, SurfaceMesh& b, const EnvelopeStats& es) {
            p.tets = std::move(m);
            p.tet_stats = st;
            p.boundary = std::move(b);
            p.envelope = es;
            p.remeshed = false;  // (retry 0 sets it after adopting its own)
          };
          // Where the first attempt does not hold, a part over three times thinner than its
          // tetrahedra are long is tried as the slab of its mid-surface before any retry (meshing
          // version 20): a roof 4 % of its diagonal thick, tapering at one end, was not
          // tetrahedralized conforming by any attempt at 1,000 (5.8 times thinner), and the retries
          // took 15 s. (Only where the ratio alone stopped the first try: otherwise it would fail
          // the same way again.) Nor where its refinement stopped at its work bound (a boundary of
          // skinny triangles): an unfinished refinement is no boundary that holds (a knife 1 m deep
          // whose edge is 1.1° sharp, at 1000: once its flat surface cells were flipped outside,
          // such a first attempt held, and the skinny retry after it took 45 s for 9 % of the
          // diagonal in, where the slab is within the bounds in 1.6 s; meshing version 43).
          const bool first_holds = holds(p.tets, p.tet_stats);  // (p.tets stays the first attempt's until a retry)
          const bool first_conforming = p.tet_stats.conforming;
          const double first_edge_length = p.tet_stats.edge_length;
          if (spdlog::should_log(spdlog::level::debug)) {
            const TetQuality q = tet_quality(p.tets);
            spdlog::debug("part {}: first attempt: {} tetrahedra, conforming {}, smallest dihedral angle {:.2f}°, {} "
                          "component(s): {}", i, p.tets.T.rows(), p.tet_stats.conforming, q.min_dihedral, q.components,
                          first_holds ? "holds" : "does not hold");
          }
          // A first attempt that holds with over 1.35 times the part's share of the target (the
          // part is thinner than its share's tetrahedra: the dihedral floor sets the count), from a
          // boundary its face budget stopped (not the bounds), is tried again from a boundary of
          // as many more faces as the count exceeds the share by (the part's own, where fewer); kept
          // where it holds with at most 1.35 times the first's tetrahedra (meshing version 48). A
          // coin 4 mm thick, 0.1 m across, 48 sides, at 150: 1,288 tetrahedra from 42 of its sides
          // (0.20 % of the diagonal out, 0.22 % in), 1,590 from all 48 (exact). Three small
          // segments of the spinal cord at 150 would take 6 to 35 times their tetrahedra: they keep
          // the first.
          if (first_holds && opt.more_faces_where_over_target && !abandoned && !p.target && p.offset == 0 &&
              !p.envelope.bounded && p.envelope.collapses > 0 && p.tets.T.rows() > 1.35 * t.target_tets) {
            EnvelopeOptions more = e;
            const double scale = static_cast<double>(p.tets.T.rows()) / t.target_tets;
            more.target_faces = static_cast<int>(std::min<double>(std::lround(e.target_faces * scale), max_retry_faces));
            EnvelopeStats es;
            SurfaceMesh b = simplify(p, more, &es, nullptr);
            if (b.F.rows() > p.boundary.F.rows() && !(p.check && does_self_intersect(b))) {
              // (Its refinement bounded as a skinny boundary's first attempt is: trimesh's
              // cylinder.stl at 300, 416 long, thin faces, refined 14 s to 11,105 tetrahedra.)
              TetrahedralizeStats st;
              t.max_refine_work = opt.skinny_refine_work;
              TetMesh m = tetrahedralize_part(b, &st, t.max_tets, t.max_attempts);
              t.max_refine_work = 0;
              const bool keep = holds(m, st) && !st.work_exceeded && m.T.rows() <= 1.35 * p.tets.T.rows();
              spdlog::debug("part {}: {} tetrahedra for a share of {}: from {} boundary faces (not {}), {} tetrahedra, {}", i,
                            p.tets.T.rows(), t.target_tets, b.F.rows(), p.boundary.F.rows(), m.T.rows(),
                            keep ? "kept" : "not kept");
              if (keep) adopt(m, st, b, es);
            }
          }
          if (stopped_at_ratio && (!first_holds || p.tet_stats.work_exceeded) && !abandoned &&
              mesh_thin_part(p, bounds, 3.0, nullptr)) {
            spdlog::debug("part {}: its boundary did not hold{}; meshed as the slab of its mid-surface", i,
                          first_holds ? " (its refinement stopped at its work bound)" : "");
            return;
          }
          // A first attempt that split its boundary's edges over four times per face and still did
          // not hold takes no retry: the part goes to its winding-number solid (below) at once
          // (meshing version 21). The retries start from the same or a finer boundary and did not
          // hold either on the CAD parts measured: trimesh's idler_riser.STL (3,038 splits for
          // 486 faces) and cylinder.stl at 150 (614 for 66), 7-51 s of retries before the solid
          // held, 0.5-6 s. Where retries did hold (a coil spring of 2 mm wire at 150: 2,960
          // splits for 1,744 faces), the first attempt split under twice per face; in the corpus,
          // the organs and the generated shapes the only other first attempt that did not hold
          // split under once per face (the sacrum's).
          // (Since meshing version 55 the first recovery itself gives up there, at
          // TetrahedralizeOptions::recovery_splits_per_face, and that run is not refined.)
          const bool hopeless = !first_holds && (p.tet_stats.recovery_abandoned ||
                                                 p.tet_stats.boundary_splits > 4 * static_cast<int>(p.boundary.F.rows()));
          if (hopeless)
            spdlog::debug("part {}: its first attempt split {} boundary edges for {} faces and did not hold: no retry but the remeshed surface", i,
                          p.tet_stats.boundary_splits, p.boundary.F.rows());
          // Retry 0 (meshing version 22), before the others (but a boundary of mostly skinny
          // triangles' split version, below, since version 26): the part's own surface remeshed into
          // round triangles (remesh_isotropic: a quarter of the interior edge length; creases over
          // 40° kept as polylines, corners where they turn, every vertex on the surface) and, where
          // that lies within the bounds of the surface both ways, simplified within them again
          // against the surface (its triangles kept round: 25°, folds of 45°), then
          // tetrahedralized. Where the remeshed surface lies too far off (creases collapsed across
          // features smaller than the length), it is made again shorter in proportion to how far,
          // twice at most, and at most 35,000 triangles. CAD tessellations are long, thin triangles
          // (a fillet's strips 0.6 mm by 10 mm, fans across flat faces: 66 % of trimesh's
          // octagonal pocket under 5°), whose diametral balls hold the other side of every wall
          // near them: recovery splits them round after round and does not converge
          // (plate_holes.STL at 150: 2,377 tetrahedra, 0.83 of its volume, 0.0°, 18.5 s; through
          // this retry 1,140 tetrahedra, 0.998, 6.7°, 12.6 s). The first attempts the hopeless gate
          // above turns away are of this kind, so this comes before it takes effect.
          bool held = first_holds;
          bool split_stopped = false;  // the skinny split stopped at its face budget, far over (below)
          // A boundary of mostly skinny triangles goes first to its rounder version, before retry 0
          // (meshing version 26): split to rounder triangles (edges at most `skinny` long) and
          // simplified within the same bounds, so that the simplification can collapse along the
          // part (version 14). Where its simplification coarsens it (version 14's rod,
          // 1 m long, 3 mm across, 12 sides and 40 rings, at 150: 204 faces, 152 tetrahedra, volume
          // 1.000), it is the better mesh, and retry 0's remesh of the same rod held only at 1.3 mm
          // (646 tetrahedra, 0.982). Where it does not coarsen (a rod 2 m long, 2 cm across, 16
          // sides and one ring, turned off the axes: 23,360 faces split, 17,762 simplified, whose
          // refinement took 46 s for 2.7°), it is not tetrahedralized: over max_retry_faces.
          if (skinny > 0 && (p.tet_stats.work_exceeded || !held) && !abandoned && !hopeless) {
            bool split_complete = true;
            const SurfaceMesh split = split_long_edges(p.surface, skinny, &split_complete);
            // Where the split stopped at its face budget with edges still over `skinny` and over 8
            // times max_retry_faces (a tube of 12 rings and 300 sides: 194,400 faces), its
            // simplification does not coarsen it below max_retry_faces either (64 s for 139,064
            // faces, refused below): not simplified (meshing version 30). Smaller splits that stopped
            // early do simplify (trimesh's boolean.glb: a part split to 15,936 faces, simplified to 28).
            const bool still_skinny = !split_complete && split.F.rows() > 8 * static_cast<Eigen::Index>(max_retry_faces);
            EnvelopeStats es;
            SurfaceMesh b = still_skinny ? SurfaceMesh{} : simplify_envelope(split, e, &es, nullptr);  // (no p.target)
            split_stopped = still_skinny;
            if (still_skinny) {
              spdlog::debug("part {}: boundary of mostly skinny triangles: split at {:.4g} stopped at {} faces, edges "
                            "still longer: not simplified", i, skinny, split.F.rows());
            } else if (b.F.rows() > max_retry_faces) {
              spdlog::debug("part {}: boundary of mostly skinny triangles: split at {:.4g} to {} faces, simplified to {}: "
                            "too many to tetrahedralize", i, skinny, split.F.rows(), b.F.rows());
            } else if (!(p.check && does_self_intersect(b))) {
              TetrahedralizeStats st;
              TetMesh m = tetrahedralize_part(b, &st, t.max_tets, t.max_attempts);
              spdlog::debug("part {}: boundary of mostly skinny triangles ({} tetrahedra, refinement work {:.3g}{}): split "
                            "at {:.4g} to {} faces, simplified to {}: {} tetrahedra, conforming {}",
                            i, p.tets.T.rows(), p.tet_stats.refine_work, p.tet_stats.work_exceeded ? ", over its bound" : "",
                            skinny, split.F.rows(), b.F.rows(), m.T.rows(), st.conforming);
              ++p.retries;
              // A first attempt that holds, its refinement stopped at the work bound, is replaced
              // only by a split boundary that holds at fewer tetrahedra: the split's purpose is a
              // boundary coarser along the part (version 14's rod at 150: 152 tetrahedra), and the
              // first keeps the input's own faces (meshing version 47). A box 2 m by 1 cm by 1 cm,
              // turned, 100 m from the origin, written with 7 digits: at 300 the first attempt
              // held on the box's 12 faces (1,895 tetrahedra, 0.11 % of the diagonal out), the
              // split boundary took its place (2,747, 0.20 % out); at 1000 a split boundary that was
              // not conforming took the place of one that held, and the retries after it took 11 s
              // to come back to the box's 12 faces.
              const bool take = first_holds && opt.skinny_split_keeps_first_that_holds
                                    ? holds(m, st) && m.T.rows() < p.tets.T.rows()
                                    : p.tet_stats.work_exceeded || better(m, st, p.tets, p.tet_stats);
              if (take) adopt(m, st, b, es);
              held = held || holds(p.tets, p.tet_stats);
            }
          }
          // (Not where the skinny split stopped far over its budget: CGAL's remesh of the same
          // skinny triangles ran over 5 min on the knot of 12 rings; meshing version 30.)
          if (!held && !abandoned && p.offset == 0 && !p.target && opt.remesh_retry && !split_stopped) {
            const TriangleBvh own(p.surface.V, p.surface.F);
            EnvelopeOptions er = e;  // the remeshed surface's triangles are round: kept round
            er.min_triangle_angle = std::max(er.min_triangle_angle, 25.0);
            er.min_fold_angle = std::max(er.min_fold_angle, 45.0);
            er.max_inside *= 0.8;  // a margin for the peeling of boundary slivers after it (trimesh's
                                   // angle_block.STL at 150: 0.45 % of the diagonal in, then 0.50 %)
            // At most 35,000 triangles (their simplification takes seconds) where a quarter of the
            // part's triangles or more have an angle under 10° (CAD tessellations: 31-88 % of
            // trimesh's parts, 0-19 % of the corpus's scans and organs), else 10,000: the sacrum at
            // 150 went on to 36,000 that did not hold either, 8 s.
            int thin_angles = 0;
            for (Eigen::Index f = 0; f < p.surface.F.rows(); ++f) {
              const Eigen::Vector3d a = p.surface.V.row(p.surface.F(f, 0)), b = p.surface.V.row(p.surface.F(f, 1)),
                                    c = p.surface.V.row(p.surface.F(f, 2));
              std::array<double, 3> len{(b - a).norm(), (c - b).norm(), (a - c).norm()};
              std::sort(len.begin(), len.end());
              // The smallest angle is opposite the shortest edge: its sine is twice the area over
              // the product of the two others.
              thin_angles += (b - a).cross(c - a).norm() < std::sin(10.0 * M_PI / 180.0) * len[1] * len[2];
            }
            const double max_faces = 4 * thin_angles >= p.surface.F.rows() ? 35000 : 10000;
            // At most the length whose chords lose about remesh_volume_loss (2.5 %) of the part's
            // volume, from its mean curvature (meshing version 27): a rod 2 m long, 2 cm across,
            // 32 sides, at 1000, was remeshed at 5.5 mm first (3.6 % lost, 11.8 s of CGAL's
            // remeshing) and then at 4.1 mm, which held; now 4.5 mm at once.
            double h = 0.25 * L;
            if (opt.remesh_volume_loss > 0)
              h = std::min(h, chord_length_for_volume_loss(p.surface, p.volume, opt.remesh_volume_loss, RemeshOptions{}.sharp_angle));
            if (h < 0.25 * L)
              spdlog::debug("part {}: retry 0: {:.4g} (not {:.4g}), where its chords lose about {:.3g} % of its volume", i, h,
                            0.25 * L, 100 * opt.remesh_volume_loss);
            for (int attempt = 0; attempt < 3; ++attempt) {
              if (!(h > 0) || part_area / (0.433 * h * h) > max_faces) break;
              RemeshOptions ro;
              ro.edge_length = h;
              SurfaceMesh b = remesh_isotropic(p.surface, ro);
              if (b.F.rows() == 0 || abandoned) break;
              const auto [out, in] = farthest_both_ways(b.V, b.F, p.surface, own, part_spacing);
              spdlog::debug("part {}: retry 0 (remeshed at {:.4g}): {} faces, {:.3g} / {:.3g} off its surface (bounds "
                            "{:.3g} / {:.3g})", i, h, b.F.rows(), out, in, e.max_outside, e.max_inside);
              if (out > e.max_outside || in > e.max_inside) {
                // Off by about a third of the edge length where creases collapse across small
                // features: shorter in proportion, with a margin (at most 4 times shorter).
                h *= std::clamp(0.8 * std::min(e.max_outside / out, e.max_inside / in), 0.25, 0.8);
                continue;
              }
              // Nor 3 % off the part's volume: a rod thinner than the bounds (1 m long, 3 mm
              // across, 12 sides) keeps them as a rod of three sides, 0.83 of its volume.
              auto volume_kept = [&](const SurfaceMesh& m) { return std::abs(signed_volume(m) / p.volume - 1.0) <= 0.03; };
              if (!volume_kept(b)) {
                // Chords of a curved surface lose volume as the square of their length: shorter
                // toward 2 % lost, 0.3-0.8 times (meshing version 26). A rod 2 m long, 2 cm
                // across, 16 sides, at 150, lost 11.9 % at 10 mm and 3.0 % at 5.1 mm; halving
                // again went over the triangles' cap. Now 10 mm, then 4.2 mm, which holds; the
                // remesh at 5.1 mm it skips took 6 s of CGAL's time (12 s with 32 sides).
                const double kept = signed_volume(b) / p.volume;
                spdlog::debug("part {}: retry 0 (remeshed at {:.4g}): {:.3f} of its volume", i, h, kept);
                h *= std::clamp(std::sqrt(0.02 / std::abs(kept - 1.0)), 0.3, 0.8);
                continue;
              }
              if (does_self_intersect(b)) {  // (tested last: the most work)
                spdlog::debug("part {}: retry 0 (remeshed at {:.4g}): intersects itself", i, h);
                break;
              }
              EnvelopeStats es;
              b = simplify_envelope(b, p.surface, er, &es, nullptr);
              if (does_self_intersect(b) || !volume_kept(b)) {
                spdlog::debug("part {}: retry 0: simplified to {} faces, which intersect or hold {:.3f} of its volume", i,
                              b.F.rows(), signed_volume(b) / p.volume);
                break;
              }
              TetrahedralizeStats st;
              TetMesh m = tetrahedralize_part(b, &st, t.max_tets, 2);  // (two edge lengths, as the retries below)
              ++p.retries;
              held = holds(m, st);
              spdlog::debug("part {}: retry 0 (remeshed at {:.4g}): simplified to {} faces, {} tetrahedra, conforming {}, "
                            "smallest dihedral angle {:.2f}°, holds {}",
                            i, h, b.F.rows(), m.T.rows(), st.conforming,
                            spdlog::should_log(spdlog::level::debug) ? tet_quality(m).min_dihedral : 0.0, held);
              if (held || better(m, st, p.tets, p.tet_stats)) {
                adopt(m, st, b, es);
                p.remeshed = true;
              }
              break;  // (held, or a shorter length would hold no better: thin walls want the slab)
            }
          }
          // The part's winding-number solid by Mesh_3 (below, where no boundary holds), kept where it
          // holds; tried once.
          bool solid_tried = false;
          auto try_solid = [&] {
            solid_tried = true;
            const double dilation = opt.winding_dilation * opt.max_deviation * diag;
            const double growth = dilation * part_area / p.volume;  // estimated volume growth
            if (p.offset == 0 && !p.target && !abandoned && growth <= 0.5) {
              const double part_diag = bounding_box_diagonal(p.surface.V);
              const double allowed = allowed_solid_growth(target);
              const double shrink =
                  target >= 1000 && growth > allowed ? std::max(opt.solid_min_scale, allowed / growth) : 1.0;
              double scale = shrink;  // (the dilation's and the facet distance's factor)
              // (facet: a further factor on the facet distance.)
              auto make = [&](double facet, TetrahedralizeStats* st, double* ratio) {
                WindingTetrahedralizeOptions wo = opt.winding_mesh;
                wo.target_tets = t.target_tets;
                wo.seed = t.seed;
                wo.facet_distance = std::min(
                    0.5, facet * scale * opt.winding_facet_distance * opt.max_deviation * diag / part_diag);
                wo.dilation = std::min(0.5, scale * dilation / part_diag);
                WindingTetrahedralizeStats ws;
                TetMesh m = tetrahedralize_winding_number(p.surface.V, p.surface.F, p.volume, wo, &ws, nullptr);
                st->attempts = ws.attempts;
                st->edge_length = ws.cell_size;
                st->peeled = ws.peeled_slivers;
                st->relocated = ws.relocated;
                st->flips = ws.flips;
                *ratio = m.T.rows() > 0 ? tet_quality(m).volume / p.volume : 0.0;
                spdlog::debug("part {}: its winding-number solid by Mesh_3 (dilation × {:.2f}, facet distance × {:.2f}): {} "
                              "tetrahedra, volume ratio {:.3f}", i, scale, facet * scale, m.T.rows(), *ratio);
                return m;
              };
              auto kept = [&](const TetMesh& m, const TetrahedralizeStats& st, double ratio) {
                return holds(m, st) && ratio >= 0.9 && ratio <= 1.2;
              };
              TetrahedralizeStats st;
              double ratio = 0;
              TetMesh m = make(1.0, &st, &ratio);
              // Grown over the volume bound (1.2; 1.1 from 1,000 tetrahedra: a thin CAD plate, walls
              // about 3 mm thick, at 150: its dilation alone made it 1.412 times its volume, and
              // the part kept a boundary that was not conforming, 1.36 % of the diagonal in): made
              // again once with the dilation and facet distance scaled toward the growth allowed
              // (0.15 below 1,000 tetrahedra, 0.08 from there), to no less than solid_min_scale of
              // them (0.4 before version 57); kept where it holds and the first did not, or nearer
              // the volume (meshing version 54).
              if (ratio > (target >= 1000 ? 1.1 : 1.2) && scale > opt.solid_min_scale) {
                const double first_scale = scale;
                scale = std::max(opt.solid_min_scale, scale * allowed / (ratio - 1.0));
                TetrahedralizeStats st2;
                double ratio2 = 0;
                TetMesh m2 = make(1.0, &st2, &ratio2);
                if (kept(m2, st2, ratio2) && (!kept(m, st, ratio) || ratio2 < ratio))
                  m = std::move(m2), st = st2, ratio = ratio2;
                else
                  scale = first_scale;
              }
              if (!kept(m, st, ratio)) return;
              // Where the input lies over the inner bound outside it (Mesh_3's facets cut across a
              // thin crest: a bust scanned in 99,938 faces at 150, 0.56 % of the diagonal), made
              // again at 0.75 of the facet distance, kept where it holds nearer (the bust: 0.09 %;
              // forty-eighth session, meshing version 51).
              if (opt.solid_facet_retry) {
                auto outside = [&](const TetMesh& x) {
                  return farthest_outside(TetLocator(x), TriangleBvh(x.V, boundary_faces(x.T)), p.surface, part_spacing);
                };
                const double in = outside(m);
                if (in > e.max_inside) {
                  TetrahedralizeStats st2;
                  double ratio2 = 0;
                  TetMesh m2 = make(0.75, &st2, &ratio2);
                  const double in2 = kept(m2, st2, ratio2) ? outside(m2) : INFINITY;
                  spdlog::debug("part {}: its winding-number solid lies {:.3g} in (bound {:.3g}); at 0.75 of the facet "
                                "distance {:.3g}: {}", i, in, e.max_inside, in2, in2 < in ? "kept" : "not kept");
                  if (in2 < in) m = std::move(m2), st = st2;
                }
              }
              p.tets = std::move(m);
              p.tet_stats = st;
              p.by_winding_number = true;
              p.remeshed = false;
            }
          };
          // Where the first attempt lost conformity (recovery gave up) on a part of over
          // `solid_first_faces` faces, the solid comes before retries 1 and 3: each simplifies the
          // part again, 1-2 times the first simplification's seconds, and on the scans measured
          // whose first boundary lost conformity (the sacrum, the urchin of version 24, a bust of
          // 99,938 faces) none held, where the solid did (forty-eighth session: the bust took 38 s,
          // 13 of them in retry 1).
          // Or (meshing version 53) on a part as thick as solid_first_thickness of the first
          // attempt's edge length: the sacrum at 1000 (10,818 faces, 10 mm thick on average, 16 mm
          // edges) lost conformity in retries 1, 3 and 4 as well, 7.6 s of its 12-15 s, and its
          // solid held in 2 s; the comb of the tests (2 mm teeth, 0.33 of its edge length) holds at
          // retry 4, where its solid takes 52,073 tetrahedra.
          const double thickness = 2 * p.volume / part_area;
          const bool thick = opt.solid_first_thickness > 0 && first_edge_length > 0 &&
                             thickness >= opt.solid_first_thickness * first_edge_length;
          if (!first_conforming && !holds(p.tets, p.tet_stats) && opt.solid_first_faces > 0 &&
              (p.surface.F.rows() > opt.solid_first_faces || thick)) {
            try_solid();
            if (p.by_winding_number)
              spdlog::debug("part {}: its first boundary lost conformity ({} faces, {:.3g} of its edge length thick on "
                            "average): its winding-number solid kept before retries 1 and 3",
                            i, p.surface.F.rows(), thickness / first_edge_length);
          }
          const Eigen::Index first_count = p.tets.T.rows();
          // Retry 3 (version 14), where neither held: simplified within the same bounds toward four
          // times the faces, the boundary a larger target would take (a 1 m by 0.6 m slab 2 cm
          // thick, waved 5 cm: its 280 faces at 150 pinched it, not conforming, 1.2 % in; its
          // 4,096 faces are over the own-surface retry's limit; 446 faces at 300 held).
          for (int retry = 1; retry <= 3 && !hopeless && !holds(p.tets, p.tet_stats); ++retry) {
            SurfaceMesh b;
            EnvelopeStats es;
            if (retry == 1) {
              EnvelopeOptions e2 = e;
              e2.max_outside *= 0.5;
              e2.max_inside *= 0.5;
              b = simplify(p, e2, &es, nullptr);
              if (p.check && does_self_intersect(b)) continue;
              // Where the target's face count, not the bounds, stopped the simplification, half the
              // bounds give the same boundary, and tetrahedralizing it again gives the same mesh.
              if (b.F.rows() == p.boundary.F.rows() && b.V.rows() == p.boundary.V.rows() && b.F == p.boundary.F &&
                  b.V == p.boundary.V) {
                spdlog::debug("part {}: retry 1 (half the bounds) gives the same boundary: skipped", i);
                continue;
              }
            } else if (retry == 2) {
              if (p.check || p.surface.F.rows() > max_retry_faces) continue;
              b = p.surface;
            } else {
              EnvelopeOptions e3 = e;
              e3.target_faces = 4 * e.target_faces;
              if (e3.target_faces >= p.surface.F.rows()) continue;  // retry 2's own surface, or about it
              // Where the first simplification stopped at its bounds above the new target's edges,
              // that target never stops it: the same collapses, the same boundary, skipped below
              // after the work (a bust of 99,938 faces: 8.6 s; forty-eighth session).
              const size_t edges3 = static_cast<size_t>(std::max(4, e3.target_faces)) * 3 / 2;
              if (first_envelope.bounded && static_cast<size_t>(first_boundary.F.rows()) * 3 / 2 > edges3 &&
                  first_boundary.F.rows() <= p.boundary.F.rows()) {
                spdlog::debug("part {}: retry 3 (four times the faces) gives the first boundary: skipped", i);
                continue;
              }
              b = simplify(p, e3, &es, nullptr);
              if (p.check && does_self_intersect(b)) continue;
              if (b.F.rows() <= p.boundary.F.rows()) continue;  // the bounds, not the count, set it: the same
            }
            // A retry is bounded: at most twice the first attempt's tetrahedra (at least 4,000)
            // and two edge lengths; around a sharp tip its recovery and refinement can split
            // without end (a 96-sided cone's own surface: 19,417 tetrahedra, 72 s, still not
            // conforming; a 64-sided one: five edge lengths, 20 s).
            TetrahedralizeStats st;
            TetMesh m = tetrahedralize_part(b, &st, std::max(4000, 2 * static_cast<int>(first_count)), 2);
            spdlog::debug("part {}: retry {} ({}): {} faces, {} tetrahedra, conforming {}", i, retry,
                          retry == 1 ? "half the bounds" : retry == 2 ? "its own surface" : "four times the faces", b.F.rows(), m.T.rows(), st.conforming);
            ++p.retries;
            if (better(m, st, p.tets, p.tet_stats)) adopt(m, st, b, es);
          }
          // Retry 4 (meshing version 25), where none held: the first boundary again, from a finer
          // start, at 1/2 then 1/4 of the first edge length (TetrahedralizeOptions::
          // edge_length_scale; one attempt each, not exuded), kept where it holds. Walls thinner
          // than the spacing of the boundary's points and closer to each other than it, that
          // branch (so not a thin part: its sides are not two), put each other's points in the
          // diametral balls of their triangles, and recovery by splits gave up at its cap in every
          // attempt: a comb of 2 mm teeth 4 mm apart at 150 kept 12,176 tetrahedra, not
          // conforming, 1.8 % of the diagonal in; from a quarter of the length, its 204 faces give
          // about 5,300 tetrahedra, the comb exactly, in about a second. (Last: it is not the
          // target's count, and the retries above hold at fewer where they hold.)
          // Not for a boundary of mostly skinny triangles (its retry above): its faces' shape, not
          // their points' spacing, keeps them out of the triangulation (a CAD cylinder of 104
          // sides, 8 long, caps fanned: with remesh_retry off it held here at a quarter, 18,060
          // tetrahedra in 55 s, where its winding-number solid takes a second). Its refinement
          // has the skinny parts' work bound.
          // Nor for a first boundary that intersects itself (the envelope's collapses are checked
          // for folds only locally: two sides of a thin crest can cross): no tetrahedralization
          // has two crossing triangles among its faces, so no finer start can hold (a bust scanned
          // in 99,938 faces spent 1.5-5.5 s here on one of 1,506).
          bool first_crosses = false;
          if (!holds(p.tets, p.tet_stats) && !abandoned && p.offset == 0 && skinny == 0) {
            first_crosses = does_self_intersect(first_boundary);
            if (first_crosses) spdlog::debug("part {}: no retry 4: its first boundary intersects itself", i);
          }
          for (double scale : {0.5, 0.25}) {
            if (holds(p.tets, p.tet_stats) || abandoned || p.offset > 0 || skinny > 0 || first_crosses) break;
            TetrahedralizeOptions saved = t;
            t.edge_length_scale = scale;
            t.max_refine_work = opt.skinny_refine_work;
            t.exude = false;  // (its walls' tetrahedra are as flat as the walls are thin: the exuder
                              // cannot improve them, and on the comb it ran to its 30 s time limit)
            TetrahedralizeStats st;
            TetMesh m = tetrahedralize_part(first_boundary, &st, t.max_tets, 1);
            t = saved;
            ++p.retries;
            // Held, and its boundary within the bounds of the part's surface both ways: peeling
            // boundary slivers moves it inward (an urchin's 20 spikes at 150: 0.50 % of the
            // diagonal in, where its winding-number solid, below, holds the bounds).
            bool held_now = holds(m, st);
            TwoWayDistance off;
            if (held_now) {
              off = farthest_both_ways(m.V, boundary_faces(m.T), p.surface, TriangleBvh(p.surface.V, p.surface.F),
                                       part_spacing);
              held_now = off.out <= e.max_outside && off.in <= e.max_inside;
            }
            spdlog::debug("part {}: retry 4 (a finer start, {:.2f} of the edge length): {} tetrahedra, conforming {}, "
                          "{:.3g} / {:.3g} off its surface (bounds {:.3g} / {:.3g}), holds {}",
                          i, scale, m.T.rows(), st.conforming, off.out, off.in, e.max_outside, e.max_inside, held_now);
            if (held_now) {
              SurfaceMesh b = first_boundary;
              adopt(m, st, b, first_envelope);
            }
            // Where half the length did not recover the boundary, a quarter (about 8 times the
            // tetrahedra) is not tried (forty-seventh session, the same meshes): of 133 rows measured
            // (the corpus at four targets, the generated shapes of versions 9, 24 and 26 at 150 and
            // 1000, a scanned bust) none kept a mesh made at a quarter; the sacrum at 1000 spent 3.7
            // of its 14-18 s there, the urchin at 150 made 10,981 tetrahedra there that were not kept.
            if (!st.conforming) break;
          }
          // A part whose boundary still does not hold (a cone's sharp tip between thin triangles,
          // whose recovery splits them ten times over: 52 of 90 generated cones failed, some not
          // conforming with 8 % of the diagonal out) is meshed as the solid its own surface's
          // winding number encloses, by Mesh_3 (the winding-number route, on this part alone:
          // conforming by construction, its boundary within the same deviation bounds, slivers
          // exuded, moved and flipped). Kept where it holds and keeps the part's volume within the
          // issue's looser bound, [0.9, 1.2]: its dilation thickens a thin shell (a 1 mm bowl: 3.7
          // times its volume), whose best boundary attempt stays.
          // Not tried where the dilation alone would grow the part by half: about dilation × area /
          // volume (a 1 mm bowl: 2.7; the sacrum, whose solid keeps 1.19 of its volume: 0.21, so a
          // fifth was too tight a cut).
          // At 1,000 tetrahedra and more, where the issue's volume bound is [0.95, 1.1], a part the
          // dilation would grow by more than 8 % gets a smaller dilation and facet distance, in
          // proportion, down to 0.4 of them (more tetrahedra: the sacrum at 1000, 5,298 → about
          // 14,000, volume 1.19 → 1.09).
          if (!solid_tried && !holds(p.tets, p.tet_stats)) try_solid();
          spdlog::debug("part {}: {} faces, volume {:.4g}, boundary {} faces, target {}, {} tetrahedra, conforming {}", i,
                        p.surface.F.rows(), p.volume, p.boundary.F.rows(), t.target_tets, p.tets.T.rows(),
                        p.tet_stats.conforming);
        });
      });
    };
    mesh_parts(parts, 0);
    // The boundary route holds where every part has tetrahedra. A part whose best attempt is still
    // not conforming (boundary faces not recovered: tetrahedra classified by the winding number) or
    // keeps a dihedral angle below the floor is kept and reported (tets.conforming, min_dihedral_deg,
    // a warning): it is still the part's shape, where the convex shells would inflate it (the
    // spinal cord at 150 tetrahedra: 21,976 times its volume).
    auto which = [&](size_t i) {
      return parts.size() > 1 ? "part " + std::to_string(i + 1) + " of " + std::to_string(parts.size()) : std::string("the input");
    };
    for (size_t i = 0; i < parts.size(); ++i)  // first: a failed part (the others may have been skipped)
      if (parts[i].failed) return fail(which(i) + " intersects itself, and so does its simplified boundary");
    for (size_t i = 0; i < parts.size(); ++i) {
      const Part& p = parts[i];
      if (p.tets.T.rows() == 0) return fail("the tetrahedralization of " + which(i) + "'s boundary produced no tetrahedra");
      if (!p.tet_stats.conforming)
        spdlog::warn("the tetrahedralization of {}'s boundary is not conforming after {} retries (some boundary faces "
                     "are not faces of the mesh: its tetrahedra are classified by the winding number)", which(i), p.retries);
    }
    r.parts = static_cast<int>(parts.size());
    r.boundary_from_input = !wrapped;
    if (!wrapped) {
      r.input_volume_from_winding_number = !r.info.closed;
      r.input_volume = 0;
      for (const Part& p : parts) r.input_volume += p.volume;
      r.info.volume = r.input_volume;
    }
    // Concatenated in part order.
    {
      std::vector<SurfaceMesh> b;
      std::vector<TetMesh> t;
      for (Part& p : parts) {
        b.push_back(std::move(p.boundary));
        p.tets_count = static_cast<int>(p.tets.T.rows());
        t.push_back(std::move(p.tets));
        r.boundary_retries += p.retries;
        r.parts_by_winding_number += p.by_winding_number;
        r.parts_remeshed += p.remeshed;
        r.envelope.faces += p.envelope.faces;
        r.envelope.collapses += p.envelope.collapses;
        r.envelope.bounded = r.envelope.bounded || p.envelope.bounded;
        r.boundary_target_faces += p.target_faces;
        TetrahedralizeStats& s = r.tet_stats;
        s.attempts = std::max(s.attempts, p.tet_stats.attempts);
        s.edge_length = std::max(s.edge_length, p.tet_stats.edge_length);
        s.minimum_tets += p.tet_stats.minimum_tets;
        s.boundary_splits += p.tet_stats.boundary_splits;
        s.steiner_points += p.tet_stats.steiner_points;
        s.peeled += p.tet_stats.peeled;
        s.relocated += p.tet_stats.relocated;
        s.flips += p.tet_stats.flips;
        s.contractions += p.tet_stats.contractions;
        s.exuder_nan_stops += p.exuder_nan_stops;
        s.exuder_pump_bounds += p.exuder_pump_bounds;
        s.conforming = s.conforming && p.tet_stats.conforming;
      }
      r.boundary = concatenate(b, &SurfaceMesh::F);
      r.tets = concatenate(t, &TetMesh::T);
    }
    if (wrapped) {
      // The input's own volume: where its winding number is above ½ (the union of overlapping or
      // welded segments, each counted once).
      r.input_volume_from_winding_number = true;
      r.input_volume = input_winding_volume();
      r.info.volume = r.input_volume;
    }
    label_by_shells(r.tets);

    timer.start("measuring");
    measure(r, opt);

    // Why the count is off the target, when it is by more than 35%.
    const double tets = r.quality.tets;
    const std::string dihedral = std::to_string(static_cast<int>(opt.tetrahedralize.refine_dihedral));
    const std::string in_parts =
        r.parts > 1 ? " over the input's " + std::to_string(r.parts) + " parts (each meshed on its own)" : "";
    bool sheet_capped = false;
    double thinnest = INFINITY;
    for (const Part& p : parts) {
      sheet_capped = sheet_capped || p.sheet_capped;
      if (p.thin > 0) thinnest = std::min(thinnest, p.thin), ++r.thin_parts;
    }
    if (tets > 1.35 * target && r.thin_parts > 0) {
      r.target_exceeded_because = std::to_string(r.thin_parts) + " of the input's parts " +
                                  (r.thin_parts == 1 ? "is" : "are") + " much thinner than the tetrahedra the target gives (down to " +
                                  percent(thinnest / bounding_box_diagonal(r.input.V)) +
                                  " of the bounding-box diagonal): each is one layer of prisms across its thickness, whose "
                                  "triangles are at most 8 times as wide as it is thick (flatter tetrahedra would fall below "
                                  "the 5 degree floor), which takes " + std::to_string(r.quality.tets) + " tetrahedra" + in_parts;
    } else if (tets > 1.35 * target && sheet_capped) {
      r.target_exceeded_because = "open sheets are meshed as slabs " + percent(opt.sheet_thickness * opt.max_deviation) +
                                  " of the bounding-box diagonal thick (--sheet-thickness): one layer of prisms whose "
                                  "triangles are at most 5 times as wide as that (flatter tetrahedra would fall below the "
                                  "5 degree floor) and short enough for the slab to hold the sheet where it curves, which "
                                  "takes " + std::to_string(r.quality.tets) + " tetrahedra" + in_parts;
    } else if (tets > 1.35 * target) {
      if (r.envelope.bounded)
        r.target_exceeded_because =
            "keeping the boundary within " + percent(opt.max_deviation) + " of the bounding-box diagonal outside and " +
            percent(opt.inner_deviation * opt.max_deviation) + " inside the input surface takes " +
            std::to_string(r.boundary.F.rows()) + " boundary triangles" + in_parts + " (a mesh of " +
            std::to_string(r.target_tets) + " tetrahedra has about " + std::to_string(r.boundary_target_faces) +
            "), and tetrahedra with dihedral angles of at least " + dihedral + " degrees between them need " +
            std::to_string(r.quality.tets);
      else
        r.target_exceeded_because = "the boundary's " + std::to_string(r.boundary.F.rows()) + " triangles" + in_parts +
                                    " and tetrahedra with dihedral angles of at least " + dihedral +
                                    " degrees (flatter where the solid is thinner than the edge length) need " +
                                    std::to_string(r.quality.tets) + " tetrahedra";
    } else if (tets < 0.65 * target) {
      r.target_exceeded_because = "the solid's boundary holds only " + std::to_string(r.boundary.F.rows()) +
                                  " triangles" + in_parts + " and refining the inside stopped at " +
                                  std::to_string(r.quality.tets) + " tetrahedra";
    }
    // A part meshed as its winding-number solid (its boundary did not hold) has Mesh_3's count,
    // not the boundary's: say so.
    if (!r.target_exceeded_because.empty() && r.parts_by_winding_number > 0) {
      std::string list;
      for (size_t i = 0; i < parts.size(); ++i)
        if (parts[i].by_winding_number)
          list += (list.empty() ? "" : ", ") + std::to_string(parts[i].tets_count) + " of them in " +
                  (parts.size() > 1 ? "part " + std::to_string(i + 1) : std::string("the input"));
      const std::string why =
          "could not be tetrahedralized conforming with dihedral angles of at least 5 degrees, so it is meshed as its own "
          "winding-number solid by CGAL Mesh_3 within the same bounds";
      if (r.parts_by_winding_number == static_cast<int>(parts.size()))
        r.target_exceeded_because = (parts.size() > 1 ? "each part's simplified boundary " : "the input's simplified boundary ") +
                                    why + ", which takes " + std::to_string(r.quality.tets) + " tetrahedra";
      else
        r.target_exceeded_because += "; " + list + ", whose simplified boundary " + why;
    }
    timer.stop();
    return std::move(r);
  };

  // The route for inputs that are not closed parts (open scans; non-manifold, welded or
  // self-intersecting segments): the input's alpha wrap (a closed 2-manifold without
  // self-intersections, `offset` outside the input, filling what is narrower than `alpha`), whose
  // components are the parts of the boundary route. The bounds are what the wrap leaves of the
  // input's: its own distance from the input is measured and taken off max_outside (at least a
  // quarter of it is kept). Every deviation in the report is still measured against the input.
  // Where the wrap cannot be meshed: the convex shells.
  auto wrap_route = [&](const std::string& why) -> MeshResult {
    spdlog::info("meshing the input's alpha wrap instead of its own boundary: {}", why);
    timer.start("wrapping");
    AlphaWrapOptions wo;
    wo.alpha = opt.wrap_alpha * opt.max_deviation;
    wo.offset = opt.wrap_offset * opt.max_deviation;
    SurfaceMesh wrap;
    try {
      wrap = alpha_wrap(r.input, wo);
    } catch (const std::exception& e) {
      return shells_route(why + "; its alpha wrap failed (" + e.what() + ")");
    }
    if (wrap.F.rows() == 0) return shells_route(why + "; its alpha wrap is empty");
    wrap.F = orient_outward(wrap.V, wrap.F);
    r.wrap.deviation = farthest_sample(wrap.V, wrap.F, TriangleBvh(r.input.V, r.input.F),
                                       deviation_spacing(diag, {area(wrap)}));
    r.wrap.used = true;
    r.wrap.alpha = wo.alpha;
    r.wrap.offset = wo.offset;
    r.wrap.faces = static_cast<int>(wrap.F.rows());
    int bad;
    std::vector<Part> parts = closed_components(wrap, [](double v) { return v > 0; }, &bad);
    const int n = static_cast<int>(parts.size());
    if (bad >= 0)
      return shells_route(why + "; component " + std::to_string(bad + 1) + " of its alpha wrap is not a closed "
                          "oriented 2-manifold enclosing volume");
    spdlog::debug("alpha wrap: alpha {:.3g}, offset {:.3g}: {} faces, {} components, {:.3g} from the input", wo.alpha * diag,
                  wo.offset * diag, wrap.F.rows(), n, r.wrap.deviation);
    EnvelopeOptions e = eopt;  // max_inside not widened by the offset: the wrap's faces cut chords
                               // through the offset band, down to the input itself at convex bulges
    e.max_outside = std::max(0.25 * eopt.max_outside, eopt.max_outside - r.wrap.deviation);
    r.method = "alpha_wrap";
    r.fallback_because = why;
    return boundary_route(parts, e, true, [&](const std::string& w) { return shells_route(why + "; on its alpha wrap, " + w); });
  };
  // Open scans whose holes are all narrow (meshing version 18): the cap over each (hole_caps.h)
  // within the outer bound of the scan. Where the winding-number solid's boundary fails them
  // (Mesh_3 does not find it about a solid thinner than its seeds' spacing: a rod 4 mm across and
  // 1 m long with one end open came out 8.3 times its volume), the scan with each hole capped by a
  // fan about its rim's centroid is a closed part, meshed by the boundary route (simplified against
  // itself, the outer bound less the caps' distance). Empty where the input is not such a scan or the capped surface is not
  // closed parts (a fan that crosses the scan).
  // The parts capped_route meshes: those of an open 2-manifold input with each hole capped by a fan
  // from its centroid, where every cap lies within the outer bound (`widest`: the farthest cap's
  // distance, units; `holes`: how many) and the capped input is closed parts without
  // self-intersection; else none. Made once: the winding-number route asks before its
  // surface is made (seed_finer_if_no_facet), capped_route after it is not found.
  struct Capped {
    std::optional<std::vector<Part>> parts;
    double widest = 0;
    size_t holes = 0;
  };
  std::optional<Capped> capped_made;
  auto capped_parts = [&]() -> const Capped& {
    if (capped_made) return *capped_made;
    Capped& c = capped_made.emplace();
    if (!is_open_two_manifold(r.input.F)) return c;
    const std::vector<std::vector<int>> loops = boundary_loops(r.input.F);
    c.holes = loops.size();
    for (const std::vector<int>& loop : loops) {
      if (loop.size() < 3) return c;
      c.widest = std::max(c.widest, hole_cap_distance(r.input.V, loop));
    }
    if (!(c.widest <= eopt.max_outside)) return c;
    // Each boundary edge as its face runs along it; a cap face runs the other way.
    std::set<std::pair<int, int>> along;
    {
      std::map<std::pair<int, int>, int> count;
      for (Eigen::Index f = 0; f < r.input.F.rows(); ++f)
        for (int e = 0; e < 3; ++e) {
          const int u = r.input.F(f, e), v = r.input.F(f, (e + 1) % 3);
          ++count[{std::min(u, v), std::max(u, v)}];
        }
      for (Eigen::Index f = 0; f < r.input.F.rows(); ++f)
        for (int e = 0; e < 3; ++e) {
          const int u = r.input.F(f, e), v = r.input.F(f, (e + 1) % 3);
          if (count.at({std::min(u, v), std::max(u, v)}) == 1) along.insert({u, v});
        }
    }
    SurfaceMesh capped;
    size_t cap_faces = 0;
    for (const std::vector<int>& loop : loops) cap_faces += loop.size();
    capped.V.resize(r.input.V.rows() + static_cast<Eigen::Index>(loops.size()), 3);
    capped.V.topRows(r.input.V.rows()) = r.input.V;
    capped.F.resize(r.input.F.rows() + static_cast<Eigen::Index>(cap_faces), 3);
    capped.F.topRows(r.input.F.rows()) = r.input.F;
    Eigen::Index v = r.input.V.rows(), f = r.input.F.rows();
    for (const std::vector<int>& loop : loops) {
      Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
      for (int i : loop) centroid += r.input.V.row(i);
      capped.V.row(v) = centroid / static_cast<double>(loop.size());
      for (size_t i = 0; i < loop.size(); ++i) {
        const int a = loop[i], b = loop[(i + 1) % loop.size()];
        if (along.count({a, b})) capped.F.row(f++) << b, a, static_cast<int>(v);
        else capped.F.row(f++) << a, b, static_cast<int>(v);
      }
      ++v;
    }
    capped.F = orient_outward(capped.V, capped.F);
    int bad;
    std::vector<Part> parts = closed_components(capped, [](double volume) { return volume > 0; }, &bad);
    if (bad >= 0 || parts.empty() || does_self_intersect(capped)) return c;
    c.parts = std::move(parts);
    return c;
  };
  auto capped_route = [&](const std::string& why,
                          const std::function<MeshResult(const std::string&)>& fail) -> std::optional<MeshResult> {
    const Capped& c = capped_parts();
    if (!c.parts) return std::nullopt;
    std::vector<Part> parts = *c.parts;  // (boundary_route takes them to mesh)
    const double widest = c.widest;
    const size_t holes = c.holes;
    spdlog::info("meshing the input with its {} holes capped (each cap within {:.3g} of it): {}", holes, widest, why);
    leave_boundary_route("capped_boundary", why + "; its " + std::to_string(holes) + " holes are narrower than "
                         "the bound: meshed capped", static_cast<int>(parts.size()));
    EnvelopeOptions e = eopt;  // (the caps lie up to `widest` off the input; at least a quarter kept, as the wrap's)
    e.max_outside = std::max(0.25 * eopt.max_outside, eopt.max_outside - widest);
    return boundary_route(parts, e, false, fail);
  };
  // Inputs that are not closed parts (meshing version 11): the boundary of their winding-number
  // solid, as Mesh_3 finds it (winding_number_surface: a closed 2-manifold without
  // self-intersection, within the facet distance and the dilation of the input), is simplified
  // against the input itself (the outer bound to the input's nearest triangle, the inner bound at
  // the input's own points: simplify_envelope with a target) and tetrahedralized, component by
  // component, by the boundary route. Mesh_3's own tetrahedra follow the surface with facets of
  // about one size (the heart: 14,372 tetrahedra, where a boundary within the same bounds needs
  // 10,600 and the lungs half of Mesh_3's). Where that surface cannot be had or a part does not
  // hold (conforming, the dihedral floor), Mesh_3's tetrahedra of the solid (winding_route).
  // `dilation`: as a multiple of max_deviation (open scans: winding_dilation, as Mesh_3's own
  // tetrahedra; welded segments: winding_surface_dilation).
  // `only`: the solid of these components of the input only (not closed parts: open, non-manifold
  // or welded), beside the closed parts `beside`, meshed as parts of their own (meshing version
  // 35); null: the whole input's.
  auto winding_boundary_route = [&](const std::string& why, double dilation, const SurfaceMesh* only = nullptr,
                                    std::vector<Part>* beside = nullptr) -> MeshResult {
    const SurfaceMesh& source = only ? *only : r.input;
    if (only)
      spdlog::info("meshing the boundary of the winding-number solid of the input's components that are not closed "
                   "parts, beside its {} closed part{}: {}", beside->size(), beside->size() == 1 ? "" : "s", why);
    else
      spdlog::info("meshing the boundary of the input's winding-number solid instead of its own: {}", why);
    leave_boundary_route("winding_number_boundary", why, 0);
    timer.start("winding-number surface");
    r.input_volume_from_winding_number = true;
    WindingTetrahedralizeOptions wo = opt.winding_mesh;
    wo.seed = opt.tetrahedralize.seed;
    if (only) wo.seed_faces_if_no_facet = true;  // (a few small components: their faces are few)
    // (Where the solid is not found, a thin open scan with narrow holes is meshed capped; the whole
    // of any other input has its seeds taken again finer first: the spinal cord with holes. `only`
    // components are seeded along their faces instead, as before.)
    wo.seed_finer_if_no_facet = wo.seed_finer_if_no_facet && !only && !capped_parts().parts;
    if (opt.hollow_winding_solid && !only) {
      wo.hollow_cell = opt.hollow_cell;
      wo.hollow_depth = opt.hollow_depth * opt.max_deviation;
    }
    wo.facet_distance = opt.winding_facet_distance * opt.max_deviation;
    wo.dilation = dilation * opt.max_deviation;
    // The dilation adds about its width times the solid's surface area: where that is over twice
    // the growth allowed below (thin walls: a mug 4 mm thick, 0.18 m across, at 0.3 of the bound:
    // 25.7 % estimated, 24.8 % measured), the first solid is made at the dilation and facet
    // distance that should just keep within it, to no less than 0.3 of them, rather than grown
    // first and made again twice (meshing version 31: the mug at 1,000, three Mesh_3 runs of about
    // 5 s each before). The area is the input's faces' that face out of the solid (winding number
    // below ½ just outside them): faces inside other parts or between welded segments add
    // nothing (the lungs: 10.1-10.4 % by all of their faces, under 8 % so). Only at twice the
    // allowance, since the estimate can be far over: trimesh's cycloidal.ply, 119 parts with
    // sharp edges, 15.2 %, and its solid grew under 8 % (made at 0.53 of the dilation, it took
    // 79 s instead of 38). The input's own signed volume stands for its winding-number volume
    // here (computed beside Mesh_3 below).
    const bool fine_target = opt.tetrahedralize.target_tets >= 1000;
    const double allowed_growth = allowed_solid_growth(opt.tetrahedralize.target_tets);
    if (r.info.closed && !only && opt.estimate_winding_growth) {
      const double v = signed_volume(r.input), width = wo.dilation * diag;
      // (By all of the faces first: that bounds it, and the winding numbers are needed only above.)
      double predicted = v > 0 ? area(r.input) * width / v : 0.0;
      if (predicted > 2 * allowed_growth) {
        Eigen::VectorXd outside;
        const Eigen::VectorXd face_area =
            face_offset_winding_numbers(FastWindingNumber(r.input.V, r.input.F), r.input.V, r.input.F, 0.1 * width, &outside, nullptr);
        predicted = 0;  // (summed in face order: deterministic)
        for (Eigen::Index f = 0; f < r.input.F.rows(); ++f)
          if (outside(f) < 0.5) predicted += face_area(f);
        predicted *= width / v;
      }
      if (predicted > 2 * allowed_growth) {
        const double shrink = std::max(0.3, allowed_growth / predicted);
        wo.facet_distance *= shrink;
        wo.dilation *= shrink;
        spdlog::debug("winding-number surface: its dilation would add about {:.1f} % to the input's volume; made with "
                      "the dilation and facet distance × {:.2f}", 100.0 * predicted, shrink);
      }
    }
    // The input's volume (its winding number's, a parallel loop) beside Mesh_3 (one thread).
    tbb::task_group volume_task;
    volume_task.run([&] { r.input_volume = input_winding_volume(); });
    SurfaceMesh solid;
    try {
      solid = winding_number_surface(source.V, source.F, wo, &r.winding_stats);
      r.winding_solids = 1;
    } catch (...) {
      volume_task.wait();
      throw;
    }
    volume_task.wait();
    r.info.volume = r.input_volume;
    // At 1,000 tetrahedra and more, where the issue's volume bound on closed inputs is
    // [0.95, 1.1]: a solid the dilation grew by more than 8 % (the liver: 12.6 %, so 1.116 after
    // simplification) is made again with the dilation and the facet distance scaled down in
    // proportion, to no less than 0.4 of them a round (a part's own solid: MeshOptions::solid_min_scale).
    // Below 1,000 tetrahedra (bound [0.9, 1.2]), one grown by more than 15 % (meshing version 30:
    // a mug whose handle, a tube twisted so that it intersects itself, grew 25 %: 1.248). Again,
    // up to three rounds in all, while still over halfway from there to the bound (9 %, 17.5 %;
    // version 30): the growth falls slower than the dilation on thin parts (five linked tori,
    // tubes 16 mm across in a chain 0.41 m long, at 1,000: 19.2 %, then 12.1 % at 0.42 and 8.9 %
    // at 0.28 of the dilation, so 1.089 after simplification, not 1.121), and rounds below that
    // line only add faces (the liver at 1,000: 9.7 %, 8.4 %, then 8.1 % and 8.0 % in 6 s more).
    const double source_volume = only ? winding_volume(only->V, only->F) : r.input_volume;
    if (r.info.closed && source_volume > 0 && solid.F.rows() > 0) {
      const double again = fine_target ? 0.09 : 0.175;
      for (int round = 0; round < 3; ++round) {
        const double growth = signed_volume(solid) / source_volume - 1.0;
        if (!(growth > (round == 0 ? allowed_growth : again))) break;
        const double shrink = std::max(0.4, allowed_growth / growth);
        wo.facet_distance *= shrink;
        wo.dilation *= shrink;
        spdlog::debug("winding-number surface: {:.1f} % over the input's volume; again with the dilation and facet "
                      "distance × {:.2f}", 100.0 * growth, shrink);
        WindingTetrahedralizeStats finer_stats;
        SurfaceMesh finer = winding_number_surface(source.V, source.F, wo, &finer_stats);
        ++r.winding_solids;
        if (finer.F.rows() == 0) break;  // (the last solid found kept, and its figures in the report)
        solid = std::move(finer);
        r.winding_stats = finer_stats;
      }
    }
    auto mesh3 = [&](const std::string& because) {
      if (only) {  // (the caller meshes the whole input's solid instead)
        MeshResult whole;
        whole.method = kWholeSolid;
        whole.fallback_because = because;
        return whole;
      }
      auto tetrahedra = [&](const std::string& w) {
        spdlog::info("meshing the winding-number solid by Mesh_3 as it is: {}", w);
        return winding_route(why + "; its boundary " + w);
      };
      if (std::optional<MeshResult> c = capped_route(why + "; its winding-number solid's boundary " + because,
                                                     [&](const std::string& w) { return tetrahedra(because + "; capped, " + w); }))
        return std::move(*c);
      return tetrahedra(because);
    };
    // No solid at all (triangles welded into a fan, say: no volume, and not open sheets either):
    // the convex shells of a flat input took minutes to grow a blob around it. (Judged, as before
    // version 40, by the winding-number volume with its cones from the origin: 0 for a fan through
    // the origin. From the bounding box's centre a fan has some, and so do its faces anywhere else:
    // moved 5 m away, the fan goes to convex shells, as it did. The decomposition's interior
    // voxels are none for a rod 4 mm across too, so they cannot tell either. The volume from the
    // origin is the one from the centre moved by the jump-weighted area: no second pass.)
    auto from_origin = [&] {
      const Eigen::RowVector3d centre = 0.5 * (r.input.V.colwise().minCoeff() + r.input.V.colwise().maxCoeff());
      return input_winding_volume() + centre.dot(input_jump_area);
    };
    if (solid.F.rows() == 0 && !(std::abs(from_origin()) > 1e-9 * diag * diag * diag))
      throw InputError("the surface encloses no volume (winding number above 1/2 nowhere) and is not open sheets "
                       "(one layer of triangles, each sheet on its own: these are welded to each other)");
    int bad;
    std::vector<Part> pieces = closed_components(solid, [](double v) { return v != 0; }, &bad);
    const int n = static_cast<int>(pieces.size());
    if (n == 0) return mesh3("was not found by Mesh_3");
    if (bad >= 0)
      return mesh3("(component " + std::to_string(bad + 1) + " of " + std::to_string(n) +
                   ") is not a closed oriented 2-manifold enclosing volume");
    for (Part& p : pieces) {
      p.target = &source;
      spdlog::debug("winding-number surface component {}: {} faces, volume {:.4g}", p.component, p.surface.F.rows(), p.volume);
    }
    // A component facing inward (negative volume) bounds a void of the solid (winding number
    // below ½ inside it) within the smallest outward component around it: a cavity of that part
    // (as the boundary route takes a hollow part), or filled where under 1 % of the part's volume
    // (the liver's winding-number solid has a void of 0.03 %: 112 faces that would hold as many
    // tetrahedra, and a solid organ there is what the file means).
    std::vector<Part> parts;
    for (const Part& p : pieces)
      if (p.volume > 0) parts.push_back(p);
    if (parts.empty()) return mesh3("encloses no volume");
    int filled = 0;
    for (int c = 0; c < n; ++c) {
      const Part& cavity = pieces[static_cast<size_t>(c)];
      if (cavity.volume > 0) continue;
      const Eigen::RowVector3d probe = cavity.surface.V.row(0);
      int container = -1;
      for (size_t i = 0; i < parts.size(); ++i) {
        if (container >= 0 && parts[i].volume >= parts[static_cast<size_t>(container)].volume) continue;
        if (FastWindingNumber(parts[i].surface.V, parts[i].surface.F)(probe) > 0.5) container = static_cast<int>(i);
      }
      if (container < 0) return mesh3("has an inward component inside no outward one");
      Part& outer = parts[static_cast<size_t>(container)];
      if (-cavity.volume < 0.01 * outer.volume) {
        ++filled;
        continue;
      }
      outer.surface = concatenate(std::vector<SurfaceMesh>{outer.surface, cavity.surface}, &SurfaceMesh::F);
      outer.volume += cavity.volume;
      ++r.cavities;
    }
    if (filled > 0) spdlog::debug("winding-number surface: {} voids under 1 % of their part's volume filled", filled);
    spdlog::debug("winding-number surface: {} faces, {} components", solid.F.rows(), n);
    timer.stop();
    if (beside) {  // the closed parts first, in the input's order, then the solid's
      for (Part& p : parts) beside->push_back(std::move(p));
      parts = std::move(*beside);
    }
    MeshResult b = boundary_route(parts, eopt, true, [&](const std::string& w) { return mesh3("could not be meshed: " + w); });
    if (b.method != "winding_number_boundary") return b;
    if (only) {  // the input's volume as its parts': the closed ones' own (overlaps counted, as the
                 // boundary route counts them) and the others' winding-number solid's
      b.input_volume = source_volume;
      for (const Part& p : parts)
        if (p.beside_solid) b.input_volume += p.volume;
      b.info.volume = b.input_volume;
      b.volume_ratio.reset();
      if (b.info.closed && b.input_volume > 0) b.volume_ratio = b.quality.volume / b.input_volume;
    }
    std::string worse;
    if (!b.tet_stats.conforming) worse = "was not tetrahedralized conforming";
    else if (b.quality.min_dihedral < opt.tetrahedralize.min_dihedral) worse = "keeps a dihedral angle below the floor";
    if (worse.empty()) return b;
    r = std::move(b);
    return mesh3(worse);
  };
  // The convex shells, as asked (MeshOptions::shells_only, or shells_fallback for inputs that are
  // not closed parts), where Mesh_3 can mesh them so that they hold the input. Where it cannot (a
  // part thinner than its cells: a 1 m rod of 3 mm radius at 150 gave 24 tetrahedra around its
  // middle, 3.6 times its volume, a diagonal off it), the default route meshes the input instead:
  // a mesh around it, as asked, only not its convex shells. `asked`: the option, for the report;
  // `own`: the options of the default route.
  auto shells_where_they_hold = [&](const std::string& why, const std::string& asked, const MeshOptions& own) {
    MeshResult shells = shells_route(why);
    // Nor where its volume is far below the input's: Mesh_3's facets are chords of the shells, and
    // across a thin part they cut it away (the same rod at 1000: 0.73 of its volume).
    // Nor where it is far larger than the shells themselves: dilated to hold points Mesh_3 had
    // missed (a disc 0.2 m across and 1 mm thick, one convex shell: 15,000 times its volume).
    double hulls = 0;
    for (const ConvexShell& c : shells.decomposition.shells) hulls += c.hull.volume;
    spdlog::debug("convex shells: {} shells of {:.4g} in all, their mesh {:.4g}", shells.decomposition.shells.size(), hulls,
                  shells.quality.volume);
    const bool holds = shells.shell_stats.covered >= 0.999;
    const bool encloses = !shells.volume_ratio || *shells.volume_ratio >= 0.8;
    const bool bounded = !(hulls > 0 && shells.quality.volume > 3.0 * hulls);
    if (holds && encloses && bounded) return shells;
    const std::string short_of =
        !holds      ? "held " + percent(shells.shell_stats.covered) + " of the input's vertices"
        : !encloses ? "had " + percent(*shells.volume_ratio) + " of the input's volume"
                    : "was " + std::to_string(static_cast<long>(std::lround(shells.quality.volume / hulls))) +
                          " times the shells' volume";
    spdlog::warn("the convex shells' Mesh_3 mesh {}: meshing the input by the default route instead", short_of);
    MeshResult d = mesh_surface_once(surface, own, progress, &shells.decomposition);
    after_earlier_try(d, shells);
    const std::string because = "the convex shells were asked for, but their Mesh_3 mesh " + short_of + " (" + asked + ")";
    d.fallback_because = d.fallback_because.empty() ? because : because + "; " + d.fallback_because;
    return d;
  };
  if (opt.shells_only) {
    MeshOptions own = opt;
    own.shells_only = false;
    return shells_where_they_hold("the convex shells were asked for (MeshOptions::shells_only)", "--shells-only", own);
  }
  // The parts: each face-connected component of the input that is a closed oriented 2-manifold
  // enclosing volume bounds its own solid and is its own boundary (when it intersects itself, only
  // if its simplified boundary no longer does: slivers of zero area, say, collapse away). Parts are
  // meshed one by one, so touching or overlapping parts stay as the input has them. Where a
  // component is not such a part (open, non-manifold, welded to another), the whole input takes the
  // fallback: its convex shells meshed with Mesh_3 (shells_route above).
  timer.start("boundary");
  std::vector<Part> parts;
  std::vector<int> candidates;  // components that are not parts (sheets, open scans, or the fallback)
  const std::vector<std::vector<int>> faces = faces_by_component(component_of, components);
  std::vector<int> cavity_of(static_cast<size_t>(components), -1);  // the part a component is a cavity of
  {
    std::vector<Part> component(static_cast<size_t>(components));
    std::vector<char> usable(static_cast<size_t>(components), 0);
    tbb::parallel_for(0, components, [&](int c) {
      tbb::this_task_arena::isolate([&] {
        Part& p = component[static_cast<size_t>(c)];
        p.surface = sub_mesh(r.input, faces[static_cast<size_t>(c)]);
        const SurfaceMesh& m = p.surface;
        const bool closed = is_closed(m.F), manifold = is_oriented_two_manifold(m.F, static_cast<int>(m.V.rows()));
        p.volume = signed_volume(m);
        // Enclosing volume: a mean thickness (3 volume / area) above a millionth of the diagonal
        // (a face and its twin, say, enclose none).
        usable[static_cast<size_t>(c)] = closed && manifold && 3.0 * p.volume > 1e-6 * diag * area(m);
        p.check = usable[static_cast<size_t>(c)] && does_self_intersect(m);
        spdlog::debug("component {}: {} faces, closed {}, oriented 2-manifold {}, volume {:.4g}, self-intersecting {}", c,
                      m.F.rows(), closed, manifold, p.volume, p.check);
      });
    });
    // Cavities: a closed component that the file orients inward, all its faces facing into it, and
    // that lies inside another closed component, is a cavity of that one (a hollow ball given as
    // its outer and inner shells): the two bound one solid, the space between them, as the winding
    // number of the file's faces says (1 between, 1 - 1 = 0 inside the inner shell). Its faces join
    // that part, facing into the cavity (tetrahedralize() and Mesh_3's winding number both take
    // nested components as the boundary of the space between). Before, the inner shell became a
    // solid of its own, overlapping the other (a hollow ball meshed as a full ball and a second one
    // inside it). Components the file orients outward, or inconsistently, stay parts of their own.
    {
      std::vector<int> inward;
      for (int c = 0; c < components; ++c) {
        if (!usable[static_cast<size_t>(c)]) continue;
        bool all = true;
        for (int f : faces[static_cast<size_t>(c)]) all = all && r.input.F.row(f) != given.row(f);
        if (all) inward.push_back(c);
      }
      std::vector<std::unique_ptr<FastWindingNumber>> winding(static_cast<size_t>(components));
      for (int c : inward) {
        const Eigen::RowVector3d probe = component[static_cast<size_t>(c)].surface.V.row(0);
        int container = -1;
        for (int d = 0; d < components; ++d) {
          if (d == c || !usable[static_cast<size_t>(d)] || std::find(inward.begin(), inward.end(), d) != inward.end()) continue;
          const Part& o = component[static_cast<size_t>(d)];
          if (!(o.volume > component[static_cast<size_t>(c)].volume)) continue;
          if (container >= 0 && o.volume >= component[static_cast<size_t>(container)].volume) continue;
          auto& w = winding[static_cast<size_t>(d)];
          if (!w) w = std::make_unique<FastWindingNumber>(o.surface.V, o.surface.F);
          if ((*w)(probe) > 0.5) container = d;
        }
        cavity_of[static_cast<size_t>(c)] = container;
      }
    }
    for (int c = 0; c < components; ++c) {
      const int d = cavity_of[static_cast<size_t>(c)];
      if (d < 0) continue;
      Part& outer = component[static_cast<size_t>(d)];
      const Part& cavity = component[static_cast<size_t>(c)];
      spdlog::info("component {} lies inside component {} and faces into itself: a cavity of it", c, d);
      SurfaceMesh inner = cavity.surface;
      inner.F.col(1).swap(inner.F.col(2));  // facing into the cavity
      outer.surface = concatenate(std::vector<SurfaceMesh>{outer.surface, inner}, &SurfaceMesh::F);
      outer.volume -= cavity.volume;
      outer.check = outer.check || cavity.check || does_self_intersect(outer.surface);
      ++r.cavities;
    }
    for (int c = 0; c < components; ++c) {
      if (cavity_of[static_cast<size_t>(c)] >= 0) continue;
      if (usable[static_cast<size_t>(c)]) {
        component[static_cast<size_t>(c)].component = c;
        parts.push_back(std::move(component[static_cast<size_t>(c)]));
      } else {
        candidates.push_back(c);
      }
    }
  }
  int unusable = static_cast<int>(candidates.size());
  // Open sheets (a curtain, a cloth given as one layer of triangles): components that are open
  // oriented 2-manifolds, not welded to others, with a winding number of about ½ on both sides
  // over most of their area (sheet.h). When every component that is not a part is such a sheet,
  // each becomes a part: the slab of sheet_thickness around it (the sheet in its middle), meshed
  // by the boundary route like any closed part. Otherwise (an open scan of a solid, welded or
  // non-manifold segments) the fallback below, as before.
  if (unusable > 0) {
    // Edges in three or more faces of the whole input (a sheet welded to something).
    std::vector<std::uint64_t> keys;
    keys.reserve(static_cast<size_t>(3 * r.input.F.rows()));
    for (Eigen::Index f = 0; f < r.input.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t a = static_cast<std::uint32_t>(r.input.F(f, k)), b = static_cast<std::uint32_t>(r.input.F(f, (k + 1) % 3));
        keys.push_back(std::min(a, b) << 32 | std::max(a, b));
      }
    std::sort(keys.begin(), keys.end());
    auto welded = [&](const SurfaceMesh& m, const std::vector<int>& index) {  // index: m's vertices in r.input
      for (Eigen::Index f = 0; f < m.F.rows(); ++f)
        for (int k = 0; k < 3; ++k) {
          const std::uint64_t a = static_cast<std::uint32_t>(index[static_cast<size_t>(m.F(f, k))]),
                              b = static_cast<std::uint32_t>(index[static_cast<size_t>(m.F(f, (k + 1) % 3))]);
          const std::uint64_t key = std::min(a, b) << 32 | std::max(a, b);
          if (std::upper_bound(keys.begin(), keys.end(), key) - std::lower_bound(keys.begin(), keys.end(), key) > 2) return true;
        }
      return false;
    };
    std::vector<Part> sheets(candidates.size());
    std::atomic<int> others{0}, scans{0};  // components neither closed parts nor sheets; open scans among them
    const double h = 0.5 * opt.sheet_thickness * opt.max_deviation * diag;
    tbb::parallel_for(size_t(0), candidates.size(), [&](size_t i) {
      tbb::this_task_arena::isolate([&] {
        if (others > 0) return;
        std::vector<int> index;
        SurfaceMesh m = sub_mesh(r.input, faces[static_cast<size_t>(candidates[i])], &index);
        if (const int split = split_bow_ties(m, &index))  // (holes that touch at a vertex)
          spdlog::debug("component {}: {} bow-tie vertex cop{} split off", candidates[i], split, split == 1 ? "y" : "ies");
        const SheetEvidence ev = sheet_evidence(m.V, m.F);
        spdlog::debug("component {}: open 2-manifold {}, sheet-like winding numbers over {:.1f}% of its area", candidates[i],
                      ev.open_manifold, 100.0 * ev.sheet_area_fraction);
        if (!ev.open_manifold || welded(m, index)) {
          ++others;
          return;
        }
        if (!is_sheet(ev) && !opt.open_scans_as_sheets) {  // an open scan of a solid: holes, its winding number inside and outside
          ++scans;
          return;
        }
        Part& p = sheets[i];
        p.component = candidates[i];
        p.scan = !is_sheet(ev);
        p.surface = thicken_sheet(m, h);
        p.sheet = m;
        p.volume = signed_volume(p.surface);
        p.offset = h;
        if (!(p.volume > 0)) ++others;
      });
    });
    if (others == 0 && scans == 0) {
      spdlog::info("{} open sheet{} of the input {} meshed as slabs {:.3g} thick (--sheet-thickness)", sheets.size(),
                   sheets.size() == 1 ? "" : "s", sheets.size() == 1 ? "is" : "are", 2 * h);
      r.sheets = static_cast<int>(sheets.size());
      for (const Part& p : sheets) r.scan_sheets += p.scan ? 1 : 0;
      r.sheet_thickness = 2 * h;
      for (Part& p : sheets) parts.push_back(std::move(p));
      std::sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) { return a.component < b.component; });
      unusable = 0;
    } else if (others == 0 && scans > 0 && !opt.wrap) {
      // Open scans of solids (a scan with holes, not welded to anything): the solid their winding
      // number encloses, holes closed (meshing version 8: Mesh_3's tetrahedra of it; before, the
      // convex shells: the dragon 3.8-10.9 % of the diagonal out; version 11: its boundary
      // simplified against the scan, as for welded segments below, whatever --shells-fallback).
      // With open sheets beside them (a scan's stray triangle, left alone where holes were cut
      // around it: a sheet of one face), the same, so that the slab is tried after the solid
      // (mesh_surface_near_origin) for all of them (meshing version 31; before, such an input
      // took the welded segments' fallback below, and its slab was never tried: the bunny with
      // six holes 4 % of its diagonal across, 3.6 % of the diagonal out at every target).
      const int open_sheets = static_cast<int>(candidates.size()) - scans;
      const std::string why = std::to_string(scans.load()) + " of the input's " + std::to_string(components) +
                              " components are " + kOpenScans + " (holes, not welded to other components)" +
                              (open_sheets > 0 ? ", " + std::to_string(open_sheets) + " open sheet" +
                                                     (open_sheets == 1 ? "" : "s")
                                               : std::string());
      // Their hole rims are creases of the solid that Mesh_3's facets cut: the larger dilation
      // (at 0.3 an elephant with holes 1-3 % of the diagonal wide had 0.50-0.67 % in, at 0.45
      // 0.43-0.45 %).
      return opt.winding ? winding_route(why) : winding_boundary_route(why, opt.winding_dilation);
    }
  }
  // The route for inputs that are not closed parts, and where the boundary route fails.
  const std::function<MeshResult(const std::string&)> fallback =
      opt.wrap      ? std::function<MeshResult(const std::string&)>(wrap_route)
      : opt.winding ? std::function<MeshResult(const std::string&)>(winding_route)
      : opt.shells_fallback ? std::function<MeshResult(const std::string&)>([&](const std::string& why) {
                        // (since meshing version 17: before, the shells were kept whatever they held)
                        MeshOptions own = opt;
                        own.shells_fallback = false;
                        return shells_where_they_hold(why, "--shells-fallback", own);
                      })
                    : std::function<MeshResult(const std::string&)>([&](const std::string& why) {
                        return winding_boundary_route(why, opt.winding_surface_dilation);
                      });
  // Closed parts beside the components that are not (meshing version 35): a many-part model with
  // a stray non-manifold fin or a sheet welded to itself took the whole model to its winding-number
  // solid (twelve crossing boards, each a closed part, beside a fin of three triangles on one edge:
  // 1.59 times their volume, 0.77 % of the diagonal in, Mesh_3 finding no surface from their
  // corners). Only the others' solid now, beside the closed parts meshed as they are; where that
  // solid cannot be meshed, the whole input's, as before.
  const std::string not_parts = std::to_string(unusable) + " of the input's " + std::to_string(components) +
                                " components are not closed, oriented 2-manifolds enclosing volume (open, "
                                "non-manifold, or welded to other components)";
  if (unusable > 0 && !parts.empty() && opt.closed_parts_beside_solid && !opt.wrap && !opt.winding &&
      !opt.shells_fallback) {
    std::vector<int> rest_faces;
    for (int c : candidates)
      rest_faces.insert(rest_faces.end(), faces[static_cast<size_t>(c)].begin(), faces[static_cast<size_t>(c)].end());
    std::sort(rest_faces.begin(), rest_faces.end());
    const SurfaceMesh rest = sub_mesh(r.input, rest_faces);
    const bool self_intersecting = std::any_of(parts.begin(), parts.end(), [](const Part& p) { return p.check; });
    // Only stray components, under a tenth of the input's area, beside closed parts that do not
    // intersect themselves: where the others are much of it (an organ of welded segments: the
    // left lung's 11 of 16, 3,140 tetrahedra, 0.49 % of the diagonal in, 2,698 and 0.44 % as one
    // solid) or a closed part may fail on its own (trimesh's chair, its self-intersecting
    // frame with the two stray components' solid: 7,687 tetrahedra and 16 s, 4,002 and 9 s as
    // one solid), one solid holds the bounds better.
    if (!self_intersecting && area(rest) < kStrayAreaShare * area(r.input)) {
      decomposition();  // (waited for: `r` is copied, to be restored where this try is not kept)
      const MeshResult before = r;
      // (`parts` is not used again: the whole input's solid below, where this try is not kept.)
      std::vector<Part> beside = std::move(parts);
      for (Part& p : beside) p.beside_solid = true;
      MeshResult m = winding_boundary_route(not_parts, opt.winding_surface_dilation, &rest, &beside);
      if (m.method != kWholeSolid) return m;
      spdlog::info("the solid of the components that are not closed parts {}: meshing the whole input's solid instead",
                   m.fallback_because);
      std::vector<std::pair<std::string, double>> seconds = std::move(r.seconds);  // (the try's stages kept)
      r = before;
      r.seconds = std::move(seconds);
    }
  }
  if (unusable > 0) return fallback(not_parts);
  if (parts.empty()) throw InputError("the surface encloses no volume (winding number above 1/2 nowhere)");
  return boundary_route(parts, eopt, false, fallback);

}

// mesh_surface for an input near the origin (see below).
MeshResult mesh_surface_near_origin(const SurfaceMesh& surface, const MeshOptions& opt, Progress* progress) {
  // An open scan meshed as a solid closes its holes: a hole wider than the outer bound leaves its
  // cap that far from the input (a tube open at both ends, 10 cm across and 40 cm long: 11.7 % of
  // the diagonal), and no solid can do better (a surface spanning the hole's rim within the bound
  // of the scan runs along the whole scan: a slab). Its slab (sheet.h: the surface thickened by the
  // sheet thickness, as an open sheet) is tried instead and kept where it holds every bound. Where
  // the caps lie more than 1.5 times the bound (max_deviation) off: the outer bound that the
  // boundary route's own dilation and chords keep within (meshing version 15; version 14: three
  // times, since a detailed scan's slab, remeshed to equal triangles, folded over itself or took
  // 15,000-130,000 tetrahedra in 30-50 s; simplify_sheet now grades it).
  const double diag = surface.V.rows() > 0 && surface.V.allFinite() ? bounding_box_diagonal(surface.V) : 0.0;
  const double trigger = 1.5 * opt.max_deviation * diag;
  // (Not where a route was asked for: --winding, --wrap, --shells-fallback, --shells-only.)
  const bool routes_free = !(opt.open_scans_as_sheets || opt.shells_only || opt.winding || opt.wrap || opt.shells_fallback) &&
                           diag > 0;
  // Whether the slab s holds every bound; r: the solid it is tried against (its components).
  auto holds = [&](const MeshResult& s, int components, double inner_share) {
    const bool ok = s.sheets > 0 && s.deviation_out <= opt.max_deviation * diag &&
                    s.deviation_in <= inner_share * opt.max_deviation * diag &&
                    s.quality.min_dihedral >= opt.tetrahedralize.min_dihedral && s.tet_stats.conforming &&
                    s.quality.components == components;
    spdlog::debug("the open scan as a sheet: deviation out {:.3g} in {:.3g} (diagonal {:.3g}), {} tetrahedra, {} degrees, "
                  "conforming {}, {} components for {}: {}",
                  s.deviation_out, s.deviation_in, diag, s.quality.tets, s.quality.min_dihedral, s.tet_stats.conforming,
                  s.quality.components, components, ok ? "kept" : "not kept");
    return ok;
  };
  auto as_sheet = [&](MeshResult& s, double cap, bool estimated) {
    spdlog::info("the input's holes are wider than the deviation bound (as a solid, its caps over them {} {} of the "
                 "diagonal off it): meshed as a sheet, a slab {:.3g} thick",
                 estimated ? "would lie about" : "lie", percent(cap / diag), opt.sheet_thickness * opt.max_deviation * diag);
    const std::string why = "its holes are wider than the deviation bound: as a solid, the caps over them " +
                            std::string(estimated ? "would lie about " : "lay ") + percent(cap / diag) +
                            " of the diagonal off the input; meshed as an open sheet";
    s.fallback_because = s.fallback_because.empty() ? why : why + "; " + s.fallback_because;
  };
  MeshOptions o = opt;
  o.open_scans_as_sheets = true;
  // A winding-number solid whose caps over holes lie over 1.5 times the bound off the input (welded
  // segments, whose slab is never made; an open scan whose slab does not hold): made again hollowed
  // where the outside reaches in through the holes (WindingTetrahedralizeOptions::hollow_cell), a
  // shell around the holes' rims instead of caps over them; kept where it lies nearer the input,
  // no farther inside than the capped solid or within the inner bound, with the same components,
  // conforming and above the dihedral floor (meshing version 36).
  const bool hollowing = routes_free && opt.hollow_where_caps_lie_far && !opt.hollow_winding_solid;
  auto hollowed = [&](const Decomposition* d, Progress* p) -> std::optional<MeshResult> {
    MeshOptions h = opt;
    h.hollow_winding_solid = true;
    try {
      return mesh_surface_once(surface, h, p, d);
    } catch (const InputError& e) {
      spdlog::debug("the hollowed solid: {}", e.what());
      return std::nullopt;
    }
  };
  // (`made`: the hollowed solid, where hollow_first made it before the capped one `r`; its seconds
  // then go first in r's where r is kept.)
  auto hollowed_if_nearer = [&](MeshResult r, std::optional<MeshResult> made = std::nullopt) -> MeshResult {
    const bool made_before = made.has_value();
    auto capped_kept = [&]() {
      if (made_before) after_earlier_try(r, *made);
      return std::move(r);
    };
    if (!hollowing || r.method != "winding_number_boundary" || !winding_solid_of_open_input(r) || !(r.deviation_out > trigger))
      return capped_kept();
    if (!made) made = hollowed(r.decomposition.shells.empty() ? nullptr : &r.decomposition, nullptr);
    if (!made) return r;
    const MeshResult& h = *made;
    const bool ok = h.method == "winding_number_boundary" && h.deviation_out < r.deviation_out &&
                    h.deviation_in <= std::max(r.deviation_in, opt.inner_deviation * opt.max_deviation * diag) &&
                    h.quality.min_dihedral >= opt.tetrahedralize.min_dihedral && h.tet_stats.conforming &&
                    h.quality.components == r.quality.components;
    spdlog::info("the input's solid hollowed where the outside reaches in through its holes: {} of the diagonal out and {} "
                 "in (capped: {} and {}), {} tetrahedra, {} components (capped: {}): {}",
                 percent(h.deviation_out / diag), percent(h.deviation_in / diag), percent(r.deviation_out / diag),
                 percent(r.deviation_in / diag), h.quality.tets, h.quality.components, r.quality.components,
                 ok ? "kept" : "not kept");
    if (!ok) return capped_kept();
    MeshResult s = std::move(*made);
    const std::string why = "its holes are wider than the deviation bound: as a solid, the caps over them lay " +
                            percent(r.deviation_out / diag) +
                            " of the diagonal off the input; hollowed where the outside reaches in through them";
    s.fallback_because = s.fallback_because.empty() ? why : why + "; " + s.fallback_because;
    after_earlier_try(s, r);
    return s;
  };
  // The hollowed solid first, where the holes' outlines say that the capped solid's caps would lie
  // over 1.5 times the bound off (`cap`, hole_cap_distance of the widest): kept where it holds the
  // bounds (the outer one as hollowed_if_nearer's trigger, the inner one up to
  // first_try_inner_deviation), conforming, above the dihedral floor
  // and one mesh per part of its solid; else the capped solid is made and compared with it as
  // before, without making it again (meshing version 38; before, the capped solid was always made
  // first: the left lung with holes 13.4-15.6 s, the heart with holes 32-45 s).
  auto hollow_first = [&](double cap, const Decomposition* d, std::optional<MeshResult>& made) -> bool {
    if (!hollowing || !opt.hollow_first || !(cap > trigger)) return false;
    made = hollowed(d, progress);
    if (!made) return false;
    const MeshResult& s = *made;
    const bool ok = s.method == "winding_number_boundary" && winding_solid_of_open_input(s) &&
                    s.winding_stats.hollow_depth > 0 && s.deviation_out <= trigger &&
                    s.deviation_in <= std::max(opt.inner_deviation, opt.first_try_inner_deviation) * opt.max_deviation * diag &&
                    s.quality.min_dihedral >= opt.tetrahedralize.min_dihedral && s.tet_stats.conforming &&
                    s.quality.components == s.parts;
    spdlog::info("the input's holes are wider than the deviation bound (as a solid, its caps over them would lie about {} of "
                 "the diagonal off it): its solid hollowed where the outside reaches in through them first: {} of the "
                 "diagonal out and {} in, {} tetrahedra, {} components for {} parts: {}",
                 percent(cap / diag), percent(s.deviation_out / diag), percent(s.deviation_in / diag), s.quality.tets,
                 s.quality.components, s.parts, ok ? "kept" : "the capped solid made too");
    if (!ok) return false;
    const std::string why = "its holes are wider than the deviation bound: as a solid, the caps over them would lie about " +
                            percent(cap / diag) + " of the diagonal off the input; hollowed where the outside reaches in through them";
    made->fallback_because = made->fallback_because.empty() ? why : why + "; " + made->fallback_because;
    return true;
  };
  // Open scans whose widest hole's cap (hole_caps.h: the largest circle inside a hole's outline)
  // would lie beyond that: the slab first, and the solid only where the slab does not hold (the
  // bunny with holes 2 % of its diagonal wide: 15.5 s, the solid and then the slab; the slab
  // alone, 10 s; meshing version 16).
  // (The input's faces without duplicates and flat ones, as mesh_surface_once cleans them: where
  // the slab or the hollowed solid may be tried first, the holes' outlines are judged on them.)
  const SurfaceMesh cleaned = routes_free && (opt.slab_first_for_wide_holes || (hollowing && opt.hollow_first))
                                  ? SurfaceMesh{surface.V, without_duplicate_and_flat_faces(surface.V, surface.F)}
                                  : SurfaceMesh{};
  if (routes_free && opt.slab_first_for_wide_holes) {
    // (Bow ties split first, as the components are judged: holes cut into a scan touch at a vertex
    // where they meet; meshing version 31.)
    SurfaceMesh c = cleaned;
    split_bow_ties(c);
    double cap = 0;
    if (is_open_two_manifold(c.F))
      for (const std::vector<int>& loop : boundary_loops(c.F)) cap = std::max(cap, hole_cap_distance(c.V, loop));
    if (cap > trigger) {
      spdlog::debug("the open scan's widest hole: a cap over it would lie {:.3g} from it ({} of the diagonal): its slab first",
                    cap, percent(cap / diag));
      MeshResult s;
      bool made = false;
      try {
        s = mesh_surface_once(surface, o, progress);
        made = true;
      } catch (const InputError& e) {
        spdlog::debug("the open scan as a sheet: {}", e.what());
      }
      // (Open sheets, a curtain, whose outline is the "hole": no scan among them, so that try was
      // the usual route, as it is.)
      if (made && s.scan_sheets == 0) return s;
      // (Up to first_try_inner_deviation inside: five vertebrae, two with holes cut, as slabs
      // beside the three closed ones 0.4515 % of the diagonal in, where the closed ones alone give
      // 0.455 % at 300; their solid, hollowed, 0.43 % in but one mesh of the five, in 14 s, not 2.)
      if (holds(s, s.parts, std::max(opt.inner_deviation, opt.first_try_inner_deviation))) {
        as_sheet(s, cap, true);
        return s;
      }
      // (No second try of the slab after the solid.)
      const Decomposition* d = s.decomposition.shells.empty() ? nullptr : &s.decomposition;
      std::optional<MeshResult> hollow;
      if (hollow_first(cap, d, hollow)) {
        after_earlier_try(*hollow, s);
        return std::move(*hollow);
      }
      MeshResult r = mesh_surface_once(surface, opt, progress, d);
      after_earlier_try(r, s);  // (the decomposition: the slab's try made it)
      return hollowed_if_nearer(std::move(r), std::move(hollow));
    }
  }
  // Segments welded to each other with holes (mostly_welded_segments): no slab is made of them,
  // and their solid caps the holes.
  std::optional<MeshResult> made;
  if (hollowing && opt.hollow_first && mostly_welded_segments(cleaned)) {
    double cap = 0;
    for (const std::vector<int>& loop : boundary_loops(cleaned.F)) cap = std::max(cap, hole_cap_distance(cleaned.V, loop));
    if (hollow_first(cap, nullptr, made)) return std::move(*made);
  }
  MeshResult r = mesh_surface_once(surface, opt, progress, made && !made->decomposition.shells.empty() ? &made->decomposition : nullptr);
  // (Only open scans: components that are open 2-manifolds, each on its own. Welded, non-manifold
  // or self-intersecting segments, a scanned dragon with holes, make no slab: no second try. The
  // sheet of their solid's boundary without its caps was tried in the eighteenth session: the
  // simplified boundary, 1,350 faces for the dragon, spans the rims too coarsely, 5.5 % in.)
  // (Also where the solid holds the outer bound but not the inner one: open scans beside closed
  // parts, the spinal cord's segments with holes cut through some, whose winding-number surface
  // Mesh_3 does not find and whose Mesh_3 solid is 0.86 % in; as slabs beside the closed parts,
  // within the bounds. Meshing version 34.)
  const bool capped = winding_solid_of_open_input(r) && r.fallback_because.find(kOpenScans) != std::string::npos &&
                      (r.deviation_out > trigger || r.deviation_in > opt.inner_deviation * opt.max_deviation * diag);
  if (!capped || !routes_free) return hollowed_if_nearer(std::move(r), std::move(made));
  MeshResult s;
  try {
    s = mesh_surface_once(surface, o, nullptr, r.decomposition.shells.empty() ? nullptr : &r.decomposition);
  } catch (const InputError& e) {
    spdlog::debug("the open scan as a sheet: {}", e.what());
    return hollowed_if_nearer(std::move(r), std::move(made));
  }
  // (One mesh per part meshed: per component of the input, each a slab. Not the solid's count of
  // components: a stray triangle beside a scan is one more slab, where the solid had swallowed it.)
  if (!holds(s, s.parts, opt.inner_deviation)) return hollowed_if_nearer(std::move(r), std::move(made));
  as_sheet(s, r.deviation_out, false);
  after_earlier_try(s, r);
  if (made) after_earlier_try(s, *made);
  return s;
}

// deviation_exceeded_because's sentence for deviation_in, where it is over 1.5 times the inner
// bound (meshing version 37; before, only deviation_out was explained).
std::string deviation_in_exceeded_because(const MeshResult& r, const MeshOptions& opt, double diag) {
  const double bound = opt.inner_deviation * opt.max_deviation;
  if (!(r.deviation_in > 1.5 * bound * diag)) return {};
  const std::string off = "input surface points lie up to " + percent(r.deviation_in / diag) +
                          " of the diagonal outside the mesh, over 1.5 times the inner bound (" + percent(bound) + ")";
  if (r.method == "winding_number_boundary" || winding_solid_of_open_input(r))
    return off + ": parts of the input whose winding number stays under 1/2 on both sides (a flap or a sheet "
                 "between holes, or inside the solid) are held only by the solid's dilation, a layer thinner than "
                 "Mesh_3's facets follow there; --wrap meshes its alpha wrap instead, around both sides of the input";
  return off;
}

// deviation_exceeded_because's sentence for deviation_out, where it is over 1.5 times the bound.
std::string outer_deviation_exceeded_because(const MeshResult& r, const MeshOptions& opt, double diag) {
  const std::string off = "up to " + percent(r.deviation_out / diag) +
                          " of the diagonal off the input, over 1.5 times --max-deviation (" + percent(opt.max_deviation) + ")";
  if (r.method == "convex_shells")
    return "the convex shells' mesh lies " + off + ": shells are as loose as the input is concave (the paper's method; " +
           "the default route keeps within the bound)";
  if (winding_solid_of_open_input(r) && r.winding_stats.hollow_depth > 0)
    return "the input's winding-number solid, hollowed where the outside reaches in through its holes, lies " + off +
           " (its shell, " + percent((r.winding_stats.dilation + r.winding_stats.hollow_depth) / diag) +
           " of the diagonal thick, is thinner than Mesh_3's facets follow everywhere); --wrap meshes its alpha wrap "
           "instead, a thin closed shell around both sides of the input, at many times the tetrahedra and seconds";
  if (winding_solid_of_open_input(r))
    return "the input's winding-number solid closes its holes, and its caps over holes wider than the bound lie " + off +
           " (a closed solid can do no better); no slab of the input within the bounds could be made (welded or "
           "overlapping segments have none, and an open scan's may fold over itself or leave slivers); --wrap meshes "
           "its alpha wrap instead, a thin closed shell that goes into holes wider than --wrap-alpha and around both "
           "sides of the input: far nearer to it, at many times the tetrahedra and seconds";
  return "the mesh's boundary lies " + off;
}

// mesh_surface for an input anywhere: moved to the origin where far from it, and meshed there by
// `near_origin` (a function of the moved surface: mesh_surface_near_origin, or the dense input's
// proxy route, whose decimation too needs the digits at the origin).
template <typename NearOrigin>
MeshResult mesh_surface_placed(const SurfaceMesh& surface, NearOrigin&& near_origin) {
  // An input far from the origin next to its size (the corpus bunny, 1.6 m across its diagonal,
  // moved to (1e5, -2e5, 3e5) m, as a model in world or survey coordinates is) keeps its details
  // in the last few digits of its coordinates: the predicates fall back to exact arithmetic and
  // the constructions round. At 300 it took 59 s and 3,107 tetrahedra (1.07 times its volume)
  // against 5 s and 1,864 at the origin (its coordinates written to 17 digits). It is meshed
  // moved to the origin (its bounding box's centre) and every result moved back: the same 1,864.
  if (surface.V.rows() > 0 && surface.V.allFinite()) {
    const Eigen::RowVector3d lo = surface.V.colwise().minCoeff(), hi = surface.V.colwise().maxCoeff();
    const Eigen::RowVector3d c = 0.5 * (lo + hi);
    if (c.norm() > 4.0 * (hi - lo).norm()) {
      spdlog::debug("the input lies {:.4g} from the origin, {:.3g} times its diagonal: meshed moved to the origin", c.norm(),
                    c.norm() / (hi - lo).norm());
      SurfaceMesh moved = surface;
      moved.V.rowwise() -= c;
      MeshResult r = near_origin(moved);
      auto back = [&](Eigen::MatrixX3d& V) {
        if (V.rows() > 0) V.rowwise() += c;
      };
      back(r.input.V);
      back(r.boundary.V);
      back(r.tets.V);
      for (ConvexShell& shell : r.decomposition.shells) {
        back(shell.hull.V);
        if (shell.hull.planes.rows() > 0) shell.hull.planes.col(3) += shell.hull.planes.leftCols<3>() * c.transpose();
      }
      return r;
    }
  }
  return near_origin(surface);
}

}  // namespace

// Why the mesh's boundary lies beyond 1.5 times the outer bound, or input surface points beyond
// 1.5 times the inner bound outside it, where either does (the report's
// deviation_exceeded_because); empty where neither does.
std::string deviation_exceeded_because(const MeshResult& r, const MeshOptions& opt) {
  const double diag = r.input.V.rows() > 0 ? bounding_box_diagonal(r.input.V) : 0.0;
  if (!(diag > 0)) return {};
  const std::string inner = deviation_in_exceeded_because(r, opt, diag);
  if (!(r.deviation_out > 1.5 * opt.max_deviation * diag)) return inner;
  return outer_deviation_exceeded_because(r, opt, diag) + (inner.empty() ? "" : "; " + inner);
}

namespace {
// mesh_surface for an input of over opt.dense_faces triangles (meshing version 49): a dense scan
// (the corpus bunny subdivided once, 301,632 faces, took 19-24 s at the default, 12-15 s of it in
// the envelope's edge collapses, about 25 µs each) is decimated by quadric error within
// dense_error of the inner bound (decimate_quadric: its vertices within that of the planes of the
// input faces they took in; topology, borders and seams kept) and the proxy meshed. The result's
// input, analysis, volume and measures are the input's: measured against it, not assumed. (The
// proxy's vertices lie within its error, a tenth of the inner bound, of the input's planes; the
// input's vertices can lie farther from the proxy, under chords: 1.73 times that on a many-part
// scan, docs/meshing.md, "Version 50".) The proxy is meshed with the bounds as asked: reduced by
// its error, the bunny took 2,334 tetrahedra at the default where its own surface takes 1,691
// (with the bounds as asked, 1,677, within them against the input); and where a route keeps its
// bound only to 1.5 times (the winding-number route), meshing again with reduced bounds doubled
// the seconds. Since version 54 from 30,000 triangles (a bust of 99,938 took 15-18 s, 8.6 s of it
// in the collapses; 6.3 s through its proxy), and only where the proxy has dense_min_saving fewer:
// a bumpy sphere of 20,480 faces, every vertex of which the bounds need, kept 20,380 in its proxy,
// took four times the seconds and lay 0.526 % of the diagonal in with it (0.482 % without).
MeshResult mesh_through_proxy(const SurfaceMesh& surface, const MeshOptions& opt, Progress* progress) {
  if (!(opt.dense_error >= 0 && opt.dense_error < 1)) throw InputError("MeshOptions::dense_error must be in [0, 1)");
  // (Bad inputs and options: the usual errors, from the usual route.)
  if (!surface.V.allFinite() || surface.V.rows() == 0 || !(opt.max_deviation > 0 && opt.max_deviation < 1) ||
      !(opt.inner_deviation > 0 && opt.inner_deviation <= 1))
    return mesh_surface_near_origin(surface, opt, progress);
  const double diag = bounding_box_diagonal(surface.V);
  if (!(diag > 0)) return mesh_surface_near_origin(surface, opt, progress);
  const auto t0 = std::chrono::steady_clock::now();
  if (progress) progress->stage("decimating the dense input");
  const double inner = opt.inner_deviation * opt.max_deviation, error = opt.dense_error * inner;  // (fractions)
  DecimateOptions d;
  d.max_error = error * diag;
  DecimateStats ds;
  const SurfaceMesh proxy = decimate_quadric(surface, d, &ds);
  if (progress) progress->finish();
  const double decimating = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (surface.F.rows() - ds.faces < opt.dense_min_saving) {
    spdlog::debug("dense input: {} faces decimated to {} in {:.2f} s, under {} fewer: the input itself meshed",
                  surface.F.rows(), ds.faces, decimating, opt.dense_min_saving);
    MeshResult r = mesh_surface_near_origin(surface, opt, progress);
    r.seconds.insert(r.seconds.begin(), {"decimating (proxy not kept)", decimating});
    return r;
  }
  spdlog::debug("dense input: {} faces decimated to {} ({} collapses, {} vertices kept where they are, largest error {:.3g} "
                "of the diagonal) in {:.2f} s: the proxy meshed",
                surface.F.rows(), ds.faces, ds.collapses, ds.frozen_vertices, ds.max_error / diag, decimating);
  // The input's own analysis, beside the proxy's meshing (in an arena of its own, as the
  // decomposition's: the meshing's CGAL random state stays its own).
  SurfaceMesh input;
  SurfaceInfo info;
  double input_volume = 0;
  tbb::task_arena analysing_arena;
  tbb::task_group analysing;
  analysing_arena.execute([&] {
    analysing.run([&] {
      input.V = surface.V;
      input.F = orient_outward(surface.V, without_duplicate_and_flat_faces(surface.V, surface.F));
      info = analyse_surface(input);
      info.self_intersecting = does_self_intersect(input);
      input_volume = signed_volume(input);
    });
  });
  MeshResult r;
  try {
    r = mesh_surface_near_origin(proxy, opt, progress);
  } catch (...) {
    arena_wait(analysing_arena, analysing);
    throw;
  }
  arena_wait(analysing_arena, analysing);
  // The proxy's result as the input's: a closed input's parts' volumes scaled by the two surfaces'
  // signed volumes (the same parts; an open surface's signed volume depends on the origin, and an
  // open input's winding-number volume is the proxy's, within its error); measured against the input.
  const auto t1 = std::chrono::steady_clock::now();
  const double proxy_volume = signed_volume(r.input);
  const double proxy_out = r.deviation_out, proxy_in = r.deviation_in;
  r.input = std::move(input);
  r.info = info;
  if (r.info.closed && proxy_volume != 0 && input_volume / proxy_volume > 0) r.input_volume *= input_volume / proxy_volume;
  // The shells, made of the proxy, hold the input's own vertices too (decompose.h's promise): the
  // corpus bunny's proxy's shells left 8,613 of its 37,706 vertices outside, by up to the proxy's
  // error (version 54).
  const int held = hold_points(r.decomposition, r.input.V, 1e-9 * diag);
  measure(r, opt);
  spdlog::debug("dense input: the mesh lies {} out, {} in of the proxy; {} out, {} in of the input; {} input vertices "
                "taken into the shells", percent(proxy_out / diag), percent(proxy_in / diag), percent(r.deviation_out / diag),
                percent(r.deviation_in / diag), held);
  r.proxy_faces = ds.faces;
  r.proxy_error = d.max_error;
  r.seconds.insert(r.seconds.begin(), {"decimating", decimating});
  r.seconds.emplace_back("measuring against the input", std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count());
  return r;
}
}  // namespace

MeshResult mesh_surface(const SurfaceMesh& surface, const MeshOptions& opt, Progress* progress) {
  if (opt.dense_faces < 0) throw InputError("--dense-faces must be at least 0 (0: never decimate)");
  if (opt.dense_min_saving < 0) throw InputError("--dense-min-saving must be at least 0");
  if (!(opt.inner_retry_deviation >= 0)) throw InputError("MeshOptions::inner_retry_deviation must be at least 0");
  if (!(opt.solid_first_thickness >= 0)) throw InputError("MeshOptions::solid_first_thickness must be at least 0");
  const auto t0 = std::chrono::steady_clock::now();
  auto run = [&](const MeshOptions& o) {
    return mesh_surface_placed(surface, [&](const SurfaceMesh& s) {
      return o.dense_faces > 0 && s.F.rows() > o.dense_faces ? mesh_through_proxy(s, o, progress)
                                                             : mesh_surface_near_origin(s, o, progress);
    });
  };
  MeshResult r = run(opt);
  // Input points over inner_retry_deviation × max_deviation outside the mesh: the envelope's samples
  // of the input are spaced by the inner bound, so points between them can lie past it (an urchin of
  // 20 spikes at 1000: 0.502 % of the diagonal, the inner bound 0.45 %). Meshed again with the inner
  // bound 0.85 times as large, kept where nearer and no worse otherwise (meshing version 51). Only
  // the routes whose boundary the envelope simplifies within that bound: Mesh_3's own tetrahedra
  // (--winding) and the convex shells would come out the same.
  const double diag = bounding_box_diagonal(surface.V);
  // (Nor a boundary route whose every part is its own winding-number solid: the solid does not use
  // the inner bound, and the boundary attempts before it, simplified again within the smaller
  // bound, held on none of the rows measured; a CAD part at 150 spent 29 s of its 63 meshing
  // again to the same solid after the same retries. Version 54.)
  const bool enveloped = (r.method == "boundary" && !(r.parts > 0 && r.parts_by_winding_number == r.parts)) ||
                         r.method == "winding_number_boundary" || r.method == "capped_boundary" || r.method == "alpha_wrap";
  if (opt.inner_retry_deviation > 0 && enveloped && r.deviation_in > opt.inner_retry_deviation * opt.max_deviation * diag) {
    MeshOptions o = opt;
    o.inner_deviation *= 0.85;
    spdlog::info("input points lie {:.3g} % of the diagonal outside the mesh: meshing again with the inner bound at "
                 "{:.3g} of --max-deviation", 100 * r.deviation_in / diag, o.inner_deviation);
    MeshResult again = run(o);
    const bool keep = again.tets.T.rows() > 0 && again.deviation_in < r.deviation_in &&
                      again.deviation_out <= std::max(r.deviation_out, 1.5 * opt.max_deviation * diag) &&
                      again.quality.components == r.quality.components &&
                      again.quality.min_dihedral >= std::min(r.quality.min_dihedral, opt.tetrahedralize.min_dihedral);
    spdlog::debug("meshed again at {:.3g} of --max-deviation inside: {:.3g} % of the diagonal in, {:.3g} % out, {} "
                  "tetrahedra: {}", o.inner_deviation, 100 * again.deviation_in / diag, 100 * again.deviation_out / diag,
                  again.tets.T.rows(), keep ? "kept" : "not kept");
    if (keep) r = std::move(again);
  }
  r.deviation_exceeded_because = deviation_exceeded_because(r, opt);
  // The wall time no stage above accounts for: tries whose results were not kept and whose stages
  // went with them (an open scan's slab that threw: 7 s of the ogre's 10 s were in no stage).
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double staged = 0;
  for (const auto& stage : r.seconds) staged += stage.second;
  if (wall - staged > 0.05) r.seconds.emplace_back("tries not kept", wall - staged);
  return r;
}

MeshResult mesh_file(const std::filesystem::path& path, const MeshOptions& opt, Progress* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (progress) progress->stage("loading " + path.filename().string());
  const SurfaceMesh s = load_surface(path);
  if (s.F.rows() > kMaxMeshTriangles)
    throw InputError(path.string() + ": " + std::to_string(s.F.rows()) + " triangles: squeeze mesh takes surfaces of up to " +
                     std::to_string(kMaxMeshTriangles) +
                     " (the simulation mesh is coarse anyway): decimate it first, e.g. Blender's Decimate modifier");
  const double load = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  MeshResult r;
  try {
    r = mesh_surface(s, opt, progress);
  } catch (const InputError& e) {  // what the surface is (no volume, ...): named by its file
    const std::string what = e.what(), name = path.string();
    if (what.compare(0, name.size(), name) == 0) throw;
    throw InputError(name + ": " + what);
  }
  r.seconds.insert(r.seconds.begin(), {"loading", load});
  return r;
}

SurfaceMesh shells_surface(const Decomposition& d) {
  Eigen::Index nv = 0, nf = 0;
  for (const auto& s : d.shells) nv += s.hull.V.rows(), nf += s.hull.F.rows();
  SurfaceMesh m;
  m.V.resize(nv, 3);
  m.F.resize(nf, 3);
  Eigen::Index v = 0, f = 0;
  for (const auto& s : d.shells) {
    m.V.middleRows(v, s.hull.V.rows()) = s.hull.V;
    m.F.middleRows(f, s.hull.F.rows()) = s.hull.F.array() + static_cast<int>(v);
    v += s.hull.V.rows();
    f += s.hull.F.rows();
  }
  return m;
}

nlohmann::json mesh_report(const MeshResult& r, const std::string& input_name) {
  using nlohmann::json;
  json seconds = json::object();
  double total = 0;
  for (const auto& [name, s] : r.seconds) {
    seconds[name] = seconds.value(name, 0.0) + s;  // a stage run twice (the fallback after the boundary route)
    total += s;
  }
  seconds["total"] = total;
  for (const auto& [name, s] : r.beside) seconds[name] = seconds.value(name, 0.0) + s;
  const double diag = bounding_box_diagonal(r.input.V);
  auto frac = [&](double x) { return diag > 0 ? x / diag : 0.0; };
  return json{
      {"deviation_out", frac(r.deviation_out)},
      {"deviation_in", frac(r.deviation_in)},
      {"volume_ratio", r.volume_ratio ? json(*r.volume_ratio) : json(nullptr)},
      {"target_tets", r.target_tets},
      {"sheets", r.sheets > 0 ? json{{"count", r.sheets}, {"thickness", frac(r.sheet_thickness)}} : json(nullptr)},
      {"thin_parts", r.thin_parts},
      {"method", r.method},
      {"fallback_because", r.fallback_because.empty() ? json(nullptr) : json(r.fallback_because)},
      {"alpha_wrap", r.wrap.used ? json{{"alpha", r.wrap.alpha},
                                        {"offset", r.wrap.offset},
                                        {"faces", r.wrap.faces},
                                        {"deviation", frac(r.wrap.deviation)}}
                                 : json(nullptr)},
      {"target_exceeded_because", r.target_exceeded_because.empty() ? json(nullptr) : json(r.target_exceeded_because)},
      {"proxy", r.proxy_faces > 0 ? json{{"faces", r.proxy_faces}, {"max_error", frac(r.proxy_error)}} : json(nullptr)},
      {"deviation_exceeded_because", r.deviation_exceeded_because.empty() ? json(nullptr) : json(r.deviation_exceeded_because)},
      {"input",
       {{"file", input_name},
        {"vertices", r.info.vertices},
        {"faces", r.info.faces},
        {"components", r.info.components},
        {"connected_parts", r.parts},
        {"closed", r.info.closed},
        {"boundary_edges", r.info.boundary_edges},
        {"nonmanifold_edges", r.info.nonmanifold_edges},
        {"self_intersecting", r.info.self_intersecting},
        {"bbox_diagonal", diag},
        {"volume", r.input_volume},
        {"volume_method", r.input_volume_from_winding_number ? "winding_number" : "divergence"}}},
      {"decomposition",
       {{"hulls", r.decomposition.shells.size()},
        {"max_concavity", r.decomposition.max_concavity},
        {"max_concavity_fraction", frac(r.decomposition.max_concavity)},
        {"concavity_threshold", r.decomposition.threshold},
        {"hit_max_hulls", r.decomposition.hit_max_hulls},
        {"hull_budget", r.hull_budget}}},
      {"boundary",
       {{"source", r.method == "boundary" ? json("input") : r.method == "alpha_wrap" ? json("alpha_wrap") : json(nullptr)},
        {"parts", r.parts},
        {"target_faces", r.boundary_target_faces},
        {"faces", r.boundary.F.rows()},
        {"collapses", r.envelope.collapses},
        {"retries", r.boundary_retries},
        {"parts_by_winding_number", r.parts_by_winding_number},
        {"parts_remeshed", r.parts_remeshed},
        {"cavities", r.cavities},
        {"stopped_by_deviation", r.envelope.bounded}}},
      {"tets",
       {{"tets", r.quality.tets},
        {"vertices", r.quality.vertices},
        {"min_dihedral_deg", r.quality.min_dihedral},
        {"max_dihedral_deg", r.quality.max_dihedral},
        {"min_tet_volume", r.quality.min_volume},
        {"min_edge", r.quality.min_edge},
        {"mean_edge", r.quality.mean_edge},
        {"min_edge_ratio", r.quality.mean_edge > 0 ? r.quality.min_edge / r.quality.mean_edge : 0.0},
        {"volume", r.quality.volume},
        {"volume_ratio", r.input_volume > 0 ? r.quality.volume / r.input_volume : 0.0},
        {"components", r.quality.components},
        {"faces_shared_by_more_than_two", r.quality.overshared_faces},
        {"attempts", r.tet_stats.attempts},
        {"edge_length", r.tet_stats.edge_length},
        {"boundary_splits", r.tet_stats.boundary_splits},
        {"steiner_points", r.tet_stats.steiner_points},
        {"conforming", r.tet_stats.conforming},
        {"peeled_slivers", r.method == "convex_shells" ? r.shell_stats.peeled_slivers : r.tet_stats.peeled},
        {"relocated_sliver_vertices", r.tet_stats.relocated},  // 0 unless tetrahedralize() meshed it
        {"flipped_slivers", r.tet_stats.flips},
        {"contracted_sliver_edges", r.tet_stats.contractions},
        {"exuder_nan_stops", r.tet_stats.exuder_nan_stops},
        {"exuder_pump_bounds", r.tet_stats.exuder_pump_bounds}}},
      {"winding_number",  // Mesh_3 of the winding-number solid: its tetrahedra, or its boundary's surface
       r.method == "winding_number" || r.method == "winding_number_boundary"
           ? json{{"attempts", r.winding_stats.attempts},
                  {"cell_size", r.winding_stats.cell_size},
                  {"facet_distance", frac(r.winding_stats.facet_distance)},
                  {"dilation", frac(r.winding_stats.dilation)},
                  {"hollow_depth", r.winding_stats.hollow_depth > 0 ? json(frac(r.winding_stats.hollow_depth)) : json(nullptr)},
                  {"seeds", r.winding_stats.seeds},
                  {"relocated", r.winding_stats.relocated},
                  {"flips", r.winding_stats.flips},
                  {"time_limit_reached", r.winding_stats.time_limit_reached},
                  {"solids", r.winding_solids}}
           : json(nullptr)},
      {"convex_shells",
       r.method == "convex_shells"
           ? json{{"attempts", r.shell_stats.attempts},
                  {"cell_size", r.shell_stats.cell_size},
                  {"offset", r.shell_stats.offset},
                  {"facet_distance", r.shell_stats.facet_distance},
                  {"covered", r.shell_stats.covered}}
           : json(nullptr)},
      {"coverage",
       {{"inside_fraction", r.inside_fraction},
        {"within_tolerance_fraction", r.covered_fraction},
        {"max_outside_distance", r.max_outside_distance},
        {"max_outside_distance_fraction", frac(r.max_outside_distance)},
        {"deviation_sample_spacing", r.deviation_sample_spacing}}},
      {"seconds", seconds}};
}

}  // namespace squeeze::meshing
