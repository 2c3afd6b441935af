#include "accel/common/ray_sets.h"

#include "accel/common/accel_factory.h"
#include "geometry/spec_string.h"
#include "rays/ray_generators.h"

namespace raylab {
namespace {

Hit first_hit_of(const Primitive& tracer, const Ray& r) {
  Ray ray = r;
  Hit hit;
  tracer.intersect(ray, hit);
  return hit;
}

}  // namespace

std::vector<Ray> make_ray_set(const std::string& spec, const std::shared_ptr<const Scene>& scene) {
  std::shared_ptr<Aggregate> tracer;  // built on first use: primary/lines/edges need none
  const FirstHitFunction first_hit = [&](const Ray& r) {
    if (!tracer) tracer = make_accelerator("embree-robust", scene);
    return first_hit_of(*tracer, r);
  };
  return generate_rays(spec, *scene, first_hit);
}

std::vector<Ray> make_ray_set(const std::string& spec, const std::shared_ptr<const Scene>& scene,
                              const Primitive& first_hits) {
  return generate_rays(spec, *scene, [&](const Ray& r) { return first_hit_of(first_hits, r); });
}

bool is_any_hit_ray_spec(const std::string& spec) {
  const std::string name = parse_spec(spec).name;
  return name == "shadow" || name == "ao";
}

bool is_feature_ray_spec(const std::string& spec) {
  const std::string name = parse_spec(spec).name;
  return name == "edges" || name == "vertices" || name == "touching" || name == "grazing";
}

}  // namespace raylab
