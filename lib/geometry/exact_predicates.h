#pragma once
/// Exact geometric decisions, behind a small interface so that CGAL headers stay in one
/// translation unit (exact_predicates.cpp). Inputs are floats, which CGAL's double kernels
/// represent exactly; every decision below is exact for them.
#include <memory>

#include "geometry/ray.h"
#include "geometry/sphere.h"
#include "geometry/triangle_kernels.h"

namespace raylab {

/// A point o + 2^k·d (k an integer) of `ray`, k chosen so that every coordinate is the exact sum
/// in double: a CGAL Epick ray through o and this point is then exactly the ray, where
/// Epick::Ray_3(o, d) would round o + d (and make the ray degenerate when |d| is far below |o|,
/// which CGAL's predicates do not accept). Returns false for an invalid ray and when no k within
/// ±64 of the one matching the magnitudes of o and d gives exact sums; callers then decide
/// without an Epick ray.
bool exact_second_point(const Ray& ray, Vec3d& second);

/// Set to true on the calling thread whenever an ExactFirstHit is made, i.e. a ray takes the exact
/// path; AggregateBase reads and clears it to count RayCounters::exact_fallbacks.
bool& exact_path_taken_on_this_thread();

/// Accumulates, exactly, the first hit along one ray among the primitives offered to it.
///
/// A triangle is hit when the closed triangle meets the ray segment {o + t·d : tmin <= t <= tmax}
/// (CGAL::do_intersect on Exact_predicates_inexact_constructions_kernel, with the ray through o
/// and exact_second_point; on Exact_predicates_exact_constructions_kernel where there is none). Its hit parameter is
/// the exact rational t of the first contact point not before tmin (CGAL Epeck constructions;
/// for a ray lying in the triangle's plane, the entry of the contact segment). A sphere's hit
/// parameter is the exact algebraic root (CORE::Expr). Offers are ordered by exact t, then by
/// the lower primitive id, so the result does not depend on the order of the offers.
/// Degenerate (zero-area) triangles and spheres of radius <= 0 are never hit.
class ExactFirstHit {
 public:
  /// Sets exact_path_taken_on_this_thread().
  explicit ExactFirstHit(const Ray& ray);
  ~ExactFirstHit();
  ExactFirstHit(ExactFirstHit&&) noexcept;
  ExactFirstHit& operator=(ExactFirstHit&&) noexcept;

  /// Returns true when the triangle becomes the current first hit.
  bool offer_triangle(unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2);
  bool offer_sphere(unsigned prim, const Sphere& sphere);

  bool has_hit() const;
  /// The first hit, with t rounded to the nearest float; u, v from a double evaluation.
  Hit hit() const;
  /// A float that is >= the exact t of the current first hit (tmax while there is none), for
  /// conservative pruning of candidates.
  float closest_upper_bound() const;
  /// Floats lo <= t <= hi around the exact t of the current first hit (CGAL::to_interval of the
  /// exact number, rounded outward); requires has_hit().
  void best_time_bounds(float& lo, float& hi) const;
  /// The sign of (exact t of this first hit) - (exact t of other's), both for the same ray;
  /// requires has_hit() on both.
  int compare_time(const ExactFirstHit& other) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The exact kernel under the common kernel interface (triangle_kernels.h): every offer goes to
/// one ExactFirstHit, so the first hit is ordered exactly whatever the order of the offers.
struct ExactKernel {
  /// It decides t in the closed [tmin, tmax] exactly, so any-hit queries must not widen tmax
  /// (primitive.h, any_hit_ray), as for the certified kernel.
  static constexpr bool kClosedInterval = true;
  struct Context {
    ExactFirstHit first;
  };
  static Context prepare(const Ray& ray) { return {ExactFirstHit(ray)}; }
  static float closest(const Context& c) { return c.first.closest_upper_bound(); }
  static bool intersect(Context& c, unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2,
                        TriangleHit& hit) {
    if (!c.first.offer_triangle(prim, p0, p1, p2)) return false;
    const Hit h = c.first.hit();
    hit = {h.t, h.u, h.v};
    return true;
  }
  static bool intersect_sphere(Context& c, unsigned prim, const Sphere& s, TriangleHit& hit) {
    if (!c.first.offer_sphere(prim, s)) return false;
    const Hit h = c.first.hit();
    hit = {h.t, h.u, h.v};
    return true;
  }
};

/// Exact orientation of d relative to the plane through a, b, c: +1 when d is on the positive
/// side (CGAL::orientation convention: POSITIVE when (a,b,c,d) is positively oriented), 0 when
/// coplanar, -1 otherwise.
int exact_orientation(const Vec3f& a, const Vec3f& b, const Vec3f& c, const Vec3f& d);

/// Whether the closed triangle (p0,p1,p2) intersects the closed box, decided exactly. A
/// degenerate triangle is tested as the segment or point it is.
bool exact_triangle_intersects_box(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box);

}  // namespace raylab
