#pragma once
/// One ray against the N child boxes of a wide node at once.
///
///  - WideBoxRay<N, true>: Ize's conservative slab test (Ize, "Robust BVH Ray Traversal", JCGT
///    2013) lane by lane exactly as intersect_box (bounds.h) computes it: t = (bound - org)·inv
///    with a separate multiply, the far distance scaled by kIzeFarScale, and min/max operand
///    orders that reproduce intersect_box's branches, NaN (0·inf) lanes included. So a lane is
///    hit exactly when intersect_box accepts that box, with the same entry distance (up to the
///    sign of a zero).
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
  int near[3], far[3];
  bool finite_inverse;
  float tmin;

  explicit WideBoxRay(const Ray& r) : tmin(r.tmin) {
    // safe_inverse as one division: d + 0 turns -0 into +0, and IEEE 1/+0 is +inf.
    alignas(16) float i[4];
    const __m128 d = _mm_add_ps(_mm_setr_ps(r.dir.x, r.dir.y, r.dir.z, 1.0f), _mm_setzero_ps());
    _mm_store_ps(i, _mm_div_ps(_mm_set1_ps(1.0f), d));
    finite_inverse = true;
    for (int a = 0; a < 3; ++a) {
      org[a] = F::broadcast(r.org[a]);
      inv[a] = F::broadcast(i[a]);
      near[a] = i[a] >= 0.0f ? a : 3 + a;
      far[a] = i[a] >= 0.0f ? 3 + a : a;
      // Under FTZ, |d| > 2^126 gives a flushed inverse of 0, and (±inf - o)·0 = NaN would keep an
      // empty lane's t0 at tmin: such rays take the masked path as zero components do.
      finite_inverse = finite_inverse && std::isfinite(i[a]) && i[a] != 0.0f;
    }
  }

  /// Bit i set when child i of `node` is hit on [tmin, tmax]; entry distances go to `entry`
  /// (32-byte aligned).
  [[gnu::always_inline]] unsigned hit(const WideBvhNode<N>& node, float tmax, float* entry) const {
    const float (*bounds)[N] = node.bounds;
    if (finite_inverse) {
      // No component of the direction is zero: rounding is monotone, so lo <= hi gives
      // (lo - o)·inv <= (hi - o)·inv for inv > 0 and >= for inv < 0, and no product is NaN;
      // intersect_box's swap is then the choice of planes by the sign of inv (equal distances
      // may differ in the sign of a zero, which no comparison sees). An empty lane (+inf, -inf)
      // gives near = +inf, far = -inf and misses.
      F t0 = F::broadcast(tmin), far_min = F::broadcast(std::numeric_limits<float>::infinity());
      for (int a = 0; a < 3; ++a) {
        t0 = max((F::load(bounds[near[a]]) - org[a]) * inv[a], t0);
        far_min = min((F::load(bounds[far[a]]) - org[a]) * inv[a], far_min);
      }
      const F t1 = min(far_min * F::broadcast(kIzeFarScale), F::broadcast(tmax));
      t0.store(entry);
      return t0 <= t1;
    }
    // intersect_box scales each far distance and takes min(far·s, t1) per axis; rounding is
    // monotone, so min over axes of far·s equals (min over axes of far)·s, NaN lanes skipped
    // alike (the running minimum starts at +inf, and +inf·s = +inf leaves t1 unchanged).
    F t0 = F::broadcast(tmin), far_min = F::broadcast(std::numeric_limits<float>::infinity());
    for (int a = 0; a < 3; ++a) {
      const F tn = (F::load(bounds[a]) - org[a]) * inv[a];
      const F tf = (F::load(bounds[3 + a]) - org[a]) * inv[a];
      t0 = max(min(tf, tn), t0);        // near = tn > tf ? tf : tn; near > t0 ? near : t0 (NaN keeps t0)
      far_min = min(max(tn, tf), far_min);  // far = tn > tf ? tn : tf; NaN keeps the running minimum
    }
    const F t1 = min(far_min * F::broadcast(kIzeFarScale), F::broadcast(tmax));
    t0.store(entry);
    return (t0 <= t1) & ((1u << node.used) - 1);  // an inverted slab is swapped: mask empty lanes
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

  /// As the robust test. Empty lanes (+inf, -inf) give near = +inf > far, except where an
  /// inverse flushed to 0 (|d| > 2^126 under FTZ) makes them NaN: the result is masked by `used`.
  [[gnu::always_inline]] unsigned hit(const WideBvhNode<N>& node, float tmax, float* entry) const {
    const float (*bounds)[N] = node.bounds;
    F t0 = F::broadcast(tmin), t1 = F::broadcast(tmax);
    for (int a = 0; a < 3; ++a) {
      t0 = max(fmsub(F::load(bounds[near[a]]), inv[a], org_inv[a]), t0);
      t1 = min(fmsub(F::load(bounds[far[a]]), inv[a], org_inv[a]), t1);
    }
    t0.store(entry);
    return (t0 <= t1) & ((1u << node.used) - 1);
  }
};

}  // namespace raylab
