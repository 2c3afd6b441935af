#pragma once
/// Front-to-back kd-tree traversal (Kaplan 1985; Arvo; Jansen 1986; Havran's thesis ch. 5,
/// TA_B^rec), recursive and with an explicit stack.
///
/// At an interior node the split plane's t* = (s - o[a]) / d[a] is computed once. The child
/// holding the ray's points with t < t* is the near child (the lower one when d[a] > 0); with
/// the node's interval [tmin, tmax] the three cases are
///   t* > tmax:          only the near child, on [tmin, tmax];
///   t* < tmin:          only the far child, on [tmin, tmax];
///   tmin <= t* <= tmax: the near child on [tmin, t*], then the far child on [t*, tmax].
/// Robustness: t* carries a relative error below 3 ulps, so the comparisons use t* widened by
/// kPlaneSlack·|t*| on each side, or the interval widened as much (kd_traverse_lines): a child is
/// skipped only when the exact ray surely misses it.
/// A ray with d[a] = ±0 has inv[a] = +inf (safe_inverse) and t* = ±inf by its origin's side:
/// t* = +inf keeps it in the near (lower) child, t* = -inf in the far (upper) one. A ray lying in a split plane (d[a] = 0,
/// o[a] = s) has t* = 0·inf = NaN: every comparison with NaN is false, so it visits both
/// children on the whole interval (one would suffice, as every point of the plane lies in both
/// closed children and placement is closed). No branch tests for NaN or infinity: the widening
/// t*·(1 ∓ kPlaneSlack) maps ±inf to itself and NaN to NaN.
/// A hit ends traversal only once it lies inside the current cell's interval: the far child is
/// skipped when the closest hit so far is before the far child's entry.
/// With the certified kernel the same comparisons are conservative for the exact ray: the root
/// interval is taken on [tmin, initial_closest] (kernel_choice.h), Kernel::closest() is an upper
/// bound of the exact first hit raised past the rounding of any entry t, and the widened t* has
/// a relative slack (1e-6) above its rounding error (γ3 < 2^-21).
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/bvh/packed_triangles_simd.h"
#include "accel/common/kernel_choice.h"
#include "accel/common/tree_ray.h"
#include "accel/kdtree/kdtree_node.h"
#include "accel/kdtree/kdtree_node_lines.h"
#include "accel/kdtree/kdtree_triangle_soup.h"
#include "geometry/bounds.h"
#include "scene/scene_primitives.h"

namespace raylab {

/// The arrays traversal reads.
struct KdTreeView {
  const KdNode* nodes;
  const std::uint32_t* prims;
  const Scene* scene;
  Bounds3f bounds;
  /// The triangles by primitive id (kdtree_triangle_soup.h), or null: read the scene.
  const KdTriangle* tris = nullptr;
  /// The same nodes regrouped into cache lines (kdtree_node_lines.h), for kd_traverse_lines.
  const KdNode* lines = nullptr;
  /// The leaves of `lines` packed 4-wide (kd_pack_leaves), or null: a leaf of `lines` then holds
  /// its first packet's index instead of an offset into `prims`.
  const TrianglePacket* packets = nullptr;
};

/// The plane's t* at an interior node, with its widened bounds and the near/far children.
struct KdPlaneCrossing {
  float t_lo, t_hi;
  std::uint32_t near, far;
};

inline KdPlaneCrossing kd_cross(const KdNode& node, std::uint32_t index, const Ray& ray, const Vec3f& inv) {
  const int a = node.axis();
  const float t = (node.split - ray.org[a]) * inv[a];  // NaN: the ray lies in the plane
  const WidenedPlaneT w = widened_plane_t(t);
  const bool lower_first = inv[a] > 0.0f;  // inv = +inf for d = ±0: t* = ±inf keeps the origin's side
  const std::uint32_t lower = index + 1, upper = node.above_child();
  return {w.lo, w.hi, lower_first ? lower : upper, lower_first ? upper : lower};
}

/// Tests primitives prims[0, n) of `scene`, skipping those the mailbox has seen; true on a hit
/// (an any-hit query stops at the first).
template <bool kAnyHit, class Kernel, bool kMailbox, class Counters>
inline bool kd_test_primitives(const Scene& scene, const std::uint32_t* prims, std::uint32_t n,
                               TreeRay<Kernel, kMailbox>& r, Hit& hit, Counters& counters) {
  bool found = false;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (r.mailbox.seen(prims[i])) {
      counters.mailbox_skip();
      continue;
    }
    if (intersect_scene_primitive<Kernel>(scene, prims[i], r.ctx, hit, counters)) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
  }
  return found;
}

/// Tests the primitives of a leaf; returns true on a hit (any-hit queries stop there).
template <bool kAnyHit, class Kernel, bool kMailbox, class Counters>
inline bool kd_test_leaf(const KdTreeView& tree, const KdNode& node, TreeRay<Kernel, kMailbox>& r, Hit& hit,
                         Counters& counters) {
  counters.leaf();
  bool found = false;
  if (tree.tris != nullptr) {
    const std::uint32_t* p = tree.prims + node.first;
    for (std::uint32_t i = 0, n = node.count(); i < n; ++i) {
      const std::uint32_t prim = p[i];
      if (r.mailbox.seen(prim)) {
        counters.mailbox_skip();
        continue;
      }
      counters.prim_test();
      TriangleHit th;
      const KdTriangle& tri = tree.tris[prim];
      if (Kernel::intersect(r.ctx, prim, tri.v0, tri.v1, tri.v2, th)) {
        counters.prim_hit();
        set_scene_hit(hit, th, prim);
        found = true;
        if constexpr (kAnyHit) return true;
      }
    }
    return found;
  }
  return kd_test_primitives<kAnyHit>(*tree.scene, tree.prims + node.first, node.count(), r, hit, counters);
}

/// Tests a leaf of `lines` whose triangles are packed (kd_pack_leaves), in the leaf's order, with
/// the SIMD watertight kernel, bit-identical to kd_test_leaf (packed_triangles_simd.h): two
/// packets at a time as one 8-lane test where the kernel has one (kPairedPackets; measured on
/// BM_KdTrace, alternating, CPU time: 1.08x the kd-tree's throughput on primary and on diffuse
/// rays against one packet at a time), the last odd packet alone. With a mailbox, lane by lane
/// with the scalar kernel.
template <bool kAnyHit, class Kernel, bool kMailbox, class Counters>
inline bool kd_test_packed_leaf(const TrianglePacket* packet, std::uint32_t count, TreeRay<Kernel, kMailbox>& r,
                                Hit& hit, Counters& counters) {
  counters.leaf();
  bool found = false;
  for (std::uint32_t i = 0; i < count; i += kPacketWidth, ++packet) {
    const std::uint32_t lanes = std::min<std::uint32_t>(count - i, kPacketWidth);
    if constexpr (kMailbox) {
      for (std::uint32_t l = 0; l < lanes; ++l) {
        const std::uint32_t prim = packet->prim[l];
        if (r.mailbox.seen(prim)) {
          counters.mailbox_skip();
          continue;
        }
        counters.prim_test();
        TriangleHit th;
        const int lane = static_cast<int>(l);
        if (Kernel::intersect(r.ctx, prim, packet->vertex(lane, 0), packet->vertex(lane, 1), packet->vertex(lane, 2), th)) {
          counters.prim_hit();
          set_scene_hit(hit, th, prim);
          found = true;
          if constexpr (kAnyHit) return true;
        }
      }
    } else {
      if constexpr (kPairedPackets<Kernel>) {
        if (count - i > kPacketWidth) {
          const int pair_lanes = static_cast<int>(std::min<std::uint32_t>(count - i, 2 * kPacketWidth));
          if (intersect_triangle_packets<Kernel, kAnyHit, 2 * kPacketWidth>(r.ctx, r.packet, packet, pair_lanes, hit,
                                                                            counters)) {
            found = true;
            if constexpr (kAnyHit) return true;
          }
          i += kPacketWidth;
          ++packet;
          continue;
        }
      }
      if (intersect_triangle_packet<Kernel, kAnyHit>(r.ctx, r.packet, *packet, static_cast<int>(lanes), hit, counters)) {
        found = true;
        if constexpr (kAnyHit) return true;
      }
    }
  }
  return found;
}

/// Iterative traversal (Havran's TA_B^rec with an explicit stack) over the cache-line layout
/// (tree.lines, kdtree_node_lines.h), where the children of a node are the pair c, c + 1: the
/// near child is c + [inv[a] <= 0] without a branch. The three cases stay branches: a fully
/// branchless selection (cmov/blend) puts every node's load behind the previous node's
/// arithmetic and measured ~25% slower than predicted branches on BM_KdTrace. For kAnyHit,
/// returns at the first hit (the caller passes a ray whose tmax is already closed).
/// The slack is put on the interval rather than on t*: t* is compared with [lo, hi] =
/// [tmin - kPlaneSlack·|tmin|, min(tmax, closest) + kPlaneSlack·|min(tmax, closest)|], which
/// changes only when the interval does, and a child's bound is the unwidened t* (the slack of
/// 1e-6 on one side covers the rounding of both t's, 2γ3 < 2^-20). A widened infinite bound can
/// be NaN (inf - inf), which fails every comparison: the ray then visits both children, never
/// fewer. Measured on BM_KdTrace
/// (alternating, CPU time) 1.04x on primary and 1.05x on diffuse rays against widening t* at
/// every node.
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool kd_traverse_lines(const KdTreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  TreeRay<Kernel, kMailbox> r;
  if (!r.enter(ray, tree.bounds)) return false;
  float tmin = r.tmin, tmax = r.tmax;
  const Vec3f& inv = r.inv;
  const float org[4] = {ray.org.x, ray.org.y, ray.org.z, 0.0f}, rcp[4] = {inv.x, inv.y, inv.z, 0.0f};
  // Bit a, repeated every 4 bits: the upper child is the near one along axis a. Shifted by a
  // node's bits mod 32 (axis + 4·(above_child mod 8)) it gives that bit: one shift on the
  // node-to-node chain. BM_KdTrace (alternating, CPU time): a per-axis table load instead was
  // 1.03-1.10x slower, shifting by the masked axis 1.01x slower (17 of 18 runs).
  const std::uint32_t upper_first =
      ((inv.x > 0.0f ? 0u : 1u) | (inv.y > 0.0f ? 0u : 2u) | (inv.z > 0.0f ? 0u : 4u)) * 0x11111111u;
  auto below = [](float x) { return x - kPlaneSlack * std::abs(x); };
  auto above = [](float x) { return x + kPlaneSlack * std::abs(x); };
  struct Entry {
    std::uint32_t node;
    float tmin, tmax;
  };
  Entry stack[72];  // depth <= 64
  int top = 0;
  bool found = false;
  std::uint32_t index = 0;
  for (;;) {
    const KdNode* node = &tree.lines[index];
    float lo = below(tmin), hi = above(std::min(tmax, Kernel::closest(r.ctx)));
    while (!node->is_leaf()) {
      counters.node();
      const std::uint32_t a = node->bits & 3u;
      const float t = (node->split - org[a]) * rcp[a];  // NaN: the ray lies in the plane
      const std::uint32_t near = node->above_child() + ((upper_first >> (node->bits & 31u)) & 1u), far = near ^ 1u;
      if (t > hi) {  // t* > tmax
        index = near;
      } else if (t < lo) {  // t* < tmin
        index = far;
      } else {  // tmin <= t* <= tmax (NaN: both, whole)
        // An empty leaf (an empty-space cut-off's child) is not visited: an empty near child
        // hands the ray to the far one, an empty far child is not pushed.
        const float far_tmin = t > tmin ? t : tmin;
        if (tree.lines[near].is_empty_leaf()) {
          index = far;
          tmin = far_tmin;
          lo = below(tmin);
        } else {
          stack[top] = {far, far_tmin, tmax};
          top += !tree.lines[far].is_empty_leaf();
          index = near;
          tmax = t < tmax ? t : tmax;
          hi = above(std::min(tmax, Kernel::closest(r.ctx)));
        }
      }
      node = &tree.lines[index];
    }
    const bool h = tree.packets != nullptr
                       ? kd_test_packed_leaf<kAnyHit>(tree.packets + node->first, node->count(), r, hit, counters)
                       : kd_test_leaf<kAnyHit>(tree, *node, r, hit, counters);
    if (h) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
    do {
      if (top == 0) return found;
      --top;
    } while (Kernel::closest(r.ctx) < below(stack[top].tmin));  // the hit lies before that cell
    index = stack[top].node;
    tmin = stack[top].tmin;
    tmax = stack[top].tmax;
  }
}

/// Recursive traversal, the lecture's form.
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
struct KdRecursiveTraversal {
  const KdTreeView& tree;
  const Ray& ray;
  TreeRay<Kernel, kMailbox>& r;
  Hit& hit;
  Counters& counters;
  bool found = false;

  /// Returns true when an any-hit query is answered.
  bool visit(std::uint32_t index, float tmin, float tmax) {
    const KdNode& node = tree.nodes[index];
    if (node.is_leaf()) {
      const bool h = kd_test_leaf<kAnyHit>(tree, node, r, hit, counters);
      found |= h;
      return kAnyHit && h;
    }
    counters.node();
    const KdPlaneCrossing c = kd_cross(node, index, ray, r.inv);
    if (c.t_lo > std::min(tmax, Kernel::closest(r.ctx))) return visit(c.near, tmin, tmax);  // t* > tmax
    if (c.t_hi < tmin) return visit(c.far, tmin, tmax);                                  // t* < tmin
    if (visit(c.near, tmin, c.t_hi < tmax ? c.t_hi : tmax)) return true;  // tmin <= t* <= tmax (NaN: both, whole)
    const float far_tmin = c.t_lo > tmin ? c.t_lo : tmin;
    if (Kernel::closest(r.ctx) < far_tmin) return false;  // the hit lies inside the near cell
    return visit(c.far, far_tmin, tmax);
  }
};

template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool kd_traverse_recursive(const KdTreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  TreeRay<Kernel, kMailbox> r;
  if (!r.enter(ray, tree.bounds)) return false;
  KdRecursiveTraversal<Kernel, kAnyHit, kMailbox, Counters> t{tree, ray, r, hit, counters};
  t.visit(0, r.tmin, r.tmax);
  return t.found;
}

}  // namespace raylab
