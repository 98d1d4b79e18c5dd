#include "squeeze/ffd/ffd.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/surface_normals.h"
#include "squeeze/meshing/tet_locator.h"

namespace squeeze::ffd {

namespace {

using Vec3 = Eigen::Vector3d;

// Barycentric coordinates of p in tetrahedron t, solved by LU and polished by `steps` rounds of
// iterative refinement against the residual of the very sum replay() evaluates (w0·v0 + ... + w3·v3).
Eigen::Vector4d barycentric(const meshing::TetMesh& m, int t, const Vec3& p, int steps) {
  const Vec3 v0 = m.V.row(m.T(t, 0)).transpose(), v1 = m.V.row(m.T(t, 1)).transpose(),
             v2 = m.V.row(m.T(t, 2)).transpose(), v3 = m.V.row(m.T(t, 3)).transpose();
  Eigen::Matrix3d M;
  M.col(0) = v1 - v0;
  M.col(1) = v2 - v0;
  M.col(2) = v3 - v0;
  const Eigen::PartialPivLU<Eigen::Matrix3d> lu(M);
  Vec3 x = lu.solve(p - v0);
  for (int s = 0; s < steps; ++s) {
    const double w0 = 1.0 - x.sum();
    const Vec3 r = p - (w0 * v0 + x(0) * v1 + x(1) * v2 + x(2) * v3);
    x += lu.solve(r);
  }
  return Eigen::Vector4d(1.0 - x.sum(), x(0), x(1), x(2));
}

constexpr Eigen::Index kReplayGrain = 16384;  // vertices per task: ~1 MB of binding, L2-sized

}  // namespace

Binding bind_surface(const Eigen::MatrixX3d& V, const meshing::TetMesh& rest, const BindOptions& options, Progress* progress,
             const std::string& name) {
  const Eigen::Index n = V.rows();
  if (n == 0) throw InputError(name + ": has no vertices");
  if (rest.T.rows() == 0) throw InputError(name + ": the tetrahedral mesh has no tetrahedron");
  if (!V.allFinite()) {
    Eigen::Index bad = 0;
    while (V.row(bad).allFinite()) ++bad;
    throw InputError(name + ": vertex " + std::to_string(bad) + " has a NaN or infinite coordinate");
  }
  if (!rest.V.allFinite()) throw InputError(name + ": the tetrahedral mesh has a NaN or infinite coordinate");

  Binding b;
  b.tet.resize(n);
  b.bary.resize(n, 4);
  b.T = rest.T;
  b.tet_vertices = static_cast<int>(rest.V.rows());
  std::vector<double> distance(static_cast<size_t>(n), 0.0);
  std::vector<char> outside(static_cast<size_t>(n), 0);

  const meshing::TetLocator locator(rest);
  if (progress) progress->stage("binding", static_cast<double>(n));
  std::atomic<Eigen::Index> done{0};
  // Each vertex's result depends on that vertex only, so any partition gives the same binding.
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, 512), [&](const tbb::blocked_range<Eigen::Index>& r) {
    for (Eigen::Index i = r.begin(); i != r.end(); ++i) {
      const Eigen::RowVector3d p = V.row(i);
      int t = locator.locate(p);
      if (t < 0) {
        t = locator.nearest(p, &distance[static_cast<size_t>(i)]);
        outside[static_cast<size_t>(i)] = 1;
      }
      b.tet(i) = t;
      b.bary.row(i) = barycentric(rest, t, p.transpose(), options.refine_steps).transpose();
    }
    if (progress) progress->update(static_cast<double>(done += static_cast<Eigen::Index>(r.size())));
  });
  if (progress) progress->finish();

  for (Eigen::Index i = 0; i < n; ++i) {
    if (!b.bary.row(i).allFinite())
      throw InputError(name + ": vertex " + std::to_string(i) + " falls in tetrahedron " + std::to_string(b.tet(i)) +
                       ", which is degenerate (zero volume)");
    if (outside[static_cast<size_t>(i)]) {
      ++b.outside;
      b.max_outside_distance = std::max(b.max_outside_distance, distance[static_cast<size_t>(i)]);
    }
  }
  const double diagonal = meshing::bounding_box_diagonal(V);
  if (b.max_outside_distance > options.max_outside * diagonal)
    throw InputError(name + ": " + std::to_string(b.outside) + " vertices lie outside the tetrahedral mesh, up to " +
                     std::to_string(b.max_outside_distance / diagonal) + " of the diagonal from it (limit " +
                     std::to_string(options.max_outside) + ")");
  return b;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> weight_matrix(const Binding& b) {
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(b.tet.size()) * 4);
  for (Eigen::Index i = 0; i < b.tet.size(); ++i)
    for (int k = 0; k < 4; ++k) entries.emplace_back(static_cast<int>(i), b.T(b.tet(i), k), b.bary(i, k));
  Eigen::SparseMatrix<double, Eigen::RowMajor> W(b.tet.size(), b.tet_vertices);
  W.setFromTriplets(entries.begin(), entries.end());
  return W;
}

void replay(const Binding& b, const Eigen::MatrixX3d& X, Eigen::MatrixX3d& out) {
  if (X.rows() != b.tet_vertices)
    throw std::invalid_argument("replay: the state has " + std::to_string(X.rows()) + " vertices, the binding " +
                                std::to_string(b.tet_vertices));
  const Eigen::Index n = b.tet.size();
  if (out.rows() != n) out.resize(n, 3);
  // The coarse state row-major (x y z of a vertex together): the four gathers of a surface vertex
  // then touch four cache lines at most, and the whole of it stays in cache.
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> Xr = X;
  const double* x = Xr.data();
  const int* tet = b.tet.data();
  const int* T = b.T.data();
  const double* w = b.bary.data();
  double* ox = out.data();
  double* oy = ox + n;
  double* oz = oy + n;
  auto run = [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index i = begin; i < end; ++i) {
      const int* v = T + 4 * static_cast<size_t>(tet[i]);
      const double* wi = w + 4 * i;
      const double* a = x + 3 * static_cast<size_t>(v[0]);
      const double* c = x + 3 * static_cast<size_t>(v[1]);
      const double* d = x + 3 * static_cast<size_t>(v[2]);
      const double* e = x + 3 * static_cast<size_t>(v[3]);
      ox[i] = wi[0] * a[0] + wi[1] * c[0] + wi[2] * d[0] + wi[3] * e[0];
      oy[i] = wi[0] * a[1] + wi[1] * c[1] + wi[2] * d[1] + wi[3] * e[1];
      oz[i] = wi[0] * a[2] + wi[1] * c[2] + wi[2] * d[2] + wi[3] * e[2];
    }
  };
  if (n <= 2 * kReplayGrain) {
    run(0, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, kReplayGrain),
                    [&](const tbb::blocked_range<Eigen::Index>& r) { run(r.begin(), r.end()); });
}

Eigen::MatrixX3d replay(const Binding& b, const Eigen::MatrixX3d& X) {
  Eigen::MatrixX3d out;
  replay(b, X, out);
  return out;
}

Eigen::MatrixX3d vertex_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  Eigen::MatrixX3d FN, N;
  meshing::area_weighted_normals(V, F, FN, N);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, N.rows(), 16384),
                    [&](const tbb::blocked_range<Eigen::Index>& r) {
                      for (Eigen::Index i = r.begin(); i != r.end(); ++i) {
                        const double len = N.row(i).norm();
                        if (len > 0) N.row(i) /= len;
                      }
                    });
  return N;
}

void check_same_connectivity(const meshing::TetMesh& rest, const meshing::TetMesh& deformed, const std::string& rest_name,
                             const std::string& deformed_name) {
  if (rest.V.rows() != deformed.V.rows() || rest.T.rows() != deformed.T.rows())
    throw InputError(deformed_name + ": not a deformation of " + rest_name + ": " +
                     std::to_string(deformed.V.rows()) + " vertices and " + std::to_string(deformed.T.rows()) +
                     " tetrahedra, against " + std::to_string(rest.V.rows()) + " and " +
                     std::to_string(rest.T.rows()));
  for (Eigen::Index t = 0; t < rest.T.rows(); ++t)
    if (rest.T.row(t) != deformed.T.row(t)) {
      auto str = [](const Eigen::RowVector4i& r) {
        return "(" + std::to_string(r(0)) + " " + std::to_string(r(1)) + " " + std::to_string(r(2)) + " " +
               std::to_string(r(3)) + ")";
      };
      throw InputError(deformed_name + ": not a deformation of " + rest_name + ": tetrahedron " + std::to_string(t) +
                       " is " + str(deformed.T.row(t)) + " here but " + str(rest.T.row(t)) + " there");
    }
}

}  // namespace squeeze::ffd
