#include "accel/bsp/bsp_plane.h"

#include <cmath>

#include "geometry/exact_predicates.h"

namespace raylab {

bool triangle_plane(const Scene& scene, std::uint32_t prim, BspPlane& plane) {
  if (scene.is_sphere(prim)) return false;
  const auto& t = scene.mesh.triangles[prim];
  const Vec3d p0(scene.mesh.vertices[t[0]]), p1(scene.mesh.vertices[t[1]]), p2(scene.mesh.vertices[t[2]]);
  const Vec3d n = cross(p1 - p0, p2 - p0);
  if (!(dot(n, n) > 0.0) || !is_finite(n)) return false;
  plane.normal = n;
  plane.origin = p0;
  plane.offset = dot(n, p0);
  const Vec3d e1 = abs(p1 - p0), e2 = abs(p2 - p0);
  plane.scale = (e1.x + e1.y + e1.z) * (e2.x + e2.y + e2.z);
  plane.axis = -1;
  plane.prim = prim;
  return true;
}

BspSide classify(const Scene& scene, std::uint32_t prim, const BspPlane& plane) {
  if (scene.is_sphere(prim)) {
    const Sphere& s = scene.sphere(prim);
    const Bounds3f b = s.bounds();
    if (plane.axis >= 0) {
      if (b.hi[plane.axis] < plane.pos) return BspSide::negative;
      if (b.lo[plane.axis] > plane.pos) return BspSide::positive;
      return BspSide::both;
    }
    const Vec3d c = Vec3d(b.center());
    const double r = 0.5 * double(max_component(b.diagonal()));
    const double dist = plane.signed_distance(c) / length(plane.normal);
    const double margin = r * (1.0 + 1e-6) + 1e-9 * (length(c - plane.origin) * plane.scale / length(plane.normal));
    if (dist > margin) return BspSide::positive;
    if (dist < -margin) return BspSide::negative;
    return BspSide::both;
  }
  const auto& t = scene.mesh.triangles[prim];
  const auto& v = scene.mesh.vertices;
  bool pos = false, neg = false;
  if (plane.axis >= 0) {
    for (int i = 0; i < 3; ++i) {
      const float x = v[t[i]][plane.axis];
      pos |= x > plane.pos;
      neg |= x < plane.pos;
    }
  } else {
    const auto& pt = scene.mesh.triangles[plane.prim];
    const Vec3f &a = v[pt[0]], &b = v[pt[1]], &c = v[pt[2]];
    // The orientation's sign convention, calibrated once against signed_distance's: for the
    // plane z = 0 through (0,0,0), (1,0,0), (0,1,0) the normal (b-a)×(c-a) is +z.
    static const int convention = exact_orientation({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
    for (int i = 0; i < 3; ++i) {
      const int o = convention * exact_orientation(a, b, c, v[t[i]]);
      pos |= o > 0;
      neg |= o < 0;
    }
  }
  if (pos && !neg) return BspSide::positive;
  if (neg && !pos) return BspSide::negative;
  return BspSide::both;
}

}  // namespace raylab
