// squeeze::meshing (internal) — a memo of a pure inside/outside test, keyed by the exact bits of
// the query point.
//
// Mesh_3 asks its implicit domain about the same points again and again: a facet's dual segment
// is bisected whenever the facet is (re)examined, cell circumcentres are shared by the facets
// around them, and a resumed refine_mesh_3 (the cover pass of winding_number_surface) rescans
// every facet of the complex. On the heart at 500 tetrahedra, 1.45 M calls of the winding-number
// solid's test ask about 0.81 M distinct points. The test is a pure function of the point, so
// answering a repeated point from the memo gives bit-identical meshes.
//
// Open addressing with linear probing over a power-of-two table of 32-byte slots, grown at half
// load up to `max_slots` (then new points are answered but no longer remembered). Not
// thread-safe: one memo per caller (Mesh_3 runs Sequential_tag here).
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

namespace squeeze::meshing::detail {

class LabelMemo {
 public:
  /// max_slots  power of two >= 2: the table's largest size (32 bytes a slot; the default, 2^23,
  ///            is 256 MiB and remembers about 4.2 M points)
  explicit LabelMemo(std::size_t max_slots = std::size_t{1} << 23) : max_slots_(max_slots) {
    slots_.resize(std::min<std::size_t>(max_slots, 1 << 12));
  }

  /// The label of p: test(p) the first time p is asked (bit for bit), the remembered one after.
  template <class Test>
  bool operator()(const Eigen::Vector3d& p, const Test& test) {
    std::uint64_t k[3];
    std::memcpy(k, p.data(), sizeof k);
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(k) & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (s.state == 0) {  // empty: not seen
        const bool label = test(p);
        if (used_ + 1 > slots_.size() / 2) {
          if (slots_.size() >= max_slots_) return label;  // full: answer, do not remember
          grow();
        }
        insert(k, label);
        return label;
      }
      if (s.key[0] == k[0] && s.key[1] == k[1] && s.key[2] == k[2]) {
        ++hits_;
        return s.state == 2;
      }
    }
  }
  std::size_t remembered() const { return used_; }
  std::size_t hits() const { return hits_; }

 private:
  struct Slot {
    std::uint64_t key[3] = {0, 0, 0};  // the bits of x, y, z
    std::uint8_t state = 0;            // 0 empty, 1 outside, 2 inside
  };
  static std::size_t hash(const std::uint64_t* k) {
    std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
    h = (h ^ (h >> 29) ^ k[1]) * 0xBF58476D1CE4E5B9ull;
    h = (h ^ (h >> 31) ^ k[2]) * 0x94D049BB133111EBull;
    return static_cast<std::size_t>(h ^ (h >> 32));
  }
  void insert(const std::uint64_t* k, bool label) {
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = hash(k) & mask;
    while (slots_[i].state != 0) i = (i + 1) & mask;
    slots_[i] = Slot{{k[0], k[1], k[2]}, static_cast<std::uint8_t>(label ? 2 : 1)};
    ++used_;
  }
  void grow() {
    std::vector<Slot> old(slots_.size() * 2);
    old.swap(slots_);
    used_ = 0;
    for (const Slot& s : old)
      if (s.state != 0) insert(s.key, s.state == 2);
  }
  std::vector<Slot> slots_;
  std::size_t used_ = 0, hits_ = 0;
  std::size_t max_slots_;
};

}  // namespace squeeze::meshing::detail
