#pragma once
/// `embree` and `embree-robust`: an Embree 3 scene, the lab's speed baseline.
///
/// Used as Embree's manual recommends: FTZ/DAZ set on every tracing thread (raylab's tracer does
/// this for every accelerator, see geometry/float_mode.h), one RTCDevice per process, triangle
/// geometry in Embree-owned (padded) buffers, spheres as RTC_GEOMETRY_TYPE_SPHERE_POINT,
/// instances as RTC_GEOMETRY_TYPE_INSTANCE over one committed scene per base (the flat geometry
/// beside them in the root scene), rtcIntersect1 /
/// rtcOccluded1 with an initialised RTCIntersectContext, and the build (rtcCommitScene) timed
/// apart from tracing: construction of this object is the build.
///
/// Embree reports no traversal counters; raylab's counters stay 0 for it.
#include <embree3/rtcore.h>

#include <memory>
#include <string>

#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

struct EmbreeConfig {
  enum class Quality { low, medium, high };
  Quality quality = Quality::medium;  ///< rtcSetSceneBuildQuality
  bool robust = false;                ///< RTC_SCENE_FLAG_ROBUST (watertight along edges)
};

std::unique_ptr<Aggregate> make_embree_accel(std::shared_ptr<const Scene> scene, const EmbreeConfig& config);

/// The committed root scene of an `embree` / `embree-robust` accelerator, for callers that trace
/// it with rtcIntersect1 / rtcOccluded1 themselves (Embree without raylab's call path); null for
/// any other aggregate. Valid while `accel` lives.
RTCScene embree_rtc_scene(const Aggregate& accel);

}  // namespace raylab
