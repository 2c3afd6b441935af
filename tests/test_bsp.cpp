#include <gtest/gtest.h>

#include "accel/bsp/bsp.h"
#include "accel/bsp/bsp_cell.h"
#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/tracer.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

BspConfig bsp_config(const std::string& params) {
  SpecReader r(parse_spec("bsp" + (params.empty() ? "" : ":" + params)));
  return read_bsp_config(r);
}

TEST(BspCell, SplittingTheUnitCubeDiagonally) {
  const ConvexCell cube(Bounds3f({0, 0, 0}, {1, 1, 1}));
  EXPECT_NEAR(cube.surface_area(), 6.0, 1e-12);
  BspPlane p;
  p.normal = Vec3d(1, 1, 0);
  p.origin = Vec3d(1, 0, 0);  // x + y = 1: two triangular prisms
  ConvexCell a, b;
  cube.split(p, a, b);
  const double expected = 2 * 0.5 + 1 + 1 + std::sqrt(2.0);
  EXPECT_NEAR(a.surface_area(), expected, 1e-9);
  EXPECT_NEAR(b.surface_area(), expected, 1e-9);
}

TEST(BspPlaneClassification, ExactSidesOfATrianglePlane) {
  auto s = std::make_shared<Scene>();
  auto& m = s->mesh;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {0, 0, -1}, {1, 0, 1}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  BspPlane p;
  ASSERT_TRUE(triangle_plane(*s, 0, p));  // z = 0, normal +z
  EXPECT_EQ(classify(*s, 0, p), BspSide::both);      // coplanar
  EXPECT_EQ(classify(*s, 1, p), BspSide::positive);  // above
  EXPECT_EQ(classify(*s, 2, p), BspSide::both);      // straddles
}

TEST(BspTree, RaysInItsPlanesAgreeWithTheOracleAsWellAsBruteForce) {
  for (const std::string spec : {"walls:n=6,angle=30", "soup:n=500", "grass:blades=100"}) {
    const auto scene = make_scene(spec);
    const BspTree tree(scene, bsp_config(""));
    EXPECT_GT(tree.data().leaves, 1u) << spec;
    // Rays lying in split planes: from a node's plane, two in-plane directions.
    std::vector<Ray> rays;
    for (const BspNode& n : tree.data().nodes) {
      if (n.is_leaf() || rays.size() > 2000) continue;
      const Vec3d nn(n.normal[0], n.normal[1], n.normal[2]);
      const Vec3d u = normalize(std::abs(nn.x) > 0.5 ? cross(nn, Vec3d(0, 1, 0)) : cross(nn, Vec3d(1, 0, 0)));
      const Vec3d v = cross(normalize(nn), u);
      const Vec3d c(tree.data().bounds.center());
      const Vec3d origin(n.origin[0], n.origin[1], n.origin[2]);
      const Vec3d foot = c - nn * (dot(nn, c - origin) / dot(nn, nn));
      for (double ang : {0.3, 1.9, 4.0}) {
        const Vec3d dir = u * std::cos(ang) + v * std::sin(ang);
        const Vec3d org = foot - dir * (2.0 * length(Vec3d(tree.data().bounds.diagonal())));
        rays.push_back({Vec3f(org), Vec3f(dir)});
      }
    }
    // Rays in a plane of the scene's triangles graze them: there the watertight kernel itself
    // departs from the exact answer. The BSP tree must agree with the exact oracle at least as
    // well as brute force with the same kernel, ray by ray in total.
    const auto brute = make_accelerator("brute", scene);
    const auto exact = make_accelerator("exact", scene);
    const double diag = length(Vec3d(scene->bounds().diagonal()));
    const auto ref = trace_rays(*exact, rays, TraceOptions{1, false, false});
    const auto ref_o = trace_rays(*exact, rays, TraceOptions{1, false, true});
    const auto base = trace_rays(*brute, rays, TraceOptions{1, false, false});
    const auto base_o = trace_rays(*brute, rays, TraceOptions{1, false, true});
    const std::size_t base_m = compare_hits(rays, base.hits, ref.hits, diag).mismatches;
    const std::size_t base_mo = compare_occlusion(base_o.blocked, ref_o.blocked).mismatches;
    for (const std::string accel_spec : {"bsp", "bsp:axis_candidates=0"}) {
      const auto accel = make_accelerator(accel_spec, scene);
      const auto got = trace_rays(*accel, rays, TraceOptions{1, false, false});
      const auto got_o = trace_rays(*accel, rays, TraceOptions{1, false, true});
      EXPECT_LE(compare_hits(rays, got.hits, ref.hits, diag).mismatches, base_m) << accel_spec << " on " << spec;
      EXPECT_LE(compare_occlusion(got_o.blocked, ref_o.blocked).mismatches, base_mo) << accel_spec << " on " << spec;
    }
  }
  const BspTree walls(make_scene("walls:n=6,angle=30"), bsp_config("axis_candidates=0"));
  EXPECT_GT(walls.data().triangle_planes, 0u);
}

}  // namespace
}  // namespace raylab
