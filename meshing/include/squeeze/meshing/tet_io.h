// squeeze::meshing — reading and writing tetrahedral meshes.
#pragma once
#include <filesystem>
#include <string>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// The tetrahedral formats, chosen by extension:
///   .mesh       Medit (INRIA), ASCII, MeshVersionFormatted 1
///   .msh        Gmsh 2.2 ASCII (element type 4 = 4-node tetrahedron)
///   .vtk        VTK legacy ASCII unstructured grid (cell type 10)
///   .vtu        VTK XML unstructured grid, ASCII
///   .node/.ele  TetGen (0-based, written as a pair; either name may be given)
/// Labels are written as Medit references, Gmsh physical tags, VTK cell data "label" and a TetGen
/// region attribute.
bool is_tet_format(const std::filesystem::path& path);

/// Writes `mesh` by the extension of `path`, through temporary files renamed at the end. For
/// TetGen, writes both PATH.node and PATH.ele.
/// Throws InputError on an unknown extension or a write failure.
void save_tet_mesh(const std::filesystem::path& path, const TetMesh& mesh);

/// Reads a mesh written by save_tet_mesh (and the common subsets of these formats written by
/// other tools: Gmsh 2.2 ASCII, Medit ASCII, legacy VTK ASCII, TetGen). Elements other than
/// tetrahedra are ignored.
/// Throws InputError ("PATH: problem") if the file is missing, malformed, holds no tetrahedron,
/// has an index out of range, or a NaN or infinite coordinate.
TetMesh load_tet_mesh(const std::filesystem::path& path);

}  // namespace squeeze::meshing
