#include "accel/exact/exact_oracle.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "accel/exact/contact_classes.h"
#include "accel/exact/ray_conditioning.h"
#include "geometry/exact_contact.h"
#include "geometry/exact_predicates.h"
#include "geometry/float_mode.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using TriangleList = std::vector<Epick::Triangle_3>;
using AabbPrimitive = CGAL::AABB_triangle_primitive<Epick, TriangleList::const_iterator>;
using AabbTraits = CGAL::AABB_traits<Epick, AabbPrimitive>;

CGAL::Bbox_3 to_bbox(const Bounds3f& b) { return {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z}; }
using AabbTree = CGAL::AABB_tree<AabbTraits>;

class ExactOracle final : public AggregateBase<ExactOracle> {
 public:
  explicit ExactOracle(std::shared_ptr<const Scene> scene) : scene_(std::move(scene)), bounds_(scene_->bounds()) {
    const FloatModeScope ieee(false);
    const TriangleMesh& mesh = scene_->mesh;
    triangles_.reserve(mesh.size());
    ids_.reserve(mesh.size());
    for (std::size_t i = 0; i < mesh.size(); ++i) {
      const Vec3f &a = mesh.vertex(i, 0), &b = mesh.vertex(i, 1), &c = mesh.vertex(i, 2);
      if (is_degenerate_exact(a, b, c)) {  // never hit; CGAL requires non-degenerate triangles
        degenerate_.push_back(static_cast<unsigned>(i));
        continue;
      }
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

 /// The classes of `ray` (contact_classes.h); `adjacency` is of this oracle's scene.
  RayContact classify(const Ray& ray, const MeshAdjacency& adjacency) const {
    RayContact out;
    if (!is_valid(ray)) return out;
    const FloatModeScope ieee(false);
    ExactContactClassifier classifier(ray);
    NoCounters none;
    for_each_candidate(
        ray, [&](unsigned prim) {
          const auto& t = scene_->mesh.triangles[prim];
          const auto& v = scene_->mesh.vertices;
          classifier.offer_triangle(v[t[0]], v[t[1]], v[t[2]]);
        },
        [&](unsigned i) { classifier.offer_sphere(scene_->spheres[i]); }, none);
    out.contact = classifier.contact();
    if (out.contact == Contact::touching || out.contact == Contact::on_surface) {
      out.ill_conditioned = true;
      return out;
    }
    // The segment that matters: up to the first contact, or through the scene when there is none.
    double t_end = out.contact == Contact::none ? double(ray.tmax) : classifier.first_t();
    if (!std::isfinite(t_end)) {
      const Vec3f inv = safe_inverse(ray.dir);
      float t0, t1;
      const Bounds3f box(bounds_.lo - abs(bounds_.lo) * 1e-3f - Vec3f(1e-30f), bounds_.hi + abs(bounds_.hi) * 1e-3f + Vec3f(1e-30f));
      t_end = intersect_box(box, ray, inv, ray.tmin, ray.tmax, t0, t1) ? double(t1) : double(ray.tmin);
    }
    std::vector<std::uint32_t> tris, spheres;
    tube_candidates(ray, t_end, tris, spheres);
    out.ill_conditioned = near_contour_or_surface(*scene_, adjacency, ray, t_end, tris, spheres);
    return out;
  }

  const Scene& scene() const { return *scene_; }

 private:
  template <class Counters>
  void offer_all(const Ray& ray, ExactFirstHit& first, Counters& counters) const {
    for_each_candidate(
        ray, [&](unsigned prim) {
          const auto& t = scene_->mesh.triangles[prim];
          const auto& v = scene_->mesh.vertices;
          first.offer_triangle(prim, v[t[0]], v[t[1]], v[t[2]]);
        },
        [&](unsigned i) { first.offer_sphere(static_cast<unsigned>(scene_->mesh.size()) + i, scene_->spheres[i]); },
        counters);
  }

  /// Calls triangle(prim) for every triangle that may meet the ray (the AABB tree's candidates)
  /// and sphere(index) for every sphere whose box it meets.
  template <class Triangle, class SphereFn, class Counters>
  void for_each_candidate(const Ray& ray, Triangle&& triangle, SphereFn&& sphere, Counters& counters) const {
    const FloatModeScope ieee(false);
    if (!triangles_.empty()) {
      auto offer = [&](unsigned prim) {
        counters.prim_test();
        triangle(prim);
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
      for (unsigned i = 0; i < scene_->spheres.size(); ++i) {
        float t0, t1;
        if (!intersect_box(scene_->spheres[i].bounds(), ray, inv, ray.tmin, ray.tmax, t0, t1)) continue;
        counters.prim_test();
        sphere(i);
      }
    }
  }

  /// The triangles and spheres whose boxes come within twice the largest radius of
  /// ray_conditioning's test of the segment [tmin, t_end] (a superset of those it tests).
  void tube_candidates(const Ray& ray, double t_end, std::vector<std::uint32_t>& tris,
                       std::vector<std::uint32_t>& spheres) const {
    const Vec3d a = Vec3d(ray.org) + Vec3d(ray.dir) * double(ray.tmin), b = Vec3d(ray.org) + Vec3d(ray.dir) * t_end;
    // Everything ray_conditioning measures lies within this of the segment: the displacement
    // radius, the float scale of the triangles near it (64u of their distance) and a margin.
    const double r = 16.0 * ulp_displacement(ray, std::max(std::abs(t_end), double(ray.tmin))) +
                     1e-5 * (length(b - a) + max_component(abs(Vec3d(bounds_.diagonal())))) + 1e-30;
    auto near = [&](const CGAL::Bbox_3& box) {
      // Slab test of the segment against the box widened by r.
      double t0 = 0.0, t1 = 1.0;
      for (int k = 0; k < 3; ++k) {
        const double lo = box.min(k) - r, hi = box.max(k) + r, o = a[k], dd = b[k] - a[k];
        if (dd == 0.0) {
          if (o < lo || o > hi) return false;
          continue;
        }
        double u0 = (lo - o) / dd, u1 = (hi - o) / dd;
        if (u0 > u1) std::swap(u0, u1);
        t0 = std::max(t0, u0);
        t1 = std::min(t1, u1);
        if (t0 > t1) return false;
      }
      return true;
    };
    struct Tube {
      decltype(near)& test;
      const ExactOracle& self;
      std::vector<std::uint32_t>& out;
      bool go_further() const { return true; }
      void intersection(int, const AabbPrimitive& p) {
        if (test(p.datum().bbox())) out.push_back(self.ids_[static_cast<std::size_t>(p.id() - self.triangles_.cbegin())]);
      }
      bool do_intersect(int, const CGAL::AABB_node<AabbTraits>& node) const {
        return test(node.bbox());
      }
    } traits{near, *this, tris};
    if (!triangles_.empty()) tree_.traversal(0, traits);
    // Zero-area triangles are never hit, but a float kernel sees a sliver of either orientation.
    for (const std::uint32_t prim : degenerate_)
      if (near(to_bbox(scene_->mesh.triangle_bounds(prim)))) tris.push_back(prim);
    for (unsigned i = 0; i < scene_->spheres.size(); ++i)
      if (near(to_bbox(scene_->spheres[i].bounds()))) spheres.push_back(static_cast<std::uint32_t>(scene_->mesh.size() + i));
  }

  static std::vector<TriangleList::const_iterator>& candidates_buffer() {
    thread_local std::vector<TriangleList::const_iterator> buffer;
    return buffer;
  }

  std::shared_ptr<const Scene> scene_;
  Bounds3f bounds_;
  TriangleList triangles_;
  std::vector<unsigned> ids_;
  std::vector<std::uint32_t> degenerate_;  ///< zero-area triangles: never hit, but seen by float kernels
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

void require_spheres_stay_spheres(const Scene& scene) {
  for (std::size_t i = 0; i < scene.instances.size(); ++i)
    if (!scene.base_of(i).spheres.empty() && !is_similarity(scene.instances[i].transform))
      throw InputError("scene '" + scene.spec + "': instance " + std::to_string(i) +
                       " scales spheres non-uniformly, which the flat copy cannot hold");
}

std::shared_ptr<const Scene> flatten_instances(const Scene& scene) {
  if (!scene.instanced()) throw std::logic_error("flatten_instances: scene is not instanced");
  require_valid_instances(scene);
  if (scene.total_primitive_count() > kExactOracleMaxPrimitives)
    throw InputError("scene '" + scene.spec + "': the exact oracle flattens instances and accepts at most " +
                     std::to_string(static_cast<long long>(kExactOracleMaxPrimitives)) + " primitives, this has " +
                     std::to_string(static_cast<long long>(scene.total_primitive_count())));
  require_spheres_stay_spheres(scene);
  auto flat = std::make_shared<Scene>();
  flat->spec = scene.spec + " (flattened)";
  std::vector<Sphere> spheres;
  append_transformed(*flat, spheres, scene, AffineTransform::identity());
  for (const auto& inst : scene.instances) append_transformed(*flat, spheres, *scene.bases[inst.base], inst.transform);
  flat->spheres = std::move(spheres);
  return flat;
}

unsigned flat_primitive_id(const Scene& scene, const Hit& hit) {
  // flatten_instances' order: triangles of the flat geometry, then of instance 0, 1, ...; then
  // the spheres in the same order.
  const auto part = [&](std::size_t k) -> const Scene& { return k == 0 ? scene : scene.base_of(k - 1); };
  const std::size_t parts = scene.instances.size() + 1;
  const std::size_t own = hit.instance == kInvalidId ? 0 : std::size_t(hit.instance) + 1;
  const Scene& mine = part(own);
  std::size_t id = 0;
  if (hit.prim < mine.mesh.size()) {
    for (std::size_t k = 0; k < own; ++k) id += part(k).mesh.size();
    return static_cast<unsigned>(id + hit.prim);
  }
  for (std::size_t k = 0; k < parts; ++k) id += part(k).mesh.size();
  for (std::size_t k = 0; k < own; ++k) id += part(k).spheres.size();
  return static_cast<unsigned>(id + (hit.prim - mine.mesh.size()));
}

namespace {

/// An accelerator built on flatten_instances(scene), reporting hits as (instance, prim) like
/// instanced accelerators: part 0 of the copy is the flat geometry, part k + 1 instance k.
class FlattenedInstances final : public AggregateBase<FlattenedInstances> {
 public:
  FlattenedInstances(const Scene& scene, std::unique_ptr<Aggregate> flat) : inner_(std::move(flat)) {
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
  std::string name() const override { return inner_->name(); }
  AccelStats stats() const override { return inner_->stats(); }
  Bounds3f bounds() const override { return inner_->bounds(); }
  bool reports_counters() const override { return inner_->reports_counters(); }
  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    bool found;
    if constexpr (Counters::enabled) found = inner_->intersect(ray, hit, counters);
    else found = inner_->intersect(ray, hit);
    if (!found) return false;
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
    if constexpr (Counters::enabled) return inner_->occluded(ray, counters);
    else return inner_->occluded(ray);
  }

 private:
  std::unique_ptr<Aggregate> inner_;
  /// Part p's triangles are the flat ids triangle_start_[p] .. triangle_start_[p+1]-1; its spheres
  /// the same in sphere_start_, counted after all triangles.
  std::vector<std::size_t> triangle_start_, sphere_start_;
  std::vector<unsigned> base_triangles_;  ///< triangles of each part's own scene: its spheres' first id
};

}  // namespace

std::unique_ptr<Aggregate> make_over_flattened_instances(
    const Scene& scene, const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make) {
  return std::make_unique<FlattenedInstances>(scene, make(flatten_instances(scene)));
}

std::vector<RayContact> classify_contacts(const std::shared_ptr<const Scene>& scene, const std::vector<Ray>& rays,
                                          int threads) {
  const std::shared_ptr<const Scene> flat = scene->instanced() ? flatten_instances(*scene) : scene;
  const ExactOracle oracle(flat);
  const MeshAdjacency adjacency(flat->mesh);
  std::vector<RayContact> out(rays.size());
  tbb::task_arena arena(threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = oracle.classify(rays[i], adjacency);
    });
  });
  return out;
}

std::unique_ptr<Aggregate> make_exact_oracle(std::shared_ptr<const Scene> scene) {
  if (scene->instanced())
    return make_over_flattened_instances(
        *scene, [](std::shared_ptr<const Scene> flat) { return std::make_unique<ExactOracle>(std::move(flat)); });
  return std::make_unique<ExactOracle>(std::move(scene));
}

}  // namespace raylab
