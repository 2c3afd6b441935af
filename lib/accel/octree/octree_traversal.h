#pragma once
/// Front-to-back octree traversal in ray order, three ways (OctreeConfig::traversal):
///  - octree_traverse_stack (the default): iterative, each node's centre-plane crossings
///    ordered at once, leaves tested 8 triangles at a time when packed (octree_pack_leaves).
///  - octree_traverse_revelles: the parametric algorithm of Revelles, Ureña and Lastra (WSCG
///    2000), octree_revelles.h.
///  - octree_traverse_kd: each node's three centre planes taken one at a time (x, then y, then
///    z), each exactly as a kd-tree split (kdtree_traversal.h: the plane's t is computed once,
///    widened by its rounding error, and a ray lying in a plane visits one side). It visits the
///    same children in the same order as Revelles's algorithm, by a different mechanism (up to
///    three plane crossings per node instead of one ordered walk over the eight children), and
///    is kept for comparison.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "accel/common/packed_tree_leaves.h"
#include "accel/kdtree/kdtree_traversal.h"
#include "accel/octree/octree_node.h"
#include "accel/octree/octree_revelles.h"

namespace raylab {

struct OctreeView {
  const OctNode* nodes;
  const std::uint32_t* prims;
  const Scene* scene;
  Bounds3f bounds;
  /// The leaves packed 4-wide (octree_pack_leaves), or null: a leaf's `first` then is the offset of
  /// its primitive ids in `prims`.
  const TrianglePacket* packets = nullptr;
};

/// The leaves of `nodes` packed 4-wide (pack_tree_leaves): `packed_nodes` is a copy of `nodes`
/// whose leaves index `packets`; both stay empty when the scene holds a sphere.
inline void octree_pack_leaves(const Scene& scene, const std::vector<OctNode>& nodes,
                               const std::vector<std::uint32_t>& prims, std::vector<OctNode>& packed_nodes,
                               std::vector<TrianglePacket>& packets) {
  pack_tree_leaves(
      scene, nodes, prims,
      [](OctNode& n) -> std::pair<std::uint32_t*, std::uint32_t> {
        if (!n.is_leaf()) return {nullptr, 0u};
        return {&n.first, n.count};
      },
      packed_nodes, packets);
}

/// Tests the primitives of a leaf, 8 at a time when the leaves are packed (kd_test_packed_leaf,
/// bit-identical to the scalar kernel), else one by one (kd_test_primitives); true on a hit.
template <bool kAnyHit, class Kernel, bool kMailbox, class Counters>
inline bool octree_test_leaf(const OctreeView& tree, const OctNode& node, TreeRay<Kernel, kMailbox>& r, Hit& hit,
                             Counters& counters) {
  if (tree.packets != nullptr)
    return kd_test_packed_leaf<kAnyHit>(tree.packets + node.first, node.count, r, hit, counters);
  counters.leaf();
  return kd_test_primitives<kAnyHit>(*tree.scene, tree.prims + node.first, node.count, r, hit, counters);
}

template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool octree_traverse_kd(const OctreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  TreeRay<Kernel, kMailbox> r;
  if (!r.enter(ray, tree.bounds)) return false;
  const Vec3f& inv = r.inv;
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
  stack[top++] = {tree.bounds, 0, 0, 0, r.tmin, r.tmax};
  bool found = false;
  while (top > 0) {
    Entry e = stack[--top];
    if (Kernel::closest(r.ctx) < e.tmin) continue;  // the hit lies before this cell
    for (;;) {
      const OctNode& node = tree.nodes[e.node];
      if (e.level == 0) {
        if (node.is_leaf()) {
          if (octree_test_leaf<kAnyHit>(tree, node, r, hit, counters)) {
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
      if (!(octree_split_axes(e.box) & (1u << a))) {  // not split along a: the lower child's range is the box's
        ++e.level;
        continue;
      }
      float t = (octree_mid(e.box, a) - ray.org[a]) * inv[a];
      if (std::isnan(t)) t = 0.0f;
      const float slack = std::isfinite(t) ? kPlaneSlack * std::abs(t) : 0.0f;
      const float t_lo = t - slack, t_hi = t + slack;
      const std::uint8_t lower = e.bits, upper = static_cast<std::uint8_t>(e.bits | (1u << a));
      const std::uint8_t near = inv[a] > 0.0f ? lower : upper, far = inv[a] > 0.0f ? upper : lower;
      const auto level = static_cast<std::uint8_t>(e.level + 1);
      if (t_lo > std::min(e.tmax, Kernel::closest(r.ctx))) {
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

/// The box of child `real` of `box`, whose centre is `mid` (octree_child_box without recomputing it).
inline Bounds3f octree_child_box(const Bounds3f& box, const float mid[3], unsigned real) {
  Bounds3f c = box;
  for (int a = 0; a < 3; ++a) {
    if (real & (1u << a)) c.lo[a] = mid[a];
    else c.hi[a] = mid[a];
  }
  return c;
}

/// Iterative front-to-back traversal with an explicit stack (the default).
///
/// At a node met on [tmin, tmax] the centre planes' t_a = (mid_a - o_a)/d_a are widened by their
/// rounding error to [lo_a, hi_a], as the kd-tree's split t* (kd_cross); along axis a the ray's
/// near half (the lower one when d_a > 0) holds it on [tmin, min(tmax, hi_a)] and the far half on
/// [max(tmin, lo_a), tmax]; a ray lying in the plane (t_a = NaN) takes lo_a = -inf, hi_a = +inf,
/// both halves on the whole interval. A child's interval is the intersection of its three halves'
/// (the three centre planes taken as kd-tree splits, as octree_traverse_kd), so a child is skipped
/// only when the exact ray surely misses it; a child starting after the closest hit is skipped.
/// In mirrored bits (bit a set: the far half of axis a) the children met are, in order of entry:
/// c0 = the far halves of the axes crossed before tmin, then c0 with the bits of the crossings
/// within the interval added one at a time in increasing t (Revelles, Ureña and Lastra 2000: at
/// most four children, their order fixed by which centre plane the ray crosses first; here a
/// sort of at most three keys). That sequence is exact when the crossings' widened intervals are
/// pairwise disjoint; otherwise (the ray passes within rounding of a cell edge or corner, or lies
/// in a plane) every child's interval is computed and those met are visited in order of entry.
template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool octree_traverse_stack(const OctreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  TreeRay<Kernel, kMailbox> r;
  if (!r.enter(ray, tree.bounds)) return false;
  float tmin = r.tmin, tmax = r.tmax;
  const Vec3f& inv = r.inv;
  // Real child = mirrored child ^ flip: bit a of flip is set when the near half of axis a is the
  // upper one (inv = +inf for d = ±0: t = ±inf keeps the origin's side, as in kd_cross).
  const unsigned flip = (inv.x > 0.0f ? 0u : 1u) | (inv.y > 0.0f ? 0u : 2u) | (inv.z > 0.0f ? 0u : 4u);
  struct Entry {  // no default member initialisers: the stack is not written before use
    float lo[3], hi[3];
    std::uint32_t node;
    float tmin, tmax;
  };
  Entry stack[7 * 21];  // depth <= 20 (octree_max_depth), at most 7 pushes per level
  int top = 0;
  bool found = false;
  Bounds3f box = tree.bounds;
  std::uint32_t index = 0;
  for (;;) {
    const OctNode* node = &tree.nodes[index];
    while (!node->is_leaf()) {
      counters.node();
      const float tcut = std::min(tmax, Kernel::closest(r.ctx));
      float mid[3], lo[3], hi[3];
      unsigned c0 = 0, crossed = 0;
      const unsigned split = octree_split_axes(box);
      for (int a = 0; a < 3; ++a) {
        // Along an axis that is not split (octree_split_axes) the only child is the real lower
        // one over the box's range: its plane goes to +inf when the lower half is the near one
        // (never crossed), to -inf when it is the far one (crossed before entry).
        const bool is_split = split & (1u << a);
        mid[a] = is_split ? octree_mid(box, a) : box.hi[a];
        const float t = is_split ? (mid[a] - ray.org[a]) * inv[a]  // NaN: the ray lies in the plane
                                 : (flip & (1u << a) ? -kInf : kInf);
        const WidenedPlaneT w = widened_plane_t(t);
        lo[a] = std::max(-kInf, w.lo);  // NaN -> -inf
        hi[a] = std::min(kInf, w.hi);   // NaN -> +inf
        if (hi[a] < tmin) c0 |= 1u << a;
        else if (!(lo[a] > tcut)) crossed |= 1u << a;
      }
      // The children met, in order of entry: real index, interval.
      unsigned kid[8];
      float kid_in[8], kid_out[8];
      int kids = 0;
      int order[3], n = 0;
      for (int a = 0; a < 3; ++a)
        if (crossed & (1u << a)) order[n++] = a;
      if (n > 1 && lo[order[1]] < lo[order[0]]) std::swap(order[0], order[1]);
      if (n > 2) {
        if (lo[order[2]] < lo[order[1]]) std::swap(order[1], order[2]);
        if (lo[order[1]] < lo[order[0]]) std::swap(order[0], order[1]);
      }
      bool apart = true;
      for (int i = 0; i + 1 < n; ++i) apart = apart && hi[order[i]] < lo[order[i + 1]];
      if (apart) {
        unsigned c = c0;
        for (int i = 0; i <= n; ++i) {
          const float in = i > 0 ? std::max(tmin, lo[order[i - 1]]) : tmin;
          const float out = i < n ? std::min(tcut, hi[order[i]]) : tcut;
          if (i > 0) c |= 1u << order[i - 1];
          const unsigned real = c ^ flip;
          if (node->has_child(real) && in <= out) kid[kids] = real, kid_in[kids] = in, kid_out[kids++] = out;
        }
      } else {
        for (unsigned c = 0; c < 8; ++c) {
          const unsigned real = c ^ flip;
          if (!node->has_child(real)) continue;
          float in = tmin, out = tcut;
          for (int a = 0; a < 3; ++a)
            if (c & (1u << a)) in = std::max(in, lo[a]);
            else out = std::min(out, hi[a]);
          if (!(in <= out)) continue;
          int k = kids++;  // insertion by entry
          for (; k > 0 && kid_in[k - 1] > in; --k) {
            kid[k] = kid[k - 1];
            kid_in[k] = kid_in[k - 1];
            kid_out[k] = kid_out[k - 1];
          }
          kid[k] = real, kid_in[k] = in, kid_out[k] = out;
        }
      }
      if (kids == 0) goto pop;
      for (int k = kids - 1; k > 0; --k) {
        Entry& e = stack[top++];
        for (int a = 0; a < 3; ++a) {
          const bool upper = kid[k] & (1u << a);
          e.lo[a] = upper ? mid[a] : box.lo[a];
          e.hi[a] = upper ? box.hi[a] : mid[a];
        }
        e.node = node->child(kid[k]);
        e.tmin = kid_in[k];
        e.tmax = kid_out[k];
      }
      index = node->child(kid[0]);
      box = octree_child_box(box, mid, kid[0]);
      tmin = kid_in[0];
      tmax = kid_out[0];
      node = &tree.nodes[index];
    }
    if (octree_test_leaf<kAnyHit>(tree, *node, r, hit, counters)) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
  pop:
    do {
      if (top == 0) return found;
      --top;
    } while (Kernel::closest(r.ctx) < stack[top].tmin);  // the hit lies before that cell
    box.lo = Vec3f(stack[top].lo[0], stack[top].lo[1], stack[top].lo[2]);
    box.hi = Vec3f(stack[top].hi[0], stack[top].hi[1], stack[top].hi[2]);
    index = stack[top].node;
    tmin = stack[top].tmin;
    tmax = stack[top].tmax;
  }
}

template <class Kernel, bool kAnyHit, bool kMailbox, class Counters>
bool octree_traverse_revelles(const OctreeView& tree, const Ray& ray, Hit& hit, Counters& counters) {
  TreeRay<Kernel, kMailbox> r;
  r.prepare(ray);  // the walk finds its own root interval
  bool found = false;
  auto leaf = [&](std::uint32_t index, const Bounds3f&, float, float) {
    const bool in_leaf = octree_test_leaf<kAnyHit>(tree, tree.nodes[index], r, hit, counters);
    found = found || in_leaf;
    return kAnyHit && in_leaf;
  };
  auto cut = [&] { return Kernel::closest(r.ctx); };
  octree_walk_revelles(tree.nodes, tree.bounds, traversal_ray<Kernel>(ray), leaf, cut, counters);
  return found;
}

}  // namespace raylab
