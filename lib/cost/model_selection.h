#pragma once
/// "No more model than a scene needs": choosing the terms of a cost model (cost_model.h) by
/// leave-one-scene-out cross-validation, with AIC and BIC reported beside it.
///
/// The held-out error of a term subset: every scene's rows are predicted by the model fitted on
/// the other scenes' rows; the error is the mean absolute percentage error (MAPE) of those
/// predictions. Selection is backward elimination over the level's candidate terms (those whose
/// feature is not zero on every row): start from all of them, drop the optional term whose
/// removal gives the lowest held-out error as long as that error is not higher than with the
/// term, and stop when every removal raises it. A term that does not lower held-out error is
/// therefore dropped. The same elimination, scoring only the held-out rows of one scene family,
/// gives the terms that family needs (`by_scene_family`).
///
/// With fewer than two scenes there is nothing to hold out: the in-sample BIC decides instead,
/// and `cross_validated` is false.
///
/// Coverage of the 90% intervals (cost_model.h), measured on held-out scenes: a row of scene S
/// gets the prediction and the constants' covariance of the model fitted without S, and the
/// residual spread s_res of the held-out predictions of every other scene (so S's own errors do
/// not widen its interval), with the replicate floor; coverage90 is the share of rows whose
/// measured time lies inside. A held-out prediction ≤ 0 counts as outside. Replicate rows share
/// their scene, so they are always held out together.
#include <map>
#include <string>
#include <vector>

#include "cost/cost_model.h"
#include "cost/fit.h"
#include "cost/run_record.h"

namespace raylab {

struct HeldOutPrediction {
  std::vector<double> predicted;  ///< per run, from the model fitted without the run's scene
  /// per run, xᵀΣx/ŷ² of that model (cost_model.h: parameter_log_variance)
  std::vector<double> parameter_log_variance;
  double mape = 0.0;
  double r2 = 0.0;
  bool valid = false;  ///< false with fewer than two scenes, or when a fold could not be fitted
};

/// Leave-one-scene-out predictions of `terms` over `runs`.
HeldOutPrediction leave_one_scene_out(ModelLevel level, const std::vector<std::string>& terms,
                                      const std::vector<RunRecord>& runs, const FitOptions& options);

/// sqrt(mean ln²(measured/predicted)) over the held-out rows whose scene is not `except_scene`
/// (empty: every row) and whose prediction is positive; NaN when there is none.
double held_out_log_sigma(const HeldOutPrediction& p, const std::vector<RunRecord>& runs,
                          const std::string& except_scene = {});

/// The share of `runs` whose measured time lies inside its held-out 90% interval (header
/// comment), with the floor `replicate_log_sigma` (NaN: none); NaN when `p` is not valid.
double held_out_coverage90(const HeldOutPrediction& p, const std::vector<RunRecord>& runs, double replicate_log_sigma);

/// One model on the elimination path.
struct ScoredModel {
  std::vector<std::string> terms;
  double held_out_mape = 0.0;
  double in_sample_mape = 0.0;
  double aic = 0.0, bic = 0.0;
};

struct TermSelection {
  std::vector<std::string> terms;      ///< selected
  std::vector<std::string> dropped;    ///< candidates dropped, in the order they went
  std::vector<std::string> unused;     ///< candidate terms whose feature is 0 on every run
  std::vector<ScoredModel> path;       ///< the full model first, then each elimination step taken
  HeldOutPrediction held_out;          ///< of the selected model
  bool cross_validated = false;
  std::map<std::string, std::vector<std::string>> by_scene_family;
};

/// Selects the terms of `level` for `runs` (all of one structure family, ≥ 1 row per term).
TermSelection select_terms(ModelLevel level, const std::vector<RunRecord>& runs, const FitOptions& options);

/// Fits `terms` on `runs`.
FittedCostModel fit_cost_model(ModelLevel level, const std::vector<std::string>& terms,
                               const std::vector<RunRecord>& runs, const FitOptions& options, FitResult* details = nullptr);

}  // namespace raylab
