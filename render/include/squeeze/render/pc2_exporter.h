// squeeze::render — `--export pc2` and `--export mdd`: point caches (.pc2, .mdd) of the
// high-resolution surfaces, beside a rest OBJ per object.
#pragma once
#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "squeeze/render/exporter.h"

namespace squeeze::render {

/// Writes a point cache frame by frame, in one of the two formats Blender's Mesh Cache modifier
/// (and 3ds Max, LightWave, Houdini) read:
///   pc2  a 32-byte header (char[12] "POINTCACHE2\0", int32 version 1, int32 points, float32 start
///        frame, float32 sample rate, int32 samples), then samples × points × 3 float32 (x, y, z),
///        little-endian;
///   mdd  int32 samples, int32 points, samples × float32 time (s), then samples × points × 3
///        float32 (x, y, z), all big-endian.
/// Written under a temporary name, renamed by close(); the destructor removes an unclosed file.
class PointCacheWriter {
 public:
  enum class Format { pc2, mdd };
  /// `start_frame` is the first sample's frame and `fps` the frames per second: pc2 stores the
  /// start frame and a sample rate of 1 (one sample per frame); mdd stores each sample's time,
  /// (start_frame + i) / fps. Throws InputError ("PATH: cannot open for writing").
  PointCacheWriter(Format format, const std::filesystem::path& path, int points, int samples, float start_frame = 0,
                   double fps = 30);
  ~PointCacheWriter();
  PointCacheWriter(const PointCacheWriter&) = delete;
  PointCacheWriter& operator=(const PointCacheWriter&) = delete;
  /// Appends one sample: V #points by 3 (m). Throws InputError on a write failure or a wrong size.
  void append(const Eigen::MatrixX3d& V);
  /// Checks that every sample was appended, then renames the file into place. Throws InputError.
  void close();

 private:
  void write_or_throw(const void* data, size_t bytes);
  Format format_;
  std::filesystem::path path_, tmp_;
  std::FILE* file_ = nullptr;
  int points_, samples_, written_ = 0;
  std::vector<float> row_;
};

/// A .pc2 writer (PointCacheWriter::Format::pc2) with pc2's own header fields.
class Pc2Writer : public PointCacheWriter {
 public:
  Pc2Writer(const std::filesystem::path& path, int points, int samples, float start_frame = 0, float sample_rate = 1);
};

/// `--export pc2` (and `mdd`), per object: export/NAME.obj, the rest surface (world coordinates, m;
/// exactly the vertices of the rendered surface, in their order: every vertex is used by a face, so
/// Blender's default OBJ importer keeps them all, in this order), written by begin();
/// export/NAME.pc2 (NAME.mdd), one sample per frame of the range, renamed into place by finish().
/// In Blender: import the OBJ with the default axes, add a Mesh Cache modifier with the default
/// axes, and set its Frame Start to the range's first frame (docs/render.md).
class PointCacheExporter final : public Exporter {
 public:
  explicit PointCacheExporter(PointCacheWriter::Format format) : format_(format) {}
  void begin(const ExportContext& context) override;
  void frame(int k, double t, const std::vector<ExportState>& states) override;
  void finish() override;

 private:
  PointCacheWriter::Format format_;
  std::vector<std::unique_ptr<PointCacheWriter>> writers_;  // per object
};

}  // namespace squeeze::render
