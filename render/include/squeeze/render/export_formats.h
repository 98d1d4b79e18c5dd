// squeeze::render — the registry of export formats. `--export NAME,...` of `squeeze render` and
// `squeeze run` (parse_exports in render.h), its help text and the "unknown export" message are
// made from this list, and render_trajectory makes its exporters from it by name.
//
// To add a format: its Exporter (exporter.h) in its own source render/src/NAME_exporter.cpp, which
// also defines `ExportFormat NAME_export_format()` ({name, description, factory}); that file in
// render/CMakeLists.txt; and NAME in the one registration line of render/src/export_formats.cpp
// (docs/render.md, "To add an export format"). A header for the class is optional.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "squeeze/render/exporter.h"

namespace squeeze::render {

/// One export format.
struct ExportFormat {
  std::string name;         // the --export name: a contract (scripts and docs use it); no comma, not "none"
  std::string description;  // one line for --help: what is written, per what
  std::function<std::unique_ptr<Exporter>()> make;  // a fresh exporter (nothing written yet)
};

/// Every registered format, in the order of the help text.
const std::vector<ExportFormat>& export_formats();

/// The format registered as `name`, or nullptr.
const ExportFormat* find_export_format(const std::string& name);

/// The registered names, comma-separated: "pc2, obj, ply, vtu".
std::string export_format_names();

/// The help text of --export: "Comma-separated exports: pc2 (DESCRIPTION), obj (…), …; or none".
std::string export_option_help();

/// Fresh exporters for `names` (registered names, in that order; a repeated name counts once).
/// Throws InputError ("exports: unknown export 'x' (pc2, obj, ply, vtu)") for a name not registered.
std::vector<std::unique_ptr<Exporter>> make_exporters(const std::vector<std::string>& names);

}  // namespace squeeze::render
