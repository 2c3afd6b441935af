#include "accel/grid/grid_placement.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

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
  /// The cells of the range (each hi >= lo).
  std::size_t cell_count() const {
    return std::size_t(hi[0] - lo[0] + 1) * std::size_t(hi[1] - lo[1] + 1) * std::size_t(hi[2] - lo[2] + 1);
  }
};

inline CellRange cell_range(const GridGeometry& g, const Bounds3f& b, float margin) {
  CellRange r;
  for (int a = 0; a < 3; ++a) {
    r.lo[a] = g.cell_of(a, b.lo[a] - margin);
    r.hi[a] = g.cell_of(a, b.hi[a] + margin);
  }
  return r;
}

/// Sutherland-Hodgman: the part of the convex polygon in[0, n) with x[kAxis] >= bound (kKeepAbove)
/// or <= bound, written to out (at most n + 1 vertices); returns its vertex count.
template <int kAxis, bool kKeepAbove>
inline int clip_polygon(const Vec3f* in, int n, Vec3f* out, float bound) {
  auto side = [bound](const Vec3f& v) { return kKeepAbove ? v[kAxis] - bound : bound - v[kAxis]; };
  int m = 0;
  float da = side(in[0]);
  for (int i = 0; i < n; ++i) {
    const Vec3f& a = in[i];
    const Vec3f& b = in[i + 1 == n ? 0 : i + 1];
    const float db = side(b);
    if (da >= 0.0f) out[m++] = a;
    if ((da < 0.0f) != (db < 0.0f)) {
      const float t = std::clamp(da / (da - db), 0.0f, 1.0f);
      Vec3f p = a + (b - a) * t;
      p[kAxis] = bound;
      out[m++] = p;
    }
    da = db;
  }
  return m;
}

/// Vectors of N lanes in the GCC/Clang vector extensions (16 lanes: one AVX-512 register, or two
/// AVX2, with -march=native), one strip of cells per lane; every operation is the IEEE operation
/// of its scalar counterpart, lane by lane.
template <int N>
struct StripVectors;
template <>
struct StripVectors<8> {
  using Floats = float __attribute__((vector_size(8 * sizeof(float))));
  using Ints = std::int32_t __attribute__((vector_size(8 * sizeof(std::int32_t))));
};
template <>
struct StripVectors<16> {
  using Floats = float __attribute__((vector_size(16 * sizeof(float))));
  using Ints = std::int32_t __attribute__((vector_size(16 * sizeof(std::int32_t))));
};

/// GridGeometry::cell_of, lane by lane (the same operations, so the same cells).
template <class Floats, class Ints>
inline Ints cells_of(const GridGeometry& g, int a, Floats x) {
  Floats f = (x - g.box.lo[a]) * g.inv_cell[a];
  const float last = static_cast<float>(g.res[a] - 1);
  f = f < 0.0f ? Floats{} : f;
  f = last < f ? Floats{} + last : f;
  return __builtin_convertvector(f, Ints);
}

/// The x-ranges of cells of the rows first .. last (at most N, along kU) that the convex polygon
/// slab[0, ns) reaches, row(u, i_lo, i_hi) for each (see for_each_clipped_row_across).
template <int N, int kU, class Row>
inline void scan_strips(const GridGeometry& g, const Vec3f* slab, int ns, const CellRange& r, float slack, int first,
                        int last, Row&& row) {
  using Floats = typename StripVectors<N>::Floats;
  using Ints = typename StripVectors<N>::Ints;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  Ints lane{};
  for (int s = 0; s < N; ++s) lane[s] = s;
  // The strips' bounds, plane(kU, u) - slack and plane(kU, u + 1) + slack, lane by lane.
  const Ints u = first + lane;
  const Ints in_range = u <= last;
  const Floats lo_plane = g.box.lo[kU] + __builtin_convertvector(u, Floats) * g.cell[kU];
  Floats hi_plane = g.box.lo[kU] + __builtin_convertvector(u + 1, Floats) * g.cell[kU];
  hi_plane = u + 1 == g.res[kU] ? Floats{} + g.box.hi[kU] : hi_plane;
  const Floats strip_lo = lo_plane - slack, strip_hi = hi_plane + slack;
  Floats xlo = Floats{} + kInf, xhi = Floats{} - kInf;
  for (int e = 0; e < ns; ++e) {
    Vec3f p = slab[e], q = slab[e + 1 == ns ? 0 : e + 1];
    if (q[kU] < p[kU]) std::swap(p, q);
    const float pu = p[kU], qu = q[kU], px = p[0], qx = q[0], slope = (qx - px) * (1.0f / (qu - pu));
    const Ints meets = in_range & (pu <= strip_hi) & (qu >= strip_lo);
    Floats at_lo, at_hi;
    if (std::abs(slope) <= std::numeric_limits<float>::max()) [[likely]] {
      // the strip's bounds clamped into [p_u, q_u] where it meets the edge
      const Floats u_lo = strip_lo > pu ? strip_lo : pu, u_hi = strip_hi < qu ? strip_hi : qu;
      at_lo = px + (u_lo - pu) * slope;
      at_hi = px + (u_hi - pu) * slope;
    } else {
      at_lo = Floats{} + px;
      at_hi = Floats{} + qx;
    }
    const Floats low = at_lo < at_hi ? at_lo : at_hi, high = at_lo < at_hi ? at_hi : at_lo;
    xlo = (meets & (low < xlo)) ? low : xlo;
    xhi = (meets & (high > xhi)) ? high : xhi;
  }
  const Ints i0 = cells_of<Floats, Ints>(g, 0, xlo - slack), i1 = cells_of<Floats, Ints>(g, 0, xhi + slack);
  const Ints found = (xlo <= xhi) & (i0 <= r.hi[0]) & (i1 >= r.lo[0]);
  for (int s = 0, strips = std::min(N, last - first + 1); s < strips; ++s)
    if (found[s]) row(first + s, std::max(r.lo[0], i0[s]), std::min(r.hi[0], i1[s]));
}

/// Calls row(j, k, i_lo, i_hi) for the rows of cells along x (cells j along y, k along z) of range
/// `r` that a triangle's part in them reaches, with the range of cells along x that part spans: the
/// triangle clipped to each slab of cells along kV (y or z) widened by 2·margin (Sutherland and
/// Hodgman 1974), then the x-extent of that polygon's part within the strip of each row along the
/// other axis kU widened by 2·margin, widened by 2·margin. The part in a strip is not built: a
/// convex polygon's extent in a strip [a, b] is attained on its boundary there, so each edge pq
/// (p_u <= q_u) that meets the strip gives its points at u = max(a, p_u) and min(b, q_u), x = p_x
/// + (u - p_u)·s with slope s = (q_x - p_x)·(1 / (q_u - p_u)): one pass over the polygon's edges
/// scan-converts it into 8 or 16 strips at once (scan_strips). An edge whose slope overflows (q_u
/// - p_u below |q_x - p_x|·2^-128, far below the margin) gives both its endpoints to every strip
/// it meets. The clipping and the interpolation round by a few ulps of the coordinates, far below
/// the extra margin, so the rows and ranges include every cell whose box widened by `margin` the
/// triangle meets (and lie within the bounding box's). In exact arithmetic these are the cells
/// whose box widened by 2·margin the triangle meets, whatever the axes (the triangle's part in a
/// row is convex, so it spans whole ranges), which leaves kV free: the fewer slabs, the fewer
/// clips. Rows come slab by slab, in increasing order along kU within a slab.
template <int kV, int kU, class Row>
inline void for_each_clipped_row_across(const GridGeometry& g, const Vec3f (&tri)[3], const CellRange& r, float margin,
                                        Row&& row) {
  const float slack = 2.0f * margin;
  float vlo = tri[0][kV], vhi = tri[0][kV];
  for (int q = 1; q < 3; ++q) vlo = std::min(vlo, tri[q][kV]), vhi = std::max(vhi, tri[q][kV]);
  Vec3f slab_tmp[8], slab_buf[8];  // a slab's part may stay in slab_tmp
  for (int v = r.lo[kV]; v <= r.hi[kV]; ++v) {
    // A clip that keeps every vertex returns its input, so it is skipped when the triangle's
    // extent along kV says so: float subtraction is monotone, so the extent decides it exactly
    // (the first slab's lower plane and the last one's upper plane).
    int ns = 3;
    const Vec3f* slab = tri;
    if (r.lo[kV] != r.hi[kV]) {
      const float below = g.plane(kV, v) - slack, above = g.plane(kV, v + 1) + slack;
      if (!(vlo - below >= 0.0f)) {
        ns = clip_polygon<kV, true>(slab, ns, slab_tmp, below);
        slab = slab_tmp;
      }
      if (!(above - vhi >= 0.0f)) {
        ns = clip_polygon<kV, false>(slab, ns, slab_buf, above);
        slab = slab_buf;
      }
      if (ns == 0) continue;
    }
    float ulo = slab[0][kU], uhi = slab[0][kU];
    for (int q = 1; q < ns; ++q) ulo = std::min(ulo, slab[q][kU]), uhi = std::max(uhi, slab[q][kU]);
    const int u0 = std::max(r.lo[kU], g.cell_of(kU, ulo - slack)), u1 = std::min(r.hi[kU], g.cell_of(kU, uhi + slack));
    auto slab_row = [&](int u, int i0, int i1) {
      if constexpr (kV == 2)
        row(u, v, i0, i1);
      else
        row(v, u, i0, i1);
    };
    if (u1 - u0 < 8)
      scan_strips<8, kU>(g, slab, ns, r, slack, u0, u1, slab_row);
    else
      for (int first = u0; first <= u1; first += 16)
        scan_strips<16, kU>(g, slab, ns, r, slack, first, u1, slab_row);
  }
}

/// Calls row(j, k, i_lo, i_hi) for the runs of cells along x of the cells of a triangle with
/// bounding-box cell range `r`: for_each_clipped_row_across with slabs along the axis of y and z
/// the range spans fewer cells of (a tall blade of grass is clipped to its few slabs along z, and
/// its many rows along y are scan-converted). With at most one axis spanning several cells the
/// cells are the range's (the triangle is connected), and nothing is clipped.
template <class Row>
inline void for_each_clipped_row(const GridGeometry& g, const Vec3f (&tri)[3], const CellRange& r, float margin,
                                 Row&& row) {
  const int nx = r.hi[0] - r.lo[0] + 1, ny = r.hi[1] - r.lo[1] + 1, nz = r.hi[2] - r.lo[2] + 1;
  if ((nx > 1) + (ny > 1) + (nz > 1) <= 1) {
    for (int k = r.lo[2]; k <= r.hi[2]; ++k)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j) row(j, k, r.lo[0], r.hi[0]);
    return;
  }
  if (nz <= ny)
    for_each_clipped_row_across<2, 1>(g, tri, r, margin, row);
  else
    for_each_clipped_row_across<1, 2>(g, tri, r, margin, row);
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
    std::size_t total = 0;
    for (std::size_t p = 0; p < n; ++p) total += range_of(p).cell_count();
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
    run_first.resize(capacity);  // not written: BuildArray
    run_count.resize(capacity);
    std::uint32_t* const first_of = run_first.data();
    std::uint8_t* const count_of = run_count.data();
    std::size_t runs = 0;
    BuildArray<std::uint32_t> runs_end(n);  // primitive p's runs: [runs_end[p-1] (0 for p = 0), runs_end[p])
    bool recorded = true;
    std::size_t total = 0;
    for (std::size_t p = 0; p < n; ++p) {
      rows_of(p, [&](int j, int k, int ilo, int ihi) {
        const std::uint32_t first = g.index(ilo, j, k), count = std::uint32_t(ihi - ilo + 1);
        ++cursor[first];
        if (ihi + 1 < nx) --cursor[first + count];
        total += count;
        if (count <= kLongestRun && runs < capacity) [[likely]] {
          first_of[runs] = first;
          count_of[runs++] = static_cast<std::uint8_t>(count);
          return;
        }
        for (std::uint32_t at = 0; recorded && at < count; at += kLongestRun) {
          if (runs == capacity) {
            recorded = false;
            break;
          }
          first_of[runs] = first + at;
          count_of[runs++] = static_cast<std::uint8_t>(std::min(count - at, kLongestRun));
        }
      });
      if (recorded) runs_end[p] = static_cast<std::uint32_t>(runs);
    }
    if (!recorded) {
      run_first = {};
      run_count = {};
      runs_end = {};
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

std::size_t count_placed_references(const Scene& scene, const GridGeometry& grid, GridPlacement placement,
                                    float margin) {
  if (placement == GridPlacement::exact) throw std::invalid_argument("count_placed_references: place=exact");
  std::size_t total = 0;
  const auto& v = scene.mesh.vertices;
  for (std::uint32_t prim = 0; prim < scene.primitive_count(); ++prim) {
    const CellRange r = cell_range(grid, prim_bounds(scene, prim), margin);
    if (placement == GridPlacement::bbox || scene.is_sphere(prim)) {
      total += r.cell_count();
      continue;
    }
    const auto& t = scene.mesh.triangles[prim];
    const Vec3f tri[3] = {v[t[0]], v[t[1]], v[t[2]]};
    for_each_clipped_row(grid, tri, r, margin, [&](int, int, int ilo, int ihi) { total += std::size_t(ihi - ilo + 1); });
  }
  return total;
}

CellLists place_all_primitives(const Scene& scene, const GridGeometry& grid, GridPlacement placement, float margin,
                               CellRefIds ids) {
  return place(scene, scene.primitive_count(), [](std::size_t p) { return static_cast<std::uint32_t>(p); }, grid,
               placement, margin, ids);
}

}  // namespace raylab
