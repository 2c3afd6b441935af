// Google Benchmark figures of the uniform grid (and the nested grid) against Embree, single
// thread, on the same rays in the same process: grass with a million blades (3 M triangles), the
// sphereflake and the teapot-in-a-stadium. Counters: rays/s, and `vs_embree`, our throughput over
// Embree's (1.0 = as fast; on the same rays, Embree's pass alternating with ours, best pass of
// each over the same number of passes). BM_GridBuild reports build
// throughput in primitives per second (items_per_second) for the default placement (clipped),
// place=bbox and the nested grid.
//   build/experiments/bench_grid --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "bench_env.h"
#include "scene/scene_spec.h"

using namespace raylab;

namespace {

const std::vector<std::string> kScenes = {"grass:blades=1000000", "sphereflake:depth=4", "stadium"};

struct Fixture {
  std::shared_ptr<const Scene> scene;
  std::vector<Ray> rays;
  std::unique_ptr<Aggregate> embree;
};

Fixture& fixture(const std::string& spec) {
  static std::map<std::string, Fixture> cache;
  Fixture& f = cache[spec];
  if (!f.scene) {
    f.scene = make_scene(spec);
    f.rays = make_ray_set("primary:65536", f.scene);
    f.embree = make_accelerator("embree", f.scene);
  }
  return f;
}

void BM_Trace(benchmark::State& state, const std::string& scene_spec, const std::string& accel_spec) {
  Fixture& f = fixture(scene_spec);
  const auto accel = make_accelerator(accel_spec, f.scene);
  double best = 1e300, embree_best = 1e300;
  for (auto _ : state) {
    const TraceResult r = trace_rays(*accel, f.rays, TraceOptions{1, false, false});
    best = std::min(best, r.seconds);
    benchmark::DoNotOptimize(r.hit_count);
    embree_best = std::min(embree_best, trace_rays(*f.embree, f.rays, TraceOptions{1, false, false}).seconds);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * f.rays.size()));
  state.counters["primitives"] = static_cast<double>(f.scene->primitive_count());
  state.counters["ns_per_ray"] = best / static_cast<double>(f.rays.size()) * 1e9;
  state.counters["embree_ns_per_ray"] = embree_best / static_cast<double>(f.rays.size()) * 1e9;
  state.counters["vs_embree"] = embree_best / best;  // throughput ratio: ours / Embree's
}

void BM_GridBuild(benchmark::State& state, const std::string& scene_spec, const std::string& accel_spec) {
  Fixture& f = fixture(scene_spec);
  for (auto _ : state) {
    auto accel = make_accelerator(accel_spec, f.scene);
    benchmark::DoNotOptimize(accel.get());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * f.scene->primitive_count()));
}

const bool registered = [] {
  for (const auto& s : kScenes) {
    for (const std::string a : {"grid", "grid:place=bbox", "grid:d=1", "nested-grid", "embree"})
      benchmark::RegisterBenchmark(("BM_Trace/" + s + "/" + a).c_str(), BM_Trace, s, a)->Unit(benchmark::kMillisecond)->UseRealTime();
    for (const std::string a : {"grid", "grid:d=1", "grid:place=bbox", "grid:place=bbox,d=1", "nested-grid"})
      benchmark::RegisterBenchmark(("BM_GridBuild/" + s + "/" + a).c_str(), BM_GridBuild, s, a)->Unit(benchmark::kMillisecond)->UseRealTime();
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
