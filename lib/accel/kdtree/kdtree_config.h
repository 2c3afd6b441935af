#pragma once
/// Parameters of the kd-tree (`kdtree:key=value,...`); the factory fills them and rejects others.
#include <cstdint>

#include "accel/common/kernel_choice.h"
#include "accel/kdtree/split_clipping.h"
#include "accel/kdtree/sah_cost.h"

namespace raylab {

enum class KdBuilder {
  midpoint,  ///< the spatial median of the node's longest axis
  median,    ///< the median of the primitives' bound centres along the node's longest axis
  sah,       ///< the surface area heuristic (MacDonald and Booth 1990; Wald and Havran 2006)
};

enum class KdSweep {
  sort,    ///< sort each node's candidates again: O(N log² N) (the lecture's sweep)
  events,  ///< presorted events kept sorted through splits: O(N log N) (Wald and Havran 2006 §4.3)
};

enum class KdTraversal {
  recursive,  ///< Kaplan/Arvo/Jansen recursive in-order traversal
  stack,      ///< the same order with an explicit stack (Havran's thesis, TA_B^rec), over nodes in cache lines
};

/// The default C_isect for C_trav = 1: the ratio of the lab's fitted kd-tree constants
/// (data/cost/default_model.json, families.kdtree.builder: C_isect 1.43 ns per test against
/// C_trav 7.28 ns per node, i.e. 0.196), which `cost=default` applies. A leaf test is one
/// 4-wide packet test while a node visit is a dependent load, so the lecture's 1:1.5 splits far
/// too deep (sphere:n=262144: 1.3M nodes against 196k). On BM_KdTrace (bench_kdtree: bunny00,
/// armadillo, ChineseDragon-10kv) 1:0.2 traced ~20-30% faster than 1:1.5 on primary and diffuse
/// rays, in less than half the memory (noisy shared machine; ratios to Embree in the same run).
/// Fixed here rather than read from the model, so that refitting it does not change the tree.
inline constexpr double kKdDefaultIsect = 0.2;

struct KdTreeConfig {
  KdBuilder builder = KdBuilder::sah;
  KdSweep sweep = KdSweep::events;
  ClipMode clip = ClipMode::exact;
  KdTraversal traversal = KdTraversal::stack;
  /// C_trav = 1, C_isect = 0.2 (kKdDefaultIsect), empty bonus 0.2.
  SahCost cost{1.0, kKdDefaultIsect, 0.2, 0.0};
  /// Safety depth limit; 0 means the pbrt-v3 rule 8 + 1.3·log2(N) (pbrt-v3 §4.4.1), capped at 64.
  int max_depth = 0;
  /// midpoint and median stop at this many primitives (SAH stops on cost alone).
  int leaf_size = 4;
  /// Remember the last primitives tested by a ray and skip repeats (Amanatides and Woo 1987).
  bool mailbox = false;
  KernelChoice kernel = KernelChoice::watertight;
};

/// The depth limit actually used for `n` primitives.
int kd_max_depth(const KdTreeConfig& config, std::size_t n);

}  // namespace raylab
