#include "accel/grid/grid_placement.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "geometry/exact_predicates.h"
#include "geometry/input_error.h"

namespace raylab {

std::array<int, 3> grid_resolution(const Bounds3f& box, double n, double density, std::int64_t max_cells) {
  const Vec3d e(box.diagonal());
  const double emax = max_component(e);
  if (!(emax > 0.0)) return {1, 1, 1};
  double target = density * std::cbrt(std::max(n, 1.0));
  std::array<int, 3> r{};
  for (int attempt = 0; attempt < 64; ++attempt) {
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) {
      r[a] = static_cast<int>(std::clamp(std::lround(target * e[a] / emax), 1L, 1L << 30));
      cells *= r[a];
    }
    if (cells <= static_cast<double>(max_cells)) return r;
    target *= 0.99 * std::cbrt(static_cast<double>(max_cells) / cells);
  }
  return {1, 1, 1};
}

namespace {

struct CellRange {
  int lo[3], hi[3];
};

inline CellRange cell_range(const GridGeometry& g, const Bounds3f& b, float margin) {
  CellRange r;
  for (int a = 0; a < 3; ++a) {
    r.lo[a] = g.cell_of(a, b.lo[a] - margin);
    r.hi[a] = g.cell_of(a, b.hi[a] + margin);
  }
  return r;
}

inline Bounds3f prim_bounds(const Scene& s, std::uint32_t prim) {
  if (s.is_sphere(prim)) return s.sphere(prim).bounds();
  const auto& t = s.mesh.triangles[prim];
  const auto& v = s.mesh.vertices;
  Bounds3f b(v[t[0]]);
  b.extend(v[t[1]]);
  b.extend(v[t[2]]);
  return b;
}

bool sphere_meets_box(const Sphere& s, const Bounds3f& box, float margin) {
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double c = s.center[a];
    const double lo = double(box.lo[a]) - margin, hi = double(box.hi[a]) + margin;
    const double d = c < lo ? lo - c : (c > hi ? c - hi : 0.0);
    d2 += d * d;
  }
  const double r = double(s.radius) * (1.0 + 1e-6) + margin;
  return d2 <= r * r;
}

bool prim_meets_cell(const Scene& s, std::uint32_t prim, const Bounds3f& cell, float margin) {
  if (s.is_sphere(prim)) return sphere_meets_box(s.sphere(prim), cell, margin);
  const auto& t = s.mesh.triangles[prim];
  const auto& v = s.mesh.vertices;
  return exact_triangle_intersects_box(v[t[0]], v[t[1]], v[t[2]], widened(cell, margin));
}

void check_ref_count(std::size_t total) {
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw InputError("grid: " + std::to_string(total) +
                     " cell references overflow 32-bit offsets; lower the density d or use place=exact");
}

template <class PrimAt>
CellLists place(const Scene& scene, std::size_t n, PrimAt prim_at, const GridGeometry& g, GridPlacement placement,
                float margin) {
  CellLists out;
  const std::size_t cells = g.cell_count();
  out.offsets.assign(cells + 1, 0);
  std::uint32_t* count = out.offsets.data() + 1;
  if (placement == GridPlacement::bbox) {
    std::size_t total = 0;
    for (std::size_t p = 0; p < n; ++p) {
      const CellRange r = cell_range(g, prim_bounds(scene, prim_at(p)), margin);
      for (int k = r.lo[2]; k <= r.hi[2]; ++k)
        for (int j = r.lo[1]; j <= r.hi[1]; ++j) {
          std::uint32_t* row = count + g.index(0, j, k);
          for (int i = r.lo[0]; i <= r.hi[0]; ++i) ++row[i];
        }
      total += std::size_t(r.hi[0] - r.lo[0] + 1) * std::size_t(r.hi[1] - r.lo[1] + 1) * std::size_t(r.hi[2] - r.lo[2] + 1);
    }
    check_ref_count(total);
    for (std::size_t c = 0; c < cells; ++c) out.offsets[c + 1] += out.offsets[c];
    out.refs.resize(total);
    // Fill: `cursor` reuses offsets[c] as the write position of cell c, restored afterwards by a shift.
    std::uint32_t* cursor = out.offsets.data();
    for (std::size_t p = 0; p < n; ++p) {
      const std::uint32_t prim = prim_at(p);
      const CellRange r = cell_range(g, prim_bounds(scene, prim), margin);
      for (int k = r.lo[2]; k <= r.hi[2]; ++k)
        for (int j = r.lo[1]; j <= r.hi[1]; ++j) {
          std::uint32_t* row = cursor + g.index(0, j, k);
          for (int i = r.lo[0]; i <= r.hi[0]; ++i) out.refs[row[i]++] = prim;
        }
    }
    for (std::size_t c = cells; c > 0; --c) out.offsets[c] = out.offsets[c - 1];
    out.offsets[0] = 0;
    return out;
  }
  // exact: the decisions are made once into (cell, prim) pairs, then counting-sorted.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(n * 2);
  for (std::size_t p = 0; p < n; ++p) {
    const std::uint32_t prim = prim_at(p);
    const CellRange r = cell_range(g, prim_bounds(scene, prim), margin);
    const bool single = r.lo[0] == r.hi[0] && r.lo[1] == r.hi[1] && r.lo[2] == r.hi[2];
    for (int k = r.lo[2]; k <= r.hi[2]; ++k)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j)
        for (int i = r.lo[0]; i <= r.hi[0]; ++i)
          if (single || prim_meets_cell(scene, prim, g.cell_box(i, j, k), margin)) pairs.emplace_back(g.index(i, j, k), prim);
  }
  check_ref_count(pairs.size());
  for (const auto& pr : pairs) ++count[pr.first];
  for (std::size_t c = 0; c < cells; ++c) out.offsets[c + 1] += out.offsets[c];
  out.refs.resize(pairs.size());
  std::vector<std::uint32_t> cursor(out.offsets.begin(), out.offsets.end() - 1);
  for (const auto& pr : pairs) out.refs[cursor[pr.first]++] = pr.second;
  return out;
}

}  // namespace

CellLists place_primitives(const Scene& scene, const std::uint32_t* prims, std::size_t n, const GridGeometry& grid,
                           GridPlacement placement, float margin) {
  return place(scene, n, [prims](std::size_t p) { return prims[p]; }, grid, placement, margin);
}

CellLists place_all_primitives(const Scene& scene, const GridGeometry& grid, GridPlacement placement, float margin) {
  return place(scene, scene.primitive_count(), [](std::size_t p) { return static_cast<std::uint32_t>(p); }, grid,
               placement, margin);
}

}  // namespace raylab
