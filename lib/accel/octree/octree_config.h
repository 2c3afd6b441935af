#pragma once
/// Parameters of the octree (`octree:key=value,...`).
#include "accel/common/kernel_choice.h"
#include "accel/kdtree/sah_cost.h"
#include "accel/kdtree/split_clipping.h"

namespace raylab {

enum class OctreeTraversal {
  revelles,  ///< Revelles, Ureña and Lastra 2000: parametric, first-node and next-node tables, mirroring
  kd,        ///< the three centre planes of a node taken as three kd-tree splits
};

struct OctreeConfig {
  ClipMode clip = ClipMode::exact;  ///< placement and clipping as in the kd-tree (split_clipping.h)
  /// A node is split at its centre when C_trav + Σ SA(child)/SA·leaf(N(child)) < leaf(N) (SahCost::leaf),
  /// the kd-tree's SAH applied to the eight children (no empty-space bonus). Defaults as the kd-tree's.
  SahCost cost;
  /// Safety depth limit; 0 means 3 + ceil(log8 N), at most 20.
  int max_depth = 0;
  /// Remember the last primitives tested by a ray and skip repeats.
  bool mailbox = false;
  OctreeTraversal traversal = OctreeTraversal::revelles;
  KernelChoice kernel = KernelChoice::watertight;
};

int octree_max_depth(const OctreeConfig& config, std::size_t n);

}  // namespace raylab
