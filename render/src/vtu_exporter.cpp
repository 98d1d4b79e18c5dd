#include "squeeze/render/export_formats.h"
#include "squeeze/render/vtu_exporter.h"

#include <fstream>
#include <iomanip>
#include <system_error>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/tet_io.h"

namespace squeeze::render {
namespace fs = std::filesystem;

void write_pvd(const fs::path& path, const std::vector<std::pair<double, std::string>>& datasets) {
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream o(tmp);
    o << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
         "  <Collection>\n";
    o << std::setprecision(9);
    for (const auto& [t, file] : datasets)
      o << "    <DataSet timestep=\"" << t << "\" group=\"\" part=\"0\" file=\"" << file << "\"/>\n";
    o << "  </Collection>\n</VTKFile>\n";
    if (!o) throw InputError(path.string() + ": write failed");
  });
}

void VtuExporter::begin(const ExportContext& c) {
  folder_ = c.folder;
  std::error_code ec;
  fs::create_directories(folder_ / "vtu", ec);
  if (ec) throw InputError((folder_ / "vtu").string() + ": cannot create the directory: " + ec.message());
  names_.clear();
  tets_.clear();
  for (const ExportObject& ob : c.objects) {
    names_.push_back(ob.name);
    tets_.push_back(ob.tets);
  }
  datasets_.assign(c.objects.size(), {});
}

void VtuExporter::frame(int k, double t, const std::vector<ExportState>& states) {
  for (size_t b = 0; b < names_.size(); ++b) {
    meshing::TetMesh mesh;
    mesh.V = states[b].coarse;
    mesh.T = tets_[b];
    const std::string file = "vtu/" + frame_file_name(names_[b] + "_", k, ".vtu");
    meshing::save_tet_mesh(folder_ / file, mesh);
    datasets_[b].emplace_back(t, file);
  }
}

void VtuExporter::finish() {
  for (size_t b = 0; b < names_.size(); ++b) write_pvd(folder_ / (names_[b] + ".pvd"), datasets_[b]);
}

ExportFormat vtu_export_format() {
  return {"vtu", "coarse tet meshes per frame + .pvd for ParaView", [] { return std::make_unique<VtuExporter>(); }};
}

}  // namespace squeeze::render
