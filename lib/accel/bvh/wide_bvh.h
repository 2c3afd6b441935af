#pragma once
/// A wide BVH (4 or 8 children per node) collapsed from the binary one, after Wald, Benthin and
/// Boulos, "Getting Rid of Packets: Efficient SIMD Single-Ray Traversal using Multi-Branching
/// BVHs" (RT 2008), and Embree's BVH4/BVH8. Two collapses (BvhCollapse):
///  - greedy: each wide node takes a binary node's two children and repeatedly opens the
///    interior child of largest surface area until it has `N` children (or only leaves remain),
///    so the SAH-expensive boxes are the ones replaced by their children;
///  - sah: the collapse of least wide SAH cost (Ylitie, Karras and Laine, "Efficient Incoherent
///    Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, §3.1), by dynamic
///    programming over the binary tree: which nodes become wide nodes, how each wide node's `N`
///    lanes are shared among the subtrees below it, and which small subtrees become one leaf.
///
/// Layout: one 64-byte aligned node holds its children's boxes as SoA float arrays (one
/// N-wide load per slab bound), the children's references and the number of used lanes. Leaves
/// are references into an array of triangle packets (packed_triangles.h).
#include <cstdint>
#include <vector>

#include "accel/bvh/bvh_config.h"
#include "accel/bvh/bvh_node.h"
#include "accel/bvh/packed_triangles.h"
#include "accel/common/build_array_allocator.h"
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
  BuildArray<Node> nodes;  ///< node 0 is the root (always interior, >= 1 child)
  BuildArray<TrianglePacket> packets;
  Bounds3f root_box;

  std::size_t bytes() const { return nodes.size() * sizeof(Node) + packets.size() * sizeof(TrianglePacket); }
};

/// What collapse_bvh builds.
struct WideCollapseOptions {
  BvhCollapse method = BvhCollapse::sah;
  /// The wide SAH BvhCollapse::sah minimises.
  WideSahCost cost;
  /// The most primitives a leaf merged from a binary subtree holds (BvhCollapse::sah); binary
  /// leaves are kept whole whatever their size.
  std::uint32_t max_leaf_primitives = 16;
  /// Threads of the collapse (BvhConfig::threads: 0 means every hardware thread); the tree does
  /// not depend on them.
  int threads = 0;
};

/// Collapses `tree` (built over `scene`, which must not be instanced) into an N-wide BVH. Each
/// wide leaf is one binary leaf, or (BvhCollapse::sah) the binary leaves of one subtree merged,
/// packed; every binary leaf reference appears in exactly one packet lane; every wide child box
/// is a binary node's box. Throws std::length_error when a leaf or the packet array exceeds
/// WideRef's encoding.
template <int N>
WideBvh<N> collapse_bvh(const Bvh2& tree, const Scene& scene, const WideCollapseOptions& options = {});

extern template WideBvh<4> collapse_bvh<4>(const Bvh2&, const Scene&, const WideCollapseOptions&);
extern template WideBvh<8> collapse_bvh<8>(const Bvh2&, const Scene&, const WideCollapseOptions&);

/// The wide SAH cost of `wide` (full float nodes) under `options.cost`, areas relative to
/// the root box's: Σ_nodes c_node·SA(node) + Σ_leaves c_packet·SA(leaf)·packets(leaf). The cost
/// BvhCollapse::sah minimises: no other collapse of the same binary tree costs less.
template <int N>
double wide_sah_cost(const WideBvh<N>& wide, const WideCollapseOptions& options);

extern template double wide_sah_cost<4>(const WideBvh<4>&, const WideCollapseOptions&);
extern template double wide_sah_cost<8>(const WideBvh<8>&, const WideCollapseOptions&);

}  // namespace raylab
