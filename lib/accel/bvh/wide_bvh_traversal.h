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

/// Prefetches the cache lines of the interior node `ref` (leaves are left to the leaf test).
template <class Node>
[[gnu::always_inline]] inline void prefetch_node(const Node* nodes, std::uint32_t ref) {
  if (WideRef::is_leaf(ref)) return;
  const char* p = reinterpret_cast<const char*>(nodes + ref);
  for (std::size_t line = 0; line < sizeof(Node); line += 64) _mm_prefetch(p + line, _MM_HINT_T0);
}

/// Traverses `nodes` (root 0; WideBvhNode<N> or QuantizedWideBvhNode<N>). `closest` is the
/// current closest-hit distance, which `leaf(first_packet, packet_count, closest)` lowers when it
/// finds a hit and reports by returning true. Returns whether any leaf reported a hit; with
/// kAnyHit the first report ends traversal.
template <int N, bool kRobust, bool kAnyHit, class Node, class Counters, class LeafFn>
bool traverse_wide_bvh(const Node* nodes, const Ray& ray, float& closest_out, Counters& counters,
                       LeafFn&& leaf) {
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
      // so those of the children taken later arrive while the nearest one is traversed.
      for (unsigned m = mask; m != 0; m &= m - 1) prefetch_node(nodes, node.child[std::countr_zero(m)]);
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
