#pragma once
/// The build-time model: seconds to build a structure over N primitives,
///   build_s = a·N·log2 N + b·N [+ c],
/// fitted with Ceres (fit.h, relative residuals, Huber loss) per accelerator spec: per builder
/// and its parameters (the data set's `accel` column), since a spatial-split BVH and a binned one
/// of the same family differ tenfold. The sort-like term N·log2 N and the linear term are kept;
/// the constant c only when leave-one-scene-out cross-validation keeps it
/// (selected_linear_model.h, which also gives the held-out MAPE and the 90% interval).
///
/// Its rows: one per (scene, accel) of the data set, the build time measured once (sweep.h);
/// rows without a positive build time are left out.
#include <functional>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "cost/fit.h"
#include "cost/run_record.h"
#include "cost/selected_linear_model.h"

namespace raylab {

/// n_log2_n (N·log2 N, required), n (N, required), one (1).
const std::vector<LinearTermDoc>& build_time_terms();

/// The feature row of a scene of `primitives` primitives.
FeatureRow build_time_features(double primitives);

/// Build-time models by accelerator spec, as the data set spells it (accel_spec_key.h finds an
/// entry for another spelling).
using BuildTimeModels = std::map<std::string, SelectedLinearModel>;

/// Fits every accelerator spec of `runs` with rows of at least two scenes. `progress` gets a
/// line for each spec left out.
BuildTimeModels fit_build_time_models(const std::vector<RunRecord>& runs, const FitOptions& options,
                                      const std::function<void(const std::string&)>& progress = {});

/// model.json's `build` section: {SPEC: selected_linear_model_json, ...}.
nlohmann::ordered_json build_time_models_json(const BuildTimeModels& models);
BuildTimeModels read_build_time_models(const nlohmann::ordered_json& j, const std::string& where);

}  // namespace raylab
