#pragma once
/// How the cost model's data set times a case, shared by `raylab sweep`, `raylab predict
/// --measure` and the experiments: passes over the same rays with counters compiled out, each
/// pass of ours next to a pass of Embree's, so that both see the same machine state; the minimum
/// is the figure (the least disturbed pass), the median beside it.
///
/// Single-threaded passes are timed in CPU time of the tracing thread (TraceResult::
/// thread_cpu_seconds): on a quiet machine it equals the wall clock, and on a shared one it
/// leaves out the time the thread waited for a core, which otherwise dominates the noise (seen
/// here under a load of 5 on 2 cores: a kd-tree pass varied 690-970 ns per ray in wall clock and
/// 490-550 in CPU time, with Embree's at 186 in both). Multi-threaded passes use the wall clock.
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
  bool thread_cpu = false;  ///< timed in CPU time of the tracing thread (threads = 1), else wall clock
  double ns_per_ray_min = 0, ns_per_ray_median = 0;  ///< ours
  double ns_per_ray_max = 0;                         ///< ours, the slowest pass
  double embree_ns_per_ray_min = 0;                  ///< Embree's passes (0 when no Embree was given)
  double embree_ns_per_ray_median = 0;
  double embree_ns_per_ray_max = 0;                  ///< Embree's slowest pass
};

/// Times `ours` (and, when not null, `embree`) on `rays`, alternating passes. `rays` must not be empty.
AlternatingTiming time_alternating(const Primitive& ours, const Primitive* embree, const std::vector<Ray>& rays,
                                   const TimingOptions& options);

}  // namespace raylab
