#include "cost/sweep.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/timing_cpu.h"
#include "accel/common/tracer.h"
#include "cost/model_file.h"
#include "cost/provenance.h"
#include "cost/run_record.h"
#include "geometry/input_error.h"
#include "rays/ray_generators.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

const char* kListKeys[] = {"scenes", "accels", "rays"};

void validate_scene_spec(const std::string& where, const std::string& spec) {
  const SpecString s = parse_spec(spec);
  if (s.name == "file" || s.name.find_first_of("/.") != std::string::npos) return;  // read when the case runs
  for (const auto& k : scene_kinds())
    if (k.name == s.name) return;
  throw InputError(where + ": unknown scene kind '" + s.name + "' in '" + spec + "' (see raylab scenes)");
}

void validate_accel_spec(const std::string& where, const std::string& spec) {
  validate_accelerator_spec(spec);
  const std::string family = structure_family(spec);
  const auto& families = feature_families();
  if (std::find(families.begin(), families.end(), family) == families.end()) {
    std::string valid;
    for (const auto& f : families) valid += (valid.empty() ? "" : ", ") + f;
    throw InputError(where + ": '" + spec + "' has no tree features for a cost model (structures: " + valid + ")");
  }
}

void validate_ray_spec(const std::string& where, const std::string& spec) {
  const SpecString s = parse_spec(spec);
  const auto names = ray_generator_names();
  if (std::find(names.begin(), names.end(), s.name) == names.end())
    throw InputError(where + ": unknown ray generator '" + s.name + "' in '" + spec + "' (see raylab rays)");
}

std::string read_text_file(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the " + what);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::vector<std::size_t> SweepPlan::accels_of(std::size_t s) const {
  if (s < scene_accels.size() && !scene_accels[s].empty()) return scene_accels[s];
  std::vector<std::size_t> all(accels.size());
  for (std::size_t a = 0; a < all.size(); ++a) all[a] = a;
  return all;
}

std::int64_t SweepPlan::primary_case_count() const {
  std::int64_t n = 0;
  for (std::size_t s = 0; s < scenes.size(); ++s) n += static_cast<std::int64_t>(accels_of(s).size() * rays.size());
  return n;
}

std::int64_t SweepPlan::case_count() const {
  return primary_case_count() + static_cast<std::int64_t>(replicated.size()) * replicate_repeats;
}

SweepCase SweepPlan::case_at(std::int64_t number) const {
  if (number < 0 || number >= case_count())
    throw std::out_of_range("case " + std::to_string(number) + " of " + std::to_string(case_count()));
  SweepCase c;
  c.number = number;
  std::int64_t primary = number;
  const std::int64_t p = primary_case_count();
  if (number >= p) {
    const auto n = static_cast<std::int64_t>(replicated.size());
    c.replicate = (number - p) / n + 1;
    primary = replicated[static_cast<std::size_t>((number - p) % n)];
    c.first_case = primary;
  }
  const auto r = static_cast<std::int64_t>(rays.size());
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const std::vector<std::size_t> on_scene = accels_of(s);
    const auto here = static_cast<std::int64_t>(on_scene.size()) * r;
    if (primary >= here) {
      primary -= here;
      continue;
    }
    c.scene = scenes[s];
    c.accel = accels[on_scene[static_cast<std::size_t>(primary / r)]];
    c.rays = rays[static_cast<std::size_t>(primary % r)];
    return c;
  }
  throw std::logic_error("SweepPlan::case_at: inconsistent plan");
}

std::string SweepPlan::describe() const {
  std::size_t least = accels.size(), most = 0;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    least = std::min(least, accels_of(s).size());
    most = std::max(most, accels_of(s).size());
  }
  std::string text = std::to_string(case_count()) + " cases = " + std::to_string(scenes.size()) + " scenes x ";
  if (least == accels.size()) text += std::to_string(accels.size()) + " accels";
  else text += (least == most ? std::to_string(most) : std::to_string(least) + ".." + std::to_string(most)) + " of " +
               std::to_string(accels.size()) + " accels";
  text += " x " + std::to_string(rays.size()) + " rays";
  if (!replicated.empty())
    text += " + " + std::to_string(static_cast<std::int64_t>(replicated.size()) * replicate_repeats) + " replicates";
  return text;
}

std::vector<std::size_t> sample_accels(const std::vector<std::string>& accels, const std::string& scene, std::size_t count,
                                       std::uint64_t seed) {
  auto fnv1a = [](const std::string& text) {
    std::uint64_t h = 14695981039346656037ull;
    for (const unsigned char ch : text) {
      h ^= ch;
      h *= 1099511628211ull;
    }
    return h;
  };
  // family -> its accels, best rank first
  std::map<std::string, std::vector<std::pair<std::uint64_t, std::size_t>>> by_family;
  for (std::size_t a = 0; a < accels.size(); ++a)
    by_family[structure_family(accels[a])].push_back({fnv1a(std::to_string(seed) + "|" + scene + "|" + accels[a]), a});
  std::vector<std::vector<std::pair<std::uint64_t, std::size_t>>> families;
  for (auto& [name, members] : by_family) {
    std::sort(members.begin(), members.end());
    families.push_back(members);
  }
  std::sort(families.begin(), families.end(), [](const auto& x, const auto& y) { return x.front() < y.front(); });
  std::vector<std::size_t> chosen;
  for (std::size_t round = 0; chosen.size() < std::min(count, accels.size()); ++round)
    for (const auto& members : families)
      if (round < members.size() && chosen.size() < count) chosen.push_back(members[round].second);
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

std::vector<std::int64_t> replicated_cases(const SweepPlan& plan, double fraction) {
  SweepPlan primary = plan;
  primary.replicated.clear();
  const std::int64_t p = primary.primary_case_count();
  if (fraction <= 0 || p == 0) return {};
  const auto n = std::min(p, static_cast<std::int64_t>(std::ceil(fraction * static_cast<double>(p) - 1e-9)));
  std::set<std::int64_t> chosen;
  for (std::int64_t j = 0; j < n; ++j)
    chosen.insert(static_cast<std::int64_t>(std::floor((static_cast<double>(j) + 0.5) * static_cast<double>(p) /
                                                       static_cast<double>(n))));
  // Every structure family and every scene family has a replicate.
  std::set<std::string> covered;
  std::vector<std::pair<std::string, std::string>> keys(static_cast<std::size_t>(p));
  for (std::int64_t c = 0; c < p; ++c) {
    const SweepCase k = primary.case_at(c);
    keys[static_cast<std::size_t>(c)] = {"accel " + structure_family(k.accel), "scene " + scene_family_of(k.scene)};
  }
  for (const std::int64_t c : chosen) {
    covered.insert(keys[static_cast<std::size_t>(c)].first);
    covered.insert(keys[static_cast<std::size_t>(c)].second);
  }
  for (std::int64_t c = 0; c < p; ++c) {
    const auto& [accel_family, scene_family] = keys[static_cast<std::size_t>(c)];
    if (covered.count(accel_family) && covered.count(scene_family)) continue;
    chosen.insert(c);
    covered.insert(accel_family);
    covered.insert(scene_family);
  }
  return {chosen.begin(), chosen.end()};
}

std::string plan_path(const std::string& name_or_path) {
  if (name_or_path == "quick" || name_or_path == "full") return raylab_data_dir() + "/plans/" + name_or_path + ".json";
  return name_or_path;
}

namespace {

/// A count in [1, limit] from a JSON value, or InputError naming `where`.
std::size_t read_count(const nlohmann::json& v, const std::string& where, std::size_t limit) {
  if (!v.is_number_integer() || v.get<std::int64_t>() < 1 || v.get<std::int64_t>() > static_cast<std::int64_t>(limit))
    throw InputError(where + ": expected an integer in [1, " + std::to_string(limit) + "]");
  return static_cast<std::size_t>(v.get<std::int64_t>());
}

void read_spec_list(const nlohmann::json& list, const std::string& path, const std::string& key,
                    std::vector<std::string>& into) {
  if (!list.is_array() || list.empty()) throw InputError(path + ": '" + key + "' must be a non-empty list of spec strings");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = path + ": " + key + "[" + std::to_string(i) + "]";
    if (!list[i].is_string() || list[i].get<std::string>().empty())
      throw InputError(where + ": expected a non-empty spec string");
    const std::string spec = list[i].get<std::string>();
    if (!seen.insert(spec).second) throw InputError(where + ": '" + spec + "' is listed twice");
    try {
      if (key == "accels") validate_accel_spec(where, spec);
      else validate_ray_spec(where, spec);
    } catch (const InputError& e) {
      const std::string msg = e.what();
      throw InputError(msg.rfind(where, 0) == 0 ? msg : where + ": " + msg);
    }
    into.push_back(spec);
  }
}

}  // namespace

SweepPlan load_plan(const std::string& name_or_path) {
  const std::string path = plan_path(name_or_path);
  const std::string text = read_text_file(path, "plan");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    std::string msg = e.what();
    const auto colon = msg.find("parse error");
    throw InputError(path + ": malformed JSON: " + (colon == std::string::npos ? msg : msg.substr(colon)));
  }
  if (!j.is_object()) throw InputError(path + ": a plan is a JSON object with keys scenes, accels, rays");
  static const std::set<std::string> kKeys = {"scenes", "accels", "rays", "description", "accels_per_scene",
                                              "sample_seed", "replicates", "seconds_per_case"};
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!kKeys.count(it.key()))
      throw InputError(path + ": unknown key '" + it.key() +
                       "' (valid: scenes, accels, rays, description, accels_per_scene, sample_seed, replicates, "
                       "seconds_per_case)");
  for (const char* key : kListKeys)
    if (!j.contains(key)) throw InputError(path + ": missing key '" + std::string(key) + "'");
  SweepPlan plan;
  plan.source = name_or_path;
  read_spec_list(j["accels"], path, "accels", plan.accels);
  read_spec_list(j["rays"], path, "rays", plan.rays);

  std::uint64_t seed = 1;
  if (j.contains("sample_seed")) {
    if (!j["sample_seed"].is_number_unsigned()) throw InputError(path + ": sample_seed: expected a non-negative integer");
    seed = j["sample_seed"].get<std::uint64_t>();
  }
  if (j.contains("seconds_per_case")) {
    const auto& t = j["seconds_per_case"];
    if (!t.is_number() || !(t.get<double>() > 0.0 && t.get<double>() <= 10.0))
      throw InputError(path + ": seconds_per_case: expected a number of seconds in (0, 10]");
    plan.seconds_per_case = t.get<double>();
  }
  std::size_t per_scene = 0;  // 0: every accel
  if (j.contains("accels_per_scene")) per_scene = read_count(j["accels_per_scene"], path + ": accels_per_scene", plan.accels.size());

  const auto& scenes = j["scenes"];
  if (!scenes.is_array() || scenes.empty())
    throw InputError(path + ": 'scenes' must be a non-empty list of scene specs or {\"scene\": SPEC, \"accels\": ...} objects");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const std::string where = path + ": scenes[" + std::to_string(i) + "]";
    const nlohmann::json& entry = scenes[i];
    std::string spec;
    std::vector<std::size_t> on_scene;
    std::size_t sample = per_scene;
    if (entry.is_object()) {
      for (auto it = entry.begin(); it != entry.end(); ++it)
        if (it.key() != "scene" && it.key() != "accels")
          throw InputError(where + ": unknown key '" + it.key() + "' (valid: scene, accels)");
      if (!entry.contains("scene") || !entry["scene"].is_string() || entry["scene"].get<std::string>().empty())
        throw InputError(where + ": expected \"scene\": a non-empty spec string");
      spec = entry["scene"].get<std::string>();
      if (entry.contains("accels")) {
        const auto& accels = entry["accels"];
        if (accels.is_number()) {
          sample = read_count(accels, where + ": accels", plan.accels.size());
        } else if (accels.is_array() && !accels.empty()) {
          sample = 0;
          for (std::size_t a = 0; a < accels.size(); ++a) {
            const std::string at = where + ": accels[" + std::to_string(a) + "]";
            const auto found = accels[a].is_string()
                                   ? std::find(plan.accels.begin(), plan.accels.end(), accels[a].get<std::string>())
                                   : plan.accels.end();
            if (found == plan.accels.end())
              throw InputError(at + ": expected one of the plan's accels (a spec string listed in \"accels\")");
            const auto index = static_cast<std::size_t>(found - plan.accels.begin());
            if (std::find(on_scene.begin(), on_scene.end(), index) != on_scene.end())
              throw InputError(at + ": '" + *found + "' is listed twice");
            on_scene.push_back(index);
          }
          std::sort(on_scene.begin(), on_scene.end());
        } else {
          throw InputError(where + ": accels: expected a non-empty list of the plan's accels or a count");
        }
      }
    } else if (entry.is_string() && !entry.get<std::string>().empty()) {
      spec = entry.get<std::string>();
    } else {
      throw InputError(where + ": expected a non-empty spec string or a {\"scene\": SPEC, \"accels\": ...} object");
    }
    if (!seen.insert(spec).second) throw InputError(where + ": '" + spec + "' is listed twice");
    try {
      validate_scene_spec(where, spec);
    } catch (const InputError& e) {
      const std::string msg = e.what();
      throw InputError(msg.rfind(where, 0) == 0 ? msg : where + ": " + msg);
    }
    if (sample > 0 && sample < plan.accels.size()) on_scene = sample_accels(plan.accels, spec, sample, seed);
    plan.scenes.push_back(spec);
    plan.scene_accels.push_back(on_scene);
  }

  if (j.contains("replicates")) {
    const std::string where = path + ": replicates";
    const auto& rep = j["replicates"];
    if (!rep.is_object()) throw InputError(where + ": expected {\"fraction\": F, \"repeats\": R}");
    for (auto it = rep.begin(); it != rep.end(); ++it)
      if (it.key() != "fraction" && it.key() != "repeats")
        throw InputError(where + ": unknown key '" + it.key() + "' (valid: fraction, repeats)");
    if (!rep.contains("fraction") || !rep["fraction"].is_number() || !(rep["fraction"].get<double>() > 0) ||
        rep["fraction"].get<double>() > 1)
      throw InputError(where + ": fraction: expected a number in (0, 1]");
    if (rep.contains("repeats")) plan.replicate_repeats = static_cast<std::int64_t>(read_count(rep["repeats"], where + ": repeats", 10));
    plan.replicated = replicated_cases(plan, rep["fraction"].get<double>());
  }
  return plan;
}

void check_row_in_plan(const SweepPlan& plan, const RunRecord& r, const std::string& where) {
  if (r.case_number >= plan.case_count())
    throw InputError(where + ": case " + std::to_string(r.case_number) + " is not in plan " + plan.source + " (" +
                     std::to_string(plan.case_count()) + " cases)");
  const SweepCase c = plan.case_at(r.case_number);
  if (c.scene != r.scene || c.accel != r.accel || c.rays != r.rays)
    throw InputError(where + ": case " + std::to_string(r.case_number) + " is (" + r.scene + ", " + r.accel + ", " +
                     r.rays + ") but plan " + plan.source + " says (" + c.scene + ", " + c.accel + ", " + c.rays + ")");
  if (c.replicate != r.replicate)
    throw InputError(where + ": case " + std::to_string(r.case_number) + " is replicate " + std::to_string(r.replicate) +
                     " but plan " + plan.source + " says replicate " + std::to_string(c.replicate));
}

ShardSpec parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  std::int64_t k = 0, n = 0;
  if (slash == std::string::npos || !parse_int(text.substr(0, slash), k) || !parse_int(text.substr(slash + 1), n) ||
      n < 1 || k < 0 || k >= n || n > (std::int64_t{1} << 20))
    throw InputError("--shard '" + text + "': expected K/N with 0 <= K < N (e.g. 0/4)");
  return {k, n};
}

BuiltStructure build_structure(const std::string& accel_spec, const std::shared_ptr<const Scene>& scene, int threads,
                               int max_passes, double max_seconds) {
  BuiltStructure b;
  TimingArena arena(threads);
  double total = 0;
  for (int pass = 0; pass < std::max(max_passes, 1) && (pass < 2 || total < max_seconds); ++pass) {
    b.accel.reset();
    const auto start = std::chrono::steady_clock::now();
    arena.execute([&] { b.accel = make_accelerator(accel_spec, scene, model_build_context()); });
    const double seconds = seconds_since(start);
    b.build_s = pass == 0 ? seconds : std::min(b.build_s, seconds);
    b.build_s_max = pass == 0 ? seconds : std::max(b.build_s_max, seconds);
    b.build_passes = pass + 1;
    total += seconds;
  }
  b.features = tree_features(*b.accel, *scene);
  return b;
}

RunRecord measure_case(const SweepCase& c, const Scene& scene, const BuiltStructure& built, const Aggregate& embree,
                       const std::vector<Ray>& rays, const TimingOptions& timing) {
  if (rays.empty()) throw InputError("rays '" + c.rays + "': no rays to time");
  RunRecord r;
  r.case_number = c.number;
  r.scene = c.scene;
  r.accel = c.accel;
  r.rays = c.rays;
  r.replicate = c.replicate;
  r.family = structure_family(c.accel);
  r.scene_family = scene_family_of(c.scene);
  r.ray_kind = parse_spec(c.rays).name;
  r.query = timing.any_hit ? "occluded" : "intersect";
  r.primitives = static_cast<std::int64_t>(scene.total_primitive_count());
  r.ray_count = static_cast<std::int64_t>(rays.size());
  r.threads = resolve_thread_count(timing.threads);
  const Provenance& p = provenance_of_this_process();
  r.git_revision = p.git_revision;
  r.host = p.host;
  r.cpu_model = p.cpu_model;
  r.isa = p.isa;
  r.l2_bytes = p.l2_bytes;
  r.llc_bytes = p.llc_bytes;
  r.l1d_bytes = p.l1d_bytes;
  r.cache_source = p.cache_source;

  const AlternatingTiming t = time_alternating(*built.accel, &embree, rays, timing);
  r.passes = t.passes;
  r.clock = t.thread_cpu ? "thread_cpu" : "wall";
  r.ns_per_ray_min = t.ns_per_ray_min;
  r.ns_per_ray_median = t.ns_per_ray_median;
  r.ns_per_ray_max = t.ns_per_ray_max;
  r.embree_ns_per_ray_min = t.embree_ns_per_ray_min;
  r.embree_ns_per_ray_max = t.embree_ns_per_ray_max;
  r.embree_bytes = static_cast<std::int64_t>(embree.stats().bytes);
  r.build_s = built.build_s;
  r.build_s_max = built.build_s_max;
  r.build_passes = built.build_passes;

  const TraceResult counted = trace_rays(*built.accel, rays, TraceOptions{timing.threads, true, timing.any_hit});
  const double n = static_cast<double>(rays.size());
  r.nodes_per_ray = static_cast<double>(counted.counters.nodes) / n;
  r.leaves_per_ray = static_cast<double>(counted.counters.leaves) / n;
  r.tests_per_ray = static_cast<double>(counted.counters.prim_tests) / n;
  r.hits_per_ray = static_cast<double>(counted.counters.prim_hits) / n;
  r.mailbox_skips_per_ray = static_cast<double>(counted.counters.mailbox_skips) / n;
  r.hit_rate = static_cast<double>(counted.hit_count) / n;

  fill_tree_features(r, built.features);
  fill_memory_features(r, built.features);
  return r;
}

SweepSummary run_sweep(const SweepPlan& plan, const SweepOptions& options) {
  namespace fs = std::filesystem;
  if (options.out.empty()) throw InputError("sweep: --out is required");
  const bool exists = fs::exists(options.out);
  if (exists && !options.resume)
    throw InputError(options.out + ": exists; use --resume to continue it, or choose another --out");

  // The cases already measured (resume), checked against the plan.
  std::set<std::int64_t> done;
  if (exists) {
    std::size_t complete = 0;
    const std::vector<RunRecord> rows = read_runs_csv(options.out, true, &complete);
    if (complete < fs::file_size(options.out)) {
      if (options.progress) options.progress("dropping an incomplete last line of " + options.out);
      fs::resize_file(options.out, complete);
    }
    for (const RunRecord& r : rows) {
      check_row_in_plan(plan, r, options.out);
      if (!done.insert(r.case_number).second)
        throw InputError(options.out + ": case " + std::to_string(r.case_number) + " appears twice");
    }
  }

  std::ofstream out(options.out, std::ios::app | std::ios::binary);
  if (!out) throw InputError(options.out + ": cannot write");
  const bool created = !exists;
  if (created || fs::file_size(options.out) == 0) out << runs_csv_header() << '\n' << std::flush;

  std::vector<std::int64_t> todo;
  for (std::int64_t i = options.shard.index; i < plan.case_count(); i += options.shard.count)
    if (!done.count(i)) todo.push_back(i);
  SweepSummary summary;
  summary.skipped = static_cast<std::int64_t>(done.size());
  if (options.progress) {
    char line[200];
    std::snprintf(line, sizeof line, "; shard %lld/%lld: %zu to run, %zu done", static_cast<long long>(options.shard.index),
                  static_cast<long long>(options.shard.count), todo.size(), done.size());
    options.progress("sweep " + plan.source + ": " + plan.describe() + line);
  }

  // Caches for the current scene (cases are scene-major) and the current structure, which a
  // replicate builds again.
  std::string scene_spec, accel_spec;
  std::int64_t built_replicate = -1;
  const auto sweep_start = std::chrono::steady_clock::now();
  std::shared_ptr<const Scene> scene;
  std::unique_ptr<Aggregate> embree;
  std::map<std::string, std::vector<Ray>> rays;
  BuiltStructure built;
  TimingOptions timing = options.timing;
  timing.threads = options.threads;
  if (plan.seconds_per_case) timing.min_seconds = *plan.seconds_per_case;
  try {
    for (std::size_t k = 0; k < todo.size(); ++k) {
      const SweepCase c = plan.case_at(todo[k]);
      const auto start = std::chrono::steady_clock::now();
      if (c.scene != scene_spec) {
        built = {};
        embree.reset();
        rays.clear();
        accel_spec.clear();
        scene = make_scene(c.scene);
        if (scene->instanced())
          throw InputError("plan " + plan.source + ": scene '" + c.scene + "' is instanced; the cost model needs flat scenes");
        scene_spec = c.scene;
        embree = make_accelerator("embree", scene);
      }
      if (c.accel != accel_spec || c.replicate != built_replicate) {
        built = {};
        built = build_structure(c.accel, scene, options.threads, kSweepBuildPasses, kSweepBuildSeconds);
        accel_spec = c.accel;
        built_replicate = c.replicate;
      }
      auto& ray_set = rays[c.rays];
      if (ray_set.empty()) ray_set = make_ray_set(c.rays, scene);
      timing.any_hit = is_any_hit_ray_spec(c.rays);
      const RunRecord row = measure_case(c, *scene, built, *embree, ray_set, timing);
      out << to_csv_row(row) << '\n' << std::flush;
      if (!out) throw InputError(options.out + ": write failed");
      ++summary.measured;
      if (options.progress) {
        const double elapsed = seconds_since(sweep_start);
        const double rest = elapsed / static_cast<double>(k + 1) * static_cast<double>(todo.size() - k - 1);
        char line[200];
        std::snprintf(line, sizeof line, "[%zu/%zu] case %lld%s: %.0f ns/ray (Embree %.0f), %.1f s; %.0f s in, ~%.0f s to go",
                      k + 1, todo.size(), static_cast<long long>(c.number),
                      c.replicate > 0 ? (" (replicate " + std::to_string(c.replicate) + " of case " +
                                         std::to_string(c.first_case) + ")").c_str()
                                      : "",
                      row.ns_per_ray_min, row.embree_ns_per_ray_min, seconds_since(start), elapsed, rest);
        options.progress(std::string(line) + ": " + c.scene + " | " + c.accel + " | " + c.rays);
      }
    }
  } catch (...) {
    out.close();
    if (created && summary.measured == 0) fs::remove(options.out);
    throw;
  }
  return summary;
}

}  // namespace raylab
