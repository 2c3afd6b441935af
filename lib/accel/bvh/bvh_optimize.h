#pragma once
/// Post-build optimisation of the binary BVH by reinsertion, after Bittner, Hapala and Havran,
/// "Fast Insertion-Based Optimization of Bounding Volume Hierarchies" (Computer Graphics Forum
/// 32(1), 2013): each pass takes the interior nodes of largest inefficiency and reinserts each
/// one's two child subtrees, the larger first, each at the position found by a branch-and-bound
/// search from the root that least increases the SAH cost (bvh_config.h's BvhSahCost), until the
/// cost stops improving or the budget ends. Unlike the paper, which removes a node and reinserts
/// both children unconditionally (the cost may rise for a while), a child moves alone, as a whole
/// subtree with its parent node (as in Meister and Bittner, "Parallel Reinsertion for Bounding
/// Volume Hierarchy Optimization", Eurographics 2018), and only where the cost drops: greedy
/// unconditional reinsertion raised the cost of binned-SAH trees here at every pass.
///
/// Whole subtrees move, so every leaf keeps its primitives (the leaf-size limits of the build
/// still hold, also after the wide collapse) and the leaves' SAH term is invariant: the cost
/// changes only through the interior nodes' areas, so the tree minimising Σ_interior SA is the
/// SAH optimum for any c_trav > 0 and c_isect (the constants scale the reported cost only).
#include <cstddef>

#include "accel/bvh/bvh_config.h"
#include "accel/bvh/bvh_node.h"

namespace raylab {

/// What one optimisation did.
struct BvhOptimizeStats {
  double cost_before = 0.0;  ///< bvh_sah_cost of the input tree
  double cost_after = 0.0;   ///< bvh_sah_cost of the returned tree (<= cost_before)
  int passes = 0;            ///< passes run (each removes a batch of nodes and reinserts their children)
  std::size_t moves = 0;     ///< subtrees moved over all passes
  double seconds = 0.0;      ///< wall time of the optimisation
};

/// Reinsertion-optimises `bvh` in place under `cost` and returns what it did. The result holds
/// the same leaves (node count, leaf boxes and the `prims` array unchanged) under new interior
/// nodes, laid out depth first with siblings adjacent as the builders lay them out. Every move
/// lowers the cost, so the cost never rises; a result deeper than kBvhMaxDepth is discarded (the
/// input stays). Stops when `max_passes` (0: no limit) passes ran, when `budget_seconds` (0: no
/// limit) have passed since the passes began (asked every 64 nodes of a pass; the tree then
/// depends on timing), or when fifty passes in a row lowered the cost by less than 0.1% in all.
/// Each pass chooses 2% of the interior nodes, none chosen in the 50 passes before. The moves
/// run on one thread; `threads` other than 1 (0: the TBB arena's) sets up the tree and ranks each
/// pass's nodes in TBB tasks, with the same result. Deterministic without a time budget.
BvhOptimizeStats optimize_bvh_reinsertion(Bvh2& bvh, const BvhSahCost& cost, int max_passes = 0,
                                          double budget_seconds = 0.0, int threads = 1);

}  // namespace raylab
