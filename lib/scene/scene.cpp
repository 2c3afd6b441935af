#include "scene/scene.h"

#include <algorithm>
#include <cstdint>

namespace raylab {
namespace {

/// Closed and consistently oriented: every directed edge (a, b) occurs exactly once and its
/// reverse (b, a) occurs too, so each undirected edge is used by exactly two triangles that
/// traverse it in opposite directions. Decided on vertex indices.
bool closed_mesh(const TriangleMesh& mesh) {
  if (mesh.size() == 0) return false;
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * mesh.size());
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>((k + 1) % 3)];
      if (a == b) return false;
      edges.push_back(a << 32 | b);
    }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
  for (const std::uint64_t e : edges) {
    const std::uint64_t reverse = (e << 32) | (e >> 32);
    if (!std::binary_search(edges.begin(), edges.end(), reverse)) return false;
  }
  return true;
}

}  // namespace

SceneInfo describe(const Scene& scene) {
  SceneInfo info;
  if (scene.instanced()) {
    const SceneInfo base = describe(*scene.base);
    const std::size_t n = scene.instances.size();
    info.triangles = base.triangles * n;
    info.spheres = base.spheres * n;
    info.degenerate_triangles = base.degenerate_triangles * n;
    info.closed = base.closed;
    info.instances = n;
  } else {
    info.triangles = scene.mesh.size();
    info.spheres = scene.spheres.size();
    for (std::size_t t = 0; t < scene.mesh.size(); ++t)
      if (is_degenerate_exact(scene.mesh.vertex(t, 0), scene.mesh.vertex(t, 1), scene.mesh.vertex(t, 2))) ++info.degenerate_triangles;
    info.closed = scene.mesh.size() > 0 ? closed_mesh(scene.mesh) : !scene.spheres.empty();
  }
  info.primitives = scene.total_primitive_count();
  info.bounds = scene.bounds();
  return info;
}

}  // namespace raylab
