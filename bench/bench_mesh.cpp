// Benchmarks of `squeeze mesh` (issue 3); see bench/README.md for what each figure means.
//
//  BM_Mesh/<model>            the whole pipeline on a corpus model (load, analyse, decompose,
//                             tetrahedralize, measure) as `squeeze mesh MODEL` runs it without
//                             --target-tets, per-stage seconds as counters
//  BM_MeshTarget/<model>_<N>  the same with --target-tets N: tets, hulls, min dihedral, min/mean
//                             edge, volume ratio and coverage as counters
//  BM_TetrahedralizeVsTetgen  squeeze's tetrahedralization of the bunny's surface (the boundary
//                             version 4 meshes) against the Debian `tetgen` binary meshing the same
//                             surface (`tetgen -pq1.414 -Q bunny.off`), and their ratio
//  BM_RodPipeline/<N>, BM_RodWithoutSplit/<N>  a faceted 1 m by 3 mm rod (tests/shapes.h): the
//                             whole pipeline (version 14) against it with split_skinny off (13)
//  BM_ThinPlatePipeline/<N>, BM_ThinPlateWithoutPrisms/<N>  a closed 1 m plate 5 mm thick: the whole
//                             pipeline (version 15: one layer of prisms) against it with
//                             thin_parts_as_prisms off (version 14)
//  BM_ScanWithHolesSlabFirst/<N>, BM_ScanWithHolesSolidFirst/<N>  the bunny of tests/data with four
//                             holes of 2 % of its diagonal: its slab tried first, its widest hole's
//                             cap estimated from its outline (version 16), against the solid first
//                             and then the slab (slab_first_for_wide_holes off, version 15)
//  BM_LiverWithHoles/<hollow first>  the liver (segments welded to each other) with three holes of
//                             3 % of its diagonal, cut at the thirty-third session's centres, at
//                             300: its solid hollowed first by its holes' outlines (1, version 38)
//                             against the capped solid first and then the hollowed one (0, versions
//                             36-37); both end at the same mesh
//  BM_HeartShellsRelocated/<N>, BM_HeartShellsPerturbed/<N>  the heart's convex shells meshed by
//                             Mesh_3 (--shells-fallback): slivers relocated and flipped after the
//                             exuder (version 17) against Mesh_3's sliver perturber (version 16)
//  BM_FlipSlivers, BM_FlipSliversOneCallPerFlip  flip_slivers on 9,669 tetrahedra (the sphere
//                             without the exuder) under 25°: every flip in one call (since the 25th session)
//                             against one call per flip (the work each flip did before)
//  BM_TetrahedralizeNotRecovered/<bounded>  tetrahedralize() of the sacrum's own surface at 150
//                             (scenes/assets; its boundary is not recovered before refinement):
//                             refinement stopped past unrecovered_refine_work (1, version 23)
//                             against no bound (0), with the conflict-zone cells searched
//  BM_ThinBottle/<prisms>       squeeze mesh's pipeline on a 1.5 mm bottle at 300: one layer of
//                             prisms (1, version 24) against the boundary route (0, as before it)
//  BM_CombExuder/<pumps>       squeeze mesh's pipeline on a comb of 2 mm teeth at 1000: the exuder
//                             stopped at 5 pumps per sliver (version 43) or 20 (versions 25-42)
//                             against no bound (0)
//  BM_TurnedPlate/<placement>/<flip>/<pumps>  two thin plates turned in space at 2000: flat cells
//                             on the surface flipped outside (1, version 43) or refined (0), the
//                             exuder's pumps per sliver 5 (version 43) or 20
//  BM_RibbedPlate/<own>         the tests' plate with 3 mm ribs at 150: conformity recovery's cap
//                             raised by refinement's points (1, version 45) or not (0)
//  BM_FewDigitRod/<keep>       a rod 2 m by 1 cm, turned, 100 m from the origin, 7 digits, at 1000:
//                             a first attempt that holds kept unless the split boundary holds at
//                             fewer tetrahedra (1, version 47) or replaced by it (0)
//  BM_DenseScan/<proxy>        the corpus bunny Loop-subdivided once (301,632 faces, tests/shapes.h)
//                             at the default target: meshed through its quadric-decimated proxy
//                             (1, version 49) or as it is (0: dense_faces 0); the proxy's faces,
//                             tetrahedra and both deviations (fractions of the diagonal) as counters
//  BM_MidDenseScan/<proxy>     the corpus bunny (75,408 faces) at the default target: meshed
//                             through its proxy (1, version 54: dense_faces 30,000) or as it is
//                             (0, dense_faces 100,000 as before); proxy faces, tetrahedra, deviations
//  BM_HopelessCadRecovery/<budget> trimesh's ADIS16480.STL at 150: its first recovery given up at 4
//                             splits per face and not refined (1, version 55) or at the point cap,
//                             refined (0): seconds, tetrahedra, deviations
//  BM_Decimate                decimate_quadric() alone on that bunny, within 0.045 % of its
//                             diagonal (the pipeline's default bound): faces left, collapses
//  BM_SolidFirst/<first>       the tests' urchin at 150: its winding-number solid before retries 1
//                             and 3 (1) or after every retry (0): seconds, retries, tetrahedra
//  BM_ContractSlivers/<contract> the tests' urchin of 24 spikes at 1000: the slivers' edges
//                             contracted (1) or not (0): seconds, retries, tetrahedra, contractions
//  BM_ThickSolidFirst/<first>   the sacrum at 1000: its winding-number solid before retries 1 and
//                             3 by its thickness (1) or after every retry (0): seconds, retries
//  BM_SimplifyEnvelope/<no_local_crossings>  simplify_envelope() on the corpus bunny toward 1,000
//                             faces within the default bounds, with (1) or without (0) the test for
//                             faces crossing around each collapse: ms, faces, collapses
//  BM_TriangleBvh/<query>      TriangleBvh's nearest() (0 unbounded, 1 within 1 % of the diagonal)
//                             and any_within() (2) on the heart's 40,620 triangles: ns per query
//  BM_TetLocator              TetLocator::locate() on the tests' sphere at 1,000 tetrahedra, points
//                             spread over its bounding box: ns per query
//  BM_WindingNumber/<100 beta> FastWindingNumber queries on the heart's 40,620 triangles at the kind
//                             of points the winding-number route's Mesh_3 oracle asks about: the
//                             input's vertices moved along their normals by 0.5-8 times the
//                             dilation either way, and points spread over its bounding box: µs per
//                             query, the mean winding number, and the largest difference from the
//                             exact sum over every triangle at every 100th point
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "shapes.h"
#include "squeeze/meshing/decimate.h"
#include "squeeze/meshing/envelope.h"
#include "squeeze/meshing/mesh_pipeline.h"
#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/tet_cleanup.h"
#include "squeeze/meshing/tet_locator.h"
#include "squeeze/meshing/tetrahedralize.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/winding_number.h"

namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

fs::path data(const std::string& name) { return fs::path(SQUEEZE_TEST_DATA) / name; }

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The options of `squeeze mesh` without flags (cli/cmd_mesh.cpp): since meshing version 4 the
// library's defaults.
squeeze::meshing::MeshOptions boundary_first_options() { return {}; }

// mesh_surface(m, o) once per iteration (the A/B benches below differ by one option); the last
// result, its tetrahedra counted as "tets".
squeeze::meshing::MeshResult mesh_each_iteration(benchmark::State& state, const squeeze::meshing::SurfaceMesh& m,
                                                 const squeeze::meshing::MeshOptions& o) {
  squeeze::meshing::MeshResult r;
  for (auto _ : state) r = squeeze::meshing::mesh_surface(m, o);
  state.counters["tets"] = static_cast<double>(r.quality.tets);
  return r;
}

// The whole pipeline, as `squeeze mesh MODEL -o out.mesh` runs it (without writing the file).
void BM_Mesh(benchmark::State& state, const std::string& model) {
  const squeeze::meshing::MeshOptions options = boundary_first_options();  // the command line's defaults
  std::map<std::string, double> stage_sum;
  double tets = 0, hulls = 0, volume_ratio = 0;
  for (auto _ : state) {
    const squeeze::meshing::MeshResult r = squeeze::meshing::mesh_file(data(model), options);
    for (const auto* stages : {&r.seconds, &r.beside})  // beside: the decomposition, run beside the rest
      for (const auto& [name, s] : *stages) stage_sum[name] += s;
    tets = r.quality.tets;
    hulls = static_cast<double>(r.decomposition.shells.size());
    volume_ratio = r.input_volume > 0 ? r.quality.volume / r.input_volume : 0;
    benchmark::DoNotOptimize(r.tets.T.data());
  }
  for (const auto& [name, s] : stage_sum) {
    std::string key = "s_" + name;  // e.g. s_decomposing
    for (char& c : key)
      if (c == ' ') c = '_';
    state.counters[key] = benchmark::Counter(s, benchmark::Counter::kAvgIterations);
  }
  state.counters["tets"] = tets;
  state.counters["hulls"] = hulls;
  state.counters["volume_ratio"] = volume_ratio;
}
BENCHMARK_CAPTURE(BM_Mesh, bunny, std::string("bunny00.off"))->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Mesh, dragon, std::string("ChineseDragon-10kv.off"))
    ->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Mesh, elephant, std::string("elephant.off"))
    ->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// `squeeze mesh MODEL --target-tets N`: the count and the quality figures of goal "small coarse
// meshes for the scenes" (the Falling Objects scene: bunny + dragon + plate in about 400 tets).
void BM_MeshTarget(benchmark::State& state, const std::string& model, int target) {
  squeeze::meshing::MeshOptions options;
  options.tetrahedralize.target_tets = target;
  squeeze::meshing::MeshResult r;
  for (auto _ : state) {
    r = squeeze::meshing::mesh_file(data(model), options);
    benchmark::DoNotOptimize(r.tets.T.data());
  }
  state.counters["target"] = target;
  state.counters["tets"] = r.quality.tets;
  state.counters["hulls"] = static_cast<double>(r.decomposition.shells.size());
  state.counters["min_dihedral"] = r.quality.min_dihedral;
  state.counters["min_edge_ratio"] = r.quality.mean_edge > 0 ? r.quality.min_edge / r.quality.mean_edge : 0;
  state.counters["volume_ratio"] = r.input_volume > 0 ? r.quality.volume / r.input_volume : 0;
  state.counters["covered"] = r.covered_fraction;
  for (const auto* stages : {&r.seconds, &r.beside})
    for (const auto& [name, s] : *stages) {
      std::string key = "s_" + name;
      for (char& c : key)
        if (c == ' ') c = '_';
      state.counters[key] = s;
    }
}
BENCHMARK_CAPTURE(BM_MeshTarget, bunny_300, std::string("bunny00.off"), 300)
    ->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_MeshTarget, bunny_150, std::string("bunny00.off"), 150)
    ->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_MeshTarget, dragon_150, std::string("ChineseDragon-10kv.off"), 150)
    ->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_MeshTarget, heart_300, std::string("organs/heart.off"), 300)
    ->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// A surface as an OFF file (TetGen 1.5 reads .off with -p).
void write_shell_off(const fs::path& p, const squeeze::meshing::SurfaceMesh& h) {
  std::ofstream out(p);
  out.precision(17);
  out << "OFF\n" << h.V.rows() << ' ' << h.F.rows() << " 0\n";
  for (Eigen::Index i = 0; i < h.V.rows(); ++i) out << h.V(i, 0) << ' ' << h.V(i, 1) << ' ' << h.V(i, 2) << '\n';
  for (Eigen::Index f = 0; f < h.F.rows(); ++f) out << "3 " << h.F(f, 0) << ' ' << h.F(f, 1) << ' ' << h.F(f, 2) << '\n';
}

long tets_in_ele(const fs::path& ele) {
  std::ifstream in(ele);
  long n = -1;
  in >> n;
  return n;
}

// squeeze's tetrahedralization of the bunny's surface vs tetgen on the same surface.
void BM_TetrahedralizeVsTetgen(benchmark::State& state) {
  const char* tetgen = "/usr/bin/tetgen";
  if (::access(tetgen, X_OK) != 0) {
    state.SkipWithError("/usr/bin/tetgen not found (apt-get install tetgen)");
    return;
  }
  const squeeze::meshing::MeshOptions options = boundary_first_options();
  const squeeze::meshing::SurfaceMesh bunny = squeeze::meshing::load_surface(data("bunny00.off"));
  const squeeze::meshing::SurfaceMesh oriented{bunny.V, squeeze::meshing::orient_outward(bunny.V, bunny.F)};
  const fs::path dir = fs::temp_directory_path() / ("squeeze-bench-tetgen-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<fs::path> files;
  files.push_back(dir / "bunny.off");
  write_shell_off(files.back(), oriented);

  double squeeze_s = 0, tetgen_s = 0, squeeze_tets = 0, tetgen_tets = 0;
  int failures = 0;
  for (auto _ : state) {
    auto t0 = Clock::now();
    squeeze::meshing::TetrahedralizeStats stats;
    const squeeze::meshing::TetMesh m = squeeze::meshing::tetrahedralize(oriented, options.tetrahedralize, &stats);
    squeeze_s += seconds_since(t0);
    squeeze_tets = static_cast<double>(m.T.rows());

    t0 = Clock::now();
    long total = 0;
    for (const fs::path& f : files) {
      const std::string cmd = std::string(tetgen) + " -pq1.414 -Q '" + f.string() + "' > /dev/null 2>&1";
      if (std::system(cmd.c_str()) != 0) ++failures;
    }
    tetgen_s += seconds_since(t0);
    for (const fs::path& f : files) total += std::max(0L, tets_in_ele(fs::path(f).replace_extension(".1.ele")));
    tetgen_tets = static_cast<double>(total);
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (failures) state.SkipWithError(("tetgen failed on " + std::to_string(failures) + " runs").c_str());
  const double n = static_cast<double>(state.iterations());
  state.counters["squeeze_s"] = squeeze_s / n;
  state.counters["tetgen_s"] = tetgen_s / n;
  state.counters["squeeze_over_tetgen"] = tetgen_s > 0 ? squeeze_s / tetgen_s : 0;
  state.counters["squeeze_tets"] = squeeze_tets;
  state.counters["tetgen_tets"] = tetgen_tets;
}
BENCHMARK(BM_TetrahedralizeVsTetgen)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace

// A faceted rod (1 m by 3 mm, 12 sides, 40 rings; tests/shapes.h), meshing version 14: the whole
// pipeline (its boundary split to rounder triangles after a bounded first try) against the same
// pipeline with MeshOptions::split_skinny off (version 13's way: its own boundary, refinement
// unbounded, then the retries).
void BM_RodPipeline(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh rod = sqs::ringed_rod(0.003, 1.0, 12, 40);
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = static_cast<int>(state.range(0));
  long tets = 0;
  for (auto _ : state) tets = squeeze::meshing::mesh_surface(rod, o).quality.tets;
  state.counters["tets"] = static_cast<double>(tets);
}
BENCHMARK(BM_RodPipeline)->Arg(150)->Arg(1000)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

void BM_RodWithoutSplit(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh rod = sqs::ringed_rod(0.003, 1.0, 12, 40);
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = static_cast<int>(state.range(0));
  o.split_skinny = false;  // version 13: its own boundary only, refinement unbounded, then the retries
  long tets = 0;
  double dihedral = 0;
  for (auto _ : state) {
    const squeeze::meshing::MeshResult r = squeeze::meshing::mesh_surface(rod, o);
    tets = r.quality.tets;
    dihedral = r.quality.min_dihedral;
  }
  state.counters["tets"] = static_cast<double>(tets);
  state.counters["min_dihedral"] = dihedral;
}
BENCHMARK(BM_RodWithoutSplit)->Arg(150)->Arg(1000)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// A long rod of few sides (2 m by 2 cm, 32 sides, one ring; tests/shapes.h) at 1000, meshing
// version 27: retry 0's first remesh at the length whose chords lose about 2.5 % of its volume
// (Arg 1: MeshOptions::remesh_volume_loss 0.025), against a quarter of the interior edge length
// first, which lost 3.6 % and was made again shorter (Arg 0: version 26).
void BM_LongRodRemesh(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh rod = sqs::ringed_rod(0.01, 2.0, 32, 1);
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.remesh_volume_loss = state.range(0) != 0 ? 0.025 : 0.0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, rod, o);
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0);
  state.counters["min_dihedral"] = r.quality.min_dihedral;
}
BENCHMARK(BM_LongRodRemesh)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The U-shaped curtain of tests/shapes.h at the default target: its mesh (one layer of prisms) is
// ready in a fraction of the time; the convex decomposition beside it (the report's shells, the
// tetrahedra's labels) cuts it 22 times. Arg 1: large polygons sampled by area (meshing version
// 29); 0: by their longest edge, as before (DecompositionOptions::samples_by_area).
void BM_UCurtainDecomposition(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m = sqs::u_curtain();
  squeeze::meshing::MeshOptions o;
  o.decomposition.samples_by_area = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  state.counters["shells"] = static_cast<double>(r.decomposition.shells.size());
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0);
}
BENCHMARK(BM_UCurtainDecomposition)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The closed box [0, lx] × [0, ly] × [0, lz], turned by `angle` (rad) about `axis` and then moved by
// `shift`: 8 vertices, 12 outward triangles.
squeeze::meshing::SurfaceMesh turned_box(double lx, double ly, double lz, double angle = 0.0,
                                         const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ(),
                                         const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  squeeze::meshing::SurfaceMesh m;
  m.V.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    m.V.row(i) = (R * Eigen::Vector3d((i & 1) * lx, ((i >> 1) & 1) * ly, ((i >> 2) & 1) * lz) + shift).transpose();
  m.F.resize(12, 3);
  m.F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  return m;
}

// A closed plate 1 m square and 5 mm thick (12 triangles) at a target of 150, meshing version 15:
// one layer of prisms across its thickness (MeshOptions::thin_parts_as_prisms), against the same
// pipeline with it off (version 14's way: its boundary tetrahedralized, Delaunay refinement between
// sides 5 mm apart).
squeeze::meshing::SurfaceMesh plate_5mm() { return turned_box(1.0, 1.0, 0.005); }

// Plates turned in space at 2000 tetrahedra (meshing version 43), the boundary route: Arg 0 the
// placement (0: 0.8 × 0.4 × 0.006 m turned 0.7 rad about (1, 2, 3) and moved to (3, -2, 5); 1: 0.5
// × 0.5 × 0.004 m turned 2 rad about (1, 1, 1)); Arg 1 whether flat cells on the surface are flipped
// outside (TetrahedralizeOptions::flip_flat_surface_cells) or refined (0, version 42); Arg 2 the
// exuder's pumps per sliver (5 since version 43, 20 before).
void BM_TurnedPlate(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m =
      state.range(0) == 0 ? turned_box(0.8, 0.4, 0.006, 0.7, {1, 2, 3}, {3, -2, 5})
                          : turned_box(0.5, 0.5, 0.004, 2.0, {1, 1, 1}, {0, 0, 0});
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 2000;
  o.tetrahedralize.flip_flat_surface_cells = state.range(1) != 0;
  o.tetrahedralize.exude_pumps_per_sliver = state.range(2);
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0.0);
  state.counters["min_dihedral"] = r.quality.min_dihedral;
  state.counters["boundary_splits"] = r.tet_stats.boundary_splits;
  state.counters["pump_bounds"] = r.tet_stats.exuder_pump_bounds;
}
BENCHMARK(BM_TurnedPlate)
    ->Args({0, 1, 5})
    ->Args({0, 0, 5})
    ->Args({0, 1, 20})
    ->Args({0, 0, 20})
    ->Args({1, 1, 5})
    ->Args({1, 0, 5})
    ->Args({1, 1, 20})
    ->Args({1, 0, 20})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

void plate(benchmark::State& state, bool prisms) {
  const squeeze::meshing::SurfaceMesh m = plate_5mm();
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = static_cast<int>(state.range(0));
  o.thin_parts_as_prisms = prisms;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0.0);
  state.counters["min_dihedral"] = r.quality.min_dihedral;
  state.counters["conforming"] = r.tet_stats.conforming ? 1 : 0;
}
void BM_ThinPlatePipeline(benchmark::State& state) { plate(state, true); }
void BM_ThinPlateWithoutPrisms(benchmark::State& state) { plate(state, false); }
BENCHMARK(BM_ThinPlatePipeline)->Arg(150)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_ThinPlateWithoutPrisms)->Arg(150)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The plate with 3 mm ribs of the tests (sqs::ribbed_plate) at 150 through the whole pipeline:
// conformity recovery's cap raised by refinement's points (1, version 45) or counting every point
// (0, before: the first attempts lose the boundary and retry 0 remeshes it).
void BM_RibbedPlate(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m = sqs::ribbed_plate();
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.tetrahedralize.recovery_cap_on_own_splits = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  state.counters["tets"] = static_cast<double>(r.quality.tets);
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0.0);
  state.counters["min_dihedral"] = r.quality.min_dihedral;
  state.counters["conforming"] = r.tet_stats.conforming ? 1 : 0;
}
BENCHMARK(BM_RibbedPlate)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// A rod 2 m long and 1 cm across, turned 1.2 rad about (0.2, 0.3, 1), moved to (100, -50, 20) and
// rounded to 7 significant digits (as a file written so has it), at 1000 through the whole
// pipeline: a first attempt on its own faces that holds, its refinement stopped at its work bound,
// is kept unless the split boundary holds at fewer tetrahedra (1, version 47:
// MeshOptions::skinny_split_keeps_first_that_holds), or gives way to any split boundary (0, versions
// 26-46).
void BM_FewDigitRod(benchmark::State& state) {
  squeeze::meshing::SurfaceMesh m = turned_box(2.0, 0.01, 0.01, 1.2, {0.2, 0.3, 1}, {100, -50, 20});
  m.V = m.V.unaryExpr([](double x) { return sqs::significant_digits(x, 7); });
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.skinny_split_keeps_first_that_holds = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  const double diag = squeeze::meshing::bounding_box_diagonal(m.V);
  state.counters["tets"] = static_cast<double>(r.quality.tets);
  state.counters["boundary_faces"] = static_cast<double>(r.boundary.F.rows());
  state.counters["conforming"] = r.tet_stats.conforming ? 1 : 0;
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0.0);
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["min_dihedral"] = r.quality.min_dihedral;
}
BENCHMARK(BM_FewDigitRod)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// An open scan whose holes are wider than the bound (the bunny of tests/data, four holes of 2 % of
// its diagonal in radius cut around seeded vertices: sqs::with_holes, as tests/test_meshing_v4.cpp
// cuts them): both orders end at the same slab.
void scan_with_holes(benchmark::State& state, bool slab_first) {
  const squeeze::meshing::SurfaceMesh m = sqs::with_holes(squeeze::meshing::load_surface(data("bunny00.off")), 0.02);
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = static_cast<int>(state.range(0));
  o.slab_first_for_wide_holes = slab_first;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  const double diag = squeeze::meshing::bounding_box_diagonal(m.V);
  state.counters["sheets"] = r.sheets;
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["deviation_in"] = r.deviation_in / diag;
  state.counters["min_dihedral"] = r.quality.min_dihedral;
}
void BM_ScanWithHolesSlabFirst(benchmark::State& state) { scan_with_holes(state, true); }
void BM_ScanWithHolesSolidFirst(benchmark::State& state) { scan_with_holes(state, false); }
BENCHMARK(BM_ScanWithHolesSlabFirst)->Arg(300)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_ScanWithHolesSolidFirst)->Arg(300)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// Welded segments with holes wider than the bound: the hollowed solid made first, or after the
// capped one (MeshOptions::hollow_first).
void BM_LiverWithHoles(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m = sqs::with_holes_at(
      squeeze::meshing::load_surface(fs::path(SQUEEZE_SOURCE_DIR) / "scenes" / "assets" / "liver.off"),
      {{-0.0397111, 0.3670973333, 0.0689651}, {-0.0943798667, 0.340173, 0.0258854}, {-0.128658, 0.389611, 0.0096255767}},
      0.03);
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 300;
  o.hollow_first = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  const double diag = squeeze::meshing::bounding_box_diagonal(m.V);
  int surfaces = 0;
  for (const auto& [stage, seconds] : r.seconds) surfaces += stage == "winding-number surface";
  state.counters["tets"] = r.quality.tets;
  state.counters["solids_made"] = surfaces;
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["deviation_in"] = r.deviation_in / diag;
}
BENCHMARK(BM_LiverWithHoles)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The heart of tests/data with four holes 3 % of its diagonal in radius around seeded vertices
// (seed 391 of the thirty-eighth session): its solid hollowed, a thin shell of 29,730
// tetrahedra, at 300 (meshing version 40). Arg 0: conformity recovery
// remembers a cell per boundary triangle (TetrahedralizeOptions::remember_facet_cells; 0 asks the
// triangulation each time); arg 1: the inside test's memo, 2^arg slots
// (WindingTetrahedralizeOptions::label_memo_log2_slots; 22 before). The same mesh in every run.
void BM_HeartWithHoles(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m = sqs::with_holes_at(squeeze::meshing::load_surface(data("organs/heart.off")),
                                                             {{0.075214, 0.467939, 0.0640765},
                                                              {0.00254863, 0.47815, 0.0756827},
                                                              {0.0392196, 0.429359, 0.0836583},
                                                              {0.0058577, 0.430776, 0.0496153}},
                                                             0.03);
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 300;
  o.tetrahedralize.remember_facet_cells = state.range(0) != 0;
  o.winding_mesh.label_memo_log2_slots = static_cast<int>(state.range(1));
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  for (const auto& [stage, seconds] : r.seconds) {
    if (stage == "winding-number surface") state.counters["surface_s"] = seconds;
    if (stage == "tetrahedralizing") state.counters["tetrahedralizing_s"] = seconds;
  }
  const double diag = squeeze::meshing::bounding_box_diagonal(m.V);
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["deviation_in"] = r.deviation_in / diag;
}
BENCHMARK(BM_HeartWithHoles)
    ->Args({1, 23})
    ->Args({0, 23})
    ->Args({1, 22})
    ->Args({0, 22})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

// A figure-eight tube 6 mm across on a curve 12 cm wide, which passes through itself (the
// winding-number boundary route), at a target of 1,000: its solid's growth estimated before the
// first Mesh_3 run (arg 1, meshing version 31) against made at the full dilation and made again
// while it grew too much (arg 0, version 30: three runs).
void BM_SelfIntersectingTube(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m = sqs::figure_eight_tube(0.06, 0.003, 10, 64);
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.estimate_winding_growth = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0.0);
  state.counters["solids"] = r.winding_solids;
  for (const auto& [stage, seconds] : r.seconds)
    if (stage == "winding-number surface") state.counters["surface_s"] = seconds;
}
BENCHMARK(BM_SelfIntersectingTube)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The cover pass of the winding-number surface (winding_number_surface: the input's points its
// facets leave outside, taken to the solid's surface as more seeds) with the points that could
// only land near a seed already taken skipped (Arg 1, version 35's speed-up; the same seeds and
// mesh) and with each one tested and bisected (Arg 0), at 1000. The model: $SQUEEZE_BENCH_COVER_MODEL
// where set (trimesh's chair_model.obj, whose pass this was written for, is not among the
// project's data), else the heart of tests/data (a short pass: the same seeds either way).
void BM_WindingSurfaceCoverPass(benchmark::State& state) {
  const char* model = std::getenv("SQUEEZE_BENCH_COVER_MODEL");
  const squeeze::meshing::SurfaceMesh m = squeeze::meshing::load_surface(model ? fs::path(model) : data("organs/heart.off"));
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.winding_mesh.cover_skip = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  state.counters["seeds"] = r.winding_stats.seeds;
  for (const auto& [stage, seconds] : r.seconds)
    if (stage == "winding-number surface") state.counters["surface_s"] = seconds;
}
BENCHMARK(BM_WindingSurfaceCoverPass)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The winding-number solid's cover pass (tetrahedralize_winding_number: the input's points its
// facets cut off, taken to the solid's surface as more seeds and refined again; Arg 1, meshing
// version 56) against none (Arg 0, version 55), at 150. The model: $SQUEEZE_BENCH_SOLID_MODEL
// through the default route where set (trimesh's featuretype.STL, a CAD part that goes to its
// solid, is not among the project's data), else the heart of tests/data by the winding-number
// route (`--winding`).
void BM_WindingSolidCoverPass(benchmark::State& state) {
  const char* model = std::getenv("SQUEEZE_BENCH_SOLID_MODEL");
  const squeeze::meshing::SurfaceMesh m = squeeze::meshing::load_surface(model ? fs::path(model) : data("organs/heart.off"));
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.winding = model == nullptr;
  o.winding_mesh.cover_solid = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  const double diag = squeeze::meshing::bounding_box_diagonal(m.V);
  state.counters["tets"] = r.quality.tets;
  state.counters["deviation_in"] = r.deviation_in / diag;
  state.counters["deviation_out"] = r.deviation_out / diag;
}
BENCHMARK(BM_WindingSolidCoverPass)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The heart's convex shells meshed by Mesh_3 (`squeeze mesh heart.off --shells-fallback`, the
// paper's coarse mesh): their slivers relocated and flipped after the exuder (version 17) against
// Mesh_3's sliver perturber before it (ShellTetrahedralizeOptions::perturb, version 16).
void heart_shells(benchmark::State& state, bool perturb) {
  const squeeze::meshing::SurfaceMesh m = squeeze::meshing::load_surface(data("organs/heart.off"));
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = static_cast<int>(state.range(0));
  o.shells_fallback = true;
  o.shells.perturb = perturb;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, m, o);
  const double diag = squeeze::meshing::bounding_box_diagonal(m.V);
  state.counters["attempts"] = r.shell_stats.attempts;
  state.counters["covered"] = r.shell_stats.covered;
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["min_dihedral"] = r.quality.min_dihedral;
}
void BM_HeartShellsRelocated(benchmark::State& state) { heart_shells(state, false); }
void BM_HeartShellsPerturbed(benchmark::State& state) { heart_shells(state, true); }
BENCHMARK(BM_HeartShellsRelocated)->Arg(300)->Arg(500)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_HeartShellsPerturbed)->Arg(300)->Arg(500)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// flip_slivers on the sphere of tests/data tetrahedralized without the exuder (9,669 tetrahedra),
// flipping everything under 25°: all flips in one call (its qualities, vertex lists and slivers
// kept up to date flip by flip, since the twenty-fifth session) against one call per flip (each call measuring every
// tetrahedron and listing every vertex's again, as every flip did before).
squeeze::meshing::TetMesh flip_bench_mesh() {
  squeeze::meshing::TetrahedralizeOptions o;
  o.target_tets = 20000;
  o.exude = false;
  o.max_attempts = 1;
  return squeeze::meshing::tetrahedralize(squeeze::meshing::load_surface(data("sphere.off")), o);
}
void BM_FlipSlivers(benchmark::State& state) {
  const squeeze::meshing::TetMesh mesh = flip_bench_mesh();
  int flips = 0;
  for (auto _ : state) {
    squeeze::meshing::TetMesh m = mesh;
    flips = squeeze::meshing::flip_slivers(m, 25.0, 100000);
  }
  state.counters["tets"] = static_cast<double>(mesh.T.rows());
  state.counters["flips"] = flips;
}
void BM_FlipSliversOneCallPerFlip(benchmark::State& state) {
  const squeeze::meshing::TetMesh mesh = flip_bench_mesh();
  int flips = 0;
  for (auto _ : state) {
    squeeze::meshing::TetMesh m = mesh;
    flips = 0;
    while (squeeze::meshing::flip_slivers(m, 25.0, 1) == 1) ++flips;
  }
  state.counters["tets"] = static_cast<double>(mesh.T.rows());
  state.counters["flips"] = flips;
}
// tetrahedralize() of a surface whose boundary is not recovered before refinement (the sacrum's
// own, at 150: the mesh is classified by the winding number, one squeeze mesh's retries replace):
// its refinement bounded by unrecovered_refine_work (Arg 1, the default since version 23) against
// none (Arg 0, the eight rounds before). Runs that are not conforming are not exuded either way.
void BM_TetrahedralizeNotRecovered(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh s =
      squeeze::meshing::load_surface(fs::path(SQUEEZE_SOURCE_DIR) / "scenes" / "assets" / "sacrum_coccyx.off");
  squeeze::meshing::TetrahedralizeOptions o;
  o.target_tets = 150;
  o.max_attempts = 1;
  if (state.range(0) == 0) o.unrecovered_refine_work = 0;
  squeeze::meshing::TetrahedralizeStats st;
  squeeze::meshing::TetMesh m;
  for (auto _ : state) m = squeeze::meshing::tetrahedralize(s, o, &st);
  state.counters["tets"] = static_cast<double>(m.T.rows());
  state.counters["recovered"] = st.recovered;
  state.counters["refine_work"] = st.refine_work;
}
// squeeze mesh's pipeline on a bottle with a 1.5 mm wall at 300 (sqs::thin_bottle): one layer of
// prisms since version 24 (Arg 1), against the boundary route it took before, whose slab lay off
// the bounds (Arg 0: MeshOptions::thin_parts_as_prisms off), with the deviation inward.
void BM_ThinBottle(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh bottle = sqs::thin_bottle();
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 300;
  o.thin_parts_as_prisms = state.range(0) != 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, bottle, o);
  state.counters["thin_parts"] = r.thin_parts;
  state.counters["deviation_in"] = r.deviation_in;
}
BENCHMARK(BM_ThinBottle)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
// squeeze mesh's pipeline on the comb (sqs::comb, read from an OFF file as squeeze mesh reads it) at
// 1000: the exuder of its first attempt stopped at Arg pumps per sliver (5 since version 43, 20 in
// versions 25-42), against no pump bound (Arg 0: it pumps round in a circle to its 30 s time limit).
void BM_CombExuder(benchmark::State& state) {
  const fs::path path = fs::temp_directory_path() / ("squeeze_bench_comb_" + std::to_string(getpid()) + ".off");
  squeeze::meshing::save_surface(path, sqs::comb());
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.tetrahedralize.exude_pumps_per_sliver = state.range(0);
  squeeze::meshing::MeshResult r;
  for (auto _ : state) r = squeeze::meshing::mesh_file(path, o);
  fs::remove(path);
  state.counters["tets"] = static_cast<double>(r.quality.tets);
  state.counters["pump_bounds"] = r.tet_stats.exuder_pump_bounds;
  state.counters["volume_ratio"] = r.volume_ratio.value_or(0);
}
BENCHMARK(BM_CombExuder)->Arg(5)->Arg(20)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

BENCHMARK(BM_TetrahedralizeNotRecovered)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

BENCHMARK(BM_FlipSlivers)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_FlipSliversOneCallPerFlip)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// FastWindingNumber on the heart: the inside test of the winding-number route (winding_tetrahedralize.h),
// 71 % of the heart's meshing samples in perf before meshing version 19.
void BM_WindingNumber(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m = squeeze::meshing::load_surface(data("organs/heart.off"));
  Eigen::MatrixX3d FN, N;
  squeeze::meshing::area_weighted_normals(m.V, m.F, FN, N);
  const Eigen::RowVector3d lo = m.V.colwise().minCoeff(), hi = m.V.colwise().maxCoeff();
  const double dilation = 0.0045 * (hi - lo).norm();  // the route's default: 0.45 x 1 % of the diagonal
  std::vector<Eigen::RowVector3d> q;
  for (Eigen::Index v = 0; v < m.V.rows(); v += 4) {
    if (!(N.row(v).norm() > 0)) continue;
    const Eigen::RowVector3d n = N.row(v).normalized();
    for (double k : {-8.0, -2.0, -0.5, 0.5, 2.0, 8.0}) q.push_back(m.V.row(v) + k * dilation * n);
  }
  std::srand(1);
  for (int i = 0; i < 20000; ++i) {
    Eigen::RowVector3d u;
    for (int k = 0; k < 3; ++k) u(k) = lo(k) + (hi(k) - lo(k)) * (std::rand() / (RAND_MAX + 1.0));
    q.push_back(u);
  }
  const double beta = static_cast<double>(state.range(0)) / 100.0;
  const squeeze::meshing::FastWindingNumber w(m.V, m.F, beta);
  double sum = 0, seconds = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    sum = 0;
    for (const auto& p : q) sum += w(p);
    benchmark::DoNotOptimize(sum);
    seconds += seconds_since(t0);
  }
  // Against the exact sum over every triangle (winding_number), at every 100th query.
  double worst = 0;
  for (size_t i = 0; i < q.size(); i += 100)
    worst = std::max(worst, std::abs(w(q[i]) - squeeze::meshing::winding_number(m.V, m.F, q[i])));
  state.counters["queries"] = static_cast<double>(q.size());
  state.counters["us_per_query"] = 1e6 * seconds / (static_cast<double>(state.iterations()) * static_cast<double>(q.size()));
  state.counters["mean_winding_number"] = sum / static_cast<double>(q.size());
  state.counters["max_error"] = worst;
}
// beta × 100: 125 is the winding-number route's (winding_tetrahedralize.h), 150 the default
// (FastWindingNumber, the decomposition's); 200 and 400 were theirs until meshing version 19.
BENCHMARK(BM_WindingNumber)->Arg(125)->Arg(150)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// The corpus bunny Loop-subdivided once: 301,632 faces of a smooth surface, as a fine scan has.
const squeeze::meshing::SurfaceMesh& dense_bunny() {
  static const squeeze::meshing::SurfaceMesh m = sqs::loop_subdivided(squeeze::meshing::load_surface(data("bunny00.off")), 1);
  return m;
}

// The same with Gaussian noise of 0.01 % of the diagonal on every vertex (seeded), as a scanner's.
const squeeze::meshing::SurfaceMesh& noisy_dense_bunny() {
  static const squeeze::meshing::SurfaceMesh m = [] {
    squeeze::meshing::SurfaceMesh n = dense_bunny();
    std::mt19937 rng(1);
    std::normal_distribution<double> noise(0.0, 1e-4 * squeeze::meshing::bounding_box_diagonal(n.V));
    for (Eigen::Index i = 0; i < n.V.size(); ++i) n.V.data()[i] += noise(rng);
    return n;
  }();
  return m;
}

// 1: the dense bunny through its proxy; 0: the input itself (dense_faces 0); 2: the noisy one
// through its proxy.
void BM_DenseScan(benchmark::State& state) {
  squeeze::meshing::MeshOptions o;
  if (state.range(0) == 0) o.dense_faces = 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, state.range(0) == 2 ? noisy_dense_bunny() : dense_bunny(), o);
  const double diag = squeeze::meshing::bounding_box_diagonal(r.input.V);
  state.counters["proxy_faces"] = r.proxy_faces;
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["deviation_in"] = r.deviation_in / diag;
}
BENCHMARK(BM_DenseScan)->Arg(1)->Arg(0)->Arg(2)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The corpus bunny (75,408 faces, between version 54's dense_faces and version 53's) at the
// default target: 1: through its proxy (the default, 30,000); 0: the input itself (100,000).
void BM_MidDenseScan(benchmark::State& state) {
  squeeze::meshing::MeshOptions o;
  if (state.range(0) == 0) o.dense_faces = 100000;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, squeeze::meshing::load_surface(data("bunny00.off")), o);
  const double diag = squeeze::meshing::bounding_box_diagonal(r.input.V);
  state.counters["proxy_faces"] = r.proxy_faces;
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["deviation_in"] = r.deviation_in / diag;
}
BENCHMARK(BM_MidDenseScan)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// trimesh's ADIS16480.STL (7,436 faces, tests/data/cad) at 150: the first recovery of its simplified
// boundary (1,614 faces) gives up at 4 splits per face, unrefined (1: the default since version 55),
// or at the point cap after 21,456 splits, refined (0: recovery_splits_per_face 0, as before).
void BM_HopelessCadRecovery(benchmark::State& state) {
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  if (state.range(0) == 0) o.tetrahedralize.recovery_splits_per_face = 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, squeeze::meshing::load_surface(data("cad/ADIS16480.STL")), o);
  const double diag = squeeze::meshing::bounding_box_diagonal(r.input.V);
  state.counters["deviation_out"] = r.deviation_out / diag;
  state.counters["deviation_in"] = r.deviation_in / diag;
}
BENCHMARK(BM_HopelessCadRecovery)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The urchin of the tests (4,992 faces) at 150, whose first boundary loses conformity and whose
// retries do not hold: its winding-number solid tried before retries 1 and 3 (1: solid_first_faces
// under its faces) or after every retry (0: version 50's order). The same mesh either way
// (MeshingV4.SolidFirstWhere...); the boundary retries made as a counter.
void BM_SolidFirst(benchmark::State& state) {
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 150;
  o.solid_first_faces = state.range(0) == 1 ? 4000 : 0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, sqs::urchin(), o);
  state.counters["retries"] = r.boundary_retries;
}
BENCHMARK(BM_SolidFirst)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The tests' urchin of 24 spikes (seed 23) at 1000, whose remeshed boundary (retry 0) is conforming
// with interior slivers across a spike's tip: their edges contracted (1: contract_max_length 0.25,
// meshing version 52) or not (0: version 51, every retry and then its winding-number solid). The
// boundary retries, tetrahedra and contractions as counters.
void BM_ContractSlivers(benchmark::State& state) {
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.tetrahedralize.contract_max_length = state.range(0) == 1 ? 0.25 : 0.0;
  o.solid_first_thickness = 0;  // (its solid after every retry, as versions 51 and 52: the contractions' own effect)
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, sqs::urchin23(), o);
  state.counters["retries"] = r.boundary_retries;
  state.counters["contractions"] = r.tet_stats.contractions;
}
BENCHMARK(BM_ContractSlivers)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The sacrum of scenes/assets at 1000, whose large part (10,818 faces, 0.64 of its edge length
// thick) loses conformity on its first boundary and on every retry: its winding-number solid right
// after retry 0 (1: solid_first_thickness 0.5, meshing version 53) or after retries 1, 3 and 4 (0:
// version 52). The same mesh either way (MeshingV4.ThickPartWhose...); the retries as a counter.
void BM_ThickSolidFirst(benchmark::State& state) {
  static const squeeze::meshing::SurfaceMesh sacrum =
      squeeze::meshing::load_surface(fs::path(SQUEEZE_SOURCE_DIR) / "scenes" / "assets" / "sacrum_coccyx.off");
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  o.solid_first_thickness = state.range(0) == 1 ? 0.5 : 0.0;
  const squeeze::meshing::MeshResult r = mesh_each_iteration(state, sacrum, o);
  state.counters["retries"] = r.boundary_retries;
}
BENCHMARK(BM_ThickSolidFirst)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// Arguments: the dense bunny (0) or the noisy one (1); planes checked one by one (1, the default
// since meshing version 50) or the quadric's root alone (0, version 49).
void BM_Decimate(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh& m = state.range(0) == 1 ? noisy_dense_bunny() : dense_bunny();
  squeeze::meshing::DecimateOptions o;
  o.plane_by_plane = state.range(1) == 1;
  o.max_error = 0.1 * 0.45 * 0.01 * squeeze::meshing::bounding_box_diagonal(m.V);  // (MeshOptions' defaults)
  squeeze::meshing::DecimateStats stats;
  for (auto _ : state) benchmark::DoNotOptimize(squeeze::meshing::decimate_quadric(m, o, &stats).F.data());
  state.counters["faces"] = stats.faces;
  state.counters["collapses"] = stats.collapses;
}
BENCHMARK(BM_Decimate)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// simplify_envelope() on the corpus bunny (75,408 faces) within the pipeline's default bounds (1 %
// of the diagonal out, 0.45 % in) toward 1,000 faces, with the test for crossing faces around each
// collapse (1, no_local_crossings, the default since meshing version 51) or without (0): the cost of
// that test; faces left and collapses as counters.
void BM_SimplifyEnvelope(benchmark::State& state) {
  static const squeeze::meshing::SurfaceMesh m = squeeze::meshing::load_surface(data("bunny00.off"));
  const double diag = squeeze::meshing::bounding_box_diagonal(m.V);
  squeeze::meshing::EnvelopeOptions e;
  e.max_outside = 0.01 * diag;
  e.max_inside = 0.0045 * diag;
  e.target_faces = 1000;
  e.no_local_crossings = state.range(0) == 1;
  squeeze::meshing::EnvelopeStats stats;
  for (auto _ : state) benchmark::DoNotOptimize(squeeze::meshing::simplify_envelope(m, e, &stats).F.data());
  state.counters["faces"] = stats.faces;
  state.counters["collapses"] = stats.collapses;
}
BENCHMARK(BM_SimplifyEnvelope)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// TriangleBvh on the heart's 40,620 triangles, at the kind of points the envelope's checks and the
// deviation measures ask about: the input's vertices moved along their normals by 0.1-3 % of the
// diagonal either way, and points spread over its bounding box. The argument is the query:
// 0 nearest() without a bound (simplify's gap check), 1 nearest() within 1 % of the diagonal
// (simplify's bound check), 2 any_within() 1 % (the one-sided Hausdorff distances).
// Nanoseconds per query, and a checksum of the answers (the same across layouts of the tree).
void BM_TriangleBvh(benchmark::State& state) {
  const squeeze::meshing::SurfaceMesh m = squeeze::meshing::load_surface(data("organs/heart.off"));
  Eigen::MatrixX3d FN, N;
  squeeze::meshing::area_weighted_normals(m.V, m.F, FN, N);
  const Eigen::RowVector3d lo = m.V.colwise().minCoeff(), hi = m.V.colwise().maxCoeff();
  const double diag = (hi - lo).norm();
  std::vector<Eigen::Vector3d> q;
  for (Eigen::Index v = 0; v < m.V.rows(); v += 2) {
    if (!(N.row(v).norm() > 0)) continue;
    const Eigen::RowVector3d n = N.row(v).normalized();
    for (double k : {-0.03, -0.01, -0.001, 0.001, 0.01, 0.03}) q.push_back((m.V.row(v) + k * diag * n).transpose());
  }
  std::srand(1);
  for (int i = 0; i < 20000; ++i) {
    Eigen::Vector3d u;
    for (int k = 0; k < 3; ++k) u(k) = lo(k) + (hi(k) - lo(k)) * (std::rand() / (RAND_MAX + 1.0));
    q.push_back(u);
  }
  const squeeze::meshing::TriangleBvh bvh(m.V, m.F);
  const int kind = static_cast<int>(state.range(0));
  const double bound = 0.01 * diag;
  double sum = 0, seconds = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    sum = 0;
    for (const auto& p : q) {
      int f = -1;
      if (kind == 0) sum += bvh.nearest(p, &f), sum += f;
      else if (kind == 1) sum += std::min(bvh.nearest(p, &f, nullptr, bound), 1.0), sum += f;
      else sum += bvh.any_within(p, bound);
    }
    benchmark::DoNotOptimize(sum);
    seconds += seconds_since(t0);
  }
  state.counters["queries"] = static_cast<double>(q.size());
  state.counters["ns_per_query"] = 1e9 * seconds / (static_cast<double>(state.iterations()) * static_cast<double>(q.size()));
  state.counters["checksum"] = sum;
}
BENCHMARK(BM_TriangleBvh)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// TetLocator::locate() on the tests' sphere meshed at 1,000 tetrahedra, at points spread over its
// bounding box (about half inside): ns per query; the tetrahedra found summed as a checksum (the
// same before and after a change of how barycentric coordinates are computed).
void BM_TetLocator(benchmark::State& state) {
  squeeze::meshing::MeshOptions o;
  o.tetrahedralize.target_tets = 1000;
  const squeeze::meshing::TetMesh m = squeeze::meshing::mesh_surface(squeeze::meshing::load_surface(data("sphere.off")), o).tets;
  const squeeze::meshing::TetLocator locator(m);
  const Eigen::RowVector3d lo = m.V.colwise().minCoeff(), hi = m.V.colwise().maxCoeff();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::RowVector3d> q(200000);
  for (auto& p : q)
    for (int k = 0; k < 3; ++k) p(k) = lo(k) + (hi(k) - lo(k)) * u(rng);
  double sum = 0, seconds = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    sum = 0;
    for (const auto& p : q) sum += locator.locate(p);
    benchmark::DoNotOptimize(sum);
    seconds += seconds_since(t0);
  }
  state.counters["tets"] = static_cast<double>(m.T.rows());
  state.counters["ns_per_query"] = 1e9 * seconds / (static_cast<double>(state.iterations()) * static_cast<double>(q.size()));
  state.counters["checksum"] = sum;
}
BENCHMARK(BM_TetLocator)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

BENCHMARK_MAIN();
