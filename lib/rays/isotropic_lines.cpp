#include "rays/isotropic_lines.h"

#include <limits>

#include "rays/random.h"
#include "rays/sampling.h"

namespace raylab {

std::vector<Ray> isotropic_lines(const Vec3d& centre, double radius, std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<Ray> rays;
  rays.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(), u4 = rng.uniform();
    const Vec3d d = sample_uniform_sphere(u1, u2);
    const Frame frame(d);
    const Vec3d q = centre + frame.to_world(sample_uniform_disk(u3, u4) * radius);
    rays.push_back(Ray{Vec3f(q - d * radius), Vec3f(d), 0.0f, std::numeric_limits<float>::infinity()});
  }
  return rays;
}

}  // namespace raylab
