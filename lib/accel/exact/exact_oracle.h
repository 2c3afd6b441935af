#pragma once
/// `exact`: the exact oracle. Candidates are pruned conservatively with a CGAL AABB tree over
/// the triangles (CGAL::AABB_tree::all_intersected_primitives, whose box and triangle tests are
/// exact predicates on the float-exact double coordinates), spheres by their outward-rounded
/// boxes; then ExactFirstHit (geometry/exact_predicates.h) decides every candidate exactly and
/// orders the hits exactly. Instanced scenes are flattened first (flatten_instances: every base
/// under every instance transform, beside the flat geometry), which is the geometry the oracle
/// then answers for; its hits name instance and primitive as scene.h describes.
#include <functional>
#include <memory>

#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

/// Largest flattened scene the oracle accepts (triangles + spheres).
inline constexpr double kExactOracleMaxPrimitives = 1u << 26;

/// Builds the oracle; throws InputError when an instanced scene would flatten to more than
/// kExactOracleMaxPrimitives primitives.
std::unique_ptr<Aggregate> make_exact_oracle(std::shared_ptr<const Scene> scene);

/// Throws InputError naming the scene and the instance when an instance places spheres under a
/// transform that is not a rotation times a uniform scale: the flat copy (flatten_instances, and
/// the geometry the certified answers are stated for) holds spheres, not ellipsoids.
void require_spheres_stay_spheres(const Scene& scene);

/// The flat copy of an instanced scene the oracle uses: the flat geometry's triangles, then those
/// of instance 0, 1, ... (vertices transformed in double, rounded to float), then the spheres in
/// the same order. Throws InputError when the copy would exceed kExactOracleMaxPrimitives, for an
/// invalid instance (require_valid_instances), and for spheres under a non-uniform scale.
std::shared_ptr<const Scene> flatten_instances(const Scene& scene);

/// The id in flatten_instances(scene) of the primitive a hit on the instanced `scene` names
/// (instance and primitive within its base, or a primitive of the flat geometry).
unsigned flat_primitive_id(const Scene& scene, const Hit& hit);

/// `make(flatten_instances(scene))`, reporting hits as (instance, prim) like instanced
/// accelerators: how the oracle, and every accelerator with kernel=certified, answer for an
/// instanced scene (the flat copy is the geometry the exact answer is defined on).
std::unique_ptr<Aggregate> make_over_flattened_instances(
    const Scene& scene, const std::function<std::unique_ptr<Aggregate>(std::shared_ptr<const Scene>)>& make);

}  // namespace raylab
