// squeeze::fem — stateless per-element kernels of the constraint-based deformable model:
// energies, constraint gradients, elastic and damping forces of one edge or one tetrahedron.
//
// Source: M. Teschner, B. Heidelberger, M. Müller, M. Gross, "A versatile and robust model for
// geometrically complex deformable solids", CGI 2004, doi:10.1109/CGI.2004.1309199, as used by
// S. Rodriguez, J.-M. Lien, N. M. Amato, "Planning motion in completely deformable environments",
// ICRA 2006, Section IV-A:
//   E = ½ k C²                                                         (eq. 1)
//   F_i = −k C ∂C/∂p_i                                                 (eq. 2)
//   C_D = (|p_j − p_i| − D0) / D0                                      (eq. 3, distance)
//   C_V = (⅙ (p_j − p_i)·((p_k − p_i)×(p_l − p_i)) − V0) / V0          (eq. 4, volume)
// and the damping force of Teschner et al. 2004 (Section 3):
//   F_damp,i = −k_d (Σ_j ∂C/∂p_j · v_j) ∂C/∂p_i.
//
// Units: positions in m, velocities in m/s. C is a dimensionless ratio, so the stiffness k is an
// energy (J = N·m); ∂C/∂p is in 1/m, the elastic force k C ∂C/∂p in N. The damping coefficient
// k_d multiplies (1/s)·(1/m), so it is in J·s = N·m·s.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace squeeze::fem {

using Vec3 = Eigen::Vector3d;

/// Distance constraint C_D of edge (pi,pj) with rest length D0 > 0 (m); grad_j receives ∂C/∂p_j
/// (1/m); ∂C/∂p_i = −grad_j. A zero-length edge has a zero gradient.
inline double distance_constraint(const Vec3& pi, const Vec3& pj, double D0, Vec3* grad_j) {
  const Vec3 d = pj - pi;
  const double len = d.norm();
  if (grad_j) *grad_j = len > 0 ? Vec3(d / (len * D0)) : Vec3::Zero();
  return (len - D0) / D0;
}

/// E_D = ½ k C_D² (J), k in J.
inline double distance_energy(const Vec3& pi, const Vec3& pj, double D0, double k) {
  const double C = distance_constraint(pi, pj, D0, nullptr);
  return 0.5 * k * C * C;
}

/// Elastic plus damping forces (N) of one edge: fi on p_i, fj = −fi on p_j.
///   k   stiffness (J), kd  damping (J·s), vi, vj  velocities (m/s)
inline void distance_forces(const Vec3& pi, const Vec3& pj, const Vec3& vi, const Vec3& vj, double D0, double k,
                            double kd, Vec3& fi, Vec3& fj) {
  Vec3 g;
  const double C = distance_constraint(pi, pj, D0, &g);
  const double rate = g.dot(vj - vi);  // dC/dt (1/s)
  fj = -(k * C + kd * rate) * g;
  fi = -fj;
}

/// Volume constraint C_V of tetrahedron (p0,p1,p2,p3) with rest volume V0 > 0 (m³); grad[0..3]
/// receive ∂C/∂p_k (1/m). Negative for inverted tetrahedra, whose forces restore the volume.
inline double volume_constraint(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double V0,
                                Vec3 grad[4]) {
  const Vec3 a = p1 - p0, b = p2 - p0, c = p3 - p0;
  const Vec3 bc = b.cross(c);
  const double V = a.dot(bc) / 6.0;
  if (grad) {
    const double s = 1.0 / (6.0 * V0);
    grad[1] = s * bc;
    grad[2] = s * c.cross(a);
    grad[3] = s * a.cross(b);
    grad[0] = -(grad[1] + grad[2] + grad[3]);
  }
  return (V - V0) / V0;
}

/// E_V = ½ k C_V² (J), k in J.
inline double volume_energy(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double V0, double k) {
  const double C = volume_constraint(p0, p1, p2, p3, V0, nullptr);
  return 0.5 * k * C * C;
}

/// Elastic plus damping forces (N) of one tetrahedron on its four vertices.
///   p, v  positions (m) and velocities (m/s) of the four vertices; k (J), kd (J·s)
inline void volume_forces(const Vec3 p[4], const Vec3 v[4], double V0, double k, double kd, Vec3 f[4]) {
  Vec3 g[4];
  const double C = volume_constraint(p[0], p[1], p[2], p[3], V0, g);
  const double rate = g[0].dot(v[0]) + g[1].dot(v[1]) + g[2].dot(v[2]) + g[3].dot(v[3]);
  const double s = -(k * C + kd * rate);
  for (int i = 0; i < 4; ++i) f[i] = s * g[i];
}

}  // namespace squeeze::fem
