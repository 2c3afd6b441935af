#pragma once
/// The one factory: an accelerator from a spec `NAME[:key=value,...]` (geometry/spec_string.h),
/// e.g. `embree:quality=high` or `brute:kernel=mt`. Unknown names and unknown or malformed
/// parameters throw InputError listing the valid ones. Every accelerator registered here is run
/// by the oracle test suite (tests/test_oracle.cpp) on every scene and ray kind it lists.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "accel/common/fitted_cost.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/kernel_choice.h"
#include "accel/exact/contact_classes.h"
#include "geometry/spec_string.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

/// The classes an accuracy bound is stated for, from the exact oracle's classification of each
/// ray (accel/exact/contact_classes.h): ill-conditioned rays (of any contact class) first, then
/// by contact class; well-conditioned rays without a contact count with the crossing ones (a
/// float method decides both by the same rounding-free margin).
enum class RayBucket : std::uint8_t { crossing, touching, on_surface, ill_conditioned };
inline constexpr int kRayBuckets = 4;

RayBucket ray_bucket(const RayContact& c);
/// "crossing", "touching", "on_surface", "ill_conditioned".
const char* ray_bucket_name(RayBucket b);

/// How closely an accelerator agrees with the exact oracle: the largest fraction of the rays of
/// each bucket that may mismatch, in the sense of compare_hits (hit_comparison.h), or, for
/// `exact` methods, of compare_hits_exact (the same primitive, or one whose exact t equals the
/// oracle's: no tolerance).
///
/// A watertight float kernel decides every well-conditioned crossing exactly, at shared edges
/// and vertices of closed and open meshes alike. A touching contact (a silhouette vertex or
/// edge, a boundary edge, a ray in a face's plane), a ray starting on a surface, and any
/// ill-conditioned ray turn on the last bit of the ray: no float kernel can follow them, so float
/// methods claim nothing there (1.0) and the report measures them. Methods that are not
/// watertight also fail on crossings through shared edges and vertices, mostly on the rays aimed
/// at them (`edges:`, `vertices:`: the feature bound) and rarely elsewhere.
struct AccuracyBound {
  double crossing_features = 0.0;  ///< well-conditioned crossing/no-contact rays of feature-aimed kinds
  double crossing_other = 0.0;     ///< well-conditioned crossing/no-contact rays of every other kind
  double touching = 0.0;
  double on_surface = 0.0;
  double ill_conditioned = 0.0;
  bool exact = false;     ///< held to the exact rule (compare_hits_exact) in every bucket
  /// The ray/primitive kernel the method runs: certified, watertight, mt or exact; empty for a
  /// method that runs another library's (Embree).
  std::string kernel;
  std::string statement;  ///< one sentence per class for listings and the report

  double max_mismatch_rate(RayBucket bucket, bool feature_rays) const;
};

/// The mismatches `bound` allows among `rays` rays of bucket `b`.
std::size_t allowed_mismatches(const AccuracyBound& bound, RayBucket b, bool feature_rays, std::size_t rays);
/// Whether `c` (compared with classes) stays within `bound` in every bucket; otherwise, in
/// `why`, one clause per bucket it exceeds.
bool within_bound(const AccuracyBound& bound, const HitComparison& c, bool feature_rays, std::string* why = nullptr);

/// The bound of a float method: the given rates on well-conditioned crossings of feature-aimed and
/// other ray kinds, no claim (1.0) on touching, on-surface and ill-conditioned rays.
AccuracyBound float_accuracy(double crossing_features, double crossing_other, std::string statement);
/// The bound of a watertight float kernel with conservative traversal; `how` names them, e.g.
/// "watertight kernel, conservative placement and traversal".
AccuracyBound watertight_accuracy(const std::string& how);
/// The bound of the exact kernel: 0 everywhere, by the exact rule.
AccuracyBound exact_accuracy(const std::string& how);
/// The same bound, for the certified kernel.
AccuracyBound certified_accuracy(const std::string& how);
/// watertight_accuracy(how) or, for kernel=certified, certified_accuracy.
AccuracyBound kernel_accuracy(KernelChoice kernel, const std::string& how);

struct AccelKind {
  std::string name;
  std::string summary;
  std::vector<ParamDoc> params;
  /// Builds the accelerator on `scene`, reading its parameters from `reader` (the factory calls
  /// reader.finish(params) afterwards) and resolving what lies above lib/accel (`cost=`) through
  /// the context.
  std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>, SpecReader&, const BuildContext&)> build;
  /// The accuracy the oracle suite holds this accelerator to, given its parameters.
  std::function<AccuracyBound(SpecReader&)> accuracy;
  /// Parameter settings the oracle suite runs besides the defaults, e.g. {"kernel=mt"}.
  std::vector<std::string> oracle_variants = {};
};

/// AccelKind::build for a builder whose config carries a `cost=` request (`fitted_cost`) and the
/// SAH constants it sets (`cost`): reads the config, resolves the request through the build
/// context for the scene's primitive count (apply_fitted_cost), and builds with `make`.
template <class ReadConfig, class Make>
auto build_with_fitted_cost(ReadConfig read_config, Make make) {
  return [read_config, make](std::shared_ptr<const Scene> scene, SpecReader& r, const BuildContext& context) {
    auto config = read_config(r);
    apply_fitted_cost(config.fitted_cost, context, scene->total_primitive_count(), config.cost);
    return make(std::move(scene), config);
  };
}

/// For an instanced scene (scene.h): builds `make(base)` once per base and places it under each
/// of its instances' transforms (TransformedPrimitive), plus `make` on the flat geometry (a copy,
/// Scene::flat_part) when there is any, all in a BVH top level (accel/bvh/primitive_bvh.h: binned
/// SAH over the world bounds, robust traversal). Hits name the instance (kInvalidId on the flat
/// geometry) and the primitive within its base. Throws InputError for an invalid instance
/// (require_valid_instances: a singular or non-finite transform, a missing or nested base).
std::unique_ptr<Aggregate> make_instanced_aggregate(
    const Scene& scene, const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make);

/// For an instanced scene and an accelerator with kernel `kernel`: make_instanced_aggregate, or
/// with kernel=certified make_over_flattened_instances (exact_oracle.h): the certified answer is
/// the exact answer on the flat copy of the scene, the geometry the oracle answers for, which a
/// ray transformed into an instance's frame in float does not see exactly.
std::unique_ptr<Aggregate> make_instanced_for_kernel(
    KernelChoice kernel, const Scene& scene,
    const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make);

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

/// Builds the accelerator described by `spec` on `scene`; throws InputError for bad specs. A
/// spec's `cost=MODEL` is resolved through `context` (fitted_cost.h; lib/cost's
/// model_build_context() reads model files): without a resolver it is an InputError.
std::unique_ptr<Aggregate> make_accelerator(const std::string& spec, std::shared_ptr<const Scene> scene,
                                            const BuildContext& context = {});

/// The accuracy bound for `spec`.
AccuracyBound accuracy_bound(const std::string& spec);

/// The one check of an accelerator spec before any scene is loaded or structure built (the
/// tool's commands, the sweep plans): a known name, known keys, and every value the kind reads
/// (ranges, choices, exclusive keys), as accuracy_bound reads them. Throws InputError naming the
/// fault. Reads no model file for `cost=`; `auto` reads its model.
void validate_accelerator_spec(const std::string& spec);

/// `spec` with every parameter of its kind written out, in the kind's documented order, the given
/// value or else the default (ParamDoc::default_value): `kdtree` → `kdtree:builder=sah,sweep=events,
/// ...`. The report names each key number's spec this way, so that a changed default shows up as a
/// changed spec. A value with commas, colons or spaces is wrapped in parentheses; a default that
/// depends on other parameters is written as its documentation, e.g. `leaf_size=(4 (width=2), ...)`.
/// Throws InputError for an unknown name or key.
std::string canonical_spec(const std::string& spec);

}  // namespace raylab
