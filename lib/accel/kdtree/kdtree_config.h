#pragma once
/// Parameters of the kd-tree (`kdtree:key=value,...`); the factory fills them and rejects others.
#include <cstdint>
#include <optional>

#include "accel/common/fitted_cost.h"
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

/// The default C_isect for C_trav = 1 (also the BSP tree's, bsp_config.h). A leaf test is one
/// 8-wide test of two packets (kd_test_packed_leaf) while a node visit is a dependent load and a
/// hard-to-predict branch, so a triangle costs far less than a node: the lecture's 1:1.5 splits
/// far too deep (sphere:n=262144: 1.3M nodes against 196k), and so did 1:0.2, the ratio of the
/// lab's fitted constants (data/cost/default_model.json, families.kdtree.builder: C_isect
/// 1.43 ns per test against C_trav 7.28 ns per node, fitted with 4-wide leaves; `cost=default`
/// applies them). On BM_KdTrace (bench_kdtree: bunny00, armadillo, ChineseDragon-10kv; passes
/// alternating with 1:0.2 in one process, CPU time, geometric mean of the medians of 2 runs)
/// C_isect 0.17 / 0.1 / 0.07 / 0.05 / 0.03 traced 1.03 / 1.10 / 1.13 / 1.12 / 1.05x as fast on
/// primary rays and 1.02 / 1.07 / 1.10 / 1.09 / 1.04x on diffuse rays, and 0.07 takes 72 bytes
/// per triangle instead of 105 (the BSP tree with 0.07: 1.18x primary, 1.21x diffuse, 1 run).
/// Fixed here rather than read from the model, so that refitting it does not change the tree.
inline constexpr double kKdDefaultIsect = 0.07;

struct KdTreeConfig {
  KdBuilder builder = KdBuilder::sah;
  KdSweep sweep = KdSweep::events;
  ClipMode clip = ClipMode::exact;
  KdTraversal traversal = KdTraversal::stack;
  /// C_trav = 1, C_isect = 0.07 (kKdDefaultIsect), empty bonus 0.2.
  SahCost cost{1.0, kKdDefaultIsect, 0.2, 0.0};
  /// `cost=MODEL` of the spec, which the build resolves into `cost` (fitted_cost.h).
  std::optional<FittedCostRequest> fitted_cost;
  /// Safety depth limit; 0 means the pbrt-v3 rule 8 + 1.3·log2(N) (pbrt-v3 §4.4.1), capped at 64.
  int max_depth = 0;
  /// midpoint and median stop at this many primitives (SAH stops on cost alone).
  int leaf_size = 4;
  /// Remember the last primitives tested by a ray and skip repeats (Amanatides and Woo 1987).
  bool mailbox = false;
  KernelChoice kernel = KernelChoice::certified;
};

/// The depth limit actually used for `n` primitives.
int kd_max_depth(const KdTreeConfig& config, std::size_t n);

}  // namespace raylab
