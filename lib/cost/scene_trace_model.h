#pragma once
/// The scene-level trace model: nanoseconds per ray of one accelerator spec on one ray class,
/// predicted from the scene alone (scene_features.h), before any structure is built: what `auto`
/// weighs against the predicted build time (auto_accel.h). Its candidate terms:
///   ns/ray = c0 + c1·log2 N [+ c2·log2(area_ratio)] [+ c3·crossings] [+ c4·log2(1 + 1/crossings)],
/// c0, c1 kept (a tree's depth grows as log N), the others (the spread of triangle sizes, the
/// scene's depth complexity and its emptiness) only where leave-one-scene-out cross-validation
/// keeps them (selected_linear_model.h). Fitted with Ceres per accelerator spec and ray class
/// (run_record.h: ray_class_of) on the data set's rows, to the fit's target time (model_fit.h).
///
/// The data set has no scene-feature columns: the fit takes each scene's features from a table
/// (load_scene_features: each scene of the rows loaded once, by its spec). Rows whose scene has
/// none there (it cannot be loaded here, or is instanced) are left out.
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

/// one, log2_n (required), log2_area_ratio, crossings, log2_emptiness.
const std::vector<LinearTermDoc>& scene_trace_terms();

FeatureRow scene_trace_features(const SceneFeatures& f);

/// Models by accelerator spec (as the data set spells it), then by ray class.
using SceneTraceModels = std::map<std::string, std::map<std::string, SelectedLinearModel>>;

/// Fits every (spec, ray class) of `runs` with rows of at least two scenes in `features`.
SceneTraceModels fit_scene_trace_models(const std::vector<RunRecord>& runs, const SceneFeatureTable& features,
                                        const FitOptions& options,
                                        const std::function<void(const std::string&)>& progress = {});

/// model.json's `scene_trace` section: {SPEC: {CLASS: selected_linear_model_json}}.
nlohmann::ordered_json scene_trace_models_json(const SceneTraceModels& models);
SceneTraceModels read_scene_trace_models(const nlohmann::ordered_json& j, const std::string& where);

}  // namespace raylab
