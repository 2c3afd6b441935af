#pragma once
/// The scene's triangles with their vertices copied in, indexed by primitive id (a triangle
/// soup): a leaf's test reads prim → 36 contiguous bytes instead of prim → three vertex
/// indices → three vertices. One copy per triangle rather than per leaf reference: with exact
/// clipping a triangle is referenced by ~4 leaves (armadillo), and copies per reference cost
/// 40 B each (231 B per triangle in all) for no measurable speed-up on CGAL meshes.
#include <vector>

#include "geometry/vec3.h"
#include "scene/scene.h"

namespace raylab {

struct KdTriangle {
  Vec3f v0, v1, v2;
};
static_assert(sizeof(KdTriangle) == 36);

/// The soup of a scene of triangles only; empty when the scene holds a sphere (traversal then
/// reads the scene).
inline std::vector<KdTriangle> make_triangle_soup(const Scene& scene) {
  std::vector<KdTriangle> out;
  if (!scene.spheres.empty()) return out;
  out.reserve(scene.mesh.size());
  const auto& v = scene.mesh.vertices;
  for (const auto& t : scene.mesh.triangles) out.push_back({v[t[0]], v[t[1]], v[t[2]]});
  return out;
}

}  // namespace raylab
