#include "geometry/triangle_clipping.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace raylab {

namespace {

/// A clip polygon: at most 3 + 6 vertices (each clip adds at most one).
struct ClipPolygon {
  double p[12][3];
  unsigned exact[12];  ///< bit k: coordinate k is the exact coordinate of the true vertex
  int n = 0;
};

/// Keeps the part of `in` with sign·(p[axis] - plane) >= 0 (one Sutherland-Hodgman step).
/// Returns false, leaving `out` untouched, when every vertex is kept: the clip is then the
/// identity.
bool clip_polygon(const ClipPolygon& in, int axis, double plane, double sign, ClipPolygon& out) {
  double d[12];
  bool all_in = true;
  for (int i = 0; i < in.n; ++i) {
    d[i] = sign * (in.p[i][axis] - plane);
    all_in &= d[i] >= 0.0;
  }
  if (all_in) return false;
  int m = 0;
  for (int i = 0; i < in.n; ++i) {
    const int j = i + 1 == in.n ? 0 : i + 1;
    const double da = d[i], db = d[j];
    if (da >= 0.0) {
      for (int k = 0; k < 3; ++k) out.p[m][k] = in.p[i][k];
      out.exact[m++] = in.exact[i];
    }
    if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
      const double s = da / (da - db);
      for (int k = 0; k < 3; ++k) out.p[m][k] = in.p[i][k] + (in.p[j][k] - in.p[i][k]) * s;
      out.p[m][axis] = plane;
      out.exact[m++] = 1u << axis;
    }
  }
  out.n = m;
  return true;
}

/// std::nextafter(f, -inf) for f not NaN and not -inf, on the bits (so independent of the
/// denormal modes, like the library function).
float next_down(float f) {
  const auto b = std::bit_cast<std::uint32_t>(f);
  const std::uint32_t down = (b & 0x7fffffffu) == 0 ? 0x80000001u : ((b >> 31) ? b + 1 : b - 1);
  return std::bit_cast<float>(down);
}
/// std::nextafter(f, +inf) for f not NaN and not +inf.
float next_up(float f) {
  const auto b = std::bit_cast<std::uint32_t>(f);
  const std::uint32_t up = (b & 0x7fffffffu) == 0 ? 0x00000001u : ((b >> 31) ? b - 1 : b + 1);
  return std::bit_cast<float>(up);
}
/// The largest float <= x and the smallest float >= x, without branches.
float round_down(double x) {
  const float f = static_cast<float>(x);
  const float g = next_down(f);
  return static_cast<double>(f) > x ? g : f;
}
float round_up(double x) {
  const float f = static_cast<float>(x);
  const float g = next_up(f);
  return static_cast<double>(f) < x ? g : f;
}

ClipPolygon triangle_polygon(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  ClipPolygon a;
  for (const Vec3f& p : {p0, p1, p2}) {
    a.p[a.n][0] = p.x;
    a.p[a.n][1] = p.y;
    a.p[a.n][2] = p.z;
    a.exact[a.n++] = 7u;
  }
  return a;
}

/// Clips poly[cur] to the six slabs of `box`, leaving the result in poly[cur]; false when it
/// vanishes in double precision.
bool clip_to_box(ClipPolygon (&poly)[2], int& cur, const Bounds3f& box) {
  for (int axis = 0; axis < 3; ++axis) {
    if (clip_polygon(poly[cur], axis, box.lo[axis], 1.0, poly[cur ^ 1])) cur ^= 1;
    if (clip_polygon(poly[cur], axis, box.hi[axis], -1.0, poly[cur ^ 1])) cur ^= 1;
    if (poly[cur].n == 0) return false;
  }
  return true;
}

/// The clipped polygon's bounds, widened and rounded outward, intersected with `fallback` (the
/// triangle's bounds intersected with the box clipped to).
Bounds3f polygon_bounds(const ClipPolygon& a, const Bounds3f& box, const Bounds3f& tri, const Bounds3f& fallback) {
  // Each computed coordinate is a convex combination evaluated in double after at most seven
  // clips; 1e-12 of the magnitude of the coordinates bounds its error with a wide margin.
  const double scale = std::max(max_component(abs(Vec3d(box.lo))), max_component(abs(Vec3d(box.hi))));
  const double scale_tri = std::max(max_component(abs(Vec3d(tri.lo))), max_component(abs(Vec3d(tri.hi))));
  const double margin = 1e-12 * (std::max(scale, scale_tri) + std::numeric_limits<double>::min());
  // round_down and round_up are monotone: rounding the extremes equals the extremes of the
  // rounded coordinates.
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int i = 0; i < a.n; ++i)
    for (int k = 0; k < 3; ++k) {
      const double x = a.p[i][k];
      const double m = (a.exact[i] >> k & 1u) ? 0.0 : margin;
      lo[k] = std::min(lo[k], x - m);
      hi[k] = std::max(hi[k], x + m);
    }
  Bounds3f r;
  for (int k = 0; k < 3; ++k) {
    r.lo[k] = round_down(lo[k]);
    r.hi[k] = round_up(hi[k]);
  }
  return intersect(r, fallback);
}

}  // namespace

Bounds3f clipped_triangle_bounds(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box) {
  Bounds3f tri(p0, p1);
  tri.extend(p2);
  const Bounds3f fallback = intersect(tri, box);
  // Entirely inside: nothing to clip, the bounds are exact.
  if (box.contains(tri.lo) && box.contains(tri.hi)) return tri;
  ClipPolygon poly[2] = {triangle_polygon(p0, p1, p2), {}};
  int cur = 0;
  if (!clip_to_box(poly, cur, box)) return fallback;
  return polygon_bounds(poly[cur], box, tri, fallback);
}

void clipped_triangle_bounds_split(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box, int axis,
                                   float pos, Bounds3f& lower, Bounds3f& upper) {
  Bounds3f tri(p0, p1);
  tri.extend(p2);
  const Bounds3f lower_box = box.below(axis, pos), upper_box = box.above(axis, pos);
  const Bounds3f lower_fallback = intersect(tri, lower_box), upper_fallback = intersect(tri, upper_box);
  const bool in_lower = lower_box.contains(tri.lo) && lower_box.contains(tri.hi);
  const bool in_upper = upper_box.contains(tri.lo) && upper_box.contains(tri.hi);
  ClipPolygon poly[2] = {triangle_polygon(p0, p1, p2), {}};
  int cur = 0;
  if (!(in_lower || in_upper) && !clip_to_box(poly, cur, box)) {
    lower = lower_fallback;
    upper = upper_fallback;
    return;
  }
  ClipPolygon half;
  auto side = [&](bool inside, double sign, const Bounds3f& child, const Bounds3f& fallback) {
    if (inside) return tri;  // entirely in the child: exact
    const ClipPolygon* a = &poly[cur];
    if (clip_polygon(poly[cur], axis, pos, sign, half)) a = &half;
    return a->n == 0 ? fallback : polygon_bounds(*a, child, tri, fallback);
  };
  lower = side(in_lower, -1.0, lower_box, lower_fallback);
  upper = side(in_upper, 1.0, upper_box, upper_fallback);
}

double clipped_triangle_area(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box) {
  ClipPolygon poly[2] = {triangle_polygon(p0, p1, p2), {}};
  int cur = 0;
  if (!clip_to_box(poly, cur, box)) return 0.0;
  const ClipPolygon& a = poly[cur];
  // Half the norm of Σ (v_i - v_0) × (v_{i+1} - v_0) over the fan of the convex polygon.
  Vec3d sum(0.0);
  const Vec3d v0(a.p[0][0], a.p[0][1], a.p[0][2]);
  for (int i = 1; i + 1 < a.n; ++i) {
    const Vec3d u = Vec3d(a.p[i][0], a.p[i][1], a.p[i][2]) - v0;
    const Vec3d w = Vec3d(a.p[i + 1][0], a.p[i + 1][1], a.p[i + 1][2]) - v0;
    sum = sum + cross(u, w);
  }
  return 0.5 * length(sum);
}

}  // namespace raylab
