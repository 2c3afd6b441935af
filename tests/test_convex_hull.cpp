// Convex hulls and projected areas (geometry/convex_hull.h), and Crofton's theorem on a body
// whose answer is known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/convex_hull.h"
#include "geometry/input_error.h"
#include "scene/scene.h"

using namespace raylab;

namespace {

std::vector<Vec3f> unit_cube_with_inner_points() {
  std::vector<Vec3f> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? 1.0f : 0.0f, i & 2 ? 1.0f : 0.0f, i & 4 ? 1.0f : 0.0f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.1f, 0.9f);
  for (int i = 0; i < 50; ++i) p.emplace_back(u(rng), u(rng), u(rng));
  return p;
}

}  // namespace

TEST(ConvexHull, CubeIsClosedOutwardWithItsCorners) {
  const TriangleMesh hull = convex_hull(unit_cube_with_inner_points());
  EXPECT_EQ(hull.vertices.size(), 8u);
  EXPECT_EQ(hull.size(), 12u);
  Scene s;
  s.mesh = hull;
  EXPECT_TRUE(describe(s).closed);
  double volume6 = 0;
  for (std::size_t t = 0; t < hull.size(); ++t)
    volume6 += dot(Vec3d(hull.vertex(t, 0)), cross(Vec3d(hull.vertex(t, 1)), Vec3d(hull.vertex(t, 2))));
  EXPECT_NEAR(volume6, 6.0, 1e-9);  // outward faces: six times the volume, positive
  EXPECT_NEAR(surface_area(hull), 6.0, 1e-9);
}

TEST(ConvexHull, ProjectedAreasOfTheCube) {
  const auto points = unit_cube_with_inner_points();
  EXPECT_NEAR(projected_area(points, Vec3d(0, 0, 1)), 1.0, 1e-12);
  EXPECT_NEAR(projected_area(points, Vec3d(0, -2, 0)), 1.0, 1e-12);
  EXPECT_NEAR(projected_area(points, Vec3d(1, 1, 1)), std::sqrt(3.0), 1e-12);  // a regular hexagon
  // Crofton: the mean over uniform directions is S/4 = 1.5 (the cube's projection along a unit
  // direction d has area |d.x| + |d.y| + |d.z|, whose mean is 3/2).
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  double sum = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) sum += projected_area(points, Vec3d(g(rng), g(rng), g(rng)));
  EXPECT_NEAR(sum / n, 1.5, 0.01);
}

TEST(ConvexHull, RefusesFlatOrTooFewPoints) {
  EXPECT_THROW(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), InputError);
  EXPECT_THROW(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5f, 0.5f, 0}}), InputError);
  EXPECT_THROW(projected_area({{0, 0, 0}}, Vec3d(0.0)), InputError);
}
