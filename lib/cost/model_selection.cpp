#include "cost/model_selection.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>

#include "geometry/input_error.h"

namespace raylab {
namespace {

std::vector<double> measured_times(const std::vector<RunRecord>& runs) {
  std::vector<double> y;
  y.reserve(runs.size());
  for (const RunRecord& r : runs) y.push_back(r.ns_per_ray_min);
  return y;
}

std::vector<std::vector<double>> design(ModelLevel level, const std::vector<std::string>& terms,
                                        const std::vector<RunRecord>& runs) {
  std::vector<std::vector<double>> x;
  x.reserve(runs.size());
  for (const RunRecord& r : runs) x.push_back(feature_row(level, terms, r));
  return x;
}

/// Bit j set: candidate j is in the subset.
using TermMask = std::uint32_t;

std::vector<std::string> terms_of(TermMask mask, const std::vector<std::string>& candidates) {
  std::vector<std::string> t;
  for (std::size_t j = 0; j < candidates.size(); ++j)
    if (mask >> j & 1u) t.push_back(candidates[j]);
  return t;
}

/// MAPE of the held-out predictions over the runs `rows` selects.
double held_out_error(const HeldOutPrediction& p, const std::vector<RunRecord>& runs,
                      const std::function<bool(const RunRecord&)>& rows) {
  std::vector<double> predicted, measured;
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (rows(runs[i])) {
      predicted.push_back(p.predicted[i]);
      measured.push_back(runs[i].ns_per_ray_min);
    }
  return measured.empty() ? 0.0 : mean_absolute_percentage_error(predicted, measured);
}

}  // namespace

FittedCostModel fit_cost_model(ModelLevel level, const std::vector<std::string>& terms,
                               const std::vector<RunRecord>& runs, const FitOptions& options, FitResult* details) {
  const FitResult fit = fit_linear_terms(design(level, terms, runs), measured_times(runs), options);
  FittedCostModel m;
  m.level = level;
  m.terms = terms;
  m.values = fit.values;
  m.std_errors = fit.std_errors;
  m.covariance = fit.covariance;
  if (details) *details = fit;
  return m;
}

HeldOutPrediction leave_one_scene_out(ModelLevel level, const std::vector<std::string>& terms,
                                      const std::vector<RunRecord>& runs, const FitOptions& options) {
  HeldOutPrediction out;
  out.predicted.assign(runs.size(), std::numeric_limits<double>::quiet_NaN());
  out.parameter_log_variance.assign(runs.size(), std::numeric_limits<double>::quiet_NaN());
  std::set<std::string> scenes;
  for (const RunRecord& r : runs) scenes.insert(r.scene);
  if (scenes.size() < 2) return out;
  // The folds are independent Ceres problems: fitted in parallel.
  const std::vector<std::string> held_out(scenes.begin(), scenes.end());
  std::atomic<bool> failed{false};
  tbb::parallel_for(std::size_t{0}, held_out.size(), [&](std::size_t s) {
    std::vector<RunRecord> train;
    for (const RunRecord& r : runs)
      if (r.scene != held_out[s]) train.push_back(r);
    try {
      const FittedCostModel model = fit_cost_model(level, terms, train, options);
      for (std::size_t i = 0; i < runs.size(); ++i)
        if (runs[i].scene == held_out[s]) {
          out.predicted[i] = model.predict(runs[i]);
          out.parameter_log_variance[i] = model.parameter_log_variance(runs[i]);
        }
    } catch (const InputError&) {  // fewer rows than terms without this scene
      failed = true;
    }
  });
  if (failed) return out;
  const std::vector<double> y = measured_times(runs);
  out.mape = mean_absolute_percentage_error(out.predicted, y);
  out.r2 = coefficient_of_determination(out.predicted, y);
  out.valid = true;
  return out;
}

double held_out_log_sigma(const HeldOutPrediction& p, const std::vector<RunRecord>& runs,
                          const std::string& except_scene) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < runs.size() && i < p.predicted.size(); ++i) {
    if (runs[i].scene == except_scene || !(p.predicted[i] > 0) || !(runs[i].ns_per_ray_min > 0)) continue;
    const double e = std::log(runs[i].ns_per_ray_min / p.predicted[i]);
    sum += e * e;
    ++n;
  }
  return n ? std::sqrt(sum / static_cast<double>(n)) : std::numeric_limits<double>::quiet_NaN();
}

double held_out_coverage90(const HeldOutPrediction& p, const std::vector<RunRecord>& runs, double replicate_log_sigma) {
  if (!p.valid || runs.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::map<std::string, double> sigma_without;  // s_res of the other scenes' held-out rows, per scene
  std::size_t inside = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    auto it = sigma_without.find(runs[i].scene);
    if (it == sigma_without.end())
      it = sigma_without.emplace(runs[i].scene, held_out_log_sigma(p, runs, runs[i].scene)).first;
    const double noise = std::isfinite(replicate_log_sigma) ? std::max(it->second, replicate_log_sigma) : it->second;
    const double parameter = std::isfinite(p.parameter_log_variance[i]) ? p.parameter_log_variance[i] : 0.0;
    const IntervalPrediction interval = log_normal_interval90(p.predicted[i], std::sqrt(parameter + noise * noise));
    const double y = runs[i].ns_per_ray_min;
    if (y >= interval.lo && y <= interval.hi) ++inside;  // false for a NaN interval
  }
  return static_cast<double>(inside) / static_cast<double>(runs.size());
}

TermSelection select_terms(ModelLevel level, const std::vector<RunRecord>& runs, const FitOptions& options) {
  if (runs.empty()) throw InputError("model selection: no runs");
  TermSelection sel;
  std::vector<std::string> candidates;
  std::vector<bool> required;
  for (const CostTerm& t : cost_terms(level)) {
    bool any = false;
    for (const RunRecord& r : runs) any |= t.feature(r) != 0.0;
    if (!any) {
      sel.unused.push_back(t.name);
      continue;
    }
    candidates.push_back(t.name);
    required.push_back(t.required);
  }
  if (candidates.empty()) throw InputError("model selection: every feature of the " + std::string(level_name(level)) + " model is 0");

  std::set<std::string> scenes;
  for (const RunRecord& r : runs) scenes.insert(r.scene);
  sel.cross_validated = scenes.size() >= 2;

  std::map<TermMask, HeldOutPrediction> cv_cache;
  auto cross_validation = [&](TermMask mask) -> const HeldOutPrediction& {
    auto it = cv_cache.find(mask);
    if (it == cv_cache.end())
      it = cv_cache.emplace(mask, leave_one_scene_out(level, terms_of(mask, candidates), runs, options)).first;
    return it->second;
  };
  auto score = [&](TermMask mask) {
    ScoredModel s;
    s.terms = terms_of(mask, candidates);
    s.in_sample_mape = s.aic = s.bic = std::numeric_limits<double>::infinity();
    try {
      FitResult fit;
      fit_cost_model(level, s.terms, runs, options, &fit);
      s.in_sample_mape = fit.mape;
      s.aic = fit.aic;
      s.bic = fit.bic;
    } catch (const InputError&) {  // more terms than rows: not a candidate
    }
    const HeldOutPrediction& cv = cross_validation(mask);
    s.held_out_mape = cv.valid ? cv.mape : std::numeric_limits<double>::infinity();
    return s;
  };
  // The error a subset is judged by: held-out MAPE over the rows `rows` picks, or BIC without
  // cross-validation.
  auto eliminate = [&](const std::function<bool(const RunRecord&)>& rows, std::vector<ScoredModel>* path,
                       std::vector<std::string>* dropped) {
    auto error_of = [&](TermMask mask) {
      if (!sel.cross_validated) return score(mask).bic;
      const HeldOutPrediction& cv = cross_validation(mask);
      return cv.valid ? held_out_error(cv, runs, rows) : std::numeric_limits<double>::infinity();
    };
    TermMask current = (TermMask{1} << candidates.size()) - 1;
    double error = error_of(current);
    if (path) path->push_back(score(current));
    for (;;) {
      int best_term = -1;
      double best_error = error;
      for (std::size_t j = 0; j < candidates.size(); ++j) {
        if (!(current >> j & 1u) || required[j]) continue;
        const double e = error_of(current & ~(TermMask{1} << j));
        if (e <= best_error) {
          best_error = e;
          best_term = static_cast<int>(j);
        }
      }
      if (best_term < 0) break;
      current &= ~(TermMask{1} << best_term);
      error = best_error;
      if (dropped) dropped->push_back(candidates[static_cast<std::size_t>(best_term)]);
      if (path) path->push_back(score(current));
    }
    return current;
  };

  const TermMask chosen = eliminate([](const RunRecord&) { return true; }, &sel.path, &sel.dropped);
  sel.terms = terms_of(chosen, candidates);
  sel.held_out = cross_validation(chosen);
  if (sel.cross_validated) {
    std::set<std::string> families;
    for (const RunRecord& r : runs) families.insert(r.scene_family);
    for (const std::string& f : families)
      sel.by_scene_family[f] =
          terms_of(eliminate([&](const RunRecord& r) { return r.scene_family == f; }, nullptr, nullptr), candidates);
  }
  return sel;
}

}  // namespace raylab
