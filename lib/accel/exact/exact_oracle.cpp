#include "accel/exact/exact_oracle.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <vector>

#include "geometry/exact_predicates.h"
#include "geometry/float_mode.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using TriangleList = std::vector<Epick::Triangle_3>;
using AabbPrimitive = CGAL::AABB_triangle_primitive<Epick, TriangleList::const_iterator>;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<Epick, AabbPrimitive>>;

class ExactOracle final : public AggregateBase<ExactOracle> {
 public:
  explicit ExactOracle(std::shared_ptr<const Scene> scene) : scene_(std::move(scene)), bounds_(scene_->bounds()) {
    const FloatModeScope ieee(false);
    const TriangleMesh& mesh = scene_->mesh;
    triangles_.reserve(mesh.size());
    ids_.reserve(mesh.size());
    for (std::size_t i = 0; i < mesh.size(); ++i) {
      const Vec3f &a = mesh.vertex(i, 0), &b = mesh.vertex(i, 1), &c = mesh.vertex(i, 2);
      if (is_degenerate_exact(a, b, c)) continue;  // never hit; CGAL requires non-degenerate triangles
      triangles_.emplace_back(Epick::Point_3(a.x, a.y, a.z), Epick::Point_3(b.x, b.y, b.z),
                              Epick::Point_3(c.x, c.y, c.z));
      ids_.push_back(static_cast<unsigned>(i));
    }
    if (!triangles_.empty()) {
      tree_.insert(triangles_.cbegin(), triangles_.cend());
      tree_.build();
    }
  }

  std::string name() const override { return "exact"; }
  AccelStats stats() const override {
    return {triangles_.size() * (sizeof(Epick::Triangle_3) + sizeof(unsigned) + 2 * sizeof(void*)), tree_.size(), -1.0};
  }
  Bounds3f bounds() const override { return bounds_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    ExactFirstHit first(ray);
    offer_all(ray, first, counters);
    if (!first.has_hit()) return false;
    hit = first.hit();
    ray.tmax = hit.t;
    return true;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    ExactFirstHit first(ray);
    offer_all(ray, first, counters);
    return first.has_hit();
  }

 private:
  template <class Counters>
  void offer_all(const Ray& ray, ExactFirstHit& first, Counters& counters) const {
    const FloatModeScope ieee(false);
    if (!triangles_.empty()) {
      auto offer = [&](unsigned prim) {
        counters.prim_test();
        const auto& t = scene_->mesh.triangles[prim];
        const auto& v = scene_->mesh.vertices;
        first.offer_triangle(prim, v[t[0]], v[t[1]], v[t[2]]);
      };
      Vec3d second;
      if (exact_second_point(ray, second)) {
        candidates_buffer().clear();
        const Epick::Ray_3 query(Epick::Point_3(ray.org.x, ray.org.y, ray.org.z),
                                 Epick::Point_3(second.x, second.y, second.z));
        tree_.all_intersected_primitives(query, std::back_inserter(candidates_buffer()));
        for (const auto it : candidates_buffer()) offer(ids_[static_cast<std::size_t>(it - triangles_.cbegin())]);
      } else if (is_valid(ray)) {
        for (const unsigned prim : ids_) offer(prim);  // no exact Epick ray: every triangle is a candidate
      }
    }
    if (!scene_->spheres.empty()) {
      const Vec3f inv = safe_inverse(ray.dir);
      const auto base = static_cast<unsigned>(scene_->mesh.size());
      for (unsigned i = 0; i < scene_->spheres.size(); ++i) {
        float t0, t1;
        if (!intersect_box(scene_->spheres[i].bounds(), ray, inv, ray.tmin, ray.tmax, t0, t1)) continue;
        counters.prim_test();
        first.offer_sphere(base + i, scene_->spheres[i]);
      }
    }
  }

  static std::vector<TriangleList::const_iterator>& candidates_buffer() {
    thread_local std::vector<TriangleList::const_iterator> buffer;
    return buffer;
  }

  std::shared_ptr<const Scene> scene_;
  Bounds3f bounds_;
  TriangleList triangles_;
  std::vector<unsigned> ids_;
  AabbTree tree_;
};

}  // namespace

std::shared_ptr<const Scene> flatten_instances(const Scene& scene) {
  if (!scene.instanced()) throw std::logic_error("flatten_instances: scene is not instanced");
  if (scene.total_primitive_count() > kExactOracleMaxPrimitives)
    throw InputError("scene '" + scene.spec + "': the exact oracle flattens instances and accepts at most " +
                     std::to_string(static_cast<long long>(kExactOracleMaxPrimitives)) + " primitives, this has " +
                     std::to_string(static_cast<long long>(scene.total_primitive_count())));
  const Scene& base = *scene.base;
  if (base.instanced()) throw InputError("scene '" + scene.spec + "': nested instancing is not supported by the oracle");
  auto flat = std::make_shared<Scene>();
  flat->spec = scene.spec + " (flattened)";
  // Primitive id = instance * P + prim, for triangles then spheres of each instance in turn. To
  // keep ids in that order the flat scene stores the instances' spheres as triangles' siblings
  // only when the base has no spheres; mixed bases are rejected.
  if (!base.spheres.empty() && base.mesh.size() > 0)
    throw InputError("scene '" + scene.spec + "': the oracle cannot flatten instances of mixed triangle/sphere scenes");
  for (const auto& xf : scene.instances) {
    const auto offset = static_cast<std::uint32_t>(flat->mesh.vertices.size());
    for (const auto& v : base.mesh.vertices) flat->mesh.vertices.push_back(xf.apply_point(v));
    for (auto t : base.mesh.triangles) flat->mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    for (const auto& s : base.spheres) {
      // Uniform scale assumed for spheres: radius scales with the cube root of |det|.
      const double scale = std::cbrt(std::abs(xf.determinant()));
      flat->spheres.push_back({xf.apply_point(s.center), static_cast<float>(s.radius * scale)});
    }
  }
  return flat;
}

/// Wraps the flat oracle so that hits report (instance, prim) like instanced accelerators.
class InstancedExactOracle final : public AggregateBase<InstancedExactOracle> {
 public:
  InstancedExactOracle(std::shared_ptr<const Scene> flat, unsigned per_instance)
      : inner_(std::move(flat)), per_instance_(per_instance) {}
  std::string name() const override { return "exact"; }
  AccelStats stats() const override { return inner_.stats(); }
  Bounds3f bounds() const override { return inner_.bounds(); }
  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    if (!inner_.intersect_impl(ray, hit, counters)) return false;
    hit.instance = hit.prim / per_instance_;
    hit.prim %= per_instance_;
    return true;
  }
  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    return inner_.occluded_impl(ray, counters);
  }

 private:
  ExactOracle inner_;
  unsigned per_instance_;
};

std::unique_ptr<Aggregate> make_exact_oracle(std::shared_ptr<const Scene> scene) {
  if (scene->instanced()) {
    const auto per_instance = static_cast<unsigned>(scene->base->primitive_count());
    return std::make_unique<InstancedExactOracle>(flatten_instances(*scene), per_instance);
  }
  return std::make_unique<ExactOracle>(std::move(scene));
}

}  // namespace raylab
