#pragma once
/// Traces a batch of rays through any primitive with TBB, FTZ/DAZ set on every tracing thread,
/// and times the trace alone (builds are timed by the caller).
#include <cstdint>
#include <vector>

#include "scene/primitive.h"

namespace raylab {

struct TraceOptions {
  int threads = 0;         ///< 0: all hardware threads; 1: the single-core figure
  bool counters = false;   ///< collect per-ray counters (the counted virtual path)
  bool occlusion = false;  ///< any-hit queries (occluded) instead of closest hit
};

struct TraceResult {
  std::vector<Hit> hits;              ///< closest-hit mode: one per ray
  std::vector<std::uint8_t> blocked;  ///< occlusion mode: one per ray
  RayCounters counters;               ///< summed over rays (zero unless TraceOptions::counters)
  double seconds = 0.0;               ///< wall-clock time of the trace
  /// CPU time of the calling thread during the trace: with threads = 1 the trace runs on that
  /// thread alone, and this excludes the time a shared machine kept it waiting for a core.
  double thread_cpu_seconds = 0.0;
  std::size_t hit_count = 0;          ///< rays that hit (or are occluded)
};

TraceResult trace_rays(const Primitive& prim, const std::vector<Ray>& rays, const TraceOptions& options);

/// The number of threads `threads` stands for (0: the hardware concurrency).
int resolve_thread_count(int threads);

}  // namespace raylab
