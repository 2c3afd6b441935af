#pragma once
/// The cells of a built tree, top-down: what its surface-area expectations sum over
/// (tree_features.h), and what an isotropic line must meet for a traversal without early exit to
/// visit them (the lecture's "probability of hitting a node is proportional to its surface area").
///
/// A kd-tree or octree cell and a BVH node are boxes; a BSP cell is a convex polyhedron. The
/// walk visits a parent before its children, depth first, in the order tree_features sums them.
#include <cstddef>
#include <functional>

#include "geometry/bounds.h"
#include "geometry/vec3.h"
#include "scene/primitive.h"

namespace raylab {

class ConvexCell;

struct StructureCell {
  Bounds3f box;                          ///< the cell's box (unused for a BSP cell)
  const ConvexCell* polytope = nullptr;  ///< a BSP cell; null for box cells
  double surface_area = 0.0;
  bool leaf = false;
  std::size_t primitives = 0;   ///< references a leaf holds (0 for interior cells and empty leaves)
  std::size_t test_groups = 0;  ///< SIMD groups a leaf's tests run in (wide BVHs: packets); 0: ⌈primitives/4⌉
  int depth = 0;                ///< the root: 0

  /// Whether the line {origin + t·direction, t real} meets the closed cell (for a BSP cell, as
  /// computed in double from its faces; on a box, the slab test in double).
  bool meets_line(const Vec3d& origin, const Vec3d& direction) const;
};

/// Whether walk_structure_cells can walk `accel`: the kd-tree, the octree, the BSP tree and the
/// BVH of every width.
bool has_structure_cells(const Aggregate& accel);

/// Calls `visit` on every cell of `accel`, parents first; the children of a cell are walked only
/// when `visit` returns true for it. Throws InputError when has_structure_cells(accel) is false.
void walk_structure_cells(const Aggregate& accel, const std::function<bool(const StructureCell&)>& visit);

}  // namespace raylab
