#include "accel/nested_grid/nested_grid.h"

#include <numeric>
#include <string>

#include "accel/grid/grid_placement.h"
#include "accel/grid/grid_spec.h"
#include "geometry/input_error.h"

namespace raylab {

std::vector<ParamDoc> nested_grid_params() {
  std::vector<ParamDoc> p = {
      {"mode", "nested", "nested (refine crowded cells recursively) | two-level (Kalojanov et al. 2011)"},
      {"threshold", "64", "nested: refine cells with more primitives than this, in [1, 2^30]"},
      {"depth", "2", "nested: levels of refinement below the top grid, in [1, 8]"},
      {"top_d", "1", "two-level: density d of the top grid, in [0.01, 64]"},
      {"sub_d", "1.5", "density d of the refined grids (both modes), in [0.01, 64]"},
  };
  for (auto& q : grid_cell_params()) p.push_back(q);
  return p;
}

NestedGridConfig read_nested_grid_config(SpecReader& r) {
  NestedGridConfig c;
  c.cells = read_grid_config(r);
  c.mode = r.get_choice("mode", "nested", {"nested", "two-level"}) == "two-level" ? NestedGridMode::two_level
                                                                                   : NestedGridMode::nested;
  c.threshold = static_cast<int>(r.get_int("threshold", 64, 1, std::int64_t(1) << 30));
  c.depth = static_cast<int>(r.get_int("depth", 2, 1, 8));
  c.top_density = r.get_double("top_d", 1.0, 0.01, 64.0);
  c.sub_density = r.get_double("sub_d", 1.5, 0.01, 64.0);
  return c;
}

NestedGrid::NestedGrid(std::shared_ptr<const Scene> scene, const NestedGridConfig& config)
    : scene_(std::move(scene)), config_(config), bounds_(scene_->bounds()) {
  if (scene_->instanced()) throw InputError("nested-grid: scene '" + scene_->spec + "' is instanced twice over");
  const GridFrame frame = make_grid_frame(scene_);
  origin_ = frame.origin;
  const Scene& placed = *frame.scene;
  margin_ = grid_margin(placed.bounds());
  const Bounds3f box = widened(placed.bounds(), margin_);
  const Vec3f d = box.diagonal();
  extent_ = d.x + d.y + d.z;
  std::vector<std::uint32_t> all(scene_->primitive_count());
  std::iota(all.begin(), all.end(), 0u);
  std::vector<CellLists> lists;
  build_level(placed, all.data(), all.size(), box, 0, lists);
  // The leaf lists of every level gathered into one exactly sized array, each reference written
  // once (no reallocation while levels are built).
  std::size_t total = 0;
  for (const Cell& cell : cells_) total += cell.count == kChild ? 0 : cell.count;
  if (total > kChild - 1) throw InputError("nested-grid: cell references overflow 32-bit offsets; lower d or the depth");
  refs_.resize(total);
  std::size_t at = 0;
  for (std::size_t gi = 0; gi < levels_.size(); ++gi) {
    const Level& level = levels_[gi];
    const std::uint32_t* from = lists[gi].refs.data();
    for (std::size_t c = 0; c < level.geom.cell_count(); ++c) {
      Cell& cell = cells_[level.cell_base + c];
      if (cell.count == kChild) continue;
      std::copy_n(from + cell.begin, cell.count, refs_.data() + at);
      cell.begin = static_cast<std::uint32_t>(at);
      at += cell.count;
    }
    lists[gi] = {};
  }
  tris_ = renumber_cell_triangles(*scene_, refs_.data(), refs_.size());
}

std::uint32_t NestedGrid::build_level(const Scene& placed, const std::uint32_t* prims, std::size_t n,
                                      const Bounds3f& box, int level, std::vector<CellLists>& level_lists) {
  const bool two_level = config_.mode == NestedGridMode::two_level;
  const double density =
      level > 0 ? config_.sub_density : (two_level ? config_.top_density : config_.cells.density);
  const GridGeometry geom(box, grid_resolution(box, static_cast<double>(n), density, config_.cells.max_cells));
  if (level > 0 && static_cast<double>(cells_.size() + geom.cell_count()) > cell_budget_) return kChild;
  CellLists lists = place_primitives(placed, prims, n, geom, config_.cells.placement, margin_);
  if (level > 0) {
    // A refinement is futile when its cells see, on average, more than half of the parent cell's
    // primitives (long or crowded primitives spanning the whole cell): the caller keeps a leaf.
    std::size_t nonempty = 0;
    for (std::size_t c = 0; c < geom.cell_count(); ++c) nonempty += lists.count(c) != 0;
    if (2 * lists.refs.size() > n * nonempty) return kChild;
  }
  const auto gi = static_cast<std::uint32_t>(levels_.size());
  const std::size_t base = cells_.size();
  levels_.push_back({geom, base});
  level_lists.emplace_back();
  if (level == 0) {
    cell_budget_ = static_cast<double>(geom.cell_count()) + config_.cells_per_primitive_budget * double(n);
    cells_.reserve(static_cast<std::size_t>(cell_budget_));  // address space only: levels append without copying
  }
  cells_.resize(base + geom.cell_count());
  const int max_level = two_level ? 1 : config_.depth;
  const std::size_t refine_above = two_level ? 1 : static_cast<std::size_t>(config_.threshold);
  for (int k = 0; k < geom.res[2]; ++k)
    for (int j = 0; j < geom.res[1]; ++j)
      for (int i = 0; i < geom.res[0]; ++i) {
        const std::uint32_t c = geom.index(i, j, k);
        const std::uint32_t b = lists.offsets[c], cnt = lists.count(c);
        if (level < max_level && cnt > refine_above) {
          Bounds3f content;
          for (std::uint32_t r = b; r < b + cnt; ++r) content.extend(placed.primitive_bounds(lists.refs[r]));
          const Bounds3f child_box = widened(raylab::intersect(widened(geom.cell_box(i, j, k), margin_), content), margin_);
          const auto res = grid_resolution(child_box, cnt, config_.sub_density, config_.cells.max_cells);
          if (!child_box.empty() && std::size_t(res[0]) * res[1] * res[2] > 1) {
            const std::uint32_t child = build_level(placed, lists.refs.data() + b, cnt, child_box, level + 1, level_lists);
            if (child != kChild) {
              cells_[base + c] = {child, kChild};
              continue;
            }
          }
        }
        cells_[base + c] = {b, cnt};
      }
  level_lists[gi] = std::move(lists);
  return gi;
}

}  // namespace raylab
