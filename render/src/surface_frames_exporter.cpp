#include "squeeze/render/export_formats.h"
#include "squeeze/render/surface_frames_exporter.h"

#include <system_error>
#include <utility>

#include "squeeze/common/error.h"
#include "squeeze/meshing/surface_io.h"

namespace squeeze::render {
namespace fs = std::filesystem;

SurfaceFramesExporter::SurfaceFramesExporter(std::string extension) : extension_(std::move(extension)) {}

void SurfaceFramesExporter::begin(const ExportContext& c) {
  folder_ = c.folder / extension_;
  std::error_code ec;
  fs::create_directories(folder_, ec);
  if (ec) throw InputError(folder_.string() + ": cannot create the directory: " + ec.message());
  names_.clear();
  faces_.clear();
  for (const ExportObject& ob : c.objects) {
    names_.push_back(ob.name);
    faces_.push_back(ob.faces);
  }
}

void SurfaceFramesExporter::frame(int k, double, const std::vector<ExportState>& states) {
  for (size_t b = 0; b < names_.size(); ++b)
    meshing::save_surface(folder_ / frame_file_name(names_[b] + "_", k, "." + extension_),
                          meshing::SurfaceMesh{states[b].surface, faces_[b]});
}

ExportFormat obj_export_format() {
  return {"obj", "deformed surface per frame and object", [] { return std::make_unique<SurfaceFramesExporter>("obj"); }};
}

ExportFormat ply_export_format() {
  return {"ply", "the same as PLY, single precision", [] { return std::make_unique<SurfaceFramesExporter>("ply"); }};
}

}  // namespace squeeze::render
