#pragma once
/// The lecture's BVH2 stack traversal: the nearer child (by box entry distance) is visited
/// first, the farther one is pushed with its entry distance and skipped on pop once the closest
/// hit so far lies before it.
///
/// Box tests: the robust variant is Ize's conservative slab test (Ize 2013, bounds.h), so a box
/// the exact ray touches is never rejected; with the watertight kernel the traversal then
/// agrees with the exact oracle. The fast variant is the usual slab test on precomputed
/// origin·(1/d) products, which may reject a box the ray touches within rounding.
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/bvh/bvh_node.h"
#include "geometry/bounds.h"

namespace raylab {

/// Per-ray data of the box test.
template <bool kRobust>
struct BvhRay;

template <>
struct BvhRay<true> {
  Ray ray;
  Vec3f inv;
  explicit BvhRay(const Ray& r) : ray(r), inv(safe_inverse(r.dir)) {}
  /// Entry distance into `box` on [ray.tmin, tmax], or false.
  bool hit(const Bounds3f& box, float tmax, float& entry) const {
    float t0, t1;
    if (!intersect_box(box, ray, inv, ray.tmin, tmax, t0, t1)) return false;
    entry = t0;
    return true;
  }
};

template <>
struct BvhRay<false> {
  Vec3f inv, org_inv;
  float tmin;
  explicit BvhRay(const Ray& r) : tmin(r.tmin) {
    for (int a = 0; a < 3; ++a) {
      const float d = std::abs(r.dir[a]) < 1e-18f ? std::copysign(1e-18f, r.dir[a]) : r.dir[a];
      inv[a] = 1.0f / d;
      org_inv[a] = r.org[a] * inv[a];
    }
  }
  bool hit(const Bounds3f& box, float tmax, float& entry) const {
    float t0 = tmin, t1 = tmax;
    for (int a = 0; a < 3; ++a) {
      float tn = box.lo[a] * inv[a] - org_inv[a];
      float tf = box.hi[a] * inv[a] - org_inv[a];
      if (tn > tf) std::swap(tn, tf);
      t0 = tn > t0 ? tn : t0;
      t1 = tf < t1 ? tf : t1;
    }
    entry = t0;
    return t0 <= t1;
  }
};

/// Traverses `nodes` (root 0). `closest` is the current closest-hit distance, which
/// `leaf(first, count, closest)` lowers when it finds a hit and reports by returning true.
/// Returns whether any leaf reported a hit; with kAnyHit the first such report ends traversal.
template <bool kRobust, bool kAnyHit, class Counters, class LeafFn>
bool traverse_bvh2(const Bvh2Node* nodes, const Ray& ray, float& closest, Counters& counters, LeafFn&& leaf) {
  const BvhRay<kRobust> r(ray);
  struct Entry {
    std::uint32_t node;
    float t;
  };
  Entry stack[kBvhMaxDepth + 1];
  int top = 0;
  float entry;
  if (!r.hit(nodes[0].box, closest, entry)) return false;
  stack[top++] = {0u, entry};
  bool found = false;
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.t > closest) continue;
    std::uint32_t index = e.node;
    for (;;) {
      const Bvh2Node& node = nodes[index];
      if (node.is_leaf()) {
        counters.leaf();
        if (leaf(node.first, node.count, closest)) {
          found = true;
          if constexpr (kAnyHit) return true;
        }
        break;
      }
      counters.node();
      float t_left, t_right;
      const bool hit_left = r.hit(nodes[node.first].box, closest, t_left);
      const bool hit_right = r.hit(nodes[node.first + 1].box, closest, t_right);
      if (hit_left && hit_right) {
        const bool left_first = t_left <= t_right;
        stack[top++] = left_first ? Entry{node.first + 1, t_right} : Entry{node.first, t_left};
        index = left_first ? node.first : node.first + 1;
      } else if (hit_left) {
        index = node.first;
      } else if (hit_right) {
        index = node.first + 1;
      } else {
        break;
      }
    }
  }
  return found;
}

}  // namespace raylab
