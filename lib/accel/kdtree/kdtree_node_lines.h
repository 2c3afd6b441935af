#pragma once
/// The kd-tree's nodes regrouped into 64-byte cache lines for the stack traversal: the children
/// of an interior node are an adjacent pair, and a line holds a node with as many levels of its
/// subtree as fit (a root, its pair, and its two grandchild pairs), so that a descent reads one
/// line per two or three levels instead of one per upper child (Havran's thesis §4.6 on
/// subtree-clustered kd-tree layouts; the van Emde Boas idea of Gil and Itai 1999 in its
/// simplest, one-line form).
///
/// Node encoding is KdNode's (kdtree_node.h), except that an interior node's above_child() is
/// the first of its two children: the lower child there, the upper child next to it.
#include <cstdint>
#include <deque>
#include <vector>

#include "accel/kdtree/kdtree_node.h"

namespace raylab {

struct alignas(64) KdNodeLine {
  KdNode node[8];
};

/// Regroups a tree in the build layout (lower child at index + 1, upper at above_child()) into
/// lines; node i of the result is line i / 8, slot i % 8, and node 0 is the root.
inline std::vector<KdNodeLine> kd_node_lines(const std::vector<KdNode>& tree) {
  std::vector<KdNodeLine> lines;
  if (tree.empty()) return lines;
  auto at = [&](std::uint32_t i) -> KdNode& { return lines[i / 8].node[i % 8]; };
  struct Pending {
    std::uint32_t lower, upper, parent;  // source children, and the placed parent
  };
  std::deque<Pending> pending;
  struct Placed {
    std::uint32_t src, dst;
  };
  // Places the nodes of `first` and, breadth first, their descendants while pairs fit the line.
  auto fill = [&](std::uint32_t base, std::uint32_t used, std::vector<Placed> queue) {
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const auto [src, dst] = queue[q];
      const KdNode& n = tree[src];
      at(dst) = n;
      if (n.is_leaf()) continue;
      const std::uint32_t lower = src + 1, upper = n.above_child();
      if (used + 2 <= 8) {
        at(dst).set_above_child(base + used);
        queue.push_back({lower, base + used});
        queue.push_back({upper, base + used + 1});
        used += 2;
      } else {
        pending.push_back({lower, upper, dst});
      }
    }
  };
  lines.emplace_back();
  fill(0, 2, {{0, 0}});  // slot 1 stays empty: pairs start at even slots
  while (!pending.empty()) {
    const Pending p = pending.front();
    pending.pop_front();
    const auto base = static_cast<std::uint32_t>(lines.size() * 8);
    lines.emplace_back();
    at(p.parent).set_above_child(base);
    fill(base, 2, {{p.lower, base}, {p.upper, base + 1}});
  }
  return lines;
}

}  // namespace raylab
