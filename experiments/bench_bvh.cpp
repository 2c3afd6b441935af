// Google Benchmark figures of the BVH against Embree, single thread, on the rays of exp_bvh:
//  - BM_BvhTrace/<scene>/<rays>/<bvh spec>: the BVH traced through raylab's tracer (trace_rays,
//    as exp_bvh does) against its like-for-like Embree (`embree-robust` for the robust default,
//    `embree` for robust=off), passes alternating, best pass of each kept. Counters:
//      vs_embree         our throughput over the like-for-like Embree's, both through raylab
//      vs_embree_fast    our throughput over `embree` (Embree's fast, non-watertight mode)
//      vs_embree_direct  our own loop (the rays through Aggregate::intersect/occluded in a plain
//                        loop, no TBB, no result vectors) over Embree called directly on the same
//                        rays (rtcIntersect1 / rtcOccluded1 in a tight loop on the like-for-like
//                        Embree's own RTCScene): the comparison without raylab's call path on
//                        either side
//      nodes, leaves, tests per ray (counted pass); triangles, the scene's primitives
//   build/experiments/bench_bvh --benchmark_min_time=0.1
//   build/experiments/bench_bvh --benchmark_filter='armadillo/diffuse'
//   RAYLAB_BENCH_BVH_SPECS='bvh;bvh:width=4' build/experiments/bench_bvh   (other specs, ';'-separated)
//   RAYLAB_BENCH_BVH_SCENES='grass:blades=3500000' build/experiments/bench_bvh   (other scenes, likewise)
#include <benchmark/benchmark.h>
#include <time.h>

#include <cstdlib>
#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/timing_cpu.h"
#include "accel/common/tracer.h"
#include "cost/model_file.h"
#include "bench_env.h"
#include "embree_direct.h"
#include "geometry/float_mode.h"
#include "scene/scene_spec.h"

using namespace raylab;
using raylab::experiments::DirectEmbree;
using raylab::experiments::own_loop;

namespace {

/// The closed scene of issue 17's goals (exp_bvh's kClosedRoom): the object in a room without
/// windows, traced with rays from a camera inside it, so every diffuse ray hits.
const std::string kClosedRoom = "room:of=cgal:armadillo,window=0";
const std::vector<std::string> kScenes = {"cgal:armadillo", "cgal:bunny00", "cgal:elephant",
                                          "stadium:object=(sphere:n=5000),ratio=1000", "walls:n=400,angle=30",
                                          "grass:blades=100000", kClosedRoom};
const std::vector<std::string> kRayKinds = {"primary:65536", "diffuse:65536", "shadow:65536"};
const std::vector<std::string> kBvhSpecs = {"bvh", "bvh:robust=off"};

/// The ray spec traced on `scene_spec`: the closed room's rays start from a camera inside it.
std::string rays_on(const std::string& scene_spec, const std::string& ray_spec) {
  return scene_spec == kClosedRoom ? ray_spec + ",camera=inside" : ray_spec;
}

std::shared_ptr<const Scene> scene_for(const std::string& spec) {
  static std::map<std::string, std::shared_ptr<const Scene>> cache;
  auto& s = cache[spec];
  if (!s) s = make_scene(spec);
  return s;
}

const std::vector<Ray>& rays_for(const std::string& scene_spec, const std::string& ray_spec) {
  static std::map<std::pair<std::string, std::string>, std::vector<Ray>> cache;
  auto& r = cache[{scene_spec, ray_spec}];
  if (r.empty()) r = make_ray_set(ray_spec, scene_for(scene_spec));
  return r;
}

double thread_cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Thread CPU seconds of `f()` (single thread: the time a shared machine keeps it waiting is out),
/// on the timing CPU when `RAYLAB_TIMING_CPU` names one.
template <class F>
double cpu_seconds_of(F&& f) {
  const TimingCpuScope pinned;
  const double start = thread_cpu_now();
  f();
  return thread_cpu_now() - start;
}

void BM_BvhTrace(benchmark::State& state, const std::string& scene_spec, const std::string& ray_spec,
                 const std::string& accel_spec) {
  const auto scene = scene_for(scene_spec);
  const auto& rays = rays_for(scene_spec, ray_spec);
  const bool any = is_any_hit_ray_spec(ray_spec);
  const bool robust = accel_spec.find("robust=off") == std::string::npos;
  const auto accel = make_accelerator(accel_spec, scene, model_build_context());
  const auto like = make_accelerator(robust ? "embree-robust" : "embree", scene);
  const auto fast = make_accelerator("embree", scene);
  const DirectEmbree embree_direct(*like);
  const TraceOptions options{1, false, any};
  double ours = 1e300, like_s = 1e300, fast_s = 1e300, own = 1e300, direct_s = 1e300;
  std::size_t own_hits = 0, direct_hits = 0;
  for (auto _ : state) {
    ours = std::min(ours, trace_rays(*accel, rays, options).thread_cpu_seconds);
    like_s = std::min(like_s, trace_rays(*like, rays, options).thread_cpu_seconds);
    if (!robust) fast_s = like_s;
    else fast_s = std::min(fast_s, trace_rays(*fast, rays, options).thread_cpu_seconds);
    const FloatModeScope ftz(true);
    own = std::min(own, cpu_seconds_of([&] { own_hits = own_loop(*accel, rays, any); }));
    direct_s = std::min(direct_s, cpu_seconds_of([&] { direct_hits = embree_direct.trace(rays, any); }));
  }
  benchmark::DoNotOptimize(own_hits + direct_hits);
  const double n = static_cast<double>(rays.size());
  const TraceResult counted = trace_rays(*accel, rays, TraceOptions{1, true, any});
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * rays.size()));
  state.counters["ns_per_ray"] = ours / n * 1e9;
  state.counters["vs_embree"] = like_s / ours;
  state.counters["vs_embree_fast"] = fast_s / ours;
  state.counters["vs_embree_direct"] = direct_s / own;
  state.counters["nodes"] = static_cast<double>(counted.counters.nodes) / n;
  state.counters["leaves"] = static_cast<double>(counted.counters.leaves) / n;
  state.counters["tests"] = static_cast<double>(counted.counters.prim_tests) / n;
  state.counters["triangles"] = static_cast<double>(scene->total_primitive_count());
  // Bytes per triangle: ours (AccelStats::bytes) and Embree's fast-mode scene (BVH and geometry buffers).
  state.counters["bytes_per_tri"] = static_cast<double>(accel->stats().bytes) / state.counters["triangles"];
  state.counters["embree_bytes_per_tri"] = static_cast<double>(fast->stats().bytes) / state.counters["triangles"];
}

const bool registered = [] {
  const auto scenes = scene_specs_from_env("RAYLAB_BENCH_BVH_SCENES", kScenes, scene_for);
  const auto specs = accelerator_specs_from_env("RAYLAB_BENCH_BVH_SPECS", kBvhSpecs);
  for (const auto& s : scenes)
    for (const auto& r : kRayKinds)
      for (const auto& a : specs)
        benchmark::RegisterBenchmark(("BM_BvhTrace/" + s + "/" + rays_on(s, r) + "/" + a).c_str(), BM_BvhTrace, s,
                                     rays_on(s, r), a)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(5);
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
