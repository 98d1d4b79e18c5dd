// squeeze::meshing — the volume a closed surface loses when it is remeshed into chords of a given
// length, predicted from its integrated mean curvature.
#pragma once
#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

/// Integrated mean curvature of a closed, outward, 2-manifold surface over its smooth edges:
/// M = ½ Σ_e |e| θ_e, θ_e the signed turn of the normals across edge e (radians; positive where
/// the surface is convex, negative where concave), over the edges that turn by at most
/// `sharp_angle` (creases sharper than that are kept by the remeshing and lose nothing). Units:
/// model units (a cylinder of length L: π L; a sphere of radius R: 4 π R). Edges not shared by
/// exactly two faces are skipped. Throws nothing. Source: the discrete mean curvature of
/// Steiner's formula (Sullivan, "Curvatures of smooth and discrete surfaces", 2008,
/// doi:10.1007/978-3-7643-8621-4_9, §3).
///   surface      V #V by 3 (units), F #F by 3, outward
///   sharp_angle  degrees
double integrated_mean_curvature(const SurfaceMesh& surface, double sharp_angle);

/// The edge length (model units) at which a remesh of `surface` into about equilateral triangles
/// whose vertices lie on it loses about `volume_loss` (a fraction) of `volume` to its chords:
/// h = √(8 · volume_loss · volume / M), M from integrated_mean_curvature. A triangle of edge h
/// over a surface of mean curvature H lies on average h² H / 8 inside it (a sphere: exact to
/// second order; a cylinder: 2.5 % more than the remeshes measured, docs/meshing.md version 27),
/// so the loss is h² M / (8 V). +infinity where M ≤ 0 (flat or concave on balance: chords lose
/// nothing) or volume ≤ 0. Throws nothing.
///   surface      V #V by 3 (units), F #F by 3, outward, closed
///   volume       its enclosed volume (units³)
///   volume_loss  fraction, > 0
///   sharp_angle  degrees: creases kept by the remesh (RemeshOptions::sharp_angle)
double chord_length_for_volume_loss(const SurfaceMesh& surface, double volume, double volume_loss, double sharp_angle);

}  // namespace squeeze::meshing
