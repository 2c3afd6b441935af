#pragma once
/// A convex cell of a BSP tree as its polygonal faces, in double precision: enough to rank
/// candidate planes by the surface areas of the cells they cut (the SAH of the BSP builder).
#include <vector>

#include "accel/bsp/bsp_plane.h"
#include "geometry/bounds.h"

namespace raylab {

class ConvexCell {
 public:
  ConvexCell() = default;
  explicit ConvexCell(const Bounds3f& box);

  double surface_area() const;
  /// A float box containing the cell (its vertices rounded outward).
  Bounds3f bounds() const;
  bool empty() const { return faces_.empty(); }
  /// The two parts of this cell on the negative and positive sides of `plane`.
  void split(const BspPlane& plane, ConvexCell& negative, ConvexCell& positive) const;

 private:
  std::vector<std::vector<Vec3d>> faces_;
};

}  // namespace raylab
