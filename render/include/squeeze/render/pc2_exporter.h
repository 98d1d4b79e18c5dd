// squeeze::render — `--export pc2`: Blender point caches (.pc2) of the high-resolution surfaces.
#pragma once
#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "squeeze/render/exporter.h"

namespace squeeze::render {

/// Writes a point cache (.pc2) frame by frame, as Blender's Mesh Cache modifier reads it:
/// a 32-byte header (char[12] "POINTCACHE2\0", int32 version 1, int32 points, float32 start frame,
/// float32 sample rate, int32 samples), then samples × points × 3 float32 (x, y, z), little-endian.
/// Written under a temporary name, renamed by close(); the destructor removes an unclosed file.
class Pc2Writer {
 public:
  /// Throws InputError ("PATH: cannot open for writing").
  Pc2Writer(const std::filesystem::path& path, int points, int samples, float start_frame = 0,
            float sample_rate = 1);
  ~Pc2Writer();
  Pc2Writer(const Pc2Writer&) = delete;
  Pc2Writer& operator=(const Pc2Writer&) = delete;
  /// Appends one sample: V #points by 3 (m). Throws InputError on a write failure or a wrong size.
  void append(const Eigen::MatrixX3d& V);
  /// Checks that every sample was appended, then renames the file into place. Throws InputError.
  void close();

 private:
  std::filesystem::path path_, tmp_;
  std::FILE* file_ = nullptr;
  int points_, samples_, written_ = 0;
  std::vector<float> row_;
};

/// `--export pc2`, per object: export/NAME.obj, the rest surface (world coordinates, m; our OBJ
/// writer keeps the vertex order), written by begin(); export/NAME.pc2, one sample per frame of the
/// range (start frame: the range's first, sample rate 1), renamed into place by finish().
class Pc2Exporter final : public Exporter {
 public:
  void begin(const ExportContext& context) override;
  void frame(int k, double t, const std::vector<ExportState>& states) override;
  void finish() override;

 private:
  std::vector<std::unique_ptr<Pc2Writer>> writers_;  // per object
};

}  // namespace squeeze::render
