#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

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
    // The default C_isect (kdtree_config.h) keeps scenes this small in one leaf.
    const BspTree tree(scene, bsp_config("c_isect=0.2"));
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
    for (const std::string accel_spec : {"bsp:c_isect=0.2", "bsp:axis_candidates=0,c_isect=0.2"}) {
      const auto accel = make_accelerator(accel_spec, scene);
      const auto got = trace_rays(*accel, rays, TraceOptions{1, false, false});
      const auto got_o = trace_rays(*accel, rays, TraceOptions{1, false, true});
      EXPECT_LE(compare_hits(rays, got.hits, ref.hits, diag).mismatches, base_m) << accel_spec << " on " << spec;
      EXPECT_LE(compare_occlusion(got_o.blocked, ref_o.blocked).mismatches, base_mo) << accel_spec << " on " << spec;
    }
  }
  const BspTree walls(make_scene("walls:n=6,angle=30"), bsp_config("axis_candidates=0,c_isect=0.2"));
  EXPECT_GT(walls.data().triangle_planes, 0u);
}

// Cells cut by slanted planes and then by an axis plane next to z = 0: the crossings' rounding
// is relative to the coordinates interpolated from (here up to 18), not to the near-zero z, and
// the boxes of both children of a plane that crosses the cell must reach the plane.
TEST(BspCell, ChildBoxesReachTheirPlaneNearZero) {
  const ConvexCell root(Bounds3f({0.0f, 14.0f, -2.68f}, {5.0f, 18.0f, 3.2e-14f}));
  BspPlane axis;
  axis.axis = 2;
  axis.pos = -0x1.31a67ap-45f;
  axis.normal = Vec3d(0, 0, 1);
  axis.origin = Vec3d(0, 0, axis.pos);
  for (int i = 0; i < 200; ++i) {
    BspPlane slanted;
    slanted.normal = Vec3d(std::cos(0.1 * i), 0.3 + std::sin(0.37 * i), 0.7 + 0.5 * std::sin(1.3 * i));
    slanted.origin = Vec3d(2.5 + std::sin(0.7 * i), 16.0 + std::cos(0.9 * i), -1.0);
    slanted.scale = 4.0;
    ConvexCell a, b;
    root.split(slanted, a, b);
    for (const ConvexCell* c : {&a, &b}) {
      if (c->empty()) continue;
      ConvexCell below, above;
      c->split(axis, below, above);
      if (below.empty() || above.empty()) continue;  // the plane misses the cell
      EXPECT_GE(below.bounds().hi.z, axis.pos) << i;
      EXPECT_LE(above.bounds().lo.z, axis.pos) << i;
    }
  }
}

// Rays at shared edges and vertices of a closed CAD mesh whose flat face lies at z = -3.4e-14:
// its triangles were dropped from the cells next to that face (cell boxes too tight there, and
// slivers between nearly coplanar supporting planes), so these rays hit a farther triangle.
TEST(BspTree, ClosedMeshKeepsEveryTriangleAndAgreesOnItsEdges) {
  const auto scene = make_scene("cgal:fandisk_large");
  const BspTree bsp(scene, bsp_config(""));
  const auto exact = make_accelerator("exact", scene);
  const std::vector<Ray> rays = {
      {{0x1.d0b9d6p+1f, 0x1.e0b63p+3f, 0x1.1ee76cp-4f}, {-0x1.a293p-6f, 0x1.fa78p-7f, -0x1.1ee76cp-4f}},
      {{0x1.ab0fa6p+1f, 0x1.d5481cp+3f, 0x1.2372d4p-4f}, {0x1.9a2ep-7f, 0x1.89fcp-6f, -0x1.2372d4p-4f}},
      {{0x1.ac8ed6p+1f, 0x1.df29eep+3f, 0x1.253d5cp-4f}, {0x1.3c7ep-6f, -0x1.1b78p-6f, -0x1.253d5cp-4f}},
      {{0x1.90ba5ap+1f, 0x1.db8eep+3f, 0x1.2601cap-4f}, {-0x1.7f4ap-7f, 0x1.7194p-6f, -0x1.2601cap-4f}},
      {{0x1.d7307cp+1f, 0x1.d41cbep+3f, 0x1.1e2a5ep-4f}, {-0x1.69cdp-6f, 0x1.536cp-6f, -0x1.1e2a5ep-4f}},
  };
  const auto ref = trace_rays(*exact, rays, TraceOptions{1, false, false});
  const auto got = trace_rays(bsp, rays, TraceOptions{1, false, false});
  const double diag = length(Vec3d(scene->bounds().diagonal()));
  const HitComparison c = compare_hits(rays, got.hits, ref.hits, diag);
  EXPECT_EQ(c.mismatches, 0u);
  for (std::size_t i = 0; i < rays.size(); ++i) EXPECT_FLOAT_EQ(got.hits[i].t, 1.0f) << i;

  std::vector<bool> referenced(scene->primitive_count(), false);
  for (std::uint32_t p : bsp.data().prims) referenced[p] = true;
  EXPECT_EQ(std::count(referenced.begin(), referenced.end(), false), 0);
}

TEST(BspTree, EmptySpaceBonusCutsOffEmptySpace) {
  // The centre and triangle-plane candidates leave primitives on both sides, so only the
  // empty-space cuts next to the primitives' bounds can earn the bonus: without them the
  // parameter would change nothing (these scenes built identical trees at 0 and 0.9).
  auto empty_leaves = [](const BspTreeData& data) {
    return std::count_if(data.nodes.begin(), data.nodes.end(), [](const BspNode& n) { return n.is_leaf() && n.count == 0; });
  };
  for (const std::string spec : {"walls:n=8,angle=30", "grass:blades=200"}) {
    const auto scene = make_scene(spec);
    const BspTree none(scene, bsp_config("empty_bonus=0"));
    const BspTree strong(scene, bsp_config("empty_bonus=0.9"));
    EXPECT_NE(none.structure_hash(), strong.structure_hash()) << spec;
    EXPECT_GT(empty_leaves(strong.data()), empty_leaves(none.data())) << spec;
  }
}

}  // namespace
}  // namespace raylab
