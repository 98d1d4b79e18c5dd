// squeeze::render — H.264 MP4 video of rendered frames, through FFmpeg's libavcodec/libavformat
// (Debian libavcodec-dev, libavformat-dev, libswscale-dev; the H.264 encoder is libx264).
//
//   VideoWriter video("out/video.mp4", 1280, 720, 30.0);
//   for (each frame) video.add(image);   // RGBA8, rows bottom to top (Renderer::draw)
//   video.finish();                      // flushes the encoder, renames into place
#pragma once
#include <filesystem>
#include <memory>
#include <string>

#include "squeeze/render/renderer.h"

namespace squeeze::render {

/// Whether an H.264 encoder is available; if not, `why` (may be null) gets one line saying what to
/// install.
bool video_available(std::string* why = nullptr);

/// Writes frames into an MP4 (H.264, yuv420p, constant frame rate `fps`, CRF 20, one frame per
/// add()) under a temporary name renamed into place by finish(); the destructor removes an
/// unfinished file. yuv420p needs even sides: an odd width or height loses its last column or row
/// (a warning says so). Throws InputError ("PATH: problem") when the encoder is missing, the file
/// cannot be written, or an image has another size.
class VideoWriter {
 public:
  VideoWriter(const std::filesystem::path& path, int width, int height, double fps);
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  /// Encodes one frame: `image` RGBA8, rows bottom to top, width × height as constructed.
  void add(const Image& image);
  /// Flushes the encoder, writes the MP4 index and renames the file into place.
  void finish();
  /// Frames added so far.
  int frames() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace squeeze::render
