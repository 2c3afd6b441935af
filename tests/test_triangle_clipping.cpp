#include <gtest/gtest.h>

#include <random>

#include "geometry/exact_predicates.h"
#include "geometry/triangle_clipping.h"

namespace raylab {
namespace {

TEST(TriangleClipping, TriangleInsideTheBoxKeepsItsExactBounds) {
  const Bounds3f box({0, 0, 0}, {4, 4, 4});
  const Bounds3f b = clipped_triangle_bounds({1, 1, 1}, {2, 1, 1}, {1, 3, 2}, box);
  EXPECT_EQ(b.lo, Vec3f(1, 1, 1));
  EXPECT_EQ(b.hi, Vec3f(2, 3, 2));
}

TEST(TriangleClipping, ClippedBoundsAreTighterThanTheBoxIntersection) {
  // A diagonal triangle through the corner region: its part inside the unit box is small.
  const Bounds3f box({0, 0, 0}, {1, 1, 1});
  const Bounds3f b = clipped_triangle_bounds({-1, 0.5f, 0.5f}, {0.5f, -1, 0.5f}, {-1, -1, 0.5f}, box);
  EXPECT_FALSE(b.empty());
  EXPECT_LE(b.hi.x, 0.5f + 1e-6f);
  EXPECT_LE(b.hi.y, 0.5f + 1e-6f);
  EXPECT_EQ(b.lo.z, 0.5f);
  EXPECT_EQ(b.hi.z, 0.5f);
}

/// Random triangles against random boxes: the clipped bounds lie in the box and contain every
/// sampled point of triangle ∩ box; they are never empty when the exact predicate says the
/// triangle meets the box.
TEST(TriangleClipping, ContainsEverySampledPointOfTheIntersection) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f), w(0.0f, 1.0f);
  int meeting = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3f p0(u(rng), u(rng), u(rng)), p1(u(rng), u(rng), u(rng)), p2(u(rng), u(rng), u(rng));
    const Bounds3f box(Vec3f(u(rng), u(rng), u(rng)), Vec3f(u(rng), u(rng), u(rng)));
    const Bounds3f b = clipped_triangle_bounds(p0, p1, p2, box);
    if (!exact_triangle_intersects_box(p0, p1, p2, box)) continue;
    ++meeting;
    ASSERT_FALSE(b.empty());
    EXPECT_TRUE(box.contains(b.lo) && box.contains(b.hi));
    for (int s = 0; s < 200; ++s) {
      float a = w(rng), c = w(rng);
      if (a + c > 1.0f) { a = 1.0f - a; c = 1.0f - c; }
      const Vec3d p = Vec3d(p0) * (1.0 - a - c) + Vec3d(p1) * double(a) + Vec3d(p2) * double(c);
      const bool inside = p.x >= box.lo.x && p.x <= box.hi.x && p.y >= box.lo.y && p.y <= box.hi.y &&
                          p.z >= box.lo.z && p.z <= box.hi.z;
      if (!inside) continue;
      for (int k = 0; k < 3; ++k) {
        EXPECT_LE(double(b.lo[k]), p[k] + 1e-12 * (1 + std::abs(p[k])));
        EXPECT_GE(double(b.hi[k]), p[k] - 1e-12 * (1 + std::abs(p[k])));
      }
    }
  }
  EXPECT_GT(meeting, 100);
}

/// The same guarantees for both children of a split box, from one clip of the triangle to the
/// parent box: each child's bounds lie in the child and contain every sampled point of
/// triangle ∩ child, and are never empty when the exact predicate says the triangle meets it.
TEST(TriangleClipping, SplitClipContainsEverySampledPointOfEachChild) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f), w(0.0f, 1.0f);
  int meeting = 0, inside_one_child = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    // Some triangles lie inside the parent box, so that one child holds them whole.
    const float spread = trial % 3 == 0 ? 0.5f : 1.0f;
    const Vec3f p0 = Vec3f(u(rng), u(rng), u(rng)) * spread, p1 = Vec3f(u(rng), u(rng), u(rng)) * spread,
                p2 = Vec3f(u(rng), u(rng), u(rng)) * spread;
    const Bounds3f box(Vec3f(u(rng), u(rng), u(rng)), Vec3f(u(rng), u(rng), u(rng)));
    if (box.empty()) continue;
    const int axis = trial % 3;
    const float pos = box.lo[axis] + w(rng) * (box.hi[axis] - box.lo[axis]);
    Bounds3f child[2] = {box, box};
    child[0].hi[axis] = pos;
    child[1].lo[axis] = pos;
    Bounds3f got[2];
    clipped_triangle_bounds_split(p0, p1, p2, box, axis, pos, got[0], got[1]);
    for (int c = 0; c < 2; ++c) {
      if (!exact_triangle_intersects_box(p0, p1, p2, child[c])) continue;
      ++meeting;
      const Bounds3f& b = got[c];
      ASSERT_FALSE(b.empty());
      EXPECT_TRUE(child[c].contains(b.lo) && child[c].contains(b.hi));
      inside_one_child += child[c].contains(min(min(p0, p1), p2)) && child[c].contains(max(max(p0, p1), p2));
      for (int s = 0; s < 200; ++s) {
        float a = w(rng), e = w(rng);
        if (a + e > 1.0f) { a = 1.0f - a; e = 1.0f - e; }
        const Vec3d p = Vec3d(p0) * (1.0 - a - e) + Vec3d(p1) * double(a) + Vec3d(p2) * double(e);
        bool inside = true;
        for (int k = 0; k < 3; ++k) inside &= p[k] >= child[c].lo[k] && p[k] <= child[c].hi[k];
        if (!inside) continue;
        for (int k = 0; k < 3; ++k) {
          EXPECT_LE(double(b.lo[k]), p[k] + 1e-12 * (1 + std::abs(p[k])));
          EXPECT_GE(double(b.hi[k]), p[k] - 1e-12 * (1 + std::abs(p[k])));
        }
      }
    }
  }
  EXPECT_GT(meeting, 200);
  EXPECT_GT(inside_one_child, 5);
}

TEST(TriangleClipping, TriangleTouchingAFaceGivesAFlatBox) {
  const Bounds3f box({0, 0, 0}, {1, 1, 1});
  const Bounds3f b = clipped_triangle_bounds({1, 0.2f, 0.2f}, {2, 0.8f, 0.2f}, {2, 0.2f, 0.8f}, box);
  EXPECT_FALSE(b.empty());
  EXPECT_EQ(b.lo.x, 1.0f);
  EXPECT_EQ(b.hi.x, 1.0f);
}

}  // namespace
}  // namespace raylab
