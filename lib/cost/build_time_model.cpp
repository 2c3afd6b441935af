#include "cost/build_time_model.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "geometry/input_error.h"

namespace raylab {

const std::vector<LinearTermDoc>& build_time_terms() {
  static const std::vector<LinearTermDoc> terms = {
      {"n_log2_n", "N·log2 N, N the primitives (a sort, or a top-down build of log N levels)", true},
      {"n", "N (a pass over the primitives)", true},
      {"one", "1 (a fixed cost per build)", false},
      {"spread", "the cells beyond one per triangle that a grid of N cells meets (scene_features.h: "
                 "spread_references; the references a spatial subdivision clips and stores)", false},
  };
  return terms;
}

FeatureRow build_time_features(const SceneFeatures& scene) {
  const double n = std::max(scene.primitives, 1.0);
  return {{"n_log2_n", n * std::log2(n)}, {"n", n}, {"one", 1.0}, {"spread", spread_references(scene)}};
}

BuildTimeModels fit_build_time_models(const std::vector<RunRecord>& runs, const SceneFeatureTable& features,
                                      const FitOptions& options,
                                      const std::function<void(const std::string&)>& progress) {
  std::map<std::string, std::vector<const RunRecord*>> by_spec;
  std::set<std::pair<std::string, std::string>> seen;
  for (const RunRecord& r : runs)
    if (r.build_s > 0 && seen.insert({r.accel, r.scene}).second) by_spec[r.accel].push_back(&r);
  BuildTimeModels models;
  for (const auto& [spec, rows] : by_spec) {
    // The spread term only where every scene of the spec's rows has its features: a row without
    // them would read as a scene without spread.
    const bool spread = std::all_of(rows.begin(), rows.end(), [&](const RunRecord* r) {
      const auto it = features.find(r->scene);
      return it != features.end() && it->second;
    });
    if (!spread && progress && !features.empty())
      progress("build time of " + spec + ": without the spread term (a scene of its rows has no features)");
    std::vector<FeatureRow> x;
    std::vector<double> y, primitives;
    std::vector<std::string> scenes;
    for (const RunRecord* r : rows) {
      SceneFeatures f;
      if (spread) f = *features.at(r->scene);
      f.primitives = static_cast<double>(r->primitives);  // the row's count, as the range check reads
      x.push_back(build_time_features(f));
      y.push_back(r->build_s);
      scenes.push_back(r->scene);
      primitives.push_back(static_cast<double>(r->primitives));
    }
    try {
      models[spec] = fit_selected_linear_model(build_time_terms(), x, y, scenes, primitives, options);
    } catch (const InputError& e) {
      if (progress) progress("build time of " + spec + ": not modelled (" + e.what() + ")");
    }
  }
  return models;
}

nlohmann::ordered_json build_time_models_json(const BuildTimeModels& models) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [spec, m] : models) j[spec] = selected_linear_model_json(m);
  return j;
}

BuildTimeModels read_build_time_models(const nlohmann::ordered_json& j, const std::string& where) {
  if (!j.is_object()) throw InputError(where + ": expected a JSON object of accelerator specs");
  BuildTimeModels models;
  for (auto it = j.begin(); it != j.end(); ++it)
    models[it.key()] = read_selected_linear_model(it.value(), where + "." + it.key(), build_time_terms());
  return models;
}

}  // namespace raylab
