// The cell walk of lib/cost/structure_cells.h: it visits every cell tree_features sums over, it
// prunes where told, and its line tests agree with the geometry of boxes and BSP cells.
#include <gtest/gtest.h>

#include <cmath>

#include "accel/bsp/bsp_cell.h"
#include "accel/common/accel_factory.h"
#include "cost/structure_cells.h"
#include "cost/tree_features.h"
#include "geometry/input_error.h"
#include "scene/scene_spec.h"

using namespace raylab;

TEST(StructureCells, WalkCoversWhatTreeFeaturesCounts) {
  const auto scene = make_scene("soup:n=600");
  for (const std::string spec : {"kdtree", "octree", "bsp", "bvh:width=2", "bvh:width=4", "bvh"}) {
    SCOPED_TRACE(spec);
    const auto accel = make_accelerator(spec, scene);
    ASSERT_TRUE(has_structure_cells(*accel));
    const TreeFeatures f = tree_features(*accel, *scene);
    std::size_t inner = 0, leaves = 0, refs = 0;
    walk_structure_cells(*accel, [&](const StructureCell& c) {
      if (!c.leaf) ++inner;
      else if (c.primitives > 0) ++leaves, refs += c.primitives;
      return true;
    });
    EXPECT_EQ(inner, f.inner_nodes);
    EXPECT_EQ(leaves, f.leaves);
    EXPECT_EQ(refs, f.references);
  }
  EXPECT_FALSE(has_structure_cells(*make_accelerator("grid", scene)));
  EXPECT_THROW(walk_structure_cells(*make_accelerator("grid", scene), [](const StructureCell&) { return true; }),
               InputError);
}

TEST(StructureCells, VisitReturningFalsePrunesTheChildren) {
  const auto accel = make_accelerator("kdtree", make_scene("sphere:n=500"));
  int visits = 0;
  walk_structure_cells(*accel, [&](const StructureCell& c) {
    ++visits;
    EXPECT_EQ(c.depth, 0);
    return false;
  });
  EXPECT_EQ(visits, 1);
}

TEST(StructureCells, LinesMeetBoxesAndConvexCellsAsTheGeometrySays) {
  StructureCell box;
  box.box = Bounds3f(Vec3f(0.0f), Vec3f(1.0f));
  EXPECT_TRUE(box.meets_line(Vec3d(-1, 0.5, 0.5), Vec3d(1, 0, 0)));
  EXPECT_TRUE(box.meets_line(Vec3d(0.5, 0.5, 5), Vec3d(0, 0, 1)));  // behind the origin: a line, not a ray
  EXPECT_FALSE(box.meets_line(Vec3d(-1, 1.5, 0.5), Vec3d(1, 0, 0)));
  EXPECT_FALSE(box.meets_line(Vec3d(-1, 0.2, 0.5), Vec3d(1, 2, 0)));  // passes the corner region outside
  // The unit cube cut by the plane x + y = 1: a line near the corner (0, 0) meets only the lower half.
  const ConvexCell cube(Bounds3f(Vec3f(0.0f), Vec3f(1.0f)));
  BspPlane plane;
  plane.normal = Vec3d(1, 1, 0);
  plane.origin = Vec3d(1, 0, 0);
  plane.offset = dot(plane.normal, plane.origin);
  ConvexCell lower, upper;
  cube.split(plane, lower, upper);
  const Vec3d o(0.1, 0.1, -1), d(0, 0, 1);
  EXPECT_TRUE(cube.meets_line(o, d));
  EXPECT_TRUE(lower.meets_line(o, d));
  EXPECT_FALSE(upper.meets_line(o, d));
  EXPECT_TRUE(upper.meets_line(Vec3d(0.9, 0.9, -1), d));
  EXPECT_NEAR(lower.surface_area() + upper.surface_area(), cube.surface_area() + 2 * std::sqrt(2.0), 1e-12);
}
