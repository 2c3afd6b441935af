#include "geometry/convex_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_2.h>
#include <CGAL/convex_hull_3.h>

#include <cmath>
#include <iterator>
#include <map>

#include "geometry/input_error.h"

namespace raylab {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Point2 = Kernel::Point_2;

/// Whether the points span space (four of them are not coplanar), decided exactly.
bool spans_space(const std::vector<Point3>& p) {
  std::size_t j = 1;
  while (j < p.size() && p[j] == p[0]) ++j;
  std::size_t k = j + 1;
  while (k < p.size() && CGAL::collinear(p[0], p[j], p[k])) ++k;
  for (std::size_t l = k + 1; l < p.size(); ++l)
    if (CGAL::orientation(p[0], p[j], p[k], p[l]) != CGAL::COPLANAR) return true;
  return false;
}

}  // namespace

TriangleMesh convex_hull(const std::vector<Vec3f>& points) {
  if (points.size() < 4) throw InputError("convex hull: needs at least four points");
  std::vector<Point3> cgal_points;
  cgal_points.reserve(points.size());
  for (const auto& p : points) {
    if (!is_finite(p)) throw InputError("convex hull: a point is not finite");
    cgal_points.emplace_back(p.x, p.y, p.z);
  }
  if (!spans_space(cgal_points)) throw InputError("convex hull: the points are coplanar");
  CGAL::Surface_mesh<Point3> hull;
  CGAL::convex_hull_3(cgal_points.begin(), cgal_points.end(), hull);
  TriangleMesh mesh;
  std::map<CGAL::Surface_mesh<Point3>::Vertex_index, std::uint32_t> index;
  for (const auto v : hull.vertices()) {
    const Point3& p = hull.point(v);
    index[v] = static_cast<std::uint32_t>(mesh.vertices.size());
    // Hull vertices are input points, so the doubles convert back to the floats exactly.
    mesh.vertices.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  for (const auto f : hull.faces()) {
    std::array<std::uint32_t, 3> t{};
    int k = 0;
    for (const auto v : hull.vertices_around_face(hull.halfedge(f)))
      if (k < 3) t[static_cast<std::size_t>(k++)] = index[v];
    if (k != 3) throw InputError("convex hull: a face is not a triangle");
    mesh.triangles.push_back(t);
  }
  return mesh;
}

double surface_area(const TriangleMesh& mesh) {
  double area = 0.0;
  for (std::size_t t = 0; t < mesh.size(); ++t) {
    const Vec3d a(mesh.vertex(t, 0)), b(mesh.vertex(t, 1)), c(mesh.vertex(t, 2));
    area += 0.5 * length(cross(b - a, c - a));
  }
  return area;
}

double projected_area(const std::vector<Vec3f>& points, const Vec3d& direction) {
  if (!is_finite(direction) || dot(direction, direction) == 0.0)
    throw InputError("projected area: the direction is zero or not finite");
  const Vec3d n = normalize(direction);
  const Vec3d u = normalize(std::abs(n.x) < 0.9 ? cross(n, Vec3d(1, 0, 0)) : cross(n, Vec3d(0, 1, 0)));
  const Vec3d v = cross(n, u);
  std::vector<Point2> projected;
  projected.reserve(points.size());
  for (const auto& p : points) projected.emplace_back(dot(Vec3d(p), u), dot(Vec3d(p), v));
  std::vector<Point2> hull;
  CGAL::convex_hull_2(projected.begin(), projected.end(), std::back_inserter(hull));
  double twice = 0.0;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Point2& a = hull[i];
    const Point2& b = hull[(i + 1) % hull.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * std::abs(twice);
}

}  // namespace raylab
