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
  /// A float box containing the exact cell (the intersection of the root box with the closed
  /// half-spaces of the exact planes split by), rounded outward from box().
  Bounds3f bounds() const;
  bool empty() const { return faces_.empty(); }
  /// Whether the line {origin + t·direction} meets the cell: it crosses (or touches) one of its
  /// faces, decided in double by the orientation of the line against each face's edges.
  bool meets_line(const Vec3d& origin, const Vec3d& direction) const;
  /// The two parts of this cell on the negative and positive sides of `plane`.
  void split(const BspPlane& plane, ConvexCell& negative, ConvexCell& positive) const;

  /// Estimates of what split() would give, for ranking candidate planes without building the
  /// parts: their surface areas and boxes around their computed vertices (not widened by the
  /// error bounds of bounds()). False when a part holds no vertex strictly on its side.
  struct SplitEstimate {
    double negative_area = 0.0, positive_area = 0.0;
    Bounds3f negative_box, positive_box;
  };
  bool estimate_split(const BspPlane& plane, SplitEstimate& estimate) const;

 private:
  /// The faces as computed in double: each vertex within error_ (per coordinate) of the exact
  /// cell's corresponding vertex.
  std::vector<std::vector<Vec3d>> faces_;
  /// Per face, +1 when its vertex order turns about the outward normal (Newell's area vector
  /// points out of the cell), else -1: set by orient_faces() whenever faces_ is.
  std::vector<double> outward_;
  void orient_faces();
  /// A box containing the exact cell: the parent's box cut to the points that may lie on this
  /// side, widened by error_ (first-order forward error analysis of the clipping).
  Bounds3d box_;
  double error_ = 0.0;
  double magnitude_ = 0.0;  ///< the largest |coordinate| of the root box, which scales rounding
};

}  // namespace raylab
