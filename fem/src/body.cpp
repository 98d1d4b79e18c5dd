#include "squeeze/fem/body.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "squeeze/common/error.h"
#include "squeeze/meshing/tet_cleanup.h"
#include "squeeze/meshing/tet_faces.h"
#include "squeeze/meshing/tet_geometry.h"

namespace squeeze::fem {
namespace {

void check_material(const Material& mat, bool rigid) {
  if (!rigid && !(mat.density > 0))
    throw InputError("fem body: material density must be > 0, got " + std::to_string(mat.density));
  if (!(mat.k_distance >= 0 && mat.k_volume >= 0 && mat.damping_distance >= 0 && mat.damping_volume >= 0) ||
      !std::isfinite(mat.k_distance + mat.k_volume + mat.damping_distance + mat.damping_volume))
    throw InputError("fem body: material stiffness and damping must be finite and >= 0");
  if (!(mat.deformation_damping >= 0 && std::isfinite(mat.deformation_damping)))
    throw InputError("fem body: material deformation_damping must be finite and >= 0");
  if (!(mat.mass_scaling == 0 || (mat.mass_scaling >= 1 && std::isfinite(mat.mass_scaling))))
    throw InputError("fem body: material mass_scaling must be 0 (off) or >= 1, got " + std::to_string(mat.mass_scaling));
}

void build_csr(int n, const std::vector<std::pair<int, int>>& pairs, std::vector<int>& start, std::vector<int>& code) {
  start.assign(static_cast<size_t>(n) + 1, 0);
  for (const auto& p : pairs) ++start[static_cast<size_t>(p.first) + 1];
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  code.assign(pairs.size(), 0);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (const auto& p : pairs) code[fill[p.first]++] = p.second;  // pairs are in element order
}

}  // namespace

Body::Body(const meshing::TetMesh& mesh, const Material& mat, bool is_rigid, const Eigen::Affine3d& transform)
    : rigid(is_rigid), material(mat) {
  const int nv = static_cast<int>(mesh.V.rows()), nt = static_cast<int>(mesh.T.rows());
  if (nt == 0) throw InputError("fem body: the mesh has no tetrahedron");
  if (!mesh.V.allFinite()) throw InputError("fem body: the mesh has a NaN or infinite coordinate");
  if (mesh.T.minCoeff() < 0 || mesh.T.maxCoeff() >= nv)
    throw InputError("fem body: a tetrahedron has a vertex index out of range");
  check_material(mat, is_rigid);

  rest.resize(nv, 3);
  for (int i = 0; i < nv; ++i) rest.row(i) = (transform * Eigen::Vector3d(mesh.V.row(i).transpose())).transpose();
  T = mesh.T;

  V0.resize(nt);
  for (int t = 0; t < nt; ++t) {
    V0(t) = meshing::tet_volume(rest.row(T(t, 0)), rest.row(T(t, 1)), rest.row(T(t, 2)), rest.row(T(t, 3)));
    if (!(V0(t) > 0))
      throw InputError("fem body: tetrahedron " + std::to_string(t) + " has a non-positive volume " +
                       std::to_string(V0(t)));
  }

  // Edges.
  std::vector<std::pair<int, int>> e;
  e.reserve(static_cast<size_t>(nt) * 6);
  for (int t = 0; t < nt; ++t)
    for (const auto& ke : meshing::kTetEdge) {
      int i = T(t, ke[0]), j = T(t, ke[1]);
      if (i > j) std::swap(i, j);
      e.emplace_back(i, j);
    }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  E.resize(static_cast<Eigen::Index>(e.size()), 2);
  D0.resize(static_cast<Eigen::Index>(e.size()));
  for (size_t k = 0; k < e.size(); ++k) {
    E(k, 0) = e[k].first;
    E(k, 1) = e[k].second;
    D0(k) = (rest.row(e[k].second) - rest.row(e[k].first)).norm();
  }

  // Rest volume represented by each edge: each tet shares its volume equally among its 6 edges.
  edge_volume = Eigen::VectorXd::Zero(D0.size());
  for (int t = 0; t < nt; ++t)
    for (const auto& ke : meshing::kTetEdge) {
      int i = T(t, ke[0]), j = T(t, ke[1]);
      if (i > j) std::swap(i, j);
      const auto it = std::lower_bound(e.begin(), e.end(), std::make_pair(i, j));
      edge_volume(it - e.begin()) += V0(t) / 6.0;
    }

  // Incidence list (vertex → edges).
  std::vector<std::pair<int, int>> inc;
  inc.reserve(e.size() * 2);
  for (int k = 0; k < E.rows(); ++k) {
    inc.emplace_back(E(k, 0), 2 * k);
    inc.emplace_back(E(k, 1), 2 * k + 1);
  }
  std::stable_sort(inc.begin(), inc.end(), [](auto& a, auto& b) { return a.first < b.first; });
  build_csr(nv, inc, edge_start, edge_code);

  // Face adjacency and boundary (faces shared by three or more tets are left unconnected).
  meshing::TetFaces faces = meshing::tet_faces(T);
  neighbor = std::move(faces.neighbor);
  boundary_face = std::move(faces.boundary_face);
  F = std::move(faces.boundary);
  on_boundary.assign(static_cast<size_t>(nv), 0);
  for (Eigen::Index k = 0; k < F.rows(); ++k)
    for (int c = 0; c < 3; ++c) on_boundary[F(k, c)] = 1;
  set_material(mat);
}

void Body::set_material(const Material& mat) {
  check_material(mat, rigid);
  material = mat;
  const int nv = vertices(), nt = tets();
  const Eigen::Index ne = E.rows();
  // Element coefficients: energy density × represented volume (or uniform).
  const double we = mat.volume_weighted ? edge_volume.mean() : 0.0, wt = mat.volume_weighted ? V0.mean() : 0.0;
  k_edge.resize(ne);
  kd_edge.resize(ne);
  for (Eigen::Index e = 0; e < ne; ++e) {
    const double w = mat.volume_weighted ? edge_volume(e) / we : 1.0;
    k_edge(e) = mat.k_distance * w;
    kd_edge(e) = mat.damping_distance * w;
  }
  k_tet.resize(nt);
  kd_tet.resize(nt);
  for (int t = 0; t < nt; ++t) {
    const double w = mat.volume_weighted ? V0(t) / wt : 1.0;
    k_tet(t) = mat.k_volume * w;
    kd_tet(t) = mat.damping_volume * w;
  }
  // Lumped masses, then selective mass scaling.
  mass = Eigen::VectorXd::Zero(nv);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) mass(T(t, k)) += 0.25 * mat.density * V0(t);
  added_mass = 0;
  if (!rigid && mat.mass_scaling > 0) {
    const Eigen::VectorXd s = vertex_stiffness(*this);
    std::vector<double> w2;
    w2.reserve(static_cast<size_t>(nv));
    for (int i = 0; i < nv; ++i)
      if (mass(i) > 0 && s(i) > 0) w2.push_back(s(i) / mass(i));
    if (!w2.empty()) {
      const auto mid = w2.begin() + static_cast<std::ptrdiff_t>(w2.size() / 2);
      std::nth_element(w2.begin(), mid, w2.end());
      const double target = mat.mass_scaling * mat.mass_scaling * *mid;  // (κ ω_med)²
      for (int i = 0; i < nv; ++i) {
        const double need = s(i) / target;
        if (need > mass(i)) {
          added_mass += need - mass(i);
          mass(i) = need;
        }
      }
    }
  }
}

void vertex_frequency_bounds(const Body& B, const Eigen::VectorXd& mass, Eigen::VectorXd& w2, Eigen::VectorXd* gamma) {
  const int nv = B.vertices();
  w2 = Eigen::VectorXd::Zero(nv);
  if (gamma) *gamma = Eigen::VectorXd::Zero(nv);
  auto inv = [&](int v) { return mass(v) > 0 ? 1.0 / mass(v) : 0.0; };
  for (Eigen::Index e = 0; e < B.E.rows(); ++e) {
    const double a = (inv(B.E(e, 0)) + inv(B.E(e, 1))) / (B.D0(e) * B.D0(e));
    for (int k = 0; k < 2; ++k) {
      w2(B.E(e, k)) += B.k_edge(e) * a;
      if (gamma) (*gamma)(B.E(e, k)) += B.kd_edge(e) * a;
    }
  }
  for (int t = 0; t < B.tets(); ++t) {
    Eigen::Vector3d p[4], g[4];
    for (int k = 0; k < 4; ++k) p[k] = B.rest.row(B.T(t, k)).transpose();
    const Eigen::Vector3d a = p[1] - p[0], b = p[2] - p[0], c = p[3] - p[0];
    const double f = 1.0 / (6.0 * B.V0(t));
    g[1] = f * b.cross(c);
    g[2] = f * c.cross(a);
    g[3] = f * a.cross(b);
    g[0] = -(g[1] + g[2] + g[3]);
    double sum = 0;
    for (int k = 0; k < 4; ++k) sum += g[k].squaredNorm() * inv(B.T(t, k));
    for (int k = 0; k < 4; ++k) {
      w2(B.T(t, k)) += B.k_tet(t) * sum;
      if (gamma) (*gamma)(B.T(t, k)) += B.kd_tet(t) * sum;
    }
  }
}

Eigen::VectorXd vertex_stiffness(const Body& B, Eigen::VectorXd* damping) {
  const int nv = B.vertices();
  Eigen::VectorXd s = Eigen::VectorXd::Zero(nv);
  if (damping) *damping = Eigen::VectorXd::Zero(nv);
  for (Eigen::Index e = 0; e < B.E.rows(); ++e) {
    const double g2 = 1.0 / (B.D0(e) * B.D0(e));  // |∂C_D/∂p|²
    for (int k = 0; k < 2; ++k) {
      s(B.E(e, k)) += B.k_edge(e) * g2;
      if (damping) (*damping)(B.E(e, k)) += B.kd_edge(e) * g2;
    }
  }
  for (int t = 0; t < B.tets(); ++t) {
    Eigen::Vector3d p[4], g[4];
    for (int k = 0; k < 4; ++k) p[k] = B.rest.row(B.T(t, k)).transpose();
    const Eigen::Vector3d a = p[1] - p[0], b = p[2] - p[0], c = p[3] - p[0];
    const double f = 1.0 / (6.0 * B.V0(t));  // ∂C_V/∂p_k (constraints.h, eq. 4)
    g[1] = f * b.cross(c);
    g[2] = f * c.cross(a);
    g[3] = f * a.cross(b);
    g[0] = -(g[1] + g[2] + g[3]);
    for (int k = 0; k < 4; ++k) {
      s(B.T(t, k)) += B.k_tet(t) * g[k].squaredNorm();
      if (damping) (*damping)(B.T(t, k)) += B.kd_tet(t) * g[k].squaredNorm();
    }
  }
  return s;
}

double Body::mean_edge_length() const { return D0.size() ? D0.mean() : 0.0; }

double Body::total_volume() const { return V0.sum(); }

double volume(const Body& body, const Eigen::Ref<const RowMatrixX3d>& X) {
  double v = 0;
  for (int t = 0; t < body.tets(); ++t)
    v += meshing::tet_volume(X.row(body.T(t, 0)), X.row(body.T(t, 1)), X.row(body.T(t, 2)), X.row(body.T(t, 3)));
  return v;
}

meshing::TetMesh box_tet_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n) {
  if (n.minCoeff() < 1) throw InputError("box_tet_mesh: cell counts must be >= 1");
  if (!((hi - lo).minCoeff() > 0)) throw InputError("box_tet_mesh: lo must be below hi on every axis");
  meshing::TetMesh m;
  const int nx = n[0] + 1, ny = n[1] + 1, nz = n[2] + 1;
  m.V.resize(nx * ny * nz, 3);
  auto id = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        m.V.row(id(i, j, k)) = (lo.array() + (hi - lo).array() * Eigen::Array3d(double(i) / n[0], double(j) / n[1],
                                                                                 double(k) / n[2]))
                                   .transpose();
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.T.resize(6 * n[0] * n[1] * n[2], 4);
  int t = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (const auto& p : kPerm) {
          int c[3] = {i, j, k};
          int v[4];
          v[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            v[s + 1] = id(c[0], c[1], c[2]);
          }
          m.T.row(t++) << v[0], v[1], v[2], v[3];
        }
  meshing::orient_positively(m);
  return m;
}

meshing::TetMesh ball_tet_mesh(double radius, int n) {
  if (!(radius > 0)) throw InputError("ball_tet_mesh: radius must be > 0");
  meshing::TetMesh box = box_tet_mesh(Eigen::Vector3d::Constant(-radius), Eigen::Vector3d::Constant(radius),
                             Eigen::Vector3i::Constant(n));
  meshing::TetMesh m;
  m.V = box.V;
  std::vector<int> keep;
  for (int c = 0; c < box.T.rows() / 6; ++c) {  // 6 consecutive tets per cell
    const int ci = c % n, cj = (c / n) % n, ck = c / (n * n);  // box_tet_mesh's cell order
    const Eigen::Vector3d center = Eigen::Vector3d(ci + 0.5, cj + 0.5, ck + 0.5) * (2 * radius / n) -
                                   Eigen::Vector3d::Constant(radius);
    if (center.norm() <= radius)
      for (int k = 0; k < 6; ++k) keep.push_back(6 * c + k);
  }
  if (keep.empty()) throw InputError("ball_tet_mesh: n must be >= 1");
  m.T.resize(static_cast<Eigen::Index>(keep.size()), 4);
  for (size_t r = 0; r < keep.size(); ++r) m.T.row(r) = box.T.row(keep[r]);
  meshing::remove_unused_vertices(m);
  return m;
}

}  // namespace squeeze::fem
