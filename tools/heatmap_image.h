#pragma once
/// PNG output of `raylab render`: shaded images and traversal-cost heatmaps with a colour bar.
#include <string>
#include <vector>

#include "geometry/ray.h"
#include "scene/scene.h"

namespace raylab {

/// Lambertian-style shade in [0.15, 1] of a hit, lit from unit direction `light` (two-sided).
double shading_cosine(const Scene& scene, const Hit& hit, const Ray& ray, const Vec3d& light);

/// `values` in [0, 1] per pixel (row-major, top row first); negative = background.
void write_shaded_png(const std::string& path, const std::vector<float>& values, int width, int height);

/// Per-pixel costs mapped through a perceptual colour ramp (0 .. max), with a colour bar on the
/// right labelled 0, max/2 and max, and `title` printed under the image.
void write_heatmap_png(const std::string& path, const std::vector<float>& costs, int width, int height,
                       const std::string& title);

}  // namespace raylab
