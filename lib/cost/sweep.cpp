#include "cost/sweep.h"

#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "accel/common/accel_factory.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "cost/provenance.h"
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
  SpecReader reader(parse_spec(spec));
  const AccelKind& kind = find_accelerator_kind(reader.spec().name);
  reader.reject_unknown_keys(kind.params);
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

std::int64_t SweepPlan::case_count() const {
  return static_cast<std::int64_t>(scenes.size() * accels.size() * rays.size());
}

SweepCase SweepPlan::case_at(std::int64_t number) const {
  const auto r = static_cast<std::int64_t>(rays.size()), a = static_cast<std::int64_t>(accels.size());
  SweepCase c;
  c.number = number;
  c.rays = rays[static_cast<std::size_t>(number % r)];
  c.accel = accels[static_cast<std::size_t>(number / r % a)];
  c.scene = scenes[static_cast<std::size_t>(number / r / a)];
  return c;
}

std::string plan_path(const std::string& name_or_path) {
  if (name_or_path == "quick" || name_or_path == "full") return raylab_data_dir() + "/plans/" + name_or_path + ".json";
  return name_or_path;
}

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
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    if (key != "scenes" && key != "accels" && key != "rays" && key != "description")
      throw InputError(path + ": unknown key '" + key + "' (valid: scenes, accels, rays, description)");
  }
  SweepPlan plan;
  plan.source = name_or_path;
  std::vector<std::string>* lists[] = {&plan.scenes, &plan.accels, &plan.rays};
  for (int k = 0; k < 3; ++k) {
    const std::string key = kListKeys[k];
    if (!j.contains(key)) throw InputError(path + ": missing key '" + key + "'");
    const auto& list = j[key];
    if (!list.is_array() || list.empty()) throw InputError(path + ": '" + key + "' must be a non-empty list of spec strings");
    std::set<std::string> seen;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string where = path + ": " + key + "[" + std::to_string(i) + "]";
      if (!list[i].is_string() || list[i].get<std::string>().empty())
        throw InputError(where + ": expected a non-empty spec string");
      const std::string spec = list[i].get<std::string>();
      if (!seen.insert(spec).second) throw InputError(where + ": '" + spec + "' is listed twice");
      try {
        if (k == 0) validate_scene_spec(where, spec);
        else if (k == 1) validate_accel_spec(where, spec);
        else validate_ray_spec(where, spec);
      } catch (const InputError& e) {
        const std::string msg = e.what();
        throw InputError(msg.rfind(where, 0) == 0 ? msg : where + ": " + msg);
      }
      lists[k]->push_back(spec);
    }
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
}

ShardSpec parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  std::int64_t k = 0, n = 0;
  if (slash == std::string::npos || !parse_int(text.substr(0, slash), k) || !parse_int(text.substr(slash + 1), n) ||
      n < 1 || k < 0 || k >= n || n > (std::int64_t{1} << 20))
    throw InputError("--shard '" + text + "': expected K/N with 0 <= K < N (e.g. 0/4)");
  return {k, n};
}

BuiltStructure build_structure(const std::string& accel_spec, const std::shared_ptr<const Scene>& scene, int threads) {
  BuiltStructure b;
  tbb::task_arena arena(resolve_thread_count(threads));
  const auto start = std::chrono::steady_clock::now();
  arena.execute([&] { b.accel = make_accelerator(accel_spec, scene); });
  b.build_s = seconds_since(start);
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

  const AlternatingTiming t = time_alternating(*built.accel, &embree, rays, timing);
  r.passes = t.passes;
  r.clock = t.thread_cpu ? "thread_cpu" : "wall";
  r.ns_per_ray_min = t.ns_per_ray_min;
  r.ns_per_ray_median = t.ns_per_ray_median;
  r.embree_ns_per_ray_min = t.embree_ns_per_ray_min;
  r.build_s = built.build_s;

  const TraceResult counted = trace_rays(*built.accel, rays, TraceOptions{timing.threads, true, timing.any_hit});
  const double n = static_cast<double>(rays.size());
  r.nodes_per_ray = static_cast<double>(counted.counters.nodes) / n;
  r.leaves_per_ray = static_cast<double>(counted.counters.leaves) / n;
  r.tests_per_ray = static_cast<double>(counted.counters.prim_tests) / n;
  r.hits_per_ray = static_cast<double>(counted.counters.prim_hits) / n;
  r.mailbox_skips_per_ray = static_cast<double>(counted.counters.mailbox_skips) / n;
  r.hit_rate = static_cast<double>(counted.hit_count) / n;

  fill_tree_features(r, built.features);
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
    std::snprintf(line, sizeof line, "sweep %s: %lld cases (%zu scenes x %zu accels x %zu rays); shard %lld/%lld: %zu to run, %zu done",
                  plan.source.c_str(), static_cast<long long>(plan.case_count()), plan.scenes.size(), plan.accels.size(),
                  plan.rays.size(), static_cast<long long>(options.shard.index), static_cast<long long>(options.shard.count),
                  todo.size(), done.size());
    options.progress(line);
  }

  // Caches for the current scene (cases are scene-major) and the current structure.
  std::string scene_spec, accel_spec;
  std::shared_ptr<const Scene> scene;
  std::unique_ptr<Aggregate> embree;
  std::map<std::string, std::vector<Ray>> rays;
  BuiltStructure built;
  TimingOptions timing = options.timing;
  timing.threads = options.threads;
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
      if (c.accel != accel_spec) {
        built = {};
        built = build_structure(c.accel, scene, options.threads);
        accel_spec = c.accel;
      }
      auto& ray_set = rays[c.rays];
      if (ray_set.empty()) ray_set = make_ray_set(c.rays, scene);
      timing.any_hit = is_any_hit_ray_spec(c.rays);
      const RunRecord row = measure_case(c, *scene, built, *embree, ray_set, timing);
      out << to_csv_row(row) << '\n' << std::flush;
      if (!out) throw InputError(options.out + ": write failed");
      ++summary.measured;
      if (options.progress) {
        char line[160];
        std::snprintf(line, sizeof line, "[%zu/%zu] case %lld: %.0f ns/ray (Embree %.0f), %.1f s", k + 1, todo.size(),
                      static_cast<long long>(c.number), row.ns_per_ray_min, row.embree_ns_per_ray_min,
                      seconds_since(start));
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
