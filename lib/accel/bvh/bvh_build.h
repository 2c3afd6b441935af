#pragma once
/// Building the binary BVH (bvh_node.h): the lecture's midpoint and median splits, the
/// full-sweep and binned SAH, and spatial splits (SBVH). Builders are deterministic: equal
/// inputs give equal trees with any thread count. Both entry points then optimise the tree as
/// config.optimize asks (bvh_optimize.h), deterministically unless config.optimize_budget is set.
#include <vector>

#include "accel/bvh/bvh_config.h"
#include "accel/bvh/bvh_node.h"
#include "scene/scene.h"

namespace raylab {

/// An object-partition BVH over `boxes` (the references are box indices). The `spatial` builder
/// needs the geometry and is not available here: it is treated as `binned`. Empty boxes are
/// allowed (they are never hit); no boxes give a tree without nodes.
Bvh2 build_bvh_over_boxes(const std::vector<Bounds3f>& boxes, const BvhConfig& config);

/// A BVH over the primitives of `scene`, which must not be instanced.
Bvh2 build_bvh(const Scene& scene, const BvhConfig& config);

/// The SAH cost of a finished tree (bvh_config.h's BvhSahCost), with areas relative to the
/// root's: Σ_interior c_trav·SA(n)/SA(root) + Σ_leaves c_isect·N(n)·SA(n)/SA(root), N in whole leaf blocks.
double bvh_sah_cost(const Bvh2& bvh, const BvhSahCost& cost);

/// Depth of the deepest leaf (the root has depth 0).
int bvh_depth(const Bvh2& bvh);

}  // namespace raylab
