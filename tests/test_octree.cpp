#include <gtest/gtest.h>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/tracer.h"
#include "accel/octree/octree.h"
#include "geometry/exact_predicates.h"
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
    const Octree tree(scene, octree_config(""));
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
    for (const std::string accel_spec : {"octree", "octree:clip=none", "octree:clip=bbox,mailbox=on"}) {
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
