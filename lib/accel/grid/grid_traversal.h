#pragma once
/// The 3D-DDA of Amanatides and Woo ("A Fast Voxel Traversal Algorithm for Ray Tracing",
/// Eurographics 1987): the 6-connected sequence of cells a ray pierces, each with its t-interval.
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/grid/grid_geometry.h"
#include "geometry/ray.h"

namespace raylab {

/// Calls `visit(cell_index, t_enter, t_exit)` for the cells of `g` the ray o + t·d pierces for t
/// in [t0, t1] (t0 <= t1, both inside the grid's slab interval), in order, until `visit`
/// returns true; returns whether it did. A ray whose slab interval starts at t0 = +inf reaches
/// the grid at no finite t (its origin lies outside a slab it runs parallel to, while another
/// slab's distances overflow, as intersect_box reports them for a direction component near
/// 2^-126): it pierces no cell, and the entry point o + t0·d, NaN on its parallel axis, is never
/// formed.
///
/// The intervals partition [t0, t1]: each cell's t_exit is the next cell's t_enter, so every
/// t in [t0, t1] lies in some visited cell's closed interval. A zero direction component (±0)
/// never steps along its axis. The next crossing along an axis is recomputed from the boundary
/// plane itself rather than accumulated, so rounding does not drift over long rays; what rounding
/// remains (a few ulps of the coordinates, e.g. when a ray runs along a cell face or through an
/// edge) is absorbed by the placement margin (grid_geometry.h).
template <class Visit>
inline bool grid_dda(const GridGeometry& g, const Vec3f& org, const Vec3f& dir, const Vec3f& inv_dir, float t0, float t1,
                     Visit&& visit) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  if (!(t0 < kInf)) return false;
  int cell[3], step[3], out[3];
  float next[3];
  for (int a = 0; a < 3; ++a) {
    cell[a] = g.cell_of(a, org[a] + dir[a] * t0);
    if (std::isinf(inv_dir[a])) {  // ±0 (or a denormal, flushed or not): the ray never leaves this slab
      step[a] = 0;
      out[a] = -2;
      next[a] = kInf;
    } else if (dir[a] > 0.0f) {
      step[a] = 1;
      out[a] = g.res[a];
      next[a] = (g.plane(a, cell[a] + 1) - org[a]) * inv_dir[a];
    } else if (dir[a] < 0.0f) {
      step[a] = -1;
      out[a] = -1;
      next[a] = (g.plane(a, cell[a]) - org[a]) * inv_dir[a];
    } else {
      step[a] = 0;
      out[a] = -2;
      next[a] = kInf;
    }
  }
  const std::int64_t stride[3] = {1, g.res[0], std::int64_t(g.res[0]) * g.res[1]};
  std::int64_t index = g.index(cell[0], cell[1], cell[2]);
  float enter = t0;
  for (;;) {
    const int a = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
    float exit = next[a] < t1 ? next[a] : t1;
    if (exit < enter) exit = enter;
    if (visit(static_cast<std::uint32_t>(index), enter, exit)) return true;
    if (!(next[a] < t1)) return false;
    cell[a] += step[a];
    if (cell[a] == out[a]) return false;
    index += step[a] * stride[a];
    enter = exit;
    next[a] = (g.plane(a, cell[a] + (step[a] > 0 ? 1 : 0)) - org[a]) * inv_dir[a];
  }
}

}  // namespace raylab
