#pragma once
/// Secondary rays leaving the surfaces a camera sees: diffuse bounces, shadow rays and ambient
/// occlusion rays, the incoherent workloads of a path tracer (Pharr, Jakob and Humphreys,
/// "Physically Based Rendering", 4th ed., ch. 13).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "geometry/ray.h"
#include "rays/camera.h"
#include "scene/scene.h"

namespace raylab {

/// Returns the first hit of a ray in the scene; the caller supplies a tracer (an accelerator or
/// a brute-force loop), so this layer does not depend on any accelerator.
using FirstHitFunction = std::function<Hit(const Ray&)>;

/// A hit point in world space with its unit geometric normal turned to face the incoming ray.
struct SurfacePoint {
  Vec3f p;
  Vec3f n;
};

/// The world-space point and geometric normal of `hit` (which must be valid for `ray` in
/// `scene`). Triangles: p from the barycentrics, n = (p1 − p0) × (p2 − p0); spheres: p = o + t·d
/// projected onto the sphere, n = p − c. For a hit on an instance both are computed in its base
/// scene and mapped to the world by Scene::instances[hit.instance]: points by the transform,
/// normals by its inverse transpose. Throws std::logic_error for a hit naming a primitive or
/// instance the scene does not have (a tracer bug).
SurfacePoint surface_at(const Scene& scene, const Ray& ray, const Hit& hit);

/// Exactly `n` surface points seen by `camera`, or none when the camera sees nothing.
///
/// Primary rays through pixel centres of a square image of side ceil(sqrt(2n)) are traced in
/// scanline order; when fewer than n of them hit, the side is doubled, up to an image of
/// max(16n, 2^16) pixels. Of the h hits of the last image, hits ⌊i·h/n⌋ for i < n are taken
/// when h ≥ n (evenly spread over the image), else hit i mod h (points are reused: a scene that
/// covers few pixels still yields n rays). Deterministic.
std::vector<SurfacePoint> visible_points(const Scene& scene, const Camera& camera, std::size_t n,
                                         const FirstHitFunction& trace);

enum class SurfaceRayKind {
  diffuse,  ///< cosine-weighted about the normal; unit direction, tmin = 0, tmax = inf
  shadow,   ///< toward a uniform point of the area light (light_point); tmax just below 1
  ambient_occlusion,  ///< cosine-weighted; unit direction, tmax = 0.1 × scene diagonal
};

/// The area light of shadow rays: the horizontal square of side D/2 (D = length of the scene
/// box diagonal) centred D/2 above the centre of the top face of the box (world +y is up).
/// (u1, u2) in [0,1)^2 picks the point.
Vec3d light_point(const Bounds3f& scene_bounds, double u1, double u2);

/// The upper end of a shadow ray's t: the direction spans origin to light point, so t = 1 is
/// the light; stopping just short of it keeps any geometry at the light itself out.
inline constexpr float kShadowTmax = 1.0f - 0x1.0p-12f;

/// `n` rays of the given kind, one from each of visible_points(scene, camera, n, trace); the
/// origin is the point offset off the surface along its normal (offset_ray.h), toward the
/// camera's side. Returns an empty vector when the camera sees nothing. Deterministic for a
/// given seed.
std::vector<Ray> surface_rays(SurfaceRayKind kind, const Scene& scene, const Camera& camera, std::size_t n,
                              std::uint64_t seed, const FirstHitFunction& trace);

}  // namespace raylab
