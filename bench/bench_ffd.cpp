// Benchmarks of the ffd stage (issue 4): binding the 37,706-vertex bunny to its coarse tetrahedral
// mesh, and replay throughput on the bunny subdivided three times (2.4M vertices), quoted next to
// the machine's memory bandwidth measured in the same run (a STREAM-style parallel copy).
//
//   build/bench/bench_ffd            (prints the Google Benchmark table, then a summary line)
//
// Replay traffic per surface vertex: tet index 4 B + four weights 32 B read, three coordinates
// 24 B written = 60 B ("useful bytes", counted like STREAM counts its copy: 16 B per element, the
// write-allocate read not included). The coarse state (a few thousand vertices) stays in cache.
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <vector>

#include "squeeze/ffd/ffd.h"
#include "squeeze/meshing/mesh_pipeline.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/tet_io.h"

namespace {

using namespace squeeze;
using namespace squeeze::meshing;
using namespace squeeze::ffd;

constexpr double kBytesPerVertex = 4 + 32 + 24;

struct Data {
  SurfaceMesh bunny, fine;
  TetMesh tets;
  Eigen::MatrixX3d deformed;  // a twisted, scaled state of the coarse mesh
  Binding fine_binding;
};

// One level of 1-to-4 midpoint subdivision.
SurfaceMesh subdivide(const SurfaceMesh& m) {
  std::map<std::pair<int, int>, int> mid;
  std::vector<Eigen::RowVector3d> V;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) V.push_back(m.V.row(i));
  auto midpoint = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    V.push_back(0.5 * (m.V.row(a) + m.V.row(b)));
    return mid[key] = static_cast<int>(V.size()) - 1;
  };
  SurfaceMesh out;
  out.F.resize(4 * m.F.rows(), 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const int a = m.F(f, 0), b = m.F(f, 1), c = m.F(f, 2);
    const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.F.row(4 * f) << a, ab, ca;
    out.F.row(4 * f + 1) << ab, b, bc;
    out.F.row(4 * f + 2) << ca, bc, c;
    out.F.row(4 * f + 3) << ab, bc, ca;
  }
  out.V.resize(static_cast<Eigen::Index>(V.size()), 3);
  for (size_t i = 0; i < V.size(); ++i) out.V.row(static_cast<Eigen::Index>(i)) = V[i];
  return out;
}

Data& data() {
  static std::unique_ptr<Data> d;
  if (d) return *d;
  d = std::make_unique<Data>();
  LoadOptions keep;
  keep.keep_order = true;
  d->bunny = load_surface(SQUEEZE_TEST_DATA "/bunny00.off", keep);
  if (const char* cached = std::getenv("SQUEEZE_BENCH_TETS")) {  // e.g. from `squeeze mesh bunny00.off`
    d->tets = load_tet_mesh(cached);
  } else {
    std::fprintf(stderr, "bench_ffd: meshing the bunny (about 8 s; set SQUEEZE_BENCH_TETS to skip)...\n");
    d->tets = mesh_surface(load_surface(SQUEEZE_TEST_DATA "/bunny00.off"), MeshOptions{}).tets;
  }
  d->fine = d->bunny;
  for (int level = 0; level < 3; ++level) d->fine = subdivide(d->fine);
  d->deformed = d->tets.V;
  for (Eigen::Index i = 0; i < d->deformed.rows(); ++i) {
    const double z = d->tets.V(i, 2), a = 0.8 * z, c = std::cos(a), s = std::sin(a);
    const double x = d->tets.V(i, 0), y = d->tets.V(i, 1);
    d->deformed.row(i) << 1.1 * (c * x - s * y), 0.9 * (s * x + c * y), z + 0.1 * x;
  }
  d->fine_binding = bind_surface(d->fine.V, d->tets);
  std::fprintf(stderr, "bench_ffd: bunny %lld vertices, coarse mesh %lld tets / %lld vertices, fine %lld vertices\n",
               static_cast<long long>(d->bunny.V.rows()), static_cast<long long>(d->tets.T.rows()),
               static_cast<long long>(d->tets.V.rows()), static_cast<long long>(d->fine.V.rows()));
  return *d;
}

// Best figures of this run, for the summary line.
double g_bind_seconds = 0, g_replay_bytes_per_s = 0, g_replay_vertices_per_s = 0, g_eigen_vertices_per_s = 0,
       g_copy_bytes_per_s = 0;

void BM_BindBunny(benchmark::State& state) {
  Data& d = data();
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    Binding b = bind_surface(d.bunny.V, d.tets);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (g_bind_seconds == 0 || s < g_bind_seconds) g_bind_seconds = s;
    benchmark::DoNotOptimize(b.tet.data());
    state.counters["outside"] = b.outside;
  }
  state.counters["vertices"] = static_cast<double>(d.bunny.V.rows());
}
BENCHMARK(BM_BindBunny)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

void BM_ReplayFine(benchmark::State& state) {
  Data& d = data();
  Eigen::MatrixX3d out;
  replay(d.fine_binding, d.deformed, out);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    replay(d.fine_binding, d.deformed, out);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double vps = static_cast<double>(out.rows()) / s;
    if (vps > g_replay_vertices_per_s) g_replay_vertices_per_s = vps, g_replay_bytes_per_s = vps * kBytesPerVertex;
    benchmark::DoNotOptimize(out.data());
  }
  const double n = static_cast<double>(d.fine.V.rows());
  state.counters["vertices/s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["bytes/s"] = benchmark::Counter(n * kBytesPerVertex, benchmark::Counter::kIsIterationInvariantRate,
                                                 benchmark::Counter::kIs1024);
}
BENCHMARK(BM_ReplayFine)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

// The same product through Eigen's sparse matrix (single-threaded), for comparison.
void BM_ReplayFineEigenSparse(benchmark::State& state) {
  Data& d = data();
  const Eigen::SparseMatrix<double, Eigen::RowMajor> W = weight_matrix(d.fine_binding);
  Eigen::MatrixX3d out = W * d.deformed;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    out.noalias() = W * d.deformed;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    g_eigen_vertices_per_s = std::max(g_eigen_vertices_per_s, static_cast<double>(out.rows()) / s);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["vertices/s"] =
      benchmark::Counter(static_cast<double>(d.fine.V.rows()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ReplayFineEigenSparse)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

void BM_VertexNormalsFine(benchmark::State& state) {
  Data& d = data();
  const Eigen::MatrixX3d V = replay(d.fine_binding, d.deformed);
  for (auto _ : state) benchmark::DoNotOptimize(vertex_normals(V, d.fine.F).data());
  state.counters["vertices/s"] =
      benchmark::Counter(static_cast<double>(V.rows()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_VertexNormalsFine)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

// STREAM "copy": b[i] = a[i] over 2 x 256 MB, parallel like replay; 16 B per element.
void BM_StreamCopy(benchmark::State& state) {
  const size_t n = size_t{32} << 20;
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) a[i] = 1.0 + static_cast<double>(i), b[i] = 0.0;
  });
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) b[i] = a[i];
    });
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    g_copy_bytes_per_s = std::max(g_copy_bytes_per_s, 16.0 * static_cast<double>(n) / s);
    benchmark::DoNotOptimize(b.get());
    benchmark::ClobberMemory();
  }
  state.counters["bytes/s"] = benchmark::Counter(16.0 * static_cast<double>(n),
                                                 benchmark::Counter::kIsIterationInvariantRate,
                                                 benchmark::Counter::kIs1024);
}
BENCHMARK(BM_StreamCopy)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  // Best-of-run figures (decimal GB = 1e9 B).
  if (g_bind_seconds > 0) std::printf("bind bunny: %.3f s (goal < 0.2 s)\n", g_bind_seconds);
  if (g_replay_vertices_per_s > 0)
    std::printf("replay: %.3g vertices/s = %.2f GB/s (Eigen sparse product: %.3g vertices/s)\n",
                g_replay_vertices_per_s, g_replay_bytes_per_s * 1e-9, g_eigen_vertices_per_s);
  if (g_copy_bytes_per_s > 0) std::printf("STREAM copy: %.2f GB/s\n", g_copy_bytes_per_s * 1e-9);
  if (g_replay_bytes_per_s > 0 && g_copy_bytes_per_s > 0)
    std::printf("replay / copy bandwidth: %.2f (goal >= 0.5)\n", g_replay_bytes_per_s / g_copy_bytes_per_s);
  return 0;
}
