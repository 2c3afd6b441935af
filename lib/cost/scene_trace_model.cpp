#include "cost/scene_trace_model.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>

#include "geometry/input_error.h"

namespace raylab {

const std::vector<LinearTermDoc>& scene_trace_terms() {
  static const std::vector<LinearTermDoc> terms = {
      {"one", "1 (ns per ray at any size)", true},
      {"log2_n", "log2 N, N the primitives (a tree's depth)", true},
      {"log2_area_ratio", "log2 of largest / median triangle area (teapot in a stadium)", false},
      {"crossings", "total triangle area / scene box area (surfaces a line crosses)", false},
      {"log2_emptiness", "log2(1 + scene box area / total triangle area) (empty space)", false},
  };
  return terms;
}

FeatureRow scene_trace_features(const SceneFeatures& f) {
  return {{"one", 1.0},
          {"log2_n", std::log2(std::max(f.primitives, 1.0))},
          {"log2_area_ratio", std::log2(std::max(f.area_ratio, 1.0))},
          {"crossings", f.crossings},
          {"log2_emptiness", f.total_area > 0 ? std::log2(1.0 + f.box_area / f.total_area) : 0.0}};
}

SceneTraceModels fit_scene_trace_models(const std::vector<RunRecord>& runs, const SceneFeatureTable& features,
                                        const FitOptions& options,
                                        const std::function<void(const std::string&)>& progress) {
  auto features_of = [&](const std::string& scene) -> const SceneFeatures* {
    const auto it = features.find(scene);
    return it == features.end() || !it->second ? nullptr : &*it->second;
  };
  std::map<std::pair<std::string, std::string>, std::vector<const RunRecord*>> groups;
  for (const RunRecord& r : runs)
    if (features_of(r.scene) && r.ns_per_ray_min > 0) groups[{r.accel, ray_class_of(r.ray_kind)}].push_back(&r);
  // The (spec, class) fits are independent: fitted in parallel, reported in order.
  const std::vector<std::pair<std::pair<std::string, std::string>, std::vector<const RunRecord*>>> work(groups.begin(),
                                                                                                       groups.end());
  std::vector<std::optional<SelectedLinearModel>> fitted(work.size());
  std::vector<std::string> failures(work.size());
  tbb::parallel_for(std::size_t{0}, work.size(), [&](std::size_t g) {
    const std::vector<const RunRecord*>& rows = work[g].second;
    std::vector<FeatureRow> x;
    std::vector<double> y, primitives;
    std::vector<std::string> scenes;
    for (const RunRecord* r : rows) {
      x.push_back(scene_trace_features(*features_of(r->scene)));
      y.push_back(r->ns_per_ray_min);
      scenes.push_back(r->scene);
      primitives.push_back(static_cast<double>(r->primitives));
    }
    try {
      fitted[g] = fit_selected_linear_model(scene_trace_terms(), x, y, scenes, primitives, options);
    } catch (const InputError& e) {
      failures[g] = e.what();
    }
  });
  SceneTraceModels models;
  for (std::size_t g = 0; g < work.size(); ++g) {
    const auto& [spec, cls] = work[g].first;
    if (fitted[g]) models[spec][cls] = std::move(*fitted[g]);
    else if (progress) progress("scene-level model of " + spec + ", " + cls + " rays: not fitted (" + failures[g] + ")");
  }
  return models;
}

nlohmann::ordered_json scene_trace_models_json(const SceneTraceModels& models) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [spec, by_class] : models)
    for (const auto& [cls, m] : by_class) j[spec][cls] = selected_linear_model_json(m);
  return j;
}

SceneTraceModels read_scene_trace_models(const nlohmann::ordered_json& j, const std::string& where) {
  if (!j.is_object()) throw InputError(where + ": expected a JSON object of accelerator specs");
  SceneTraceModels models;
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!it.value().is_object()) throw InputError(where + "." + it.key() + ": expected a JSON object of ray classes");
    for (auto c = it.value().begin(); c != it.value().end(); ++c)
      models[it.key()][c.key()] =
          read_selected_linear_model(c.value(), where + "." + it.key() + "." + c.key(), scene_trace_terms());
  }
  return models;
}

}  // namespace raylab
