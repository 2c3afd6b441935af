#pragma once
/// The finished kd-tree repacked into two-level treelets: one 32-byte node holds an interior
/// node's split plane and its two children's planes, and the (up to) four grandchildren, so that
/// a ray decides two levels with one node load and no dependent load between the levels (the
/// wide kd node of the issue; in the spirit of the multi-level nodes of Wald's "Realtime Ray
/// Tracing" thesis and of Havran's subtree-clustered layouts, thesis §4.6). The tree itself is
/// unchanged: the same planes and leaves, only packed differently (kd_traverse_treelets reads it).
///
/// Node contract: plane 0 is the treelet root's, plane 1 its lower child's, plane 2 its upper
/// child's; child[2X + Y] is side Y (0 lower, 1 upper) of plane 1 + X under side X of plane 0.
/// A child of the root that is a leaf has no plane: its axis is kKdNoPlane (a fourth coordinate
/// whose origin is 0 and inverse direction +inf, so its plane, at 1, lies at t = +inf for every
/// ray and the near slot 2X gets the whole interval) and its slots are {the leaf, empty leaf}.
///
/// Child words: bit 0 set for a leaf. An interior child is (treelet index << 1). A
/// leaf is (first packet << 6) | (count << 1) | 1 when count < kKdBigLeaf and its first packet
/// fits 26 bits; otherwise (index into big_leaves << 6) | (kKdBigLeaf << 1) | 1. The empty leaf
/// is the word 1 (count 0).
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "accel/bvh/packed_triangles.h"
#include "accel/kdtree/huge_pages.h"
#include "accel/kdtree/kdtree_node.h"
#include "geometry/ray.h"
#include "scene/scene.h"

namespace raylab {

inline constexpr std::uint32_t kKdNoPlane = 3;
inline constexpr std::uint32_t kKdBigLeaf = 31;
inline constexpr std::uint32_t kKdEmptyChild = 1;

struct alignas(32) KdTreelet {
  float split[3];
  std::uint8_t axis[4];  ///< plane k's axis, kKdNoPlane for a leaf child of the root; axis[3] unused
  std::uint32_t child[4];
};
static_assert(sizeof(KdTreelet) == 32);

/// A leaf whose count or first packet does not fit its child word.
struct KdBigLeaf {
  std::uint32_t first, count;
};

struct KdTreelets {
  std::vector<KdTreelet> nodes;
  std::vector<TrianglePacket> packets;  ///< the leaves' triangles 4-wide, leaves in depth-first order
  std::vector<KdBigLeaf> big_leaves;
  std::uint32_t root = kKdEmptyChild;  ///< the child word of the tree's root (a leaf for a one-node tree)

  std::size_t bytes() const {
    return nodes.size() * sizeof(KdTreelet) + packets.size() * sizeof(TrianglePacket) +
           big_leaves.size() * sizeof(KdBigLeaf);
  }
};

inline bool kd_child_is_leaf(std::uint32_t child) { return (child & 1u) != 0; }

/// The first packet and primitive count of a leaf child word.
inline KdBigLeaf kd_child_leaf(std::uint32_t child, const KdBigLeaf* big_leaves) {
  const std::uint32_t count = (child >> 1) & 31u;
  if (count == kKdBigLeaf) return big_leaves[child >> 6];
  return {child >> 6, count};
}

/// Repacks `tree` (the build layout: lower child at index + 1, upper at above_child(), leaves
/// indexing `prims`) into treelets, treelets in depth-first order (a treelet's first interior
/// grandchild follows it) and leaves packed in depth-first order, lower child first. Empty
/// (no treelets, no packets) when the scene holds a sphere: packets hold triangles only.
inline KdTreelets kd_treelets(const Scene& scene, const std::vector<KdNode>& tree, const std::vector<std::uint32_t>& prims) {
  KdTreelets out;
  if (!scene.spheres.empty() || tree.empty()) return out;
  std::size_t packets = 0, interior = 0;
  for (const KdNode& n : tree) {
    if (n.is_leaf()) packets += (n.count() + kPacketWidth - 1) / kPacketWidth;
    else ++interior;
  }
  out.packets.reserve(packets);
  advise_huge_pages(out.packets.data(), packets * sizeof(TrianglePacket));
  out.nodes.reserve(interior);
  auto leaf_word = [&](const KdNode& n) -> std::uint32_t {
    if (n.count() == 0) return kKdEmptyChild;
    const auto first = static_cast<std::uint32_t>(out.packets.size());
    pack_leaf(scene, std::span<const std::uint32_t>(prims.data() + n.first, n.count()), out.packets);
    if (n.count() < kKdBigLeaf && first < (1u << 26)) return (first << 6) | (n.count() << 1) | 1u;
    const auto index = static_cast<std::uint32_t>(out.big_leaves.size());
    if (index >= (1u << 26)) throw std::length_error("kd treelets: more than 2^26 large leaves");
    out.big_leaves.push_back({first, n.count()});
    return (index << 6) | (kKdBigLeaf << 1) | 1u;
  };
  // The child word of node i, packing its subtree.
  auto pack = [&](auto&& self, std::uint32_t i) -> std::uint32_t {
    const KdNode& n = tree[i];
    if (n.is_leaf()) return leaf_word(n);
    const auto index = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes.emplace_back();
    KdTreelet t{};
    t.split[0] = n.split;
    t.axis[0] = static_cast<std::uint8_t>(n.axis());
    t.axis[3] = kKdNoPlane;
    const std::uint32_t sides[2] = {i + 1, n.above_child()};
    std::uint32_t grandchildren[4];  // build-layout node indices; kInvalidId: the empty slot
    for (int x = 0; x < 2; ++x) {
      const KdNode& c = tree[sides[x]];
      if (c.is_leaf()) {
        t.split[1 + x] = 1.0f;
        t.axis[1 + x] = kKdNoPlane;
        grandchildren[2 * x] = sides[x];
        grandchildren[2 * x + 1] = kInvalidId;
      } else {
        t.split[1 + x] = c.split;
        t.axis[1 + x] = static_cast<std::uint8_t>(c.axis());
        grandchildren[2 * x] = sides[x] + 1;
        grandchildren[2 * x + 1] = c.above_child();
      }
    }
    for (int k = 0; k < 4; ++k)
      t.child[k] = grandchildren[k] == kInvalidId ? kKdEmptyChild : self(self, grandchildren[k]);
    out.nodes[index] = t;
    return index << 1;
  };
  out.root = pack(pack, 0);
  return out;
}

}  // namespace raylab
