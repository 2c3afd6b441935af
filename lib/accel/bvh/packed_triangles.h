#pragma once
/// Leaf primitives packed for SIMD tests: up to kPacketWidth triangles per packet, their three
/// vertices in SoA order (v[vertex][axis][lane]), copied from the mesh at build time so a leaf
/// test reads one contiguous block instead of gathering indices and vertices. A packet holds
/// either triangles or spheres, never both; sphere packets carry only ids and are tested
/// scalar. Unused lanes have id kInvalidId and NaN vertices, which no kernel hits.
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "geometry/ray.h"
#include "scene/scene.h"

namespace raylab {

inline constexpr int kPacketWidth = 4;

struct alignas(16) TrianglePacket {
  float v[3][3][kPacketWidth];
  std::uint32_t prim[kPacketWidth];

  /// Lanes in use (they are a prefix).
  int size() const {
    int n = 0;
    while (n < kPacketWidth && prim[n] != kInvalidId) ++n;
    return n;
  }
  Vec3f vertex(int lane, int k) const { return {v[k][0][lane], v[k][1][lane], v[k][2][lane]}; }
};
static_assert(sizeof(TrianglePacket) == 160);

/// A TrianglePacket by reference: each lane's vertex indices into the scene's mesh and its
/// primitive id, one 64-byte line (a TrianglePacket takes two and a half). The leaves of
/// `bvh:leaves=indexed`, which gather the vertices at each test (gather_packet). Unused lanes
/// have id kInvalidId; a sphere packet's lanes carry ids only.
struct alignas(64) IndexedPacket {
  std::uint32_t vertex[3][kPacketWidth];
  std::uint32_t prim[kPacketWidth];

  /// Lanes in use (they are a prefix).
  int size() const {
    int n = 0;
    while (n < kPacketWidth && prim[n] != kInvalidId) ++n;
    return n;
  }
};
static_assert(sizeof(IndexedPacket) == 64);

/// `packets` by reference, in order (the same leaves, indexed into `scene.mesh`).
std::vector<IndexedPacket> index_packets(const Scene& scene, std::span<const TrianglePacket> packets);

/// The TrianglePacket that pack_leaf made for `indexed`: each triangle lane's vertices gathered
/// from `scene.mesh`, NaN vertices in unused lanes, and (a sphere packet) the ids alone. (AVX2's
/// 4-lane gathers, one per vertex and axis, measured no faster on bunny00 and its Loop-refined
/// 1.2·10^6 triangles: `raylab sweep`, 2 measurements each.)
[[gnu::always_inline]] inline void gather_packet(const Scene& scene, const IndexedPacket& indexed, TrianglePacket& out) {
  for (int lane = 0; lane < kPacketWidth; ++lane) out.prim[lane] = indexed.prim[lane];
  if (scene.is_sphere(indexed.prim[0])) return;  // sphere packets are tested by id (packed_triangles_simd.h)
  const Vec3f* vertices = scene.mesh.vertices.data();
  for (int lane = 0; lane < kPacketWidth; ++lane) {
    if (indexed.prim[lane] == kInvalidId) {
      for (auto& vertex : out.v)
        for (auto& axis : vertex) axis[lane] = std::numeric_limits<float>::quiet_NaN();
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const Vec3f& x = vertices[indexed.vertex[k][lane]];
      for (int a = 0; a < 3; ++a) out.v[k][a][lane] = x[a];
    }
  }
}

/// Appends the packets of one leaf holding `prims` (triangles first, in their order, then
/// spheres) to `out`; returns how many were appended.
std::uint32_t pack_leaf(const Scene& scene, std::span<const std::uint32_t> prims, std::vector<TrianglePacket>& out);

}  // namespace raylab
