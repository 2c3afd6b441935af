#pragma once
/// Convex hulls for the lecture's Crofton claims (experiments/exp_crofton.cpp): the hull of a
/// point set as a closed triangle mesh, and the area of the hull's orthogonal projection.
/// Computed with CGAL (convex_hull_3, convex_hull_2) on the exact-predicates kernel, so the
/// combinatorics are exact for the float input; areas are summed in double. This header
/// includes no CGAL header.
#include <vector>

#include "geometry/triangle_mesh.h"
#include "geometry/vec3.h"

namespace raylab {

/// The convex hull of `points` as a closed triangle mesh whose vertices are input points and
/// whose faces are oriented outward. Throws InputError for fewer than four points or points
/// that are all coplanar (the hull is then not a body).
TriangleMesh convex_hull(const std::vector<Vec3f>& points);

/// Total area of the triangles of `mesh`, in double.
double surface_area(const TriangleMesh& mesh);

/// The area of the orthogonal projection of the convex hull of `points` onto the plane
/// perpendicular to `direction` (any non-zero vector): the area of the planar convex hull of
/// the projected points, in double.
double projected_area(const std::vector<Vec3f>& points, const Vec3d& direction);

}  // namespace raylab
