#pragma once
/// The exact class of a ray's first contact with a surface: does it cross the surface, touch it,
/// start on it, or miss it? Decided with exact predicates (CGAL, behind this interface as in
/// exact_predicates.h), for the accuracy statements that are made per class
/// (accel_factory.h: AccuracyBound).
///
/// Definitions. Let t* be the exact first-hit parameter of the ray segment {o + t·d : tmin <= t
/// <= tmax} among the primitives offered (ExactFirstHit's rule) and p = o + t*·d.
///  - none:       no primitive meets the segment.
///  - on_surface: t* = tmin: the segment starts on a surface.
///  - crossing:   the lines parallel to the ray through every point near p all meet the
///                primitives that contain p, near p: the ray passes from one side of the surface
///                to the other. Exactly: p lies in the relative interior of a triangle whose plane
///                the ray does not lie in, or in a sphere the line meets twice; or, projecting
///                along d, the triangles containing p (those whose plane the ray does not lie in)
///                cover a whole neighbourhood of p's projection: each covers a closed angular
///                sector at p (a half-plane at an edge point, the corner angle at a vertex), and
///                the union of the sectors is the full circle. A transversal hit at an edge
///                shared by two faces, or at a vertex inside its fan's tangent cone, is a crossing.
///  - touching:   any other contact: p on a silhouette edge or a boundary edge, at a vertex
///                outside the tangent cone of its fan, a ray lying in a face's plane, a sphere
///                met at one point. Every parallel line on one side misses: the exact answer
///                turns on the last bit of the ray.
#include <cstdint>
#include <memory>

#include "geometry/ray.h"
#include "geometry/sphere.h"

namespace raylab {

enum class Contact : std::uint8_t { none, crossing, touching, on_surface };

/// "none", "crossing", "touching", "on_surface".
const char* contact_name(Contact c);

/// Offered every primitive that may meet the ray (in any order), classifies its first contact.
class ExactContactClassifier {
 public:
  explicit ExactContactClassifier(const Ray& ray);
  ~ExactContactClassifier();
  ExactContactClassifier(ExactContactClassifier&&) noexcept;
  ExactContactClassifier& operator=(ExactContactClassifier&&) noexcept;

  void offer_triangle(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2);
  void offer_sphere(const Sphere& sphere);

  Contact contact() const;
  /// t* rounded to a double (meaningful when contact() != none).
  double first_t() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raylab
