// squeeze::meshing — the whole `squeeze mesh` pipeline: load, analyse, decompose into convex
// shells, build the simulation mesh's boundary, tetrahedralize, measure. Paper: Rodriguez, Lien,
// Amato, ICRA 2006, Section VI-A, Fig. 3; docs/meshing.md says what version 4 does and why.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "squeeze/meshing/decompose.h"
#include "squeeze/meshing/envelope.h"
#include "squeeze/meshing/surface.h"
#include "squeeze/meshing/surface_analysis.h"
#include "squeeze/meshing/tet_mesh.h"
#include "squeeze/meshing/tet_quality.h"
#include "squeeze/meshing/shell_tetrahedralize.h"
#include "squeeze/meshing/tetrahedralize.h"
#include "squeeze/meshing/winding_tetrahedralize.h"

namespace squeeze {
class Progress;
}

namespace squeeze::meshing {

/// Version of the meshing algorithms: part of every cache key made from meshing results (the
/// scene loader's coarse-mesh cache). Bump it whenever a change alters the meshes produced.
constexpr int kMeshingAlgorithmVersion = 57;  // 57: a closed part's winding-number solid grown over its volume bound is scaled down to no less than MeshOptions::solid_min_scale, 0.2, not 0.4 (a CAD counter's thin part at the default: 1.142 of its volume, 1.079 since); 56: tetrahedralize_winding_number seeds the input's points its solid leaves outside by more than cover_tolerance and refines again, as winding_number_surface does (a CAD part's solid at 150 lay 0.84 % of the diagonal in where its facets cut off corners; 0.28 % since); 55: tetrahedralize()'s first conformity recovery of a run gives up once it would split more boundary edges than 4 times the boundary's faces in a round that does not converge (recovery_splits_per_face), and that run is not refined; squeeze mesh treats it as the first attempt that split over four times per face (no retry but the remeshed surface); no sliver moves or flips on a mesh kept that is not conforming (a CAD part at 150: 29 s in one such first attempt, 5 s since); 54: inputs of over 30,000 triangles, not 100,000, meshed through their decimated proxy where it has at least 15,000 triangles fewer (a bust of 99,938 faces took 15-18 s at 150 and 300, 8.6 s of it in the envelope's edge collapses; 6.3 s since), the shells grown to hold the input's own vertices, a far input decimated at the origin; a part's winding-number solid grown over the volume bound (1.2, 1.1 from 1,000 tetrahedra) made again once with the dilation and facet distance scaled toward the growth allowed (a thin CAD plate at 150: 1.412 times its volume, so it kept a boundary that was not conforming, 1.36 % of the diagonal in); no inner-bound retry where every part is its own solid (the same solid again: 29 s of a CAD part's 63); 53: a part whose first boundary lost conformity goes to its winding-number solid before retries 1 and 3 also where its mean thickness (twice its volume over its area) is at least half its first attempt's edge length (the sacrum at 1000: 7.6 s of retries that did not hold); 52: tetrahedralize() contracts short edges of the slivers left after its moves, flips and peeling of short ones, before its last peeling (an urchin of 24 spikes at 1000 kept five interior slivers across a spike's tip in a conforming mesh, went on to every retry and its winding-number solid: 15,765 tetrahedra in 16 s, 5,838 in 7 s since); 51: the envelope's collapses make no face that crosses a face around the collapse's link or another new face (a scanned bust of 99,938 faces kept one face through a fan of three, and its retries took 26 s); a part of over 20,000 faces whose first boundary lost conformity tries its winding-number solid before retries 1 and 3 (the bust: 38 s, 15 s since); retry 3 skipped where the first simplification stopped at its bounds above its target (the same boundary); a part's winding-number solid that leaves it over the inner bound outside made again at 0.75 of the facet distance (the bust at 150: 0.557 % of the diagonal in, 0.087 % since); a result over 0.5 of max_deviation in meshed again at 0.85 of the inner bound (an urchin at 1000: 0.502 %); 50: a dense input's proxy decimated with each vertex within the bound of every input face's plane it took in, checked one by one where the quadric's root is over it (a noisy scan of 301,632 faces kept 109,058 in its proxy, 41,438 since); 49: inputs of over 100,000 triangles meshed through a proxy decimated by quadric error within a tenth of the inner bound (decimate.h), measured against the input (a fine scan of 301,632 faces took 24 s, 12-15 s of it in the envelope's edge collapses); 48: a closed part whose first tetrahedralization holds with over 1.35 times its share of the target, from a boundary its face budget stopped, tried again from as many times more faces, kept where it holds with at most 1.35 times the tetrahedra (a coin 4 mm thick at 150 lost 6 of its 48 sides, 0.22 % of the diagonal in); 47: a first boundary attempt that holds, its refinement stopped at the work bound, is replaced by the skinny split's boundary only where that holds at fewer tetrahedra (a box 2 m by 1 cm written with 7 digits far from the origin kept a remeshed boundary 0.2 % off, or went through 11 s of retries for its own faces); 46: TriangleBvh's segments within 1e-5 of their length of a triangle's plane at both ends cross nothing there (a wall written with 9 digits stands off perpendicular by 1e-9: a star-shaped plate's slab met its side walls and stood 0.86 mm out of it); 45: conformity recovery's cap (four points per point) counts recovery's own splits, not the points refinement adds (a plate with 3 mm ribs lost its boundary at the cap in its tenth refinement round and was remeshed: 12 s, 1.2 s since); 44: tetrahedralize()'s refinement may always add as many points as the recovered boundary has (its safety net max_tets, by a small part's share of the volume, had stopped it before it began: a model's screws kept slivers of 3.2°); 43: an inside cell of no volume on the surface (four points of one flat patch, two of its faces surface triangles) has its surface diagonal flipped, which puts it outside, instead of being refined (a thin plate turned in space: rounds of splits, up to 16 s); a thin part whose first boundary attempt stopped at its work bound tried as its slab; the exuder stops after 5 pumps per sliver, not 20; tetrahedralize() and the Mesh_3 routes keep CGAL's cell orientation until their sliver moves are done (a floating-point sign test turned a nearly flat cell the wrong way round, and the moves inflated it inverted); 42: a segment in a triangle's plane (up to rounding) crosses nothing in TriangleBvh (a thin plate turned in space lost half its slab's thickness at the rim); 41: conformity recovery splits an edge unless every triangle on it was split 10 times (not: unless any was); 40: conformity recovery flips a surface edge only across a convex quad (a corner on the new diagonal gave a triangle of zero area, split at the same point again and again); the winding-number volume's cones from the bounding box's centre, not the origin (open scans far from it), and its magnitude sizes Mesh_3's cells; 39: the winding-number surface's cover pass takes both sides' surface points where the solid is thin at an input point left outside (outside it within the probe on both sides: a flap between holes), the facet distance apart, and where the first seeds give Mesh_3 no facet, the vertices' seeds again a facet distance apart (a long, thin scan); 38: the hollowed solid made first (before the capped one) where the holes' outlines say caps would lie over 1.5 times the bound off: welded segments only, or an open scan whose slab does not hold; 37: the input's orientation keeps the file's where a component welded to others (non-manifold edges) has large parts the file orients consistently and turns between (a seam between welded segments left manifold by a hole); the slab tried first for wide holes kept up to first_try_inner_deviation (0.5 of max_deviation) inside, not 0.45 (vertebrae with holes stay apart); 36: a winding-number solid whose caps over holes lie over 1.5 times the bound off (welded segments; an open scan whose slab does not hold) made again hollowed where the outside reaches in through the holes (a flood of a grid from its border), kept where nearer the input; 35: closed parts beside stray components that are not (under a tenth of the area; no closed part intersecting itself) meshed as parts, the others as their own winding-number solid (seeded along their faces where their vertices give Mesh_3 no facet), the whole input's solid where that fails; 34: an open scan's winding-number solid that misses the inner bound is tried as slabs too (kept where they hold every bound); slivers over up to four faces of a sheet may be dropped whatever its size (0.5 % of them above 800); 33: an open sheet's own triangles, where they are its last try, split to the width a prism may have (a few large creased polygons); 32: open sheets' and scans' prisms whose slivers are left over at most 0.5 % of the faces drop those tetrahedra (a spike's tip, a fold), where every sheet vertex keeps one; graded sheets get 16 rounds of mends while under 10 % of their faces hold slivers (8 and 1 %); 31: open scans with open sheets beside them (a stray triangle) take the open scans' route, so that their slab is tried, and the slab after the solid needs one mesh per part; bow ties split before the widest hole's cap is estimated; the winding-number route's first solid made at the dilation whose growth (its width times the outward faces' area) is estimated within the bound, where over twice it; 30: the winding-number route's solid made again up to three times while over 8 % above the input's volume (at 1,000 tetrahedra and more), or 15 % (below); a skinny boundary whose split stopped at its face budget over 8 times max_retry_faces not simplified; 29: the convex decomposition samples large polygons about a voxel apart by their area, not a grid of their longest edge (the same meshes; shells and tet labels differ); a boundary still of mostly skinny triangles over max_retry_faces not tetrahedralized by any attempt; 28: walls between welded segments found with the patches oriented without their twin pairs (voxel models of closed cubes); 27: retry 0's first remesh length at most the one whose chords lose about 2.5 % of the part's volume (by its mean curvature); 26: a boundary of mostly skinny triangles tried split before retry 0, and tetrahedralized only where its simplification coarsened it; retry 0 shortens its remesh length after a volume loss toward 2 % lost (not by half); refinement stops at its work budget within a round (long rods of few sides); 25: a closed part no boundary attempt held is tried from a finer start (the first boundary at 1/2 and 1/4 of the first edge length, not exuded) before its winding-number solid; the exuder stops after 20 pumps per sliver; 24: thin parts whose sides are closed surfaces (hollow: a cavity) meshed as closed slabs; thin parts' mid-surfaces keep their outline and creases within a quarter of the inner bound, and a slab off the bounds is made again at 0.6 and 0.36 of its edge length; 23: tetrahedralization runs whose boundary is not conforming are not exuded, and where it was not recovered before refinement their refinement stops past a work bound (unrecovered_refine_work); thin parts' prisms split up to six rounds, not three (knife edges); 22: a closed part whose first tetrahedralization does not hold tried first on its own surface remeshed into round triangles (a quarter of the interior edge length, shorter where that lies off the bounds; creases over 40° kept) where that lies within the bounds; 21: OBJ and OFF polygon faces that their first corner does not fan (concave) ear-clipped, OBJ lines continued by a backslash; a part whose first tetrahedralization split its boundary over four times per face and did not hold goes to its winding-number solid without retries; the decomposition's voxels at most 8 × resolution³; 20: thin parts: faces beside a side over a bevel join it, slabs no thinner than a quarter of the mean thickness where the part tapers, the slab tried (L over 3 times the thickness) where no boundary attempt held; of attempts that are not conforming, the one that keeps the volume; 19: winding numbers with the far field to second order (beta 1.5; the winding-number route 1.25, any_within for its dilation); conformity recovery gives up at four splits a point, not 1.5, or where it stalls (thin tubes, fins); convex shells dilated by at most 5 % of the diagonal; thin parts' sides flooded only across faces paired at their thickness (perforated plates); rough sheets on their own triangles where a retry would remesh them far finer; bow-tie vertices split before sheets and open scans are judged; 18: walls between segments welded to each other (one copy or a face and its twin) dropped where the segments then close (walls_between_welded_segments); open scans with narrow holes whose winding-number surface fails meshed capped (capped_route); 17: convex shells meshed by Mesh_3 without its sliver perturber (their slivers relocated and flipped, tet_cleanup.h); 16: open scans whose widest hole would leave a cap over 1.5 times the bound off (hole_caps.h) meshed as sheets first, the solid only where the slab does not hold; 15: closed parts much thinner than their tetrahedra meshed as one layer of prisms across their thickness; inputs far from the origin meshed moved to it; open sheets remeshed finer than wanted graded by simplify_sheet, their creases kept, prisms that invert thinned, slabs of nearby parts kept apart; open scans whose caps lie over 1.5 times the bound off meshed as sheets; 14: closed parts of mostly skinny triangles split to rounder ones where their own boundary is too much refinement work or does not hold; shells meshes that do not hold the input refused (shells_only); open scans whose caps lie over three times the bound off meshed as sheets; 13: open sheets: outline edges under a quarter of the edge length collapsed, the slab's slivers moved and flipped; 12: version 11 with open scans at winding_dilation (a commit of 11 gave them 0.3; the key tells cached meshes apart); 11: inputs that are not closed parts by their winding-number solid's boundary, simplified against the input; 10: a part whose boundary does not hold as its winding-number solid, cavities, bounded retries; 9: unseen shapes (cylinders, debris, cones, flat caps in few digits); 8: open scans by winding number; 7: open sheets as slabs; 6: sliver moves and flips

struct MeshOptions {
  DecompositionOptions decomposition;   // convex shells (--shells, tet labels, the report)
  TetrahedralizeOptions tetrahedralize; // target tet count, quality bounds
  ShellTetrahedralizeOptions shells;    // the fallback (convex shells meshed with Mesh_3, version 3)
                                        // where the input's boundary cannot be meshed as it is;
                                        // its target_tets and seed are taken from tetrahedralize
  double tets_per_hull = 40;            // the hull budget is also at most target_tets / this (at
                                        // least 1); 0: decomposition.max_hulls alone
  double max_deviation = 0.01;          // fraction of the bbox diagonal: how far the tet mesh's
                                        // boundary may stray outside the input surface (the
                                        // report's deviation_out)
  double inner_deviation = 0.45;        // how far input surface points may lie outside the tet mesh
                                        // (deviation_in), as a share of max_deviation
  double inner_retry_deviation = 0.5;   // a result whose deviation_in is over this share of
                                        // max_deviation (the bounds' samples are spaced by the inner
                                        // bound: points between them can lie past it) is meshed again
                                        // with inner_deviation 0.85 times as large, and kept where
                                        // nearer (meshing version 51); 0: not
  double coverage_tolerance = 0.005;    // fraction of the bbox diagonal for the coverage figure
  WindingTetrahedralizeOptions winding_mesh;  // with `winding`: the winding-number
                                        // solid meshed with Mesh_3 (winding_tetrahedralize.h); its
                                        // target_tets and seed are taken from tetrahedralize, its
                                        // facet_distance and dilation from max_deviation (below)
  bool winding = false;                 // inputs that are not closed parts (welded, non-manifold
                                        // or self-intersecting segments; open scans of solids):
                                        // their winding-number solid meshed by Mesh_3 as it is
                                        // (true: tight, but 3–20k tetrahedra on the organs,
                                        // docs/meshing.md). False (version 11): the boundary of
                                        // that mesh simplified against the input and tetrahedralized
                                        // by the boundary route, Mesh_3's mesh kept where that fails
  double winding_surface_dilation = 0.3; // the dilation of the winding-number solid of welded,
                                        // non-manifold or self-intersecting segments whose boundary
                                        // the default route simplifies (version 11), as a multiple
                                        // of max_deviation: less than winding_dilation, as the
                                        // input's points its facets leave outside are seeded
                                        // (winding_tetrahedralize.h cover_tolerance); at 0.45 two
                                        // touching organs' coarse meshes overlapped 3.24 points
                                        // more than their surfaces. Open scans of solids keep
                                        // winding_dilation (their hole rims are creases)
  double skinny_refine_work = 2e6;      // a closed part whose boundary is mostly long, thin triangles
                                        // (skinny_split_length, split_long_edges.h) is tetrahedralized
                                        // with this bound on its refinement's work
                                        // (TetrahedralizeOptions::max_refine_work: about 0.5 s here);
                                        // beyond it, or where its mesh does not hold, its boundary
                                        // is split to rounder triangles and meshed again. 0: no bound
  bool skinny_split_keeps_first_that_holds = true;  // a first attempt that holds, its refinement
                                        // stopped at skinny_refine_work, gives way to the split
                                        // boundary's mesh only where that holds at fewer tetrahedra
                                        // (version 47); false: to any split mesh, as in versions
                                        // 26-46 (bench_mesh measures against it)
  bool split_skinny = true;             // false: parts of mostly skinny triangles meshed on their own
                                        // boundary only, as before version 14 (bench_mesh measures
                                        // against it)
  bool remesh_retry = true;             // a closed part whose first tetrahedralization does not hold
                                        // is tried on its own surface remeshed into round triangles
                                        // (remesh.h; a quarter of the interior edge length, shorter
                                        // where that lies off the bounds) before the other retries (version 22); false: not,
                                        // as in version 21
  double remesh_volume_loss = 0.025;    // fraction: retry 0's first remesh length is at most the one
                                        // whose chords lose about this much of the part's volume
                                        // (chord_volume.h, from its mean curvature; version 27);
                                        // 0: a quarter of the interior edge length, shortened only
                                        // after a remesh lost over 3 %, as version 26 (bench_mesh
                                        // measures against it)
  int solid_first_faces = 20000;        // a part of more faces whose first boundary lost conformity
                                        // (recovery gave up) tries its winding-number solid before
                                        // retries 1 and 3, which simplify it again (meshing version
                                        // 51); 0: after every retry, as version 50
  double solid_first_thickness = 0.5;   // ... and so does a part of fewer faces whose mean
                                        // thickness (twice its volume over its area) is at least
                                        // this × its first attempt's interior edge length: Mesh_3
                                        // meshes it at about its target, where the retries' new
                                        // boundaries lose conformity as the first did (the sacrum at
                                        // 1000: 0.64; version 53). Thinner parts (a comb's 2 mm
                                        // teeth, 0.33) keep the retries first: their solid takes tens
                                        // of thousands of tetrahedra. 0: faces alone
  bool solid_facet_retry = true;        // a closed part's winding-number solid (its boundary did not
                                        // hold) that leaves the part over the inner bound outside it is
                                        // made again at 0.75 of the facet distance, kept where nearer
                                        // (meshing version 51); false: as version 50
  double solid_min_scale = 0.2;         // a closed part's winding-number solid that grows over its
                                        // volume bound is made with its dilation and facet distance
                                        // scaled down toward the growth allowed, to no less than this
                                        // (version 54: 0.4; 0.2 since version 57, as version 56's
                                        // cover pass seeds the corners a finer facet distance cuts
                                        // off: a CAD counter's thin part at the default stopped at
                                        // 0.4 with 1.142 of its volume, 1.079 at 0.22); in (0, 1]
  bool thin_parts_as_prisms = true;     // closed parts much thinner than their tetrahedra would be
                                        // long (a plate, a bowl) meshed as one layer of prisms
                                        // across their thickness (version 15); false: as any part,
                                        // as before (bench_mesh measures against it)
  bool open_scans_as_sheets = false;    // open 2-manifold components that enclose a solid (open scans)
                                        // meshed as open sheets (slabs) too; mesh_surface tries it by
                                        // itself where the solid's caps over wide holes lie over 1.5
                                        // times the outer bound (max_deviation) off (version 15)
  bool hollow_winding_solid = false;    // the whole input's winding-number solid hollowed where
                                        // the outside reaches in through holes: a shell around
                                        // their rims instead of caps over them
                                        // (WindingTetrahedralizeOptions::hollow_cell); mesh_surface
                                        // tries it by itself where the caps lie over 1.5 times the
                                        // outer bound off (version 36)
  bool hollow_where_caps_lie_far = true;  // that try (false: the capped solid kept, version 35)
  bool hollow_first = true;             // with it: where the holes' outlines say the caps would lie
                                        // that far (hole_caps.h; welded segments, or an open scan
                                        // whose slab does not hold), the hollowed solid is made
                                        // first and kept where it holds the bounds, the capped one
                                        // only where it does not (version 38; false: capped first)
  double hollow_depth = 0.6;            // how deep the hollowed shell reaches inside the input, as a
                                        // multiple of max_deviation
  double hollow_cell = 0.005;           // the grid the outside is flooded on to find where it reaches
                                        // in through holes, as a fraction of the diagonal
  bool slab_first_for_wide_holes = true;  // where the widest hole's cap would lie that far off by its
                                        // outline (hole_caps.h), the slab is tried before the solid
                                        // (version 16); false: the solid first, as version 15
                                        // (bench_mesh measures against it)
  double first_try_inner_deviation = 0.5;  // that slab, and the hollowed solid tried first
                                        // (hollow_first), are kept where input surface points lie up
                                        // to this share of max_deviation outside them (and they
                                        // hold every other bound): above inner_deviation, whose
                                        // margin is for the routes' own targets; what is made
                                        // instead can merge parts lying closer than its dilation
                                        // (five vertebrae with holes: one mesh; version 37) or
                                        // costs the capped solid's seconds (version 38)
  bool shells_fallback = false;         // welded, non-manifold or self-intersecting segments: their
                                        // convex shells meshed with Mesh_3, as before version 11
  bool shells_only = false;             // every input (closed parts too) meshed as its convex shells
                                        // with Mesh_3: a coarse mesh around the input, the paper's
                                        // (a simulation mesh in which a tight mesh is embedded,
                                        // fem::World::embed); route "all_convex_shells"
  bool wrap = false;                    // the same inputs: mesh their alpha wrap (alpha_wrap.h) by
                                        // the boundary route (true; before `winding`); the convex
                                        // shells only where either fails
  double wrap_alpha = 1.0;              // the alpha wrap's alpha, as a multiple of max_deviation
                                        // (gaps, holes, cavities narrower than this are filled)
  double wrap_offset = 0.2;             // its offset outside the input, as a multiple of max_deviation
  bool more_faces_where_over_target = true;  // a closed part whose first tetrahedralization holds
                                        // with over 1.35 times its share of the target, from a boundary
                                        // its face budget stopped, tried again from as many times more
                                        // faces; kept where it holds with at most 1.35 times the first's
                                        // tetrahedra (a thin coin keeps all of its sides; version 48)
  int dense_faces = 30000;              // inputs of more triangles are meshed through a proxy:
                                        // decimate_quadric() (decimate.h) within dense_error of them,
                                        // meshed with the bounds as asked, the results measured
                                        // against the input itself (0: never; meshing version 49;
                                        // 100,000 before version 54)
  int dense_min_saving = 15000;         // ... where the proxy has at least this many triangles fewer
                                        // than the input (about a second of the envelope's edge
                                        // collapses, against the proxy's decimation and measures);
                                        // else the input itself is meshed: a surface whose every
                                        // vertex the bounds need gains nothing from its proxy but
                                        // the proxy's error (version 54)
  double dense_error = 0.1;             // the proxy's bound, as a share of the inner bound
                                        // (inner_deviation × max_deviation × the bbox diagonal)
  double winding_facet_distance = 0.4;  // the winding-number route's Mesh_3 facet distance, as a
                                        // multiple of max_deviation (boundary facets are chords: they
                                        // sag about this far below the solid's surface)
  double sheet_thickness = 1.0;         // open sheets (sheet.h: one layer of triangles, no volume)
                                        // are meshed as slabs this thick, as a multiple of
                                        // max_deviation × the bbox diagonal, the sheet in the middle
                                        // (so their boundary lies half of max_deviation out)
  double winding_dilation = 0.45;       // its dilation of the solid, as a multiple of max_deviation
                                        // (chords sag up to about twice the facet distance: the
                                        // dilation keeps them within inner_deviation of the input;
                                        // deviation_out is then about dilation + facet distance)
  bool estimate_winding_growth = true;  // closed inputs on the winding-number boundary route: the
                                        // first solid made at the dilation that should keep its
                                        // growth (about dilation × area) within the volume bound;
                                        // false: made at the full dilation, then again while over
                                        // (meshing version 30's order)
  bool closed_parts_beside_solid = true;  // inputs with closed parts beside components that are not
                                        // (open, non-manifold, welded: a chair's stray fin): the
                                        // closed parts meshed as parts and the rest as its own
                                        // winding-number solid, kept where that holds (version 35);
                                        // false: the whole input's winding-number solid
  double sheet_sliver_drop = 0.005;     // open sheets and scans' slabs: where the prisms over at most
                                        // this fraction of the sheet's faces, or four (version 34),
                                        // still hold tetrahedra under the dihedral floor (a spike's
                                        // tip, a fold), those tetrahedra are dropped (tet_cleanup.h:
                                        // drop_slivers), kept where every sheet vertex left on none
                                        // lies within the inner bound of the rest; its mends also
                                        // run 16 rounds while under a tenth of the faces hold
                                        // slivers; 0: never, 8 rounds and a hundredth (version 31)
};

/// The alpha wrap the pipeline made (inputs that are not closed parts).
struct WrapStats {
  bool used = false;
  double alpha = 0;       // fraction of the bbox diagonal
  double offset = 0;      // fraction of the bbox diagonal
  int faces = 0;          // faces of the wrap
  double deviation = 0;   // units: the wrap's largest distance from the input surface
};

/// Everything `squeeze mesh` computes.
struct MeshResult {
  SurfaceMesh input;            // as loaded (welded), faces oriented outward per component
  SurfaceInfo info;             // counts, closedness, self-intersection, volume
  Decomposition decomposition;  // convex shells
  int hull_budget = 0;          // max_hulls the decomposition ran with (see hull_budget())
  int parts = 0;                // parts meshed on their own: the input's components that are closed
                                // oriented 2-manifolds enclosing volume (the fallback: the
                                // input's face-connected components)
  bool boundary_from_input = false;  // the tet mesh is made from the input's own boundary (method
                                     // "boundary"); false on the fallback
  SurfaceMesh boundary;         // the simplified boundaries of all parts (one closed surface each)
  int boundary_target_faces = 0;  // the face count the target asked of them, summed
  int boundary_retries = 0;     // parts' boundaries tried again (version 22: first its own surface
                                // remeshed into round triangles; then half the bounds, the part's own
                                // surface, then toward four times the faces; and a mostly skinny
                                // part's split boundary) after a non-conforming or sliver
                                // tetrahedralization
  int parts_remeshed = 0;       // parts meshed from their own surface remeshed into round triangles
                                // (retry 0, MeshOptions::remesh_retry; version 22)
  int parts_by_winding_number = 0;  // parts whose boundary still did not hold after the retries,
                                // meshed as their winding-number solid by Mesh_3 instead
  int cavities = 0;             // closed components the file orients inward that lie inside another
                                // (a hollow ball's inner shell): meshed as cavities of that part
  EnvelopeStats envelope;
  TetMesh tets;                 // the coarse tetrahedral mesh: one conforming mesh per part, in part order
  TetQuality quality;
  TetrahedralizeStats tet_stats;
  std::string method = "boundary";  // "boundary": the parts' simplified boundaries tetrahedralized;
                                    // "alpha_wrap": the same of the input's alpha wrap, where the
                                    // input is not closed parts and wrap is asked for;
                                    // "winding_number": the input's winding-number solid meshed
                                    // by Mesh_3 (with `winding`, or where the next fails);
                                    // "winding_number_boundary": that mesh's boundary simplified
                                    // against the input and tetrahedralized (inputs that are not
                                    // closed parts, version 11); "convex_shells": the fallback
                                    // (see fallback_because)
  std::string fallback_because;     // empty, or why the boundary route was not taken
  ShellTetrahedralizeStats shell_stats;  // method "convex_shells"
  WindingTetrahedralizeStats winding_stats;  // methods "winding_number" and "winding_number_boundary"
  int winding_solids = 0;       // method "winding_number_boundary": winding-number solids made (one,
                                // and one more each time the last grew the input's volume too much)
  WrapStats wrap;                   // method "alpha_wrap" (or the shells after it failed)
  int target_tets = 0;
  int sheets = 0;                   // open sheets meshed as slabs (sheet.h; method "boundary")
  int scan_sheets = 0;              // ... of them, open scans of solids (MeshOptions::open_scans_as_sheets)
  double sheet_thickness = 0;       // ... their thickness (units)
  int thin_parts = 0;               // closed parts much thinner than their tetrahedra would be long (a
                                    // plate, a bowl), meshed as one layer of prisms across their
                                    // thickness (method "boundary"; meshing version 15)
  std::string target_exceeded_because;  // empty: the count is within ±35% of the target
  std::string deviation_exceeded_because;  // empty: deviation_out is within 1.5 × max_deviation of the
                                // diagonal (the bound the routes keep within, their chords and dilation
                                // included) and deviation_in within 1.5 × the inner bound; else why
                                // not (meshing version 17; deviation_in: 37)
  double input_volume = 0;      // the parts' enclosed volumes, summed (overlapping parts count twice,
                                // as their tet meshes do)
  bool input_volume_from_winding_number = false;
  std::optional<double> volume_ratio;  // tet volume / the solid's volume, closed inputs only
  double deviation_out = 0;     // largest distance of tet-boundary points from the input surface (units)
  double deviation_in = 0;      // largest distance of input-surface points outside the tet mesh (units)
  double deviation_sample_spacing = 0;  // spacing of the points measured (units)
  int proxy_faces = 0;          // inputs over MeshOptions::dense_faces triangles: the faces of the
                                // proxy meshed in their place (0: the input itself was meshed)
  double proxy_error = 0;       // ... the proxy's bound (units): its vertices lie within it of the
                                // planes of the input's faces they took in
  double inside_fraction = 0;   // input vertices inside the tet mesh
  double covered_fraction = 0;  // ... inside or within coverage_tolerance × diagonal of it
  double max_outside_distance = 0;  // worst distance of an input vertex outside the mesh (units)
  std::vector<std::pair<std::string, double>> seconds;  // per stage, one after the other (their sum: the total)
  std::vector<std::pair<std::string, double>> beside;   // per stage run beside those ("decomposing"; not in the total)
};

/// The hull budget the pipeline uses: min(decomposition.max_hulls, max(1, round(target_tets /
/// tets_per_hull))), or decomposition.max_hulls when tets_per_hull is 0.
int hull_budget(const MeshOptions& options);

/// The routes of inputs that are not closed parts (welded, non-manifold or self-intersecting
/// segments; open scans), by name, as scenes ask for them (objects[].mesh_route) and as the
/// flags of `squeeze mesh` set them: "auto" (the default: the boundary of the winding-number
/// solid, simplified and tetrahedralized), "convex_shells" (shells_fallback), "winding_number"
/// (winding), "alpha_wrap" (wrap), "all_convex_shells" (shells_only: closed parts too). One table
/// for every caller.
const std::vector<std::string>& mesh_route_names();

/// Sets the options of the route `name` (mesh_route_names) on `options`, the other routes' flags
/// cleared. Throws InputError "unknown mesh route "NAME" (auto, convex_shells, ...)".
void set_mesh_route(MeshOptions& options, const std::string& name);

/// The report's deviation_exceeded_because for a result `r` of mesh_surface (which sets it): empty
/// where r.deviation_out is within 1.5 × options.max_deviation of the input's bounding-box diagonal
/// and r.deviation_in within 1.5 × inner_deviation × max_deviation; else a sentence per excess and
/// its cause by r.method (meshing versions 17 and, for deviation_in, 37). Lengths in r are model
/// units; the sentence gives them as percentages of the diagonal. Throws nothing. Source: squeeze's
/// own report (docs/meshing.md, "Report keys").
std::string deviation_exceeded_because(const MeshResult& r, const MeshOptions& options);

/// Runs the pipeline on an already loaded surface (faces need not be consistently oriented).
/// Throws InputError on bad options or an input that yields no volume at all.
MeshResult mesh_surface(const SurfaceMesh& surface, const MeshOptions& options, Progress* progress = nullptr);

/// Loads `path` (see load_surface) and runs mesh_surface on it.
MeshResult mesh_file(const std::filesystem::path& path, const MeshOptions& options, Progress* progress = nullptr);

/// The largest surface mesh_file() takes (triangles): beyond it an InputError asks for a decimated
/// surface before any work (docs/meshing.md, "Limits").
constexpr long kMaxMeshTriangles = 1000000;

/// All convex shells as one surface (for --shells).
SurfaceMesh shells_surface(const Decomposition& d);

/// The report of `squeeze mesh --report` (keys documented in docs/meshing.md).
nlohmann::json mesh_report(const MeshResult& r, const std::string& input_name);

}  // namespace squeeze::meshing
