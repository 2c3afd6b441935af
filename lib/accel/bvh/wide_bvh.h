#pragma once
/// A wide BVH (4 or 8 children per node) collapsed from the binary one, after Wald, Benthin and
/// Boulos, "Getting Rid of Packets: Efficient SIMD Single-Ray Traversal using Multi-Branching
/// BVHs" (RT 2008), and Embree's BVH4/BVH8: each wide node takes a binary node's two children
/// and repeatedly opens the interior child of largest surface area until it has `N` children
/// (or only leaves remain), so the SAH-expensive boxes are the ones replaced by their children.
///
/// Layout: one 64-byte aligned node holds its children's boxes as SoA float arrays (one
/// N-wide load per slab bound), the children's references and the number of used lanes. Leaves
/// are references into an array of triangle packets (packed_triangles.h).
#include <cstdint>
#include <vector>

#include "accel/bvh/bvh_node.h"
#include "accel/bvh/packed_triangles.h"
#include "scene/scene.h"

namespace raylab {

/// A child reference: an interior node index, or (top bit set) a leaf of `count` packets from
/// packet `first`, with first < 2^25 and 1 <= count <= 64.
struct WideRef {
  static constexpr std::uint32_t kLeafBit = 0x80000000u;
  static constexpr std::uint32_t kCountShift = 25;
  static constexpr std::uint32_t kFirstMask = (1u << kCountShift) - 1;
  static constexpr std::uint32_t kMaxLeafPackets = 64;

  static bool is_leaf(std::uint32_t ref) { return (ref & kLeafBit) != 0; }
  static std::uint32_t leaf(std::uint32_t first, std::uint32_t count) {
    return kLeafBit | ((count - 1) << kCountShift) | first;
  }
  static std::uint32_t first(std::uint32_t ref) { return ref & kFirstMask; }
  static std::uint32_t count(std::uint32_t ref) { return ((ref >> kCountShift) & 63u) + 1; }
};

template <int N>
struct alignas(64) WideBvhNode {
  static_assert(N == 4 || N == 8);
  /// bounds[0..2]: lo x, y, z; bounds[3..5]: hi x, y, z. Unused lanes hold empty boxes
  /// (+inf, -inf), which the box tests miss by plane choice; where the robust test mirrors
  /// intersect_box's swap (a zero direction component) it masks them with `used` instead.
  float bounds[6][N];
  std::uint32_t child[N];
  std::uint32_t used = 0;  ///< lanes [0, used) are children

  Bounds3f box(int i) const {
    Bounds3f b;
    b.lo = {bounds[0][i], bounds[1][i], bounds[2][i]};
    b.hi = {bounds[3][i], bounds[4][i], bounds[5][i]};
    return b;
  }
};
static_assert(sizeof(WideBvhNode<4>) == 128);
static_assert(sizeof(WideBvhNode<8>) == 256);

/// Nodes of type `Node`: WideBvhNode<N>, or QuantizedWideBvhNode<N> (quantized_wide_node.h).
template <int N, class Node = WideBvhNode<N>>
struct WideBvh {
  std::vector<Node> nodes;  ///< node 0 is the root (always interior, >= 1 child)
  std::vector<TrianglePacket> packets;
  Bounds3f root_box;

  std::size_t bytes() const { return nodes.size() * sizeof(Node) + packets.size() * sizeof(TrianglePacket); }
};

/// Collapses `tree` (built over `scene`, which must not be instanced) into an N-wide BVH whose
/// leaves are the binary leaves, packed. Every binary leaf reference appears in exactly one
/// packet lane; every wide child box is the binary node's box. Throws std::length_error when a
/// leaf or the packet array exceeds WideRef's encoding.
template <int N>
WideBvh<N> collapse_bvh(const Bvh2& tree, const Scene& scene);

extern template WideBvh<4> collapse_bvh<4>(const Bvh2&, const Scene&);
extern template WideBvh<8> collapse_bvh<8>(const Bvh2&, const Scene&);

}  // namespace raylab
