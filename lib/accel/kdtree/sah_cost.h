#pragma once
/// The lecture's SAH cost of splitting a node (MacDonald and Booth 1990), with the empty-space
/// bonus of Wald and Havran 2006 (their λ(p) = 1 - bonus when one side is empty):
///
///   Cost = C_trav + (SA(L)/SA·N(L)·C_isect + SA(R)/SA·N(R)·C_isect)·(1 - bonus if N(L)·N(R) = 0)
///
/// and of a leaf: N·C_isect. A node is split only when its best split costs less than the leaf.
#include <cstddef>

#include "geometry/bounds.h"

namespace raylab {

struct SahCost {
  double c_trav = 1.0;       ///< cost of one traversal step
  double c_isect = 1.5;      ///< cost of one ray-primitive test (the lecture's "highly optimized" 1:1.5)
  double empty_bonus = 0.2;  ///< Wald and Havran's 0.8 factor for cutting off empty space

  double leaf(std::size_t n) const { return c_isect * static_cast<double>(n); }

  /// Cost of splitting a node of surface area `sa` into children of areas sa_l, sa_r holding
  /// n_l and n_r primitives.
  double split(double sa, double sa_l, double sa_r, std::size_t n_l, std::size_t n_r) const {
    const double bonus = (n_l == 0 || n_r == 0) ? 1.0 - empty_bonus : 1.0;
    return c_trav + bonus * c_isect * (sa_l / sa * static_cast<double>(n_l) + sa_r / sa * static_cast<double>(n_r));
  }
};

/// Surface area in double precision (the SAH ranks splits by it).
inline double surface_area_d(const Bounds3f& b) {
  if (b.empty()) return 0.0;
  const double dx = double(b.hi.x) - b.lo.x, dy = double(b.hi.y) - b.lo.y, dz = double(b.hi.z) - b.lo.z;
  return 2.0 * (dx * dy + dy * dz + dz * dx);
}

}  // namespace raylab
