#include "accel/grid/grid_frame.h"

#include <cmath>

#include "accel/grid/grid_geometry.h"

namespace raylab {
namespace {

/// Whether v - origin is exact in float on every axis.
bool exact_difference(const Vec3f& v, const Vec3f& origin) {
  for (int a = 0; a < 3; ++a)
    if (double(v[a] - origin[a]) != double(v[a]) - double(origin[a])) return false;
  return true;
}

}  // namespace

GridFrame make_grid_frame(std::shared_ptr<const Scene> scene) {
  GridFrame world{Vec3f(0.0f), scene};
  if (scene->instanced()) return world;
  const Bounds3f b = scene->bounds();
  if (b.empty()) return world;
  Vec3f origin(0.0f);
  Bounds3f in_frame_bounds = b;
  for (int a = 0; a < 3; ++a) {
    const float extent = b.hi[a] - b.lo[a];
    if (b.lo[a] > 0.0f && b.lo[a] >= extent) origin[a] = b.lo[a];
    if (b.hi[a] < 0.0f && -b.hi[a] >= extent) origin[a] = b.hi[a];
    in_frame_bounds.lo[a] = b.lo[a] - origin[a];
    in_frame_bounds.hi[a] = b.hi[a] - origin[a];
  }
  if (!(4.0f * grid_margin(in_frame_bounds) < grid_margin(b))) return world;

  auto framed = std::make_shared<Scene>();
  framed->spec = scene->spec;
  framed->mesh.triangles = scene->mesh.triangles;
  framed->mesh.vertices.reserve(scene->mesh.vertices.size());
  for (const Vec3f& v : scene->mesh.vertices) {
    if (!exact_difference(v, origin)) return world;
    framed->mesh.vertices.push_back(v - origin);
  }
  framed->spheres.reserve(scene->spheres.size());
  for (const Sphere& s : scene->spheres) {
    if (!exact_difference(s.center, origin)) return world;
    framed->spheres.push_back({s.center - origin, s.radius});
  }
  return {origin, std::move(framed)};
}

void to_world(CellTriangles& tris, const Vec3f& origin) {
  for (CellTriangles::Triangle& t : tris.tris) {
    t.v0 = t.v0 + origin;
    t.v1 = t.v1 + origin;
    t.v2 = t.v2 + origin;
  }
}

}  // namespace raylab
