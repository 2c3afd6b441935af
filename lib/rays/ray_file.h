#pragma once
/// Ray files and hit files: the plain-text formats in which ray sets and first hits are saved,
/// exchanged and compared.
///
/// Ray file: one ray per line, eight whitespace-separated numbers
///
///     ox oy oz dx dy dz tmin tmax
///
/// Lines that are blank or start with '#' (after leading whitespace) are skipped. Numbers are
/// decimal or `inf` (tmax only); every value is rounded once to float when read. write_rays
/// prints the shortest decimal that reads back to the same float (std::to_chars), so a ray
/// file round-trips bit for bit, denormals and infinities included.
///
/// Hit file (CSV): the header `ray,prim,t,u,v`, then one row per ray in ray order. A miss is
/// written `ray,-1,inf,0,0`. For an instanced scene (scene.h) two columns follow: `instance`,
/// the index into Scene::instances of the instance hit, and `base`, the index into Scene::bases
/// of the base it places; both are -1 for a miss and for a hit on the flat geometry, and `prim`
/// is then the primitive id within that base (or within the flat geometry). Without a scene, the
/// `instance` column alone is written when any hit carries one. With contact classes (`raylab trace --classify`) a last column `contact` holds each
/// ray's class (none, crossing, touching, on_surface, with `+ill` appended for an ill-conditioned
/// ray; accel/exact/contact_classes.h). Floats are written shortest round-trip.
#include <cstddef>
#include <string>
#include <vector>

#include "geometry/ray.h"

namespace raylab {

struct Scene;

/// Most rays (and hit rows) a file may hold: 2^28, the limit of every ray set.
inline constexpr std::size_t kMaxRaysPerFile = std::size_t{1} << 28;

/// Writes `rays` to `path` (a `#` header line, then one ray per line). Throws InputError when
/// the file cannot be written.
void write_rays(const std::string& path, const std::vector<Ray>& rays);

/// Reads a ray file, streaming it line by line. Throws InputError "PATH:LINE: <fault>" for a
/// line that does not hold exactly eight numbers, a number that does not parse completely or is
/// out of float range, NaN, an infinite value other than tmax = +inf, tmin < 0, tmin > tmax or
/// a zero direction; "PATH: no rays" for a file without rays; "PATH: cannot open" when it
/// cannot be read; and an error for more than kMaxRaysPerFile rays.
std::vector<Ray> read_rays(const std::string& path);

/// Writes one CSV row per hit (see above); `scene`, when given, is the scene the hits are on;
/// `contacts` (one label per hit), when given, fills the column `contact`. Throws InputError
/// when the file cannot be written.
void write_hits_csv(const std::string& path, const std::vector<Hit>& hits, const Scene* scene = nullptr,
                    const std::vector<std::string>* contacts = nullptr);

/// Reads a hit file written by write_hits_csv (with or without the instance, base and contact
/// columns; the base column is checked to be -1 exactly where the instance is, and not returned;
/// contact labels are not read back). Throws
/// InputError "PATH:LINE: <fault>" on a wrong header, a wrong field count, a ray column that is
/// not the row index, a prim that is neither -1 nor a valid id, a miss whose t is not inf, or a
/// number that does not parse.
std::vector<Hit> read_hits_csv(const std::string& path);

}  // namespace raylab
