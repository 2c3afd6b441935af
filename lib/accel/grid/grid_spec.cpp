#include "accel/grid/grid_spec.h"

#include "geometry/input_error.h"

namespace raylab {

std::vector<ParamDoc> grid_cell_params() {
  return {
      {"d", "3", "density: max(nx, ny, nz) = d·∛n (the lecture's heuristic, d ≈ 3), in [0.01, 64]"},
      {"place", "clipped",
       "placement: bbox (cells the bounding box overlaps) | exact (cells the primitive meets, CGAL) | clipped (the "
       "triangle clipped to each row of cells, float; spheres by bbox)"},
      {"accept", "in-cell", "in-cell (hit must lie in the cell's t-interval) | first (the lecture's mistake)"},
      {"mailbox", "on", "per-ray mailbox: on | off"},
      {"max_cells", "134217728", "cap on the cells of one grid (d is lowered to meet it), in [1, 2^30]"},
      kernel_param_doc("certified (accept=in-cell), watertight (accept=first)"),
  };
}

GridConfig read_grid_config(SpecReader& r) {
  GridConfig c;
  c.density = r.get_double("d", 3.0, 0.01, 64.0);
  const std::string place = r.get_choice("place", "clipped", {"bbox", "exact", "clipped"});
  c.placement = place == "exact" ? GridPlacement::exact : (place == "clipped" ? GridPlacement::clipped : GridPlacement::bbox);
  c.acceptance =
      r.get_choice("accept", "in-cell", {"in-cell", "first"}) == "first" ? GridAcceptance::first : GridAcceptance::in_cell;
  c.mailbox = r.get_bool("mailbox", true);
  c.max_cells = r.get_int("max_cells", std::int64_t(1) << 27, 1, std::int64_t(1) << 30);
  c.kernel = read_kernel_choice(
      r, c.acceptance == GridAcceptance::first ? KernelChoice::watertight : KernelChoice::certified);
  if (c.kernel == KernelChoice::certified && c.acceptance == GridAcceptance::first)
    throw InputError("accelerator '" + r.spec().text + "': kernel=certified needs in-cell acceptance (accept=in-cell)");
  return c;
}

AccuracyBound grid_accuracy(const GridConfig& c) {
  if (c.acceptance == GridAcceptance::first) {
    AccuracyBound b = float_accuracy(1.0, 1.0,
                                     "accept=first is the lecture's mistake: a hit found in a cell may lie beyond it, "
                                     "behind a closer hit in a later cell; no agreement is claimed");
    b.kernel = "watertight";  // the only kernel accept=first allows
    return b;
  }
  return kernel_accuracy(c.kernel, "in-cell acceptance");
}

}  // namespace raylab
