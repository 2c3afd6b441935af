#pragma once
/// Spheres, the second shape (the sphereflake, and the lecture's theory section).
#include <cmath>
#include <numbers>

#include "geometry/bounds.h"
#include "geometry/ray.h"

namespace raylab {

struct Sphere {
  Vec3f center;
  float radius = 0.0f;

  Bounds3f bounds() const {
    // Rounded outward by one float ulp of the largest coordinate so the box contains the sphere.
    const float slack = radius * (1.0f + 4.0f * std::numeric_limits<float>::epsilon());
    Bounds3f b(center - Vec3f(slack), center + Vec3f(slack));
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::nextafter(b.lo[a], -std::numeric_limits<float>::infinity());
      b.hi[a] = std::nextafter(b.hi[a], std::numeric_limits<float>::infinity());
    }
    return b;
  }
};

/// Closest hit of a ray with a sphere surface in [tmin, tmax], computed in double with the
/// numerically stable quadratic (pbrt-v4 §6.8.1 / Ray Tracing Gems ch. 7: the discriminant from
/// the distance of the centre to the line). Returns false on a miss.
inline bool intersect_sphere(const Sphere& s, const Ray& ray, float tmin, float tmax, float& t_out, float& u_out,
                             float& v_out) {
  const Vec3d o = Vec3d(ray.org) - Vec3d(s.center);
  const Vec3d d(ray.dir);
  const double a = dot(d, d);
  const double b = dot(o, d);
  const Vec3d closest = o - d * (b / a);
  const double r = s.radius;
  const double disc = a * (r * r - dot(closest, closest));
  if (disc < 0.0) return false;
  const double q = -b - std::copysign(std::sqrt(disc), b);
  double t0 = q / a, t1 = (q != 0.0) ? (dot(o, o) - r * r) / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  double t = t0;
  if (t < tmin) t = t1;
  if (t < tmin || t > tmax) return false;
  const Vec3d p = o + d * t;
  const double phi = std::atan2(p.y, p.x);
  const double theta = std::acos(std::clamp(p.z / r, -1.0, 1.0));
  t_out = static_cast<float>(t);
  u_out = static_cast<float>((phi + std::numbers::pi) / (2 * std::numbers::pi));
  v_out = static_cast<float>(theta / std::numbers::pi);
  return true;
}

}  // namespace raylab
