#pragma once
/// `raylab fit`: from a data set (run_record.h) to a fitted cost model per structure family, both
/// levels (cost_model.h), with selected terms (model_selection.h), uncertainties (fit.h), the
/// constants the SAH builders take (`cost=`), the range of the data each model was fitted on, and
/// the replicate error of its data.
///
/// Using a family's model: `FamilyModel::predict(level, run)` gives the prediction, its 90%
/// interval (cost_model.h) and the range check; `check_range(run)` alone answers "is this run
/// outside my data, by which feature and by what factor?".
///
/// The fitted range. A feature value v against the range lo..hi of the rows the family was fitted
/// on is outside by the factor f = v/hi above it, lo/v below it (f = 1 inside). The features
/// checked are kRangeFeatures (primitives, e_inner, e_tests); the run's factor is the worst one.
/// Outside the range (f > 1) a prediction still predicts, and its interval's half-width in log
/// space is multiplied by w = 1 + log2 f (twice as wide at a factor 2, three times at 4);
/// kStrictRangeFactor is the factor beyond which `raylab predict --strict` refuses.
///
/// Replicate error. Rows with the same (scene, accel, rays, threads) are replicates: the same
/// case measured again. A group's error is the mean over its pairs of |t1 - t2| / ((t1 + t2)/2),
/// t the fit target's time (FitTarget); the family's replicate error is the mean over its groups.
/// For log-normal noise of spread s per measurement, E|ln t1 - ln t2| = 2s/√π, so the replicate
/// spread is s_rep = replicate_error·√π/2 (the floor of every interval, cost_model.h).
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "accel/common/fitted_cost.h"
#include "cost/build_time_model.h"
#include "cost/cost_model.h"
#include "cost/fit.h"
#include "cost/model_selection.h"
#include "cost/run_record.h"
#include "cost/scene_trace_model.h"
#include "cost/spec_trace_effects.h"

namespace raylab {

struct LevelFit {
  FittedCostModel model;
  std::vector<bool> at_bound;
  double in_sample_mape = 0, in_sample_r2 = 0;
  double held_out_mape = 0, held_out_r2 = 0;  ///< leave-one-scene-out; 0 without cross-validation
  /// Share of the held-out measured times inside their 90% intervals (model_selection.h:
  /// held_out_coverage90); NaN without cross-validation or from a version-1 model file.
  double held_out_coverage90 = std::numeric_limits<double>::quiet_NaN();
  bool cross_validated = false;
  double aic = 0, bic = 0, condition_number = 0;
  bool converged = false;
  std::string solver_message;  ///< Ceres' termination message when not converged (not stored in model files)
  std::vector<std::string> dropped, unused;
  std::map<std::string, std::vector<std::string>> by_scene_family;
  std::vector<ScoredModel> path;
  std::vector<double> held_out_predictions;  ///< per row of the family (not stored in model files)
};

/// A feature's range over the rows a model was fitted on.
struct FittedRange {
  double lo = 0, hi = 0;
};

/// The features whose fitted range a prediction is checked against.
inline const std::vector<std::string> kRangeFeatures = {"primitives", "e_inner", "e_tests"};
/// `raylab predict --strict` refuses a run outside the range by more than this factor.
inline constexpr double kStrictRangeFactor = 2.0;

/// One feature of a run against its fitted range.
struct FeatureRangeCheck {
  std::string feature;
  double value = 0, lo = 0, hi = 0;
  double factor = 1.0;  ///< value/hi above, lo/value below, 1 inside (infinite for 0 below lo > 0)
  bool outside() const { return factor > 1.0; }
  bool above() const { return value > hi; }
  /// "primitives 8.89e+04 is 4.4x above the fitted 3600..20384"
  std::string describe() const;
};

/// `value` of `feature` against `range` (the factor rule of the header comment); for any model
/// with a fitted range (the build-time model's primitives too).
FeatureRangeCheck check_feature_range(const std::string& feature, double value, const FittedRange& range);

/// A run against the fitted range of every feature of kRangeFeatures that the model has.
struct RangeCheck {
  FeatureRangeCheck worst;                ///< the largest factor (factor 1 and no feature when inside)
  std::vector<FeatureRangeCheck> outside;  ///< every feature outside, in kRangeFeatures' order
  bool extrapolated() const { return worst.factor > 1.0; }
  /// w = 1 + log2(worst factor), 1 inside.
  double widening() const;
};

/// The value of range feature `name` (one of kRangeFeatures) for a run.
double range_feature(const std::string& name, const RunRecord& run);

/// A family's prediction for one run: the prediction with its (widened) interval, and the range check.
struct FamilyPrediction {
  IntervalPrediction interval;
  RangeCheck range;
};

/// The replicate error of a set of runs (header comment).
struct ReplicateError {
  double mape = std::numeric_limits<double>::quiet_NaN();  ///< NaN when no key has two rows
  std::size_t groups = 0;                                   ///< keys with two or more rows
};
ReplicateError replicate_error(const std::vector<RunRecord>& runs);

/// s_rep = mape·√π/2 (header comment); NaN for NaN.
double replicate_log_sigma(double replicate_mape);

struct FamilyModel {
  std::string family;
  std::size_t rows = 0;
  std::vector<std::string> scenes;
  LevelFit counters, tree;
  /// The SAH constants the builders take (fitted_cost.h): the tree-level constants of interior
  /// visits, leaf visits and tests, each with its ray-kind and memory corrections averaged over
  /// the rows (SIMD test groups by their mean groups per test), or the counters-level ones
  /// when the tree level has no positive interior or test constant; a counters constant held at
  /// 0 then enters as its standard error.
  FittedSahCost builder;
  std::string builder_source;  ///< "tree" or "counters[, with ... at its standard error]"
  std::map<std::string, FittedRange> ranges;  ///< primitives, e_inner, e_tests, sah_1_1
  /// Replicate error of the family's rows (fit target times): NaN when it has no replicates.
  double replicate_error = std::numeric_limits<double>::quiet_NaN();
  std::size_t replicate_groups = 0;

  /// Where `run` lies against `ranges` (header comment).
  RangeCheck check_range(const RunRecord& run) const;
  /// The `level` model's prediction for `run`, its 90% interval with the replicate floor and
  /// widened by check_range(run).widening().
  FamilyPrediction predict(ModelLevel level, const RunRecord& run) const;
  const LevelFit& level_fit(ModelLevel level) const { return level == ModelLevel::counters ? counters : tree; }
};

/// What a fit takes as each run's time.
enum class FitTarget {
  minimum,  ///< ns_per_ray_min as measured
  /// ns_per_ray_min · E*/E: the run's minimum scaled by how much Embree, timed in the same passes,
  /// was slowed against its least disturbed minimum E* over every run on the same scene and rays.
  /// Machine noise hits both structures of a pass alike, so this removes most of it.
  embree_normalized,
};

const char* target_name(FitTarget target);
/// "min" or "embree-normalized"; throws InputError otherwise.
FitTarget parse_fit_target(const std::string& name);

/// `runs` with ns_per_ray_min replaced by the time `target` takes, and the passes' median and slowest
/// (ns_per_ray_median, ns_per_ray_max) scaled by the same factor.
std::vector<RunRecord> with_fit_target(std::vector<RunRecord> runs, FitTarget target);

struct CostModelSet {
  /// Version 2 added the intervals' data (covariance, residual_log_sigma, held_out.coverage90,
  /// replicate_error); version-1 files are still read (model_file.h).
  static constexpr int kVersion = 2;
  std::string created;      ///< UTC time of the fit
  std::string runs_source;  ///< the data set's path
  std::size_t rows = 0;
  std::vector<std::string> hosts, cpu_models, git_revisions;
  FitOptions options;
  FitTarget target = FitTarget::embree_normalized;
  std::map<std::string, FamilyModel> families;
  /// Build seconds per accelerator spec (build_time_model.h) and ns per ray per spec and ray
  /// class from scene features alone (scene_trace_model.h): what `auto` chooses with before it
  /// builds. Empty in model files written without them (auto then builds every candidate).
  BuildTimeModels build;
  SceneTraceModels scene_trace;
  /// Each spec's effect on log trace time, the scene's removed (spec_trace_effects.h): how `auto`
  /// ranks candidates. Empty in files written without them (auto then uses the scene-level models).
  SpecTraceEffects trace_effects;

  /// The model of `family`; throws InputError listing the families the model has.
  const FamilyModel& family(const std::string& name) const;
};

/// Fits every structure family of `runs` to the times `target` takes. `progress` gets one line
/// per family.
CostModelSet fit_cost_model_set(const std::vector<RunRecord>& runs, const FitOptions& options,
                                FitTarget target = FitTarget::embree_normalized,
                                const std::function<void(const std::string&)>& progress = {});

/// The rows of `runs` of one family, in their order.
std::vector<RunRecord> runs_of_family(const std::vector<RunRecord>& runs, const std::string& family);

}  // namespace raylab
