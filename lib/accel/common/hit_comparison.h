#pragma once
/// Agreement of a set of hits with a reference (the exact oracle, or brute force), as
/// `raylab trace --check` and the oracle suite count it.
///
/// A ray mismatches when it (a) hits where the reference misses, (b) misses where the reference
/// hits, or (c) hits with |t - t_ref| > kHitTolerance · (|t_ref| + (|o| + D) / |d|), D the
/// diagonal of the scene's bounds: a few thousand float ulps of the coordinates involved, far
/// above the rounding of any float kernel on a non-grazing hit. A hit on another primitive
/// within that bound (a shared edge or vertex, coincident faces) is agreement, counted as a tie.
#include <cstdint>
#include <vector>

#include "geometry/ray.h"

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

  double mismatch_rate() const { return rays ? static_cast<double>(mismatches) / static_cast<double>(rays) : 0.0; }
};

/// `scene_diagonal` is |D| above.
HitComparison compare_hits(const std::vector<Ray>& rays, const std::vector<Hit>& hits, const std::vector<Hit>& reference,
                           double scene_diagonal);

/// For any-hit queries: a mismatch is a differing blocked flag.
HitComparison compare_occlusion(const std::vector<std::uint8_t>& blocked, const std::vector<std::uint8_t>& reference);

}  // namespace raylab
