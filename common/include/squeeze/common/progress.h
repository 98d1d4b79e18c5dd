// squeeze::common — progress display on stderr for long work.
#pragma once
#include <chrono>
#include <mutex>
#include <string>

namespace squeeze {

/// A one-line progress display on stderr: "squeeze: STAGE: 42% (420/1000), 12.5/s, 46 s left,
/// 3.4 s | DETAIL". It stays silent for the first second (short work prints nothing), redraws at
/// most 10 times a second on a terminal; when stderr is not a terminal (CI logs) it prints a line
/// at most every 10 s and one at the end of the stage. Off when disabled (`--quiet`).
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
  /// The same with a short free text shown after the figures (e.g. "nodes 120, best 0.31 m").
  void update(double done, const std::string& detail);
  /// Ends the current stage (prints its elapsed time once something was shown).
  void finish();

 private:
  void draw(bool final_line);
  bool enabled_;
  bool tty_;
  bool shown_ = false;
  std::string name_, detail_;
  double total_ = 0.0, done_ = 0.0;
  std::chrono::steady_clock::time_point start_, last_draw_;
  std::mutex mutex_;
};

}  // namespace squeeze
