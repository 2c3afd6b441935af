#pragma once
/// Parameters of the BSP tree (`bsp:key=value,...`).
#include <optional>

#include "accel/common/fitted_cost.h"
#include "accel/common/kernel_choice.h"
#include "accel/kdtree/kdtree_config.h"
#include "accel/kdtree/sah_cost.h"

namespace raylab {

struct BspConfig {
  /// The kd-tree's SAH (sah_cost.h) on the areas of the convex cells. Defaults as the kd-tree's
  /// (kdtree_config.h: C_trav 1, C_isect 0.07); the spec reader sets them.
  SahCost cost{1.0, kKdDefaultIsect, 0.2, 0.0};
  /// `cost=MODEL` of the spec, which the build resolves into `cost` (fitted_cost.h).
  std::optional<FittedCostRequest> fitted_cost;
  /// Candidate supporting planes of the node's triangles tried per node (auto-partition),
  /// taken evenly spaced through the node's list.
  int triangle_candidates = 6;
  /// Axis-aligned candidates per axis: the quantiles k/(n+1) of the primitives' centres.
  int axis_candidates = 2;
  /// Nodes with at most this many primitives become leaves without trying a split.
  int leaf_size = 4;
  /// Safety depth limit; 0 means 6 + 1.3·log2(N), at most 48.
  int max_depth = 0;
  KernelChoice kernel = KernelChoice::certified;
};

int bsp_max_depth(const BspConfig& config, std::size_t n);

}  // namespace raylab
