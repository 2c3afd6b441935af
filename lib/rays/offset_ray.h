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
/// p and so with its rounding error; near the origin, where ulps become tiny, a fixed float
/// offset is added instead. The paper's constants, a threshold |p| < 1/32 and an offset n/65536,
/// are for a scene of unit size; both are multiplied by `scene_scale` (the diagonal of the scene's
/// bounding box; 1 when it is not a positive finite number), so a scene and a uniformly scaled
/// copy get the same rays up to rounding. With the paper's constants, a mesh scaled by 10^-4 had
/// its diffuse rays start 1.5·10^-5 off its surface, a tenth of its diagonal.
inline Vec3f offset_ray_origin(const Vec3f& p, const Vec3f& n, float scene_scale) {
  const float scale = std::isfinite(scene_scale) && scene_scale > 0.0f ? scene_scale : 1.0f;
  const float origin = scale / 32.0f;
  const float float_offset = scale / 65536.0f;
  constexpr float kIntScale = 256.0f;
  Vec3f out;
  for (int a = 0; a < 3; ++a) {
    const auto of_i = static_cast<std::int32_t>(kIntScale * n[a]);
    const auto bits = std::bit_cast<std::int32_t>(p[a]);
    const float p_i = std::bit_cast<float>(bits + (p[a] < 0.0f ? -of_i : of_i));
    out[a] = std::abs(p[a]) < origin ? p[a] + float_offset * n[a] : p_i;
  }
  return out;
}

}  // namespace raylab
