// squeeze::render — PNG files through libpng, and a background encoder thread.
#pragma once
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include "squeeze/render/renderer.h"

namespace squeeze::render {

/// Writes `image` (RGBA8, rows bottom to top) as an 8-bit RGB PNG, top row first, through a
/// temporary file renamed into place (write_atomically): no half-written PNG is ever left.
/// `compression` is zlib's level, 0-9 (1: fast); Sub filter, run-length strategy (~20 ms and
/// ~170 kB for a 1280×720 frame).
/// Throws InputError ("PATH: problem") if the file cannot be written.
void write_png(const std::filesystem::path& path, const Image& image, int compression = 1);

/// An 8-bit PNG read back for tests and checks: pixels RGB (3 bytes) or RGBA (4), rows top to bottom.
struct PngImage {
  int width = 0, height = 0, channels = 0;
  std::vector<std::uint8_t> pixels;
};
/// Throws InputError ("PATH: not a valid PNG: reason").
PngImage read_png(const std::filesystem::path& path);

/// Encodes images on one background thread while the caller renders the next one. A bounded queue
/// (`capacity` images) applies back-pressure. The first error of the thread is rethrown by the next
/// push() or by finish(); images queued after it are dropped.
class PngWriter {
 public:
  explicit PngWriter(int capacity = 2, int compression = 1);
  ~PngWriter();  // waits for the queue (errors are lost here: call finish() to see them)
  PngWriter(const PngWriter&) = delete;
  PngWriter& operator=(const PngWriter&) = delete;

  /// Queues `image` (moved from) for `path`; blocks while the queue is full.
  void push(const std::filesystem::path& path, Image&& image);
  /// Waits until every queued image is written; rethrows the thread's first error.
  void finish();
  /// Gives `image` the pixel buffer of an image already written, if one is free (saves
  /// allocating and faulting in a fresh buffer per frame); otherwise leaves it as it is.
  void recycle(Image& image);

 private:
  void run();
  void rethrow();
  struct Job {
    std::filesystem::path path;
    Image image;
  };
  int capacity_, compression_;
  std::deque<Job> queue_;
  std::vector<std::vector<std::uint8_t>> spare_;  // pixel buffers of written images
  std::mutex mutex_;
  std::condition_variable changed_;
  bool stop_ = false, busy_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace squeeze::render
