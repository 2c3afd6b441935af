#pragma once
/// The leaves' triangles laid out contiguously: one copy of the three vertices per leaf
/// reference, in the order of the primitive index array, so that a leaf's tests read one
/// contiguous run instead of following index → triangle → vertex (Wald's thesis §7.2 on
/// kd-tree data layout; Embree stores triangles with their vertices the same way).
#include <cstdint>
#include <vector>

#include "geometry/vec3.h"
#include "scene/scene.h"

namespace raylab {

struct KdLeafTriangle {
  Vec3f v0, v1, v2;
  std::uint32_t prim;
};
static_assert(sizeof(KdLeafTriangle) == 40);

/// The gathered copy of `prims` (leaf references) for a scene of triangles only; empty when
/// the scene holds a sphere (traversal then reads the scene).
inline std::vector<KdLeafTriangle> gather_leaf_triangles(const Scene& scene, const std::vector<std::uint32_t>& prims) {
  std::vector<KdLeafTriangle> out;
  if (!scene.spheres.empty()) return out;
  out.reserve(prims.size());
  const auto& v = scene.mesh.vertices;
  for (const std::uint32_t p : prims) {
    const auto& t = scene.mesh.triangles[p];
    out.push_back({v[t[0]], v[t[1]], v[t[2]], p});
  }
  return out;
}

}  // namespace raylab
