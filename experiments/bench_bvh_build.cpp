// Google Benchmark figures of the BVH's build time against Embree's, on the scenes of exp_bvh's
// build table. Each iteration builds ours and Embree's in turn (alternating, so machine noise
// hits both alike), each through make_accelerator inside a TBB arena of the stated threads, as
// exp_bvh times them; the best wall-clock time of each is kept.
//  - BM_BvhBuild/<scene>/<threads>: `bvh` (binned SAH, width 8) against Embree medium quality;
//    BM_BvhBuild/<scene>/<threads>/<spec>: another spec of $RAYLAB_BENCH_BVH_BUILD_SPECS against
//    the same (for example an optimised tree: build + optimise against Embree medium).
//  - BM_SbvhBuild/<scene>/<threads>: `bvh:builder=spatial` against Embree high quality.
// Counters:
//      vs_embree     our best wall-clock build seconds over Embree's (< 1: we build faster)
//      vs_embree_cpu the same with the process's CPU seconds (every thread; the steadier figure
//                    at 1 thread on a shared machine)
//      faults, embree_faults  fewest minor page faults of a build (first touches: slow on VMs)
//      ours_ms, embree_ms, bytes_per_tri, embree_bytes_per_tri, sah_cost, triangles (the scene's primitives)
//   build/experiments/bench_bvh_build
//   build/experiments/bench_bvh_build --benchmark_filter='BM_BvhBuild/.*/1'
//   RAYLAB_BENCH_BVH_BUILD_SCENES='subdivided:of=cgal:bunny00,levels=2'
//     RAYLAB_BENCH_BVH_BUILD_SPECS='bvh;bvh:optimize=reinsert,optimize_budget=0.1' build/experiments/bench_bvh_build
//     (one command line; other scenes and specs, ';'-separated; `bvh` keeps the name without a spec)
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>
#include <time.h>

#include <chrono>
#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/tracer.h"
#include "scene/scene_spec.h"
#include "bench_env.h"

using namespace raylab;

namespace {

const std::vector<std::string> kScenes = {"cgal:armadillo",
                                          "cgal:bunny00",
                                          "cgal:elephant",
                                          "stadium:object=(sphere:n=5000),ratio=1000",
                                          "walls:n=400,angle=30",
                                          "grass:blades=100000",
                                          "room:of=cgal:armadillo,window=0"};

std::shared_ptr<const Scene> scene_for(const std::string& spec) {
  static std::map<std::string, std::shared_ptr<const Scene>> cache;
  auto& s = cache[spec];
  if (!s) s = make_scene(spec);
  return s;
}

double process_cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

long minor_faults_now() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

struct BuildTime {
  double wall = 1e300, cpu = 1e300;  ///< seconds; cpu: the process's CPU time (every thread, page faults included)
  double faults = 1e300;             ///< minor page faults (first touches of fresh memory)
  void keep_best(const BuildTime& t) {
    wall = std::min(wall, t.wall);
    cpu = std::min(cpu, t.cpu);
    faults = std::min(faults, t.faults);
  }
};

/// Builds `spec` in an arena of `threads`; keeps the structure in `out`.
BuildTime timed_build(const std::string& spec, const std::shared_ptr<const Scene>& scene, int threads,
                      std::unique_ptr<Aggregate>& out) {
  out.reset();
  tbb::task_arena arena(resolve_thread_count(threads));
  const double cpu = process_cpu_now();
  const long faults = minor_faults_now();
  const auto start = std::chrono::steady_clock::now();
  arena.execute([&] { out = make_accelerator(spec, scene); });
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), process_cpu_now() - cpu,
          static_cast<double>(minor_faults_now() - faults)};
}

void BM_Build(benchmark::State& state, const std::string& scene_spec, const std::string& ours_spec,
              const std::string& embree_spec, int threads) {
  const auto scene = scene_for(scene_spec);
  const std::string ours_full = with_param(ours_spec, "threads=" + std::to_string(threads));
  std::unique_ptr<Aggregate> ours, theirs;
  BuildTime ours_t, theirs_t;
  for (auto _ : state) {
    ours_t.keep_best(timed_build(ours_full, scene, threads, ours));
    theirs_t.keep_best(timed_build(embree_spec, scene, threads, theirs));
  }
  const double tris = static_cast<double>(scene->total_primitive_count());
  state.counters["vs_embree"] = ours_t.wall / theirs_t.wall;
  state.counters["vs_embree_cpu"] = ours_t.cpu / theirs_t.cpu;
  state.counters["ours_ms"] = ours_t.wall * 1e3;
  state.counters["embree_ms"] = theirs_t.wall * 1e3;
  state.counters["faults"] = ours_t.faults;
  state.counters["embree_faults"] = theirs_t.faults;
  state.counters["bytes_per_tri"] = static_cast<double>(ours->stats().bytes) / tris;
  state.counters["embree_bytes_per_tri"] = static_cast<double>(theirs->stats().bytes) / tris;
  state.counters["sah_cost"] = ours->stats().sah_cost;
  state.counters["triangles"] = tris;
}

const bool registered = [] {
  const auto scenes = scene_specs_from_env("RAYLAB_BENCH_BVH_BUILD_SCENES", kScenes, scene_for);
  const auto specs = accelerator_specs_from_env("RAYLAB_BENCH_BVH_BUILD_SPECS", {"bvh"});
  for (const auto& s : scenes) {
    for (const auto& spec : specs)
      for (int threads : {1, 2})
        benchmark::RegisterBenchmark(
            ("BM_BvhBuild/" + s + "/" + std::to_string(threads) + (spec == "bvh" ? "" : "/" + spec)).c_str(),
            BM_Build, s, spec, "embree", threads)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(7);
    benchmark::RegisterBenchmark(("BM_SbvhBuild/" + s + "/2").c_str(), BM_Build, s, "bvh:builder=spatial",
                                 "embree:quality=high", 2)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(5);
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
