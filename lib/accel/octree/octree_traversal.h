#pragma once
/// Front-to-back octree traversal in ray order, two ways (OctreeConfig::traversal):
///  - octree_traverse_revelles: the parametric algorithm of Revelles, Ureña and Lastra (WSCG
///    2000), octree_revelles.h.
///  - octree_traverse_kd: each node's three centre planes taken one at a time (x, then y, then
///    z), each exactly as a kd-tree split (kdtree_traversal.h: the plane's t is computed once,
///    widened by its rounding error, and a ray lying in a plane visits one side). It visits the
///    same children in the same order as Revelles's algorithm, by a different mechanism (up to
///    three plane crossings per node instead of one ordered walk over the eight children), and
///    is kept for comparison.
#include <cmath>
#include <cstdint>

#include "accel/kdtree/kdtree_traversal.h"
#include "accel/octree/octree_node.h"
#include "accel/octree/octree_revelles.h"

namespace raylab {

struct OctreeView {
  const OctNode* nodes;
  const std::uint32_t* prims;
  const Scene* scene;
  Bounds3f bounds;
};

/// Tests the primitives of a leaf (kd_test_primitives); true on a hit.
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
inline bool octree_test_leaf(const OctreeView& tree, const OctNode& node, typename Kernel::Context& ctx, Hit& hit,
                             KdMailbox<kMailbox>& mailbox, Counters& counters) {
  counters.leaf();
  return kd_test_primitives<Kernel, kAnyHit>(*tree.scene, tree.prims + node.first, node.count, ctx, hit, mailbox,
                                             counters);
}

template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool octree_traverse_kd(const OctreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  const Vec3f inv = safe_inverse(ray.dir);
  float t0, t1;
  if (!kd_root_interval(tree.bounds, traversal_ray<Kernel>(ray), inv, t0, t1)) return false;
  auto ctx = Kernel::prepare(ray);
  KdMailbox<kMailbox> mailbox;
  /// A node of the tree (level 0), or one of its half-, quarter- or eighth-cells selected by the
  /// first `level` bits of `bits` (level 3: child `bits`).
  struct Entry {
    Bounds3f box;
    std::uint32_t node;
    std::uint8_t level, bits;
    float tmin, tmax;
  };
  Entry stack[3 * 24 + 8];
  int top = 0;
  stack[top++] = {tree.bounds, 0, 0, 0, t0, t1};
  bool found = false;
  while (top > 0) {
    Entry e = stack[--top];
    if (Kernel::closest(ctx) < e.tmin) continue;  // the hit lies before this cell
    for (;;) {
      const OctNode& node = tree.nodes[e.node];
      if (e.level == 0) {
        if (node.is_leaf()) {
          if (octree_test_leaf<Kernel, kAnyHit>(tree, node, ctx, hit, mailbox, counters)) {
            found = true;
            if constexpr (kAnyHit) return true;
          }
          break;
        }
        counters.node();
      }
      if (e.level == 3) {
        if (!node.has_child(e.bits)) break;  // an empty child is not stored
        e = {octree_child_box(e.box, e.bits), node.child(e.bits), 0, 0, e.tmin, e.tmax};
        continue;
      }
      const int a = e.level;
      float t = (octree_mid(e.box, a) - ray.org[a]) * inv[a];
      if (std::isnan(t)) t = 0.0f;
      const float slack = std::isfinite(t) ? kKdPlaneSlack * std::abs(t) : 0.0f;
      const float t_lo = t - slack, t_hi = t + slack;
      const std::uint8_t lower = e.bits, upper = static_cast<std::uint8_t>(e.bits | (1u << a));
      const std::uint8_t near = inv[a] > 0.0f ? lower : upper, far = inv[a] > 0.0f ? upper : lower;
      const auto level = static_cast<std::uint8_t>(e.level + 1);
      if (t_lo > std::min(e.tmax, Kernel::closest(ctx))) {
        e.bits = near;
      } else if (t_hi < e.tmin) {
        e.bits = far;
      } else {
        stack[top++] = {e.box, e.node, level, far, std::max(t_lo, e.tmin), e.tmax};
        e.bits = near;
        e.tmax = std::min(t_hi, e.tmax);
      }
      e.level = level;
    }
  }
  return found;
}

template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool octree_traverse_revelles(const OctreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  auto ctx = Kernel::prepare(ray);
  KdMailbox<kMailbox> mailbox;
  bool found = false;
  auto leaf = [&](std::uint32_t index, const Bounds3f&, float, float) {
    const bool in_leaf = octree_test_leaf<Kernel, kAnyHit>(tree, tree.nodes[index], ctx, hit, mailbox, counters);
    found = found || in_leaf;
    return kAnyHit && in_leaf;
  };
  auto cut = [&] { return Kernel::closest(ctx); };
  octree_walk_revelles(tree.nodes, tree.bounds, traversal_ray<Kernel>(ray), leaf, cut, counters);
  return found;
}

}  // namespace raylab
