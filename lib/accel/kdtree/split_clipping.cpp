#include "accel/kdtree/split_clipping.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "accel/common/huge_pages.h"
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
  // Written once (not value-initialised first), into huge pages when large (huge_pages.h).
  std::vector<PrimRef> refs;
  refs.reserve(n);
  advise_huge_pages(refs.data(), n * sizeof(PrimRef));
  for (std::uint32_t i = 0; i < n; ++i) refs.push_back({scene.primitive_bounds(i), i});
  return refs;
}

bool ref_meets_box(const Scene& scene, const PrimRef& ref, const Bounds3f& child, ClipMode mode) {
  if (!ref.box.overlaps(child)) return false;
  if (mode != ClipMode::exact || scene.is_sphere(ref.prim)) return true;
  const auto& t = scene.mesh.triangles[ref.prim];
  const auto& v = scene.mesh.vertices;
  const Vec3f &p0 = v[t[0]], &p1 = v[t[1]], &p2 = v[t[2]];
  // A vertex in the closed box (decided exactly: float comparisons of floats) is a common point
  // of the closed triangle, or of the segment or point a degenerate one is tested as.
  if (child.contains(p0) || child.contains(p1) || child.contains(p2)) return true;
  return exact_triangle_intersects_box(p0, p1, p2, child);
}

namespace {

/// Whether an edge of the triangle crosses the plane x_axis = s strictly (one vertex below,
/// one above, by exact float comparisons) at a point whose other two coordinates lie inside
/// box's extents by a margin that exceeds the rounding error of computing them. That point is
/// then a common point of the triangle (or of the segment a degenerate one is tested as) and
/// of both closed children of box split at s.
///
/// The crossing X_b = P_b + (Q_b - P_b)·t, t = (s - P_a)/(Q_a - P_a), is evaluated in double
/// from float inputs: with t in (0, 1) each of the six operations adds a relative error of at
/// most 2^-53, so |computed - exact| < 16·2^-53·(|P_b| + |Q_b|); the margin is 1e-12 times that
/// sum, plus the smallest normal double.
bool crossing_edge_in_face(const Vec3f* v, int axis, float s, const Bounds3f& box) {
  const int b1 = axis == 0 ? 1 : 0, b2 = axis == 2 ? 1 : 2;
  for (int i = 0; i < 3; ++i) {
    const Vec3f& p = v[i];
    const Vec3f& q = v[i == 2 ? 0 : i + 1];
    if (!((p[axis] < s && q[axis] > s) || (p[axis] > s && q[axis] < s))) continue;
    const double t = (double(s) - p[axis]) / (double(q[axis]) - p[axis]);
    bool inside = true;
    for (const int b : {b1, b2}) {
      const double x = double(p[b]) + (double(q[b]) - p[b]) * t;
      const double margin =
          1e-12 * (std::abs(double(p[b])) + std::abs(double(q[b]))) + std::numeric_limits<double>::min();
      inside = inside && x - margin > box.lo[b] && x + margin < box.hi[b];
    }
    if (inside) return true;
  }
  return false;
}

}  // namespace

void ref_meets_children(const Scene& scene, const PrimRef& ref, const Bounds3f& box, int axis, float s,
                        ClipMode mode, bool& in_l, bool& in_r) {
  const Bounds3f lbox = box.below(axis, s), rbox = box.above(axis, s);
  in_l = ref.box.overlaps(lbox);
  in_r = ref.box.overlaps(rbox);
  if (mode != ClipMode::exact || scene.is_sphere(ref.prim) || !(in_l || in_r)) return;
  const auto& t = scene.mesh.triangles[ref.prim];
  const auto& vs = scene.mesh.vertices;
  const Vec3f v[3] = {vs[t[0]], vs[t[1]], vs[t[2]]};
  if (in_l && in_r && box.lo[axis] <= s && s <= box.hi[axis] && crossing_edge_in_face(v, axis, s, box)) return;
  // As ref_meets_box: a vertex in the closed child box, or else the exact predicate.
  if (in_l && !(lbox.contains(v[0]) || lbox.contains(v[1]) || lbox.contains(v[2])))
    in_l = exact_triangle_intersects_box(v[0], v[1], v[2], lbox);
  if (in_r && !(rbox.contains(v[0]) || rbox.contains(v[1]) || rbox.contains(v[2])))
    in_r = exact_triangle_intersects_box(v[0], v[1], v[2], rbox);
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

void ref_bounds_in_children(const Scene& scene, const PrimRef& ref, const Bounds3f& box, int axis, float s,
                            ClipMode mode, Bounds3f& lower, Bounds3f& upper) {
  if (mode != ClipMode::exact || scene.is_sphere(ref.prim)) {
    lower = ref_bounds_in(scene, ref, box.below(axis, s), mode);
    upper = ref_bounds_in(scene, ref, box.above(axis, s), mode);
    return;
  }
  const auto& t = scene.mesh.triangles[ref.prim];
  const auto& v = scene.mesh.vertices;
  Bounds3f l, u;
  clipped_triangle_bounds_split(v[t[0]], v[t[1]], v[t[2]], box, axis, s, l, u);
  // As in ref_bounds_in: rounding may leave a clipped box empty; the box intersection stays
  // conservative.
  l = intersect(l, ref.box);
  u = intersect(u, ref.box);
  lower = l.empty() ? intersect(ref.box, box.below(axis, s)) : l;
  upper = u.empty() ? intersect(ref.box, box.above(axis, s)) : u;
}

}  // namespace raylab
