#pragma once
/// The exact oracle's classification of rays (geometry/exact_contact.h): the class of each ray's
/// first contact (crossing, touching, on_surface, none) and whether the ray is ill-conditioned in
/// float, i.e. whether its exact answer changes when the ray moves by a few units in the last
/// place. The accuracy statements (AccuracyBound) and `raylab trace --check exact` count
/// mismatches per class.
///
/// Ill-conditioned. Let Δ(t) = 32u·(|o|∞ + |t|·|d|∞), u = 2^-24: how far the point at parameter t
/// moves when the origin and direction move by a few ulps. A ray is ill-conditioned when
///  (a) its contact is touching or on_surface (an arbitrarily small move turns a touch into a miss
///      or a crossing, a start on the surface into a start on either side), or
///  (b) its segment [tmin, t* + Δ] (the whole segment when there is no contact) passes, in the
///      projection along d, within 2Δ(t) of a contour of the surface, or so close to it that the
///      float edge function of the contour is within 4 times its rounding error bound (the
///      certified kernel's B, certified_kernel.h): an edge whose triangles do not lie on both
///      sides of it (a silhouette, boundary or non-manifold edge), a vertex whose fan's projected
///      sectors do not cover its neighbourhood, a triangle seen edge-on, or a zero-area triangle
///      (never hit, but a sliver of either orientation to float arithmetic); a near-touch or a
///      near-miss, or
///  (c) its start (the point at tmin) lies within 2Δ(tmin) (or 64u of the triangle's distance) of
///      a triangle or sphere surface.
/// Distances are evaluated in double in the sheared projection along d (the watertight kernel's)
/// with a factor-2 margin; candidates come from the oracle's AABB tree with a tube query around
/// the segment. The criterion is the float error scale, not an exact one: a crossing at a shared
/// edge or inside a vertex's tangent cone stays well-conditioned (moving the ray moves the hit
/// point continuously), and a float kernel is exact on well-conditioned crossings only if it is
/// watertight; on ill-conditioned rays none can be.
#include <cstdint>
#include <memory>
#include <vector>

#include "geometry/exact_contact.h"
#include "geometry/ray.h"
#include "scene/scene.h"

namespace raylab {

struct RayContact {
  Contact contact = Contact::none;
  bool ill_conditioned = false;
};

/// Classifies every ray against `scene` (instanced scenes: their flat copy, as the oracle), on
/// `threads` threads (0: all).
std::vector<RayContact> classify_contacts(const std::shared_ptr<const Scene>& scene, const std::vector<Ray>& rays,
                                          int threads = 0);

}  // namespace raylab
