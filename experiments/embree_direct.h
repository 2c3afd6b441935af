#pragma once
/// Embree called directly, without raylab's call path: an Embree accelerator's RTCScene traced
/// by rtcIntersect1 / rtcOccluded1 in a tight loop, beside a structure's own loop
/// (Aggregate::intersect / occluded in a plain loop). Shared by bench_bvh and exp_bvh; the
/// caller sets FTZ/DAZ (FloatModeScope) as raylab's tracer does.
#include <embree3/rtcore.h>

#include <limits>
#include <stdexcept>
#include <vector>

#include "accel/embree/embree_accel.h"
#include "scene/primitive.h"

namespace raylab::experiments {

/// An `embree` / `embree-robust` accelerator's own RTCScene, traced by the caller (no raylab wrapper).
class DirectEmbree {
 public:
  /// `embree` must be made by make_accelerator("embree...") and outlive this object.
  explicit DirectEmbree(const Aggregate& embree) : scene_(embree_rtc_scene(embree)) {
    if (!scene_) throw std::invalid_argument("DirectEmbree: " + embree.name() + " is not an Embree accelerator");
  }

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
  RTCScene scene_;
};

/// The rays through `accel`'s own entry points in a plain loop; returns the rays that hit.
inline std::size_t own_loop(const Aggregate& accel, const std::vector<Ray>& rays, bool any_hit) {
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

}  // namespace raylab::experiments
