// Instanced scenes at the lecture's scale: 3.1 billion triangles held as one base mesh and
// 10,300 transforms, built and traced by `bvh` (a BVH on the base under a BVH over the
// instances), and checked against the exact oracle under a brute-force top level.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <set>

#include "accel/brute/brute_force.h"
#include "accel/bvh/primitive_bvh.h"
#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "geometry/input_error.h"
#include "scene/procedural.h"
#include "scene/scene_spec.h"
#include "scene/transformed_primitive.h"

namespace raylab {
namespace {

TEST(Instancing, LectureSceneOfThreeBillionTrianglesBuildsAndTracesLikeTheOracle) {
  const auto scene = make_scene(kLectureInstancedSceneSpec);
  ASSERT_TRUE(scene->instanced());
  ASSERT_EQ(scene->bases.size(), 1u);
  const Scene& base = *scene->bases[0];
  const SceneInfo info = describe(*scene);
  EXPECT_EQ(info.primitives, static_cast<double>(base.primitive_count()) * static_cast<double>(scene->instances.size()));
  EXPECT_EQ(info.primitives, scene->total_primitive_count());
  EXPECT_NEAR(info.primitives, 3.1e9, 0.05e9);
  EXPECT_EQ(info.instances, scene->instances.size());

  // The watertight kernel: instances as transformed BVHs under a top level. The certified default
  // answers through CertifiedInstances (test_certified_instances.cpp).
  const std::shared_ptr<const Aggregate> bvh = make_accelerator("bvh:kernel=watertight", scene);
  const auto* top = dynamic_cast<const PrimitiveBvh*>(bvh.get());
  ASSERT_NE(top, nullptr) << "an instanced scene must get a BVH top level";
  EXPECT_EQ(top->size(), scene->instances.size());
  EXPECT_GT(top->stats().nodes, scene->instances.size() / 2);

  const auto rays = make_ray_set("primary:4096", scene);
  const TraceResult got = trace_rays(*bvh, rays, TraceOptions{});
  const double diagonal = length(Vec3d(scene->bounds().diagonal()));

  // Every hit lies on the triangle it names, placed by the instance it names.
  std::set<unsigned> instances_hit;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Hit& h = got.hits[i];
    if (!h.valid()) continue;
    ASSERT_LT(h.instance, scene->instances.size()) << "ray " << i;
    ASSERT_LT(h.prim, base.mesh.size()) << "ray " << i;
    ASSERT_GE(h.t, rays[i].tmin) << "ray " << i;
    ASSERT_LE(h.t, rays[i].tmax) << "ray " << i;
    instances_hit.insert(h.instance);
    const Vec3d p0(base.mesh.vertex(h.prim, 0)), p1(base.mesh.vertex(h.prim, 1)), p2(base.mesh.vertex(h.prim, 2));
    const Vec3d on_triangle = scene->instances[h.instance].transform.apply_point(p0 * (1.0 - h.u - h.v) + p1 * double(h.u) + p2 * double(h.v));
    const Vec3d on_ray = Vec3d(rays[i].org) + Vec3d(rays[i].dir) * double(h.t);
    EXPECT_LE(length(on_ray - on_triangle), 1e-5 * (length(Vec3d(rays[i].org)) + diagonal)) << "ray " << i;
  }
  EXPECT_GT(got.hit_count, rays.size() / 4);
  EXPECT_GT(instances_hit.size(), 100u);

  // Any-hit queries on the same rays agree with the closest hits.
  TraceOptions any_hit;
  any_hit.occlusion = true;
  const TraceResult blocked = trace_rays(*bvh, rays, any_hit);
  for (std::size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(bool(blocked.blocked[i]), got.hits[i].valid()) << "ray " << i;

  // The reference on a sub-sample: the exact oracle on the base under every instance transform,
  // every instance tried (no top-level structure to trust).
  const std::shared_ptr<const Primitive> oracle = make_accelerator("exact", scene->bases[0]);
  std::vector<std::shared_ptr<const Primitive>> placed;
  for (std::size_t i = 0; i < scene->instances.size(); ++i)
    placed.push_back(std::make_shared<TransformedPrimitive>(oracle, scene->instances[i].transform, static_cast<unsigned>(i)));
  const BruteForceOverPrimitives reference(std::move(placed));
  std::vector<Ray> sample;
  std::vector<Hit> sample_hits;
  for (std::size_t i = 0; i < rays.size(); i += 4) {
    sample.push_back(rays[i]);
    sample_hits.push_back(got.hits[i]);
  }
  const TraceResult ref = trace_rays(reference, sample, TraceOptions{});
  const HitComparison c = compare_hits(sample, sample_hits, ref.hits, diagonal);
  EXPECT_EQ(c.mismatches, 0u) << c.false_hits << " false, " << c.missed_hits << " missed, " << c.wrong_t << " wrong t";
  EXPECT_LE(c.ties, sample.size() / 100);
  EXPECT_GT(ref.hit_count, sample.size() / 4);
}

// Several bases beside flat geometry (issue 20): every accelerator and the oracle refuse an
// instance that names no base, a singular or non-finite transform, and a nested or empty base,
// with one line naming the scene and the instance.
TEST(Instancing, InvalidInstancesAreRefusedByEveryAccelerator) {
  auto base = std::make_shared<Scene>(*make_scene("sphere:n=50"));
  auto nested = std::make_shared<Scene>();
  nested->bases = {base};
  nested->instances = {{AffineTransform::identity(), 0}};
  AffineTransform nan_transform;
  nan_transform.m[1][3] = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<std::string, std::function<void(Scene&)>>> faults = {
      {"names base 3", [](Scene& s) { s.instances[1].base = 3; }},
      {"singular transform", [](Scene& s) { s.instances[1].transform = AffineTransform::scaling({1, 0, 1}); }},
      {"singular transform", [](Scene& s) { s.instances[1].transform = AffineTransform::scaling({1e-200, 1e-200, 1e-200}); }},
      {"non-finite transform", [&](Scene& s) { s.instances[1].transform = nan_transform; }},
      {"itself instanced", [&](Scene& s) { s.bases[0] = nested; }},
      {"is empty", [](Scene& s) { s.bases[0] = std::make_shared<Scene>(); }},
  };
  for (const auto& [fault, edit] : faults) {
    auto s = std::make_shared<Scene>();
    s->spec = "hand-made";
    s->bases = {base};
    s->instances = {{AffineTransform::identity(), 0}, {AffineTransform::translation({3, 0, 0}), 0}};
    edit(*s);
    for (const std::string accel : {"bvh", "kdtree", "grid", "embree", "exact"}) {
      try {
        make_accelerator(accel, s);
        ADD_FAILURE() << accel << " accepted a scene whose instance " << fault;
      } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("scene 'hand-made'"), std::string::npos) << msg;
        EXPECT_NE(msg.find(fault), std::string::npos) << accel << ": " << msg;
      }
    }
  }
}

}  // namespace
}  // namespace raylab
