#include "cost/model_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>

#include "cost/json_reader.h"
#include "cost/output_file.h"
#include "cost/provenance.h"
#include "geometry/input_error.h"
#include "geometry/input_warning.h"

namespace raylab {
namespace {

using Json = nlohmann::ordered_json;
constexpr const char* kFormat = "raylab-cost-model";

Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json strings(const std::vector<std::string>& v) {
  Json a = Json::array();
  for (const auto& s : v) a.push_back(s);
  return a;
}

Json level_json(const LevelFit& f) {
  Json terms = Json::array();
  for (std::size_t j = 0; j < f.model.terms.size(); ++j) {
    const CostTerm& t = find_cost_term(f.model.level, f.model.terms[j]);
    terms.push_back({{"name", t.name},
                     {"meaning", t.meaning},
                     {"value", f.model.values[j]},
                     {"std_error", number_or_null(f.model.std_errors[j])},
                     {"at_bound", j < f.at_bound.size() && f.at_bound[j]}});
  }
  Json by_family = Json::object();
  for (const auto& [family, t] : f.by_scene_family) by_family[family] = strings(t);
  Json path = Json::array();
  for (const ScoredModel& s : f.path)
    path.push_back({{"terms", strings(s.terms)},
                    {"held_out_mape", number_or_null(s.held_out_mape)},
                    {"in_sample_mape", number_or_null(s.in_sample_mape)},
                    {"aic", number_or_null(s.aic)},
                    {"bic", number_or_null(s.bic)}});
  const std::size_t k = f.model.terms.size();
  Json covariance = nullptr;
  if (f.model.covariance.size() == k * k) {
    covariance = Json::array();
    for (std::size_t i = 0; i < k; ++i)
      covariance.push_back(std::vector<double>(f.model.covariance.begin() + static_cast<std::ptrdiff_t>(i * k),
                                               f.model.covariance.begin() + static_cast<std::ptrdiff_t>((i + 1) * k)));
  }
  return {{"terms", terms},
          {"covariance", covariance},
          {"residual_log_sigma", number_or_null(f.model.residual_log_sigma)},
          {"in_sample", {{"mape", f.in_sample_mape}, {"r2", f.in_sample_r2}}},
          {"held_out",
           {{"cross_validated", f.cross_validated},
            {"mape", f.held_out_mape},
            {"r2", f.held_out_r2},
            {"coverage90", number_or_null(f.held_out_coverage90)}}},
          {"aic", f.aic},
          {"bic", f.bic},
          {"condition_number", number_or_null(f.condition_number)},
          {"converged", f.converged},
          {"dropped", strings(f.dropped)},
          {"unused", strings(f.unused)},
          {"by_scene_family", by_family},
          {"selection_path", path}};
}

/// The log-space spread of a version-1 file's model, which stored no residual spread: for
/// log-normal errors of spread s, MAPE ≈ E|ε| = s·√(2/π), so s ≈ MAPE·√(π/2) (held-out MAPE when
/// cross-validated).
double log_sigma_from_mape(double mape) { return mape * std::sqrt(std::acos(-1.0) / 2.0); }

LevelFit read_level(const JsonReader& r, ModelLevel level, int version) {
  LevelFit f;
  f.model.level = level;
  const Json& terms = r.at("terms");
  if (!terms.is_array() || terms.empty()) throw InputError(r.where() + ".terms: expected a non-empty list");
  for (std::size_t j = 0; j < terms.size(); ++j) {
    const JsonReader t(terms[j], r.where() + ".terms[" + std::to_string(j) + "]");
    const std::string name = t.string("name");
    try {
      find_cost_term(level, name);
    } catch (const InputError& e) {
      throw InputError(t.where() + ": " + e.what());
    }
    const double value = t.number("value");
    if (value < 0) throw InputError(t.where() + ".value: a cost constant must not be negative");
    f.model.terms.push_back(name);
    f.model.values.push_back(value);
    f.model.std_errors.push_back(t.number("std_error", true));
    f.at_bound.push_back(t.boolean("at_bound"));
  }
  const JsonReader in = r.object("in_sample"), out = r.object("held_out");
  f.in_sample_mape = in.number("mape");
  f.in_sample_r2 = in.number("r2");
  f.cross_validated = out.boolean("cross_validated");
  f.held_out_mape = out.number("mape");
  f.held_out_r2 = out.number("r2");
  if (version >= 2) {
    f.held_out_coverage90 = out.number("coverage90", true);
    f.model.residual_log_sigma = r.number("residual_log_sigma", true);
    const Json& cov = r.at("covariance");
    const std::size_t k = f.model.terms.size();
    if (!cov.is_null()) {
      if (!cov.is_array() || cov.size() != k)
        throw InputError(r.where() + ".covariance: expected null or a " + std::to_string(k) + "x" + std::to_string(k) +
                         " matrix (one row per term)");
      for (std::size_t i = 0; i < k; ++i) {
        if (!cov[i].is_array() || cov[i].size() != k)
          throw InputError(r.where() + ".covariance[" + std::to_string(i) + "]: expected " + std::to_string(k) +
                           " numbers");
        for (const Json& v : cov[i]) {
          if (!v.is_number() || !std::isfinite(v.get<double>()))
            throw InputError(r.where() + ".covariance[" + std::to_string(i) + "]: expected finite numbers");
          f.model.covariance.push_back(v.get<double>());
        }
      }
    }
  } else {
    f.model.residual_log_sigma = log_sigma_from_mape(f.cross_validated ? f.held_out_mape : f.in_sample_mape);
  }
  f.aic = r.number("aic");
  f.bic = r.number("bic");
  f.condition_number = r.number("condition_number", true);
  f.converged = r.boolean("converged");
  f.dropped = r.strings("dropped");
  f.unused = r.strings("unused");
  const JsonReader by = r.object("by_scene_family");
  for (auto it = by.json().begin(); it != by.json().end(); ++it) f.by_scene_family[it.key()] = by.strings(it.key());
  const Json& path = r.at("selection_path");
  if (!path.is_array()) throw InputError(r.where() + ".selection_path: expected a list");
  for (std::size_t k = 0; k < path.size(); ++k) {
    const JsonReader s(path[k], r.where() + ".selection_path[" + std::to_string(k) + "]");
    ScoredModel m;
    m.terms = s.strings("terms");
    m.held_out_mape = s.number("held_out_mape", true);
    m.in_sample_mape = s.number("in_sample_mape", true);
    m.aic = s.number("aic", true);
    m.bic = s.number("bic", true);
    f.path.push_back(std::move(m));
  }
  return f;
}

}  // namespace

std::string default_model_path() { return raylab_data_dir() + "/cost/default_model.json"; }

std::string resolve_model_path(const std::string& path) { return path == "default" ? default_model_path() : path; }

void write_model_file(const CostModelSet& set, const std::string& path) {
  Json families = Json::object();
  for (const auto& [name, m] : set.families) {
    Json ranges = Json::object();
    for (const auto& [key, range] : m.ranges) ranges[key] = {range.lo, range.hi};
    families[name] = {{"rows", m.rows},
                      {"scenes", strings(m.scenes)},
                      {"counters", level_json(m.counters)},
                      {"tree", level_json(m.tree)},
                      {"builder",
                       {{"c_trav", m.builder.c_trav},
                        {"c_leaf", m.builder.c_leaf},
                        {"c_isect", m.builder.c_isect},
                        {"source", m.builder_source}}},
                      {"ranges", ranges},
                      {"replicate_error", number_or_null(m.replicate_error)},
                      {"replicate_groups", m.replicate_groups}};
  }
  Json j = {{"format", kFormat},
                  {"version", CostModelSet::kVersion},
                  {"created", set.created},
                  {"data",
                   {{"runs", set.runs_source},
                    {"rows", set.rows},
                    {"hosts", strings(set.hosts)},
                    {"cpu_models", strings(set.cpu_models)},
                    {"git_revisions", strings(set.git_revisions)}}},
                  {"fit",
                   {{"target", target_name(set.target)},
                    {"residual", set.options.residual == ResidualKind::relative ? "relative" : "absolute"},
                    {"loss", "huber"},
                    {"loss_scale", set.options.loss_scale},
                    {"nonnegative", set.options.nonnegative}}},
                  {"families", families}};
  if (!set.build.empty()) j["build"] = build_time_models_json(set.build);
  if (!set.scene_trace.empty()) j["scene_trace"] = scene_trace_models_json(set.scene_trace);
  if (!set.trace_effects.empty()) j["scene_trace_effects"] = spec_trace_effects_json(set.trace_effects);
  write_file_atomically(path, j.dump(2) + "\n");
}

CostModelSet read_model_file(const std::string& path_in) {
  const std::string path = resolve_model_path(path_in);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the cost model");
  Json j;
  try {
    j = Json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    const std::string msg = e.what();
    const auto at = msg.find("parse error");
    throw InputError(path + ": malformed JSON: " + (at == std::string::npos ? msg : msg.substr(at)));
  }
  const JsonReader root(j, path);
  if (!root.at("format").is_string() || root.string("format") != kFormat)
    throw InputError(path + ": not a raylab cost model (format is not '" + std::string(kFormat) + "')");
  const double version_number = root.number("version");
  if (version_number != 1 && version_number != CostModelSet::kVersion)
    throw InputError(path + ": cost model version " + root.at("version").dump() + ", this raylab reads versions 1 to " +
                     std::to_string(CostModelSet::kVersion) + " (refit it with raylab fit)");
  const int version = static_cast<int>(version_number);
  CostModelSet set;
  set.created = root.string("created");
  const JsonReader data = root.object("data");
  set.runs_source = data.string("runs");
  set.rows = static_cast<std::size_t>(data.number("rows"));
  set.hosts = data.strings("hosts");
  set.cpu_models = data.strings("cpu_models");
  set.git_revisions = data.strings("git_revisions");
  const JsonReader fit = root.object("fit");
  try {
    set.target = parse_fit_target(fit.string("target"));
  } catch (const InputError& e) {
    throw InputError(path + ".fit.target: " + e.what());
  }
  set.options.residual = fit.string("residual") == "absolute" ? ResidualKind::absolute : ResidualKind::relative;
  set.options.loss_scale = fit.number("loss_scale");
  set.options.nonnegative = fit.boolean("nonnegative");
  const JsonReader families = root.object("families");
  if (families.json().empty()) throw InputError(path + ".families: the model has no structure family");
  for (auto it = families.json().begin(); it != families.json().end(); ++it) {
    const JsonReader f = families.object(it.key());
    FamilyModel m;
    m.family = it.key();
    m.rows = static_cast<std::size_t>(f.number("rows"));
    m.scenes = f.strings("scenes");
    m.counters = read_level(f.object("counters"), ModelLevel::counters, version);
    m.tree = read_level(f.object("tree"), ModelLevel::tree, version);
    if (version >= 2) {
      m.replicate_error = f.number("replicate_error", true);
      const double groups = f.number("replicate_groups");
      if (groups < 0) throw InputError(f.where() + ".replicate_groups: expected a count >= 0");
      m.replicate_groups = static_cast<std::size_t>(groups);
    }
    const JsonReader b = f.object("builder");
    m.builder = {b.number("c_trav"), b.number("c_leaf"), b.number("c_isect")};
    m.builder_source = b.string("source");
    const JsonReader ranges = f.object("ranges");
    for (auto r = ranges.json().begin(); r != ranges.json().end(); ++r) {
      const Json& v = r.value();
      if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number())
        throw InputError(ranges.where() + "." + r.key() + ": expected [lo, hi]");
      m.ranges[r.key()] = {v[0].get<double>(), v[1].get<double>()};
    }
    set.families[m.family] = std::move(m);
  }
  if (j.contains("build")) set.build = read_build_time_models(j.at("build"), path + ".build");
  if (j.contains("scene_trace")) set.scene_trace = read_scene_trace_models(j.at("scene_trace"), path + ".scene_trace");
  if (j.contains("scene_trace_effects"))
    set.trace_effects = read_spec_trace_effects(j.at("scene_trace_effects"), path + ".scene_trace_effects");
  return set;
}

std::shared_ptr<const CostModelSet> load_model_file(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, std::pair<std::string, std::shared_ptr<const CostModelSet>>> cache;
  const std::string resolved = resolve_model_path(path);
  // The version of the file: its size and modification time (none when it cannot be read, which
  // read_model_file then reports).
  std::error_code ec;
  const auto size = std::filesystem::file_size(resolved, ec);
  const auto mtime = std::filesystem::last_write_time(resolved, ec);
  const std::string version =
      ec ? std::string() : std::to_string(size) + "@" + std::to_string(mtime.time_since_epoch().count());
  std::lock_guard lock(mutex);
  auto it = cache.find(resolved);
  if (it == cache.end() || version.empty() || it->second.first != version) {
    auto set = std::make_shared<const CostModelSet>(read_model_file(resolved));
    it = cache.insert_or_assign(resolved, std::make_pair(version, std::move(set))).first;
  }
  return it->second.second;
}

namespace {

/// `m`'s builder constants (m the family `family` of the model file `resolved`), checked usable.
const FittedSahCost& usable_builder_costs(const FamilyModel& m, const std::string& resolved, const std::string& family) {
  if (!(m.builder.c_trav > 0) || !(m.builder.c_isect > 0) || !(m.builder.c_leaf >= 0))
    throw InputError(resolved + ": the fitted constants of '" + family + "' are not positive (c_trav " +
                     std::to_string(m.builder.c_trav) + ", c_isect " + std::to_string(m.builder.c_isect) +
                     "); a builder cannot use them");
  return m.builder;
}

}  // namespace

FittedSahCost load_builder_costs(const std::string& path, const std::string& family) {
  const std::string resolved = resolve_model_path(path);
  const std::shared_ptr<const CostModelSet> set = load_model_file(resolved);
  return usable_builder_costs(set->family(family), resolved, family);
}

BuildContext model_build_context(bool warn_outside_range) {
  BuildContext context;
  context.fitted_costs = [warn_outside_range](const FittedCostRequest& request, double primitives) {
    // One read of the model (load_model_file) for the constants and the range both.
    const std::string resolved = resolve_model_path(request.model);
    const std::shared_ptr<const CostModelSet> set = load_model_file(resolved);
    const FamilyModel& m = set->family(request.family);
    const FittedSahCost costs = usable_builder_costs(m, resolved, request.family);
    if (const auto range = m.ranges.find("primitives"); warn_outside_range && range != m.ranges.end()) {
      const FeatureRangeCheck check = check_feature_range("primitives", primitives, range->second);
      // Once per model file and family in a process: a sweep builds many structures.
      if (check.outside())
        warn_input_once("cost=" + resolved + "|" + request.family,
                        "cost=" + request.model + ": " + request.family + " " + check.describe() +
                            "; its constants are used as they are");
    }
    return costs;
  };
  return context;
}

}  // namespace raylab
