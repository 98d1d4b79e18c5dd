// squeeze::render — `--export vtu`: the coarse tet meshes per frame for ParaView (.vtu + .pvd).
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "squeeze/render/exporter.h"

namespace squeeze::render {

/// Writes a ParaView collection (.pvd) indexing `datasets` = (time in s, file path relative to the
/// .pvd), through a temporary file. Throws InputError.
void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& datasets);

/// `--export vtu`: export/vtu/NAME_00000.vtu per frame and object (the deformed coarse tet mesh,
/// VTK XML, ASCII), and per object export/NAME.pvd, a ParaView collection indexing them by time
/// (s), written by finish().
class VtuExporter final : public Exporter {
 public:
  void begin(const ExportContext& context) override;
  void frame(int k, double t, const std::vector<ExportState>& states) override;
  void finish() override;

 private:
  std::filesystem::path folder_;  // OUT/export
  std::vector<std::string> names_;
  std::vector<Eigen::MatrixX4i> tets_;
  std::vector<std::vector<std::pair<double, std::string>>> datasets_;  // per object: (t, vtu/FILE)
};

}  // namespace squeeze::render
