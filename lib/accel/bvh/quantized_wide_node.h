#pragma once
/// A wide BVH node whose child boxes are 8-bit offsets from the node's own box, after Ylitie,
/// Karras and Laine, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"
/// (HPG 2017), and Embree's compressed nodes on CPUs: per axis, an origin o (the least lower
/// bound of the children) and a power-of-two step s, and per child and bound a byte q, whose
/// plane is the float
///     dequantize(q, s, o) = o + q·s,
/// q·s exact (q < 2^8, s = 2^e with -120 <= e <= 127), so the sum is the only rounding, whether
/// the traversal fuses it or not. The bytes are chosen at build time against that very float:
/// every lower plane lies at or below the full node's, every upper plane at or above it, so each
/// child box contains the box it stands for. A conservative box test (Ize 2013) on the enlarged
/// boxes keeps every box the exact ray meets and gives entry distances no later than the full
/// node's: the certified kernel's first hits stay exact, a float kernel's are those of full nodes
/// up to ties in t (which the visiting order breaks), and traversal may visit more nodes.
///
/// 128 bytes at width 8 (the full node's 256), 96 at width 4 (128).
#include <cstdint>
#include <vector>

#include "accel/bvh/wide_bvh.h"

namespace raylab {

/// The float of byte `q` on an axis of step `step` and origin `origin` (see above).
inline float dequantize(std::uint8_t q, float step, float origin) { return origin + static_cast<float>(q) * step; }

template <int N>
struct alignas(N == 8 ? 64 : 32) QuantizedWideBvhNode {
  static_assert(N == 4 || N == 8);
  float origin[3];
  float step[3];  ///< powers of two
  /// q[0..2]: lower x, y, z; q[3..5]: upper x, y, z, per child lane. Unused lanes hold 0 and are
  /// masked by `used`.
  std::uint8_t q[6][N];
  std::uint32_t child[N];
  std::uint32_t used = 0;  ///< lanes [0, used) are children

  /// Child i's box as the traversal sees it (containing the full node's box i).
  Bounds3f box(int i) const {
    Bounds3f b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = dequantize(q[a][i], step[a], origin[a]);
      b.hi[a] = dequantize(q[3 + a][i], step[a], origin[a]);
    }
    return b;
  }
};
static_assert(sizeof(QuantizedWideBvhNode<4>) == 96);
static_assert(sizeof(QuantizedWideBvhNode<8>) == 128);

/// The quantized node of `node`: the same children, each box enlarged to the nearest planes of
/// the node's grid (see above). Boxes must be finite.
template <int N>
QuantizedWideBvhNode<N> quantize_wide_node(const WideBvhNode<N>& node);

template <int N>
using QuantizedWideBvh = WideBvh<N, QuantizedWideBvhNode<N>>;

/// `wide` with every node quantized, in the same order (child references keep their meaning);
/// the packets move over.
template <int N>
QuantizedWideBvh<N> quantize_wide_bvh(WideBvh<N>&& wide);

extern template QuantizedWideBvhNode<4> quantize_wide_node<4>(const WideBvhNode<4>&);
extern template QuantizedWideBvhNode<8> quantize_wide_node<8>(const WideBvhNode<8>&);
extern template QuantizedWideBvh<4> quantize_wide_bvh<4>(WideBvh<4>&&);
extern template QuantizedWideBvh<8> quantize_wide_bvh<8>(WideBvh<8>&&);

}  // namespace raylab
