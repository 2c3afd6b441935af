#pragma once
/// An octree node (8 bytes): a leaf holds a primitive range; an interior node holds a mask of its
/// non-empty children (eight, or four or two for a flat node: octree_split_axes) and the index of
/// the first of them, stored consecutively in child order (child i has bit a of i set when it is
/// the upper half along axis a). Empty children are not stored: the mask says a ray's walk can
/// skip them without loading a node.
#include <algorithm>
#include <bit>
#include <cstdint>

#include "geometry/bounds.h"

namespace raylab {

struct OctNode {
  /// `count` at or above this marks an interior node, its low 8 bits the mask of stored children;
  /// a leaf's count stays below it (a leaf lists distinct 32-bit primitive ids, none of them kInvalidId).
  static constexpr std::uint32_t kInterior = 0xffffff00u;
  std::uint32_t first = 0;          ///< first stored child, or offset into the primitive index array
  std::uint32_t count = kInterior;  ///< leaf primitive count, or kInterior | mask of stored children

  bool is_leaf() const { return count < kInterior; }
  /// Interior: whether child i is stored (holds primitives), and its index when it is.
  bool has_child(unsigned i) const { return (count >> i) & 1u; }
  std::uint32_t child(unsigned i) const {
    return first + static_cast<std::uint32_t>(std::popcount(count & 0xffu & ((1u << i) - 1u)));
  }
};

/// The centre plane of `box` along `axis`, computed identically by builder and traversal.
inline float octree_mid(const Bounds3f& box, int axis) { return 0.5f * (box.lo[axis] + box.hi[axis]); }

/// The axes (bit a) along which `box` is split at its centre: those at least half as long as
/// its longest. A node of a flat or elongated box splits into four or two children, not eight,
/// so cells stay within a factor 2 of cubes instead of keeping the root box's aspect ratio at
/// every depth (a flat layer of thin primitives, such as grass, is otherwise cut along its thin
/// axis at every level and every primitive referenced in every slice). Builder and traversal
/// compute it from the same box.
inline unsigned octree_split_axes(const Bounds3f& box) {
  const float dx = box.hi.x - box.lo.x, dy = box.hi.y - box.lo.y, dz = box.hi.z - box.lo.z;
  const float half = 0.5f * std::max(std::max(dx, dy), dz);
  return (dx >= half ? 1u : 0u) | (dy >= half ? 2u : 0u) | (dz >= half ? 4u : 0u);
}

/// Whether `box` has a child `i` (it is not split along the axes of i's other bits).
inline bool octree_child_exists(const Bounds3f& box, unsigned i) { return (i & ~octree_split_axes(box)) == 0; }

/// The box of child `i` of `box` (octree_child_exists); along an axis that is not split the
/// child keeps the whole range.
inline Bounds3f octree_child_box(const Bounds3f& box, unsigned i) {
  Bounds3f c = box;
  const unsigned split = octree_split_axes(box);
  for (int a = 0; a < 3; ++a) {
    if (!(split & (1u << a))) continue;
    const float m = octree_mid(box, a);
    if (i & (1u << a)) c.lo[a] = m;
    else c.hi[a] = m;
  }
  return c;
}

}  // namespace raylab
