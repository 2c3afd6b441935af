#include "cost/timing.h"

#include <algorithm>

#include "accel/common/tracer.h"

namespace raylab {
namespace {

double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace

AlternatingTiming time_alternating(const Primitive& ours, const Primitive* embree, const std::vector<Ray>& rays,
                                   const TimingOptions& options) {
  const TraceOptions trace{options.threads, false, options.any_hit};
  const bool thread_cpu = resolve_thread_count(options.threads) == 1;
  auto seconds = [&](const Primitive& p) {
    const TraceResult r = trace_rays(p, rays, trace);
    return thread_cpu ? r.thread_cpu_seconds : r.seconds;
  };
  std::vector<double> mine, theirs;
  double spent = 0;
  while (static_cast<int>(mine.size()) < options.max_passes &&
         (static_cast<int>(mine.size()) < options.min_passes || spent < options.min_seconds)) {
    if (embree) theirs.push_back(seconds(*embree));
    const double s = seconds(ours);
    mine.push_back(s);
    spent += s;
  }
  const double per_ray = 1e9 / static_cast<double>(rays.size());
  AlternatingTiming t;
  t.passes = static_cast<int>(mine.size());
  t.thread_cpu = thread_cpu;
  t.ns_per_ray_min = *std::min_element(mine.begin(), mine.end()) * per_ray;
  t.ns_per_ray_median = median_of(mine) * per_ray;
  t.ns_per_ray_max = *std::max_element(mine.begin(), mine.end()) * per_ray;
  if (!theirs.empty()) {
    t.embree_ns_per_ray_min = *std::min_element(theirs.begin(), theirs.end()) * per_ray;
    t.embree_ns_per_ray_median = median_of(theirs) * per_ray;
    t.embree_ns_per_ray_max = *std::max_element(theirs.begin(), theirs.end()) * per_ray;
  }
  return t;
}

}  // namespace raylab
