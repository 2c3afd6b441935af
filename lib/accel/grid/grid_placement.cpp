#include "accel/grid/grid_placement.h"

#include <algorithm>
#include <bit>
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

/// Sutherland-Hodgman: the part of the convex polygon in[0, n) with x[axis] >= bound (keep_above)
/// or <= bound, written to out (at most n + 1 vertices); returns its vertex count.
inline int clip_polygon(const Vec3f* in, int n, Vec3f* out, int axis, float bound, bool keep_above) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3f& a = in[i];
    const Vec3f& b = in[i + 1 == n ? 0 : i + 1];
    const float da = keep_above ? a[axis] - bound : bound - a[axis];
    const float db = keep_above ? b[axis] - bound : bound - b[axis];
    if (da >= 0.0f) out[m++] = a;
    if ((da < 0.0f) != (db < 0.0f)) {
      const float t = std::clamp(da / (da - db), 0.0f, 1.0f);
      Vec3f p = a + (b - a) * t;
      p[axis] = bound;
      out[m++] = p;
    }
  }
  return m;
}

/// Calls row(j, k, i_lo, i_hi) for the rows of cells (j, k) of range `r` that a triangle's part
/// in them reaches, with the x-range of cells that part spans: the triangle clipped to each
/// slab k widened by 2·margin, then to each row j widened by 2·margin, and the part's y- and
/// x-extents widened by 2·margin. The extra margin covers the float rounding of the clipping (a
/// few ulps of the coordinates, far below the margin), so the rows and ranges include every
/// cell whose box widened by `margin` the triangle meets (and lie within the bounding box's).
template <class Row>
inline void for_each_clipped_row(const GridGeometry& g, const Vec3f (&tri)[3], const CellRange& r, float margin,
                                 Row&& row) {
  const float slack = 2.0f * margin;
  Vec3f slab[8], tmp[8], cell_row[8];
  for (int k = r.lo[2]; k <= r.hi[2]; ++k) {
    int ns = 3;
    std::copy(tri, tri + 3, slab);
    if (r.lo[2] != r.hi[2]) {
      ns = clip_polygon(tri, 3, tmp, 2, g.plane(2, k) - slack, true);
      ns = clip_polygon(tmp, ns, slab, 2, g.plane(2, k + 1) + slack, false);
      if (ns == 0) continue;
    }
    float ylo = slab[0].y, yhi = slab[0].y;
    for (int v = 1; v < ns; ++v) ylo = std::min(ylo, slab[v].y), yhi = std::max(yhi, slab[v].y);
    const int jlo = std::max(r.lo[1], g.cell_of(1, ylo - slack)), jhi = std::min(r.hi[1], g.cell_of(1, yhi + slack));
    for (int j = jlo; j <= jhi; ++j) {
      const Vec3f* part = slab;
      int nr = ns;
      if (jlo != jhi) {
        nr = clip_polygon(slab, ns, tmp, 1, g.plane(1, j) - slack, true);
        nr = clip_polygon(tmp, nr, cell_row, 1, g.plane(1, j + 1) + slack, false);
        if (nr == 0) continue;
        part = cell_row;
      }
      float xlo = part[0].x, xhi = part[0].x;
      for (int v = 1; v < nr; ++v) xlo = std::min(xlo, part[v].x), xhi = std::max(xhi, part[v].x);
      const int ilo = std::max(r.lo[0], g.cell_of(0, xlo - slack)), ihi = std::min(r.hi[0], g.cell_of(0, xhi + slack));
      if (ilo <= ihi) row(j, k, ilo, ihi);
    }
  }
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

/// The order placement visits primitives in: by the index of their bounds' lowest cell (row
/// (j, k), then column i), a stable counting sort in `counts` (cell_count + 1 entries, zero on
/// entry and on return). Cells are stored in index order, so visiting primitives in this order
/// walks the cell arrays nearly sequentially instead of at random (grass lists its blades in
/// random positions), and primitives that share cells get nearby positions. A cell lists its
/// primitives in this order. Only one key per primitive is kept: the passes recompute cell ranges.
/// With `copy` (a scene of triangles only), also writes the triangles in visit order to it,
/// scattered while the scene is read in input order (sequential reads, independent writes).
template <class PrimAt>
BuildArray<std::uint32_t> visit_order(const Scene& scene, std::size_t n, PrimAt prim_at, const GridGeometry& g,
                                      float margin, std::uint32_t* counts, BuildArray<CellTriangles::Triangle>* copy) {
  BuildArray<std::uint32_t> key(n);
  for (std::size_t p = 0; p < n; ++p) {
    const Bounds3f b = prim_bounds(scene, prim_at(p));
    key[p] = g.index(g.cell_of(0, b.lo.x - margin), g.cell_of(1, b.lo.y - margin), g.cell_of(2, b.lo.z - margin));
    ++counts[key[p] + 1];
  }
  const std::size_t cells = g.cell_count();
  for (std::size_t c = 1; c < cells; ++c) counts[c] += counts[c - 1];
  BuildArray<std::uint32_t> order(n);
  if (copy) {
    copy->resize(n);
    const auto& v = scene.mesh.vertices;
    for (std::size_t p = 0; p < n; ++p) {
      const std::uint32_t at = counts[key[p]]++, prim = prim_at(p);
      const auto& t = scene.mesh.triangles[prim];
      order[at] = prim;
      (*copy)[at] = {v[t[0]], v[t[1]], v[t[2]]};
    }
  } else {
    for (std::size_t p = 0; p < n; ++p) order[counts[key[p]]++] = prim_at(p);
  }
  std::fill(counts, counts + cells + 1, 0u);
  return order;
}

template <class PrimAt>
CellLists place(const Scene& scene, std::size_t n, PrimAt prim_at, const GridGeometry& g, GridPlacement placement,
                float margin, CellRefIds ids) {
  CellLists out;
  const std::size_t cells = g.cell_count();
  out.offsets.assign(cells + 1, 0);
  const bool local = ids == CellRefIds::visit_order;
  // The triangles in visit order, copied once: the reference ids of a local build, and
  // sequential reads for the passes (clipping reads every triangle again).
  const bool gather = scene.spheres.empty() && (local || placement == GridPlacement::clipped);
  CellTriangles visit_tris;
  BuildArray<std::uint32_t> order =
      visit_order(scene, n, prim_at, g, margin, out.offsets.data(), gather ? &visit_tris.tris : nullptr);
  if (gather) visit_tris.prim_of = std::move(order);
  const BuildArray<std::uint32_t>& prims = gather ? visit_tris.prim_of : order;
  // The cell range of the p-th primitive visited, from its copied triangle when there is one.
  auto range_of = [&](std::size_t p) {
    if (!gather) return cell_range(g, prim_bounds(scene, prims[p]), margin);
    const CellTriangles::Triangle& t = visit_tris.tris[p];
    Bounds3f b(t.v0);
    b.extend(t.v1);
    b.extend(t.v2);
    return cell_range(g, b, margin);
  };
  // Calls row(j, k, i_lo, i_hi) for the rows of cells of the bounding box of primitive p.
  auto bbox_rows = [&](std::size_t p, auto&& row) {
    const CellRange r = range_of(p);
    for (int k = r.lo[2]; k <= r.hi[2]; ++k)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j) row(j, k, r.lo[0], r.hi[0]);
  };
  // The fill of a two-pass placement whose counts are in offsets[c]: an inclusive prefix sum
  // makes offsets[c] the end of cell c, and filling backwards (last primitive first) over the
  // runs of cells runs_of(p, run) reports for primitive p, run(first cell, cell count), leaves it
  // at the start, with every cell's list in visiting order.
  auto fill = [&](std::size_t total, auto&& runs_of) {
    std::uint32_t* cursor = out.offsets.data();
    for (std::size_t c = 1; c < cells; ++c) cursor[c] += cursor[c - 1];
    out.offsets[cells] = static_cast<std::uint32_t>(total);
    out.refs.resize(total);
    std::uint32_t* refs = out.refs.data();
    for (std::size_t p = n; p-- > 0;) {
      const std::uint32_t ref = local ? static_cast<std::uint32_t>(p) : prims[p];
      runs_of(p, [&](std::uint32_t first, std::uint32_t count) {
        std::uint32_t* run = cursor + first;
        for (std::uint32_t i = 0; i < count; ++i) refs[--run[i]] = ref;
      });
    }
    if (local) out.triangles = std::move(visit_tris);
  };
  // The rows rows_of(p, row) reports, as runs.
  auto as_runs = [&](auto& rows_of) {
    return [&](std::size_t p, auto&& run) {
      rows_of(p, [&](int j, int k, int ilo, int ihi) { run(g.index(ilo, j, k), std::uint32_t(ihi - ilo + 1)); });
    };
  };
  std::uint32_t* count = out.offsets.data() + 1;
  if (placement == GridPlacement::bbox) {
    // Counting sort without a shift pass: counts go to offsets[c], then the fill.
    //
    // Where references outnumber 8 per primitive plus 3 per cell, the counts come from a 3D
    // difference array instead of one increment per reference: +1 and -1 at the 8 corners of
    // each cell range by inclusion-exclusion (corners past the last cell dropped), then prefix
    // sums along x, y and z. Arithmetic is modulo 2^32, exact for counts below 2^32
    // (check_ref_count).
    std::uint32_t* cursor = out.offsets.data();
    auto volume = [](const CellRange& r) {
      return std::size_t(r.hi[0] - r.lo[0] + 1) * std::size_t(r.hi[1] - r.lo[1] + 1) * std::size_t(r.hi[2] - r.lo[2] + 1);
    };
    std::size_t total = 0;
    for (std::size_t p = 0; p < n; ++p) total += volume(range_of(p));
    check_ref_count(total);
    const int nx = g.res[0], ny = g.res[1], nz = g.res[2];
    if (total > 8 * n + 3 * cells) {
      for (std::size_t p = 0; p < n; ++p) {
        const CellRange r = range_of(p);
        for (unsigned corner = 0; corner < 8; ++corner) {
          const int i = corner & 1u ? r.hi[0] + 1 : r.lo[0];
          const int j = corner & 2u ? r.hi[1] + 1 : r.lo[1];
          const int k = corner & 4u ? r.hi[2] + 1 : r.lo[2];
          if (i == nx || j == ny || k == nz) continue;
          cursor[g.index(i, j, k)] += std::popcount(corner) % 2 == 0 ? 1u : ~0u;
        }
      }
      const std::size_t row_cells = std::size_t(nx), slab_cells = row_cells * std::size_t(ny);
      for (std::size_t base = 0; base < cells; base += row_cells)
        for (std::size_t i = 1; i < row_cells; ++i) cursor[base + i] += cursor[base + i - 1];
      for (std::size_t base = 0; base < cells; base += slab_cells)
        for (std::size_t c = base + row_cells; c < base + slab_cells; ++c) cursor[c] += cursor[c - row_cells];
      for (std::size_t c = slab_cells; c < cells; ++c) cursor[c] += cursor[c - slab_cells];
    } else {
      for (std::size_t p = 0; p < n; ++p) {
        const CellRange c = range_of(p);
        for (int k = c.lo[2]; k <= c.hi[2]; ++k)
          for (int j = c.lo[1]; j <= c.hi[1]; ++j) {
            std::uint32_t* row = cursor + g.index(0, j, k);
            for (int i = c.lo[0]; i <= c.hi[0]; ++i) ++row[i];
          }
      }
    }
    fill(total, as_runs(bbox_rows));
    return out;
  }
  if (placement == GridPlacement::clipped) {
    // One clipping pass records the rows of cells of every primitive as runs (first cell, cell
    // count), in visiting order, and counts them by a difference array along each row (+1 at the
    // run's first cell, -1 past its last), then prefix sums along x; the fill replays the runs.
    // Clipping is most of the work, and a run (5 bytes) is written and read once instead.
    const int nx = g.res[0];
    std::uint32_t* cursor = out.offsets.data();
    auto rows_of = [&](std::size_t p, auto&& row) {
      const CellRange r = range_of(p);
      if ((r.lo[1] == r.hi[1] && r.lo[2] == r.hi[2]) || (!gather && scene.is_sphere(prims[p])))
        return bbox_rows(p, row);
      if (gather) {
        const CellTriangles::Triangle& t = visit_tris.tris[p];
        const Vec3f tri[3] = {t.v0, t.v1, t.v2};
        for_each_clipped_row(g, tri, r, margin, row);
      } else {
        const auto& t = scene.mesh.triangles[prims[p]];
        const auto& v = scene.mesh.vertices;
        const Vec3f tri[3] = {v[t[0]], v[t[1]], v[t[2]]};
        for_each_clipped_row(g, tri, r, margin, row);
      }
    };
    // A run: its first cell and its cell count; a row of more than 255 cells is several runs.
    // The runs of the bounding boxes' rows bound them; the arrays reserve that bound (address
    // space: only the runs written are touched), capped at 32 per primitive plus one per cell.
    // Past the cap (large triangles, or references beyond 32 bits, which are reported after
    // counting) recording stops and the fill clips the primitives again.
    constexpr std::uint32_t kLongestRun = 255;
    BuildArray<std::uint32_t> run_first;
    BuildArray<std::uint8_t> run_count;
    std::size_t bbox_runs_total = 0;
    for (std::size_t p = 0; p < n; ++p) {
      const CellRange r = range_of(p);
      bbox_runs_total += std::size_t(r.hi[1] - r.lo[1] + 1) * std::size_t(r.hi[2] - r.lo[2] + 1) *
                         ((std::size_t(r.hi[0] - r.lo[0]) + kLongestRun) / kLongestRun);
    }
    const std::size_t capacity = std::min(bbox_runs_total, 32 * n + cells);
    run_first.reserve(capacity);
    run_count.reserve(capacity);
    BuildArray<std::uint32_t> runs_end(n);  // primitive p's runs: [runs_end[p-1] (0 for p = 0), runs_end[p])
    bool recorded = true;
    std::size_t total = 0;
    for (std::size_t p = 0; p < n; ++p) {
      rows_of(p, [&](int j, int k, int ilo, int ihi) {
        const std::uint32_t first = g.index(ilo, j, k), count = std::uint32_t(ihi - ilo + 1);
        ++cursor[first];
        if (ihi + 1 < nx) --cursor[first + count];
        total += count;
        for (std::uint32_t at = 0; recorded && at < count; at += kLongestRun) {
          if (run_first.size() == capacity) {
            recorded = false;
            run_first = {};
            run_count = {};
            runs_end = {};
            break;
          }
          run_first.push_back(first + at);
          run_count.push_back(static_cast<std::uint8_t>(std::min(count - at, kLongestRun)));
        }
      });
      if (recorded) runs_end[p] = static_cast<std::uint32_t>(run_first.size());
    }
    check_ref_count(total);
    for (std::size_t base = 0; base < cells; base += std::size_t(nx))
      for (std::size_t i = 1; i < std::size_t(nx); ++i) cursor[base + i] += cursor[base + i - 1];
    if (recorded)
      fill(total, [&](std::size_t p, auto&& run) {
        for (std::uint32_t r = p == 0 ? 0 : runs_end[p - 1]; r < runs_end[p]; ++r) run(run_first[r], run_count[r]);
      });
    else
      fill(total, as_runs(rows_of));
    return out;
  }
  // exact: the decisions are made once into (cell, prim) pairs, then counting-sorted.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(n * 2);
  for (std::size_t p = 0; p < n; ++p) {
    const std::uint32_t prim = prims[p];
    const CellRange r = range_of(p);
    const bool single = r.lo[0] == r.hi[0] && r.lo[1] == r.hi[1] && r.lo[2] == r.hi[2];
    for (int k = r.lo[2]; k <= r.hi[2]; ++k)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j)
        for (int i = r.lo[0]; i <= r.hi[0]; ++i)
          if (single || prim_meets_cell(scene, prim, g.cell_box(i, j, k), margin))
            pairs.emplace_back(g.index(i, j, k), local ? static_cast<std::uint32_t>(p) : prim);
  }
  check_ref_count(pairs.size());
  for (const auto& pr : pairs) ++count[pr.first];
  for (std::size_t c = 0; c < cells; ++c) out.offsets[c + 1] += out.offsets[c];
  out.refs.resize(pairs.size());
  std::vector<std::uint32_t> cursor(out.offsets.begin(), out.offsets.end() - 1);
  for (const auto& pr : pairs) out.refs[cursor[pr.first]++] = pr.second;
  if (local) out.triangles = std::move(visit_tris);
  return out;
}

}  // namespace

CellLists place_primitives(const Scene& scene, const std::uint32_t* prims, std::size_t n, const GridGeometry& grid,
                           GridPlacement placement, float margin) {
  return place(scene, n, [prims](std::size_t p) { return prims[p]; }, grid, placement, margin,
               CellRefIds::primitive);
}

CellLists place_all_primitives(const Scene& scene, const GridGeometry& grid, GridPlacement placement, float margin,
                               CellRefIds ids) {
  return place(scene, scene.primitive_count(), [](std::size_t p) { return static_cast<std::uint32_t>(p); }, grid,
               placement, margin, ids);
}

}  // namespace raylab
