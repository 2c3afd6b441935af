#pragma once
/// The one factory: an accelerator from a spec `NAME[:key=value,...]` (geometry/spec_string.h),
/// e.g. `embree:quality=high` or `brute:kernel=mt`. Unknown names and unknown or malformed
/// parameters throw InputError listing the valid ones. Every accelerator registered here is run
/// by the oracle test suite (tests/test_oracle.cpp) on every scene and ray kind it lists.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "geometry/spec_string.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

/// How closely an accelerator agrees with the exact oracle, in the sense of compare_hits
/// (hit_comparison.h): the largest fraction of rays that may mismatch, per kind of ray.
///
/// Rays aimed at edges and vertices (`edges:`, `vertices:`) are where float methods fail. On a
/// closed mesh such a ray crosses the surface, so a watertight method must agree exactly. On an
/// open mesh (a boundary edge, a soup, a degenerate triangle) it grazes the surface at the
/// feature: the exact answer there turns on the last bit of the ray, and no float kernel,
/// watertight or not, can follow it; only the exact kernel states 0 there.
struct AccuracyBound {
  double max_mismatch_rate_closed_features = 0.0;  ///< feature-aimed rays on closed meshes
  double max_mismatch_rate_open_features = 0.0;    ///< feature-aimed rays on open meshes
  double max_mismatch_rate_other = 0.0;            ///< every other ray kind
  std::string statement;                           ///< one sentence for listings and the report

  /// The bound for rays of `ray_spec` on a scene that is (or is not) closed.
  double max_mismatch_rate(const std::string& ray_spec, bool scene_closed) const;
};

struct AccelKind {
  std::string name;
  std::string summary;
  std::vector<ParamDoc> params;
  /// Builds the accelerator on `scene`, reading its parameters from `reader` (the factory calls
  /// reader.finish(params) afterwards).
  std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>, SpecReader&)> build;
  /// The accuracy the oracle suite holds this accelerator to, given its parameters.
  std::function<AccuracyBound(SpecReader&)> accuracy;
  /// Parameter settings the oracle suite runs besides the defaults, e.g. {"kernel=mt"}.
  std::vector<std::string> oracle_variants = {};
};

/// For an instanced scene (scene.h): builds `make(base)` once per base and places it under each
/// of its instances' transforms (TransformedPrimitive), plus `make` on the flat geometry (a copy,
/// Scene::flat_part) when there is any, all in a BVH top level (accel/bvh/primitive_bvh.h: binned
/// SAH over the world bounds, robust traversal). Hits name the instance (kInvalidId on the flat
/// geometry) and the primitive within its base. Throws InputError for an invalid instance
/// (require_valid_instances: a singular or non-finite transform, a missing or nested base).
std::unique_ptr<Aggregate> make_instanced_aggregate(
    const Scene& scene, const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make);

/// Every accelerator the lab knows, in listing order: the built-in kinds of accel_factory.cpp,
/// then the registered ones by `order`.
const std::vector<AccelKind>& accelerator_kinds();

/// Registers an accelerator kind from its own translation unit, at static-initialisation time:
///
///   namespace { const AccelRegistration kdtree_registration(make_kdtree_kind(), 40); }
///
/// raylab is one shared library, so every registration in it runs before main(). Registering
/// after accelerator_kinds() has first been called is a logic error (std::logic_error).
struct AccelRegistration {
  AccelRegistration(AccelKind kind, int order);
};

/// Looks up `name`; throws InputError listing the valid names.
const AccelKind& find_accelerator_kind(const std::string& name);

/// Builds the accelerator described by `spec` on `scene`; throws InputError for bad specs.
std::unique_ptr<Aggregate> make_accelerator(const std::string& spec, std::shared_ptr<const Scene> scene);

/// The accuracy bound for `spec`.
AccuracyBound accuracy_bound(const std::string& spec);

}  // namespace raylab
