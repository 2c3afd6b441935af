#pragma once
/// The triangles a grid's cells reference, copied out of the scene in the order the cells first
/// reference them, with the cell lists renumbered to index the copy. A cell's test then reads 36
/// contiguous bytes per triangle instead of an index triple and three vertices, and cells that
/// are near each other in the grid read triangles that are near each other in memory, whatever
/// order the scene lists them in (grass lists its blades in random positions).
#include <cstdint>
#include <vector>

#include "accel/common/build_array_allocator.h"
#include "geometry/vec3.h"
#include "scene/scene.h"

namespace raylab {

struct CellTriangles {
  struct Triangle {
    Vec3f v0, v1, v2;
  };
  BuildArray<Triangle> tris;          ///< by local id
  BuildArray<std::uint32_t> prim_of;  ///< local id → the scene's primitive id

  std::size_t bytes() const { return tris.size() * sizeof(Triangle) + prim_of.size() * sizeof(std::uint32_t); }
};
static_assert(sizeof(CellTriangles::Triangle) == 36);

/// The triangles of `scene` (which holds no sphere) with local ids 0, 1, ... in the order of `prim_of`.
CellTriangles copy_cell_triangles(const Scene& scene, BuildArray<std::uint32_t> prim_of);

/// Renumbers the primitive ids in refs[0, n) to local ids, 0, 1, ... in order of first
/// appearance, and returns the copied triangles. A scene that holds a sphere is left as it is (the
/// result is empty and `refs` keeps the scene's ids): cells then test the scene's primitives.
CellTriangles renumber_cell_triangles(const Scene& scene, std::uint32_t* refs, std::size_t n);

}  // namespace raylab
