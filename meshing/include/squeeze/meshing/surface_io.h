// squeeze::meshing — reading and writing triangle surfaces: through assimp, and by squeeze's own
// readers and writers for the formats in the table of meshing/src/surface_io.cpp (OFF, OBJ).
// To add a format assimp lacks (or reads or writes badly): its reader and/or writer in
// surface_io.cpp and one line in that table.
#pragma once
#include <filesystem>
#include <string>

#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

struct LoadOptions {
  bool merge_coincident = true;  // weld vertices with identical coordinates (across meshes too)
  double weld_tolerance = 1e-12; // ... and, with merge_coincident, those within this fraction of the
                                 // bounding-box diagonal in every coordinate (0: identical only)
  bool drop_degenerate = true;   // drop faces with a repeated vertex index after welding
  bool keep_order = false;       // keep the file's vertices (unreferenced ones too) and faces in file
                                 // order: no welding, no dropping, no assimp post-processing (see below)
  bool assimp_in_child = true;   // formats assimp reads are read in a child process, whose crash (Debian's
                                 // assimp 5.2 frees some 3MF scenes twice) is an InputError; false: in
                                 // this process (the fuzz target, whose coverage the child would not report;
                                 // also, with a warning, where no child process can be started)
};

/// Loads every triangle (and polygon, split as a fan from its first corner: convex polygons only
/// come out right) of every mesh in `path`, in any format assimp reads (OFF, OBJ with or without
/// MTL, PLY ascii/binary, STL ascii/binary, glTF, ...), with node transforms applied, so several
/// meshes in one file come out as one SurfaceMesh. Points and lines are ignored. OFF and OBJ are
/// read by squeeze's own parsers (double precision), the rest by assimp.
/// Returns the mesh; vertices keep first-occurrence order.
/// With `keep_order` (used by `squeeze deform`, whose output must match its input vertex for
/// vertex), V is the file's vertex list as written, unreferenced vertices included, and F its faces
/// in order, polygons split as fans (v0,v[j-1],v[j]); merge_coincident and drop_degenerate are
/// ignored. ASCII OFF and OBJ are read by our own parsers, in double precision (assimp reads OFF in
/// single precision and duplicates OBJ vertices per face corner); PLY comes through assimp, which
/// keeps its vertex list (single precision); STL has no shared vertices at all, so
/// its "vertices" are the three corners of every facet, in facet order. Several meshes in one file
/// are concatenated in node order.
/// Throws InputError ("PATH: problem") if the file is missing or unreadable, the format unknown, it
/// holds no triangle, a coordinate is NaN or infinite, every face is degenerate, or assimp's
/// importer crashes on it (assimp_in_child).
SurfaceMesh load_surface(const std::filesystem::path& path, const LoadOptions& options = {});

/// Writes `mesh` in the format given by the extension of `path` (.off, .obj, .ply, .stl, .glb,
/// .gltf, ... — any format assimp exports), through a temporary file renamed at the end.
/// Throws InputError if the extension is unknown or the file cannot be written.
/// .off and .obj are written by our own writers (17 significant digits, every vertex of V in order,
/// unreferenced ones too); the other formats by assimp, in single precision (ai_real is float).
void save_surface(const std::filesystem::path& path, const SurfaceMesh& mesh);

/// Whether save_surface can write a file with this extension, case-insensitive (checked before
/// long work).
bool is_surface_format(const std::filesystem::path& path);

/// The writable extensions for messages: squeeze's own (.off, .obj), then a few of assimp's:
/// ".off, .obj, .ply, .stl, .gltf, .glb, ...".
std::string surface_format_examples();

}  // namespace squeeze::meshing
