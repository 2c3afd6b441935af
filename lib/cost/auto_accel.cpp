#include "cost/auto_accel.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "accel/common/accel_factory.h"
#include "cost/model_file.h"
#include "cost/tree_features.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

const std::vector<std::string> kRayKinds = {"primary", "diffuse", "shadow", "lines", "ao", "mixed"};
/// The kinds `mixed` averages over: the camera, a bounce and a shadow ray of a path tracer.
const std::vector<std::string> kMixedKinds = {"primary", "diffuse", "shadow"};

std::vector<ParamDoc> auto_params() {
  return {{"model", "default", "the cost model (raylab fit): a model.json path, or 'default' for the lab's committed model"},
          {"rays", "mixed", "the ray kind to choose for: primary | diffuse | shadow | lines | ao | mixed (mean of "
                            "primary, diffuse and shadow)"}};
}

double predict_ns(const FamilyModel& model, const TreeFeatures& f, const std::string& rays, double primitives) {
  if (rays != "mixed") return model.tree.model.predict(record_for_prediction(f, rays, primitives));
  double sum = 0;
  for (const std::string& kind : kMixedKinds) sum += model.tree.model.predict(record_for_prediction(f, kind, primitives));
  return sum / static_cast<double>(kMixedKinds.size());
}

/// Chooses among the candidates on a flat scene and returns the chosen structure.
std::unique_ptr<Aggregate> choose(const std::shared_ptr<const Scene>& scene, const CostModelSet& models,
                                  const std::string& model_path, AutoChoice& choice) {
  std::vector<std::string> families;
  for (const auto& [family, m] : models.families) families.push_back(family);
  std::unique_ptr<Aggregate> best;
  double best_ns = std::numeric_limits<double>::infinity();
  for (const std::string& spec : auto_candidate_specs(families, model_path)) {
    AutoCandidate c{spec, std::numeric_limits<double>::quiet_NaN(), ""};
    const std::string family = structure_family(spec);
    if (family == "bsp" && scene->primitive_count() > kAutoBspMaxPrimitives) {
      c.skipped = "more than " + std::to_string(kAutoBspMaxPrimitives) + " primitives";
      choice.candidates.push_back(c);
      continue;
    }
    std::unique_ptr<Aggregate> accel;
    try {
      accel = make_accelerator(spec, scene);
    } catch (const InputError& e) {  // e.g. a model whose constants a builder cannot use
      c.skipped = e.what();
      choice.candidates.push_back(c);
      continue;
    }
    const TreeFeatures f = tree_features(*accel, *scene);
    c.predicted_ns_per_ray = predict_ns(models.family(family), f, choice.rays, scene->total_primitive_count());
    choice.candidates.push_back(c);
    if (c.predicted_ns_per_ray < best_ns) {
      best_ns = c.predicted_ns_per_ray;
      best = std::move(accel);
      choice.chosen = spec;
      choice.predicted_ns_per_ray = best_ns;
    }
  }
  if (!best) throw InputError("auto: the cost model " + model_path + " ranks none of the lab's structures");
  return best;
}

std::unique_ptr<Aggregate> make_auto(std::shared_ptr<const Scene> scene, SpecReader& r) {
  const std::string model_path = r.get_string("model", "default");
  AutoChoice choice;
  choice.rays = r.get_choice("rays", "mixed", kRayKinds);
  choice.model = resolve_model_path(model_path);
  const CostModelSet models = read_model_file(model_path);
  if (!scene->instanced()) {
    auto chosen = choose(scene, models, model_path, choice);
    return std::make_unique<AutoAccelerator>(std::move(chosen), std::move(choice));
  }
  // Instances: choose for each base (placed under its instances) and for the flat geometry apart;
  // the choice reported is the one for the part with the most primitives.
  double largest = -1.0;
  const AutoChoice blank = choice;
  auto top = make_instanced_aggregate(*scene, [&](std::shared_ptr<const Scene> part) {
    AutoChoice part_choice = blank;
    auto chosen = choose(part, models, model_path, part_choice);
    if (part->total_primitive_count() > largest) {
      largest = part->total_primitive_count();
      choice = std::move(part_choice);
    }
    return chosen;
  });
  return std::make_unique<AutoAccelerator>(std::move(top), std::move(choice));
}

AccelKind make_auto_kind() {
  return {"auto",
          "the structure a fitted cost model predicts fastest for the scene (raylab fit; see docs/cost_model.md)",
          auto_params(),
          [](std::shared_ptr<const Scene> scene, SpecReader& r) { return make_auto(std::move(scene), r); },
          [](SpecReader& r) -> AccuracyBound {
            // The loosest bound of the candidates: every one of them may be chosen.
            r.get_choice("rays", "mixed", kRayKinds);
            const std::string model = r.get_string("model", "default");
            const CostModelSet models = read_model_file(model);
            std::vector<std::string> families;
            for (const auto& [family, m] : models.families) families.push_back(family);
            AccuracyBound loosest;
            for (const std::string& spec : auto_candidate_specs(families, model)) {
              const AccuracyBound b = accuracy_bound(spec);
              loosest.crossing_features = std::max(loosest.crossing_features, b.crossing_features);
              loosest.crossing_other = std::max(loosest.crossing_other, b.crossing_other);
              loosest.touching = std::max(loosest.touching, b.touching);
              loosest.on_surface = std::max(loosest.on_surface, b.on_surface);
              loosest.ill_conditioned = std::max(loosest.ill_conditioned, b.ill_conditioned);
              loosest.statement = b.statement;
            }
            loosest.statement = "the bound of the structure it chooses; all candidates: " + loosest.statement;
            return loosest;
          },
          {"rays=diffuse"}};
}

const AccelRegistration auto_registration(make_auto_kind(), 100);

}  // namespace

std::vector<std::string> auto_candidate_specs(const std::vector<std::string>& families, const std::string& model) {
  const std::string cost = "cost=" + (model.find_first_of(",:()") == std::string::npos ? model : "(" + model + ")");
  const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
      {"bvh", {"bvh:width=2", "bvh:width=2," + cost}},
      {"bvh4", {"bvh:width=4", "bvh:width=4," + cost}},
      {"bvh8", {"bvh:width=8", "bvh:width=8," + cost}},
      {"kdtree", {"kdtree", "kdtree:" + cost}},
      {"octree", {"octree", "octree:" + cost}},
      {"bsp", {"bsp"}},
      {"grid", {"grid:d=1", "grid:d=2", "grid:d=3", "grid:d=5"}},
      {"nested-grid", {"nested-grid", "nested-grid:mode=two-level"}},
  };
  std::vector<std::string> specs;
  for (const auto& [family, list] : variants)
    if (std::find(families.begin(), families.end(), family) != families.end())
      specs.insert(specs.end(), list.begin(), list.end());
  return specs;
}

}  // namespace raylab
