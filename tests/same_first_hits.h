#pragma once
// Two structures over one scene that claim the same first hits (a layout change: quantized
// nodes, indexed leaves), compared on random segments between points of the scene's box. Used by
// test_quantized_wide_node.cpp and test_indexed_leaves.cpp.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>

#include "geometry/bounds.h"
#include "geometry/ray.h"

namespace raylab::test {

/// Expects `b` to report `a`'s first hit (primitive, t, u, v; or none) on each of `rays` random
/// rays through two points of `box`, and its occlusion of the segment's first half; stops at the
/// first ray on which one finds a hit and the other not. Returns how many rays hit.
template <class A, class B>
int expect_same_first_hits(const A& a, const B& b, const Bounds3f& box, unsigned seed, int rays,
                           const std::string& what) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  int hits = 0;
  for (int i = 0; i < rays; ++i) {
    const Vec3f p = box.lo + box.diagonal() * Vec3f{unit(rng), unit(rng), unit(rng)};
    const Vec3f q = box.lo + box.diagonal() * Vec3f{unit(rng), unit(rng), unit(rng)};
    if (p == q) continue;
    SCOPED_TRACE(what + " ray " + std::to_string(i));
    Ray r1{p, q - p, 0.0f, std::numeric_limits<float>::infinity()}, r2 = r1;
    Hit h1, h2;
    const bool found = a.intersect(r1, h1);
    const bool found_b = b.intersect(r2, h2);
    EXPECT_EQ(found, found_b);
    if (found != found_b) return hits;
    if (found) {
      EXPECT_EQ(h1.prim, h2.prim);
      EXPECT_EQ(h1.t, h2.t);
      EXPECT_EQ(h1.u, h2.u);
      EXPECT_EQ(h1.v, h2.v);
    }
    const Ray segment{p, q - p, 0.0f, 0.5f};
    EXPECT_EQ(a.occluded(segment), b.occluded(segment));
    hits += found;
  }
  return hits;
}

}  // namespace raylab::test
