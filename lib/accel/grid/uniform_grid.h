#pragma once
/// `grid`: the lecture's uniform grid. Build: the scene's box, the resolution max(nx, ny, nz) =
/// d·∛n (grid_config.h), primitives placed in cells (grid_placement.h) and stored as CSR.
/// Traversal: the 3D-DDA of Amanatides and Woo 1987 (grid_traversal.h) with in-cell acceptance
/// and a per-ray mailbox (cell_intersector.h).
#include <cmath>
#include <limits>
#include <memory>

#include "accel/grid/cell_intersector.h"
#include "accel/grid/grid_config.h"
#include "accel/grid/grid_geometry.h"
#include "accel/grid/grid_placement.h"
#include "accel/grid/grid_traversal.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

class UniformGrid final : public AggregateBase<UniformGrid> {
 public:
  /// Builds the grid over `scene`, which must not be instanced and must not be empty.
  UniformGrid(std::shared_ptr<const Scene> scene, const GridConfig& config);

  std::string name() const override { return "grid"; }
  /// bytes: the offsets, the index array and the copied triangles; nodes: cells.
  AccelStats stats() const override { return {lists_.bytes() + tris_.bytes(), grid_.cell_count(), -1.0}; }
  std::optional<std::uint64_t> structure_hash() const override;
  Bounds3f bounds() const override { return bounds_; }

  const GridGeometry& geometry() const { return grid_; }
  /// The cell lists; their references are local ids of triangles() when it is not empty.
  const CellLists& cells() const { return lists_; }
  const CellTriangles& triangles() const { return tris_; }
  const GridConfig& config() const { return config_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    return config_.mailbox ? closest<Counters, true>(ray, hit, counters) : closest<Counters, false>(ray, hit, counters);
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    return config_.mailbox ? any<Counters, true>(ray, counters) : any<Counters, false>(ray, counters);
  }

 private:
  template <class Counters, bool kMailbox>
  bool closest(Ray& ray, Hit& hit, Counters& counters) const {
    const Vec3f inv = safe_inverse(ray.dir);
    float t0, t1;
    if (!intersect_box(grid_.box, ray, inv, ray.tmin, ray.tmax, t0, t1)) return false;
    ClosestHitInCells<Counters, kMailbox> state(*scene_, tris_, ray, config_.acceptance, cell_widening(ray, extent_), counters);
    const std::uint32_t* refs = lists_.refs.data();
    const std::uint32_t* offsets = lists_.offsets.data();
    grid_dda(grid_, ray.org, ray.dir, inv, t0, t1, [&](std::uint32_t c, float enter, float exit) {
      counters.node();
      const std::uint32_t b = offsets[c], e = offsets[c + 1];
      return b != e && state.leaf(refs + b, refs + e, enter, exit);
    });
    if (!state.found) return false;
    hit = state.hit;
    ray.tmax = hit.t;
    return true;
  }

  template <class Counters, bool kMailbox>
  bool any(const Ray& ray, Counters& counters) const {
    const Ray closed = closed_for_any_hit(ray);
    const Vec3f inv = safe_inverse(ray.dir);
    float t0, t1;
    if (!intersect_box(grid_.box, closed, inv, closed.tmin, closed.tmax, t0, t1)) return false;
    AnyHitInCells<Counters, kMailbox> state(*scene_, tris_, closed, counters);
    const std::uint32_t* refs = lists_.refs.data();
    const std::uint32_t* offsets = lists_.offsets.data();
    return grid_dda(grid_, ray.org, ray.dir, inv, t0, t1, [&](std::uint32_t c, float enter, float exit) {
      counters.node();
      const std::uint32_t b = offsets[c], e = offsets[c + 1];
      return b != e && state.leaf(refs + b, refs + e, enter, exit);
    });
  }

  std::shared_ptr<const Scene> scene_;
  GridConfig config_;
  Bounds3f bounds_;
  GridGeometry grid_;
  float extent_ = 0.0f;  ///< sum of the grid's extents, the D of cell_widening
  CellLists lists_;
  CellTriangles tris_;
};

}  // namespace raylab
