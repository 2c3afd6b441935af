#pragma once
/// A wide BVH with quantised child boxes, after Ylitie, Karras and Laine, "Efficient Incoherent
/// Ray Traversal on GPUs Through Compressed Wide BVHs" (HPG 2017) and Embree's compressed BVH8:
/// each node stores a grid (an origin and a power-of-two cell size per axis) and every child
/// box as 8-bit cell indices on it, so an 8-wide node takes 128 bytes instead of 256.
///
/// Contract: a child box decodes as origin + q·cell per plane, computed in float (q·cell is exact,
/// so the fused and the unfused forms round alike, once), and the decoded box contains the
/// exact child box: lo planes round down, hi planes up, checked at build time against the
/// decoding itself with FTZ/DAZ semantics (the traversal's float mode). A box test that is
/// conservative for the decoded box is therefore conservative for the exact one.
#include <cstdint>
#include <vector>

#include "accel/bvh/wide_bvh.h"

namespace raylab {

template <int N>
struct alignas(64) CompressedWideBvhNode {
  static_assert(N == 4 || N == 8);  // only the 8-wide tree is compressed (bvh.cpp)
  static constexpr int kWidth = N;
  float origin[3];
  float cell[3];  ///< per axis, a power of two in [2^-126, 2^127] (a float, not an exponent: no scalar decode)
  /// planes[0..2][i]: lo x, y, z of child i in cells; planes[3..5][i]: hi. Unused lanes hold
  /// lo 255, hi 0; the box tests mask them with `used`.
  std::uint8_t planes[6][N];
  std::uint32_t child[N];  ///< WideRef references, as WideBvhNode's
  std::uint32_t used = 0;  ///< lanes [0, used) are children

  /// Plane `k` (0..5) of child `i` decoded as the traversal decodes it.
  float plane(int k, int i) const;
  Bounds3f box(int i) const {
    Bounds3f b;
    b.lo = {plane(0, i), plane(1, i), plane(2, i)};
    b.hi = {plane(3, i), plane(4, i), plane(5, i)};
    return b;
  }
};
static_assert(sizeof(CompressedWideBvhNode<8>) == 128);

/// origin + q·cell rounded once to float, a result below the normal range flushed to a signed
/// zero (FTZ). Inputs are never denormal (origin is chosen normal or zero, cell is normal).
float decode_compressed_plane(float origin, float cell, std::uint8_t q);

template <int N>
inline float CompressedWideBvhNode<N>::plane(int k, int i) const {
  return decode_compressed_plane(origin[k % 3], cell[k % 3], planes[k][i]);
}

template <int N>
struct CompressedWideBvh {
  std::vector<CompressedWideBvhNode<N>> nodes;  ///< node 0 is the root, as WideBvh's
  std::vector<TrianglePacket> packets;
  Bounds3f root_box;

  std::size_t bytes() const {
    return nodes.size() * sizeof(CompressedWideBvhNode<N>) + packets.size() * sizeof(TrianglePacket);
  }
};

/// Quantises every node of `wide` (same node indices, references and packets, which are moved
/// out of `wide`). Throws std::length_error when a box cannot be held on an 8-bit grid of a
/// normal power-of-two cell (coordinates beyond ~1e36).
template <int N>
CompressedWideBvh<N> compress_wide_bvh(WideBvh<N>&& wide);

extern template CompressedWideBvh<8> compress_wide_bvh<8>(WideBvh<8>&&);

}  // namespace raylab
