#include "accel/kdtree/split_clipping.h"

#include "geometry/exact_predicates.h"
#include "geometry/input_error.h"
#include "geometry/triangle_clipping.h"

namespace raylab {

const std::vector<std::string>& clip_mode_names() {
  static const std::vector<std::string> names = {"none", "bbox", "exact"};
  return names;
}

ClipMode parse_clip_mode(const std::string& name) {
  if (name == "none") return ClipMode::none;
  if (name == "bbox") return ClipMode::bbox;
  if (name == "exact") return ClipMode::exact;
  throw InputError("unknown clip mode '" + name + "' (valid: none, bbox, exact)");
}

std::vector<PrimRef> make_root_refs(const Scene& scene) {
  const auto n = static_cast<std::uint32_t>(scene.primitive_count());
  std::vector<PrimRef> refs(n);
  for (std::uint32_t i = 0; i < n; ++i) refs[i] = {scene.primitive_bounds(i), i};
  return refs;
}

bool ref_meets_box(const Scene& scene, const PrimRef& ref, const Bounds3f& child, ClipMode mode) {
  if (!ref.box.overlaps(child)) return false;
  if (mode != ClipMode::exact || scene.is_sphere(ref.prim)) return true;
  const auto& t = scene.mesh.triangles[ref.prim];
  const auto& v = scene.mesh.vertices;
  return exact_triangle_intersects_box(v[t[0]], v[t[1]], v[t[2]], child);
}

Bounds3f ref_bounds_in(const Scene& scene, const PrimRef& ref, const Bounds3f& child, ClipMode mode) {
  switch (mode) {
    case ClipMode::none: return ref.box;
    case ClipMode::bbox: return intersect(ref.box, child);
    case ClipMode::exact: break;
  }
  if (scene.is_sphere(ref.prim)) return intersect(ref.box, child);
  const auto& t = scene.mesh.triangles[ref.prim];
  const auto& v = scene.mesh.vertices;
  const Bounds3f b = intersect(clipped_triangle_bounds(v[t[0]], v[t[1]], v[t[2]], child), ref.box);
  // The exact predicate said the triangle meets `child`; should rounding have left the clipped
  // bounds empty, fall back to the (still conservative) box intersection.
  return b.empty() ? intersect(ref.box, child) : b;
}

}  // namespace raylab
