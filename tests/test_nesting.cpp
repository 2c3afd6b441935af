// Aggregates are primitives (the lecture's pbrt design): accelerators of different types nest
// under transforms, and the nested structure answers like the exact oracle on the flattened
// geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>

#include "accel/brute/brute_force.h"
#include "accel/bvh/primitive_bvh.h"
#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "scene/scene_spec.h"
#include "scene/transformed_primitive.h"

namespace raylab {
namespace {

/// One accelerator of type `accel` on `scene`, placed in the world by `xf`.
struct Child {
  std::shared_ptr<const Scene> scene;
  std::string accel;
  AffineTransform xf;
};

/// The children as TransformedPrimitives (instance i = child i), and the same geometry
/// flattened into one scene for the exact oracle: child i's triangle k is flat triangle
/// offset[i] + k.
struct PlacedChildren {
  std::vector<std::shared_ptr<const Primitive>> prims;
  std::shared_ptr<Scene> flat;
  std::vector<unsigned> offset;
};

PlacedChildren place_children(const std::vector<Child>& children) {
  PlacedChildren out;
  out.flat = std::make_shared<Scene>();
  out.flat->spec = "flattened children";
  for (std::size_t i = 0; i < children.size(); ++i) {
    const Child& c = children[i];
    out.prims.push_back(std::make_shared<TransformedPrimitive>(
        std::shared_ptr<const Primitive>(make_accelerator(c.accel, c.scene)), c.xf, static_cast<unsigned>(i)));
    out.offset.push_back(static_cast<unsigned>(out.flat->mesh.size()));
    TriangleMesh placed = c.scene->mesh;
    for (auto& v : placed.vertices) v = c.xf.apply_point(v);
    out.flat->mesh.append(placed);
  }
  return out;
}

TEST(Nesting, AcceleratorsOfDifferentTypesNestUnderTransforms) {
  const auto sphere = make_scene("sphere:n=600");
  const auto soup = make_scene("soup:n=400");
  const std::vector<Child> children = {
      {sphere, "embree-robust", AffineTransform::translation({-2.5, 0, 0})},
      {soup, "brute", AffineTransform::translation({0, 0.2, 0}) * AffineTransform::rotation({0, 1, 0}, 0.7) *
                          AffineTransform::scaling({2, 2, 2})},
      {sphere, "exact", AffineTransform::translation({2.5, 0.5, 0}) * AffineTransform::rotation({1, 0, 0}, 0.3)},
  };
  const PlacedChildren placed = place_children(children);
  const auto& prims = placed.prims;
  const auto& flat = placed.flat;
  const auto& offset = placed.offset;
  const BruteForceOverPrimitives top(prims);
  const auto oracle = make_accelerator("exact", flat);
  const double diagonal = length(Vec3d(flat->bounds().diagonal()));

  for (const std::string spec : {"primary:4096", "lines:4096"}) {
    const auto rays = make_ray_set(spec, flat);
    const TraceResult ref = trace_rays(*oracle, rays, TraceOptions{});
    TraceResult got = trace_rays(top, rays, TraceOptions{});
    std::size_t per_child[3] = {0, 0, 0};
    for (Hit& h : got.hits) {
      if (!h.valid()) continue;
      ASSERT_LT(h.instance, children.size());
      ++per_child[h.instance];
      h.prim += offset[h.instance];  // to the flat scene's ids
      h.instance = kInvalidId;
    }
    const HitComparison c = compare_hits(rays, got.hits, ref.hits, diagonal);
    // Transforming rays instead of vertices rounds differently; a ray within rounding of an edge
    // may flip. That is rare on these ray kinds.
    EXPECT_LE(c.mismatches, rays.size() / 1000) << spec << ": " << c.false_hits << " false, " << c.missed_hits
                                                << " missed, " << c.wrong_t << " wrong t";
    EXPECT_GT(ref.hit_count, rays.size() / 20) << spec;
    for (int i = 0; i < 3; ++i) EXPECT_GT(per_child[i], 0u) << spec << ": child " << i << " (" << children[i].accel << ") was never hit";
  }
}

/// x' = scale[i]·x[axis[i]]: a signed axis permutation with power-of-two scales. Such a transform
/// and its inverse map floats to floats exactly, so the flattened copy below is the very
/// geometry each instance sees and the comparison with the oracle needs no rounding allowance.
AffineTransform exact_transform(const std::array<int, 3>& axis, const Vec3d& scale) {
  AffineTransform xf;
  xf.m = {{{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}}};
  for (int i = 0; i < 3; ++i) xf.m[i][axis[i]] = scale[i];
  return xf;
}

TEST(Nesting, BvhTopLevelOverBvhKdtreeGridAndEmbreeAgreesWithExactOracle) {
  // Object-space extents: sphere [-1,1]^3, soups [0,1]^3, grass [0,1]x[0,0.05]x[0,1]. World boxes:
  // sphere [-1,1]^3; soup A [-2,0]x[0,2]x[0,2]; soup B [0,2]x[-2,0]x[-2,0]; grass
  // [-4,0]x[0,0.4]x[0,4]. Each soup and the grass overlap the sphere, and soup A the grass.
  const std::vector<Child> children = {
      {make_scene("sphere:n=800"), "bvh", exact_transform({2, 0, 1}, {1, 1, 1})},
      {make_scene("soup:n=400"), "kdtree", exact_transform({0, 1, 2}, {-2, 2, 2})},
      {make_scene("soup:n=400,seed=2"), "grid", exact_transform({1, 2, 0}, {2, -2, -2})},
      {make_scene("grass:blades=3000"), "embree", exact_transform({0, 1, 2}, {-4, 8, 4})},
  };
  const PlacedChildren placed = place_children(children);
  const auto& prims = placed.prims;
  const auto& flat = placed.flat;
  const auto& offset = placed.offset;
  std::size_t overlapping_pairs = 0;
  for (std::size_t i = 0; i < prims.size(); ++i)
    for (std::size_t j = i + 1; j < prims.size(); ++j) {
      Bounds3f both = prims[i]->bounds();
      bool overlap = true;
      for (int a = 0; a < 3; ++a) overlap &= std::max(both.lo[a], prims[j]->bounds().lo[a]) < std::min(both.hi[a], prims[j]->bounds().hi[a]);
      overlapping_pairs += overlap;
    }
  ASSERT_GE(overlapping_pairs, 3u);

  const PrimitiveBvh top(prims);
  ASSERT_EQ(top.size(), children.size());
  EXPECT_GT(top.stats().nodes, 0u);
  const auto oracle = make_accelerator("exact", flat);
  const double diagonal = length(Vec3d(flat->bounds().diagonal()));

  for (const std::string spec : {"primary:4096", "lines:4096"}) {
    const auto rays = make_ray_set(spec, flat);
    const TraceResult ref = trace_rays(*oracle, rays, TraceOptions{});
    TraceResult got = trace_rays(top, rays, TraceOptions{});
    std::vector<std::size_t> per_child(children.size(), 0);
    for (Hit& h : got.hits) {
      if (!h.valid()) continue;
      ASSERT_LT(h.instance, children.size());
      ++per_child[h.instance];
      h.prim += offset[h.instance];  // to the flat scene's ids
      h.instance = kInvalidId;
    }
    const HitComparison c = compare_hits(rays, got.hits, ref.hits, diagonal);
    EXPECT_EQ(c.mismatches, 0u) << spec << ": " << c.false_hits << " false, " << c.missed_hits << " missed, "
                                << c.wrong_t << " wrong t";
    EXPECT_GT(ref.hit_count, rays.size() / 20) << spec;
    for (std::size_t i = 0; i < children.size(); ++i)
      EXPECT_GT(per_child[i], 0u) << spec << ": child " << i << " (" << children[i].accel << ") was never hit";

    // The counted path must give the same hits.
    TraceOptions counted;
    counted.counters = true;
    const TraceResult got_counted = trace_rays(top, rays, counted);
    EXPECT_EQ(got_counted.hit_count, got.hit_count) << spec;
    EXPECT_GT(got_counted.counters.nodes, 0u) << spec;
    EXPECT_GT(got_counted.counters.prim_tests, 0u) << spec << ": inner primitives' counters were not passed through";
  }

  for (const std::string spec : {"shadow:4096", "ao:4096", "lines:4096"}) {
    const auto rays = make_ray_set(spec, flat);
    TraceOptions any_hit;
    any_hit.occlusion = true;
    const TraceResult ref = trace_rays(*oracle, rays, any_hit);
    const TraceResult got = trace_rays(top, rays, any_hit);
    const HitComparison c = compare_occlusion(got.blocked, ref.blocked);
    EXPECT_EQ(c.mismatches, 0u) << spec;
    EXPECT_GT(ref.hit_count, 0u) << spec;
    EXPECT_LT(ref.hit_count, rays.size()) << spec;
  }
}

TEST(Nesting, PrimitiveBvhFindsTheClosestOfOverlappingInstances) {
  // Eight copies of one sphere on a line, each overlapping the next; a ray along the line from
  // either end must hit the nearest copy whatever order the tree visits them in.
  const auto sphere = make_scene("sphere:n=200");
  const std::shared_ptr<const Primitive> inner = make_accelerator("bvh", sphere);
  std::vector<std::shared_ptr<const Primitive>> prims;
  for (unsigned i = 0; i < 8; ++i)
    prims.push_back(std::make_shared<TransformedPrimitive>(inner, AffineTransform::translation({1.0 * i, 0, 0}), i));
  const PrimitiveBvh top(prims);
  for (const float dir : {1.0f, -1.0f}) {
    Ray ray{{dir > 0 ? -10.0f : 17.0f, 0.01f, 0.02f}, {dir, 0, 0}};
    Hit hit;
    ASSERT_TRUE(top.intersect(ray, hit));
    EXPECT_EQ(hit.instance, dir > 0 ? 0u : 7u);
    EXPECT_NEAR(hit.t, 9.0, 5e-2);  // the tessellated equator lies within 1.3% inside the unit sphere
    EXPECT_EQ(ray.tmax, hit.t);
    EXPECT_TRUE(top.occluded(Ray{ray.org, ray.dir, 0.0f, 9.1f}));
    EXPECT_FALSE(top.occluded(Ray{ray.org, ray.dir, 0.0f, 8.9f}));
  }
  const PrimitiveBvh empty(std::vector<std::shared_ptr<const Primitive>>{});
  Ray ray{{0, 0, 0}, {1, 0, 0}};
  Hit hit;
  EXPECT_FALSE(empty.intersect(ray, hit));
  EXPECT_FALSE(empty.occluded(ray));
}

TEST(Nesting, TransformedPrimitivePreservesTAcrossSpaces) {
  const auto sphere = make_scene("sphere:n=200");
  const std::shared_ptr<const Primitive> inner = make_accelerator("brute", sphere);
  const TransformedPrimitive moved(inner, AffineTransform::translation({10, 0, 0}) * AffineTransform::scaling({3, 3, 3}), 7);
  Ray ray{{10, 0, 20}, {0, 0, -2}};  // unnormalised on purpose
  Hit hit;
  ASSERT_TRUE(moved.intersect(ray, hit));
  EXPECT_EQ(hit.instance, 7u);
  EXPECT_NEAR(hit.t, (20.0 - 3.0) / 2.0, 1e-2);  // the sphere's pole at z = 3, reached at t = 8.5
  EXPECT_EQ(ray.tmax, hit.t);
  EXPECT_TRUE(moved.occluded(Ray{{10, 0, 20}, {0, 0, -2}, 0.0f, 9.0f}));
  EXPECT_FALSE(moved.occluded(Ray{{10, 0, 20}, {0, 0, -2}, 0.0f, 8.0f}));
}

}  // namespace
}  // namespace raylab
