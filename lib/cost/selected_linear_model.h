#pragma once
/// A linear model in named terms (fit.h, fitted with Ceres) whose terms are chosen by
/// leave-one-group-out cross-validation, with a 90% prediction interval from its held-out
/// residuals: the form of the build-time model (build_time_model.h) and of the scene-level trace
/// model (scene_trace_model.h). A group is a scene: every fold predicts one scene's rows from a
/// model fitted on the other scenes'.
///
/// Residuals: (ŷ - y)/√(y·ŷ), the first-order ln(ŷ/y), symmetric in over- and under-prediction
/// (relative residuals (ŷ - y)/y bound under-prediction by 1 and so bias a fit low when times
/// spread by factors, as build times do across scenes), by reweighted fits with absolute
/// residuals (fit.h) and plain least squares: with a robust loss the reweighting can settle on the
/// scenes it already predicts and ignore the rest (a Huber scale of 10% did so on build times
/// spread tenfold), so these models take no Huber loss, whatever the options say.
///
/// Selection: backward elimination as in model_selection.h: start from every candidate term whose
/// feature is not 0 on every row, drop the optional term whose removal gives the lowest held-out
/// MAPE while that error does not rise, stop when every removal raises it. With too few scenes
/// to hold out a fit of every term, forward instead: from the required terms, add the optional
/// term that lowers the held-out MAPE most, while one does and the scenes can hold the fit out.
///
/// Interval: q90 = the 90% quantile of |ln(y/ŷ)| over the held-out predictions ŷ of the selected
/// model; the interval is [ŷ·e^-q, ŷ·e^q], widened outside the fitted range of primitives N to
/// q·(1 + |log2(N/nearest bound)|). Its coverage is measured on data that did not set it: each
/// scene's held-out rows against the q90 of the other scenes' held-out residuals; `coverage90` is
/// the fraction inside (with one row per scene, (n - 1)/n for n scenes by construction: a
/// conformal interval). Without cross-validation (fewer scenes than required terms + 1) only the required
/// terms are fitted, q90 comes from the in-sample residuals (scaled by sqrt(n/(n-k))) and the
/// held-out figures are NaN.
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cost/fit.h"

namespace raylab {

/// A candidate term: its feature's name, what it is, and whether selection keeps it always.
struct LinearTermDoc {
  std::string name;
  std::string meaning;
  bool required = false;
};

/// The features of one row (or one prediction), by term name.
using FeatureRow = std::map<std::string, double>;

struct SelectedLinearModel {
  std::vector<std::string> terms;
  std::vector<double> values;      ///< per unit of each term's feature
  std::vector<double> std_errors;  ///< NaN where Ceres' covariance could not be computed
  std::size_t rows = 0, scenes = 0;
  bool cross_validated = false;
  double held_out_mape = 0.0;  ///< a fraction; NaN without cross-validation
  double coverage90 = 0.0;     ///< fraction of held-out rows inside their interval; NaN without
  double log_q90 = 0.0;        ///< q of the interval, in natural-log units
  double range_lo = 0.0, range_hi = 0.0;  ///< primitives N of the rows

  double predict(const FeatureRow& features) const;
  /// The factor by which `primitives` is outside [range_lo, range_hi]; 1 inside.
  double extrapolation_factor(double primitives) const;
  /// The 90% interval of predict(features) for a scene of `primitives`.
  std::pair<double, double> interval90(const FeatureRow& features, double primitives) const;
  double value_of(const std::string& term) const;  ///< 0 when the model lacks the term
  double std_error_of(const std::string& term) const;
};

/// Fits `candidates` to y (> 0, relative residuals as `options` says) over rows `x`, one scene
/// name per row in `scenes` and its primitive count in `primitives`. Throws InputError when the
/// required terms cannot be fitted (fewer rows than terms).
SelectedLinearModel fit_selected_linear_model(const std::vector<LinearTermDoc>& candidates,
                                              const std::vector<FeatureRow>& x, const std::vector<double>& y,
                                              const std::vector<std::string>& scenes,
                                              const std::vector<double>& primitives, const FitOptions& options);

/// The model as model.json stores it: {terms, values, std_errors, held_out: {cross_validated,
/// mape, coverage90}, log_q90, rows, scenes, range: {lo, hi}} (NaN as null).
nlohmann::ordered_json selected_linear_model_json(const SelectedLinearModel& m);

/// Reads what selected_linear_model_json wrote; InputError naming `where` and the key otherwise,
/// or when a term is not one of `candidates`.
SelectedLinearModel read_selected_linear_model(const nlohmann::ordered_json& j, const std::string& where,
                                               const std::vector<LinearTermDoc>& candidates);

}  // namespace raylab
