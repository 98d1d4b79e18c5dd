// squeeze::render — exports for other tools: Blender point caches (.pc2) and ParaView collections (.pvd).
#pragma once
#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

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

/// Writes a ParaView collection (.pvd) indexing `datasets` = (time in s, file path relative to the
/// .pvd), through a temporary file. Throws InputError.
void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& datasets);

}  // namespace squeeze::render
