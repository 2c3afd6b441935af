#pragma once
/// Agreement of a set of hits with a reference (the exact oracle, or brute force), as
/// `raylab trace --check` and the oracle suite count it.
///
/// compare_hits (the tolerance rule): a ray mismatches when it (a) hits where the reference
/// misses, (b) misses where the reference hits, or (c) hits with
/// |t - t_ref| > kHitTolerance · (|t_ref| + (|o| + D) / |d|), D the diagonal of the scene's bounds:
/// a few thousand float ulps of the coordinates involved, far above the rounding of any float
/// kernel on a non-grazing hit. A hit on another primitive within that bound (a shared edge or
/// vertex, coincident faces) is agreement, counted as a tie.
///
/// compare_hits_exact (the exact rule, for the exact and certified kernels): a hit agrees only
/// when it names the reference's primitive, or another primitive that the ray meets first at the
/// same exact t (decided with ExactFirstHit, exact_predicates.h; counted as a tie). No tolerance.
///
/// Given the exact oracle's classes of the rays (contact_classes.h), both also count mismatches
/// per contact class, per accuracy bucket (accel_factory.h) and among ill-conditioned rays.
#include <array>
#include <cstdint>
#include <vector>

#include "accel/exact/contact_classes.h"
#include "geometry/ray.h"
#include "scene/scene.h"

namespace raylab {

inline constexpr double kHitTolerance = 1e-4;

struct HitComparison {
  std::size_t rays = 0;
  std::size_t mismatches = 0;  ///< false_hits + missed_hits + wrong_t
  std::size_t false_hits = 0;
  std::size_t missed_hits = 0;
  std::size_t wrong_t = 0;
  std::size_t ties = 0;
  std::vector<std::size_t> first_mismatches;  ///< up to 16 ray indices, for diagnosis

  // With classes only:
  std::array<std::size_t, 4> class_rays{}, class_mismatches{};    ///< by Contact (none, crossing, touching, on_surface)
  std::array<std::size_t, 4> bucket_rays{}, bucket_mismatches{};  ///< by RayBucket
  std::size_t ill_conditioned = 0, ill_conditioned_mismatches = 0;

  double mismatch_rate() const { return rays ? static_cast<double>(mismatches) / static_cast<double>(rays) : 0.0; }
};

/// `scene_diagonal` is |D| above; `classes` (one per ray) may be null.
HitComparison compare_hits(const std::vector<Ray>& rays, const std::vector<Hit>& hits, const std::vector<Hit>& reference,
                           double scene_diagonal, const std::vector<RayContact>* classes = nullptr);

/// The exact rule above; `scene` is the scene both were traced on (an instanced one is flattened
/// as the oracle flattens it).
HitComparison compare_hits_exact(const Scene& scene, const std::vector<Ray>& rays, const std::vector<Hit>& hits,
                                 const std::vector<Hit>& reference, const std::vector<RayContact>* classes = nullptr);

/// For any-hit queries: a mismatch is a differing blocked flag.
HitComparison compare_occlusion(const std::vector<std::uint8_t>& blocked, const std::vector<std::uint8_t>& reference,
                                const std::vector<RayContact>* classes = nullptr);

}  // namespace raylab
