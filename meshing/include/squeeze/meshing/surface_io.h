// squeeze::meshing — reading and writing triangle surfaces through assimp.
#pragma once
#include <filesystem>

#include "squeeze/meshing/surface.h"

namespace squeeze {

struct LoadOptions {
  bool merge_coincident = true;  // weld vertices with identical coordinates (across meshes too)
  bool drop_degenerate = true;   // drop faces with a repeated vertex index after welding
};

/// Loads every triangle (and polygon, triangulated) of every mesh in `path`, in any format assimp
/// reads (OFF, OBJ with or without MTL, PLY ascii/binary, STL ascii/binary, glTF, ...), with node
/// transforms applied, so several meshes in one file come out as one SurfaceMesh. Points and lines
/// are ignored.
/// Returns the mesh; vertices keep first-occurrence order.
/// Throws InputError ("PATH: problem") if the file is missing or unreadable, the format unknown, it
/// holds no triangle, a coordinate is NaN or infinite, or every face is degenerate.
SurfaceMesh load_surface(const std::filesystem::path& path, const LoadOptions& options = {});

/// Writes `mesh` in the format given by the extension of `path` (.off, .obj, .ply, .stl, .glb,
/// .gltf, ... — any format assimp exports), through a temporary file renamed at the end.
/// Throws InputError if the extension is unknown or the file cannot be written.
void save_surface(const std::filesystem::path& path, const SurfaceMesh& mesh);

}  // namespace squeeze
