#pragma once
/// Spec effects on trace time: an additive model of the data set's log times,
///   ln t(spec, scene, rays) = a(spec, class) + b(scene, rays) + ε,
/// a two-way layout without interaction (class: run_record.h, ray_class_of). b is what makes a
/// scene and its rays slow for every structure (how many surfaces a ray crosses, how many rays
/// hit); a(spec, class) is what the structure adds, the same on every scene. Only differences of
/// a are determined: they compare two specs through every scene either shares with the others.
///
/// Why `auto` (auto_accel.h) ranks candidates by it: each spec's scene-level model
/// (scene_trace_model.h) predicts its absolute time from the scene's features, fitted on the
/// scenes the plan gave that spec; held out, they err by tens of per cent (each one's
/// held_out.mape in model.json), and ranking two specs by two such predictions adds both
/// errors. With the effects, the scene-level models vote on the new scene's b, b̂ = median
/// over specs s of (ln t̂_s - a_s) (the models fitted on scenes of its size, auto_accel.h), and
/// each candidate is predicted as exp(a_c + b̂): the candidates' differences come from paired
/// measurements on shared scenes.
///
/// Fit: least squares by backfitting (alternating means of the residuals over the rows of each b
/// and each a, from a = 0, until no effect moves by more than 1e-9), on the fastest time of each
/// (spec, scene, rays) of the data set (replicates measure the same case). log_q90 is the 90%
/// quantile (nearest rank) of |ε| over a spec's rows of the class: in-sample, so with few scenes
/// it understates the spread.
#include <cstddef>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "cost/run_record.h"

namespace raylab {

struct SpecTraceEffect {
  double effect = 0.0;   ///< a(spec, class), natural-log units
  double log_q90 = 0.0;  ///< the spread of its rows about a + b (above)
  std::size_t scenes = 0;
};

/// Effects by spec (as the data set spells it), then by ray class.
struct SpecTraceEffects {
  std::map<std::string, std::map<std::string, SpecTraceEffect>> by_spec;
  bool empty() const { return by_spec.empty(); }
};

/// The effects of every spec and class of `runs` (times: ns_per_ray_min, as the fit's target
/// makes them). Rows without a positive finite time are left out.
SpecTraceEffects fit_spec_trace_effects(const std::vector<RunRecord>& runs);

/// model.json's `scene_trace_effects`: {SPEC: {CLASS: {effect, log_q90, scenes}}}.
nlohmann::ordered_json spec_trace_effects_json(const SpecTraceEffects& effects);
/// Throws InputError naming the key at `where` for a malformed section.
SpecTraceEffects read_spec_trace_effects(const nlohmann::ordered_json& j, const std::string& where);

}  // namespace raylab
