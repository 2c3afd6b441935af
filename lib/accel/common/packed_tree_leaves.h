#pragma once
/// The leaves of a tree whose nodes are an array packed 4-wide for the SIMD leaf test
/// (packed_triangles.h, kd_test_packed_leaf), for structures whose leaves index a primitive
/// list (octree, BSP tree).
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "accel/bvh/packed_triangles.h"
#include "scene/scene.h"

namespace raylab {

/// Sets `packed_nodes` to a copy of `nodes` in which every leaf holds the index of its first
/// packet in `packets` instead of its offset into `prims`; a leaf's triangles are packed in its
/// order (pack_leaf), ceil(count / kPacketWidth) consecutive packets. `leaf(node)` returns
/// {&node's offset field, its primitive count} for a leaf and {nullptr, 0} for an interior node.
/// Both outputs stay empty when the scene holds a sphere (traversal then reads `prims`).
template <class Node, class Leaf>
void pack_tree_leaves(const Scene& scene, const std::vector<Node>& nodes, const std::vector<std::uint32_t>& prims,
                      Leaf&& leaf, std::vector<Node>& packed_nodes, std::vector<TrianglePacket>& packets) {
  if (!scene.spheres.empty()) return;
  packed_nodes = nodes;
  std::size_t count = 0;  // sized first: growing by doubling would copy the packets
  for (Node& n : packed_nodes)
    if (const auto [first, size] = leaf(n); first != nullptr) count += (size + kPacketWidth - 1) / kPacketWidth;
  packets.reserve(count);
  for (Node& n : packed_nodes)
    if (const auto [first, size] = leaf(n); first != nullptr) {
      const auto packet = static_cast<std::uint32_t>(packets.size());
      pack_leaf(scene, std::span<const std::uint32_t>(prims.data() + *first, size), packets);
      *first = packet;
    }
}

}  // namespace raylab
