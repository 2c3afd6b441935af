#pragma once
/// Parameters of the nested grid (`nested-grid`).
#include <vector>

#include "accel/common/accel_factory.h"
#include "accel/grid/grid_config.h"

namespace raylab {

enum class NestedGridMode {
  /// The lecture's nested grid: a cell holding more than `threshold` primitives gets a grid of its
  /// own, with the lecture's heuristic at density `sub_d` applied to its primitives, recursively
  /// up to `depth` levels below the top.
  nested,
  /// The two-level grid of Kalojanov, Billeter and Slusallek ("Two-Level Grids for Ray Tracing on
  /// GPUs", Eurographics 2011): a coarse top grid (density `top_d`) in which every cell holding at
  /// least two primitives gets a grid whose resolution follows its own primitive count
  /// (max axis sub_d·∛n_cell); exactly two levels, no threshold.
  two_level,
};

struct NestedGridConfig {
  GridConfig cells;  ///< d, placement, acceptance, mailbox, max_cells of every level
  NestedGridMode mode = NestedGridMode::nested;
  int threshold = 64;        ///< nested: refine cells with more primitives than this
  int depth = 2;             ///< nested: levels of refinement below the top grid
  double top_density = 1.0;  ///< two-level: d of the top grid (Kalojanov et al. keep the top level coarse)
  /// Density of the refined grids. Lower than the top's d: a refined cell's grid costs d³ cells
  /// per primitive in it, and Kalojanov et al. find about one cell per primitive best.
  double sub_density = 1.5;
  /// Refinement stops once the cells of all levels would exceed the top grid's cells plus this
  /// many per primitive (memory budget; refinement is also skipped where futile, see nested_grid.cpp).
  double cells_per_primitive_budget = 8.0;
};

std::vector<ParamDoc> nested_grid_params();
/// Reads nested_grid_params() (InputError on bad values).
NestedGridConfig read_nested_grid_config(SpecReader& reader);

}  // namespace raylab
