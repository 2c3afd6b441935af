#include "accel/common/hit_comparison.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "accel/common/accel_factory.h"
#include "accel/exact/exact_oracle.h"
#include "geometry/exact_predicates.h"
#include "geometry/float_mode.h"

namespace raylab {
namespace {

/// Records ray i's outcome in `c`.
void record(HitComparison& c, std::size_t i, bool mismatch, const std::vector<RayContact>* classes) {
  if (mismatch) {
    ++c.mismatches;
    if (c.first_mismatches.size() < 16) c.first_mismatches.push_back(i);
  }
  if (!classes) return;
  const RayContact& k = (*classes)[i];
  const auto cls = static_cast<std::size_t>(k.contact), bucket = static_cast<std::size_t>(ray_bucket(k));
  ++c.class_rays[cls];
  ++c.bucket_rays[bucket];
  c.ill_conditioned += k.ill_conditioned;
  if (!mismatch) return;
  ++c.class_mismatches[cls];
  ++c.bucket_mismatches[bucket];
  c.ill_conditioned_mismatches += k.ill_conditioned;
}

/// Counts a hit where the reference misses, or a miss where it hits, as a mismatch; false when
/// both hit or both miss (the caller then compares the two hits).
bool presence_mismatch(HitComparison& c, const Hit& h, const Hit& r) {
  if (h.valid() == r.valid()) return false;
  ++(h.valid() ? c.false_hits : c.missed_hits);
  return true;
}

void check_sizes(std::size_t rays, std::size_t a, std::size_t b, const std::vector<RayContact>* classes,
                 const char* what) {
  if (rays != a || rays != b || (classes && classes->size() != rays))
    throw std::invalid_argument(std::string(what) + ": rays, hits, reference and classes differ in size");
}

/// Triangle or sphere `prim` of a flat scene offered to `first`.
bool offer(ExactFirstHit& first, const Scene& flat, unsigned prim) {
  if (flat.is_sphere(prim)) return first.offer_sphere(prim, flat.sphere(prim));
  return first.offer_triangle(prim, flat.mesh.vertex(prim, 0), flat.mesh.vertex(prim, 1), flat.mesh.vertex(prim, 2));
}

}  // namespace

HitComparison compare_hits(const std::vector<Ray>& rays, const std::vector<Hit>& hits, const std::vector<Hit>& reference,
                           double scene_diagonal, const std::vector<RayContact>* classes) {
  check_sizes(rays.size(), hits.size(), reference.size(), classes, "compare_hits");
  HitComparison c;
  c.rays = rays.size();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Hit& h = hits[i];
    const Hit& r = reference[i];
    bool mismatch = presence_mismatch(c, h, r);
    if (!mismatch && h.valid()) {
      const double dir_len = length(Vec3d(rays[i].dir));
      const double tol =
          kHitTolerance * (std::abs(double(r.t)) + (length(Vec3d(rays[i].org)) + scene_diagonal) / dir_len);
      if (!(std::abs(double(h.t) - double(r.t)) <= tol)) {
        ++c.wrong_t;
        mismatch = true;
      } else if (h.prim != r.prim || h.instance != r.instance) {
        ++c.ties;
      }
    }
    record(c, i, mismatch, classes);
  }
  return c;
}

HitComparison compare_hits_exact(const Scene& scene, const std::vector<Ray>& rays, const std::vector<Hit>& hits,
                                 const std::vector<Hit>& reference, const std::vector<RayContact>* classes) {
  check_sizes(rays.size(), hits.size(), reference.size(), classes, "compare_hits_exact");
  std::shared_ptr<const Scene> flat_owner;
  const Scene* flat = &scene;
  if (scene.instanced()) {
    flat_owner = flatten_instances(scene);
    flat = flat_owner.get();
  }
  auto flat_id = [&](const Hit& h) { return scene.instanced() ? flat_primitive_id(scene, h) : h.prim; };
  const FloatModeScope ieee(false);
  HitComparison c;
  c.rays = rays.size();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Hit& h = hits[i];
    const Hit& r = reference[i];
    bool mismatch = presence_mismatch(c, h, r);
    if (!mismatch && h.valid() && (h.prim != r.prim || h.instance != r.instance)) {
      const unsigned a = flat_id(h), b = flat_id(r);
      ExactFirstHit got(rays[i]), ref(rays[i]);
      const bool valid_ids = a < flat->primitive_count() && b < flat->primitive_count();
      if (valid_ids && offer(got, *flat, a) && offer(ref, *flat, b) && got.compare_time(ref) == 0) {
        ++c.ties;
      } else {
        ++c.wrong_t;
        mismatch = true;
      }
    }
    record(c, i, mismatch, classes);
  }
  return c;
}

HitComparison compare_occlusion(const std::vector<std::uint8_t>& blocked, const std::vector<std::uint8_t>& reference,
                                const std::vector<RayContact>* classes) {
  check_sizes(blocked.size(), blocked.size(), reference.size(), classes, "compare_occlusion");
  HitComparison c;
  c.rays = blocked.size();
  for (std::size_t i = 0; i < blocked.size(); ++i) {
    const bool mismatch = bool(blocked[i]) != bool(reference[i]);
    if (mismatch) {
      if (blocked[i]) ++c.false_hits;
      else ++c.missed_hits;
    }
    record(c, i, mismatch, classes);
  }
  return c;
}

}  // namespace raylab
