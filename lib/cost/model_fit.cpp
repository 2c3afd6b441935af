#include "cost/model_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include "cost/output_file.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

/// sqrt(Σ ln²(measured/predicted) / (n - k)) of a model over the rows it was fitted on; NaN when
/// n ≤ k or a prediction is not positive.
double in_sample_log_sigma(const FittedCostModel& model, const std::vector<RunRecord>& runs) {
  const std::size_t k = model.terms.size();
  if (runs.size() <= k) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (const RunRecord& r : runs) {
    const double predicted = model.predict(r);
    if (!(predicted > 0)) return std::numeric_limits<double>::quiet_NaN();
    const double e = std::log(r.ns_per_ray_min / predicted);
    sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(runs.size() - k));
}

LevelFit fit_level(ModelLevel level, const std::vector<RunRecord>& runs, const FitOptions& options,
                   double replicate_sigma) {
  LevelFit out;
  const TermSelection sel = select_terms(level, runs, options);
  FitResult fit;
  out.model = fit_cost_model(level, sel.terms, runs, options, &fit);
  out.at_bound = fit.at_bound;
  out.in_sample_mape = fit.mape;
  out.in_sample_r2 = fit.r2;
  out.aic = fit.aic;
  out.bic = fit.bic;
  out.condition_number = fit.condition_number;
  out.converged = fit.converged;
  out.solver_message = fit.message;
  out.cross_validated = sel.cross_validated && sel.held_out.valid;
  if (out.cross_validated) {
    out.held_out_mape = sel.held_out.mape;
    out.held_out_r2 = sel.held_out.r2;
    out.held_out_predictions = sel.held_out.predicted;
    out.held_out_coverage90 = held_out_coverage90(sel.held_out, runs, replicate_sigma);
    out.model.residual_log_sigma = held_out_log_sigma(sel.held_out, runs);
  } else {
    out.model.residual_log_sigma = in_sample_log_sigma(out.model, runs);
  }
  out.dropped = sel.dropped;
  out.unused = sel.unused;
  out.by_scene_family = sel.by_scene_family;
  out.path = sel.path;
  return out;
}

/// Which SAH constant a tree-level term feeds, and the factor that turns its feature into the
/// base feature's unit (averaged over the rows).
enum class Role { none, inner, leaf, test };

Role role_of(const std::string& term) {
  if (term.rfind("inner_", 0) == 0) return Role::inner;  // inner_<class>, inner_memory
  if (term.rfind("leaf_", 0) == 0) return Role::leaf;
  if (term.rfind("test_", 0) == 0) return Role::test;  // test_<class>, test_groups
  return Role::none;
}

double base_feature(Role role, const RunRecord& r) {
  return role == Role::inner ? r.e_inner : role == Role::leaf ? r.e_leaves : r.e_tests;
}

FittedSahCost builder_constants(const FittedCostModel& model, const std::vector<RunRecord>& runs) {
  FittedSahCost c;
  for (std::size_t j = 0; j < model.terms.size(); ++j) {
    const Role role = role_of(model.terms[j]);
    if (role == Role::none) continue;
    const CostTerm& term = find_cost_term(model.level, model.terms[j]);
    double ratio = 0;
    std::size_t n = 0;
    for (const RunRecord& r : runs) {
      const double base = base_feature(role, r);
      if (base > 0) {
        ratio += term.feature(r) / base;
        ++n;
      }
    }
    const double contribution = n ? model.values[j] * ratio / static_cast<double>(n) : 0.0;
    (role == Role::inner ? c.c_trav : role == Role::leaf ? c.c_leaf : c.c_isect) += contribution;
  }
  return c;
}

}  // namespace

double range_feature(const std::string& name, const RunRecord& run) {
  if (name == "primitives") return static_cast<double>(run.primitives);
  if (name == "e_inner") return run.e_inner;
  if (name == "e_tests") return run.e_tests;
  if (name == "sah_1_1") return run.sah_1_1;
  throw InputError("unknown range feature '" + name + "' (valid: primitives, e_inner, e_tests, sah_1_1)");
}

std::string FeatureRangeCheck::describe() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s %.3g is %.*fx %s the fitted %.6g..%.6g", feature.c_str(), value, factor < 10 ? 1 : 0,
                factor, above() ? "above" : "below", lo, hi);
  return buf;
}

double RangeCheck::widening() const { return range_widening(worst.factor); }

FeatureRangeCheck check_feature_range(const std::string& feature, double value, const FittedRange& range) {
  FeatureRangeCheck c;
  c.feature = feature;
  c.value = value;
  c.lo = range.lo;
  c.hi = range.hi;
  if (c.value > c.hi) c.factor = c.hi > 0 ? c.value / c.hi : std::numeric_limits<double>::infinity();
  else if (c.value < c.lo) c.factor = c.value > 0 ? c.lo / c.value : std::numeric_limits<double>::infinity();
  return c;
}

RangeCheck FamilyModel::check_range(const RunRecord& run) const {
  RangeCheck check;
  for (const std::string& feature : kRangeFeatures) {
    const auto it = ranges.find(feature);
    if (it == ranges.end()) continue;
    const FeatureRangeCheck c = check_feature_range(feature, range_feature(feature, run), it->second);
    if (!c.outside()) continue;
    check.outside.push_back(c);
    if (c.factor > check.worst.factor) check.worst = c;
  }
  return check;
}

FamilyPrediction FamilyModel::predict(ModelLevel level, const RunRecord& run) const {
  FamilyPrediction p;
  p.range = check_range(run);
  p.interval = level_fit(level).model.predict_interval(run, replicate_log_sigma(replicate_error), p.range.widening());
  return p;
}

ReplicateError replicate_error(const std::vector<RunRecord>& runs) {
  std::map<std::tuple<std::string, std::string, std::string, std::int64_t>, std::vector<double>> groups;
  for (const RunRecord& r : runs) groups[{r.scene, r.accel, r.rays, r.threads}].push_back(r.ns_per_ray_min);
  ReplicateError out;
  double sum = 0;
  for (const auto& [key, times] : groups) {
    if (times.size() < 2) continue;
    double pairs = 0, group = 0;
    for (std::size_t a = 0; a < times.size(); ++a)
      for (std::size_t b = a + 1; b < times.size(); ++b) {
        const double mean = 0.5 * (times[a] + times[b]);
        group += mean > 0 ? std::abs(times[a] - times[b]) / mean : 0.0;
        pairs += 1;
      }
    sum += group / pairs;
    ++out.groups;
  }
  if (out.groups) out.mape = sum / static_cast<double>(out.groups);
  return out;
}

double replicate_log_sigma(double replicate_mape) { return replicate_mape * std::sqrt(std::acos(-1.0)) / 2.0; }

const FamilyModel& CostModelSet::family(const std::string& name) const {
  const auto it = families.find(name);
  if (it != families.end()) return it->second;
  std::string have;
  for (const auto& [f, m] : families) have += (have.empty() ? "" : ", ") + f;
  throw InputError("the cost model has no entry for structure family '" + name + "' (it has: " +
                   (have.empty() ? "none" : have) + ")");
}

std::vector<RunRecord> runs_of_family(const std::vector<RunRecord>& runs, const std::string& family) {
  std::vector<RunRecord> out;
  for (const RunRecord& r : runs)
    if (r.family == family) out.push_back(r);
  return out;
}

const char* target_name(FitTarget target) {
  return target == FitTarget::minimum ? "min" : "embree-normalized";
}

FitTarget parse_fit_target(const std::string& name) {
  if (name == "min") return FitTarget::minimum;
  if (name == "embree-normalized") return FitTarget::embree_normalized;
  throw InputError("fit target '" + name + "': expected min or embree-normalized");
}

std::vector<RunRecord> with_fit_target(std::vector<RunRecord> runs, FitTarget target) {
  if (target == FitTarget::minimum) return runs;
  std::map<std::pair<std::string, std::string>, double> least;
  for (const RunRecord& r : runs) {
    if (!(r.embree_ns_per_ray_min > 0))
      throw InputError("fit: case " + std::to_string(r.case_number) + " has no Embree time to normalise by (use --target min)");
    auto [it, fresh] = least.try_emplace({r.scene, r.rays}, r.embree_ns_per_ray_min);
    if (!fresh) it->second = std::min(it->second, r.embree_ns_per_ray_min);
  }
  for (RunRecord& r : runs) {
    const double scale = least[{r.scene, r.rays}] / r.embree_ns_per_ray_min;
    r.ns_per_ray_min *= scale;
    r.ns_per_ray_median *= scale;
    r.ns_per_ray_max *= scale;
  }
  return runs;
}

CostModelSet fit_cost_model_set(const std::vector<RunRecord>& measured, const FitOptions& options, FitTarget target,
                                const std::function<void(const std::string&)>& progress) {
  if (measured.empty()) throw InputError("fit: the data set is empty");
  for (const RunRecord& r : measured)
    if (!(r.ns_per_ray_min > 0)) throw InputError("fit: case " + std::to_string(r.case_number) + " has no positive time");
  const std::vector<RunRecord> runs = with_fit_target(measured, target);
  CostModelSet set;
  set.target = target;
  set.created = utc_timestamp();
  set.rows = runs.size();
  set.options = options;
  std::set<std::string> families, hosts, cpus, revisions;
  for (const RunRecord& r : runs) {
    families.insert(r.family);
    hosts.insert(r.host);
    cpus.insert(r.cpu_model);
    revisions.insert(r.git_revision);
  }
  set.hosts.assign(hosts.begin(), hosts.end());
  set.cpu_models.assign(cpus.begin(), cpus.end());
  set.git_revisions.assign(revisions.begin(), revisions.end());

  for (const std::string& name : families) {
    const std::vector<RunRecord> rows = runs_of_family(runs, name);
    FamilyModel m;
    m.family = name;
    m.rows = rows.size();
    std::set<std::string> scenes;
    for (const RunRecord& r : rows) scenes.insert(r.scene);
    m.scenes.assign(scenes.begin(), scenes.end());
    if (progress) progress(name + ": fitting the counters and tree models on " + std::to_string(rows.size()) + " rows");
    const ReplicateError replicates = replicate_error(rows);
    m.replicate_error = replicates.mape;
    m.replicate_groups = replicates.groups;
    const double replicate_sigma = replicate_log_sigma(m.replicate_error);
    try {
      m.counters = fit_level(ModelLevel::counters, rows, options, replicate_sigma);
      m.tree = fit_level(ModelLevel::tree, rows, options, replicate_sigma);
    } catch (const InputError& e) {
      throw InputError("structure family '" + name + "' (" + std::to_string(rows.size()) + " rows): " + e.what());
    }
    m.builder = builder_constants(m.tree.model, rows);
    m.builder_source = "tree";
    if (!(m.builder.c_trav > 0) || !(m.builder.c_isect > 0)) {
      m.builder = {m.counters.model.value_of("node") + m.counters.model.value_of("node_incoherent"),
                   m.counters.model.value_of("leaf"), m.counters.model.value_of("test")};
      m.builder_source = "counters";
      // A constant held at its bound 0 is not resolved by the data: it enters as its standard
      // error, the largest value the fit cannot tell from 0.
      auto resolve = [&](double& c, const char* term) {
        if (c > 0) return;
        const auto it = std::find(m.counters.model.terms.begin(), m.counters.model.terms.end(), term);
        const double se = m.counters.model.std_errors[static_cast<std::size_t>(it - m.counters.model.terms.begin())];
        if (std::isfinite(se) && se > 0) {
          c = se;
          m.builder_source = "counters, with " + std::string(term) + " at its standard error";
        }
      };
      resolve(m.builder.c_trav, "node");
      resolve(m.builder.c_isect, "test");
    }
    for (const char* feature : {"primitives", "e_inner", "e_tests", "sah_1_1"}) {
      FittedRange range{range_feature(feature, rows.front()), range_feature(feature, rows.front())};
      for (const RunRecord& r : rows) {
        range.lo = std::min(range.lo, range_feature(feature, r));
        range.hi = std::max(range.hi, range_feature(feature, r));
      }
      m.ranges[feature] = range;
    }
    set.families[name] = std::move(m);
  }
  if (progress) progress("fitting the build-time and scene-level models");
  std::vector<std::string> scenes;
  for (const RunRecord& r : runs) scenes.push_back(r.scene);
  const SceneFeatureTable features = load_scene_features(scenes, progress);
  set.build = fit_build_time_models(measured, features, options, progress);
  set.scene_trace = fit_scene_trace_models(runs, features, options, progress);
  set.trace_effects = fit_spec_trace_effects(runs);
  return set;
}

}  // namespace raylab
