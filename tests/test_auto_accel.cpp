// `auto` that chooses before it builds (auto_accel.h): on a model fitted from a tiny sweep of this
// machine, it builds only what it chose (counted), its choice minimises the predicted build +
// count × trace time, and moves with the count; for many rays it races the candidates its
// intervals cannot tell apart and keeps the measured best; without build-time models it builds
// every candidate; a bad count is one error line.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "accel/common/accel_factory.h"
#include "accel/common/hit_comparison.h"
#include "accel/common/ray_sets.h"
#include "accel/common/tracer.h"
#include "cost/accel_spec_key.h"
#include "cost/auto_accel.h"
#include "cost/model_file.h"
#include "cost/sweep.h"
#include "geometry/input_error.h"
#include "scene/scene_spec.h"

namespace raylab {
namespace {

namespace fs = std::filesystem;

fs::path scratch_dir() {
  const auto dir = fs::temp_directory_path() / ("raylab_auto_accel_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

/// Four scenes of 300 to 6k triangles, three structures, two ray kinds: 24 cases, a few seconds.
constexpr const char* kTinyPlan = R"({
  "description": "test_auto_accel: a tiny sweep for the build-time and scene-level models",
  "scenes": ["soup:n=300", "sphere:n=1500", "walls:n=60,angle=30", "soup:n=6000"],
  "accels": ["bvh", "grid:d=1", "kdtree"],
  "rays": ["primary:256", "diffuse:256"]
})";

/// The model fitted on the tiny sweep, once per process.
const std::string& tiny_model() {
  static const std::string path = [] {
    const fs::path dir = scratch_dir();
    std::ofstream(dir / "plan.json") << kTinyPlan;
    SweepOptions options;
    options.out = (dir / "runs.csv").string();
    fs::remove(options.out);
    run_sweep(load_plan((dir / "plan.json").string()), options);
    CostModelSet set = fit_cost_model_set(read_runs_csv(options.out), FitOptions{});
    set.runs_source = options.out;
    const std::string model = (dir / "model.json").string();
    write_model_file(set, model);
    return model;
  }();
  return path;
}

const AutoChoice& choice_of(const Aggregate& a) {
  const auto* chooser = dynamic_cast<const AutoAccelerator*>(&a);
  if (!chooser) throw std::runtime_error("not an auto accelerator");
  return chooser->choice();
}

std::size_t built_count(const AutoChoice& c) {
  std::size_t n = 0;
  for (const AutoCandidate& k : c.candidates) n += k.built;
  return n;
}

/// The mismatches of `accel` against `reference` on the rays of `ray_spec`, one thread.
std::size_t mismatches_against(const Aggregate& accel, const std::string& reference,
                               const std::shared_ptr<const Scene>& scene, const std::string& ray_spec) {
  const std::vector<Ray> rays = make_ray_set(ray_spec, scene);
  const auto ref = make_accelerator(reference, scene);
  return compare_hits(rays, trace_rays(accel, rays, {1}).hits, trace_rays(*ref, rays, {1}).hits,
                      length(Vec3d(scene->bounds().diagonal())))
      .mismatches;
}

/// The measured build + count × sampled trace seconds of a raced candidate.
double measured_total(const AutoChoice& c, const AutoCandidate& k) {
  return k.measured_build_s + c.count * k.measured_ns_per_ray * 1e-9;
}

/// The chosen candidate minimises the predicted total over the predicted candidates, unless
/// candidates were raced: then every one raced was built and timed, each overlapped the best
/// prediction's 90% interval, and the chosen one has the least measured total of them.
void expect_minimises_prediction(const AutoChoice& c) {
  const AutoCandidate* best = nullptr;
  for (const AutoCandidate& k : c.candidates)
    if (k.skipped.empty() && (!best || k.predicted_total_s < best->predicted_total_s)) best = &k;
  ASSERT_NE(best, nullptr);
  if (!c.sampled) {
    EXPECT_EQ(c.chosen, best->spec);
    return;
  }
  EXPECT_TRUE(best->built);
  const AutoCandidate* chosen = nullptr;
  for (const AutoCandidate& k : c.candidates) {
    if (!k.built) continue;
    EXPECT_LE(k.total_lo_s, best->total_hi_s) << k.spec << " raced without overlapping " << best->spec;
    ASSERT_TRUE(std::isfinite(k.measured_build_s) && std::isfinite(k.measured_ns_per_ray)) << k.spec;
    if (k.spec == c.chosen) chosen = &k;
  }
  ASSERT_NE(chosen, nullptr) << c.chosen << " was not raced";
  for (const AutoCandidate& k : c.candidates) {
    if (k.built) {
      EXPECT_LE(measured_total(c, *chosen), measured_total(c, k)) << k.spec;
    }
  }
}

TEST(AutoAccel, ModelFileHasTheBuildAndSceneLevelModels) {
  const CostModelSet set = read_model_file(tiny_model());
  for (const char* spec : {"bvh", "grid:d=1", "kdtree"}) {
    ASSERT_EQ(set.build.count(spec), 1u) << spec;
    EXPECT_EQ(set.build.at(spec).rows, 4u) << spec;
    EXPECT_TRUE(set.build.at(spec).cross_validated) << spec;
    ASSERT_EQ(set.scene_trace.count(spec), 1u) << spec;
    EXPECT_EQ(set.scene_trace.at(spec).count("camera"), 1u) << spec;
    EXPECT_EQ(set.scene_trace.at(spec).count("bounce"), 1u) << spec;
    EXPECT_EQ(set.scene_trace.at(spec).count("occlusion"), 0u) << spec;  // no shadow rays in the plan
  }
}

// Every candidate the tiny model has a spec effect for is predicted as exp(a + b̂), one b̂ for
// the scene (spec_trace_effects.h): two candidates' predictions differ by exp(a1 - a2), what the
// paired measurements say, whatever their own scene-level models predict for this scene.
TEST(AutoAccel, CandidatesAreRankedByTheirSpecEffects) {
  const CostModelSet set = read_model_file(tiny_model());
  std::map<std::string, double> bounce_effect;  // by canonical spec
  for (const char* spec : {"bvh", "grid:d=1", "kdtree"}) {
    ASSERT_EQ(set.trace_effects.by_spec.count(spec), 1u) << spec;
    const SpecTraceEffect& e = set.trace_effects.by_spec.at(spec).at("bounce");
    EXPECT_EQ(e.scenes, 4u) << spec;
    bounce_effect[canonical_accel_spec(spec)] = e.effect;
  }
  const auto accel = make_accelerator("auto:model=" + tiny_model() + ",rays=diffuse", make_scene("soup:n=2500"));
  const AutoChoice& c = choice_of(*accel);
  const AutoCandidate* first = nullptr;
  std::size_t predicted = 0;
  for (const AutoCandidate& k : c.candidates) {
    if (!k.skipped.empty()) continue;
    ++predicted;
    EXPECT_EQ(k.trace_model, "effects") << k.spec;
    if (!first) {
      first = &k;
      continue;
    }
    const double expected = std::exp(bounce_effect.at(canonical_accel_spec(k.spec)) -
                                     bounce_effect.at(canonical_accel_spec(first->spec)));
    EXPECT_NEAR(k.predicted_ns_per_ray / first->predicted_ns_per_ray, expected, 1e-9 * expected) << k.spec;
  }
  EXPECT_EQ(predicted, 3u);
}

TEST(AutoAccel, ChoosesBeforeBuildingAndBuildsOnlyWhatItChose) {
  const auto scene = make_scene("soup:n=3000");
  const auto accel = make_accelerator("auto:model=" + tiny_model() + ",rays=diffuse,count=10000", scene);
  const AutoChoice& c = choice_of(*accel);
  EXPECT_EQ(c.method, "predicted");
  EXPECT_EQ(c.count, 10000.0);
  if (c.sampled) {
    EXPECT_GE(c.candidates_built, 2u);
  } else {
    EXPECT_EQ(c.candidates_built, 1u);
  }
  EXPECT_EQ(built_count(c), c.candidates_built);
  expect_minimises_prediction(c);
  EXPECT_GT(c.choose_s, 0.0);
  EXPECT_TRUE(std::isfinite(c.predicted_build_s));
  bool any_skipped = false;
  for (const AutoCandidate& k : c.candidates) {
    if (k.spec == c.chosen) {
      EXPECT_TRUE(k.built);
    }
    any_skipped |= !k.skipped.empty();
  }
  EXPECT_TRUE(any_skipped);  // the candidates the tiny model has no entry for (bvh:width=2, octree, ...)
  EXPECT_FALSE(c.runner_up.empty());
  EXPECT_EQ(mismatches_against(*accel, "bvh", scene, "diffuse:512"), 0u);  // what it built traces correctly
}

TEST(AutoAccel, TheChoiceMovesWithTheCountAsItsPredictionsSay) {
  const auto scene = make_scene("sphere:n=4000");
  const auto few = make_accelerator("auto:model=" + tiny_model() + ",rays=primary,count=100", scene);
  const auto many = make_accelerator("auto:model=" + tiny_model() + ",rays=primary,count=1e9", scene);
  const AutoChoice &a = choice_of(*few), &b = choice_of(*many);
  expect_minimises_prediction(a);
  expect_minimises_prediction(b);
  // Argmins of build + N·trace: more rays never choose a slower tree or a cheaper build.
  if (!a.sampled && !b.sampled) {
    EXPECT_LE(b.predicted_ns_per_ray, a.predicted_ns_per_ray);
    EXPECT_GE(b.predicted_build_s, a.predicted_build_s);
  }
  EXPECT_NEAR(b.predicted_trace_s, 1e9 * b.predicted_ns_per_ray * 1e-9, 1e-9 * b.predicted_trace_s);
}

TEST(AutoAccel, ForManyRaysItRacesThePlausibleCandidatesAndKeepsTheMeasuredBest) {
  // 10^9 rays: the race's budget (5% of the predicted total) is far above every build here, so
  // every candidate whose interval overlaps the best prediction's is built and timed.
  const auto scene = make_scene("walls:n=80,angle=45");
  const auto accel = make_accelerator("auto:model=" + tiny_model() + ",rays=diffuse,count=1e9", scene);
  const AutoChoice& c = choice_of(*accel);
  ASSERT_EQ(c.method, "predicted");
  const AutoCandidate* best = nullptr;
  for (const AutoCandidate& k : c.candidates)
    if (k.skipped.empty() && (!best || k.predicted_total_s < best->predicted_total_s)) best = &k;
  ASSERT_NE(best, nullptr);
  std::size_t overlapping = 0;
  for (const AutoCandidate& k : c.candidates)
    if (k.skipped.empty() && k.total_lo_s <= best->total_hi_s) ++overlapping;
  EXPECT_EQ(c.candidates_built, overlapping);
  EXPECT_EQ(built_count(c), c.candidates_built);
  EXPECT_EQ(c.sampled, overlapping > 1);
  expect_minimises_prediction(c);
  if (c.sampled) {
    EXPECT_NE(c.note.find("timed on 4096 rays"), std::string::npos) << c.note;
  }
  EXPECT_EQ(mismatches_against(*accel, "bvh", scene, "diffuse:512"), 0u);  // what it kept traces correctly
}

TEST(AutoAccel, TheSampleIsAThousandthOfTheCountWithinItsBounds) {
  EXPECT_EQ(auto_sample_rays(1), kAutoSampleRays);
  EXPECT_EQ(auto_sample_rays(1e4), kAutoSampleRays);
  EXPECT_EQ(auto_sample_rays(1e6), 1000u);
  EXPECT_EQ(auto_sample_rays(1e8), kAutoSampleMaxRays);
  EXPECT_EQ(auto_sample_rays(1e18), kAutoSampleMaxRays);
}

// The race samples its diffuse and shadow rays from the structure it built first (ray_sets.h)
// instead of building Embree's: on a closed mesh they are the rays Embree's first hits give, but
// for the rare ray whose first hit the two tracers round differently.
TEST(AutoAccel, TheRaceSamplesTheRaysEmbreeWouldGiveFromItsOwnStructure) {
  const auto scene = make_scene("cgal:fandisk");
  const auto bvh = make_accelerator("bvh", scene);
  const float diagonal = length(scene->bounds().diagonal());
  for (const std::string spec : {"diffuse:512", "shadow:512"}) {
    const std::vector<Ray> embree = make_ray_set(spec, scene), own = make_ray_set(spec, scene, *bvh);
    ASSERT_EQ(own.size(), embree.size()) << spec;
    std::size_t apart = 0;
    for (std::size_t i = 0; i < own.size(); ++i)
      if (length(own[i].org - embree[i].org) > 1e-5f * diagonal || length(own[i].dir - embree[i].dir) > 1e-4f) ++apart;
    EXPECT_LE(apart, own.size() / 100) << spec << ": rays apart from Embree's";
  }
}

TEST(AutoAccel, WithoutACountNothingIsTimedAndTheChoiceRepeats) {
  const auto scene = make_scene("soup:n=2500");
  const std::string spec = "auto:model=" + tiny_model() + ",rays=diffuse";
  const auto one = make_accelerator(spec, scene), two = make_accelerator(spec, scene);
  const AutoChoice &a = choice_of(*one), &b = choice_of(*two);
  EXPECT_EQ(a.method, "predicted");
  EXPECT_FALSE(a.sampled);
  EXPECT_EQ(a.candidates_built, 1u);
  EXPECT_EQ(a.chosen, b.chosen);
  EXPECT_EQ(one->structure_hash(), two->structure_hash());
  // Without a count, the least predicted time per ray wins.
  for (const AutoCandidate& k : a.candidates) {
    if (k.skipped.empty()) {
      EXPECT_GE(k.predicted_ns_per_ray, a.predicted_ns_per_ray) << k.spec;
    }
  }
}

TEST(AutoAccel, ARepeatedChoiceOutsideTheRangeWarnsOnce) {
  // Eight times the tiny sweep's largest scene, a size no other test here builds; without a count
  // nothing is timed, so both builds choose alike and the warning's text repeats.
  const auto scene = make_scene("soup:n=50000");
  const std::string spec = "auto:model=" + tiny_model() + ",rays=primary";
  testing::internal::CaptureStderr();
  const auto one = make_accelerator(spec, scene), two = make_accelerator(spec, scene);
  const std::string warnings = testing::internal::GetCapturedStderr();
  EXPECT_GT(choice_of(*one).extrapolation_factor, 5.0);
  EXPECT_EQ(choice_of(*two).extrapolation_factor, choice_of(*one).extrapolation_factor);
  const std::string line = "raylab: warning: auto: 5e+04 primitives lie outside the range";
  const auto at = warnings.find(line);
  EXPECT_NE(at, std::string::npos) << warnings;
  EXPECT_EQ(warnings.find(line, at + 1), std::string::npos) << "warned twice: " << warnings;
}

// The scene's effect b̂ is voted by the scene-level models fitted on scenes of its size when at
// least kAutoEffectMinVoters are: a model narrowed to scenes twice as large no longer votes, nor
// widens the intervals or warns. With fewer such models every model votes, as before.
TEST(AutoAccel, OnlyModelsFittedOnTheScenesSizeVoteOnItsEffect) {
  static_assert(kAutoEffectMinVoters == 3);
  CostModelSet base = read_model_file(tiny_model());
  // A fourth voter: bvh's scene-level models and effects again under another spec.
  base.scene_trace["bvh:leaf_size=8"] = base.scene_trace.at("bvh");
  base.trace_effects.by_spec["bvh:leaf_size=8"] = base.trace_effects.by_spec.at("bvh");
  auto with_narrowed = [&](const std::vector<std::string>& specs, const std::string& name) {
    CostModelSet set = base;
    for (const std::string& spec : specs)
      for (auto& [cls, m] : set.scene_trace.at(spec)) m.range_lo = 5000, m.range_hi = 6000;
    const std::string path = (scratch_dir() / name).string();
    write_model_file(set, path);
    return path;
  };
  const auto scene = make_scene("soup:n=2500");  // inside the tiny sweep's 300..6000, 2x below 5000
  testing::internal::CaptureStderr();
  const auto three_in_range =
      make_accelerator("auto:model=" + with_narrowed({"kdtree"}, "model_one_narrowed.json") + ",rays=diffuse", scene);
  const std::string warnings = testing::internal::GetCapturedStderr();
  EXPECT_EQ(choice_of(*three_in_range).extrapolation_factor, 1.0);
  EXPECT_EQ(warnings.find("lie outside the range"), std::string::npos) << warnings;
  const auto two_in_range = make_accelerator(
      "auto:model=" + with_narrowed({"kdtree", "grid:d=1"}, "model_two_narrowed.json") + ",rays=diffuse", scene);
  EXPECT_NEAR(choice_of(*two_in_range).extrapolation_factor, 2.0, 1e-9);
}

TEST(AutoAccel, InstancedScenesChooseForEachPart) {
  const auto scene = make_scene("instances:of=(sphere:n=800),count=6");
  const auto accel = make_accelerator("auto:model=" + tiny_model() + ",rays=primary,count=5000", scene);
  const AutoChoice& c = choice_of(*accel);
  EXPECT_EQ(c.method, "predicted");
  EXPECT_GE(c.candidates_built, 1u);
  EXPECT_EQ(mismatches_against(*accel, "embree", scene, "primary:512"), 0u);
}

TEST(AutoAccel, WithoutBuildTimeModelsEveryCandidateIsBuiltAndSaysSo) {
  // The tiny model less its build-time and scene-level models: a model file written before them.
  CostModelSet set = read_model_file(tiny_model());
  set.build.clear();
  set.scene_trace.clear();
  const std::string without = (scratch_dir() / "model_without_build.json").string();
  write_model_file(set, without);
  const auto scene = make_scene("sphere:n=600");
  const auto accel = make_accelerator("auto:model=" + without + ",rays=primary,count=1000", scene);
  const AutoChoice& c = choice_of(*accel);
  EXPECT_EQ(c.method, "built-all");
  EXPECT_FALSE(c.note.empty());
  EXPECT_EQ(built_count(c), c.candidates_built);
  EXPECT_GE(c.candidates_built, 8u);
}

TEST(AutoAccel, ABadCountIsOneErrorNamingTheForm) {
  const auto scene = make_scene("sphere:n=200");
  for (const char* bad : {"-5", "abc", "0", "2.5", "1e30"}) {
    try {
      make_accelerator(std::string("auto:rays=primary,count=") + bad, scene);
      ADD_FAILURE() << "count=" << bad << " accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("count=" + std::string(bad)), std::string::npos) << what;
      EXPECT_NE(what.find("auto:rays=KIND,count=N"), std::string::npos) << what;
    }
  }
}

TEST(AutoAccel, TraceHandsItsRayCountDownAndPrintsTheChoice) {
  const fs::path out = scratch_dir() / "trace.json", err = scratch_dir() / "trace.err";
  const std::string cmd = std::string(RAYLAB_TOOL_PATH) + " trace --scene soup:n=2000 --accel auto:model=" +
                          tiny_model() + ",rays=primary --rays primary:777 --threads 1 --json >" + out.string() +
                          " 2>" + err.string();
  const int raw = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(raw) && WEXITSTATUS(raw) == 0) << cmd;
  std::stringstream text;
  text << std::ifstream(out).rdbuf();
  const auto j = nlohmann::json::parse(text.str());
  EXPECT_EQ(j.at("auto_method"), "predicted");
  EXPECT_EQ(j.at("auto_count").get<double>(), j.at("rays").get<double>());  // primary:777 rounds to its pixel grid
  for (const char* key : {"auto_choose_s", "auto_predicted_build_s", "auto_predicted_trace_s", "build_s", "trace_s"})
    EXPECT_TRUE(j.at(key).is_number()) << key;
  EXPECT_FALSE(j.at("auto_choice").at("chosen").get<std::string>().empty());
  EXPECT_TRUE(j.at("auto_runner_up").at("spec").is_string());
  EXPECT_TRUE(j.at("auto_runner_up").at("predicted_total_s").is_number());
  const std::size_t built = j.at("auto_candidates_built");
  if (j.at("auto_sampled").get<bool>()) {
    EXPECT_GE(built, 2u);
  } else {
    EXPECT_EQ(built, 1u);
  }
  EXPECT_EQ(j.at("auto_extrapolation_factor").get<double>(), 1.0);  // 2000 triangles: inside 300..6000
  {
    std::stringstream warnings;
    warnings << std::ifstream(err).rdbuf();
    EXPECT_EQ(warnings.str().find("outside the range"), std::string::npos) << warnings.str();
  }

  // Ten times the largest scene of the sweep: auto still chooses, widens its intervals and says so once.
  const std::string far = std::string(RAYLAB_TOOL_PATH) + " trace --scene soup:n=60000 --accel auto:model=" +
                          tiny_model() + ",rays=primary --rays primary:256 --threads 1 --no-counters --json >" +
                          out.string() + " 2>" + err.string();
  const int far_status = std::system(far.c_str());
  ASSERT_TRUE(WIFEXITED(far_status) && WEXITSTATUS(far_status) == 0) << far;
  std::stringstream far_text, far_err;
  far_text << std::ifstream(out).rdbuf();
  far_err << std::ifstream(err).rdbuf();
  const auto f = nlohmann::json::parse(far_text.str());
  EXPECT_EQ(f.at("auto_method"), "predicted");
  EXPECT_GT(f.at("auto_extrapolation_factor").get<double>(), 5.0);
  const std::string warning = far_err.str();
  const auto at = warning.find("raylab: warning: auto: 6e+04 primitives lie outside the range its models were fitted on");
  EXPECT_NE(at, std::string::npos) << warning;
  EXPECT_EQ(warning.find("outside the range", warning.find("outside the range") + 1), std::string::npos)
      << "warned more than once: " << warning;

  const std::string bad = std::string(RAYLAB_TOOL_PATH) +
                          " trace --scene soup:n=200 --accel auto:count=-5 --rays primary:16 >" + out.string() +
                          " 2>" + err.string();
  const int status = std::system(bad.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::stringstream e;
  e << std::ifstream(err).rdbuf();
  const std::string message = e.str();
  EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 1) << message;
  EXPECT_EQ(message.rfind("raylab: error: ", 0), 0u) << message;
}

}  // namespace
}  // namespace raylab
