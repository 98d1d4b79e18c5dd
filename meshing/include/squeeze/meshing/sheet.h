// squeeze::meshing — open sheets (a curtain, a cloth, a leaf given as one layer of triangles): how
// to tell them from open scans of solids, and the thin closed slab that stands for them in a
// tetrahedral mesh.
//
// A surface without thickness encloses no volume, so no tetrahedral mesh can be its shape; the
// nearest one is a slab of small thickness around it, with the sheet in its middle. The convex
// shells the pipeline falls back to for other open inputs would be a blob (a 1 × 0.6 m quad: 38,045
// tetrahedra, deviation 66 % of the diagonal); the slab is a plate (docs/meshing.md, "Open sheets").
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::meshing {

class TriangleBvh;

/// What sheet_evidence measures of one face-connected component.
struct SheetEvidence {
  bool open_manifold = false;  // it has boundary edges, no edge in three or more faces, every
                               // edge in two faces traversed once each way (consistently
                               // oriented), and every boundary vertex on two boundary edges (no
                               // bow tie): a 2-manifold with boundary, offsettable
  bool closed_manifold = false;  // no boundary edge, no edge in three or more faces, every edge
                               // traversed once each way: a closed, oriented 2-manifold (one side
                               // of a hollow thin part, say; sheet_area_fraction is not measured)
  double sheet_area_fraction = 0;  // the share of its area (0..1) where the component's own
                               // winding number on both sides of the face, a ten-thousandth of the
                               // diagonal away, is between 0.25 and 0.75 in magnitude: about ½ on
                               // each side, as beside a sheet (beside a solid's wall it is about 0
                               // on one side and 1 on the other; an open scan of a solid reads as
                               // a solid except near its holes)
};

/// Measures the component (V, F) alone (other components do not count).
///   V  #V by 3 positions (units), F  #F by 3 vertex indices, one face-connected component
/// Cost: one fast winding-number tree and two evaluations per face. Throws nothing.
SheetEvidence sheet_evidence(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// Whether the evidence says sheet: open_manifold and sheet_area_fraction >= min_fraction.
inline bool is_sheet(const SheetEvidence& e, double min_fraction = 0.75) {
  return e.open_manifold && e.sheet_area_fraction >= min_fraction;
}

/// Splits each bow tie of a surface: a vertex where two or more fans of faces meet at a point
/// only (four or more boundary edges at it: a scan whose holes touch at a vertex, assimp's test
/// model sphereWithHole.stl) gets a copy per fan but the first, each copy moved a hundredth of
/// the fan's shortest edge at it toward the fan's centroid, so that the copies are distinct
/// points (MeshLab's "Split Vertices Non Manifold" with a displacement). Fans are the faces at the
/// vertex joined across edges in exactly two faces; faces around edges in three or more are left
/// as they are (non-manifold edges are not bow ties).
///   m      V #V by 3, F #F by 3 (units); new vertices are appended, F rewritten in place
///   index  when given, #V entries (any values, e.g. each vertex's index in a larger mesh): a
///          copy's entry repeats its vertex's
/// Returns how many copies were made (0: m and index unchanged). Throws nothing.
/// (Meshing version 19; before, a bow tie made the component "not an open 2-manifold", and a scan
/// with such holes took its capped solid, 2.4 % of the diagonal out on sphereWithHole.stl.)
int split_bow_ties(SurfaceMesh& m, std::vector<int>* index = nullptr);

/// The closed slab around an open, consistently oriented sheet: the sheet moved by +half_thickness
/// along its unit area-weighted vertex normals (faces as given), a copy moved by −half_thickness
/// (faces reversed), and one strip of two triangles along each boundary edge joining them. Faces
/// face outward (positive signed volume) when the sheet is oriented; where it folds more sharply
/// than half_thickness allows, the slab intersects itself (the caller checks).
///   sheet           V #V by 3, F #F by 3 (units)
///   half_thickness  > 0 (units)
/// Returns 2·#V vertices (the +side first) and 2·#F + 2·#boundary edges faces.
/// Throws InputError if half_thickness is not positive or a vertex has no normal (all its faces
/// have zero area).
SurfaceMesh thicken_sheet(const SurfaceMesh& sheet, double half_thickness);

/// The sheet remeshed to triangles of about `edge_length` (near-equilateral), vertices on the input
/// sheet, boundary vertices on its boundary polylines: CGAL's isotropic remeshing (Botsch and
/// Kobbelt, "A remeshing approach to multiresolution modeling", SGP 2004), `iterations` rounds,
/// the outline's corners (turns over 20°) kept. Outline edges still under a quarter of
/// `edge_length` (corners a pixel apart on a staircase outline) are then collapsed, shortest
/// first, to their midpoint or onto their corner: the outline may move by up to an eighth of
/// `edge_length`, which the caller measures.
/// Where max_border_sag is finite, the outline first keeps, as corners, the vertices of each border
/// polyline that a greedy walk needs so that no chord between consecutive kept ones passes farther
/// than max_border_sag from the vertices it skips (nor is longer than edge_length); creases are
/// kept over the angle a chord of edge_length would cut by more than it (20-60°, else 60°): a curved
/// outline (a bottle's rim 14 mm across, remeshed at 12 mm: an octagon 1.9 mm inside its circle)
/// keeps its sag within that, its edges shorter there (meshing version 24).
///   sheet        an open or closed, oriented 2-manifold (units); edge_length > 0 (units)
///   max_border_sag  units (INFINITY: the outline follows edge_length alone)
/// Throws InputError if edge_length is not positive or the sheet is not an oriented 2-manifold.
/// (Implemented in envelope.cpp, the CGAL surface-mesh translation unit.)
SurfaceMesh remesh_sheet(const SurfaceMesh& sheet, double edge_length, int iterations = 3,
                         double max_border_sag = INFINITY);

/// Splits the longest edge of each listed face of `sheet` at its midpoint, moved onto `onto` (the
/// input sheet) when given, and every face on a split edge with it (one split edge: two triangles;
/// two: three; three: four, red refinement), so that the result stays conforming and oriented as
/// `sheet` was. Where a graded sheet's prisms leave slivers (a long edge over a slab thinned where
/// the sheet curves), their faces are split and the prisms made again (meshing version 15).
///   sheet  V #V by 3, F #F by 3 (units), 2-manifold; faces  indices into F (repeats ignored)
/// Returns the number of edges split. Throws InputError on a face index out of range.
int split_sheet_faces(SurfaceMesh& sheet, const std::vector<int>& faces, const TriangleBvh* onto = nullptr);

/// Moves the vertices of the listed faces and their neighbours, outline vertices excepted, half way
/// to the mean of their neighbours (one Jacobi step of umbrella smoothing, Taubin 1995's λ = ½):
/// a fold of the sheet there flattens, so its prisms need not have their offsets thinned to a
/// sliver (an elephant scanned with holes: its graded sheet's prisms left slivers over 21 faces;
/// splitting them alone did not converge, smoothing first did, meshing version 16). Where the
/// sheet is a regular grid or flat and evenly tessellated, vertices stay in place (or in the plane).
/// No vertex moves farther than max_move; the caller measures how far the sheet moved from the input.
///   sheet  V #V by 3, F #F by 3 (units), 2-manifold; faces  indices into F; max_move (units)
/// Returns the number of vertices moved. Throws InputError on a face index out of range.
int smooth_sheet_faces(SurfaceMesh& sheet, const std::vector<int>& faces, double max_move = INFINITY);

/// One layer of tetrahedra between the two sides of the slab around `sheet`: thicken_sheet's
/// vertices (the +side, then the −side), each triangle's prism split into three tetrahedra, every
/// quadrilateral side split along the diagonal from its lower-numbered sheet vertex on the −side to
/// the other on the +side, so that neighbouring prisms share their split (conforming); each
/// tetrahedron positively oriented (Dompierre, Labbé, Vallet, Camarero, "How to subdivide pyramids,
/// prisms and hexahedra into tetrahedra", IMR 1999).
///   sheet           an open, consistently oriented sheet (units); half_thickness > 0 (units)
///   slab            optional: also the slab (thicken_sheet), whose faces are the mesh's boundary
///   inverted        optional: where false is returned, the faces whose prisms stay inverted
/// Returns false (out and slab untouched) where a prism is inverted or flat: the sheet folds more
/// sharply than half_thickness allows. Throws as thicken_sheet.
bool sheet_tets(const SurfaceMesh& sheet, double half_thickness, TetMesh& out, SurfaceMesh* slab = nullptr,
                std::vector<int>* inverted = nullptr);

/// The same with a half thickness per vertex of `sheet` (a thin closed part's mid-surface, each
/// vertex half as far from both sides as the part is thick there; meshing version 15).
///   half_thickness  #V positive values (units)
/// Throws InputError when there is not one per vertex or one is not positive.
bool sheet_tets(const SurfaceMesh& sheet, const std::vector<double>& half_thickness, TetMesh& out,
                SurfaceMesh* slab = nullptr, std::vector<int>* inverted = nullptr);

}  // namespace squeeze::meshing
