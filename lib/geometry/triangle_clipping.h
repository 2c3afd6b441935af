#pragma once
/// Bounds of the part of a triangle inside a box, for split clipping ("perfect splits", Havran's
/// thesis §4.5; Wald and Havran 2006 §4.3).
#include "geometry/bounds.h"
#include "geometry/vec3.h"

namespace raylab {

/// A box that contains the intersection of the closed triangle (p0, p1, p2) with the closed
/// `box`, and is contained in `box`.
///
/// The triangle is clipped against the six slabs of the box (Sutherland-Hodgman) in double
/// precision; every computed coordinate is widened by a bound on its rounding error and rounded
/// outward to float, and the result is intersected with `box`. Original vertices and coordinates
/// on a clipping plane are exact and are not widened. When the clipped polygon vanishes in
/// double precision (the triangle only touches the box, or misses it), the triangle's bounds
/// intersected with `box` are returned, which still contain the true intersection; the result
/// may then be empty when the triangle misses the box.
Bounds3f clipped_triangle_bounds(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box);

/// clipped_triangle_bounds for both children of `box` split at `pos` along `axis`: `lower` for
/// the box with hi[axis] = pos, `upper` for the box with lo[axis] = pos. The triangle is clipped
/// to `box` once and that polygon by the split plane, so each result carries the same guarantee
/// (it contains triangle ∩ child and lies in the child) without clipping twice.
void clipped_triangle_bounds_split(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box, int axis,
                                   float pos, Bounds3f& lower, Bounds3f& upper);

/// The area of the closed triangle (p0, p1, p2) inside the closed `box`, clipped in double
/// precision (Sutherland-Hodgman): approximate to rounding, for measures such as the end-point
/// overlap, never for placement decisions.
double clipped_triangle_area(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box);

}  // namespace raylab
