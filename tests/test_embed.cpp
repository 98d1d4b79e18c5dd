// Tests of embedded collision meshes (fem::World::embed): a deformable object simulated on one mesh
// (a coarse cage) collides and measures its volume with another (the tight mesh of its surface)
// whose vertices follow the cage by barycentric coordinates.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "squeeze/common/error.h"
#include "squeeze/fem/body.h"
#include "squeeze/fem/forces.h"
#include "squeeze/fem/integrator.h"
#include "squeeze/fem/world.h"

using namespace squeeze;
using namespace squeeze::fem;
using Eigen::Vector3d;

namespace {

meshing::TetMesh translated(meshing::TetMesh m, const Vector3d& t) {
  m.V.rowwise() += t.transpose();
  return m;
}

Material soft() {
  Material m;
  m.k_distance = m.k_volume = 20;
  m.damping_distance = m.damping_volume = 0.01;
  m.deformation_damping = 20;
  return m;
}

// A ball thrown at a rigid wall, embedded in itself or not.
World ball_at_wall(const std::string& integrator, bool embed_itself) {
  WorldOptions o;
  o.integrator = integrator;
  o.h = integrator == "implicit" ? 1.0 / 60 : 2e-4;
  o.gravity.setZero();
  o.contact_stiffness = 2e4;
  o.contact_damping = 5;
  World w(o);
  const meshing::TetMesh ball = ball_tet_mesh(0.1, 5);
  w.add_body(Body(ball, soft()));
  w.add_body(Body(translated(box_tet_mesh(Vector3d(0, -0.5, -0.5), Vector3d(0.2, 0.5, 0.5), Eigen::Vector3i(2, 5, 5)),
                             Vector3d(0.08, 0, 0)),
                  Material{}, true));
  if (embed_itself) w.embed(0, ball);
  w.prepare();
  return w;
}

}  // namespace

// An object embedded in its own mesh (every vertex follows itself: barycentric coordinates 1, 0,
// 0, 0 up to rounding) has the same contacts and the same forces as without the embedding, and
// the implicit integrator moves it the same way.
TEST(FemEmbed, ABodyEmbeddedInItselfCollidesAsItDoesAlone) {
  {
    World a = ball_at_wall("verlet", false), b = ball_at_wall("verlet", true);
    ASSERT_FALSE(a.embedded(0));
    ASSERT_TRUE(b.embedded(0));
    State s = a.initial_state();  // the ball reaches 2 cm into the wall's face (x = 0.08)
    RowMatrixX3d Fa, Fb;
    for (int i = 0; i < s.x.rows(); ++i) s.v(i, 0) = 1.0;
    a.total_forces(s, nullptr, Fa);
    b.total_forces(s, nullptr, Fb);
    ASSERT_GT(a.last_stats().colliding_vertices, 5);
    EXPECT_EQ(a.last_stats().colliding_vertices, b.last_stats().colliding_vertices);
    EXPECT_LE((Fa - Fb).cwiseAbs().maxCoeff(), 1e-9 * Fa.cwiseAbs().maxCoeff());
    EXPECT_GT(Fa.col(0).minCoeff(), 0.0 - 1e-9) << "the wall pushes the ball back (−x) only on its colliding side";
  }
  World a = ball_at_wall("implicit", false), b = ball_at_wall("implicit", true);
  State sa = a.initial_state(), sb = b.initial_state();
  for (int i = 0; i < sa.x.rows(); ++i) sa.v(i, 0) = sb.v(i, 0) = 2.0;
  for (int k = 0; k < 20; ++k) {
    a.step(sa);
    b.step(sb);
  }
  EXPECT_LT(sa.v.col(0).mean(), 0.0) << "it came off the wall";
  EXPECT_LE((sa.x - sb.x).cwiseAbs().maxCoeff(), 1e-6);
}

// A cage (a 30 cm box) around a 10 cm ball embedded in it falls on a rigid slab: it rests on the
// ball, the box's bottom below the slab's top; without the ball it rests on the box.
TEST(FemEmbed, ACageRestsOnItsEmbeddedSurface) {
  auto drop = [](bool embed, double* ball_bottom) {
    WorldOptions o;
    o.integrator = "implicit";
    o.h = 1.0 / 60;
    o.contact_stiffness = 1e4;
    o.contact_damping = 10;
    World w(o);
    const Vector3d c(0, 0.25, 0);
    w.add_body(Body(translated(box_tet_mesh(Vector3d::Constant(-0.15), Vector3d::Constant(0.15), Eigen::Vector3i::Constant(3)), c),
                    soft()));
    w.add_body(Body(box_tet_mesh(Vector3d(-0.5, -0.2, -0.5), Vector3d(0.5, 0, 0.5), Eigen::Vector3i(4, 1, 4)), Material{}, true));
    if (embed) w.embed(0, translated(ball_tet_mesh(0.1, 6), c));
    State s = w.initial_state();
    for (int k = 0; k < 90; ++k) w.step(s);
    EXPECT_TRUE(s.x.allFinite());
    if (ball_bottom) *ball_bottom = w.collision_positions(s, 0).col(1).minCoeff();
    return s.x.col(1).minCoeff();  // the cage's bottom
  };
  double ball = 0;
  const double cage_embedded = drop(true, &ball), cage_alone = drop(false, nullptr);
  std::printf("resting: the embedded ball's bottom at %.4f m, its cage's at %.4f m; the cage alone at %.4f m\n", ball,
              cage_embedded, cage_alone);
  EXPECT_NEAR(ball, 0.0, 0.01);          // on the slab
  EXPECT_LT(cage_embedded, -0.03);       // the box's bottom (5 cm below the ball's) went into the slab
  EXPECT_NEAR(cage_alone, 0.0, 0.01);    // without the ball, the box rests on it
}

// body_volume measures the embedded mesh: at rest its volume, under an affine map of the cage its
// volume times the determinant (barycentric coordinates reproduce affine maps).
TEST(FemEmbed, VolumeIsTheEmbeddedMeshsAndFollowsAffineMaps) {
  World w;
  w.add_body(Body(box_tet_mesh(Vector3d::Constant(-0.2), Vector3d::Constant(0.2), Eigen::Vector3i::Constant(2)), soft()));
  const meshing::TetMesh ball = ball_tet_mesh(0.12, 5);
  w.embed(0, ball);
  w.prepare();
  const double V0 = Body(ball, soft()).total_volume();
  State s = w.initial_state();
  EXPECT_NEAR(w.body_volume(s, 0), V0, 1e-12 * V0);
  EXPECT_NE(V0, w.body(0).total_volume());
  Eigen::Matrix3d A;
  A << 1.1, 0.2, 0, 0, 0.9, 0.1, 0.05, 0, 1.2;
  for (int i = 0; i < s.x.rows(); ++i) s.x.row(i) = (A * s.x.row(i).transpose() + Vector3d(0.3, -1, 2)).transpose();
  EXPECT_NEAR(w.body_volume(s, 0), A.determinant() * V0, 1e-9 * V0);
  const RowMatrixX3d X = w.collision_positions(s, 0);
  ASSERT_EQ(X.rows(), ball.V.rows());
  for (Eigen::Index k = 0; k < X.rows(); ++k)
    EXPECT_LE((X.row(k).transpose() - (A * ball.V.row(k).transpose() + Vector3d(0.3, -1, 2))).norm(), 1e-12);
}

TEST(FemEmbed, BadEmbeddingsAreRefused) {
  World w;
  w.add_body(Body(box_tet_mesh(Vector3d::Zero(), Vector3d::Ones(), Eigen::Vector3i::Constant(1)), soft()));
  w.add_body(Body(box_tet_mesh(Vector3d::Constant(2), Vector3d::Constant(3), Eigen::Vector3i::Constant(1)), Material{}, true));
  const meshing::TetMesh ball = ball_tet_mesh(0.3, 3);
  EXPECT_THROW(w.embed(1, ball), InputError);   // rigid
  EXPECT_THROW(w.embed(2, ball), InputError);   // out of range
  EXPECT_THROW(w.embed(-1, ball), InputError);
  meshing::TetMesh inverted = ball;
  inverted.T.col(0).swap(inverted.T.col(1));
  EXPECT_THROW(w.embed(0, inverted), InputError);
  EXPECT_THROW(w.embed(0, meshing::TetMesh{}), InputError);
  meshing::TetMesh nan = ball;
  nan.V(0, 0) = std::nan("");
  EXPECT_THROW(w.embed(0, nan), InputError);
  EXPECT_FALSE(w.embedded(0));
  w.embed(0, ball);
  EXPECT_TRUE(w.embedded(0));
  EXPECT_EQ(w.collision_body(0).vertices(), ball.V.rows());
}

// The floor holds an embedded mesh, not its cage: the box cage around the ball sinks into the
// floor until the ball rests on it, with the implicit step and with Verlet.
TEST(FemEmbed, TheFloorHoldsTheEmbeddedSurface) {
  for (const std::string integrator : {"implicit", "verlet"}) {
    SCOPED_TRACE(integrator);
    WorldOptions o;
    o.integrator = integrator;
    o.h = integrator == "implicit" ? 1.0 / 60 : 5e-4;
    o.floor = true;
    o.contact_stiffness = 1e4;
    o.contact_damping = 10;
    World w(o);
    const Vector3d c(0, 0.25, 0);
    Material firm = soft();
    firm.k_distance = firm.k_volume = 2000;  // holds its 27 kg
    w.add_body(Body(translated(box_tet_mesh(Vector3d::Constant(-0.15), Vector3d::Constant(0.15), Eigen::Vector3i::Constant(3)), c),
                    firm));
    w.embed(0, translated(ball_tet_mesh(0.1, 6), c));
    State s = w.initial_state();
    const int steps = static_cast<int>(std::lround(3.0 / o.h));
    double ball = 1, cage = 1;  // lowest points over the last second (Verlet bounces longer)
    for (int k = 0; k < steps; ++k) {
      w.step(s);
      if (k >= steps - static_cast<int>(std::lround(1.0 / o.h))) {
        const double b = w.collision_positions(s, 0).col(1).minCoeff();
        if (b < ball) ball = b, cage = s.x.col(1).minCoeff();
      }
    }
    ASSERT_TRUE(s.x.allFinite());
    std::printf("%s: on the floor, the ball's bottom at %.4f m at the lowest in the last second, its cage's then %.4f m\n",
                integrator.c_str(), ball, cage);
    EXPECT_LT(ball, 0.005);        // it lands on the ball (a penalty floor: Verlet bounces 3-4 cm deep,
    EXPECT_GT(ball, -0.05);        // the implicit step's damping settles it 4-5 mm deep)
    EXPECT_LT(cage, ball - 0.03);  // the box's bottom, 5 cm below the ball's, is then under the floor
  }
}
