#pragma once
/// PNG output of `raylab render`: shaded images and traversal-cost heatmaps with a colour bar.
#include <string>
#include <vector>

#include "geometry/ray.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

/// Lambertian-style shade in [0.15, 1] of a hit, lit from unit direction `light` (two-sided).
double shading_cosine(const Scene& scene, const Hit& hit, const Ray& ray, const Vec3d& light);

/// `values` in [0, 1] per pixel (row-major, top row first); negative = background.
void write_shaded_png(const std::string& path, const std::vector<float>& values, int width, int height);

/// How write_heatmap_png maps a cost c in [0, max] to the colour ramp: linearly (c / max), or
/// logarithmically (log(1 + c) / log(1 + max)), which keeps costs that span decades apart.
enum class HeatmapScale { linear, log };

/// Per-pixel costs mapped through a perceptual colour ramp (0 .. max), with a colour bar on the
/// right (labelled 0, max/2 and max on the linear scale; 0, the powers of ten up to max, and max
/// on the log scale) and `title` printed under the image. `max_cost` > 0 fixes the top of the
/// scale (so that several images share one; larger costs saturate); 0 takes the image's maximum.
void write_heatmap_png(const std::string& path, const std::vector<float>& costs, int width, int height,
                       const std::string& title, HeatmapScale scale = HeatmapScale::linear, double max_cost = 0.0);

/// The traversal cost of each ray through `accel` (which must report counters): nodes + leaves +
/// primitive tests of its closest-hit query, computed on `threads` threads (0: all).
std::vector<float> traversal_cost_per_ray(const Aggregate& accel, const std::vector<Ray>& rays, int threads);

}  // namespace raylab
