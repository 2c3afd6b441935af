#pragma once
/// A per-ray mailbox (the lecture's "primitive intersection cache"; Amanatides and Woo 1987,
/// Arnaldi et al. 1987), kept on the tracing thread's stack instead of in the primitives, so it
/// needs no ray numbers and no shared mutable state.
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <limits>

#include "geometry/ray.h"

namespace raylab {

/// Direct-mapped by primitive id: a colliding primitive evicts the previous one, which then is
/// merely tested again. Each entry remembers the outcome of the test, not just that it ran: with
/// in-cell acceptance a primitive hit beyond the cell it was tested in must still be found in a
/// later cell, so the hit (t, u, v) is stored and re-used. A miss (t = +inf) stays a miss, since
/// the closest-hit bound only shrinks along the ray.
class RayMailbox {
 public:
  static constexpr unsigned kSize = 32;  ///< power of two
  struct Entry {
    float t, u, v;
  };

  /// Clears the ids only (128 bytes): the outcomes are read only under a matching id.
  RayMailbox() { std::fill(std::begin(prims_), std::end(prims_), kInvalidId); }
  /// The stored outcome for `prim`, or nullptr when it has not been tested (or was evicted).
  const Entry* find(std::uint32_t prim) const {
    const unsigned slot = prim & (kSize - 1);
    return prims_[slot] == prim ? &entries_[slot] : nullptr;
  }
  void store_miss(std::uint32_t prim) { store(prim, {std::numeric_limits<float>::infinity(), 0.0f, 0.0f}); }
  void store_hit(std::uint32_t prim, const Hit& h) { store(prim, {h.t, h.u, h.v}); }

 private:
  void store(std::uint32_t prim, const Entry& e) {
    const unsigned slot = prim & (kSize - 1);
    prims_[slot] = prim;
    entries_[slot] = e;
  }
  std::uint32_t prims_[kSize];
  Entry entries_[kSize];
};

}  // namespace raylab
