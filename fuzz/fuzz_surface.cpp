// libFuzzer target: the surface loader (meshing::load_surface) on OFF, OBJ, PLY and STL. The first
// byte picks the format (the extension the loader dispatches on) and the load mode; the rest is
// the file.
#include "fuzz_common.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/surface_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kExt[] = {".off", ".obj", ".ply", ".stl"};
  const auto path = squeeze::fuzz::put(std::string("in") + kExt[data[0] % 4], data + 1, size - 1);
  squeeze::meshing::LoadOptions o;
  o.keep_order = (data[0] >> 2) & 1;
  try {
    squeeze::meshing::load_surface(path, o);
  } catch (const squeeze::InputError&) {
  }
  return 0;
}
