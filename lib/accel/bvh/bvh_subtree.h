#pragma once
/// Subtrees built apart (by parallel tasks) and concatenated into one Bvh2 in a fixed order, so
/// that node numbering does not depend on scheduling: the task decomposition depends only on
/// the references, and each task appends to its own node array.
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "accel/bvh/bvh_node.h"

namespace raylab {

struct BvhSubtree {
  /// nodes[0] is the subtree's root. Interior nodes index this array; leaves index the
  /// builder's reference array (resolved by bvh_concatenate).
  std::vector<Bvh2Node> nodes;
  /// (slot, subtree): the root of `subtree` takes the place of nodes[slot].
  std::vector<std::pair<std::uint32_t, std::unique_ptr<BvhSubtree>>> grafts;

  BvhSubtree() : nodes(1) {}
};

/// Places `root` and its grafts depth first into one node array, then gathers each leaf's
/// references into `prims` in node order: a leaf [first, first + count) of the builder's
/// references becomes prims[new_first, new_first + count) with prims[k] = ref_id(first + i).
template <class RefId>
Bvh2 bvh_concatenate(const BvhSubtree& root, std::size_t primitive_count, RefId&& ref_id) {
  Bvh2 bvh;
  bvh.primitive_count = primitive_count;
  bvh.nodes.resize(1);
  auto place = [&bvh](auto&& self, const BvhSubtree& s, std::uint32_t root_slot) -> void {
    const auto base = static_cast<std::uint32_t>(bvh.nodes.size());
    bvh.nodes.resize(base + s.nodes.size() - 1);
    auto slot = [&](std::uint32_t i) { return i == 0 ? root_slot : base + i - 1; };
    for (std::uint32_t i = 0; i < s.nodes.size(); ++i) {
      Bvh2Node n = s.nodes[i];
      if (!n.is_leaf()) n.first = slot(n.first);  // children are never the subtree's root
      bvh.nodes[slot(i)] = n;
    }
    for (const auto& [g, sub] : s.grafts) self(self, *sub, slot(g));
  };
  place(place, root, 0u);
  std::size_t refs = 0;
  for (const Bvh2Node& n : bvh.nodes) refs += n.count;
  bvh.prims.reserve(refs);
  for (Bvh2Node& n : bvh.nodes) {
    if (!n.is_leaf()) continue;
    const auto first = static_cast<std::uint32_t>(bvh.prims.size());
    for (std::uint32_t k = 0; k < n.count; ++k) bvh.prims.push_back(ref_id(n.first + k));
    n.first = first;
  }
  return bvh;
}

}  // namespace raylab
