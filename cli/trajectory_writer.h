// The output of `squeeze simulate` and `squeeze replay`: DIR/metrics.csv (one row per frame) and
// DIR/trajectory/ (index.json, rest meshes, one binary frame per output frame). Formats:
// scenes/README.md ("Metrics" and "Trajectory format"). The writer fills a folder that is not yet
// visible — the staging folder of a FolderReplacement (common/atomic_file.h), which the command
// swaps into place after commit(); index.json and metrics.csv are written last, by commit().
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
  /// folder: an existing, empty folder (FolderReplacement::staging()). Throws InputError when it
  /// cannot be written.
  TrajectoryWriter(fem::SceneWorld& world, const std::filesystem::path& folder, double fps, double time_step, int frames);
  /// Appends frame number `frames_written()` at time t (s).
  void add_frame(const fem::State& s, double t);
  int frames_written() const { return written_; }
  /// Writes trajectory/index.json and metrics.csv.
  void commit();

 private:
  fem::SceneWorld& w_;
  std::filesystem::path out_, tmp_;  // the folder; its trajectory/
  int frames_ = 0, written_ = 0;
  double fps_ = 30, h_ = 0;
  std::ostringstream csv_;
  std::vector<double> buffer_;
  std::string index_;
};

}  // namespace squeeze::cli
