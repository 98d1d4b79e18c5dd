// squeeze::render — `--export obj` and `--export ply`: the deformed high-resolution surfaces,
// one file per frame and object.
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "squeeze/render/exporter.h"

namespace squeeze::render {

/// Per frame and object, export/EXT/NAME_00000.EXT: the deformed surface in any format
/// meshing::save_surface writes, chosen by EXT ("obj": our OBJ writer, vertex order kept, double
/// precision; "ply": through assimp, single precision). Each file is renamed into place when
/// written; finish() has nothing left to do.
class SurfaceFramesExporter final : public Exporter {
 public:
  /// `extension` without the dot, e.g. "obj"; it also names the subfolder.
  explicit SurfaceFramesExporter(std::string extension);
  void begin(const ExportContext& context) override;
  void frame(int k, double t, const std::vector<ExportState>& states) override;
  void finish() override {}

 private:
  std::string extension_;
  std::filesystem::path folder_;  // OUT/export/EXT
  std::vector<std::string> names_;
  std::vector<Eigen::MatrixX3i> faces_;
};

}  // namespace squeeze::render
