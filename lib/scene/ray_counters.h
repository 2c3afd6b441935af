#pragma once
/// Per-ray work counters. Traversal code is templated on the counter type: `RayCounters` counts,
/// `NoCounters` compiles every increment away, so timed runs pay nothing for them.
#include <cstdint>

namespace raylab {

struct RayCounters {
  std::uint64_t nodes = 0;          ///< interior nodes (or cells) visited
  std::uint64_t leaves = 0;         ///< leaves visited
  std::uint64_t prim_tests = 0;     ///< ray-primitive intersection tests
  std::uint64_t prim_hits = 0;      ///< tests that found a hit closer than the closest so far (pbrt's "Ray/Tri hits")
  std::uint64_t mailbox_skips = 0;  ///< tests saved by a mailbox
  /// Rays that took the exact path (made an ExactFirstHit: the certified kernel's fallback, or
  /// every ray of the exact kernels), counted once per ray by AggregateBase.
  std::uint64_t exact_fallbacks = 0;
  /// Rays for which the certified kernel ran its double (interval) stage, counted once per ray
  /// as exact_fallbacks; the rest were decided by its static filters alone (in float, and the
  /// plane's determinants in double).
  std::uint64_t interval_stage = 0;

  static constexpr bool enabled = true;
  void node() { ++nodes; }
  void leaf() { ++leaves; }
  void prim_test() { ++prim_tests; }
  void prim_hit() { ++prim_hits; }
  void mailbox_skip() { ++mailbox_skips; }
  RayCounters& operator+=(const RayCounters& o) {
    nodes += o.nodes; leaves += o.leaves; prim_tests += o.prim_tests; prim_hits += o.prim_hits; mailbox_skips += o.mailbox_skips;
    exact_fallbacks += o.exact_fallbacks;
    interval_stage += o.interval_stage;
    return *this;
  }
};

struct NoCounters {
  static constexpr bool enabled = false;
  void node() {}
  void leaf() {}
  void prim_test() {}
  void prim_hit() {}
  void mailbox_skip() {}
};

}  // namespace raylab
