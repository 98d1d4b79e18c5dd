// squeeze::fem — the implicit time integrator ("implicit" in the integrator registry): backward
// Euler for the same model as the paper's Verlet step (Teschner 2004 distance and volume energies,
// their damping, gravity, pins, rigid objects, the floor and the penalty contacts). Each step
// minimises the incremental potential (Martin et al., "Example-based elastic materials", 2011;
// Gast et al., "Optimization integrator for large time steps", TVCG 2015):
//
//   G(x) = ½ ‖x − y‖²_M / h² + E(x) + D(x),   y = x_n + h v_n + h² M⁻¹ (m g + f_ext),
//   v_{n+1} = (x − x_n) / h,
//
// E the elastic energies (constraints.h, eqs. 3–4) plus the penalty energies ½ k_c d² of the
// contacts and the floor and ½ k_a |x − x_rest|² of the soft attachments (World::attach), D the
// dissipation potentials of the damping terms: for an attachment, ½ (c_a / h) |x − x_n|²; for an element,
// ½ (k_d / h) (∇C(x_n)·(x − x_n))² (Teschner's damping force −k_d (∇C·v) ∇C with the gradient taken
// at the start of the step); for a contact, ½ (c_c / h) (r·(Δx_p − Σ b_k Δx_k))²; for the floor,
// ½ (c_c / h) min(0, Δy)². Contacts are detected at x_n and linearised there (depth
// d(x) = d_0 − r·((x_p − x_p⁰) − Σ b_k (x_k − x_k⁰))); after a converged solve they are detected again at
// the result and new ones join the minimisation (contact_rounds).
//
// Solver: Newton's method with a backtracking line search on G. Each Newton step solves H Δ = −∇G
// with the exact Hessian (constraints.h: distance_hessian, volume_hessian_blocks) by conjugate
// gradients preconditioned by the last sparse LDLᵀ factorisation of a Hessian of the same h (BlockLDLT,
// block_ldlt.h: 3×3 blocks, AMD ordering of the vertex graph); when CG needs more than max_cg_iterations, the current Hessian is
// factorised (and becomes the preconditioner). Where the exact Hessian is not positive definite
// (CG meets negative curvature, or the step is no descent), the positive semi-definite one is used
// (compressed-edge and volume curvature terms dropped: distance_hessian with psd, volume_hessian_gn).
// Everything is sequential or summed in a fixed order: bit-identical results whatever the number
// of threads.
//
// Substeps (accuracy): a step of h is split into k equal substeps so that no free vertex is
// predicted to move more than motion_fraction of its object's mean edge length per substep
// (|v| h + ½ |a| h² with every force at the start, capped where the vertex's own edges resist it;
// an object in free flight, out of reach of everything else, by its motion about its centre of
// mass only: docs/fem.md); a substep whose solution moved a vertex more than twice that is
// redone as two halves. Resting contacts are carried from one substep to the next, and a vertex
// that detection finds pushed out of the same object the other way than its carried contact (inside
// a part thinner than its edges, past its mid-plane) keeps the carried plane. This keeps contacts resolved at any h: the nominal time step (the scene's
// "auto": one frame interval, scene.h) is chosen for the motion one wants to see, not for stability.
#pragma once
#include <memory>

#include "squeeze/fem/integrator.h"

namespace squeeze::fem {

struct ImplicitOptions {
  int max_newton_iterations = 40;  // per substep; a substep that does not converge keeps its last iterate (counted)
  double tolerance = 1e-3;         // converged when the residual force would move no free vertex by more than
                                   // tolerance × its object's mean edge length in one substep (‖g_i‖ h² / m_i),
                                   // or the last Newton step moved none by more than that
  double cg_tolerance = 1e-2;      // relative residual of the conjugate-gradient solve of a Newton step
  int max_cg_iterations = 8;       // CG iterations with the last factorisation as preconditioner before the
                                   // Hessian is factorised anew (0: factorise every Newton iteration)
  double inexact_cg_tolerance = 0.1;  // ... unless they reduced the relative residual to this: an inexact
                                      // Newton direction, taken (the line search keeps it safe) instead of
                                      // a new factorisation (0: always factorise after max_cg_iterations)
  double motion_fraction = 0.5;    // largest predicted motion per substep, in mean edge lengths of the object
  int max_substeps = 1024;         // substeps of one step at most
  int contact_rounds = 3;          // re-detections of contacts after a converged solve (0: detect at x_n only)
};

/// The implicit integrator with these options (make_integrator("implicit") uses the defaults).
/// Throws InputError if an option is out of range.
std::unique_ptr<TimeIntegrator> make_implicit_integrator(const ImplicitOptions& options);

}  // namespace squeeze::fem
