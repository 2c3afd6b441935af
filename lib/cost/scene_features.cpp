#include "cost/scene_features.h"

#include <array>
#include <cstdint>
#include <algorithm>
#include <vector>

namespace raylab {

SceneFeatures scene_features(const Scene& scene) {
  SceneFeatures f;
  f.primitives = static_cast<double>(scene.primitive_count());
  f.triangles = static_cast<double>(scene.triangle_count());
  const std::size_t n = scene.triangle_count();
  // Every triangle's area for the total and the largest; every stride-th one's for the median.
  const std::size_t stride = std::max<std::size_t>(1, n / kMedianSample);
  std::vector<double> sample;
  sample.reserve(n / stride + 1);
  for (std::size_t t = 0; t < n; ++t) {
    const Vec3d a(scene.mesh.vertex(t, 0)), b(scene.mesh.vertex(t, 1)), c(scene.mesh.vertex(t, 2));
    const double area = 0.5 * length(cross(b - a, c - a));
    f.total_area += area;
    f.max_area = std::max(f.max_area, area);
    if (t % stride == 0 && area > 0) sample.push_back(area);
  }
  if (!sample.empty()) {
    const auto mid = sample.begin() + static_cast<std::ptrdiff_t>(sample.size() / 2);
    std::nth_element(sample.begin(), mid, sample.end());
    f.median_area = *mid;
    f.area_ratio = f.max_area / f.median_area;
  }
  Bounds3f box;
  for (const std::array<std::uint32_t, 3>& tri : scene.mesh.triangles)
    for (const std::uint32_t v : tri) box.extend(scene.mesh.vertices[v]);
  for (std::size_t s = 0; s < scene.spheres.size(); ++s)
    box.extend(scene.primitive_bounds(static_cast<unsigned>(n + s)));
  if (scene.primitive_count() > 0) f.box_area = static_cast<double>(box.surface_area());
  if (f.box_area > 0) f.crossings = f.total_area / f.box_area;
  return f;
}

}  // namespace raylab
