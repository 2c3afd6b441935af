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

/// Appends the packets of one leaf holding `prims` (triangles first, in their order, then
/// spheres) to `out`; returns how many were appended.
std::uint32_t pack_leaf(const Scene& scene, std::span<const std::uint32_t> prims, std::vector<TrianglePacket>& out);

}  // namespace raylab
