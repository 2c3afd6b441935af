#pragma once
/// Placing primitives in the cells of one grid (the lecture's preprocessing step 3), stored
/// compactly: one index array and per-cell offsets (CSR), built by a counting sort.
#include <cstdint>
#include <vector>

#include "accel/common/build_array_allocator.h"
#include "accel/grid/cell_triangles.h"
#include "accel/grid/grid_config.h"
#include "accel/grid/grid_geometry.h"
#include "scene/scene.h"

namespace raylab {

/// What the references of cell lists are.
enum class CellRefIds {
  primitive,    ///< the scene's primitive ids
  visit_order,  ///< positions in CellLists::triangles, the order placement visited the primitives (triangles only)
};

/// Cell c holds refs[offsets[c] .. offsets[c+1]).
struct CellLists {
  BuildArray<std::uint32_t> offsets;       ///< cell_count + 1 entries
  BuildArray<std::uint32_t> refs;  ///< primitive ids, or positions in `triangles`
  CellTriangles triangles;         ///< with CellRefIds::visit_order: the triangles in visit order; else empty

  std::uint32_t count(std::size_t c) const { return offsets[c + 1] - offsets[c]; }
  std::size_t bytes() const { return (offsets.size() + refs.size()) * sizeof(std::uint32_t); }
};

/// Places `prims` (ids of `scene`, which must not be instanced) in the cells of `grid`, every cell
/// widened by `margin` on each side (grid_geometry.h). Primitives are visited in the order of the
/// index of the cell of their bounds' lowest corner, which is the order of every cell's list:
///  - bbox: the cells the primitive's bounding box overlaps; two passes (count, then fill) over
///    the cell ranges of the primitives.
///  - exact: among those, the cells whose closed (widened) box the triangle meets, decided by
///    CGAL's exact predicate (exact_triangle_intersects_box); a sphere is kept when the distance
///    from its centre to the box, evaluated in double, is at most its radius·(1 + 1e-6) + margin
///    (conservative: double rounding is far below that slack).
/// Throws InputError when the references would overflow 32-bit offsets.
CellLists place_primitives(const Scene& scene, const std::uint32_t* prims, std::size_t n, const GridGeometry& grid,
                           GridPlacement placement, float margin);

/// The same for all primitives of the scene (ids 0 .. primitive_count-1), with references of kind `ids`.
CellLists place_all_primitives(const Scene& scene, const GridGeometry& grid, GridPlacement placement, float margin,
                               CellRefIds ids = CellRefIds::primitive);

/// The number of references place_all_primitives stores with placement bbox or clipped (exact
/// is not supported and throws std::invalid_argument), the primitives' cells found as placement
/// finds them, in scene order, and only counted: the cost of finding the cells alone.
std::size_t count_placed_references(const Scene& scene, const GridGeometry& grid, GridPlacement placement, float margin);

}  // namespace raylab
