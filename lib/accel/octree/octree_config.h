#pragma once
/// Parameters of the octree (`octree:key=value,...`).
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
  /// kd-tree's, C_trav = 8: an interior visit of the Revelles walk costs about 5× a triangle test
  /// (the fitted cost model, data/cost/default_model.json: 58 ns per node against 11 ns per test),
  /// not the kd-tree's 1:1.5; with C_trav = 1 the octree of a 16k-triangle bunny had 211,360
  /// nodes and traced 0.43× the kd-tree's throughput, with 8 about 20,000 nodes and 0.5×.
  SahCost cost{8.0};
  /// Safety depth limit; 0 means 3 + ceil(log8 N), at most 20.
  int max_depth = 0;
  /// Remember the last primitives tested by a ray and skip repeats.
  bool mailbox = false;
  OctreeTraversal traversal = OctreeTraversal::stack;
  KernelChoice kernel = KernelChoice::watertight;
};

int octree_max_depth(const OctreeConfig& config, std::size_t n);

}  // namespace raylab
