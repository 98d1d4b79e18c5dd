// squeeze::meshing — the quality figures of a tetrahedral mesh reported by `squeeze mesh`
// (mesh_pipeline.h's report, docs/meshing.md).
#pragma once
#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

/// Quality figures of a tetrahedral mesh.
struct TetQuality {
  int tets = 0, vertices = 0;
  double min_volume = 0, volume = 0;         // units³: smallest signed tet volume, sum of them
  double min_dihedral = 0, max_dihedral = 0; // degrees, over all tetrahedra (dihedral_angles)
  double min_edge = 0, mean_edge = 0;        // units, over the mesh's unique edges
  int components = 0;                        // face-connected components (tet_components)
  int overshared_faces = 0;                  // faces shared by three or more tetrahedra (must be 0)
};

/// The quality figures of `mesh` (all 0 but `vertices` for a mesh without tetrahedra).
///   mesh  V #V by 3 (units), T #T by 4 positively oriented
TetQuality tet_quality(const TetMesh& mesh);

}  // namespace squeeze::meshing
