#include "geometry/triangle_clipping.h"

#include <array>
#include <cmath>
#include <limits>

namespace raylab {
namespace {

struct ClipVertex {
  Vec3d p;
  bool exact[3];  ///< per coordinate: the value is the exact coordinate of the true vertex
};

/// A polygon of at most 3 + 6 vertices (each clip adds at most one).
struct Polygon {
  std::array<ClipVertex, 12> v;
  int n = 0;
};

/// Keeps the part of `in` with sign·(p[axis] - plane) >= 0.
void clip(const Polygon& in, int axis, double plane, double sign, Polygon& out) {
  out.n = 0;
  for (int i = 0; i < in.n; ++i) {
    const ClipVertex& a = in.v[i];
    const ClipVertex& b = in.v[(i + 1) % in.n];
    const double da = sign * (a.p[axis] - plane), db = sign * (b.p[axis] - plane);
    if (da >= 0.0) out.v[out.n++] = a;
    if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
      const double s = da / (da - db);
      ClipVertex c;
      c.p = a.p + (b.p - a.p) * s;
      for (int k = 0; k < 3; ++k) c.exact[k] = false;
      c.p[axis] = plane;
      c.exact[axis] = true;
      out.v[out.n++] = c;
    }
  }
}

float round_down(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
float round_up(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

Bounds3f clipped_triangle_bounds(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box) {
  Bounds3f tri(p0, p1);
  tri.extend(p2);
  const Bounds3f fallback = intersect(tri, box);
  // Entirely inside: nothing to clip, the bounds are exact.
  if (box.contains(tri.lo) && box.contains(tri.hi)) return tri;

  Polygon a, b;
  for (const Vec3f& p : {p0, p1, p2}) a.v[a.n++] = ClipVertex{Vec3d(p), {true, true, true}};
  for (int axis = 0; axis < 3; ++axis) {
    clip(a, axis, box.lo[axis], 1.0, b);
    clip(b, axis, box.hi[axis], -1.0, a);
    if (a.n == 0) return fallback;
  }
  // Each computed coordinate is a convex combination evaluated in double after at most six
  // clips; 1e-12 of the magnitude of the coordinates bounds its error with a wide margin.
  const double scale = std::max(max_component(abs(Vec3d(box.lo))), max_component(abs(Vec3d(box.hi))));
  const double scale_tri = std::max(max_component(abs(Vec3d(tri.lo))), max_component(abs(Vec3d(tri.hi))));
  const double margin = 1e-12 * (std::max(scale, scale_tri) + std::numeric_limits<double>::min());
  Bounds3f r;
  for (int i = 0; i < a.n; ++i)
    for (int k = 0; k < 3; ++k) {
      const double x = a.v[i].p[k];
      const double m = a.v[i].exact[k] ? 0.0 : margin;
      r.lo[k] = std::min(r.lo[k], round_down(x - m));
      r.hi[k] = std::max(r.hi[k], round_up(x + m));
    }
  return intersect(r, fallback);
}

}  // namespace raylab
