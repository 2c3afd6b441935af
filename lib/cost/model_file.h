#pragma once
/// The versioned JSON of a fitted cost model (`raylab fit --out model.json`), read by `raylab
/// predict`, by the builders' `cost=` (fitted_cost.h) and by the `auto` accelerator. The format
/// is documented in docs/cost_model.md; its top level is
///
///   {"format": "raylab-cost-model", "version": 2, "created": ..., "data": {...}, "fit": {...},
///    "families": {"kdtree": {"counters": {...}, "tree": {...}, "builder": {...}, "ranges": {...},
///                            "replicate_error": ..., "replicate_groups": ...}, ...}}
///
/// Version 2 added what the 90% intervals need (cost_model.h): each level's "covariance" (k×k or
/// null), "residual_log_sigma" and "held_out.coverage90", and each family's "replicate_error" and
/// "replicate_groups". Version-1 files are still read: they have no covariance, coverage or
/// replicate error, and their residual spread is estimated from the stored MAPE (s ≈ MAPE·√(π/2)).
/// A file of another format or version, a missing key, or a non-finite value is an InputError
/// naming the file and the key.
#include <memory>
#include <string>

#include "cost/model_fit.h"

namespace raylab {

/// Writes `set` to `path` atomically (a temporary file renamed over it), so that a failed write
/// leaves no partial model behind.
void write_model_file(const CostModelSet& set, const std::string& path);

/// Reads and validates a model file; `default` names default_model_path().
CostModelSet read_model_file(const std::string& path);

/// The one way the builders' `cost=`, `auto` and `predict` read a model: read_model_file once per
/// process for each resolved path, size and modification time (a file rewritten since is read
/// again). Safe to call from several threads.
std::shared_ptr<const CostModelSet> load_model_file(const std::string& path);

/// The model committed with the lab (data/cost/default_model.json), which `./lab report` refits.
std::string default_model_path();

/// `path`, with `default` resolved to default_model_path().
std::string resolve_model_path(const std::string& path);

/// The SAH constants for `family` from the model at `path`; throws InputError when the family is
/// missing or its constants are not positive. The file is read by load_model_file.
FittedSahCost load_builder_costs(const std::string& path, const std::string& family);

/// The build context that resolves the builders' `cost=MODEL` (fitted_cost.h) with
/// load_builder_costs, for the tool, the sweeps, `auto` and the experiments to hand to
/// make_accelerator. With `warn_outside_range`, a scene outside the family's fitted range of
/// primitives gets one warning on stderr per model and family (the model's own range check,
/// model_fit.h), and the constants; without it (a probe build) the range is not checked.
BuildContext model_build_context(bool warn_outside_range = true);

}  // namespace raylab
