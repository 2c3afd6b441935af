// Rays through shared edges and vertices of closed meshes. Each ray crosses the surface from
// outside near the feature (rays/feature_rays.h), so the exact oracle reports a hit for every
// one of them. The watertight kernel must miss none; the Möller-Trumbore kernel's misses are
// recorded (as a test property and on stdout), not bounded: they are what the lecture's
// "robustness" discussion is about.
#include <gtest/gtest.h>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "scene/cgal_meshes.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

std::vector<std::string> closed_test_meshes() {
  std::vector<std::string> specs = {"sphere:n=4000", "sphereflake:depth=1,as=triangles"};
  for (const auto& name : cgal_reference_meshes()) {
    const auto scene = make_scene("cgal:" + name);
    if (scene->mesh.size() <= 120000 && describe(*scene).closed) specs.push_back("cgal:" + name);
    if (specs.size() >= 6) break;
  }
  return specs;
}

TEST(WatertightKernel, MissesNoRayThroughSharedEdgesAndVerticesOfClosedMeshes) {
  const auto specs = closed_test_meshes();
  ASSERT_GE(specs.size(), 3u) << "need closed meshes to test on";
  std::size_t total_rays = 0, mt_missed = 0;
  for (const auto& spec : specs) {
    const auto scene = make_scene(spec);
    ASSERT_TRUE(describe(*scene).closed) << spec;
    const auto oracle = make_accelerator("exact", scene);
    const auto watertight = make_accelerator("brute:kernel=watertight", scene);
    const auto mt = make_accelerator("brute:kernel=mt", scene);
    const double diagonal = length(Vec3d(scene->bounds().diagonal()));
    for (const std::string rays_spec : {"edges:2048", "vertices:2048"}) {
      const auto rays = make_ray_set(rays_spec, scene);
      const TraceResult ref = trace_rays(*oracle, rays, TraceOptions{});
      const std::size_t ref_hits = ref.hit_count;
      EXPECT_EQ(ref_hits, rays.size()) << spec << " " << rays_spec << ": every feature-aimed ray crosses the surface";
      const HitComparison w = compare_hits(rays, trace_rays(*watertight, rays, TraceOptions{}).hits, ref.hits, diagonal);
      EXPECT_EQ(w.missed_hits, 0u) << spec << " " << rays_spec;
      EXPECT_EQ(w.mismatches, 0u) << spec << " " << rays_spec;
      const HitComparison m = compare_hits(rays, trace_rays(*mt, rays, TraceOptions{}).hits, ref.hits, diagonal);
      std::cout << "[ mt-misses ] " << spec << " " << rays_spec << ": Moller-Trumbore missed " << m.missed_hits << " of "
                << rays.size() << " (watertight: " << w.missed_hits << ")\n";
      total_rays += rays.size();
      mt_missed += m.missed_hits;
    }
  }
  ::testing::Test::RecordProperty("feature_rays", static_cast<int>(total_rays));
  ::testing::Test::RecordProperty("moller_trumbore_misses", static_cast<int>(mt_missed));
}

}  // namespace
}  // namespace raylab
