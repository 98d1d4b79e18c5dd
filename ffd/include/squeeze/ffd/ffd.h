// squeeze::ffd — free-form deformation of high-resolution surfaces by a coarse tetrahedral mesh
// (Rodriguez, Lien, Amato, ICRA 2006, Section VI-A: "deformations applied to the tetrahedral
// meshes are indirectly applied to the enclosed geometry using Free Form Deformation, which
// computes the global coordinates of each vertex x of the geometry at every simulation time step
// using the barycentric coordinates of x in x's enclosing tetrahedron").
//
// The planner and the simulator only see the coarse mesh. bind_surface() attaches every surface vertex to
// one tetrahedron of the rest mesh with its four barycentric coordinates (the rows of a sparse
// #S by #V_tet weight matrix W with four entries each); replay() maps any deformed state X of the
// coarse mesh (same connectivity) to the surface, W·X. Because the coordinates of a vertex sum to
// one, any affine map of the coarse mesh is reproduced exactly (up to rounding), also for
// vertices outside the mesh, which use the extrapolated coordinates of their nearest tetrahedron.
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <limits>
#include <string>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze {
class Progress;
}

namespace squeeze::ffd {

struct BindOptions {
  double max_outside = std::numeric_limits<double>::infinity();  // largest allowed distance of a
                                        // vertex outside every tetrahedron from the mesh, as a
                                        // fraction of the surface's bounding-box diagonal; farther
                                        // is an InputError (default: no limit)
  int refine_steps = 1;                 // iterative-refinement steps of each vertex's barycentric
                                        // solve (0: plain LU); 1 brings the rest-state error to ~1 ulp
};

/// The binding of a surface to a rest tetrahedral mesh.
///   tet    #S index of the tetrahedron each surface vertex is bound to (into T)
///   bary   #S by 4 barycentric coordinates in that tetrahedron, row-major; rows sum to 1; all
///          >= -1e-10 for vertices inside the mesh, some negative for the others (extrapolation)
///   T      #T by 4 the rest mesh's tetrahedra (row-major copy; replay needs only the binding)
///   tet_vertices   #V of the rest mesh (columns of the weight matrix)
///   outside        how many surface vertices lie outside every tetrahedron
///   max_outside_distance   the largest distance of those from their tetrahedron (model units; 0
///                  when none is outside)
struct Binding {
  Eigen::VectorXi tet;
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> bary;
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> T;
  int tet_vertices = 0;
  int outside = 0;
  double max_outside_distance = 0;
};

/// Binds the surface vertices V (#S by 3, model units) to the rest mesh `rest` (positively
/// oriented, non-empty): each vertex goes to the tetrahedron containing it (TetLocator's uniform
/// grid; ties to the lowest index) or, outside every tetrahedron, to the nearest one. Parallel over
/// vertices (TBB); the result does not depend on the number of threads.
/// `progress` (may be null) gets a "binding" stage counted in vertices.
/// Throws InputError ("NAME: problem", NAME = `name`) if V is empty or not finite, the mesh has no
/// tetrahedron or a degenerate (zero-volume) one is needed, or a vertex is farther outside than
/// options.max_outside allows.
Binding bind_surface(const Eigen::MatrixX3d& V, const meshing::TetMesh& rest, const BindOptions& options = {},
                     Progress* progress = nullptr, const std::string& name = "surface");

/// The binding as the sparse #S by #V_tet weight matrix W (row-major, four entries per row, columns
/// sorted), so that replay(b, X) == W * X up to rounding (replay() is a hand-written gather over the
/// binding itself, which measures faster than Eigen's sparse product; see docs/ffd.md).
Eigen::SparseMatrix<double, Eigen::RowMajor> weight_matrix(const Binding& binding);

/// Deformed surface vertices for the coarse-mesh state X (#V_tet by 3, same vertex order as the
/// rest mesh): out (#S by 3) = W·X, by a gather loop over the binding (parallel in chunks of 16k
/// vertices; each output row is written by exactly one thread, so results are deterministic).
/// `out` is resized when its size differs (no allocation in steady state).
/// Throws std::invalid_argument if X does not have binding.tet_vertices rows.
void replay(const Binding& binding, const Eigen::MatrixX3d& X, Eigen::MatrixX3d& out);
Eigen::MatrixX3d replay(const Binding& binding, const Eigen::MatrixX3d& X);

/// Area-weighted unit vertex normals of the triangle mesh (V, F) (for rendering after replay):
/// N #V by 3, the normalized sum of the (unnormalized) cross products of the faces around each
/// vertex; zero for vertices with no face of non-zero area. Orientation follows F.
Eigen::MatrixX3d vertex_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// Checks that `deformed` is a state of `rest`: same number of vertices and identical T.
/// Throws InputError ("DEFORMED_NAME: problem", naming the first difference) otherwise.
void check_same_connectivity(const meshing::TetMesh& rest, const meshing::TetMesh& deformed, const std::string& rest_name,
                             const std::string& deformed_name);

}  // namespace squeeze::ffd
