#pragma once
/// The `cost=MODEL` parameter of the SAH builders (kd-tree, BVH, octree, BSP): split and
/// termination constants taken from a fitted cost model (lib/cost, model_file.h) instead of
/// c_trav/c_isect. MODEL is a model file's path, or `default` for the model committed with the lab.
///
/// lib/accel sits below lib/cost and reads no model file. Reading a spec, `cost=` becomes a
/// FittedCostRequest; building, the request is resolved into plain numbers through the
/// BuildContext the caller hands down (make_accelerator, accel_factory.h; lib/cost's
/// model_build_context() reads the model and checks the scene against its fitted range). The
/// builders see only the numbers (SahCost). A context without a resolver makes `cost=` an
/// InputError.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "geometry/input_error.h"
#include "geometry/spec_string.h"

namespace raylab {

/// SAH constants in nanoseconds per event, for one structure family.
struct FittedSahCost {
  double c_trav = 0.0;   ///< per interior node visited
  double c_leaf = 0.0;   ///< per non-empty leaf visited, beyond its tests
  double c_isect = 0.0;  ///< per primitive test
};

/// A spec's `cost=MODEL`, for the structure family `family` (tree_features.h: structure_family).
struct FittedCostRequest {
  std::string model;   ///< as the spec gives it: a model file's path, or `default`
  std::string family;
};

/// What a build needs from above lib/accel.
struct BuildContext {
  /// The constants of `request.family` in `request.model`, for a scene of `primitives`
  /// primitives; throws InputError for a model that cannot be read or lacks the family.
  std::function<FittedSahCost(const FittedCostRequest& request, double primitives)> fitted_costs;
};

/// The documentation line of `cost=`, for the builders' parameter lists.
ParamDoc fitted_cost_param();

/// When the spec has `cost=`, its request for `family` (and the spec must not also set any of
/// `manual_keys`, e.g. c_trav and c_isect: InputError); otherwise nothing.
std::optional<FittedCostRequest> read_fitted_cost(SpecReader& reader, const std::string& family,
                                                  const std::vector<std::string>& manual_keys);

/// Fills `cost` (SahCost or BvhSahCost) from c_trav and c_isect with the given defaults, and
/// returns the spec's `cost=` request when it has one (the constants stay at their defaults
/// until apply_fitted_cost).
template <class Cost>
std::optional<FittedCostRequest> read_sah_constants(SpecReader& reader, const std::string& family,
                                                    double default_trav, double default_isect, Cost& cost) {
  std::optional<FittedCostRequest> request = read_fitted_cost(reader, family, {"c_trav", "c_isect"});
  cost.c_trav = request ? default_trav : reader.get_double("c_trav", default_trav, 1e-6, 1e6);
  cost.c_isect = request ? default_isect : reader.get_double("c_isect", default_isect, 1e-6, 1e6);
  return request;
}

/// Resolves `request` through `context` into `cost` for a scene of `primitives` primitives:
/// c_trav, c_isect and, where the cost type has one, c_leaf. Nothing to do without a request;
/// InputError when the context cannot resolve one.
template <class Cost>
void apply_fitted_cost(const std::optional<FittedCostRequest>& request, const BuildContext& context,
                       double primitives, Cost& cost) {
  if (!request) return;
  if (!context.fitted_costs)
    throw InputError("cost=" + request->model + ": this program reads no cost models (no build context resolves cost=)");
  const FittedSahCost f = context.fitted_costs(*request, primitives);
  cost.c_trav = f.c_trav;
  cost.c_isect = f.c_isect;
  if constexpr (requires { cost.c_leaf; }) cost.c_leaf = f.c_leaf;
}

}  // namespace raylab
