#include "accel/embree/embree_accel.h"

#include <embree3/rtcore.h>

#include <atomic>
#include <cstring>
#include <algorithm>
#include <stdexcept>
#include <vector>

namespace raylab {
namespace {

/// Bytes Embree holds, as told by its memory monitor callback.
std::atomic<long long> g_embree_bytes{0};

bool monitor_memory(void*, ssize_t bytes, bool) {
  g_embree_bytes += bytes;
  return true;
}

RTCDevice shared_device() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (!d) throw std::runtime_error("embree: rtcNewDevice failed (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
    rtcSetDeviceMemoryMonitorFunction(d, monitor_memory, nullptr);
    return d;
  }();
  return device;
}

void check(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(e) + ")");
}

RTCBuildQuality to_rtc(EmbreeConfig::Quality q) {
  switch (q) {
    case EmbreeConfig::Quality::low: return RTC_BUILD_QUALITY_LOW;
    case EmbreeConfig::Quality::high: return RTC_BUILD_QUALITY_HIGH;
    default: return RTC_BUILD_QUALITY_MEDIUM;
  }
}

/// Geometry ids within one Embree scene: a flat scene's triangles and spheres, then (in the
/// root of an instanced scene) instance i as kFirstInstanceGeometry + i.
constexpr unsigned kTriangleGeometry = 0;
constexpr unsigned kSphereGeometry = 1;
constexpr unsigned kFirstInstanceGeometry = 2;

RTCScene new_scene(RTCDevice device, const EmbreeConfig& config) {
  RTCScene rtc = rtcNewScene(device);
  rtcSetSceneFlags(rtc, config.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(rtc, to_rtc(config.quality));
  return rtc;
}

/// Attaches a scene's flat geometry to `rtc`: triangles as geomID 0, spheres as geomID 1.
void attach_flat_geometry(RTCDevice device, RTCScene rtc, const Scene& scene, const EmbreeConfig& config) {
  if (scene.mesh.size() > 0) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, to_rtc(config.quality));
    // Embree-allocated buffers are padded for its 16-byte loads past the last vertex.
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), scene.mesh.vertices.size()));
    std::memcpy(v, scene.mesh.vertices.data(), scene.mesh.vertices.size() * sizeof(Vec3f));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(unsigned), scene.mesh.size()));
    std::memcpy(idx, scene.mesh.triangles.data(), scene.mesh.size() * 3 * sizeof(unsigned));
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(rtc, g, kTriangleGeometry);
    rtcReleaseGeometry(g);
  }
  if (!scene.spheres.empty()) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                          4 * sizeof(float), scene.spheres.size()));
    for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
      const Sphere& s = scene.spheres[i];
      v[4 * i + 0] = s.center.x; v[4 * i + 1] = s.center.y; v[4 * i + 2] = s.center.z; v[4 * i + 3] = s.radius;
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(rtc, g, kSphereGeometry);
    rtcReleaseGeometry(g);
  }
}

class EmbreeAccel final : public AggregateBase<EmbreeAccel> {
 public:
  EmbreeAccel(std::shared_ptr<const Scene> scene, const EmbreeConfig& config)
      : scene_(std::move(scene)), config_(config), device_(shared_device()) {
    const long long bytes_before = g_embree_bytes.load();
    if (scene_->instanced()) require_valid_instances(*scene_);
    root_ = new_scene(device_, config);
    attach_flat_geometry(device_, root_, *scene_, config);
    for (const auto& base : scene_->bases) {
      RTCScene inner = new_scene(device_, config);
      inner_.push_back(inner);
      attach_flat_geometry(device_, inner, *base, config);
      rtcCommitScene(inner);
      check(device_, "rtcCommitScene (base)");
    }
    for (std::size_t i = 0; i < scene_->instances.size(); ++i) {
      RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(g, inner_[scene_->instances[i].base]);
      float m[12];
      const auto& xf = scene_->instances[i].transform;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) m[r * 4 + c] = static_cast<float>(xf.m[r][c]);
      rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(root_, g, kFirstInstanceGeometry + static_cast<unsigned>(i));
      rtcReleaseGeometry(g);
    }
    rtcCommitScene(root_);
    check(device_, "rtcCommitScene");
    // Geometry buffers are counted too: they are Embree's copy of the scene.
    bytes_ = static_cast<std::size_t>(std::max(0LL, g_embree_bytes.load() - bytes_before));
    RTCBounds b;
    rtcGetSceneBounds(root_, &b);
    bounds_ = Bounds3f(Vec3f(b.lower_x, b.lower_y, b.lower_z), Vec3f(b.upper_x, b.upper_y, b.upper_z));
  }
  ~EmbreeAccel() override {
    if (root_) rtcReleaseScene(root_);
    for (RTCScene inner : inner_) rtcReleaseScene(inner);
  }
  EmbreeAccel(const EmbreeAccel&) = delete;
  EmbreeAccel& operator=(const EmbreeAccel&) = delete;

  std::string name() const override { return config_.robust ? "embree-robust" : "embree"; }
  /// Bytes Embree allocated while building this scene (its memory monitor callback), which
  /// includes its copy of the vertex and index buffers.
  AccelStats stats() const override { return {bytes_, 0, -1.0}; }
  bool reports_counters() const override { return false; }
  Bounds3f bounds() const override { return bounds_; }
  RTCScene rtc_scene() const { return root_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters&) const {
    if (!in_embree_range(ray)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    set_ray(ray, rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(root_, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    // Embree's float arithmetic overflows on coordinates near FLT_LARGE and can report a hit at
    // t = inf, outside [tmin, tmax] (found by fuzz_build_trace): that is no hit.
    if (!(rh.ray.tfar >= ray.tmin && rh.ray.tfar <= ray.tmax)) return false;
    hit.t = rh.ray.tfar;
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    hit.instance = rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID ? kInvalidId : rh.hit.instID[0] - kFirstInstanceGeometry;
    const Scene& part = hit.instance == kInvalidId ? *scene_ : scene_->base_of(hit.instance);
    hit.prim = rh.hit.primID + (rh.hit.geomID == kSphereGeometry ? static_cast<unsigned>(part.mesh.size()) : 0u);
    ray.tmax = hit.t;
    return true;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters&) const {
    if (!in_embree_range(ray)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r;
    set_ray(ray, r);
    rtcOccluded1(root_, &context, &r);
    return r.tfar == -std::numeric_limits<float>::infinity();
  }

 private:
  /// Embree's RayK::valid() (asserted in Debian's build, undefined behaviour otherwise) wants
  /// every origin and direction component within ±FLT_LARGE = 1.844e18; finite rays beyond that
  /// (found by the adversarial suite) are reported as "no hit" instead of aborting.
  static bool in_embree_range(const Ray& ray) {
    constexpr float kLarge = 1.844e18f;
    auto ok = [](const Vec3f& v) { return std::abs(v.x) <= kLarge && std::abs(v.y) <= kLarge && std::abs(v.z) <= kLarge; };
    return ok(ray.org) && ok(ray.dir);
  }

  static void set_ray(const Ray& ray, RTCRay& r) {
    r.org_x = ray.org.x; r.org_y = ray.org.y; r.org_z = ray.org.z;
    r.dir_x = ray.dir.x; r.dir_y = ray.dir.y; r.dir_z = ray.dir.z;
    r.tnear = ray.tmin;
    r.tfar = ray.tmax;
    r.time = 0.0f;
    r.mask = 0xffffffffu;
    r.id = 0;
    r.flags = 0;
  }

  std::shared_ptr<const Scene> scene_;
  EmbreeConfig config_;
  RTCDevice device_;
  RTCScene root_ = nullptr;
  std::vector<RTCScene> inner_;  ///< one per base
  std::size_t bytes_ = 0;
  Bounds3f bounds_;
};

}  // namespace

std::unique_ptr<Aggregate> make_embree_accel(std::shared_ptr<const Scene> scene, const EmbreeConfig& config) {
  return std::make_unique<EmbreeAccel>(std::move(scene), config);
}

RTCScene embree_rtc_scene(const Aggregate& accel) {
  const auto* e = dynamic_cast<const EmbreeAccel*>(&accel);
  return e ? e->rtc_scene() : nullptr;
}

}  // namespace raylab
