#pragma once
/// Building an octree: centre splits, placement and clipping as the kd-tree's
/// (split_clipping.h), cost-based termination (octree_config.h).
#include <cstdint>
#include <vector>

#include "accel/octree/octree_config.h"
#include "accel/octree/octree_node.h"
#include "scene/scene.h"

namespace raylab {

struct OctreeData {
  std::vector<OctNode> nodes;        ///< node 0 is the root
  std::vector<std::uint32_t> prims;  ///< leaf primitive lists, each sorted by id
  Bounds3f bounds;                   ///< the root box: the scene's bounds, padded along flat axes
  double sah_cost = 0.0;
  std::size_t leaves = 0;
  int depth = 0;
};

/// Builds the octree. `scene` must not be instanced. Deterministic.
OctreeData build_octree(const Scene& scene, const OctreeConfig& config);

/// Calls f(box, first, count) for every leaf, the empty children that are not stored included
/// (count 0).
template <class F>
void for_each_octree_leaf(const OctreeData& data, F&& f) {
  struct Item {
    std::uint32_t node;
    Bounds3f box;
  };
  std::vector<Item> todo = {{0, data.bounds}};
  while (!todo.empty()) {
    const Item it = todo.back();
    todo.pop_back();
    const OctNode& n = data.nodes[it.node];
    if (n.is_leaf()) {
      f(it.box, n.first, n.count);
      continue;
    }
    for (unsigned i = 0; i < 8; ++i)
      if (!octree_child_exists(it.box, i)) continue;
      else if (n.has_child(i)) todo.push_back({n.child(i), octree_child_box(it.box, i)});
      else f(octree_child_box(it.box, i), 0u, 0u);
  }
}

}  // namespace raylab
