#pragma once
/// Leaf primitives packed for SIMD tests: up to kPacketWidth triangles per packet, their three
/// vertices in SoA order (v[vertex][axis][lane]), copied from the mesh at build time so a leaf
/// test reads one contiguous block instead of gathering indices and vertices. A packet holds
/// either triangles or spheres, never both; sphere packets carry only ids and are tested
/// scalar. Unused lanes have id kInvalidId and NaN vertices, which no kernel hits.
#include <immintrin.h>

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

/// A TrianglePacket by reference: each lane's vertex indices (into IndexedLeaves::vertices) and its
/// primitive id, one 64-byte line (a TrianglePacket takes two and a half). The leaves of
/// `bvh:leaves=indexed`, which gather the vertices at each test (gather_packet). Unused lanes
/// have id kInvalidId and vertex indices 0; a sphere packet's lanes carry ids only.
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

/// Packed leaves by reference: `packets` index `vertices`, which hold each mesh vertex the leaves
/// use once, in the order the packets first use them, so a leaf's vertices lie together in memory
/// whatever the mesh's order (grass and Loop-refined meshes list a leaf's vertices far apart, and
/// each gathered triangle would miss the cache on its own). `vertices` ends with one spare vertex
/// (gather_packet reads 16 bytes per vertex), which `bytes()` counts.
struct IndexedLeaves {
  std::vector<IndexedPacket> packets;
  std::vector<Vec3f> vertices;

  std::size_t bytes() const { return packets.size() * sizeof(IndexedPacket) + vertices.size() * sizeof(Vec3f); }
};

/// `packets` (of `scene`) by reference, in order: the same leaves, indexed.
IndexedLeaves index_packets(const Scene& scene, std::span<const TrianglePacket> packets);

/// The TrianglePacket that pack_leaf made for `indexed`, a packet whose vertex indices refer to
/// `vertices` (IndexedLeaves::vertices, spare vertex included): each triangle lane's vertices, NaN
/// vertices in unused lanes, and (a sphere packet of `scene`) the ids alone. Per corner, the four
/// lanes' vertices are loaded 16 bytes each (x, y, z and the next float) and transposed into the
/// packet's x, y and z vectors, which are stored whole, so the leaf test's vector loads forward
/// from the stores. (Element-wise copies took 1.00-1.15x the time of these on bunny00, its
/// Loop-refined 1.2·10^6 triangles and grass of 2.1·10^6, primary, diffuse and shadow rays:
/// `raylab sweep`, one measurement each; AVX2 gathers were slower than element-wise copies on the
/// grass.)
[[gnu::always_inline]] inline void gather_packet(const Scene& scene, const Vec3f* vertices, const IndexedPacket& indexed,
                                                 TrianglePacket& out) {
  static_assert(kPacketWidth == 4 && sizeof(Vec3f) == 3 * sizeof(float));
  const __m128i prims = _mm_load_si128(reinterpret_cast<const __m128i*>(indexed.prim));
  _mm_store_si128(reinterpret_cast<__m128i*>(out.prim), prims);
  if (scene.is_sphere(indexed.prim[0])) return;  // sphere packets are tested by id (packed_triangles_simd.h)
  // Unused lanes (id kInvalidId) get pack_leaf's quiet NaN.
  const __m128 unused = _mm_castsi128_ps(_mm_cmpeq_epi32(prims, _mm_set1_epi32(static_cast<int>(kInvalidId))));
  const __m128 nan = _mm_set1_ps(std::numeric_limits<float>::quiet_NaN());
  const auto in_use = [&](__m128 x) {
#if defined(__SSE4_1__)
    return _mm_blendv_ps(x, nan, unused);
#else
    return _mm_or_ps(_mm_and_ps(unused, nan), _mm_andnot_ps(unused, x));
#endif
  };
  const float* coords = &vertices->x;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t* v = indexed.vertex[k];
    __m128 a = _mm_loadu_ps(coords + 3 * std::size_t{v[0]}), b = _mm_loadu_ps(coords + 3 * std::size_t{v[1]});
    __m128 c = _mm_loadu_ps(coords + 3 * std::size_t{v[2]}), d = _mm_loadu_ps(coords + 3 * std::size_t{v[3]});
    _MM_TRANSPOSE4_PS(a, b, c, d);  // a: the lanes' x, b: y, c: z
    _mm_store_ps(out.v[k][0], in_use(a));
    _mm_store_ps(out.v[k][1], in_use(b));
    _mm_store_ps(out.v[k][2], in_use(c));
  }
}

/// Writes the packets of one leaf holding `prims` (triangles first, in their order, then
/// spheres) from `out` on: packed_leaf_packets(triangles, spheres) of them, the count returned.
std::uint32_t pack_leaf(const Scene& scene, std::span<const std::uint32_t> prims, TrianglePacket* out);

/// The same packets, appended to `out`; returns how many were appended.
std::uint32_t pack_leaf(const Scene& scene, std::span<const std::uint32_t> prims, std::vector<TrianglePacket>& out);

/// The packets pack_leaf appends for a leaf of `triangles` triangles and `spheres` spheres: each
/// kind in whole packets of kPacketWidth.
inline std::size_t packed_leaf_packets(std::size_t triangles, std::size_t spheres) {
  return (triangles + kPacketWidth - 1) / kPacketWidth + (spheres + kPacketWidth - 1) / kPacketWidth;
}

}  // namespace raylab
