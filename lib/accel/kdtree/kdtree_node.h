#pragma once
/// The kd-tree node of pbrt-v3 §4.4.1: 8 bytes. An interior node stores the split position and
/// axis, its lower child is the next node and its upper child is at `above_child`; a leaf stores
/// its primitive count and the offset of its primitive indices.
#include <cstdint>

namespace raylab {

struct KdNode {
  union {
    float split;          ///< interior
    std::uint32_t first;  ///< leaf: offset into the primitive index array
  };
  std::uint32_t bits;  ///< low 2 bits: axis, or 3 for a leaf; the rest: above child or count

  static KdNode make_leaf(std::uint32_t first, std::uint32_t count) {
    KdNode n;
    n.first = first;
    n.bits = 3u | (count << 2);
    return n;
  }
  static KdNode make_interior(int axis, float split) {
    KdNode n;
    n.split = split;
    n.bits = static_cast<std::uint32_t>(axis);
    return n;
  }
  void set_above_child(std::uint32_t index) { bits = (bits & 3u) | (index << 2); }

  bool is_leaf() const { return (bits & 3u) == 3u; }
  bool is_empty_leaf() const { return bits == 3u; }
  int axis() const { return static_cast<int>(bits & 3u); }
  std::uint32_t count() const { return bits >> 2; }
  std::uint32_t above_child() const { return bits >> 2; }
};
static_assert(sizeof(KdNode) == 8);

}  // namespace raylab
