#pragma once
/// A BSP node (64 bytes): an interior node holds its plane (double precision) and the index of its positive
/// child (the negative child is the next node); a leaf holds a primitive range.
#include <cstdint>

namespace raylab {

struct BspNode {
  static constexpr std::uint32_t kInterior = 0xffffffffu;
  double normal[3];  ///< the plane: normal·(p - origin) = 0
  double origin[3];
  double scale;  ///< bounds the normal's magnitude and rounding (BspPlane::scale)
  std::uint32_t index;  ///< interior: positive child; leaf: offset into the primitive index array
  std::uint32_t count;  ///< leaf primitive count, or kInterior

  bool is_leaf() const { return count != kInterior; }
};

}  // namespace raylab
