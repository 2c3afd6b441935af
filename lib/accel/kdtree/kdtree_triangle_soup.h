#pragma once
/// The scene's triangles with their vertices copied in, indexed by primitive id (a triangle
/// soup): a leaf's test reads prim → 36 contiguous bytes instead of prim → three vertex
/// indices → three vertices. One copy per triangle rather than per leaf reference: with exact
/// clipping a triangle is referenced by ~4 leaves (armadillo), and copies per reference cost
/// 40 B each (231 B per triangle in all) for no measurable speed-up on CGAL meshes.
#include <span>
#include <vector>

#include "accel/bvh/packed_triangles.h"
#include "accel/common/huge_pages.h"
#include "accel/kdtree/kdtree_node_lines.h"
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

/// The leaves' triangles packed kPacketWidth-wide in SoA order (packed_triangles.h), for the
/// SIMD watertight test (packed_triangles_simd.h): a leaf's primitives prims[first, first + count),
/// in their order, fill ceil(count / kPacketWidth) consecutive packets, and the leaf's `first` in
/// `lines` (kdtree_node_lines.h) becomes the index of its first packet; its count stays the
/// primitive count. Copies per reference (40 B each) buy contiguous 4-wide leaf tests. Empty,
/// with `lines` untouched, when the scene holds a sphere.
inline std::vector<TrianglePacket> kd_pack_leaves(const Scene& scene, const std::vector<std::uint32_t>& prims,
                                                  std::vector<KdNodeLine>& lines) {
  std::vector<TrianglePacket> out;
  if (!scene.spheres.empty() || lines.empty()) return out;
  KdNode* nodes = lines.front().node;
  // Leaves in depth-first order, lower child first.
  auto for_each_leaf = [&](auto&& f) {
    std::vector<std::uint32_t> todo = {0};
    while (!todo.empty()) {
      KdNode& n = nodes[todo.back()];
      todo.pop_back();
      if (n.is_leaf()) {
        f(n);
      } else {
        todo.push_back(n.above_child() + 1);
        todo.push_back(n.above_child());
      }
    }
  };
  // Sized before packing (every primitive is a triangle here): growing by doubling would copy
  // the packets and touch about twice their memory.
  std::size_t packets = 0;
  for_each_leaf([&](const KdNode& n) { packets += (n.count() + kPacketWidth - 1) / kPacketWidth; });
  out.reserve(packets);
  advise_huge_pages(out.data(), packets * sizeof(TrianglePacket));
  for_each_leaf([&](KdNode& n) {
    const auto first = static_cast<std::uint32_t>(out.size());
    pack_leaf(scene, std::span<const std::uint32_t>(prims.data() + n.first, n.count()), out);
    n.first = first;
  });
  return out;
}

}  // namespace raylab
