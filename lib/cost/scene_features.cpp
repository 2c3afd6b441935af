#include "cost/scene_features.h"

#include <algorithm>
#include <vector>

namespace raylab {

SceneFeatures scene_features(const Scene& scene) {
  SceneFeatures f;
  f.primitives = static_cast<double>(scene.primitive_count());
  f.triangles = static_cast<double>(scene.triangle_count());
  std::vector<double> areas;
  areas.reserve(scene.triangle_count());
  Bounds3f box;
  for (std::size_t t = 0; t < scene.triangle_count(); ++t) {
    const Vec3d a(scene.mesh.vertex(t, 0)), b(scene.mesh.vertex(t, 1)), c(scene.mesh.vertex(t, 2));
    const double area = 0.5 * length(cross(b - a, c - a));
    f.total_area += area;
    if (area > 0) areas.push_back(area);
    box.extend(scene.mesh.triangle_bounds(t));
  }
  for (std::size_t s = 0; s < scene.spheres.size(); ++s)
    box.extend(scene.primitive_bounds(static_cast<unsigned>(scene.triangle_count() + s)));
  if (!areas.empty()) {
    const auto mid = areas.begin() + static_cast<std::ptrdiff_t>(areas.size() / 2);
    std::nth_element(areas.begin(), mid, areas.end());
    f.median_area = *mid;
    f.max_area = *std::max_element(areas.begin(), areas.end());
    f.area_ratio = f.max_area / f.median_area;
  }
  if (scene.primitive_count() > 0) f.box_area = static_cast<double>(box.surface_area());
  if (f.box_area > 0) f.crossings = f.total_area / f.box_area;
  return f;
}

}  // namespace raylab
