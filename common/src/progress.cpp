#include "squeeze/common/progress.h"

#include <unistd.h>

#include <cstdio>

namespace squeeze {
using clock = std::chrono::steady_clock;

Progress::Progress(bool enabled) : enabled_(enabled), tty_(::isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() { finish(); }

void Progress::stage(const std::string& name, double total) {
  finish();
  std::lock_guard<std::mutex> lock(mutex_);
  name_ = name;
  detail_.clear();
  total_ = total;
  done_ = 0.0;
  shown_ = false;
  start_ = last_draw_ = clock::now();
}

void Progress::update(double done) {
  if (!enabled_) return;
  std::string detail;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    detail = detail_;
  }
  update(done, detail);
}

void Progress::update(double done, const std::string& detail) {
  if (!enabled_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = done;
  detail_ = detail;
  const auto now = clock::now();
  if (now - start_ < std::chrono::seconds(1)) return;
  if (shown_ && now - last_draw_ < std::chrono::milliseconds(tty_ ? 100 : 10000)) return;
  last_draw_ = now;
  draw(false);
}

void Progress::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!enabled_ || name_.empty()) return;
  if (shown_) draw(true);
  name_.clear();
}

void Progress::draw(bool final_line) {
  const double secs = std::chrono::duration<double>(clock::now() - start_).count();
  char buf[256];
  if (total_ > 0.0 && !final_line) {
    const double rate = secs > 0 ? done_ / secs : 0.0;
    char eta[48] = "";
    if (rate > 0 && done_ < total_) std::snprintf(eta, sizeof eta, ", %.0f s left", (total_ - done_) / rate);
    std::snprintf(buf, sizeof buf, "%s: %.0f%% (%.0f/%.0f), %.3g/s%s, %.1f s", name_.c_str(),
                  100.0 * done_ / total_, done_, total_, rate, eta, secs);
  } else {
    std::snprintf(buf, sizeof buf, "%s: %s %.1f s", name_.c_str(), final_line ? "done in" : "",
                  secs);
  }
  const std::string tail = detail_.empty() ? "" : " | " + detail_;
  if (tty_)
    std::fprintf(stderr, "\r\033[Ksqueeze: %s%s%s", buf, tail.c_str(), final_line ? "\n" : "");
  else
    std::fprintf(stderr, "squeeze: %s%s\n", buf, tail.c_str());
  std::fflush(stderr);
  shown_ = true;
}

}  // namespace squeeze
