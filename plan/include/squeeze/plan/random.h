// squeeze::plan — the planners' random stream: small and fully specified (the standard
// distributions are not portable across library implementations; a plan must replay the same
// everywhere). splitmix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators",
// OOPSLA 2014).
#pragma once
#include <cstdint>

namespace squeeze::plan {

class Random {
 public:
  // The seed is mixed first: splitmix64 walks one Weyl sequence, and seeds k and k + 1 used directly
  // would start one draw apart on it (correlated streams).
  explicit Random(std::uint64_t seed) : s_(mix(seed + 0xD1B54A32D192ED03ULL)) {}
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  std::uint64_t next() { return mix(s_ += 0x9E3779B97F4A7C15ULL); }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }  // [lo, hi)
  int index(int n) { return static_cast<int>(uniform() * n); }                 // [0, n)

 private:
  std::uint64_t s_;
};

}  // namespace squeeze::plan
