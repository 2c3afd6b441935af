#pragma once
/// The build-time model: seconds to build a structure over N primitives,
///   build_s = a·N·log2 N + b·N [+ c] [+ e·spread],
/// fitted with Ceres (fit.h; residuals as selected_linear_model.h says) per accelerator spec: per builder
/// and its parameters (the data set's `accel` column), since a spatial-split BVH and a binned one
/// of the same family differ tenfold. The sort-like term N·log2 N and the linear term are kept;
/// the constant c and the spread (scene_features.h: spread_references, the cells beyond one per
/// triangle that a grid of N cells meets, which a grid, an octree or a spatial split clips and
/// stores) only when leave-one-scene-out cross-validation keeps them (selected_linear_model.h,
/// which also gives the held-out MAPE and the 90% interval). Both are read before any build, from
/// one pass over the scene, as `auto` needs.
///
/// Its rows: one per (scene, accel) of the data set, the build time the fastest of the sweep's
/// passes (sweep.h); rows without a positive build time are left out.
#include <functional>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "cost/fit.h"
#include "cost/run_record.h"
#include "cost/scene_features.h"
#include "cost/selected_linear_model.h"

namespace raylab {

/// n_log2_n (N·log2 N, required), n (N, required), one (1), spread.
const std::vector<LinearTermDoc>& build_time_terms();

/// The feature row of a scene (N its `primitives`; a SceneFeatures with only a count gives
/// spread 0).
FeatureRow build_time_features(const SceneFeatures& scene);

/// Build-time models by accelerator spec, as the data set spells it (accel_spec_key.h finds an
/// entry for another spelling).
using BuildTimeModels = std::map<std::string, SelectedLinearModel>;

/// Fits every accelerator spec of `runs` with rows of at least two scenes; the spread term is a
/// candidate for a spec when every scene of its rows has features in `features`. `progress` gets
/// a line for each spec left out, or fitted without the spread.
BuildTimeModels fit_build_time_models(const std::vector<RunRecord>& runs, const SceneFeatureTable& features,
                                      const FitOptions& options,
                                      const std::function<void(const std::string&)>& progress = {});

/// model.json's `build` section: {SPEC: selected_linear_model_json, ...}.
nlohmann::ordered_json build_time_models_json(const BuildTimeModels& models);
BuildTimeModels read_build_time_models(const nlohmann::ordered_json& j, const std::string& where);

}  // namespace raylab
