// The output of `squeeze simulate` and `squeeze replay`: DIR/metrics.csv (one row per frame) and
// DIR/trajectory/ (index.json, rest meshes, one binary frame per output frame). Formats:
// scenes/README.md ("Metrics" and "Trajectory format"). Everything is written into a temporary
// folder and moved into place by commit(); if the writer is destroyed before, nothing is left.
#pragma once
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "squeeze/fem/scene.h"

namespace squeeze::cli {

class TrajectoryWriter {
 public:
  /// world: the scene's world (used for metrics: contacts are computed on it for every frame).
  /// output: DIR (created if missing; its parent must exist). Throws InputError on a bad DIR.
  TrajectoryWriter(fem::SceneWorld& world, const std::string& output, double fps, double time_step, int frames);
  ~TrajectoryWriter();
  /// Appends frame number `frames_written()` at time t (s).
  void add_frame(const fem::State& s, double t);
  int frames_written() const { return written_; }
  /// Writes index.json and metrics.csv and moves the trajectory into place.
  void commit();

 private:
  fem::SceneWorld& w_;
  std::filesystem::path out_, tmp_;
  bool created_ = false, committed_ = false;
  int frames_ = 0, written_ = 0;
  double fps_ = 30, h_ = 0;
  std::ostringstream csv_;
  std::vector<double> buffer_;
  std::string index_;
};

}  // namespace squeeze::cli
