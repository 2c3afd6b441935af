#pragma once
/// A BSP node (64 bytes): an interior node holds its plane (double precision) and the index of its positive
/// child (the negative child is the next node); a leaf holds a primitive range. An interior node
/// whose plane is axis-aligned says so in `count`, so that traversal can take it as a kd-tree split.
#include <cstdint>

namespace raylab {

struct BspNode {
  static constexpr std::uint32_t kInterior = 0xffffffffu;  ///< interior, a triangle's plane
  /// kAxisInterior + a: interior, the plane p[a] = origin[a] (a float), normal e_a, scale 1.
  static constexpr std::uint32_t kAxisInterior = 0xfffffffcu;
  double normal[3];  ///< the plane: normal·(p - origin) = 0
  double origin[3];
  double scale;  ///< bounds the normal's magnitude and rounding (BspPlane::scale)
  std::uint32_t index;  ///< interior: positive child; leaf: offset into the primitive index array
  std::uint32_t count;  ///< leaf primitive count (below kAxisInterior), or kInterior, or kAxisInterior + axis

  bool is_leaf() const { return count < kAxisInterior; }
  /// Interior: the axis of an axis-aligned plane, or -1.
  int axis() const { return count == kInterior ? -1 : static_cast<int>(count - kAxisInterior); }
};

}  // namespace raylab
