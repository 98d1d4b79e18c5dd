#include "squeeze/render/export_formats.h"

#include <algorithm>

#include "squeeze/common/error.h"

namespace squeeze::render {

// The registry: one line names every export format, in the order of the help text. Each NAME is
// defined in its exporter's source (render/src/*_exporter.cpp) as `ExportFormat NAME_export_format()`.
#define SQUEEZE_EXPORT_FORMATS(X) X(pc2) X(obj) X(ply) X(vtu) X(mdd) X(glb)

#define SQUEEZE_DECLARE_FORMAT(NAME) ExportFormat NAME##_export_format();
SQUEEZE_EXPORT_FORMATS(SQUEEZE_DECLARE_FORMAT)
#undef SQUEEZE_DECLARE_FORMAT

const std::vector<ExportFormat>& export_formats() {
#define SQUEEZE_FORMAT_ENTRY(NAME) NAME##_export_format(),
  static const std::vector<ExportFormat> formats = {SQUEEZE_EXPORT_FORMATS(SQUEEZE_FORMAT_ENTRY)};
#undef SQUEEZE_FORMAT_ENTRY
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
