#pragma once
/// An octree node: an interior node holds the index of its eight consecutive children (child i
/// has bit a of i set when it is the upper half along axis a); a leaf holds a primitive range.
#include <cstdint>

#include "geometry/bounds.h"

namespace raylab {

struct OctNode {
  static constexpr std::uint32_t kInterior = 0xffffffffu;
  std::uint32_t first = 0;          ///< first child, or offset into the primitive index array
  std::uint32_t count = kInterior;  ///< leaf primitive count, or kInterior

  bool is_leaf() const { return count != kInterior; }
};

/// The centre plane of `box` along `axis`, computed identically by builder and traversal.
inline float octree_mid(const Bounds3f& box, int axis) { return 0.5f * (box.lo[axis] + box.hi[axis]); }

/// The box of child `i` of `box`.
inline Bounds3f octree_child_box(const Bounds3f& box, unsigned i) {
  Bounds3f c = box;
  for (int a = 0; a < 3; ++a) {
    const float m = octree_mid(box, a);
    if (i & (1u << a)) c.lo[a] = m;
    else c.hi[a] = m;
  }
  return c;
}

}  // namespace raylab
