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
/// kKdPlaneSlack·|t*| on each side (a child is skipped only when the exact ray surely misses it).
/// A ray with d[a] = ±0 has inv[a] = +inf (safe_inverse) and t* = ±inf by its origin's side:
/// t* = +inf keeps it in the near (lower) child, t* = -inf in the far (upper) one. A ray lying in a split plane (d[a] = 0,
/// o[a] = s) has t* = 0·inf = NaN: every comparison with NaN is false, so it visits both
/// children on the whole interval (one would suffice, as every point of the plane lies in both
/// closed children and placement is closed). No branch tests for NaN or infinity: the widening
/// t*·(1 ∓ kKdPlaneSlack) maps ±inf to itself and NaN to NaN.
/// A hit ends traversal only once it lies inside the current cell's interval: the far child is
/// skipped when the closest hit so far is before the far child's entry.
/// With the certified kernel the same comparisons are conservative for the exact ray: the root
/// interval is taken on [tmin, initial_closest] (kernel_choice.h), Kernel::closest() is an upper
/// bound of the exact first hit raised past the rounding of any entry t, and the widened t* has
/// a relative slack (1e-6) above its rounding error (γ3 < 2^-21).
#include <immintrin.h>

#include <cmath>
#include <cstring>
#include <cstdint>
#include <limits>

#include "accel/bvh/packed_triangles_simd.h"
#include "accel/common/kernel_choice.h"
#include "accel/kdtree/kdtree_node.h"
#include "accel/kdtree/kdtree_node_lines.h"
#include "accel/kdtree/kdtree_treelets.h"
#include "accel/kdtree/kdtree_triangle_soup.h"
#include "geometry/bounds.h"
#include "scene/scene_primitives.h"

namespace raylab {

inline constexpr float kKdPlaneSlack = 1e-6f;

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
  /// The same tree in two-level treelets (kdtree_treelets.h), for kd_traverse_treelets; their
  /// leaves index `packets` and `big_leaves`, and `treelet_root` is the root's child word.
  const KdTreelet* treelets = nullptr;
  const KdBigLeaf* big_leaves = nullptr;
  std::uint32_t treelet_root = kKdEmptyChild;
};

/// A direct-mapped mailbox of the last primitives a ray tested (Amanatides and Woo 1987): a
/// primitive tested once need not be tested again, since the closest hit only moves closer.
template <bool kEnabled>
struct KdMailbox {
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
struct KdMailbox<false> {
  bool seen(std::uint32_t) { return false; }
};

/// The entry interval of a ray into the root box, widened like the split t's.
inline bool kd_root_interval(const Bounds3f& bounds, const Ray& ray, const Vec3f& inv, float& t0, float& t1) {
  if (!intersect_box(bounds, ray, inv, ray.tmin, ray.tmax, t0, t1)) return false;
  t0 = std::max(ray.tmin, t0 - kKdPlaneSlack * std::abs(t0));
  t1 = std::min(ray.tmax, t1 + kKdPlaneSlack * std::abs(t1));
  return true;
}

/// The plane's t* at an interior node, with its widened bounds and the near/far children.
struct KdPlaneCrossing {
  float t_lo, t_hi;
  std::uint32_t near, far;
};

inline KdPlaneCrossing kd_cross(const KdNode& node, std::uint32_t index, const Ray& ray, const Vec3f& inv) {
  const int a = node.axis();
  const float t = (node.split - ray.org[a]) * inv[a];  // NaN: the ray lies in the plane
  const float w0 = t * (1.0f - kKdPlaneSlack), w1 = t * (1.0f + kKdPlaneSlack);
  const bool lower_first = inv[a] > 0.0f;  // inv = +inf for d = ±0: t* = ±inf keeps the origin's side
  const std::uint32_t lower = index + 1, upper = node.above_child();
  return {w0 < w1 ? w0 : w1, w0 < w1 ? w1 : w0, lower_first ? lower : upper, lower_first ? upper : lower};
}

/// A split plane's t* = (split - o) · inv widened by kKdPlaneSlack on each side, as in kd_cross
/// (NaN when the ray lies in the plane).
struct KdSlab {
  float lo, hi;
};

/// Tests primitives prims[0, n) of `scene`, skipping those the mailbox has seen; true on a hit
/// (an any-hit query stops at the first).
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
inline bool kd_test_primitives(const Scene& scene, const std::uint32_t* prims, std::uint32_t n,
                               typename Kernel::Context& ctx, Hit& hit, KdMailbox<kMailbox>& mailbox,
                               Counters& counters) {
  bool found = false;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (mailbox.seen(prims[i])) {
      counters.mailbox_skip();
      continue;
    }
    if (intersect_scene_primitive<Kernel>(scene, prims[i], ctx, hit, counters)) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
  }
  return found;
}

/// Tests the primitives of a leaf; returns true on a hit (any-hit queries stop there).
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
inline bool kd_test_leaf(const KdTreeView& tree, const KdNode& node, typename Kernel::Context& ctx, Hit& hit,
                         KdMailbox<kMailbox>& mailbox, Counters& counters) {
  counters.leaf();
  bool found = false;
  if (tree.tris != nullptr) {
    const std::uint32_t* p = tree.prims + node.first;
    for (std::uint32_t i = 0, n = node.count(); i < n; ++i) {
      const std::uint32_t prim = p[i];
      if (mailbox.seen(prim)) {
        counters.mailbox_skip();
        continue;
      }
      counters.prim_test();
      TriangleHit th;
      const KdTriangle& tri = tree.tris[prim];
      if (Kernel::intersect(ctx, prim, tri.v0, tri.v1, tri.v2, th)) {
        counters.prim_hit();
        set_scene_hit(hit, th, prim);
        found = true;
        if constexpr (kAnyHit) return true;
      }
    }
    return found;
  }
  return kd_test_primitives<Kernel, kAnyHit>(*tree.scene, tree.prims + node.first, node.count(), ctx, hit, mailbox,
                                             counters);
}

/// Tests a leaf of `lines` whose triangles are packed (kd_pack_leaves), in the leaf's order, with
/// the SIMD watertight kernel, bit-identical to kd_test_leaf (packed_triangles_simd.h); with a
/// mailbox, lane by lane with the scalar kernel.
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
inline bool kd_test_packed_leaf(const TrianglePacket* packet, std::uint32_t count, typename Kernel::Context& ctx,
                                const typename PacketKernel<Kernel>::Ray& packet_ray, Hit& hit,
                                KdMailbox<kMailbox>& mailbox, Counters& counters) {
  counters.leaf();
  bool found = false;
  for (std::uint32_t i = 0; i < count; i += kPacketWidth, ++packet) {
    const std::uint32_t lanes = std::min<std::uint32_t>(count - i, kPacketWidth);
    if constexpr (kMailbox) {
      for (std::uint32_t l = 0; l < lanes; ++l) {
        const std::uint32_t prim = packet->prim[l];
        if (mailbox.seen(prim)) {
          counters.mailbox_skip();
          continue;
        }
        counters.prim_test();
        TriangleHit th;
        const int lane = static_cast<int>(l);
        if (Kernel::intersect(ctx, prim, packet->vertex(lane, 0), packet->vertex(lane, 1), packet->vertex(lane, 2), th)) {
          counters.prim_hit();
          set_scene_hit(hit, th, prim);
          found = true;
          if constexpr (kAnyHit) return true;
        }
      }
    } else {
      if (intersect_triangle_packet<Kernel, kAnyHit>(ctx, packet_ray, *packet, static_cast<int>(lanes), hit, counters)) {
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
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool kd_traverse_lines(const KdTreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  const Vec3f inv = safe_inverse(ray.dir);
  float tmin, tmax;
  if (!kd_root_interval(tree.bounds, traversal_ray<Kernel>(ray), inv, tmin, tmax)) return false;
  auto ctx = Kernel::prepare(ray);
  const typename PacketKernel<Kernel>::Ray packet_ray(ctx);
  KdMailbox<kMailbox> mailbox;
  const float org[4] = {ray.org.x, ray.org.y, ray.org.z, 0.0f}, rcp[4] = {inv.x, inv.y, inv.z, 0.0f};
  const std::uint32_t upper_first[4] = {inv.x > 0.0f ? 0u : 1u, inv.y > 0.0f ? 0u : 1u, inv.z > 0.0f ? 0u : 1u, 0u};
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
    while (!node->is_leaf()) {
      counters.node();
      const std::uint32_t a = node->bits & 3u;
      const float t = (node->split - org[a]) * rcp[a];  // NaN: the ray lies in the plane
      const float w0 = t * (1.0f - kKdPlaneSlack), w1 = t * (1.0f + kKdPlaneSlack);
      const float t_lo = w0 < w1 ? w0 : w1, t_hi = w0 < w1 ? w1 : w0;
      const std::uint32_t near = node->above_child() + upper_first[a], far = near ^ 1u;
      if (t_lo > std::min(tmax, Kernel::closest(ctx))) {  // t* > tmax
        index = near;
      } else if (t_hi < tmin) {  // t* < tmin
        index = far;
      } else {  // tmin <= t* <= tmax (NaN: both, whole)
        // An empty leaf (an empty-space cut-off's child) is not visited: an empty near child
        // hands the ray to the far one, an empty far child is not pushed.
        const float far_tmin = t_lo > tmin ? t_lo : tmin;
        if (tree.lines[near].is_empty_leaf()) {
          index = far;
          tmin = far_tmin;
        } else {
          stack[top] = {far, far_tmin, tmax};
          top += !tree.lines[far].is_empty_leaf();
          index = near;
          tmax = t_hi < tmax ? t_hi : tmax;
        }
      }
      node = &tree.lines[index];
    }
    const bool h = tree.packets != nullptr
                       ? kd_test_packed_leaf<Kernel, kAnyHit, kMailbox>(tree.packets + node->first, node->count(), ctx,
                                                                        packet_ray, hit, mailbox, counters)
                       : kd_test_leaf<Kernel, kAnyHit, kMailbox>(tree, *node, ctx, hit, mailbox, counters);
    if (h) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
    do {
      if (top == 0) return found;
      --top;
    } while (Kernel::closest(ctx) < stack[top].tmin);  // the hit lies before that cell
    index = stack[top].node;
    tmin = stack[top].tmin;
    tmax = stack[top].tmax;
  }
}

/// The slabs (KdSlab) of a treelet's three planes, lane k for plane k (lane 3 unused), computed
/// together: lane j of org4 and rcp4 is the ray's origin and inverse direction along axis j
/// (lane 3: 0 and +inf, the plane-less axis kKdNoPlane, whose plane at 1 gives t* = +inf).
/// Bit-identical to kd_cross's t_lo and t_hi plane by plane.
struct KdTreeletSlabs {
  alignas(16) float lo[4];
  alignas(16) float hi[4];
};

inline KdTreeletSlabs kd_treelet_slabs(const KdTreelet& n, __m128 org4, __m128 rcp4) {
  const __m128 split = _mm_load_ps(n.split);  // lane 3 holds the axis bytes: unused
#if defined(__AVX__)
  std::int32_t axes;
  std::memcpy(&axes, n.axis, sizeof axes);
  const __m128i axis = _mm_cvtepu8_epi32(_mm_cvtsi32_si128(axes));
  const __m128 o = _mm_permutevar_ps(org4, axis), r = _mm_permutevar_ps(rcp4, axis);
#else
  alignas(16) float org[4], rcp[4];
  _mm_store_ps(org, org4);
  _mm_store_ps(rcp, rcp4);
  const __m128 o = _mm_setr_ps(org[n.axis[0]], org[n.axis[1]], org[n.axis[2]], 0.0f);
  const __m128 r = _mm_setr_ps(rcp[n.axis[0]], rcp[n.axis[1]], rcp[n.axis[2]], 0.0f);
#endif
  static constexpr float kBelow = 1.0f - kKdPlaneSlack, kAbove = 1.0f + kKdPlaneSlack;
  const __m128 t = _mm_mul_ps(_mm_sub_ps(split, o), r);  // NaN: the ray lies in the plane
  const __m128 w0 = _mm_mul_ps(t, _mm_set1_ps(kBelow)), w1 = _mm_mul_ps(t, _mm_set1_ps(kAbove));
  KdTreeletSlabs s;
  _mm_store_ps(s.lo, _mm_min_ps(w0, w1));  // w0 < w1 ? w0 : w1
  _mm_store_ps(s.hi, _mm_max_ps(w1, w0));  // w1 > w0 ? w1 : w0, so w0 on NaN
  return s;
}

/// Iterative traversal over two-level treelets (tree.treelets, kdtree_treelets.h): the same
/// front-to-back order and the same widened comparisons as kd_traverse_lines, two levels per
/// node load. The three planes' t* are computed independently; the near side X of plane 0 is
/// side [inv[a0] <= 0], and under it the near side of plane 1 + X, so the four grandchildren in
/// ray order and their intervals follow from the direction signs without a branch:
///   near side of plane 0 on [tmin, min(t0_hi, tmax)], far side on [max(t0_lo, tmin), tmax],
///   each split again by its own plane the same way.
/// A grandchild is entered when its interval is not empty and starts before the closest hit
/// (lo <= min(hi, closest)); the later ones are pushed far first, the first is entered. The
/// min/max keep the bound on a NaN t* (a ray lying in the plane), so that ray visits both sides
/// on the whole interval, as in kd_traverse_lines. A plane-less child (kKdNoPlane) has t* = +inf:
/// its near slot, the leaf, gets the whole interval. Counters count one node per treelet.
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool kd_traverse_treelets(const KdTreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  const Vec3f inv = safe_inverse(ray.dir);
  float tmin, tmax;
  if (!kd_root_interval(tree.bounds, traversal_ray<Kernel>(ray), inv, tmin, tmax)) return false;
  auto ctx = Kernel::prepare(ray);
  const typename PacketKernel<Kernel>::Ray packet_ray(ctx);
  KdMailbox<kMailbox> mailbox;
  const __m128 org4 = _mm_setr_ps(ray.org.x, ray.org.y, ray.org.z, 0.0f);
  const __m128 rcp4 = _mm_setr_ps(inv.x, inv.y, inv.z, std::numeric_limits<float>::infinity());
  // Bit a: the upper side of an axis-a plane comes first (inv[a] <= 0); bit 3 (kKdNoPlane): 0.
  const std::uint32_t upper_first = (inv.x > 0.0f ? 0u : 1u) | (inv.y > 0.0f ? 0u : 2u) | (inv.z > 0.0f ? 0u : 4u);
  auto below = [](float t, float bound) { return t < bound ? t : bound; };  // NaN t: bound
  auto above = [](float t, float bound) { return t > bound ? t : bound; };
  struct Entry {
    std::uint32_t child;
    float tmin, tmax;
  };
  Entry stack[104];  // at most 3 per treelet, at most 32 treelets deep (depth <= 64)
  int top = 0;
  bool found = false;
  std::uint32_t child = tree.treelet_root;
  for (;;) {
    if (!kd_child_is_leaf(child)) {
      counters.node();
      const KdTreelet& n = tree.treelets[child >> 1];
      const std::uint32_t x = (upper_first >> n.axis[0]) & 1u;
      const std::uint32_t an = n.axis[1 + x], af = n.axis[2 - x];
      const KdTreeletSlabs s = kd_treelet_slabs(n, org4, rcp4);
      const KdSlab p0{s.lo[0], s.hi[0]}, pn{s.lo[1 + x], s.hi[1 + x]}, pf{s.lo[2 - x], s.hi[2 - x]};
      const std::uint32_t* near_pair = n.child + 2 * x;
      const std::uint32_t* far_pair = n.child + 2 * (x ^ 1u);
      const std::uint32_t sn = (upper_first >> an) & 1u, sf = (upper_first >> af) & 1u;
      const std::uint32_t a_child = near_pair[sn], b_child = near_pair[sn ^ 1u];
      const std::uint32_t c_child = far_pair[sf], d_child = far_pair[sf ^ 1u];
      const float near_hi = below(p0.hi, tmax), far_lo = above(p0.lo, tmin);
      const float a_hi = below(pn.hi, near_hi), b_lo = above(pn.lo, tmin);
      const float c_hi = below(pf.hi, tmax), d_lo = above(pf.lo, far_lo);
      const float closest = Kernel::closest(ctx);
      // Pushed without branches: an entry is written, and kept when it is to be visited.
      stack[top] = {d_child, d_lo, tmax};
      top += static_cast<int>(d_child != kKdEmptyChild) & static_cast<int>(d_lo <= std::min(tmax, closest));
      stack[top] = {c_child, far_lo, c_hi};
      top += static_cast<int>(c_child != kKdEmptyChild) & static_cast<int>(far_lo <= std::min(c_hi, closest));
      stack[top] = {b_child, b_lo, near_hi};
      top += static_cast<int>(b_child != kKdEmptyChild) & static_cast<int>(b_lo <= std::min(near_hi, closest));
      if (a_child != kKdEmptyChild && tmin <= std::min(a_hi, closest)) {
        child = a_child;
        tmax = a_hi;
        continue;
      }
    } else {
      const KdBigLeaf leaf = kd_child_leaf(child, tree.big_leaves);
      if (kd_test_packed_leaf<Kernel, kAnyHit, kMailbox>(tree.packets + leaf.first, leaf.count, ctx, packet_ray, hit,
                                                         mailbox, counters)) {
        found = true;
        if constexpr (kAnyHit) return true;
      }
    }
    do {
      if (top == 0) return found;
      --top;
    } while (Kernel::closest(ctx) < stack[top].tmin);  // the hit lies before that cell
    child = stack[top].child;
    tmin = stack[top].tmin;
    tmax = stack[top].tmax;
  }
}

/// Recursive traversal, the lecture's form.
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
struct KdRecursiveTraversal {
  const KdTreeView& tree;
  const Ray& ray;
  Vec3f inv;
  typename Kernel::Context ctx;
  Hit& hit;
  Counters& counters;
  KdMailbox<kMailbox> mailbox;
  bool found = false;

  /// Returns true when an any-hit query is answered.
  bool visit(std::uint32_t index, float tmin, float tmax) {
    const KdNode& node = tree.nodes[index];
    if (node.is_leaf()) {
      const bool h = kd_test_leaf<Kernel, kAnyHit, kMailbox>(tree, node, ctx, hit, mailbox, counters);
      found |= h;
      return kAnyHit && h;
    }
    counters.node();
    const KdPlaneCrossing c = kd_cross(node, index, ray, inv);
    if (c.t_lo > std::min(tmax, Kernel::closest(ctx))) return visit(c.near, tmin, tmax);  // t* > tmax
    if (c.t_hi < tmin) return visit(c.far, tmin, tmax);                                  // t* < tmin
    if (visit(c.near, tmin, c.t_hi < tmax ? c.t_hi : tmax)) return true;  // tmin <= t* <= tmax (NaN: both, whole)
    const float far_tmin = c.t_lo > tmin ? c.t_lo : tmin;
    if (Kernel::closest(ctx) < far_tmin) return false;  // the hit lies inside the near cell
    return visit(c.far, far_tmin, tmax);
  }
};

template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool kd_traverse_recursive(const KdTreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  const Vec3f inv = safe_inverse(ray.dir);
  float tmin, tmax;
  if (!kd_root_interval(tree.bounds, traversal_ray<Kernel>(ray), inv, tmin, tmax)) return false;
  KdRecursiveTraversal<Kernel, kAnyHit, kMailbox, Counters> t{tree, ray, inv, Kernel::prepare(ray), hit, counters, {}};
  t.visit(0, tmin, tmax);
  return t.found;
}

}  // namespace raylab
