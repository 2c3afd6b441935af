#pragma once
/// The `cost=MODEL` parameter of the SAH builders (kd-tree, BVH, octree, BSP): split and
/// termination constants taken from a fitted cost model (lib/cost, model_file.h) instead of
/// c_trav/c_isect. MODEL is a model file's path, or `default` for the model committed with the lab.
///
/// lib/accel sits below lib/cost, so it reads model files through a loader that lib/cost
/// registers at static-initialisation time (set_fitted_cost_loader); without one (a program
/// linked without lib/cost), `cost=` is an InputError.
#include <string>
#include <vector>

#include "geometry/spec_string.h"

namespace raylab {

/// SAH constants in nanoseconds per event, for one structure family.
struct FittedSahCost {
  double c_trav = 0.0;   ///< per interior node visited
  double c_leaf = 0.0;   ///< per non-empty leaf visited, beyond its tests
  double c_isect = 0.0;  ///< per primitive test
};

/// Reads the constants for `family` (tree_features.h: structure_family) from the model at `path`
/// (or `default`); throws InputError naming the file and the missing family.
using FittedCostLoader = FittedSahCost (*)(const std::string& path, const std::string& family);

void set_fitted_cost_loader(FittedCostLoader loader);

/// The documentation line of `cost=`, for the builders' parameter lists.
ParamDoc fitted_cost_param();

/// When the spec has `cost=`, the fitted constants for `family` (and the spec must not also set
/// any of `manual_keys`, e.g. c_trav and c_isect: InputError); otherwise false.
bool read_fitted_cost(SpecReader& reader, const std::string& family, const std::vector<std::string>& manual_keys,
                      FittedSahCost& out);

/// Fills `cost` (SahCost or BvhSahCost) from `cost=` when given, else from c_trav and c_isect
/// with the given defaults. C_leaf is taken where the cost type has one.
template <class Cost>
void read_sah_constants(SpecReader& reader, const std::string& family, double default_trav, double default_isect,
                        Cost& cost) {
  if (FittedSahCost f; read_fitted_cost(reader, family, {"c_trav", "c_isect"}, f)) {
    cost.c_trav = f.c_trav;
    cost.c_isect = f.c_isect;
    if constexpr (requires { cost.c_leaf; }) cost.c_leaf = f.c_leaf;
    return;
  }
  cost.c_trav = reader.get_double("c_trav", default_trav, 1e-6, 1e6);
  cost.c_isect = reader.get_double("c_isect", default_isect, 1e-6, 1e6);
}

}  // namespace raylab
