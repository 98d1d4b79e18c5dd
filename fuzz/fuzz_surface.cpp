// libFuzzer target: the surface loader (meshing::load_surface) on OFF, OBJ, PLY and STL. The first
// byte picks the format (the extension the loader dispatches on) and the load mode; the rest is
// the file.
#include "fuzz_common.h"
#include "fuzz_surface_input.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/surface_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const squeeze::fuzz::SurfaceInput in = squeeze::fuzz::surface_input(data[0]);
  const auto path = squeeze::fuzz::put(std::string("in") + in.extension, data + 1, size - 1);
  squeeze::meshing::LoadOptions o;
  o.keep_order = in.keep_order;
  o.assimp_in_child = false;  // (libFuzzer sees crashes and coverage in this process only)
  try {
    squeeze::meshing::load_surface(path, o);
  } catch (const squeeze::InputError&) {
  }
  return 0;
}
