#include "cost/model_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "cost/output_file.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

LevelFit fit_level(ModelLevel level, const std::vector<RunRecord>& runs, const FitOptions& options) {
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
  for (RunRecord& r : runs) r.ns_per_ray_min *= least[{r.scene, r.rays}] / r.embree_ns_per_ray_min;
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
    try {
      m.counters = fit_level(ModelLevel::counters, rows, options);
      m.tree = fit_level(ModelLevel::tree, rows, options);
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
    auto range_of = [&](double (*f)(const RunRecord&)) {
      FittedRange range{f(rows.front()), f(rows.front())};
      for (const RunRecord& r : rows) {
        range.lo = std::min(range.lo, f(r));
        range.hi = std::max(range.hi, f(r));
      }
      return range;
    };
    m.ranges["primitives"] = range_of([](const RunRecord& r) { return static_cast<double>(r.primitives); });
    m.ranges["e_inner"] = range_of([](const RunRecord& r) { return r.e_inner; });
    m.ranges["e_tests"] = range_of([](const RunRecord& r) { return r.e_tests; });
    m.ranges["sah_1_1"] = range_of([](const RunRecord& r) { return r.sah_1_1; });
    set.families[name] = std::move(m);
  }
  if (progress) progress("fitting the build-time and scene-level models");
  set.build = fit_build_time_models(measured, options, progress);
  set.scene_trace = fit_scene_trace_models(runs, options, progress);
  return set;
}

}  // namespace raylab
