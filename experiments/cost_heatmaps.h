#pragma once
/// Traversal-cost heatmaps for the report (the images `raylab render --heatmap --log` draws):
/// several accelerators on one scene, seen by one camera, on one log colour scale, so that the
/// images compare.
#include <string>
#include <vector>

#include "accel/common/accel_factory.h"
#include "rays/camera.h"
#include "tools/heatmap_image.h"

namespace raylab::experiments {

struct HeatmapImage {
  std::string accel;  ///< accelerator spec
  std::string file;   ///< PNG file name, written into the output directory
  double mean_cost = 0, max_cost = 0;  ///< nodes + leaves + primitive tests per pixel
};

/// Renders `images` (their accel and file set) of `scene` through `camera` at width × height and
/// fills in their mean and largest costs. With `shared_scale`, one colour scale runs from the least
/// to the largest cost of all the images, so that they compare; without, each image has its own,
/// from its least to its largest cost (for images whose costs lie decades apart, where a shared
/// scale paints one of them in a single colour).
inline void write_cost_heatmaps(const std::shared_ptr<const Scene>& scene, const Camera& camera, int width, int height,
                                const std::string& out_dir, std::vector<HeatmapImage>& images,
                                bool shared_scale = true) {
  const std::vector<Ray> rays = image_rays(camera, width, height);
  std::vector<std::vector<float>> costs;
  double top = 0, bottom = 1e300;
  for (auto& im : images) {
    const auto accel = make_accelerator(im.accel, scene);
    costs.push_back(traversal_cost_per_ray(*accel, rays, 0));
    double sum = 0, max = 0, min = 1e300;
    for (float c : costs.back()) sum += c, max = std::max<double>(max, c), min = std::min<double>(min, c);
    im.mean_cost = sum / static_cast<double>(rays.size());
    im.max_cost = max;
    top = std::max(top, max);
    bottom = std::min(bottom, min);
  }
  for (std::size_t i = 0; i < images.size(); ++i)
    write_heatmap_png(out_dir + "/" + images[i].file, costs[i], width, height,
                      "nodes + leaves + tests per pixel: " + images[i].accel, HeatmapScale::log,
                      shared_scale ? std::max(top, 1.0) : 0.0, shared_scale ? std::min(bottom, top) : -1.0);
}

}  // namespace raylab::experiments
