// squeeze::meshing — splitting a surface's long edges at their midpoints (the surface unchanged).
#pragma once
#include <array>
#include <functional>
#include <vector>

#include "squeeze/meshing/surface.h"

namespace squeeze::meshing {

/// Splits every edge of `surface` longer than `max_length` at its midpoint, in rounds, until none
/// is: red–green refinement (a triangle with one long edge becomes 2 triangles, with two 3 — its
/// quadrilateral split along the shorter diagonal —, with three 4). Midpoints are shared by both
/// triangles of an edge, so a conforming mesh stays conforming; every new vertex lies on an edge
/// of the input, so the surface (as a point set) and each triangle's orientation are unchanged.
/// Used before a Delaunay tetrahedralization: a long, thin triangle (the side of a cylinder of few
/// segments) has a circumsphere far larger than itself, which conformity recovery cannot split
/// down to within its limits (meshing/tetrahedralize.h).
/// A round starts only while the faces number at most 8 #F + 10,000, so a bound far below the
/// input's longest edges stops there (edges longer than max_length then remain). Source: the
/// red–green refinement of Bank, Sherman, Weiser, "Refinement algorithms and data structures for
/// regular local mesh refinement", Scientific Computing (IMACS), 1983, on surface triangles.
///   surface     #V by 3, #F by 3
///   max_length  model units, > 0 (else InputError)
///   complete    optional output: true when every edge of the result is at most max_length, false
///               when the face budget (or 64 rounds) stopped the refinement first
/// Returns the refined surface: the input's vertices first, in order, then the midpoints.
SurfaceMesh split_long_edges(const SurfaceMesh& surface, double max_length, bool* complete = nullptr);

/// One round of that red–green refinement on the faces F, given the new vertex on each split edge:
/// midpoint(a, b) is its index (the same for (b, a)), or -1 where the edge is not split;
/// squared_length(a, b) between two vertices chooses a quadrilateral's shorter diagonal. Each face
/// keeps its orientation. Shared by split_long_edges and split_sheet_faces (sheet.h).
std::vector<std::array<int, 3>> red_green_split(const std::vector<std::array<int, 3>>& F,
                                                const std::function<int(int, int)>& midpoint,
                                                const std::function<double(int, int)>& squared_length);

/// The median length (model units) of the edges of `surface`'s triangles (each edge counted once
/// per triangle); 0 for a surface without faces. Throws nothing.
double median_edge_length(const SurfaceMesh& surface);

/// Options of skinny_split_length.
struct SkinnySplitOptions {
  double max_aspect = 6.0;       // a triangle is skinny when its longest edge exceeds this many times its shortest
  double area_fraction = 0.5;    // ... and the surface needs splitting when skinny triangles hold more of its area
  double shortest_edges = 4.0;   // the split length: this many times the skinny triangles' median shortest edge
};

/// The edge length (model units) to which `surface`'s long edges should be split before it is
/// simplified and tetrahedralized, or 0 where it need not be. A surface made mostly of long,
/// thin triangles (a faceted rod: 12 sides, 40 rings, triangles 16 times longer than wide) leaves
/// an edge-collapse simplification no collapse that keeps its triangles' angles, and a Delaunay
/// refinement of it searches conflict zones the size of the whole part (1 m × 3 mm rod at 1,000
/// tetrahedra: 97 s); split to triangles about as long as `shortest_edges` times their width, the
/// same rod simplifies to a few hundred faces and meshes in under a second. Scanned and remeshed
/// surfaces (skinny triangles a few percent of their area) get 0. Throws nothing. Source:
/// squeeze's own criterion (meshing version 14, docs/meshing.md); the split itself is
/// split_long_edges' red-green refinement.
///   surface  #V by 3, #F by 3 (model units)
///   opt      SkinnySplitOptions (ratios, dimensionless)
double skinny_split_length(const SurfaceMesh& surface, const SkinnySplitOptions& opt = {});

}  // namespace squeeze::meshing
