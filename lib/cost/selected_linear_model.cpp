#include "cost/selected_linear_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "cost/cost_model.h"
#include "cost/replicates.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

using Json = nlohmann::ordered_json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Fits of the reweighting (the weights settle within a few rounds).
constexpr int kReweightingRounds = 4;
/// A prediction below this fraction of its measurement weighs as if it were this fraction.
constexpr double kLeastPredictedFraction = 0.1;

double log_residual(double predicted, double measured) {
  return std::abs(std::log(std::max(predicted, 1e-300) / measured));
}

struct Design {
  std::vector<std::string> terms;
  std::vector<double> scale;  ///< each column divided by its largest |value|, so Ceres sees O(1) numbers
};

Design design_of(const std::vector<std::string>& terms, const std::vector<FeatureRow>& x) {
  Design d{terms, std::vector<double>(terms.size(), 1.0)};
  for (std::size_t j = 0; j < terms.size(); ++j) {
    double largest = 0;
    for (const FeatureRow& row : x) largest = std::max(largest, std::abs(row.at(terms[j])));
    if (largest > 0) d.scale[j] = largest;
  }
  return d;
}

std::vector<double> scaled_row(const Design& d, const FeatureRow& row) {
  std::vector<double> r(d.terms.size());
  for (std::size_t j = 0; j < d.terms.size(); ++j) r[j] = row.at(d.terms[j]) / d.scale[j];
  return r;
}

/// Fits `terms` on the rows `use` selects; values and standard errors in the features' own units.
SelectedLinearModel fit_terms(const std::vector<std::string>& terms, const std::vector<FeatureRow>& x,
                              const std::vector<double>& y, const std::vector<bool>& use, const FitOptions& options,
                              FitResult* details = nullptr) {
  std::vector<FeatureRow> rows;
  std::vector<double> ys;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (use[i]) {
      rows.push_back(x[i]);
      ys.push_back(y[i]);
    }
  const Design d = design_of(terms, rows);
  std::vector<std::vector<double>> a;
  for (const FeatureRow& row : rows) a.push_back(scaled_row(d, row));
  // Residuals (ŷ - y)/√(y·ŷ), the first-order ln(ŷ/y), by reweighting: absolute residuals of rows
  // scaled by w_i = 1/√(y_i·ŷ_i) of the previous fit, starting from ŷ = y (relative residuals).
  FitOptions weighted = options;
  weighted.residual = ResidualKind::absolute;
  weighted.loss_scale = 0;
  std::vector<double> predicted = ys;
  FitResult fit;
  for (int round = 0; round < kReweightingRounds; ++round) {
    std::vector<std::vector<double>> aw = a;
    std::vector<double> yw = ys;
    for (std::size_t i = 0; i < ys.size(); ++i) {
      const double w = 1.0 / std::sqrt(ys[i] * std::max(predicted[i], kLeastPredictedFraction * ys[i]));
      for (double& v : aw[i]) v *= w;
      yw[i] *= w;
    }
    fit = fit_linear_terms(aw, yw, weighted);
    for (std::size_t i = 0; i < ys.size(); ++i) predicted[i] = predict_linear_terms(fit.values, a[i]);
  }
  fit.mape = mean_absolute_percentage_error(predicted, ys);
  fit.r2 = coefficient_of_determination(predicted, ys);
  SelectedLinearModel m;
  m.terms = terms;
  for (std::size_t j = 0; j < terms.size(); ++j) {
    m.values.push_back(fit.values[j] / d.scale[j]);
    m.std_errors.push_back(fit.std_errors[j] / d.scale[j]);
  }
  if (details) *details = fit;
  return m;
}

struct CrossValidation {
  bool valid = false;
  std::vector<double> predicted;
  double mape = kNaN;
};

CrossValidation leave_one_scene_out(const std::vector<std::string>& terms, const std::vector<FeatureRow>& x,
                                    const std::vector<double>& y, const std::vector<std::string>& scenes,
                                    const FitOptions& options) {
  CrossValidation cv;
  cv.predicted.assign(x.size(), kNaN);
  const std::set<std::string> names(scenes.begin(), scenes.end());
  if (names.size() < 2) return cv;
  for (const std::string& held : names) {
    std::vector<bool> use(x.size());
    std::size_t train = 0;
    for (std::size_t i = 0; i < x.size(); ++i) train += (use[i] = scenes[i] != held);
    if (train < terms.size()) return cv;
    try {
      const SelectedLinearModel m = fit_terms(terms, x, y, use, options);
      for (std::size_t i = 0; i < x.size(); ++i)
        if (!use[i]) cv.predicted[i] = m.predict(x[i]);
    } catch (const InputError&) {
      return cv;
    }
  }
  cv.mape = mean_absolute_percentage_error(cv.predicted, y);
  cv.valid = std::isfinite(cv.mape);
  return cv;
}

Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

}  // namespace

double SelectedLinearModel::predict(const FeatureRow& features) const {
  double s = 0;
  for (std::size_t j = 0; j < terms.size(); ++j) s += values[j] * features.at(terms[j]);
  return s;
}

double SelectedLinearModel::extrapolation_factor(double primitives) const {
  if (primitives > range_hi && range_hi > 0) return primitives / range_hi;
  if (primitives < range_lo && primitives > 0) return range_lo / primitives;
  return 1.0;
}

std::pair<double, double> SelectedLinearModel::interval90(const FeatureRow& features, double primitives) const {
  const double y = predict(features);
  const double q = log_q90 * range_widening(extrapolation_factor(primitives));
  return {y * std::exp(-q), y * std::exp(q)};
}

double SelectedLinearModel::value_of(const std::string& term) const {
  const auto it = std::find(terms.begin(), terms.end(), term);
  return it == terms.end() ? 0.0 : values[static_cast<std::size_t>(it - terms.begin())];
}

double SelectedLinearModel::std_error_of(const std::string& term) const {
  const auto it = std::find(terms.begin(), terms.end(), term);
  return it == terms.end() ? kNaN : std_errors[static_cast<std::size_t>(it - terms.begin())];
}

SelectedLinearModel fit_selected_linear_model(const std::vector<LinearTermDoc>& candidates,
                                              const std::vector<FeatureRow>& x, const std::vector<double>& y,
                                              const std::vector<std::string>& scenes,
                                              const std::vector<double>& primitives, const FitOptions& options) {
  if (x.empty() || x.size() != y.size() || x.size() != scenes.size() || x.size() != primitives.size())
    throw InputError("fit: no rows, or rows, times, scenes and sizes of unequal count");
  std::vector<std::string> present;
  std::vector<bool> is_required;
  for (const LinearTermDoc& t : candidates) {
    bool any = false;
    for (const FeatureRow& row : x) any |= row.at(t.name) != 0.0;
    if (!any && !t.required) continue;
    present.push_back(t.name);
    is_required.push_back(t.required);
  }
  auto terms_of = [&](const std::vector<bool>& keep) {
    std::vector<std::string> t;
    for (std::size_t j = 0; j < present.size(); ++j)
      if (keep[j]) t.push_back(present[j]);
    return t;
  };
  std::vector<bool> keep(present.size(), true);
  CrossValidation cv = leave_one_scene_out(present, x, y, scenes, options);
  // One step of selection: the optional term whose removal (`add` false) or addition (`add` true)
  // gives the lowest held-out MAPE, applied to `keep` and `cv`; false when none does as well as
  // `cv` (a removal may keep the error, an addition must lower it).
  auto step = [&](bool add) {
    int best = -1;
    CrossValidation best_cv = cv;
    for (std::size_t j = 0; j < present.size(); ++j) {
      if (is_required[j] || keep[j] == add) continue;
      std::vector<bool> trial = keep;
      trial[j] = add;
      const CrossValidation c = leave_one_scene_out(terms_of(trial), x, y, scenes, options);
      if (c.valid && (add ? c.mape < best_cv.mape : c.mape <= best_cv.mape)) {
        best_cv = c;
        best = static_cast<int>(j);
      }
    }
    if (best < 0) return false;
    keep[static_cast<std::size_t>(best)] = add;
    cv = best_cv;
    return true;
  };
  if (cv.valid) {
    while (step(false)) {
    }
  } else {  // too few scenes for every term: the required ones, then optional ones added forward
    for (std::size_t j = 0; j < present.size(); ++j) keep[j] = is_required[j];
    cv = leave_one_scene_out(terms_of(keep), x, y, scenes, options);
    while (cv.valid && step(true)) {
    }
  }
  const std::vector<std::string> terms = terms_of(keep);
  FitResult fit;
  SelectedLinearModel m = fit_terms(terms, x, y, std::vector<bool>(x.size(), true), options, &fit);
  m.rows = x.size();
  m.scenes = std::set<std::string>(scenes.begin(), scenes.end()).size();
  m.range_lo = *std::min_element(primitives.begin(), primitives.end());
  m.range_hi = *std::max_element(primitives.begin(), primitives.end());
  m.cross_validated = cv.valid;
  if (cv.valid) {
    std::vector<double> residuals(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) residuals[i] = log_residual(cv.predicted[i], y[i]);
    m.held_out_mape = cv.mape;
    m.log_q90 = quantile90(residuals);
    std::size_t inside = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      std::vector<double> others;
      for (std::size_t k = 0; k < x.size(); ++k)
        if (scenes[k] != scenes[i]) others.push_back(residuals[k]);
      inside += residuals[i] <= quantile90(others);
    }
    m.coverage90 = static_cast<double>(inside) / static_cast<double>(x.size());
  } else {
    std::vector<double> residuals;
    for (std::size_t i = 0; i < x.size(); ++i) residuals.push_back(log_residual(m.predict(x[i]), y[i]));
    const double n = static_cast<double>(x.size()), k = static_cast<double>(terms.size());
    m.log_q90 = quantile90(residuals) * (n > k ? std::sqrt(n / (n - k)) : 2.0);
    m.held_out_mape = m.coverage90 = kNaN;
  }
  return m;
}

Json selected_linear_model_json(const SelectedLinearModel& m) {
  Json values = Json::array(), errors = Json::array();
  for (std::size_t j = 0; j < m.terms.size(); ++j) {
    values.push_back(m.values[j]);
    errors.push_back(number_or_null(m.std_errors[j]));
  }
  return {{"terms", m.terms},
          {"values", values},
          {"std_errors", errors},
          {"held_out",
           {{"cross_validated", m.cross_validated},
            {"mape", number_or_null(m.held_out_mape)},
            {"coverage90", number_or_null(m.coverage90)}}},
          {"log_q90", m.log_q90},
          {"rows", m.rows},
          {"scenes", m.scenes},
          {"range", {{"lo", m.range_lo}, {"hi", m.range_hi}}}};
}

SelectedLinearModel read_selected_linear_model(const Json& j, const std::string& where,
                                               const std::vector<LinearTermDoc>& candidates) {
  auto at = [&](const Json& o, const std::string& key, const std::string& path) -> const Json& {
    if (!o.is_object() || !o.contains(key)) throw InputError(path + ": missing key '" + key + "'");
    return o.at(key);
  };
  auto number = [&](const Json& v, const std::string& path, bool nullable) {
    if (nullable && v.is_null()) return kNaN;
    if (!v.is_number() || !std::isfinite(v.get<double>())) throw InputError(path + ": expected a finite number");
    return v.get<double>();
  };
  auto numbers = [&](const std::string& key, bool nullable) {
    const Json& v = at(j, key, where);
    if (!v.is_array()) throw InputError(where + "." + key + ": expected a list of numbers");
    std::vector<double> out;
    for (std::size_t k = 0; k < v.size(); ++k)
      out.push_back(number(v[k], where + "." + key + "[" + std::to_string(k) + "]", nullable));
    return out;
  };
  SelectedLinearModel m;
  const Json& terms = at(j, "terms", where);
  if (!terms.is_array() || terms.empty()) throw InputError(where + ".terms: expected a non-empty list of term names");
  for (const Json& t : terms) {
    const bool known = t.is_string() && std::any_of(candidates.begin(), candidates.end(), [&](const LinearTermDoc& c) {
                         return c.name == t.get<std::string>();
                       });
    if (!known) {
      std::string valid;
      for (const LinearTermDoc& c : candidates) valid += (valid.empty() ? "" : ", ") + c.name;
      throw InputError(where + ".terms: " + t.dump() + " is not a term (valid: " + valid + ")");
    }
    m.terms.push_back(t.get<std::string>());
  }
  m.values = numbers("values", false);
  m.std_errors = numbers("std_errors", true);
  if (m.values.size() != m.terms.size() || m.std_errors.size() != m.terms.size())
    throw InputError(where + ": terms, values and std_errors of unequal length");
  const Json& held = at(j, "held_out", where);
  const Json& cv = at(held, "cross_validated", where + ".held_out");
  if (!cv.is_boolean()) throw InputError(where + ".held_out.cross_validated: expected true or false");
  m.cross_validated = cv.get<bool>();
  m.held_out_mape = number(at(held, "mape", where + ".held_out"), where + ".held_out.mape", true);
  m.coverage90 = number(at(held, "coverage90", where + ".held_out"), where + ".held_out.coverage90", true);
  m.log_q90 = number(at(j, "log_q90", where), where + ".log_q90", false);
  if (m.log_q90 < 0) throw InputError(where + ".log_q90: must not be negative");
  m.rows = static_cast<std::size_t>(number(at(j, "rows", where), where + ".rows", false));
  m.scenes = static_cast<std::size_t>(number(at(j, "scenes", where), where + ".scenes", false));
  const Json& range = at(j, "range", where);
  m.range_lo = number(at(range, "lo", where + ".range"), where + ".range.lo", false);
  m.range_hi = number(at(range, "hi", where + ".range"), where + ".range.hi", false);
  return m;
}

}  // namespace raylab
