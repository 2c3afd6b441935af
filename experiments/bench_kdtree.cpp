// Google Benchmark figures of the SAH kd-tree, single thread:
//  - BM_KdBuild: the event-sweep build (Wald and Havran 2006) of a ~1.2M-triangle mesh
//    (subdivided:of=cgal:bunny00,levels=2), with exact clipping and with none; counter
//    build_s is the building thread's CPU time, best of the iterations;
//    `exact_over_none` (on the exact run) is the cost of exactness, measured in the same process;
//    `over_embree_1t` is its ratio to Embree's medium-quality build on one thread (the issue's ~3x).
//  - BM_KdTrace: traversal on primary and diffuse rays of CGAL meshes; counter `vs_embree` is our
//    throughput over Embree's on the same rays (1.0 = as fast), Embree's pass alternating with ours,
//    best pass of each over the same number of passes.
//   build/experiments/bench_kdtree --benchmark_min_time=0.2
// BM_KdTrace measures the spec in $RAYLAB_KD_SPEC when set (e.g. RAYLAB_KD_SPEC=kdtree:cost=default);
// with $RAYLAB_KD_BASE set (e.g. RAYLAB_KD_BASE=kdtree:traversal=stack) it times that spec too, in
// the same alternation, and counter `vs_base` is our throughput over the base spec's. With
// $RAYLAB_KD_CPU_TIME=1 a pass is timed by the tracing thread's CPU time instead of wall time (on
// a loaded machine it leaves out the time the thread waited for a core).
#include <benchmark/benchmark.h>

#include <tbb/task_arena.h>

#include <cstdlib>
#include <ctime>
#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/timing_cpu.h"
#include "accel/common/tracer.h"
#include "cost/model_file.h"
#include "scene/scene_spec.h"
#include "bench_env.h"

using namespace raylab;

namespace {

const std::string kBigMesh = "subdivided:of=cgal:bunny00,levels=2";
const std::vector<std::string> kMeshes = {"cgal:bunny00", "cgal:armadillo", "cgal:ChineseDragon-10kv"};

std::shared_ptr<const Scene> scene_for(const std::string& spec) {
  static std::map<std::string, std::shared_ptr<const Scene>> cache;
  auto& s = cache[spec];
  if (!s) s = make_scene(spec);
  return s;
}

/// The kd-tree spec BM_KdTrace measures: $RAYLAB_KD_SPEC, or the default `kdtree`.
std::string kd_spec() {
  static const std::string spec = accelerator_specs_from_env("RAYLAB_KD_SPEC", {"kdtree"}).front();
  return spec;
}

/// The spec BM_KdTrace compares against, $RAYLAB_KD_BASE, or empty.
std::string kd_base_spec() {
  static const std::string spec = accelerator_specs_from_env("RAYLAB_KD_BASE", {""}).front();
  return spec;
}

/// A single-threaded trace pass's time: wall time, or with $RAYLAB_KD_CPU_TIME=1 the tracing
/// thread's CPU time (trace_rays runs a one-thread arena on the calling thread).
double pass_seconds(const Aggregate& accel, const std::vector<Ray>& rays) {
  static const bool cpu = [] {
    const char* env = std::getenv("RAYLAB_KD_CPU_TIME");
    return env != nullptr && std::string(env) == "1";
  }();
  const TraceResult r = trace_rays(accel, rays, TraceOptions{1, false, false});
  benchmark::DoNotOptimize(r.hit_count);
  return cpu ? r.thread_cpu_seconds : r.seconds;
}

/// CPU time of the calling thread spent building `accel_spec` (single-threaded builds only): on a
/// shared machine it leaves out the time the thread waited for a core.
double seconds_to_build(const std::string& accel_spec, const std::shared_ptr<const Scene>& scene) {
  const TimingCpuScope pinned;
  timespec start{}, end{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &start);
  auto accel = make_accelerator(accel_spec, scene, model_build_context());
  benchmark::DoNotOptimize(accel.get());
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &end);
  return static_cast<double>(end.tv_sec - start.tv_sec) + 1e-9 * static_cast<double>(end.tv_nsec - start.tv_nsec);
}

/// Embree's medium-quality build of `scene` confined to the calling thread (a one-thread TBB
/// arena, which Embree's TBB tasking runs in), best of `repeats`.
double embree_single_thread_build_s(const std::shared_ptr<const Scene>& scene, int repeats) {
  tbb::task_arena arena(1);
  double best = 1e300;
  for (int i = 0; i < repeats; ++i)
    arena.execute([&] { best = std::min(best, seconds_to_build("embree:quality=medium", scene)); });
  return best;
}

void BM_KdBuild(benchmark::State& state, const std::string& accel_spec, bool compare) {
  const auto scene = scene_for(kBigMesh);
  double best = 1e300;
  for (auto _ : state) best = std::min(best, seconds_to_build(accel_spec, scene));
  state.counters["triangles"] = static_cast<double>(scene->mesh.size());
  state.counters["build_s"] = best;
  if (!compare) return;
  state.counters["exact_over_none"] = best / seconds_to_build("kdtree:clip=none", scene);
  state.counters["over_embree_1t"] = best / embree_single_thread_build_s(scene, 3);
}

void BM_KdTrace(benchmark::State& state, const std::string& scene_spec, const std::string& ray_spec) {
  const auto scene = scene_for(scene_spec);
  const auto rays = make_ray_set(ray_spec, scene);
  const auto embree = make_accelerator("embree", scene);
  const auto accel = make_accelerator(kd_spec(), scene, model_build_context());
  const std::string base_spec = kd_base_spec();
  const auto base = base_spec.empty() ? nullptr : make_accelerator(base_spec, scene, model_build_context());
  double best = 1e300, embree_s = 1e300, base_s = 1e300;
  for (auto _ : state) {
    best = std::min(best, pass_seconds(*accel, rays));
    embree_s = std::min(embree_s, pass_seconds(*embree, rays));
    if (base) base_s = std::min(base_s, pass_seconds(*base, rays));
  }
  if (base) state.counters["vs_base"] = base_s / best;
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * rays.size()));
  state.counters["ns_per_ray"] = best / static_cast<double>(rays.size()) * 1e9;
  state.counters["embree_ns_per_ray"] = embree_s / static_cast<double>(rays.size()) * 1e9;
  state.counters["vs_embree"] = embree_s / best;
  const double tris = static_cast<double>(scene->mesh.size());
  state.counters["bytes_per_tri"] = static_cast<double>(accel->stats().bytes) / tris;
  state.counters["embree_bytes_per_tri"] = static_cast<double>(embree->stats().bytes) / tris;
}

const bool registered = [] {
  benchmark::RegisterBenchmark("BM_KdBuild/events/exact", BM_KdBuild, "kdtree:sweep=events,clip=exact", true)
      ->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
  benchmark::RegisterBenchmark("BM_KdBuild/events/none", BM_KdBuild, "kdtree:sweep=events,clip=none", false)
      ->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
  for (const auto& m : kMeshes)
    for (const std::string r : {"primary:65536", "diffuse:65536"})
      benchmark::RegisterBenchmark(("BM_KdTrace/" + m + "/" + r).c_str(), BM_KdTrace, m, r)
          ->Unit(benchmark::kMillisecond)->UseRealTime();
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
