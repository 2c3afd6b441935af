#pragma once
/// The `grid:key=value,...` parameters (accel_factory.h), shared with `nested-grid`.
#include <vector>

#include "accel/common/accel_factory.h"
#include "accel/grid/grid_config.h"

namespace raylab {

/// d, place, accept, mailbox, max_cells with their defaults.
std::vector<ParamDoc> grid_cell_params();

/// Reads the parameters of grid_cell_params() (InputError on bad values).
GridConfig read_grid_config(SpecReader& reader);

/// In-cell acceptance agrees with the oracle as brute force with the same kernel does;
/// accept=first is the lecture's mistake and claims nothing.
AccuracyBound grid_accuracy(const GridConfig& config);

}  // namespace raylab
