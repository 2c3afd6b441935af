#include "cost/spec_trace_effects.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>

#include "cost/json_reader.h"
#include "cost/replicates.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

/// Backfitting stops when no effect moves by more than this, or after kMaxSweeps sweeps.
constexpr double kTolerance = 1e-9;
constexpr int kMaxSweeps = 10000;

}  // namespace

SpecTraceEffects fit_spec_trace_effects(const std::vector<RunRecord>& runs) {
  // The fastest time of each (spec, scene, rays).
  std::map<std::tuple<std::string, std::string, std::string>, double> fastest;
  std::map<std::string, std::string> kind_of;  // rays -> ray kind
  for (const RunRecord& r : runs) {
    if (!(r.ns_per_ray_min > 0) || !std::isfinite(r.ns_per_ray_min)) continue;
    auto [it, fresh] = fastest.try_emplace({r.accel, r.scene, r.rays}, r.ns_per_ray_min);
    if (!fresh) it->second = std::min(it->second, r.ns_per_ray_min);
    kind_of[r.rays] = r.ray_kind;
  }
  // Rows as indices into the a's (spec, class) and the b's (scene, rays).
  std::map<std::pair<std::string, std::string>, std::size_t> a_index, b_index;
  struct Row {
    std::size_t a, b;
    double log_t;
    std::string scene;
  };
  std::vector<Row> rows;
  for (const auto& [key, ns] : fastest) {
    const auto& [spec, scene, rays] = key;
    const std::size_t a = a_index.try_emplace({spec, ray_class_of(kind_of.at(rays))}, a_index.size()).first->second;
    const std::size_t b = b_index.try_emplace({scene, rays}, b_index.size()).first->second;
    rows.push_back({a, b, std::log(ns), scene});
  }
  std::vector<double> a(a_index.size(), 0.0), b(b_index.size(), 0.0);
  // One backfitting step: each effect of `target` the mean of log t minus the other effect.
  auto update = [&](std::vector<double>& target, const std::vector<double>& other, bool target_is_a) {
    std::vector<double> sum(target.size(), 0.0), n(target.size(), 0.0);
    for (const Row& r : rows) {
      const std::size_t t = target_is_a ? r.a : r.b, o = target_is_a ? r.b : r.a;
      sum[t] += r.log_t - other[o];
      n[t] += 1;
    }
    double moved = 0;
    for (std::size_t i = 0; i < target.size(); ++i) {
      const double next = sum[i] / n[i];
      moved = std::max(moved, std::abs(next - target[i]));
      target[i] = next;
    }
    return moved;
  };
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    const double moved_b = update(b, a, false), moved_a = update(a, b, true);
    if (std::max(moved_a, moved_b) <= kTolerance) break;
  }
  std::vector<std::vector<double>> residuals(a.size());
  std::vector<std::set<std::string>> scenes(a.size());
  for (const Row& r : rows) {
    residuals[r.a].push_back(std::abs(r.log_t - a[r.a] - b[r.b]));
    scenes[r.a].insert(r.scene);
  }
  SpecTraceEffects out;
  for (const auto& [spec_class, i] : a_index)
    out.by_spec[spec_class.first][spec_class.second] = {a[i], quantile90(residuals[i]), scenes[i].size()};
  return out;
}

nlohmann::ordered_json spec_trace_effects_json(const SpecTraceEffects& effects) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [spec, by_class] : effects.by_spec)
    for (const auto& [cls, e] : by_class) j[spec][cls] = {{"effect", e.effect}, {"log_q90", e.log_q90}, {"scenes", e.scenes}};
  return j;
}

SpecTraceEffects read_spec_trace_effects(const nlohmann::ordered_json& j, const std::string& where) {
  const JsonReader specs(j, where);
  SpecTraceEffects out;
  for (auto s = j.begin(); s != j.end(); ++s) {
    const JsonReader classes = specs.object(s.key());
    for (auto c = s.value().begin(); c != s.value().end(); ++c) {
      const JsonReader r = classes.object(c.key());
      SpecTraceEffect e;
      e.effect = r.number("effect");
      e.log_q90 = r.number("log_q90");
      const double scenes = r.number("scenes");
      if (e.log_q90 < 0) throw InputError(r.where() + ".log_q90: must not be negative");
      if (!(scenes >= 1) || scenes != std::floor(scenes)) throw InputError(r.where() + ".scenes: expected a positive count");
      e.scenes = static_cast<std::size_t>(scenes);
      out.by_spec[s.key()][c.key()] = e;
    }
  }
  return out;
}

}  // namespace raylab
