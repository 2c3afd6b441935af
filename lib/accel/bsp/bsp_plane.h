#pragma once
/// A BSP split plane: axis-aligned (exact coordinate comparisons) or the supporting plane of a
/// scene triangle (exact orientation, CGAL). Points p with n·p - offset < 0 are on the negative
/// side (the lower child).
#include <cstdint>

#include "geometry/vec3.h"
#include "scene/scene.h"

namespace raylab {

/// Relative bound on the rounding of a double dot product of float data and of the plane's own
/// construction (about 10 ulps of double), with a wide margin: n·(p - origin) is within
/// kBspRelError·scale·|p - origin|_1 of the exact plane's value.
inline constexpr double kBspRelError = 1e-13;

struct BspPlane {
  Vec3d normal;            ///< unnormalised: (p1-p0)×(p2-p0) in double, or a unit axis
  Vec3d origin;            ///< a point of the plane: the triangle's p0, or pos·e_axis
  double offset = 0.0;     ///< normal·origin (approximate; for display and cell clipping)
  /// |p1-p0|_1·|p2-p0|_1 (1 for an axis plane): bounds |normal| and scales its rounding error.
  double scale = 1.0;
  std::int32_t axis = -1;  ///< 0..2 for an axis-aligned plane, -1 for a triangle's plane
  std::uint32_t prim = 0;  ///< the triangle whose supporting plane this is (axis < 0)
  float pos = 0.0f;        ///< the axis position (axis >= 0)

  double signed_distance(const Vec3d& p) const { return dot(normal, p - origin); }
};

/// Which children a primitive goes to.
enum class BspSide : std::uint8_t { negative, positive, both };

/// Exact classification: a triangle with vertices strictly on both sides, or lying in the plane,
/// goes to both children (it is referenced twice, not split); one that only touches the plane
/// goes to the side of its other vertices (its points on the plane lie in both closed cells, so a
/// ray's hit there is found from that side). Spheres are classified conservatively by their
/// centre's distance in double precision.
BspSide classify(const Scene& scene, std::uint32_t prim, const BspPlane& plane);

/// The supporting plane of triangle `prim`; false for a triangle with a zero normal in double.
bool triangle_plane(const Scene& scene, std::uint32_t prim, BspPlane& plane);

}  // namespace raylab
