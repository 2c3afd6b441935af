#include <gtest/gtest.h>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/tracer.h"
#include "accel/octree/octree.h"
#include "geometry/exact_predicates.h"
#include "scene/ray_counters.h"
#include <random>
#include "scene/scene_spec.h"

namespace raylab {
namespace {

OctreeConfig octree_config(const std::string& params) {
  SpecReader r(parse_spec("octree" + (params.empty() ? "" : ":" + params)));
  return read_octree_config(r);
}

TEST(Octree, ExactClippingLosesNoTriangle) {
  for (const std::string spec : {"soup:n=600", "walls:n=6,angle=30", "grass:blades=100"}) {
    const auto scene = make_scene(spec);
    const Octree tree(scene, octree_config("c_trav=8"));  // a deep tree: many clipped leaves
    std::size_t leaves = 0;
    for_each_octree_leaf(tree.data(), [&](const Bounds3f& box, std::uint32_t first, std::uint32_t count) {
      ++leaves;
      std::vector<bool> listed(scene->mesh.size(), false);
      for (std::uint32_t i = 0; i < count; ++i)
        if (tree.data().prims[first + i] < scene->mesh.size()) listed[tree.data().prims[first + i]] = true;
      for (std::uint32_t t = 0; t < scene->mesh.size(); ++t) {
        const auto& tri = scene->mesh.triangles[t];
        const auto& v = scene->mesh.vertices;
        const bool meets = exact_triangle_intersects_box(v[tri[0]], v[tri[1]], v[tri[2]], box);
        ASSERT_EQ(meets, static_cast<bool>(listed[t])) << spec << ": triangle " << t;
      }
    });
    EXPECT_GT(leaves, 8u) << spec;
  }
}

/// Rays along the octree's centre planes (axis-parallel, origins on the planes) and along cell
/// edges, against brute force.
TEST(Octree, RaysAlongCentrePlanesAgreeWithBruteForce) {
  for (const std::string spec : {"soup:n=800", "walls:n=6,angle=30"}) {
    const auto scene = make_scene(spec);
    const Octree probe(scene, octree_config(""));
    const Bounds3f b = probe.data().bounds;
    std::vector<Ray> rays;
    for (int level = 1; level <= 3; ++level) {
      const int cells = 1 << level;
      for (int i = 0; i <= cells; ++i)
        for (int j = 0; j <= cells; ++j)
          for (int a = 0; a < 3; ++a) {
            const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
            Vec3f o;
            o[a] = b.lo[a] - 1.0f;
            o[a1] = b.lo[a1] + (b.hi[a1] - b.lo[a1]) * float(i) / float(cells);
            o[a2] = b.lo[a2] + (b.hi[a2] - b.lo[a2]) * float(j) / float(cells);
            Vec3f d(0.0f);
            d[a] = 1.0f;
            rays.push_back({o, d});  // along a cell edge
            o[a2] = b.lo[a2] + (b.hi[a2] - b.lo[a2]) * (float(j) + 0.37f) / float(cells);
            rays.push_back({o, d});  // along a cell face
            Vec3f d2(0.0f);
            d2[a] = 0.8f;
            d2[a2] = 0.6f;
            rays.push_back({o, d2});  // in a face plane, oblique
          }
    }
    const auto brute = make_accelerator("brute", scene);
    const double diag = length(Vec3d(scene->bounds().diagonal()));
    // Deep trees (c_trav=8), so that the rays run along the planes of many nodes.
    for (const std::string accel_spec :
         {"octree:c_trav=8", "octree:c_trav=8,clip=none", "octree:c_trav=8,clip=bbox,mailbox=on",
          "octree:c_trav=8,traversal=kd", "octree:c_trav=8,traversal=revelles"}) {
      const auto accel = make_accelerator(accel_spec, scene);
      const auto ref = trace_rays(*brute, rays, TraceOptions{1, false, false});
      const auto got = trace_rays(*accel, rays, TraceOptions{1, false, false});
      EXPECT_GT(ref.hit_count, 0u);
      EXPECT_EQ(compare_hits(rays, got.hits, ref.hits, diag).mismatches, 0u) << accel_spec << " on " << spec;
      const auto ref_o = trace_rays(*brute, rays, TraceOptions{1, false, true});
      const auto got_o = trace_rays(*accel, rays, TraceOptions{1, false, true});
      EXPECT_EQ(compare_occlusion(got_o.blocked, ref_o.blocked).mismatches, 0u) << accel_spec << " on " << spec;
    }
  }
}

/// The parametric walk (Revelles et al.) visits leaves front to back, and visits every leaf
/// whose box the ray crosses over an interval of positive length (computed in double).
TEST(Octree, RevellesVisitsLeavesFrontToBackAndMissesNone) {
  const auto scene = make_scene("soup:n=1500");
  const Octree tree(scene, octree_config("c_trav=8"));  // a deep tree: many leaves
  const Bounds3f root = tree.data().bounds;
  std::vector<std::pair<Bounds3f, std::uint32_t>> leaves;  // box, node index: the stored (non-empty) leaves
  {
    std::vector<std::pair<std::uint32_t, Bounds3f>> todo = {{0, root}};
    while (!todo.empty()) {
      const auto [n, box] = todo.back();
      todo.pop_back();
      const OctNode& node = tree.data().nodes[n];
      if (node.is_leaf()) leaves.push_back({box, n});
      else
        for (unsigned i = 0; i < 8; ++i)
          if (node.has_child(i)) todo.push_back({node.child(i), octree_child_box(box, i)});
    }
  }
  ASSERT_GT(leaves.size(), 64u);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const Vec3f ext = root.diagonal();
  NoCounters counters;
  for (int r = 0; r < 3000; ++r) {
    Vec3f o, d;
    for (int a = 0; a < 3; ++a) {
      o[a] = root.lo[a] + ext[a] * (1.6f * u(rng) - 0.3f);
      d[a] = 2.0f * u(rng) - 1.0f;
    }
    if (r % 5 == 0) d[r % 3] = (r % 2) ? 0.0f : -0.0f;  // a zero component of either sign
    const Ray ray{o, d};
    std::vector<std::uint32_t> order;
    std::vector<float> enter;
    octree_walk_revelles(
        tree.data().nodes.data(), root, ray,
        [&](std::uint32_t index, const Bounds3f&, float t_enter, float) {
          order.push_back(index);
          enter.push_back(t_enter);
          return false;
        },
        [] { return std::numeric_limits<float>::infinity(); }, counters);
    for (std::size_t i = 1; i < enter.size(); ++i)
      EXPECT_GE(enter[i], enter[i - 1] - 1e-5f * (1.0f + std::abs(enter[i - 1]))) << "ray " << r << ", leaf " << i;
    std::vector<std::uint32_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << "ray " << r << " visits a leaf twice";
    for (const auto& [box, index] : leaves) {
      double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) {
          if (o[a] < box.lo[a] || o[a] > box.hi[a]) t0 = t1 + 1.0;
          continue;
        }
        double ta = (double(box.lo[a]) - o[a]) / d[a], tb = (double(box.hi[a]) - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (t1 - t0 > 1e-9 * (1.0 + std::abs(t1))) {
        EXPECT_TRUE(std::binary_search(sorted.begin(), sorted.end(), index)) << "ray " << r << " skips leaf " << index;
      }
    }
  }
}

/// Axis-parallel rays with +0 and -0 components through the centres of the nodes (they lie in
/// two centre planes of every ancestor at once), and diagonal rays through node centres
/// (through the corners of eight children), against the exact oracle.
TEST(Octree, RevellesRaysThroughNodeCentresAgreeWithExactOracle) {
  for (const std::string spec : {"soup:n=800", "walls:n=6,angle=30", "grass:blades=150"}) {
    const auto scene = make_scene(spec);
    const Octree probe(scene, octree_config("c_trav=8"));  // a deep tree: many node centres
    std::vector<Ray> rays;
    std::vector<std::pair<std::uint32_t, Bounds3f>> todo = {{0, probe.data().bounds}};
    while (!todo.empty() && rays.size() < 6000) {
      const auto [n, box] = todo.back();
      todo.pop_back();
      const Vec3f c(octree_mid(box, 0), octree_mid(box, 1), octree_mid(box, 2));
      for (int a = 0; a < 3; ++a)
        for (const float s : {1.0f, -1.0f}) {
          Vec3f d(s > 0 ? 0.0f : -0.0f);
          d[a] = s;
          Vec3f o = c;
          o[a] = s > 0 ? probe.data().bounds.lo[a] - 1.0f : probe.data().bounds.hi[a] + 1.0f;
          rays.push_back({o, d});
          Vec3f dn(s > 0 ? -0.0f : 0.0f);  // the other sign of zero
          dn[a] = s;
          rays.push_back({o, dn});
        }
      for (unsigned k = 0; k < 8; ++k) {
        const Vec3f d((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f, (k & 4) ? 1.0f : -1.0f);
        rays.push_back({c - d * 2.0f * length(probe.data().bounds.diagonal()), d});
      }
      const OctNode& node = probe.data().nodes[n];
      if (!node.is_leaf())
        for (unsigned i = 0; i < 8; ++i)
          if (node.has_child(i)) todo.push_back({node.child(i), octree_child_box(box, i)});
    }
    const auto oracle = make_accelerator("exact", scene);
    const double diag = length(Vec3d(scene->bounds().diagonal()));
    const auto ref = trace_rays(*oracle, rays, TraceOptions{1, false, false});
    const auto ref_o = trace_rays(*oracle, rays, TraceOptions{1, false, true});
    EXPECT_GT(ref.hit_count, 0u);
    for (const std::string accel_spec :
         {"octree:c_trav=8", "octree:c_trav=8,clip=none,mailbox=on", "octree:c_trav=8,traversal=kd",
          "octree:c_trav=8,traversal=revelles"}) {
      const auto accel = make_accelerator(accel_spec, scene);
      const auto got = trace_rays(*accel, rays, TraceOptions{1, false, false});
      EXPECT_EQ(compare_hits(rays, got.hits, ref.hits, diag).mismatches, 0u) << accel_spec << " on " << spec;
      const auto got_o = trace_rays(*accel, rays, TraceOptions{1, false, true});
      EXPECT_EQ(compare_occlusion(got_o.blocked, ref_o.blocked).mismatches, 0u) << accel_spec << " on " << spec;
    }
  }
}

/// A flat scene's nodes split along their long axes only (octree_split_axes): the root of a
/// lawn is not split along its thin axis, no node stores a child that its box does not have,
/// and the deep nodes, whose boxes have become near cubes, split eight ways.
TEST(Octree, FlatNodesSplitAlongTheirLongAxesOnly) {
  const auto scene = make_scene("grass:blades=400");
  const Octree tree(scene, octree_config("c_trav=2"));
  const Bounds3f root = tree.data().bounds;
  const Vec3f ext = root.diagonal();
  int thin = 0;
  for (int a = 1; a < 3; ++a)
    if (ext[a] < ext[thin]) thin = a;
  ASSERT_LT(ext[thin], 0.25f * max_component(ext)) << "the lawn is not flat";
  EXPECT_EQ(octree_split_axes(root) & (1u << thin), 0u);
  bool eight_way = false;
  std::vector<std::pair<std::uint32_t, Bounds3f>> todo = {{0, root}};
  while (!todo.empty()) {
    const auto [n, box] = todo.back();
    todo.pop_back();
    const OctNode& node = tree.data().nodes[n];
    if (node.is_leaf()) continue;
    eight_way = eight_way || octree_split_axes(box) == 7u;
    for (unsigned i = 0; i < 8; ++i) {
      EXPECT_TRUE(!node.has_child(i) || octree_child_exists(box, i));
      if (node.has_child(i)) todo.push_back({node.child(i), octree_child_box(box, i)});
    }
  }
  EXPECT_TRUE(eight_way);
}

TEST(Octree, CostTerminationAndDepthLimit) {
  const auto scene = make_scene("soup:n=2000");
  const Octree shallow(scene, octree_config("max_depth=2"));
  EXPECT_LE(shallow.data().depth, 2);
  const Octree cheap(scene, octree_config("c_isect=80"));
  const Octree dear(scene, octree_config("c_isect=1.5,c_trav=4"));
  EXPECT_GE(cheap.stats().nodes, dear.stats().nodes);
  EXPECT_EQ(Octree(scene, octree_config("")).structure_hash(), Octree(scene, octree_config("")).structure_hash());
}

}  // namespace
}  // namespace raylab
