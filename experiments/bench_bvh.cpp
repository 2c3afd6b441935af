// Google Benchmark figures of the BVH against Embree, single thread, on the rays of exp_bvh:
//  - BM_BvhTrace/<scene>/<rays>/<bvh spec>: the BVH traced through raylab's tracer (trace_rays,
//    as exp_bvh does) against its like-for-like Embree (`embree-robust` for the robust default,
//    `embree` for robust=off), passes alternating, best pass of each kept. Counters:
//      vs_embree         our throughput over the like-for-like Embree's, both through raylab
//      vs_embree_fast    our throughput over `embree` (Embree's fast, non-watertight mode)
//      vs_embree_direct  our own loop (the rays through Aggregate::intersect/occluded in a plain
//                        loop, no TBB, no result vectors) over Embree called directly on the same
//                        rays (rtcIntersect1 / rtcOccluded1 in a tight loop on an RTCScene this
//                        benchmark builds itself, same quality and robust flag as the like-for-like
//                        Embree): the comparison without raylab's call path on either side
//      nodes, leaves, tests per ray (counted pass)
//   build/experiments/bench_bvh --benchmark_min_time=0.1
//   build/experiments/bench_bvh --benchmark_filter='armadillo/diffuse'
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <time.h>

#include <cstring>
#include <limits>
#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "geometry/float_mode.h"
#include "scene/scene_spec.h"

using namespace raylab;

namespace {

const std::vector<std::string> kScenes = {"cgal:armadillo", "cgal:elephant", "stadium:object=(sphere:n=5000),ratio=1000",
                                          "walls:n=400,angle=30", "grass:blades=100000",
                                          "room:of=cgal:armadillo"};
const std::vector<std::string> kRayKinds = {"primary:65536", "diffuse:65536", "shadow:65536"};
const std::vector<std::string> kBvhSpecs = {"bvh", "bvh:robust=off"};

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

/// Thread CPU seconds of `f()` (single thread: the time a shared machine keeps it waiting is out).
template <class F>
double cpu_seconds_of(F&& f) {
  const double start = thread_cpu_now();
  f();
  return thread_cpu_now() - start;
}

/// An Embree scene over a scene's triangles, traced by the benchmark itself (no raylab wrapper).
class DirectEmbree {
 public:
  DirectEmbree(const Scene& scene, bool robust) {
    device_ = rtcNewDevice(nullptr);
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    if (robust) rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_MEDIUM);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), scene.mesh.vertices.size()));
    std::memcpy(v, scene.mesh.vertices.data(), scene.mesh.vertices.size() * sizeof(Vec3f));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(unsigned), scene.mesh.size()));
    std::memcpy(idx, scene.mesh.triangles.data(), scene.mesh.size() * 3 * sizeof(unsigned));
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene_);
  }
  ~DirectEmbree() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  DirectEmbree(const DirectEmbree&) = delete;
  DirectEmbree& operator=(const DirectEmbree&) = delete;

  /// Rays that hit (closest hit) or are occluded (any hit).
  std::size_t trace(const std::vector<Ray>& rays, bool any_hit) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    std::size_t hits = 0;
    for (const Ray& ray : rays) {
      RTCRayHit rh;
      rh.ray.org_x = ray.org.x, rh.ray.org_y = ray.org.y, rh.ray.org_z = ray.org.z;
      rh.ray.dir_x = ray.dir.x, rh.ray.dir_y = ray.dir.y, rh.ray.dir_z = ray.dir.z;
      rh.ray.tnear = ray.tmin, rh.ray.tfar = ray.tmax, rh.ray.time = 0.0f;
      rh.ray.mask = 0xffffffffu, rh.ray.id = 0, rh.ray.flags = 0;
      if (any_hit) {
        rtcOccluded1(scene_, &context, &rh.ray);
        hits += rh.ray.tfar == -std::numeric_limits<float>::infinity();
      } else {
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &context, &rh);
        hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      }
    }
    return hits;
  }

 private:
  RTCDevice device_;
  RTCScene scene_;
};

/// The rays through `accel`'s own entry points in a plain loop; returns the rays that hit.
std::size_t own_loop(const Aggregate& accel, const std::vector<Ray>& rays, bool any_hit) {
  std::size_t hits = 0;
  for (const Ray& r : rays) {
    if (any_hit) {
      hits += accel.occluded(r);
    } else {
      Ray ray = r;
      Hit hit;
      hits += accel.intersect(ray, hit);
    }
  }
  return hits;
}

void BM_BvhTrace(benchmark::State& state, const std::string& scene_spec, const std::string& ray_spec,
                 const std::string& accel_spec) {
  const auto scene = scene_for(scene_spec);
  const auto& rays = rays_for(scene_spec, ray_spec);
  const bool any = is_any_hit_ray_spec(ray_spec);
  const bool robust = accel_spec.find("robust=off") == std::string::npos;
  const auto accel = make_accelerator(accel_spec, scene);
  const auto like = make_accelerator(robust ? "embree-robust" : "embree", scene);
  const auto fast = make_accelerator("embree", scene);
  const bool direct = scene->spheres.empty() && !scene->instanced();
  std::unique_ptr<DirectEmbree> embree_direct;
  if (direct) embree_direct = std::make_unique<DirectEmbree>(*scene, robust);
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
    if (direct) direct_s = std::min(direct_s, cpu_seconds_of([&] { direct_hits = embree_direct->trace(rays, any); }));
  }
  benchmark::DoNotOptimize(own_hits + direct_hits);
  const double n = static_cast<double>(rays.size());
  const TraceResult counted = trace_rays(*accel, rays, TraceOptions{1, true, any});
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * rays.size()));
  state.counters["ns_per_ray"] = ours / n * 1e9;
  state.counters["vs_embree"] = like_s / ours;
  state.counters["vs_embree_fast"] = fast_s / ours;
  if (direct) state.counters["vs_embree_direct"] = direct_s / own;
  state.counters["nodes"] = static_cast<double>(counted.counters.nodes) / n;
  state.counters["leaves"] = static_cast<double>(counted.counters.leaves) / n;
  state.counters["tests"] = static_cast<double>(counted.counters.prim_tests) / n;
}

const bool registered = [] {
  for (const auto& s : kScenes)
    for (const auto& r : kRayKinds)
      for (const auto& a : kBvhSpecs)
        benchmark::RegisterBenchmark(("BM_BvhTrace/" + s + "/" + r + "/" + a).c_str(), BM_BvhTrace, s, r, a)
            ->Unit(benchmark::kMillisecond)
            ->Iterations(5);
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
