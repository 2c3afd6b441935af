#pragma once
/// A ray o + t·d restricted to t in [tmin, tmax]. The direction is not required to be unit length:
/// every kernel and accelerator reports t in the units of the given direction, so t survives
/// affine transforms of the ray unchanged (pbrt's TransformedPrimitive convention).
#include <limits>

#include "geometry/vec3.h"

namespace raylab {

struct Ray {
  Vec3f org;
  Vec3f dir;
  float tmin = 0.0f;
  float tmax = std::numeric_limits<float>::infinity();

  Vec3f at(float t) const { return org + dir * t; }
};

/// True when origin and direction are finite, the direction is non-zero and 0 <= tmin <= tmax
/// (tmax may be +inf). Accelerators return "no hit" for any other ray.
inline bool is_valid(const Ray& r) {
  return is_finite(r.org) && is_finite(r.dir) && (r.dir.x != 0.0f || r.dir.y != 0.0f || r.dir.z != 0.0f) &&
         r.tmin >= 0.0f && r.tmin <= r.tmax;  // comparisons are false for NaN
}

inline constexpr unsigned kInvalidId = 0xffffffffu;

/// The first hit along a ray. `prim` indexes the scene's primitives (triangles first, then
/// spheres); `instance` is the instance index for instanced scenes and kInvalidId otherwise.
/// (u, v) are the barycentrics of the hit for triangles (p = (1-u-v)·p0 + u·p1 + v·p2) and the
/// spherical angles normalised to [0,1] for spheres.
struct Hit {
  float t = std::numeric_limits<float>::infinity();
  float u = 0.0f, v = 0.0f;
  unsigned prim = kInvalidId;
  unsigned instance = kInvalidId;

  bool valid() const { return prim != kInvalidId; }
};

}  // namespace raylab
