#pragma once
/// Ray-triangle intersection kernels behind one interface.
///
///   Kernel::Context ctx = Kernel::prepare(ray);         // once per ray
///   Kernel::intersect(ctx, prim, p0, p1, p2, hit)      // per triangle
///   Kernel::intersect_sphere(ctx, prim, sphere, hit)   // per sphere
///
/// `intersect` reports a hit on the closed triangle only when it is strictly closer than the
/// current closest hit held in the context (initially ray.tmax) and not before ray.tmin; it then
/// updates the context and writes `hit`. Degenerate (zero-area) triangles are never hit.
///
///  - MollerTrumboreKernel: Möller and Trumbore, "Fast, Minimum Storage Ray/Triangle
///    Intersection", JGT 1997. Float; not watertight (rays through shared edges can miss both).
///  - WatertightKernel: Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1)
///    2013, with its double-precision recomputation of edge functions that evaluate to zero.
///  - ExactKernel (exact_predicates.h): CGAL exact predicates and exact first-hit ordering.
#include <cmath>
#include <utility>

#include "geometry/ray.h"
#include "geometry/sphere.h"

namespace raylab {

struct TriangleHit {
  float t = 0.0f, u = 0.0f, v = 0.0f;
};

enum class TriangleKernelKind { moller_trumbore, watertight, exact };

struct MollerTrumboreKernel {
  struct Context {
    Ray ray;
    float tmax;
  };
  static Context prepare(const Ray& ray) { return {ray, ray.tmax}; }
  static float closest(const Context& c) { return c.tmax; }

  static bool intersect(Context& c, unsigned /*prim*/, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, TriangleHit& hit) {
    const Vec3f e1 = p1 - p0, e2 = p2 - p0;
    const Vec3f pv = cross(c.ray.dir, e2);
    const float det = dot(e1, pv);
    if (det == 0.0f || !std::isfinite(det)) return false;
    const float inv_det = 1.0f / det;
    const Vec3f tv = c.ray.org - p0;
    const float u = dot(tv, pv) * inv_det;
    if (u < 0.0f || u > 1.0f) return false;
    const Vec3f qv = cross(tv, e1);
    const float v = dot(c.ray.dir, qv) * inv_det;
    if (v < 0.0f || u + v > 1.0f) return false;
    const float t = dot(e2, qv) * inv_det;
    if (!(t >= c.ray.tmin && t < c.tmax)) return false;
    c.tmax = t;
    hit = {t, u, v};
    return true;
  }

  static bool intersect_sphere(Context& c, unsigned /*prim*/, const Sphere& s, TriangleHit& hit) {
    float t, u, v;
    if (!raylab::intersect_sphere(s, c.ray, c.ray.tmin, c.tmax, t, u, v) || !(t < c.tmax)) return false;
    c.tmax = t;
    hit = {t, u, v};
    return true;
  }
};

/// The watertight test's shear (Woop, Benthin and Wald 2013, section 3): kz the dominant axis of
/// `dir`, kx and ky the other two, swapped when dir[kz] < 0 to keep the winding; sx, sy, sz shear
/// and scale the ray onto +z. Sets those six members of any kernel's context.
template <class Context>
[[gnu::always_inline]] inline void set_watertight_shear(Context& c, const Vec3f& dir) {
  static constexpr int kNextAxis[3] = {1, 2, 0};
  c.kz = max_abs_axis(dir);
  c.kx = kNextAxis[c.kz];
  c.ky = kNextAxis[c.kx];
  if (dir[c.kz] < 0.0f) std::swap(c.kx, c.ky);
  c.sx = dir[c.kx] / dir[c.kz];
  c.sy = dir[c.ky] / dir[c.kz];
  c.sz = 1.0f / dir[c.kz];
}

/// Sets `ctx` to Kernel::prepare(ray): in place where the kernel has prepare(Context&, const Ray&)
/// (a context too large to return and move per ray), else by assignment.
template <class Kernel>
[[gnu::always_inline]] inline void prepare_context(typename Kernel::Context& ctx, const Ray& ray) {
  if constexpr (requires { Kernel::prepare(ctx, ray); }) Kernel::prepare(ctx, ray);
  else ctx = Kernel::prepare(ray);
}

struct WatertightKernel {
  /// The per-ray shear of Woop et al.: kz is the dominant axis of the direction; kx, ky are
  /// swapped when d[kz] < 0 to keep the winding.
  struct Context {
    Vec3f org, dir;
    int kx, ky, kz;
    float sx, sy, sz;
    float tmin, tmax;
  };
  [[gnu::always_inline]] static Context prepare(const Ray& ray) {
    Context c;
    c.org = ray.org;
    c.dir = ray.dir;
    set_watertight_shear(c, ray.dir);
    c.tmin = ray.tmin;
    c.tmax = ray.tmax;
    return c;
  }
  static float closest(const Context& c) { return c.tmax; }

  static bool intersect(Context& c, unsigned /*prim*/, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, TriangleHit& hit) {
    const Vec3f a = p0 - c.org, b = p1 - c.org, d = p2 - c.org;
    const float ax = a[c.kx] - c.sx * a[c.kz], ay = a[c.ky] - c.sy * a[c.kz];
    const float bx = b[c.kx] - c.sx * b[c.kz], by = b[c.ky] - c.sy * b[c.kz];
    const float cx = d[c.kx] - c.sx * d[c.kz], cy = d[c.ky] - c.sy * d[c.kz];
    float U = cx * by - cy * bx;
    float V = ax * cy - ay * cx;
    float W = bx * ay - by * ax;
    if (U == 0.0f || V == 0.0f || W == 0.0f) {  // the paper's double-precision fallback
      U = static_cast<float>(double(cx) * double(by) - double(cy) * double(bx));
      V = static_cast<float>(double(ax) * double(cy) - double(ay) * double(cx));
      W = static_cast<float>(double(bx) * double(ay) - double(by) * double(ax));
    }
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return false;
    const float det = U + V + W;
    if (det == 0.0f || !std::isfinite(det)) return false;
    const float az = c.sz * a[c.kz], bz = c.sz * b[c.kz], cz = c.sz * d[c.kz];
    const float T = U * az + V * bz + W * cz;
    const float inv_det = 1.0f / det;
    const float t = T * inv_det;
    if (!(t >= c.tmin && t < c.tmax)) return false;
    c.tmax = t;
    hit = {t, V * inv_det, W * inv_det};
    return true;
  }

  static bool intersect_sphere(Context& c, unsigned /*prim*/, const Sphere& s, TriangleHit& hit) {
    float t, u, v;
    if (!raylab::intersect_sphere(s, Ray{c.org, c.dir, c.tmin, c.tmax}, c.tmin, c.tmax, t, u, v) || !(t < c.tmax)) return false;
    c.tmax = t;
    hit = {t, u, v};
    return true;
  }
};

}  // namespace raylab
