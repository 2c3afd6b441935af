#pragma once
/// Axis-aligned boxes. An empty box has lo = +inf, hi = -inf so that `extend` needs no branch.
#include <limits>

#include "geometry/ray.h"
#include "geometry/vec3.h"

namespace raylab {

template <class T>
struct Bounds3 {
  Vec3<T> lo{std::numeric_limits<T>::infinity()};
  Vec3<T> hi{-std::numeric_limits<T>::infinity()};

  constexpr Bounds3() = default;
  constexpr Bounds3(const Vec3<T>& a, const Vec3<T>& b) : lo(min(a, b)), hi(max(a, b)) {}
  explicit constexpr Bounds3(const Vec3<T>& p) : lo(p), hi(p) {}

  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  void extend(const Vec3<T>& p) { lo = min(lo, p); hi = max(hi, p); }
  void extend(const Bounds3& b) { lo = min(lo, b.lo); hi = max(hi, b.hi); }
  Vec3<T> diagonal() const { return hi - lo; }
  Vec3<T> center() const { return (lo + hi) * T(0.5); }
  T surface_area() const {
    if (empty()) return T(0);
    const Vec3<T> d = diagonal();
    return T(2) * (d.x * d.y + d.y * d.z + d.z * d.x);
  }
  bool contains(const Vec3<T>& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  /// The lower and upper parts of a split at `pos` along `axis`: hi[axis] or lo[axis] becomes pos.
  Bounds3 below(int axis, T pos) const {
    Bounds3 b = *this;
    b.hi[axis] = pos;
    return b;
  }
  Bounds3 above(int axis, T pos) const {
    Bounds3 b = *this;
    b.lo[axis] = pos;
    return b;
  }
  bool overlaps(const Bounds3& b) const {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z && b.lo.z <= hi.z;
  }
  int largest_axis() const {
    const Vec3<T> d = diagonal();
    return d.x >= d.y ? (d.x >= d.z ? 0 : 2) : (d.y >= d.z ? 1 : 2);
  }
};

template <class T> inline Bounds3<T> join(Bounds3<T> a, const Bounds3<T>& b) { a.extend(b); return a; }
template <class T> inline Bounds3<T> intersect(const Bounds3<T>& a, const Bounds3<T>& b) {
  Bounds3<T> r; r.lo = max(a.lo, b.lo); r.hi = min(a.hi, b.hi); return r;
}

using Bounds3f = Bounds3<float>;
using Bounds3d = Bounds3<double>;

/// Ray-box slab test with Ize's conservative rounding (Ize, "Robust BVH Ray Traversal", JCGT
/// 2013): the far distance is scaled by 1 + 2γ(3) so that a box the exact ray touches is never
/// rejected. `inv_dir` holds 1/d per component (±inf for zero components; a 0·inf NaN compares
/// false and keeps the interval). On success the entry/exit are written to [t0, t1].
inline bool intersect_box(const Bounds3f& b, const Ray& ray, const Vec3f& inv_dir, float tmin, float tmax, float& t0,
                          float& t1) {
  constexpr float kFarScale = 1.0f + 2.0f * (3.0f * std::numeric_limits<float>::epsilon() * 0.5f) /
                                         (1.0f - 3.0f * std::numeric_limits<float>::epsilon() * 0.5f);
  for (int a = 0; a < 3; ++a) {
    float tn = (b.lo[a] - ray.org[a]) * inv_dir[a];
    float tf = (b.hi[a] - ray.org[a]) * inv_dir[a];
    if (tn > tf) std::swap(tn, tf);
    tf *= kFarScale;
    tmin = tn > tmin ? tn : tmin;  // NaN (0·inf) keeps the previous bound
    tmax = tf < tmax ? tf : tmax;
    if (tmin > tmax) return false;
  }
  t0 = tmin;
  t1 = tmax;
  return true;
}

/// 1/d per component, with +inf for both +0 and -0: a ray parallel to a slab then keeps the
/// slab's interval exactly when its origin lies in the closed slab (a -inf inverse would turn an
/// origin on the slab's face into an empty interval).
inline Vec3f safe_inverse(const Vec3f& d) {
  auto inv = [](float x) { return x != 0.0f ? 1.0f / x : std::numeric_limits<float>::infinity(); };
  return {inv(d.x), inv(d.y), inv(d.z)};
}

}  // namespace raylab
