#pragma once
/// Subtrees built apart (by parallel tasks) and concatenated into one Bvh2 in a fixed order, so
/// that node numbering does not depend on scheduling: the task decomposition depends only on
/// the references, and each task appends to its own node array.
#include <tbb/parallel_invoke.h>

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "accel/common/huge_pages.h"
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

/// Children of nodes with at least this many references are built as separate tasks.
inline constexpr std::size_t kBvhTaskMinReferences = 4096;

/// Turns out.nodes[slot] into an interior node with two new children and builds them:
/// build(subtree, child_slot, side) with side 0 (left) or 1 (right). A node of at least
/// kBvhTaskMinReferences references builds its children as parallel tasks, each into its own
/// grafted subtree (child_slot 0); a smaller one builds them in place, left first.
template <class BuildChild>
void bvh_split_node(BvhSubtree& out, std::uint32_t slot, std::size_t references, BuildChild&& build) {
  const auto child = static_cast<std::uint32_t>(out.nodes.size());
  out.nodes.resize(out.nodes.size() + 2);
  out.nodes[slot].first = child;
  out.nodes[slot].count = 0;
  if (references >= kBvhTaskMinReferences) {
    auto l = std::make_unique<BvhSubtree>(), r = std::make_unique<BvhSubtree>();
    BvhSubtree &lt = *l, &rt = *r;
    out.grafts.emplace_back(child, std::move(l));
    out.grafts.emplace_back(child + 1, std::move(r));
    tbb::parallel_invoke([&] { build(lt, 0u, 0); }, [&] { build(rt, 0u, 1); });
  } else {
    build(out, child, 0);
    build(out, child + 1, 1);
  }
}

/// Places `root` and its grafts depth first into one node array, then gathers each leaf's
/// references into `prims` in node order: a leaf [first, first + count) of the builder's
/// references becomes prims[new_first, new_first + count) with prims[k] = ref_id(first + i).
template <class RefId>
Bvh2 bvh_concatenate(const BvhSubtree& root, std::size_t primitive_count, RefId&& ref_id) {
  Bvh2 bvh;
  bvh.primitive_count = primitive_count;
  // Sized once: each subtree's root takes its graft's slot.
  auto count = [](auto&& self, const BvhSubtree& s) -> std::size_t {
    std::size_t c = s.nodes.size() - 1;
    for (const auto& g : s.grafts) c += self(self, *g.second);
    return c;
  };
  bvh.nodes.reserve(count(count, root) + 1);
  advise_huge_pages(bvh.nodes.data(), bvh.nodes.capacity() * sizeof(Bvh2Node));
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
  advise_huge_pages(bvh.prims.data(), refs * sizeof(std::uint32_t));
  for (Bvh2Node& n : bvh.nodes) {
    if (!n.is_leaf()) continue;
    const auto first = static_cast<std::uint32_t>(bvh.prims.size());
    for (std::uint32_t k = 0; k < n.count; ++k) bvh.prims.push_back(ref_id(n.first + k));
    n.first = first;
  }
  return bvh;
}

}  // namespace raylab
