// The `raylab` command-line tool: list accelerators and scenes, describe a scene, trace a ray set
// through an accelerator (optionally checked against the exact oracle), render an image or a
// traversal-cost heatmap. Bad input of any kind: one line `raylab: error: ...`, exit status 2.
#include <sys/resource.h>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/timing_cpu.h"
#include "accel/common/tracer.h"
#include "accel/exact/contact_classes.h"
#include "cost/auto_accel.h"
#include "cost/model_file.h"
#include "geometry/float_mode.h"
#include "geometry/input_error.h"
#include "rays/camera.h"
#include "rays/ray_file.h"
#include "rays/ray_generators.h"
#include "scene/cgal_meshes.h"
#include "scene/file_format.h"
#include "scene/scene_spec.h"
#include "tools/cost_commands.h"
#include "tools/heatmap_image.h"

namespace raylab {
namespace {

using Clock = std::chrono::steady_clock;

std::size_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

/// Runs `work` and, when it takes longer than a few seconds, prints a progress line to stderr
/// every 5 s and a closing line with its duration.
template <class Work>
auto timed_step(const std::string& what, Work&& work, double* seconds = nullptr) {
  std::mutex m;
  std::condition_variable cv;
  bool done = false;
  const auto start = Clock::now();
  std::thread reporter([&] {
    std::unique_lock lock(m);
    int ticks = 0;
    while (!cv.wait_for(lock, std::chrono::seconds(ticks == 0 ? 3 : 5), [&] { return done; })) {
      ++ticks;
      std::fprintf(stderr, "raylab: %s ... %.0f s\n", what.c_str(),
                   std::chrono::duration<double>(Clock::now() - start).count());
    }
    if (ticks > 0)
      std::fprintf(stderr, "raylab: %s done in %.1f s\n", what.c_str(),
                   std::chrono::duration<double>(Clock::now() - start).count());
  });
  auto finish = [&] {
    { std::lock_guard lock(m); done = true; }
    cv.notify_all();
    reporter.join();
    if (seconds) *seconds = std::chrono::duration<double>(Clock::now() - start).count();
  };
  try {
    auto result = work();
    finish();
    return result;
  } catch (...) {
    finish();
    throw;
  }
}

/// Any-hit results: CSV `ray,blocked` with blocked 0 or 1 (and `contact` with --classify).
void write_blocked_csv(const std::string& path, const std::vector<std::uint8_t>& blocked,
                       const std::vector<std::string>* contacts) {
  std::ofstream out(path);
  if (!out) throw InputError(path + ": cannot write");
  out << (contacts ? "ray,blocked,contact\n" : "ray,blocked\n");
  for (std::size_t i = 0; i < blocked.size(); ++i) {
    out << i << ',' << int(blocked[i]);
    if (contacts) out << ',' << (*contacts)[i];
    out << '\n';
  }
  if (!out) throw InputError(path + ": write failed");
}

/// The `contact` column of --classify: the class, with `+ill` for an ill-conditioned ray.
std::vector<std::string> contact_labels(const std::vector<RayContact>& classes) {
  std::vector<std::string> labels;
  labels.reserve(classes.size());
  for (const RayContact& c : classes) labels.push_back(std::string(contact_name(c.contact)) + (c.ill_conditioned ? "+ill" : ""));
  return labels;
}

/// An accuracy bound as `raylab accels` lists it: the statement, then the rate allowed per class.
void print_accuracy(const std::string& label, const AccuracyBound& b) {
  std::cout << "    " << label << ": " << b.statement << "\n      max mismatch rate per class ("
            << (b.exact ? "exact rule" : "tolerance rule") << "): crossing " << b.crossing_other
            << " (edge/vertex-aimed: " << b.crossing_features << "), touching " << b.touching << ", on_surface "
            << b.on_surface << ", ill_conditioned " << b.ill_conditioned << "\n";
}

/// The kernel `spec` runs (its accuracy bound's, which reads the spec as the build does; the
/// accelerator's own name when it runs none of raylab's, as Embree) and the accuracy it states
/// (`raylab accels`), for trace.
void put_kernel_guarantee(nlohmann::ordered_json& j, const std::string& spec) {
  const AccuracyBound b = accuracy_bound(spec);
  j["kernel"] = b.kernel.empty() ? parse_spec(spec).name : b.kernel;
  j["guarantee"] = {{"exact", b.exact},
                    {"rule", b.exact ? "exact" : "tolerance"},
                    {"statement", b.statement},
                    {"max_mismatch_rate",
                     {{"crossing", b.crossing_other},
                      {"crossing_edge_or_vertex_aimed", b.crossing_features},
                      {"touching", b.touching},
                      {"on_surface", b.on_surface},
                      {"ill_conditioned", b.ill_conditioned}}}};
}

void print_accels() {
  for (const auto& k : accelerator_kinds()) {
    std::cout << k.name << "\n    " << k.summary << "\n";
    for (const auto& p : k.params)
      std::cout << "    " << p.key << "=...  " << p.description << " (default " << p.default_value << ")\n";
    SpecReader none(parse_spec(k.name));
    print_accuracy("accuracy", k.accuracy(none));
    // The default kernel is the certified one; the watertight one is listed beside it.
    const bool has_watertight = std::any_of(k.params.begin(), k.params.end(), [](const ParamDoc& p) {
      return p.key == "kernel" && p.description.find("watertight") != std::string::npos;
    });
    if (has_watertight) print_accuracy("accuracy with kernel=watertight", accuracy_bound(k.name + ":kernel=watertight"));
  }
}

void print_scenes() {
  for (const auto& k : scene_kinds()) {
    std::cout << k.name << "\n    " << k.summary << "\n";
    for (const auto& p : k.params)
      std::cout << "    " << p.key << "=...  " << p.description << " (default " << p.default_value << ")\n";
    if (k.name != "file") continue;
    for (const auto& f : file_formats()) {
      std::string extensions;
      for (const auto& e : f.extensions) extensions += (extensions.empty() ? "" : " ") + e;
      std::cout << "    " << fmt::format("{:<6}", extensions) << " " << f.name << ", read by " << library_name(f.library)
                << (f.library == FileLibrary::openmesh ? " (one mesh)" : " (node tree: shared meshes become instances)") << "\n";
    }
  }
}

void print_ray_generators() {
  for (const auto& g : ray_generator_docs()) {
    std::cout << g.usage << "\n    " << g.summary << "\n";
    for (const auto& p : g.params)
      std::cout << "    " << p.key << "=...  " << p.description << " (default " << p.default_value << ")\n";
  }
}

struct InfoOptions {
  std::string scene;
  bool json = false;
};

int run_info(const InfoOptions& o) {
  const auto scene = timed_step("loading " + o.scene, [&] { return make_scene(o.scene); });
  const SceneInfo info = describe(*scene);
  nlohmann::ordered_json j;
  j["scene"] = o.scene;
  j["meshes"] = info.meshes;
  j["instances"] = info.instances;
  j["triangles"] = info.triangles;
  j["unique_triangles"] = info.unique_triangles;
  j["primitives"] = static_cast<std::uint64_t>(info.primitives);
  j["spheres"] = info.spheres;
  j["degenerate_triangles"] = info.degenerate_triangles;
  j["lines"] = info.lines;    // of the source file, left out of the triangles above
  j["points"] = info.points;
  j["closed"] = info.closed;
  j["bounds_min"] = {info.bounds.lo.x, info.bounds.lo.y, info.bounds.lo.z};
  j["bounds_max"] = {info.bounds.hi.x, info.bounds.hi.y, info.bounds.hi.z};
  if (o.json) {
    std::cout << j.dump() << "\n";
  } else {
    for (auto it = j.begin(); it != j.end(); ++it) std::cout << it.key() << ": " << it.value().dump() << "\n";
  }
  return 0;
}

struct TraceCommand {
  std::string scene, accel = "embree", rays = "primary:65536", check, hits_out, rays_out;
  int threads = 0;
  bool json = false;
  bool counters = true;
  bool classify = false;
};

int run_trace(const TraceCommand& o) {
  if (!o.check.empty() && o.check != "exact" && o.check != "brute")
    throw InputError("--check " + o.check + ": expected exact or brute");
  if (o.threads < 0 || o.threads > 1024) throw InputError("--threads " + std::to_string(o.threads) + ": expected 0..1024");
  validate_accelerator_spec(o.accel);  // before any expensive work
  const auto scene = timed_step("loading scene " + o.scene, [&] { return make_scene(o.scene); });
  const std::vector<Ray> rays = timed_step("generating rays " + o.rays, [&] { return make_ray_set(o.rays, scene); });
  if (!o.rays_out.empty()) write_rays(o.rays_out, rays);
  const bool any_hit = is_any_hit_ray_spec(o.rays);

  double build_s = 0;
  const std::size_t rss_before = peak_rss_bytes();
  // `auto` weighs build time against the trace of the rays that follow: without its own count=, it
  // is handed the count of this ray set.
  std::string accel_spec = o.accel;
  if (const SpecString s = parse_spec(o.accel); s.name == "auto" && !SpecReader(s).has("count"))
    accel_spec += (s.params.empty() && s.positional.empty() ? ":count=" : ",count=") + std::to_string(rays.size());
  auto accel = timed_step("building " + o.accel, [&] { return make_accelerator(accel_spec, scene, model_build_context()); },
                          &build_s);
  TraceOptions topt{o.threads, false, any_hit};
  const TraceResult timed = timed_step("tracing", [&] { return trace_rays(*accel, rays, topt); });
  RayCounters counters;
  if (o.counters) {
    topt.counters = true;
    counters = timed_step("counting", [&] { return trace_rays(*accel, rays, topt); }).counters;
  }
  const AccelStats stats = accel->stats();
  const double n = static_cast<double>(rays.size());

  nlohmann::ordered_json j;
  j["scene"] = o.scene;
  j["triangles"] = describe(*scene).triangles;
  j["primitives"] = static_cast<std::uint64_t>(scene->total_primitive_count());
  j["accel"] = o.accel;
  j["build_s"] = build_s;
  j["ray_spec"] = o.rays;
  j["rays"] = rays.size();
  j["query"] = any_hit ? "occluded" : "intersect";
  j["threads"] = resolve_thread_count(o.threads);
  j["trace_s"] = timed.seconds;
  j["mrays_per_s"] = timed.seconds > 0 ? n / timed.seconds * 1e-6 : 0.0;
  j["hit_rate"] = n > 0 ? static_cast<double>(timed.hit_count) / n : 0.0;
  j["nodes_per_ray"] = n > 0 ? static_cast<double>(counters.nodes) / n : 0.0;
  j["leaves_per_ray"] = n > 0 ? static_cast<double>(counters.leaves) / n : 0.0;
  j["prim_tests_per_ray"] = n > 0 ? static_cast<double>(counters.prim_tests) / n : 0.0;
  j["prim_hits_per_test"] = counters.prim_tests > 0 ? static_cast<double>(counters.prim_hits) / counters.prim_tests : 0.0;
  j["mailbox_skips_per_ray"] = n > 0 ? static_cast<double>(counters.mailbox_skips) / n : 0.0;
  j["exact_fallbacks_per_ray"] = n > 0 ? static_cast<double>(counters.exact_fallbacks) / n : 0.0;
  j["interval_stage_per_ray"] = n > 0 ? static_cast<double>(counters.interval_stage) / n : 0.0;
  j["accel_bytes"] = stats.bytes;
  j["bytes_per_primitive"] = scene->total_primitive_count() > 0 ? stats.bytes / scene->total_primitive_count() : 0.0;
  j["accel_nodes"] = stats.nodes;
  if (stats.sah_cost >= 0) j["sah_cost"] = stats.sah_cost;
  if (const auto hash = accel->structure_hash()) j["structure_hash"] = fmt::format("{:016x}", *hash);
  const auto* auto_chooser = dynamic_cast<const AutoAccelerator*>(accel.get());
  put_kernel_guarantee(j, auto_chooser ? auto_chooser->choice().chosen : o.accel);
  if (const auto* chooser = dynamic_cast<const AutoAccelerator*>(accel.get())) {
    const AutoChoice& c = chooser->choice();
    nlohmann::ordered_json candidates = nlohmann::ordered_json::array();
    for (const AutoCandidate& k : c.candidates) {
      nlohmann::ordered_json e = {{"spec", k.spec}};
      if (k.skipped.empty()) e["predicted_ns_per_ray"] = k.predicted_ns_per_ray;
      else e["skipped"] = k.skipped;
      if (std::isfinite(k.predicted_total_s)) {
        e["predicted_build_s"] = k.predicted_build_s;
        e["predicted_total_s"] = k.predicted_total_s;
        e["interval90_total_s"] = {k.total_lo_s, k.total_hi_s};
        e["trace_model"] = k.trace_model;
      }
      e["built"] = k.built;
      if (std::isfinite(k.measured_build_s)) e["measured_build_s"] = k.measured_build_s;
      if (std::isfinite(k.measured_ns_per_ray)) e["sampled_ns_per_ray"] = k.measured_ns_per_ray;
      candidates.push_back(e);
    }
    j["auto_choice"] = {{"chosen", c.chosen},
                        {"predicted_ns_per_ray", c.predicted_ns_per_ray},
                        {"rays", c.rays},
                        {"model", c.model},
                        {"candidates", candidates}};
    auto number_or_null = [](double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(); };
    j["auto_method"] = c.method;
    j["auto_count"] = c.count;
    j["auto_choose_s"] = c.choose_s;
    j["auto_predicted_build_s"] = number_or_null(c.predicted_build_s);
    j["auto_predicted_trace_s"] = number_or_null(c.predicted_trace_s);
    j["auto_runner_up"] = c.runner_up.empty() ? nlohmann::ordered_json()
                                              : nlohmann::ordered_json{{"spec", c.runner_up},
                                                                       {"predicted_total_s", number_or_null(c.runner_up_total_s)}};
    j["auto_candidates_built"] = c.candidates_built;
    j["auto_sampled"] = c.sampled;
    j["auto_extrapolation_factor"] = c.extrapolation_factor;
    if (!c.note.empty()) j["auto_note"] = c.note;
  }
  j["build_rss_growth_bytes"] = peak_rss_bytes() - rss_before;

  // The exact oracle's classes of the rays: with --check exact (mismatches per class) and --classify.
  std::vector<RayContact> classes;
  if (o.classify || o.check == "exact")
    classes = timed_step("classifying the rays' contacts", [&] { return classify_contacts(scene, rays, o.threads); });
  if (!classes.empty()) {
    std::size_t ill = 0;
    std::array<std::size_t, 4> per_class{};
    for (const RayContact& c : classes) {
      ill += c.ill_conditioned;
      ++per_class[static_cast<std::size_t>(c.contact)];
    }
    for (const Contact k : {Contact::none, Contact::crossing, Contact::touching, Contact::on_surface})
      j[std::string("rays_") + contact_name(k)] = per_class[static_cast<std::size_t>(k)];
    j["ill_conditioned_rays"] = ill;
  }
  if (!o.check.empty()) {
    double check_s = 0;
    auto reference = timed_step("building the " + o.check + " reference",
                                [&] { return make_accelerator(o.check, scene, model_build_context()); });
    const TraceResult ref = timed_step("tracing the " + o.check + " reference",
                                       [&] { return trace_rays(*reference, rays, TraceOptions{o.threads, false, any_hit}); },
                                       &check_s);
    // Methods stated exact (the exact and certified kernels) are checked by the exact rule.
    const AccuracyBound bound = accuracy_bound(o.accel);
    const bool exact_rule = o.check == "exact" && bound.exact;
    const std::vector<RayContact>* cls = classes.empty() ? nullptr : &classes;
    const HitComparison c = any_hit      ? compare_occlusion(timed.blocked, ref.blocked, cls)
                            : exact_rule ? compare_hits_exact(*scene, rays, timed.hits, ref.hits, cls)
                                         : compare_hits(rays, timed.hits, ref.hits,
                                                        length(Vec3d(scene->bounds().diagonal())), cls);
    j["check"] = o.check;
    j["check_rule"] = any_hit ? "blocked" : (exact_rule ? "exact" : "tolerance");
    j["check_s"] = check_s;
    j["mismatches"] = c.mismatches;
    j["ties"] = c.ties;
    j["false_hits"] = c.false_hits;
    j["missed_hits"] = c.missed_hits;
    j["wrong_t"] = c.wrong_t;
    if (cls) {
      for (const Contact k : {Contact::none, Contact::crossing, Contact::touching, Contact::on_surface})
        j[std::string("mismatches_") + contact_name(k)] = c.class_mismatches[static_cast<std::size_t>(k)];
      j["mismatches_ill_conditioned"] = c.ill_conditioned_mismatches;
    }
    if (cls && o.check == "exact") {
      // The accelerator's stated accuracy (`raylab accels`), judged per bucket as the oracle suite judges it.
      nlohmann::json buckets;
      for (int k = 0; k < kRayBuckets; ++k)
        buckets[ray_bucket_name(static_cast<RayBucket>(k))] = {{"rays", c.bucket_rays[k]}, {"mismatches", c.bucket_mismatches[k]}};
      j["mismatches_by_bucket"] = buckets;
      std::string exceeded;
      j["within_stated_bound"] = within_bound(bound, c, is_feature_ray_spec(o.rays), &exceeded);
      if (!exceeded.empty()) j["bound_exceeded"] = exceeded;
    }
    j["first_mismatch_rays"] = c.first_mismatches;
  }
  j["peak_rss_bytes"] = peak_rss_bytes();
  if (!o.hits_out.empty()) {
    const std::vector<std::string> labels = o.classify ? contact_labels(classes) : std::vector<std::string>{};
    const std::vector<std::string>* contacts = o.classify ? &labels : nullptr;
    if (any_hit) write_blocked_csv(o.hits_out, timed.blocked, contacts);
    else write_hits_csv(o.hits_out, timed.hits, scene.get(), contacts);
  }
  if (o.json) {
    std::cout << j.dump() << "\n";
  } else {
    for (auto it = j.begin(); it != j.end(); ++it) std::cout << it.key() << ": " << it.value().dump() << "\n";
  }
  return 0;
}

struct RenderCommand {
  std::string scene, accel = "embree", out;
  std::string camera = "outside";  ///< a camera_placement_names() entry (camera.h)
  int width = 512, height = 512, threads = 0;
  bool heatmap = false;
  bool log_scale = false;  ///< --log: the heatmap's colours on a log scale
};

int run_render(const RenderCommand& o) {
  if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384)
    throw InputError("--width/--height must be in [1, 16384]");
  if (o.threads < 0 || o.threads > 1024) throw InputError("--threads " + std::to_string(o.threads) + ": expected 0..1024");
  if (o.out.size() < 5 || o.out.substr(o.out.size() - 4) != ".png") throw InputError("--out " + o.out + ": expected a .png path");
  if (o.log_scale && !o.heatmap) throw InputError("--log: a log colour scale needs --heatmap");
  validate_accelerator_spec(o.accel);
  const auto scene = timed_step("loading scene " + o.scene, [&] { return make_scene(o.scene); });
  auto accel = timed_step("building " + o.accel, [&] { return make_accelerator(o.accel, scene, model_build_context()); });
  const Camera camera = placed_camera(parse_camera_placement(o.camera), scene->bounds());
  const std::vector<Ray> rays = image_rays(camera, o.width, o.height);
  std::vector<float> values(rays.size());
  if (o.heatmap) {
    if (!accel->reports_counters())
      throw InputError("--heatmap: accelerator '" + o.accel + "' reports no traversal counters");
    values = timed_step("rendering heatmap", [&] { return traversal_cost_per_ray(*accel, rays, o.threads); });
    write_heatmap_png(o.out, values, o.width, o.height, "nodes + leaves + primitive tests per pixel (" + o.accel + ")",
                      o.log_scale ? HeatmapScale::log : HeatmapScale::linear);
  } else {
    const TraceResult result = timed_step("rendering", [&] { return trace_rays(*accel, rays, TraceOptions{o.threads}); });
    const Vec3d light = normalize(Vec3d(0.4, 0.8, 0.45));
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Hit& h = result.hits[i];
      if (!h.valid()) { values[i] = -1.0f; continue; }
      values[i] = static_cast<float>(shading_cosine(*scene, h, rays[i], light));
    }
    write_shaded_png(o.out, values, o.width, o.height);
  }
  std::cerr << "raylab: wrote " << o.out << "\n";
  return 0;
}

}  // namespace
}  // namespace raylab

int main(int argc, char** argv) {
  using namespace raylab;
  CLI::App app{"raylab: a laboratory for ray shooting (see README.md)"};
  app.require_subcommand(1);

  app.add_subcommand("accels", "list the accelerators, their parameters and accuracy bounds");
  app.add_subcommand("scenes", "list the scene kinds and their parameters");
  app.add_subcommand("rays", "list the ray generators and their parameters");
  auto* cgal = app.add_subcommand("cgal-meshes", "list the CGAL demo meshes available as cgal:NAME");

  InfoOptions info;
  auto* info_cmd = app.add_subcommand(
      "info", "print meshes, instances, triangles (over all instances and unique), bounds, degenerate count and closedness of a scene, and the lines and points its file holds (left out)");
  info_cmd->add_option("scene", info.scene, "scene spec")->required();
  info_cmd->add_flag("--json", info.json, "print one JSON object");

  TraceCommand trace;
  auto* trace_cmd = app.add_subcommand("trace", "build an accelerator on a scene and trace a ray set");
  trace_cmd->add_option("--scene", trace.scene, "scene spec, e.g. cgal:bunny00 or sphereflake:depth=3")->required();
  trace_cmd->add_option("--accel", trace.accel, "accelerator spec, e.g. embree:quality=high (see `raylab accels`)");
  trace_cmd->add_option("--rays", trace.rays, "ray spec: primary:N, diffuse:N, shadow:N, ao:N, lines:N, edges:N, vertices:N, file:PATH");
  trace_cmd->add_option("--threads", trace.threads, "tracing threads (0: all; 1: single-core figures)");
  trace_cmd->add_option("--check", trace.check, "compare every ray against a reference: exact | brute");
  trace_cmd->add_option("--hits-out", trace.hits_out,
                        "write hits as CSV ray,prim,t,u,v (plus instance,base on an instanced scene; contact with "
                        "--classify)");
  trace_cmd->add_option("--rays-out", trace.rays_out, "write the traced rays in the ray file format");
  trace_cmd->add_flag("--json", trace.json, "print one JSON object instead of key: value lines");
  trace_cmd->add_flag("!--no-counters", trace.counters, "skip the second, counted pass");
  trace_cmd->add_flag("--classify", trace.classify,
                      "classify every ray's first contact exactly (crossing, touching, on_surface, none; +ill when "
                      "ill-conditioned): counts in the output, a `contact` column in --hits-out");

  RenderCommand render;
  auto* render_cmd = app.add_subcommand("render", "render a shaded image or a traversal-cost heatmap to PNG");
  render_cmd->add_option("--scene", render.scene, "scene spec")->required();
  render_cmd->add_option("--accel", render.accel, "accelerator spec");
  render_cmd->add_option("--out", render.out, "output .png")->required();
  render_cmd->add_option("--width", render.width, "image width");
  render_cmd->add_option("--height", render.height, "image height");
  render_cmd->add_option("--threads", render.threads, "threads");
  render_cmd->add_option("--camera", render.camera, "outside (framing the scene box) or inside (for enclosed scenes)")
      ->check(CLI::IsMember(camera_placement_names()));
  render_cmd->add_flag("--heatmap", render.heatmap, "nodes + tests per pixel with a colour bar");
  render_cmd->add_flag("--log", render.log_scale, "with --heatmap: a logarithmic colour scale");

  SweepCommand sweep;
  auto* sweep_cmd = app.add_subcommand("sweep", "measure the cost model's data set: every case of a plan, one CSV row each");
  sweep_cmd->add_option("--plan", sweep.plan, "quick | full | a plan file (JSON: scenes, accels, rays)")->required();
  sweep_cmd->add_option("--out", sweep.out, "the runs CSV (appended row by row); required unless --check");
  sweep_cmd->add_option("--shard", sweep.shard, "K/N: run the cases whose number is K modulo N");
  sweep_cmd->add_flag("--resume", sweep.resume, "continue an existing --out, skipping its cases");
  sweep_cmd->add_option("--threads", sweep.threads, "tracing and build threads (default 1: the single-thread figures)");
  sweep_cmd->add_option("--passes", sweep.passes, "timed passes per case, at least 5 (default 5)");
  sweep_cmd->add_flag("--check", sweep.check, "validate the plan, print its case count and run nothing");

  MergeCommand merge;
  auto* merge_cmd = app.add_subcommand(
      "merge", "merge a sharded sweep's runs CSVs into one data set, sorted by case, when no case is missing or repeated");
  merge_cmd->add_option("--plan", merge.plan, "the plan the shards ran (quick | full | a plan file)")->required();
  merge_cmd->add_option("--out", merge.out, "the merged runs CSV (must not exist); OUT.sweep.json records the merge")
      ->required();
  merge_cmd->add_option("--shards", merge.shards, "N of the shards' --shard K/N (default: one file per shard)");
  merge_cmd->add_option("--note", merge.note, "how the shards were run, for the merge record");
  merge_cmd->add_option("shard_files", merge.shard_files, "the shards' runs CSVs (a missing file: a shard with no row)")
      ->required();

  FitCommand fit;
  auto* fit_cmd = app.add_subcommand("fit", "fit the cost model (Ceres) to a data set and select its terms");
  fit_cmd->add_option("--runs", fit.runs, "the runs CSV of raylab sweep")->required();
  fit_cmd->add_option("--out", fit.out, "the model file to write (model.json)")->required();
  fit_cmd->add_option("--loss-scale", fit.loss_scale, "Huber loss scale on relative residuals (default 0.1 = 10%)");
  fit_cmd->add_option("--target", fit.target,
                      "embree-normalized (default: each time scaled by its Embree passes' disturbance) | min");
  fit_cmd->add_flag("--allow-mixed-hardware", fit.allow_mixed_hardware, "fit rows measured on different CPU models");
  fit_cmd->add_flag("--json", fit.json, "print a JSON summary instead of the table");

  PredictCommand predict;
  auto* predict_cmd = app.add_subcommand("predict", "predict ns/ray of an accelerator on a scene from a fitted model");
  predict_cmd->add_option("--model", predict.model, "model.json, or 'default' (the committed model)");
  predict_cmd->add_option("--scene", predict.scene, "scene spec")->required();
  predict_cmd->add_option("--accel", predict.accel, "accelerator spec")->required();
  predict_cmd->add_option("--rays", predict.rays, "ray spec (its kind selects the ray-kind terms)");
  predict_cmd->add_flag("--measure", predict.measure, "also trace and time it as raylab sweep does");
  predict_cmd->add_option("--threads", predict.threads, "threads (default 1)");
  predict_cmd->add_option("--passes", predict.passes, "timed passes with --measure, at least 5");
  predict_cmd->add_flag("--strict", predict.strict,
                        "refuse to predict more than a factor 2 outside the data the model was fitted on");
  predict_cmd->add_flag("--allow-extrapolation", predict.allow_extrapolation,
                        "accepted for old scripts, no effect: outside the fitted range predict warns and widens the interval");
  predict_cmd->add_flag("--json", predict.json, "print one JSON object");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "raylab: error: " << e.what() << " (see raylab --help)\n";
    return 2;
  }
  try {
    (void)timing_cpu();  // a bad RAYLAB_TIMING_CPU fails before any work
    if (app.got_subcommand("accels")) print_accels();
    else if (app.got_subcommand("scenes")) print_scenes();
    else if (app.got_subcommand("rays")) print_ray_generators();
    else if (cgal->parsed()) { for (const auto& n : cgal_mesh_names()) std::cout << "cgal:" << n << "\n"; }
    else if (info_cmd->parsed()) return run_info(info);
    else if (trace_cmd->parsed()) return run_trace(trace);
    else if (render_cmd->parsed()) return run_render(render);
    else if (sweep_cmd->parsed()) return run_sweep_command(sweep);
    else if (merge_cmd->parsed()) return run_merge_command(merge);
    else if (fit_cmd->parsed()) return run_fit_command(fit);
    else if (predict_cmd->parsed()) return run_predict_command(predict);
    return 0;
  } catch (const InputError& e) {
    std::cerr << "raylab: error: " << e.what() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "raylab: error: out of memory\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "raylab: error: " << e.what() << "\n";
    return 3;
  }
}
