// squeeze::meshing — reading and writing tetrahedral meshes.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// One tetrahedral-mesh format: its file extensions and its reader and writer. save_tet_mesh,
/// load_tet_mesh, is_tet_format, their error messages, `squeeze mesh` (help and checks) and the
/// scene loader (fem::object_tet_mesh: tet mesh or surface?) all go through tet_formats().
struct TetFormat {
  /// Extensions, lower case with the dot (".mesh"); matched case-insensitively. Several for a format
  /// written as a set of files (TetGen: {".node", ".ele"}); any of them names the mesh.
  std::vector<std::string> extensions;
  std::string name;         // short name for help texts ("Medit"), or empty when the extension says it
  std::string description;  // one line: what exactly is read and written
  /// Reads the mesh at `path`. Throws InputError ("PATH: problem") as load_tet_mesh says.
  TetMesh (*read)(const std::filesystem::path& path);
  /// Writes `mesh` at `path` (every file of the format), each through a temporary file renamed
  /// at the end. Throws InputError on a write failure.
  void (*write)(const std::filesystem::path& path, const TetMesh& mesh);
};

/// The tetrahedral formats, in the order messages list them:
///   .mesh       Medit (INRIA), ASCII, MeshVersionFormatted 2 (double precision; reads 1 and 2)
///   .msh        Gmsh 2.2 ASCII (element type 4 = 4-node tetrahedron)
///   .vtk        VTK legacy ASCII unstructured grid (cell type 10)
///   .vtu        VTK XML unstructured grid, ASCII
///   .node/.ele  TetGen (0-based, written as a pair; either name may be given)
/// Labels are written as Medit references, Gmsh physical tags, VTK cell data "label" and a TetGen
/// region attribute. To add a format: its reader and writer in meshing/src/tet_io.cpp and one line
/// in the table there (tet_formats()).
const std::vector<TetFormat>& tet_formats();

/// The format of `path` by its extension (case-insensitive), or null.
const TetFormat* find_tet_format(const std::filesystem::path& path);

/// Whether `path` has the extension of a tetrahedral format (find_tet_format is not null).
bool is_tet_format(const std::filesystem::path& path);

/// The extensions of tet_formats() for messages: ".mesh, .msh, .vtk, .vtu or .node/.ele"; with
/// `names`, each followed by its short name if it has one: ".mesh (Medit), .msh (Gmsh 2.2), ...".
std::string tet_format_list(bool names = false);

/// Writes `mesh` in the format of the extension of `path`, through temporary files renamed at the
/// end. For TetGen, writes both PATH.node and PATH.ele.
///   mesh  V #V by 3, T #T by 4, label #T or empty (written as 1)
/// Throws InputError on an unknown extension ("PATH: unknown tetrahedral mesh format '.EXT' (use
/// tet_format_list())") or a write failure.
void save_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh);

/// Reads a mesh written by save_tet_mesh (and the common subsets of these formats written by
/// other tools: Gmsh 2.2 ASCII, Medit ASCII, legacy VTK ASCII, TetGen), in the format of the
/// extension of `path`. Elements other than tetrahedra are ignored.
/// Returns V #V by 3, T #T by 4 (as in the file, not reoriented), label #T (1 where the file has
/// none).
/// Throws InputError ("PATH: problem") if the extension is unknown, the file is missing, malformed,
/// holds no tetrahedron, has an index out of range, or a NaN or infinite coordinate.
TetMesh load_tet_mesh(const std::filesystem::path& path);

}  // namespace squeeze::meshing
