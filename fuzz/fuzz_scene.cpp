// libFuzzer target: the scene loader (fem::load_scene: JSON parsing and every key's validation; no
// meshing). The input is the scene file; a tetrahedron "a.mesh" lies beside it for objects to name.
#include "fuzz_common.h"
#include "squeeze/common/error.h"
#include "squeeze/fem/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  static const bool mesh_written = [] {
    const std::string tet = "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
                            "Tetrahedra\n1\n1 2 3 4 1\nEnd\n";
    squeeze::fuzz::put("a.mesh", reinterpret_cast<const std::uint8_t*>(tet.data()), tet.size());
    return true;
  }();
  (void)mesh_written;
  const auto path = squeeze::fuzz::put("scene.json", data, size);
  try {
    squeeze::fem::load_scene(path);
  } catch (const squeeze::InputError&) {
  }
  return 0;
}
