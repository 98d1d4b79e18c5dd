// The alpha wrap (meshing/alpha_wrap.h) over the real meshes of tests/data: closed, an oriented
// 2-manifold without self-intersections, holding every input vertex (its faces cut chords through the offset band), and
// following the input to within alpha + offset.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "meshing_test_util.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/alpha_wrap.h"
#include "squeeze/meshing/surface_analysis.h"
#include "squeeze/meshing/surface_io.h"
#include "squeeze/meshing/triangle_bvh.h"
#include "squeeze/meshing/winding_number.h"

namespace {

using namespace squeeze::meshing;

TEST(AlphaWrap, ClosesCorpusMeshesAroundTheirInput) {
  // The dragon is open and intersects itself; the left lung is 18 segments welded at shared walls.
  for (const std::string name : {"sphere.off", "ChineseDragon-10kv.off", "bunny00.off", "organs/lung_left.off"}) {
    const SurfaceMesh in = load_surface(sqt::data(name));
    const double diag = bounding_box_diagonal(in.V);
    AlphaWrapOptions o;
    o.alpha = 0.02;
    o.offset = 0.003;
    const SurfaceMesh w = alpha_wrap(in, o);
    ASSERT_GT(w.F.rows(), 0) << name;
    EXPECT_TRUE(is_closed(w.F)) << name;
    EXPECT_TRUE(is_oriented_two_manifold(w.F, static_cast<int>(w.V.rows()))) << name;
    EXPECT_FALSE(does_self_intersect(w)) << name;
    EXPECT_GT(analyse_surface(w).volume, 0.0) << name << ": outward";
    // Every input vertex inside the wrap; the nearest at most the offset from it.
    const FastWindingNumber wn(w.V, w.F);
    const TriangleBvh wrap_surface(w.V, w.F);
    int outside = 0;
    double nearest = INFINITY;
    std::vector<char> used(static_cast<size_t>(in.V.rows()), 0);  // vertices of faces (the wrap ignores others)
    for (Eigen::Index f = 0; f < in.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) used[static_cast<size_t>(in.F(f, k))] = 1;
    for (Eigen::Index i = 0; i < in.V.rows(); ++i) {
      if (!used[static_cast<size_t>(i)]) continue;
      outside += wn(in.V.row(i)) < 0.5;
      nearest = std::min(nearest, wrap_surface.nearest(in.V.row(i).transpose()));
    }
    EXPECT_EQ(outside, 0) << name;
    EXPECT_LE(nearest, 1.01 * o.offset * diag) << name << ": the wrap's vertices lie on the offset surface";
    // Every wrap vertex within alpha + offset of the input.
    const TriangleBvh input_surface(in.V, in.F);
    double farthest = 0;
    for (Eigen::Index i = 0; i < w.V.rows(); ++i)
      farthest = std::max(farthest, input_surface.nearest(w.V.row(i).transpose()));
    EXPECT_LE(farthest, (o.alpha + o.offset) * diag) << name;
  }
}

TEST(AlphaWrap, RejectsBadOptionsAndEmptyInput) {
  SurfaceMesh empty;
  EXPECT_THROW(alpha_wrap(empty), squeeze::InputError);
  const SurfaceMesh s = load_surface(sqt::data("sphere.off"));
  AlphaWrapOptions o;
  o.alpha = 0;
  EXPECT_THROW(alpha_wrap(s, o), squeeze::InputError);
  o.alpha = 0.02;
  o.offset = -1;
  EXPECT_THROW(alpha_wrap(s, o), squeeze::InputError);
}

}  // namespace
