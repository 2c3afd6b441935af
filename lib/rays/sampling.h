#pragma once
/// Warps from the unit square to directions and disks (pbrt-v4, "Sampling Algorithms", ch. A.5)
/// and the orthonormal basis they are expressed in.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "geometry/vec3.h"

namespace raylab {

/// An orthonormal basis (s, t, n) around the unit vector n, branch-free and continuous except
/// at n.z = -1 (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1) 2017).
struct Frame {
  Vec3d s, t, n;

  explicit Frame(const Vec3d& unit_n) : n(unit_n) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    s = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t = {b, sign + n.y * n.y * a, -n.y};
  }
  Vec3d to_world(const Vec3d& local) const { return s * local.x + t * local.y + n * local.z; }
};

/// Uniform direction on the unit sphere (Archimedes: z uniform in [-1, 1]).
inline Vec3d sample_uniform_sphere(double u1, double u2) {
  const double z = 1.0 - 2.0 * u1;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.0 * std::numbers::pi * u2;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Uniform point on the unit disk in the xy-plane (polar map, r = sqrt(u1)).
inline Vec3d sample_uniform_disk(double u1, double u2) {
  const double r = std::sqrt(u1);
  const double phi = 2.0 * std::numbers::pi * u2;
  return {r * std::cos(phi), r * std::sin(phi), 0.0};
}

/// Cosine-weighted direction about +z (Malley's method: a uniform disk point lifted to the
/// hemisphere); density cos(theta)/pi.
inline Vec3d sample_cosine_hemisphere(double u1, double u2) {
  const Vec3d d = sample_uniform_disk(u1, u2);
  return {d.x, d.y, std::sqrt(std::max(0.0, 1.0 - d.x * d.x - d.y * d.y))};
}

/// Uniform direction in the cone of half-angle acos(cos_max) about +z.
inline Vec3d sample_uniform_cone(double u1, double u2, double cos_max) {
  const double cos_theta = 1.0 - u1 * (1.0 - cos_max);
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  const double phi = 2.0 * std::numbers::pi * u2;
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

}  // namespace raylab
