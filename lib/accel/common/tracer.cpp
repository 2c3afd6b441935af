#include "accel/common/tracer.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <time.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "accel/common/timing_cpu.h"
#include "geometry/float_mode.h"

namespace raylab {

namespace {

double thread_cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

int resolve_thread_count(int threads) {
  if (threads > 0) return threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

TraceResult trace_rays(const Primitive& prim, const std::vector<Ray>& rays, const TraceOptions& options) {
  TraceResult result;
  const std::size_t n = rays.size();
  if (options.occlusion) result.blocked.assign(n, 0);
  else result.hits.assign(n, Hit{});
  tbb::combinable<RayCounters> counters;
  std::atomic<std::size_t> hit_count{0};
  TimingArena arena(options.threads);
  const double cpu_start = thread_cpu_now();
  const auto start = std::chrono::steady_clock::now();
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64), [&](const tbb::blocked_range<std::size_t>& range) {
      const FloatModeScope ftz(true);
      std::size_t local_hits = 0;
      RayCounters* c = options.counters ? &counters.local() : nullptr;
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (options.occlusion) {
          const bool blocked = c ? prim.occluded(rays[i], *c) : prim.occluded(rays[i]);
          result.blocked[i] = blocked;
          local_hits += blocked;
        } else {
          Ray ray = rays[i];
          const bool found = c ? prim.intersect(ray, result.hits[i], *c) : prim.intersect(ray, result.hits[i]);
          local_hits += found;
        }
      }
      hit_count += local_hits;
    });
  });
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.thread_cpu_seconds = thread_cpu_now() - cpu_start;
  result.hit_count = hit_count;
  counters.combine_each([&](const RayCounters& c) { result.counters += c; });
  return result;
}

}  // namespace raylab
