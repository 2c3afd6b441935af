#pragma once
/// Spawning secondary rays from a surface point without self-intersection.
#include <bit>
#include <cmath>
#include <cstdint>

#include "geometry/vec3.h"

namespace raylab {

/// Moves the surface point `p` off the surface along the unit normal `n` (pointing to the side
/// the new ray leaves into) by a few float ulps, as in Wächter and Binder, "A Fast and Robust
/// Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6 (2019): away from the origin
/// the offset is an integer number of ulps (256·n per axis), which scales with the magnitude of
/// p and so with its rounding error; near the origin (|p| < 1/32), where ulps become tiny, a
/// fixed float offset of n/65536 is added instead. The constants are the paper's.
inline Vec3f offset_ray_origin(const Vec3f& p, const Vec3f& n) {
  constexpr float kOrigin = 1.0f / 32.0f;
  constexpr float kFloatScale = 1.0f / 65536.0f;
  constexpr float kIntScale = 256.0f;
  Vec3f out;
  for (int a = 0; a < 3; ++a) {
    const auto of_i = static_cast<std::int32_t>(kIntScale * n[a]);
    const auto bits = std::bit_cast<std::int32_t>(p[a]);
    const float p_i = std::bit_cast<float>(bits + (p[a] < 0.0f ? -of_i : of_i));
    out[a] = std::abs(p[a]) < kOrigin ? p[a] + kFloatScale * n[a] : p_i;
  }
  return out;
}

}  // namespace raylab
