#pragma once
/// `raylab fit`: from a data set (run_record.h) to a fitted cost model per structure family, both
/// levels (cost_model.h), with selected terms (model_selection.h), uncertainties (fit.h), the
/// constants the SAH builders take (`cost=`), and the range of the data each model was fitted on.
#include <functional>
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

namespace raylab {

struct LevelFit {
  FittedCostModel model;
  std::vector<bool> at_bound;
  double in_sample_mape = 0, in_sample_r2 = 0;
  double held_out_mape = 0, held_out_r2 = 0;  ///< leave-one-scene-out; 0 without cross-validation
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

/// `runs` with ns_per_ray_min replaced by the time `target` takes.
std::vector<RunRecord> with_fit_target(std::vector<RunRecord> runs, FitTarget target);

struct CostModelSet {
  static constexpr int kVersion = 1;
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
