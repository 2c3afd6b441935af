#pragma once
/// The SAH builders behind build_bvh_over_boxes and build_bvh (internal; bvh_build.h is the
/// public interface). Every builder keeps leaves at depth <= kBvhMaxDepth by switching to median
/// splits at depth kBvhMaxDepth - 32, and gives the same tree with any thread count.
#include <vector>

#include "accel/bvh/bvh_config.h"
#include "accel/bvh/bvh_node.h"
#include "scene/scene.h"

namespace raylab {

/// Full-sweep SAH (bvh_sweep_sah.cpp), serial.
Bvh2 build_bvh_sweep_sah(const std::vector<Bounds3f>& boxes, const BvhConfig& config);

/// Binned SAH, parallel with TBB in an arena of config.threads (bvh_binned_sah.cpp), over
/// `boxes` or over the primitives of `scene` (not instanced; no box array in between).
Bvh2 build_bvh_binned_sah(const std::vector<Bounds3f>& boxes, const BvhConfig& config);
Bvh2 build_bvh_binned_sah(const Scene& scene, const BvhConfig& config);

/// SBVH: binned object splits and binned spatial splits with exact clipping and reference
/// unsplitting (bvh_spatial_split.cpp). `scene` must not be instanced.
Bvh2 build_bvh_spatial(const Scene& scene, const BvhConfig& config);

}  // namespace raylab
