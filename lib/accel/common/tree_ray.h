#pragma once
/// A ray prepared for a front-to-back traversal of a spatial subdivision (kd-tree, octree, BSP
/// tree): its reciprocal direction, its interval in the root box, the triangle kernel's context
/// and its broadcast form for the 4-wide leaf test, and an optional mailbox.
///
/// Robustness: a plane's or box face's t = (p - o[a]) · inv[a] carries a relative error below
/// 3 ulps, so traversals compare t widened by kPlaneSlack·|t| on each side (kdtree_traversal.h).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "accel/bvh/packed_triangles_simd.h"
#include "accel/common/kernel_choice.h"
#include "geometry/bounds.h"

namespace raylab {

/// The relative widening of a plane's t (above its rounding error of 3 ulps, and above the
/// certified kernel's γ3 < 2^-21).
inline constexpr float kPlaneSlack = 1e-6f;

/// A plane's t widened by kPlaneSlack·|t| on each side: lo <= t <= hi for finite t, ±inf kept,
/// and NaN (the ray lies in the plane) in both, which fails every comparison.
struct WidenedPlaneT {
  float lo, hi;
};
inline WidenedPlaneT widened_plane_t(float t) {
  const float w0 = t * (1.0f - kPlaneSlack), w1 = t * (1.0f + kPlaneSlack);
  return {w0 < w1 ? w0 : w1, w0 < w1 ? w1 : w0};
}

/// A direct-mapped mailbox of the last primitives a ray tested (Amanatides and Woo 1987): a
/// primitive tested once need not be tested again, since the closest hit only moves closer.
template <bool kEnabled>
struct TreeMailbox {
  std::uint32_t slot[8] = {kInvalidId, kInvalidId, kInvalidId, kInvalidId,
                           kInvalidId, kInvalidId, kInvalidId, kInvalidId};
  bool seen(std::uint32_t prim) {
    std::uint32_t& s = slot[prim & 7u];
    if (s == prim) return true;
    s = prim;
    return false;
  }
};
template <>
struct TreeMailbox<false> {
  bool seen(std::uint32_t) { return false; }
};

/// The entry interval [t0, t1] of `ray` into `bounds`, widened like a plane's t and clamped to
/// [ray.tmin, ray.tmax]; false when the ray misses the box.
inline bool tree_root_interval(const Bounds3f& bounds, const Ray& ray, const Vec3f& inv, float& t0, float& t1) {
  if (!intersect_box(bounds, ray, inv, ray.tmin, ray.tmax, t0, t1)) return false;
  t0 = std::max(ray.tmin, t0 - kPlaneSlack * std::abs(t0));
  t1 = std::min(ray.tmax, t1 + kPlaneSlack * std::abs(t1));
  return true;
}

/// The ray as a traversal reads it: set by enter() (or prepare(), for a traversal that finds its
/// own root interval).
template <class Kernel, bool kMailbox = false>
struct TreeRay {
  Vec3f inv;                                  ///< safe_inverse(dir): +inf for d = ±0
  float tmin, tmax;                           ///< the root interval (tree_root_interval)
  typename Kernel::Context ctx;               ///< the kernel's context; Kernel::closest(ctx) is the hit so far
  typename PacketKernel<Kernel>::Ray packet;  ///< ctx broadcast for the packed leaf test
  TreeMailbox<kMailbox> mailbox;

  /// Prepares the kernel's context (and its packet form) for `ray`, without the root interval
  /// (for a traversal that computes its own).
  void prepare(const Ray& ray) {
    prepare_context<Kernel>(ctx, ray);
    packet = typename PacketKernel<Kernel>::Ray(ctx);
  }

  /// Prepares `ray` for a tree over `bounds`: false when it misses the box, which is tested with
  /// tmax raised as initial_closest() (kernel_choice.h); the context is then left unprepared.
  bool enter(const Ray& ray, const Bounds3f& bounds) {
    inv = safe_inverse(ray.dir);
    if (!tree_root_interval(bounds, traversal_ray<Kernel>(ray), inv, tmin, tmax)) return false;
    prepare(ray);
    return true;
  }
};

}  // namespace raylab
