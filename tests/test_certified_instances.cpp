// Certified first hits on instanced scenes without a flat copy (accel/exact/certified_instances.h):
// the exact oracle's answers on its flat copy, by the exact rule, on closed and open meshes,
// spheres, far from the origin and tiny, with rays aimed at edges and vertices, touching and
// grazing ones; and the lecture's 3.1·10^9 triangles traced certified.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "accel/exact/certified_instances.h"
#include "accel/exact/exact_oracle.h"
#include "geometry/input_error.h"
#include "scene/procedural.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

TEST(CertifiedInstances, AgreeWithTheOracleOnTheFlatCopyByTheExactRule) {
  // The oracle suite runs certified-instances on its scenes (instances, glTF instances under
  // non-uniform scales beside flat geometry, far and tiny transformed scenes); these add an open
  // mesh of one shared vertex far from the origin, a tiny rotated closed mesh, and spheres.
  for (const std::string& spec : std::vector<std::string>{
           "transformed:of=(instances:of=(fan:n=16),count=8),translate=1e4:0:0",
           "transformed:of=(instances:of=(sphere:n=200),count=8),rotate=x:30,scale=1e-4",
           "instances:of=(sphereflake:depth=1),count=8"}) {
    SCOPED_TRACE(spec);
    const auto scene = make_scene(spec);
    ASSERT_TRUE(scene->instanced());
    const CertifiedInstances certified(scene);
    const auto oracle = make_exact_oracle(scene);
    const auto flat = flatten_instances(*scene);
    for (const std::string rays_spec : {"diffuse:600", "edges:300", "vertices:300", "touching:200", "grazing:200"}) {
      SCOPED_TRACE(rays_spec);
      if (rays_spec != "diffuse:600" && flat->mesh.size() == 0) continue;  // spheres only: no edges
      const auto rays = make_ray_set(rays_spec, flat);  // aimed at the flat copy's edges and vertices
      const TraceResult got = trace_rays(certified, rays, TraceOptions{1});
      const TraceResult ref = trace_rays(*oracle, rays, TraceOptions{1});
      const HitComparison c = compare_hits_exact(*scene, rays, got.hits, ref.hits);
      EXPECT_EQ(c.mismatches, 0u) << "first mismatching rays: " << ::testing::PrintToString(c.first_mismatches);
      EXPECT_GT(ref.hit_count, 0u);
    }
    const auto shadow = make_ray_set("shadow:400", flat);
    TraceOptions any_hit{1};
    any_hit.occlusion = true;
    const TraceResult blocked = trace_rays(certified, shadow, any_hit), ref = trace_rays(*oracle, shadow, any_hit);
    EXPECT_EQ(compare_occlusion(blocked.blocked, ref.blocked).mismatches, 0u);
  }
}

TEST(CertifiedInstances, SpheresUnderANonUniformScaleAreRefusedAsTheFlatCopyRefusesThem) {
  const auto base = make_scene("sphereflake:depth=1");
  ASSERT_FALSE(base->spheres.empty());
  Scene scene;
  scene.spec = "stretched spheres";
  scene.bases.push_back(base);
  scene.instances.push_back({AffineTransform::scaling(Vec3d(1, 2, 1)), 0});
  EXPECT_THROW(CertifiedInstances(std::make_shared<const Scene>(scene)), InputError);
}

TEST(CertifiedInstances, TheLectureSceneOfThreeBillionTrianglesIsTracedCertified) {
  const auto scene = make_scene(kLectureInstancedSceneSpec);
  ASSERT_GT(scene->total_primitive_count(), kExactOracleMaxPrimitives);
  const auto certified = make_accelerator("bvh", scene);
  ASSERT_NE(dynamic_cast<const CertifiedInstances*>(certified.get()), nullptr)
      << "beyond the flat copy's limit, the default (certified) kernel answers from the bases alone";
  const auto watertight = make_accelerator("bvh:kernel=watertight", scene);
  const auto rays = make_ray_set("primary:1024", scene);
  const TraceResult got = trace_rays(*certified, rays, TraceOptions{1});
  const TraceResult reference = trace_rays(*watertight, rays, TraceOptions{1});
  const Scene& base = *scene->bases[0];
  std::size_t same = 0, hits = 0;
  std::set<unsigned> instances_hit;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Hit& h = got.hits[i];
    EXPECT_EQ(h.valid(), reference.hits[i].valid()) << "ray " << i;
    if (!h.valid()) continue;
    ++hits;
    ASSERT_LT(h.instance, scene->instances.size());
    ASSERT_LT(h.prim, base.mesh.size());
    instances_hit.insert(h.instance);
    same += h.instance == reference.hits[i].instance && h.prim == reference.hits[i].prim;
    // The hit lies on the plane of the triangle it names, as the flat copy places it. Its t is the
    // kernel's float estimate inside its enclosure of the exact t (certified_kernel.h): the first
    // hit is exact, its t as close as a float kernel's, a few 10^-6 relative here, where each
    // triangle is small against its distance from the ray's origin.
    const AffineTransform& xf = scene->instances[h.instance].transform;
    const Vec3d p0(xf.apply_point(base.mesh.vertex(h.prim, 0))), p1(xf.apply_point(base.mesh.vertex(h.prim, 1))),
        p2(xf.apply_point(base.mesh.vertex(h.prim, 2)));
    const Vec3d n = cross(p1 - p0, p2 - p0), o(rays[i].org), d(rays[i].dir);
    const double plane_t = dot(p0 - o, n) / dot(d, n);
    EXPECT_LE(std::abs(double(h.t) - plane_t), 1e-4 * plane_t) << "ray " << i;
  }
  EXPECT_GT(hits, rays.size() / 4);
  EXPECT_GT(instances_hit.size(), 50u);
  // Primary rays cross the bunnies well away from edges: the watertight kernel's first hits
  // are the certified ones on all but a handful.
  EXPECT_GE(same, hits - hits / 100);
}

}  // namespace
}  // namespace raylab
