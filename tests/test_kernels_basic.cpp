// Contract tests of the four ray-triangle kernels on hand-made configurations whose answers
// are known exactly.
#include <gtest/gtest.h>

#include "geometry/certified_kernel.h"
#include "geometry/exact_predicates.h"
#include "geometry/triangle_kernels.h"

namespace raylab {
namespace {

const Vec3f P0(0, 0, 0), P1(1, 0, 0), P2(0, 1, 0);

template <class Kernel>
bool hits(const Ray& ray, const Vec3f& a, const Vec3f& b, const Vec3f& c, TriangleHit* out = nullptr) {
  auto ctx = Kernel::prepare(ray);
  TriangleHit h;
  const bool found = Kernel::intersect(ctx, 0, a, b, c, h);
  if (out) *out = h;
  return found;
}

template <class K>
class KernelContract : public ::testing::Test {};
using AllKernels = ::testing::Types<MollerTrumboreKernel, WatertightKernel, ExactKernel, CertifiedKernel>;
TYPED_TEST_SUITE(KernelContract, AllKernels);

TYPED_TEST(KernelContract, InteriorHitReportsTAndBarycentrics) {
  TriangleHit h;
  ASSERT_TRUE(hits<TypeParam>({{0.25f, 0.5f, 2.0f}, {0, 0, -1}}, P0, P1, P2, &h));
  EXPECT_FLOAT_EQ(h.t, 2.0f);
  EXPECT_NEAR(h.u, 0.25f, 1e-6);
  EXPECT_NEAR(h.v, 0.5f, 1e-6);
}

TYPED_TEST(KernelContract, MissOutsideAndBehind) {
  EXPECT_FALSE(hits<TypeParam>({{0.75f, 0.75f, 2.0f}, {0, 0, -1}}, P0, P1, P2));
  EXPECT_FALSE(hits<TypeParam>({{0.25f, 0.25f, -2.0f}, {0, 0, -1}}, P0, P1, P2));
}

TYPED_TEST(KernelContract, RespectsTminAndTmax) {
  EXPECT_FALSE(hits<TypeParam>({{0.25f, 0.25f, 2.0f}, {0, 0, -1}, 0.0f, 1.5f}, P0, P1, P2));
  EXPECT_FALSE(hits<TypeParam>({{0.25f, 0.25f, 2.0f}, {0, 0, -1}, 2.5f, 10.0f}, P0, P1, P2));
  EXPECT_TRUE(hits<TypeParam>({{0.25f, 0.25f, 2.0f}, {0, 0, -1}, 1.5f, 2.5f}, P0, P1, P2));
}

TYPED_TEST(KernelContract, DegenerateTriangleIsNeverHit) {
  EXPECT_FALSE(hits<TypeParam>({{0.5f, 0.0f, 2.0f}, {0, 0, -1}}, P0, P1, Vec3f(2, 0, 0)));
  EXPECT_FALSE(hits<TypeParam>({{0.0f, 0.0f, 2.0f}, {0, 0, -1}}, P0, P0, P0));
}

TYPED_TEST(KernelContract, ClosestOfTwoWins) {
  auto ctx = TypeParam::prepare({{0.25f, 0.25f, 5.0f}, {0, 0, -1}});
  TriangleHit h;
  const Vec3f up(0, 0, 1);
  EXPECT_TRUE(TypeParam::intersect(ctx, 0, P0, P1, P2, h));                 // t = 5
  EXPECT_TRUE(TypeParam::intersect(ctx, 1, P0 + up, P1 + up, P2 + up, h));  // t = 4, closer
  EXPECT_FALSE(TypeParam::intersect(ctx, 2, P0, P1, P2, h));                // t = 5, farther
  EXPECT_FLOAT_EQ(h.t, 4.0f);
}

// The exact kernel decides the closed triangle exactly: a ray through a vertex or along an edge
// hits; a ray one float ulp outside misses.
TEST(ExactKernel, ClosedTriangleBoundaryIsHitAndOneUlpOutsideIsNot) {
  EXPECT_TRUE(hits<ExactKernel>({{0, 0, 1}, {0, 0, -1}}, P0, P1, P2));        // vertex
  EXPECT_TRUE(hits<ExactKernel>({{0.5f, 0.5f, 1}, {0, 0, -1}}, P0, P1, P2));  // hypotenuse
  const float just_out = std::nextafter(0.5f, 1.0f);
  EXPECT_FALSE(hits<ExactKernel>({{just_out, 0.5f, 1}, {0, 0, -1}}, P0, P1, P2));
  EXPECT_FALSE(hits<ExactKernel>({{-1e-30f, 0.5f, 1}, {0, 0, -1}}, P0, P1, P2));
}

TEST(ExactKernel, RayInThePlaneHitsAtTheEntryOfTheContactSegment) {
  TriangleHit h;
  ASSERT_TRUE(hits<ExactKernel>({{-1.0f, 0.25f, 0.0f}, {1, 0, 0}}, P0, P1, P2, &h));
  EXPECT_FLOAT_EQ(h.t, 1.0f);
  ASSERT_TRUE(hits<ExactKernel>({{-1.0f, 0.25f, 0.0f}, {1, 0, 0}, 1.5f}, P0, P1, P2, &h));
  EXPECT_FLOAT_EQ(h.t, 1.5f);  // starts inside the contact segment
}

TEST(ExactKernel, OrderingIsExactBeyondFloatResolution) {
  // Two parallel triangles whose distances differ by less than a float ulp of t: both t round
  // to the same float, but the exact order is known, whatever the order of the offers.
  const float z_near = 1.0f, z_far = std::nextafter(1.0f, 2.0f);
  const Vec3f org(0.25f, 0.25f, 3.0f);
  const Vec3f far_shift(0, 0, z_far), near_shift(0, 0, z_near);
  for (int order = 0; order < 2; ++order) {
    ExactFirstHit first(Ray{org, Vec3f(0, 0, -1)});
    if (order == 0) {
      first.offer_triangle(7, P0 + near_shift, P1 + near_shift, P2 + near_shift);
      first.offer_triangle(3, P0 + far_shift, P1 + far_shift, P2 + far_shift);
    } else {
      first.offer_triangle(3, P0 + far_shift, P1 + far_shift, P2 + far_shift);
      first.offer_triangle(7, P0 + near_shift, P1 + near_shift, P2 + near_shift);
    }
    ASSERT_TRUE(first.has_hit());
    EXPECT_EQ(first.hit().prim, 3u) << "the far-in-z triangle is nearer along a ray travelling down from z = 3";
  }
}

TEST(ExactKernel, EqualTimesBreakTiesByLowerPrimitiveId) {
  ExactFirstHit first(Ray{{0.5f, 0.0f, 1.0f}, {0, 0, -1}});
  first.offer_triangle(9, P0, P1, P2);
  first.offer_triangle(4, P0, P1, Vec3f(0.5f, -1.0f, 0.0f));  // shares the edge x in [0,1], y = 0
  ASSERT_TRUE(first.has_hit());
  EXPECT_EQ(first.hit().prim, 4u);
}

TEST(ExactKernel, SphereRootsAreOrderedExactlyAgainstTriangles) {
  ExactFirstHit first(Ray{{0, 0, 10}, {0, 0, -1}});
  first.offer_sphere(5, Sphere{{0, 0, 0}, 1.0f});                                    // t = 9
  first.offer_triangle(2, Vec3f(-1, -1, 1), Vec3f(1, -1, 1), Vec3f(0, 1, 1));         // t = 9, tie
  ASSERT_TRUE(first.has_hit());
  EXPECT_EQ(first.hit().prim, 2u);
  EXPECT_FLOAT_EQ(first.hit().t, 9.0f);
  first.offer_triangle(1, Vec3f(-1, -1, 0.5f), Vec3f(1, -1, 0.5f), Vec3f(0, 1, 0.5f));  // t = 9.5
  EXPECT_EQ(first.hit().prim, 2u);
}

// Where |d| is far below |o|, o + d rounds to o in double: CGAL's Epick ray through o and
// o + d is then degenerate (a point), outside its predicates' preconditions, and answered a hit
// here (found by fuzz_build_trace). The exact kernel takes a second point o + 2^k·d that double
// holds exactly.
TEST(ExactKernel, DirectionFarBelowTheOriginDecidesTheTrueRay) {
  const float tiny = 0x1p-126f;
  const Vec3f wall_a(0, 1, 0), wall_b(0, 0, 0), wall_c(0, 0, 1);  // in the plane x = 0, z <= 1
  EXPECT_FALSE(hits<ExactKernel>({{0, 0, 1.0049f}, {0, 0, tiny}, 0.0f, 0.0f}, wall_a, wall_b, wall_c));
  EXPECT_FALSE(hits<ExactKernel>({{0, 0, 1.0049f}, {0, 0, tiny}}, wall_a, wall_b, wall_c));
  TriangleHit h;
  ASSERT_TRUE(hits<ExactKernel>({{0.25f, 0.25f, -1.0f}, {0, 0, tiny}}, P0, P1, P2, &h));
  EXPECT_EQ(h.t, 0x1p126f);

  const Ray far{{1e6f, 3.0f, 0.0f}, {1e-10f, 1.0f, 0.0f}};
  Vec3d second;
  ASSERT_TRUE(exact_second_point(far, second));
  const double scale = second.y - 3.0;  // d.y = 1
  EXPECT_GT(scale, 0.0);
  EXPECT_EQ(second.x - 1e6f, double(1e-10f) * scale);  // exact: the point lies on the ray
  EXPECT_EQ(second.z, 0.0);
}

TEST(ExactKernel, InvalidRaysNeverHit) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(hits<ExactKernel>({{nan, 0, 1}, {0, 0, -1}}, P0, P1, P2));
  EXPECT_FALSE(hits<ExactKernel>({{0.2f, 0.2f, 1}, {0, 0, 0}}, P0, P1, P2));
}

}  // namespace
}  // namespace raylab
