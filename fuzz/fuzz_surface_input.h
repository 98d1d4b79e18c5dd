// The layout of a fuzz_surface input, shared by the harness (fuzz/fuzz_surface.cpp) and the test
// that replays its findings (tests/test_reliability.cpp), so that both read a kept input alike:
// the first byte picks the file extension (the loader dispatches on it) and the load mode; the
// rest of the bytes are the file.
#pragma once
#include <cstdint>

namespace squeeze::fuzz {

struct SurfaceInput {
  const char* extension;  // ".off", ".obj", ".ply" or ".stl"
  bool keep_order;        // meshing::LoadOptions::keep_order
};

/// What the first byte of a fuzz_surface input selects.
inline SurfaceInput surface_input(std::uint8_t first) {
  static const char* const kExtensions[] = {".off", ".obj", ".ply", ".stl"};
  return {kExtensions[first % 4], ((first >> 2) & 1) != 0};
}

}  // namespace squeeze::fuzz
