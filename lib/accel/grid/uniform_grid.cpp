#include "accel/grid/uniform_grid.h"

#include "accel/common/structure_hash.h"
#include "geometry/input_error.h"

namespace raylab {

UniformGrid::UniformGrid(std::shared_ptr<const Scene> scene, const GridConfig& config)
    : scene_(std::move(scene)), config_(config), bounds_(scene_->bounds()) {
  if (scene_->instanced()) throw InputError("grid: scene '" + scene_->spec + "' is instanced twice over");
  const GridFrame frame = make_grid_frame(scene_);
  origin_ = frame.origin;
  const Scene& placed = *frame.scene;
  const float margin = grid_margin(placed.bounds());
  margin_ = margin;
  const Bounds3f box = widened(placed.bounds(), margin);
  grid_ = GridGeometry(box, grid_resolution(box, static_cast<double>(scene_->primitive_count()), config_.density,
                                            config_.max_cells));
  const Vec3f d = box.diagonal();
  extent_ = d.x + d.y + d.z;
  const bool triangles_only = scene_->spheres.empty();
  lists_ = place_all_primitives(placed, grid_, config_.placement, margin,
                                triangles_only ? CellRefIds::visit_order : CellRefIds::primitive);
  tris_ = std::move(lists_.triangles);
  to_world(tris_, origin_);
}

std::optional<std::uint64_t> UniformGrid::structure_hash() const { return fnv1a(lists_.refs, fnv1a(lists_.offsets)); }

}  // namespace raylab
