// squeeze::meshing — the triangles of one polygon face (a file's n-gon, an extrusion's cap).
#pragma once
#include <array>
#include <vector>

namespace squeeze::meshing {

/// Triangulates one polygon, appending its triangles to `tris` with the polygon's orientation:
/// the fan from its first corner where every fan triangle turns the polygon's way (convex
/// polygons, and any the fan covers once), else ear clipping in the polygon's plane (its Newell
/// normal). Corners at the same point as an ear's (a keyhole's bridge walked both ways) do not
/// block it. Where no ear is left (a degenerate polygon), the rest is fanned; so is a polygon of
/// over 512 corners (ear clipping's cubic worst case), and one with a corner index outside pts.
/// Source: Eberly, "Triangulation by ear clipping", Geometric Tools, 2002. A concave polygon's
/// fan crosses outside it (trimesh's wallhole.obj, a wall whose faces are 8- and 11-gons around a
/// window: 1.24 times its volume as fans, meshing version 21).
///   pts   #P points (any units)
///   poly  #n corner indices into pts, in order around the polygon (n >= 3), no repeated corner
///   tris  #n - 2 triangles appended (indices into pts), each turning as the polygon does
/// Throws nothing.
void triangulate_polygon(const std::vector<std::array<double, 3>>& pts, const std::vector<long>& poly,
                         std::vector<std::array<int, 3>>& tris);

}  // namespace squeeze::meshing
