#pragma once
/// A BVH over arbitrary primitives: the top level of a two-level scheme (instances of any
/// accelerator, each under its own transform; pbrt-v3 §4.1.2 and §4.3, the lecture's nested
/// aggregates). The tree is built on the primitives' world bounds with an object-split builder
/// (bvh_build.h, binned SAH by default) and traversed near-first with Ize's conservative box
/// test (bvh_traversal.h), so no primitive whose bounds the ray touches is skipped. Leaves call
/// each primitive's virtual intersect/occluded: this is the dynamic-dispatch boundary.
#include <memory>
#include <vector>

#include "accel/bvh/bvh_build.h"
#include "accel/bvh/bvh_traversal.h"
#include "scene/primitive.h"

namespace raylab {

/// The top-level defaults: binned SAH, leaves of at most 2 primitives, and c_isect = 8·c_trav,
/// since testing a primitive here means a transform and a whole inner traversal (tens of node
/// visits), not one triangle test.
BvhConfig primitive_bvh_default_config();

class PrimitiveBvh final : public AggregateBase<PrimitiveBvh> {
 public:
  /// `prims` must be non-null; their bounds must be finite or empty (empty ones are never hit).
  /// Only `builder` (spatial is treated as binned), `max_leaf_size`, `bins`, `cost` and
  /// `threads` of `config` are used; the traversal is always the robust one.
  explicit PrimitiveBvh(std::vector<std::shared_ptr<const Primitive>> prims,
                        const BvhConfig& config = primitive_bvh_default_config());

  std::string name() const override { return "bvh-over-primitives"; }
  /// Bytes and nodes of the top level only (the tree, its references and the leaf-ordered
  /// primitive pointers), not of the primitives themselves.
  AccelStats stats() const override;
  Bounds3f bounds() const override { return bounds_; }
  // No structure_hash(): the hash would cover the top level only, not the primitives under it.

  std::size_t size() const { return prims_.size(); }
  const Bvh2& tree() const { return tree_; }

  /// Counters: the top level's nodes and leaves, plus whatever the primitives count; visiting a
  /// primitive is not itself counted as a primitive test.
  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    if (tree_.nodes.empty()) return false;
    Ray local = ray;
    float closest = ray.tmax;
    const bool found = traverse_bvh2<true, false>(
        tree_.nodes.data(), ray, closest, counters, [&](std::uint32_t first, std::uint32_t count, float& t) {
          bool any = false;
          local.tmax = t;
          for (std::uint32_t i = first; i < first + count; ++i) {
            // A hit lowers local.tmax, so later primitives (here and in later leaves) must beat it.
            if constexpr (Counters::enabled) any |= leaf_prims_[i]->intersect(local, hit, counters);
            else any |= leaf_prims_[i]->intersect(local, hit);
          }
          t = local.tmax;
          return any;
        });
    if (found) ray.tmax = closest;
    return found;
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    if (tree_.nodes.empty()) return false;
    // Box tests on [tmin, tmax] are closed (Ize's test is conservative), as occluded() requires;
    // the primitives apply the closed interval themselves.
    float closest = ray.tmax;
    return traverse_bvh2<true, true>(tree_.nodes.data(), ray, closest, counters,
                                     [&](std::uint32_t first, std::uint32_t count, float&) {
                                       for (std::uint32_t i = first; i < first + count; ++i) {
                                         if constexpr (Counters::enabled) {
                                           if (leaf_prims_[i]->occluded(ray, counters)) return true;
                                         } else if (leaf_prims_[i]->occluded(ray)) {
                                           return true;
                                         }
                                       }
                                       return false;
                                     });
  }

 private:
  std::vector<std::shared_ptr<const Primitive>> prims_;  ///< ownership, in the caller's order
  BvhConfig config_;
  Bvh2 tree_;
  /// leaf_prims_[i] = prims_[tree_.prims[i]].get(): leaves read their primitives contiguously.
  std::vector<const Primitive*> leaf_prims_;
  Bounds3f bounds_;
  double sah_cost_ = 0.0;
};

}  // namespace raylab
