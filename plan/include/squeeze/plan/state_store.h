// squeeze::plan — storage of tree-node states: one block (x rows, then v rows) per deformable
// object, shared with the parent's block when bit-identical (an object at rest, or not touched
// along the branch), so a node costs only the objects that moved.
#pragma once
#include <cstring>
#include <memory>
#include <vector>

#include "squeeze/fem/world.h"

namespace squeeze::plan {

class StateStore {
 public:
  using Block = std::shared_ptr<const std::vector<double>>;
  using Blocks = std::vector<Block>;

  explicit StateStore(const fem::World& w) {
    for (int b = 0; b < w.bodies(); ++b)
      if (w.first_state_row(b) >= 0) objects_.push_back({w.first_state_row(b), w.body(b).vertices()});
  }
  /// The blocks of s; a block equal to the parent's (if given) is shared, not copied. The rest
  /// overlaps (State::overlap), if any, are one more block after the objects'.
  Blocks store(const fem::State& s, const Blocks* parent) {
    Blocks blocks;
    auto keep = [&](const double* p, size_t n, size_t o) {
      if (parent && o < parent->size()) {
        const std::vector<double>& q = *(*parent)[o];
        if (q.size() == n && std::memcmp(q.data(), p, n * sizeof(double)) == 0) {
          blocks.push_back((*parent)[o]);
          return;
        }
      }
      auto blk = std::make_shared<std::vector<double>>(p, p + n);
      bytes_ += n * sizeof(double);
      blocks.push_back(std::move(blk));
    };
    for (size_t o = 0; o < objects_.size(); ++o) {
      const Rows r = objects_[o];
      const size_t n = static_cast<size_t>(r.count) * 3;
      const double* x = s.x.data() + static_cast<size_t>(r.first) * 3;
      const double* v = s.v.data() + static_cast<size_t>(r.first) * 3;
      if (parent) {
        const std::vector<double>& p = *(*parent)[o];
        if (std::memcmp(p.data(), x, n * sizeof(double)) == 0 && std::memcmp(p.data() + n, v, n * sizeof(double)) == 0) {
          blocks.push_back((*parent)[o]);
          continue;
        }
      }
      auto blk = std::make_shared<std::vector<double>>(2 * n);
      std::memcpy(blk->data(), x, n * sizeof(double));
      std::memcpy(blk->data() + n, v, n * sizeof(double));
      bytes_ += 2 * n * sizeof(double);
      blocks.push_back(std::move(blk));
    }
    if (s.overlap.size() > 0) keep(s.overlap.data(), static_cast<size_t>(s.overlap.size()), objects_.size());
    return blocks;
  }
  /// Writes the blocks into s (whose rows and shape must be the world's) and sets its time.
  void restore(const Blocks& blocks, double time, fem::State& s) const {
    for (size_t o = 0; o < objects_.size(); ++o) {
      const Rows r = objects_[o];
      const size_t n = static_cast<size_t>(r.count) * 3;
      const std::vector<double>& b = *blocks[o];
      std::memcpy(s.x.data() + static_cast<size_t>(r.first) * 3, b.data(), n * sizeof(double));
      std::memcpy(s.v.data() + static_cast<size_t>(r.first) * 3, b.data() + n, n * sizeof(double));
    }
    if (blocks.size() > objects_.size()) {
      const std::vector<double>& o = *blocks[objects_.size()];
      s.overlap = Eigen::Map<const Eigen::VectorXd>(o.data(), static_cast<Eigen::Index>(o.size()));
    }
    s.time = time;
  }
  /// Bytes of all blocks stored (shared ones counted once).
  std::size_t bytes() const { return bytes_; }

 private:
  struct Rows {
    int first = 0, count = 0;
  };
  std::vector<Rows> objects_;
  std::size_t bytes_ = 0;
};

}  // namespace squeeze::plan
