#pragma once
/// `exact`: the exact oracle. Candidates are pruned conservatively with a CGAL AABB tree over
/// the triangles (CGAL::AABB_tree::all_intersected_primitives, whose box and triangle tests are
/// exact predicates on the float-exact double coordinates), spheres by their outward-rounded
/// boxes; then ExactFirstHit (geometry/exact_predicates.h) decides every candidate exactly and
/// orders the hits exactly. Instanced scenes are flattened first (object vertices transformed
/// in double and rounded to float), which is the geometry the oracle then answers for.
#include <memory>

#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

/// Largest flattened scene the oracle accepts (triangles + spheres).
inline constexpr double kExactOracleMaxPrimitives = 1u << 26;

/// Builds the oracle; throws InputError when an instanced scene would flatten to more than
/// kExactOracleMaxPrimitives primitives.
std::unique_ptr<Aggregate> make_exact_oracle(std::shared_ptr<const Scene> scene);

/// The flat copy of an instanced scene the oracle uses (primitive id = instance·P + prim).
std::shared_ptr<const Scene> flatten_instances(const Scene& scene);

}  // namespace raylab
