#pragma once
/// `brute`: every ray against every primitive, the lecture's |Image| x |Objects| baseline.
#include <memory>
#include <vector>

#include "scene/primitive.h"
#include "scene/scene.h"
#include "scene/scene_primitives.h"

namespace raylab {

/// Brute force over a scene's own geometry with ray kernel `Kernel`.
template <class Kernel>
class BruteForce final : public AggregateBase<BruteForce<Kernel>> {
 public:
  /// `scene` must not be instanced (see BruteForceOverPrimitives).
  explicit BruteForce(std::shared_ptr<const Scene> scene) : scene_(std::move(scene)), bounds_(scene_->bounds()) {}

  std::string name() const override { return "brute"; }
  AccelStats stats() const override { return {}; }
  Bounds3f bounds() const override { return bounds_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    auto ctx = Kernel::prepare(ray);
    bool found = false;
    const auto n = static_cast<unsigned>(scene_->primitive_count());
    counters.leaf();
    for (unsigned prim = 0; prim < n; ++prim) found |= intersect_scene_primitive<Kernel>(*scene_, prim, ctx, hit, counters);
    if (found) ray.tmax = hit.t;
    return found;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    auto ctx = Kernel::prepare(any_hit_ray<Kernel>(ray));
    Hit hit;
    const auto n = static_cast<unsigned>(scene_->primitive_count());
    counters.leaf();
    for (unsigned prim = 0; prim < n; ++prim)
      if (intersect_scene_primitive<Kernel>(*scene_, prim, ctx, hit, counters)) return true;
    return false;
  }

 private:
  std::shared_ptr<const Scene> scene_;
  Bounds3f bounds_;
};

/// Brute force over a list of primitives (instances, nested accelerators): the generic
/// aggregate, one virtual call per primitive.
class BruteForceOverPrimitives final : public AggregateBase<BruteForceOverPrimitives> {
 public:
  explicit BruteForceOverPrimitives(std::vector<std::shared_ptr<const Primitive>> prims) : prims_(std::move(prims)) {
    for (const auto& p : prims_) bounds_.extend(p->bounds());
  }

  std::string name() const override { return "brute"; }
  AccelStats stats() const override { return {prims_.size() * sizeof(void*), 0, -1.0}; }
  Bounds3f bounds() const override { return bounds_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    bool found = false;
    counters.leaf();
    for (const auto& p : prims_) {
      counters.prim_test();
      if constexpr (Counters::enabled) found |= p->intersect(ray, hit, counters);
      else found |= p->intersect(ray, hit);
    }
    return found;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    counters.leaf();
    for (const auto& p : prims_) {
      counters.prim_test();
      if constexpr (Counters::enabled) {
        if (p->occluded(ray, counters)) return true;
      } else if (p->occluded(ray)) {
        return true;
      }
    }
    return false;
  }

 private:
  std::vector<std::shared_ptr<const Primitive>> prims_;
  Bounds3f bounds_;
};

}  // namespace raylab
