#pragma once
/// Which primitives a child cell of a spatial subdivision receives, and with which bounds
/// (`clip=none|bbox|exact`). Shared by the kd-tree, the octree and the axis-aligned planes of the
/// BSP tree.
///
///  - none:  a primitive goes to every child whose closed box its own bounds overlap; split
///           candidates come from its unclipped bounds.
///  - bbox:  the same placement, with bounds intersected with the node box (Havran's thesis
///           §4.5, "split clipping" by boxes).
///  - exact: a triangle goes to a child if and only if it intersects the child's closed box,
///           decided by CGAL's exact Triangle_3/Bbox_3 predicate; its bounds are the clipped bounds
///           of triangle ∩ box (geometry/triangle_clipping.h), the "perfect splits" of Wald and
///           Havran 2006 §4.3. Spheres are placed by their bounds, as in `bbox`.
///
/// Every mode is conservative: a primitive that meets a child's closed box is always placed in
/// it, so a ray's hit point, which lies in some closed leaf box, is found in that leaf.
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/bounds.h"
#include "scene/scene.h"

namespace raylab {

enum class ClipMode { none, bbox, exact };

/// The spec names of the clip modes: "none", "bbox", "exact".
const std::vector<std::string>& clip_mode_names();
ClipMode parse_clip_mode(const std::string& name);

/// A primitive reference inside a node: the primitive id and its (possibly clipped) bounds.
struct PrimRef {
  Bounds3f box;
  std::uint32_t prim = 0;
};

/// The root references: every primitive of `scene` (not instanced) with its bounds.
std::vector<PrimRef> make_root_refs(const Scene& scene);

/// Whether `ref` (already in a node) belongs to the closed `child` box of that node.
bool ref_meets_box(const Scene& scene, const PrimRef& ref, const Bounds3f& child, ClipMode mode);

/// ref_meets_box(ref, lbox) and ref_meets_box(ref, rbox) for the children lbox, rbox of `box`
/// split at `s` along `axis` (same results), with one more filter before the exact predicate:
/// an edge crossing the plane well inside the face shared by the children proves both.
void ref_meets_children(const Scene& scene, const PrimRef& ref, const Bounds3f& box, int axis, float s,
                        ClipMode mode, bool& in_l, bool& in_r);

/// The bounds of `ref` in `child`, given ref_meets_box: the unchanged bounds for `none`, the
/// bounds intersected with `child` for `bbox`, the clipped triangle bounds for `exact`.
Bounds3f ref_bounds_in(const Scene& scene, const PrimRef& ref, const Bounds3f& child, ClipMode mode);

/// ref_bounds_in for both children of `box` split at `s` along `axis`, for a reference that
/// meets both; for `exact`, a triangle is clipped to `box` once (clipped_triangle_bounds_split).
void ref_bounds_in_children(const Scene& scene, const PrimRef& ref, const Bounds3f& box, int axis, float s,
                            ClipMode mode, Bounds3f& lower, Bounds3f& upper);

}  // namespace raylab
