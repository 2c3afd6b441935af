#pragma once
/// pbrt's TransformedPrimitive: any primitive (an accelerator included) placed in the world by an
/// affine object-to-world transform. Rays are taken to object space with the inverse; the
/// direction is not renormalised, so t is the same in both spaces. Hits are tagged with the
/// instance index.
#include <memory>

#include "geometry/transform.h"
#include "scene/primitive.h"

namespace raylab {

class TransformedPrimitive final : public Primitive {
 public:
  /// `object_to_world` must be invertible.
  TransformedPrimitive(std::shared_ptr<const Primitive> inner, const AffineTransform& object_to_world, unsigned instance)
      : inner_(std::move(inner)),
        world_to_object_(object_to_world.inverse()),
        world_bounds_(object_to_world.apply(inner_->bounds())),
        instance_(instance) {}

  Bounds3f bounds() const override { return world_bounds_; }

  bool intersect(Ray& ray, Hit& hit) const override { return intersect_counted(ray, hit, nullptr); }
  bool intersect(Ray& ray, Hit& hit, RayCounters& counters) const override {
    return intersect_counted(ray, hit, &counters);
  }
  bool occluded(const Ray& ray) const override { return inner_->occluded(world_to_object_.apply(ray)); }
  bool occluded(const Ray& ray, RayCounters& counters) const override {
    return inner_->occluded(world_to_object_.apply(ray), counters);
  }

  const Primitive& inner() const { return *inner_; }
  unsigned instance() const { return instance_; }

 private:
  bool intersect_counted(Ray& ray, Hit& hit, RayCounters* counters) const {
    Ray local = world_to_object_.apply(ray);
    const bool found = counters ? inner_->intersect(local, hit, *counters) : inner_->intersect(local, hit);
    if (!found) return false;
    ray.tmax = local.tmax;
    hit.instance = instance_;
    return true;
  }

  std::shared_ptr<const Primitive> inner_;
  AffineTransform world_to_object_;
  Bounds3f world_bounds_;
  unsigned instance_;
};

}  // namespace raylab
