#include "squeeze/render/export_formats.h"

#include <algorithm>

#include "squeeze/common/error.h"
#include "squeeze/render/pc2_exporter.h"
#include "squeeze/render/surface_frames_exporter.h"
#include "squeeze/render/vtu_exporter.h"

namespace squeeze::render {

const std::vector<ExportFormat>& export_formats() {
  // One line per format: {name, one-line description, factory}.
  static const std::vector<ExportFormat> formats = {
      {"pc2", "rest OBJ + Blender point cache per object", [] { return std::make_unique<Pc2Exporter>(); }},
      {"obj", "deformed surface per frame and object", [] { return std::make_unique<SurfaceFramesExporter>("obj"); }},
      {"ply", "the same as PLY, single precision", [] { return std::make_unique<SurfaceFramesExporter>("ply"); }},
      {"vtu", "coarse tet meshes per frame + .pvd for ParaView", [] { return std::make_unique<VtuExporter>(); }},
  };
  return formats;
}

const ExportFormat* find_export_format(const std::string& name) {
  for (const ExportFormat& f : export_formats())
    if (f.name == name) return &f;
  return nullptr;
}

std::string export_format_names() {
  std::string s;
  for (const ExportFormat& f : export_formats()) s += (s.empty() ? "" : ", ") + f.name;
  return s;
}

std::string export_option_help() {
  std::string list;
  for (const ExportFormat& f : export_formats()) list += (list.empty() ? "" : ", ") + f.name + " (" + f.description + ")";
  return "Comma-separated exports: " + list + "; or none";
}

std::vector<std::unique_ptr<Exporter>> make_exporters(const std::vector<std::string>& names) {
  std::vector<std::unique_ptr<Exporter>> exporters;
  std::vector<std::string> made;
  for (const std::string& name : names) {
    const ExportFormat* f = find_export_format(name);
    if (!f) throw InputError("exports: unknown export '" + name + "' (" + export_format_names() + ")");
    if (std::find(made.begin(), made.end(), name) != made.end()) continue;
    made.push_back(name);
    exporters.push_back(f->make());
  }
  return exporters;
}

}  // namespace squeeze::render
