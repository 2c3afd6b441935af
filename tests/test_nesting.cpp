// Aggregates are primitives (the lecture's pbrt design): accelerators of different types nest
// under transforms, and the nested structure answers like the exact oracle on the flattened
// geometry.
#include <gtest/gtest.h>

#include "accel/brute/brute_force.h"
#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "scene/scene_spec.h"
#include "scene/transformed_primitive.h"

namespace raylab {
namespace {

TEST(Nesting, AcceleratorsOfDifferentTypesNestUnderTransforms) {
  const auto sphere = make_scene("sphere:n=600");
  const auto soup = make_scene("soup:n=400");
  struct Child {
    std::shared_ptr<const Scene> scene;
    std::string accel;
    AffineTransform xf;
  };
  const std::vector<Child> children = {
      {sphere, "embree-robust", AffineTransform::translation({-2.5, 0, 0})},
      {soup, "brute", AffineTransform::translation({0, 0.2, 0}) * AffineTransform::rotation({0, 1, 0}, 0.7) *
                          AffineTransform::scaling({2, 2, 2})},
      {sphere, "exact", AffineTransform::translation({2.5, 0.5, 0}) * AffineTransform::rotation({1, 0, 0}, 0.3)},
  };
  std::vector<std::shared_ptr<const Primitive>> prims;
  auto flat = std::make_shared<Scene>();
  flat->spec = "flattened children";
  std::vector<unsigned> offset;
  for (std::size_t i = 0; i < children.size(); ++i) {
    const Child& c = children[i];
    prims.push_back(std::make_shared<TransformedPrimitive>(std::shared_ptr<const Primitive>(make_accelerator(c.accel, c.scene)),
                                                           c.xf, static_cast<unsigned>(i)));
    offset.push_back(static_cast<unsigned>(flat->mesh.size()));
    TriangleMesh placed = c.scene->mesh;
    for (auto& v : placed.vertices) v = c.xf.apply_point(v);
    flat->mesh.append(placed);
  }
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
