#pragma once
/// The cost model: ns per ray as a sum of named terms, each a feature of a run times a
/// non-negative constant (nanoseconds per event), fitted per structure family (fit.h).
///
/// Two levels (the lecture's Cost(node) = C_trav + P(L)·Cost(L) + P(R)·Cost(R), measured):
///  - `counters`: time from the measured counters of a traced pass (the machine constants):
///      ns/ray = c0 + c_node·nodes + c_leaf·leaves + c_test·tests [+ corrections];
///    c_node : c_test is the lecture's C_trav : C_isect, measured.
///  - `tree`: time from the structure alone (what a builder can use): the same form on the
///    surface-area expectations of tree_features.h, with correction terms (end-point overlap,
///    SIMD leaf granularity, memory, rays that start inside the scene or stop at any hit).
///
/// The candidate terms of a level are one list; a model is a subset of it that keeps the
/// level's required terms, so model selection (model_selection.h) is a loop over subsets.
///
/// 90% prediction intervals. Times are positive and their errors relative, so an interval is
/// symmetric in log space. For a run with feature row x and prediction ŷ = cᵀx > 0,
///
///   s²  = xᵀΣx / ŷ²  +  max(s_res², s_rep²)
///   lo, hi = ŷ · exp(∓ z₉₀ · s · w),   z₉₀ = Φ⁻¹(0.95) = 1.645,
///
/// where Σ is the constants' covariance (fit.h: σ²(JᵀJ)⁻¹; xᵀΣx/ŷ² is the variance of ln ŷ by the
/// delta method), s_res the spread of ln(measured/predicted) of the fit (held-out predictions
/// when cross-validated: model_selection.h), s_rep the spread one measurement has when the same
/// case is measured again (model_fit.h: replicate_log_sigma), and w ≥ 1 the widening outside the
/// fitted range (model_fit.h: RangeCheck::widening, 1 + log2 of the factor outside). The residual
/// spread already contains the machine's noise, so the replicate noise enters as a floor rather
/// than a second time: no model predicts a time tighter than the machine repeats it.
#include <limits>
#include <string>
#include <vector>

#include "cost/run_record.h"

namespace raylab {

enum class ModelLevel { counters, tree };

const char* level_name(ModelLevel level);

struct CostTerm {
  std::string name;
  std::string meaning;  ///< what the feature counts, for listings and model.json
  bool required = false;  ///< kept by model selection (the lecture's two constants)
  double (*feature)(const RunRecord&) = nullptr;
};

/// The candidate terms of a level, in listing order.
const std::vector<CostTerm>& cost_terms(ModelLevel level);

/// The term named `name` of `level`; throws InputError naming the valid ones.
const CostTerm& find_cost_term(ModelLevel level, const std::string& name);

/// The feature row of `terms` (names of `level`) for one run.
std::vector<double> feature_row(ModelLevel level, const std::vector<std::string>& terms, const RunRecord& run);

/// z of a two-sided 90% normal interval, Φ⁻¹(0.95).
inline constexpr double kZ90 = 1.6448536269514722;

/// A prediction (ns per ray) with its 90% interval.
struct IntervalPrediction {
  double ns = 0.0;
  /// ns·exp(∓kZ90·log_sigma·widening); NaN when unknown (a prediction ≤ 0, or no noise scale).
  double lo = std::numeric_limits<double>::quiet_NaN(), hi = std::numeric_limits<double>::quiet_NaN();
  double log_sigma = std::numeric_limits<double>::quiet_NaN();  ///< s above, before widening
  double widening = 1.0;                                         ///< w above
};

/// The interval of a log-normal prediction: `predicted`·exp(∓kZ90·`log_sigma`·`widening`). For
/// any model with a log-space spread (the build-time model too); lo = hi = NaN when predicted ≤ 0
/// or log_sigma is not finite.
IntervalPrediction log_normal_interval90(double predicted, double log_sigma, double widening = 1.0);

/// w = 1 + log2(factor) for factor > 1, else 1: the interval widening outside a fitted range,
/// `factor` the most a feature lies outside it (model_fit.h: check_feature_range). Every model's
/// interval widens by this one rule (the build-time and scene-level models too).
double range_widening(double factor);

/// A fitted model of one level for one structure family.
struct FittedCostModel {
  ModelLevel level = ModelLevel::counters;
  std::vector<std::string> terms;
  std::vector<double> values;      ///< ns per unit of each term's feature
  std::vector<double> std_errors;  ///< NaN where unknown
  /// The constants' covariance Σ (ns², k×k row-major, fit.h); empty when unknown (a fit with no
  /// more rows than terms, or a version-1 model file).
  std::vector<double> covariance;
  /// s_res above: the standard deviation of ln(measured/predicted), about 0 (leave-one-scene-out
  /// predictions when cross-validated, else in-sample with n - k degrees of freedom); NaN unknown.
  double residual_log_sigma = std::numeric_limits<double>::quiet_NaN();

  double predict(const RunRecord& run) const;
  /// xᵀΣx/ŷ², the variance of ln ŷ from the constants' uncertainty; 0 without a covariance, NaN
  /// when ŷ ≤ 0.
  double parameter_log_variance(const RunRecord& run) const;
  /// The prediction and its 90% interval (formula above); `replicate_log_sigma` NaN: no floor.
  IntervalPrediction predict_interval(const RunRecord& run,
                                      double replicate_log_sigma = std::numeric_limits<double>::quiet_NaN(),
                                      double widening = 1.0) const;
  /// The value of term `name`, 0 when the model does not have it.
  double value_of(const std::string& name) const;
  bool has(const std::string& name) const;
};

}  // namespace raylab
