#pragma once
/// Certified first hits on an instanced scene without a flat copy. The geometry answered for is
/// the one flatten_instances (exact_oracle.h) defines: every instance's vertices transformed in
/// double and rounded to float, spheres under similarities likewise; but no copy is stored, so a
/// scene of 3.1·10^9 triangles takes the memory of its bases.
///
/// Each base, and the flat geometry as one more part under the identity, gets one binned BVH in
/// object space (bvh_build.h); a BVH over the parts' world boxes leads to them. A node's box is
/// taken to world space as the ray meets it: centre and half extents through the transform
/// (A·c + b and |A|·h, in double), widened by 2^-22 of the magnitudes involved, which covers the
/// double arithmetic and the rounding of a vertex to float (or its flush to zero, 2^-125), so the
/// widened box holds every world triangle under the node. The ray is tested against it in world
/// space, in double, with entry and exit distances widened by a relative 2^-40; nothing the ray
/// meets is skipped. At a leaf, each triangle's world vertices are computed exactly as the flat
/// copy computes them and offered to one CertifiedKernel context per ray (certified_kernel.h),
/// which orders the hits of all instances exactly. Hits name the instance (kInvalidId for the
/// flat geometry) and the primitive within its base, as make_instanced_aggregate's do.
#include <memory>
#include <vector>

#include "accel/bvh/bvh_node.h"
#include "geometry/transform.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

class CertifiedInstances final : public AggregateBase<CertifiedInstances> {
 public:
  /// Any scene (one without instances is its own flat copy); throws InputError for an invalid
  /// instancing (require_valid_instances) and for spheres under a non-uniform scale (as
  /// flatten_instances). Registered as the accelerator `certified-instances`, so that the oracle
  /// suite runs it on every scene.
  explicit CertifiedInstances(std::shared_ptr<const Scene> scene);

  std::string name() const override { return "certified-instances"; }
  AccelStats stats() const override;
  Bounds3f bounds() const override { return bounds_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const;
  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const;

 private:
  /// The flat geometry (instance kInvalidId) or one instance of a base, with its tree.
  struct Part {
    const Scene* geometry = nullptr;
    const Bvh2* tree = nullptr;
    AffineTransform object_to_world;
    std::array<std::array<double, 3>, 3> abs_linear{};  ///< |A|, for half extents
    double sphere_scale = 1.0;                           ///< cbrt|det A|, as flatten_instances scales radii
    unsigned instance = kInvalidId;
  };
  template <bool kAnyHit, class Counters>
  bool trace(const Ray& ray, Hit& hit, Counters& counters) const;

  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<const Scene> flat_part_;  ///< the flat geometry as a scene of its own, when there is any
  std::vector<Bvh2> trees_;                 ///< per base, then the flat part's last
  std::vector<Part> parts_;
  Bvh2 top_;  ///< over the parts' world boxes
  Bounds3f bounds_;
};

}  // namespace raylab
