#pragma once
/// The exact path of the certified kernel (certified_kernel.h): the first hit among the
/// primitives offered to it, decided exactly, with ExactFirstHit's rule (closed triangles, the
/// segment [tmin, tmax], the first contact point's exact t, ties to the lower id).
///
/// It is a second implementation, kept apart from ExactFirstHit (exact_predicates.h), which the
/// exact oracle uses, so that the oracle judges the certified kernel's exact decisions rather
/// than repeating them. For a triangle the line does not lie in (the case of every ray through
/// an edge or a vertex of a mesh) everything is exact arithmetic on the float inputs in CGAL::Mpzf
/// (exact binary floats: +, -, × without rounding; no filter, since the kernel's double stage
/// already failed): the hit by the signs of the three Plücker products d·((p_i - o)×(p_j - o)),
/// and t = ((p0 - o)·((p1 - o)×(p2 - o))) / (d·n), n = (p1 - p0)×(p2 - p0), kept as an exact
/// fraction and compared by cross-multiplication; no geometric
/// construction is made. A ray in (or parallel to) a triangle's plane and a sphere use
/// ExactFirstHit's constructions.
#include <memory>

#include "geometry/ray.h"
#include "geometry/sphere.h"

namespace raylab {

class ExactFallback {
 public:
  /// Sets exact_path_taken_on_this_thread().
  explicit ExactFallback(const Ray& ray);
  ~ExactFallback();
  ExactFallback(ExactFallback&&) noexcept;
  ExactFallback& operator=(ExactFallback&&) noexcept;

  /// True when the primitive becomes the current first hit.
  bool offer_triangle(unsigned prim, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2);
  bool offer_sphere(unsigned prim, const Sphere& sphere);

  bool has_hit() const;
  /// The first hit: t rounded, (u, v) evaluated in double.
  Hit hit() const;
  /// Doubles lo <= t <= hi around the exact t of the current first hit; requires has_hit().
  void best_time_bounds(double& lo, double& hi) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raylab
