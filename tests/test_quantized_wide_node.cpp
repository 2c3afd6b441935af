// Quantized wide nodes (lib/accel/bvh/quantized_wide_node.h): every child box the traversal reads
// contains the full node's box, read alike by the scalar and SIMD dequantization with and without
// FTZ/DAZ, near the origin, far from it, tiny and huge; the box tests keep every child the full
// node's tests hit, no later; and `bvh:nodes=quantized` finds the first hits of `nodes=full`.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>

#include "accel/bvh/bvh.h"
#include "accel/bvh/quantized_wide_node.h"
#include "accel/bvh/simd_box_test.h"
#include "geometry/float_mode.h"
#include "scene/scene_spec.h"
#include "same_first_hits.h"

namespace raylab {
namespace {

bool box_contains(const Bounds3f& outer, const Bounds3f& inner) {
  for (int a = 0; a < 3; ++a)
    if (!(outer.lo[a] <= inner.lo[a] && inner.hi[a] <= outer.hi[a])) return false;
  return true;
}

/// A node of `used` random child boxes of extent ~`size` around `centre`; one in five flat on an
/// axis, one in ten equal to the first.
template <int N>
WideBvhNode<N> random_node(std::mt19937& rng, int used, float centre, float size) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 9);
  WideBvhNode<N> node;
  node.used = static_cast<std::uint32_t>(used);
  for (int i = 0; i < N; ++i) {
    node.child[i] = static_cast<std::uint32_t>(i);
    for (int a = 0; a < 3; ++a) {
      float lo = centre + size * unit(rng), hi = centre + size * unit(rng);
      if (lo > hi) std::swap(lo, hi);
      if (pick(rng) < 2) hi = lo;
      if (i > 0 && pick(rng) == 0) lo = node.bounds[a][0], hi = node.bounds[3 + a][0];
      node.bounds[a][i] = i < used ? lo : std::numeric_limits<float>::infinity();
      node.bounds[3 + a][i] = i < used ? hi : -std::numeric_limits<float>::infinity();
    }
  }
  return node;
}

/// Checks that quantize_wide_node(node)'s boxes contain node's, that the SIMD planes are the
/// scalar ones bit for bit, and that no plane lies more than two steps (plus the rounding at the
/// origin's magnitude) outside the full one.
template <int N>
void check_quantized(const WideBvhNode<N>& node) {
  const QuantizedWideBvhNode<N> q = quantize_wide_node(node);
  ASSERT_EQ(q.used, node.used);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(std::exp2(std::ilogb(q.step[a])), q.step[a]) << "the step is a power of two";
    EXPECT_TRUE(q.origin[a] == 0.0f || std::abs(q.origin[a]) >= std::numeric_limits<float>::min());
  }
  for (int p = 0; p < 6; ++p) {
    alignas(32) float planes[N];
    child_planes(q, p, p % 3).store(planes);
    for (int i = 0; i < static_cast<int>(q.used); ++i) {
      const Bounds3f box = q.box(i);
      const float scalar = p < 3 ? box.lo[p] : box.hi[p - 3];
      ASSERT_EQ(std::bit_cast<std::uint32_t>(planes[i]), std::bit_cast<std::uint32_t>(scalar))
          << "plane " << p << " lane " << i;
    }
  }
  for (int i = 0; i < static_cast<int>(q.used); ++i) {
    const Bounds3f full = node.box(i), box = q.box(i);
    ASSERT_TRUE(box_contains(box, full)) << "lane " << i;
    for (int a = 0; a < 3; ++a) {
      const double slack = 2.0 * q.step[a] + std::abs(double(q.origin[a])) * 0x1p-23 + 0x1p-126;
      EXPECT_LE(double(full.lo[a]) - box.lo[a], slack) << "lane " << i << " axis " << a;
      EXPECT_LE(double(box.hi[a]) - full.hi[a], slack) << "lane " << i << " axis " << a;
    }
  }
}

TEST(QuantizedWideNode, EveryChildBoxContainsItsFullBoxAtEveryScale) {
  std::mt19937 rng(11);
  // Centres and sizes: near the origin, 10^4 and 10^7 away with small boxes (the step then meets
  // the origin's rounding), tiny (10^-30, near the subnormals, and subnormal), huge (10^37, near
  // overflow), and boxes straddling 0.
  const std::pair<float, float> scales[] = {{0.0f, 1.0f},    {1e4f, 1e-3f},    {-1e7f, 0.5f},   {1e4f, 1e-9f},
                                            {0.0f, 1e-30f},  {1e-36f, 1e-37f}, {0.0f, 1e-39f},  {2e-38f, 1e-39f},
                                            {0.0f, 1e37f},   {-1e38f, 1e37f}};
  for (const bool flush : {false, true}) {
    const FloatModeScope mode(flush);
    for (const auto& [centre, size] : scales)
      for (int trial = 0; trial < 300; ++trial) {
        SCOPED_TRACE("centre " + std::to_string(centre) + " size " + std::to_string(size) +
                     " flush " + std::to_string(flush));
        check_quantized(random_node<8>(rng, 1 + trial % 8, centre, size));
        check_quantized(random_node<4>(rng, 1 + trial % 4, centre, size));
      }
  }
}

/// Random rays against a random node, full and quantized: the quantized test keeps every lane the
/// full one hits, with an entry no later, for the robust and the fast test.
template <int N, bool kRobust>
void check_box_tests(std::mt19937& rng, float centre, float size) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 9);
  int hits = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const WideBvhNode<N> full = random_node<N>(rng, 1 + trial % N, centre, size);
    const QuantizedWideBvhNode<N> q = quantize_wide_node(full);
    Ray ray{Vec3f(centre) + Vec3f{unit(rng), unit(rng), unit(rng)} * (3.0f * size),
            Vec3f{unit(rng), unit(rng), unit(rng)}, 0.0f, std::numeric_limits<float>::infinity()};
    for (int a = 0; a < 3; ++a)
      if (pick(rng) == 0) ray.dir[a] = pick(rng) < 5 ? 0.0f : -0.0f;  // the robust test's masked path
    if (ray.dir == Vec3f(0.0f)) ray.dir.x = 1.0f;
    if (pick(rng) < 5)  // aimed at a child
      ray.org = full.box(trial % static_cast<int>(full.used)).center() - ray.dir * 2.0f * size;
    const WideBoxRay<N, kRobust> test(ray);
    alignas(32) float entry_full[N], entry_q[N];
    const unsigned mask_full = test.hit(full, ray.tmax, entry_full);
    const unsigned mask_q = test.hit(q, ray.tmax, entry_q);
    ASSERT_EQ(mask_full & ~mask_q, 0u) << "trial " << trial << ": a child the full node hits is missed";
    ASSERT_EQ(mask_q >> full.used, 0u) << "trial " << trial << ": an unused lane is hit";
    for (unsigned m = mask_full; m != 0; m &= m - 1) {
      const int i = std::countr_zero(m);
      ASSERT_LE(entry_q[i], entry_full[i]) << "trial " << trial << " lane " << i;
    }
    hits += std::popcount(mask_full);
  }
  EXPECT_GT(hits, 1000);
}

TEST(QuantizedWideNode, BoxTestsKeepEveryChildTheFullNodeHitsNoLater) {
  std::mt19937 rng(5);
  for (const auto& [centre, size] : {std::pair{0.0f, 1.0f}, std::pair{1e4f, 1e-2f}, std::pair{0.0f, 1e-20f}}) {
    SCOPED_TRACE("centre " + std::to_string(centre) + " size " + std::to_string(size));
    check_box_tests<8, true>(rng, centre, size);
    check_box_tests<8, false>(rng, centre, size);
    check_box_tests<4, true>(rng, centre, size);
    check_box_tests<4, false>(rng, centre, size);
  }
}

/// The same first hits as full nodes: the same leaves, under boxes that only grew.
TEST(QuantizedWideNode, BvhFindsTheFirstHitsOfFullNodes) {
  for (const char* spec : {"soup:n=3000", "walls:n=12,angle=30", "sphereflake:depth=1",
                           "transformed:of=(sphere:n=2000),translate=1e4:-1e4:1e4",
                           "transformed:of=(soup:n=2000),scale=1e-4"}) {
    const auto scene = make_scene(spec);
    const Bounds3f box = scene->bounds();
    for (const int width : {4, 8})
      for (const KernelChoice kernel : {KernelChoice::certified, KernelChoice::watertight}) {
        BvhConfig config;
        config.threads = 1;
        config.width = width;
        config.kernel = kernel;
        const Bvh full(scene, config);
        config.nodes = BvhNodes::quantized;
        const Bvh quantized(scene, config);
        EXPECT_LT(quantized.stats().bytes, full.stats().bytes);
        EXPECT_EQ(quantized.stats().nodes, full.stats().nodes);
        const int hits = test::expect_same_first_hits(full, quantized, box, static_cast<unsigned>(width), 3000,
                                                      std::string(spec) + " width " + std::to_string(width));
        EXPECT_GT(hits, 100);
      }
  }
}

}  // namespace
}  // namespace raylab
