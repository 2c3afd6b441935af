#pragma once
/// Ray sets named by spec strings `NAME:COUNT[,key=value...]` (spec_string.h), e.g.
/// `diffuse:100000,seed=7`, `lines:1000000`, `file:rays.txt`.
///
/// Every generator is deterministic: the same spec on the same scene gives the same rays on
/// every machine (rays/random.h). Random generators take `seed=` (default 1). COUNT is in
/// [1, 2^28]. ray_generator_docs() lists the generators and their parameters.
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/ray.h"
#include "geometry/spec_string.h"
#include "rays/surface_rays.h"
#include "scene/scene.h"

namespace raylab {

inline constexpr std::int64_t kMaxRayCount = std::int64_t{1} << 28;
inline constexpr std::uint64_t kDefaultRaySeed = 1;

/// The rays named by `spec` for `scene`. `trace` is used by the generators that start on visible
/// surfaces (diffuse, shadow, ao) and may be empty for the others. Throws InputError naming the
/// spec on an unknown generator or parameter, a bad value, an empty scene, a scene the
/// camera does not see (diffuse, shadow, ao) or a scene without triangles (edges, vertices).
std::vector<Ray> generate_rays(const std::string& spec, const Scene& scene, const FirstHitFunction& trace);

/// One generator, for listings (`raylab rays --list`) and messages.
struct RayGeneratorDoc {
  std::string name;
  std::string usage;    ///< e.g. "primary:N"
  std::string summary;  ///< one paragraph
  std::vector<ParamDoc> params;
};

std::vector<RayGeneratorDoc> ray_generator_docs();
std::vector<std::string> ray_generator_names();

}  // namespace raylab
