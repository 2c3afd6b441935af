#pragma once
/// The per-ray work inside the cells of a grid, shared by the uniform and the nested grid:
/// offering a cell's primitives to the kernel (watertight or certified), accepting hits by the
/// cell's t-interval, and the mailbox.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "accel/common/kernel_choice.h"
#include "accel/grid/cell_triangles.h"
#include "accel/grid/grid_config.h"
#include "accel/grid/grid_frame.h"
#include "accel/grid/grid_geometry.h"
#include "accel/grid/mailbox.h"
#include "geometry/certified_kernel.h"
#include "geometry/triangle_kernels.h"
#include "scene/scene_primitives.h"

namespace raylab {

/// The t-widening w of a ray's cell intervals: 2^-16 · (|o|∞ + D) / |d|∞ for a grid of diagonal
/// extent D, with o the ray's origin in the grid's frame (grid_frame.h). It covers the rounding
/// of the DDA's crossings (computed in the frame) and of the kernel's t (whose terms scale with
/// |v - o| <= |o|∞ + D for a vertex v in the grid, the same in either frame), and stays far
/// below hit_comparison.h's tolerance (1e-4 of the same scale), so a hit accepted up to w beyond
/// its cell is at most a tie with any closer hit in the next cell.
inline float cell_widening(const Ray& ray, float grid_extent) {
  return kGridMarginScale * (max_component(abs(ray.org)) + grid_extent) / max_component(abs(ray.dir));
}

struct NoMailbox {};

/// Offers cell reference `ref` to the kernel: a local id of `tris` when `tris` holds triangles
/// (cell_triangles.h), else a primitive id of `scene`. On a hit closer than the context's closest,
/// writes `hit` with the scene's primitive id.
template <class Kernel, class Counters>
inline bool intersect_cell_ref(const Scene& scene, const CellTriangles& tris, std::uint32_t ref,
                               typename Kernel::Context& ctx, Hit& hit, Counters& counters) {
  if (tris.tris.empty()) return intersect_scene_primitive<Kernel>(scene, ref, ctx, hit, counters);
  counters.prim_test();
  const CellTriangles::Triangle& t = tris.tris[ref];
  TriangleHit th;
  if (!Kernel::intersect(ctx, ref, t.v0, t.v1, t.v2, th)) return false;
  counters.prim_hit();
  set_scene_hit(hit, th, tris.prim_of[ref]);
  return true;
}

/// Every primitive of `scene` offered to the certified kernel: the grids' path for a ray whose
/// 3D-DDA would leave the placement margin even from where it enters the grid (EntryRay,
/// grid_geometry.h). True on a hit (with kAnyHit, at the first).
template <bool kAnyHit, class Counters>
inline bool certified_over_all_primitives(const Scene& scene, const Ray& ray, Hit& hit, Counters& counters) {
  CertifiedKernel::Context ctx = CertifiedKernel::prepare(ray);
  bool found = false;
  counters.leaf();
  for (unsigned prim = 0, n = static_cast<unsigned>(scene.primitive_count()); prim < n; ++prim)
    if (intersect_scene_primitive<CertifiedKernel>(scene, prim, ctx, hit, counters)) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
  return found;
}

/// Requests the cache lines of the copied triangles of references [begin, end) before they are
/// tested, so that their memory latencies overlap instead of following one another.
inline void prefetch_cell_triangles(const CellTriangles& tris, const std::uint32_t* begin, const std::uint32_t* end) {
  if (tris.tris.empty()) return;
  for (const std::uint32_t* p = begin; p != end; ++p) {
    const char* t = reinterpret_cast<const char*>(tris.tris.data() + *p);
    __builtin_prefetch(t);
    __builtin_prefetch(t + sizeof(CellTriangles::Triangle) - 1);
  }
}

/// The scene's primitive id of cell reference `ref`.
inline std::uint32_t cell_ref_prim(const CellTriangles& tris, std::uint32_t ref) {
  return tris.tris.empty() ? ref : tris.prim_of[ref];
}

/// Closest-hit state of one ray in a grid (the watertight kernel).
template <class Kernel, class Counters, bool kMailbox>
struct ClosestHitInCells {
  static_assert(std::is_same_v<Kernel, WatertightKernel>);
  const Scene& scene;
  const CellTriangles& tris;
  WatertightKernel::Context ctx;
  GridAcceptance acceptance;
  float widen;
  Counters& counters;
  float best;  ///< t of the accepted hit (ray.tmax while none)
  Hit hit;
  bool found = false;
  [[no_unique_address]] std::conditional_t<kMailbox, RayMailbox, NoMailbox> mailbox;

  ClosestHitInCells(const Scene& s, const CellTriangles& ct, const Ray& ray, GridAcceptance acc, float w, Counters& c)
      : scene(s), tris(ct), ctx(WatertightKernel::prepare(ray)), acceptance(acc), widen(w), counters(c), best(ray.tmax) {}

  /// Offers the cell's references [begin, end) with t-interval [t_enter, t_exit]; returns true
  /// when the traversal may stop (a hit was accepted in this cell).
  bool leaf(const std::uint32_t* begin, const std::uint32_t* end, float /*t_enter*/, float t_exit) {
    counters.leaf();
    const float limit = acceptance == GridAcceptance::first ? best : t_exit + widen;
    prefetch_cell_triangles(tris, begin, end);
    bool here = false;
    for (const std::uint32_t* p = begin; p != end; ++p) {
      const std::uint32_t prim = *p;
      if constexpr (kMailbox) {
        if (const RayMailbox::Entry* e = mailbox.find(prim)) {
          counters.mailbox_skip();
          if (e->t < best && e->t <= limit) {
            best = e->t;
            hit = Hit{e->t, e->u, e->v, cell_ref_prim(tris, prim), kInvalidId};
            here = true;
          }
          continue;
        }
      }
      ctx.tmax = best;
      Hit h;
      if (intersect_cell_ref<WatertightKernel>(scene, tris, prim, ctx, h, counters)) {
        if (h.t <= limit) {
          best = h.t;
          hit = h;
          here = true;
        } else if constexpr (kMailbox) {
          mailbox.store_hit(prim, h);
        }
      } else if constexpr (kMailbox) {
        mailbox.store_miss(prim);
      }
    }
    found |= here;
    return here;
  }
};

/// Closest-hit state of one ray in a grid with the certified kernel. The kernel keeps the first
/// hit over every cell offered so far, so hits need no acceptance test of their own and the
/// mailbox only skips primitives already offered. The walk stops after a cell whose interval
/// ends at or after the certified upper bound of the first hit's exact t: every t' below it lies
/// in the interval of a visited cell, whose primitives include every one the exact ray meets at
/// t' as long as the 3D-DDA stays within the placement margin of its cells
/// (dda_within_margin, grid_geometry.h; the grids check it per ray). The cells' intervals are in
/// the t of the DDA's ray, which is the world ray's t minus t_base (an EntryRay's, else 0).
template <class Counters, bool kMailbox>
struct ClosestHitInCells<CertifiedKernel, Counters, kMailbox> {
  const Scene& scene;
  const CellTriangles& tris;
  CertifiedKernel::Context ctx;
  Counters& counters;
  Hit hit;
  bool found = false;
  double t_base = 0.0;
  [[no_unique_address]] std::conditional_t<kMailbox, RayMailbox, NoMailbox> mailbox;

  ClosestHitInCells(const Scene& s, const CellTriangles& ct, const Ray& ray, GridAcceptance, float, Counters& c)
      : scene(s), tris(ct), ctx(CertifiedKernel::prepare(ray)), counters(c) {}

  bool leaf(const std::uint32_t* begin, const std::uint32_t* end, float /*t_enter*/, float t_exit) {
    counters.leaf();
    prefetch_cell_triangles(tris, begin, end);
    for (const std::uint32_t* p = begin; p != end; ++p) {
      if constexpr (kMailbox) {
        if (mailbox.find(*p)) {
          counters.mailbox_skip();
          continue;
        }
        mailbox.store_miss(*p);
      }
      found |= intersect_cell_ref<CertifiedKernel>(scene, tris, *p, ctx, hit, counters);
    }
    return found && covers(CertifiedKernel::best_upper(ctx), t_exit);
  }

  /// Whether every world t up to `upper` lies at or before t_base + t_exit (the double sum
  /// lowered by its rounding).
  bool covers(float upper, float t_exit) const {
    if (t_base == 0.0) return upper <= t_exit;
    const double t = t_base + double(t_exit);
    return double(upper) <= t - 0x1p-52 * std::abs(t);
  }
};

/// Any-hit state of one ray in a grid: any hit in [tmin, tmax] ends the ray, wherever it lies.
template <class Kernel, class Counters, bool kMailbox>
struct AnyHitInCells {
  const Scene& scene;
  const CellTriangles& tris;
  typename Kernel::Context ctx;
  Counters& counters;
  [[no_unique_address]] std::conditional_t<kMailbox, RayMailbox, NoMailbox> mailbox;

  /// `ray`: for the watertight kernel, closed_for_any_hit of the query.
  AnyHitInCells(const Scene& s, const CellTriangles& ct, const Ray& ray, Counters& c)
      : scene(s), tris(ct), ctx(Kernel::prepare(ray)), counters(c) {}

  bool leaf(const std::uint32_t* begin, const std::uint32_t* end, float, float) {
    counters.leaf();
    prefetch_cell_triangles(tris, begin, end);
    Hit h;
    for (const std::uint32_t* p = begin; p != end; ++p) {
      if constexpr (kMailbox) {
        if (mailbox.find(*p)) {
          counters.mailbox_skip();
          continue;
        }
      }
      if (intersect_cell_ref<Kernel>(scene, tris, *p, ctx, h, counters)) return true;
      if constexpr (kMailbox) mailbox.store_miss(*p);
    }
    return false;
  }
};

/// A grid query: the ray in the grid's frame (grid_frame.h), whether its float box test met the
/// grid's box and the interval [t0, t1] it clipped, and the grid's box, frame origin and placement
/// margin.
struct GridQuery {
  const Ray& local;
  bool entered;
  float t0, t1;
  const Bounds3f& box;
  const Vec3f& frame_origin;
  float margin;
};

/// Whether a query whose float box test missed the grid's box meets no primitive. Ize's box test
/// (bounds.h) is conservative for the float ray it is given: the world ray itself in the world
/// frame, else the world ray moved into the frame and rounded (u/2·|o|∞), and primitives lie the
/// placement margin inside the box. The watertight kernel claims nothing there.
template <class Kernel>
inline bool trusts_box_miss(const GridQuery& q) {
  return !std::is_same_v<Kernel, CertifiedKernel> || is_world_frame(q.frame_origin) ||
         0x1p-23f * max_component(abs(q.local.org)) < q.margin;
}

/// How a grid query is answered (grid_path).
enum class GridPath {
  none,            ///< no primitive can be met
  local,           ///< the 3D-DDA of q.local over [q.t0, q.t1]
  entry,           ///< the 3D-DDA of the EntryRay over [0, its tmax]
  every_primitive  ///< certified_over_all_primitives
};

/// The path of query `q` of `ray` (the world ray; for any-hit queries its any_hit_ray): q.local's
/// DDA unless a float box miss decides it (trusts_box_miss) or, with the certified kernel, that
/// DDA could leave the placement margin (dda_within_margin: a ray from far outside). Then the
/// EntryRay of `ray` (grid_geometry.h, written to `entry`) if it stays within the margin less its
/// offset, none when it misses the box, and otherwise every primitive.
template <class Kernel>
inline GridPath grid_path(const Ray& ray, const GridQuery& q, EntryRay& entry) {
  if (!q.entered) {
    if (trusts_box_miss<Kernel>(q)) return GridPath::none;
  } else if (!std::is_same_v<Kernel, CertifiedKernel> || dda_within_margin(q.local, q.t1, q.box, q.margin)) {
    return GridPath::local;
  }
  entry = entry_ray(ray, initial_closest<Kernel>(ray), q.box, q.frame_origin);
  if (entry.offset >= q.margin) return GridPath::every_primitive;
  if (entry.missed) return GridPath::none;
  return dda_within_margin(entry.ray, entry.ray.tmax, q.box, q.margin - entry.offset) ? GridPath::entry
                                                                                       : GridPath::every_primitive;
}

/// The grid's part of a closest-hit query shared by the uniform and the nested grid:
/// `walk(state, dda_ray, s0, s1)` runs the 3D-DDA of dda_ray over [s0, s1] with a
/// ClosestHitInCells state, whose kernel tests `ray`, on the path grid_path chooses. On a hit,
/// writes `hit` and sets ray.tmax to its t.
template <class Kernel, class Counters, bool kMailbox, class Walk>
inline bool closest_hit_in_grid(const Scene& scene, const CellTriangles& tris, Ray& ray, Hit& hit, const GridQuery& q,
                                GridAcceptance acceptance, float extent, Counters& counters, Walk&& walk) {
  EntryRay entry;
  const GridPath path = grid_path<Kernel>(ray, q, entry);
  bool found = false;
  if (path == GridPath::every_primitive) {
    found = certified_over_all_primitives<false>(scene, ray, hit, counters);
  } else if (path != GridPath::none) {
    ClosestHitInCells<Kernel, Counters, kMailbox> state(scene, tris, ray, acceptance, cell_widening(q.local, extent),
                                                        counters);
    if constexpr (std::is_same_v<Kernel, CertifiedKernel>) {
      if (path == GridPath::entry) state.t_base = entry.t_base;
    }
    if (path == GridPath::local) walk(state, q.local, q.t0, q.t1);
    else walk(state, entry.ray, 0.0f, entry.ray.tmax);
    found = state.found;
    if (found) hit = state.hit;
  }
  if (found) ray.tmax = hit.t;
  return found;
}

/// The any-hit counterpart of closest_hit_in_grid: `walk(state, dda_ray, s0, s1)` with an
/// AnyHitInCells state, returning whether it found a hit; `ray` is any_hit_ray of the query.
template <class Kernel, class Counters, bool kMailbox, class Walk>
inline bool any_hit_in_grid(const Scene& scene, const CellTriangles& tris, const Ray& ray, const GridQuery& q,
                            Counters& counters, Walk&& walk) {
  EntryRay entry;
  const GridPath path = grid_path<Kernel>(ray, q, entry);
  if (path == GridPath::none) return false;
  if (path == GridPath::every_primitive) {
    Hit hit;
    return certified_over_all_primitives<true>(scene, ray, hit, counters);
  }
  AnyHitInCells<Kernel, Counters, kMailbox> state(scene, tris, ray, counters);
  return path == GridPath::local ? walk(state, q.local, q.t0, q.t1) : walk(state, entry.ray, 0.0f, entry.ray.tmax);
}

}  // namespace raylab
