// libFuzzer target: every tet-mesh reader (meshing::load_tet_mesh): Medit .mesh, Gmsh .msh, legacy
// VTK .vtk, VTK XML .vtu, TetGen .node/.ele. The first byte picks the format; for TetGen the rest
// is split at the first '\x00' into the .node and the .ele file.
#include <algorithm>

#include "fuzz_common.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/tet_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kExt[] = {".mesh", ".msh", ".vtk", ".vtu", ".ele"};
  const std::string ext = kExt[data[0] % 5];
  ++data, --size;
  std::filesystem::path path;
  if (ext == ".ele") {
    const std::uint8_t* split = std::find(data, data + size, std::uint8_t{0});
    squeeze::fuzz::put("in.node", data, static_cast<size_t>(split - data));
    const size_t rest = split == data + size ? 0 : static_cast<size_t>(data + size - split - 1);
    path = squeeze::fuzz::put("in.ele", split == data + size ? split : split + 1, rest);
  } else {
    path = squeeze::fuzz::put("in" + ext, data, size);
  }
  try {
    squeeze::meshing::load_tet_mesh(path);
  } catch (const squeeze::InputError&) {
  }
  return 0;
}
