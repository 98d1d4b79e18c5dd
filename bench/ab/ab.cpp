// Interleaved A/B timing of fem builds in one process (for a noisy machine): each library (built
// by mklib.sh from a source tree) steps its own copy of the bench_fem scene; the libraries take
// turns, `steps` steps each, for `rounds` rounds, and the tool prints per library the min, first
// quartile and median ns per tet-step, the final state hash (equal hashes: same physics), and per
// library the median over rounds of its time divided by the first library's.
// Usage: ab N THREADS ROUNDS STEPS LIB.so...
#include <dlfcn.h>
#include <tbb/global_control.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>
int main(int argc, char** argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: ab N THREADS ROUNDS STEPS LIB.so... (e.g. ab 7 2 30 300 base.so new.so)\n");
    return 2;
  }
  const int n = atoi(argv[1]), threads = atoi(argv[2]), rounds = atoi(argv[3]), steps = atoi(argv[4]);
  if (n < 1 || threads < 1 || rounds < 1 || steps < 1) {
    fprintf(stderr, "ab: N, THREADS, ROUNDS and STEPS must be positive integers\n");
    return 2;
  }
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  struct L { std::string name; void (*setup)(int); double (*run)(int); unsigned long long (*hash)(); std::vector<double> t; };
  std::vector<L> libs;
  for (int a = 5; a < argc; ++a) {
    void* h = dlopen(argv[a], RTLD_NOW | RTLD_LOCAL);
    if (!h) { fprintf(stderr, "ab: %s\n", dlerror()); return 1; }
    libs.push_back({argv[a], (void (*)(int))dlsym(h, "setup"), (double (*)(int))dlsym(h, "run"),
                    (unsigned long long (*)())dlsym(h, "state_hash"), {}});
    if (!libs.back().setup || !libs.back().run || !libs.back().hash) {
      fprintf(stderr, "ab: %s: not built by mklib.sh (no setup / run / state_hash)\n", argv[a]);
      return 1;
    }
  }
  for (auto& l : libs) l.setup(n);
  for (int r = 0; r < rounds; ++r)
    for (size_t i = 0; i < libs.size(); ++i) { auto& l = libs[(i + r) % libs.size()]; l.t.push_back(l.run(steps)); }
  for (auto& l : libs) {
    std::vector<double> t = l.t; std::sort(t.begin(), t.end());
    printf("%-28s min %6.2f  q25 %6.2f  median %6.2f  hash %016llx\n", l.name.c_str(), t[0], t[t.size() / 4], t[t.size() / 2], l.hash());
  }
  for (size_t i = 1; i < libs.size(); ++i) {
    std::vector<double> q;
    for (int r = 0; r < rounds; ++r) q.push_back(libs[i].t[r] / libs[0].t[r]);
    std::sort(q.begin(), q.end());
    printf("%s / %s: median ratio of rounds %.3f (q25 %.3f, q75 %.3f)\n", libs[i].name.c_str(), libs[0].name.c_str(), q[q.size() / 2], q[q.size() / 4], q[3 * q.size() / 4]);
  }
}
