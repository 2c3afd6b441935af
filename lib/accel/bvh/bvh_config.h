#pragma once
/// Parameters of the BVH (`bvh:key=value,...`); the factory fills them and rejects others.
#include <cstddef>
#include <optional>

#include "accel/common/fitted_cost.h"
#include "accel/common/kernel_choice.h"

namespace raylab {

enum class BvhBuilder {
  midpoint,  ///< the spatial middle of the centroid bounds' longest axis
  median,    ///< the median centroid along the centroid bounds' longest axis
  sweep,     ///< full-sweep SAH over all three axes (the lecture's "sweep build")
  binned,    ///< binned SAH (Wald 2007), parallel with TBB
  spatial,   ///< SBVH: binned SAH plus spatial splits (Stich, Friedrich and Dietrich 2009)
};

/// Optimisation of the binary tree after the build, before any wide collapse (bvh_optimize.h).
enum class BvhOptimize {
  none,
  reinsert,  ///< reinsertion (Bittner, Hapala and Havran 2013) under `cost`
};

/// How a wide tree stores its child boxes.
enum class BvhNodes {
  full,       ///< float boxes (WideBvhNode)
  quantized,  ///< 8-bit boxes relative to the node's own, enlarged outward (quantized_wide_node.h)
};

/// How the binary tree is collapsed into the wide one (wide_bvh.h).
enum class BvhCollapse {
  greedy,  ///< each wide node opens its interior child of largest area until it has N children
  sah,     ///< the collapse of least wide SAH cost, leaves merged where cheaper (dynamic programming)
};

/// What a wide tree's leaves hold.
enum class BvhLeaves {
  packed,   ///< TrianglePackets: each triangle's vertices copied, SoA (packed_triangles.h)
  indexed,  ///< IndexedLeaves: packets of vertex indices into one copy of the leaves' vertices, gathered at each test
};

/// The SAH of a BVH (MacDonald and Booth 1990; the lecture's Cost = N_A·S_A + N_B·S_B):
///   node cost = c_trav + c_isect·(N_A·SA(A) + N_B·SA(B)) / SA(node),   leaf cost = c_isect·N,
/// where a count N is rounded up to whole blocks of `leaf_block` primitives (bvh_leaf_units).
struct BvhSahCost {
  double c_trav = 1.0;
  double c_isect = 1.0;
  /// Primitives a leaf test handles at once, a power of two: Embree's SAH counts triangles in
  /// blocks of 4 (leaf cost = area·⌈N/4⌉), the packet width of its Triangle4 leaves. 1 counts
  /// primitives.
  unsigned leaf_block = 1;
};

/// The wide SAH of the collapse of a binary tree into a 4- or 8-wide one (wide_bvh.h,
/// BvhCollapse::sah), per unit of area: a wide node visit (its N child boxes tested at once) and a
/// packet test (kPacketWidth primitives at once). bench_bvh against Embree, robust and robust=off,
/// 3 repetitions each: 3:1 traced as fast as 2:1 and 4:1 (the bunny refined to 1.2·10^6
/// triangles, walls:n=2000,angle=60), 2:1 faster than 1:1 and 0.5:1 (that bunny,
/// grass:blades=60000); differences under ~5% are within the noise. A larger c_node merges more
/// leaves: fewer nodes and bytes, more tests.
struct WideSahCost {
  double c_node = 3.0;
  double c_packet = 1.0;
};

/// N primitives counted in whole blocks of `block` (a power of two): block·⌈N/block⌉, N itself
/// for block 1. A mask, not a division: the split sweeps call it for every candidate.
inline unsigned bvh_leaf_units(std::size_t n, unsigned block) {
  return static_cast<unsigned>((n + block - 1) & ~static_cast<std::size_t>(block - 1));
}

struct BvhConfig {
  BvhBuilder builder = BvhBuilder::binned;
  /// Children per node of the traversed tree: 2 (BVH2, the lecture's stack traversal) or a wide
  /// tree collapsed from the binary one, 4 or 8 (SIMD box tests).
  int width = 2;
  /// The builder makes a leaf of at most this many primitives (SAH may stop earlier); the spec
  /// default is 4 at width 2, 16 (four triangle packets) for the SAH builders at width 8, and 8
  /// (two packets) otherwise.
  int max_leaf_size = 4;
  /// The most SAH bins per axis (binned and spatial builders): small nodes use fewer (4 + n/20,
  /// as Embree), and spatial splits use half as many.
  int bins = 32;
  BvhSahCost cost;
  /// `cost=MODEL` of the spec, which the build resolves into `cost` (fitted_cost.h).
  std::optional<FittedCostRequest> fitted_cost;
  /// SBVH: a spatial split is tried only where the object split's child overlap exceeds
  /// alpha·SA(root) (Stich et al. 2009 §4.3).
  double spatial_alpha = 1e-5;
  /// SBVH: the references may grow to at most (1 + max_duplication)·N, N the primitive count.
  double max_duplication = 1.0;
  BvhOptimize optimize = BvhOptimize::none;
  /// Optimisation passes at most; 0 runs until the SAH cost stops improving (bvh_optimize.h).
  int optimize_passes = 0;
  /// Wall time of the optimisation passes at most, in seconds, asked every 64 nodes of a pass; 0
  /// gives no limit (a limit makes the tree depend on the machine's speed). Setting up the passes
  /// and writing the tree back are not counted (what the whole optimisation adds to the build:
  /// docs/bvh_scale, bench_bvh_build).
  double optimize_budget = 0.0;
  /// How the wide tree (width 4 or 8) is collapsed from the binary one.
  BvhCollapse collapse = BvhCollapse::sah;
  /// The wide SAH of BvhCollapse::sah. With `cost=MODEL` it is the model's: its wide families'
  /// constants are per wide node visit and per primitive test (c_node = c_trav, c_packet =
  /// kPacketWidth·c_isect), and the binary tree keeps `cost`'s defaults (read_bvh_config).
  WideSahCost wide_cost;
  /// Child boxes of the wide tree (width 4 or 8).
  BvhNodes nodes = BvhNodes::full;
  /// Leaves of the wide tree (width 4 or 8).
  BvhLeaves leaves = BvhLeaves::packed;
  /// Ize's conservative slab test and `kernel`; off gives the `fast` variant (plain slab test,
  /// Moller-Trumbore, whatever `kernel` says), held by the oracle suite to its stated bound.
  bool robust = true;
  /// The triangle/sphere kernel of the robust traversal (the spec rejects kernel=certified with
  /// robust=off, and takes watertight as robust=off's default).
  KernelChoice kernel = KernelChoice::certified;
  /// Build threads; 0 means every hardware thread.
  int threads = 0;
};

}  // namespace raylab
