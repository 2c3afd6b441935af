#pragma once
/// Features of a scene alone, from one O(N) pass over its triangles (no structure built): what
/// `auto` predicts each candidate's trace time from before it builds (scene_trace_model.h).
///
/// Besides the counts and the box, the surface-area statistics the structures' costs depend on:
///  - `crossings` = total triangle area / surface area of the scene box (of its vertices). By Cauchy–Crofton, a
///    random line meeting the box crosses on average 2·A/SA(box) surface (Santaló, "Integral
///    Geometry and Geometric Probability", 1976): this is half that, the depth complexity of
///    the scene seen by a line;
///  - `area_ratio` = largest / median triangle area: ≈ 1 for a uniform mesh, ≫ 1 for a
///    teapot in a stadium (Havran's "teapot in a stadium", the case uniform grids lose);
///  - spread_references(): how many cells of a grid of about N cells the triangles meet beyond
///    one each, what a spatial subdivision's build pays for (the build-time model's `spread`).
/// Spheres count in `primitives` but not in the area statistics (triangles only).
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace raylab {

struct SceneFeatures {
  double primitives = 0;     ///< triangles + spheres of the flat geometry
  double triangles = 0;      ///< of the flat geometry
  double total_area = 0;     ///< Σ triangle areas
  double median_area = 0;    ///< of the non-degenerate triangles of a sample (kMedianSample); 0 for none
  double max_area = 0;
  double box_area = 0;       ///< surface area of the bounds of the flat geometry
  double crossings = 0;      ///< total_area / box_area (0 for an empty box)
  double area_ratio = 1;     ///< max_area / median_area (1 when undefined)
  double sqrt_area_sum = 0;  ///< Σ √(triangle area)
  double largest_extent = 0; ///< the scene box's largest side
};

/// The cells beyond one per triangle that the triangles meet in a grid of cubic cells of side
/// h = largest_extent / ∛N (the lecture's resolution at density 1, grid_config.h): a convex
/// planar piece of area A and perimeter P, placed at random, meets on average
/// 1 + (3/4)·P/h + (3/2)·A/h² cells (Steiner's formula for the Minkowski sum with a cell, its
/// face and edge terms averaged over orientations; Cauchy: the mean projection of a planar convex
/// curve on a random axis is P/4, of a unit normal's component 1/2). P is taken as an equilateral
/// triangle's, √(12√3·A) ≈ 4.56·√A, so that one pass needs one square root per triangle; thin
/// triangles (the equilateral's is the least perimeter for an area) then count for fewer cells than
/// they meet. N + this is within 0.75–1.25 of the references grid:d=1 places on a sphere, a soup
/// and a sphereflake (test_build_time_model.cpp). 0 for a scene without triangles or extent.
double spread_references(const SceneFeatures& f);

/// Features by scene spec, as a fit's rows name their scenes: nullopt for a scene that cannot be
/// loaded here or is instanced (its features are those of its flat part alone).
using SceneFeatureTable = std::map<std::string, std::optional<SceneFeatures>>;

/// Loads each of `scene_specs` once and computes its features; `progress` gets a line for each
/// scene left out.
SceneFeatureTable load_scene_features(const std::vector<std::string>& scene_specs,
                                      const std::function<void(const std::string&)>& progress = {});

/// Triangles the median area is taken over: every ⌊N/kMedianSample⌋-th one (all of a smaller scene),
/// 1,024 to 2,047 of them: the selection over every triangle of a 16k-triangle mesh took as long as
/// the area pass, and a strided sample of 1,024 puts the median within a few per cent, which moves
/// log2(area_ratio), the feature the models read, by a few hundredths.
inline constexpr std::size_t kMedianSample = 1024;

/// The features of `scene`'s flat geometry (instances are not followed: `auto` calls this per
/// part, on bases and the flat part apart). One O(N) pass (single-precision
/// areas summed in double), in parallel over fixed chunks whose sums are added in chunk order, so
/// the result does not depend on the thread count; the median by selection in the sample.
SceneFeatures scene_features(const Scene& scene);

}  // namespace raylab
