#include "cost/auto_accel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "cost/accel_spec_key.h"
#include "cost/build_time_model.h"
#include "cost/cost_model.h"
#include "cost/model_file.h"
#include "cost/replicates.h"
#include "cost/scene_features.h"
#include "cost/scene_trace_model.h"
#include "cost/spec_trace_effects.h"
#include "cost/tree_features.h"
#include "geometry/input_error.h"
#include "geometry/input_warning.h"

namespace raylab {
namespace {

const std::vector<std::string> kRayKinds = {"primary", "diffuse", "shadow", "lines", "ao", "mixed"};
/// The kinds `mixed` averages over: the camera, a bounce and a shadow ray of a path tracer.
const std::vector<std::string> kMixedKinds = {"primary", "diffuse", "shadow"};

std::vector<ParamDoc> auto_params() {
  return {{"model", "default", "the cost model (raylab fit): a model.json path, or 'default' for the lab's committed model"},
          {"rays", "mixed", "the ray kind to choose for: primary | diffuse | shadow | lines | ao | mixed (mean of "
                            "primary, diffuse and shadow)"},
          {"count", "the rays traced", "the number of rays the structure will trace: the choice minimises predicted "
                                       "build + count x trace time (raylab trace passes its own count)"}};
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// `count=`: a positive whole number of rays (1e9 allowed); 0 when not given.
double parse_count(SpecReader& r) {
  if (!r.has("count")) return 0.0;
  const std::string text = r.get_string("count", "");
  double v = 0;
  if (!parse_double(text, v) || !std::isfinite(v) || v < 1 || v != std::floor(v) || v > 1e18)
    throw InputError("auto: count=" + text +
                     ": expected a positive whole number of rays (the form: auto:rays=KIND,count=N[,model=PATH], e.g. "
                     "auto:rays=diffuse,count=1e6)");
  return v;
}

/// The ray classes (run_record.h: ray_class_of) a choice for `rays` averages over.
std::vector<std::string> classes_of(const std::string& rays) {
  if (rays != "mixed") return {ray_class_of(rays)};
  std::vector<std::string> out;
  for (const std::string& kind : kMixedKinds) out.push_back(ray_class_of(kind));
  return out;
}

/// What a choice minimises: predicted (or measured) build + count × trace seconds, or the
/// trace time per ray alone without a count.
double objective(double build_s, double ns_per_ray, double count) {
  return count > 0 ? build_s + count * ns_per_ray * 1e-9 : ns_per_ray * 1e-9;
}

/// canonical_accel_spec, or "" for a spec this lab does not know (a model of another version).
std::string canonical_key(const std::string& spec) {
  try {
    return canonical_accel_spec(spec);
  } catch (const InputError&) {
    return "";
  }
}

/// The rays of one kind a race times every racer on.
struct RaySample {
  std::vector<Ray> rays;
  bool any_hit = false;
};

/// `sample_rays` rays of the choice's kind (split evenly over the kinds of `mixed`), generated
/// once per race; diffuse and shadow rays start where `first_hits`, the race's first structure,
/// finds the visible surface (ray_sets.h), so that sampling builds nothing more.
std::vector<RaySample> race_sample(const std::shared_ptr<const Scene>& scene, const std::string& rays,
                                   std::size_t sample_rays, const Aggregate& first_hits) {
  const std::vector<std::string> kinds = rays == "mixed" ? kMixedKinds : std::vector<std::string>{rays};
  std::vector<RaySample> sample;
  for (const std::string& kind : kinds) {
    const std::string spec = kind + ":" + std::to_string(sample_rays / kinds.size());
    sample.push_back({make_ray_set(spec, scene, first_hits), is_any_hit_ray_spec(spec)});
  }
  return sample;
}

/// The fastest of kAutoSamplePasses single-threaded passes over each kind of the sample, in ns per
/// ray (mean over the kinds).
double sampled_ns_per_ray(const Aggregate& accel, const std::vector<RaySample>& sample) {
  double sum = 0;
  for (const RaySample& kind : sample) {
    double best = std::numeric_limits<double>::infinity();
    for (int pass = 0; pass < kAutoSamplePasses; ++pass)
      best = std::min(best, trace_rays(accel, kind.rays, TraceOptions{1, false, kind.any_hit}).seconds);
    sum += best / static_cast<double>(std::max<std::size_t>(kind.rays.size(), 1)) * 1e9;
  }
  return sum / static_cast<double>(sample.size());
}

double predict_ns(const FamilyModel& model, const TreeFeatures& f, const std::string& rays, double primitives) {
  if (rays != "mixed") return model.tree.model.predict(record_for_prediction(f, rays, primitives));
  double sum = 0;
  for (const std::string& kind : kMixedKinds) sum += model.tree.model.predict(record_for_prediction(f, kind, primitives));
  return sum / static_cast<double>(kMixedKinds.size());
}

/// Chooses among the candidates on a flat scene by building every one and predicting each from
/// its tree (the model file has no build-time or scene-level models).
std::unique_ptr<Aggregate> choose_built_all(const std::shared_ptr<const Scene>& scene, const CostModelSet& models,
                                            const std::string& model_path, AutoChoice& choice) {
  const auto start = Clock::now();
  choice.method = "built-all";
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
      accel = make_accelerator(spec, scene, model_build_context());  // candidates' cost=MODEL: auto's model
    } catch (const InputError& e) {  // e.g. a model whose constants a builder cannot use
      c.skipped = e.what();
      choice.candidates.push_back(c);
      continue;
    }
    ++choice.candidates_built;
    c.built = true;
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
  double second = std::numeric_limits<double>::infinity();
  for (const AutoCandidate& c : choice.candidates)
    if (c.skipped.empty() && c.spec != choice.chosen && c.predicted_ns_per_ray < second) {
      second = c.predicted_ns_per_ray;
      choice.runner_up = c.spec;
      choice.runner_up_total_s = choice.count > 0 ? choice.count * second * 1e-9 : kNaN;
    }
  if (choice.count > 0) choice.predicted_trace_s = choice.count * choice.predicted_ns_per_ray * 1e-9;
  choice.choose_s = seconds_since(start);
  return best;
}

/// Chooses on a flat scene from its features alone, then builds what it chose (and the runner-up
/// when their intervals overlap); nullptr when the model predicts no candidate.
std::unique_ptr<Aggregate> choose_predicted(const std::shared_ptr<const Scene>& scene, const CostModelSet& models,
                                            const std::string& model_path, AutoChoice& choice) {
  const auto start = Clock::now();
  const SceneFeatures sf = scene_features(*scene);
  const FeatureRow trace_x = scene_trace_features(sf);
  const FeatureRow build_x = build_time_features(sf);
  const std::vector<std::string> classes = classes_of(choice.rays);
  std::vector<std::string> families;
  for (const auto& [family, m] : models.families) families.push_back(family);
  // The model entries by canonical spec (accel_spec_key.h), each spec canonicalised once.
  std::map<std::string, const SelectedLinearModel*> build_by_key;
  std::map<std::string, const std::map<std::string, SelectedLinearModel>*> trace_by_key;
  for (const auto& [spec, m] : models.build) build_by_key.emplace(canonical_key(spec), &m);
  for (const auto& [spec, m] : models.scene_trace) trace_by_key.emplace(canonical_key(spec), &m);
  // The spec effects (spec_trace_effects.h) of at least kAutoEffectMinScenes scenes, and per ray
  // class the scene's effect b̂: the median vote ln t̂_s - a_s of the specs with a scene-level
  // model and an effect, with the median of their intervals' half-widths (log units). Only the
  // models fitted on scenes of this size vote when at least kAutoEffectMinVoters of them do
  // (extrapolation factor 1); else every model votes, and b̂ carries their largest factor.
  std::map<std::string, const std::map<std::string, SpecTraceEffect>*> effect_by_key;
  for (const auto& [spec, m] : models.trace_effects.by_spec) effect_by_key.emplace(canonical_key(spec), &m);
  auto effect_of = [&](const std::string& key, const std::string& cls) -> const SpecTraceEffect* {
    const auto e = effect_by_key.find(key);
    if (key.empty() || e == effect_by_key.end()) return nullptr;
    const auto c = e->second->find(cls);
    return c != e->second->end() && c->second.scenes >= kAutoEffectMinScenes ? &c->second : nullptr;
  };
  struct SceneEffect {
    double b, log_half_width, extrapolation_factor;
  };
  std::map<std::string, SceneEffect> scene_effect;
  for (const std::string& cls : classes) {
    std::vector<SceneEffect> all, in_range;  // one vote per model
    for (const auto& [key, by_class] : trace_by_key) {
      const SpecTraceEffect* e = effect_of(key, cls);
      const auto m = by_class->find(cls);
      if (!e || m == by_class->end()) continue;
      const double t = m->second.predict(trace_x);
      if (!(t > 0) || !std::isfinite(t)) continue;  // a linear model can predict no time at all
      const SceneEffect v{std::log(t) - e->effect, std::log(m->second.interval90(trace_x, sf.primitives).second / t),
                          m->second.extrapolation_factor(sf.primitives)};
      all.push_back(v);
      if (!(v.extrapolation_factor > 1.0)) in_range.push_back(v);
    }
    const std::vector<SceneEffect>& voters = in_range.size() >= kAutoEffectMinVoters ? in_range : all;
    if (voters.empty()) continue;
    std::vector<double> votes, half_widths;
    double extrapolation = 1.0;
    for (const SceneEffect& v : voters) {
      votes.push_back(v.b);
      half_widths.push_back(v.log_half_width);
      extrapolation = std::max(extrapolation, v.extrapolation_factor);
    }
    scene_effect[cls] = {median(votes), median(half_widths), extrapolation};
  }
  std::vector<AutoCandidate> candidates;
  std::vector<std::pair<double, double>> upper;  // each candidate's 90% upper build s and ns per ray
  std::vector<std::size_t> ranked;  // predicted candidates, best first
  for (const std::string& spec : auto_candidate_specs(families, model_path)) {
    AutoCandidate c{spec, kNaN, ""};
    std::pair<double, double> upper_of_c{kNaN, kNaN};
    const std::string key = canonical_key(spec);
    const auto b_it = build_by_key.find(key);
    const auto t_it = trace_by_key.find(key);
    const SelectedLinearModel* build = b_it == build_by_key.end() ? nullptr : b_it->second;
    const auto* trace = t_it == trace_by_key.end() ? nullptr : t_it->second;
    if (structure_family(spec) == "bsp" && scene->primitive_count() > kAutoBspMaxPrimitives) {
      c.skipped = "more than " + std::to_string(kAutoBspMaxPrimitives) + " primitives";
    } else if (!build) {
      c.skipped = "the model has no build-time model of this spec";
    } else {
      double ns = 0, ns_lo = 0, ns_hi = 0;
      for (const std::string& cls : classes) {
        const double share = 1.0 / static_cast<double>(classes.size());
        const SpecTraceEffect* e = effect_of(key, cls);
        const auto scene_it = scene_effect.find(cls);
        if (e && scene_it != scene_effect.end()) {
          // exp(a + b̂), its interval the two spreads added in quadrature.
          const SceneEffect& b = scene_it->second;
          const double t = std::exp(e->effect + b.b), q = std::hypot(e->log_q90, b.log_half_width);
          c.extrapolation_factor = std::max(c.extrapolation_factor, b.extrapolation_factor);
          ns += share * t, ns_lo += share * t * std::exp(-q), ns_hi += share * t * std::exp(q);
          if (c.trace_model.empty()) c.trace_model = "effects";
          continue;
        }
        const auto own = trace ? trace->find(cls) : std::map<std::string, SelectedLinearModel>::const_iterator{};
        if (!trace || own == trace->end()) {
          c.skipped = "the model has no scene-level trace model of this spec for " + cls + " rays";
          break;
        }
        const auto [lo, hi] = own->second.interval90(trace_x, sf.primitives);
        c.extrapolation_factor = std::max(c.extrapolation_factor, own->second.extrapolation_factor(sf.primitives));
        ns += share * own->second.predict(trace_x), ns_lo += share * lo, ns_hi += share * hi;
        c.trace_model = "scene-level";
      }
      if (c.skipped.empty()) {
        c.extrapolation_factor = std::max(c.extrapolation_factor, build->extrapolation_factor(sf.primitives));
        const auto [b_lo, b_hi] = build->interval90(build_x, sf.primitives);
        c.predicted_ns_per_ray = ns;
        c.predicted_build_s = build->predict(build_x);
        c.predicted_total_s = objective(c.predicted_build_s, ns, choice.count);
        c.total_lo_s = objective(b_lo, ns_lo, choice.count);
        c.total_hi_s = objective(b_hi, ns_hi, choice.count);
        upper_of_c = {b_hi, ns_hi};
        if (std::isfinite(c.predicted_total_s)) ranked.push_back(candidates.size());
        else c.skipped = "the prediction is not a finite number";
      }
    }
    candidates.push_back(std::move(c));
    upper.push_back(upper_of_c);
  }
  if (ranked.empty()) return nullptr;
  std::stable_sort(ranked.begin(), ranked.end(), [&](std::size_t a, std::size_t b) {
    return candidates[a].predicted_total_s < candidates[b].predicted_total_s;
  });
  choice.method = "predicted";
  choice.choose_s = seconds_since(start);

  // Build the best (the next one when a builder refuses the spec). With a count, race the others
  // whose 90% interval overlaps the best's, in rank order, while the race's estimated cost stays
  // within kAutoSampleBudget of the best's predicted total: build each, time it on a sample, and
  // keep the lowest measured total (the leader and one contender held at once).
  auto build = [&](std::size_t k) -> std::unique_ptr<Aggregate> {
    AutoCandidate& c = candidates[k];
    const auto t = Clock::now();
    try {
      auto accel = make_accelerator(c.spec, scene, model_build_context());
      c.measured_build_s = seconds_since(t);
      c.built = true;
      ++choice.candidates_built;
      return accel;
    } catch (const InputError& e) {  // e.g. a model whose constants a builder cannot use
      c.skipped = e.what();
      return nullptr;
    }
  };
  std::unique_ptr<Aggregate> best;
  std::size_t best_k = 0, next = 0;
  while (!best && next < ranked.size()) best = build(best_k = ranked[next++]);
  if (!best) throw InputError("auto: no candidate the cost model " + model_path + " predicts could be built");
  const std::size_t predicted_k = best_k;
  if (choice.count > 0) {  // without a count the choice stays a pure function of the scene
    const std::size_t sample = auto_sample_rays(choice.count);
    const double budget = kAutoSampleBudget * candidates[predicted_k].predicted_total_s;
    // What a candidate's sample passes can cost, at the 90% upper end of its ns per ray.
    auto passes_cost = [&](std::size_t k) {
      return kAutoSamplePasses * static_cast<double>(sample) * upper[k].second * 1e-9;
    };
    std::vector<std::size_t> racers;
    double estimated = passes_cost(predicted_k);
    for (std::size_t i = next; i < ranked.size(); ++i) {
      const std::size_t k = ranked[i];
      if (candidates[k].total_lo_s > candidates[predicted_k].total_hi_s) continue;  // surely slower
      const double cost = upper[k].first + passes_cost(k);
      if (estimated + cost > budget) continue;
      estimated += cost;
      racers.push_back(k);
    }
    if (!racers.empty()) {
      auto measured_total = [&](std::size_t k) {
        return objective(candidates[k].measured_build_s, candidates[k].measured_ns_per_ray, choice.count);
      };
      const std::vector<RaySample> rays = race_sample(scene, choice.rays, sample, *best);
      candidates[best_k].measured_ns_per_ray = sampled_ns_per_ray(*best, rays);
      std::size_t raced = 1;
      for (const std::size_t k : racers) {
        std::unique_ptr<Aggregate> contender = build(k);
        if (!contender) continue;
        ++raced;
        candidates[k].measured_ns_per_ray = sampled_ns_per_ray(*contender, rays);
        if (measured_total(k) < measured_total(best_k)) {
          best = std::move(contender);
          best_k = k;
        }
      }
      choice.sampled = raced > 1;
      choice.note = std::to_string(raced) + " candidates raced (the best prediction, " + candidates[predicted_k].spec +
                    ", and those whose 90% intervals overlapped its own, within " +
                    std::to_string(static_cast<int>(kAutoSampleBudget * 100)) +
                    "% of its predicted total): each built and timed on " + std::to_string(sample) +
                    " rays, the lowest measured total kept";
    }
  }
  const AutoCandidate& chosen = candidates[best_k];
  choice.chosen = chosen.spec;
  choice.predicted_ns_per_ray = chosen.predicted_ns_per_ray;
  choice.predicted_build_s = chosen.predicted_build_s;
  choice.extrapolation_factor = chosen.extrapolation_factor;
  if (choice.count > 0) choice.predicted_trace_s = choice.count * chosen.predicted_ns_per_ray * 1e-9;
  const std::size_t runner = ranked.front() == best_k ? (ranked.size() > 1 ? ranked[1] : best_k) : ranked.front();
  if (runner != best_k) {
    choice.runner_up = candidates[runner].spec;
    choice.runner_up_total_s = candidates[runner].predicted_total_s;
  }
  choice.candidates = std::move(candidates);
  return best;
}

/// Chooses among the candidates on a flat scene and returns the chosen structure.
std::unique_ptr<Aggregate> choose(const std::shared_ptr<const Scene>& scene, const CostModelSet& models,
                                  const std::string& model_path, AutoChoice& choice) {
  if (!models.build.empty() && !models.scene_trace.empty()) {
    AutoChoice predicted = choice;
    if (auto chosen = choose_predicted(scene, models, model_path, predicted)) {
      choice = std::move(predicted);
      return chosen;
    }
    choice.note = "the model's build-time and scene-level models predict none of the candidates: every candidate built";
  } else {
    choice.note = "the model file has no build-time or scene-level models (raylab fit writes them): every candidate "
                  "built";
  }
  return choose_built_all(scene, models, model_path, choice);
}

/// One warning line when the choice rests on models used outside the sizes they were fitted on;
/// once per process for the same text (a process that builds `auto` on the same scene again,
/// as an experiment's rounds do, is told once; AutoChoice::extrapolation_factor keeps it for each).
void warn_if_extrapolated(const AutoChoice& choice, double primitives) {
  if (!(choice.extrapolation_factor > 1.0)) return;
  char numbers[160];
  std::snprintf(numbers, sizeof numbers, "%.4g primitives lie outside the range its models were fitted on, by a factor %.3g",
                primitives, choice.extrapolation_factor);
  char widening[64];
  std::snprintf(widening, sizeof widening, "%.2fx", range_widening(choice.extrapolation_factor));
  const std::string message = "auto: " + std::string(numbers) + " (its choice " + choice.chosen +
                              "); the 90% intervals are widened by " + widening + " (docs/cost_model.md)";
  warn_input_once(message, message);
}

std::unique_ptr<Aggregate> make_auto(std::shared_ptr<const Scene> scene, SpecReader& r) {
  const std::string model_path = r.get_string("model", "default");
  AutoChoice choice;
  choice.count = parse_count(r);
  choice.rays = r.get_choice("rays", "mixed", kRayKinds);
  choice.model = resolve_model_path(model_path);
  const std::shared_ptr<const CostModelSet> loaded = load_model_file(model_path);
  const CostModelSet& models = *loaded;
  if (!scene->instanced()) {
    auto chosen = choose(scene, models, model_path, choice);
    warn_if_extrapolated(choice, scene->total_primitive_count());
    return std::make_unique<AutoAccelerator>(std::move(chosen), std::move(choice));
  }
  // Instances: choose for each base (placed under its instances) and for the flat geometry apart;
  // the choice reported is the one for the part with the most primitives.
  double largest = -1.0, choose_s = 0, extrapolation = 1.0;
  std::size_t built = 0;
  const AutoChoice blank = choice;
  auto top = make_instanced_aggregate(*scene, [&](std::shared_ptr<const Scene> part) {
    AutoChoice part_choice = blank;
    auto chosen = choose(part, models, model_path, part_choice);
    choose_s += part_choice.choose_s;
    built += part_choice.candidates_built;
    extrapolation = std::max(extrapolation, part_choice.extrapolation_factor);
    if (part->total_primitive_count() > largest) {
      largest = part->total_primitive_count();
      choice = std::move(part_choice);
    }
    return chosen;
  });
  choice.choose_s = choose_s;
  choice.candidates_built = built;
  choice.extrapolation_factor = extrapolation;
  warn_if_extrapolated(choice, largest);
  return std::make_unique<AutoAccelerator>(std::move(top), std::move(choice));
}

AccelKind make_auto_kind() {
  return {"auto",
          "the structure a fitted cost model predicts fastest for the scene (raylab fit; see docs/cost_model.md)",
          auto_params(),
          // auto reads its model itself (lib/cost), so it needs nothing from the context.
          [](std::shared_ptr<const Scene> scene, SpecReader& r, const BuildContext&) { return make_auto(std::move(scene), r); },
          [](SpecReader& r) -> AccuracyBound {
            // The loosest bound of the candidates: every one of them may be chosen.
            r.get_choice("rays", "mixed", kRayKinds);
            parse_count(r);
            const std::string model = r.get_string("model", "default");
            const std::shared_ptr<const CostModelSet> loaded = load_model_file(model);
            const CostModelSet& models = *loaded;
            std::vector<std::string> families;
            for (const auto& [family, m] : models.families) families.push_back(family);
            AccuracyBound loosest;
            loosest.exact = true;
            bool first = true;
            for (const std::string& spec : auto_candidate_specs(families, model)) {
              const AccuracyBound b = accuracy_bound(spec);
              loosest.kernel = first || loosest.kernel == b.kernel ? b.kernel : "";  // one kernel, or none named
              first = false;
              loosest.exact = loosest.exact && b.exact;
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
      {"grid", {"grid:d=1", "grid:d=2", "grid:d=3", "grid:d=6"}},  // the densities the plans sweep
      {"nested-grid", {"nested-grid", "nested-grid:mode=two-level"}},
  };
  std::vector<std::string> specs;
  for (const auto& [family, list] : variants)
    if (std::find(families.begin(), families.end(), family) != families.end())
      specs.insert(specs.end(), list.begin(), list.end());
  return specs;
}

}  // namespace raylab
