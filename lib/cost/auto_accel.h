#pragma once
/// `auto[:model=PATH,rays=KIND,count=N]`: the accelerator a fitted cost model picks for the scene it is
/// given. Every candidate structure (the lab's own: BVH of each width, kd-tree, octree, BSP tree,
/// uniform and nested grids, with the parameter variants the model can rank, including trees
/// built from the model itself, `cost=`) whose family the model covers is built, its features
/// read (tree_features.h), and its time predicted by the model's tree level for rays of KIND
/// (default: the mean over primary, diffuse and shadow rays); the fastest prediction is kept and
/// the others freed. Embree and brute force are not candidates. The BSP tree is skipped above
/// kAutoBspMaxPrimitives (its build is quadratic in the worst case). Without `model=` the lab's
/// committed default model (model_file.h) is used, and the choice says so. On an instanced
/// scene the choice is made for each base and for the flat geometry apart (placed as
/// make_instanced_aggregate places them); the choice reported is the largest part's.
///
/// With `count=N` and a model file that has build-time and scene-level models (build_time_model.h,
/// scene_trace_model.h), `auto` chooses BEFORE it builds (`method` "predicted"): from the scene's
/// features alone (scene_features.h, one O(N) pass) it predicts each candidate's build seconds and
/// its ns per ray, and keeps the candidate of least predicted build + N × trace time; candidates
/// the model has no entry for (by accel_spec_key.h) are skipped. A candidate's ns per ray is
/// exp(a + b̂) where the model has its spec effect a from at least kAutoEffectMinScenes scenes
/// (spec_trace_effects.h: b̂ the scene's effect, voted by the scene-level models fitted on scenes
/// of its size when at least kAutoEffectMinVoters are, else by every one), else its own
/// scene-level prediction. It builds that one, then races the
/// others whose 90% interval of the total overlaps its own, in the order of their predicted totals,
/// as long as the race's estimated cost (each racer's build and sample passes at the upper ends of
/// their intervals) stays within kAutoSampleBudget of the best's predicted total: each racer is
/// built and timed on auto_sample_rays(N) rays of the kind chosen for (the fastest of
/// kAutoSamplePasses passes, one thread), and the lowest measured build + N × trace time is kept
/// (`sampled`; a choice that then depends on timing). For few rays the budget admits no racer and
/// only the predicted best is built; for many it admits the plausible ones. Without `count` the
/// predicted time per ray alone decides (as for infinitely many rays), and nothing is timed: the
/// choice is a function of the scene and the model (the determinism suite builds `auto` so). A
/// model file without those models gives today's behaviour (`method` "built-all"): every candidate
/// built, the tree model's fastest kept.
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "scene/primitive.h"
#include "scene/scene.h"

namespace raylab {

inline constexpr std::size_t kAutoBspMaxPrimitives = std::size_t{1} << 15;
/// The fewest scenes a spec effect (spec_trace_effects.h) is measured on for `auto` to use it.
inline constexpr std::size_t kAutoEffectMinScenes = 2;
/// The fewest scene-level models fitted on the scene's size (extrapolation factor 1) that vote on
/// its effect b̂ alone; with fewer, every model votes. A model outside its range of primitives
/// votes a time it has no data for, and its factor would widen every candidate's interval.
inline constexpr std::size_t kAutoEffectMinVoters = 3;
/// The rays each racing candidate is timed on (split evenly over the kinds of `mixed`): a
/// thousandth of the count, within [kAutoSampleRays, kAutoSampleMaxRays].
inline constexpr std::size_t kAutoSampleRays = 384;
inline constexpr std::size_t kAutoSampleMaxRays = 4096;
inline constexpr int kAutoSamplePasses = 3;
/// The most the race may cost (builds beyond the best and every sample pass, estimated at their
/// intervals' upper ends), as a fraction of the best candidate's predicted total.
inline constexpr double kAutoSampleBudget = 0.05;

inline std::size_t auto_sample_rays(double count) {
  const double thousandth = count / 1000.0;
  if (!(thousandth > static_cast<double>(kAutoSampleRays))) return kAutoSampleRays;
  if (thousandth >= static_cast<double>(kAutoSampleMaxRays)) return kAutoSampleMaxRays;
  return static_cast<std::size_t>(thousandth);
}

struct AutoCandidate {
  std::string spec;
  double predicted_ns_per_ray = 0.0;  ///< NaN when skipped
  std::string skipped;                ///< why, when skipped
  // method "predicted" only (NaN otherwise):
  double predicted_build_s = std::numeric_limits<double>::quiet_NaN();
  double predicted_total_s = std::numeric_limits<double>::quiet_NaN();  ///< build + count × trace
  double total_lo_s = std::numeric_limits<double>::quiet_NaN();  ///< its 90% interval
  double total_hi_s = std::numeric_limits<double>::quiet_NaN();
  bool built = false;
  double measured_build_s = std::numeric_limits<double>::quiet_NaN();     ///< when built
  double measured_ns_per_ray = std::numeric_limits<double>::quiet_NaN();  ///< when timed on the sample
  /// How far the scene's primitives lie outside the range its build-time and trace models were
  /// fitted on (the largest factor, SelectedLinearModel::extrapolation_factor); 1 inside.
  double extrapolation_factor = 1.0;
  /// How its trace time was predicted: "effects" (spec_trace_effects.h) or "scene-level" (its own
  /// model, scene_trace_model.h); "scene-level" when any ray class of a mixed choice used its own.
  std::string trace_model = "";
};

struct AutoChoice {
  std::string model;  ///< the model file used
  std::string rays;   ///< the ray kind predicted for, or "mixed"
  std::string chosen;
  double predicted_ns_per_ray = 0.0;
  std::vector<AutoCandidate> candidates;
  std::string method;  ///< "predicted" (chosen before building) or "built-all" (every candidate built)
  std::string note;    ///< why built-all, or which candidates were raced
  double count = 0;    ///< the rays chosen for (`count=`); 0 when not given
  /// Seconds from the scene to the choice: the feature pass and the predictions ("predicted"),
  /// or building and reading every candidate ("built-all"). Summed over the parts of an
  /// instanced scene, as are candidates_built.
  double choose_s = 0;
  double predicted_build_s = std::numeric_limits<double>::quiet_NaN();
  double predicted_trace_s = std::numeric_limits<double>::quiet_NaN();  ///< count × ns per ray; NaN without count
  std::string runner_up;  ///< the second-best candidate, empty when there is none
  double runner_up_total_s = std::numeric_limits<double>::quiet_NaN();  ///< its predicted total (or ns per ray × count)
  std::size_t candidates_built = 0;
  bool sampled = false;  ///< candidates raced: built and timed on auto_sample_rays(count) rays each
  /// The chosen candidate's extrapolation_factor (the largest over the parts of an instanced
  /// scene): above 1, the choice rests on models used outside their data, and auto warns once.
  double extrapolation_factor = 1.0;
};

/// The candidate specs for a model whose families are `families` (model path spliced into the
/// `cost=` variants).
std::vector<std::string> auto_candidate_specs(const std::vector<std::string>& families, const std::string& model);

class AutoAccelerator final : public Aggregate {
 public:
  AutoAccelerator(std::unique_ptr<Aggregate> chosen, AutoChoice choice)
      : inner_(std::move(chosen)), choice_(std::move(choice)) {}

  std::string name() const override { return "auto"; }
  AccelStats stats() const override { return inner_->stats(); }
  bool reports_counters() const override { return inner_->reports_counters(); }
  std::optional<std::uint64_t> structure_hash() const override { return inner_->structure_hash(); }
  Bounds3f bounds() const override { return inner_->bounds(); }
  bool intersect(Ray& ray, Hit& hit) const override { return inner_->intersect(ray, hit); }
  bool intersect(Ray& ray, Hit& hit, RayCounters& c) const override { return inner_->intersect(ray, hit, c); }
  bool occluded(const Ray& ray) const override { return inner_->occluded(ray); }
  bool occluded(const Ray& ray, RayCounters& c) const override { return inner_->occluded(ray, c); }

  const AutoChoice& choice() const { return choice_; }
  const Aggregate& chosen() const { return *inner_; }

 private:
  std::unique_ptr<Aggregate> inner_;
  AutoChoice choice_;
};

}  // namespace raylab
