#pragma once
/// Static dispatch from a primitive id of a Scene to its shape (triangle or sphere) and a ray
/// kernel: the inner loop every accelerator over scene geometry runs.
#include "geometry/triangle_kernels.h"
#include "scene/scene.h"

namespace raylab {

/// Writes a kernel's hit on primitive `prim` of a scene (not an instance) into `hit`.
inline void set_scene_hit(Hit& hit, const TriangleHit& th, unsigned prim) {
  hit.t = th.t;
  hit.u = th.u;
  hit.v = th.v;
  hit.prim = prim;
  hit.instance = kInvalidId;
}

/// Offers primitive `prim` to the kernel context; on a hit closer than the context's current
/// closest, writes `hit` (t, u, v, prim; instance cleared) and returns true.
template <class Kernel, class Counters>
inline bool intersect_scene_primitive(const Scene& scene, unsigned prim, typename Kernel::Context& ctx, Hit& hit,
                                      Counters& counters) {
  counters.prim_test();
  TriangleHit th;
  bool found;
  if (scene.is_sphere(prim)) {
    found = Kernel::intersect_sphere(ctx, prim, scene.sphere(prim), th);
  } else {
    const auto& tri = scene.mesh.triangles[prim];
    const auto& v = scene.mesh.vertices;
    found = Kernel::intersect(ctx, prim, v[tri[0]], v[tri[1]], v[tri[2]], th);
  }
  if (!found) return false;
  counters.prim_hit();
  set_scene_hit(hit, th, prim);
  return true;
}

}  // namespace raylab
