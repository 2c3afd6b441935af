#pragma once
/// Parameters of the octree (`octree:key=value,...`).
#include <optional>

#include "accel/common/fitted_cost.h"
#include "accel/common/kernel_choice.h"
#include "accel/kdtree/sah_cost.h"
#include "accel/kdtree/split_clipping.h"

namespace raylab {

enum class OctreeTraversal {
  stack,     ///< iterative, explicit stack, crossings ordered per node (octree_traverse_stack)
  revelles,  ///< Revelles, Ureña and Lastra 2000: parametric, first-node and next-node tables, mirroring
  kd,        ///< the three centre planes of a node taken as three kd-tree splits
};

struct OctreeConfig {
  ClipMode clip = ClipMode::exact;  ///< placement and clipping as in the kd-tree (split_clipping.h)
  /// A node is split at its centre when C_trav + Σ SA(child)/SA·leaf(N(child)) < leaf(N) (SahCost::leaf),
  /// the kd-tree's SAH applied to the eight children (no empty-space bonus). C_isect as the
  /// kd-tree's, C_trav = 48, measured: with leaves tested 4-wide (octree_pack_leaves) and the
  /// stack traversal, exp_spatial quick (bunny 16k, dragon, stadium, walls, grass 10k; primary
  /// rays) gave the geometric mean throughput 0.57x the kd-tree's at C_trav 8, 0.77x at 24 and
  /// 32, 0.85x at 48 and 64, 0.81x at 96 (diffuse rays: 0.74x at 24, 0.79x at 32, 0.81x at 48).
  /// A deeper tree visits fewer triangles but more nodes, each a dependent load into a
  /// structure several times the kd-tree's size (references are copied into 40-byte packet
  /// lanes), and a leaf of up to 4 triangles costs one packet test whatever its count.
  SahCost cost{48.0};
  /// `cost=MODEL` of the spec, which the build resolves into `cost` (fitted_cost.h).
  std::optional<FittedCostRequest> fitted_cost;
  /// Safety depth limit; 0 means 3 + ceil(log8 N), at most 20.
  int max_depth = 0;
  /// Remember the last primitives tested by a ray and skip repeats.
  bool mailbox = false;
  OctreeTraversal traversal = OctreeTraversal::stack;
  KernelChoice kernel = KernelChoice::certified;
};

int octree_max_depth(const OctreeConfig& config, std::size_t n);

}  // namespace raylab
