#pragma once
/// Building a kd-tree over a scene's own primitives: midpoint, median or SAH splits (the
/// lecture; Havran's thesis ch. 4), SAH by the sort or the event sweep (Wald and Havran 2006),
/// with split clipping (split_clipping.h).
#include <cstdint>
#include <vector>

#include "accel/kdtree/kdtree_config.h"
#include "accel/kdtree/kdtree_node.h"
#include "scene/scene.h"

namespace raylab {

struct KdTreeData {
  std::vector<KdNode> nodes;         ///< depth first; node 0 is the root
  std::vector<std::uint32_t> prims;  ///< leaf primitive lists, each sorted by id
  Bounds3f bounds;                   ///< the root box: the scene's bounds
  double sah_cost = 0.0;             ///< Σ interior C_trav·SA/SA(root) + Σ leaves C_isect·N·SA/SA(root)
  std::size_t leaves = 0;
  int depth = 0;  ///< of the deepest leaf
};

/// Builds the tree. `scene` must not be instanced. Single-threaded and deterministic.
KdTreeData build_kdtree(const Scene& scene, const KdTreeConfig& config);

/// Calls f(box, first, count) for every leaf, with the closed leaf box and its primitive range in
/// data.prims.
template <class F>
void for_each_kd_leaf(const KdTreeData& data, F&& f) {
  struct Item {
    std::uint32_t node;
    Bounds3f box;
  };
  std::vector<Item> todo = {{0, data.bounds}};
  while (!todo.empty()) {
    const Item it = todo.back();
    todo.pop_back();
    const KdNode& n = data.nodes[it.node];
    if (n.is_leaf()) {
      f(it.box, n.first, n.count());
      continue;
    }
    todo.push_back({n.above_child(), it.box.above(n.axis(), n.split)});
    todo.push_back({it.node + 1, it.box.below(n.axis(), n.split)});
  }
}

}  // namespace raylab
