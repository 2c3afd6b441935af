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

/// How write_heatmap_png maps a cost c in [lo, hi] to the colour ramp: linearly ((c − lo) / (hi −
/// lo)), or logarithmically ((log(1 + c) − log(1 + lo)) / (log(1 + hi) − log(1 + lo))), which keeps
/// costs that span decades apart.
enum class HeatmapScale { linear, log };

/// The position in [0, 1] of cost `c` on a colour scale from `lo` to `hi` (0.5 for every cost when
/// hi ≤ lo: a constant image; costs outside [lo, hi] saturate).
double heatmap_position(double c, double lo, double hi, HeatmapScale scale);

/// Per-pixel costs mapped through a perceptual colour ramp from `min_cost` to `max_cost`, with a
/// colour bar on the right labelled with both ends and, between them, the powers of ten on the log
/// scale (the midpoint on the linear scale, or where no power of ten fits), and `title` printed
/// under the image. `max_cost` > 0 fixes the top of the scale and `min_cost` ≥ 0 its bottom (so
/// that several images share one; costs beyond saturate); by default the scale runs from the
/// image's least to its largest cost, so that it shows the data's range.
void write_heatmap_png(const std::string& path, const std::vector<float>& costs, int width, int height,
                       const std::string& title, HeatmapScale scale = HeatmapScale::linear, double max_cost = 0.0,
                       double min_cost = -1.0);

/// The traversal cost of each ray through `accel` (which must report counters): nodes + leaves +
/// primitive tests of its closest-hit query, computed on `threads` threads (0: all).
std::vector<float> traversal_cost_per_ray(const Aggregate& accel, const std::vector<Ray>& rays, int threads);

}  // namespace raylab
