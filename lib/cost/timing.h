#pragma once
/// How the cost model's data set times a case, shared by `raylab sweep`, `raylab predict
/// --measure` and the experiments: passes over the same rays with counters compiled out, each
/// pass of ours next to a pass of Embree's, so that both see the same machine state; the minimum
/// is the figure (the least disturbed pass), the median beside it.
#include <vector>

#include "geometry/ray.h"
#include "scene/primitive.h"

namespace raylab {

struct TimingOptions {
  int min_passes = 5;           ///< at least this many passes of each
  double min_seconds = 0.1;     ///< and until ours have taken this long in total
  int max_passes = 50;
  int threads = 1;              ///< tracing threads (1: the single-thread headline figure)
  bool any_hit = false;         ///< occluded() queries instead of intersect()
};

struct AlternatingTiming {
  int passes = 0;
  double ns_per_ray_min = 0, ns_per_ray_median = 0;  ///< ours
  double embree_ns_per_ray_min = 0;                  ///< Embree's passes (0 when no Embree was given)
  double embree_ns_per_ray_median = 0;
};

/// Times `ours` (and, when not null, `embree`) on `rays`, alternating passes. `rays` must not be empty.
AlternatingTiming time_alternating(const Primitive& ours, const Primitive* embree, const std::vector<Ray>& rays,
                                   const TimingOptions& options);

}  // namespace raylab
