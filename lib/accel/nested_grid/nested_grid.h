#pragma once
/// `nested-grid`: grids in the cells of grids (the lecture's answer to the teapot in the stadium),
/// or the two-level grid of Kalojanov, Billeter and Slusallek 2011 (nested_grid_config.h).
/// Every level is a regular grid traversed by the 3D-DDA of Amanatides and Woo 1987; a refined
/// cell hands its clipped t-interval to its child grid, so the leaf cells' t-intervals still
/// partition the ray and in-cell acceptance and the mailbox work as in the uniform grid.
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "accel/grid/cell_intersector.h"
#include "accel/grid/grid_frame.h"
#include "accel/grid/grid_placement.h"
#include "accel/grid/grid_geometry.h"
#include "accel/grid/grid_traversal.h"
#include "accel/nested_grid/nested_grid_config.h"
#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

class NestedGrid final : public AggregateBase<NestedGrid> {
 public:
  /// Builds over `scene`, which must not be instanced and must not be empty.
  NestedGrid(std::shared_ptr<const Scene> scene, const NestedGridConfig& config);

  std::string name() const override { return "nested-grid"; }
  /// bytes: levels, cells, the index array and the copied triangles; nodes: cells over all levels.
  AccelStats stats() const override {
    return {levels_.size() * sizeof(Level) + cells_.size() * sizeof(Cell) + refs_.size() * sizeof(std::uint32_t) +
                tris_.bytes(),
            cells_.size(), -1.0};
  }
  Bounds3f bounds() const override { return bounds_; }
  std::size_t level_count() const { return levels_.size(); }
  const Vec3f& frame_origin() const { return origin_; }

  /// Calls f(box, count, refined) for every cell of every level: its box in the grid's frame
  /// (grid_frame.h: scene coordinates minus frame_origin()), its primitive count (0 for a refined
  /// cell) and whether a grid of the next level refines it.
  template <class F>
  void for_each_cell(F&& f) const {
    for (const Level& level : levels_)
      for (int k = 0; k < level.geom.res[2]; ++k)
        for (int j = 0; j < level.geom.res[1]; ++j)
          for (int i = 0; i < level.geom.res[0]; ++i) {
            const Cell cell = cells_[level.cell_base + level.geom.index(i, j, k)];
            const bool refined = cell.count == kChild;
            f(level.geom.cell_box(i, j, k), refined ? 0u : cell.count, refined);
          }
  }

  template <class Counters>
  bool intersect_impl(Ray& ray, Hit& hit, Counters& counters) const {
    if (config_.cells.kernel == KernelChoice::certified)
      return config_.cells.mailbox ? closest<CertifiedKernel, Counters, true>(ray, hit, counters)
                                   : closest<CertifiedKernel, Counters, false>(ray, hit, counters);
    return config_.cells.mailbox ? closest<WatertightKernel, Counters, true>(ray, hit, counters)
                                 : closest<WatertightKernel, Counters, false>(ray, hit, counters);
  }
  template <class Counters>
  bool occluded_impl(const Ray& ray, Counters& counters) const {
    if (config_.cells.kernel == KernelChoice::certified)
      return config_.cells.mailbox ? any<CertifiedKernel, Counters, true>(ray, counters)
                                   : any<CertifiedKernel, Counters, false>(ray, counters);
    return config_.cells.mailbox ? any<WatertightKernel, Counters, true>(ray, counters)
                                 : any<WatertightKernel, Counters, false>(ray, counters);
  }

 private:
  static constexpr std::uint32_t kChild = 0xffffffffu;
  /// A leaf cell holds refs_[begin, begin + count); a refined cell has count == kChild and
  /// begin = the index of its grid in levels_.
  struct Cell {
    std::uint32_t begin = 0, count = 0;
  };
  struct Level {
    GridGeometry geom;
    std::size_t cell_base = 0;
  };

  /// Builds the grid of one level over `prims` of `placed` (the scene in the grid's frame) in
  /// `box` and returns its index in levels_, or kChild when a refinement (level > 0) would be
  /// futile. The level's cell lists go to lists[index], and a leaf cell's begin indexes them until
  /// the build gathers them into refs_.
  std::uint32_t build_level(const Scene& placed, const std::uint32_t* prims, std::size_t n, const Bounds3f& box,
                            int level, std::vector<CellLists>& lists);

  /// The 3D-DDA of `local` (a ray in the grid's frame) through level gi over [t0, t1].
  template <class Counters, class State>
  bool traverse(std::uint32_t gi, const Ray& local, const Vec3f& inv, float t0, float t1, State& state,
                Counters& counters) const {
    const Level& L = levels_[gi];
    return grid_dda(L.geom, local.org, local.dir, inv, t0, t1, [&](std::uint32_t c, float enter, float exit) {
      counters.node();
      const Cell cell = cells_[L.cell_base + c];
      if (cell.count == kChild) {
        float c0, c1;
        if (!intersect_box(levels_[cell.begin].geom.box, local, inv, enter, exit, c0, c1)) return false;
        return traverse(cell.begin, local, inv, c0, c1, state, counters);
      }
      return cell.count != 0 && state.leaf(refs_.data() + cell.begin, refs_.data() + cell.begin + cell.count, enter, exit);
    });
  }

  template <class Kernel, class Counters, bool kMailbox>
  bool closest(Ray& ray, Hit& hit, Counters& counters) const {
    const Ray local = in_frame(ray, origin_);
    const Vec3f inv = safe_inverse(ray.dir);
    const Bounds3f& box = levels_[0].geom.box;
    float t0 = 0.0f, t1 = 0.0f;
    const bool entered = intersect_box(box, local, inv, ray.tmin, initial_closest<Kernel>(ray), t0, t1);
    return closest_hit_in_grid<Kernel, Counters, kMailbox>(
        *scene_, tris_, ray, hit, GridQuery{local, entered, t0, t1, box, origin_, margin_}, config_.cells.acceptance, extent_,
        counters,
        [&](auto& state, const Ray& r, float s0, float s1) { return traverse(0, r, inv, s0, s1, state, counters); });
  }

  template <class Kernel, class Counters, bool kMailbox>
  bool any(const Ray& query, Counters& counters) const {
    const Ray ray = any_hit_ray<Kernel>(query);
    const Ray local = in_frame(ray, origin_);
    const Vec3f inv = safe_inverse(ray.dir);
    const Bounds3f& box = levels_[0].geom.box;
    float t0 = 0.0f, t1 = 0.0f;
    const bool entered = intersect_box(box, local, inv, ray.tmin, initial_closest<Kernel>(ray), t0, t1);
    return any_hit_in_grid<Kernel, Counters, kMailbox>(
        *scene_, tris_, ray, GridQuery{local, entered, t0, t1, box, origin_, margin_}, counters,
        [&](auto& state, const Ray& r, float s0, float s1) { return traverse(0, r, inv, s0, s1, state, counters); });
  }

  std::shared_ptr<const Scene> scene_;
  NestedGridConfig config_;
  Bounds3f bounds_;
  Vec3f origin_{0.0f};  ///< the frame's origin (grid_frame.h); every level's geometry is in the frame
  float margin_ = 0.0f;  ///< the placement margin (grid_margin of the scene in the frame)
  float extent_ = 0.0f;
  double cell_budget_ = 0.0;   ///< see NestedGridConfig::cells_per_primitive_budget
  std::vector<Level> levels_;  ///< levels_[0] is the top grid
  std::vector<Cell> cells_;
  BuildArray<std::uint32_t> refs_;  ///< local ids of tris_ (primitive ids when tris_ is empty)
  CellTriangles tris_;
};

}  // namespace raylab
