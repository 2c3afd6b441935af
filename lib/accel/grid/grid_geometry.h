#pragma once
/// The geometry of one regular grid: its box, its resolution and its cell size, and the
/// robustness margins that make float traversal agree with placement.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "geometry/bounds.h"
#include "geometry/ray.h"

namespace raylab {

/// The relative size of the two robustness margins (about 128 float ulps), far below
/// the tolerance hit_comparison.h allows for t and far above the rounding of the 3D-DDA.
inline constexpr float kGridMarginScale = 1.0f / 65536.0f;

struct GridGeometry {
  Bounds3f box;
  std::array<int, 3> res{1, 1, 1};
  Vec3f cell{1.0f};      ///< cell size per axis
  Vec3f inv_cell{1.0f};  ///< 1 / cell size

  GridGeometry() = default;
  GridGeometry(const Bounds3f& b, const std::array<int, 3>& r) : box(b), res(r) {
    const Vec3f d = b.diagonal();
    for (int a = 0; a < 3; ++a) {
      cell[a] = d[a] / static_cast<float>(res[a]);
      inv_cell[a] = cell[a] > 0.0f ? 1.0f / cell[a] : 0.0f;
    }
  }

  std::size_t cell_count() const { return std::size_t(res[0]) * std::size_t(res[1]) * std::size_t(res[2]); }
  std::uint32_t index(int i, int j, int k) const {
    return static_cast<std::uint32_t>((std::size_t(k) * std::size_t(res[1]) + std::size_t(j)) * std::size_t(res[0]) +
                                      std::size_t(i));
  }
  /// The cell holding coordinate `x` along axis `a`, clamped into the grid.
  int cell_of(int a, float x) const {
    const float f = (x - box.lo[a]) * inv_cell[a];
    return static_cast<int>(std::clamp(f, 0.0f, static_cast<float>(res[a] - 1)));
  }
  /// Coordinate of the boundary plane k along axis a (k = 0 .. res[a]).
  float plane(int a, int k) const { return k == res[a] ? box.hi[a] : box.lo[a] + static_cast<float>(k) * cell[a]; }
  Bounds3f cell_box(int i, int j, int k) const {
    Bounds3f b;
    b.lo = {plane(0, i), plane(1, j), plane(2, k)};
    b.hi = {plane(0, i + 1), plane(1, j + 1), plane(2, k + 1)};
    return b;
  }
};

/// The placement margin δ of a scene with bounds `b`: 2^-16 of (its largest coordinate magnitude
/// + its largest extent). Cells are widened by δ when primitives are placed, so that a point the
/// 3D-DDA attributes to a cell by float rounding (a few ulps of the coordinates) lies in that
/// cell's primitives' region; grids are built on the scene box widened by δ. The grids take the
/// bounds of the scene in their frame (grid_frame.h), whose coordinates are at most a few extents.
inline float grid_margin(const Bounds3f& b) {
  const float mag = std::max(max_component(abs(b.lo)), max_component(abs(b.hi)));
  return std::max(kGridMarginScale * (mag + max_component(b.diagonal())), 1e-30f);
}

/// Whether the float 3D-DDA (grid_traversal.h) of `ray` through a grid with box `box` and
/// placement margin `margin`, over an interval ending at t1, keeps every point o + t·d within
/// the margin of the cell whose interval holds t, so that the cell's list (placed on cells
/// widened by the margin) holds every primitive through that point. Rounding moves those points
/// by at most 32u·(|o|∞ + |t1|·|d|∞ + |box|∞), u = 2^-24: the start cell (o + d·t0 and its
/// cell index: 2u|d·t0| + u|o| + about 10u|box|), each crossing t* = (plane - o)·(1/d) (γ3 relative,
/// 3u(|plane| + |o|) along its axis), and the two ways planes are computed (cell_of for bbox
/// placement, plane() for exact placement and the DDA: about 10u|box|). The test asks for
/// twice that, half the margin, which leaves room for the nested grids' clipped intervals.
/// All in the grid's frame (grid_frame.h): `ray` is the ray in the frame, `box` and `margin` the
/// frame's. False for a ray from far outside (|o| much larger than the scene): the certified grids
/// then walk its EntryRay (below) instead.
inline bool dda_within_margin(const Ray& ray, float t1, const Bounds3f& box, float margin) {
  const float mag = std::max(max_component(abs(box.lo)), max_component(abs(box.hi)));
  const float reach = max_component(abs(ray.org)) + std::abs(t1) * max_component(abs(ray.dir)) + mag;
  return 0x1p-18f * reach <= margin;
}

/// A ray from far outside a grid, moved to where it enters the grid's box. The 3D-DDA of a ray
/// whose origin lies many grid extents away rounds its crossings to the ulps of |o| and leaves
/// the placement margin (dda_within_margin); moved, it rounds to the ulps of the grid's extent.
/// The entry and exit t of the world ray on the box (in the frame whose origin is `frame_origin`,
/// grid_frame.h), clipped to [tmin, tmax], are computed in double: the points where the world ray
/// crosses the box's planes are found within 2^-50·(|o - frame_origin|∞ + |box|∞), so the interval
/// misses or cuts off only points within that distance of the box's surface. The entry point
/// o + t_base·d is computed in double (within 2^-50 of |o|∞ + |t_base|·|d|∞ + |frame_origin|∞) and
/// rounded once into the frame (u/2 of its coordinates), so that `ray`'s point at s lies within
/// those bounds of the world ray's point at t_base + s, for s in [0, ray.tmax]. `offset` is their
/// sum, per axis; primitives lie at least the placement margin inside the grid's box, so with
/// offset below the margin, `missed` means the ray meets no primitive.
struct EntryRay {
  Ray ray;        ///< in the grid's frame: origin the entry point, tmin 0, tmax the length in t (rounded up)
  double t_base;  ///< the world ray's t at ray.org
  float offset;   ///< the bound above
  bool missed;    ///< the interval is empty (ray and t_base unset)
};

/// The EntryRay of `world` (its direction, and the t-range [world.tmin, tmax]) on `box`, a box in
/// the frame whose origin is `frame_origin`.
inline EntryRay entry_ray(const Ray& world, float tmax, const Bounds3f& box, const Vec3f& frame_origin) {
  EntryRay out{};
  const float box_mag = std::max(max_component(abs(box.lo)), max_component(abs(box.hi)));
  float reach = box_mag;
  double t0 = world.tmin, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    const double o = double(world.org[a]) - double(frame_origin[a]), d = world.dir[a];
    reach = std::max(reach, float(std::abs(o)) + box_mag);
    if (d == 0.0) {
      if (o < box.lo[a] || o > box.hi[a]) t1 = -1.0;
      continue;
    }
    double tn = (double(box.lo[a]) - o) / d, tf = (double(box.hi[a]) - o) / d;
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
  }
  out.missed = !(t0 <= t1);
  if (!out.missed) {
    for (int a = 0; a < 3; ++a) {
      out.ray.org[a] = static_cast<float>(double(world.org[a]) + t0 * double(world.dir[a]) - double(frame_origin[a]));
      reach = std::max(reach, std::abs(world.org[a]) + float(std::abs(t0)) * std::abs(world.dir[a]) +
                                  std::abs(frame_origin[a]));
    }
    out.ray.dir = world.dir;
    out.ray.tmin = 0.0f;
    out.ray.tmax = std::nextafter(static_cast<float>(t1 - t0), std::numeric_limits<float>::infinity());
    out.t_base = t0;
  }
  out.offset = 0x1p-24f * max_component(abs(out.ray.org)) + 0x1p-49f * reach;
  return out;
}

inline Bounds3f widened(Bounds3f b, float margin) {
  b.lo = b.lo - Vec3f(margin);
  b.hi = b.hi + Vec3f(margin);
  return b;
}

}  // namespace raylab
