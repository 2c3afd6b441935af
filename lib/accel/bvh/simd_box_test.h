#pragma once
/// One ray against the N child boxes of a wide node at once.
///
///  - WideBoxRay<N, true>: Ize's conservative slab test (Ize, "Robust BVH Ray Traversal", JCGT
///    2013). Where no direction component is zero (or flushed), each plane distance is one FMA,
///    t = bound·inv - c, with c = org·inv rounded and then moved by 4u·|c| (u = 2^-24; at least
///    2^-126) away from the box: up for near planes, down for far ones, so c covers the exact
///    org·inv, and the near distance is at most (bound - org)·inv computed exactly and rounded
///    once, the far one at least it. Each is then within a factor (1 ± u)^2 of the exact distance with the exact
///    1/d, and Ize's far factor 1 + 2γ3 (> (1 + u)^2 / (1 - u)^2, rounding included) keeps every
///    box the exact ray meets; entries exceed the exact ones by at most (1 + u)^2 (intersect_box:
///    (1 + u)^3). Otherwise (a zero component) lane by lane exactly as intersect_box computes it:
///    t = (bound - org)·inv, the far distance scaled by kIzeFarScale, min/max operand orders that
///    reproduce intersect_box's branches, NaN (0·inf) lanes included.
///  - WideBoxRay<N, false>: the fast slab test, near/far planes chosen by the direction's signs,
///    t = bound·inv - org·inv fused; may reject a box the ray touches within rounding.
///
/// Both read a node's planes as floats: a quantized node's (quantized_wide_node.h) are
/// dequantized first, and its boxes enclose the full node's, so both tests keep every child the
/// full node's test keeps, with an entry no later (monotone in the planes).
#include <algorithm>
#include <cmath>
#include <limits>

#include "accel/bvh/quantized_wide_node.h"
#include "accel/bvh/simd.h"
#include "accel/bvh/wide_bvh.h"
#include "geometry/bounds.h"

namespace raylab {

/// intersect_box's far-distance factor, 1 + 2γ(3).
inline constexpr float kIzeFarScale = 1.0f + 2.0f * (3.0f * std::numeric_limits<float>::epsilon() * 0.5f) /
                                                 (1.0f - 3.0f * std::numeric_limits<float>::epsilon() * 0.5f);

/// Plane `p` of a node's N child boxes (0..2: lower x, y, z; 3..5: upper), `a` = p mod 3.
template <int N>
[[gnu::always_inline]] inline simd::Float<N> child_planes(const WideBvhNode<N>& node, int p, int /*a*/) {
  return simd::Float<N>::load(node.bounds[p]);
}
template <int N>
[[gnu::always_inline]] inline simd::Float<N> child_planes(const QuantizedWideBvhNode<N>& node, int p, int a) {
  using F = simd::Float<N>;
  return fmadd(F::from_bytes(node.q[p]), F::broadcast(node.step[a]), F::broadcast(node.origin[a]));  // = dequantize
}

/// Whether a node's unused lanes hold empty boxes (+inf, -inf) that every fused test misses.
template <class Node>
inline constexpr bool kUnusedLanesMiss = true;
template <int N>
inline constexpr bool kUnusedLanesMiss<QuantizedWideBvhNode<N>> = false;

template <int N, bool kRobust>
struct WideBoxRay;

template <int N>
struct WideBoxRay<N, true> {
  using F = simd::Float<N>;
  F inv[3];
  F org_inv_near[3], org_inv_far[3];  ///< c for near and far planes (see above)
  float org[3];  ///< broadcast only on the rare path with a zero component
  int near[3], far[3];
  bool fused;  ///< every inverse finite and non-zero, every c finite: the FMA test applies
  float tmin;

  [[gnu::always_inline]] explicit WideBoxRay(const Ray& r) : tmin(r.tmin) {
    // safe_inverse as one division: d + 0 turns -0 into +0, and IEEE 1/+0 is +inf.
    alignas(16) float i[4], c_near[4], c_far[4];
    const __m128 d = _mm_add_ps(_mm_setr_ps(r.dir.x, r.dir.y, r.dir.z, 1.0f), _mm_setzero_ps());
    const __m128 iv = _mm_div_ps(_mm_set1_ps(1.0f), d);
    // fl(c + p) >= c + p - u·|c + p| >= c + 2.9u·|c|, beyond the exact org·inv (within u·|c| of
    // c, or 2^-126 where FTZ flushed it); likewise below. Lane 3 (org 0, inverse 1) is finite.
    const __m128 c = _mm_mul_ps(_mm_setr_ps(r.org.x, r.org.y, r.org.z, 0.0f), iv);
    const __m128 pad = _mm_max_ps(_mm_mul_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), c), _mm_set1_ps(0x1p-22f)),
                                  _mm_set1_ps(std::numeric_limits<float>::min()));
    const __m128 cn = _mm_add_ps(c, pad), cf = _mm_sub_ps(c, pad);
    _mm_store_ps(i, iv);
    _mm_store_ps(c_near, cn);
    _mm_store_ps(c_far, cf);
    // Under FTZ, |d| > 2^126 gives a flushed inverse of 0, and (±inf - o)·0 = NaN would keep an
    // empty lane's t0 at tmin: such rays take the masked path as zero components do, as do rays
    // whose c overflows. |x| < inf is false for ±inf and NaN.
    const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity()), abs_mask = _mm_set1_ps(-0.0f);
    const auto finite = [&](__m128 x) { return _mm_cmplt_ps(_mm_andnot_ps(abs_mask, x), inf); };
    const __m128 ok = _mm_and_ps(_mm_and_ps(finite(iv), _mm_cmpneq_ps(iv, _mm_setzero_ps())),
                                 _mm_and_ps(finite(cn), finite(cf)));
    fused = _mm_movemask_ps(ok) == 0xF;
#if !defined(__FMA__)
    fused = false;  // bound·inv must not round on its own
#endif
    for (int a = 0; a < 3; ++a) {
      org[a] = r.org[a];
      inv[a] = F::broadcast(i[a]);
      org_inv_near[a] = F::broadcast(c_near[a]);
      org_inv_far[a] = F::broadcast(c_far[a]);
      near[a] = i[a] >= 0.0f ? a : 3 + a;
      far[a] = i[a] >= 0.0f ? 3 + a : a;
    }
  }

  /// Bit i set when child i of `node` (a WideBvhNode<N> or QuantizedWideBvhNode<N>) is hit on
  /// [tmin, tmax]; entry distances go to `entry` (32-byte aligned).
  template <class Node>
  [[gnu::always_inline]] unsigned hit(const Node& node, float tmax, float* entry) const {
    if (fused) {
      // No component of the direction is zero: the planes are chosen by the sign of inv, and no
      // distance is NaN. An empty lane (+inf, -inf) gives near = +inf, far = -inf and misses.
      F t0 = F::broadcast(tmin), far_min = F::broadcast(std::numeric_limits<float>::infinity());
      for (int a = 0; a < 3; ++a) {
        t0 = max(fmsub(child_planes(node, near[a], a), inv[a], org_inv_near[a]), t0);
        far_min = min(fmsub(child_planes(node, far[a], a), inv[a], org_inv_far[a]), far_min);
      }
      const F t1 = min(far_min * F::broadcast(kIzeFarScale), F::broadcast(tmax));
      t0.store(entry);
      if constexpr (kUnusedLanesMiss<Node>) return t0 <= t1;
      return (t0 <= t1) & ((1u << node.used) - 1);
    }
    // intersect_box scales each far distance and takes min(far·s, t1) per axis; rounding is
    // monotone, so min over axes of far·s equals (min over axes of far)·s, NaN lanes skipped
    // alike (the running minimum starts at +inf, and +inf·s = +inf leaves t1 unchanged).
    F t0 = F::broadcast(tmin), far_min = F::broadcast(std::numeric_limits<float>::infinity());
    for (int a = 0; a < 3; ++a) {
      const F o = F::broadcast(org[a]);
      const F tn = (child_planes(node, a, a) - o) * inv[a];
      const F tf = (child_planes(node, 3 + a, a) - o) * inv[a];
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

  [[gnu::always_inline]] explicit WideBoxRay(const Ray& r) : tmin(r.tmin) {
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
  template <class Node>
  [[gnu::always_inline]] unsigned hit(const Node& node, float tmax, float* entry) const {
    F t0 = F::broadcast(tmin), t1 = F::broadcast(tmax);
    for (int a = 0; a < 3; ++a) {
      t0 = max(fmsub(child_planes(node, near[a], a), inv[a], org_inv[a]), t0);
      t1 = min(fmsub(child_planes(node, far[a], a), inv[a], org_inv[a]), t1);
    }
    t0.store(entry);
    return (t0 <= t1) & ((1u << node.used) - 1);
  }
};

}  // namespace raylab
