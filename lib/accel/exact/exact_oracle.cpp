#include "accel/exact/exact_oracle.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
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

namespace {

/// Whether the linear part of `xf` is a rotation times a uniform scale (up to rounding), which
/// maps a sphere onto a sphere.
bool is_similarity(const AffineTransform& xf) {
  const Vec3d c[3] = {xf.apply_vector(Vec3d(1, 0, 0)), xf.apply_vector(Vec3d(0, 1, 0)), xf.apply_vector(Vec3d(0, 0, 1))};
  const double n = dot(c[0], c[0]);
  const double tol = 1e-9 * n;
  return std::abs(dot(c[1], c[1]) - n) <= tol && std::abs(dot(c[2], c[2]) - n) <= tol && std::abs(dot(c[0], c[1])) <= tol &&
         std::abs(dot(c[0], c[2])) <= tol && std::abs(dot(c[1], c[2])) <= tol;
}

/// Appends `part`'s geometry under `xf` to `flat` (vertices transformed in double, rounded to float).
void append_transformed(Scene& flat, std::vector<Sphere>& spheres, const Scene& part, const AffineTransform& xf) {
  const auto offset = static_cast<std::uint32_t>(flat.mesh.vertices.size());
  for (const auto& v : part.mesh.vertices) flat.mesh.vertices.push_back(xf.apply_point(v));
  for (auto t : part.mesh.triangles) flat.mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const double scale = std::cbrt(std::abs(xf.determinant()));
  for (const auto& s : part.spheres) spheres.push_back({xf.apply_point(s.center), static_cast<float>(s.radius * scale)});
}

}  // namespace

std::shared_ptr<const Scene> flatten_instances(const Scene& scene) {
  if (!scene.instanced()) throw std::logic_error("flatten_instances: scene is not instanced");
  require_valid_instances(scene);
  if (scene.total_primitive_count() > kExactOracleMaxPrimitives)
    throw InputError("scene '" + scene.spec + "': the exact oracle flattens instances and accepts at most " +
                     std::to_string(static_cast<long long>(kExactOracleMaxPrimitives)) + " primitives, this has " +
                     std::to_string(static_cast<long long>(scene.total_primitive_count())));
  for (std::size_t i = 0; i < scene.instances.size(); ++i)
    if (!scene.base_of(i).spheres.empty() && !is_similarity(scene.instances[i].transform))
      throw InputError("scene '" + scene.spec + "': instance " + std::to_string(i) +
                       " scales spheres non-uniformly, which the oracle's flat copy cannot hold");
  auto flat = std::make_shared<Scene>();
  flat->spec = scene.spec + " (flattened)";
  std::vector<Sphere> spheres;
  append_transformed(*flat, spheres, scene, AffineTransform::identity());
  for (const auto& inst : scene.instances) append_transformed(*flat, spheres, *scene.bases[inst.base], inst.transform);
  flat->spheres = std::move(spheres);
  return flat;
}

/// Wraps the oracle on the flat copy so that hits name (instance, prim) like instanced
/// accelerators: part 0 of the copy is the flat geometry, part k + 1 instance k.
class InstancedExactOracle final : public AggregateBase<InstancedExactOracle> {
 public:
  explicit InstancedExactOracle(const Scene& scene) : inner_(flatten_instances(scene)) {
    triangle_start_.push_back(0);
    sphere_start_.push_back(0);
    base_triangles_.push_back(static_cast<unsigned>(scene.mesh.size()));
    auto add_part = [&](const Scene& part) {
      triangle_start_.push_back(triangle_start_.back() + part.mesh.size());
      sphere_start_.push_back(sphere_start_.back() + part.spheres.size());
    };
    add_part(scene);
    for (const auto& inst : scene.instances) {
      add_part(*scene.bases[inst.base]);
      base_triangles_.push_back(static_cast<unsigned>(scene.bases[inst.base]->mesh.size()));
    }
  }
  std::string name() const override { return "exact"; }
  AccelStats stats() const override { return inner_.stats(); }
  Bounds3f bounds() const override { return inner_.bounds(); }
  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    if (!inner_.intersect_impl(ray, hit, counters)) return false;
    const std::size_t triangles = triangle_start_.back();
    const bool sphere = hit.prim >= triangles;
    const std::vector<std::size_t>& start = sphere ? sphere_start_ : triangle_start_;
    const std::size_t id = sphere ? hit.prim - triangles : hit.prim;
    // The last part whose range starts at or before id (parts without primitives are skipped).
    const auto part = static_cast<std::size_t>(std::upper_bound(start.begin(), start.end(), id) - start.begin()) - 1;
    hit.instance = part == 0 ? kInvalidId : static_cast<unsigned>(part - 1);
    hit.prim = static_cast<unsigned>(id - start[part]) + (sphere ? base_triangles_[part] : 0u);
    return true;
  }
  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    return inner_.occluded_impl(ray, counters);
  }

 private:
  ExactOracle inner_;
  /// Part p's triangles are the flat ids triangle_start_[p] .. triangle_start_[p+1]-1; its spheres
  /// the same in sphere_start_, counted after all triangles.
  std::vector<std::size_t> triangle_start_, sphere_start_;
  std::vector<unsigned> base_triangles_;  ///< triangles of each part's own scene: its spheres' first id
};

std::unique_ptr<Aggregate> make_exact_oracle(std::shared_ptr<const Scene> scene) {
  if (scene->instanced()) return std::make_unique<InstancedExactOracle>(*scene);
  return std::make_unique<ExactOracle>(std::move(scene));
}

}  // namespace raylab
