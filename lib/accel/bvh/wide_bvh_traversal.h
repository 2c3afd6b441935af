#pragma once
/// Single-ray traversal of an N-wide BVH (Wald, Benthin and Boulos 2008; Embree's BVH4/BVH8
/// single-ray kernels): one SIMD test of the ray against a node's N child boxes (simd_box_test.h),
/// then the hit children in near-first order: the nearest is visited next, the others are pushed
/// far-to-near with their entry distances and skipped on pop once the closest hit lies before
/// them. Any-hit traversal pushes hit children unordered and stops at the first hit.
#include <immintrin.h>

#include <bit>
#include <cstdint>

#include "accel/bvh/simd_box_test.h"
#include "accel/bvh/wide_bvh.h"

namespace raylab {

/// Prefetches the cache lines of child `ref`: an interior node's, or a leaf's first packet's (the
/// leaf test reads the others after it). `Leaf` is TrianglePacket or IndexedPacket.
template <class Node, class Leaf>
[[gnu::always_inline]] inline void prefetch_child(const Node* nodes, const Leaf* leaves, std::uint32_t ref) {
  const char* p = WideRef::is_leaf(ref) ? reinterpret_cast<const char*>(leaves + WideRef::first(ref))
                                        : reinterpret_cast<const char*>(nodes + ref);
  const std::size_t bytes = WideRef::is_leaf(ref) ? sizeof(Leaf) : sizeof(Node);
  for (std::size_t offset = 0; offset < bytes; offset += 64) _mm_prefetch(p + offset, _MM_HINT_T0);
  _mm_prefetch(p + bytes - 1, _MM_HINT_T0);  // a packet is 16-byte aligned: it may reach one line further
}

/// Traverses `nodes` (root 0; WideBvhNode<N> or QuantizedWideBvhNode<N>) whose leaves reference
/// `leaves` (TrianglePacket, or IndexedPacket for indexed leaves). `closest` is the current
/// closest-hit distance, which `leaf(first_packet, packet_count, closest)` lowers when it finds a
/// hit and reports by returning true. Returns whether any leaf reported a hit; with kAnyHit the
/// first report ends traversal.
template <int N, bool kRobust, bool kAnyHit, class Node, class Leaf, class Counters, class LeafFn>
bool traverse_wide_bvh(const Node* nodes, const Leaf* leaves, const Ray& ray, float& closest_out,
                       Counters& counters, LeafFn&& leaf) {
  const WideBoxRay<N, kRobust> r(ray);
  float closest = closest_out;  // a register copy: the stack stores cannot alias it
  struct Entry {
    std::uint32_t ref;
    float t;
  };
  // Every level pushes at most N - 1 entries and leaves are at depth <= kBvhMaxDepth.
  Entry stack[(kBvhMaxDepth + 1) * (N - 1) + 1];
  int top = 0;
  std::uint32_t ref = 0;
  bool found = false;
  alignas(32) float entry[N];
  for (;;) {
    if (!WideRef::is_leaf(ref)) {
      const Node& node = nodes[ref];
      counters.node();
      unsigned mask = r.hit(node, closest, entry);
      // Incoherent rays miss the caches on most node loads: start every hit child's lines now,
      // so those of the children taken later arrive while the nearest one is traversed. Leaves
      // too: at 10^6 triangles and more their packets miss as often (`raylab sweep`, with leaf
      // prefetch against without, each against Embree in one process, 3 measurements: 1.02-1.08
      // on 1.2·10^6 and 2.1·10^6 triangles, 1.00-1.02 on 7.5·10^4).
      for (unsigned m = mask; m != 0; m &= m - 1) prefetch_child(nodes, leaves, node.child[std::countr_zero(m)]);
      if (mask != 0) {
        const int i = std::countr_zero(mask);
        mask &= mask - 1;
        if (mask == 0) {
          ref = node.child[i];
          continue;
        }
        if constexpr (kAnyHit) {
          ref = node.child[i];
          for (; mask != 0; mask &= mask - 1) {
            const int k = std::countr_zero(mask);
            stack[top++] = {node.child[k], entry[k]};
          }
          continue;
        } else {
          const int j = std::countr_zero(mask);
          mask &= mask - 1;
          if (mask == 0) {
            const bool i_first = entry[i] <= entry[j];
            stack[top++] = i_first ? Entry{node.child[j], entry[j]} : Entry{node.child[i], entry[i]};
            ref = i_first ? node.child[i] : node.child[j];
            continue;
          }
          // Three or more: push all, insertion-sort the pushed run far-to-near, take the top.
          const int base = top;
          stack[top++] = {node.child[i], entry[i]};
          stack[top++] = {node.child[j], entry[j]};
          for (; mask != 0; mask &= mask - 1) {
            const int k = std::countr_zero(mask);
            stack[top++] = {node.child[k], entry[k]};
          }
          for (int a = base + 1; a < top; ++a) {
            const Entry e = stack[a];
            int b = a;
            for (; b > base && stack[b - 1].t < e.t; --b) stack[b] = stack[b - 1];
            stack[b] = e;
          }
          ref = stack[--top].ref;
          continue;
        }
      }
    } else {
      counters.leaf();
      if (leaf(WideRef::first(ref), WideRef::count(ref), closest)) {
        found = true;
        if constexpr (kAnyHit) {
          closest_out = closest;
          return true;
        }
      }
    }
    for (;;) {
      if (top == 0) {
        closest_out = closest;
        return found;
      }
      const Entry e = stack[--top];
      if (e.t <= closest) {
        ref = e.ref;
        break;
      }
    }
  }
}

}  // namespace raylab
