// squeeze::common — progress display on stderr for long work.
#pragma once
#include <chrono>
#include <mutex>
#include <string>

namespace squeeze {

/// A one-line progress display on stderr. It stays silent for the first second (short work prints
/// nothing), redraws at most 10 times a second, and is off when disabled (`--quiet`) or when
/// stderr is not a terminal and verbosity is normal (CI logs get one line per stage instead).
/// Thread-safe: update() may be called from worker threads.
class Progress {
 public:
  /// `enabled` false: prints nothing at all.
  explicit Progress(bool enabled);
  ~Progress();

  /// Starts a named stage (e.g. "decomposing"); `total` 0 means unknown.
  void stage(const std::string& name, double total = 0.0);
  /// Reports `done` units of the current stage's total.
  void update(double done);
  /// Ends the current stage (prints its elapsed time once something was shown).
  void finish();

 private:
  void draw(bool final_line);
  bool enabled_;
  bool tty_;
  bool shown_ = false;
  std::string name_;
  double total_ = 0.0, done_ = 0.0;
  std::chrono::steady_clock::time_point start_, last_draw_;
  std::mutex mutex_;
};

}  // namespace squeeze
