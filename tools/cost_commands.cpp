#include "tools/cost_commands.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "cost/accel_spec_key.h"
#include "cost/build_time_model.h"
#include "cost/merge.h"
#include "cost/model_file.h"
#include "cost/scene_features.h"
#include "cost/sweep.h"
#include "geometry/input_error.h"
#include "geometry/input_warning.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

void progress_line(const std::string& line) { std::cerr << "raylab: " << line << std::endl; }

std::string percent(double fraction) { return fmt::format("{:.1f}%", 100.0 * fraction); }

/// A held-out error at most this many times the replicate error is as good as the machine can tell.
constexpr double kReplicateVerdictRatio = 1.5;

void print_level(const LevelFit& f, const char* title) {
  std::cout << fmt::format("  {} model: held-out MAPE {}, R² {:.3f}{}, 90% intervals cover {}; in-sample MAPE {}, R² "
                           "{:.3f}; AIC {:.1f}, BIC {:.1f}, condition {:.3g}{}\n",
                           title, f.cross_validated ? percent(f.held_out_mape) : "n/a", f.held_out_r2,
                           f.cross_validated ? " (leave one scene out)" : " (one scene: nothing held out)",
                           std::isfinite(f.held_out_coverage90) ? percent(f.held_out_coverage90) + " of held-out times"
                                                                 : std::string("n/a"),
                           percent(f.in_sample_mape), f.in_sample_r2, f.aic, f.bic, f.condition_number,
                           f.converged ? "" : " NOT CONVERGED");
  for (std::size_t j = 0; j < f.model.terms.size(); ++j) {
    const CostTerm& t = find_cost_term(f.model.level, f.model.terms[j]);
    std::cout << fmt::format("    {:<17} {:>22} ns   {}{}\n", t.name,
                             format_with_error(f.model.values[j], f.model.std_errors[j]), t.meaning,
                             j < f.at_bound.size() && f.at_bound[j] ? " [at bound 0]" : "");
  }
  auto join = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s.empty() ? std::string("none") : s;
  };
  std::cout << "    dropped (no lower held-out error): " << join(f.dropped) << "; zero on every row: " << join(f.unused)
            << "\n";
  for (const auto& [family, terms] : f.by_scene_family)
    std::cout << "    scene family " << family << " needs: " << join(terms) << "\n";
}

/// The family's replicate error beside each level's held-out error, with the verdict where the
/// model is as good as the machine's repeatability lets anyone tell.
void print_replicate_error(const FamilyModel& m) {
  if (!std::isfinite(m.replicate_error)) {
    std::cout << "  replicate error: n/a (no case of this family measured twice)\n";
    return;
  }
  std::cout << fmt::format("  replicate error {} over {} replicated cases", percent(m.replicate_error), m.replicate_groups);
  for (const LevelFit* f : {&m.counters, &m.tree}) {
    if (!f->cross_validated) continue;
    const double ratio = m.replicate_error > 0 ? f->held_out_mape / m.replicate_error : std::numeric_limits<double>::infinity();
    std::cout << fmt::format("; {} held-out MAPE {} = {:.2g}x it{}", level_name(f->model.level), percent(f->held_out_mape),
                             ratio, ratio <= kReplicateVerdictRatio ? ": within 1.5x the replicate error: as good as "
                                                                      "this machine can tell"
                                                                    : "");
  }
  std::cout << "\n";
}

}  // namespace

int run_sweep_command(const SweepCommand& o) {
  if (o.threads < 1 || o.threads > 1024) throw InputError("--threads " + std::to_string(o.threads) + ": expected 1..1024");
  if (o.passes < 5 || o.passes > 1000) throw InputError("--passes " + std::to_string(o.passes) + ": expected 5..1000");
  const ShardSpec shard = parse_shard(o.shard);
  const SweepPlan plan = load_plan(o.plan);
  if (o.check) {
    std::cout << fmt::format("plan {} ({}): {}\n", plan.source, std::filesystem::absolute(plan_path(plan.source)).string(),
                             plan.describe());
    return 0;
  }
  SweepOptions options;
  options.out = o.out;
  options.shard = shard;
  options.resume = o.resume;
  options.threads = o.threads;
  options.timing.min_passes = o.passes;
  options.progress = progress_line;
  const SweepSummary s = run_sweep(plan, options);
  progress_line(fmt::format("sweep done: {} cases measured, {} already in {}", s.measured, s.skipped, o.out));
  return 0;
}

int run_merge_command(const MergeCommand& o) {
  const SweepPlan plan = load_plan(o.plan);
  MergeOptions options;
  options.shard_files = o.shard_files;
  options.shard_count = o.shards;
  options.out = o.out;
  options.note = o.note;
  MergeResult r;
  try {
    r = merge_shards(plan, options);
  } catch (const IncompleteMerge& e) {
    if (!e.result.missing_cases.empty() && e.result.duplicates.empty()) {
      std::string list;
      for (const auto k : e.result.incomplete_shards) list += (list.empty() ? "" : ",") + std::to_string(k);
      std::cout << "incomplete_shards=" << list << std::endl;
    }
    throw;
  }
  for (const ShardFileRows& f : r.files)
    if (f.torn_tail) progress_line("note: " + f.path + " ends in a half-written row (ignored; its case is in another file)");
  std::set<std::string> cpus;
  for (const RunRecord& row : r.rows) cpus.insert(row.cpu_model);
  if (cpus.size() > 1)
    progress_line(fmt::format("note: rows from {} CPU models; raylab fit refuses them unless --allow-mixed-hardware",
                              cpus.size()));
  progress_line(fmt::format("merged {} rows of plan {} from {} shard files into {} (how it was run: {})", r.rows.size(),
                            plan.source, r.files.size(), o.out, merge_record_path(o.out)));
  return 0;
}

namespace {

/// The build-time models (build_time_model.h), one line per accelerator spec.
void print_build_models(const BuildTimeModels& models) {
  if (models.empty()) return;
  std::cout << "\nbuild-time model, seconds = a·N·log2 N + b·N [+ c], per accelerator spec (held out: leave one "
               "scene out; 90% interval coverage on held-out scenes):\n";
  std::cout << fmt::format("  {:<32} {:>22} {:>22} {:>22} {:>9} {:>9} {:>17}\n", "accel", "a (ns)", "b (ns)", "c (ms)",
                           "MAPE", "cover90", "N fitted");
  for (const auto& entry : models) {
    const SelectedLinearModel& m = entry.second;  // a plain reference: clang 14 captures no structured binding
    const std::string& spec = entry.first;
    auto cell = [&](const char* term, double unit) {
      if (std::find(m.terms.begin(), m.terms.end(), term) == m.terms.end()) return std::string("-");
      return format_with_error(m.value_of(term) * unit, m.std_error_of(term) * unit);
    };
    std::cout << fmt::format("  {:<32} {:>22} {:>22} {:>22} {:>9} {:>9} {:>8.3g}..{:<8.3g}\n", spec,
                             cell("n_log2_n", 1e9), cell("n", 1e9), cell("one", 1e3),
                             m.cross_validated ? percent(m.held_out_mape) : "n/a",
                             m.cross_validated ? percent(m.coverage90) : "n/a", m.range_lo, m.range_hi);
  }
}

}  // namespace

int run_fit_command(const FitCommand& o) {
  if (!(o.loss_scale > 0) || !std::isfinite(o.loss_scale))
    throw InputError("--loss-scale: expected a positive number (the Huber scale, as a fraction)");
  if (o.out.empty()) throw InputError("fit: --out is required");
  const std::vector<RunRecord> runs = read_runs_csv(o.runs);
  std::set<std::string> cpus;
  for (const RunRecord& r : runs) cpus.insert(r.cpu_model);
  if (cpus.size() > 1 && !o.allow_mixed_hardware) {
    std::string list;
    for (const auto& c : cpus) list += (list.empty() ? "" : "; ") + c;
    throw InputError(o.runs + ": rows from " + std::to_string(cpus.size()) + " CPU models (" + list +
                     "): constants do not carry across machines; refit per machine or pass --allow-mixed-hardware");
  }
  FitOptions options;
  options.loss_scale = o.loss_scale;
  const FitTarget target = parse_fit_target(o.target);
  CostModelSet set = fit_cost_model_set(runs, options, target,
                                        o.json ? std::function<void(const std::string&)>{} : progress_line);
  set.runs_source = o.runs;
  for (const auto& [name, m] : set.families)
    for (const LevelFit* f : {&m.counters, &m.tree})
      if (!f->converged)
        throw InputError("fit: the " + std::string(level_name(f->model.level)) + " model of '" + name +
                         "' did not converge (" + f->solver_message + "); no model written");
  write_model_file(set, o.out);

  if (o.json) {
    nlohmann::ordered_json j;
    j["model"] = o.out;
    j["rows"] = set.rows;
    for (const auto& [name, m] : set.families) {
      for (const LevelFit* f : {&m.counters, &m.tree}) {
        auto& e = j["families"][name][level_name(f->model.level)];
        e["held_out_mape"] = f->held_out_mape;
        e["held_out_r2"] = f->held_out_r2;
        e["held_out_coverage90"] = std::isfinite(f->held_out_coverage90) ? nlohmann::ordered_json(f->held_out_coverage90)
                                                                         : nlohmann::ordered_json(nullptr);
        e["terms"] = f->model.terms;
        e["values"] = f->model.values;
      }
      j["families"][name]["replicate_error"] =
          std::isfinite(m.replicate_error) ? nlohmann::ordered_json(m.replicate_error) : nlohmann::ordered_json(nullptr);
      j["families"][name]["replicate_groups"] = m.replicate_groups;
    }
    for (const auto& [spec, m] : set.build)
      j["build"][spec] = {{"terms", m.terms}, {"values", m.values}, {"held_out_mape", m.held_out_mape},
                          {"coverage90", m.coverage90}};
    std::cout << j.dump() << "\n";
    return 0;
  }
  std::cout << fmt::format("cost model of {} ({} rows, CPU {}): target {}, Huber loss scale {} on relative residuals\n",
                           o.runs, set.rows, *cpus.begin(), target_name(target), o.loss_scale);
  for (const auto& [name, m] : set.families) {
    std::cout << fmt::format("\n{}: {} rows over {} scenes\n", name, m.rows, m.scenes.size());
    print_level(m.counters, "counters");
    const double node = m.counters.model.value_of("node"), test = m.counters.model.value_of("test");
    if (node > 0 && test > 0)
      std::cout << fmt::format("    measured C_trav:C_isect = 1:{:.2f} (the lecture: 1:80 in pbrt, 1:1.5 optimized)\n",
                               test / node);
    print_level(m.tree, "tree");
    print_replicate_error(m);
    std::cout << fmt::format("  builder constants (cost={}): c_trav {:.3g}, c_leaf {:.3g}, c_isect {:.3g} ns, from the {} "
                             "model\n",
                             o.out, m.builder.c_trav, m.builder.c_leaf, m.builder.c_isect, m.builder_source);
  }
  print_build_models(set.build);
  std::cout << "\nwrote " << o.out << "\n";
  return 0;
}

int run_predict_command(const PredictCommand& o) {
  if (o.threads < 1 || o.threads > 1024) throw InputError("--threads " + std::to_string(o.threads) + ": expected 1..1024");
  if (o.passes < 5 || o.passes > 1000) throw InputError("--passes " + std::to_string(o.passes) + ": expected 5..1000");
  const std::shared_ptr<const CostModelSet> loaded = load_model_file(o.model);
  const CostModelSet& models = *loaded;
  validate_accelerator_spec(o.accel);
  const std::string family = structure_family(o.accel);
  const FamilyModel& model = models.family(family);
  const std::string ray_kind = parse_spec(o.rays).name;

  const auto scene = make_scene(o.scene);
  if (scene->instanced()) throw InputError("predict: scene '" + o.scene + "' is instanced; predict on its base scene");
  const BuiltStructure built = build_structure(o.accel, scene, o.threads);
  const RunRecord features = record_for_prediction(built.features, ray_kind, scene->total_primitive_count());

  // The model knows its fitted range: outside it the interval widens, and --strict refuses.
  const FamilyPrediction tree = model.predict(ModelLevel::tree, features);
  const RangeCheck& range = tree.range;
  if (o.strict && range.worst.factor > kStrictRangeFactor) {
    std::string list;
    for (const FeatureRangeCheck& c : range.outside)
      if (c.factor > kStrictRangeFactor)
        list += (list.empty() ? "" : "; ") + fmt::format("{} {:.4g} (fitted on {:.4g}..{:.4g})", c.feature, c.value, c.lo, c.hi);
    throw InputError("predict: " + family + " is more than a factor 2 outside the model's data: " + list +
                     " (without --strict it predicts with a widened interval)");
  }
  if (range.extrapolated())
    warn_input(family + " is outside the model's data: " + range.worst.describe() + "; the interval is widened");

  auto interval_json = [](const IntervalPrediction& p) {
    return std::isfinite(p.lo) && std::isfinite(p.hi) ? nlohmann::ordered_json::array({p.lo, p.hi})
                                                      : nlohmann::ordered_json(nullptr);
  };
  nlohmann::ordered_json j;
  j["model"] = resolve_model_path(o.model);
  j["scene"] = o.scene;
  j["accel"] = o.accel;
  j["rays"] = o.rays;
  j["family"] = family;
  j["predicted_ns_per_ray"] = tree.interval.ns;
  j["interval90_ns_per_ray"] = interval_json(tree.interval);
  j["extrapolated"] = range.extrapolated();
  if (range.extrapolated()) {
    j["extrapolated_feature"] = range.worst.feature;
    j["extrapolation_factor"] = range.worst.factor;
    j["interval_widening"] = range.widening();
  }
  if (o.measure) {
    const std::vector<Ray> rays = make_ray_set(o.rays, scene);
    const auto embree = make_accelerator("embree", scene);
    TimingOptions timing;
    timing.threads = o.threads;
    timing.min_passes = o.passes;
    timing.any_hit = is_any_hit_ray_spec(o.rays);
    const RunRecord measured = measure_case({0, o.scene, o.accel, o.rays}, *scene, built, *embree, rays, timing);
    const FamilyPrediction counters = model.predict(ModelLevel::counters, measured);
    j["measured_ns_per_ray"] = measured.ns_per_ray_min;
    j["measured_ns_per_ray_median"] = measured.ns_per_ray_median;
    j["measured_ns_per_ray_max"] = measured.ns_per_ray_max;
    j["measured_in_interval90"] = tree.interval.lo <= measured.ns_per_ray_min && measured.ns_per_ray_min <= tree.interval.hi;
    j["passes"] = measured.passes;
    j["embree_ns_per_ray"] = measured.embree_ns_per_ray_min;
    j["embree_ns_per_ray_max"] = measured.embree_ns_per_ray_max;
    j["predicted_from_counters_ns_per_ray"] = counters.interval.ns;
    j["interval90_from_counters_ns_per_ray"] = interval_json(counters.interval);
    j["nodes_per_ray"] = measured.nodes_per_ray;
    j["tests_per_ray"] = measured.tests_per_ray;
  }
  j["build_s"] = built.build_s;
  // The build-time model of this accelerator spec (build_time_model.h), when the model file has one.
  const double n = scene->total_primitive_count();
  if (const SelectedLinearModel* b = find_spec_model(models.build, o.accel)) {
    const FeatureRow f = build_time_features(scene_features(*scene));  // a flat scene: predict refuses instances
    const auto [lo, hi] = b->interval90(f, n);
    j["predicted_build_s"] = b->predict(f);
    j["interval90_build_s"] = {lo, hi};
  } else {
    j["predicted_build_s"] = nullptr;
  }
  if (o.measure) j["measured_build_s"] = built.build_s;
  if (o.json) {
    std::cout << j.dump() << "\n";
  } else {
    for (auto it = j.begin(); it != j.end(); ++it) std::cout << it.key() << ": " << it.value().dump() << "\n";
  }
  return 0;
}

}  // namespace raylab
