#pragma once
/// Ray sets for a scene, as the tool, the tests and the experiments make them: the generators of
/// lib/rays with the visible-surface generators (diffuse, shadow, ao) fed by Embree's robust
/// mode, which is fast and independent of the accelerator under test.
#include <memory>
#include <string>
#include <vector>

#include "geometry/ray.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

/// The rays named by `spec` (rays/ray_generators.h) for `scene`; throws InputError on bad specs.
std::vector<Ray> make_ray_set(const std::string& spec, const std::shared_ptr<const Scene>& scene);

/// The same rays with the visible-surface generators fed by `first_hits`, a structure already
/// built on `scene` (no Embree device or BVH is built). The rays equal make_ray_set's wherever the
/// two give the same first hits; `auto`'s race samples its rays so, from the structure it built first.
std::vector<Ray> make_ray_set(const std::string& spec, const std::shared_ptr<const Scene>& scene,
                              const Primitive& first_hits);

/// True for ray kinds traced as any-hit (occluded) queries: `shadow` and `ao`.
bool is_any_hit_ray_spec(const std::string& spec);

/// True for ray kinds aimed at edges and vertices (edges, vertices, touching, grazing), to which
/// AccuracyBound's feature bound applies.
bool is_feature_ray_spec(const std::string& spec);

}  // namespace raylab
