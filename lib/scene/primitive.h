#pragma once
/// The lecture's pbrt design (pbrt-v3 §4.1): a primitive has bounds, a closest-hit `intersect`
/// and an any-hit `occluded`; an aggregate (accelerator) is itself a primitive, so aggregates
/// nest, and a TransformedPrimitive (transformed_primitive.h) wraps any primitive in a
/// transform. Dynamic dispatch lives here, at the primitive/aggregate boundary only; inside an
/// accelerator the loops over nodes and shapes are templates.
#include <cmath>
#include <cstddef>
#include <limits>
#include <cstdint>
#include <optional>
#include <string>

#include "geometry/bounds.h"
#include "geometry/exact_predicates.h"
#include "geometry/interval.h"
#include "geometry/ray.h"
#include "scene/ray_counters.h"

namespace raylab {

class Primitive {
 public:
  virtual ~Primitive() = default;

  virtual Bounds3f bounds() const = 0;

  /// Closest hit with ray.tmin <= t < ray.tmax. On a hit, writes `hit`, sets ray.tmax = hit.t and
  /// returns true; otherwise leaves both alone. An invalid ray (see is_valid) never hits.
  virtual bool intersect(Ray& ray, Hit& hit) const = 0;
  /// The same, adding this ray's work to `counters`.
  virtual bool intersect(Ray& ray, Hit& hit, RayCounters& counters) const = 0;

  /// Whether any hit exists with ray.tmin <= t <= ray.tmax.
  virtual bool occluded(const Ray& ray) const = 0;
  virtual bool occluded(const Ray& ray, RayCounters& counters) const = 0;
};

/// The ray an any-hit query hands to kernels, which accept t < tmax: tmax moved up one float so
/// that a hit exactly at the query's tmax counts, as occluded()'s closed interval requires.
inline Ray closed_for_any_hit(const Ray& ray) {
  Ray closed = ray;
  closed.tmax = std::nextafter(ray.tmax, std::numeric_limits<float>::infinity());
  return closed;
}

/// What an accelerator reports about itself next to timings.
struct AccelStats {
  std::size_t bytes = 0;        ///< memory of the acceleration structure (not of the scene geometry)
  std::size_t nodes = 0;        ///< nodes or cells, 0 where not applicable
  double sah_cost = -1.0;       ///< SAH cost of the finished structure, < 0 where not defined
};

class Aggregate : public Primitive {
 public:
  virtual std::string name() const = 0;
  virtual AccelStats stats() const = 0;
  /// False for accelerators whose traversal raylab cannot see (Embree): their counters stay 0.
  virtual bool reports_counters() const { return true; }
  /// A hash of the built structure (e.g. FNV-1a over the node and index arrays), for the
  /// determinism tests: equal inputs and parameters must give equal hashes with any thread
  /// count and across runs. nullopt for accelerators without an inspectable structure.
  virtual std::optional<std::uint64_t> structure_hash() const { return std::nullopt; }
};

/// Counts one ray into RayCounters::exact_fallbacks when it took the exact path anywhere below
/// the outermost counted aggregate call on this thread (nested aggregates, instances), read from
/// exact_path_taken_on_this_thread(), and into RayCounters::interval_stage likewise from
/// interval_stage_taken_on_this_thread(). Only the counted virtuals use it: timed runs pay nothing.
class ExactPathTally {
 public:
  explicit ExactPathTally(RayCounters& counters) : counters_(counters) {
    if (depth()++ == 0) exact_path_taken_on_this_thread() = false, interval_stage_taken_on_this_thread() = false;
  }
  ~ExactPathTally() {
    if (--depth() == 0) {
      if (exact_path_taken_on_this_thread()) ++counters_.exact_fallbacks;
      if (interval_stage_taken_on_this_thread()) ++counters_.interval_stage;
    }
  }
  ExactPathTally(const ExactPathTally&) = delete;
  ExactPathTally& operator=(const ExactPathTally&) = delete;

 private:
  static int& depth() {
    thread_local int d = 0;
    return d;
  }
  RayCounters& counters_;
};

/// For any-hit queries: the ray a kernel with a half-open [tmin, tmax) should see
/// (closed_for_any_hit), or the ray itself for a kernel that accepts the closed interval.
template <class Kernel>
inline Ray any_hit_ray(const Ray& ray) {
  if constexpr (requires { Kernel::kClosedInterval; }) return ray;
  else return closed_for_any_hit(ray);
}

/// Implements Primitive's four virtuals for an accelerator whose traversal is
///   template <class Counters> bool intersect_impl(Ray&, Hit&, Counters&) const;
///   template <class Counters> bool occluded_impl(const Ray&, Counters&) const;
/// (CRTP), so each virtual call lands in one statically compiled loop.
template <class Derived>
class AggregateBase : public Aggregate {
 public:
  bool intersect(Ray& ray, Hit& hit) const final {
    if (!is_valid(ray)) return false;
    NoCounters c;
    return self().intersect_impl(ray, hit, c);
  }
  bool intersect(Ray& ray, Hit& hit, RayCounters& counters) const final {
    if (!is_valid(ray)) return false;
    const ExactPathTally tally(counters);
    return self().intersect_impl(ray, hit, counters);
  }
  bool occluded(const Ray& ray) const final {
    if (!is_valid(ray)) return false;
    NoCounters c;
    return self().occluded_impl(ray, c);
  }
  bool occluded(const Ray& ray, RayCounters& counters) const final {
    if (!is_valid(ray)) return false;
    const ExactPathTally tally(counters);
    return self().occluded_impl(ray, counters);
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

}  // namespace raylab
