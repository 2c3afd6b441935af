#pragma once
/// The lecture's SAH cost of splitting a node (MacDonald and Booth 1990), with the empty-space
/// bonus of Wald and Havran 2006 (their λ(p) = 1 - bonus when one side is empty) and a per-leaf
/// visit cost C_leaf (0 unless a fitted cost model supplies one, lib/cost):
///
///   Cost = C_trav + (SA(L)/SA·leaf(N(L)) + SA(R)/SA·leaf(N(R)))·(1 - bonus if N(L)·N(R) = 0),
///   leaf(N) = C_leaf + N·C_isect for N > 0, and 0 for an empty leaf (traversals skip those).
///
/// A node is split only when its best split costs less than the leaf.
#include <cstddef>

#include "geometry/bounds.h"

namespace raylab {

struct SahCost {
  double c_trav = 1.0;       ///< cost of one traversal step
  double c_isect = 1.5;      ///< cost of one ray-primitive test (the lecture's "highly optimized" 1:1.5)
  double empty_bonus = 0.2;  ///< Wald and Havran's 0.8 factor for cutting off empty space
  double c_leaf = 0.0;       ///< cost of visiting a non-empty leaf, beyond its tests

  double leaf(std::size_t n) const { return n == 0 ? 0.0 : c_isect * static_cast<double>(n) + c_leaf; }

  /// Cost of splitting a node of surface area `sa` into children of areas sa_l, sa_r holding
  /// n_l and n_r primitives. (The C_leaf part is a separate addend, so that C_leaf = 0 gives
  /// the textbook formula to the last bit.)
  double split(double sa, double sa_l, double sa_r, std::size_t n_l, std::size_t n_r) const {
    const double bonus = (n_l == 0 || n_r == 0) ? 1.0 - empty_bonus : 1.0;
    const double visited = (n_l > 0 ? sa_l / sa : 0.0) + (n_r > 0 ? sa_r / sa : 0.0);
    return c_trav + bonus * c_isect * (sa_l / sa * static_cast<double>(n_l) + sa_r / sa * static_cast<double>(n_r)) +
           bonus * c_leaf * visited;
  }
};

/// Surface area in double precision (the SAH ranks splits by it).
inline double surface_area_d(const Bounds3f& b) {
  if (b.empty()) return 0.0;
  const double dx = double(b.hi.x) - b.lo.x, dy = double(b.hi.y) - b.lo.y, dz = double(b.hi.z) - b.lo.z;
  return 2.0 * (dx * dy + dy * dz + dz * dx);
}

}  // namespace raylab
