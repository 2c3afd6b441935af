// The BVH builders (lib/accel/bvh/bvh_build.h): tree validity for every builder, the depth
// contract, the SBVH duplication bound and coverage of clipped references, SAH quality
// relations, determinism across thread counts, and degenerate inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "accel/bvh/bvh_build.h"
#include "accel/bvh/bvh_optimize.h"
#include "geometry/exact_predicates.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

const std::vector<BvhBuilder> kAllBuilders = {BvhBuilder::midpoint, BvhBuilder::median, BvhBuilder::sweep,
                                              BvhBuilder::binned, BvhBuilder::spatial};

std::string builder_name(BvhBuilder b) {
  switch (b) {
    case BvhBuilder::midpoint: return "midpoint";
    case BvhBuilder::median: return "median";
    case BvhBuilder::sweep: return "sweep";
    case BvhBuilder::binned: return "binned";
    case BvhBuilder::spatial: return "spatial";
  }
  return "?";
}

BvhConfig config_for(BvhBuilder b, int threads = 1) {
  BvhConfig c;
  c.builder = b;
  c.threads = threads;
  return c;
}

bool box_inside(const Bounds3f& inner, const Bounds3f& outer) {
  return inner.empty() || (outer.contains(inner.lo) && outer.contains(inner.hi));
}

/// Sample points of the triangle (a barycentric grid, in double precision).
std::vector<Vec3d> triangle_samples(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  std::vector<Vec3d> out;
  constexpr int k = 6;
  for (int i = 0; i <= k; ++i)
    for (int j = 0; i + j <= k; ++j) {
      const double u = double(i) / k, v = double(j) / k;
      out.push_back(Vec3d(a) * (1.0 - u - v) + Vec3d(b) * u + Vec3d(c) * v);
    }
  return out;
}

bool contains_with_tolerance(const Bounds3f& box, const Vec3d& p, double tol) {
  for (int a = 0; a < 3; ++a)
    if (p[a] < double(box.lo[a]) - tol || p[a] > double(box.hi[a]) + tol) return false;
  return true;
}

/// Checks the structural contract of `bvh` over `scene`.
void expect_valid(const Scene& scene, const Bvh2& bvh, BvhBuilder builder) {
  SCOPED_TRACE(builder_name(builder) + " on " + scene.spec);
  const std::size_t n = scene.primitive_count();
  ASSERT_EQ(bvh.primitive_count, n);
  ASSERT_FALSE(bvh.nodes.empty());
  EXPECT_LE(bvh_depth(bvh), kBvhMaxDepth);
  const bool splits = builder == BvhBuilder::spatial;
  if (!splits) {
    EXPECT_EQ(bvh.prims.size(), n);
  }

  // Every node reached once, children inside parents, leaves inside prims.
  std::vector<int> reached(bvh.nodes.size(), 0);
  std::vector<std::vector<std::uint32_t>> leaves_of(n);  // leaves referencing each primitive
  std::vector<std::uint32_t> todo = {0};
  std::size_t refs = 0;
  while (!todo.empty()) {
    const std::uint32_t i = todo.back();
    todo.pop_back();
    ASSERT_LT(i, bvh.nodes.size());
    ++reached[i];
    const Bvh2Node& node = bvh.nodes[i];
    if (node.is_leaf()) {
      ASSERT_LE(std::size_t(node.first) + node.count, bvh.prims.size());
      refs += node.count;
      for (std::uint32_t k = 0; k < node.count; ++k) {
        const std::uint32_t p = bvh.prims[node.first + k];
        ASSERT_LT(p, n);
        leaves_of[p].push_back(i);
      }
      continue;
    }
    ASSERT_LT(std::size_t(node.first) + 1, bvh.nodes.size());
    for (std::uint32_t c = node.first; c <= node.first + 1; ++c) {
      EXPECT_TRUE(box_inside(bvh.nodes[c].box, node.box)) << "child " << c << " of node " << i;
      todo.push_back(c);
    }
  }
  EXPECT_EQ(refs, bvh.prims.size());
  for (std::size_t i = 0; i < reached.size(); ++i) EXPECT_EQ(reached[i], 1) << "node " << i;

  const Bounds3f root = bvh.nodes[0].box;
  const double tol = 1e-6 * double(length(root.diagonal()));
  for (std::uint32_t p = 0; p < n; ++p) {
    ASSERT_FALSE(leaves_of[p].empty()) << "primitive " << p << " not referenced";
    const Bounds3f pb = scene.primitive_bounds(p);
    for (std::uint32_t leaf : leaves_of[p]) {
      const Bounds3f& lb = bvh.nodes[leaf].box;
      if (!splits) {
        EXPECT_TRUE(box_inside(pb, lb)) << "primitive " << p << " outside its leaf " << leaf;
        continue;
      }
      EXPECT_TRUE(pb.overlaps(lb)) << "primitive " << p << " misses its leaf " << leaf;
      if (scene.is_sphere(p)) continue;
      const Vec3f a = scene.mesh.vertex(p, 0), b = scene.mesh.vertex(p, 1), c = scene.mesh.vertex(p, 2);
      if (!is_degenerate_exact(a, b, c)) {
        EXPECT_TRUE(exact_triangle_intersects_box(a, b, c, lb)) << "triangle " << p << " misses its leaf " << leaf;
      }
    }
    // The leaves of a primitive cover it (clipped references stay conservative).
    if (splits && !scene.is_sphere(p)) {
      const Vec3f a = scene.mesh.vertex(p, 0), b = scene.mesh.vertex(p, 1), c = scene.mesh.vertex(p, 2);
      for (const Vec3d& s : triangle_samples(a, b, c)) {
        const bool covered = std::any_of(leaves_of[p].begin(), leaves_of[p].end(), [&](std::uint32_t leaf) {
          return contains_with_tolerance(bvh.nodes[leaf].box, s, tol);
        });
        EXPECT_TRUE(covered) << "a point of triangle " << p << " lies in none of its leaves";
      }
    }
  }
}

Scene scene_from_spec(const std::string& spec) { return *make_scene(spec); }

Scene identical_triangles(int count) {
  Scene s;
  s.spec = "identical";
  s.mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int i = 0; i < count; ++i) s.mesh.triangles.push_back({0u, 1u, 2u});
  return s;
}

Scene zero_area_triangles() {
  Scene s;
  s.spec = "zero-area";
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (std::uint32_t i = 0; i < 300; ++i) {
    const Vec3f a(u(rng), u(rng), u(rng)), d(u(rng), u(rng), u(rng));
    const auto base = static_cast<std::uint32_t>(s.mesh.vertices.size());
    if (i % 3 == 0) {
      s.mesh.vertices.insert(s.mesh.vertices.end(), {a, a, a});  // a point
    } else {
      s.mesh.vertices.insert(s.mesh.vertices.end(), {a, a + d, a + d * 2.0f});  // a segment
    }
    s.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return s;
}

Scene single_triangle() {
  Scene s;
  s.spec = "single";
  s.mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 1}};
  s.mesh.triangles.push_back({0u, 1u, 2u});
  return s;
}

Scene single_sphere() {
  Scene s;
  s.spec = "single-sphere";
  s.spheres.push_back({Vec3f(1, 2, 3), 0.5f});
  return s;
}

/// Rotated walls with spheres among them.
Scene walls_and_spheres() {
  Scene s = scene_from_spec("walls:n=20,angle=30");
  s.spec = "walls+spheres";
  std::mt19937 rng(3);
  const Bounds3f b = s.bounds();
  std::uniform_real_distribution<float> ux(b.lo.x, b.hi.x), uy(b.lo.y, b.hi.y), uz(b.lo.z, b.hi.z);
  for (int i = 0; i < 60; ++i) s.spheres.push_back({Vec3f(ux(rng), uy(rng), uz(rng)), 0.05f + 0.01f * float(i % 7)});
  return s;
}

void expect_equal_trees(const Bvh2& a, const Bvh2& b) {
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  ASSERT_EQ(a.prims, b.prims);
  EXPECT_EQ(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(Bvh2Node)), 0);
}

TEST(BvhBuild, EveryBuilderGivesAValidTreeOnScenes) {
  for (const std::string spec : {"walls:n=40,angle=30", "walls:n=30,angle=0", "soup:n=3000", "sphereflake:depth=2",
                                 "grass:blades=1500"}) {
    const Scene scene = scene_from_spec(spec);
    for (BvhBuilder b : kAllBuilders) expect_valid(scene, build_bvh(scene, config_for(b)), b);
  }
}

TEST(BvhBuild, EveryBuilderHandlesDegenerateInputs) {
  for (const Scene& scene : {identical_triangles(200), zero_area_triangles(), single_triangle(), single_sphere(),
                             walls_and_spheres()})
    for (BvhBuilder b : kAllBuilders) {
      BvhConfig c = config_for(b);
      expect_valid(scene, build_bvh(scene, c), b);
      c.max_leaf_size = 1;
      expect_valid(scene, build_bvh(scene, c), b);
    }
}

TEST(BvhBuild, DepthContractHoldsOnExponentiallySpacedBoxes) {
  // Boxes at 2^-i along x: midpoint and SAH splits peel one box per level without the fallback.
  std::vector<Bounds3f> boxes;
  for (int i = 0; i < 120; ++i) {
    const float x = std::ldexp(1.0f, -i);
    boxes.emplace_back(Vec3f(x, 0, 0), Vec3f(x * 1.5f, 1, 1));
  }
  for (BvhBuilder b : {BvhBuilder::midpoint, BvhBuilder::median, BvhBuilder::sweep, BvhBuilder::binned}) {
    BvhConfig c = config_for(b);
    c.max_leaf_size = 1;
    const Bvh2 bvh = build_bvh_over_boxes(boxes, c);
    EXPECT_LE(bvh_depth(bvh), kBvhMaxDepth) << builder_name(b);
    EXPECT_EQ(bvh.prims.size(), boxes.size());
    // Reinsertion favours chains on such boxes; its result keeps the contract too.
    c.optimize = BvhOptimize::reinsert;
    const Bvh2 optimized = build_bvh_over_boxes(boxes, c);
    EXPECT_LE(bvh_depth(optimized), kBvhMaxDepth) << builder_name(b);
    EXPECT_EQ(optimized.prims.size(), boxes.size());
    EXPECT_LE(bvh_sah_cost(optimized, c.cost), bvh_sah_cost(bvh, c.cost));
  }
}

TEST(BvhBuild, BoxesBuilderAcceptsEmptyBoxesAndNoBoxes) {
  std::vector<Bounds3f> boxes = {Bounds3f(), Bounds3f(Vec3f(1, 1, 1), Vec3f(2, 2, 2)), Bounds3f(),
                                 Bounds3f(Vec3f(-3, 0, 0), Vec3f(-2, 1, 1))};
  for (BvhBuilder b : kAllBuilders) {
    const Bvh2 bvh = build_bvh_over_boxes(boxes, config_for(b));
    std::vector<std::uint32_t> prims = bvh.prims;
    std::sort(prims.begin(), prims.end());
    EXPECT_EQ(prims, (std::vector<std::uint32_t>{0, 1, 2, 3})) << builder_name(b);
    EXPECT_TRUE(build_bvh_over_boxes({}, config_for(b)).nodes.empty());
  }
}

TEST(BvhBuild, SpatialSplitsRespectTheDuplicationBound) {
  const Scene scene = scene_from_spec("walls:n=100,angle=30");
  const double n = double(scene.primitive_count());
  for (double d : {0.0, 0.05, 0.3, 1.0, 3.0}) {
    BvhConfig c = config_for(BvhBuilder::spatial);
    c.max_duplication = d;
    const Bvh2 bvh = build_bvh(scene, c);
    EXPECT_LE(double(bvh.prims.size()), std::floor((1.0 + d) * n)) << "max_duplication " << d;
    if (d == 0.0) {
      EXPECT_EQ(bvh.prims.size(), scene.primitive_count());
    }
    if (d == 1.0) {
      expect_valid(scene, bvh, BvhBuilder::spatial);
    }
  }
}

TEST(BvhBuild, SpatialSplitsLowerSahCostOnRotatedWalls) {
  const Scene scene = scene_from_spec("walls:n=100,angle=30");
  const BvhSahCost cost;
  const double binned = bvh_sah_cost(build_bvh(scene, config_for(BvhBuilder::binned)), cost);
  const Bvh2 sbvh = build_bvh(scene, config_for(BvhBuilder::spatial));
  const double spatial = bvh_sah_cost(sbvh, cost);
  EXPECT_LT(spatial, 0.9 * binned) << "binned " << binned << ", spatial " << spatial;
  EXPECT_GT(sbvh.prims.size(), scene.primitive_count());  // some references were split
}

TEST(BvhBuild, SweepSahCostIsAtMostMidpointOnClusteredBoxes) {
  // Tight clusters of small boxes scattered over a large extent, plus a few large boxes.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> centre(-100.0f, 100.0f), offset(-1.0f, 1.0f), size(0.01f, 0.2f);
  std::vector<Bounds3f> boxes;
  for (int c = 0; c < 12; ++c) {
    const Vec3f o(centre(rng), centre(rng), centre(rng));
    for (int i = 0; i < 250; ++i) {
      const Vec3f p = o + Vec3f(offset(rng), offset(rng), offset(rng)) * (c % 3 == 0 ? 0.1f : 1.0f);
      boxes.emplace_back(p, p + Vec3f(size(rng), size(rng), size(rng)));
    }
  }
  for (int i = 0; i < 20; ++i) {
    const Vec3f p(centre(rng), centre(rng), centre(rng));
    boxes.emplace_back(p, p + Vec3f(5.0f));
  }
  const BvhSahCost cost;
  const double midpoint = bvh_sah_cost(build_bvh_over_boxes(boxes, config_for(BvhBuilder::midpoint)), cost);
  const double sweep = bvh_sah_cost(build_bvh_over_boxes(boxes, config_for(BvhBuilder::sweep)), cost);
  const double binned = bvh_sah_cost(build_bvh_over_boxes(boxes, config_for(BvhBuilder::binned)), cost);
  EXPECT_LE(sweep, midpoint);
  EXPECT_LE(binned, midpoint);
  EXPECT_LE(sweep, binned * 1.02);  // the full sweep sees every candidate the bins see, up to leaf choices
}

TEST(BvhBuild, BuildsAreDeterministicAcrossThreadCountsAndRuns) {
  // Large enough for parallel tasks (>= 4096 references) and parallel binning (>= 65536).
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 100.0f), s(0.0f, 0.5f);
  std::vector<Bounds3f> boxes(150000);
  for (auto& b : boxes) {
    const Vec3f p(u(rng), u(rng), u(rng) * 0.1f);
    b = Bounds3f(p, p + Vec3f(s(rng), s(rng), s(rng)));
  }
  const Bvh2 one = build_bvh_over_boxes(boxes, config_for(BvhBuilder::binned, 1));
  expect_equal_trees(one, build_bvh_over_boxes(boxes, config_for(BvhBuilder::binned, 2)));
  expect_equal_trees(one, build_bvh_over_boxes(boxes, config_for(BvhBuilder::binned, 2)));
  expect_equal_trees(one, build_bvh_over_boxes(boxes, config_for(BvhBuilder::binned, 0)));

  const Scene walls = scene_from_spec("walls:n=800,angle=30");
  for (BvhBuilder b : {BvhBuilder::binned, BvhBuilder::spatial, BvhBuilder::sweep}) {
    const Bvh2 first = build_bvh(walls, config_for(b, 1));
    expect_equal_trees(first, build_bvh(walls, config_for(b, 2)));
    expect_equal_trees(first, build_bvh(walls, config_for(b, 2)));
  }
}

TEST(BvhBuild, SahCountsLeavesInWholeBlocks) {
  EXPECT_EQ(bvh_leaf_units(1, 4), 4u);
  EXPECT_EQ(bvh_leaf_units(4, 4), 4u);
  EXPECT_EQ(bvh_leaf_units(5, 4), 8u);
  EXPECT_EQ(bvh_leaf_units(8, 4), 8u);
  EXPECT_EQ(bvh_leaf_units(0, 4), 0u);
  EXPECT_EQ(bvh_leaf_units(7, 1), 7u);
  // Two pairs of unit boxes 10 apart (half areas: node 23, each pair 3), c_trav = 3. Counting
  // primitives, the split costs 3 + (2·3 + 2·3)/23 = 3.52 < 4, the leaf's cost; counting blocks
  // of 4, it costs 3 + (4·3 + 4·3)/23 = 4.04 > 4: one leaf.
  const Bounds3f near_box(Vec3f(0.0f), Vec3f(1.0f)), far_box(Vec3f(10.0f, 0.0f, 0.0f), Vec3f(11.0f, 1.0f, 1.0f));
  const std::vector<Bounds3f> boxes = {near_box, far_box, near_box, far_box};
  for (BvhBuilder b : {BvhBuilder::binned, BvhBuilder::sweep}) {
    BvhConfig by_prims = config_for(b);
    by_prims.max_leaf_size = 8;
    by_prims.cost.c_trav = 3.0;
    BvhConfig by_blocks = by_prims;
    by_blocks.cost.leaf_block = 4;
    EXPECT_EQ(build_bvh_over_boxes(boxes, by_prims).nodes.size(), 3u);
    const Bvh2 leaf = build_bvh_over_boxes(boxes, by_blocks);
    ASSERT_EQ(leaf.nodes.size(), 1u);
    EXPECT_EQ(leaf.nodes[0].count, 4u);
    EXPECT_DOUBLE_EQ(bvh_sah_cost(leaf, by_blocks.cost), 4.0);
  }
}

/// Each leaf's references, sorted, in a sorted list: equal for trees with the same leaves.
std::vector<std::vector<std::uint32_t>> leaf_contents(const Bvh2& bvh) {
  std::vector<std::vector<std::uint32_t>> leaves;
  for (const Bvh2Node& n : bvh.nodes) {
    if (!n.is_leaf()) continue;
    leaves.emplace_back(bvh.prims.begin() + n.first, bvh.prims.begin() + n.first + n.count);
    std::sort(leaves.back().begin(), leaves.back().end());
  }
  std::sort(leaves.begin(), leaves.end());
  return leaves;
}

TEST(BvhOptimize, ReinsertionKeepsLeavesAndContainmentAndNeverRaisesTheSahCost) {
  BvhSahCost wide_cost;  // the constants and leaf blocks bvh.cpp gives 8-wide trees
  wide_cost.c_trav = 3.0;
  wide_cost.leaf_block = 4;
  for (const std::string spec : {"walls:n=40,angle=30", "soup:n=3000", "sphereflake:depth=2", "grass:blades=1500"}) {
    const Scene scene = scene_from_spec(spec);
    for (BvhBuilder b : {BvhBuilder::midpoint, BvhBuilder::binned, BvhBuilder::spatial}) {
      for (const BvhSahCost& cost : {BvhSahCost{}, wide_cost}) {
        SCOPED_TRACE(builder_name(b) + " on " + spec + ", c_trav " + std::to_string(cost.c_trav));
        BvhConfig config = config_for(b);
        config.cost = cost;
        const Bvh2 plain = build_bvh(scene, config);
        Bvh2 tree = plain;
        const BvhOptimizeStats stats = optimize_bvh_reinsertion(tree, cost);
        expect_valid(scene, tree, b);
        EXPECT_EQ(tree.nodes.size(), plain.nodes.size());
        EXPECT_EQ(leaf_contents(tree), leaf_contents(plain));
        EXPECT_DOUBLE_EQ(stats.cost_before, bvh_sah_cost(plain, cost));
        EXPECT_DOUBLE_EQ(stats.cost_after, bvh_sah_cost(tree, cost));
        EXPECT_LE(stats.cost_after, stats.cost_before);
        EXPECT_GT(stats.passes, 0);
        // Interior boxes are tight: the union of their children's.
        for (const Bvh2Node& n : tree.nodes) {
          if (n.is_leaf()) continue;
          Bounds3f u = tree.nodes[n.first].box;
          u.extend(tree.nodes[n.first + 1].box);
          ASSERT_TRUE(u.lo == n.box.lo && u.hi == n.box.hi) << "a loose interior box";
        }
        // Every one of these trees has room that reinsertion must find (measured: 0.7% to 23% lower).
        EXPECT_LT(stats.cost_after, 0.995 * stats.cost_before);
        // The build entry point applies it as configured, deterministically.
        config.optimize = BvhOptimize::reinsert;
        expect_equal_trees(tree, build_bvh(scene, config));
      }
    }
  }
}

TEST(BvhOptimize, ReinsertionIsTheSameWithAnyThreadCount) {
  // 150k boxes: ~75k interior nodes, more than the parallel set-up's and ranking's 2^14 blocks.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 100.0f), s(0.0f, 2.0f);
  std::vector<Bounds3f> boxes(150000);
  for (auto& b : boxes) {
    const Vec3f p(u(rng), u(rng), u(rng));
    b = Bounds3f(p, p + Vec3f(s(rng), s(rng), s(rng)));
  }
  const BvhConfig config = config_for(BvhBuilder::binned, 1);
  const Bvh2 plain = build_bvh_over_boxes(boxes, config);
  Bvh2 one = plain;
  const BvhOptimizeStats serial = optimize_bvh_reinsertion(one, config.cost, 3, 0.0, 1);
  EXPECT_LT(serial.cost_after, serial.cost_before);
  for (int threads : {2, 0}) {
    Bvh2 many = plain;
    const BvhOptimizeStats parallel = optimize_bvh_reinsertion(many, config.cost, 3, 0.0, threads);
    EXPECT_EQ(parallel.moves, serial.moves) << threads << " threads";
    expect_equal_trees(one, many);
  }
}

TEST(BvhOptimize, PassLimitAndTinyTrees) {
  const Scene scene = scene_from_spec("soup:n=3000");
  BvhConfig config = config_for(BvhBuilder::midpoint);
  Bvh2 one = build_bvh(scene, config), many = one;
  const BvhOptimizeStats after_one = optimize_bvh_reinsertion(one, config.cost, 1);
  const BvhOptimizeStats after_many = optimize_bvh_reinsertion(many, config.cost);
  EXPECT_EQ(after_one.passes, 1);
  EXPECT_GT(after_many.passes, 1);
  EXPECT_LE(after_many.cost_after, after_one.cost_after);
  for (const Scene& tiny : {single_triangle(), identical_triangles(3), identical_triangles(40), zero_area_triangles()}) {
    config.optimize = BvhOptimize::reinsert;
    config.max_leaf_size = 1;
    expect_valid(tiny, build_bvh(tiny, config), BvhBuilder::midpoint);
  }
  Bvh2 empty = build_bvh_over_boxes({}, config);
  EXPECT_TRUE(empty.nodes.empty());
}

}  // namespace
}  // namespace raylab
