#pragma once
/// `grid`: the lecture's uniform grid. Build: the scene's box, the resolution max(nx, ny, nz) =
/// d·∛n (grid_config.h), primitives placed in cells (grid_placement.h) and stored as CSR.
/// Traversal: the 3D-DDA of Amanatides and Woo 1987 (grid_traversal.h) with in-cell acceptance
/// and a per-ray mailbox (cell_intersector.h); with kernel=certified, the certified acceptance
/// of cell_intersector.h and, for a ray whose DDA could leave the placement margin
/// (dda_within_margin), the DDA from where it enters the grid (EntryRay, grid_geometry.h).
#include <cmath>
#include <limits>
#include <memory>

#include "accel/grid/cell_intersector.h"
#include "accel/grid/grid_config.h"
#include "accel/grid/grid_frame.h"
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

  /// The grid's geometry, in its frame (grid_frame.h): scene coordinates minus frame_origin().
  const GridGeometry& geometry() const { return grid_; }
  const Vec3f& frame_origin() const { return origin_; }
  /// The placement margin of the grid's cells (grid_margin of the scene in the frame).
  float margin() const { return margin_; }
  /// The cell lists; their references are local ids of triangles() when it is not empty.
  const CellLists& cells() const { return lists_; }
  const CellTriangles& triangles() const { return tris_; }
  const GridConfig& config() const { return config_; }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    if (config_.kernel == KernelChoice::certified)
      return config_.mailbox ? closest<CertifiedKernel, Counters, true>(ray, hit, counters)
                             : closest<CertifiedKernel, Counters, false>(ray, hit, counters);
    return config_.mailbox ? closest<WatertightKernel, Counters, true>(ray, hit, counters)
                           : closest<WatertightKernel, Counters, false>(ray, hit, counters);
  }

  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    if (config_.kernel == KernelChoice::certified)
      return config_.mailbox ? any<CertifiedKernel, Counters, true>(ray, counters)
                             : any<CertifiedKernel, Counters, false>(ray, counters);
    return config_.mailbox ? any<WatertightKernel, Counters, true>(ray, counters)
                           : any<WatertightKernel, Counters, false>(ray, counters);
  }

 private:
  template <class Kernel, class Counters, bool kMailbox>
  bool closest(Ray& ray, Hit& hit, Counters& counters) const {
    const Ray local = in_frame(ray, origin_);
    const Vec3f inv = safe_inverse(ray.dir);
    float t0 = 0.0f, t1 = 0.0f;
    const bool entered = intersect_box(grid_.box, local, inv, ray.tmin, initial_closest<Kernel>(ray), t0, t1);
    return closest_hit_in_grid<Kernel, Counters, kMailbox>(
        *scene_, tris_, ray, hit, GridQuery{local, entered, t0, t1, grid_.box, origin_, margin_}, config_.acceptance, extent_,
        counters, [&](auto& state, const Ray& r, float s0, float s1) { return walk(r, inv, s0, s1, state, counters); });
  }

  template <class Kernel, class Counters, bool kMailbox>
  bool any(const Ray& query, Counters& counters) const {
    const Ray ray = any_hit_ray<Kernel>(query);
    const Ray local = in_frame(ray, origin_);
    const Vec3f inv = safe_inverse(ray.dir);
    float t0 = 0.0f, t1 = 0.0f;
    const bool entered = intersect_box(grid_.box, local, inv, ray.tmin, initial_closest<Kernel>(ray), t0, t1);
    return any_hit_in_grid<Kernel, Counters, kMailbox>(
        *scene_, tris_, ray, GridQuery{local, entered, t0, t1, grid_.box, origin_, margin_}, counters,
        [&](auto& state, const Ray& r, float s0, float s1) { return walk(r, inv, s0, s1, state, counters); });
  }

  /// The 3D-DDA of `local` (a ray in the grid's frame) over [t0, t1], offering each non-empty
  /// cell to `state`; true when `state` stopped it.
  template <class State, class Counters>
  bool walk(const Ray& local, const Vec3f& inv, float t0, float t1, State& state, Counters& counters) const {
    const std::uint32_t* refs = lists_.refs.data();
    const std::uint32_t* offsets = lists_.offsets.data();
    return grid_dda(grid_, local.org, local.dir, inv, t0, t1, [&](std::uint32_t c, float enter, float exit) {
      counters.node();
      const std::uint32_t b = offsets[c], e = offsets[c + 1];
      return b != e && state.leaf(refs + b, refs + e, enter, exit);
    });
  }

  std::shared_ptr<const Scene> scene_;
  GridConfig config_;
  Bounds3f bounds_;
  Vec3f origin_{0.0f};  ///< the frame's origin (grid_frame.h); grid_ is in the frame
  GridGeometry grid_;
  float margin_ = 0.0f;  ///< the placement margin (grid_margin of the scene in the frame)
  float extent_ = 0.0f;  ///< sum of the grid's extents, the D of cell_widening
  CellLists lists_;
  CellTriangles tris_;
};

}  // namespace raylab
