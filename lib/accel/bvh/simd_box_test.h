#pragma once
/// One ray against the N child boxes of a wide node at once.
///
///  - WideBoxRay<N, true>: Ize's conservative slab test (Ize, "Robust BVH Ray Traversal", JCGT
///    2013) lane by lane exactly as intersect_box (bounds.h) computes it: t = (bound - org)·inv
///    with a separate multiply, the far distance scaled by kIzeFarScale, and min/max operand
///    orders that reproduce intersect_box's branches, NaN (0·inf) lanes included. So a lane is
///    hit exactly when intersect_box accepts that box, with the same entry distance.
///  - WideBoxRay<N, false>: the fast slab test, near/far planes chosen by the direction's signs,
///    t = bound·inv - org·inv fused; may reject a box the ray touches within rounding.
#include <cmath>
#include <limits>

#include "accel/bvh/simd.h"
#include "accel/bvh/wide_bvh.h"
#include "geometry/bounds.h"

namespace raylab {

/// intersect_box's far-distance factor, 1 + 2γ(3).
inline constexpr float kIzeFarScale = 1.0f + 2.0f * (3.0f * std::numeric_limits<float>::epsilon() * 0.5f) /
                                                 (1.0f - 3.0f * std::numeric_limits<float>::epsilon() * 0.5f);

template <int N, bool kRobust>
struct WideBoxRay;

template <int N>
struct WideBoxRay<N, true> {
  using F = simd::Float<N>;
  F org[3], inv[3];
  float tmin;

  explicit WideBoxRay(const Ray& r) : tmin(r.tmin) {
    const Vec3f i = safe_inverse(r.dir);
    for (int a = 0; a < 3; ++a) {
      org[a] = F::broadcast(r.org[a]);
      inv[a] = F::broadcast(i[a]);
    }
  }

  /// Bit i set when child lane i (of bounds[6][N]) is hit on [tmin, tmax]; entry distances go
  /// to `entry` (32-byte aligned). Lanes past `used` are not masked here.
  unsigned hit(const float (*bounds)[N], float tmax, float* entry) const {
    F t0 = F::broadcast(tmin), t1 = F::broadcast(tmax);
    const F scale = F::broadcast(kIzeFarScale);
    for (int a = 0; a < 3; ++a) {
      const F tn = (F::load(bounds[a]) - org[a]) * inv[a];
      const F tf = (F::load(bounds[3 + a]) - org[a]) * inv[a];
      const F near = min(tf, tn);        // tn > tf ? tf : tn
      const F far = max(tn, tf) * scale; // tn > tf ? tn : tf
      t0 = max(near, t0);                // near > t0 ? near : t0 (NaN keeps t0)
      t1 = min(far, t1);                 // far < t1 ? far : t1 (NaN keeps t1)
    }
    t0.store(entry);
    return t0 <= t1;
  }
};

template <int N>
struct WideBoxRay<N, false> {
  using F = simd::Float<N>;
  F inv[3], org_inv[3];
  int near[3], far[3];
  float tmin;

  explicit WideBoxRay(const Ray& r) : tmin(r.tmin) {
    for (int a = 0; a < 3; ++a) {
      const float d = std::abs(r.dir[a]) < 1e-18f ? std::copysign(1e-18f, r.dir[a]) : r.dir[a];
      const float i = 1.0f / d;
      inv[a] = F::broadcast(i);
      org_inv[a] = F::broadcast(r.org[a] * i);
      near[a] = i >= 0.0f ? a : 3 + a;
      far[a] = i >= 0.0f ? 3 + a : a;
    }
  }

  unsigned hit(const float (*bounds)[N], float tmax, float* entry) const {
    F t0 = F::broadcast(tmin), t1 = F::broadcast(tmax);
    for (int a = 0; a < 3; ++a) {
      t0 = max(fmsub(F::load(bounds[near[a]]), inv[a], org_inv[a]), t0);
      t1 = min(fmsub(F::load(bounds[far[a]]), inv[a], org_inv[a]), t1);
    }
    t0.store(entry);
    return t0 <= t1;
  }
};

}  // namespace raylab
